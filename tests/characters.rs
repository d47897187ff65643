//! Characters: glTF models skinned and posed at the scene time, checked against an independent
//! double-precision skinning of the generated tail rig, frame by frame against `--time`, and
//! malformed files refused with one line naming the file and the JSON location.

#![allow(clippy::needless_range_loop)] // matrix entries indexed as the formulas write them

mod common;

use pelage::mesh::gltf::{self, ClipChoice};
use pelage::mesh::rig::TailRig;
use pelage::mesh::skin;
use pelage::render::PreparedScene;
use serde_json::{Value, json};
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn tail_json() -> Value {
    serde_json::from_str(&TailRig::default().to_gltf()).expect("the rig is JSON")
}

#[test]
fn the_committed_tail_is_the_generator_output() {
    let committed = std::fs::read_to_string(root().join("scenes/meshes/tail/tail.gltf"))
        .expect("scenes/meshes/tail/tail.gltf");
    assert!(
        committed == TailRig::default().to_gltf(),
        "scenes/meshes/tail/tail.gltf is stale: cargo run --example tail_rig"
    );
}

type M = [[f64; 4]; 4];

fn mul(a: &M, b: &M) -> M {
    let mut m = [[0.0; 4]; 4];
    for r in 0..4 {
        for c in 0..4 {
            m[r][c] = (0..4).map(|k| a[r][k] * b[k][c]).sum();
        }
    }
    m
}

fn translation(t: [f64; 3]) -> M {
    let mut m = [[0.0; 4]; 4];
    for (k, row) in m.iter_mut().enumerate() {
        row[k] = 1.0;
    }
    for k in 0..3 {
        m[k][3] = t[k];
    }
    m
}

fn rotation_z(angle: f64) -> M {
    let (s, c) = angle.sin_cos();
    [
        [c, -s, 0.0, 0.0],
        [s, c, 0.0, 0.0],
        [0.0, 0.0, 1.0, 0.0],
        [0.0, 0.0, 0.0, 1.0],
    ]
}

/// The tail's "Wag" clip at `t` in f64, from the rig's definition (not from the file): joint k
/// (k ≥ 1) turns about z by `angle(t)·(1 + 0.2k)`, the keys' angles 0, 0.5, 0, −0.5, 0 at
/// 0, 0.5, 1, 1.5, 2 s interpolated linearly (slerp about one axis is linear in the angle); the
/// root moves by `(x, 0, 0.1·x)`, x with keys 0, 0.2, 0, −0.2, 0.
fn wag_palette_f64(t: f64) -> Vec<M> {
    let keys = [0.0, 0.5, 0.0, -0.5, 0.0];
    let x_keys = [0.0, 0.2, 0.0, -0.2, 0.0];
    let k = ((t / 0.5).floor() as usize).min(3);
    let u = (t - 0.5 * k as f64) / 0.5;
    let angle = keys[k] + (keys[k + 1] - keys[k]) * u;
    let x = x_keys[k] + (x_keys[k + 1] - x_keys[k]) * u;
    let rig = TailRig::default();
    let spacing = f64::from(rig.length) / f64::from(rig.joints - 1);
    let mut globals: Vec<M> = Vec::new();
    for j in 0..rig.joints as usize {
        let local = if j == 0 {
            translation([x, 0.0, 0.1 * x])
        } else {
            mul(
                &translation([0.0, spacing, 0.0]),
                &rotation_z(angle * (1.0 + 0.2 * j as f64)),
            )
        };
        let global = if j == 0 {
            local
        } else {
            mul(&globals[j - 1], &local)
        };
        globals.push(global);
    }
    globals
        .iter()
        .enumerate()
        .map(|(j, g)| mul(g, &translation([0.0, -(j as f64) * spacing, 0.0])))
        .collect()
}

