//! Tangent frames (mesh stage): the T, B, N basis that takes world vectors into the fur texture's
//! space (thesis 3.2.1, eq. 3.1–3.3).
//!
//! How a mesh gets its frames (in [`Mesh::from_parts`], the procedural meshes and the OBJ
//! loader), in order:
//! 1. **Face normal** from positions: `n_f = (p2 − p1) × (p3 − p1)`, whose length is twice the
//!    face's area.
//! 2. **Vertex normal** = normalised sum of the unit face normals of every face touching a
//!    vertex *with the same position*, each weighted by the face's angle at that corner
//!    (angle-weighted, so the result does not depend on how quads were split into triangles;
//!    welded across UV seams so shells do not crack). A sum or face normal whose squared length
//!    under- or overflows f32 (tiny or huge faces) is scaled by its largest component before
//!    normalising, so it still gives a unit vector. If that sum
//!    is zero or not finite (an isolated vertex, or faces that cancel), the normal of the first
//!    adjacent face with non-zero area is used, and if there is none, +Y.
//! 3. **Face T and B** (eq. 3.1, 3.2, [`face_tangents`]): ∂p/∂u and ∂p/∂v of the face, solved
//!    from its edges and UV differences. Faces whose UVs are degenerate (zero UV area, all UVs
//!    equal) have none and are skipped.
//! 4. **Vertex `dpdu`, `dpdv`** = area-weighted average of the adjacent faces' T and B. Across
//!    a UV seam, vertices with the same position pool their faces only when their own sums
//!    agree in direction (positive dot for both T and B): a wrap-around seam (torus, sphere,
//!    `u = 1` next to `u = 0`) gets identical, symmetric derivatives on both sides, while a
//!    mirrored seam keeps each side's own orientation. A position shared by more than
//!    [`MAX_SEAM_GROUP`] vertices is no seam but a degenerate fan (a seam joins a handful of
//!    copies; a UV sphere's pole one per segment): there each vertex keeps its own sums, so the
//!    pooling, which compares every pair of a group, costs at most `MAX_SEAM_GROUP` steps a
//!    vertex.
//! 5. **Frame** ([`TangentFrame::from_derivatives`]): N = vertex normal; T = `dpdu`
//!    Gram–Schmidt-orthogonalised against N and normalised; B = N × T, flipped when it points
//!    against `dpdv` (mirrored UVs). So T, B, N are always orthonormal.
//!
//! Eq. 3.3 (N = T × B) is not used to *define* N (N comes from positions, as the thesis says
//! "the normal values are recalculated"); it is a property we check: for non-mirrored UVs
//! `T × B = N` exactly by construction, and the raw face T × B points along the geometric
//! normal. With mirrored UVs, `T × B = −N` ([`TangentFrame::is_right_handed`] is false).

use glam::{Mat3, Vec2, Vec3};

use super::{Mesh, Vertex, weld_by_position};

/// The most vertices at one position whose derivatives are pooled across a UV seam (module
/// docs, step 4); a larger group keeps each vertex's own.
pub const MAX_SEAM_GROUP: usize = 1024;

/// An orthonormal basis at a surface point: `tangent` follows the texture's u axis, `binormal`
/// its v axis, `normal` points out of the surface. Tangent-space coordinates of a world vector
/// `w` are `(w·tangent, w·binormal, w·normal)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TangentFrame {
    /// Unit vector along increasing texture u.
    pub tangent: Vec3,
    /// Unit vector along increasing texture v.
    pub binormal: Vec3,
    /// Unit outward surface normal.
    pub normal: Vec3,
}

impl TangentFrame {
    /// The frame of step 5 in the [module docs](self): N = `normal` (assumed unit length),
    /// T = `dpdu` orthogonalised against N, B = N × T, flipped if `B · dpdv < 0`.
    ///
    /// Fallbacks, so the result is never NaN: if `dpdu` is zero, not finite or (almost) parallel
    /// to N, T is taken from `dpdv` (T = B' × N); if that fails too, T = [`arbitrary_tangent`].
    pub fn from_derivatives(normal: Vec3, dpdu: Vec3, dpdv: Vec3) -> TangentFrame {
        let tangent = orthogonal_part(dpdu, normal)
            .or_else(|| orthogonal_part(dpdv, normal).map(|b| b.cross(normal).normalize()))
            .unwrap_or_else(|| arbitrary_tangent(normal));
        let mut binormal = normal.cross(tangent);
        if binormal.dot(dpdv) < 0.0 {
            binormal = -binormal;
        }
        TangentFrame {
            tangent,
            binormal,
            normal,
        }
    }

