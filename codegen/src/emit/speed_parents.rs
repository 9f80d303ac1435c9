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
use super::context::{Context, scalar_type};
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

/// The straight-line kernels are emitted up to this many multiply-adds of the factorisation
/// (`Σ_k d_k (d_k + 1) / 2`, `d_k` the ancestors of speed `k`): a humanoid on a floating base
/// has about 1,700, a 100-speed tree of ten branches 1,650, while a 60-speed chain would have
/// 36,000 lines; above it the runtime's loops factor along `SPEED_PARENTS`.
pub const KERNEL_LIMIT: usize = 6_000;

/// The ancestors of `i`, nearest first.
fn ancestors(lambda: &[Option<usize>], i: usize) -> Vec<usize> {
    let mut out = Vec::new();
    let mut at = lambda[i];
    while let Some(p) = at {
        out.push(p);
        at = lambda[p];
    }
    out
}

/// The module's parent array when it has `TREE_KERNELS` too (within [`KERNEL_LIMIT`]).
fn kernel_parents(cx: &Context<'_>) -> Option<Vec<Option<usize>>> {
    let lambda = module_parents(cx)?;
    let work: usize = (0..lambda.len())
        .map(|k| {
            let d = ancestors(&lambda, k).len();
            d * (d + 1) / 2
        })
        .sum();
    (work <= KERNEL_LIMIT).then_some(lambda)
}

