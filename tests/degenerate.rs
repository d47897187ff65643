//! Degenerate geometry renders whole scenes without panicking and without NaN: zero-area faces,
//! repeated vertices, coordinates of 1e30, UVs all equal, faces with missing normals or UVs,
//! non-manifold meshes, triangles crossing the camera plane, a camera inside the mesh. NaN and
//! infinite coordinates are refused by the loader with an error naming the line.
//!
//! What "without NaN" is checked on: every mesh attribute and extruded shell
//! (`pelage::robust::check_mesh`, `shells_and_fins`), and every pixel of the rendered image
//! being opaque (fur is blended over an opaque background, and a NaN anywhere in a pixel's
//! blend chain would make its alpha NaN, quantised to 0). The float framebuffer itself is
//! checked on random triangles with NaN, infinite and huge coordinates by
//! `tests/robustness.rs` (`pelage::robust::triangle`).

use pelage::mesh::{MeshError, load_obj};
use pelage::render::PreparedScene;
use pelage::scene::Scene;
use std::path::{Path, PathBuf};

fn dir() -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("degenerate");
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir
}

/// A small, cheap scene around `mesh` (TOML for the `[mesh]` table) seen from `eye`.
fn scene(mesh: &str, eye: [f32; 3], extra: &str) -> String {
    format!(
        "[image]\nwidth = 48\nheight = 36\n[camera]\neye = {eye:?}\ntarget = [0.0, 0.1, 0.0]\nnear = 0.05\n\
         [mesh]\n{mesh}\n[fur]\nnumber_of_strands = 60\nnumber_of_shells = 4\ntexture_resolution = 16\n\
         model_difference = 0.1\n{extra}"
    )
}

/// Renders the scene text and checks the image: right size, every pixel opaque.
fn render(name: &str, text: &str) -> Vec<u8> {
    let scene = Scene::parse(text, name, &dir()).unwrap_or_else(|e| panic!("{name}: {e}"));
    let prepared = PreparedScene::new(&scene).unwrap_or_else(|e| panic!("{name}: {e}"));
    pelage::robust::check_mesh(prepared.mesh());
    pelage::robust::shells_and_fins(prepared.mesh());
    let image = prepared
        .render(16)
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    assert_eq!(image.rgba8.len(), 48 * 36 * 4, "{name}");
    for (i, px) in image.rgba8.chunks_exact(4).enumerate() {
        assert_eq!(
            px[3], 255,
            "{name}: pixel {i} is {px:?} (NaN in its blend chain?)"
        );
    }
    image.rgba8
}

fn render_obj(name: &str, obj: &str, eye: [f32; 3], extra: &str) -> Vec<u8> {
    let file = format!("{name}.obj");
    std::fs::write(dir().join(&file), obj).expect("write obj");
    render(
        name,
        &scene(&format!("kind = \"obj\"\npath = \"{file}\""), eye, extra),
    )
}

const EYE: [f32; 3] = [0.4, 1.2, 3.0];

/// Two triangles of a unit quad with UVs: the healthy part every degenerate mesh adds to.
const QUAD: &str = "v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
                    f 1/1 4/4 3/3\nf 1/1 3/3 2/2\n";

#[test]
fn zero_area_faces_and_repeated_vertices() {
    let obj = format!(
        "{QUAD}v 0 0 0\nv 0 0 0\nv 0.5 0 0\nv 1 0 0\nvt 0.5 0.5\n\
         f 5/5 6/5 7/5\nf 5/5 7/5 8/5\nf 1/1 1/1 2/2\nf 3/3 3/3 3/3\n"
    );
    render_obj("zero-area", &obj, EYE, "");
}

