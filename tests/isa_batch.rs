//! Run-time instruction-set dispatch and batched evaluation: the x86-64-v3 copy of
//! every generated function (which fuses multiply-adds) agrees with the baseline copy to
//! rounding, and every batched function gives, in every lane, the bits of the single-state
//! function *with the same instruction set* (the same statements, multiply-add chains included,
//! in a loop over the states): for batch sizes 1, 3 (odd), 4 and 8, with every instruction set
//! the CPU has (on an AVX-512 CPU also x86-64-v4, where the batched functions run their AVX-512
//! copy and the single-state ones their x86-64-v3 copy: the same fused operations), on random
//! parameter sets and states (angles of all sizes, including a huge one that takes the slow
//! sin/cos path in one lane). The `_into` forms write every entry of the caller's
//! results (filled with NaN before the call) and give the by-value forms' bits. The
//! structure-of-arrays forms (`*_batch_soa`, at 3 and 8 states) give the array-of-states
//! forms' bits in every lane. Batched forward dynamics (`forward_dynamics_batch_soa_into`,
//! `forward_dynamics_batch`; Krang and the fixed-wheel tree) gives `forward_dynamics`' bits in
//! every lane, NaN lanes included. The looped derivatives' x86-64-v4 copies (straight-line
//! part and loop) give their x86-64-v3 copies' bits.

mod common;

use common::*;
use kanegen_model::Model;
use kanegen_reference::random::random_physical_params;
use krang_dynamics as kd;
use krang_dynamics::isa::{self, Isa};
use nalgebra::SVector;

type V = SVector<f64, 19>;

/// A cart on a horizontal rail (root `build.rs`, every registry function and the batched
/// forms): c, g and C are structurally zero, and the gravity regressor has no base parameter.
/// Warnings are denied (dead code aside: the test uses part of the module), so a function with
/// nothing to compute (single state or batched) must not, for example, bind a variable it never
/// reads or writes.
#[allow(dead_code)] // the test uses only part of the module
#[deny(warnings)]
mod slider {
    include!(concat!(env!("OUT_DIR"), "/slider.rs"));
}

fn krang(model: &Model, uniform: &mut impl FnMut() -> f64) -> kd::Krang {
    let p = random_physical_params(model, uniform);
    kd::Krang::new(kd::Params::from_array(p.try_into().unwrap()))
}

fn states<const L: usize>(uniform: &mut impl FnMut() -> f64) -> ([V; L], [V; L], [V; L]) {
    let mut q = [V::zeros(); L];
    let mut u = [V::zeros(); L];
    let mut ud = [V::zeros(); L];
    for l in 0..L {
        let (a, b, c) = random_state(uniform, 19);
        (q[l], u[l], ud[l]) = (sv(&a), sv(&b), sv(&c));
    }
    (q, u, ud)
}

/// The instruction set is global ([`isa::select`]) and the tests of this file select it: one
/// at a time.
static ISA: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn isa_lock() -> std::sync::MutexGuard<'static, ()> {
    ISA.lock().unwrap_or_else(|e| e.into_inner())
}

