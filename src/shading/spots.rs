//! Spots and stripes (thesis 3.2.4; shading stage): a weight in `[0, 1]` per spot, full inside an
//! inner region, a smooth gradient over an outer ring, zero outside; the spot colour is blended
//! over the fur colour with that weight, and the result is eq. 3.7's `strandColor`.
//!
//! Gradient choice: every ring uses the Hermite smoothstep `t²(3 − 2t)` of the linear ring
//! coordinate `t` (0 at the outer edge, 1 at the inner edge), so the colour has no visible
//! crease (Mach band) at either edge.

use super::lanes::Vec3xN;
use super::numeric::{
    finite_or_zero, pow01, pow01_lanes, ramp, ramp_lanes, saturate, saturate_select,
};
use glam::Vec3;

/// Geometric spot (thesis 3.2.4, "an ellipsoid function"): with the ellipsoid distance
/// `d = sqrt(Σ((p − c)/r)²)`, the weight is 1 for `d ≤ inner`, 0 for `d ≥ 1`, and
/// `smoothstep((1 − d)/(1 − inner))` between.
///
/// `inner` is clamped to `[0, 1]` (NaN → 0; `inner = 1` gives a hard edge, inside winning at
/// `d = 1`). Radii are taken as `|r|`; a zero or NaN radius makes the ellipsoid empty (weight
/// 0). A NaN or infinite distance gives 0.
#[inline]
pub fn ellipsoid_spot_intensity(point: Vec3, centre: Vec3, radii: Vec3, inner: f32) -> f32 {
    let r = radii.abs();
    if !(r.x > 0.0 && r.y > 0.0 && r.z > 0.0) {
        return 0.0;
    }
    let d = ((point - centre) / r).length();
    ramp(-d, -1.0, -saturate(inner))
}

/// [`ellipsoid_spot_intensity`] of `N` points (the lanes of a fur batch), lane by
/// lane the same bits: the same divisions, the dot product `(x·x + y·y) + z·z` and its square
/// root per lane, and `ramp`'s branches as selects (`ramp_lanes`).
#[inline(always)]
#[allow(clippy::needless_range_loop)] // an indexed loop over several arrays vectorises
pub fn ellipsoid_spot_intensity_lanes<const N: usize>(
    point: &Vec3xN<N>,
    centre: Vec3,
    radii: Vec3,
    inner: f32,
) -> [f32; N] {
    let r = radii.abs();
    if !(r.x > 0.0 && r.y > 0.0 && r.z > 0.0) {
        return [0.0; N];
    }
    let mut minus_distance = [0.0; N];
    for i in 0..N {
        let dx = (point.x[i] - centre.x) / r.x;
        let dy = (point.y[i] - centre.y) / r.y;
        let dz = (point.z[i] - centre.z) / r.z;
        minus_distance[i] = -((dx * dx + dy * dy) + dz * dz).sqrt();
    }
    ramp_lanes(minus_distance, -1.0, -saturate(inner))
}

/// Whether every point of the triangle `corners` lies outside the ellipsoid of
/// [`ellipsoid_spot_intensity`] by a margin that rounding cannot cross, so that every fragment
/// interpolated inside it (a convex combination of the corners, weights summing to 1 up to
/// rounding, in `f32`) gets the weight 0 exactly: the batch can skip the spot's arithmetic.
///
/// The test, in `f64`: each corner's offset from the centre over the radii, the box around
/// the three offsets grown on each axis by `10⁻⁵·(the largest magnitude involved + 1)/radius`
/// (a hundredfold the error of `f32` interpolation and of the spot's own subtraction and
/// division), and the box's nearest point to the origin at least `√1.001` away, where the
/// weight is 0 from distance 1 on. `false` for any non-finite corner, centre or radius, or
/// an empty ellipsoid (whose weight is 0 anyway).
pub fn ellipsoid_surely_outside(corners: [Vec3; 3], centre: Vec3, radii: Vec3) -> bool {
    let r = radii.abs();
    if !(r.x > 0.0 && r.y > 0.0 && r.z > 0.0 && r.is_finite() && centre.is_finite()) {
        return false;
    }
    if !corners.iter().all(|c| c.is_finite()) {
        return false;
    }
    let mut nearest_squared = 0.0f64;
    for axis in 0..3 {
        let (c, radius) = (f64::from(centre[axis]), f64::from(r[axis]));
        let at = corners.map(|p| f64::from(p[axis]));
        let largest = at.iter().fold(c.abs(), |m, v| m.max(v.abs()));
        let slack = 1e-5 * (largest + 1.0) / radius;
        let offsets = at.map(|v| (v - c) / radius);
        let low = offsets.iter().copied().fold(f64::INFINITY, f64::min) - slack;
        let high = offsets.iter().copied().fold(f64::NEG_INFINITY, f64::max) + slack;
        // The box's nearest coordinate to 0 on this axis (0 where the box straddles it).
        let nearest = if low > 0.0 {
            low
        } else if high < 0.0 {
            -high
        } else {
            0.0
        };
        nearest_squared += nearest * nearest;
    }
    nearest_squared >= 1.001
}

