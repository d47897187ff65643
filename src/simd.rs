//! Wide code paths chosen at run time (beside the pipeline): the one place where pelage picks an
//! instruction set.
//!
//! The release build targets plain x86-64 (SSE2), so every 4-lane operation of the rasterizer
//! and the fragment stage is an SSE2 instruction. A [`Kernel`] — the rasterizer's replay of one
//! draw's triangles over one tile, with the quad traversal and the fragment stage it calls, all
//! inlined — is compiled once more for x86-64-v3 and once for x86-64-v4 (AVX-512 F, BW, CD,
//! DQ, VL) with `#[target_feature]`, and [`dispatch`] runs the copy of the [`SimdLevel`] asked
//! for, once per tile and draw, never per fragment. The fur stage of a full batch is a
//! [`LevelKernel`] of its own, run through [`dispatch_level`] once per batch: one copy a level,
//! where inlined it was copied at every call site of every fixed-function copy of the quad
//! loop. The body stays ordinary Rust; only the instruction selection differs (VEX or EVEX
//! encoding, three-operand forms, `blendv` or mask registers for selects, BMI shifts) and, at
//! AVX2 and AVX-512, the batch width: the kernel runs with [`AVX2_LANES`] (32) lanes a batch at
//! AVX2, four 256-bit registers of `f32` per lane array, and [`WIDE_LANES`] (16) at AVX-512, one
//! 512-bit register, instead of the baseline's [`LANES`] (8).
//!
//! Why 32 lanes at AVX2. A batch has work that does not grow with its lanes (its set-up, the
//! spots' test once a triangle, the call and the write-back) and its steps are one chain of
//! dependent vector operations (texels, alpha test, shadow, tangent, lighting, eq. 3.7): with
//! more lanes the fixed work is paid once for more of them and every step is several
//! independent 256-bit operations, which the core overlaps. On the AMD EPYC (Zen 3) machine 16
//! lanes took the batch's instructions from 367 to 309 a fragment and the frame's CPU down by
//! about 4 % against 8 (docs/performance.md, "Batches of 16 lanes at AVX2 (AMD EPYC)"); 32 lanes
//! took about 5 % less CPU than 16 for 2 % fewer instructions: the four chains a step hide the
//! latencies that two left exposed (docs/performance.md, "Batches of 32 lanes at AVX2 (AMD
//! EPYC)"). A batch holding at most 16 lanes runs the 16-lane stage (`FurBatch::run`). While
//! the stage was still inlined into the quad loop's copies, 16 AVX2 lanes had taken 41 % more
//! CPU.
//!
//! The AVX-512 level, and why 16 lanes pay now. An earlier AVX-512 copy took 24 % more CPU than
//! the baseline with 4-lane quads, then the same as AVX2 with 8-lane batches and 7–10 % more
//! with 16 (docs/performance.md). Measured and read again for this level: the batches are not
//! the cause (thesis-4-2 fills them to 15.1 lanes of 16 against 7.7 of 8; 80 % of the lanes
//! are lit in both). The copy was: at 16 lanes LLVM left `array::from_fn` and `array::map` in
//! the batch's interpolation out of line, compiled for the baseline (a call and SSE2 code for
//! each component a batch reads, 315 call sites in the copy), and turned a table lookup of the
//! shadow's alphas into gathers; both are plain loops and arithmetic now. And the texture
//! pair's work is per lane (the texel conversion and filter run on a lane's 8 channels, the
//! results go to channel arrays by scalar stores), which wider batches do not shorten: with
//! those fixes, 16 portable lanes took the same CPU as AVX2. The 16-lane batch therefore reads
//! its texture pair with AVX-512 intrinsics (`raster::texture::pairs512`: two lanes a 512-bit
//! register, the transpose in registers), and the level took 14–15 % less CPU than AVX2 on
//! thesis-4-2 (Intel Xeon with AVX-512 FP16, docs/performance.md, "The AVX-512 level"); AVX-512
//! with 8-lane batches took 5 % more. So [`SimdLevel::detected`] picks `avx512` where the CPU
//! has it.
//!
//! Invariant: **every level gives the same bytes.** Every copy runs the same IEEE operations in
//! the same order: Rust never contracts `a·b + c` into a fused multiply-add (LLVM fuses only on
//! an explicit `mul_add`, which no fragment code calls: `src/shading/lanes.rs` forbids it, and
//! the crates below — glam, wide, libm — choose their code paths by compile-time `cfg`, which is
//! the same baseline in every copy; the AVX-512 texture path's intrinsics are each one correctly
//! rounded operation, in the scalar order), never reassociates a sum, and approximate
//! reciprocals are never used. A lane's result never depends on the batch's width.
//! `tests/simd_levels.rs` renders scenes at every level this machine has and compares the
//! bytes; `.ci/run` reruns the golden tests at the baseline after the run at the best level,
//! and at `avx2` too where the CPU has AVX-512.
//!
//! The level is the best the CPU has ([`SimdLevel::detected`]), capped by the environment
//! variable `PELAGE_SIMD` (`scalar`, `sse2`, `avx2`, `avx512`; [`SimdLevel::active`]), or set
//! per frame ([`crate::raster::Frame::set_simd_level`]). `scalar` also makes the renderer run the
//! fur fragment stage's scalar twin (one fragment at a time) instead of the quad stage; the
//! rasterizer's own quad traversal then runs at the baseline. A cap above what the CPU has runs
//! the best it has. On other architectures than x86-64 only the baseline exists.

