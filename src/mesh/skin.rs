//! Skinning (mesh stage): node transforms composed into a joint palette, and the rest mesh
//! posed by linear blend skinning, so shells and fins grow on the posed body.
//!
//! Every operation is written out in f32 in a stated order, with no fused multiply-add, so the
//! posed vertices are the same bits on every machine and every SIMD level (numeric conventions,
//! "Skinning"):
//! - **Affine transforms** are 3×4 matrices ([`Affine`]), rows of `[m0 m1 m2 | t]`. A product
//!   `a·b` computes each entry as `((a[r][0]·b[0][c] + a[r][1]·b[1][c]) + a[r][2]·b[2][c])`,
//!   plus `a[r][3]` for the translation column.
//! - **A node's local transform** is `T·R·S` (glTF 2.0 §3.5.3): the rotation matrix of the unit
//!   quaternion (normalised first, `q / sqrt(((x² + y²) + z²) + w²)`), its columns multiplied
//!   by the scale, the translation as the last column; a node given as a `matrix` uses its
//!   affine part.
//! - **Global transforms** are composed parents first, `global(child) = global(parent)·local`,
//!   in the order [`Skeleton::order`] fixes once at load (depth-first from the scene's roots, in
//!   the order the file lists them).
//! - **A palette entry** is `scale ⊙ (global(joint)·inverse_bind)` for a joint of a skin, or
//!   `scale ⊙ global(node)` for a rigid (unskinned) mesh node, every entry multiplied by the
//!   scene's `mesh.scale`.
//! - **A vertex's matrix** is `((w0·P[j0] + w1·P[j1]) + w2·P[j2]) + w3·P[j3]`, entry by entry,
//!   all four influences always (a weight of zero adds zero). Weights are normalised at load
//!   (glTF 2.0 §3.7.3.3): `w_k / (((w0 + w1) + w2) + w3)`.
//! - **Positions** are `M·p`, the derivatives `dpdu`, `dpdv` (eq. 3.1–3.2) `M₃·d` (they are
//!   tangent vectors of the posed surface), and the **normal** the cofactor matrix of `M₃`
//!   times `n`, its sign flipped where `det M₃ < 0`, normalised: the inverse transpose up to a
//!   positive factor, right under non-uniform scale. The frame is then rebuilt from the posed
//!   normal and derivatives ([`TangentFrame::from_derivatives`]), as at rest.

use glam::{Quat, Vec3, Vec4};

use super::{Mesh, TangentFrame, Vertex};

/// An affine transform: three rows `[m0, m1, m2, t]` (the last row of the 4×4 is `0 0 0 1`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Affine {
    /// Rows of the 3×4 matrix.
    pub rows: [[f32; 4]; 3],
}

