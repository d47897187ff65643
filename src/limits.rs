//! Resource limits (before the pipeline): how much memory and work a scene asks for, estimated from
//! the scene alone (and, for an OBJ mesh, a streaming scan of the file), *before* anything large is
//! allocated.
//!
//! A reference renderer is fed machine-generated scenes in bulk; a scene that would need 60 GiB
//! or a week of baking must be refused in milliseconds with a message that names the limit,
//! not discovered by the out-of-memory killer. Two budgets are checked:
//!
//! - **Memory** ([`MemoryEstimate`]): the sum of the large buffers a render holds at its peak,
//!   each named (framebuffer, kept animation frames, strands and cones, bake grids, shell and fin
//!   textures with their mips, the mesh, its edges, pending set-up triangles, OBJ parsing). The
//!   figures are the sizes of the data structures times their counts, with documented
//!   typical-case factors where a count depends on the view (set-up triangles, fin edges); they
//!   are an estimate of the peak, not a bound. The default limit is [`DEFAULT_MAX_MEMORY`]
//!   (8 GiB), fixed rather than a fraction of the machine's memory so that the same scene is
//!   accepted or refused on every machine; `pelage render --max-memory` raises it.
//! - **Bake work** ([`bake_work`]): texel writes and segment tests of the shell and fin bakes,
//!   the only stage whose cost can grow without bound while memory stays small (thick strands ×
//!   many strands × fine grids). The default limit is [`DEFAULT_MAX_BAKE_WORK`]; `--max-work`
//!   raises it.
//!
//! Bake grids are baked one layer per worker thread, so their share of the estimate counts one
//! grid per thread (the `threads` argument): with `--threads` given, acceptance does not depend
//! on the machine.

use crate::mesh::{self, MeshError};
use crate::scene::{MeshKind, Scene};
use std::fmt;

/// Default memory limit: 8 GiB.
pub const DEFAULT_MAX_MEMORY: u64 = 8 << 30;

/// Default bake work limit, in texel writes plus segment tests (about a minute of baking on
/// one core of a 2020s machine).
pub const DEFAULT_MAX_BAKE_WORK: u64 = 20_000_000_000;

/// Default drawing work limit per frame, in fragment evaluations (one per effect) and triangle
/// set-ups (see [`draw_work`]): about eight minutes a frame on one core of a 2020s machine
/// (the default scene, 3.3·10⁸ units, draws in 1.6 s of CPU time on one core).
pub const DEFAULT_MAX_DRAW_WORK: u64 = 100_000_000_000;

/// The OBJ loader's file limits, defined beside the loader that enforces them.
pub use crate::mesh::obj::{MAX_MTL_BYTES, MAX_OBJ_BYTES, MAX_OBJ_TRIANGLES};

/// Most animation frames one render may ask for.
pub const MAX_FRAMES: u32 = 100_000;

