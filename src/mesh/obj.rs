//! OBJ loading through tobj: every model of the file, triangulated and single-indexed, merged in
//! file order into one [`Mesh`]. The boundary between files and the renderer: every problem in
//! the file becomes a [`MeshError`] naming the file, or a warning, never a panic.
//!
//! - **Normals in the file are ignored**: they are recomputed from the faces (thesis 3.1.4,
//!   3.2.1: "the normal values are recalculated just to make sure the original is correct").
//! - **Materials are not used**; a material library that fails to load only adds a warning.
//! - **No UVs** (or UVs on only some vertices): a *box projection* is generated and a warning
//!   added. Each face is projected along the axis its normal is most aligned with
//!   (ties: x, then y, then z), onto the other two coordinates, oriented so the projection is
//!   never mirrored seen from outside (`T × B = N`), and scaled by the bounding box's largest
//!   extent so `uv` lies in `[0, 1]²`. Vertices shared by faces projected along different axes
//!   are duplicated (same position, so normals stay welded).

use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufReader;
use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};

use super::{Mesh, MeshError};

/// A mesh read from a file, with what was noticed on the way.
#[derive(Clone, Debug)]
pub struct LoadedMesh {
    /// The mesh.
    pub mesh: Mesh,
    /// Human-readable warnings (missing materials, generated UVs), in the order they arose.
    pub warnings: Vec<String>,
}