impl Affine {
    /// The identity.
    pub const IDENTITY: Affine = Affine {
        rows: [
            [1.0, 0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
        ],
    };

    /// All zeros (the start of a blend).
    pub const ZERO: Affine = Affine {
        rows: [[0.0; 4]; 3],
    };

    /// `T·R·S` of a translation, a rotation (normalised here) and a scale (module docs).
    pub fn from_trs(translation: Vec3, rotation: Quat, scale: Vec3) -> Affine {
        let [x, y, z, w] = normalised_quat(rotation.to_array());
        let (xx, yy, zz) = (x * x, y * y, z * z);
        let (xy, xz, yz) = (x * y, x * z, y * z);
        let (wx, wy, wz) = (w * x, w * y, w * z);
        let r = [
            [1.0 - 2.0 * (yy + zz), 2.0 * (xy - wz), 2.0 * (xz + wy)],
            [2.0 * (xy + wz), 1.0 - 2.0 * (xx + zz), 2.0 * (yz - wx)],
            [2.0 * (xz - wy), 2.0 * (yz + wx), 1.0 - 2.0 * (xx + yy)],
        ];
        let s = scale.to_array();
        let t = translation.to_array();
        let mut rows = [[0.0; 4]; 3];
        for (row, (rr, tr)) in rows.iter_mut().zip(r.iter().zip(t)) {
            *row = [rr[0] * s[0], rr[1] * s[1], rr[2] * s[2], tr];
        }
        Affine { rows }
    }

    /// The affine part of a column-major 4×4 matrix (glTF's `matrix`, `inverseBindMatrices`);
    /// `None` when its last row is not `0 0 0 1` or an entry is not finite.
    pub fn from_cols_4x4(m: &[f32; 16]) -> Option<Affine> {
        if m.iter().any(|v| !v.is_finite()) || [m[3], m[7], m[11], m[15]] != [0.0, 0.0, 0.0, 1.0] {
            return None;
        }
        let mut rows = [[0.0; 4]; 3];
        for (r, row) in rows.iter_mut().enumerate() {
            *row = [m[r], m[4 + r], m[8 + r], m[12 + r]];
        }
        Some(Affine { rows })
    }

    /// The column-major 4×4 matrix (for the GPU's joint buffer and export).
    pub fn to_cols_4x4(&self) -> [f32; 16] {
        let r = &self.rows;
        [
            r[0][0], r[1][0], r[2][0], 0.0, r[0][1], r[1][1], r[2][1], 0.0, r[0][2], r[1][2],
            r[2][2], 0.0, r[0][3], r[1][3], r[2][3], 1.0,
        ]
    }

    /// `self·other` in the order of the module docs.
    pub fn mul(&self, other: &Affine) -> Affine {
        let (a, b) = (&self.rows, &other.rows);
        let mut rows = [[0.0; 4]; 3];
        for (r, row) in rows.iter_mut().enumerate() {
            for (c, entry) in row.iter_mut().enumerate() {
                let sum = (a[r][0] * b[0][c] + a[r][1] * b[1][c]) + a[r][2] * b[2][c];
                *entry = if c == 3 { sum + a[r][3] } else { sum };
            }
        }
        Affine { rows }
    }

    /// Every entry multiplied by `s`.
    pub fn scaled(&self, s: f32) -> Affine {
        Affine {
            rows: self.rows.map(|row| row.map(|v| v * s)),
        }
    }

    /// `self + other·w`, entry by entry (one step of a vertex's blend).
    pub fn add_weighted(&self, other: &Affine, w: f32) -> Affine {
        let mut rows = self.rows;
        for (row, o) in rows.iter_mut().zip(&other.rows) {
            for (v, o) in row.iter_mut().zip(o) {
                *v += w * o;
            }
        }
        Affine { rows }
    }

    /// `M·p`: `((m0·x + m1·y) + m2·z) + t` per row.
    pub fn transform_point(&self, p: Vec3) -> Vec3 {
        let r = &self.rows;
        let row = |k: usize| ((r[k][0] * p.x + r[k][1] * p.y) + r[k][2] * p.z) + r[k][3];
        Vec3::new(row(0), row(1), row(2))
    }

    /// `M₃·v`: `(m0·x + m1·y) + m2·z` per row.
    pub fn transform_vector(&self, v: Vec3) -> Vec3 {
        let r = &self.rows;
        let row = |k: usize| (r[k][0] * v.x + r[k][1] * v.y) + r[k][2] * v.z;
        Vec3::new(row(0), row(1), row(2))
    }

    /// The normal transformed by the cofactor matrix of `M₃` (rows `a1×a2`, `a2×a0`, `a0×a1`
    /// of the rows `a_k`), negated where the determinant `a0·(a1×a2)` is negative; not
    /// normalised.
    pub fn transform_normal(&self, n: Vec3) -> Vec3 {
        let r = &self.rows;
        let a = [0, 1, 2].map(|k| Vec3::new(r[k][0], r[k][1], r[k][2]));
        let cross = |u: Vec3, v: Vec3| {
            Vec3::new(
                u.y * v.z - u.z * v.y,
                u.z * v.x - u.x * v.z,
                u.x * v.y - u.y * v.x,
            )
        };
        let dot = |u: Vec3, v: Vec3| (u.x * v.x + u.y * v.y) + u.z * v.z;
        let c = [cross(a[1], a[2]), cross(a[2], a[0]), cross(a[0], a[1])];
        let det = dot(a[0], c[0]);
        let m = Vec3::new(dot(c[0], n), dot(c[1], n), dot(c[2], n));
        if det < 0.0 { -m } else { m }
    }
}

/// `q / sqrt(((x² + y²) + z²) + w²)`; the identity when `q` is zero or not finite.
pub fn normalised_quat(q: [f32; 4]) -> [f32; 4] {
    let [x, y, z, w] = q;
    let len = (((x * x + y * y) + z * z) + w * w).sqrt();
    if !(len.is_finite() && len > 0.0) {
        return [0.0, 0.0, 0.0, 1.0];
    }
    [x / len, y / len, z / len, w / len]
}

/// A node's local transform: translation, rotation, scale (what an animation channel replaces),
/// or a fixed matrix (never animated, glTF 2.0 §3.5.3).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LocalTransform {
    /// Translation, rotation (x, y, z, w), scale.
    Trs {
        /// Translation.
        translation: Vec3,
        /// Rotation quaternion.
        rotation: Quat,
        /// Scale.
        scale: Vec3,
    },
    /// A fixed affine matrix.
    Matrix(Affine),
}

