//! Robustness checks (beside the pipeline) shared by the fuzz targets (`fuzz/`, cargo-fuzz, nightly
//! features) and the property tests (`tests/robustness.rs`, fixed seeds, run by `cargo test`): each
//! function takes arbitrary input, pushes it through one input path of the pipeline, and panics
//! only when an invariant breaks. Refusing bad input with an error is the expected outcome, never a
//! failure.
//!
//! - [`scene_text`]: the scene parser and validator, then the resource estimates.
//! - [`obj_bytes`]: the OBJ loader (line scan, tobj, merge, box projection), tangent frames,
//!   shell extrusion and fin edges. Invariant: every loaded vertex is finite with a unit normal
//!   and an orthonormal frame; extruded shells and silhouette fins are finite.
//! - [`triangle`]: clipping, triangle setup, binning and rasterization of one triangle with
//!   arbitrary clip coordinates (NaN, infinities, 1e30, crossing the camera plane). Invariant:
//!   set-up bounds lie inside the viewport and the float framebuffer holds no NaN.
//! - [`sweep_files`]: `sweep.txt` and `results.csv` as `sweep-merge` reads them, then the merge
//!   and the plots. Invariant: what parses merges or is refused, and every plot draws.
//! - [`image_bytes`]: `compare`'s image decoding (PNG 8/16-bit, OpenEXR, every format it
//!   reads). Invariant: a decoded image matches itself exactly, heat maps included.
//! - [`map_bytes`]: a scene's PNG map. Invariant: a decoded map samples to values in 0..=1.

use crate::limits::{self, MeshSize, Workload};
use crate::mesh::{self, FinWindows, Mesh};
use crate::raster::{
    BlendMode, ClipVertex, CullMode, DepthCompare, DrawState, Frame, Framebuffer, clip, setup,
};
use crate::scene::Scene;
use crate::sweep;
use glam::{Vec2, Vec3, Vec4};
use std::path::Path;

/// Parses and validates `text` as a scene; when it is accepted, estimates its memory and bake
/// work (which must not overflow or panic) and checks that it validates again.
pub fn scene_text(text: &str) {
    let Ok(scene) = Scene::parse(text, "fuzz.toml", Path::new(".")) else {
        return;
    };
    scene
        .revalidate("fuzz.toml")
        .expect("a parsed scene validates again");
    let size = match limits::mesh_size(&scene) {
        Ok(size) => size,
        // OBJ scenes name files that do not exist here.
        Err(_) => MeshSize {
            triangles: 1,
            vertices: 3,
            file_attributes: 0,
            model_bytes: 0,
        },
    };
    let estimate = limits::estimate_memory(&scene, size, &Workload::default());
    assert!(estimate.total() > 0);
    let _ = limits::bake_work(&scene);
}

/// Checks the invariants every mesh must hold (see the module docs); panics naming the first
/// vertex that breaks one.
pub fn check_mesh(mesh: &Mesh) {
    mesh.validate().expect("indices in range");
    for (i, v) in mesh.vertices.iter().enumerate() {
        assert!(v.position.is_finite(), "vertex {i}: position {v:?}");
        assert!(v.uv.is_finite(), "vertex {i}: uv {v:?}");
        assert!(
            v.dpdu.is_finite() && v.dpdv.is_finite(),
            "vertex {i}: {v:?}"
        );
        let f = v.frame;
        for (name, axis) in [
            ("normal", v.normal),
            ("tangent", f.tangent),
            ("binormal", f.binormal),
        ] {
            assert!(
                axis.is_finite() && (axis.length() - 1.0).abs() < 1e-3,
                "vertex {i}: {name} is not a unit vector: {v:?}"
            );
        }
        assert!(
            f.tangent.dot(f.normal).abs() < 1e-3 && f.binormal.dot(f.normal).abs() < 1e-3,
            "vertex {i}: frame not orthogonal: {v:?}"
        );
    }
}

/// Loads `bytes` as an OBJ file; when it is accepted, checks the mesh ([`check_mesh`]), extrudes
/// shells and selects fin edges from a few eyes, all of which must stay finite.
pub fn obj_bytes(bytes: &[u8]) {
    let Ok(loaded) = mesh::load_obj_bytes(bytes, Path::new("fuzz.obj")) else {
        return;
    };
    check_mesh(&loaded.mesh);
    shells_and_fins(&loaded.mesh);
}

