//! The regressors (opt-in registry functions) through the derivation's and the lowering's
//! evaluators, on Krang (wheeled base), the fixed-wheel tree, the two-link model and the URDF
//! arm, with random parameters and states:
//!
//! * `Y π = τ` and `Y_g β = g` (the generated τ and g) to 1e-12 relative;
//! * Y and Y_g do not depend on π: no inertial parameter reaches them (structurally), and two
//!   random parameter sets give the same Y bit for bit;
//! * every column of Y is `∂τ/∂π_p` by central differences of τ in the parameter;
//! * `Y_b π_b = τ` and `Y_gb β_b = g`; the base regressor of 50 random states has full column
//!   rank B, and B is the rank of the stacked full regressors (SVD); the grouping residual;
//! * the two-link model of the fixed-wheels report (Zafar 2014), Appendix B: its base parameters by hand;
//! * with baked parameters the regressors equal the runtime ones at the model's values.

use kanegen::model::{Model, UrdfOptions};
use kanegen::{Builder, FunctionId, FunctionSet, Generated, Options, ParamMode};
use kanegen_reference::random::{SplitMix64, random_physical_params, uniform_vec};
use nalgebra::DMatrix;
use std::sync::OnceLock;

fn models_dir() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("models")
}

fn load(name: &str) -> Model {
    let path = models_dir().join(name);
    if name.ends_with(".urdf") {
        Model::from_urdf_file(&path, &UrdfOptions::default()).expect("URDF imports")
    } else {
        Model::from_toml_file(&path).expect("model loads")
    }
}

fn generated(model: &Model, params: ParamMode) -> Generated {
    let options = Options {
        functions: FunctionSet::regressors()
            .with(FunctionId::InverseDynamics)
            .with(FunctionId::Gravity),
        params,
    };
    Builder::from_model(model.clone())
        .options(options)
        .generate()
        .expect("generates")
}

/// The model `MODELS[i]` and its runtime-parameter generation, made once per test binary.
fn cached(i: usize) -> &'static (Model, Generated) {
    static CACHE: [OnceLock<(Model, Generated)>; 4] = [const { OnceLock::new() }; 4];
    CACHE[i].get_or_init(|| {
        let model = load(MODELS[i]);
        let g = generated(&model, ParamMode::Runtime);
        (model, g)
    })
}

const MODELS: [&str; 4] = [
    "krang.toml",
    "krang-fixed-wheels.toml",
    "two-link.toml",
    "singlearm.urdf",
];

/// `max |a − b| / max(max |b|, 1)`.
fn rel_err(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    let scale = b.iter().fold(1.0f64, |m, x| m.max(x.abs()));
    a.iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
        / scale
}

/// `A x` for a row-major `rows × cols` matrix.
fn mat_vec(a: &[f64], cols: usize, x: &[f64]) -> Vec<f64> {
    a.chunks(cols)
        .map(|row| row.iter().zip(x).map(|(p, q)| p * q).sum())
        .collect()
}

struct Draw {
    params: Vec<f64>,
    q: Vec<f64>,
    u: Vec<f64>,
    ud: Vec<f64>,
}

/// Random physical parameters, with the model file's geometry (lengths, g, wheel radius and
/// track) when `geometry` is set (the base parameters' grouping coefficients are the model
/// file's), and a random state.
fn draw_with(model: &Model, uniform: &mut impl FnMut() -> f64, geometry: bool) -> Draw {
    let n = model.dof();
    let mut params = random_physical_params(model, uniform);
    if geometry {
        let regression: Vec<usize> = kanegen::kane::Regressors::of(model).inertial;
        for (i, p) in model.params.iter().enumerate() {
            if !regression.contains(&i) {
                params[i] = p.value;
            }
        }
    }
    Draw {
        params,
        q: uniform_vec(uniform, n, -3.0, 3.0),
        u: uniform_vec(uniform, n, -2.0, 2.0),
        ud: uniform_vec(uniform, n, -2.0, 2.0),
    }
}

fn draw(model: &Model, uniform: &mut impl FnMut() -> f64) -> Draw {
    draw_with(model, uniform, false)
}