// Sizes of the data structures counted (bytes). Fixed here rather than taken from
// `size_of` so the estimate does not change when a private layout does.
const FRAMEBUFFER_PER_PIXEL: u64 = 16 + 4 + 4 + 4; // f32 RGBA + f32 depth + RGBA8 + PNG bytes
const GIF_PER_PIXEL: u64 = 4 + 1; // kept RGBA8 frame + its share of the GIF
const STRAND_BYTES: u64 = 100; // root, 4 control points, radii, colour, lean
const CONE_BYTES: u64 = 68; // p0, p1, r0, r1, axis, e1, e2
const SAMPLE_BYTES: u64 = 20; // one supersample of a bake grid
const DOWNSAMPLE_PER_TEXEL: u64 = 12 + 12 + 4 + 1; // colour, tangent, alpha, covered
// Colour + tangent RGBA8 as baked, then as textures with mips (× 4/3), then side by side for
// the texture reads with an alpha plane for the shadow (9 bytes × 4/3).
const SHELL_PER_TEXEL: u64 = 8 + 11 + 12;
const VERTEX_BYTES: u64 = 92 + 100; // mesh::Vertex plus the temporaries of building frames
const CLIP_VERTEX_BYTES: u64 = 16 + 112 + 40; // clip position + the fur varyings + its screen form
const SETUP_TRIANGLE_BYTES: u64 = 160 + 12 + 8; // set-up triangle, corner indices, bin entries
const EDGE_BYTES_PER_TRIANGLE: u64 = 180; // ~1.5 edges per triangle with their face lists
const OBJ_BYTES_PER_TRIANGLE: u64 = 3 * 24 + 3 * 48 + 64; // tobj faces, index map, copies
const OBJ_BYTES_PER_ATTRIBUTE: u64 = 12 + 12; // tobj's copy and ours
/// Bytes of one exported skin vertex: position, normal, tangent, uv, binormal, ∂p/∂u, ∂p/∂v.
const EXPORT_SKIN_VERTEX_BYTES: u64 = 12 + 12 + 16 + 8 + 12 + 12 + 12;
/// Bytes `pelage compare` holds per pixel of the larger image: both images in RGBA8 and in
/// floating point, FLIP's filtered colour and feature planes, its error map and the heat maps
/// (87 measured at 1024² and 2048², rounded up for what the metrics may add).
pub const COMPARE_BYTES_PER_PIXEL: u64 = 112;
/// A glTF vertex while loading and posing: its attributes as read (position, normal, uv: 32
/// bytes), the bind vertex (92), its influences (32) and the posed copy (92).
const GLTF_BYTES_PER_VERTEX: u64 = 32 + 92 + 32 + 92;

/// Set-up triangles and their draws' vertices are kept until this many are pending (the
/// rasterizer's auto-flush).
const PENDING_ENTRIES: u64 = 1 << 20;

/// How big the mesh is: triangles and vertices.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MeshSize {
    /// Triangles.
    pub triangles: u64,
    /// Vertices (an upper estimate for OBJ files: three per triangle).
    pub vertices: u64,
    /// For OBJ files, the `v`, `vt` and `vn` statements read (0 for procedural meshes).
    pub file_attributes: u64,
    /// For glTF models, the bytes held while loading and posing: the file, its buffers, the
    /// decoded animation keys and the bind mesh with its influences (0 otherwise).
    pub model_bytes: u64,
}

/// The mesh size a scene asks for: exact for procedural meshes (from their segment counts), a
/// streaming scan for OBJ files (which also finds malformed lines, naming them).
pub fn mesh_size(scene: &Scene) -> Result<MeshSize, MeshError> {
    let m = &scene.mesh;
    let grid = |(a, b): (u32, u32)| {
        let (a, b) = (u64::from(a), u64::from(b));
        MeshSize {
            triangles: 2 * a * b,
            vertices: (a + 1) * (b + 2),
            file_attributes: 0,
            model_bytes: 0,
        }
    };
    Ok(match m.kind {
        MeshKind::Torus => grid(mesh::torus_segments(
            m.major_radius,
            m.minor_radius,
            m.model_resolution,
        )),
        MeshKind::Sphere => grid(mesh::sphere_segments(m.model_resolution)),
        MeshKind::Cylinder => grid(mesh::cylinder_segments(
            m.radius,
            m.height,
            m.model_resolution,
        )),
        MeshKind::Leg => grid(mesh::leg_segments(m.model_resolution)),
        MeshKind::Obj => {
            let path = scene.base_dir.join(m.path.clone().unwrap_or_default());
            let summary = mesh::obj::scan_obj(&path)?;
            MeshSize {
                triangles: summary.triangles,
                vertices: 3 * summary.triangles,
                file_attributes: summary.positions + summary.texcoords + summary.normals,
                model_bytes: 0,
            }
        }
        MeshKind::Gltf => {
            let path = scene.base_dir.join(m.path.clone().unwrap_or_default());
            let summary = mesh::gltf::scan(&path)?;
            // The file twice (read, and its binary chunk copied), each animation key as a
            // 16-byte value, and per vertex the bind vertex, its influences and its posed copy.
            MeshSize {
                triangles: summary.triangles,
                vertices: summary.vertices,
                file_attributes: 0,
                model_bytes: summary
                    .file_bytes
                    .saturating_mul(2)
                    .saturating_add(summary.animation_keys.saturating_mul(16))
                    .saturating_add(summary.vertices.saturating_mul(GLTF_BYTES_PER_VERTEX)),
            }
        }
    })
}