/// Every batched function of `k` at `L` states (with the active instruction set) equals its
/// single-state function with the same instruction set in each lane, and its `_into` form
/// writes the same bits over a result array filled with NaN.
fn check_batch<const L: usize>(k: &kd::Krang, q: &[V; L], u: &[V; L], ud: &[V; L]) {
    let m = k.mass_matrix_batch(q);
    let c = k.coriolis_batch(q, u);
    let g = k.gravity_batch(q);
    let t = k.inverse_dynamics_batch(q, u, ud);
    let cm = k.coriolis_matrix_batch(q, u);
    let mb = kd::baked::mass_matrix_batch(q);
    let tb = kd::baked::inverse_dynamics_batch(q, u, ud);
    for l in 0..L {
        let (ql, ul, udl) = (&q[l], &u[l], &ud[l]);
        assert!(
            same_bits(m[l].as_slice(), k.mass_matrix(ql).as_slice()),
            "M lane {l} of {L}"
        );
        assert!(
            same_bits(c[l].as_slice(), k.coriolis(ql, ul).as_slice()),
            "c lane {l}"
        );
        assert!(
            same_bits(g[l].as_slice(), k.gravity(ql).as_slice()),
            "g lane {l}"
        );
        let tl = k.inverse_dynamics(ql, ul, udl);
        assert!(same_bits(t[l].as_slice(), tl.as_slice()), "τ lane {l}");
        let cml = k.coriolis_matrix(ql, ul);
        assert!(same_bits(cm[l].as_slice(), cml.as_slice()), "C lane {l}");
        let mbl = kd::baked::mass_matrix(ql);
        assert!(
            same_bits(mb[l].as_slice(), mbl.as_slice()),
            "baked M lane {l}"
        );
        let tbl = kd::baked::inverse_dynamics(ql, ul, udl);
        assert!(
            same_bits(tb[l].as_slice(), tbl.as_slice()),
            "baked τ lane {l}"
        );
    }
    // The `_into` forms: every entry written (NaN before), the by-value forms' bits.
    let flat = |a: &[nalgebra::SMatrix<f64, 19, 19>]| -> Vec<f64> {
        a.iter().flat_map(|m| m.iter().copied()).collect()
    };
    let flat_v = |a: &[V]| -> Vec<f64> { a.iter().flat_map(|v| v.iter().copied()).collect() };
    let mut mi = [nalgebra::SMatrix::<f64, 19, 19>::from_element(f64::NAN); L];
    k.mass_matrix_batch_into(q, &mut mi);
    assert!(same_bits(&flat(&mi), &flat(&m)), "M into, {L} states");
    let mut cmi = [nalgebra::SMatrix::<f64, 19, 19>::from_element(f64::NAN); L];
    k.coriolis_matrix_batch_into(q, u, &mut cmi);
    assert!(same_bits(&flat(&cmi), &flat(&cm)), "C into");
    kd::baked::mass_matrix_batch_into(q, &mut mi);
    assert!(same_bits(&flat(&mi), &flat(&mb)), "baked M into");
    let mut vi = [V::from_element(f64::NAN); L];
    k.coriolis_batch_into(q, u, &mut vi);
    assert!(same_bits(&flat_v(&vi), &flat_v(&c)), "c into");
    let mut vi = [V::from_element(f64::NAN); L];
    k.gravity_batch_into(q, &mut vi);
    assert!(same_bits(&flat_v(&vi), &flat_v(&g)), "g into");
    let mut vi = [V::from_element(f64::NAN); L];
    k.inverse_dynamics_batch_into(q, u, ud, &mut vi);
    assert!(same_bits(&flat_v(&vi), &flat_v(&t)), "τ into");
    let mut vi = [V::from_element(f64::NAN); L];
    kd::baked::inverse_dynamics_batch_into(q, u, ud, &mut vi);
    assert!(same_bits(&flat_v(&vi), &flat_v(&tb)), "baked τ into");
}

