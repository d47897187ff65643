//! Meshes (mesh stage): procedural torus, sphere, cylinder and leg, OBJ and glTF loading, skinning
//! and animation clips, tangent frames (thesis eq. 3.1–3.3), shell extrusion (thesis 3.1.4) and fin
//! edges (thesis 3.1.2.2).
//!
//! Conventions shared by every mesh built here:
//! - front faces are counter-clockwise seen from outside: `(p1 − p0) × (p2 − p0)` points out;
//! - `uv` lies in `[0, 1]²` over the whole surface (a seamless tiling fur texture is repeated by
//!   the renderer, which multiplies `uv` by a repeat count); seams are duplicated vertices with
//!   bit-identical positions;
//! - vertex normals are computed from the faces (never read from a file) and are *welded by
//!   position*: every vertex with the same position gets the same normal, so shells extruded
//!   along the normals never crack open at UV seams (see [`frame`]).

pub mod animation;
pub mod fins;
pub mod frame;
pub mod gltf;
pub mod obj;
pub mod procedural;
pub mod rig;
pub mod shells;
pub mod skin;

use std::path::PathBuf;

use glam::{Vec2, Vec3};

pub use fins::{
    ChainLink, Edge, FinChain, FinWindows, edges, fin_chains, fin_facing, is_silhouette,
    outline_edges, silhouette_edges,
};
pub use frame::{TangentFrame, face_tangents};
pub use obj::{LoadedMesh, ObjSummary, load_obj, load_obj_bytes, scan_obj};
pub use procedural::{
    cylinder, cylinder_segments, leg, leg_segments, sphere, sphere_segments, torus, torus_segments,
};
pub use shells::{ShellSpacing, extrude, shell_offset};

/// One vertex of a [`Mesh`], with everything the shell and fin passes need.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vertex {
    /// Object-space position.
    pub position: Vec3,
    /// Unit outward vertex normal (normalised sum of angle-weighted face normals, welded by
    /// position). Equal to `frame.normal`.
    pub normal: Vec3,
    /// Texture coordinate, `[0, 1]²` over the surface.
    pub uv: Vec2,
    /// Orthonormal tangent frame (T along +u, B along +v, N outward).
    pub frame: TangentFrame,
    /// ∂p/∂u: the *unnormalised* tangent T of eq. 3.1, world length per unit of u, averaged
    /// (area-weighted) over the adjacent faces. Zero where no adjacent face has usable UVs.
    pub dpdu: Vec3,
    /// ∂p/∂v: the *unnormalised* binormal B of eq. 3.2, world length per unit of v, averaged
    /// like [`Vertex::dpdu`].
    pub dpdv: Vec3,
    /// The vertex in the object's own frame: equal to `position` for a mesh that is not posed;
    /// for a posed glTF character, its position in the rest pose. What is fixed to the object
    /// (spots, stripes, the matches of thesis 3.4) is evaluated here, so it stays on the body
    /// as the body moves.
    pub rest_position: Vec3,
    /// The normal in the object's own frame, as [`Vertex::rest_position`].
    pub rest_normal: Vec3,
    /// How far the fur tips lag behind this vertex's own motion, world units, before the
    /// scene's `motion.response` scales it: zero but for a posed character with `[motion]`
    /// ([`crate::shading::spring_lag`] over the vertex's posed trajectory).
    pub lag: Vec3,
}

impl Vertex {
    /// Makes the rest fields the current position and normal (a mesh that is not posed).
    pub fn at_rest(mut self) -> Vertex {
        self.rest_position = self.position;
        self.rest_normal = self.normal;
        self.lag = Vec3::ZERO;
        self
    }
}

/// An indexed triangle mesh with per-vertex frames.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// The vertices.
    pub vertices: Vec<Vertex>,
    /// Triangles as vertex indices, counter-clockwise seen from outside.
    pub indices: Vec<[u32; 3]>,
}

