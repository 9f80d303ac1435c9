//! Run-time instruction-set dispatch: the one place where generated code picks the best
//! instruction set the CPU has.
//!
//! Cargo builds for the baseline of the target (x86-64: SSE2, no AVX, no FMA) unless told
//! otherwise, while the CPUs controllers run on have AVX2 and FMA (x86-64-v3) or more. Every
//! generated function (and [`crate::trig::sin_cos_n`]) is therefore compiled twice, for the
//! baseline and for x86-64-v3, and [`dispatch`] chooses between the two copies at every call
//! by one relaxed atomic load of the instruction set detected once, at the first call
//! ([`active`]). The batched functions (and [`crate::trig::sin_cos_slice`]) have a third copy,
//! for x86-64-v4 (AVX-512), chosen by [`dispatch_fused_wide_with`]: their loop over the states
//! runs 8 lanes per instruction there. On an AVX-512 CPU [`active`] is [`Isa::X86_64V4`] and
//! the single-state functions run their x86-64-v3 copy (an AVX-512 copy of them was measured no
//! faster on Krang, and cost 43 % more compile time).
//!
//! How: the generated function's body is `#[inline(always)]` and is passed to [`dispatch`] as
//! an `#[inline(always)]` closure. [`dispatch`] calls it directly (the baseline copy) or through
//! a function compiled with `#[target_feature(enable = "avx,avx2,fma,…")]`, into which LLVM
//! inlines the closure and the body: that copy of the body is compiled for AVX2 with the
//! three-operand VEX encodings and 256-bit vectors where LLVM vectorizes. Calling a
//! `#[target_feature]` function needs `unsafe` (the CPU must have the features); this module
//! holds that call (the same in [`dispatch`], [`dispatch_fused_with`], through which
//! [`dispatch_fused`] and [`dispatch_pair_with`] run, and [`dispatch_fused_wide_with`], which
//! also calls the x86-64-v4 copy), right after the check that
//! the features are present; the crate's other `unsafe` blocks are the same kind of call in
//! [`crate::derivatives_loop::run`] (its AVX2 kernel, after [`active`] reported x86-64-v3 or
//! x86-64-v4) and the SSE2 and FMA intrinsics of [`crate::pair`] (two lanes; its FMA only
//! behind a [`FusedPair`], which [`dispatch_pair_with`] makes after the same check).
//!
//! Results: Rust never fuses `a * b + c` into a fused multiply-add on its own. Generated
//! functions therefore print their sums of products as [`Arith::mul_add`] chains in a body
//! generic over [`Arith`], and [`dispatch_fused`] runs the baseline copy with [`Plain`]
//! (`x * y + acc`, two roundings: **the same bits** as the sum written out, as before FMA was
//! used) and the x86-64-v3 copy with [`Fused`] (one `vfmadd`, one rounding). The two copies'
//! results therefore differ in the last bits: each fused multiply-add skips one rounding, so the
//! v3 result is within a few units in the last place of the baseline's relative to the size of
//! the terms summed (measured on Krang's M, c, g, τ and C over random parameters and states:
//! `tests/isa_batch.rs`, `dispatched_copies_agree_with_the_baseline_to_rounding`, tolerance
//! 1e-12 of the entry's scale). Bodies passed to [`dispatch`] (no `mul_add`) still give the
//! baseline's bits in both copies.
//!
//! When there is nothing to choose, [`dispatch`] is a plain call and compiles to the body alone:
//! - without the `dispatch` feature (on by default; turn it off with
//!   `default-features = false, features = ["std"]`), or without `std` (feature detection needs
//!   the operating system: `no_std` builds run the baseline copy);
//! - on other architectures (aarch64's baseline already has NEON and FMA instructions);
//! - when the crate is compiled with AVX2 and FMA enabled anyway (`-C target-cpu=native` or
//!   `-C target-cpu=x86-64-v3`): the baseline copy *is* the AVX2 copy.
//!
//! Generators can also leave dispatch out of a module (`kanegen::Builder::isa_dispatch(false)`).
//!
//! ```
//! use kanegen_runtime::isa::{self, Isa};
//!
//! // What the CPU has, and what generated functions use (the same unless `select`ed).
//! let best = isa::detected();
//! assert_eq!(isa::active(), best);
//! assert!(isa::available(Isa::Baseline));
//! // A generated function's shape: the body inlined into each copy.
//! #[inline(always)]
//! fn body(x: &[f64; 4]) -> f64 {
//!     x.iter().map(|v| v * v).sum()
//! }
//! let x = [1.0, 2.0, 3.0, 4.0];
//! let y = isa::dispatch(#[inline(always)] || body(&x));
//! assert_eq!(y, 30.0);
//! // Force the baseline copy (benchmarks, tests), then go back to the best one.
//! isa::select(Isa::Baseline).unwrap();
//! assert_eq!(isa::dispatch(#[inline(always)] || body(&x)), y);
//! isa::select(best).unwrap();
//! ```