#[test]
fn regressor_times_inertial_parameters_equals_inverse_dynamics_and_gravity() {
    for (m, name) in MODELS.iter().enumerate() {
        let (model, g) = cached(m);
        let reg = &g.derivation.regressors;
        let mut r = SplitMix64::new(7 + m as u64);
        let mut uniform = move || r.next_f64();
        let mut worst: f64 = 0.0;
        for _ in 0..if m == 0 { 30 } else { 100 } {
            let d = draw(model, &mut uniform);
            let pi: Vec<f64> = reg.inertial.iter().map(|&p| d.params[p]).collect();
            let beta: Vec<f64> = reg.beta.iter().map(|&p| d.params[p]).collect();
            for low in [false, true] {
                let eval = |id| {
                    if low {
                        g.lowered.evaluate(id, &d.params, &d.q, &d.u, &d.ud)
                    } else {
                        g.derivation.evaluate(id, &d.params, &d.q, &d.u, &d.ud)
                    }
                };
                let tau = eval(FunctionId::InverseDynamics);
                let y = eval(FunctionId::InverseDynamicsRegressor);
                worst = worst.max(rel_err(&mat_vec(&y, pi.len(), &pi), &tau));
                let grav = eval(FunctionId::Gravity);
                let yg = eval(FunctionId::GravityRegressor);
                worst = worst.max(rel_err(&mat_vec(&yg, beta.len(), &beta), &grav));
            }
        }
        println!("{name}: Y π = τ, Y_g β = g to {worst:.1e}");
        assert!(worst <= 1e-12, "{name}: {worst:e}");
    }
}

#[test]
fn regressors_do_not_depend_on_the_inertial_parameters() {
    for (m, name) in MODELS.iter().enumerate() {
        let (model, g) = cached(m);
        let reg = &g.derivation.regressors;
        // Structurally: no regression parameter is reachable from an entry.
        let ar = &g.derivation.arena;
        for f in &g.derivation.functions {
            if f.id == FunctionId::InverseDynamics || f.id == FunctionId::Gravity {
                continue;
            }
            let roots: Vec<_> = f.entries.iter().map(|e| e.2).collect();
            let needed = ar.reachable_vars(&roots);
            let mut defs: Vec<_> = roots.clone();
            defs.extend(
                ar.vars()
                    .iter()
                    .enumerate()
                    .filter(|(i, _)| needed[*i])
                    .map(|(_, v)| v.def),
            );
            let inertial: std::collections::HashSet<&str> = reg
                .inertial
                .iter()
                .map(|&p| model.params[p].name.as_str())
                .collect();
            for e in defs {
                let text = ar.display(e);
                let mentioned = text
                    .split(|c: char| !(c.is_alphanumeric() || c == '_'))
                    .find(|w| inertial.contains(w));
                assert!(
                    mentioned.is_none(),
                    "{name}: {} mentions {mentioned:?}: {text}",
                    f.id
                );
            }
        }
        // Numerically: two parameter sets with the same lengths and g, the same Y.
        let mut r = SplitMix64::new(70 + m as u64);
        let mut uniform = move || r.next_f64();
        let d = draw(model, &mut uniform);
        let mut other = random_physical_params(model, &mut uniform);
        for (i, o) in other.iter_mut().enumerate() {
            if !reg.inertial.contains(&i) {
                *o = d.params[i];
            }
        }
        for id in [
            FunctionId::InverseDynamicsRegressor,
            FunctionId::GravityRegressor,
            FunctionId::BaseRegressor,
        ] {
            let a = g.lowered.evaluate(id, &d.params, &d.q, &d.u, &d.ud);
            let b = g.lowered.evaluate(id, &other, &d.q, &d.u, &d.ud);
            assert_eq!(a, b, "{name}: {id}");
        }
    }
}

#[test]
fn regressor_columns_are_the_derivatives_of_tau_in_each_parameter() {
    for (m, name) in MODELS.iter().enumerate().skip(2) {
        let (model, g) = cached(m);
        let reg = &g.derivation.regressors;
        let mut r = SplitMix64::new(170 + m as u64);
        let mut uniform = move || r.next_f64();
        let d = draw(model, &mut uniform);
        let y = g.lowered.evaluate(
            FunctionId::InverseDynamicsRegressor,
            &d.params,
            &d.q,
            &d.u,
            &d.ud,
        );
        let cols = reg.inertial.len();
        for (c, &p) in reg.inertial.iter().enumerate() {
            let tau_at = |h: f64| {
                let mut params = d.params.clone();
                params[p] += h;
                g.lowered
                    .evaluate(FunctionId::InverseDynamics, &params, &d.q, &d.u, &d.ud)
            };
            let (hi, lo) = (tau_at(1e-3), tau_at(-1e-3));
            for row in 0..model.dof() {
                let fd = (hi[row] - lo[row]) / 2e-3;
                let exact = y[row * cols + c];
                assert!(
                    (fd - exact).abs() <= 1e-7 * (1.0 + exact.abs()),
                    "{name}: Y[{row}, {}] = {exact} vs {fd}",
                    model.params[p].name
                );
            }
        }
    }
}