use std::fmt;
use std::sync::OnceLock;

/// The environment variable that caps the level: `scalar`, `sse2` (alias `baseline`), `avx2`
/// or `avx512`.
pub const SIMD_ENV: &str = "PELAGE_SIMD";

/// An instruction-set level of the hot path, from the narrowest. Levels are ordered: a cap
/// keeps every level up to it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum SimdLevel {
    /// The baseline build with the fur fragment stage's scalar twin, one fragment at a time.
    Scalar,
    /// The baseline build (SSE2 on x86-64; the target's own baseline elsewhere).
    Sse2,
    /// x86-64-v3: AVX2, FMA (never used for fragment arithmetic), BMI1/2, LZCNT, POPCNT, MOVBE.
    Avx2,
    /// x86-64-v4: x86-64-v3 plus AVX-512 F, BW, CD, DQ and VL, with [`Kernel::run`]'s batches
    /// of [`WIDE_LANES`] lanes in 512-bit registers.
    Avx512,
}

/// An unknown value of [`SIMD_ENV`].
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{SIMD_ENV}={value:?} is not a SIMD level: expected scalar, sse2, avx2 or avx512")]
pub struct SimdLevelError {
    /// The value given.
    pub value: String,
}

impl SimdLevel {
    /// Every level, narrowest first.
    pub const ALL: [SimdLevel; 4] = [
        SimdLevel::Scalar,
        SimdLevel::Sse2,
        SimdLevel::Avx2,
        SimdLevel::Avx512,
    ];

    /// The name [`SIMD_ENV`] takes.
    pub fn name(self) -> &'static str {
        match self {
            SimdLevel::Scalar => "scalar",
            SimdLevel::Sse2 => "sse2",
            SimdLevel::Avx2 => "avx2",
            SimdLevel::Avx512 => "avx512",
        }
    }

    /// The best level this CPU runs (detected once, then cached).
    #[inline]
    pub fn detected() -> SimdLevel {
        static DETECTED: OnceLock<SimdLevel> = OnceLock::new();
        *DETECTED.get_or_init(|| {
            if x86::has_avx512() {
                SimdLevel::Avx512
            } else if x86::has_avx2() {
                SimdLevel::Avx2
            } else {
                SimdLevel::Sse2
            }
        })
    }

    /// Every level this CPU runs, narrowest first (always `Scalar` and `Sse2`).
    pub fn available() -> Vec<SimdLevel> {
        let best = SimdLevel::detected();
        SimdLevel::ALL.into_iter().filter(|&l| l <= best).collect()
    }

    /// This level as a cap: itself, or the best the CPU has when that is lower.
    pub fn capped(self) -> SimdLevel {
        self.min(SimdLevel::detected())
    }

    /// The cap [`SIMD_ENV`] sets: `Ok(None)` when unset or empty, an error for an unknown value.
    pub fn from_env() -> Result<Option<SimdLevel>, SimdLevelError> {
        match std::env::var(SIMD_ENV) {
            Ok(value) if value.trim().is_empty() => Ok(None),
            Ok(value) => value.parse().map(Some),
            Err(std::env::VarError::NotPresent) => Ok(None),
            Err(std::env::VarError::NotUnicode(value)) => Err(SimdLevelError {
                value: value.to_string_lossy().into_owned(),
            }),
        }
    }

    /// The level frames run at by default: [`SimdLevel::detected`] capped by [`SIMD_ENV`], read
    /// once per process. An unknown value of the variable is ignored here (the best level runs);
    /// the `pelage` command line refuses it first, with exit status 2.
    pub fn active() -> SimdLevel {
        static ACTIVE: OnceLock<SimdLevel> = OnceLock::new();
        *ACTIVE.get_or_init(|| match SimdLevel::from_env() {
            Ok(Some(cap)) => cap.capped(),
            Ok(None) | Err(_) => SimdLevel::detected(),
        })
    }
}