/// What a render does besides the one frame: how many frames, whether they are all kept (for
/// an animated GIF), and how many worker threads bake at once.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Workload {
    /// Frames rendered (1 for a still).
    pub frames: u32,
    /// Whether every frame is kept in memory (to write an animated GIF at the end).
    pub keep_frames: bool,
    /// Worker threads (bake grids are built one per thread).
    pub threads: u32,
    /// Whether the frame is exported (`pelage export`): the glTF buffer of the skin and every
    /// shell layer, and each texture's copy as it is encoded, are held too.
    pub export: bool,
}

impl Default for Workload {
    fn default() -> Self {
        Workload {
            frames: 1,
            keep_frames: false,
            threads: 1,
            export: false,
        }
    }
}

/// The estimated peak memory of a render, by part.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MemoryEstimate {
    /// Named contributions, bytes, in pipeline order.
    pub parts: Vec<(&'static str, u64)>,
}

impl MemoryEstimate {
    /// The sum of the parts (saturating).
    pub fn total(&self) -> u64 {
        self.parts
            .iter()
            .fold(0u64, |sum, (_, b)| sum.saturating_add(*b))
    }

    /// The largest part.
    pub fn largest(&self) -> (&'static str, u64) {
        self.parts
            .iter()
            .copied()
            .max_by_key(|&(_, b)| b)
            .unwrap_or(("nothing", 0))
    }
}

/// Saturating product of several counts.
fn product(factors: &[u64]) -> u64 {
    factors.iter().fold(1u64, |p, &f| p.saturating_mul(f))
}

/// The peak memory of rendering `scene` with a mesh of `mesh` size (see the module docs for
/// what is counted).
pub fn estimate_memory(scene: &Scene, mesh: MeshSize, work: &Workload) -> MemoryEstimate {
    let pixels = u64::from(scene.image.width) * u64::from(scene.image.height);
    let f = &scene.fur;
    let shells = u64::from(f.number_of_shells);
    let strands = u64::from(f.number_of_strands);
    let res = u64::from(f.texture_resolution);
    let side = res * u64::from(f.supersample);
    let threads = u64::from(work.threads.max(1));
    // The fin strip fitted to the shells holds at most as many strands as the tile
    // (`fur::bake_fin_for_shells`).
    let fin_strands = strands;
    let segments = u64::from(f.strand_resolution);
    let kept_frames = if work.keep_frames {
        u64::from(work.frames)
    } else {
        0
    };
    // Each pending draw keeps its set-up triangles and its vertices (which the triangles'
    // corners index) until the auto-flush; the last draw may overshoot by one draw's worth.
    let draw_entries = mesh.triangles.saturating_add(mesh.vertices);
    let pending = draw_entries
        .saturating_mul(shells + 2)
        .min(PENDING_ENTRIES.saturating_add(draw_entries));
    let mut parts = vec![
        ("the framebuffer", product(&[pixels, FRAMEBUFFER_PER_PIXEL])),
        (
            "the animation frames kept for the GIF",
            product(&[pixels, kept_frames, GIF_PER_PIXEL]),
        ),
        (
            "strands and their cones (fur.number_of_strands × fur.strand_resolution)",
            product(&[strands + fin_strands, STRAND_BYTES + segments * CONE_BYTES]),
        ),
        (
            "bake grids ((fur.texture_resolution × fur.supersample)² per worker thread)",
            product(&[side, side, shells.min(threads) + 1, SAMPLE_BYTES]).saturating_add(product(
                &[res, res, shells.min(threads) + 1, DOWNSAMPLE_PER_TEXEL],
            )),
        ),
        (
            "shell textures (fur.number_of_shells × fur.texture_resolution²)",
            product(&[shells + 1, res, res, SHELL_PER_TEXEL]).saturating_add(
                // A density map adds a band texture per layer (4 bytes per texel, its mips and
                // the 8-bit image it is built from).
                if scene.maps.density.is_some() {
                    product(&[shells + 1, res, res, 4 * 2 + 4])
                } else {
                    0
                },
            ),
        ),
        (
            "surface maps (at most 4 of 4096² texels, with mips)",
            product(&[
                [
                    &scene.maps.length,
                    &scene.maps.density,
                    &scene.maps.direction,
                    &scene.maps.colour,
                ]
                .iter()
                .filter(|m| m.is_some())
                .count() as u64,
                crate::render::maps::MAX_MAP_SIDE as u64,
                crate::render::maps::MAX_MAP_SIDE as u64,
                6,
            ]),
        ),
        (
            "the mesh",
            product(&[mesh.vertices, VERTEX_BYTES])
                .saturating_add(product(&[mesh.triangles, 12 + EDGE_BYTES_PER_TRIANGLE])),
        ),
        (
            "set-up triangles (mesh triangles × shells)",
            product(&[pending, SETUP_TRIANGLE_BYTES.max(CLIP_VERTEX_BYTES)]),
        ),
    ];
    if work.export {
        parts.push((
            "the exported meshes (mesh vertices × fur.number_of_shells, glTF)",
            // Each attribute is flattened, then copied into the buffer: twice its size.
            product(&[
                mesh.vertices,
                2 * (EXPORT_SKIN_VERTEX_BYTES + (shells + 1) * 12),
            ])
            .saturating_add(product(&[mesh.triangles, 2 * 12]))
            // The largest texture level copied out for encoding, and its PNG.
            .saturating_add(product(&[res, res, 2 * 4])),
        ));
    }
    if mesh.model_bytes > 0 {
        parts.push(("reading and posing the glTF model", mesh.model_bytes));
    }
    if mesh.file_attributes > 0 || scene.mesh.kind == MeshKind::Obj {
        parts.push((
            "reading the OBJ file",
            product(&[mesh.triangles, OBJ_BYTES_PER_TRIANGLE])
                .saturating_add(product(&[mesh.file_attributes, OBJ_BYTES_PER_ATTRIBUTE])),
        ));
    }
    MemoryEstimate { parts }
}

