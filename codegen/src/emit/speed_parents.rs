//! The speeds' parent array of a module, `SPEED_PARENTS`: for each speed, the speed nearest to
//! it on the path from its joint towards the root, which `kanegen_runtime::tree_factor`
//! factors the mass matrix along without fill-in.
//!
//! Derived from the model's tree ([`parents`]): a joint's parent speed is that of the nearest
//! moving joint above it; a floating base's six speeds form a chain at the root (the base's
//! twist couples to every body), and so do a wheeled base's two; the root joints of a fixed base
//! have none. Emitted only where it is exact: every parent before its child (`λ(i) < i`, true of
//! the speed order the loaders produce), no mimic joint (a dependent speed couples its master's
//! ancestors with its own), and every structurally non-zero entry of the module's generated mass
//! matrix on a pair of speeds one of which is an ancestor of the other ([`fits`]) — so a module
//! without the mass matrix has no `SPEED_PARENTS`, and one whose matrix does not fit falls back
//! to the dense factorisation.

use proc_macro2::TokenStream;
use quote::quote;

use super::body::nonzero_outputs;
use super::context::Context;
use super::print::idx;
use crate::registry::FunctionId;
use kanegen_model::{Base, Model};

/// `λ` of the model's speeds, or `None` where it is not defined (mimic joints, a speed driven by
/// no joint, a parent after its child).
pub(crate) fn parents(model: &Model) -> Option<Vec<Option<usize>>> {
    if !model.mimics.is_empty() {
        return None;
    }
    let n = model.dof();
    // The speed of the root joints and the base speeds' own chain.
    let mut lambda: Vec<Option<Option<usize>>> = vec![None; n];
    let root = match &model.base {
        Base::Fixed => None,
        Base::Floating => {
            for (k, l) in lambda.iter_mut().enumerate().take(6) {
                *l = Some(k.checked_sub(1));
            }
            Some(5)
        }
        Base::Wheeled(w) => {
            let (first, second) = (w.x_speed.min(w.psi_speed), w.x_speed.max(w.psi_speed));
            lambda[first] = Some(None);
            lambda[second] = Some(Some(first));
            Some(second)
        }
    };
    for (l, _, mount) in model.mounted_links() {
        let Some(s) = mount.joint.speed() else {
            continue;
        };
        // The nearest moving joint above link `l`.
        let above = model
            .path_to_base(l)
            .skip(1)
            .find_map(|(_, m)| m.joint.speed())
            .or(root);
        if s >= n || lambda[s].is_some() {
            return None;
        }
        lambda[s] = Some(above);
    }
    let lambda: Vec<Option<usize>> = lambda.into_iter().collect::<Option<_>>()?;
    let ordered = lambda
        .iter()
        .enumerate()
        .all(|(i, p)| p.is_none_or(|p| p < i));
    ordered.then_some(lambda)
}

/// Whether `j` is `i` or one of its ancestors along `lambda`.
fn ancestor_or_self(lambda: &[Option<usize>], mut i: usize, j: usize) -> bool {
    loop {
        if i == j {
            return true;
        }
        match lambda[i] {
            Some(p) => i = p,
            None => return false,
        }
    }
}

/// Whether every structurally non-zero entry of the generated mass matrix (the module's
/// `mass_matrix` program, its upper triangle) lies on a pair of related speeds.
pub(crate) fn fits(lambda: &[Option<usize>], mass_matrix: &crate::lower::Program) -> bool {
    nonzero_outputs(mass_matrix).all(|(r, c, _)| {
        *r < lambda.len()
            && *c < lambda.len()
            && (ancestor_or_self(lambda, *r, *c) || ancestor_or_self(lambda, *c, *r))
    })
}

/// The module's parent array, when it has one (see the [module docs](self)).
pub(super) fn module_parents(cx: &Context<'_>) -> Option<Vec<Option<usize>>> {
    let m = cx
        .low
        .functions
        .iter()
        .find(|f| f.id == FunctionId::MassMatrix && f.frame.is_none())?;
    let lambda = parents(cx.model)?;
    (lambda.len() == cx.low.dof && fits(&lambda, &m.program)).then_some(lambda)
}

/// `pub const SPEED_PARENTS: [Option<usize>; DOF]`, or nothing.
pub(super) fn constant(cx: &Context<'_>) -> TokenStream {
    let Some(lambda) = module_parents(cx) else {
        return TokenStream::new();
    };
    let n = idx(lambda.len());
    let entries = lambda.iter().map(|p| match p {
        Some(p) => {
            let p = idx(*p);
            quote!(Some(#p))
        }
        None => quote!(None),
    });
    quote! {
        /// The speeds' parent array `λ`: entry `i` is the speed nearest to speed `i` on the path
        /// from its joint towards the root (`None` at the root; a floating base's six speeds form
        /// a chain there), always before `i`. The mass matrix is structurally zero between two
        /// speeds neither of which is an ancestor of the other (verified on the generated
        /// matrix), so `kanegen_runtime::tree_factor::TreeFactor` factors it without fill-in:
        /// the traits' `forward_dynamics` and `mass_matrix_factor` do.
        pub const SPEED_PARENTS: [Option<usize>; #n] = [#(#entries),*];
    }
}

/// The trait item `const SPEED_PARENTS: Option<[Option<usize>; DOF]> = Some(SPEED_PARENTS);`,
/// or nothing.
pub(super) fn trait_const(cx: &Context<'_>) -> TokenStream {
    if module_parents(cx).is_none() {
        return TokenStream::new();
    }
    quote!(
        const SPEED_PARENTS: Option<[Option<usize>; DOF]> = Some(SPEED_PARENTS);
    )
}
