//! The 64 fixed pseudo-random Krang states the profiling drivers (`profile`,
//! `profile_regressors`, in this folder) and the workspace's `benches/simd.rs` cycle through: a small LCG,
//! deterministic and dependency-free.

use nalgebra::SVector;

/// A 19-vector of Krang (q, u or u̇).
pub type V = SVector<f64, 19>;

/// 64 states `(q, u, u̇)`: angles in ±π, speeds in ±2, accelerations in ±5.
pub fn states() -> Vec<(V, V, V)> {
    let mut x: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut next = move || {
        x = x
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (x >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..64)
        .map(|_| {
            let q = V::from_fn(|_, _| (2.0 * next() - 1.0) * std::f64::consts::PI);
            let u = V::from_fn(|_, _| 4.0 * next() - 2.0);
            let ud = V::from_fn(|_, _| 10.0 * next() - 5.0);
            (q, u, ud)
        })
        .collect()
}