/// Every structure-of-arrays batched function (`*_batch_soa`, inputs and results in lanes)
/// gives, in lane `l` of every entry, the bits of the array-of-states form's result `l` (which
/// [`check_batch`] compares with the single-state function), and its `_into` form writes every
/// entry of a NaN-filled result with the by-value form's bits.
fn check_soa<const L: usize>(k: &kd::Krang, q: &[V; L], u: &[V; L], ud: &[V; L]) {
    use kd::lanes::{Lanes, soa, state};
    let (qs, us, uds) = (soa(q), soa(u), soa(ud));
    let lanes = |name: &str, a: &[f64], b: &[f64]| assert!(same_bits(a, b), "{name}, {L} states");
    let m = k.mass_matrix_batch_soa(&qs);
    let c = k.coriolis_batch_soa(&qs, &us);
    let g = k.gravity_batch_soa(&qs);
    let t = k.inverse_dynamics_batch_soa(&qs, &us, &uds);
    let cm = k.coriolis_matrix_batch_soa(&qs, &us);
    let mb = kd::baked::mass_matrix_batch_soa(&qs);
    let tb = kd::baked::inverse_dynamics_batch_soa(&qs, &us, &uds);
    let (m0, c0, g0) = (
        k.mass_matrix_batch(q),
        k.coriolis_batch(q, u),
        k.gravity_batch(q),
    );
    let (t0, cm0) = (
        k.inverse_dynamics_batch(q, u, ud),
        k.coriolis_matrix_batch(q, u),
    );
    let (mb0, tb0) = (
        kd::baked::mass_matrix_batch(q),
        kd::baked::inverse_dynamics_batch(q, u, ud),
    );
    for l in 0..L {
        lanes("M", state(&m, l).as_slice(), m0[l].as_slice());
        lanes("c", state(&c, l).as_slice(), c0[l].as_slice());
        lanes("g", state(&g, l).as_slice(), g0[l].as_slice());
        lanes("τ", state(&t, l).as_slice(), t0[l].as_slice());
        lanes("C", state(&cm, l).as_slice(), cm0[l].as_slice());
        lanes("baked M", state(&mb, l).as_slice(), mb0[l].as_slice());
        lanes("baked τ", state(&tb, l).as_slice(), tb0[l].as_slice());
    }
    let bits = |a: &[Lanes<L>]| -> Vec<f64> { a.iter().flat_map(|x| x.0).collect() };
    let nan = Lanes::splat(f64::NAN);
    let mut mi = nalgebra::SMatrix::<Lanes<L>, 19, 19>::from_element(nan);
    k.mass_matrix_batch_soa_into(&qs, &mut mi);
    lanes("M into", &bits(mi.as_slice()), &bits(m.as_slice()));
    let mut mi = nalgebra::SMatrix::<Lanes<L>, 19, 19>::from_element(nan);
    k.coriolis_matrix_batch_soa_into(&qs, &us, &mut mi);
    lanes("C into", &bits(mi.as_slice()), &bits(cm.as_slice()));
    let mut vi = SVector::<Lanes<L>, 19>::from_element(nan);
    k.coriolis_batch_soa_into(&qs, &us, &mut vi);
    lanes("c into", &bits(vi.as_slice()), &bits(c.as_slice()));
    let mut vi = SVector::<Lanes<L>, 19>::from_element(nan);
    k.gravity_batch_soa_into(&qs, &mut vi);
    lanes("g into", &bits(vi.as_slice()), &bits(g.as_slice()));
    let mut vi = SVector::<Lanes<L>, 19>::from_element(nan);
    k.inverse_dynamics_batch_soa_into(&qs, &us, &uds, &mut vi);
    lanes("τ into", &bits(vi.as_slice()), &bits(t.as_slice()));
}

#[test]
fn batched_functions_equal_the_single_state_functions_bit_for_bit() {
    let _one_at_a_time = isa_lock();
    let model = model("krang.toml");
    let mut uniform = rng(14);
    for isa in Isa::ALL.into_iter().filter(|&i| isa::available(i)) {
        isa::select(isa).unwrap();
        for draw in 0..30 {
            let k = krang(&model, &mut uniform);
            let (q1, u1, ud1) = states::<1>(&mut uniform);
            check_batch(&k, &q1, &u1, &ud1);
            let (q3, u3, ud3) = states::<3>(&mut uniform);
            check_batch(&k, &q3, &u3, &ud3);
            check_soa(&k, &q3, &u3, &ud3);
            let (mut q4, u4, ud4) = states::<4>(&mut uniform);
            if draw % 5 == 0 {
                // One lane with a huge angle: that batch takes the per-lane slow sin/cos.
                q4[2][kd::index::Q1L] = 1.0e7;
            }
            check_batch(&k, &q4, &u4, &ud4);
            let (q8, u8, ud8) = states::<8>(&mut uniform);
            check_batch(&k, &q8, &u8, &ud8);
            check_soa(&k, &q8, &u8, &ud8);
        }
    }
    isa::select(isa::detected()).unwrap();
}