/// Bake work: supersample texel writes plus segment tests of the shell and fin bakes.
///
/// Each strand's cross-section covers `π·r²` of the tile, `r = fur.base_thickness`; a layer's
/// cones paint about `number_of_strands · π·r² · side²` texels, once per segment falling in the
/// layer (at least one: `max(1, strand_resolution / number_of_shells)`), over every layer; and
/// every layer tests every segment.
pub fn bake_work(scene: &Scene) -> u64 {
    let f = &scene.fur;
    let side = f64::from(f.texture_resolution) * f64::from(f.supersample);
    let shells = f64::from(f.number_of_shells);
    let strands = f64::from(f.number_of_strands);
    let segments = f64::from(f.strand_resolution);
    let r = f64::from(f.base_thickness);
    let coverage = strands * std::f64::consts::PI * r * r;
    let per_layer_segments = (segments / shells).max(1.0);
    let writes = shells * side * side * coverage * per_layer_segments;
    let tests = shells * strands * segments;
    // The fin: a side view of taller strands, about as much as one layer, baked once per round
    // of its fit to the shells and once more (`fur::bake_fin_for_shells`); the fitted strip
    // holds at most the tile's strands.
    let fin = 4.0 * (side * side * coverage + strands * segments);
    let total = writes + tests + fin;
    if total.is_finite() && total < u64::MAX as f64 {
        total as u64
    } else {
        u64::MAX
    }
}

/// The memory of `pelage compare` over images of `a` and `b` pixels (width × height, read from
/// their headers) held in files of `file_bytes` together: the files, and
/// [`COMPARE_BYTES_PER_PIXEL`] per pixel of the larger image.
pub fn compare_memory(a: (u32, u32), b: (u32, u32), file_bytes: u64) -> MemoryEstimate {
    let pixels = |(w, h): (u32, u32)| u64::from(w) * u64::from(h);
    MemoryEstimate {
        parts: vec![
            ("the image files", file_bytes),
            (
                "the images and the metrics' planes (width × height of the larger image)",
                product(&[pixels(a).max(pixels(b)), COMPARE_BYTES_PER_PIXEL]),
            ),
        ],
    }
}

