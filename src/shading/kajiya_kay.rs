//! Kajiya–Kay strand lighting (thesis eq. 2.5 and 2.7, section 3.2.3; shading stage): diffuse from
//! the sine between tangent and light, raised to Banks's exponent; specular from the reflection
//! cone, with one tangent or three (Scheuermann's shifted tangents). Every result lies in `[0, 1]`.

use super::lanes::Vec3xN;
use super::numeric::{finite_or_zero, pow01, pow01_diffuse_specular_dampened_lanes, pow01_lanes};
use super::tangent_space::{cos_sin_unit, cos_sin_unit_lanes};
use glam::Vec3;

/// Banks's exponent on the Kajiya–Kay diffuse term, 4.8 (thesis 3.2.3: "the dampening is done
/// by exponentiating the diffuse value by 4.8 as stated by Banks").
pub const BANKS_EXPONENT: f32 = 4.8;

/// Kajiya–Kay diffuse, thesis eq. 2.5 (`ψ_diffuse = k_d sin(t, l)`), raised to Banks's exponent
/// (3.2.3): `sin(t, l)^p`, in `[0, 1]`.
///
/// Inputs need not be unit (normalised inside). A tangent parallel to the light gives 0; a zero
/// or NaN vector gives `0^p` (0 for `p > 0`). Exponent convention: NaN acts as 1, negative as 0.
#[inline]
pub fn kajiya_kay_diffuse(tangent: Vec3, light: Vec3, banks_exponent: f32) -> f32 {
    let (_, s) = cos_sin_unit(tangent.normalize_or_zero(), light.normalize_or_zero());
    pow01(s, banks_exponent)
}

/// Kajiya–Kay specular, thesis eq. 2.7:
/// `max(0, (t·l)(t·e) + sin(t, l)·sin(t, e))^p`, in `[0, 1]`.
///
/// The sign convention follows the thesis's equation as printed (a `+` between the two
/// products, with `l` and `e` both pointing away from the surface point); Kajiya and Kay's own
/// derivation via `cos(θ − θ')` (eq. 2.6) would differ in the sign of the first product.
/// Inputs are normalised inside; a zero or NaN vector makes its products 0, so the result is
/// `0^p`. The exponent convention is that of [`kajiya_kay_diffuse`].
#[inline]
pub fn kajiya_kay_specular(tangent: Vec3, light: Vec3, eye: Vec3, exponent: f32) -> f32 {
    specular_unit(
        tangent.normalize_or_zero(),
        light.normalize_or_zero(),
        eye.normalize_or_zero(),
        exponent,
    )
}

/// Eq. 2.7 on vectors already unit (or zero).
#[inline]
fn specular_unit(t: Vec3, l: Vec3, e: Vec3, exponent: f32) -> f32 {
    pow01(specular_base_unit(t, l, e), exponent)
}

/// The base of eq. 2.7 before the power, `(t·l)(t·e) + sin(t, l)·sin(t, e)`, on unit vectors.
#[inline]
fn specular_base_unit(t: Vec3, l: Vec3, e: Vec3) -> f32 {
    let (cl, sl) = cos_sin_unit(t, l);
    let (ce, se) = cos_sin_unit(t, e);
    cl * ce + sl * se
}

/// The exponents of the three strand lighting terms.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightingExponents {
    /// Banks's exponent on the diffuse (eq. 2.5, 3.2.3).
    pub banks: f32,
    /// The specular exponent (eq. 2.7).
    pub specular: f32,
    /// The exponent of the single-tangent lobe the uncoloured last term is made of: the
    /// specular that is then dampened (3.2.3, eq. 3.6/3.7); under eq. 3.5 the specular
    /// exponent itself, so the lobe is `ψ_specularity1`
    /// ([`LightingModel::lobe_exponent`](super::LightingModel::lobe_exponent)).
    pub dampened: f32,
}