impl fmt::Display for SimdLevel {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for SimdLevel {
    type Err = SimdLevelError;

    /// A level's name, any case, surrounding blanks ignored; `baseline` names `sse2`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let name = s.trim().to_ascii_lowercase();
        match name.as_str() {
            "scalar" => Ok(SimdLevel::Scalar),
            "sse2" | "baseline" => Ok(SimdLevel::Sse2),
            "avx2" => Ok(SimdLevel::Avx2),
            "avx512" => Ok(SimdLevel::Avx512),
            _ => Err(SimdLevelError {
                value: s.to_string(),
            }),
        }
    }
}

/// Lanes of the batches a [`Kernel`] runs on the baseline (`Scalar`, `Sse2`): two 4-lane
/// quads, two 128-bit registers of `f32`.
pub const LANES: usize = 8;

/// Lanes of the batches a [`Kernel`] runs at [`SimdLevel::Avx512`] (and on the baseline where
/// [`BATCH_LANES_ENV`] asks): four quads, one 512-bit register of `f32`.
pub const WIDE_LANES: usize = 16;

/// Lanes of the batches a [`Kernel`] runs at [`SimdLevel::Avx2`]: eight quads, four 256-bit
/// registers of `f32`. At most 32, the bits of a batch's lane masks.
pub const AVX2_LANES: usize = 32;

/// A piece of hot code compiled once per level: its [`Kernel::run`] must be `#[inline(always)]`,
/// as must everything hot it calls (or be generic and small enough that LLVM inlines it), so
/// that the whole body lands in each level's copy. A function left out of line runs the baseline.
pub trait Kernel {
    /// What the kernel returns.
    type Output;
    /// The body, whose batches (where it batches lanes) hold `BATCH` lanes: [`LANES`],
    /// [`WIDE_LANES`] or [`AVX2_LANES`], as the level's registers suit. Mark it
    /// `#[inline(always)]`.
    fn run<const BATCH: usize>(self) -> Self::Output;
}

/// Runs `kernel` compiled for `level`, or for the best level below it that this CPU has (so no
/// value of `level` can run an instruction the CPU lacks). `Scalar` and `Sse2` run the baseline
/// with 8-lane batches, or 16 where [`BATCH_LANES_ENV`] asks; `Avx2` its copy with 32-lane
/// batches, `Avx512` its copy with 16-lane batches.
///
/// Fuzz builds (`cfg(fuzzing)`, set by cargo-fuzz) hold the baseline copy alone: the fuzz targets
/// look for panics and hangs on bad input, which every copy shares, and each copy is minutes of
/// instrumented compilation.
#[inline(always)]
pub fn dispatch<K: Kernel>(level: SimdLevel, kernel: K) -> K::Output {
    #[cfg(all(target_arch = "x86_64", not(fuzzing)))]
    {
        // The CPU's features from the cache (`detected`): some helpers are dispatched once per
        // quad, where a dozen `is_x86_feature_detected!` tests each time showed in profiles.
        let detected = SimdLevel::detected();
        if level >= SimdLevel::Avx512 && detected >= SimdLevel::Avx512 {
            // SAFETY: the features `x86::avx512` enables were detected on this CPU (`detected`:
            // `x86::has_avx512`, which checks what `x86::avx512` enables).
            return unsafe { x86::avx512(kernel) };
        }
        if level >= SimdLevel::Avx2 && detected >= SimdLevel::Avx2 {
            // SAFETY: the features `x86::avx2` enables were detected on this CPU (`detected`).
            return unsafe { x86::avx2(kernel) };
        }
    }
    let _ = level;
    #[cfg(not(fuzzing))]
    if wide_batches_everywhere() {
        return kernel.run::<WIDE_LANES>();
    }
    kernel.run::<LANES>()
}

/// A part of a [`Kernel`]'s work kept out of line, whose batch width its caller already chose
/// (a type parameter of the kernel, such as the fur stage of one full batch): compiled once per
/// level by [`dispatch_level`], not once per level and width. Its [`LevelKernel::run`] must be
/// `#[inline(always)]`, as must everything hot it calls, as for [`Kernel::run`].
///
/// Why out of line: a body inlined into a [`Kernel`] is copied at each of its call sites in each
/// level's copy (the rasterizer's fixed-function copies of the quad loop each call the shader
/// two or three times), and the fur stage's copies were most of the library's build time.
pub trait LevelKernel {
    /// What the kernel returns.
    type Output;
    /// The body. Mark it `#[inline(always)]`.
    fn run(self) -> Self::Output;
}