/// The memory of building a sweep's contact sheet of `sheet` pixels (width × height) from
/// `thumbnails` pixels of thumbnails, decoding one point image of at most `largest_point`
/// pixels at a time: the sheet, its PNG, the thumbnails kept, one decoded point image and its
/// file.
pub fn contact_sheet_memory(sheet: u64, thumbnails: u64, largest_point: u64) -> MemoryEstimate {
    MemoryEstimate {
        parts: vec![
            (
                "the contact sheet and its PNG (points × thumbnails)",
                product(&[sheet, 4 + 4]),
            ),
            ("the contact sheet's thumbnails", product(&[thumbnails, 4])),
            (
                "the point image being scaled down, and its file",
                product(&[largest_point, 4 + 4]),
            ),
        ],
    }
}

/// Checks an estimate made outside a render (`compare`, a contact sheet) against `limit`.
pub fn check_memory(
    task: &'static str,
    estimate: MemoryEstimate,
    limit: u64,
) -> Result<MemoryEstimate, LimitError> {
    if estimate.total() > limit {
        Err(LimitError::Memory {
            task,
            estimate,
            limit,
        })
    } else {
        Ok(estimate)
    }
}

/// The limits a render is checked against.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Budgets {
    /// Memory, bytes ([`estimate_memory`]).
    pub memory: u64,
    /// Bake work ([`bake_work`]).
    pub bake_work: u64,
    /// Drawing work per frame ([`draw_work`]).
    pub draw_work: u64,
}

impl Default for Budgets {
    fn default() -> Self {
        Budgets {
            memory: DEFAULT_MAX_MEMORY,
            bake_work: DEFAULT_MAX_BAKE_WORK,
            draw_work: DEFAULT_MAX_DRAW_WORK,
        }
    }
}

/// Fragments a layer is counted to shade per pixel: a closed surface is crossed twice by most
/// rays that meet it (culling is off for shells), and folds add more in places.
const LAYER_OVERDRAW: u64 = 2;
/// A triangle's set-up (vertex stage, clipping, edge functions, binning) counted as this many
/// fragment evaluations: measured, 150 ns a set-up (10⁶ triangles × 10 draws in 1.5 s of one
/// core) against 4.8 ns a counted evaluation (the default scene).
const TRIANGLE_SETUP_WORK: u64 = 32;

/// The spots, stripes and burn matches a fragment evaluates.
pub fn effects(scene: &Scene) -> u64 {
    let matches = scene.burn.as_ref().map_or(0, |b| b.matches.len());
    (scene.spots.len() + scene.stripes.len() + matches) as u64
}

/// Drawing work of one frame: fragment evaluations, `image.width × image.height ×
/// (fur.number_of_shells + 1) × 2` fragments (the skin and every layer, each crossed about
/// twice) times `1 +` the spots, stripes and burn matches each evaluates; plus triangle
/// set-ups, `mesh triangles × (fur.number_of_shells + 2)` (skin, layers and fins) at 32 units
/// each. An upper estimate: level of detail and the view only lower it.
pub fn draw_work(scene: &Scene, mesh: MeshSize) -> u64 {
    let pixels = u64::from(scene.image.width) * u64::from(scene.image.height);
    let shells = u64::from(scene.fur.number_of_shells);
    let fragments = product(&[pixels, shells + 1, LAYER_OVERDRAW, 1 + effects(scene)]);
    let setups = product(&[mesh.triangles, shells + 2, TRIANGLE_SETUP_WORK]);
    fragments.saturating_add(setups)
}