/// The rank of `a` by SVD (singular values above `1e-9` of the largest).
fn rank(a: &DMatrix<f64>) -> usize {
    let sv = a.clone().svd(false, false).singular_values;
    let max = sv.iter().fold(0.0f64, |m, x| m.max(*x));
    sv.iter().filter(|s| **s > 1e-9 * max).count()
}

#[test]
fn base_regressors_have_full_column_rank_and_reproduce_tau_and_g() {
    for (m, name) in MODELS.iter().enumerate() {
        let (model, g) = cached(m);
        let reg = &g.derivation.regressors;
        let (base, base_beta) = (reg.base.as_ref().unwrap(), reg.base_beta.as_ref().unwrap());
        assert!(
            base.check_residual <= 1e-12,
            "{name}: {}",
            base.check_residual
        );
        assert!(base_beta.check_residual <= 1e-12, "{name}");
        let n = model.dof();
        let (p, b) = (reg.inertial.len(), base.names.len());
        let (pg, bg) = (reg.beta.len(), base_beta.names.len());
        let mut r = SplitMix64::new(270 + m as u64);
        let mut uniform = move || r.next_f64();
        let states = 50;
        let mut full = DMatrix::zeros(states * n, p);
        let mut based = DMatrix::zeros(states * n, b);
        let mut full_g = DMatrix::zeros(states * n, pg);
        let mut based_g = DMatrix::zeros(states * n, bg);
        let mut worst: f64 = 0.0;
        for s in 0..states {
            let d = draw_with(model, &mut uniform, true);
            let pi: Vec<f64> = reg.inertial.iter().map(|&i| d.params[i]).collect();
            let beta: Vec<f64> = reg.beta.iter().map(|&i| d.params[i]).collect();
            let eval = |id| g.lowered.evaluate(id, &d.params, &d.q, &d.u, &d.ud);
            let y = eval(FunctionId::InverseDynamicsRegressor);
            let yb = eval(FunctionId::BaseRegressor);
            let yg = eval(FunctionId::GravityRegressor);
            let ygb = eval(FunctionId::BaseGravityRegressor);
            let tau = eval(FunctionId::InverseDynamics);
            let grav = eval(FunctionId::Gravity);
            worst = worst.max(rel_err(&mat_vec(&yb, b, &base.values(&pi)), &tau));
            worst = worst.max(rel_err(&mat_vec(&ygb, bg, &base_beta.values(&beta)), &grav));
            for row in 0..n {
                for c in 0..p {
                    full[(s * n + row, c)] = y[row * p + c];
                }
                for c in 0..b {
                    based[(s * n + row, c)] = yb[row * b + c];
                }
                for c in 0..pg {
                    full_g[(s * n + row, c)] = yg[row * pg + c];
                }
                for c in 0..bg {
                    based_g[(s * n + row, c)] = ygb[row * bg + c];
                }
            }
        }
        println!("{name}: B = {b} of {p}, gravity {bg} of {pg}; Y_b π_b = τ to {worst:.1e}");
        assert!(worst <= 1e-12, "{name}: {worst:e}");
        assert_eq!(rank(&based), b, "{name}: base regressor rank");
        assert_eq!(rank(&full), b, "{name}: full regressor rank");
        assert_eq!(rank(&based_g), bg, "{name}: base gravity regressor rank");
        assert_eq!(rank(&full_g), bg, "{name}: full gravity regressor rank");
    }
}