use core::sync::atomic::{AtomicU8, Ordering};

pub use crate::arith::{Arith, Fused, Native, Plain};
pub use crate::pair::{FusedPair, PairArith};

/// An instruction set a generated function can run with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Isa {
    /// The compilation target's own features (x86-64: SSE2, or whatever `-C target-cpu`
    /// enabled; aarch64: NEON).
    Baseline,
    /// x86-64-v3: AVX, AVX2, FMA, BMI1, BMI2, LZCNT, F16C, POPCNT (Intel Haswell, AMD Excavator
    /// and later).
    X86_64V3,
    /// x86-64-v4: x86-64-v3 and AVX-512 F, BW, CD, DQ, VL (Intel Skylake-SP, AMD Zen 4 and
    /// later): 32 vector registers, 8 `f64` lanes per register.
    X86_64V4,
}

impl Isa {
    /// Every instruction set, from the most widely available.
    pub const ALL: [Isa; 3] = [Isa::Baseline, Isa::X86_64V3, Isa::X86_64V4];

    /// `"baseline"`, `"x86-64-v3"`, `"x86-64-v4"`.
    pub fn name(self) -> &'static str {
        match self {
            Isa::Baseline => "baseline",
            Isa::X86_64V3 => "x86-64-v3",
            Isa::X86_64V4 => "x86-64-v4",
        }
    }

    fn code(self) -> u8 {
        match self {
            Isa::Baseline => BASELINE,
            Isa::X86_64V3 => V3,
            Isa::X86_64V4 => V4,
        }
    }
}

impl core::fmt::Display for Isa {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(self.name())
    }
}

/// [`select`] asked for an instruction set that this CPU lacks, or that this build cannot
/// dispatch to (no `std`, the `dispatch` feature off, another architecture).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct IsaUnavailable {
    /// The instruction set asked for.
    pub isa: Isa,
}

impl core::fmt::Display for IsaUnavailable {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "instruction set {} is not available: the CPU lacks it, or this build of \
             kanegen-runtime cannot dispatch to it (it needs the features `std` and `dispatch` \
             and an x86-64 target); use isa::detected() for the best available one",
            self.isa
        )
    }
}

impl core::error::Error for IsaUnavailable {}

const UNKNOWN: u8 = 0;
const BASELINE: u8 = 1;
const V3: u8 = 2;
const V4: u8 = 3;

/// The instruction set [`dispatch`] uses: [`UNKNOWN`] until the first call detects it.
static ACTIVE: AtomicU8 = AtomicU8::new(UNKNOWN);

/// Whether this build dispatches at all (see the module docs).
macro_rules! if_dispatching {
    ($($item:item)*) => {$(
        #[cfg(all(
            feature = "dispatch",
            feature = "std",
            target_arch = "x86_64",
            not(all(target_feature = "avx2", target_feature = "fma"))
        ))]
        $item
    )*};
}

macro_rules! if_not_dispatching {
    ($($item:item)*) => {$(
        #[cfg(not(all(
            feature = "dispatch",
            feature = "std",
            target_arch = "x86_64",
            not(all(target_feature = "avx2", target_feature = "fma"))
        )))]
        $item
    )*};
}