impl LocalTransform {
    /// The transform as a matrix.
    pub fn to_affine(&self) -> Affine {
        match *self {
            LocalTransform::Trs {
                translation,
                rotation,
                scale,
            } => Affine::from_trs(translation, rotation, scale),
            LocalTransform::Matrix(m) => m,
        }
    }
}

/// The node hierarchy of a model.
#[derive(Clone, Debug, PartialEq)]
pub struct Skeleton {
    /// Each node's parent (`None` for a root).
    pub parents: Vec<Option<usize>>,
    /// Each node's rest transform (the file's own).
    pub rest: Vec<LocalTransform>,
    /// Each node's name (empty when the file gives none).
    pub names: Vec<String>,
    /// The nodes in the order their global transforms are composed: every parent before its
    /// children (depth-first from the scene's roots, in the file's order). Nodes outside the
    /// scene are not listed and stay at the identity.
    pub order: Vec<usize>,
}

impl Skeleton {
    /// Global transforms of every node for these local transforms (`locals[i]` for node `i`).
    pub fn globals(&self, locals: &[LocalTransform]) -> Vec<Affine> {
        let mut global = vec![Affine::IDENTITY; self.parents.len()];
        for &node in &self.order {
            let local = locals.get(node).map_or(Affine::IDENTITY, |l| l.to_affine());
            global[node] = match self.parents[node] {
                Some(parent) => global[parent].mul(&local),
                None => local,
            };
        }
        global
    }
}

/// What one palette entry follows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PaletteEntry {
    /// A joint of a skin: `global(node)·inverse_bind`.
    Joint {
        /// The joint's node.
        node: usize,
        /// Its inverse bind matrix.
        inverse_bind: Affine,
    },
    /// A rigid mesh node: `global(node)`.
    Node {
        /// The node.
        node: usize,
    },
}

/// Up to four palette influences of one vertex, weights normalised (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Influences {
    /// Palette indices.
    pub joints: [u32; 4],
    /// Normalised weights, summing to 1 within rounding.
    pub weights: [f32; 4],
}

impl Influences {
    /// A vertex that follows palette entry `entry` alone.
    pub fn rigid(entry: u32) -> Influences {
        Influences {
            joints: [entry, entry, entry, entry],
            weights: [1.0, 0.0, 0.0, 0.0],
        }
    }

    /// Weights as the file gives them, normalised: `w_k / (((w0 + w1) + w2) + w3)`; `None`
    /// when one is negative or not finite, or they sum to zero.
    pub fn normalised(joints: [u32; 4], weights: [f32; 4]) -> Option<Influences> {
        if weights.iter().any(|w| !(w.is_finite() && *w >= 0.0)) {
            return None;
        }
        let sum = ((weights[0] + weights[1]) + weights[2]) + weights[3];
        if !(sum > 0.0 && sum.is_finite()) {
            return None;
        }
        Some(Influences {
            joints,
            weights: weights.map(|w| w / sum),
        })
    }

    /// `((w0·P[j0] + w1·P[j1]) + w2·P[j2]) + w3·P[j3]`. Indices are checked at load; one past
    /// the palette counts as the identity.
    pub fn blend(&self, palette: &[Affine]) -> Affine {
        let mut m = Affine::ZERO;
        for (j, w) in self.joints.iter().zip(self.weights) {
            let p = palette.get(*j as usize).unwrap_or(&Affine::IDENTITY);
            m = m.add_weighted(p, w);
        }
        m
    }
}

