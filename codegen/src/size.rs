//! How large a module will be, estimated from the model's shape before anything is derived, and
//! the two checks that use the estimate: the generator's own memory
//! ([`check_generator_memory`]: a typed [`Error::TooLarge`] instead of an aborted allocation) and
//! the size of a module for an unoptimised build ([`check_unoptimised_build`]: a typed error
//! before rustc runs for minutes and gigabytes). See docs/big-models.md.
//!
//! The estimate counts the (frame, speed) pairs where the speed moves the frame: `n(n+1)/2` for a
//! serial chain of `n` links, the sum of the depths for a tree. Every default function (M, c, g,
//! τ, C) carries expressions per pair through the recursion, and per frame its kinematics: the
//! measured output is 3.3 KB per pair and 19 KB per frame (serial chains of 30, 50 and 100
//! links with full inertias: 2.1, 5.2 and 18.6 MB; the 100-link tree of ten branches: 4.8 MB,
//! estimated 3.7 MB), and the peak memory 12 to 17 times the Rust emitted. Derivatives and
//! regressors add a factor that grows with the depth (a 100-link chain with every function:
//! about ten times the default set).

use crate::model::Model;
use crate::{Error, FunctionId, Options};

/// Default of [`Builder::unoptimised_limit`](crate::Builder::unoptimised_limit): the largest
/// estimated module, in bytes of Rust, that a build script generates for an unoptimised build
/// (`OPT_LEVEL=0`). The 100-speed tree of the tests (4.8 MB) compiles in the debug test
/// profile (53 s of rustc CPU, 1.0 GB); a serial chain of 100 links (18.6 MB, estimated
/// 17.7 MB: 842 s of rustc CPU and 4.1 GB in a debug build) is refused before rustc runs.
pub const DEFAULT_UNOPTIMISED_LIMIT: u64 = 8 << 20;

/// Bytes of emitted Rust per (frame, speed) pair for the default functions.
const BYTES_PER_PAIR: u64 = 3_300;
/// Bytes of emitted Rust per frame for the default functions (per-link kinematics, parameters,
/// documentation).
const BYTES_PER_FRAME: u64 = 19_200;
/// Peak memory of the generator per byte of emitted Rust.
const MEMORY_PER_BYTE: u64 = 14;

/// What a module of a model is estimated to cost, before it is derived.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SizeEstimate {
    /// The (frame, speed) pairs where the speed moves the frame.
    pub pairs: u64,
    /// Bytes of Rust the module will have (within about a factor of two).
    pub rust_bytes: u64,
    /// The generator's peak memory in bytes (within about a factor of two).
    pub peak_memory: u64,
}

/// The estimate for `model` with the functions of `opts`.
pub fn estimate(model: &Model, opts: &Options) -> SizeEstimate {
    // Speeds of the base (a wheeled base's xd, psid, pitch) move every frame.
    let joint_speeds = model
        .mounted_links()
        .filter(|(_, _, m)| m.joint.speed().is_some())
        .count();
    let base_speeds = model.dof().saturating_sub(joint_speeds) as u64;
    let mut depth = vec![base_speeds; model.links.len()];
    let mut pairs = 0u64;
    let mut deepest = 0u64;
    for (i, _, m) in model.mounted_links() {
        depth[i] = depth[m.parent] + u64::from(m.joint.speed().is_some());
        pairs += depth[i];
        deepest = deepest.max(depth[i]);
    }
    let weight = {
        let mut weight = 0u64;
        let dynamics = [
            FunctionId::MassMatrix,
            FunctionId::Coriolis,
            FunctionId::Gravity,
            FunctionId::InverseDynamics,
            FunctionId::CoriolisMatrix,
        ];
        // The default set's share per function (the Coriolis matrix is the largest).
        for (f, share) in dynamics.iter().zip([20u64, 12, 6, 12, 50]) {
            if opts.has(*f) {
                weight += share;
            }
        }
        let heavy = opts.has(FunctionId::InverseDynamicsDerivatives)
            || opts.has(FunctionId::InverseDynamicsRegressor)
            || opts.has(FunctionId::BaseRegressor);
        if heavy {
            weight += 10 * deepest;
        }
        // Kinematics and the rest: a tenth of the default set at least.
        weight.max(10)
    };
    let (per_frame, per_pair) = (
        weight * BYTES_PER_FRAME / 100,
        weight * BYTES_PER_PAIR / 100,
    );
    let frames = model.links.len() as u64;
    let rust_bytes = pairs
        .saturating_mul(per_pair)
        .saturating_add(frames.saturating_mul(per_frame));
    SizeEstimate {
        pairs,
        rust_bytes,
        peak_memory: rust_bytes.saturating_mul(MEMORY_PER_BYTE),
    }
}