/// Runs `kernel` compiled for `level`, or for the best level below it that this CPU has, as
/// [`dispatch`] does, without choosing a batch width (`Scalar` and `Sse2` run the baseline).
#[inline(always)]
pub fn dispatch_level<K: LevelKernel>(level: SimdLevel, kernel: K) -> K::Output {
    #[cfg(all(target_arch = "x86_64", not(fuzzing)))]
    {
        let detected = SimdLevel::detected();
        if level >= SimdLevel::Avx512 && detected >= SimdLevel::Avx512 {
            // SAFETY: the features `x86::avx512_level` enables were detected on this CPU
            // (`detected`: `x86::has_avx512`, which checks what it enables).
            return unsafe { x86::avx512_level(kernel) };
        }
        if level >= SimdLevel::Avx2 && detected >= SimdLevel::Avx2 {
            // SAFETY: the features `x86::avx2_level` enables were detected on this CPU.
            return unsafe { x86::avx2_level(kernel) };
        }
    }
    let _ = level;
    kernel.run()
}

/// The environment variable that runs the fur stage's batches [`WIDE_LANES`] wide on the
/// baseline too (`Scalar`'s rasterizer and `Sse2`): `16`, the one value it takes (unset or
/// empty: 8 there). The baseline copy of the quad traversal then runs 16-lane batches, so that
/// both widths run on the same code: a lane's result never depends on the batch's width
/// (`tests/simd_levels.rs`). For checking only; AVX-512 runs 16 lanes anyway, AVX2 32.
pub const BATCH_LANES_ENV: &str = "PELAGE_BATCH_LANES";

/// An unknown value of [`BATCH_LANES_ENV`].
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{BATCH_LANES_ENV}={value:?} is not a batch width: expected 16 (or unset)")]
pub struct BatchLanesError {
    /// The value given.
    pub value: String,
}

/// Whether [`BATCH_LANES_ENV`] asks for 16-lane batches at every level: `Ok(false)` when unset
/// or empty, an error for any other value than `16`.
pub fn wide_batches_from_env() -> Result<bool, BatchLanesError> {
    match std::env::var(BATCH_LANES_ENV) {
        Ok(value) if value.trim().is_empty() => Ok(false),
        Ok(value) if value.trim() == "16" => Ok(true),
        Ok(value) => Err(BatchLanesError { value }),
        Err(std::env::VarError::NotPresent) => Ok(false),
        Err(std::env::VarError::NotUnicode(value)) => Err(BatchLanesError {
            value: value.to_string_lossy().into_owned(),
        }),
    }
}

/// [`wide_batches_from_env`], read once per process; an unknown value is ignored here (the
/// `pelage` command line refuses it first, with exit status 2).
#[cfg_attr(fuzzing, allow(dead_code))]
fn wide_batches_everywhere() -> bool {
    static WIDE: OnceLock<bool> = OnceLock::new();
    *WIDE.get_or_init(|| wide_batches_from_env().unwrap_or(false))
}

/// The x86-64 copies and their feature tests (`is_x86_feature_detected!` caches its answer).
#[cfg(target_arch = "x86_64")]
mod x86 {
    #[cfg_attr(fuzzing, allow(unused_imports))]
    use super::{AVX2_LANES, Kernel, LevelKernel, WIDE_LANES};

    /// x86-64-v3.
    pub(super) fn has_avx2() -> bool {
        is_x86_feature_detected!("avx2")
            && is_x86_feature_detected!("fma")
            && is_x86_feature_detected!("bmi1")
            && is_x86_feature_detected!("bmi2")
            && is_x86_feature_detected!("lzcnt")
            && is_x86_feature_detected!("popcnt")
            && is_x86_feature_detected!("movbe")
    }

    /// x86-64-v4: x86-64-v3 and AVX-512 F, BW, CD, DQ, VL (which the standard library's test
    /// also checks the operating system saves).
    pub(super) fn has_avx512() -> bool {
        has_avx2()
            && is_x86_feature_detected!("avx512f")
            && is_x86_feature_detected!("avx512bw")
            && is_x86_feature_detected!("avx512cd")
            && is_x86_feature_detected!("avx512dq")
            && is_x86_feature_detected!("avx512vl")
    }

