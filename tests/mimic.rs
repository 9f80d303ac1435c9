//! Mimic joints as exact constraints (`models/mimic_gripper.urdf`: prismatic and revolute
//! fingers with multipliers −1 and 0.5, an offset, a mimic of a mimic, an independent joint below
//! a mimic joint). The reduced dynamics — the generator's derivation, its lowered programs and
//! the compiled module — against the unconstrained tree of the reference recursion projected by
//! hand with the constraint map `T` (`q_all = T q + b`, `u_all = T u`): `M = Tᵀ M_all T`,
//! `c = Tᵀ c_all`, `g = Tᵀ g_all`, `τ = Tᵀ τ_all`; the Coriolis matrix by `C u = c` and
//! `Ṁ − 2C` skew-symmetric; frame Jacobians against `J_all T` of the model imported with
//! `MimicMode::Independent`; the import modes; and a mimic with multiplier 0 against the joint
//! imported as fixed at its offset.

mod common;

use common::*;
use kanegen::model::{MimicMode, Model, ModelErrorKind, UrdfImport, UrdfOptions};
use kanegen::{Builder, FunctionId, FunctionSet, Generated, Options};
use kanegen_reference::Reference;
use kanegen_reference::random::random_physical_params;
use nalgebra::{DMatrix, DVector};

#[allow(dead_code)] // the test uses only part of the module
mod gripper {
    include!(concat!(env!("OUT_DIR"), "/mimic_gripper_all.rs"));
}

const TOL: f64 = 1e-11;

fn load(mode: MimicMode) -> Model {
    let options = UrdfOptions {
        mimic: mode,
        ..UrdfOptions::default()
    };
    Model::from_urdf_file(root().join("models/mimic_gripper.urdf"), &options).expect("imports")
}

fn generated(model: &Model) -> Generated {
    let options = Options {
        functions: FunctionSet::all(),
        ..Options::default()
    };
    Builder::from_model(model.clone())
        .options(options)
        .generate()
        .expect("generates")
}

/// The constraint map written out from the URDF's `<mimic>` elements (not from the library's
/// helpers): `T` (all speeds × independent speeds) and `b`, by joint name.
fn constraint_map(model: &Model) -> (DMatrix<f64>, DVector<f64>) {
    let (n_all, n) = (model.dof(), model.independent_dof());
    let speed = |joint: &str| {
        model
            .speeds
            .iter()
            .position(|s| s.name == format!("qd_{joint}"))
            .expect("speed")
    };
    let mut t = DMatrix::zeros(n_all, n);
    for i in 0..n {
        t[(i, i)] = 1.0;
    }
    let mut b = DVector::zeros(n_all);
    let lk = speed("left_knuckle");
    // right_finger = −left_finger; right_knuckle = −left_knuckle;
    // left_inner = 0.5 left_knuckle + 0.1; right_inner = right_knuckle − 0.2 = −left_knuckle − 0.2.
    t[(speed("right_finger"), speed("left_finger"))] = -1.0;
    t[(speed("right_knuckle"), lk)] = -1.0;
    t[(speed("left_inner"), lk)] = 0.5;
    b[speed("left_inner")] = 0.1;
    t[(speed("right_inner"), lk)] = -1.0;
    b[speed("right_inner")] = -0.2;
    (t, b)
}

fn flat(m: &DMatrix<f64>) -> Vec<f64> {
    (0..m.nrows())
        .flat_map(|r| (0..m.ncols()).map(move |c| m[(r, c)]))
        .collect()
}

#[test]
fn import_keeps_five_independent_speeds_and_four_constraints() {
    let m = load(MimicMode::Exact);
    assert_eq!((m.dof(), m.independent_dof(), m.mimics.len()), (9, 5, 4));
    let names: Vec<&str> = m.speeds[..5].iter().map(|s| s.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "qd_shoulder",
            "qd_elbow",
            "qd_left_finger",
            "qd_right_tip",
            "qd_left_knuckle"
        ]
    );
    assert_eq!(gripper::DOF, 5);
    assert_eq!(gripper::SPEED_NAMES, names.as_slice());
    // Independent: every joint its own speed; Fixed: the mimic joints are fixed.
    let ind = load(MimicMode::Independent);
    assert_eq!((ind.dof(), ind.mimics.len()), (9, 0));
    let fixed = load(MimicMode::Fixed);
    assert_eq!((fixed.dof(), fixed.mimics.len()), (5, 0));
}