    /// World → tangent space: `(w·T, w·B, w·N)` (the thesis multiplies by the TBN matrix).
    pub fn to_tangent(&self, w: Vec3) -> Vec3 {
        Vec3::new(
            w.dot(self.tangent),
            w.dot(self.binormal),
            w.dot(self.normal),
        )
    }

    /// Tangent → world space: `t.x·T + t.y·B + t.z·N`.
    pub fn to_world(&self, t: Vec3) -> Vec3 {
        self.tangent * t.x + self.binormal * t.y + self.normal * t.z
    }

    /// The matrix with columns T, B, N (tangent → world); its transpose is world → tangent.
    pub fn to_world_matrix(&self) -> Mat3 {
        Mat3::from_cols(self.tangent, self.binormal, self.normal)
    }

    /// `true` when `T × B` points along N (eq. 3.3 holds), `false` for mirrored UVs.
    pub fn is_right_handed(&self) -> bool {
        self.tangent.cross(self.binormal).dot(self.normal) > 0.0
    }
}

/// `v` with its component along unit `n` removed, normalised; `None` when that is (almost) zero
/// or not finite. Two Gram–Schmidt passes keep it orthogonal to `n` to f32 precision.
fn orthogonal_part(v: Vec3, n: Vec3) -> Option<Vec3> {
    let len = v.length();
    if !len.is_finite() || len <= f32::MIN_POSITIVE {
        return None;
    }
    let v = v / len;
    let t = v - n * n.dot(v);
    if t.length_squared() < 1e-8 {
        return None;
    }
    let t = t.normalize();
    Some((t - n * n.dot(t)).normalize())
}

/// A deterministic unit vector orthogonal to unit `n`: the coordinate axis least aligned with
/// `n` (ties: x before y before z), Gram–Schmidt-orthogonalised against `n`.
pub fn arbitrary_tangent(n: Vec3) -> Vec3 {
    let a = n.abs();
    let axis = if a.x <= a.y && a.x <= a.z {
        Vec3::X
    } else if a.y <= a.z {
        Vec3::Y
    } else {
        Vec3::Z
    };
    (axis - n * n.dot(axis)).normalize()
}

/// Eq. 3.1 and 3.2: the unnormalised tangent T = ∂p/∂u and binormal B = ∂p/∂v of a triangle
/// `p1 p2 p3` with texture coordinates `(u_k, v_k)`:
///
/// ```text
/// T = ((v3 − v1)(p2 − p1) − (v2 − v1)(p3 − p1)) / d        (3.1)
/// B = ((u2 − u1)(p3 − p1) − (u3 − u1)(p2 − p1)) / d        (3.2)
/// d = (u2 − u1)(v3 − v1) − (v2 − v1)(u3 − u1)
/// ```
///
/// Eq. 3.1 is printed correctly in the thesis. The printed eq. 3.2 has a typo in its
/// denominator (`(v2 − v1)(v3 − v1) − (u2 − u1)(v3 − v1)`); the form above is the standard
/// one (Lengyel), the solution of `p2 − p1 = Δu₁ T + Δv₁ B`, `p3 − p1 = Δu₂ T + Δv₂ B`.
///
/// Returns `None` when the UV triangle is degenerate: `d = 0`, `|d|` below 1e-6 of the sum of
/// its two products' magnitudes (collinear UVs), or a non-finite result.
pub fn face_tangents(p: [Vec3; 3], uv: [Vec2; 3]) -> Option<(Vec3, Vec3)> {
    let e1 = p[1] - p[0];
    let e2 = p[2] - p[0];
    let d1 = uv[1] - uv[0];
    let d2 = uv[2] - uv[0];
    let a = d1.x * d2.y;
    let b = d1.y * d2.x;
    let det = a - b;
    if det == 0.0 || det.abs() <= 1e-6 * (a.abs() + b.abs()) {
        return None;
    }
    let t = (e1 * d2.y - e2 * d1.y) / det;
    let bn = (e2 * d1.x - e1 * d2.x) / det;
    (t.is_finite() && bn.is_finite()).then_some((t, bn))
}