/// A skinned model: its rest mesh, the palette its vertices follow and the node hierarchy.
#[derive(Clone, Debug, PartialEq)]
pub struct Rig {
    /// The node hierarchy.
    pub skeleton: Skeleton,
    /// What each palette entry follows.
    pub palette: Vec<PaletteEntry>,
    /// Per vertex of the rest mesh, its influences.
    pub influences: Vec<Influences>,
    /// `mesh.scale`, applied to every palette entry.
    pub scale: f32,
}

impl Rig {
    /// The palette for these node transforms (module docs).
    pub fn palette(&self, locals: &[LocalTransform]) -> Vec<Affine> {
        let globals = self.skeleton.globals(locals);
        self.palette
            .iter()
            .map(|entry| {
                let m = match *entry {
                    PaletteEntry::Joint { node, inverse_bind } => globals[node].mul(&inverse_bind),
                    PaletteEntry::Node { node } => globals[node],
                };
                m.scaled(self.scale)
            })
            .collect()
    }

    /// The palette of the rest pose (every node at the file's own transform).
    pub fn rest_palette(&self) -> Vec<Affine> {
        self.palette(&self.skeleton.rest)
    }
}

/// `rest` posed by `palette`: each vertex through its blended matrix (module docs). The
/// vertices keep their uvs; the triangles are shared.
///
/// Vertices are posed in parallel: each is its own computation, so the result does not depend
/// on the thread count.
pub fn pose(rest: &Mesh, influences: &[Influences], palette: &[Affine]) -> Mesh {
    use rayon::prelude::*;
    let vertices = rest
        .vertices
        .par_iter()
        .zip(influences)
        .map(|(v, influence)| pose_vertex(v, &influence.blend(palette)))
        .collect();
    Mesh {
        vertices,
        indices: rest.indices.clone(),
    }
}

/// One vertex through `m`.
pub fn pose_vertex(v: &Vertex, m: &Affine) -> Vertex {
    let normal = m
        .transform_normal(v.normal)
        .try_normalize()
        .unwrap_or(v.normal);
    let dpdu = m.transform_vector(v.dpdu);
    let dpdv = m.transform_vector(v.dpdv);
    Vertex {
        position: m.transform_point(v.position),
        normal,
        uv: v.uv,
        frame: TangentFrame::from_derivatives(normal, dpdu, dpdv),
        dpdu,
        dpdv,
        rest_position: v.rest_position,
        rest_normal: v.rest_normal,
        lag: v.lag,
    }
}

/// A quaternion from glTF's `[x, y, z, w]`.
pub fn quat(v: Vec4) -> Quat {
    Quat::from_xyzw(v.x, v.y, v.z, v.w)
}

// Matrix entries are indexed as the formulas write them.
#[cfg(test)]
#[allow(clippy::needless_range_loop)]
mod tests {
    use super::*;

    type M64 = [[f64; 4]; 4];

    fn to64(a: &Affine) -> M64 {
        let mut m = [[0.0; 4]; 4];
        for r in 0..3 {
            for c in 0..4 {
                m[r][c] = f64::from(a.rows[r][c]);
            }
        }
        m[3][3] = 1.0;
        m
    }

    fn mul64(a: &M64, b: &M64) -> M64 {
        let mut m = [[0.0; 4]; 4];
        for r in 0..4 {
            for c in 0..4 {
                m[r][c] = (0..4).map(|k| a[r][k] * b[k][c]).sum();
            }
        }
        m
    }