#[test]
fn huge_coordinates() {
    // A whole tetrahedron at 1e18 (the largest coordinates accepted), seen from far away, and
    // one vertex at 1e18 among small ones.
    let far = "v 0 0 0\nv 1e18 0 0\nv 0 1e18 0\nv 0 0 1e18\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
    render_obj("huge", far, [6e18, 4e18, 8e18], "");
    // Farther, the view vector's length overflows f32: refused, never a background-only image.
    let text = scene(
        "kind = \"obj\"\npath = \"huge.obj\"",
        [3e30, 2e30, 4e30],
        "",
    );
    let err = Scene::parse(&text, "too-far", &dir()).unwrap_err();
    assert!(err.to_string().contains("camera.eye"), "{err}");
    let spike = format!("{QUAD}v 0 1e18 0\nvt 0.5 0.5\nf 1/1 2/2 5/5\nf 2/2 3/3 5/5\n");
    render_obj("spike", &spike, EYE, "[wind]\nstrength = 0.8\n");
    let tiny = "v 0 0 0\nv 1e-30 0 0\nv 0 1e-30 0\nf 1 2 3\n";
    render_obj("tiny", tiny, EYE, "");
}

#[test]
fn uvs_all_equal_missing_uvs_and_missing_normals() {
    let same = "v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nvt 0.3 0.3\nf 1/1 4/1 3/1\nf 1/1 3/1 2/1\n";
    render_obj("same-uv", same, EYE, "[wind]\nstrength = 1.0\n");
    // Some corners have UVs and normals, some do not.
    let mixed = "v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nvt 0 0\nvn 0 1 0\n\
                 f 1/1/1 4//1 3\nf 1 3/1 2//1\n";
    render_obj("mixed", mixed, EYE, "");
    let collinear_uv = format!("{QUAD}vt 0 0\nvt 1 1\nvt 2 2\nf 1/5 2/6 3/7\n");
    render_obj("collinear-uv", &collinear_uv, EYE, "");
}

#[test]
fn non_manifold_meshes() {
    // Three faces share the edge 1–2; a bow-tie shares only vertex 3; one face is flipped.
    let obj = "v 0 0 0\nv 1 0 0\nv 0.5 1 0\nv 0.5 -1 0\nv 0.5 0 1\nv 1.5 1.5 0\nv -0.5 1.5 0\n\
               vt 0 0\nvt 1 0\nvt 0.5 1\nvt 0.5 0\nvt 0 1\nvt 1 1\nvt 0 1\n\
               f 1/1 2/2 3/3\nf 2/2 1/1 4/4\nf 1/1 2/2 5/5\nf 3/3 6/6 7/7\nf 3/3 2/2 1/1\n";
    render_obj(
        "non-manifold",
        obj,
        EYE,
        "[burn]\nmatches = [[0, 1, 0]]\nstart = 0.0\n",
    );
}

#[test]
fn camera_inside_the_mesh_and_triangles_crossing_the_camera_plane() {
    let cube = "v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n\
                f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";
    render_obj("inside-cube", cube, [0.1, 0.2, 0.3], "");
    // The eye exactly on a vertex and on a face of the cube.
    render_obj("on-vertex", cube, [1.0, 1.0, 1.0], "");
    render_obj("on-face", cube, [0.0, 0.0, 1.0], "");
    // Procedural meshes around the eye: inside a sphere, inside the torus's tube, on the
    // cylinder's axis.
    let sphere = "kind = \"sphere\"\nradius = 2.0";
    render("inside-sphere", &scene(sphere, [0.2, 0.1, 0.3], ""));
    let torus = "kind = \"torus\"\nmajor_radius = 2.0\nminor_radius = 0.8";
    render("inside-torus", &scene(torus, [2.0, 0.3, 0.1], ""));
    render("torus-skin", &scene(torus, [2.8, 0.0, 0.0], "[wind]\n"));
    let cylinder = "kind = \"cylinder\"\nradius = 1.0\nheight = 4.0";
    render("in-cylinder", &scene(cylinder, [0.0, -1.5, 0.01], ""));
}

