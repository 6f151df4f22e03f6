//! Hot functions compiled for wider instruction sets and chosen when they run: the workspace's
//! second `unsafe` exception (the first is the prefetch hint, [`mod@crate::prefetch`]).
//!
//! The binary is built for baseline x86-64 (SSE2), so that it runs on every x86-64 processor.
//! A few self-contained hot functions run faster when compiled for a wider instruction set:
//! the nearest-hit query (`scene::Scene::intersect`: slab tests and triangle blocks on glam's
//! `Vec4`, which AVX encodes without register copies; the measured gain is AVX-512's, AVX2's is
//! about nothing there) and the Sobol point (`crate::sobol::point`: its eight 32-bit lanes are
//! one AVX2 register, and AVX-512 multiplies its 64-bit hashes in vector registers too). [`dispatch`] runs such a
//! function, written as a [`Kernel`], through one of three copies — baseline, x86-64-v3 (AVX2)
//! and x86-64-v4 (AVX-512) — the widest that the processor supports ([`Isa::active`]).
//!
//! The copies compute the same values bit for bit: they are the same Rust code, and Rust never
//! contracts a multiplication and an addition into a fused multiply-add, nor uses approximate
//! reciprocals, whatever the target features; `cfg(target_feature)` code in dependencies (glam)
//! is chosen when the crate is compiled, the same for every copy. Tests compare each available
//! copy with the baseline one (`scene_intersect_is_the_same_with_every_instruction_set` in
//! `scene`'s BVH tests, `point_copies_agree` in `sobol`), and `scripts/image-identity.sh` renders the same images with `VCM_ISA=baseline`.
//!
//! Why `unsafe`: calling a function compiled with `#[target_feature]` from code compiled
//! without it is `unsafe` in Rust, because running it on a processor without those features
//! is undefined behaviour. A copy runs only for a set at most [`Isa::detected`], which has
//! confirmed every feature the copy is compiled with. What it gains is measured in docs/bvh.md
//! ("Instruction sets chosen at run time"), which is what this exception rests on; `.ci/run`
//! checks that no other file than this one and `prefetch.rs` allows `unsafe_code`.
//!
//! A kernel's body is `#[inline(always)]`, so each copy compiles it for its own instruction set
//! (a closure was not inlined: the copies were a few bytes that called it).

use std::sync::atomic::{AtomicU8, Ordering};

/// The environment variable that limits the instruction set of [`dispatch`], read once per
/// process: `baseline`, `avx2` or `avx512` (for A/B measurements in one binary; the images are
/// the same with each).
pub const ISA_ENV: &str = "VCM_ISA";

/// The instruction sets a dispatched function can run with, narrowest first.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
#[repr(u8)]
pub enum Isa {
    /// Baseline x86-64 (SSE2), or any other architecture.
    Baseline,
    /// x86-64-v3: AVX2, FMA (which no arithmetic uses, see the module doc), BMI1/2, LZCNT.
    Avx2,
    /// x86-64-v4: AVX-512 F, BW, CD, DQ and VL on top of x86-64-v3.
    Avx512,
}

/// [`Isa::detected`]'s cache: 0 before the first detection, then the detected set plus one.
/// Only [`Isa::detect`]'s answer is ever stored.
static DETECTED: AtomicU8 = AtomicU8::new(0);

/// [`Isa::active`]'s cache: 0 before its first call, then the active set plus one. Only
/// values at most [`Isa::detected`] are ever stored.
static ACTIVE: AtomicU8 = AtomicU8::new(0);

impl Isa {
    /// The set whose discriminant is `code − 1` (the caches' encoding).
    #[inline(always)]
    fn from_code(code: u8) -> Option<Isa> {
        match code {
            1 => Some(Isa::Baseline),
            2 => Some(Isa::Avx2),
            3 => Some(Isa::Avx512),
            _ => None,
        }
    }