/// Loads `bytes` as a glTF or GLB file (no external files: only the GLB chunk and data URIs);
/// when it is accepted, poses it at rest and at a few instants of every clip, checking each
/// posed mesh ([`check_mesh`]) and its shells and fins.
pub fn gltf_bytes(bytes: &[u8]) {
    let Ok(character) = mesh::gltf::load_bytes(bytes, Path::new("fuzz.glb"), None, None, 1.0)
    else {
        return;
    };
    let rig = &character.rig;
    let rest = mesh::skin::pose(&character.bind, &rig.influences, &rig.rest_palette());
    check_posed(&rest);
    for (index, clip) in character.clips.iter().enumerate() {
        if character.morph_clips[index] {
            continue;
        }
        for time in [0.0, 0.37, 1.0e3] {
            let t = clip.clip_time(time, 1.0, true);
            let palette = rig.palette(&clip.sample(&rig.skeleton.rest, t));
            check_posed(&mesh::skin::pose(
                &character.bind,
                &rig.influences,
                &palette,
            ));
        }
    }
}

/// A posed mesh: finite positions give finite frames, shells and fins. (A pose may place
/// vertices anywhere a file's transforms send them, overflow included: those are skipped.)
fn check_posed(mesh: &Mesh) {
    if mesh
        .vertices
        .iter()
        .all(|v| v.position.is_finite() && v.position.abs().max_element() < 1e18)
    {
        for (i, v) in mesh.vertices.iter().enumerate() {
            let f = v.frame;
            assert!(
                f.tangent.is_finite() && f.binormal.is_finite() && f.normal.is_finite(),
                "posed vertex {i}: frame not finite: {v:?}"
            );
        }
    }
}

/// Shell extrusion at a few offsets and fin selection from a few eyes: all finite.
pub fn shells_and_fins(mesh: &Mesh) {
    for offset in [0.0, 0.37, 10.0] {
        for (i, p) in mesh::extrude(mesh, offset).iter().enumerate() {
            assert!(p.is_finite(), "shell at {offset}: vertex {i} at {p}");
        }
    }
    let edges = mesh::edges(mesh);
    let windows = FinWindows {
        windows: vec![(70.0, 110.0), (160.0, 200.0)],
    };
    for eye in [Vec3::new(0.0, 2.0, 9.0), Vec3::ZERO, Vec3::splat(1e30)] {
        for e in mesh::silhouette_edges(mesh, &edges, eye, &windows) {
            let edge = &edges[e];
            assert!(
                edge.vertices
                    .iter()
                    .all(|&v| (v as usize) < mesh.vertices.len())
            );
        }
    }
}

/// Side of the framebuffer [`triangle`] rasterizes into.
const RASTER_SIZE: (u32, u32) = (40, 24);

/// [`triangle`] from raw bytes, as the `triangle` fuzz target feeds it: 12 little-endian `f32`
/// (three clip-space vertices), a `u16` width and height, and a byte choosing the cull mode.
/// Shorter inputs do nothing.
pub fn triangle_bytes(data: &[u8]) {
    if data.len() < 53 {
        return;
    }
    let f = |i: usize| {
        f32::from_le_bytes([
            data[4 * i],
            data[4 * i + 1],
            data[4 * i + 2],
            data[4 * i + 3],
        ])
    };
    let v = |k: usize| Vec4::new(f(4 * k), f(4 * k + 1), f(4 * k + 2), f(4 * k + 3));
    let size = |i: usize| u32::from(u16::from_le_bytes([data[i], data[i + 1]]));
    let cull = [CullMode::None, CullMode::Back, CullMode::Front][usize::from(data[52] % 3)];
    triangle([v(0), v(1), v(2)], size(48), size(50), cull);
}