    #[cfg(not(fuzzing))]
    #[target_feature(enable = "avx2,fma,bmi1,bmi2,lzcnt,popcnt,movbe")]
    pub(super) fn avx2<K: Kernel>(kernel: K) -> K::Output {
        kernel.run::<AVX2_LANES>()
    }

    #[cfg(not(fuzzing))]
    #[target_feature(
        enable = "avx2,fma,bmi1,bmi2,lzcnt,popcnt,movbe,avx512f,avx512bw,avx512cd,avx512dq,avx512vl"
    )]
    pub(super) fn avx512<K: Kernel>(kernel: K) -> K::Output {
        kernel.run::<WIDE_LANES>()
    }

    #[cfg(not(fuzzing))]
    #[target_feature(enable = "avx2,fma,bmi1,bmi2,lzcnt,popcnt,movbe")]
    pub(super) fn avx2_level<K: LevelKernel>(kernel: K) -> K::Output {
        kernel.run()
    }

    #[cfg(not(fuzzing))]
    #[target_feature(
        enable = "avx2,fma,bmi1,bmi2,lzcnt,popcnt,movbe,avx512f,avx512bw,avx512cd,avx512dq,avx512vl"
    )]
    pub(super) fn avx512_level<K: LevelKernel>(kernel: K) -> K::Output {
        kernel.run()
    }
}

/// Elsewhere only the baseline exists.
#[cfg(not(target_arch = "x86_64"))]
mod x86 {
    pub(super) fn has_avx2() -> bool {
        false
    }

    pub(super) fn has_avx512() -> bool {
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Sum<'a>(&'a [f32]);

    impl Kernel for Sum<'_> {
        type Output = f32;
        #[inline(always)]
        fn run<const BATCH: usize>(self) -> f32 {
            // A left-to-right sum of products: any contraction or reassociation would show.
            self.0.iter().fold(0.0, |s, &x| s + x * 1.1)
        }
    }

    #[test]
    fn names_round_trip_and_unknown_names_are_refused() {
        for level in SimdLevel::ALL {
            assert_eq!(level.name().parse::<SimdLevel>(), Ok(level));
            assert_eq!(level.to_string().to_uppercase().parse(), Ok(level));
        }
        assert_eq!(" baseline ".parse(), Ok(SimdLevel::Sse2));
        assert_eq!("AVX512".parse(), Ok(SimdLevel::Avx512));
        let e = "avx1024".parse::<SimdLevel>().unwrap_err();
        assert!(e.to_string().contains("\"avx1024\""), "{e}");
        assert!(e.to_string().contains("avx2 or avx512"), "{e}");
    }

    #[test]
    fn levels_are_capped_by_the_cpu() {
        let best = SimdLevel::detected();
        assert_eq!(SimdLevel::Avx512.capped(), best);
        assert_eq!(SimdLevel::Avx2.capped(), best.min(SimdLevel::Avx2));
        assert_eq!(SimdLevel::Scalar.capped(), SimdLevel::Scalar);
        assert!(SimdLevel::available().contains(&SimdLevel::Sse2));
        assert_eq!(SimdLevel::available().last(), Some(&best));
    }

    struct Width;

    impl Kernel for Width {
        type Output = usize;
        #[inline(always)]
        fn run<const BATCH: usize>(self) -> usize {
            BATCH
        }
    }

    #[test]
    fn batches_hold_32_lanes_at_avx2_and_16_at_avx512() {
        for level in SimdLevel::ALL {
            let lanes = match level.capped() {
                SimdLevel::Avx512 => WIDE_LANES,
                SimdLevel::Avx2 => AVX2_LANES,
                _ if wide_batches_everywhere() => WIDE_LANES,
                _ => LANES,
            };
            assert_eq!(dispatch(level, Width), lanes, "{level}");
        }
    }

    impl LevelKernel for Sum<'_> {
        type Output = f32;
        #[inline(always)]
        fn run(self) -> f32 {
            Kernel::run::<LANES>(self)
        }
    }

    #[test]
    fn every_level_gives_the_same_bits() {
        let values: Vec<f32> = (0..1000).map(|i| (i as f32 * 0.37).sin() * 1e3).collect();
        let baseline = dispatch(SimdLevel::Sse2, Sum(&values));
        for level in SimdLevel::ALL {
            assert_eq!(
                dispatch(level, Sum(&values)).to_bits(),
                baseline.to_bits(),
                "{level}"
            );
            assert_eq!(
                dispatch_level(level, Sum(&values)).to_bits(),
                baseline.to_bits(),
                "{level}"
            );
        }
    }
}