#[test]
fn non_finite_coordinates_are_refused_naming_the_line() {
    for (name, obj, line) in [
        ("nan", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n", 2),
        ("inf", "v 0 0 0\nv 1 0 0\nv 0 -inf 0\nf 1 2 3\n", 3),
        ("overflow", "v 0 0 0\nv 1 0 0\nv 0 1e39 0\nf 1 2 3\n", 3),
    ] {
        let path = dir().join(format!("{name}.obj"));
        std::fs::write(&path, obj).expect("write");
        match load_obj(&path) {
            Err(MeshError::NonFinite { line: Some(l), .. }) => assert_eq!(l, line, "{name}"),
            other => panic!("{name}: {other:?}"),
        }
    }
    // Finite, but products of coordinates (normals, areas) would overflow f32.
    for (name, obj, line) in [
        ("products", "v 0 0 0\nv 1e30 0 0\nv 0 1 0\nf 1 2 3\n", 2),
        ("negative", "v 0 0 0\nv 1 0 0\nv 0 0 -2e18\nf 1 2 3\n", 3),
    ] {
        let path = dir().join(format!("{name}.obj"));
        std::fs::write(&path, obj).expect("write obj");
        match load_obj(&path) {
            Err(MeshError::Syntax {
                line: l, message, ..
            }) => {
                assert_eq!(l, line, "{name}");
                assert!(message.contains("would overflow f32"), "{name}: {message}");
            }
            other => panic!("{name}: {other:?}"),
        }
    }
}

#[test]
fn meshes_without_a_face_of_non_zero_area_are_refused_naming_the_first_face() {
    // Points, a line, and a face repeating one vertex: nothing to grow fur on.
    let obj = "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\n# faces\nf 1 2 3\nf 4 4 4\nf 1 1 2\n";
    let path = dir().join("no-area.obj");
    std::fs::write(&path, obj).expect("write obj");
    match load_obj(&path) {
        Err(MeshError::Syntax { line, message, .. }) => {
            assert_eq!(line, 6);
            assert!(message.contains("none of the 3 faces"), "{message}");
        }
        other => panic!("{other:?}"),
    }
    // One real face among them is enough; so is a tiny one (its area is 5e-61, in f64).
    let one = format!("{obj}f 1 2 4\n");
    assert!(pelage::mesh::load_obj_bytes(one.as_bytes(), Path::new("one.obj")).is_ok());
    let tiny = "v 0 0 0\nv 1e-30 0 0\nv 0 1e-30 0\nf 1 2 3\n";
    assert!(pelage::mesh::load_obj_bytes(tiny.as_bytes(), Path::new("tiny.obj")).is_ok());
}

#[test]
fn same_degenerate_scene_same_bytes() {
    let obj = format!("{QUAD}v 0 1e18 0\nvt 0.5 0.5\nf 1/1 2/2 5/5\n");
    let a = render_obj("again-a", &obj, EYE, "");
    let b = render_obj("again-b", &obj, EYE, "");
    assert_eq!(a, b);
    assert!(Path::new(&dir()).exists());
}

#[test]
fn extreme_but_valid_parameters() {
    // Every effect at the edge of its range: vanishing spot radii and stripe period, zero
    // exponents and thresholds, the strongest wind at a distant instant, a match direction of
    // length 1e-18, a burn schedule of zero length.
    let text = "time = 1e6\n\
        [image]\nwidth = 48\nheight = 36\n\
        [fur]\nnumber_of_strands = 60\nnumber_of_shells = 4\ntexture_resolution = 16\n\
        [[spots]]\nradii = [1e-38, 1e-38, 1e-38]\n\
        [[spots]]\nkind = \"light\"\nexponent = 0.0\ninner_threshold = 0.0\nouter_threshold = 0.0\n\
        [[stripes]]\nperiod = 1e-6\nwidth = 0.0\nsoftness = 0.0\n\
        [wind]\nstrength = 10.0\nfrequency = 100.0\nelasticity = 0.0\nmax_bend = 1.0\n\
        [burn]\nmatches = [[1e-18, 0, 0]]\nhigh_exponent = 0.0\nlow_exponent = 0.0\nspread_duration = 0.0\n";
    render("extreme", text);
}