/// A render refused because it would need more than a limit allows.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum LimitError {
    /// The memory estimate exceeds the limit.
    Memory {
        /// What needs it: "the render", "the comparison", "the contact sheet".
        task: &'static str,
        /// The estimate.
        estimate: MemoryEstimate,
        /// The limit, bytes.
        limit: u64,
    },
    /// The bake work exceeds the limit.
    BakeWork {
        /// The estimate.
        work: u64,
        /// The limit.
        limit: u64,
    },
    /// The drawing work of a frame exceeds the limit.
    DrawWork {
        /// The estimate.
        work: u64,
        /// The limit.
        limit: u64,
        /// Spots, stripes and burn matches per fragment.
        effects: u64,
    },
}

impl LimitError {
    /// The command-line flag that raises the limit.
    pub fn flag(&self) -> &'static str {
        match self {
            LimitError::Memory { .. } => "--max-memory",
            LimitError::BakeWork { .. } => "--max-work",
            LimitError::DrawWork { .. } => "--max-draw-work",
        }
    }
}

impl fmt::Display for LimitError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LimitError::Memory {
                task,
                estimate,
                limit,
            } => {
                let (part, bytes) = estimate.largest();
                write!(
                    f,
                    "{task} needs about {} of memory, more than the limit of {} (largest part: {part}, {})",
                    format_bytes(estimate.total()),
                    format_bytes(*limit),
                    format_bytes(bytes)
                )
            }
            LimitError::BakeWork { work, limit } => write!(
                f,
                "baking the fur needs about {:.3e} texel writes and segment tests, more than the limit of {:.3e} (fur.number_of_strands × fur.base_thickness² × (fur.texture_resolution × fur.supersample)² × fur.number_of_shells)",
                *work as f64, *limit as f64
            ),
            LimitError::DrawWork {
                work,
                limit,
                effects,
            } => write!(
                f,
                "drawing a frame needs about {:.3e} fragment evaluations and triangle set-ups, more than the limit of {:.3e} (image.width × image.height × (fur.number_of_shells + 1) × 2 fragments × (1 + {effects} spots, stripes and burn matches), plus mesh triangles × (fur.number_of_shells + 2) set-ups at 32 each)",
                *work as f64, *limit as f64
            ),
        }
    }
}

impl std::error::Error for LimitError {}

/// Checks a scene against both budgets; returns the memory estimate when it fits.
pub fn check(
    scene: &Scene,
    mesh: MeshSize,
    work: &Workload,
    budgets: &Budgets,
) -> Result<MemoryEstimate, LimitError> {
    let (max_memory, max_bake_work) = (budgets.memory, budgets.bake_work);
    let task = if work.export {
        "the export"
    } else {
        "the render"
    };
    let estimate = check_memory(task, estimate_memory(scene, mesh, work), max_memory)?;
    let bake = bake_work(scene);
    if bake > max_bake_work {
        return Err(LimitError::BakeWork {
            work: bake,
            limit: max_bake_work,
        });
    }
    let draw = draw_work(scene, mesh);
    if draw > budgets.draw_work {
        return Err(LimitError::DrawWork {
            work: draw,
            limit: budgets.draw_work,
            effects: effects(scene),
        });
    }
    Ok(estimate)
}

/// `1536` → `"1.5 KiB"`; binary units, one decimal.
pub fn format_bytes(bytes: u64) -> String {
    const UNITS: [&str; 6] = ["B", "KiB", "MiB", "GiB", "TiB", "PiB"];
    let mut value = bytes as f64;
    let mut unit = 0;
    while value >= 1024.0 && unit + 1 < UNITS.len() {
        value /= 1024.0;
        unit += 1;
    }
    if unit == 0 {
        format!("{bytes} B")
    } else {
        format!("{value:.1} {}", UNITS[unit])
    }
}