#[test]
fn two_link_base_parameters_are_the_hand_derived_groupings() {
    // Appendix B of the fixed-wheels report (Zafar 2014): both axes along −x, 1P2 = [0, L1, −L2]. The motion is planar about
    // x: only XX, MY, MZ act; body 2's mass is a point mass at 1P2 for body 1 (grouped into
    // MY1, MZ1 and XX1 with the parallel-axis term L1² + L2²); body 1's mass has no effect.
    let (model, g) = cached(2);
    let reg = &g.derivation.regressors;
    let base = reg.base.as_ref().unwrap();
    let value = |n: &str| model.params[model.param_index(n).unwrap()].value;
    let (l1, l2) = (value("L1"), value("L2"));
    let pos = |n: &str| {
        reg.inertial
            .iter()
            .position(|&p| model.params[p].name == n)
            .unwrap()
    };
    let expect: Vec<(&str, Vec<(usize, f64)>)> = vec![
        ("MYR1", vec![(pos("MY1"), 1.0), (pos("m2"), l1)]),
        ("MZR1", vec![(pos("MZ1"), 1.0), (pos("m2"), -l2)]),
        (
            "XXR1",
            vec![(pos("XX1"), 1.0), (pos("m2"), l1 * l1 + l2 * l2)],
        ),
        ("MY2", vec![(pos("MY2"), 1.0)]),
        ("MZ2", vec![(pos("MZ2"), 1.0)]),
        ("XX2", vec![(pos("XX2"), 1.0)]),
    ];
    assert_eq!(base.names.len(), expect.len(), "{:?}", base.names);
    for ((name, group), (en, eg)) in base.names.iter().zip(&base.groups).zip(&expect) {
        assert_eq!(name, en);
        assert_eq!(group.len(), eg.len(), "{name}: {group:?}");
        for ((i, c), (ei, ec)) in group.iter().zip(eg) {
            assert_eq!(i, ei, "{name}");
            assert!((c - ec).abs() <= 1e-12, "{name}: {c} vs {ec}");
        }
    }
    let without: Vec<&str> = base
        .unidentifiable
        .iter()
        .map(|&i| model.params[reg.inertial[i]].name.as_str())
        .collect();
    assert_eq!(
        without,
        [
            "m1", "MX1", "XY1", "XZ1", "YY1", "YZ1", "ZZ1", "MX2", "XY2", "XZ2", "YY2", "YZ2",
            "ZZ2"
        ]
    );
    // The gravity regressor's: m2 grouped into MY1 and MZ1.
    let bb = reg.base_beta.as_ref().unwrap();
    assert_eq!(bb.names, ["MYR1", "MZR1", "MY2", "MZ2"]);
    // The same groupings as expressions of the lengths, as derived by hand.
    let text: Vec<String> = base
        .names
        .iter()
        .zip(&base.symbolic)
        .map(|(n, g)| kanegen::kane::symbolic_group_text(model, &reg.inertial, n, g))
        .collect();
    assert_eq!(
        text,
        [
            "MYR1 = MY1 + L1*m2",
            "MZR1 = MZ1 - L2*m2",
            "XXR1 = XX1 + (L1^2 + L2^2)*m2",
            "MY2 = MY2",
            "MZ2 = MZ2",
            "XX2 = XX2"
        ]
    );
    // … and their values for any lengths.
    let mut rng = SplitMix64::new(31);
    let mut values = model.param_values();
    let (i1, i2) = (
        model.param_index("L1").unwrap(),
        model.param_index("L2").unwrap(),
    );
    for _ in 0..20 {
        let (l1, l2) = (0.1 + 1.9 * rng.next_f64(), 2.0 * rng.next_f64() - 1.0);
        values[i1] = l1;
        values[i2] = l2;
        let coef = |g: usize, member: &str| {
            base.symbolic[g]
                .iter()
                .find(|(i, _)| *i == pos(member))
                .map(|(_, c)| c.eval(&values))
                .unwrap()
        };
        assert!((coef(0, "m2") - l1).abs() <= 1e-15);
        assert!((coef(1, "m2") + l2).abs() <= 1e-15);
        assert!((coef(2, "m2") - (l1 * l1 + l2 * l2)).abs() <= 1e-14);
    }
}

/// The regressor entries `(row, col, expr)` of function `id`.
fn entries(g: &Generated, id: FunctionId) -> &[(usize, usize, kanegen::expr::ExprId)] {
    &g.derivation.function(id).unwrap().entries
}

