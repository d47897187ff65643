//! Axis-dropping projection of a world-space change onto texture (u, v) (thesis 3.2.2, reused for
//! the wind in 3.3; shading stage): find `(a, b)` with `a·dP/du + b·dP/dv ≈ change` by dropping one
//! world axis and solving the 2×2 system on the other two (Cramer's rule). Never returns NaN.

use glam::{Vec2, Vec3};

/// A world axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Axis {
    /// The x axis (index 0).
    X,
    /// The y axis (index 1).
    Y,
    /// The z axis (index 2).
    Z,
}

impl Axis {
    /// The axes in index order; ties are always broken towards the earlier one.
    pub const ALL: [Axis; 3] = [Axis::X, Axis::Y, Axis::Z];

    /// Index 0, 1, 2 for x, y, z.
    #[inline]
    pub fn index(self) -> usize {
        match self {
            Axis::X => 0,
            Axis::Y => 1,
            Axis::Z => 2,
        }
    }

    /// The axis where `|v|` is smallest, ties to the lowest index (NaN components are never
    /// chosen over a number; all-NaN gives x).
    #[inline]
    pub fn least(v: Vec3) -> Axis {
        let a = v.abs().to_array();
        let mut best = Axis::X;
        for axis in [Axis::Y, Axis::Z] {
            if a[axis.index()] < a[best.index()] || a[best.index()].is_nan() {
                best = axis;
            }
        }
        best
    }

    /// The axis where `|v|` is largest, ties to the lowest index (NaN components are never
    /// chosen over a number; all-NaN gives x).
    #[inline]
    pub fn greatest(v: Vec3) -> Axis {
        let a = v.abs().to_array();
        let mut best = Axis::X;
        for axis in [Axis::Y, Axis::Z] {
            if a[axis.index()] > a[best.index()] || a[best.index()].is_nan() {
                best = axis;
            }
        }
        best
    }

    /// The two other axes' indices, in increasing order.
    #[inline]
    fn kept(self) -> (usize, usize) {
        match self {
            Axis::X => (1, 2),
            Axis::Y => (0, 2),
            Axis::Z => (0, 1),
        }
    }
}

/// A 2×2 system whose determinant is at most this fraction of `|dP/du|·|dP/dv|` is treated as
/// singular. The determinant of the system that drops axis k is the k-th component of
/// `dP/du × dP/dv` (up to sign), so this says: the surface is within about 0.06° of containing
/// that axis. Below it, f32 round-off in the solution would be amplified over 1000×.
pub const SINGULAR_RELATIVE_DET: f32 = 1e-3;

/// Cramer's rule on the axes kept when `dropped` is removed; `None` when (near-)singular or the
/// solution is not finite.
#[inline]
fn solve_dropping(change: Vec3, dpdu: Vec3, dpdv: Vec3, dropped: Axis) -> Option<Vec2> {
    let (i, j) = dropped.kept();
    let (c, u, v) = (change.to_array(), dpdu.to_array(), dpdv.to_array());
    let det = u[i] * v[j] - v[i] * u[j];
    let scale = dpdu.length() * dpdv.length();
    if det.is_nan() || det.abs() <= SINGULAR_RELATIVE_DET * scale {
        return None;
    }
    let a = (c[i] * v[j] - v[i] * c[j]) / det;
    let b = (u[i] * c[j] - c[i] * u[j]) / det;
    let uv = Vec2::new(a, b);
    uv.is_finite().then_some(uv)
}

/// `|det|` of the system that drops `axis`, i.e. `|(dP/du × dP/dv)_axis|`.
#[inline]
fn abs_det(dpdu: Vec3, dpdv: Vec3, axis: Axis) -> f32 {
    let (i, j) = axis.kept();
    let (u, v) = (dpdu.to_array(), dpdv.to_array());
    (u[i] * v[j] - v[i] * u[j]).abs()
}