/// The three strand lighting terms of one fragment, before eq. 3.7.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StrandLighting {
    /// [`kajiya_kay_diffuse`] with Banks's exponent.
    pub diffuse: f32,
    /// [`specular_with_tangents`] with the specular exponent.
    pub specular: f32,
    /// [`kajiya_kay_specular`] of the strand's own tangent with the third exponent
    /// ([`LightingExponents::dampened`]): the lobe of the uncoloured last term, before
    /// [`uncoloured_specular`](super::uncoloured_specular) (dampened under eq. 3.6/3.7, raised
    /// to `n` under eq. 3.5).
    pub specular_to_dampen: f32,
}

/// Eq. 2.5 and 2.7 together, as the fur shader needs them: bit-identical to
/// `kajiya_kay_diffuse(t, l, banks)`, `specular_with_tangents(t, n, l, e, specular, tangents,
/// shift)` and `kajiya_kay_specular(t, l, e, dampened)`, but the tangent, light and eye are
/// normalised once and the powers are taken four at a time (they are most of a fragment's cost).
#[inline]
pub fn strand_lighting(
    tangent: Vec3,
    normal: Vec3,
    light: Vec3,
    eye: Vec3,
    exponents: LightingExponents,
    tangents: SpecularTangents,
    shift: f32,
) -> StrandLighting {
    let bases = LightingBases::new(tangent, normal, light, eye, tangents, shift);
    match tangents {
        SpecularTangents::One => {
            let [diffuse, specular, specular_to_dampen, _] = pow01_lanes(
                [bases.diffuse, bases.centre, bases.centre, 0.0],
                [exponents.banks, exponents.specular, exponents.dampened, 1.0],
            );
            StrandLighting {
                diffuse,
                specular,
                specular_to_dampen,
            }
        }
        SpecularTangents::Three(lobes) => {
            let [diffuse, centre_specular, specular_to_dampen, up_specular] = pow01_lanes(
                [bases.diffuse, bases.centre, bases.centre, bases.up],
                [
                    exponents.banks,
                    exponents.specular,
                    exponents.dampened,
                    exponents.specular,
                ],
            );
            let down_specular = pow01(bases.down, exponents.specular);
            StrandLighting {
                diffuse,
                specular: three_lobe_specular(centre_specular, up_specular, down_specular, lobes),
                specular_to_dampen,
            }
        }
    }
}

/// [`StrandLighting`] of `N` lanes, one array per term.
#[derive(Clone, Copy, Debug)]
pub struct StrandLightingLanes<const N: usize> {
    /// The diffuse terms.
    pub diffuse: [f32; N],
    /// The specular terms.
    pub specular: [f32; N],
    /// The specular terms the dampened specular is taken of.
    pub specular_to_dampen: [f32; N],
}

/// [`strand_lighting`] for `N` independent fragments (the lit lanes of a batch), lane by lane
/// bit-identical to it: the bases are computed on the lanes at once ([`Vec3xN`], the same
/// operations per lane), and each power is taken by lanes of the same exponent, three (one
/// tangent) or five (three tangents) batches for all lanes instead of three or four per lane.
#[inline(always)]
pub fn strand_lighting_lanes<const N: usize>(
    tangent: &Vec3xN<N>,
    normal: &Vec3xN<N>,
    light: &Vec3xN<N>,
    eye: &Vec3xN<N>,
    exponents: LightingExponents,
    tangents: SpecularTangents,
    shift: f32,
) -> StrandLightingLanes<N> {
    let t = tangent.normalize_or_zero();
    let l = light.normalize_or_zero();
    let e = eye.normalize_or_zero();
    let (cos_tl, sin_tl) = cos_sin_unit_lanes(&t, &l);
    let centre = specular_base_lanes(&t, &e, cos_tl, sin_tl);
    let (diffuse, centre_specular, specular_to_dampen) = pow01_diffuse_specular_dampened_lanes(
        sin_tl,
        centre,
        [exponents.banks, exponents.specular, exponents.dampened],
    );
    let specular = match tangents {
        SpecularTangents::One => centre_specular,
        SpecularTangents::Three(lobes) => {
            let n = normal.normalize_or_zero();
            let up = shifted_specular_lanes(&t, &n, &l, &e, shift, exponents.specular);
            let down = shifted_specular_lanes(&t, &n, &l, &e, -shift, exponents.specular);
            let mut specular = [0.0; N];
            for i in 0..N {
                specular[i] = three_lobe_specular(centre_specular[i], up[i], down[i], lobes);
            }
            specular
        }
    };
    StrandLightingLanes {
        diffuse,
        specular,
        specular_to_dampen,
    }
}