/// Loads an OBJ file (see the module docs for what is kept and what is recomputed).
///
/// Errors: the file cannot be opened or read ([`MeshError::Io`]), tobj rejects it
/// ([`MeshError::Parse`]), it has no faces ([`MeshError::NoFaces`]), or a position is NaN or
/// infinite ([`MeshError::NonFinite`], with the line and 1-based OBJ vertex number).
pub fn load_obj(path: &Path) -> Result<LoadedMesh, MeshError> {
    let file = File::open(path).map_err(|source| MeshError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let options = tobj::LoadOptions {
        single_index: true,
        triangulate: true,
        ..Default::default()
    };
    let parent = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let (models, materials) =
        tobj::load_obj_buf(&mut BufReader::new(file), &options, |mtl: &Path| {
            tobj::load_mtl(parent.join(mtl))
        })
        .map_err(|source| match source {
            tobj::LoadError::ReadError => MeshError::Io {
                path: path.to_path_buf(),
                source: std::io::Error::other("read error"),
            },
            source => MeshError::Parse {
                path: path.to_path_buf(),
                source,
            },
        })?;
    let mut warnings = Vec::new();
    if let Err(e) = materials {
        warnings.push(format!(
            "{}: materials not loaded ({e}); they are not used",
            path.display()
        ));
    }

    let mut positions: Vec<Vec3> = Vec::new();
    let mut uvs: Vec<Vec2> = Vec::new();
    let mut indices: Vec<[u32; 3]> = Vec::new();
    let mut has_uv = true;
    for model in &models {
        let m = &model.mesh;
        let base = positions.len() as u32;
        let count = m.positions.len() / 3;
        positions.extend(
            m.positions
                .chunks_exact(3)
                .map(|c| Vec3::new(c[0], c[1], c[2])),
        );
        if m.texcoords.len() == 2 * count {
            uvs.extend(m.texcoords.chunks_exact(2).map(|c| Vec2::new(c[0], c[1])));
        } else {
            has_uv = false;
            uvs.extend(std::iter::repeat_n(Vec2::ZERO, count));
        }
        for tri in m.indices.chunks_exact(3) {
            let face = indices.len();
            let tri = [tri[0], tri[1], tri[2]];
            if let Some(&index) = tri.iter().find(|&&i| i as usize >= count) {
                return Err(MeshError::IndexOutOfRange {
                    face,
                    index,
                    vertex_count: count,
                });
            }
            indices.push(tri.map(|i| base + i));
        }
    }
    if indices.is_empty() {
        return Err(MeshError::NoFaces {
            path: path.to_path_buf(),
        });
    }
    if let Some((vertex, p)) = positions.iter().enumerate().find(|(_, p)| !p.is_finite()) {
        return Err(non_finite(path, vertex, *p));
    }
    if !has_uv {
        warnings.push(format!(
            "{}: no texture coordinates (or only on some vertices); generated a box projection",
            path.display()
        ));
        let (p, uv, idx) = box_projection(&positions, &indices);
        positions = p;
        uvs = uv;
        indices = idx;
    }
    let mesh = Mesh::from_parts(&positions, &uvs, indices)?;
    Ok(LoadedMesh { mesh, warnings })
}

/// The error for a non-finite position at merged index `vertex`: re-reads the file to find the
/// offending `v` line (the merged index is not the file's numbering once tobj re-indexes).
fn non_finite(path: &Path, vertex: usize, p: Vec3) -> MeshError {
    let found = std::fs::read_to_string(path).ok().and_then(|text| {
        let mut number = 0;
        for (line, l) in text.lines().enumerate() {
            let mut words = l.split_whitespace();
            if words.next() != Some("v") {
                continue;
            }
            number += 1;
            let bad = words
                .take(3)
                .any(|w| w.parse::<f32>().is_ok_and(|x| !x.is_finite()));
            if bad {
                return Some((line + 1, number));
            }
        }
        None
    });
    let (line, vertex) = match found {
        Some((line, number)) => (Some(line), number),
        None => (None, vertex),
    };
    MeshError::NonFinite {
        path: PathBuf::from(path),
        line,
        vertex,
        value: p.to_array(),
    }
}

/// Box projection (module docs): returns new positions, UVs and indices, with vertices
/// duplicated per projection axis in first-use order.
#[allow(clippy::type_complexity)]
fn box_projection(
    positions: &[Vec3],
    indices: &[[u32; 3]],
) -> (Vec<Vec3>, Vec<Vec2>, Vec<[u32; 3]>) {
    let min = positions.iter().fold(Vec3::INFINITY, |m, &p| m.min(p));
    let max = positions.iter().fold(Vec3::NEG_INFINITY, |m, &p| m.max(p));
    let extent = (max - min).max_element();
    let scale = if extent > 0.0 && extent.is_finite() {
        1.0 / extent
    } else {
        1.0
    };
    // (u, v) for each of the six axes, from `p − min` and `max − p`; chosen so that
    // û × v̂ points along the axis (no mirroring).
    let project = |axis: u8, p: Vec3| -> Vec2 {
        let lo = (p - min) * scale;
        let hi = (max - p) * scale;
        match axis {
            0 => Vec2::new(hi.z, lo.y), // +x: u = −z
            1 => Vec2::new(lo.z, lo.y), // −x: u = +z
            2 => Vec2::new(lo.x, hi.z), // +y: v = −z
            3 => Vec2::new(lo.x, lo.z), // −y: v = +z
            4 => Vec2::new(lo.x, lo.y), // +z
            _ => Vec2::new(hi.x, lo.y), // −z: u = −x
        }
    };
    let mut map: BTreeMap<(u32, u8), u32> = BTreeMap::new();
    let (mut out_p, mut out_uv, mut out_i) = (Vec::new(), Vec::new(), Vec::new());
    for tri in indices {
        let [a, b, c] = tri.map(|i| positions[i as usize]);
        let n = (b - a).cross(c - a);
        let m = n.abs();
        let axis = if m.x >= m.y && m.x >= m.z {
            if n.x >= 0.0 { 0 } else { 1 }
        } else if m.y >= m.z {
            if n.y >= 0.0 { 2 } else { 3 }
        } else if n.z >= 0.0 {
            4
        } else {
            5
        };
        out_i.push(tri.map(|i| {
            *map.entry((i, axis)).or_insert_with(|| {
                let p = positions[i as usize];
                out_p.push(p);
                out_uv.push(project(axis, p));
                (out_p.len() - 1) as u32
            })
        }));
    }
    (out_p, out_uv, out_i)
}

#[cfg(test)]
mod tests {
    use super::super::frame::tests::assert_orthonormal;
    use super::*;

    /// Writes `text` to a fresh file under the system temp dir and returns its path.
    fn write_obj(name: &str, text: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("pelage-mesh-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        path
    }

    const QUAD: &str = "\
# a unit quad in two models
o first
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
vt 0 0
vt 1 0
vt 1 1
vt 0 1
vn 0 0 -1
f 1/1/1 2/2/1 3/3/1 4/4/1
o second
v 0 0 1
v 1 0 1
v 0 1 1
vt 0 0
vt 1 0
vt 0 1
f 5/5 6/6 7/7
";

    #[test]
    fn loads_and_merges_models() {
        let path = write_obj("quad.obj", QUAD);
        let loaded = load_obj(&path).unwrap();
        assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
        let mesh = &loaded.mesh;
        assert_eq!(mesh.indices.len(), 3);
        assert_eq!(mesh.vertices.len(), 7);
        mesh.validate().unwrap();
        // File normals (−z) are ignored: recomputed from the CCW winding (+z).
        for v in &mesh.vertices {
            assert!((v.normal - Vec3::Z).length() < 1e-6);
            assert!((v.frame.tangent - Vec3::X).length() < 1e-6);
        }
        // Second model comes after the first.
        assert_eq!(mesh.vertices[4].position, Vec3::new(0.0, 0.0, 1.0));
    }

    #[test]
    fn missing_file_names_path() {
        let path = std::env::temp_dir().join("pelage-no-such-dir/none.obj");
        let err = load_obj(&path).unwrap_err();
        assert!(matches!(err, MeshError::Io { .. }));
        assert!(err.to_string().contains("none.obj"), "{err}");
    }

    #[test]
    fn no_faces_is_an_error() {
        let path = write_obj("empty.obj", "v 0 0 0\nv 1 0 0\n");
        let err = load_obj(&path).unwrap_err();
        assert!(matches!(err, MeshError::NoFaces { .. }));
        assert!(err.to_string().contains("empty.obj"), "{err}");
    }

    #[test]
    fn non_finite_names_file_line_and_vertex() {
        let path = write_obj(
            "nan.obj",
            "v 0 0 0\n# comment\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n",
        );
        let err = load_obj(&path).unwrap_err();
        let msg = err.to_string();
        assert!(
            matches!(
                err,
                MeshError::NonFinite {
                    line: Some(3),
                    vertex: 2,
                    ..
                }
            ),
            "{msg}"
        );
        assert!(
            msg.contains("nan.obj:3") && msg.contains("vertex 2"),
            "{msg}"
        );
        let path = write_obj("inf.obj", "v 0 0 0\nv 1 0 0\nv 0 inf 0\nf 1 2 3\n");
        assert!(matches!(load_obj(&path), Err(MeshError::NonFinite { .. })));
    }

    #[test]
    fn parse_errors_name_file() {
        let path = write_obj("bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n");
        let err = load_obj(&path).unwrap_err();
        assert!(err.to_string().contains("bad.obj"), "{err}");
    }

    #[test]
    fn missing_material_is_a_warning() {
        let text = "mtllib nowhere.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl x\nf 1/1 2/2 3/3\n";
        let path = write_obj("mtl.obj", text);
        let loaded = load_obj(&path).unwrap();
        assert_eq!(loaded.warnings.len(), 1, "{:?}", loaded.warnings);
        assert!(loaded.warnings[0].contains("materials"));
    }

    #[test]
    fn cube_without_uvs_gets_box_projection() {
        let text = "\
v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1
f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 4 8 7 3\nf 1 5 8 4\nf 2 3 7 6
";
        let path = write_obj("cube.obj", text);
        let loaded = load_obj(&path).unwrap();
        assert_eq!(loaded.warnings.len(), 1);
        assert!(loaded.warnings[0].contains("box projection"));
        let mesh = &loaded.mesh;
        assert_eq!(mesh.indices.len(), 12);
        // Each corner is used by three faces with three axes.
        assert_eq!(mesh.vertices.len(), 24);
        for v in &mesh.vertices {
            assert_orthonormal(&v.frame, 1e-5);
            assert!(v.frame.is_right_handed(), "{v:?}");
            assert!(v.uv.cmpge(Vec2::ZERO).all() && v.uv.cmple(Vec2::ONE).all());
            // Welded normals point out of the corner.
            assert!((v.normal - v.position.normalize()).length() < 1e-5);
            // Per-face UV derivatives follow the face (dpdu ⟂ the face's axis).
        }
    }
}