/// `v` normalised when its squared length leaves f32's normal range (tiny faces, or the tiny
/// corner angles of long thin ones, whose squares underflow to imprecise subnormals; huge faces,
/// whose squares overflow): scaled by its largest component first. `None` when zero or not
/// finite. Ordinary vectors never come here, so their normals are unchanged.
fn rescaled_unit(v: Vec3) -> Option<Vec3> {
    let m = v.abs().max_element();
    if !(m.is_finite() && m > 0.0) {
        return None;
    }
    (v / m).try_normalize()
}

/// The angle at corner `a` of triangle `a b c`, in radians (0 for a degenerate corner):
/// `atan2(|e1 × e2|, e1 · e2)`, accurate for small and obtuse angles alike.
fn corner_angle(a: Vec3, b: Vec3, c: Vec3) -> f32 {
    let (e1, e2) = (b - a, c - a);
    let angle = libm::atan2f(e1.cross(e2).length(), e1.dot(e2));
    if angle.is_finite() { angle } else { 0.0 }
}

/// Builds a [`Mesh`] from positions, UVs and triangles whose indices are known to be in range
/// (faces with an out-of-range index are skipped rather than trusted). See the module docs.
pub(crate) fn build(positions: &[Vec3], uvs: &[Vec2], indices: Vec<[u32; 3]>) -> Mesh {
    let n = positions.len().min(uvs.len());
    let indices: Vec<[u32; 3]> = indices
        .into_iter()
        .filter(|t| t.iter().all(|&i| (i as usize) < n))
        .collect();
    let weld = weld_by_position(&positions[..n]);

    let mut normal_sum = vec![Vec3::ZERO; n];
    let mut first_face_normal: Vec<Option<Vec3>> = vec![None; n];
    let mut dpdu_sum = vec![Vec3::ZERO; n];
    let mut dpdv_sum = vec![Vec3::ZERO; n];
    let mut weight = vec![0.0f32; n];
    for tri in &indices {
        let [i0, i1, i2] = tri.map(|i| i as usize);
        let p = [positions[i0], positions[i1], positions[i2]];
        let face_n = (p[1] - p[0]).cross(p[2] - p[0]);
        let area2 = face_n.length();
        let unit = if area2.is_finite() && (area2 * area2).is_normal() {
            Some(face_n / area2)
        } else {
            rescaled_unit(face_n)
        };
        for (k, &i) in [i0, i1, i2].iter().enumerate() {
            let w = weld[i] as usize;
            if let Some(unit) = unit {
                normal_sum[w] += unit * corner_angle(p[k], p[(k + 1) % 3], p[(k + 2) % 3]);
                first_face_normal[w].get_or_insert(unit);
            }
        }
        if let Some((t, b)) = face_tangents(p, [uvs[i0], uvs[i1], uvs[i2]]) {
            for &i in &[i0, i1, i2] {
                dpdu_sum[i] += t * area2;
                dpdv_sum[i] += b * area2;
                weight[i] += area2;
            }
        }
    }

    // Seam welding of the derivatives: vertices that share a position and whose own sums point
    // the same way (positive dot for both T and B) pool their sums, in index order.
    let mut order: Vec<u32> = (0..n as u32).collect();
    order.sort_by_key(|&i| (weld[i as usize], i));
    let mut pooled = vec![(Vec3::ZERO, Vec3::ZERO, 0.0f32); n];
    for group in order.chunk_by(|&a, &b| weld[a as usize] == weld[b as usize]) {
        if group.len() > MAX_SEAM_GROUP {
            for &i in group {
                let i = i as usize;
                pooled[i] = (dpdu_sum[i], dpdv_sum[i], weight[i]);
            }
            continue;
        }
        for &i in group {
            let i = i as usize;
            let mut acc = (Vec3::ZERO, Vec3::ZERO, 0.0f32);
            for &j in group {
                let j = j as usize;
                let same = j == i
                    || (dpdu_sum[j].dot(dpdu_sum[i]) > 0.0 && dpdv_sum[j].dot(dpdv_sum[i]) > 0.0);
                if same {
                    acc = (acc.0 + dpdu_sum[j], acc.1 + dpdv_sum[j], acc.2 + weight[j]);
                }
            }
            pooled[i] = acc;
        }
    }

    let vertices = (0..n)
        .map(|i| {
            let w = weld[i] as usize;
            let sum = normal_sum[w];
            let normal = if sum.length_squared().is_normal() {
                sum.try_normalize()
            } else {
                rescaled_unit(sum)
            }
            .or(first_face_normal[w])
            .unwrap_or(Vec3::Y);
            let (dpdu_sum, dpdv_sum, weight) = pooled[i];
            let (dpdu, dpdv) = if weight > 0.0 && weight.is_finite() {
                (dpdu_sum / weight, dpdv_sum / weight)
            } else {
                (Vec3::ZERO, Vec3::ZERO)
            };
            let (dpdu, dpdv) = if dpdu.is_finite() && dpdv.is_finite() {
                (dpdu, dpdv)
            } else {
                (Vec3::ZERO, Vec3::ZERO)
            };
            Vertex {
                position: positions[i],
                normal,
                uv: uvs[i],
                frame: TangentFrame::from_derivatives(normal, dpdu, dpdv),
                dpdu,
                dpdv,
                rest_position: positions[i],
                rest_normal: normal,
                lag: Vec3::ZERO,
            }
        })
        .collect();
    Mesh { vertices, indices }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use glam::DVec3;

    /// Small deterministic generator for tests (xorshift64*).
    pub(crate) struct Rng(u64);
    impl Rng {
        pub(crate) fn new(seed: u64) -> Rng {
            Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
        }
        /// Uniform in [0, 1).
        pub(crate) fn next(&mut self) -> f32 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            let x = self.0.wrapping_mul(0x2545_F491_4F6C_DD1D);
            (x >> 40) as f32 / (1u64 << 24) as f32
        }
        pub(crate) fn range(&mut self, lo: f32, hi: f32) -> f32 {
            lo + (hi - lo) * self.next()
        }
        pub(crate) fn vec3(&mut self, s: f32) -> Vec3 {
            Vec3::new(self.range(-s, s), self.range(-s, s), self.range(-s, s))
        }
        pub(crate) fn vec2(&mut self) -> Vec2 {
            Vec2::new(self.next(), self.next())
        }
    }

    pub(crate) fn assert_orthonormal(f: &TangentFrame, tol: f32) {
        let TangentFrame {
            tangent: t,
            binormal: b,
            normal: n,
        } = *f;
        assert!(t.is_finite() && b.is_finite() && n.is_finite(), "{f:?}");
        for (name, v) in [("T", t), ("B", b), ("N", n)] {
            assert!(
                (v.length() - 1.0).abs() < tol,
                "|{name}| = {} in {f:?}",
                v.length()
            );
        }
        for (name, d) in [("T·B", t.dot(b)), ("T·N", t.dot(n)), ("B·N", b.dot(n))] {
            assert!(d.abs() < tol, "{name} = {d} in {f:?}");
        }
    }

    #[test]
    fn eq_3_1_3_2_match_f64_solution() {
        let mut rng = Rng::new(1);
        let mut checked = 0;
        for _ in 0..2000 {
            let p = [rng.vec3(10.0), rng.vec3(10.0), rng.vec3(10.0)];
            let uv = [rng.vec2(), rng.vec2(), rng.vec2()];
            // f64 reference: solve [Δu1 Δv1; Δu2 Δv2] [T; B] = [e1; e2].
            let d = |a: Vec3| a.as_dvec3();
            let (e1, e2) = (d(p[1] - p[0]), d(p[2] - p[0]));
            let du1 = uv[1].x as f64 - uv[0].x as f64;
            let dv1 = uv[1].y as f64 - uv[0].y as f64;
            let du2 = uv[2].x as f64 - uv[0].x as f64;
            let dv2 = uv[2].y as f64 - uv[0].y as f64;
            let det = du1 * dv2 - du2 * dv1;
            if det.abs() < 1e-2 {
                continue; // ill-conditioned: f32 inputs cannot be expected to agree closely
            }
            let t_ref: DVec3 = (e1 * dv2 - e2 * dv1) / det;
            let b_ref: DVec3 = (e2 * du1 - e1 * du2) / det;
            let (t, b) = face_tangents(p, uv).expect("non-degenerate");
            let scale = t_ref.length().max(b_ref.length());
            assert!(
                (t.as_dvec3() - t_ref).length() <= 1e-4 * scale,
                "{t} vs {t_ref}"
            );
            assert!(
                (b.as_dvec3() - b_ref).length() <= 1e-4 * scale,
                "{b} vs {b_ref}"
            );
            // Reconstruction: the edges are recovered from T and B.
            let rec = (t * (uv[1].x - uv[0].x) + b * (uv[1].y - uv[0].y)).as_dvec3();
            assert!((rec - e1).length() <= 1e-3 * (1.0 + e1.length()));
            // Eq. 3.3: T × B is parallel to the geometric normal when d > 0.
            let geo = e1.cross(e2);
            let tb = t.cross(b).as_dvec3();
            assert!(tb.dot(geo) * det.signum() > 0.0);
            checked += 1;
        }
        assert!(checked > 1000, "{checked}");
    }

    #[test]
    fn degenerate_uvs_give_none() {
        let p = [Vec3::ZERO, Vec3::X, Vec3::Y];
        assert!(face_tangents(p, [Vec2::splat(0.3); 3]).is_none());
        let collinear = [Vec2::ZERO, Vec2::new(0.5, 0.5), Vec2::new(1.0, 1.0)];
        assert!(face_tangents(p, collinear).is_none());
        assert!(face_tangents(p, [Vec2::ZERO, Vec2::X, Vec2::Y]).is_some());
    }

    #[test]
    fn frames_orthonormal_on_axes_and_random() {
        let mut rng = Rng::new(7);
        let axes = [Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X, -Vec3::Y, -Vec3::Z];
        for &n in &axes {
            for &d in &axes {
                let f = TangentFrame::from_derivatives(n, d, d.cross(n));
                assert_orthonormal(&f, 1e-6);
            }
            assert_orthonormal(
                &TangentFrame::from_derivatives(n, Vec3::ZERO, Vec3::ZERO),
                1e-6,
            );
        }
        for _ in 0..10_000 {
            let n = rng.vec3(1.0).try_normalize().unwrap_or(Vec3::Z);
            let dpdu = rng.vec3(100.0);
            let dpdv = rng.vec3(0.01);
            let f = TangentFrame::from_derivatives(n, dpdu, dpdv);
            assert_orthonormal(&f, 1e-5);
            // Near-parallel dpdu.
            let f = TangentFrame::from_derivatives(n, n * 3.0 + rng.vec3(1e-5), dpdv);
            assert_orthonormal(&f, 1e-5);
            let f = TangentFrame::from_derivatives(n, Vec3::splat(f32::NAN), Vec3::INFINITY);
            assert_orthonormal(&f, 1e-5);
        }
    }

    #[test]
    fn frame_follows_uv_directions_and_mirroring() {
        // Plane z = 0 facing +z, u along +x, v along +y.
        let f = TangentFrame::from_derivatives(Vec3::Z, Vec3::X * 2.0, Vec3::Y * 3.0);
        assert_eq!(f.tangent, Vec3::X);
        assert_eq!(f.binormal, Vec3::Y);
        assert!(f.is_right_handed());
        let w = Vec3::new(0.1, 0.2, 0.3);
        assert!((f.to_world(f.to_tangent(w)) - w).length() < 1e-6);
        assert!((f.to_world_matrix().transpose() * w - f.to_tangent(w)).length() < 1e-6);
        // Mirrored v.
        let f = TangentFrame::from_derivatives(Vec3::Z, Vec3::X, -Vec3::Y);
        assert_eq!(f.binormal, -Vec3::Y);
        assert!(!f.is_right_handed());
    }

    fn random_mesh(rng: &mut Rng, verts: usize, faces: usize, uv_mode: u32) -> Mesh {
        let positions: Vec<Vec3> = (0..verts).map(|_| rng.vec3(1.0)).collect();
        let uvs: Vec<Vec2> = (0..verts)
            .map(|i| match uv_mode {
                0 => rng.vec2(),
                1 => Vec2::splat(0.5),
                _ => Vec2::new(i as f32 * 1e-7, 0.25),
            })
            .collect();
        let mut pick = || ((rng.next() * verts as f32) as u32).min(verts as u32 - 1);
        let indices = (0..faces).map(|_| [pick(), pick(), pick()]).collect();
        Mesh::from_parts(&positions, &uvs, indices).unwrap()
    }

    #[test]
    fn mesh_frames_never_nan() {
        let mut rng = Rng::new(3);
        for uv_mode in 0..3 {
            for _ in 0..50 {
                let mesh = random_mesh(&mut rng, 12, 20, uv_mode);
                for v in &mesh.vertices {
                    assert_orthonormal(&v.frame, 1e-5);
                    assert_eq!(v.normal, v.frame.normal);
                    assert!(v.dpdu.is_finite() && v.dpdv.is_finite());
                }
            }
        }
        // Zero-area faces and repeated vertices; an isolated vertex.
        let p = [Vec3::ZERO, Vec3::ZERO, Vec3::X, Vec3::new(5.0, 5.0, 5.0)];
        let uv = [Vec2::ZERO, Vec2::X, Vec2::Y, Vec2::ONE];
        let mesh = Mesh::from_parts(&p, &uv, vec![[0, 1, 2], [0, 0, 2]]).unwrap();
        for v in &mesh.vertices {
            assert_orthonormal(&v.frame, 1e-6);
        }
        assert_eq!(mesh.vertices[3].normal, Vec3::Y);
    }

    #[test]
    fn mirrored_seam_keeps_each_side() {
        // Two quads in the xy plane sharing the edge x = 1; the right one has u mirrored, so
        // the shared edge is split into two vertex pairs with different UVs.
        let p = [
            Vec3::ZERO,
            Vec3::X,
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::Y,
            Vec3::X,
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(2.0, 1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
        ];
        let uv = [
            Vec2::ZERO,
            Vec2::X,
            Vec2::ONE,
            Vec2::Y,
            Vec2::X,
            Vec2::ZERO,
            Vec2::Y,
            Vec2::ONE,
        ];
        let idx = vec![[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]];
        let mesh = Mesh::from_parts(&p, &uv, idx).unwrap();
        for (i, v) in mesh.vertices.iter().enumerate() {
            assert_orthonormal(&v.frame, 1e-6);
            assert!((v.normal - Vec3::Z).length() < 1e-6);
            let expect = if i < 4 { Vec3::X } else { -Vec3::X };
            assert!((v.frame.tangent - expect).length() < 1e-6, "{i}: {v:?}");
            assert!((v.frame.binormal - Vec3::Y).length() < 1e-6);
            assert_eq!(v.frame.is_right_handed(), i < 4);
        }
    }

    /// `faces` copies of one triangle, each with its own three vertices, the k-th scaled in u
    /// by `1 + k` (so every copy has its own ∂p/∂u, all pointing along +x).
    fn fan(faces: usize) -> Mesh {
        let mut p = Vec::new();
        let mut uv = Vec::new();
        let mut idx = Vec::new();
        for k in 0..faces {
            let s = 1.0 + k as f32;
            p.extend([Vec3::ZERO, Vec3::X, Vec3::Y]);
            uv.extend([Vec2::ZERO, Vec2::new(s, 0.0), Vec2::Y]);
            let b = 3 * k as u32;
            idx.push([b, b + 1, b + 2]);
        }
        Mesh::from_parts(&p, &uv, idx).unwrap()
    }

    #[test]
    fn a_seam_group_pools_and_a_degenerate_fan_keeps_its_own() {
        // Up to MAX_SEAM_GROUP copies at one position pool: every copy gets the mean ∂p/∂u.
        let pooled = fan(MAX_SEAM_GROUP / 2);
        let first = pooled.vertices[0].dpdu;
        for v in &pooled.vertices {
            assert_eq!(v.dpdu, first);
        }
        // More, and each keeps its own (1/s along +x), at a cost linear in the group.
        let faces = MAX_SEAM_GROUP + 1;
        let fan = fan(faces);
        for (k, tri) in fan.vertices.chunks(3).enumerate() {
            let expect = Vec3::X / (1.0 + k as f32);
            assert!(
                (tri[0].dpdu - expect).length() < 1e-6,
                "{k}: {:?}",
                tri[0].dpdu
            );
        }
    }

    #[test]
    fn planar_grid_frames_are_exact() {
        // Quad in the xy plane, CCW from +z.
        let p = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
        let uv = [Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y];
        let mesh = Mesh::from_parts(&p, &uv, vec![[0, 1, 2], [0, 2, 3]]).unwrap();
        for v in &mesh.vertices {
            assert!((v.normal - Vec3::Z).length() < 1e-6);
            assert!((v.frame.tangent - Vec3::X).length() < 1e-6);
            assert!((v.frame.binormal - Vec3::Y).length() < 1e-6);
            assert!((v.dpdu - Vec3::X).length() < 1e-6);
            assert!((v.dpdv - Vec3::Y).length() < 1e-6);
            // Eq. 3.3 against the geometric normal.
            assert!((v.frame.tangent.cross(v.frame.binormal) - v.normal).length() < 1e-6);
        }
    }
}