/// Clips and sets up the triangle `clip` (clip-space positions) for a `width`×`height`
/// viewport and checks its bounds; then draws it, blended and depth-tested, into a small
/// framebuffer with its clip coordinates as varyings and checks that no pixel became NaN.
pub fn triangle(clip: [Vec4; 3], width: u32, height: u32, cull: CullMode) {
    let width = width.clamp(1, setup::MAX_DIMENSION);
    let height = height.clamp(1, setup::MAX_DIMENSION);
    let vertices = clip.map(|position| ClipVertex {
        position,
        varyings: (),
    });
    // Setup alone, unclipped: refuses what is outside the guard band, never overflows.
    if let Some((s, _)) = setup::setup_triangle(&vertices, width, height, cull) {
        let b = s.bounds;
        assert!(b.x1 <= width && b.y1 <= height, "{b:?}");
    }
    clip::clip_triangle(vertices, |t| {
        for v in &t {
            let p = v.position;
            assert!(p.is_finite() && p.w > 0.0, "clipped vertex {p}");
        }
        if let Some((s, _)) = setup::setup_triangle(&t, width, height, cull) {
            let b = s.bounds;
            assert!(
                b.x0 < b.x1 && b.x1 <= width && b.y0 < b.y1 && b.y1 <= height,
                "{b:?}"
            );
            assert!(s.inv_area.is_finite() && s.inv_area > 0.0);
        }
    });

    let (w, h) = RASTER_SIZE;
    let mut fb = Framebuffer::new(w, h, 8, Vec4::new(0.1, 0.2, 0.3, 1.0)).expect("framebuffer");
    let mut frame = Frame::new(&mut fb);
    let state = DrawState {
        depth_compare: DepthCompare::LessEqual,
        depth_write: true,
        blend: BlendMode::Alpha,
        cull,
    };
    let draw = frame.draw(
        &clip,
        &[[0, 1, 2], [2, 1, 0]],
        state,
        |p: &Vec4| ClipVertex {
            position: *p,
            varyings: [p.x, p.y, p.z, p.w],
        },
        |f| {
            let [x, y, z, w] = *f.varyings();
            // A colour from the interpolated varyings, bounded so only NaN can escape.
            let c = Vec4::new(x, y, z, w).clamp(Vec4::splat(-1e6), Vec4::splat(1e6));
            Some(Vec4::new(c.x.fract(), c.y.fract(), c.z.fract(), 0.5))
        },
    );
    draw.expect("indices in range");
    frame.finish();
    for (i, c) in fb.to_rgba_f32().iter().enumerate() {
        assert!(!c.is_nan(), "pixel {i} is {c}");
    }
}

/// `data` as a sweep folder's two files, as `sweep-merge` reads them: the manifest (`sweep.txt`),
/// a 0 byte, then `results.csv` (without a 0 byte, all of `data` is the results). The manifest
/// is checked against the rows' points; the results are merged, written back and plotted.
pub fn sweep_files(data: &[u8]) {
    let (manifest, results) = match data.iter().position(|&b| b == 0) {
        Some(i) => (Some(&data[..i]), &data[i + 1..]),
        None => (None, data),
    };
    let results = String::from_utf8_lossy(results);
    let Ok(parsed) = sweep::parse_results(&results, "results.csv") else {
        return;
    };
    if let Some(text) = manifest
        && let Ok(m) = sweep::Manifest::parse(&String::from_utf8_lossy(text), "sweep.txt")
    {
        let points = parsed.rows.iter().map(|r| r.point).collect();
        let _ = sweep::check_shards(&[("shard".to_string(), m, points)]);
    }
    let Ok(merged) = sweep::merge_results(&[("results.csv".to_string(), results.to_string())])
    else {
        return;
    };
    assert_eq!(
        merged.rows.len(),
        parsed.rows.len(),
        "a merge keeps every row"
    );
    if let Ok(text) = sweep::write_results(&merged.parameters, &merged.rows) {
        let again = sweep::parse_results(&text, "written.csv").expect("written results read");
        assert_eq!(again.parameters, merged.parameters);
        assert_eq!(again.rows.len(), merged.rows.len());
    }
    for metric in sweep::Metric::ALL {
        sweep::metric_plot(&merged.parameters, &merged.rows, metric).expect("a plot draws");
    }
}

/// `data` as an image file, decoded as `compare` decodes its inputs; a decoded image compared
/// with itself passes the exact tier, and its heat maps are drawn.
pub fn image_bytes(data: &[u8]) {
    let Ok(image) = crate::input::decode_image(data, Path::new("fuzz.png"), "image") else {
        return;
    };
    let exact = crate::compare::Tolerance::exact();
    let result = crate::compare::compare_images(&image, &image, &exact).expect("same size");
    assert!(result.passed(), "an image differs from itself: {result:?}");
    crate::compare::heat_map(&image, &image).expect("heat map");
    crate::compare::flip_heat_map(&image, &image).expect("FLIP map");
}

/// `data` as a scene's PNG map (`maps.length`); a decoded map samples to values in 0..=1.
pub fn map_bytes(data: &[u8]) {
    let Ok(texture) =
        crate::render::maps::decode_png_map("maps.length", Path::new("fuzz.png"), data)
    else {
        return;
    };
    let mut maps = crate::render::maps::SurfaceMaps::none();
    maps.length = Some(texture);
    for uv in [
        Vec2::ZERO,
        Vec2::splat(0.5),
        Vec2::new(0.999, 0.001),
        Vec2::splat(7.3),
    ] {
        let length = maps.length_at(uv);
        assert!((0.0..=1.0).contains(&length), "length {length} at {uv}");
    }
}