/// Whether every grouping of `groups` holds exactly at `points` random points (modular
/// arithmetic, every leaf random: q on the unit circle, u, u̇ and every parameter, lengths
/// included), and the columns without effect vanish: per group, whether it held.
fn exact_identity(
    model: &Model,
    g: &Generated,
    id: FunctionId,
    cols: usize,
    groups: &[kanegen::kane::SymbolicGroup],
    without: &[usize],
    points: usize,
) -> Vec<bool> {
    use kanegen::expr::modular::{self, ModValues};
    let n = model.dof();
    let mut rng = SplitMix64::new(77);
    let mut draw = || (rng.next_u64() >> 3) % modular::P;
    let mut ok = vec![true; groups.len() + 1];
    let mut done = 0;
    while done < points {
        let params: Vec<u64> = (0..model.params.len()).map(|_| draw()).collect();
        let sin_cos: Option<Vec<_>> = (0..n).map(|_| modular::circle_point(draw())).collect();
        let (q, u, ud): (Vec<u64>, Vec<u64>, Vec<u64>) = (
            (0..n).map(|_| draw()).collect(),
            (0..n).map(|_| draw()).collect(),
            (0..n).map(|_| draw()).collect(),
        );
        let Some(sin_cos) = sin_cos else { continue };
        let Some(vals) = g.derivation.arena.eval_mod(&ModValues {
            params: &params,
            sin_cos: &sin_cos,
            q: &q,
            u: &u,
            ud: &ud,
        }) else {
            continue;
        };
        let mut y = vec![0u64; n * cols];
        for &(r, c, e) in entries(g, id) {
            y[r * cols + c] = modular::add(y[r * cols + c], vals[e.index()]);
        }
        // π in the direction that leaves τ unchanged: a group's value is Σ coef · π_member,
        // so Σ_groups Y_kept · value = Y π for every π: check it for unit vectors of every
        // dependent member, i.e. Y_member = Σ_groups coef_member Y_kept.
        for r in 0..n {
            let yr = &y[r * cols..(r + 1) * cols];
            let mut members: Vec<usize> = groups
                .iter()
                .flat_map(|g| g.iter().skip(1).map(|(i, _)| *i))
                .collect();
            members.sort_unstable();
            members.dedup();
            for m in members {
                let mut res = yr[m];
                let mut involved = Vec::new();
                for (gi, grp) in groups.iter().enumerate() {
                    if let Some((_, c)) = grp.iter().skip(1).find(|(i, _)| *i == m) {
                        let c = c.eval_mod(&params).unwrap();
                        res = modular::add(res, modular::neg(modular::mul(c, yr[grp[0].0])));
                        involved.push(gi);
                    }
                }
                if res != 0 {
                    for gi in involved {
                        ok[gi] = false;
                    }
                }
            }
            ok[groups.len()] &= without.iter().all(|&c| yr[c] == 0);
        }
        done += 1;
    }
    ok
}

#[test]
fn every_grouping_is_an_exact_identity_in_the_configuration_and_the_geometry() {
    // Krang, the fixed-wheel tree and the two-link model have symbolic lengths and exact
    // rotations: every grouping coefficient is an expression of the lengths (and R, L) and the
    // groupings hold exactly for any geometry. Checked here independently of the generator's
    // own check, which must agree.
    for (i, file) in MODELS.iter().enumerate().take(3) {
        let (model, g) = cached(i);
        let reg = &g.derivation.regressors;
        for (base, params, id) in [
            (
                reg.base.as_ref().unwrap(),
                &reg.inertial,
                FunctionId::InverseDynamicsRegressor,
            ),
            (
                reg.base_beta.as_ref().unwrap(),
                &reg.beta,
                FunctionId::GravityRegressor,
            ),
        ] {
            let name = format!("{file} {id}");
            let ex = &base.exactness;
            assert_eq!(ex.skipped, None, "{name}");
            assert!(ex.numeric_only.is_empty(), "{name}: {:?}", ex.numeric_only);
            assert_eq!(ex.verified, ex.dependencies, "{name}");
            assert_eq!(
                ex.dependencies,
                params.len() - base.names.len(),
                "{name}: every column is kept, grouped or without effect"
            );
            let ok = exact_identity(
                model,
                g,
                id,
                params.len(),
                &base.symbolic,
                &base.unidentifiable,
                2,
            );
            assert!(ok.iter().all(|&b| b), "{name}: {ok:?}");
            // At the model file's geometry the expressions are the numeric coefficients.
            let values = model.param_values();
            for (sym, num) in base.symbolic.iter().zip(&base.groups) {
                for &(i, c) in num {
                    let s = sym.iter().find(|(j, _)| *j == i).unwrap().1.eval(&values);
                    assert!(
                        (s - c).abs() <= 1e-12 * c.abs().max(1.0),
                        "{name}: {s} vs {c}"
                    );
                }
            }
        }
    }
}