/// Whether every fragment of the triangle whose vertex normals are `normals` surely has a
/// cosine `n̂·d` below `below` with the unit direction `direction` (`n̂` the fragment's normal,
/// a convex combination of the vertex normals renormalised in `f32`, or zero where it has no
/// direction): then a light spot whose weight is 0 below that cosine skips the triangle.
///
/// Why it is safe: positive combinations of vectors inside a cone stay inside it, so with the
/// unit vertex normals within an angle `β` of their normalised sum `a`, every fragment's
/// normal lies within `β` of `a` and at least `∠(a, d) − β` from `d`. The test (in `f64`)
/// asks that angle to exceed `acos(below)` by 10⁻³ radians, far above the rounding of the
/// fragment's interpolation, normalisation and dot product (about 10⁻⁶); a zero normal has
/// cosine 0, below any positive `below`. `false` when unsure: a vertex normal without
/// direction, a cone of 80° or more, a non-finite input, or `below` outside `(−1, 1]`.
pub fn light_spot_surely_outside(normals: [Vec3; 3], direction: Vec3, below: f32) -> bool {
    if !(below > -1.0 && below <= 1.0 && direction.is_finite()) {
        return false;
    }
    let unit = normals.map(|n| n.as_dvec3().normalize_or_zero());
    if unit
        .iter()
        .any(|n| *n == glam::DVec3::ZERO || !n.is_finite())
    {
        return false;
    }
    let axis = (unit[0] + unit[1] + unit[2]).normalize_or_zero();
    if axis == glam::DVec3::ZERO {
        return false;
    }
    let d = direction.as_dvec3().normalize_or_zero();
    if d == glam::DVec3::ZERO {
        return false;
    }
    // The angles as cosines and sines, without a call to `acos` or `cos` (this runs once a
    // triangle, layer and tile: five `acos` took 4 % of a frame of the default scene). The
    // cone `β`: its cosine is the smallest of the normals' with the axis.
    let cos_cone = unit
        .iter()
        .map(|n| n.dot(axis).clamp(-1.0, 1.0))
        .fold(1.0f64, f64::min);
    if cos_cone <= COS_80_DEGREES {
        return false;
    }
    // `γ = acos(below) + 10⁻³`, by the sum of angles.
    let below = f64::from(below);
    let sin_below = (1.0 - below * below).max(0.0).sqrt();
    let (cos_margin, sin_margin) = (MARGIN_RADIANS.cos(), MARGIN_RADIANS.sin());
    let cos_gamma = below * cos_margin - sin_below * sin_margin;
    let sin_gamma = sin_below * cos_margin + below * sin_margin;
    // `β + γ` past π: no direction is that far from the axis. Else `∠(a, d) ≥ β + γ`, acos
    // decreasing, is `a·d ≤ cos(β + γ)`.
    if below < -cos_margin || cos_cone < -cos_gamma {
        return false;
    }
    let sin_cone = (1.0 - cos_cone * cos_cone).max(0.0).sqrt();
    axis.dot(d).clamp(-1.0, 1.0) <= cos_cone * cos_gamma - sin_cone * sin_gamma
}

/// `cos 80°`: a triangle whose normals spread wider is not tested.
const COS_80_DEGREES: f64 = 0.173_648_177_666_930_41;

/// The angle [`light_spot_surely_outside`] keeps from the spot's edge, far above rounding.
const MARGIN_RADIANS: f64 = 1e-3;

/// [`light_spot_lobe`] of `N` cosines, lane by lane the same bits (`pow01_lanes`).
#[inline(always)]
pub fn light_spot_lobe_lanes<const N: usize>(cosine: [f32; N], exponent: f32) -> [f32; N] {
    pow01_lanes(cosine, [exponent; N])
}

/// [`spot_gradient`] of `N` intensities, lane by lane the same bits.
#[inline(always)]
pub fn spot_gradient_lanes<const N: usize>(
    intensity: [f32; N],
    inner_threshold: f32,
    outer_threshold: f32,
) -> [f32; N] {
    ramp_lanes(intensity, outer_threshold, inner_threshold)
}

/// [`apply_spot`] on `N` lanes with one spot colour, lane by lane the same bits:
/// `fur·(1 − w) + spot·w` per component with `w = saturate(weight)`.
#[inline(always)]
#[allow(clippy::needless_range_loop)] // an indexed loop over several arrays vectorises
pub fn apply_spot_lanes<const N: usize>(
    fur_colour: &Vec3xN<N>,
    spot_colour: Vec3,
    weight: [f32; N],
) -> Vec3xN<N> {
    let mut out = *fur_colour;
    for i in 0..N {
        let w = saturate_select(weight[i]);
        let keep = 1.0 - w;
        out.x[i] = fur_colour.x[i] * keep + spot_colour.x * w;
        out.y[i] = fur_colour.y[i] * keep + spot_colour.y * w;
        out.z[i] = fur_colour.z[i] * keep + spot_colour.z * w;
    }
    out
}

/// Light-based spot lobe (thesis 3.2.4: "we use the specular value to add spots", the light
/// being fixed to the object): `max(0, n̂·l̂)^exponent`, in `[0, 1]`.
///
/// `normal` and `spot_light_dir` (towards the spot light, in the object's frame) are
/// normalised inside; a zero or NaN vector gives `0^p`. Exponent convention: NaN acts as 1,
/// negative as 0. Map the lobe to a colour weight with [`spot_gradient`].
#[inline]
pub fn light_spot_intensity(normal: Vec3, spot_light_dir: Vec3, exponent: f32) -> f32 {
    light_spot_lobe(light_spot_cosine(normal, spot_light_dir), exponent)
}

/// The cosine `n̂·l̂` inside [`light_spot_intensity`], both vectors normalised (zero or NaN
/// vectors give 0 or NaN, which the lobe maps to `0^p`).
#[inline]
pub fn light_spot_cosine(normal: Vec3, spot_light_dir: Vec3) -> f32 {
    normal
        .normalize_or_zero()
        .dot(spot_light_dir.normalize_or_zero())
}

/// The lobe of [`light_spot_intensity`] from its cosine: `max(0, cosine)^exponent`.
#[inline(always)]
pub fn light_spot_lobe(cosine: f32, exponent: f32) -> f32 {
    pow01(cosine, exponent)
}

/// The reach of a spot or match placed at a point (beyond the thesis, which fixes spot lights
/// to the object by direction alone): `(1 − d²/R²)²` for a point at squared distance
/// `distance_squared = d²` from it, inside the reach `R`; 0 at `d ≥ R`.
///
/// Why this form: it is 1 at the point, falls smoothly (its slope is 0 at the point and at the
/// reach, so no ring shows where it ends) and is exactly 0 beyond `R`, so a light lobe that
/// also lights a far surface facing the point (a torus's inner wall across the hole) stops at
/// the reach. It needs `d²` only, no square root. A reach that is not positive, or a NaN
/// distance, gives 0.
#[inline(always)]
pub fn reach_falloff(distance_squared: f32, reach: f32) -> f32 {
    let q = distance_squared / (reach * reach);
    if q < 1.0 && reach > 0.0 {
        let k = 1.0 - q;
        k * k
    } else {
        0.0
    }
}