/// The x86-64-v3 copy fuses multiply-adds (one rounding instead of two): it agrees with the
/// baseline copy to `1e-12` of the largest entry of each result (the terms summed into an
/// entry are of that size; measured worst: see the printed figure), and it does fuse (some
/// entries differ in their last bits). `sin_cos_n` fuses its kernels' Horner steps there: the
/// baseline copy gives the scalar `sin_cos`'s bits, the x86-64-v3 copy agrees with it to 2 ulp.
#[test]
fn dispatched_copies_agree_with_the_baseline_to_rounding() {
    let _one_at_a_time = isa_lock();
    let model = model("krang.toml");
    let mut uniform = rng(1414);
    let best = isa::detected();
    assert_eq!(isa::available(Isa::X86_64V3), best != Isa::Baseline);
    assert_eq!(isa::available(Isa::X86_64V4), best == Isa::X86_64V4);
    if best == Isa::Baseline {
        eprintln!("note: this CPU or build has only the baseline copy; nothing to compare");
        return;
    }
    let names = ["M", "c", "g", "τ", "C", "baked c", "fixed-wheel M"];
    let (mut differing, mut entries, mut worst) = (0usize, 0usize, 0.0f64);
    for _ in 0..200 {
        let k = krang(&model, &mut uniform);
        let (q, u, ud) = random_state(&mut uniform, 19);
        let (q, u, ud): (V, V, V) = (sv(&q), sv(&u), sv(&ud));
        let eval = |isa: Isa| {
            isa::select(isa).unwrap();
            let f = kd::fixed_wheels::KrangFixedWheels::default();
            let qf = SVector::<f64, 17>::from_fn(|i, _| q[i + 2]);
            let results: Vec<Vec<f64>> = vec![
                k.mass_matrix(&q).as_slice().to_vec(),
                k.coriolis(&q, &u).as_slice().to_vec(),
                k.gravity(&q).as_slice().to_vec(),
                k.inverse_dynamics(&q, &u, &ud).as_slice().to_vec(),
                k.coriolis_matrix(&q, &u).as_slice().to_vec(),
                kd::baked::coriolis(&q, &u).as_slice().to_vec(),
                f.mass_matrix(&qf).as_slice().to_vec(),
            ];
            let (s, c) = kanegen_runtime::trig::sin_cos_n(q.into());
            (results, [s, c].concat())
        };
        let (base, base_trig) = eval(Isa::Baseline);
        let (v3, v3_trig) = eval(best);
        let scalar: Vec<f64> = {
            let sc: Vec<(f64, f64)> = q
                .iter()
                .map(|&x| kanegen_runtime::trig::sin_cos(x))
                .collect();
            sc.iter()
                .map(|p| p.0)
                .chain(sc.iter().map(|p| p.1))
                .collect()
        };
        assert!(
            same_bits(&base_trig, &scalar),
            "sin_cos_n: baseline differs from sin_cos"
        );
        for (b, v) in base_trig.iter().zip(&v3_trig) {
            assert!(
                (b - v).abs() <= 2.0 * f64::EPSILON * b.abs().max(f64::MIN_POSITIVE),
                "sin_cos_n: {best} {v:e} vs baseline {b:e}"
            );
        }
        for ((b, v), name) in base.iter().zip(&v3).zip(names) {
            let scale = b.iter().fold(1.0f64, |s, x| s.max(x.abs()));
            for (i, (x, y)) in b.iter().zip(v).enumerate() {
                let err = (x - y).abs() / scale;
                assert!(
                    err <= 1e-12,
                    "{name}[{i}]: baseline {x:e}, {best} {y:e} (relative to {scale:e}: {err:e})"
                );
                worst = worst.max(err);
                differing += usize::from(x.to_bits() != y.to_bits());
                entries += 1;
            }
        }
    }
    eprintln!(
        "{best} vs baseline: {differing} of {entries} entries differ, worst {worst:.1e} of the \
         result's largest entry"
    );
    assert!(differing > 0, "{best} fused no multiply-add");
    isa::select(best).unwrap();
}