#[test]
fn posed_tail_matches_double_precision_skinning() {
    let path = root().join("scenes/meshes/tail/tail.gltf");
    let character = gltf::load(&path, None, 1.0).expect("the tail loads");
    let clip = character
        .clip_index(&ClipChoice::Name("Wag".into()), &path)
        .expect("Wag");
    let clip = &character.clips[clip];
    for t in [0.0f32, 0.3, 0.5, 0.75, 1.2, 1.9] {
        let palette = character
            .rig
            .palette(&clip.sample(&character.rig.skeleton.rest, t));
        let posed = skin::pose(&character.bind, &character.rig.influences, &palette);
        let expected = wag_palette_f64(f64::from(t));
        for (k, (rest, got)) in character
            .bind
            .vertices
            .iter()
            .zip(&posed.vertices)
            .enumerate()
        {
            let inf = character.rig.influences[k];
            let mut m = [[0.0f64; 4]; 4];
            for (j, w) in inf.joints.iter().zip(inf.weights) {
                for r in 0..4 {
                    for c in 0..4 {
                        m[r][c] += f64::from(w) * expected[*j as usize][r][c];
                    }
                }
            }
            let p = rest.position.to_array().map(f64::from);
            for r in 0..3 {
                let want = m[r][0] * p[0] + m[r][1] * p[1] + m[r][2] * p[2] + m[r][3];
                let g = f64::from(got.position[r]);
                assert!(
                    (g - want).abs() <= 2e-6 * (1.0 + want.abs()),
                    "t {t}, vertex {k}, axis {r}: {g} vs {want}"
                );
            }
            // Normals: the inverse transpose of M₃ (a rotation blend here), normalised.
            let n = rest.normal.to_array().map(f64::from);
            let a = |r: usize, c: usize| m[r][c];
            let cof = |r: usize, c: usize| {
                let (r1, r2, c1, c2) = ((r + 1) % 3, (r + 2) % 3, (c + 1) % 3, (c + 2) % 3);
                a(r1, c1) * a(r2, c2) - a(r1, c2) * a(r2, c1)
            };
            let mut want = [0.0; 3];
            for (r, w) in want.iter_mut().enumerate() {
                *w = (0..3).map(|c| cof(r, c) * n[c]).sum();
            }
            let len = want.iter().map(|v| v * v).sum::<f64>().sqrt();
            for r in 0..3 {
                let g = f64::from(got.normal[r]);
                assert!(
                    (g - want[r] / len).abs() < 1e-5,
                    "t {t}, vertex {k}, normal {r}: {g} vs {}",
                    want[r] / len
                );
            }
        }
    }
}

#[test]
fn every_interpolation_moves_the_tail_and_the_rest_pose_is_the_bind_pose() {
    let path = root().join("scenes/meshes/tail/tail.gltf");
    let character = gltf::load(&path, None, 1.0).expect("the tail loads");
    // Without a clip: the rest pose, which for this rig is the bind pose (the vertices as stored).
    let rest = skin::pose(
        &character.bind,
        &character.rig.influences,
        &character.rig.rest_palette(),
    );
    for (a, b) in rest.vertices.iter().zip(&character.bind.vertices) {
        assert!((a.position - b.position).length() < 1e-5);
    }
    for name in ["Wag", "Curl", "Pulse"] {
        let index = character
            .clip_index(&ClipChoice::Name(name.into()), &path)
            .expect(name);
        let clip = &character.clips[index];
        let posed = skin::pose(
            &character.bind,
            &character.rig.influences,
            &character
                .rig
                .palette(&clip.sample(&character.rig.skeleton.rest, 0.7)),
        );
        let moved = posed
            .vertices
            .iter()
            .zip(&rest.vertices)
            .map(|(a, b)| (a.position - b.position).length())
            .fold(0.0f32, f32::max);
        assert!(moved > 0.05, "{name} moves the tail by {moved} only");
    }
}

