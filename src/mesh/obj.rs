//! OBJ loading through tobj (mesh stage): every model of the file, triangulated and single-indexed,
//! merged in file order into one [`Mesh`]. The boundary between files and the renderer: every
//! problem in the file becomes a [`MeshError`] naming the file, or a warning, never a panic.
//!
//! - **Normals in the file are ignored**: they are recomputed from the faces (thesis 3.1.4,
//!   3.2.1: "the normal values are recalculated just to make sure the original is correct").
//! - **Every line is checked first** ([`scan_obj`], a streaming pass that allocates nothing per
//!   line): `v` needs 3 finite numbers (then an optional `w` ≠ 0 or 3 colour values), `vt` 2
//!   finite numbers, `vn` 3 numbers, `f` at least 3 vertices `v`, `v/vt`, `v//vn` or `v/vt/vn`
//!   whose indices (1-based, negative = relative) exist, `usemtl` a name; a malformed line is a
//!   [`MeshError::Syntax`] naming the file and line. The other statements of the OBJ
//!   specification are ignored, as are points (`p`) and polylines (`l`) of two vertices; any
//!   other first word is an error (the file is not an OBJ); like tobj, a polyline of three or more
//!   vertices is a polygon. The file must be a regular file of at most [`MAX_OBJ_BYTES`] with at
//!   most [`MAX_OBJ_TRIANGLES`] triangles.
//! - **Materials are not used.** A material library named by `mtllib` that is missing only adds
//!   a warning; one that exists is checked line by line like the OBJ (`Ka`/`Kd`/`Ks`/`Ke` 3
//!   numbers, `Ns`/`Ni`/`d` a number, `illum` an integer, `newmtl` and `map_*` a name) and a
//!   malformed line is an error naming the MTL file and line. tobj never parses it.
//! - **No UVs** (or UVs on only some vertices): a *box projection* is generated and a warning
//!   added. Each face is projected along the axis its normal is most aligned with
//!   (ties: x, then y, then z), onto the other two coordinates, oriented so the projection is
//!   never mirrored seen from outside (`T × B = N`), and scaled by the bounding box's largest
//!   extent so `uv` lies in `[0, 1]²`. Vertices shared by faces projected along different axes
//!   are duplicated (same position, so normals stay welded).

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufReader, Read};
use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};

use super::{Mesh, MeshError};

// The file-size limits live here, with the loader that enforces them, rather than in
// `crate::limits` (which re-exports them): `limits` estimates a scene's cost from the mesh
// module, so the mesh module must not reach back into it.

/// Largest OBJ file accepted, bytes (checked before the file is read).
pub const MAX_OBJ_BYTES: u64 = 2 << 30;

/// Largest triangle count an OBJ file may have (after fan triangulation of its polygons).
pub const MAX_OBJ_TRIANGLES: u64 = 32_000_000;

/// Largest MTL file accepted, bytes.
pub const MAX_MTL_BYTES: u64 = 64 << 20;

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
    let summary = scan_obj(path)?;
    // Checked again: the scan's check does not hold for a file swapped since.
    let file = open_checked(path, MAX_OBJ_BYTES, "file size in bytes")?;
    load_checked(path, &mut BufReader::new(file.take(MAX_OBJ_BYTES)), summary)
}

/// Loads OBJ text held in memory, as [`load_obj`] loads a file; `name` names it in errors.
/// Material libraries are not looked up (a warning says so). The entry point of the OBJ fuzz
/// target and of the property tests.
pub fn load_obj_bytes(bytes: &[u8], name: &Path) -> Result<LoadedMesh, MeshError> {
    let summary = scan_obj_reader(name, bytes, None)?;
    load_checked(name, &mut &bytes[..], summary)
}