#[test]
fn the_exact_identity_check_rejects_a_wrong_grouping_coefficient() {
    // Krang's XXR1 = XX1 + (L1² + L2²) m2 + …: a coefficient off in one length (L1² + L3²),
    // or off by a rounding-sized amount, is not an identity.
    let (model, g) = cached(0);
    let reg = &g.derivation.regressors;
    let base = reg.base.as_ref().unwrap();
    let xx = base.names.iter().position(|n| n == "XXR1").unwrap();
    let m2 = reg
        .inertial
        .iter()
        .position(|&p| model.params[p].name == "m2")
        .unwrap();
    let (l2, l3) = (
        model.param_index("L2").unwrap(),
        model.param_index("L3").unwrap(),
    );
    let check = |groups: &[kanegen::kane::SymbolicGroup]| {
        exact_identity(
            model,
            g,
            FunctionId::InverseDynamicsRegressor,
            reg.inertial.len(),
            groups,
            &base.unidentifiable,
            1,
        )[xx]
    };
    assert!(check(&base.symbolic));
    let mut wrong = base.symbolic.clone();
    let member = wrong[xx].iter_mut().find(|(i, _)| *i == m2).unwrap();
    assert_eq!(member.1.text(model), "L1^2 + L2^2");
    for t in &mut member.1.terms {
        for f in &mut t.1 {
            if f.0 == l2 {
                f.0 = l3;
            }
        }
    }
    assert!(!check(&wrong));
    let mut wrong = base.symbolic.clone();
    let member = wrong[xx].iter_mut().find(|(i, _)| *i == m2).unwrap();
    member.1.terms[0].0 *= 1.0 + f64::EPSILON;
    assert!(!check(&wrong));
}

#[test]
fn krang_wheel_parameters_group_into_the_base_body() {
    // The wheels enter only through 2 mw + 2 YYw/R² (ẋ) and mw L²/2 + YYw L²/(2R²) + 2 ZZw (ψ̇):
    // linear, and no wheel parameter is identifiable alone.
    let (model, g) = cached(0);
    let reg = &g.derivation.regressors;
    let base = reg.base.as_ref().unwrap();
    let wheel = |n: &str| {
        let p = model.param_index(n).unwrap();
        reg.inertial.iter().position(|&i| i == p).unwrap()
    };
    for w in ["mw", "YYw", "ZZw"] {
        let i = wheel(w);
        assert!(
            base.groups.iter().all(|g| g[0].0 != i),
            "{w} is not a base parameter of its own"
        );
        assert!(
            base.groups.iter().any(|g| g.iter().any(|&(j, _)| j == i)),
            "{w} acts"
        );
    }
    let value = |n: &str| model.params[model.param_index(n).unwrap()].value;
    let r = value("R");
    let m_group = &base.groups[0];
    let coef = |i: usize| m_group.iter().find(|&&(j, _)| j == i).map(|&(_, c)| c);
    assert_eq!(coef(wheel("mw")), Some(2.0));
    assert!((coef(wheel("YYw")).unwrap() - 2.0 / (r * r)).abs() < 1e-12);
}

#[test]
fn baked_regressors_equal_the_runtime_ones_at_the_model_values() {
    for (i, name) in [(2, "two-link.toml"), (1, "krang-fixed-wheels.toml")] {
        let (model, runtime) = cached(i);
        let model = model.clone();
        let baked = generated(&model, ParamMode::Baked);
        let params = model.param_values();
        let n = model.dof();
        let q: Vec<f64> = (0..n).map(|i| 0.3 * i as f64 - 1.1).collect();
        let u: Vec<f64> = (0..n).map(|i| 0.8 - 0.1 * i as f64).collect();
        let ud: Vec<f64> = (0..n).map(|i| 0.05 * i as f64 - 0.4).collect();
        for id in FunctionSet::regressors().iter() {
            let a = runtime.lowered.evaluate(id, &params, &q, &u, &ud);
            let b = baked.lowered.evaluate(id, &params, &q, &u, &ud);
            assert!(rel_err(&b, &a) <= 1e-13, "{name}: {id}");
        }
        assert_eq!(
            runtime.derivation.regressors.base.as_ref().unwrap().names,
            baked.derivation.regressors.base.as_ref().unwrap().names
        );
    }
}