#[test]
fn reduced_dynamics_equal_the_unconstrained_tree_projected_by_the_constraint_map() {
    let model = load(MimicMode::Exact);
    let g = generated(&model);
    let (t, b) = constraint_map(&model);
    let n = model.independent_dof();
    let mut r = rng(15);
    let mut worst = [0.0f64; 4];
    for draw in 0..100 {
        let p = if draw == 0 {
            model.param_values()
        } else {
            random_physical_params(&model, &mut r)
        };
        let (q, u, ud) = random_state(&mut r, n);
        let (qv, uv, udv) = (
            DVector::from_column_slice(&q),
            DVector::from_column_slice(&u),
            DVector::from_column_slice(&ud),
        );
        let qa = &t * &qv + &b;
        let (ua, uda) = (&t * &uv, &t * &udv);
        // The reference recursion reads the model without its constraints: the whole tree.
        let reference = Reference::<f64>::with_params(&model, &p);
        let m_all = reference.mass_matrix(qa.as_slice());
        let expected = [
            flat(&(t.transpose() * m_all * &t)),
            (t.transpose() * reference.coriolis(qa.as_slice(), ua.as_slice()))
                .as_slice()
                .to_vec(),
            (t.transpose() * reference.gravity(qa.as_slice()))
                .as_slice()
                .to_vec(),
            (t.transpose()
                * reference.inverse_dynamics(qa.as_slice(), ua.as_slice(), uda.as_slice()))
            .as_slice()
            .to_vec(),
        ];
        let ids = [
            FunctionId::MassMatrix,
            FunctionId::Coriolis,
            FunctionId::Gravity,
            FunctionId::InverseDynamics,
        ];
        // The compiled module.
        let k = gripper::MimicGripper::new(gripper::Params::from_array(
            p.clone().try_into().expect("91 parameters"),
        ));
        let (qs, us, uds) = (sv::<5>(&q), sv::<5>(&u), sv::<5>(&ud));
        let compiled = [
            rows(&k.mass_matrix(&qs)),
            k.coriolis(&qs, &us).as_slice().to_vec(),
            k.gravity(&qs).as_slice().to_vec(),
            k.inverse_dynamics(&qs, &us, &uds).as_slice().to_vec(),
        ];
        for (i, id) in ids.iter().enumerate() {
            let d = g.derivation.evaluate(*id, &p, &q, &u, &ud);
            let l = g.lowered.evaluate(*id, &p, &q, &u, &ud);
            worst[i] = worst[i]
                .max(rel_err(&d, &expected[i], 1.0))
                .max(rel_err(&l, &expected[i], 1.0))
                .max(rel_err(&compiled[i], &expected[i], 1.0));
        }
        // C u = c and Ṁ − 2C skew-symmetric (Ṁ by central differences of M along u).
        let c_mat = g
            .lowered
            .evaluate(FunctionId::CoriolisMatrix, &p, &q, &u, &ud);
        let cu: Vec<f64> = (0..n)
            .map(|i| (0..n).map(|j| c_mat[i * n + j] * u[j]).sum())
            .collect();
        assert!(rel_err(&cu, &expected[1], 1.0) < TOL, "C u = c");
        let compiled_c = rows(&k.coriolis_matrix(&qs, &us));
        assert!(rel_err(&compiled_c, &c_mat, 1.0) < TOL, "compiled C");
        let mdot = mdot_central(
            &|q: &[f64]| g.lowered.evaluate(FunctionId::MassMatrix, &p, q, &u, &ud),
            &q,
            &u,
            1e-3,
        );
        assert!(skew_defect(&mdot, &c_mat, n, 1.0) < 1e-8, "Ṁ − 2C skew");
    }
    eprintln!("worst relative errors M, c, g, τ: {worst:?}");
    for (w, name) in worst.iter().zip(["M", "c", "g", "τ"]) {
        assert!(*w < TOL, "{name}: {w}");
    }
}

/// Regression: the batched functions of a model with mimic joints (whose dependent joints'
/// sines and cosines are indexed past the independent speeds) are generated — the generator
/// panicked ("index out of bounds: the len is 5 but the index is 7") — and give, in every lane
/// of both layouts, the single-state function's bits with the same instruction set.
#[test]
fn batched_functions_of_a_model_with_mimic_joints_equal_the_single_state_ones() {
    use kanegen_runtime::lanes::{soa, state};
    let model = load(MimicMode::Exact);
    let mut uniform = rng(17);
    for _ in 0..20 {
        let p = random_physical_params(&model, &mut uniform);
        let k = gripper::MimicGripper::new(gripper::Params::from_array(
            p.try_into().expect("91 parameters"),
        ));
        let states: [_; 3] = std::array::from_fn(|_| {
            let (q, u, _) = random_state(&mut uniform, 5);
            (sv::<5>(&q), sv::<5>(&u))
        });
        let (q, u) = (states.map(|s| s.0), states.map(|s| s.1));
        let (m, c) = (k.mass_matrix_batch(&q), k.coriolis_batch(&q, &u));
        let (ms, cs) = (
            k.mass_matrix_batch_soa(&soa(&q)),
            k.coriolis_batch_soa(&soa(&q), &soa(&u)),
        );
        for l in 0..3 {
            let (m1, c1) = (k.mass_matrix(&q[l]), k.coriolis(&q[l], &u[l]));
            assert!(same_bits(m[l].as_slice(), m1.as_slice()), "M lane {l}");
            assert!(same_bits(c[l].as_slice(), c1.as_slice()), "c lane {l}");
            assert!(
                same_bits(state(&ms, l).as_slice(), m1.as_slice()),
                "SoA M lane {l}"
            );
            assert!(
                same_bits(state(&cs, l).as_slice(), c1.as_slice()),
                "SoA c lane {l}"
            );
        }
    }
}