/// tobj over text that [`scan_obj_reader`] accepted, then the merge into one [`Mesh`].
fn load_checked(
    path: &Path,
    reader: &mut impl std::io::BufRead,
    summary: ObjSummary,
) -> Result<LoadedMesh, MeshError> {
    let options = tobj::LoadOptions {
        single_index: true,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
    };
    // Materials are not used and were checked by the scan: tobj gets an empty library.
    let no_materials = |_: &Path| -> tobj::MTLLoadResult { Ok((Vec::new(), Default::default())) };
    let (models, _materials) =
        tobj::load_obj_buf(reader, &options, no_materials).map_err(|source| match source {
            tobj::LoadError::ReadError => MeshError::Io {
                path: path.to_path_buf(),
                source: std::io::Error::other("read error"),
            },
            source => MeshError::Parse {
                path: path.to_path_buf(),
                source,
            },
        })?;
    let mut warnings = summary.warnings;

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
    // A surface to grow fur on: at least one face of non-zero area (in f64, so that a tiny
    // but real triangle of 1e-30 counts).
    let has_area = indices.iter().any(|t| {
        let [a, b, c] = t.map(|i| positions[i as usize].as_dvec3());
        (b - a).cross(c - a).length_squared() > 0.0
    });
    if !has_area {
        return Err(MeshError::Syntax {
            path: path.to_path_buf(),
            line: summary.first_face_line,
            message: format!(
                "none of the {} faces (from this line on) has a non-zero area: they are all \
                 points or lines, so there is no surface to grow fur on",
                indices.len()
            ),
        });
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
    let text = crate::input::read_text(path, MAX_OBJ_BYTES, "OBJ file");
    let found = text.ok().and_then(|text| {
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

/// What [`scan_obj`] found: statement counts and warnings.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ObjSummary {
    /// `v` statements.
    pub positions: u64,
    /// `vt` statements.
    pub texcoords: u64,
    /// `vn` statements.
    pub normals: u64,
    /// Triangles after fan triangulation of the `f` statements.
    pub triangles: u64,
    /// Non-fatal problems (a material library that is missing).
    pub warnings: Vec<String>,
    /// The line of the first `f` statement (0 when there is none).
    pub first_face_line: usize,
}

/// Largest coordinate magnitude accepted in an OBJ file. Normals, areas and tangent frames
/// multiply coordinate differences: at most `2·10¹⁸` apart, a product is at most `4·10³⁶`, and
/// a sum of three stays below `f32::MAX ≈ 3.4·10³⁸`, where `1e30` would overflow to infinity.
pub const MAX_COORDINATE: f32 = 1.0e18;

/// The statements of the OBJ specification that pelage does not use: accepted and ignored (any
/// other first word on a line is an error, so a file that is not an OBJ is not read as an empty
/// one).
const OTHER_STATEMENTS: &[&str] = &[
    "vp",
    "cstype",
    "deg",
    "bmat",
    "step",
    "p",
    "curv",
    "curv2",
    "surf",
    "parm",
    "trim",
    "hole",
    "scrv",
    "sp",
    "end",
    "con",
    "g",
    "s",
    "mg",
    "o",
    "bevel",
    "c_interp",
    "d_interp",
    "lod",
    "shadow_obj",
    "trace_obj",
    "ctech",
    "stech",
    "maplib",
    "usemap",
    "call",
    "csh",
];

/// Longest line accepted in an OBJ or MTL file, bytes.
const MAX_LINE_BYTES: usize = 1 << 20;

/// Opens `path` for a line scan after checking it is a regular file of at most `max_bytes`
/// ([`crate::input::check_regular_file`]).
fn open_checked(path: &Path, max_bytes: u64, what: &'static str) -> Result<File, MeshError> {
    let io = |source| MeshError::Io {
        path: path.to_path_buf(),
        source,
    };
    let meta = std::fs::metadata(path).map_err(io)?;
    if !meta.is_file() {
        return Err(MeshError::NotAFile {
            path: path.to_path_buf(),
        });
    }
    if meta.len() > max_bytes {
        return Err(MeshError::TooLarge {
            path: path.to_path_buf(),
            what,
            value: meta.len(),
            limit: max_bytes,
        });
    }
    File::open(path).map_err(io)
}

/// Calls `each(line_number, line)` for every line of a checked file (1-based numbers, line
/// endings stripped). Errors on a line that is not UTF-8 or longer than [`MAX_LINE_BYTES`].
fn for_each_line(
    path: &Path,
    file: impl std::io::Read,
    mut each: impl FnMut(usize, &str) -> Result<(), LineError>,
) -> Result<(), MeshError> {
    use std::io::{BufRead, Read};
    let syntax = |line: usize, message: String| MeshError::Syntax {
        path: path.to_path_buf(),
        line,
        message,
    };
    let mut reader = BufReader::new(file).take(u64::MAX);
    let mut buf = Vec::new();
    let mut number = 0usize;
    loop {
        buf.clear();
        reader.set_limit(MAX_LINE_BYTES as u64 + 1);
        let n = reader
            .read_until(b'\n', &mut buf)
            .map_err(|source| MeshError::Io {
                path: path.to_path_buf(),
                source,
            })?;
        if n == 0 {
            return Ok(());
        }
        number += 1;
        if buf.last() != Some(&b'\n') && buf.len() > MAX_LINE_BYTES {
            return Err(syntax(
                number,
                format!("line longer than {MAX_LINE_BYTES} bytes"),
            ));
        }
        let text = std::str::from_utf8(&buf)
            .map_err(|_| syntax(number, "not valid UTF-8 text".to_string()))?;
        each(number, text.trim_end_matches(['\n', '\r'])).map_err(|e| match e {
            LineError::Message(m) => syntax(number, m),
            LineError::Mesh(e) => e,
        })?;
    }
}

/// Why a line was refused: a message (made into [`MeshError::Syntax`] with the line), or a
/// finished error.
enum LineError {
    Message(String),
    Mesh(MeshError),
}

impl From<String> for LineError {
    fn from(m: String) -> Self {
        LineError::Message(m)
    }
}

impl From<&str> for LineError {
    fn from(m: &str) -> Self {
        LineError::Message(m.to_string())
    }
}

/// Parses one number of statement `what`; `finite` refuses NaN and infinities.
fn number(word: Option<&str>, what: &str, finite: bool) -> Result<f32, String> {
    let word = word.ok_or_else(|| format!("`{what}` has too few numbers"))?;
    let x: f32 = word
        .parse()
        .map_err(|_| format!("`{what}`: {word:?} is not a number"))?;
    if finite && !x.is_finite() {
        return Err(format!("`{what}`: {word} is not a finite number"));
    }
    Ok(x)
}

/// Resolves one index of a face vertex (1-based, negative = relative to `count` so far) to
/// 0-based; `None` is returned for an empty field (`v//vn`).
fn face_index(field: &str, count: u64, kind: &str, corner: &str) -> Result<Option<u64>, String> {
    if field.is_empty() {
        return Ok(None);
    }
    let i: i64 = field
        .parse()
        .map_err(|_| format!("face vertex {corner:?}: {field:?} is not an index"))?;
    if i == 0 {
        return Err(format!(
            "face vertex {corner:?}: {kind} index 0 (OBJ indices start at 1)"
        ));
    }
    if i < 0 {
        let back = i.unsigned_abs();
        if back > count {
            return Err(format!(
                "face vertex {corner:?}: relative {kind} index {i}, but only {count} are defined above"
            ));
        }
        return Ok(Some(count - back));
    }
    Ok(Some(i as u64 - 1))
}

/// Checks every line of an OBJ file (see the module docs) and counts what it holds, without
/// building anything: cheap enough to run before deciding whether the mesh fits in memory.
/// Material libraries it names are checked too ([`MeshError::Syntax`] naming the MTL file);
/// a missing one is a warning.
pub fn scan_obj(path: &Path) -> Result<ObjSummary, MeshError> {
    let file = open_checked(path, MAX_OBJ_BYTES, "file size in bytes")?;
    scan_obj_reader(path, file, Some(path.parent().unwrap_or(Path::new(""))))
}

/// [`scan_obj`] over any reader; material libraries are looked up in `library_dir` (not at
/// all when `None`: a warning says they were not read).
pub fn scan_obj_reader(
    path: &Path,
    file: impl std::io::Read,
    library_dir: Option<&Path>,
) -> Result<ObjSummary, MeshError> {
    let mut s = ObjSummary::default();
    // Largest positive index of each kind, with its line, checked against the totals at the end
    // (forward references are allowed, as tobj allows them).
    let mut highest: [(u64, usize); 3] = [(0, 0); 3];
    let mut libraries: Vec<(usize, String)> = Vec::new();
    for_each_line(path, file, |line, text| {
        let mut words = text.split_whitespace();
        match words.next() {
            Some("v") => {
                let mut p = [0.0f32; 3];
                for c in &mut p {
                    *c = number(words.next(), "v", false)?;
                }
                if !p.iter().all(|c| c.is_finite()) {
                    return Err(LineError::Mesh(MeshError::NonFinite {
                        path: path.to_path_buf(),
                        line: Some(line),
                        vertex: s.positions as usize + 1,
                        value: p,
                    }));
                }
                if let Some(c) = p.iter().find(|c| c.abs() > MAX_COORDINATE) {
                    return Err(format!(
                        "`v`: coordinate {c:e} is beyond ±{MAX_COORDINATE:e}: normals and areas \
                         multiply coordinates, and would overflow f32; scale the mesh down"
                    )
                    .into());
                }
                let rest: Vec<&str> = words.collect();
                match rest.len() {
                    0 => {}
                    1 => {
                        let w = number(Some(rest[0]), "v", true)?;
                        if w == 0.0 {
                            return Err("`v`: weight w = 0".into());
                        }
                        if p.iter().any(|c| !(c / w).is_finite()) {
                            return Err(format!("`v`: {p:?} / w = {w} is not finite").into());
                        }
                    }
                    3 => {
                        for word in rest {
                            number(Some(word), "v", false)?;
                        }
                    }
                    n => {
                        return Err(format!(
                            "`v` takes 3 coordinates, then nothing, a weight or 3 colour values; found {} values",
                            3 + n
                        )
                        .into());
                    }
                }
                s.positions += 1;
            }
            Some("vt") => {
                number(words.next(), "vt", true)?;
                number(words.next(), "vt", true)?;
                s.texcoords += 1;
            }
            Some("vn") => {
                for _ in 0..3 {
                    number(words.next(), "vn", false)?;
                }
                s.normals += 1;
            }
            Some(statement @ ("f" | "l")) => {
                let mut corners = 0u64;
                for corner in words {
                    let fields: Vec<&str> = corner.split('/').collect();
                    if fields.len() > 3 {
                        return Err(format!(
                            "face vertex {corner:?}: expected v, v/vt, v//vn or v/vt/vn"
                        )
                        .into());
                    }
                    let counts = [s.positions, s.texcoords, s.normals];
                    for (k, kind) in ["position", "texture coordinate", "normal"]
                        .iter()
                        .enumerate()
                    {
                        let field = fields.get(k).copied().unwrap_or("");
                        if k == 0 && field.is_empty() {
                            return Err(format!(
                                "face vertex {corner:?}: the position index is missing"
                            )
                            .into());
                        }
                        if let Some(i) = face_index(field, counts[k], kind, corner)?
                            && i + 1 > highest[k].0
                        {
                            highest[k] = (i + 1, line);
                        }
                    }
                    corners += 1;
                }
                // tobj turns a polyline of 3 or more vertices into a polygon too.
                if corners < 3 && statement == "f" {
                    return Err(format!("`f` needs at least 3 vertices, found {corners}").into());
                }
                if corners >= 3 && s.first_face_line == 0 {
                    s.first_face_line = line;
                }
                s.triangles += corners.saturating_sub(2);
            }
            Some("usemtl") if words.next().is_none() => {
                return Err("`usemtl` needs a material name".into());
            }
            Some("usemtl") => {}
            Some("mtllib") => {
                let name = text.trim_start()["mtllib".len()..].trim();
                if name.is_empty() {
                    return Err("`mtllib` needs a file name".into());
                }
                libraries.push((line, name.to_string()));
            }
            Some(word) if word.starts_with('#') || OTHER_STATEMENTS.contains(&word) => {}
            Some(word) => {
                let shown: String = word.chars().take(40).collect();
                return Err(format!("unknown statement {shown:?} (not an OBJ file?)").into());
            }
            None => {}
        }
        Ok(())
    })?;
    let totals = [s.positions, s.texcoords, s.normals];
    for (k, kind) in ["vertex position", "texture coordinate", "normal"]
        .iter()
        .enumerate()
    {
        let (index, line) = highest[k];
        // tobj ignores texture and normal indices when the file has none of them.
        let ignored = k > 0 && totals[k] == 0;
        if index > totals[k] && !ignored {
            return Err(MeshError::Syntax {
                path: path.to_path_buf(),
                line,
                message: format!(
                    "face refers to {kind} {index}, but the file has {}",
                    totals[k]
                ),
            });
        }
    }
    if s.triangles > MAX_OBJ_TRIANGLES {
        return Err(MeshError::TooLarge {
            path: path.to_path_buf(),
            what: "triangles",
            value: s.triangles,
            limit: MAX_OBJ_TRIANGLES,
        });
    }
    if s.triangles == 0 {
        return Err(MeshError::NoFaces {
            path: path.to_path_buf(),
        });
    }
    let Some(dir) = library_dir else {
        if let Some((line, name)) = libraries.first() {
            s.warnings.push(format!(
                "{}:{line}: material library {name} not read; materials are not used",
                path.display()
            ));
        }
        return Ok(s);
    };
    // Each library once, however often it is named (a file repeating `mtllib` thousands of
    // times rescanned it each time).
    let mut seen = std::collections::BTreeSet::new();
    for (line, name) in libraries {
        if !seen.insert(name.clone()) {
            continue;
        }
        let mtl = dir.join(&name);
        if !mtl.exists() {
            s.warnings.push(format!(
                "{}:{line}: material library {name} not found; materials are not used",
                path.display()
            ));
            continue;
        }
        scan_mtl(&mtl)?;
    }
    Ok(s)
}

/// Checks every line of an MTL file (module docs). The materials themselves are not used.
pub fn scan_mtl(path: &Path) -> Result<(), MeshError> {
    let file = open_checked(path, MAX_MTL_BYTES, "file size in bytes")?;
    for_each_line(path, file, |_, text| {
        let mut words = text.split_whitespace();
        let Some(key) = words.next() else {
            return Ok(());
        };
        match key {
            "Ka" | "Kd" | "Ks" | "Ke" => {
                for _ in 0..3 {
                    number(words.next(), key, false)?;
                }
            }
            "Ns" | "Ni" | "d" => {
                number(words.next(), key, false)?;
            }
            "illum" => {
                let word = words
                    .next()
                    .ok_or_else(|| "`illum` needs an integer".to_string())?;
                word.parse::<i32>()
                    .map_err(|_| format!("`illum`: {word:?} is not an integer"))?;
            }
            "newmtl" | "map_Ka" | "map_Kd" | "map_Ks" | "map_Bump" | "map_bump" | "map_Ns"
            | "map_ns" | "map_NS" | "bump" | "map_d"
                if words.next().is_none() =>
            {
                return Err(format!("`{key}` needs a name").into());
            }
            _ => {}
        }
        Ok(())
    })
}

/// Box projection (module docs): returns new positions, UVs and indices, with vertices
/// duplicated per projection axis in first-use order.
#[allow(clippy::type_complexity)]
fn box_projection(
    positions: &[Vec3],
    indices: &[[u32; 3]],
) -> (Vec<Vec3>, Vec<Vec2>, Vec<[u32; 3]>) {
    let (p, uv, idx, _) = box_projection_with_origins(positions, indices);
    (p, uv, idx)
}

/// [`box_projection`], also giving each new vertex's original index (so per-vertex data such
/// as a glTF skin's influences can follow the duplicated vertices).
pub(crate) fn box_projection_with_origins(
    positions: &[Vec3],
    indices: &[[u32; 3]],
) -> (Vec<Vec3>, Vec<Vec2>, Vec<[u32; 3]>, Vec<u32>) {
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
    let mut origins = Vec::new();
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
                origins.push(i);
                (out_p.len() - 1) as u32
            })
        }));
    }
    (out_p, out_uv, out_i, origins)
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
    fn a_library_named_many_times_is_looked_up_once() {
        let mut text = "mtllib nowhere.mtl\n".repeat(5000);
        text.push_str("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n");
        let path = write_obj("many-mtl.obj", &text);
        let loaded = load_obj(&path).unwrap();
        assert_eq!(loaded.warnings.len(), 1, "{:?}", &loaded.warnings[..2]);
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