#[test]
fn the_derivatives_x86_64_v4_copies_give_the_x86_64_v3_copies_bits() {
    // With x86-64-v4 active, the looped derivatives run their straight-line part's x86-64-v4
    // copy (`isa::dispatch_pair_wide_with`) and `derivatives_loop::run`'s AVX-512VL copy (32
    // registers, broadcasts folded into the multiply-adds, still 256-bit): the same operations
    // in the same order as the x86-64-v3 copies, so the same bits.
    let _one_at_a_time = isa_lock();
    if !isa::available(Isa::X86_64V4) {
        eprintln!("note: this CPU or build has no x86-64-v4 copy; nothing to compare");
        return;
    }
    let model = model("krang.toml");
    let mut uniform = rng(1415);
    for _ in 0..50 {
        let k = krang(&model, &mut uniform);
        let (q, u, ud) = random_state(&mut uniform, 19);
        let (q, u, ud): (V, V, V) = (sv(&q), sv(&u), sv(&ud));
        let eval = |isa: Isa| {
            isa::select(isa).unwrap();
            k.inverse_dynamics_derivatives(&q, &u, &ud)
        };
        let (v3, v4) = (eval(Isa::X86_64V3), eval(Isa::X86_64V4));
        assert!(same_bits(v3.as_slice(), v4.as_slice()));
    }
    isa::select(isa::detected()).unwrap();
}

/// Batched forward dynamics at `L` states (both forms) against `forward_dynamics` of each
/// state, bit for bit with the active instruction set (NaN lanes included), for Krang and for
/// the fixed-wheel tree (`$k`: either; `$n`: its speeds).
macro_rules! check_forward_batch {
    ($k:expr, $n:literal, $q:expr, $u:expr, $tau:expr) => {{
        use kd::lanes::{Lanes, soa, state};
        let (k, q, u, tau) = ($k, $q, $u, $tau);
        let (q_lanes, u_lanes, tau_lanes) = (soa(q), soa(u), soa(tau));
        let mut ud = SVector::<Lanes<_>, $n>::from_element(Lanes::splat(f64::NAN));
        k.forward_dynamics_batch_soa_into(&q_lanes, &u_lanes, &tau_lanes, &mut ud);
        let by_states = k.forward_dynamics_batch(q, u, tau);
        // The form with a kept mass matrix, which holds NaN before: every entry is written.
        let mut m = nalgebra::SMatrix::<Lanes<_>, $n, $n>::from_element(Lanes::splat(f64::NAN));
        let mut ud_kept = SVector::<Lanes<_>, $n>::from_element(Lanes::splat(f64::NAN));
        k.forward_dynamics_batch_soa_with_mass_matrix(
            &q_lanes,
            &u_lanes,
            &tau_lanes,
            &mut m,
            &mut ud_kept,
        );
        for l in 0..q.len() {
            let one = k.forward_dynamics(&q[l], &u[l], &tau[l]);
            let lane = state(&ud, l);
            assert!(
                same_bits(lane.as_slice(), one.as_slice()),
                "{}: lane {l} of {}: {lane} against {one}",
                isa::active(),
                q.len()
            );
            assert!(same_bits(by_states[l].as_slice(), one.as_slice()));
            assert!(same_bits(state(&ud_kept, l).as_slice(), one.as_slice()));
            assert!(same_bits(
                state(&m, l).as_slice(),
                k.mass_matrix(&q[l]).as_slice()
            ));
        }
    }};
}

/// [`check_forward_batch`] for Krang.
fn check_forward_batch<const L: usize>(k: &kd::Krang, q: &[V; L], u: &[V; L], tau: &[V; L]) {
    check_forward_batch!(k, 19, q, u, tau);
}