/// Like [`project_to_uv`], with the dropped axis given by the caller (the wind of thesis 3.3
/// drops "the axis that we moved the most" along the negative normal).
///
/// If that system is (near-)singular (see [`SINGULAR_RELATIVE_DET`]) it falls back to the axis
/// whose system has the largest `|det|` (ties to the lowest index); if that one is singular too
/// (`dP/du` parallel to `dP/dv`, or zero) the result is zero. Any non-finite input gives zero.
#[inline]
pub fn project_to_uv_dropping(change: Vec3, dpdu: Vec3, dpdv: Vec3, dropped: Axis) -> Vec2 {
    if !(change.is_finite() && dpdu.is_finite() && dpdv.is_finite()) {
        return Vec2::ZERO;
    }
    if let Some(uv) = solve_dropping(change, dpdu, dpdv, dropped) {
        return uv;
    }
    let mut best = Axis::X;
    for axis in [Axis::Y, Axis::Z] {
        if abs_det(dpdu, dpdv, axis) > abs_det(dpdu, dpdv, best) {
            best = axis;
        }
    }
    solve_dropping(change, dpdu, dpdv, best).unwrap_or(Vec2::ZERO)
}

/// Thesis 3.2.2's projection of the `shadowChange` vector to a texture offset: drop the world
/// axis where `|change|` is smallest ("removing the lowest amount of change in the dimension
/// x, y, z"; ties to the lowest index: x before y before z), solve
/// `a·dP/du + b·dP/dv = change` on the two other axes by Cramer's rule, return `(a, b)`.
///
/// When `change` lies in the plane of `dP/du`, `dP/dv` this recovers it exactly (up to
/// round-off). Otherwise the dropped component is simply ignored, as in the thesis. Singular
/// systems and non-finite inputs: see [`project_to_uv_dropping`]. Never NaN.
#[inline]
pub fn project_to_uv(change: Vec3, dpdu: Vec3, dpdv: Vec3) -> Vec2 {
    project_to_uv_dropping(change, dpdu, dpdv, Axis::least(change))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shading::test_support::{Lcg, assert_close};

    #[test]
    fn recovers_in_plane_changes_on_random_frames() {
        // Bound on a and b: 1e-5·(1 + |a| + |b|)·cond, cond = |dpdu||dpdv| / max_k |det_k|
        // (the conditioning of the best system; the chosen one is within 1/SINGULAR of it, and
        // any non-singular system gives the same exact answer for an in-plane change).
        let mut rng = Lcg::new(30);
        let mut checked = 0;
        for _ in 0..3000 {
            let dpdu = rng.cube() * rng.range(0.01, 4.0);
            let dpdv = rng.cube() * rng.range(0.01, 4.0);
            let (a, b) = (rng.range(-2.0, 2.0), rng.range(-2.0, 2.0));
            let (u, v) = (dpdu.as_dvec3(), dpdv.as_dvec3());
            let cross = u.cross(v);
            if cross.length() < 0.05 * u.length() * v.length() {
                continue; // nearly parallel frames: tested separately
            }
            let change = (f64::from(a) * u + f64::from(b) * v).as_vec3();
            let got = project_to_uv(change, dpdu, dpdv);
            // f64 reference: least-squares solution of the (rounded) change on the plane.
            let c = change.as_dvec3();
            let (uu, uv, vv) = (u.dot(u), u.dot(v), v.dot(v));
            let det = uu * vv - uv * uv;
            let ea = (c.dot(u) * vv - c.dot(v) * uv) / det;
            let eb = (c.dot(v) * uu - c.dot(u) * uv) / det;
            let chosen = Axis::least(change);
            let (i, j) = chosen.kept();
            let chosen_det = (u[i] * v[j] - v[i] * u[j]).abs();
            let det_used = if chosen_det > 1e-3 * u.length() * v.length() {
                chosen_det
            } else {
                cross.abs().max_element()
            };
            let cond = u.length() * v.length() / det_used;
            let tol = 1e-5 * (1.0 + ea.abs() + eb.abs()) * cond;
            assert_close(got.x, ea, tol, "a");
            assert_close(got.y, eb, tol, "b");
            checked += 1;
        }
        assert!(checked > 2000);
    }

    #[test]
    fn axis_aligned_cases() {
        // Surface in the x–y plane, u along x, v along y (scaled).
        let (du, dv) = (Vec3::X * 2.0, Vec3::Y * 0.5);
        // change along x: y and z tie at 0, y (lower index) is dropped first, that system is
        // singular (det = (du × dv).y = 0), so the fallback drops z.
        assert_eq!(project_to_uv(Vec3::X, du, dv), Vec2::new(0.5, 0.0));
        assert_eq!(project_to_uv(Vec3::Y, du, dv), Vec2::new(0.0, 2.0));
        assert_eq!(
            project_to_uv(Vec3::new(1.0, 1.0, 0.0), du, dv),
            Vec2::new(0.5, 2.0)
        );
        // Out-of-plane change: the thesis ignores the dropped (least) component; here z is the
        // least when |z| < |x|, |y|.
        assert_eq!(
            project_to_uv(Vec3::new(2.0, 1.0, 0.5), du, dv),
            Vec2::new(1.0, 2.0)
        );
        // When z dominates, x (least) is dropped: the system on (y, z) is singular, the fallback
        // drops z and keeps the in-plane part.
        assert_eq!(
            project_to_uv(Vec3::new(0.0, 1.0, 5.0), du, dv),
            Vec2::new(0.0, 2.0)
        );
        // Tie-breaking of the axis choice.
        assert_eq!(Axis::least(Vec3::new(1.0, 1.0, 1.0)), Axis::X);
        assert_eq!(Axis::least(Vec3::new(2.0, 1.0, -1.0)), Axis::Y);
        assert_eq!(Axis::greatest(Vec3::new(-3.0, 1.0, 3.0)), Axis::X);
        assert_eq!(Axis::greatest(Vec3::new(f32::NAN, 1.0, 3.0)), Axis::Z);
    }

    #[test]
    fn explicit_drop_matches_f64_cramer() {
        let mut rng = Lcg::new(31);
        for _ in 0..1000 {
            let (dpdu, dpdv, change) = (rng.cube(), rng.cube(), rng.cube());
            for axis in Axis::ALL {
                let (i, j) = axis.kept();
                let (u, v, c) = (dpdu.as_dvec3(), dpdv.as_dvec3(), change.as_dvec3());
                let det = u[i] * v[j] - v[i] * u[j];
                if det.abs() < 0.05 * u.length() * v.length() {
                    continue;
                }
                let ea = (c[i] * v[j] - v[i] * c[j]) / det;
                let eb = (u[i] * c[j] - c[i] * u[j]) / det;
                let cond = u.length() * v.length() / det.abs();
                let tol = 1e-6 * (1.0 + ea.abs() + eb.abs() + c.length()) * cond;
                let got = project_to_uv_dropping(change, dpdu, dpdv, axis);
                assert_close(got.x, ea, tol, "a");
                assert_close(got.y, eb, tol, "b");
            }
        }
    }

    #[test]
    fn degenerate_inputs_give_zero() {
        let c = Vec3::new(0.3, -0.2, 0.9);
        assert_eq!(project_to_uv(c, Vec3::X, Vec3::X * 2.0), Vec2::ZERO);
        assert_eq!(project_to_uv(c, Vec3::ZERO, Vec3::Y), Vec2::ZERO);
        assert_eq!(project_to_uv(c, Vec3::ZERO, Vec3::ZERO), Vec2::ZERO);
        assert_eq!(project_to_uv(Vec3::ZERO, Vec3::X, Vec3::Y), Vec2::ZERO);
        let nan = Vec3::new(f32::NAN, 0.0, 0.0);
        assert_eq!(project_to_uv(nan, Vec3::X, Vec3::Y), Vec2::ZERO);
        assert_eq!(project_to_uv(c, nan, Vec3::Y), Vec2::ZERO);
        let inf = Vec3::new(f32::INFINITY, 0.0, 0.0);
        assert_eq!(project_to_uv(c, Vec3::X, inf), Vec2::ZERO);
        // Huge but finite: stays finite.
        let big = project_to_uv(Vec3::splat(1e30), Vec3::X * 1e-30, Vec3::Y * 1e-30);
        assert!(big.is_finite());
        // Nearly parallel (below the singular threshold): zero, not a blow-up.
        let almost = Vec3::new(1.0, 1e-5, 0.0);
        assert_eq!(project_to_uv(c, Vec3::X, almost), Vec2::ZERO);
    }
}