/// The specular base of eq. 2.7 on `N` lanes from the tangent's cosine and sine with the
/// light: `cos(t,l)·cos(t,e) + sin(t,l)·sin(t,e)`, as [`specular_base_unit`].
#[inline(always)]
fn specular_base_lanes<const N: usize>(
    t: &Vec3xN<N>,
    e: &Vec3xN<N>,
    cos_tl: [f32; N],
    sin_tl: [f32; N],
) -> [f32; N] {
    let (ce, se) = cos_sin_unit_lanes(t, e);
    let mut base = [0.0; N];
    for i in 0..N {
        base[i] = cos_tl[i] * ce[i] + sin_tl[i] * se[i];
    }
    base
}

/// The specular lobe of the tangent shifted by `shift` along the normal (eq. 3.5), on `N`
/// lanes of unit vectors: [`shift_tangent`], its base, and the power.
#[inline(always)]
fn shifted_specular_lanes<const N: usize>(
    t: &Vec3xN<N>,
    n: &Vec3xN<N>,
    l: &Vec3xN<N>,
    e: &Vec3xN<N>,
    shift: f32,
    exponent: f32,
) -> [f32; N] {
    let shifted = t
        .add_scaled([finite_or_zero(shift); N], n)
        .normalize_or_zero();
    let (cos_tl, sin_tl) = cos_sin_unit_lanes(&shifted, l);
    pow01_lanes(
        specular_base_lanes(&shifted, e, cos_tl, sin_tl),
        [exponent; N],
    )
}

/// The bases of the powers of one fragment's strand lighting, from the inputs normalised once:
/// `sin(t, l)` (eq. 2.5), the specular base of eq. 2.7 for the tangent and, with three
/// tangents, for the two shifted ones (0 with one tangent).
#[derive(Clone, Copy)]
struct LightingBases {
    diffuse: f32,
    centre: f32,
    up: f32,
    down: f32,
}

impl LightingBases {
    #[inline(always)]
    fn new(
        tangent: Vec3,
        normal: Vec3,
        light: Vec3,
        eye: Vec3,
        tangents: SpecularTangents,
        shift: f32,
    ) -> Self {
        let t = tangent.normalize_or_zero();
        let l = light.normalize_or_zero();
        let e = eye.normalize_or_zero();
        let diffuse = cos_sin_unit(t, l).1;
        let centre = specular_base_unit(t, l, e);
        let (up, down) = match tangents {
            SpecularTangents::One => (0.0, 0.0),
            SpecularTangents::Three(_) => {
                let n = normal.normalize_or_zero();
                (
                    specular_base_unit(shift_tangent(t, n, shift), l, e),
                    specular_base_unit(shift_tangent(t, n, -shift), l, e),
                )
            }
        };
        LightingBases {
            diffuse,
            centre,
            up,
            down,
        }
    }
}

/// How the three lobes of the three-tangent specular (eq. 3.5) combine into one term.
///
/// The thesis (3.2.3, after eq. 3.5): "The new specular term is the **sum** of the three
/// specular values, having three different tangent values" ([`SpecularLobes::Sum`]). The same
/// section, after eq. 3.7, gives the range of every term as "Ambient, diffuse, specularly all
/// ranges from \[0,1\]", which only the mean keeps ([`SpecularLobes::Average`]). Scene key
/// `shading.specular_lobes`; the default is [`SpecularLobes::Average`]: see
/// [`three_lobe_specular`] for why.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SpecularLobes {
    /// The thesis's sum of the three lobes, in `[0, 3]` ([`specular_lobe_sum`]).
    Sum,
    /// The mean of the three lobes, in `[0, 1]` like one lobe ([`specular_lobe_mean`]).
    #[default]
    Average,
}