#[test]
fn batched_forward_dynamics_equals_forward_dynamics_bit_for_bit() {
    let _one_at_a_time = isa_lock();
    let fixed_model = model("krang-fixed-wheels.toml");
    let model = model("krang.toml");
    let mut uniform = rng(1415);
    let mut nan_lanes = 0;
    for isa in Isa::ALL.into_iter().filter(|&i| isa::available(i)) {
        isa::select(isa).unwrap();
        for draw in 0..30 {
            let k = krang(&model, &mut uniform);
            // The accelerations of the draw, scaled, as torques.
            let (q1, u1, t1) = states::<1>(&mut uniform);
            check_forward_batch(&k, &q1, &u1, &t1.map(|t| 20.0 * t));
            let (mut q3, u3, mut t3) = states::<3>(&mut uniform);
            t3 = t3.map(|t| 20.0 * t);
            if draw % 3 == 0 {
                // A lane with a NaN input and a lane with an infinite torque: NaN lanes, the
                // other lane as alone.
                q3[0][kd::index::Q3L] = f64::NAN;
                t3[2][kd::index::XD] = f64::INFINITY;
                nan_lanes += 2;
            }
            check_forward_batch(&k, &q3, &u3, &t3);
            let (mut q8, u8, t8) = states::<8>(&mut uniform);
            if draw % 5 == 0 {
                // A huge angle: that batch's sines and cosines take the per-lane slow path.
                q8[4][kd::index::Q2R] = 1.0e7;
            }
            check_forward_batch(&k, &q8, &u8, &t8.map(|t| 20.0 * t));
            // The fixed-wheel tree (trunk of 3), 4 states: Krang's speeds from the third on.
            let p = random_physical_params(&fixed_model, &mut uniform);
            let f = kd::fixed_wheels::KrangFixedWheels::new(kd::fixed_wheels::Params::from_array(
                p.try_into().unwrap(),
            ));
            let (q, u, t) = states::<4>(&mut uniform);
            let tail = |v: [V; 4]| v.map(|v| SVector::<f64, 17>::from_fn(|i, _| v[i + 2]));
            let (qf, uf, mut tf) = (tail(q), tail(u), tail(t.map(|t| 20.0 * t)));
            if draw % 3 == 1 {
                tf[1][0] = f64::NAN;
                nan_lanes += 1;
            }
            check_forward_batch!(&f, 17, &qf, &uf, &tf);
        }
    }
    isa::select(isa::detected()).unwrap();
    assert!(nan_lanes > 0);
}

#[test]
fn batched_forward_dynamics_gives_nan_where_the_mass_matrix_is_not_positive_definite() {
    let _one_at_a_time = isa_lock();
    let mut uniform = rng(1416);
    // A non-physical last link of the left arm: M's left-arm block is not positive definite.
    let mut p = kd::Params::default();
    p.set("ZZ10l", -1.0).unwrap();
    let k = kd::Krang::new(p);
    let (q, u, tau) = states::<4>(&mut uniform);
    assert!(matches!(
        k.try_forward_dynamics(&q[0], &u[0], &tau[0]),
        Err(kd::ForwardDynamicsError::NotPositiveDefinite(_))
    ));
    for ud in k.forward_dynamics_batch(&q, &u, &tau) {
        assert!(ud.iter().all(|x| x.is_nan()), "{ud}");
    }
    check_forward_batch(&k, &q, &u, &tau);
}

/// The lane solver alone, for both block shapes (Krang's trunk of 5 and the fixed-wheel tree's
/// trunk of 3): every lane gets the bits of `BlockCholesky::solve_once` on its own matrix, and a
/// lane with a matrix that is not positive definite reports it without disturbing the others.
#[test]
fn the_lane_block_solver_equals_the_block_cholesky_of_each_lane() {
    use kd::forward_batch::block_solve_lanes;
    use kd::lanes::{Lanes, soa, state};
    use nalgebra::SMatrix;
    fn check<const T: usize, const N: usize>(
        m: &[SMatrix<f64, N, N>; 4],
        b: &[SVector<f64, N>; 4],
    ) {
        let lanes = SMatrix::<Lanes<4>, N, N>::from_fn(|r, c| Lanes::from_fn(|l| m[l][(r, c)]));
        let mut x = soa(b);
        let ok = block_solve_lanes::<T, N, 4>(&lanes, &mut x);
        for l in 0..4 {
            match kd::BlockCholesky::<T, N>::solve_once(&m[l], &b[l]) {
                Ok(one) => {
                    assert!(ok[l], "lane {l}");
                    assert!(
                        same_bits(state(&x, l).as_slice(), one.as_slice()),
                        "lane {l}"
                    );
                }
                Err(_) => assert!(!ok[l], "lane {l}"),
            }
        }
    }
    let _one_at_a_time = isa_lock();
    let model = model("krang.toml");
    let mut uniform = rng(1417);
    let fixed = kd::fixed_wheels::KrangFixedWheels::default();
    for isa in Isa::ALL.into_iter().filter(|&i| isa::available(i)) {
        isa::select(isa).unwrap();
        for draw in 0..20 {
            let k = krang(&model, &mut uniform);
            let (q, _, b) = states::<4>(&mut uniform);
            let mut m = q.map(|q| k.mass_matrix(&q));
            if draw % 4 == 0 {
                // Lane 1 not positive definite (its trunk block), the others as they are.
                m[1][(2, 2)] = -1.0;
            }
            check::<5, 19>(&m, &b);
            let qf = q.map(|q| SVector::<f64, 17>::from_fn(|i, _| q[i + 2]));
            let bf = b.map(|b| SVector::<f64, 17>::from_fn(|i, _| b[i + 2]));
            check::<3, 17>(&qf.map(|q| fixed.mass_matrix(&q)), &bf);
        }
    }
    isa::select(isa::detected()).unwrap();
}

