//! The items of a generated module besides the functions: names and indices, `Params`,
//! `Precomputed`, the wrapper type with one method per registry function, and the
//! `kanegen-runtime` trait implementations.

use proc_macro2::{Ident, TokenStream};
use quote::quote;

use super::body::{state_args, uses};
use super::context::{Context, file_name, scalar_type};
use super::print::{ident, idx, signed_lit};
use super::signature::{arg_names, return_type, wrapper_params};
use crate::lower::{Leaf, Program};
use crate::naming;
use crate::registry::{FunctionSpec, RuntimeTrait};
use kanegen_model::{Model, ParamKind};

/// `DOF`, `SPEED_NAMES`, `COORDINATE_NAMES` and the `index` constants: one per coordinate
/// (`Q_IMU`) and one per speed (`QD_IMU`), the same index, unless the speed's constant would
/// repeat a name already taken.
pub(super) fn names(cx: &Context<'_>) -> TokenStream {
    if cx.low.floating {
        return floating_names(cx);
    }
    let model = cx.model;
    let nl = idx(cx.low.dof);
    // The independent speeds (a mimic joint's dependent speed is not an input).
    let speeds = &model.speeds[..cx.low.dof];
    let speed_names: Vec<&str> = speeds.iter().map(|s| s.name.as_str()).collect();
    let coord_names: Vec<&str> = speeds.iter().map(|s| s.coordinate.as_str()).collect();
    let mut taken: Vec<String> = speeds
        .iter()
        .map(|s| ident(&s.coordinate.to_uppercase()).to_string())
        .collect();
    let mut index_consts = Vec::new();
    for (i, s) in speeds.iter().enumerate() {
        let id = ident(&s.coordinate.to_uppercase());
        let doc = format!(" Index of the coordinate `{}` in q.", s.coordinate);
        let i = idx(i);
        index_consts.push(quote!(#[doc = #doc] pub const #id: usize = #i;));
        let speed_id = ident(&s.name.to_uppercase());
        if !taken.contains(&speed_id.to_string()) {
            taken.push(speed_id.to_string());
            let doc = format!(
                " Index of the speed `{}` in u, u̇ and τ (the rate of `{}`).",
                s.name, s.coordinate
            );
            index_consts.push(quote!(#[doc = #doc] pub const #speed_id: usize = #i;));
        }
    }
    let parents = super::speed_parents::constant(cx);
    quote! {
        /// Number of generalized speeds (and coordinates).
        pub const DOF: usize = #nl;
        /// Generalized speed names, in the order of `u`.
        pub const SPEED_NAMES: [&str; #nl] = [#(#speed_names),*];
        /// Coordinate names, in the order of `q`.
        pub const COORDINATE_NAMES: [&str; #nl] = [#(#coord_names),*];
        #parents

        /// Index constants: of each coordinate in `q` (`Q_IMU`) and of its speed in `u`, `u̇`
        /// and `τ` (`QD_IMU`); a coordinate and its speed have the same index.
        pub mod index {
            #(#index_consts)*
        }
    }
}

/// [`names`] of a floating base: `NQ = DOF + 1` coordinates (the base's seven first), and the
/// index constants of each coordinate in `q` and of each speed in `u`.
fn floating_names(cx: &Context<'_>) -> TokenStream {
    let model = cx.model;
    let (nl, nq) = (idx(cx.low.dof), idx(cx.low.nq));
    let speeds = &model.speeds[..cx.low.dof];
    let speed_names: Vec<&str> = speeds.iter().map(|s| s.name.as_str()).collect();
    let coord_names = model.coordinate_names();
    let mut taken: Vec<String> = coord_names
        .iter()
        .map(|c| ident(&c.to_uppercase()).to_string())
        .collect();
    let mut index_consts = Vec::new();
    for (k, c) in coord_names.iter().enumerate() {
        let id = ident(&c.to_uppercase());
        let doc = format!(" Index of the coordinate `{c}` in q.");
        let k = idx(k);
        index_consts.push(quote!(#[doc = #doc] pub const #id: usize = #k;));
    }
    for (i, s) in speeds.iter().enumerate() {
        let speed_id = ident(&s.name.to_uppercase());
        if !taken.contains(&speed_id.to_string()) {
            taken.push(speed_id.to_string());
            let doc = if i < 6 {
                format!(
                    " Index of the floating base's speed `{}` in u, u̇ and τ.",
                    s.name
                )
            } else {
                format!(
                    " Index of the speed `{}` in u, u̇ and τ (the rate of `{}`).",
                    s.name, s.coordinate
                )
            };
            let i = idx(i);
            index_consts.push(quote!(#[doc = #doc] pub const #speed_id: usize = #i;));
        }
    }
    let parents = super::speed_parents::constant(cx);
    quote! {
        /// Number of generalized speeds: the floating base's six (`v`, `ω` in the base frame),
        /// then the joints'.
        pub const DOF: usize = #nl;
        /// Number of coordinates: the floating base's seven (position in the world, unit
        /// quaternion `(qx, qy, qz, qw)` base → world), then the joints'.
        pub const NQ: usize = #nq;
        /// Generalized speed names, in the order of `u`.
        pub const SPEED_NAMES: [&str; #nl] = [#(#speed_names),*];
        /// Coordinate names, in the order of `q`.
        pub const COORDINATE_NAMES: [&str; #nq] = [#(#coord_names),*];
        #parents

        /// Index constants: of each coordinate in `q` (`Q_HIP`, `BASE_QW`) and of each speed in
        /// `u`, `u̇` and `τ` (`QD_HIP`, `BASE_WX`). A joint's coordinate is one place after its
        /// speed (the base's quaternion has four entries for three speeds).
        pub mod index {
            #(#index_consts)*
        }
    }
}

fn param_doc(p: &kanegen_model::Param) -> String {
    let what = match p.kind {
        ParamKind::Length => "length (m)",
        ParamKind::Gravity => "gravity acceleration (m/s²)",
        ParamKind::Inertial => match p.name.chars().next() {
            Some('m') => "mass (kg)",
            Some('M') => "first moment m·S (kg·m)",
            _ => "inertia about the frame origin (kg·m²)",
        },
        ParamKind::Wheel => "wheel constant",
    };
    format!(" `{}`: {} (default {:?}).", p.name, what, p.value)
}

/// `Params` (runtime mode): one field per model parameter, access by name, arrays.
pub(super) fn params(cx: &Context<'_>) -> TokenStream {
    let model = cx.model;
    let np = idx(model.params.len());
    let t = scalar_type(cx.precision);
    let ids: Vec<Ident> = model.params.iter().map(|p| ident(&p.name)).collect();
    let docs = model.params.iter().map(param_doc);
    let values = model
        .params
        .iter()
        .map(|p| signed_lit(p.value, cx.precision));
    let names: Vec<&str> = model.params.iter().map(|p| p.name.as_str()).collect();
    let validate = validate(cx);
    let checks = set_checks(model);
    let source = format!(
        " Model parameters of `{}`, named with the reports' symbols; `Default` holds the values of `{}`.",
        model.name,
        file_name(&model.source)
    );
    quote! {
        pub use kanegen_runtime::{SetParameterError, UnknownParameter};

        /// Number of model parameters.
        pub const PARAM_COUNT: usize = #np;

        #[doc = #source]
        ///
        /// With the `serde` feature of `kanegen-runtime`: `Serialize` and `Deserialize`, as a
        /// map from name to value (missing names keep their defaults, unknown names are errors).
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub struct Params {
            #(#[doc = #docs] pub #ids: #t,)*
        }

        kanegen_runtime::params_serde!(Params, #t);

        impl Default for Params {
            fn default() -> Self {
                Self { #(#ids: #values,)* }
            }
        }

        impl Params {
            /// Parameter names in declaration order (the order of [`Params::to_array`]).
            pub const NAMES: [&'static str; #np] = [#(#names),*];

            /// The value of parameter `name`, or `None` if the model has no such parameter.
            pub fn get(&self, name: &str) -> Option<#t> {
                match name {
                    #(#names => Some(self.#ids),)*
                    _ => None,
                }
            }

            /// Set parameter `name` to `value`.
            ///
            /// # Errors
            /// [`SetParameterError::Unknown`] if the model has no such parameter (nothing is
            /// changed); [`SetParameterError::Invalid`] if `value` is not finite, or is a mass,
            /// wheel radius, track width or wheel mass that is not positive, or a wheel inertia
            /// that is negative (nothing is changed). The checks that involve several
            /// parameters at once (a body's inertia) are [`Params::validate`]'s.
            pub fn set(&mut self, name: &str, value: #t) -> Result<(), SetParameterError> {
                use kanegen_runtime::validate as v;
                let slot = match name {
                    #(#names => &mut self.#ids,)*
                    _ => return Err(UnknownParameter::new(name).into()),
                };
                let x = f64::from(value);
                v::check_finite(&[name], &[x])?;
                #checks
                *slot = value;
                Ok(())
            }

            /// All values in the order of [`Params::NAMES`].
            pub fn to_array(&self) -> [#t; #np] {
                [#(self.#ids),*]
            }

            /// Parameters from values in the order of [`Params::NAMES`].
            pub fn from_array(v: [#t; #np]) -> Self {
                let [#(#ids),*] = v;
                Self { #(#ids),* }
            }

            #validate
        }
    }
}

/// The sign checks `Params::set` makes on the value `x` (an `f64`) of parameter `name`: what
/// `Params::validate` requires of that parameter alone (positive masses, wheel radius, track and
/// wheel mass; non-negative wheel inertias).
fn set_checks(model: &Model) -> TokenStream {
    let name = |id: usize| model.params[id].name.as_str();
    let mut positive: Vec<&str> = model
        .links
        .iter()
        .filter_map(|l| l.body.as_ref())
        .map(|b| name(b.mass))
        .collect();
    let mut non_negative = Vec::new();
    if let Some(w) = model.wheeled_base() {
        positive.extend([w.radius, w.track, w.wheel_mass].map(name));
        non_negative.extend([w.wheel_axle_inertia, w.wheel_diametral_inertia].map(name));
    }
    let arm = |names: &[&str], check: TokenStream| {
        (!names.is_empty()).then(|| quote!(#(#names)|* => #check(name, x)?,))
    };
    let positive = arm(&positive, quote!(v::check_positive));
    let non_negative = arm(&non_negative, quote!(v::check_non_negative));
    quote! {
        match name {
            #positive
            #non_negative
            _ => {}
        }
    }
}

/// `Params::validate`: every value finite, then the checks of each body and of the wheels.
fn validate(cx: &Context<'_>) -> TokenStream {
    let model = cx.model;
    let field = |id: usize| {
        let f = ident(&model.params[id].name);
        quote!(f64::from(self.#f))
    };
    let rel_tol = match cx.precision {
        crate::options::Precision::F64 => 1e-9,
        crate::options::Precision::F32 => 1e-5,
    };
    let bodies = model.links.iter().filter_map(|l| l.body.as_ref()).map(|b| {
        let name = b.name.as_str();
        let mass_name = model.params[b.mass].name.as_str();
        let m = field(b.mass);
        let ms = b.first_moment.map(field);
        let j = b.inertia.map(field);
        quote!(v::check_body(#name, #mass_name, #m, [#(#ms),*], [#(#j),*], #rel_tol)?;)
    });
    let wheels = model.wheeled_base().map(|w| {
        let positive = [w.radius, w.track, w.wheel_mass].map(|id| {
            let (name, value) = (model.params[id].name.as_str(), field(id));
            quote!(v::check_positive(#name, #value)?;)
        });
        let non_negative = [w.wheel_axle_inertia, w.wheel_diametral_inertia].map(|id| {
            let (name, value) = (model.params[id].name.as_str(), field(id));
            quote!(v::check_non_negative(#name, #value)?;)
        });
        quote!(#(#positive)* #(#non_negative)*)
    });
    quote! {
        /// Checks that the parameters describe a physical robot: every value finite, every
        /// body's mass positive and its inertia about the centre of mass within the triangle
        /// inequalities (`kanegen_runtime::validate::check_body`), the wheel radius, track and
        /// wheel mass positive and the wheel inertias non-negative.
        ///
        /// # Errors
        /// The first violation, as a [`kanegen_runtime::InvalidParameter`] naming the
        /// parameter (or the body).
        pub fn validate(&self) -> Result<(), kanegen_runtime::InvalidParameter> {
            use kanegen_runtime::validate as v;
            v::check_finite(&Self::NAMES, &self.to_array())?;
            #(#bodies)*
            #wheels
            Ok(())
        }
    }
}

/// `Precomputed` (runtime mode): the parameter-only terms, computed once per parameter set.
pub(super) fn precomputed(cx: &Context<'_>) -> TokenStream {
    let p: &Program = &cx.low.precompute;
    let t = scalar_type(cx.precision);
    let printer = cx.printer(&p.stmts);
    let body = printer.statements(&[]);
    // Two slots can read one statement (a parameter-only variable and its definition, both
    // requested): one field each statement.
    let mut seen = std::collections::HashSet::new();
    let fields: Vec<Ident> = cx
        .pre
        .iter()
        .filter(|s| seen.insert(s.as_str()))
        .map(|s| ident(s))
        .collect();
    let pname = if uses(p, &|l| matches!(l, Leaf::Param(_))) {
        quote!(p)
    } else {
        quote!(_p)
    };
    let ops = format!(" Generated straight-line code: {}.", p.ops);
    quote! {
        /// Parameter-only subexpressions of the dynamics, computed once per parameter set.
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub struct Precomputed {
            #(#fields: #t,)*
        }

        impl Precomputed {
            /// Compute the parameter-only terms for `p`.
            #[doc = ""]
            #[doc = #ops]
            pub fn new(#pname: &Params) -> Self {
                #body
                Self { #(#fields),* }
            }
        }
    }
}

/// A call of the free function of `spec` from a method of the wrapper.
fn forward_call(cx: &Context<'_>, spec: &FunctionSpec) -> TokenStream {
    let f = ident(spec.name);
    let mut args = arg_names(spec.inputs);
    if spec.per_frame {
        args.extend(quote!(, frame));
    }
    let pass = wrapper_params(cx);
    quote!(#f(#pass #args))
}

/// One method of the wrapper per generated function.
fn methods(cx: &Context<'_>) -> TokenStream {
    cx.low
        .functions
        .iter()
        // One method per function (a per-frame function has one program per frame).
        .filter(|f| f.frame.is_none_or(|l| l == 0))
        .map(|f| {
            let spec = f.id.spec();
            let name = ident(spec.name);
            let doc = format!(" {}", spec.doc);
            let (mut args, _) = state_args(cx, spec.inputs);
            if spec.per_frame {
                args.extend(quote!(, frame: Frame));
            }
            let ret = return_type(cx, spec);
            let call = forward_call(cx, spec);
            let into = super::body::has_into(f).then(|| {
                let into = ident(&format!("{}_into", spec.name));
                let doc = format!(
                    " [`{0}`](Self::{0}) written into `out` (every entry), without returning the \
                     matrix by value.",
                    spec.name
                );
                let names = arg_names(spec.inputs);
                let pass = wrapper_params(cx);
                quote! {
                    #[doc = #doc]
                    #[inline]
                    pub fn #into(&self, #args, out: &mut #ret) {
                        #into(#pass #names, out)
                    }
                }
            });
            quote! {
                #[doc = #doc]
                #[inline]
                pub fn #name(&self, #args) -> #ret {
                    #call
                }
                #into
            }
        })
        .collect()
}

/// The wrapper type named after the model: with runtime parameters it holds a parameter set and
/// its precomputed terms; baked, it is a unit struct.
pub(super) fn wrapper(cx: &Context<'_>, batched: bool) -> TokenStream {
    let model = cx.model;
    let ty = ident(&naming::type_name(&model.name));
    let mut methods = methods(cx);
    methods.extend(super::combined::methods(cx));
    methods.extend(super::regressor_loop::methods(cx));
    methods.extend(super::derivatives_loop::methods(cx));
    if cx.low.floating {
        methods.extend(configuration_methods(cx));
    }
    if batched {
        methods.extend(super::batch::methods(cx));
    }
    if !cx.low.params.is_runtime() {
        let doc = format!(
            " The dynamics of `{}` with the parameter values of `{}` folded in as constants.",
            model.name,
            file_name(&model.source)
        );
        return quote! {
            #[doc = #doc]
            ///
            /// The evaluation methods are allocation-free and cannot fail.
            #[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
            pub struct #ty;

            impl #ty {
                #methods
            }
        };
    }
    let doc = format!(
        " The dynamics of `{}` with one parameter set: `τ = M(q) u̇ + c(q, u) + g(q)`.",
        model.name
    );
    quote! {
        #[doc = #doc]
        ///
        /// Construction precomputes the parameter-only terms; the evaluation methods are
        /// allocation-free and cannot fail.
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub struct #ty {
            params: Params,
            pre: Precomputed,
        }

        impl Default for #ty {
            fn default() -> Self {
                Self::new(Params::default())
            }
        }

        impl #ty {
            /// The model with parameter set `params`.
            pub fn new(params: Params) -> Self {
                Self { pre: Precomputed::new(&params), params }
            }

            /// The parameter set.
            pub fn params(&self) -> &Params {
                &self.params
            }

            /// Replace the parameter set (recomputes the parameter-only terms).
            pub fn set_params(&mut self, params: Params) {
                *self = Self::new(params);
            }

            #methods
        }
    }
}

/// The `kanegen-runtime` traits whose functions the module has all of.
pub(super) fn trait_impls(cx: &Context<'_>) -> TokenStream {
    if cx.low.floating {
        return floating_trait_impl(cx);
    }
    let ty = ident(&naming::type_name(&cx.model.name));
    let t = scalar_type(cx.precision);
    let mut out = TokenStream::new();
    let mut implemented = Vec::new();
    for tr in RuntimeTrait::ALL {
        let specs: Vec<&FunctionSpec> = crate::registry::FUNCTIONS
            .iter()
            .filter(|s| s.runtime_trait == Some(tr))
            .collect();
        let complete = specs
            .iter()
            .all(|s| cx.low.functions.iter().any(|f| f.id == s.id));
        // A trait's supertrait (RobotDynamics) must be implemented first.
        let supertrait_ok =
            tr == RuntimeTrait::RobotDynamics || implemented.contains(&RuntimeTrait::RobotDynamics);
        if !complete || !supertrait_ok {
            continue;
        }
        implemented.push(tr);
        let trait_name = ident(tr.name());
        let items = specs.iter().map(|spec| {
            let name = ident(spec.name);
            let (args, _) = state_args(cx, spec.inputs);
            let call = forward_call(cx, spec);
            if tr == RuntimeTrait::InverseDynamicsDerivatives {
                // The trait cannot name an N × 2N matrix (no `2 * N` in a const generic): its
                // method returns the two square blocks, copied as slices (column-major, they
                // are consecutive; a view's `into_owned` copies entry by entry through a
                // strided iterator).
                let n = idx(cx.low.dof);
                let nn = idx(cx.low.dof * cx.low.dof);
                return quote! {
                    fn inverse_dynamics_partials(&self, #args)
                        -> (SMatrix<#t, #n, #n>, SMatrix<#t, #n, #n>)
                    {
                        let d = #call;
                        let (d_q, d_u) = d.as_slice().split_at(#nn);
                        let mut blocks = (
                            SMatrix::<#t, #n, #n>::zeros(),
                            SMatrix::<#t, #n, #n>::zeros(),
                        );
                        blocks.0.as_mut_slice().copy_from_slice(d_q);
                        blocks.1.as_mut_slice().copy_from_slice(d_u);
                        blocks
                    }
                };
            }
            let ret = return_type(cx, spec);
            quote!(fn #name(&self, #args) -> #ret { #call })
        });
        let assoc = if tr == RuntimeTrait::RobotDynamics {
            let q_ty = quote!(SVector<#t, DOF>);
            let parents = super::speed_parents::trait_items(cx, &q_ty);
            quote! {
                type Scalar = #t;
                const SPEED_NAMES: [&'static str; DOF] = SPEED_NAMES;
                const COORDINATE_NAMES: [&'static str; DOF] = COORDINATE_NAMES;
                #parents
            }
        } else {
            quote!()
        };
        out.extend(quote! {
            impl kanegen_runtime::#trait_name<DOF> for #ty {
                #assoc
                #(#items)*
            }
        });
    }
    out
}

/// A floating base's configuration-space methods of the wrapper (`kanegen_runtime::free_flyer`).
fn configuration_methods(cx: &Context<'_>) -> TokenStream {
    let t = scalar_type(cx.precision);
    quote! {
        /// The neutral configuration: the base at the world origin with the identity quaternion,
        /// the joints at zero (`pinocchio::neutral`).
        #[inline]
        pub fn neutral(&self) -> SVector<#t, NQ> {
            kanegen_runtime::free_flyer::neutral()
        }
        /// `q ⊕ u dt`: the base moves by the SE(3) exponential of its twist `(v, ω) dt` in the
        /// base frame, the joints by `u dt` (`pinocchio::integrate`); the quaternion stays unit.
        #[inline]
        pub fn integrate(&self, q: &SVector<#t, NQ>, u: &SVector<#t, DOF>, dt: #t) -> SVector<#t, NQ> {
            kanegen_runtime::free_flyer::integrate(q, u, dt)
        }
        /// The speeds `δ` with `integrate(q0, δ, 1) = q1`: the SE(3) logarithm of the relative
        /// base pose and the joints' differences (`pinocchio::difference`).
        #[inline]
        pub fn difference(&self, q0: &SVector<#t, NQ>, q1: &SVector<#t, NQ>) -> SVector<#t, DOF> {
            kanegen_runtime::free_flyer::difference(q0, q1)
        }
        /// `q` with the base's quaternion scaled to unit norm (`pinocchio::normalize`).
        #[inline]
        pub fn normalize(&self, q: &SVector<#t, NQ>) -> SVector<#t, NQ> {
            kanegen_runtime::free_flyer::normalize(q)
        }
    }
}

/// A floating base's `kanegen_runtime::Multibody` implementation, when the module has M, c, g
/// and τ (it cannot implement `RobotDynamics`, whose `q` has `DOF` entries).
fn floating_trait_impl(cx: &Context<'_>) -> TokenStream {
    let complete = crate::registry::FUNCTIONS
        .iter()
        .filter(|s| s.runtime_trait == Some(RuntimeTrait::RobotDynamics))
        .all(|s| cx.low.functions.iter().any(|f| f.id == s.id));
    if !complete {
        return TokenStream::new();
    }
    let ty = ident(&naming::type_name(&cx.model.name));
    let t = scalar_type(cx.precision);
    let forward = |name: &str, inputs| {
        let spec = crate::registry::FUNCTIONS
            .iter()
            .find(|s| s.name == name)
            .expect("registry function");
        let f = ident(name);
        let (args, _) = state_args(cx, inputs);
        let ret = return_type(cx, spec);
        let call = forward_call(cx, spec);
        quote!(fn #f(&self, #args) -> #ret { #call })
    };
    use crate::registry::Inputs;
    let parents = super::speed_parents::trait_items(cx, &quote!(SVector<#t, NQ>));
    let methods = [
        forward("mass_matrix", Inputs::Q),
        forward("coriolis", Inputs::QU),
        forward("gravity", Inputs::Q),
        forward("inverse_dynamics", Inputs::QUUd),
    ];
    quote! {
        impl kanegen_runtime::Multibody<DOF> for #ty {
            type Scalar = #t;
            type Configuration = SVector<#t, NQ>;
            const SPEED_NAMES: [&'static str; DOF] = SPEED_NAMES;
            const COORDINATE_NAMES: &'static [&'static str] = &COORDINATE_NAMES;
            #parents
            fn neutral(&self) -> SVector<#t, NQ> {
                kanegen_runtime::free_flyer::neutral()
            }
            fn integrate(&self, q: &SVector<#t, NQ>, u: &SVector<#t, DOF>, dt: #t) -> SVector<#t, NQ> {
                kanegen_runtime::free_flyer::integrate(q, u, dt)
            }
            fn difference(&self, q0: &SVector<#t, NQ>, q1: &SVector<#t, NQ>) -> SVector<#t, DOF> {
                kanegen_runtime::free_flyer::difference(q0, q1)
            }
            fn normalize(&self, q: &SVector<#t, NQ>) -> SVector<#t, NQ> {
                kanegen_runtime::free_flyer::normalize(q)
            }
            #(#methods)*
        }
    }
}