/// The thesis's three-tangent specular (3.2.3, eq. 3.5): "the sum of the three specular
/// values", `centre + up + down`, added in that order; in `[0, 3]` for lobes in `[0, 1]`.
#[inline(always)]
pub fn specular_lobe_sum(centre: f32, up: f32, down: f32) -> f32 {
    centre + up + down
}

/// The three-tangent specular as a mean (pelage's earlier convention):
/// `(centre + up + down) / 3`, summed in that order and then divided once; in `[0, 1]` for
/// lobes in `[0, 1]`, so the specular weight of eq. 3.7 means the same with one or three
/// tangents.
#[inline(always)]
pub fn specular_lobe_mean(centre: f32, up: f32, down: f32) -> f32 {
    specular_lobe_sum(centre, up, down) / 3.0
}

/// The three lobes of eq. 3.5 combined as `lobes` says: [`specular_lobe_sum`] or
/// [`specular_lobe_mean`].
///
/// Why the mean is the default, though the thesis writes "sum": its own ranges after eq. 3.7
/// put the specular in `[0, 1]`, which the sum leaves (up to 3); with the mean the specular
/// weight of eq. 3.7 means the same with one or three tangents, so switching
/// `specular_tangents` (a column of thesis table 4.4) changes the highlight's shape, not its
/// brightness. Rendered, `scenes/specular.toml` with the sum turns the lit half of the torus
/// white (every channel clamped at 1); with the sum a scene needs a third of the weight to
/// look the same (README, "Where pelage departs from the thesis").
#[inline(always)]
pub fn three_lobe_specular(centre: f32, up: f32, down: f32, lobes: SpecularLobes) -> f32 {
    match lobes {
        SpecularLobes::Sum => specular_lobe_sum(centre, up, down),
        SpecularLobes::Average => specular_lobe_mean(centre, up, down),
    }
}

/// How many tangents the specular term of eq. 3.5 uses (thesis table 4.4: 1 or 3).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SpecularTangents {
    /// The strand tangent alone.
    #[default]
    One,
    /// The strand tangent and two copies shifted along the normal, back and forth
    /// (Scheuermann), their lobes combined as the [`SpecularLobes`] says.
    Three(SpecularLobes),
}

/// Scheuermann's shifted tangent (thesis 3.2.3, eq. 3.5): `normalize(t + shift·n)`.
///
/// Expects unit `tangent` and `normal`; returns a unit vector, or zero when `t + shift·n` has
/// no direction (e.g. `t = −n`, `shift = 1`) or is not finite. A non-finite `shift` acts as 0.
#[inline]
pub fn shift_tangent(tangent: Vec3, normal: Vec3, shift: f32) -> Vec3 {
    (tangent + finite_or_zero(shift) * normal).normalize_or_zero()
}

