//! Fin edges (thesis 3.1.2.2): the unique edges of a mesh and the silhouette test that picks
//! which of them get a fin. Invariant: the edge list is sorted and has one entry per pair of
//! distinct *positions*, so a UV seam never produces two fins on the same spot.
//!
//! Thesis: "We can understand the silhouettes by having the dot product of the
//! (eyePoint − triangleVertex), verticeNormal. For our system if the angle of these two is
//! between 70° and 110° or 160° and 200° we draw the fin texture."

use std::collections::BTreeMap;

use glam::Vec3;

use super::{Mesh, weld_by_position};

/// An undirected mesh edge with the faces that share it.
#[derive(Clone, Debug, PartialEq)]
pub struct Edge {
    /// The two end vertices, lowest index first. Each is the *lowest* vertex index with that
    /// position (seam duplicates are merged, see [`edges`]).
    pub vertices: [u32; 2],
    /// Indices of the adjacent faces, in face order: 1 on a boundary, 2 on a manifold interior
    /// edge, more on a non-manifold edge.
    pub faces: Vec<u32>,
    /// Unit normals of those faces (zero for a zero-area face), same order as `faces`.
    pub face_normals: Vec<Vec3>,
}

impl Edge {
    /// `true` when exactly one face uses this edge (an open border, e.g. a cylinder rim).
    pub fn is_boundary(&self) -> bool {
        self.faces.len() == 1
    }
}

/// The unique undirected edges of `mesh`, sorted by `vertices`.
///
/// Vertices are merged by bit-identical position first (the lowest index with a position
/// stands for all of them), so the duplicated vertices of a UV seam give one edge with both
/// adjacent faces, not two boundary edges and two fins. Edges whose ends merge into one
/// vertex (repeated indices, collapsed triangles) are dropped. Faces with an out-of-range
/// index are skipped.
pub fn edges(mesh: &Mesh) -> Vec<Edge> {
    let positions: Vec<Vec3> = mesh.vertices.iter().map(|v| v.position).collect();
    let weld = weld_by_position(&positions);
    let mut map: BTreeMap<[u32; 2], Edge> = BTreeMap::new();
    for (f, tri) in mesh.indices.iter().enumerate() {
        let Some(p) = mesh.triangle(f) else { continue };
        let normal = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
        for k in 0..3 {
            let (a, b) = (weld[tri[k] as usize], weld[tri[(k + 1) % 3] as usize]);
            if a == b {
                continue;
            }
            let key = [a.min(b), a.max(b)];
            let edge = map.entry(key).or_insert_with(|| Edge {
                vertices: key,
                faces: Vec::new(),
                face_normals: Vec::new(),
            });
            // A face that touches the edge twice (two merged corners) counts once.
            if edge.faces.last() != Some(&(f as u32)) {
                edge.faces.push(f as u32);
                edge.face_normals.push(normal);
            }
        }
    }
    map.into_values().collect()
}

/// Angle windows, in degrees, in which a fin is drawn.
///
/// The angle between two vectors lies in `[0°, 180°]`; the thesis's window 160°–200° is read
/// as "≥ 160°". In general an angle `a` matches a window `(lo, hi)` when `lo ≤ a ≤ hi` or
/// `lo ≤ 360° − a ≤ hi` (the same pair of directions measured the other way round), so
/// windows past 180° behave as the thesis intends.
#[derive(Clone, Debug, PartialEq)]
pub struct FinWindows {
    /// `(low, high)` bounds in degrees, inclusive.
    pub windows: Vec<(f32, f32)>,
}

impl Default for FinWindows {
    /// The thesis's windows: 70°–110° and 160°–200°.
    fn default() -> Self {
        FinWindows {
            windows: vec![(70.0, 110.0), (160.0, 200.0)],
        }
    }
}

impl FinWindows {
    /// Whether an angle in degrees (expected in `[0, 180]`) falls in a window.
    pub fn contains(&self, angle_degrees: f32) -> bool {
        let other = 360.0 - angle_degrees;
        self.windows
            .iter()
            .any(|&(lo, hi)| (lo..=hi).contains(&angle_degrees) || (lo..=hi).contains(&other))
    }
}

/// Angle in degrees between `a` and `b`, or `None` if either is zero or not finite.
fn angle_degrees(a: Vec3, b: Vec3) -> Option<f32> {
    let (a, b) = (a.try_normalize()?, b.try_normalize()?);
    let c = a.dot(b).clamp(-1.0, 1.0);
    Some(libm::acosf(c).to_degrees())
}

/// Thesis 3.1.2.2: is the angle between `eye − vertex_position` and `vertex_normal` inside one
/// of the `windows`? `false` when the eye sits on the vertex or the normal is zero.
pub fn is_silhouette(
    eye: Vec3,
    vertex_position: Vec3,
    vertex_normal: Vec3,
    windows: &FinWindows,
) -> bool {
    angle_degrees(eye - vertex_position, vertex_normal).is_some_and(|a| windows.contains(a))
}