    /// The widest instruction set this processor supports (detected once, then cached).
    #[inline(always)]
    pub fn detected() -> Isa {
        if let Some(isa) = Isa::from_code(DETECTED.load(Ordering::Relaxed)) {
            return isa;
        }
        let isa = Isa::detect();
        DETECTED.store(isa as u8 + 1, Ordering::Relaxed);
        isa
    }

    /// The set [`dispatch`] uses: the widest this processor supports, limited by [`ISA_ENV`]
    /// (decided once per process, then cached).
    #[inline(always)]
    pub fn active() -> Isa {
        if let Some(isa) = Isa::from_code(ACTIVE.load(Ordering::Relaxed)) {
            return isa;
        }
        let isa = Isa::from_env().min(Isa::detected());
        ACTIVE.store(isa as u8 + 1, Ordering::Relaxed);
        isa
    }

    /// Asks the processor (through the standard library) which features it has.
    #[cold]
    fn detect() -> Isa {
        #[cfg(target_arch = "x86_64")]
        {
            if has_v4() {
                return Isa::Avx512;
            }
            if has_v3() {
                return Isa::Avx2;
            }
        }
        Isa::Baseline
    }

    /// The limit [`ISA_ENV`] sets: the widest set when it is unset, an error naming the values
    /// it may take when it is set to anything else.
    pub fn limit_from_env() -> Result<Isa, String> {
        let expected = "expected baseline, avx2 or avx512";
        match std::env::var(ISA_ENV) {
            Err(std::env::VarError::NotPresent) => Ok(Isa::Avx512),
            Ok(value) => Isa::parse(&value).ok_or_else(|| format!("{ISA_ENV}={value:?}: {expected}")),
            Err(std::env::VarError::NotUnicode(value)) => Err(format!("{ISA_ENV}={value:?}: {expected}")),
        }
    }

    /// [`Isa::limit_from_env`], with the widest set for a value it does not know (front ends
    /// report that error when they start, e.g. `vcm`'s `main`).
    #[cold]
    fn from_env() -> Isa {
        Isa::limit_from_env().unwrap_or(Isa::Avx512)
    }

    /// The set named `baseline`, `avx2` or `avx512`.
    pub fn parse(name: &str) -> Option<Isa> {
        match name {
            "baseline" => Some(Isa::Baseline),
            "avx2" => Some(Isa::Avx2),
            "avx512" => Some(Isa::Avx512),
            _ => None,
        }
    }

    /// A name for reports, e.g. `AVX-512 (x86-64-v4)`.
    pub fn name(self) -> &'static str {
        match self {
            Isa::Baseline => "baseline x86-64",
            Isa::Avx2 => "AVX2 (x86-64-v3)",
            Isa::Avx512 => "AVX-512 (x86-64-v4)",
        }
    }
}

/// True when the processor has every feature in [`run_v3`]'s `target_feature` list.
#[cfg(target_arch = "x86_64")]
fn has_v3() -> bool {
    std::arch::is_x86_feature_detected!("avx2")
        && std::arch::is_x86_feature_detected!("fma")
        && std::arch::is_x86_feature_detected!("bmi1")
        && std::arch::is_x86_feature_detected!("bmi2")
        && std::arch::is_x86_feature_detected!("lzcnt")
}

/// True when the processor has every feature in [`run_v4`]'s `target_feature` list.
#[cfg(target_arch = "x86_64")]
fn has_v4() -> bool {
    has_v3()
        && std::arch::is_x86_feature_detected!("avx512f")
        && std::arch::is_x86_feature_detected!("avx512bw")
        && std::arch::is_x86_feature_detected!("avx512cd")
        && std::arch::is_x86_feature_detected!("avx512dq")
        && std::arch::is_x86_feature_detected!("avx512vl")
}