#[test]
fn fur_follows_the_posed_tail_and_frames_equal_their_instants() {
    let scene = common::scene("tail", 96, 72);
    let prepared = PreparedScene::new(&scene).expect("prepares");
    let still = prepared.render_at(0.0, 32).expect("renders").rgba8;
    let wagged = prepared.render_at(0.5, 32).expect("renders").rgba8;
    assert!(
        common::differing_pixels(&still, &wagged) > 100,
        "the wag must move the furred tail"
    );
    // Frame k at 4 fps is the render at time k/4, through the CLI.
    let dir = common::scratch("frames");
    let scene_path = root().join("scenes").join("tail.toml");
    let frames = dir.join("frames");
    let out = common::pelage(&[
        "render",
        scene_path.to_str().unwrap(),
        "--width",
        "96",
        "--height",
        "72",
        "--frames",
        "3",
        "--fps",
        "4",
        "-o",
        frames.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let at = dir.join("at.png");
    let out = common::pelage(&[
        "render",
        scene_path.to_str().unwrap(),
        "--width",
        "96",
        "--height",
        "72",
        "--time",
        "0.5",
        "-o",
        at.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let frame = std::fs::read(frames.join("frame_0002.png")).expect("frame 2");
    assert_eq!(
        frame,
        std::fs::read(&at).expect("at.png"),
        "frame 2 at 4 fps is --time 0.5"
    );
}

/// Writes `json` as `NAME.gltf` in a scratch folder and loads it.
fn load_json(name: &str, json: &Value) -> Result<gltf::Character, gltf::GltfError> {
    let dir = common::scratch(name);
    let path = dir.join(format!("{name}.gltf"));
    std::fs::write(&path, serde_json::to_vec(json).unwrap()).unwrap();
    gltf::load(&path, None, 1.0)
}

fn refused(name: &str, json: &Value, pointer: Option<&str>, words: &str) {
    let err = load_json(name, json).expect_err(name);
    let line = err.to_string();
    assert!(line.contains(&format!("{name}.gltf")), "{name}: {line}");
    if let Some(p) = pointer {
        assert_eq!(err.pointer.as_deref(), Some(p), "{name}: {line}");
    }
    assert!(line.contains(words), "{name}: {line}");
    assert!(!line.contains('\n'), "{name}: one line: {line}");
}

#[test]
fn malformed_models_are_refused_naming_file_and_location() {
    let base = tail_json();
    let edit = |f: &dyn Fn(&mut Value)| {
        let mut j = base.clone();
        f(&mut j);
        j
    };
    refused(
        "count",
        &edit(&|j| j["accessors"][0]["count"] = json!(1_000_000)),
        Some("/accessors/0"),
        "count 1000000 exceeds its buffer view",
    );
    refused(
        "index",
        &edit(&|j| {
            // Point the indices at the joints' view reinterpreted: values past the vertices.
            j["accessors"][4]["byteOffset"] = json!(0);
            j["accessors"][4]["bufferView"] = json!(0);
        }),
        Some("/accessors/4"),
        "past the primitive's",
    );
    refused(
        "joint",
        &edit(&|j| {
            j["skins"][0]["joints"] = json!([1, 2]);
        }),
        Some("/accessors/2"),
        "past the skin's 2 joints",
    );
    refused(
        "cycle",
        &edit(&|j| j["nodes"][4]["children"] = json!([1])),
        None,
        "cycle",
    );
    refused(
        "view",
        &edit(&|j| j["bufferViews"][0]["byteLength"] = json!(10_000_000)),
        Some("/bufferViews/0"),
        "exceeds its buffer",
    );
    for (name, uri) in [
        ("up", "../outside.bin"),
        ("absolute", "/etc/passwd"),
        ("file", "file:///etc/passwd"),
        ("web", "https://example.com/x.bin"),
    ] {
        refused(
            name,
            &edit(&|j| j["buffers"][0]["uri"] = json!(uri)),
            Some("/buffers/0"),
            "leaves the model's folder",
        );
    }
    refused(
        "base64",
        &edit(&|j| j["buffers"][0]["uri"] = json!("data:application/octet-stream;base64,@@@@")),
        Some("/buffers/0"),
        "base64",
    );
    refused(
        "points",
        &edit(&|j| j["meshes"][0]["primitives"][0]["mode"] = json!(0)),
        None,
        "no triangle primitives",
    );
    refused(
        "morph",
        &edit(&|j| {
            j["meshes"][0]["primitives"][0]["targets"] = json!([{"POSITION": 0}]);
            j["meshes"][0]["weights"] = json!([0.5]);
        }),
        None,
        "morph targets",
    );
    refused("json", &json!("not an object"), None, "invalid glTF JSON");
}

/// The tail's binary buffer, with `edit` applied to the floats of accessor `accessor`.
fn with_floats(accessor: usize, edit: &dyn Fn(&mut [f32])) -> Value {
    let mut j = tail_json();
    let uri = j["buffers"][0]["uri"].as_str().unwrap().to_string();
    let data = uri.split_once(";base64,").unwrap().1;
    let mut bin = gltf::decode_base64(data).unwrap();
    let view = j["accessors"][accessor]["bufferView"].as_u64().unwrap() as usize;
    let offset = j["bufferViews"][view]["byteOffset"].as_u64().unwrap() as usize;
    let length = j["bufferViews"][view]["byteLength"].as_u64().unwrap() as usize;
    let mut floats: Vec<f32> = bin[offset..offset + length]
        .chunks(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    edit(&mut floats);
    for (k, f) in floats.iter().enumerate() {
        bin[offset + 4 * k..offset + 4 * k + 4].copy_from_slice(&f.to_le_bytes());
    }
    j["buffers"][0]["uri"] = json!(format!(
        "data:application/octet-stream;base64,{}",
        pelage::mesh::rig::encode_base64(&bin)
    ));
    j
}

#[test]
fn bad_numbers_in_buffers_are_refused() {
    refused(
        "nan",
        &with_floats(0, &|f| f[4] = f32::NAN),
        Some("/accessors/0"),
        "element 1 is not finite",
    );
    refused(
        "nanweight",
        &with_floats(3, &|f| f[0] = f32::NAN),
        Some("/accessors/3"),
        "not finite",
    );
    refused(
        "zero",
        &with_floats(3, &|f| f[..4].fill(0.0)),
        Some("/accessors/3"),
        "vertex 0: weights [0.0, 0.0, 0.0, 0.0]",
    );
    // Key times of the first sampler: 0, 0.5, 0.5, ...
    let j = tail_json();
    let input = j["animations"][0]["samplers"][0]["input"].as_u64().unwrap() as usize;
    refused(
        "increase",
        &with_floats(input, &|f| f[2] = 0.5),
        Some(&format!("/accessors/{input}")),
        "key times must increase",
    );
}

#[test]
fn glb_headers_and_chunks_are_checked() {
    let fox = std::fs::read(root().join("scenes/meshes/fox/Fox.glb")).expect("Fox.glb");
    let load = |bytes: &[u8]| gltf::load_bytes(bytes, Path::new("Fox.glb"), None, None, 1.0);
    assert!(load(&fox).is_ok());
    let mut magic = fox.clone();
    magic[0] = b'x';
    assert!(load(&magic).is_err());
    let err = load(&fox[..fox.len() / 2]).expect_err("truncated");
    assert!(err.to_string().starts_with("Fox.glb: "), "{err}");
    let mut chunk = fox.clone();
    // The JSON chunk's length (bytes 12..16) past the end of the file.
    chunk[12..16].copy_from_slice(&u32::MAX.to_le_bytes());
    let err = load(&chunk).expect_err("chunk past the end");
    assert!(err.to_string().contains("GLB"), "{err}");
    for cut in [0, 4, 11, 12, 19, 20, 100] {
        assert!(load(&fox[..cut]).is_err(), "cut at {cut}");
    }
}

#[test]
fn the_fox_has_its_clips_and_colour_and_unknown_names_are_refused() {
    let path = root().join("scenes/meshes/fox/Fox.glb");
    let fox = gltf::load(&path, None, 1.0).expect("the fox loads");
    let names: Vec<&str> = fox.clips.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, ["Survey", "Walk", "Run"]);
    assert_eq!(fox.bind.triangle_count(), 576);
    assert_eq!(
        fox.rig.palette.len(),
        24,
        "one palette entry a joint of the fox's skin"
    );
    let colour = fox.base_colour.as_ref().expect("a base-colour texture");
    // The texture is mostly orange: red well above blue on average.
    let (r, b) = colour.texels.iter().fold((0u64, 0u64), |(r, b), t| {
        (r + u64::from(t[0]), b + u64::from(t[2]))
    });
    assert!(r > 2 * b, "red {r}, blue {b}");
    assert_eq!(
        fox.clip_index(&ClipChoice::Index(1), &path)
            .expect("clip 1"),
        1
    );
    let err = fox
        .clip_index(&ClipChoice::Name("Walkk".into()), &path)
        .expect_err("unknown clip");
    assert!(
        err.to_string()
            .contains("no animation clip named \"Walkk\""),
        "{err}"
    );
    assert!(err.to_string().contains("\"Walk\""), "{err}");
    assert!(fox.clip_index(&ClipChoice::Index(3), &path).is_err());
    let err = gltf::load(&path, Some("tail"), 1.0).expect_err("unknown node");
    assert!(err.to_string().contains("no node named \"tail\""), "{err}");
    // A node's subtree: the fox's own mesh node.
    assert!(gltf::load(&path, Some("fox"), 1.0).is_ok());
}

#[test]
fn scenes_refuse_unknown_clips_and_keys_out_of_place_with_exit_2() {
    let dir = common::scratch("scenes");
    let fox = root().join("scenes/meshes/fox/Fox.glb");
    let write = |name: &str, text: String| {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    };
    let mesh = format!(
        "[mesh]\nkind = \"gltf\"\npath = \"{}\"\nscale = 0.05\n",
        fox.display()
    );
    let cases = [
        (
            "clip.toml",
            format!("{mesh}[animation]\nclip = \"Fly\"\n"),
            "no animation clip named \"Fly\"",
        ),
        (
            "node.toml",
            format!("{mesh}node = \"wing\"\n"),
            "no node named \"wing\"",
        ),
        (
            "anim.toml",
            "[animation]\nclip = \"Walk\"\n".to_string(),
            "needs mesh.kind = \"gltf\"",
        ),
        (
            "colour.toml",
            "[fur]\ncolour_from_mesh = true\n".to_string(),
            "fur.colour_from_mesh",
        ),
        (
            "speed.toml",
            format!("{mesh}[animation]\nspeed = 1e9\n"),
            "animation.speed",
        ),
    ];
    for (name, text, words) in cases {
        let path = write(name, text);
        let out = common::pelage(&[
            "render",
            path.to_str().unwrap(),
            "--width",
            "32",
            "--height",
            "24",
            "-o",
            dir.join("x.png").to_str().unwrap(),
        ]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{name}: {stderr}");
        assert!(stderr.contains(words), "{name}: {stderr}");
    }
}

#[test]
fn fur_lags_behind_each_posed_vertex_and_not_behind_a_still_pose() {
    let mut scene = common::scene("tail", 96, 72);
    // The tail standing still (one keyframe): its fur lags behind the wag alone.
    scene.motion = Some(pelage::scene::MotionSettings {
        path: vec![[0.0, 0.0, 0.0, 0.0]],
        frequency: 2.0,
        damping: 0.3,
        response: 0.6,
    });
    let prepared = PreparedScene::new(&scene).expect("prepares");
    let posed = prepared.mesh_at(0.6);
    let tip = posed
        .vertices
        .iter()
        .max_by(|a, b| a.rest_position.y.total_cmp(&b.rest_position.y))
        .expect("vertices");
    assert!(
        tip.lag.length() > 1e-3,
        "the wagging tip lags: {:?}",
        tip.lag
    );
    assert!(posed.vertices.iter().all(|v| v.lag.is_finite()));
    // The rest fields stay the rest pose's.
    for (a, b) in posed.vertices.iter().zip(&prepared.mesh().vertices) {
        assert_eq!(a.rest_position, b.rest_position);
        assert_eq!(a.rest_normal, b.rest_normal);
    }
    // A clip that does not move (speed 0) leaves nothing to lag behind.
    let mut still = scene.clone();
    if let Some(a) = still.animation.as_mut() {
        a.speed = 0.0;
    }
    let prepared = PreparedScene::new(&still).expect("prepares");
    assert!(
        prepared
            .mesh_at(0.6)
            .vertices
            .iter()
            .all(|v| v.lag == glam::Vec3::ZERO)
    );
    // The lag moves the fur: the same instant without [motion] differs.
    let mut calm = scene.clone();
    calm.motion = None;
    let with = PreparedScene::new(&scene)
        .unwrap()
        .render_at(0.6, 32)
        .unwrap()
        .rgba8;
    let without = PreparedScene::new(&calm)
        .unwrap()
        .render_at(0.6, 32)
        .unwrap()
        .rgba8;
    assert!(common::differing_pixels(&with, &without) > 20);
}