/// The cosine between a unit surface normal and the direction towards a point light, given
/// the offset from the surface point to the light (`light − point`): `(n̂·o)/√(o·o)`, the
/// cosine of [`light_spot_intensity`] for a light at a point rather than in a direction.
/// A zero or NaN offset gives 0.
#[inline(always)]
pub fn point_light_cosine(unit_normal: Vec3, offset: Vec3) -> f32 {
    let length_squared = offset.dot(offset);
    if length_squared > 0.0 {
        unit_normal.dot(offset) / length_squared.sqrt()
    } else {
        0.0
    }
}

/// A light spot or match at a point (thesis 3.4, matches "stable at certain points"; 3.2.4's
/// light spot placed rather than aimed): the lobe `max(0, cos)^exponent` of the direction
/// from the surface point towards the light ([`point_light_cosine`]), times the
/// [`reach_falloff`] of the distance. So one light lights one region: the surface facing it
/// near it, fading out by `reach`.
///
/// `unit_normal` is normalised already; `point` is the surface point and `light` the light's
/// position, in the same (object) frame.
#[inline]
pub fn point_light_intensity(
    unit_normal: Vec3,
    point: Vec3,
    light: Vec3,
    reach: f32,
    exponent: f32,
) -> f32 {
    let offset = light - point;
    let falloff = reach_falloff(offset.dot(offset), reach);
    light_spot_lobe(point_light_cosine(unit_normal, offset), exponent) * falloff
}

/// A cosine below which the lobe is surely below `level`: for every f32 `c < bound`,
/// `light_spot_lobe(c, exponent) < level`. It lets a shader skip the power where the lobe cannot
/// matter (outside a spot's ring, under the burn threshold) without changing a single bit.
///
/// Derivation: `bound = (level·(1 − 10⁻³))^(1/exponent)` in f64, rounded down to f32, so the
/// exact lobe of any smaller cosine is at least 10⁻³ (relative) under `level`, far more than the
/// error of the lobe's power (at most 8 ulp for normal results, `numeric::pow01_lanes`). With
/// nothing safe to promise (`level ≤ 0`, NaN, an exponent that is not positive) the bound is
/// −∞: no cosine is skipped.
pub fn light_spot_cosine_below(level: f32, exponent: f32) -> f32 {
    if !(level > 0.0 && exponent > 0.0) {
        return f32::NEG_INFINITY;
    }
    let exact = (f64::from(level.min(1.0)) * (1.0 - 1.0e-3)).powf(1.0 / f64::from(exponent));
    let bound = exact as f32;
    if f64::from(bound) > exact {
        bound.next_down()
    } else {
        bound
    }
}

/// A cosine from which the lobe is surely above `level`: for every f32 `c ≥ bound`,
/// `light_spot_lobe(c, exponent) > level`. The twin of [`light_spot_cosine_below`], for a
/// shader that skips the power where any value above `level` has the same effect (fur surely
/// burnt away).
///
/// Derivation: `bound = (level·(1 + 10⁻³))^(1/exponent)` in f64, rounded up to f32, so the exact
/// lobe of any larger cosine is at least 10⁻³ (relative) over `level`, far more than the error
/// of the lobe's power (`numeric::pow01_lanes`). Where no cosine up to 1 is surely enough
/// (`level·(1 + 10⁻³) ≥ 1`), or with nothing safe to promise (NaN, an exponent that is not
/// positive, a `level` that is not positive), the bound is +∞: every lane takes its power.
pub fn light_spot_cosine_above(level: f32, exponent: f32) -> f32 {
    if !(level > 0.0 && exponent > 0.0) {
        return f32::INFINITY;
    }
    let target = f64::from(level) * (1.0 + 1.0e-3);
    if target >= 1.0 {
        return f32::INFINITY;
    }
    let exact = target.powf(1.0 / f64::from(exponent));
    let bound = exact as f32;
    if f64::from(bound) < exact {
        bound.next_up()
    } else {
        bound
    }
}

/// Inner circle / ring / outside of a light-based spot (thesis 3.2.4: "in the inner circle the
/// full color of the predefined spot is given, and in the outer region we add a gradient"):
/// 1 for `intensity ≥ inner_threshold`, 0 for `intensity ≤ outer_threshold`,
/// `smoothstep((I − outer)/(inner − outer))` between.
///
/// Expects `outer_threshold < inner_threshold`; otherwise it is a step at `inner_threshold`
/// (1 at or above it). NaN intensity gives 0.
#[inline]
pub fn spot_gradient(intensity: f32, inner_threshold: f32, outer_threshold: f32) -> f32 {
    ramp(intensity, outer_threshold, inner_threshold)
}

/// Blends a spot over the fur colour: `fur·(1 − w) + spot·w` with `w = saturate(weight)`
/// (NaN → 0, so the fur colour is kept). Weight 0 returns `fur_colour` exactly, weight 1
/// `spot_colour` exactly.
#[inline]
pub fn apply_spot(fur_colour: Vec3, spot_colour: Vec3, weight: f32) -> Vec3 {
    let w = saturate(weight);
    fur_colour * (1.0 - w) + spot_colour * w
}

/// Several spots in a fixed order: each `(colour, weight)` is applied with [`apply_spot`] over
/// the result of the previous ones, so a later spot covers an earlier one where both apply.
#[inline]
pub fn apply_spots(fur_colour: Vec3, spots: impl IntoIterator<Item = (Vec3, f32)>) -> Vec3 {
    spots
        .into_iter()
        .fold(fur_colour, |c, (spot, w)| apply_spot(c, spot, w))
}

/// Stripes (thesis 3.2.4, the cow of figure 3.14): periodic bands along a coordinate (e.g. a
/// texture coordinate or a world axis), centred on every multiple of `period`.
///
/// With `dist` the distance from `coordinate` to the nearest band centre
/// (`|x − period·round(x/period)|`, in `[0, period/2]`): 1 for `dist ≤ width/2`, 0 for
/// `dist ≥ width/2 + softness`, smoothstep between. `width` and `softness` are clamped to be
/// non-negative (NaN → 0; softness 0 gives hard edges). A non-positive or non-finite `period`,
/// or a non-finite coordinate, gives 0.
#[inline]
pub fn stripe_intensity(coordinate: f32, period: f32, width: f32, softness: f32) -> f32 {
    if !(period > 0.0 && period.is_finite() && coordinate.is_finite()) {
        return 0.0;
    }
    let cell = coordinate / period;
    let dist = (cell - libm::roundf(cell)).abs() * period;
    let half = 0.5 * finite_or_zero(width).max(0.0);
    let soft = finite_or_zero(softness).max(0.0);
    ramp(-dist, -(half + soft), -half)
}