    fn trs64(t: [f64; 3], q: [f64; 4], s: [f64; 3]) -> M64 {
        let len = q.iter().map(|v| v * v).sum::<f64>().sqrt();
        let [x, y, z, w] = q.map(|v| v / len);
        let r = [
            [
                1.0 - 2.0 * (y * y + z * z),
                2.0 * (x * y - w * z),
                2.0 * (x * z + w * y),
            ],
            [
                2.0 * (x * y + w * z),
                1.0 - 2.0 * (x * x + z * z),
                2.0 * (y * z - w * x),
            ],
            [
                2.0 * (x * z - w * y),
                2.0 * (y * z + w * x),
                1.0 - 2.0 * (x * x + y * y),
            ],
        ];
        let mut m = [[0.0; 4]; 4];
        for i in 0..3 {
            for j in 0..3 {
                m[i][j] = r[i][j] * s[j];
            }
            m[i][3] = t[i];
        }
        m[3][3] = 1.0;
        m
    }

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol * (1.0 + b.abs())
    }

    /// A chain of three joints bending a tail, with non-uniform scale on the middle one.
    fn chain() -> (Rig, Vec<LocalTransform>) {
        let rest = vec![
            LocalTransform::Trs {
                translation: Vec3::new(0.0, 0.0, 0.0),
                rotation: Quat::IDENTITY,
                scale: Vec3::ONE,
            },
            LocalTransform::Trs {
                translation: Vec3::new(0.0, 1.0, 0.0),
                rotation: Quat::IDENTITY,
                scale: Vec3::ONE,
            },
            LocalTransform::Trs {
                translation: Vec3::new(0.0, 1.0, 0.0),
                rotation: Quat::IDENTITY,
                scale: Vec3::ONE,
            },
        ];
        let skeleton = Skeleton {
            parents: vec![None, Some(0), Some(1)],
            rest: rest.clone(),
            names: vec!["a".into(), "b".into(), "c".into()],
            order: vec![0, 1, 2],
        };
        let globals = skeleton.globals(&rest);
        let palette = (0..3)
            .map(|k| PaletteEntry::Joint {
                node: k,
                inverse_bind: Affine::from_trs(
                    Vec3::new(0.0, -(k as f32), 0.0),
                    Quat::IDENTITY,
                    Vec3::ONE,
                ),
            })
            .collect();
        assert_eq!(
            globals[2].transform_point(Vec3::ZERO),
            Vec3::new(0.0, 2.0, 0.0)
        );
        let posed = vec![
            LocalTransform::Trs {
                translation: Vec3::new(0.1, 0.0, -0.2),
                rotation: Quat::from_rotation_z(0.3),
                scale: Vec3::ONE,
            },
            LocalTransform::Trs {
                translation: Vec3::new(0.0, 1.0, 0.0),
                rotation: Quat::from_xyzw(0.1, 0.2, 0.3, 0.9),
                scale: Vec3::new(1.5, 0.7, 1.1),
            },
            LocalTransform::Trs {
                translation: Vec3::new(0.0, 1.0, 0.0),
                rotation: Quat::from_rotation_x(-0.7),
                scale: Vec3::splat(0.9),
            },
        ];
        (
            Rig {
                skeleton,
                palette,
                influences: Vec::new(),
                scale: 0.5,
            },
            posed,
        )
    }

    fn local64(l: &LocalTransform) -> M64 {
        match *l {
            LocalTransform::Trs {
                translation: t,
                rotation: q,
                scale: s,
            } => trs64(
                t.to_array().map(f64::from),
                q.to_array().map(f64::from),
                s.to_array().map(f64::from),
            ),
            LocalTransform::Matrix(m) => to64(&m),
        }
    }

    #[test]
    fn palette_matches_a_double_precision_composition() {
        let (rig, posed) = chain();
        let palette = rig.palette(&posed);
        let mut global: Vec<M64> = Vec::new();
        for (k, l) in posed.iter().enumerate() {
            let m = local64(l);
            global.push(if k == 0 { m } else { mul64(&global[k - 1], &m) });
        }
        for (k, entry) in rig.palette.iter().enumerate() {
            let PaletteEntry::Joint { inverse_bind, .. } = entry else {
                unreachable!()
            };
            let expected = mul64(&global[k], &to64(inverse_bind));
            for r in 0..3 {
                for c in 0..4 {
                    let want = expected[r][c] * 0.5;
                    let got = f64::from(palette[k].rows[r][c]);
                    assert!(
                        close(got, want, 2e-6),
                        "joint {k} [{r}][{c}]: {got} vs {want}"
                    );
                }
            }
        }
    }

    #[test]
    fn blended_vertices_match_double_precision_skinning() {
        let (rig, posed) = chain();
        let palette = rig.palette(&posed);
        let influences = Influences::normalised([0, 1, 2, 1], [0.2, 0.5, 0.25, 0.1]).unwrap();
        let sum: f32 = influences.weights.iter().sum();
        assert!((sum - 1.0).abs() < 1e-6);
        let m = influences.blend(&palette);
        // The same blend in f64.
        let mut m64 = [[0.0f64; 4]; 3];
        let w64 = [0.2, 0.5, 0.25, 0.1].map(|w: f64| w / 1.05);
        for (j, w) in influences.joints.iter().zip(w64) {
            for r in 0..3 {
                for c in 0..4 {
                    m64[r][c] += w * f64::from(palette[*j as usize].rows[r][c]);
                }
            }
        }
        let p = Vec3::new(0.3, 1.4, -0.2);
        let got = m.transform_point(p);
        for r in 0..3 {
            let want = m64[r][0] * 0.3 + m64[r][1] * 1.4 + m64[r][2] * -0.2 + m64[r][3];
            let want = want as f32 as f64;
            assert!(
                close(f64::from(got[r]), want, 2e-6),
                "row {r}: {} vs {want}",
                got[r]
            );
        }
        // The normal: the inverse transpose of M₃ in f64, normalised.
        let a = [0, 1, 2].map(|r| [m64[r][0], m64[r][1], m64[r][2]]);
        let det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1])
            - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
            + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
        let inv_t = |r: usize, c: usize| {
            // cofactor(r, c) / det
            let (r1, r2) = ((r + 1) % 3, (r + 2) % 3);
            let (c1, c2) = ((c + 1) % 3, (c + 2) % 3);
            (a[r1][c1] * a[r2][c2] - a[r1][c2] * a[r2][c1]) / det
        };
        let n = [0.2f64, 0.9, -0.3];
        let mut want = [0.0; 3];
        for (r, w) in want.iter_mut().enumerate() {
            *w = (0..3).map(|c| inv_t(r, c) * n[c]).sum();
        }
        let len = want.iter().map(|v| v * v).sum::<f64>().sqrt();
        let got = m.transform_normal(Vec3::new(0.2, 0.9, -0.3)).normalize();
        for r in 0..3 {
            assert!(
                (f64::from(got[r]) - want[r] / len).abs() < 2e-6,
                "normal {r}: {} vs {}",
                got[r],
                want[r] / len
            );
        }
    }

    #[test]
    fn normals_follow_a_mirroring_transform() {
        let mirror = Affine::from_trs(Vec3::ZERO, Quat::IDENTITY, Vec3::new(-1.0, 2.0, 1.0));
        // A surface with normal +x; mirrored in x its outward normal is −x.
        assert_eq!(mirror.transform_normal(Vec3::X).normalize(), -Vec3::X);
        assert_eq!(mirror.transform_normal(Vec3::Y).normalize(), Vec3::Y);
    }

    #[test]
    fn weights_are_refused_when_they_cannot_be_normalised() {
        assert!(Influences::normalised([0; 4], [0.0; 4]).is_none());
        assert!(Influences::normalised([0; 4], [f32::NAN, 1.0, 0.0, 0.0]).is_none());
        assert!(Influences::normalised([0; 4], [-0.5, 1.0, 0.0, 0.0]).is_none());
        let one = Influences::normalised([3, 0, 0, 0], [2.0, 0.0, 0.0, 0.0]).unwrap();
        assert_eq!(one.weights, [1.0, 0.0, 0.0, 0.0]);
    }

    #[test]
    fn rigid_vertices_take_their_entry_exactly() {
        let m = Affine::from_trs(
            Vec3::new(1.0, 2.0, 3.0),
            Quat::from_rotation_y(0.4),
            Vec3::splat(2.0),
        );
        let blended = Influences::rigid(0).blend(&[m]);
        assert_eq!(blended, m);
    }

    #[test]
    fn matrices_round_trip_through_column_major() {
        let m = Affine::from_trs(
            Vec3::new(1.0, 2.0, 3.0),
            Quat::from_rotation_y(0.4),
            Vec3::splat(2.0),
        );
        assert_eq!(Affine::from_cols_4x4(&m.to_cols_4x4()), Some(m));
        let mut projective = m.to_cols_4x4();
        projective[3] = 0.5;
        assert_eq!(Affine::from_cols_4x4(&projective), None);
    }
}
