//! Test-only helpers (shading stage): a tiny deterministic LCG (no extra crates) and a closeness
//! check against an f64 reference value.

use glam::Vec3;

/// Knuth's MMIX linear congruential generator; the high bits are used.
pub(crate) struct Lcg(u64);

impl Lcg {
    pub(crate) fn new(seed: u64) -> Self {
        Lcg(seed ^ 0x9E37_79B9_7F4A_7C15)
    }

    pub(crate) fn next_u64(&mut self) -> u64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        self.0
    }

    /// Uniform in `[0, 1)` with 24 random bits, exactly representable in f32.
    pub(crate) fn unit(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }

    /// Uniform in `[lo, hi)`.
    pub(crate) fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.unit()
    }

    /// A vector uniform in the cube `[-1, 1)³`.
    pub(crate) fn cube(&mut self) -> Vec3 {
        Vec3::new(
            self.range(-1.0, 1.0),
            self.range(-1.0, 1.0),
            self.range(-1.0, 1.0),
        )
    }

    /// A random direction (normalised in f32), by rejection from the cube.
    pub(crate) fn direction(&mut self) -> Vec3 {
        loop {
            let v = self.cube();
            let l2 = v.length_squared();
            if l2 > 0.01 && l2 <= 1.0 {
                return v.normalize();
            }
        }
    }
}

/// Panics (in tests only) unless `|actual − expected| <= tol`.
#[track_caller]
pub(crate) fn assert_close(actual: f32, expected: f64, tol: f64, what: &str) {
    let err = (f64::from(actual) - expected).abs();
    assert!(
        actual.is_finite() && err <= tol,
        "{what}: got {actual}, expected {expected}, |err| = {err:e} > tol {tol:e}"
    );
}