/// Parses a size: a whole number of bytes with an optional binary suffix `K`, `M`, `G`, `T`
/// (also written `KiB`, `KB`, …, any case): `"8G"`, `"512MiB"`, `"1048576"`.
pub fn parse_bytes(text: &str) -> Result<u64, String> {
    let t = text.trim();
    let digits = t.find(|c: char| !c.is_ascii_digit()).unwrap_or(t.len());
    let (number, suffix) = t.split_at(digits);
    let number: u64 = number
        .parse()
        .map_err(|_| format!("{text:?} is not a size (a whole number, e.g. 8G, 512M, 1048576)"))?;
    let shift = match suffix.trim().to_ascii_lowercase().as_str() {
        "" | "b" => 0,
        "k" | "kb" | "kib" => 10,
        "m" | "mb" | "mib" => 20,
        "g" | "gb" | "gib" => 30,
        "t" | "tb" | "tib" => 40,
        other => {
            return Err(format!(
                "{text:?}: unknown unit {other:?} (use K, M, G or T)"
            ));
        }
    };
    number
        .checked_mul(1u64 << shift)
        .ok_or_else(|| format!("{text:?} is too large"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counted_sizes_cover_the_rasterizers_structures() {
        use crate::raster::clip::ClipVertex;
        use crate::raster::setup::SetupTriangle;
        use crate::render::fragment::FurVaryings;
        let corners_and_bin = 12 + 4;
        assert!(
            SETUP_TRIANGLE_BYTES >= (size_of::<SetupTriangle>() + corners_and_bin) as u64,
            "{} bytes counted, {} used",
            SETUP_TRIANGLE_BYTES,
            size_of::<SetupTriangle>() + corners_and_bin
        );
        let screen = size_of::<(crate::raster::setup::ScreenVertex, bool)>();
        assert!(CLIP_VERTEX_BYTES >= (size_of::<ClipVertex<FurVaryings>>() + screen) as u64);
    }
    use std::path::Path;

    fn scene(text: &str) -> Scene {
        Scene::parse(text, "t.toml", Path::new(".")).expect("valid scene")
    }

    #[test]
    fn reference_sized_scenes_fit_easily() {
        let s = scene("");
        let size = mesh_size(&s).expect("procedural");
        assert!(size.triangles > 400 && size.triangles < 600, "{size:?}");
        let e = estimate_memory(&s, size, &Workload::default());
        assert!(e.total() < 256 << 20, "{e:?}");
        assert!(check(&s, size, &Workload::default(), &Budgets::default()).is_ok());
        assert!(bake_work(&s) < DEFAULT_MAX_BAKE_WORK / 100);
        assert!(draw_work(&s, size) < DEFAULT_MAX_DRAW_WORK / 100);
    }

    #[test]
    fn drawing_work_counts_every_effect_per_fragment_and_triangles_per_shell() {
        let plain = scene("[image]\nwidth = 100\nheight = 10\n[fur]\nnumber_of_shells = 9\n");
        let size = MeshSize {
            triangles: 1000,
            vertices: 600,
            file_attributes: 0,
            model_bytes: 0,
        };
        // 1000 pixels × 10 layers × 2, one evaluation each; 1000 triangles × 11 × 32.
        assert_eq!(draw_work(&plain, size), 20_000 + 352_000);
        let spotted = scene(
            "[image]\nwidth = 100\nheight = 10\n[fur]\nnumber_of_shells = 9\n\
             [[spots]]\n[[spots]]\n[[stripes]]\n[burn]\nmatches = [[0, 1, 0], [1, 0, 0]]\n",
        );
        assert_eq!(effects(&spotted), 5);
        assert_eq!(draw_work(&spotted, size), 6 * 20_000 + 352_000);
        let budgets = Budgets {
            draw_work: 400_000,
            ..Budgets::default()
        };
        assert!(check(&plain, size, &Workload::default(), &budgets).is_ok());
        let err = check(&spotted, size, &Workload::default(), &budgets).unwrap_err();
        assert_eq!(err.flag(), "--max-draw-work");
        let msg = err.to_string();
        assert!(msg.contains("4.720e5"), "{msg}");
        assert!(msg.contains("5 spots, stripes and burn matches"), "{msg}");
    }

    #[test]
    fn huge_scenes_are_refused_naming_the_largest_part() {
        let s =
            scene("[fur]\nnumber_of_shells = 256\ntexture_resolution = 2048\nsupersample = 4\n");
        let size = mesh_size(&s).expect("procedural");
        let err = check(
            &s,
            size,
            &Workload {
                threads: 16,
                ..Workload::default()
            },
            &Budgets {
                memory: DEFAULT_MAX_MEMORY,
                bake_work: u64::MAX,
                draw_work: u64::MAX,
            },
        )
        .unwrap_err();
        let msg = err.to_string();
        assert!(msg.contains("more than the limit of 8.0 GiB"), "{msg}");
        assert!(
            msg.contains("bake grids") || msg.contains("shell textures"),
            "{msg}"
        );
        // Many frames kept for a GIF of a big image.
        let s = scene("[image]\nwidth = 4096\nheight = 4096\n");
        let work = Workload {
            frames: 2000,
            keep_frames: true,
            ..Workload::default()
        };
        let err = check(
            &s,
            mesh_size(&s).unwrap(),
            &work,
            &Budgets {
                memory: DEFAULT_MAX_MEMORY,
                bake_work: u64::MAX,
                draw_work: u64::MAX,
            },
        )
        .unwrap_err();
        assert!(err.to_string().contains("animation frames"), "{err}");
        // Thick strands by the million: memory is small, the bake would take days.
        let s = scene(
            "[fur]\nnumber_of_strands = 1000000\nbase_thickness = 0.2\ntexture_resolution = 1024\n",
        );
        let err = check(
            &s,
            mesh_size(&s).unwrap(),
            &Workload::default(),
            &Budgets {
                memory: u64::MAX,
                bake_work: DEFAULT_MAX_BAKE_WORK,
                draw_work: u64::MAX,
            },
        )
        .unwrap_err();
        assert!(matches!(err, LimitError::BakeWork { .. }), "{err}");
    }

    #[test]
    fn an_export_needs_more_than_the_render_and_compare_and_sheets_are_estimated() {
        let s = scene("[fur]\nnumber_of_shells = 64\n");
        let size = mesh_size(&s).expect("procedural");
        let render = estimate_memory(&s, size, &Workload::default());
        let export = estimate_memory(
            &s,
            size,
            &Workload {
                export: true,
                ..Workload::default()
            },
        );
        let extra = export.total() - render.total();
        // At least every shell's positions, 12 bytes per vertex per layer.
        assert!(extra >= size.vertices * 64 * 12, "{extra}");
        let err = check(
            &s,
            size,
            &Workload {
                export: true,
                ..Workload::default()
            },
            &Budgets {
                memory: render.total(),
                bake_work: u64::MAX,
                draw_work: u64::MAX,
            },
        )
        .unwrap_err();
        assert!(
            err.to_string().starts_with("the export needs about"),
            "{err}"
        );
        // Compare: the larger image counts, whatever the other.
        let c = compare_memory((2048, 2048), (16, 16), 1000);
        assert_eq!(c.total(), 1000 + 2048 * 2048 * COMPARE_BYTES_PER_PIXEL);
        let err = check_memory("the comparison", c, 256 << 20).unwrap_err();
        assert!(
            err.to_string().starts_with("the comparison needs about"),
            "{err}"
        );
        let sheet = contact_sheet_memory(1000, 100, 10);
        assert_eq!(sheet.total(), 8000 + 400 + 80);
        assert!(check_memory("the contact sheet", sheet.clone(), 8480).is_ok());
        assert!(check_memory("the contact sheet", sheet, 8479).is_err());
    }

    #[test]
    fn sizes_parse_and_print() {
        assert_eq!(parse_bytes("8G"), Ok(8 << 30));
        assert_eq!(parse_bytes("512MiB"), Ok(512 << 20));
        assert_eq!(parse_bytes("1048576"), Ok(1 << 20));
        assert_eq!(parse_bytes(" 2 t "), Ok(2 << 40));
        assert!(parse_bytes("").is_err());
        assert!(parse_bytes("-1G").is_err());
        assert!(parse_bytes("8X").is_err());
        assert!(parse_bytes("99999999999999999999").is_err());
        assert!(parse_bytes("20000000T").is_err());
        assert_eq!(format_bytes(1536), "1.5 KiB");
        assert_eq!(format_bytes(8 << 30), "8.0 GiB");
        assert_eq!(format_bytes(12), "12 B");
    }
}