/// Stripes from the specular value of a light fixed to the object (thesis 3.2.4: "we use the
/// specular value to add spots and stripes to the objects"): the lobe value `L` of
/// [`light_spot_intensity`], in `[0, 1]`, cut into periodic bands. Bands are centred on
/// `L = (k + ½)·period`, `k = 0, 1, …`: [`stripe_intensity`]`(L − period/2, period, width,
/// softness)`, so the side the light does not reach (`L = 0`) lies in the middle of a gap.
///
/// Each band is a ring of equal lobe value around the light's direction: with `exponent` 1 the
/// rings are equally spaced in `n̂·l̂` (equal areas on a sphere, like latitude bands around the
/// light), a larger exponent crowds them towards the light. `width` and `softness` are in lobe
/// units like `period`; a `period` of 1 or more gives at most one band. Conventions of
/// [`stripe_intensity`] and [`light_spot_intensity`] for the rest.
#[inline]
pub fn light_stripe_band(lobe: f32, period: f32, width: f32, softness: f32) -> f32 {
    stripe_intensity(lobe - 0.5 * period, period, width, softness)
}

/// [`light_stripe_band`] of the lobe of the light fixed to the object at this normal:
/// `light_stripe_band(light_spot_intensity(normal, spot_light_dir, exponent), …)`.
#[inline]
pub fn light_stripe_intensity(
    normal: Vec3,
    spot_light_dir: Vec3,
    exponent: f32,
    period: f32,
    width: f32,
    softness: f32,
) -> f32 {
    light_stripe_band(
        light_spot_intensity(normal, spot_light_dir, exponent),
        period,
        width,
        softness,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shading::test_support::{Lcg, assert_close};

    /// Weights of a triangle's corners as a fur batch's lanes have them: summing to 1 up to
    /// rounding, slightly negative at the edges; sample 0 is corner 0 itself.
    fn lane_weights(rng: &mut Lcg, sample: usize) -> [f32; 3] {
        if sample == 0 {
            return [1.0, 0.0, 0.0];
        }
        let raw = [0; 3].map(|_| rng.range(-1e-7, 1.0));
        let sum = (raw[0] + raw[1]) + raw[2];
        raw.map(|r| r * (1.0 / sum))
    }

    /// `(a·wa + b·wb) + c·wc` in `f32`, as the batch interpolates a varying.
    fn interpolate(corners: [Vec3; 3], w: [f32; 3]) -> Vec3 {
        (corners[0] * w[0] + corners[1] * w[1]) + corners[2] * w[2]
    }

    /// A light spot's test case: vertex normals in a cone of about `spread` radians around a
    /// random centre (not unit, as interpolated normals are not), a random unit direction,
    /// and `below`.
    fn light_spot_case(rng: &mut Lcg, below: f32, spread: f32) -> ([Vec3; 3], Vec3, f32) {
        let direction = rng.cube().normalize_or(Vec3::Y);
        let centre = rng.cube().normalize_or(Vec3::X);
        let normals = [0, 1, 2]
            .map(|_| (centre + rng.cube() * spread).normalize_or(Vec3::X) * rng.range(0.5, 2.0));
        (normals, direction, below)
    }

    #[test]
    fn a_triangle_surely_outside_a_light_spot_has_every_cosine_below() {
        let mut rng = Lcg::new(78);
        let (mut outside, mut unsure) = (0, 0);
        for k in 0..4000 {
            let (normals, direction, below) = light_spot_case(
                &mut rng,
                [0.97, 0.5, 0.0, -0.3][k % 4],
                [0.02, 0.2, 0.6][k % 3],
            );
            if !light_spot_surely_outside(normals, direction, below) {
                unsure += 1;
                continue;
            }
            outside += 1;
            for j in 0..200 {
                let normal = interpolate(normals, lane_weights(&mut rng, j));
                let cosine = normal.normalize_or_zero().dot(direction);
                assert!(cosine < below, "{normals:?} {normal:?} {cosine} {below}");
            }
        }
        assert!(outside > 1000 && unsure > 1000, "{outside} {unsure}");
        // Normals around the direction itself, or opposed ones, are never called outside.
        let d = Vec3::new(0.6, 0.5, 0.8).normalize();
        assert!(!light_spot_surely_outside([d, d, d], d, 0.97));
        assert!(!light_spot_surely_outside(
            [Vec3::X, -Vec3::X, Vec3::Y],
            d,
            0.97
        ));
        assert!(!light_spot_surely_outside(
            [Vec3::ZERO, Vec3::Y, Vec3::Y],
            d,
            0.97
        ));
        assert!(light_spot_surely_outside([-d, -d, -d], d, 0.97));
        assert!(!light_spot_surely_outside([-d, -d, -d], d, f32::NAN));
    }

    /// The test as it is written in angles (five `acos`, in `f64`): the cosine form must agree
    /// with it wherever the two angles are not within rounding of each other.
    fn surely_outside_by_angles(normals: [Vec3; 3], direction: Vec3, below: f32) -> Option<bool> {
        let unit = normals.map(|n| n.as_dvec3().normalize());
        let axis = (unit[0] + unit[1] + unit[2]).normalize();
        let angle = |a: glam::DVec3, b: glam::DVec3| a.dot(b).clamp(-1.0, 1.0).acos();
        let cone = unit.iter().map(|&n| angle(n, axis)).fold(0.0f64, f64::max);
        if cone >= 80f64.to_radians() {
            return Some(false);
        }
        let slack =
            angle(axis, direction.as_dvec3().normalize()) - cone - (f64::from(below).acos() + 1e-3);
        (slack.abs() > 1e-9).then_some(slack >= 0.0)
    }

    #[test]
    fn light_spot_surely_outside_is_the_test_in_angles() {
        let mut rng = Lcg::new(79);
        let (mut outside, mut inside) = (0, 0);
        for k in 0..20_000 {
            let below = [0.97, 0.5, 0.0, -0.3, -0.9, 0.999][k % 6];
            let (normals, direction, below) =
                light_spot_case(&mut rng, below, [0.02, 0.2, 0.6, 1.5][k % 4]);
            let Some(want) = surely_outside_by_angles(normals, direction, below) else {
                continue;
            };
            let got = light_spot_surely_outside(normals, direction, below);
            assert_eq!(got, want, "{normals:?} {direction:?} {below}");
            if got {
                outside += 1;
            } else {
                inside += 1;
            }
        }
        assert!(outside > 3000 && inside > 3000, "{outside} {inside}");
    }

    #[test]
    fn a_triangle_surely_outside_gives_the_weight_zero_at_every_interpolated_point() {
        let mut rng = Lcg::new(77);
        let (mut outside, mut unsure) = (0, 0);
        for k in 0..4000 {
            let centre = rng.cube() * 5.0;
            let radii = Vec3::new(
                rng.range(0.05, 3.0),
                rng.range(0.05, 3.0),
                rng.range(0.05, 3.0),
            );
            // Triangles around the ellipsoid's surface, small and large, some far out.
            let size = [0.01, 0.3, 2.0][k % 3];
            let reach = [1.0, 1.05, 1.5, 4.0][k % 4];
            let anchor = centre + rng.cube().normalize_or(Vec3::X) * radii * reach;
            let corners = [0, 1, 2].map(|_| anchor + rng.cube() * size);
            if !ellipsoid_surely_outside(corners, centre, radii) {
                unsure += 1;
                continue;
            }
            outside += 1;
            for j in 0..200 {
                let w = lane_weights(&mut rng, j);
                let point = interpolate(corners, w);
                let weight = ellipsoid_spot_intensity(point, centre, radii, 0.5);
                assert_eq!(weight.to_bits(), 0.0f32.to_bits(), "{corners:?} {w:?}");
                let lanes =
                    ellipsoid_spot_intensity_lanes(&Vec3xN::<4>::splat(point), centre, radii, 0.5);
                assert_eq!(lanes.map(f32::to_bits), [0; 4]);
            }
        }
        // The test finds most triangles clear of the ellipsoid and leaves those that touch it.
        assert!(outside > 1500 && unsure > 1000, "{outside} {unsure}");
        // A triangle through the centre, and non-finite input, are never called outside.
        let c = Vec3::new(1.0, 2.0, 3.0);
        let through = [c, c + Vec3::X * 9.0, c + Vec3::Y * 9.0];
        assert!(!ellipsoid_surely_outside(through, c, Vec3::ONE));
        let far = [
            Vec3::splat(50.0),
            Vec3::splat(51.0),
            Vec3::new(50.0, 51.0, 50.0),
        ];
        assert!(ellipsoid_surely_outside(far, c, Vec3::ONE));
        assert!(!ellipsoid_surely_outside(
            far,
            c,
            Vec3::new(1.0, f32::NAN, 1.0)
        ));
        assert!(!ellipsoid_surely_outside(far, c, Vec3::new(1.0, 0.0, 1.0)));
        let mut bad = far;
        bad[1].x = f32::INFINITY;
        assert!(!ellipsoid_surely_outside(bad, c, Vec3::ONE));
    }

    /// The lane versions at 4 and 8 lanes against the scalar terms, lane by lane.
    fn assert_lanes_are_the_scalar_spot_terms<const N: usize>(seed: u64) {
        let mut rng = Lcg::new(seed);
        let lanes = |rng: &mut Lcg, k: usize| crate::shading::lanes::tests::lanes_n::<N>(rng, k);
        for k in 0..5000usize {
            let points = lanes(&mut rng, k);
            let colours = lanes(&mut rng, k + 2);
            let centre = rng.cube() * 2.0;
            let radii = if k % 17 == 0 {
                Vec3::new(0.0, 1.0, 1.0)
            } else {
                rng.cube() * 3.0
            };
            let inner = [rng.unit(), f32::NAN, 1.0, -0.5][k % 4];
            let got =
                ellipsoid_spot_intensity_lanes(&Vec3xN::from_lanes(points), centre, radii, inner);
            let cosine: [f32; N] = std::array::from_fn(|_| rng.range(-1.2, 1.2));
            let exponent = [40.0, 1.0, 0.0, f32::NAN, 7.5][k % 5];
            let lobe = light_spot_lobe_lanes(cosine, exponent);
            let (inner_t, outer_t) = [(0.7, 0.3), (0.3, 0.7), (0.5, 0.5)][k % 3];
            let gradient = spot_gradient_lanes(lobe, inner_t, outer_t);
            let weight: [f32; N] =
                std::array::from_fn(|i| [rng.range(-0.5, 1.5), f32::NAN, 0.0, 1.0][(k + i) % 4]);
            let spot = rng.cube();
            let blended = apply_spot_lanes(&Vec3xN::from_lanes(colours), spot, weight);
            let bits = |v: Vec3| v.to_array().map(f32::to_bits);
            for i in 0..N {
                assert_eq!(
                    got[i].to_bits(),
                    ellipsoid_spot_intensity(points[i], centre, radii, inner).to_bits(),
                    "ellipsoid {:?}",
                    points[i]
                );
                assert_eq!(
                    lobe[i].to_bits(),
                    light_spot_lobe(cosine[i], exponent).to_bits()
                );
                assert_eq!(
                    gradient[i].to_bits(),
                    spot_gradient(lobe[i], inner_t, outer_t).to_bits()
                );
                assert_eq!(
                    bits(blended.lane(i)),
                    bits(apply_spot(colours[i], spot, weight[i])),
                    "apply {:?} {}",
                    colours[i],
                    weight[i]
                );
            }
        }
    }

    #[test]
    fn lanes_are_the_scalar_spot_terms_bit_for_bit() {
        assert_lanes_are_the_scalar_spot_terms::<4>(52);
        assert_lanes_are_the_scalar_spot_terms::<8>(53);
    }

    fn smooth64(t: f64) -> f64 {
        let t = t.clamp(0.0, 1.0);
        t * t * (3.0 - 2.0 * t)
    }

    #[test]
    fn ellipsoid_matches_f64_inside_ring_outside() {
        // Bound: 1e-6 + 1.5/(1 − inner)·1e-6·(1 + d): the smoothstep's slope times the error of d.
        let mut rng = Lcg::new(50);
        let (mut inside, mut ring, mut outside) = (0, 0, 0);
        for _ in 0..3000 {
            let c = rng.cube();
            let r = Vec3::new(
                rng.range(0.2, 2.0),
                rng.range(0.2, 2.0),
                rng.range(0.2, 2.0),
            );
            let p = c + rng.cube() * r;
            let inner = rng.range(0.0, 0.9);
            let q = (p.as_dvec3() - c.as_dvec3()) / r.as_dvec3();
            let d = q.length();
            let expected = if d <= f64::from(inner) {
                inside += 1;
                1.0
            } else if d >= 1.0 {
                outside += 1;
                0.0
            } else {
                ring += 1;
                smooth64((1.0 - d) / (1.0 - f64::from(inner)))
            };
            let tol = 1e-6 + 1.5 / (1.0 - f64::from(inner)) * 1e-6 * (1.0 + d);
            let got = ellipsoid_spot_intensity(p, c, r, inner);
            assert_close(got, expected, tol, "ellipsoid");
        }
        assert!(inside > 100 && ring > 100 && outside > 100);
    }

    #[test]
    fn ellipsoid_edges() {
        let r = Vec3::new(2.0, 1.0, 0.5);
        assert_eq!(
            ellipsoid_spot_intensity(Vec3::ZERO, Vec3::ZERO, r, 0.5),
            1.0
        );
        assert_eq!(ellipsoid_spot_intensity(Vec3::X, Vec3::ZERO, r, 0.5), 1.0); // d = 0.5
        assert_eq!(ellipsoid_spot_intensity(Vec3::Y, Vec3::ZERO, r, 0.5), 0.0); // d = 1
        assert_eq!(ellipsoid_spot_intensity(Vec3::Z, Vec3::ZERO, r, 0.5), 0.0); // d = 2
        // Mid-ring: d = 0.75, t = 0.5, smoothstep 0.5.
        let mid = ellipsoid_spot_intensity(Vec3::X * 1.5, Vec3::ZERO, r, 0.5);
        assert_eq!(mid, 0.5);
        // Hard edge with inner = 1: inside wins at d = 1.
        assert_eq!(ellipsoid_spot_intensity(Vec3::Y, Vec3::ZERO, r, 1.0), 1.0);
        assert_eq!(
            ellipsoid_spot_intensity(Vec3::Y * 1.01, Vec3::ZERO, r, 1.0),
            0.0
        );
        // Negative radii act as their absolute value; zero or NaN radii give an empty spot.
        assert_eq!(ellipsoid_spot_intensity(Vec3::X, Vec3::ZERO, -r, 0.5), 1.0);
        assert_eq!(
            ellipsoid_spot_intensity(Vec3::ZERO, Vec3::ZERO, Vec3::ZERO, 0.5),
            0.0
        );
        let nan = Vec3::splat(f32::NAN);
        assert_eq!(
            ellipsoid_spot_intensity(Vec3::ZERO, Vec3::ZERO, nan, 0.5),
            0.0
        );
        assert_eq!(ellipsoid_spot_intensity(nan, Vec3::ZERO, r, 0.5), 0.0);
        assert_eq!(
            ellipsoid_spot_intensity(Vec3::ZERO, Vec3::ZERO, r, f32::NAN),
            1.0
        );
        let far = Vec3::splat(f32::MAX);
        assert_eq!(ellipsoid_spot_intensity(far, Vec3::ZERO, r, 0.5), 0.0);
    }

    #[test]
    fn light_spot_matches_f64() {
        let mut rng = Lcg::new(51);
        for _ in 0..2000 {
            let (n, l, p) = (rng.cube(), rng.cube(), rng.range(1.0, 64.0));
            let c = n.as_dvec3().normalize().dot(l.as_dvec3().normalize());
            let expected = c.max(0.0).powf(f64::from(p));
            // p·c^(p−1)·1e-6 + 1e-6 (the cosine carries a few ULP).
            let tol = 1e-6 + f64::from(p) * 1e-6;
            assert_close(light_spot_intensity(n, l, p), expected, tol, "light spot");
        }
        assert_eq!(light_spot_intensity(Vec3::Y, -Vec3::Y, 4.0), 0.0);
        assert_eq!(light_spot_intensity(Vec3::Y, Vec3::Y * 5.0, 4.0), 1.0);
        assert_eq!(light_spot_intensity(Vec3::ZERO, Vec3::Y, 4.0), 0.0);
        assert_eq!(
            light_spot_intensity(Vec3::splat(f32::NAN), Vec3::Y, 4.0),
            0.0
        );
    }

    #[test]
    fn gradient_and_blending() {
        assert_eq!(spot_gradient(0.9, 0.8, 0.4), 1.0);
        assert_eq!(spot_gradient(0.8, 0.8, 0.4), 1.0);
        assert_eq!(spot_gradient(0.4, 0.8, 0.4), 0.0);
        assert_eq!(spot_gradient(0.1, 0.8, 0.4), 0.0);
        assert_close(spot_gradient(0.6, 0.8, 0.4), 0.5, 1e-6, "mid-ring");
        assert_eq!(spot_gradient(f32::NAN, 0.8, 0.4), 0.0);
        // Reversed thresholds: a step at the inner one.
        assert_eq!(spot_gradient(0.5, 0.5, 0.9), 1.0);
        assert_eq!(spot_gradient(0.49, 0.5, 0.9), 0.0);
        let mut rng = Lcg::new(52);
        for _ in 0..1000 {
            let i = rng.unit();
            let t = (f64::from(i) - 0.3) / 0.4;
            assert_close(spot_gradient(i, 0.7, 0.3), smooth64(t), 1e-5, "gradient");
        }
        let (fur, spot) = (Vec3::new(0.4, 0.25, 0.1), Vec3::new(1.0, 0.9, 0.8));
        assert_eq!(apply_spot(fur, spot, 0.0), fur);
        assert_eq!(apply_spot(fur, spot, 1.0), spot);
        assert_eq!(apply_spot(fur, spot, 2.0), spot);
        assert_eq!(apply_spot(fur, spot, f32::NAN), fur);
        let half = apply_spot(fur, spot, 0.5);
        assert_close(half.x, 0.7, 1e-7, "lerp");
        // Later spots cover earlier ones.
        let white = Vec3::ONE;
        assert_eq!(apply_spots(fur, [(spot, 1.0), (white, 1.0)]), white);
        assert_eq!(apply_spots(fur, [(white, 1.0), (spot, 1.0)]), spot);
        assert_eq!(apply_spots(fur, [(white, 1.0), (spot, 0.0)]), white);
        assert_eq!(apply_spots(fur, []), fur);
    }

    #[test]
    fn stripes_match_f64() {
        let mut rng = Lcg::new(53);
        for _ in 0..3000 {
            let x = rng.range(-10.0, 10.0);
            let period = rng.range(0.5, 3.0);
            let width = rng.range(0.0, period);
            let soft = rng.range(0.05, 0.5);
            let (xd, pd) = (f64::from(x), f64::from(period));
            let cell = xd / pd;
            let dist = (cell - cell.round()).abs() * pd;
            let half = 0.5 * f64::from(width);
            let expected = smooth64((half + f64::from(soft) - dist) / f64::from(soft));
            let tol = 1e-6 + 1.5 / f64::from(soft) * 2e-6 * (1.0 + xd.abs());
            let got = stripe_intensity(x, period, width, soft);
            assert_close(got, expected, tol, "stripe");
        }
    }

    #[test]
    fn stripe_edges() {
        assert_eq!(stripe_intensity(0.0, 1.0, 0.2, 0.1), 1.0);
        assert_eq!(stripe_intensity(3.0, 1.0, 0.2, 0.1), 1.0);
        assert_eq!(stripe_intensity(-2.05, 1.0, 0.2, 0.1), 1.0);
        assert_eq!(stripe_intensity(0.5, 1.0, 0.2, 0.1), 0.0);
        assert_eq!(stripe_intensity(0.15, 1.0, 0.2, 0.0), 0.0); // hard edge
        assert_eq!(stripe_intensity(0.05, 1.0, 0.2, 0.0), 1.0);
        assert_eq!(stripe_intensity(0.5, 1.0, 2.0, 0.1), 1.0); // bands wider than the period
        for bad in [0.0, -1.0, f32::NAN, f32::INFINITY] {
            assert_eq!(stripe_intensity(0.0, bad, 0.2, 0.1), 0.0);
        }
        assert_eq!(stripe_intensity(f32::NAN, 1.0, 0.2, 0.1), 0.0);
        assert_eq!(stripe_intensity(0.0, 1.0, f32::NAN, f32::NAN), 1.0);
    }

    #[test]
    fn light_stripes_match_f64() {
        let mut rng = Lcg::new(54);
        let (mut inside, mut ring, mut outside) = (0, 0, 0);
        for _ in 0..4000 {
            let (n, l) = (rng.cube(), rng.cube());
            let exponent = rng.range(0.5, 8.0);
            let period = rng.range(0.1, 0.5);
            let width = rng.range(0.0, 0.5 * period);
            let soft = rng.range(0.01, 0.25 * period);
            let c = n.as_dvec3().normalize().dot(l.as_dvec3().normalize());
            let lobe = c.max(0.0).powf(f64::from(exponent));
            // Distance to the nearest band centre (k + ½)·period, k ≥ 0 … or below 0.
            let pd = f64::from(period);
            let k = (lobe / pd - 0.5).round();
            let dist = (lobe - (k + 0.5) * pd).abs();
            let half = 0.5 * f64::from(width);
            let expected = smooth64((half + f64::from(soft) - dist) / f64::from(soft));
            if expected == 1.0 {
                inside += 1;
            } else if expected == 0.0 {
                outside += 1;
            } else {
                ring += 1;
            }
            // The lobe's error (a few ulps of the cosine, times p) through the ramp's slope.
            let lobe_err = 1e-6 + f64::from(exponent) * 1e-6;
            let tol = 1e-6 + 1.5 / f64::from(soft) * (lobe_err + 1e-6);
            let got = light_stripe_intensity(n, l, exponent, period, width, soft);
            assert_close(got, expected, tol, "light stripe");
            let lobe32 = light_spot_intensity(n, l, exponent);
            assert_eq!(
                got.to_bits(),
                light_stripe_band(lobe32, period, width, soft).to_bits()
            );
        }
        assert!(
            inside > 100 && ring > 100 && outside > 100,
            "{inside} {ring} {outside}"
        );
        // The unlit side sits mid-gap; the first band is centred on half a period.
        assert_eq!(light_stripe_band(0.0, 0.25, 0.1, 0.05), 0.0);
        assert_eq!(light_stripe_band(0.125, 0.25, 0.1, 0.05), 1.0);
        assert_eq!(light_stripe_band(0.375, 0.25, 0.1, 0.05), 1.0);
        assert_eq!(light_stripe_band(0.25, 0.25, 0.1, 0.05), 0.0);
        assert_eq!(
            light_stripe_intensity(Vec3::Y, -Vec3::Y, 1.0, 0.25, 0.1, 0.05),
            0.0
        );
        assert_eq!(
            light_stripe_intensity(Vec3::ZERO, Vec3::Y, 1.0, 0.25, 0.1, 0.05),
            0.0
        );
        assert_eq!(light_stripe_band(0.5, f32::NAN, 0.1, 0.05), 0.0);
    }

    #[test]
    fn reach_falloff_matches_f64_and_ends_at_the_reach() {
        let mut rng = Lcg::new(77);
        for _ in 0..2000 {
            let reach = rng.range(0.01, 50.0);
            let d = rng.range(0.0, 1.5) * reach;
            let expected = {
                let q = (f64::from(d) / f64::from(reach)).powi(2);
                if q < 1.0 { (1.0 - q).powi(2) } else { 0.0 }
            };
            assert_close(reach_falloff(d * d, reach), expected, 1e-5, "reach falloff");
        }
        assert_eq!(reach_falloff(0.0, 2.0), 1.0);
        assert_eq!(reach_falloff(4.0, 2.0), 0.0);
        assert_eq!(reach_falloff(100.0, 2.0), 0.0);
        assert_eq!(reach_falloff(1.0, 0.0), 0.0);
        assert_eq!(reach_falloff(0.0, 0.0), 0.0);
        assert_eq!(reach_falloff(1.0, -3.0), 0.0);
        assert_eq!(reach_falloff(f32::NAN, 2.0), 0.0);
        assert_eq!(reach_falloff(1.0, f32::NAN), 0.0);
        // Monotone in the distance, smooth at the reach: the last step before it is tiny.
        let mut last = 1.0;
        for k in 0..=1000 {
            let d = k as f32 / 1000.0 * 2.0;
            let f = reach_falloff(d * d, 2.0);
            assert!(f <= last, "{d}");
            last = f;
        }
        let near = reach_falloff(1.999f32.powi(2), 2.0);
        assert!(near < 1e-5, "{near}");
    }

    #[test]
    fn point_lights_match_f64() {
        let mut rng = Lcg::new(91);
        for _ in 0..2000 {
            let n = rng.cube().normalize_or_zero();
            let (point, light) = (rng.cube() * 4.0, rng.cube() * 4.0);
            let (reach, p) = (rng.range(0.5, 8.0), rng.range(1.0, 64.0));
            let offset = light.as_dvec3() - point.as_dvec3();
            let c = n.as_dvec3().dot(offset) / offset.length();
            let q = offset.length_squared() / f64::from(reach).powi(2);
            let falloff = if q < 1.0 { (1.0 - q).powi(2) } else { 0.0 };
            let expected = c.max(0.0).powf(f64::from(p)) * falloff;
            let tol = 1e-5 + f64::from(p) * 2e-6;
            assert_close(
                point_light_intensity(n, point, light, reach, p),
                expected,
                tol,
                "point light",
            );
            assert_close(
                point_light_cosine(n, light - point),
                c,
                1e-6,
                "point light cosine",
            );
        }
        // Straight above the surface point: the full lobe; beside it on the surface: none.
        let up = Vec3::Y;
        assert_eq!(point_light_intensity(up, Vec3::ZERO, up, 2.0, 8.0), 0.5625);
        assert_eq!(
            point_light_intensity(up, Vec3::ZERO, Vec3::X, 2.0, 8.0),
            0.0
        );
        // Facing it, but beyond the reach (the far wall across a torus's hole): none.
        assert_eq!(
            point_light_intensity(-Vec3::X, Vec3::X * 5.0, Vec3::ZERO, 3.0, 1.0),
            0.0
        );
        assert_eq!(point_light_cosine(up, Vec3::ZERO), 0.0);
        assert_eq!(point_light_cosine(up, Vec3::splat(f32::NAN)), 0.0);
    }

    #[test]
    fn lobes_below_the_cosine_bound_are_below_the_level() {
        let mut rng = Lcg::new(31);
        for _ in 0..300 {
            let level = rng.range(1.0e-3, 1.0);
            let exponent = if rng.unit() < 0.5 {
                rng.range(0.05, 2.0)
            } else {
                rng.range(2.0, 400.0)
            };
            let bound = light_spot_cosine_below(level, exponent);
            assert!(bound.is_finite(), "{level} {exponent}");
            // The bound is tight: the exact lobe at the bound is within 1 % of the level.
            let at_bound = f64::from(bound).max(0.0).powf(f64::from(exponent));
            assert!(at_bound <= f64::from(level) && at_bound >= 0.99 * f64::from(level) - 1e-30);
            let mut c = bound.next_down();
            for _ in 0..64 {
                assert!(
                    light_spot_lobe(c, exponent) < level,
                    "{c}^{exponent} vs {level}"
                );
                c = c.next_down();
            }
            for c in [0.0, -1.0, bound * 0.5, bound - 1e-3] {
                if c < bound {
                    assert!(light_spot_lobe(c, exponent) < level);
                }
            }
        }
        assert_eq!(light_spot_cosine_below(0.0, 4.0), f32::NEG_INFINITY);
        assert_eq!(light_spot_cosine_below(0.5, 0.0), f32::NEG_INFINITY);
        assert_eq!(light_spot_cosine_below(f32::NAN, 4.0), f32::NEG_INFINITY);
        assert_eq!(light_spot_cosine_below(0.5, f32::NAN), f32::NEG_INFINITY);
        assert_eq!(light_spot_cosine_below(0.5, f32::INFINITY), 1.0);
    }

    #[test]
    fn lobes_from_the_upper_cosine_bound_are_above_the_level() {
        let mut rng = Lcg::new(37);
        for _ in 0..300 {
            let level = rng.range(1.0e-3, 0.99);
            let exponent = if rng.unit() < 0.5 {
                rng.range(0.05, 2.0)
            } else {
                rng.range(2.0, 400.0)
            };
            let bound = light_spot_cosine_above(level, exponent);
            assert!(bound.is_finite() && bound <= 1.0, "{level} {exponent}");
            // Tight: the exact lobe at the bound is within 1 % over the level, and just under
            // the bound the exact lobe is at most the level with its margin.
            let at_bound = f64::from(bound).powf(f64::from(exponent));
            assert!(at_bound > f64::from(level) && at_bound <= 1.01 * f64::from(level));
            let mut c = bound;
            for _ in 0..64 {
                if c > 1.0 {
                    break;
                }
                assert!(
                    light_spot_lobe(c, exponent) > level,
                    "{c}^{exponent} vs {level}"
                );
                c = c.next_up();
            }
            for c in [1.0, 1.0f32.next_up(), bound + (1.0 - bound) * 0.5] {
                if c >= bound {
                    assert!(light_spot_lobe(c, exponent) > level);
                }
            }
        }
        // No cosine up to 1 is surely enough, or nothing safe to promise: +∞.
        assert_eq!(light_spot_cosine_above(0.9995, 4.0), f32::INFINITY);
        assert_eq!(light_spot_cosine_above(1.0, 4.0), f32::INFINITY);
        assert_eq!(light_spot_cosine_above(0.0, 4.0), f32::INFINITY);
        assert_eq!(light_spot_cosine_above(0.5, 0.0), f32::INFINITY);
        assert_eq!(light_spot_cosine_above(f32::NAN, 4.0), f32::INFINITY);
        assert_eq!(light_spot_cosine_above(0.5, f32::NAN), f32::INFINITY);
        let n = Vec3::new(0.3, -0.2, 0.9);
        let d = Vec3::new(1.0, 2.0, 3.0);
        assert_eq!(
            light_spot_intensity(n, d, 7.0),
            light_spot_lobe(light_spot_cosine(n, d), 7.0)
        );
    }
}