if_dispatching! {
    fn v3_present() -> bool {
        std::arch::is_x86_feature_detected!("avx")
            && std::arch::is_x86_feature_detected!("avx2")
            && std::arch::is_x86_feature_detected!("fma")
            && std::arch::is_x86_feature_detected!("bmi1")
            && std::arch::is_x86_feature_detected!("bmi2")
            && std::arch::is_x86_feature_detected!("lzcnt")
            && std::arch::is_x86_feature_detected!("f16c")
            && std::arch::is_x86_feature_detected!("popcnt")
    }

    fn v4_present() -> bool {
        v3_present()
            && std::arch::is_x86_feature_detected!("avx512f")
            && std::arch::is_x86_feature_detected!("avx512bw")
            && std::arch::is_x86_feature_detected!("avx512cd")
            && std::arch::is_x86_feature_detected!("avx512dq")
            && std::arch::is_x86_feature_detected!("avx512vl")
    }

    /// Whether this CPU can run `isa`'s copy.
    pub fn available(isa: Isa) -> bool {
        match isa {
            Isa::Baseline => true,
            Isa::X86_64V3 => v3_present(),
            Isa::X86_64V4 => v4_present(),
        }
    }

    /// `f()` compiled with x86-64-v4's features (x86-64-v3's and AVX-512 F, BW, CD, DQ, VL).
    #[target_feature(
        enable = "avx,avx2,fma,bmi1,bmi2,lzcnt,f16c,popcnt,avx512f,avx512bw,avx512cd,avx512dq,avx512vl"
    )]
    #[inline]
    fn run_v4<R, F: FnOnce() -> R>(f: F) -> R {
        f()
    }

    /// `f()` compiled with x86-64-v3's features (LLVM inlines `f` here when it is
    /// `#[inline(always)]`).
    #[target_feature(enable = "avx,avx2,fma,bmi1,bmi2,lzcnt,f16c,popcnt")]
    #[inline]
    fn run_v3<R, F: FnOnce() -> R>(f: F) -> R {
        f()
    }

    /// Calls `f` with the [`active`] instruction set: compiled twice, for the baseline and
    /// for x86-64-v3, when `f` (and what it calls) is `#[inline(always)]`. See the module docs.
    #[inline(always)]
    pub fn dispatch<R, F: FnOnce() -> R>(f: F) -> R {
        if active_code() >= V3 {
            // SAFETY: as in `dispatch_fused_with` below (the same check before the same call).
            #[allow(unsafe_code)]
            unsafe {
                return run_v3(f);
            }
        }
        f()
    }

    /// [`dispatch_fused`] passing `arg` to the copy that runs: for an argument both closures
    /// would otherwise capture, such as the `&mut` result array of a batched function
    /// (`mass_matrix_batch_into`), which two closures cannot borrow at once.
    #[inline(always)]
    pub fn dispatch_fused_with<T, R>(
        arg: T,
        plain: impl FnOnce(T) -> R,
        fused: impl FnOnce(T) -> R,
    ) -> R {
        if active_code() >= V3 {
            // SAFETY: `ACTIVE` holds `V3` or `V4` only after `v3_present()` found every feature
            // `run_v3` is compiled with (`detect` and `select` check it before storing; `V4`
            // needs `v3_present()` too), so the CPU executes its instructions. The same call as
            // in `dispatch` above.
            #[allow(unsafe_code)]
            unsafe {
                return run_v3(
                    #[inline(always)]
                    || fused(arg),
                );
            }
        }
        plain(arg)
    }

    /// [`dispatch_fused_with`] with a third copy, compiled for x86-64-v4 (AVX-512: 8 `f64`
    /// lanes per register, 32 registers), run when [`active`] is [`Isa::X86_64V4`]: what the
    /// batched functions and [`crate::trig::sin_cos_slice`] use, whose loops over the states
    /// LLVM vectorizes 8 lanes wide there. The copies for x86-64-v3 and x86-64-v4 both run
    /// `fused` (the same IEEE operations: their results are equal bit for bit).
    #[inline(always)]
    pub fn dispatch_fused_wide_with<T, R>(
        arg: T,
        plain: impl FnOnce(T) -> R,
        fused: impl FnOnce(T) -> R,
    ) -> R {
        if active_code() == V4 {
            // SAFETY: `ACTIVE` holds `V4` only after `v4_present()` found every feature
            // `run_v4` is compiled with (`detect` and `select` check it before storing), so
            // the CPU executes its instructions.
            #[allow(unsafe_code)]
            unsafe {
                return run_v4(
                    #[inline(always)]
                    || fused(arg),
                );
            }
        }
        dispatch_fused_with(arg, plain, fused)
    }
}