#[test]
fn selecting_an_instruction_set_the_cpu_lacks_is_an_error() {
    let _one_at_a_time = isa_lock();
    for isa in Isa::ALL {
        match isa::select(isa) {
            Ok(()) => assert!(isa::available(isa)),
            Err(e) => {
                assert!(!isa::available(isa));
                assert!(e.to_string().contains(isa.name()), "{e}");
            }
        }
    }
    isa::select(isa::detected()).unwrap();
    assert_eq!(isa::active(), isa::detected());
}

#[test]
fn batched_functions_with_structurally_zero_results_compile_and_write_zeros() {
    use kanegen_runtime::lanes::{soa, state};
    type S = SVector<f64, 1>;
    let k = slider::Slider::default();
    let q: [S; 3] = [S::new(0.3), S::new(-0.7), S::new(1.0e6)];
    let u: [S; 3] = [S::new(1.5), S::new(-2.0), S::new(0.0)];
    let ud: [S; 3] = [S::new(-4.0), S::new(0.5), S::new(3.0)];
    let _guard = isa_lock();
    let nan = S::new(f64::NAN);
    let (mut m, mut c, mut g, mut t, mut cm) = (
        [nalgebra::SMatrix::<f64, 1, 1>::from_element(f64::NAN); 3],
        [nan; 3],
        [nan; 3],
        [nan; 3],
        [nalgebra::SMatrix::<f64, 1, 1>::from_element(f64::NAN); 3],
    );
    k.mass_matrix_batch_into(&q, &mut m);
    k.coriolis_batch_into(&q, &u, &mut c);
    k.gravity_batch_into(&q, &mut g);
    k.inverse_dynamics_batch_into(&q, &u, &ud, &mut t);
    k.coriolis_matrix_batch_into(&q, &u, &mut cm);
    let (qs, us, uds) = (soa(&q), soa(&u), soa(&ud));
    let (cs, gs, ts, cms) = (
        k.coriolis_batch_soa(&qs, &us),
        k.gravity_batch_soa(&qs),
        k.inverse_dynamics_batch_soa(&qs, &us, &uds),
        k.coriolis_matrix_batch_soa(&qs, &us),
    );
    for l in 0..3 {
        // The cart's mass: M = [2.5], c = g = C = 0, τ = 2.5 u̇.
        assert_eq!(k.mass_matrix(&q[l])[(0, 0)], 2.5);
        assert_eq!(m[l], k.mass_matrix(&q[l]), "M lane {l}");
        for zero in [
            c[l][0],
            g[l][0],
            cm[l][(0, 0)],
            state(&cs, l)[0],
            state(&gs, l)[0],
        ] {
            assert_eq!(zero.to_bits(), 0.0f64.to_bits(), "lane {l}");
        }
        assert_eq!(state(&cms, l)[(0, 0)].to_bits(), 0.0f64.to_bits());
        assert_eq!(t[l], k.inverse_dynamics(&q[l], &u[l], &ud[l]), "τ lane {l}");
        assert_eq!(t[l][0], 2.5 * ud[l][0]);
        assert_eq!(state(&ts, l), t[l], "SoA τ lane {l}");
    }
}