/// Least squares `A x = b` (QR of the stacked rows) and the estimate's standard deviations from
/// the residual variance.
fn least_squares(a: &DMatrix<f64>, b: &nalgebra::DVector<f64>) -> (Vec<f64>, Vec<f64>, f64) {
    let x = a
        .clone()
        .svd(true, true)
        .solve(b, 1e-12)
        .expect("SVD solves");
    let r = a * &x - b;
    let dof = (a.nrows() - a.ncols()) as f64;
    let sigma2 = r.norm_squared() / dof;
    let cov = (a.transpose() * a).try_inverse().expect("full column rank");
    let std = (0..a.ncols())
        .map(|i| (sigma2 * cov[(i, i)]).sqrt())
        .collect();
    (x.iter().copied().collect(), std, sigma2.sqrt())
}

/// Identify the base parameters from `samples` (state, measured generalized forces) with the
/// base regressor `id`: the estimate, its standard deviations and the residual's RMS.
fn identify(
    g: &Generated,
    id: FunctionId,
    params: &[f64],
    samples: &[(Draw, Vec<f64>)],
) -> (Vec<f64>, Vec<f64>, f64) {
    let n = g.model.dof();
    let b = g.lowered.sizes.size_of(id);
    let mut a = DMatrix::zeros(samples.len() * n, b);
    let mut rhs = nalgebra::DVector::zeros(samples.len() * n);
    for (s, (d, tau)) in samples.iter().enumerate() {
        let y = g.lowered.evaluate(id, params, &d.q, &d.u, &d.ud);
        for row in 0..n {
            for c in 0..b {
                a[(s * n + row, c)] = y[row * b + c];
            }
            rhs[s * n + row] = tau[row];
        }
    }
    least_squares(&a, &rhs)
}

/// Gaussian noise (Box–Muller) of standard deviation `sigma`.
fn gauss(uniform: &mut impl FnMut() -> f64, sigma: f64) -> f64 {
    let (a, b) = (uniform().max(1e-300), uniform());
    sigma * (-2.0 * a.ln()).sqrt() * (std::f64::consts::TAU * b).cos()
}

#[test]
fn krang_beta_vector_is_identified_from_static_poses() {
    // As the lab did on hardware: static poses (u = u̇ = 0), the measured torques are g(q) plus
    // noise; here also the pitch is measured with noise. 120 poses.
    let (model, g) = cached(0);
    let reg = &g.derivation.regressors;
    let base = reg.base_beta.as_ref().unwrap();
    let mut r = SplitMix64::new(404);
    let mut uniform = move || r.next_f64();
    let truth = draw_with(model, &mut uniform, true).params;
    let beta: Vec<f64> = reg.beta.iter().map(|&p| truth[p]).collect();
    let expect = base.values(&beta);
    let n = model.dof();
    for (torque_noise, pitch_noise) in [(0.0, 0.0), (0.5, 2e-3)] {
        let mut samples = Vec::new();
        for _ in 0..120 {
            let q = uniform_vec(&mut uniform, n, -1.5, 1.5);
            let zero = vec![0.0; n];
            let mut tau = g
                .lowered
                .evaluate(FunctionId::Gravity, &truth, &q, &zero, &zero);
            tau.iter_mut()
                .for_each(|t| *t += gauss(&mut uniform, torque_noise));
            let mut measured = q.clone();
            measured[2] += gauss(&mut uniform, pitch_noise); // q_imu
            samples.push((
                Draw {
                    params: truth.clone(),
                    q: measured,
                    u: zero.clone(),
                    ud: zero,
                },
                tau,
            ));
        }
        let (est, std, rms) = identify(g, FunctionId::BaseGravityRegressor, &truth, &samples);
        let what = format!(
            "Krang β_b ({} of {}), noise {torque_noise} N·m, {pitch_noise} rad",
            expect.len(),
            beta.len()
        );
        assert_recovered(&what, (&est, &std, rms), &expect, torque_noise == 0.0);
    }
}