if_not_dispatching! {
    /// Whether this CPU can run `isa`'s copy (this build has only the baseline one).
    pub fn available(isa: Isa) -> bool {
        isa == Isa::Baseline
    }

    /// Calls `f`: this build has one copy of every function (see the module docs).
    #[inline(always)]
    pub fn dispatch<R, F: FnOnce() -> R>(f: F) -> R {
        f()
    }

    /// [`dispatch_fused`] passing `arg` to the copy that runs (for an argument both closures
    /// would otherwise capture, such as a `&mut` result array).
    #[inline(always)]
    pub fn dispatch_fused_with<T, R>(
        arg: T,
        plain: impl FnOnce(T) -> R,
        fused: impl FnOnce(T) -> R,
    ) -> R {
        #[cfg(all(
            feature = "std",
            any(target_feature = "fma", target_arch = "aarch64")
        ))]
        {
            let _ = plain;
            fused(arg)
        }
        #[cfg(not(all(
            feature = "std",
            any(target_feature = "fma", target_arch = "aarch64")
        )))]
        {
            let _ = fused;
            plain(arg)
        }
    }

    /// [`dispatch_fused_with`]: this build has one copy of every function.
    #[inline(always)]
    pub fn dispatch_fused_wide_with<T, R>(
        arg: T,
        plain: impl FnOnce(T) -> R,
        fused: impl FnOnce(T) -> R,
    ) -> R {
        dispatch_fused_with(arg, plain, fused)
    }
}

/// Calls `plain` (compiled for the baseline) or `fused` (compiled for x86-64-v3), by the
/// [`active`] instruction set: a generated function passes its body instantiated with [`Plain`]
/// and with [`Fused`], so that only the x86-64-v3 copy fuses multiply-adds. Without dispatch
/// (see the module docs) there is one copy: `fused` when the compilation target has FMA
/// ([`Native`] is [`Fused`]), `plain` otherwise. [`dispatch_fused_with`] without an argument.
#[inline(always)]
pub fn dispatch_fused<R>(plain: impl FnOnce() -> R, fused: impl FnOnce() -> R) -> R {
    dispatch_fused_with(
        (),
        #[inline(always)]
        |()| plain(),
        #[inline(always)]
        |()| fused(),
    )
}

/// [`dispatch_fused_with`] for a body with paired statements (see [`crate::pair`]): the copy
/// that runs also gets the two-lane multiply-add of its instruction set, [`Plain`] for the
/// baseline copy and a [`FusedPair`] for the fused one. [`dispatch_fused_with`] runs `fused`
/// only in the x86-64-v3 copy after the CPU was found to have it (FMA included), or, without
/// dispatch, in a build compiled with FMA (or on aarch64): where a [`FusedPair`] may exist.
#[inline(always)]
pub fn dispatch_pair_with<T, R>(
    arg: T,
    plain: impl FnOnce(T, Plain) -> R,
    fused: impl FnOnce(T, FusedPair) -> R,
) -> R {
    dispatch_fused_with(
        arg,
        #[inline(always)]
        |arg| plain(arg, Plain),
        #[inline(always)]
        |arg| fused(arg, FusedPair::new_unchecked()),
    )
}

/// [`dispatch_pair_with`] with a third copy of `fused`, compiled for x86-64-v4 and run when
/// [`active`] is [`Isa::X86_64V4`] (as [`dispatch_fused_wide_with`] does): for a body with
/// paired statements that gains from AVX-512's 32 registers and folded broadcasts while it
/// computes with the same two-lane and scalar operations (the same bits as its x86-64-v3
/// copy). The generated looped derivatives use it.
#[inline(always)]
pub fn dispatch_pair_wide_with<T, R>(
    arg: T,
    plain: impl FnOnce(T, Plain) -> R,
    fused: impl FnOnce(T, FusedPair) -> R,
) -> R {
    dispatch_fused_wide_with(
        arg,
        #[inline(always)]
        |arg| plain(arg, Plain),
        #[inline(always)]
        |arg| fused(arg, FusedPair::new_unchecked()),
    )
}

