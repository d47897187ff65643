//! Fin edges (thesis 3.1.2.2; mesh stage): the unique edges of a mesh, the tests that pick which of
//! them get a fin, and the chains that give neighbouring fins one continuous texture coordinate.
//! Invariant: the edge list is sorted and has one entry per pair of distinct *positions*, so a UV
//! seam never produces two fins on the same spot; every output is in edge order, never in the order
//! of a hash map.
//!
//! Two selections:
//! - **outline** (the default): an edge whose two faces disagree on facing the eye (one front,
//!   one back), or a border edge: exactly the mesh's silhouette, a connected chain of edges with
//!   no gaps and nothing elsewhere ([`outline_edges`]);
//! - **angle windows** (the thesis): "We can understand the silhouettes by having the dot product
//!   of the (eyePoint − triangleVertex), verticeNormal. For our system if the angle of these two
//!   is between 70° and 110° or 160° and 200° we draw the fin texture" ([`silhouette_edges`]).
//!   Measured on a 500-triangle torus, this picks a band of edges several faces wide, so fins
//!   stand across the visible fur and read as light panels.

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

/// Thesis-free outline test: the indices into `edges` (ascending) of the edges on the mesh's
/// silhouette seen from `eye`: a border edge (one face), or an edge two of whose faces lie on
/// opposite sides of facing the eye (`(eye − m)·n_f` of opposite signs, `m` the edge's midpoint,
/// which lies in the plane of both faces). Zero-area faces (zero normal) take no part. Edges with
/// an out-of-range vertex are skipped.
pub fn outline_edges(mesh: &Mesh, edges: &[Edge], eye: Vec3) -> Vec<usize> {
    edges
        .iter()
        .enumerate()
        .filter_map(|(k, e)| {
            let a = mesh.vertices.get(e.vertices[0] as usize)?;
            let b = mesh.vertices.get(e.vertices[1] as usize)?;
            if e.is_boundary() {
                return Some(k);
            }
            let to_eye = eye - (a.position + b.position) * 0.5;
            let mut front = false;
            let mut back = false;
            for n in e.face_normals.iter().filter(|n| **n != Vec3::ZERO) {
                let facing = to_eye.dot(*n);
                front |= facing > 0.0;
                back |= facing <= 0.0;
            }
            (front && back).then_some(k)
        })
        .collect()
}

/// One fin of a [`FinChain`]: an edge walked from `from` to `to` (mesh vertex indices).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ChainLink {
    /// Index into the edge list.
    pub edge: usize,
    /// The vertex the walk enters the edge at.
    pub from: u32,
    /// The vertex it leaves by.
    pub to: u32,
}

/// Selected edges joined end to end, so that the fin texture's `u` can run on along them.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FinChain {
    /// The edges in walking order; each link's `to` is the next one's `from`.
    pub links: Vec<ChainLink>,
    /// Whether the last link ends where the first begins (a loop round the outline).
    pub closed: bool,
}

/// Joins the `selected` edges (indices into `edges`) into chains: a chain runs through vertices
/// shared by exactly two selected edges and stops at a vertex shared by one or by three or more.
/// Deterministic: open chains start at their end vertex of lowest index, scanned in edge order;
/// loops start at their edge of lowest index, walked towards that edge's higher vertex first.
/// Every selected edge is in exactly one chain.
pub fn fin_chains(edges: &[Edge], selected: &[usize]) -> Vec<FinChain> {
    let mut selected: Vec<usize> = selected
        .iter()
        .copied()
        .filter(|&k| k < edges.len())
        .collect();
    selected.sort_unstable();
    selected.dedup();
    // Vertex → selected edges touching it, in edge order.
    let mut incident: BTreeMap<u32, Vec<usize>> = BTreeMap::new();
    for &k in &selected {
        for v in edges[k].vertices {
            incident.entry(v).or_default().push(k);
        }
    }
    let degree = |v: u32| incident.get(&v).map_or(0, Vec::len);
    let mut used: BTreeMap<usize, bool> = selected.iter().map(|&k| (k, false)).collect();
    let mut chains = Vec::new();
    let walk = |start_edge: usize, start_vertex: u32, used: &mut BTreeMap<usize, bool>| {
        let mut links = Vec::new();
        let (mut edge, mut from) = (start_edge, start_vertex);
        loop {
            used.insert(edge, true);
            let [a, b] = edges[edge].vertices;
            let to = if from == a { b } else { a };
            links.push(ChainLink { edge, from, to });
            if degree(to) != 2 {
                break;
            }
            let next = incident
                .get(&to)
                .and_then(|list| list.iter().copied().find(|&e| used.get(&e) == Some(&false)));
            match next {
                Some(e) => (edge, from) = (e, to),
                None => break,
            }
        }
        let closed = links.len() > 1 && links.last().map(|l| l.to) == Some(start_vertex);
        FinChain { links, closed }
    };
    // Open chains first, from each end vertex (degree 1, or a branch point).
    for &k in &selected {
        for v in edges[k].vertices {
            if used.get(&k) == Some(&false) && degree(v) != 2 {
                chains.push(walk(k, v, &mut used));
            }
        }
    }
    // What is left are loops through vertices of degree 2.
    for &k in &selected {
        if used.get(&k) == Some(&false) {
            chains.push(walk(k, edges[k].vertices[0], &mut used));
        }
    }
    chains
}