/// The estimates `est` (standard deviations `std`, residual RMS `rms`) of an identification
/// against the true values `expect`: without noise to 1e-9 relative (of `max(|x|, 1e-2)`),
/// with noise every estimate within 5 standard deviations.
fn assert_recovered(
    what: &str,
    (est, std, rms): (&[f64], &[f64], f64),
    expect: &[f64],
    noiseless: bool,
) {
    let worst_sigma = est
        .iter()
        .zip(expect)
        .zip(std)
        .map(|((e, x), s)| (e - x).abs() / s.max(1e-300))
        .fold(0.0f64, f64::max);
    let worst_rel = est
        .iter()
        .zip(expect)
        .map(|(e, x)| (e - x).abs() / x.abs().max(1e-2))
        .fold(0.0f64, f64::max);
    println!(
        "{what}: residual RMS {rms:.2e}, worst error {worst_rel:.1e} relative, {worst_sigma:.1} σ"
    );
    if noiseless {
        assert!(worst_rel <= 1e-9, "{worst_rel:e}");
    } else {
        assert!(worst_sigma <= 5.0, "{worst_sigma}");
    }
}

#[test]
fn fixed_wheel_base_parameters_are_identified_from_an_exciting_trajectory() {
    // Every joint follows a sum of three sinusoids (a Fourier excitation); τ = Y_b π_b + noise.
    let (model, g) = cached(1);
    let reg = &g.derivation.regressors;
    let base = reg.base.as_ref().unwrap();
    let mut r = SplitMix64::new(505);
    let mut uniform = move || r.next_f64();
    let truth = draw_with(model, &mut uniform, true).params;
    let pi: Vec<f64> = reg.inertial.iter().map(|&p| truth[p]).collect();
    let expect = base.values(&pi);
    let n = model.dof();
    let coef: Vec<[(f64, f64); 3]> = (0..n)
        .map(|_| [0; 3].map(|_| (uniform() - 0.5, 2.0 * uniform() + 0.3)))
        .collect();
    for noise in [0.0, 0.2] {
        let samples: Vec<(Draw, Vec<f64>)> = (0..300)
            .map(|k| {
                let t = 0.02 * k as f64;
                let (mut q, mut u, mut ud) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
                for j in 0..n {
                    for &(a, w) in &coef[j] {
                        q[j] += a * (w * t).sin();
                        u[j] += a * w * (w * t).cos();
                        ud[j] -= a * w * w * (w * t).sin();
                    }
                }
                let mut tau = g
                    .lowered
                    .evaluate(FunctionId::InverseDynamics, &truth, &q, &u, &ud);
                tau.iter_mut()
                    .for_each(|x| *x += gauss(&mut uniform, noise));
                (
                    Draw {
                        params: truth.clone(),
                        q,
                        u,
                        ud,
                    },
                    tau,
                )
            })
            .collect();
        let (est, std, rms) = identify(g, FunctionId::BaseRegressor, &truth, &samples);
        let what = format!(
            "fixed wheels π_b ({} of {}), noise {noise} N·m",
            expect.len(),
            pi.len()
        );
        assert_recovered(&what, (&est, &std, rms), &expect, noise == 0.0);
    }
}

#[test]
fn stats_and_listing_print_the_base_parameters() {
    let (_, g) = cached(2);
    let stats = kanegen::stats(g);
    assert!(
        stats.contains("base parameters of the inverse-dynamics regressor: 6 of 20"),
        "{stats}"
    );
    assert!(stats.contains("  XXR1 = XX1 + (L1^2 + L2^2)*m2"), "{stats}");
    assert!(
        stats.contains("14 of 14 dependencies verified exactly"),
        "{stats}"
    );
    assert!(stats.contains("base parameters of the gravity regressor: 4 of 8"));
    let listing = kanegen::listing(g);
    assert!(listing.contains("% MYR1 = MY1 + L1*m2"), "{listing}");
    // Without base regressors nothing is printed.
    let model = load("two-link.toml");
    let plain = Builder::from_model(model).generate().unwrap();
    assert!(!kanegen::stats(&plain).contains("base parameters"));
}