/// The two-lane multiply-add that goes with [`Native`] (for a module generated without
/// dispatch, `kanegen::Builder::isa_dispatch(false)`): a [`FusedPair`] when the build enables
/// FMA (and `std` is on; aarch64), [`Plain`] otherwise.
#[inline(always)]
pub fn native_pair() -> NativePair {
    // The build enables FMA (x86-64) or the lanes are portable (aarch64): see `FusedPair`.
    #[cfg(all(feature = "std", any(target_feature = "fma", target_arch = "aarch64")))]
    {
        FusedPair::new_unchecked()
    }
    #[cfg(not(all(feature = "std", any(target_feature = "fma", target_arch = "aarch64"))))]
    {
        Plain
    }
}

/// What [`native_pair`] returns.
#[cfg(all(feature = "std", any(target_feature = "fma", target_arch = "aarch64")))]
pub type NativePair = FusedPair;

/// What [`native_pair`] returns.
#[cfg(not(all(feature = "std", any(target_feature = "fma", target_arch = "aarch64"))))]
pub type NativePair = Plain;

/// The best instruction set this CPU and this build can dispatch to.
pub fn detected() -> Isa {
    if available(Isa::X86_64V4) {
        Isa::X86_64V4
    } else if available(Isa::X86_64V3) {
        Isa::X86_64V3
    } else {
        Isa::Baseline
    }
}

#[inline(always)]
fn active_code() -> u8 {
    match ACTIVE.load(Ordering::Relaxed) {
        UNKNOWN => detect(),
        code => code,
    }
}

#[cold]
#[inline(never)]
fn detect() -> u8 {
    let code = detected().code();
    // A concurrent `select` wins: keep what is there if it is no longer UNKNOWN.
    match ACTIVE.compare_exchange(UNKNOWN, code, Ordering::Relaxed, Ordering::Relaxed) {
        Ok(_) => code,
        Err(current) => current,
    }
}

/// The instruction set [`dispatch`] uses: [`detected`] at the first call, unless [`select`]ed.
pub fn active() -> Isa {
    match active_code() {
        V3 => Isa::X86_64V3,
        V4 => Isa::X86_64V4,
        _ => Isa::Baseline,
    }
}

/// Make [`dispatch`] use `isa` from now on, in every thread (for benchmarks and tests that
/// compare the copies; generated functions' results differ in the last bits, as the
/// x86-64-v3 copy fuses multiply-adds). An error if this CPU or build
/// cannot run it; nothing changes then.
pub fn select(isa: Isa) -> Result<(), IsaUnavailable> {
    if !available(isa) {
        return Err(IsaUnavailable { isa });
    }
    ACTIVE.store(isa.code(), Ordering::Relaxed);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pair::F64x2;

    fn values() -> impl Iterator<Item = f64> {
        [0.1, -2.5, 3.0e-17, 7.25, -1.0 / 3.0, 1.0e300, -0.0].into_iter()
    }

    #[test]
    fn fused_pairs_give_the_scalar_fused_bits_in_each_lane() {
        // Only where a `FusedPair` can be had: the CPU has x86-64-v3 (or the build FMA).
        let run = |f: FusedPair| {
            for a in values() {
                for b in values() {
                    let v = f.mul_add(F64x2::new(a, b), F64x2::new(b, 3.0), F64x2::new(0.7, a));
                    let lo = <crate::arith::Fused as Arith<f64>>::mul_add(a, b, 0.7);
                    let hi = <crate::arith::Fused as Arith<f64>>::mul_add(b, 3.0, a);
                    assert_eq!(v.lo().to_bits(), lo.to_bits());
                    assert_eq!(v.hi().to_bits(), hi.to_bits());
                }
            }
        };
        dispatch_pair_with((), |(), _plain| {}, |(), fused| run(fused));
    }
}