/// How squarely a fin faces the eye, the opacity of fins chosen by [`outline_edges`] (as Lengyel
/// et al. fade fins by the angle between the fin plane and the view): `|m̂·ê|` with `m̂` the fin
/// plane's normal `along × up` and `ê` the direction to the eye. A fin seen face-on (its edge
/// across the line of sight) is opaque; one seen edge-on, whose texture would be squeezed into a
/// streak, vanishes. Zero for a degenerate fin or eye.
pub fn fin_facing(along: Vec3, up: Vec3, to_eye: Vec3) -> f32 {
    let m = along.cross(up).normalize_or_zero();
    let e = to_eye.normalize_or_zero();
    m.dot(e).abs().min(1.0)
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

    #[test]
    fn outline_of_a_sphere_is_one_closed_loop_at_the_rim() {
        let mesh = sphere(1.0, 2000);
        let e = edges(&mesh);
        let eye = Vec3::new(0.3, 0.2, 10.0);
        let outline = outline_edges(&mesh, &e, eye);
        assert!(!outline.is_empty());
        for &k in &outline {
            let [a, b] = e[k].vertices;
            let mid =
                (mesh.vertices[a as usize].position + mesh.vertices[b as usize].position) / 2.0;
            // Only the rim: the view direction nearly in the tangent plane.
            let n = mid.normalize();
            let to_eye = (eye - mid).normalize();
            assert!(n.dot(to_eye).abs() < 0.2, "{mid}");
        }
        // Far fewer edges than the thesis's 70°–110° window picks.
        let window = FinWindows {
            windows: vec![(70.0, 110.0)],
        };
        assert!(outline.len() * 3 < silhouette_edges(&mesh, &e, eye, &window).len());
        let chains = fin_chains(&e, &outline);
        assert_eq!(chains.len(), 1, "one loop round a convex object");
        let chain = &chains[0];
        assert!(chain.closed);
        assert_eq!(chain.links.len(), outline.len());
        assert!(chain.links.windows(2).all(|w| w[0].to == w[1].from));
    }

    #[test]
    fn chains_stop_at_ends_and_branches_and_cover_every_edge() {
        // A path 0-1-2-3 and a branch 1-4: three open chains meeting at vertex 1.
        let mk = |a: u32, b: u32| Edge {
            vertices: [a, b],
            faces: vec![0],
            face_normals: vec![Vec3::Z],
        };
        let e = vec![mk(0, 1), mk(1, 2), mk(1, 4), mk(2, 3)];
        let chains = fin_chains(&e, &[3, 2, 1, 0, 0]);
        let mut seen: Vec<usize> = chains
            .iter()
            .flat_map(|c| c.links.iter().map(|l| l.edge))
            .collect();
        seen.sort_unstable();
        assert_eq!(seen, vec![0, 1, 2, 3]);
        assert!(chains.iter().all(|c| !c.closed));
        let long = chains
            .iter()
            .find(|c| c.links.len() == 2)
            .expect("1-2-3 runs on");
        assert_eq!(long.links[0].from, 1);
        assert_eq!(long.links[1].to, 3);
        // The same input in another order gives the same chains.
        assert_eq!(chains, fin_chains(&e, &[0, 1, 2, 3]));
    }

    #[test]
    fn facing_is_one_face_on_and_zero_edge_on() {
        let along = Vec3::X;
        let up = Vec3::Y;
        assert!((fin_facing(along, up, Vec3::Z * 5.0) - 1.0).abs() < 1e-6);
        assert!(fin_facing(along, up, Vec3::X * 5.0).abs() < 1e-6);
        let diagonal = fin_facing(along, up, Vec3::new(1.0, 0.0, 1.0));
        assert!((f64::from(diagonal) - 0.5f64.sqrt()).abs() < 1e-6);
        assert_eq!(fin_facing(Vec3::ZERO, up, Vec3::Z), 0.0);
    }
}