#[test]
fn frame_jacobians_are_the_independent_models_times_the_constraint_map() {
    let exact = load(MimicMode::Exact);
    let ind = load(MimicMode::Independent);
    let (ge, gi) = (generated(&exact), generated(&ind));
    let (t, b) = constraint_map(&exact);
    // The independent model's speeds in the order of the exact model's.
    let perm: Vec<usize> = exact
        .speeds
        .iter()
        .map(|s| ind.speed_index(&s.name).expect("same speeds"))
        .collect();
    let n = exact.independent_dof();
    let mut r = rng(16);
    for _ in 0..50 {
        let p = random_physical_params(&exact, &mut r);
        let pi: Vec<f64> = ind
            .params
            .iter()
            .map(|x| p[exact.param_index(&x.name).expect("same parameters")])
            .collect();
        let (q, u, _) = random_state(&mut r, n);
        let qa = &t * DVector::from_column_slice(&q) + &b;
        let ua = &t * DVector::from_column_slice(&u);
        let mut qi = vec![0.0; ind.dof()];
        let mut ui = vec![0.0; ind.dof()];
        for (s, &k) in perm.iter().enumerate() {
            qi[k] = qa[s];
            ui[k] = ua[s];
        }
        for l in 0..exact.links.len() {
            let li = ind.link_index(&exact.links[l].name).expect("same frames");
            let je = ge
                .lowered
                .evaluate_at(FunctionId::FrameJacobian, Some(l), &p, &q, &u, &[]);
            let ji =
                gi.lowered
                    .evaluate_at(FunctionId::FrameJacobian, Some(li), &pi, &qi, &ui, &[]);
            let ji = DMatrix::from_row_slice(6, ind.dof(), &ji);
            let mut ji_sorted = DMatrix::zeros(6, exact.dof());
            for (s, &k) in perm.iter().enumerate() {
                ji_sorted.set_column(s, &ji.column(k));
            }
            let expected = flat(&(ji_sorted * &t));
            assert!(rel_err(&je, &expected, 1.0) < TOL, "frame {l}");
            for id in [FunctionId::FramePose, FunctionId::FrameBiasAcceleration] {
                let a = ge.lowered.evaluate_at(id, Some(l), &p, &q, &u, &[]);
                let b = gi.lowered.evaluate_at(id, Some(li), &pi, &qi, &ui, &[]);
                assert!(rel_err(&a, &b, 1.0) < TOL, "{id} of frame {l}");
            }
        }
        for id in [FunctionId::KineticEnergy, FunctionId::PotentialEnergy] {
            let a = ge.lowered.evaluate(id, &p, &q, &u, &[]);
            let b = gi.lowered.evaluate(id, &pi, &qi, &ui, &[]);
            assert!(rel_err(&a, &b, 1.0) < TOL, "{id}");
        }
    }
}

fn gripper_with(joint_line: &str) -> Result<UrdfImport, kanegen::model::ModelError> {
    let text = std::fs::read_to_string(root().join("models/mimic_gripper.urdf")).expect("reads");
    let text = text.replace(
        r#"<mimic joint="left_knuckle" multiplier="0.5" offset="0.1"/>"#,
        joint_line,
    );
    UrdfImport::parse(&text, "gripper.urdf", &UrdfOptions::default())
}