/// The specular term with one or three tangents (thesis 3.2.3, eq. 3.5).
///
/// With [`SpecularTangents::One`] it is [`kajiya_kay_specular`]. With
/// [`SpecularTangents::Three`] it combines the speculars of `t`, `shift_tangent(t, n, +shift)`
/// and `shift_tangent(t, n, −shift)` with [`three_lobe_specular`]: their mean (the default) or
/// their sum (the thesis's words), in that fixed order.
#[inline]
pub fn specular_with_tangents(
    tangent: Vec3,
    normal: Vec3,
    light: Vec3,
    eye: Vec3,
    exponent: f32,
    tangents: SpecularTangents,
    shift: f32,
) -> f32 {
    let t = tangent.normalize_or_zero();
    let l = light.normalize_or_zero();
    let e = eye.normalize_or_zero();
    let centre = specular_unit(t, l, e, exponent);
    match tangents {
        SpecularTangents::One => centre,
        SpecularTangents::Three(lobes) => {
            let n = normal.normalize_or_zero();
            let up = specular_unit(shift_tangent(t, n, shift), l, e, exponent);
            let down = specular_unit(shift_tangent(t, n, -shift), l, e, exponent);
            three_lobe_specular(centre, up, down, lobes)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shading::tangent_space::tests::{sin_tol, sin64};
    use crate::shading::test_support::{Lcg, assert_close};

    /// f64 eq. 2.7 before the power: `(t·l)(t·e) + sin(t,l) sin(t,e)` with sines from cross
    /// products. Returns the base and its error bound (sum of the sine bounds plus 1e-6).
    fn spec_base64(t: Vec3, l: Vec3, e: Vec3) -> (f64, f64) {
        let (t, l, e) = (t.as_dvec3(), l.as_dvec3(), e.as_dvec3());
        let (t, l, e) = (t.normalize(), l.normalize(), e.normalize());
        let (sl, se) = (
            sin64(t.as_vec3(), l.as_vec3()),
            sin64(t.as_vec3(), e.as_vec3()),
        );
        (
            t.dot(l) * t.dot(e) + sl * se,
            1e-6 + sin_tol(sl) + sin_tol(se),
        )
    }

    /// Every tangent setting.
    const TANGENTS: [SpecularTangents; 3] = [
        SpecularTangents::One,
        SpecularTangents::Three(SpecularLobes::Sum),
        SpecularTangents::Three(SpecularLobes::Average),
    ];

    #[test]
    fn lobe_sum_and_mean_match_f64() {
        // Bound: the f32 sum of three values in [0, 1] is within 2 ulps of 2 (2.4e-7) of the
        // exact sum, the mean within that over 3 plus half an ulp of 1.
        let mut rng = Lcg::new(16);
        for _ in 0..5000 {
            let (c, u, d) = (rng.unit(), rng.unit(), rng.unit());
            let exact = f64::from(c) + f64::from(u) + f64::from(d);
            assert_close(specular_lobe_sum(c, u, d), exact, 5e-7, "sum");
            assert_close(specular_lobe_mean(c, u, d), exact / 3.0, 3e-7, "mean");
            let sum = three_lobe_specular(c, u, d, SpecularLobes::Sum);
            let mean = three_lobe_specular(c, u, d, SpecularLobes::Average);
            assert_eq!(sum.to_bits(), specular_lobe_sum(c, u, d).to_bits());
            assert_eq!(mean.to_bits(), specular_lobe_mean(c, u, d).to_bits());
        }
        // Three full lobes: the thesis's sum reaches 3, the mean 1.
        assert_eq!(specular_lobe_sum(1.0, 1.0, 1.0), 3.0);
        assert_eq!(specular_lobe_mean(1.0, 1.0, 1.0), 1.0);
        assert_eq!(SpecularLobes::default(), SpecularLobes::Average);
    }

    /// Error bound after `max(0, x)^p`: `p·max(x,0)^(p−1)·dx` (+ 1e-6), exact up to first order.
    fn pow_tol(x: f64, dx: f64, p: f64) -> f64 {
        let x = x.clamp(0.0, 1.0);
        1e-6 + p * (x + dx).min(1.0).powf((p - 1.0).max(0.0)) * dx
    }

    #[test]
    fn diffuse_matches_f64() {
        let mut rng = Lcg::new(10);
        for _ in 0..2000 {
            let (t, l) = (rng.cube(), rng.cube());
            let p = rng.range(1.0, 8.0);
            let s = sin64(t, l);
            let expected = s.powf(f64::from(p));
            let tol = pow_tol(s, sin_tol(s), f64::from(p));
            assert_close(kajiya_kay_diffuse(t, l, p), expected, tol, "diffuse");
        }
    }

    #[test]
    fn diffuse_edge_cases() {
        // Tangent parallel (or antiparallel) to the light: no diffuse.
        assert_eq!(
            kajiya_kay_diffuse(Vec3::Y, Vec3::Y * 2.0, BANKS_EXPONENT),
            0.0
        );
        assert_eq!(kajiya_kay_diffuse(Vec3::Y, -Vec3::Y, BANKS_EXPONENT), 0.0);
        // Perpendicular: full diffuse.
        assert_eq!(kajiya_kay_diffuse(Vec3::X, Vec3::Y, BANKS_EXPONENT), 1.0);
        // Degenerate vectors: finite, zero.
        assert_eq!(kajiya_kay_diffuse(Vec3::ZERO, Vec3::Y, BANKS_EXPONENT), 0.0);
        let nan = Vec3::splat(f32::NAN);
        assert_eq!(kajiya_kay_diffuse(nan, Vec3::Y, BANKS_EXPONENT), 0.0);
        // Exponent conventions.
        let s = kajiya_kay_diffuse(Vec3::new(1.0, 1.0, 0.0), Vec3::X, f32::NAN);
        assert_close(s, 0.5f64.sqrt(), 1e-6, "NaN exponent acts as 1");
        assert_eq!(kajiya_kay_diffuse(Vec3::X, Vec3::X, -1.0), 1.0);
    }

    #[test]
    fn specular_matches_f64() {
        let mut rng = Lcg::new(11);
        for _ in 0..2000 {
            let (t, l, e) = (rng.cube(), rng.cube(), rng.cube());
            let p = rng.range(1.0, 64.0);
            let (x, dx) = spec_base64(t, l, e);
            let expected = x.max(0.0).powf(f64::from(p));
            let tol = pow_tol(x, dx, f64::from(p));
            assert_close(kajiya_kay_specular(t, l, e, p), expected, tol, "specular");
        }
    }

    #[test]
    fn specular_edge_cases() {
        // Mirror configuration of the printed eq. 2.7: l = e gives (t·l)² + sin² = 1.
        let t = Vec3::new(0.3, 0.9, 0.1);
        let l = Vec3::new(-0.2, 0.5, 0.8);
        assert_close(kajiya_kay_specular(t, l, l, 40.0), 1.0, 1e-5, "l = e");
        // Eye behind the surface (normal +z, eye −z): finite and in range.
        let behind = kajiya_kay_specular(Vec3::X, Vec3::new(0.0, 0.6, 0.8), -Vec3::Z, 20.0);
        assert!((0.0..=1.0).contains(&behind));
        // Negative base clamps to 0: t·l = 1, t·e = −1, sines 0.
        assert_eq!(kajiya_kay_specular(Vec3::X, Vec3::X, -Vec3::X, 8.0), 0.0);
        // Degenerate inputs.
        for bad in [
            Vec3::ZERO,
            Vec3::splat(f32::NAN),
            Vec3::splat(f32::INFINITY),
        ] {
            assert_eq!(kajiya_kay_specular(bad, Vec3::Y, Vec3::Z, 8.0), 0.0);
            assert_eq!(kajiya_kay_specular(Vec3::X, bad, Vec3::Z, 8.0), 0.0);
            assert_eq!(kajiya_kay_specular(Vec3::X, Vec3::Y, bad, 8.0), 0.0);
        }
    }

    #[test]
    fn shifted_tangents_match_f64_sum_and_mean() {
        let mut rng = Lcg::new(12);
        for k in 0..1000 {
            let n = rng.direction();
            let t = (rng.direction() - n * 0.3).normalize_or(Vec3::X);
            let (l, e) = (rng.cube(), rng.cube());
            let (p, shift) = (rng.range(1.0, 32.0), rng.range(-0.5, 0.5));
            let one = specular_with_tangents(t, n, l, e, p, SpecularTangents::One, shift);
            assert_eq!(one, kajiya_kay_specular(t, l, e, p));
            let mut sum = 0.0;
            let mut tol = 0.0;
            for s in [0.0, f64::from(shift), -f64::from(shift)] {
                let ts = (t.as_dvec3() + s * n.as_dvec3()).normalize().as_vec3();
                let (x, dx) = spec_base64(ts, l, e);
                sum += x.max(0.0).powf(f64::from(p));
                // The shifted tangent itself carries ~1e-7 error, which moves x by < 1e-6.
                tol += pow_tol(x, dx + 1e-6, f64::from(p));
            }
            // Two f32 additions (and a division) add at most 3 ulps of 3: 1e-6.
            let (lobes, expected, tol) = if k % 2 == 0 {
                (SpecularLobes::Sum, sum, tol + 1e-6)
            } else {
                (SpecularLobes::Average, sum / 3.0, tol / 3.0 + 1e-6)
            };
            let three =
                specular_with_tangents(t, n, l, e, p, SpecularTangents::Three(lobes), shift);
            assert_close(three, expected, tol, "three-tangent specular");
        }
    }

    #[test]
    fn eq_3_5_uncoloured_term_matches_f64() {
        // (ψ_specularity1)^n from vectors: eq. 2.7 of the strand's own tangent with the
        // specular exponent p, then the power n, against the f64 base raised to p then n.
        // Bound: the lobe's (pow_tol) carried through the outer power to first order, plus
        // the outer power's own rounding (4·(1 + |n·log2 s|) ulp, numeric.rs).
        let mut rng = Lcg::new(17);
        for _ in 0..2000 {
            let (t, l, e) = (rng.cube(), rng.cube(), rng.cube());
            // n ≥ 1: below 1 the outer power's slope has no bound at 0, where the base's
            // absolute error is largest (lighting.rs tests n < 1 on exact bases).
            let (p, n) = (rng.range(1.0, 64.0), rng.range(1.0, 8.0));
            let (x, dx) = spec_base64(t, l, e);
            let lobe = x.max(0.0).powf(f64::from(p));
            let d_lobe = pow_tol(x, dx, f64::from(p));
            let expected = lobe.powf(f64::from(n));
            let own = if expected > 0.0 {
                4.0 * (1.0 + (f64::from(n) * lobe.log2()).abs()) * expected * 1.2e-7 + 1e-38
            } else {
                0.0
            };
            let tol = pow_tol(lobe, d_lobe, f64::from(n)) + own;
            let got = crate::shading::specularity1_power(kajiya_kay_specular(t, l, e, p), n);
            assert_close(got, expected, tol, "(ψ_specularity1)^n");
        }
    }

    #[test]
    fn strand_lighting_is_bit_identical_to_the_separate_terms() {
        let mut rng = Lcg::new(14);
        let special = [
            Vec3::ZERO,
            Vec3::splat(f32::NAN),
            Vec3::X,
            -Vec3::X,
            Vec3::new(1.0, 1e-8, 0.0),
        ];
        for k in 0..4000 {
            let pick = |rng: &mut Lcg, i: usize| {
                if k % 17 == i {
                    special[k % special.len()]
                } else {
                    rng.cube()
                }
            };
            let (t, l, e) = (pick(&mut rng, 0), pick(&mut rng, 1), pick(&mut rng, 2));
            let n = rng.direction();
            let exponents = LightingExponents {
                banks: [BANKS_EXPONENT, 1.0, 2.0, 0.5][k % 4],
                specular: rng.range(1.0, 120.0),
                dampened: [rng.range(1.0, 40.0), f32::NAN, 0.0][k % 3],
            };
            let shift = rng.range(-0.5, 0.5);
            for tangents in TANGENTS {
                let got = strand_lighting(t, n, l, e, exponents, tangents, shift);
                let want = StrandLighting {
                    diffuse: kajiya_kay_diffuse(t, l, exponents.banks),
                    specular: specular_with_tangents(
                        t,
                        n,
                        l,
                        e,
                        exponents.specular,
                        tangents,
                        shift,
                    ),
                    specular_to_dampen: kajiya_kay_specular(t, l, e, exponents.dampened),
                };
                assert_eq!(
                    [got.diffuse, got.specular, got.specular_to_dampen].map(f32::to_bits),
                    [want.diffuse, want.specular, want.specular_to_dampen].map(f32::to_bits),
                    "{t} {l} {e} {exponents:?} {tangents:?}: {got:?} vs {want:?}"
                );
            }
        }
    }

    #[test]
    fn strand_lighting_lanes_are_bit_identical_to_single_calls() {
        lanes_bit_for_bit::<4>();
        lanes_bit_for_bit::<8>();
    }

    fn lanes_bit_for_bit<const N: usize>() {
        let mut rng = Lcg::new(15);
        let special = [Vec3::ZERO, Vec3::splat(f32::NAN), Vec3::X, -Vec3::Z];
        for k in 0..2000 {
            let mut pick = |i: usize| {
                if k % 13 == i {
                    special[k % special.len()]
                } else {
                    rng.cube()
                }
            };
            let (t, n, l, e): ([Vec3; N], [Vec3; N], [Vec3; N], [Vec3; N]) = (
                std::array::from_fn(|_| pick(0)),
                std::array::from_fn(|_| pick(1)),
                std::array::from_fn(|_| pick(2)),
                std::array::from_fn(|_| pick(3)),
            );
            let exponents = LightingExponents {
                banks: [BANKS_EXPONENT, 1.0, 2.0, 0.5][k % 4],
                specular: rng.range(1.0, 120.0),
                dampened: [rng.range(1.0, 40.0), f32::NAN, 0.0][k % 3],
            };
            let shift = rng.range(-0.5, 0.5);
            for tangents in TANGENTS {
                let quad = strand_lighting_lanes(
                    &Vec3xN::from_lanes(t),
                    &Vec3xN::from_lanes(n),
                    &Vec3xN::from_lanes(l),
                    &Vec3xN::from_lanes(e),
                    exponents,
                    tangents,
                    shift,
                );
                for lane in 0..N {
                    let single = strand_lighting(
                        t[lane], n[lane], l[lane], e[lane], exponents, tangents, shift,
                    );
                    let bits = |s: StrandLighting| {
                        [s.diffuse, s.specular, s.specular_to_dampen].map(f32::to_bits)
                    };
                    let got = StrandLighting {
                        diffuse: quad.diffuse[lane],
                        specular: quad.specular[lane],
                        specular_to_dampen: quad.specular_to_dampen[lane],
                    };
                    assert_eq!(
                        bits(got),
                        bits(single),
                        "lane {lane} of {t:?} {l:?} {e:?} {exponents:?} {tangents:?}"
                    );
                }
            }
        }
    }

    #[test]
    fn shift_tangent_matches_f64_and_degenerates() {
        let mut rng = Lcg::new(13);
        for _ in 0..500 {
            let (t, n, s) = (rng.direction(), rng.direction(), rng.range(-1.0, 1.0));
            let got = shift_tangent(t, n, s);
            let sum = t.as_dvec3() + f64::from(s) * n.as_dvec3();
            if sum.length() < 1e-3 {
                continue;
            }
            let expected = sum.normalize();
            for k in 0..3 {
                assert_close(got[k], expected[k], 1e-6 / sum.length(), "shift_tangent");
            }
        }
        assert_eq!(shift_tangent(Vec3::X, -Vec3::X, 1.0), Vec3::ZERO);
        assert_eq!(shift_tangent(Vec3::X, Vec3::Y, f32::NAN), Vec3::X);
        let v = specular_with_tangents(
            Vec3::X,
            -Vec3::X,
            Vec3::Y,
            Vec3::Y,
            4.0,
            SpecularTangents::Three(SpecularLobes::Average),
            1.0,
        );
        assert!((0.0..=1.0).contains(&v));
    }
}