/// Errors from building or loading a mesh. Each names the file (when there is one) and the
/// line, vertex or face at fault.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// The OBJ file could not be opened or read.
    #[error("cannot read OBJ file {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying I/O error.
        source: std::io::Error,
    },
    /// tobj rejected the file (tobj reports no line numbers).
    #[error("cannot parse OBJ file {path}: {source}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// tobj's error.
        source: tobj::LoadError,
    },
    /// The file holds no triangles.
    #[error("OBJ file {path} has no faces")]
    NoFaces {
        /// The file.
        path: PathBuf,
    },
    /// A vertex position is NaN or infinite.
    #[error("{}: vertex {vertex} has a non-finite coordinate {value:?}", location(path, *line))]
    NonFinite {
        /// The file (empty for meshes not read from a file).
        path: PathBuf,
        /// Line of the offending `v` statement (1-based) when it could be found.
        line: Option<usize>,
        /// Vertex index: 1-based OBJ numbering when `line` is known, else the 0-based index in
        /// the loaded mesh.
        vertex: usize,
        /// The offending position.
        value: [f32; 3],
    },
    /// A face refers to a vertex that does not exist.
    #[error("face {face} refers to vertex {index}, but the mesh has {vertex_count} vertices")]
    IndexOutOfRange {
        /// 0-based face index.
        face: usize,
        /// The bad vertex index.
        index: u32,
        /// Number of vertices.
        vertex_count: usize,
    },
    /// A line of the file is malformed (or asks for something refused).
    #[error("{}: {message}", location(path, Some(*line)))]
    Syntax {
        /// The file (OBJ or MTL).
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// What is wrong, naming the statement.
        message: String,
    },
    /// The path names something other than a regular file (a folder, a device, a pipe).
    #[error("{path}: not a regular file")]
    NotAFile {
        /// The path.
        path: PathBuf,
    },
    /// The file is larger than a limit allows (checked before it is read).
    #[error("{path}: {what} = {value} exceeds the limit of {limit}")]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// What was counted.
        what: &'static str,
        /// The count.
        value: u64,
        /// The limit.
        limit: u64,
    },
    /// A glTF file that cannot be used (names the file and the JSON location).
    #[error(transparent)]
    Gltf(#[from] gltf::GltfError),
    /// Positions and texture coordinates have different lengths.
    #[error("{positions} positions but {uvs} texture coordinates")]
    AttributeLength {
        /// Number of positions.
        positions: usize,
        /// Number of texture coordinates.
        uvs: usize,
    },
}

fn location(path: &std::path::Path, line: Option<usize>) -> String {
    match line {
        Some(line) => format!("{}:{line}", path.display()),
        None => path.display().to_string(),
    }
}

impl Mesh {
    /// Builds a mesh from positions, texture coordinates and triangles, computing normals,
    /// `dpdu`/`dpdv` and frames (see [`frame`]).
    ///
    /// Errors when the lengths differ, an index is out of range, or a position is not finite.
    pub fn from_parts(
        positions: &[Vec3],
        uvs: &[Vec2],
        indices: Vec<[u32; 3]>,
    ) -> Result<Mesh, MeshError> {
        if positions.len() != uvs.len() {
            return Err(MeshError::AttributeLength {
                positions: positions.len(),
                uvs: uvs.len(),
            });
        }
        if let Some((vertex, p)) = positions.iter().enumerate().find(|(_, p)| !p.is_finite()) {
            return Err(MeshError::NonFinite {
                path: PathBuf::new(),
                line: None,
                vertex,
                value: p.to_array(),
            });
        }
        check_indices(&indices, positions.len())?;
        Ok(frame::build(positions, uvs, indices))
    }

    /// Checks that every index is in range.
    pub fn validate(&self) -> Result<(), MeshError> {
        check_indices(&self.indices, self.vertices.len())
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.indices.len()
    }

    /// The three positions of triangle `face`, or `None` when it or one of its indices is out of
    /// range.
    pub fn triangle(&self, face: usize) -> Option<[Vec3; 3]> {
        let [a, b, c] = *self.indices.get(face)?;
        let p = |i: u32| self.vertices.get(i as usize).map(|v| v.position);
        Some([p(a)?, p(b)?, p(c)?])
    }
}

fn check_indices(indices: &[[u32; 3]], vertex_count: usize) -> Result<(), MeshError> {
    for (face, tri) in indices.iter().enumerate() {
        if let Some(&index) = tri.iter().find(|&&i| i as usize >= vertex_count) {
            return Err(MeshError::IndexOutOfRange {
                face,
                index,
                vertex_count,
            });
        }
    }
    Ok(())
}

/// Canonical bit pattern of a position, for exact welding: `-0.0` and `0.0` map to the same key.
pub(crate) fn position_key(p: Vec3) -> [u32; 3] {
    [
        (p.x + 0.0).to_bits(),
        (p.y + 0.0).to_bits(),
        (p.z + 0.0).to_bits(),
    ]
}

/// For every vertex, the lowest index of a vertex with a bit-identical position.
pub(crate) fn weld_by_position(positions: &[Vec3]) -> Vec<u32> {
    let mut first: std::collections::BTreeMap<[u32; 3], u32> = std::collections::BTreeMap::new();
    positions
        .iter()
        .enumerate()
        .map(|(i, &p)| *first.entry(position_key(p)).or_insert(i as u32))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn validate_catches_out_of_range() {
        let p = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let uv = [Vec2::ZERO, Vec2::X, Vec2::Y];
        let mesh = Mesh::from_parts(&p, &uv, vec![[0, 1, 2]]).unwrap();
        assert!(mesh.validate().is_ok());
        let mut bad = mesh.clone();
        bad.indices.push([0, 1, 3]);
        let err = bad.validate().unwrap_err();
        assert!(err.to_string().contains("face 1"), "{err}");
        assert!(Mesh::from_parts(&p, &uv, vec![[0, 5, 2]]).is_err());
        assert!(Mesh::from_parts(&p, &uv[..2], vec![[0, 1, 2]]).is_err());
        let nan = [Vec3::ZERO, Vec3::new(f32::NAN, 0.0, 0.0), Vec3::Y];
        let err = Mesh::from_parts(&nan, &uv, vec![[0, 1, 2]]).unwrap_err();
        assert!(err.to_string().contains("vertex 1"), "{err}");
    }

    #[test]
    fn weld_merges_signed_zero() {
        let w = weld_by_position(&[Vec3::X, Vec3::new(-0.0, 0.0, 0.0), Vec3::ZERO, Vec3::X]);
        assert_eq!(w, vec![0, 1, 1, 0]);
    }
}