/// The memory this process may use: the smaller of its address-space limit (`ulimit -v`) and
/// the machine's memory, where the system says (Linux `/proc`); `None` elsewhere.
pub fn available_memory() -> Option<u64> {
    let limit = std::fs::read_to_string("/proc/self/limits")
        .ok()
        .and_then(|text| {
            let line = text.lines().find(|l| l.starts_with("Max address space"))?;
            line.split_whitespace().nth(3)?.parse::<u64>().ok()
        });
    let total = std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|text| {
            let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
            let kb = line.split_whitespace().nth(1)?.parse::<u64>().ok()?;
            Some(kb.saturating_mul(1024))
        });
    match (limit, total) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
    }
}

/// [`Error::TooLarge`] if the generator's estimated peak memory for `model` exceeds `limit`
/// bytes (no check without a limit).
pub(crate) fn check_generator_memory(
    model: &Model,
    opts: &Options,
    limit: Option<u64>,
) -> Result<(), Error> {
    let Some(limit) = limit else { return Ok(()) };
    let e = estimate(model, opts);
    if e.peak_memory <= limit {
        return Ok(());
    }
    Err(Error::TooLarge {
        model: model.name.escape_default().to_string(),
        what: format!(
            "generating it needs about {} of memory ({} (frame, speed) pairs, about {} of Rust), \
             more than the {} this process may use",
            gib(e.peak_memory),
            e.pairs,
            gib(e.rust_bytes),
            gib(limit)
        ),
        fix: "generate fewer functions (Builder::functions or --functions; the Coriolis matrix \
              is the largest default function), split the robot into smaller models, or run the generator where \
              more memory is available (Builder::memory_limit raises the limit)"
            .into(),
    })
}

/// [`Error::TooLarge`] if the module of `model` is estimated at more than `limit` bytes of Rust
/// for an unoptimised build (rustc's debug builds of straight-line code take minutes and
/// gigabytes per ten megabytes).
pub(crate) fn check_unoptimised_build(
    model: &Model,
    opts: &Options,
    limit: u64,
) -> Result<(), Error> {
    let e = estimate(model, opts);
    if e.rust_bytes <= limit {
        return Ok(());
    }
    Err(Error::TooLarge {
        model: model.name.escape_default().to_string(),
        what: format!(
            "its module would be about {} of straight-line Rust ({} (frame, speed) pairs), more \
             than the {} an unoptimised (debug) build compiles in bounded time and memory",
            gib(e.rust_bytes),
            e.pairs,
            gib(limit)
        ),
        fix: "build the crate that includes it with optimisation (`[profile.dev.package.<crate>] \
              opt-level = 1` or a release build), generate fewer functions (Builder::functions; \
              Builder::coriolis_matrix(false) drops the largest), or raise the limit with \
              Builder::unoptimised_limit"
            .into(),
    })
}

/// `bytes` in MB or GB, for messages.
fn gib(bytes: u64) -> String {
    if bytes >= 1 << 30 {
        format!("{:.1} GB", bytes as f64 / f64::from(1u32 << 30))
    } else {
        format!("{:.1} MB", bytes as f64 / f64::from(1u32 << 20))
    }
}