/// A function to run through [`dispatch`]: its arguments as fields, its body in [`Kernel::run`],
/// which must be `#[inline(always)]` so that each copy compiles the body for its own
/// instruction set (a closure was not inlined into the copies: they only called it).
pub trait Kernel {
    /// What the function returns.
    type Output;
    /// The function's body. Mark it `#[inline(always)]`.
    fn run(self) -> Self::Output;
}

/// Runs `kernel` compiled for the active instruction set ([`Isa::active`]): one cached load
/// per call.
#[inline(always)]
pub fn dispatch<K: Kernel>(kernel: K) -> K::Output {
    run_supported(Isa::active(), kernel)
}

/// Runs `kernel` compiled for the widest instruction set up to `limit` that this processor
/// supports (tests and A/B measurements compare the copies with it).
#[inline(always)]
pub fn dispatch_at<K: Kernel>(limit: Isa, kernel: K) -> K::Output {
    run_supported(limit.min(Isa::detected()), kernel)
}

/// Runs `kernel`'s copy for `isa`, which the caller guarantees to be at most
/// [`Isa::detected`]: [`Isa::active`] is (only `min(limit, detected)` is ever cached), and
/// [`dispatch_at`] takes that minimum itself.
#[inline(always)]
#[allow(unsafe_code)]
fn run_supported<K: Kernel>(isa: Isa, kernel: K) -> K::Output {
    #[cfg(target_arch = "x86_64")]
    match isa {
        // SAFETY: `isa ≤ Isa::detected()`, which is `Avx512` only when `has_v4` found every
        // feature that `run_v4` is compiled with on this processor.
        Isa::Avx512 => unsafe { run_v4(kernel) },
        // SAFETY: `isa ≤ Isa::detected()`, which is at least `Avx2` only when `has_v3` found
        // every feature of `run_v3` (`has_v4` includes `has_v3`).
        Isa::Avx2 => unsafe { run_v3(kernel) },
        Isa::Baseline => kernel.run(),
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let _ = isa;
        kernel.run()
    }
}

/// `kernel`'s body compiled for x86-64-v3.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma,bmi1,bmi2,lzcnt")]
fn run_v3<K: Kernel>(kernel: K) -> K::Output {
    kernel.run()
}

/// `kernel`'s body compiled for x86-64-v4.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma,bmi1,bmi2,lzcnt,avx512f,avx512bw,avx512cd,avx512dq,avx512vl")]
fn run_v4<K: Kernel>(kernel: K) -> K::Output {
    kernel.run()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_parse_back_and_order_by_width() {
        for isa in [Isa::Baseline, Isa::Avx2, Isa::Avx512] {
            let short = match isa {
                Isa::Baseline => "baseline",
                Isa::Avx2 => "avx2",
                Isa::Avx512 => "avx512",
            };
            assert_eq!(Isa::parse(short), Some(isa));
        }
        assert_eq!(Isa::parse("AVX2"), None);
        assert!(Isa::Baseline < Isa::Avx2 && Isa::Avx2 < Isa::Avx512);
        assert!(Isa::active() <= Isa::detected());
    }

    /// Sums `count` bit-reversed integers as floats.
    struct ReversedSum<'a> {
        count: u32,
        calls: &'a mut u32,
    }

    impl Kernel for ReversedSum<'_> {
        type Output = f32;
        #[inline(always)]
        fn run(self) -> f32 {
            *self.calls += 1;
            (0..self.count).map(|i| i.reverse_bits() as f32).sum()
        }
    }

    #[test]
    fn every_copy_runs_the_kernel_once_with_the_same_result() {
        let expected = (0..1000u32).map(|i| i.reverse_bits() as f32).sum::<f32>();
        for limit in [Isa::Baseline, Isa::Avx2, Isa::Avx512] {
            let mut calls = 0;
            let out = dispatch_at(limit, ReversedSum { count: 1000, calls: &mut calls });
            assert_eq!(calls, 1);
            assert_eq!(out.to_bits(), expected.to_bits(), "{limit:?}");
        }
    }
}