/// Quick look at the meshes: `cargo test --lib mesh::preview -- --ignored` writes PNGs
/// (normals as colours, orthographic, z-buffered; fin edges in white) to the target directory.
#[cfg(test)]
mod preview {
    use super::*;
    use glam::Mat3;

    fn render(mesh: &Mesh, rot: Mat3, fins: bool, name: &str) {
        const S: u32 = 400;
        let mut img = image::RgbImage::new(S, S);
        let mut depth = vec![f32::NEG_INFINITY; (S * S) as usize];
        let min = mesh
            .vertices
            .iter()
            .fold(Vec3::INFINITY, |m, v| m.min(rot * v.position));
        let max = mesh
            .vertices
            .iter()
            .fold(Vec3::NEG_INFINITY, |m, v| m.max(rot * v.position));
        let c = (min + max) / 2.0;
        let scale = 0.9 * S as f32 / (max - min).truncate().max_element();
        let screen = |p: Vec3| {
            let q = (rot * p - c) * scale;
            Vec3::new(q.x + S as f32 / 2.0, S as f32 / 2.0 - q.y, q.z)
        };
        for tri in &mesh.indices {
            let v = tri.map(|i| mesh.vertices[i as usize]);
            let s = v.map(|v| screen(v.position));
            let area =
                (s[1].x - s[0].x) * (s[2].y - s[0].y) - (s[2].x - s[0].x) * (s[1].y - s[0].y);
            if area >= 0.0 {
                continue; // back face (y flipped: CCW becomes negative)
            }
            let lo = s[0].min(s[1]).min(s[2]).max(Vec3::ZERO);
            let hi = s[0].max(s[1]).max(s[2]).min(Vec3::splat(S as f32 - 1.0));
            for y in lo.y as u32..=hi.y as u32 {
                for x in lo.x as u32..=hi.x as u32 {
                    let p = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                    let e =
                        |a: Vec3, b: Vec3| (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x);
                    let w = [
                        e(s[1], s[2]) / area,
                        e(s[2], s[0]) / area,
                        e(s[0], s[1]) / area,
                    ];
                    if w.iter().any(|&w| w < 0.0) {
                        continue;
                    }
                    let z = w[0] * s[0].z + w[1] * s[1].z + w[2] * s[2].z;
                    let k = (y * S + x) as usize;
                    if z > depth[k] {
                        depth[k] = z;
                        let n = (w[0] * v[0].normal + w[1] * v[1].normal + w[2] * v[2].normal)
                            .normalize();
                        let uv = w[0] * v[0].uv + w[1] * v[1].uv + w[2] * v[2].uv;
                        let check = ((uv.x * 16.0) as i32 + (uv.y * 8.0) as i32) % 2 == 0;
                        let f = if check { 1.0 } else { 0.8 };
                        let col = (rot * n * 0.5 + 0.5) * 255.0 * f;
                        img.put_pixel(x, y, image::Rgb([col.x as u8, col.y as u8, col.z as u8]));
                    }
                }
            }
        }
        if fins {
            let e = edges(mesh);
            let eye = rot.transpose() * Vec3::new(0.0, 0.0, 100.0);
            let w = FinWindows {
                windows: vec![(70.0, 110.0)],
            };
            for k in silhouette_edges(mesh, &e, eye, &w) {
                let [a, b] = e[k]
                    .vertices
                    .map(|i| screen(mesh.vertices[i as usize].position));
                for t in 0..50 {
                    let p = a.lerp(b, t as f32 / 49.0);
                    if p.x >= 0.0 && p.y >= 0.0 && p.x < S as f32 && p.y < S as f32 {
                        img.put_pixel(p.x as u32, p.y as u32, image::Rgb([255, 255, 255]));
                    }
                }
            }
        }
        img.save(format!("/work/target-mesh/preview-{name}.png"))
            .unwrap();
    }

    #[test]
    #[ignore]
    fn write_previews() {
        let tilt = Mat3::from_rotation_x(0.6) * Mat3::from_rotation_y(0.4);
        render(&procedural::torus(1.0, 0.4, 500), tilt, true, "torus");
        render(&procedural::sphere(1.0, 500), tilt, true, "sphere");
        render(
            &procedural::cylinder(0.5, 1.5, 500),
            tilt,
            false,
            "cylinder",
        );
        render(
            &procedural::leg(2000),
            Mat3::from_rotation_y(-std::f32::consts::FRAC_PI_2),
            false,
            "leg-side",
        );
        render(
            &procedural::leg(2000),
            Mat3::from_rotation_y(-0.5),
            true,
            "leg-34",
        );
    }
}