/// Indices into `edges` (ascending) of the edges that get a fin seen from `eye`: an edge is a
/// fin edge when [`is_silhouette`] holds at its midpoint with the normalised average of its two
/// vertex normals. Edges with an out-of-range vertex are skipped.
pub fn silhouette_edges(
    mesh: &Mesh,
    edges: &[Edge],
    eye: Vec3,
    windows: &FinWindows,
) -> Vec<usize> {
    edges
        .iter()
        .enumerate()
        .filter_map(|(k, e)| {
            let a = mesh.vertices.get(e.vertices[0] as usize)?;
            let b = mesh.vertices.get(e.vertices[1] as usize)?;
            let mid = (a.position + b.position) * 0.5;
            let normal = a.normal + b.normal;
            is_silhouette(eye, mid, normal, windows).then_some(k)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::procedural::{cylinder, sphere, torus};
    use glam::Vec2;

    #[test]
    fn torus_edges_are_closed_manifold() {
        let mesh = torus(1.0, 0.4, 500);
        let e = edges(&mesh);
        // A closed torus of a × b quads: 3ab edges (V − E + F = 0 with V = ab, F = 2ab).
        let (a, b) = crate::mesh::torus_segments(1.0, 0.4, 500);
        assert_eq!(e.len() as u32, 3 * a * b);
        assert!(e.iter().all(|e| e.faces.len() == 2));
        assert!(e.windows(2).all(|w| w[0].vertices < w[1].vertices));
        assert!(e.iter().all(|e| e.vertices[0] < e.vertices[1]));
    }

    #[test]
    fn cylinder_has_boundary_rims_only() {
        let mesh = cylinder(1.0, 1.0, 200);
        let (a, _) = crate::mesh::cylinder_segments(1.0, 1.0, 200);
        let boundary = edges(&mesh).iter().filter(|e| e.is_boundary()).count();
        assert_eq!(boundary as u32, 2 * a);
    }

    #[test]
    fn non_manifold_and_degenerate_do_not_panic() {
        let p = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z, -Vec3::Y];
        let uv = [Vec2::ZERO; 5];
        let idx = vec![[0, 1, 2], [1, 0, 3], [0, 1, 4], [0, 0, 1]];
        let mesh = Mesh::from_parts(&p, &uv, idx).unwrap();
        let e = edges(&mesh);
        let shared = e.iter().find(|e| e.vertices == [0, 1]).unwrap();
        assert_eq!(shared.faces, vec![0, 1, 2, 3]);
        assert_eq!(shared.face_normals[3], Vec3::ZERO);
        let fins = silhouette_edges(&mesh, &e, Vec3::new(3.0, 2.0, 1.0), &FinWindows::default());
        assert!(fins.iter().all(|&k| k < e.len()));
    }

    #[test]
    fn windows() {
        let w = FinWindows::default();
        for (a, inside) in [
            (0.0, false),
            (69.0, false),
            (70.0, true),
            (90.0, true),
            (110.0, true),
            (111.0, false),
            (159.0, false),
            (160.0, true),
            (180.0, true),
        ] {
            assert_eq!(w.contains(a), inside, "{a}");
        }
        let n = Vec3::Z;
        assert!(!is_silhouette(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, n, &w));
        assert!(is_silhouette(Vec3::new(5.0, 0.0, 0.0), Vec3::ZERO, n, &w));
        assert!(is_silhouette(Vec3::new(0.0, 0.0, -5.0), Vec3::ZERO, n, &w));
        assert!(!is_silhouette(Vec3::ZERO, Vec3::ZERO, n, &w));
        assert!(!is_silhouette(Vec3::X, Vec3::ZERO, Vec3::ZERO, &w));
    }

    #[test]
    fn sphere_fins_at_rim_not_centre() {
        let mesh = sphere(1.0, 2000);
        let e = edges(&mesh);
        let eye = Vec3::new(0.0, 0.0, 10.0);
        // Only the 70°–110° window, so back faces do not count.
        let w = FinWindows {
            windows: vec![(70.0, 110.0)],
        };
        let fins = silhouette_edges(&mesh, &e, eye, &w);
        assert!(!fins.is_empty());
        for &k in &fins {
            let [a, b] = e[k].vertices;
            let mid =
                (mesh.vertices[a as usize].position + mesh.vertices[b as usize].position) / 2.0;
            // Near the rim seen from +z: small |z|.
            assert!(mid.z.abs() < 0.45, "{mid}");
        }
        // The edges facing the eye get no fin.
        let front = e.iter().position(|e| {
            let p = mesh.vertices[e.vertices[0] as usize].position;
            p.z > 0.95
        });
        assert!(front.is_some_and(|k| !fins.contains(&k)));
        // The default windows also take the far side (≥ 160°).
        let all = silhouette_edges(&mesh, &e, eye, &FinWindows::default());
        assert!(all.len() > fins.len());
    }

    #[test]
    fn seam_gives_single_edges() {
        let mesh = sphere(1.0, 500);
        let e = edges(&mesh);
        assert!(
            e.iter().all(|e| e.faces.len() == 2),
            "a closed sphere has no border"
        );
    }
}