/// The trait items: `const SPEED_PARENTS: Option<[Option<usize>; DOF]> = Some(SPEED_PARENTS);`
/// and, with kernels, `mass_matrix_factor` through them; or nothing. `q_ty` is the type of `q`.
pub(super) fn trait_items(cx: &Context<'_>, q_ty: &TokenStream) -> TokenStream {
    if module_parents(cx).is_none() {
        return TokenStream::new();
    }
    let mut out = quote!(
        const SPEED_PARENTS: Option<[Option<usize>; DOF]> = Some(SPEED_PARENTS);
    );
    if kernel_parents(cx).is_some() {
        let t = scalar_type(cx.precision);
        out.extend(quote! {
            #[inline]
            fn mass_matrix_factor(&self, q: &#q_ty)
                -> Option<kanegen_runtime::tree_factor::TreeFactor<#t, DOF>>
            {
                kanegen_runtime::tree_factor::TreeFactor::with_kernels(
                    &self.mass_matrix(q), &SPEED_PARENTS, TREE_KERNELS,
                )
            }
        });
    }
    out
}

/// `TREE_KERNELS` and its three functions (`kanegen_runtime::tree_factor::TreeKernels`): the
/// runtime's factorisation and substitutions along `SPEED_PARENTS` unrolled, each multiply-add
/// an `Arith::mul_add` (fused in the x86-64-v3 copy); or nothing.
pub(super) fn kernels(cx: &Context<'_>) -> TokenStream {
    let Some(lambda) = kernel_parents(cx) else {
        return TokenStream::new();
    };
    let n = lambda.len();
    let t = scalar_type(cx.precision);
    let nn = idx(n);
    let anc: Vec<Vec<usize>> = (0..n).map(|i| ancestors(&lambda, i)).collect();
    // Featherstone's LTDL, k = N − 1, …, 0; column k of `h` holds row k of L.
    let mut factorise = Vec::new();
    for k in (0..n).rev() {
        let kk = idx(k);
        factorise.push(quote! {
            ok &= h[#kk][#kk] > 0.0;
            let inv = 1.0 / h[#kk][#kk];
            h[#kk][#kk] = inv;
        });
        for &i in &anc[k] {
            let ii = idx(i);
            // `j` ascending: runs of consecutive updates, which LLVM's SLP vectoriser packs.
            let mut js: Vec<usize> = std::iter::once(i).chain(anc[i].iter().copied()).collect();
            js.sort_unstable();
            let updates = js.into_iter().map(|j| {
                let jj = idx(j);
                quote!(h[#ii][#jj] = A::mul_add(-a, h[#kk][#jj], h[#ii][#jj]);)
            });
            factorise.push(quote! {{
                let a = h[#kk][#ii] * inv;
                #(#updates)*
                h[#kk][#ii] = a;
            }});
        }
    }
    // Lᵀ y = b, from the last speed up; a zero entry moves nothing. Speeds at the root only
    // (no ancestors anywhere): nothing to do.
    let unused = anc
        .iter()
        .all(Vec::is_empty)
        .then(|| quote!(let _ = (h, y);));
    let backward = (0..n).rev().filter(|&i| !anc[i].is_empty()).map(|i| {
        let ii = idx(i);
        let updates = anc[i].iter().rev().map(|&j| {
            let jj = idx(j);
            quote!(y[#jj] = A::mul_add(-h[#ii][#jj], yi, y[#jj]);)
        });
        quote! {{
            let yi = y[#ii];
            if yi != 0.0 {
                #(#updates)*
            }
        }}
    });
    // L x = D⁻¹ y, from the root down: `x_i = x_i / D_i − Σ_j L_ij x_j`, the sum in four
    // partial sums (`j` mod 4, ascending) so that its chain of dependent multiply-adds is a
    // quarter as long.
    let forward = (0..n).map(|i| {
        let ii = idx(i);
        let mut js = anc[i].clone();
        js.sort_unstable();
        if js.is_empty() {
            return quote!(x[#ii] *= h[#ii][#ii];);
        }
        let lanes = js.len().min(4);
        let init = (0..lanes).map(|l| {
            let s = quote::format_ident!("s{}", l);
            quote!(let mut #s = 0.0;)
        });
        let terms = js.iter().enumerate().map(|(n, &j)| {
            let jj = idx(j);
            let s = quote::format_ident!("s{}", n % 4);
            quote!(#s = A::mul_add(h[#ii][#jj], x[#jj], #s);)
        });
        let sum = match lanes {
            1 => quote!(s0),
            2 => quote!(s0 + s1),
            3 => quote!((s0 + s1) + s2),
            _ => quote!((s0 + s1) + (s2 + s3)),
        };
        quote! {{
            #(#init)*
            #(#terms)*
            x[#ii] = x[#ii] * h[#ii][#ii] - (#sum);
        }}
    });
    let call = |args: TokenStream| {
        if cx.isa_dispatch {
            quote! {
                kanegen_runtime::isa::dispatch_fused_with(
                    #args,
                    #[inline(always)]
                    |#args| body::<kanegen_runtime::isa::Plain>(#args),
                    #[inline(always)]
                    |#args| body::<kanegen_runtime::isa::Fused>(#args),
                )
            }
        } else {
            quote!(body::<kanegen_runtime::isa::Native>(#args))
        }
    };
    let call_factorise = call(quote!(h));
    let call_backward = call(quote!((h, y)));
    let call_forward = call(quote!((h, x)));
    quote! {
        /// Straight-line kernels of `M = Lᵀ D L` along [`SPEED_PARENTS`]
        /// (`kanegen_runtime::tree_factor`): what the traits' `mass_matrix_factor` and
        /// `forward_dynamics` of this robot run.
        pub const TREE_KERNELS: kanegen_runtime::tree_factor::TreeKernels<#t, #nn> =
            kanegen_runtime::tree_factor::TreeKernels {
                factorise: tree_factorise,
                solve_transposed_unit: tree_solve_transposed_unit,
                finish_solve: tree_finish_solve,
            };

        /// The factorisation of [`TREE_KERNELS`], in place; `false` when a pivot is not
        /// positive.
        pub fn tree_factorise(h: &mut [[#t; #nn]; #nn]) -> bool {
            #[inline(always)]
            fn body<A: kanegen_runtime::isa::Arith<#t>>(h: &mut [[#t; #nn]; #nn]) -> bool {
                let mut ok = true;
                #(#factorise)*
                ok
            }
            #call_factorise
        }

        /// `y ← L⁻ᵀ y` of [`TREE_KERNELS`].
        pub fn tree_solve_transposed_unit(h: &[[#t; #nn]; #nn], y: &mut [#t; #nn]) {
            #[inline(always)]
            fn body<A: kanegen_runtime::isa::Arith<#t>>((h, y): (&[[#t; #nn]; #nn], &mut [#t; #nn])) {
                #unused
                #(#backward)*
            }
            #call_backward
        }

        /// `x ← L⁻¹ D⁻¹ x` of [`TREE_KERNELS`].
        pub fn tree_finish_solve(h: &[[#t; #nn]; #nn], x: &mut [#t; #nn]) {
            #[inline(always)]
            fn body<A: kanegen_runtime::isa::Arith<#t>>((h, x): (&[[#t; #nn]; #nn], &mut [#t; #nn])) {
                #(#forward)*
            }
            #call_forward
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{fits, parents};
    use crate::options::{Options, ParamMode};
    use crate::registry::{FunctionId, FunctionSet};
    use kanegen_model::{Model, UrdfOptions};

    fn root() -> String {
        concat!(env!("CARGO_MANIFEST_DIR"), "/..").to_owned()
    }

    /// The lowered mass matrix of `model`.
    fn mass_matrix(model: &Model) -> crate::lower::Program {
        let options = Options {
            params: ParamMode::Runtime,
            functions: FunctionSet::default(),
        };
        let low = crate::lower::lower(&crate::kane::derive(model, options));
        low.functions
            .into_iter()
            .find(|f| f.id == FunctionId::MassMatrix)
            .unwrap()
            .program
    }

    #[test]
    fn parents_follow_the_tree_and_fit_the_generated_mass_matrix() {
        let solo = Model::from_urdf_file(
            format!("{}/tests/corpus/solo12.urdf", root()),
            &UrdfOptions::floating(),
        )
        .unwrap();
        let lambda = parents(&solo).unwrap();
        let mut expected: Vec<Option<usize>> = (0..18).map(|i: usize| i.checked_sub(1)).collect();
        for leg in 0..4 {
            expected[6 + 3 * leg] = Some(5);
        }
        assert_eq!(lambda, expected);
        assert!(fits(&lambda, &mass_matrix(&solo)));
        // Krang: the wheeled base's two speeds at the root.
        let krang = Model::from_toml_file(format!("{}/models/krang.toml", root())).unwrap();
        let lambda = parents(&krang).unwrap();
        assert_eq!(&lambda[..2], &[None, Some(0)]);
        assert!(fits(&lambda, &mass_matrix(&krang)));
    }

    #[test]
    fn a_parent_array_that_misses_a_coupling_does_not_fit() {
        let two = Model::from_toml_file(format!("{}/models/two-link.toml", root())).unwrap();
        let m = mass_matrix(&two);
        assert!(fits(&[None, Some(0)], &m));
        // Two independent roots would claim M(0, 1) = 0; the generated matrix says otherwise.
        assert!(!fits(&[None, None], &m));
    }

    #[test]
    fn mimic_joints_have_no_parent_array() {
        let gripper = Model::from_urdf_file(
            format!("{}/models/mimic_gripper.urdf", root()),
            &UrdfOptions::default(),
        )
        .unwrap();
        assert!(!gripper.mimics.is_empty());
        assert_eq!(parents(&gripper), None);
    }
}