#[test]
fn bad_mimics_are_typed_errors_naming_the_joint() {
    let cases = [
        (r#"<mimic joint="no_such_joint"/>"#, "not a moving joint"),
        (r#"<mimic joint="wrist"/>"#, "not a moving joint"),
        (r#"<mimic joint="left_inner"/>"#, "cycle"),
    ];
    for (line, expect) in cases {
        let err = gripper_with(line).expect_err(line);
        let text = err.to_string();
        assert!(
            matches!(&err.kind, ModelErrorKind::UrdfBadMimic { .. }) && text.contains(expect),
            "{line}: {text}"
        );
    }
    // A non-finite multiplier is caught with the file's other numbers.
    let err = gripper_with(r#"<mimic joint="left_knuckle" multiplier="nan"/>"#).expect_err("nan");
    assert!(
        matches!(&err.kind, ModelErrorKind::UrdfBadNumber { .. })
            && err.to_string().contains("multiplier"),
        "{err}"
    );
    // A mimic of a mimic composes (left_inner = right_knuckle = −left_knuckle).
    let ok = gripper_with(r#"<mimic joint="right_knuckle"/>"#).expect("imports");
    let m = &ok.model;
    let li = m.speed_index("qd_left_inner").expect("speed");
    let mm = m.mimic_of(li).expect("dependent");
    assert_eq!(
        (m.speeds[mm.master].name.as_str(), mm.multiplier, mm.offset),
        ("qd_left_knuckle", -1.0, 0.0)
    );
    assert!(
        ok.notes
            .iter()
            .any(|n| n.contains("mimic joint `left_inner`"))
    );
}

/// `[∂τ/∂q | ∂τ/∂u]` of the reduced model (columns: the independent speeds; the chain rule
/// through `q_dep = a q_master + b` included) against central differences of the reduced τ.
#[test]
fn inverse_dynamics_derivatives_of_the_reduced_model_match_central_differences() {
    let model = load(MimicMode::Exact);
    let g = generated(&model);
    let n = model.independent_dof();
    let mut r = rng(0x31A1C);
    for draw in 0..20 {
        let p = if draw == 0 {
            model.param_values()
        } else {
            random_physical_params(&model, &mut r)
        };
        let (q, u, ud) = random_state(&mut r, n);
        let d = g
            .lowered
            .evaluate(FunctionId::InverseDynamicsDerivatives, &p, &q, &u, &ud);
        assert_eq!(d.len(), n * 2 * n);
        let tau = |q: &[f64], u: &[f64]| {
            g.lowered
                .evaluate(FunctionId::InverseDynamics, &p, q, u, &ud)
        };
        let h = 1e-6;
        for j in 0..2 * n {
            let (mut qa, mut qb, mut ua, mut ub) = (q.clone(), q.clone(), u.clone(), u.clone());
            if j < n {
                qa[j] += h;
                qb[j] -= h;
            } else {
                ua[j - n] += h;
                ub[j - n] -= h;
            }
            let (ta, tb) = (tau(&qa, &ua), tau(&qb, &ub));
            for i in 0..n {
                let fd = (ta[i] - tb[i]) / (2.0 * h);
                let exact = d[i * 2 * n + j];
                assert!(
                    (exact - fd).abs() <= 1e-6 * (1.0 + fd.abs()),
                    "draw {draw}: d tau_{i} / d x_{j}: {exact} vs {fd}"
                );
            }
        }
    }
}

#[test]
fn a_mimic_with_multiplier_zero_is_the_joint_fixed_at_its_offset() {
    // `q_k = 0 · q_j + 0.3`: the exact constraint leaves one speed and holds k at 0.3 rad, which
    // is what importing the mimic joint as fixed at its offset gives (its child then merges into
    // the parent link, so the two models have different parameters but the same dynamics).
    let inertial = |m: f64| {
        format!(
            r#"<inertial><origin xyz="0.1 0.05 0"/><mass value="{m}"/><inertia ixx="0.02" iyy="0.03" izz="0.04" ixy="0" ixz="0" iyz="0"/></inertial>"#
        )
    };
    let urdf = format!(
        r#"<robot name="r"><link name="a"/>
        <link name="b">{}</link><link name="c">{}</link>
        <joint name="j" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/>
          <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
        <joint name="k" type="revolute"><parent link="b"/><child link="c"/><origin xyz="1 0 0"/>
          <axis xyz="0 1 0"/><mimic joint="j" multiplier="0" offset="0.3"/>
          <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
        </robot>"#,
        inertial(1.5),
        inertial(0.7)
    );
    let import = |mimic| {
        let options = UrdfOptions {
            mimic,
            ..UrdfOptions::default()
        };
        Model::from_urdf_str(&urdf, "mimic0.urdf", &options).expect("imports")
    };
    let (exact, fixed) = (import(MimicMode::Exact), import(MimicMode::Fixed));
    assert_eq!((exact.independent_dof(), fixed.independent_dof()), (1, 1));
    let (ge, gf) = (generated(&exact), generated(&fixed));
    let (pe, pf) = (exact.param_values(), fixed.param_values());
    let mut r = rng(23);
    for _ in 0..50 {
        let (q, u, ud) = random_state(&mut r, 1);
        for id in [
            FunctionId::MassMatrix,
            FunctionId::Coriolis,
            FunctionId::Gravity,
            FunctionId::InverseDynamics,
        ] {
            let e = ge.lowered.evaluate(id, &pe, &q, &u, &ud);
            let f = gf.lowered.evaluate(id, &pf, &q, &u, &ud);
            let err = rel_err(&e, &f, 1.0);
            assert!(err <= TOL, "{id:?} at q = {q:?}: {err:e}");
        }
    }
}
