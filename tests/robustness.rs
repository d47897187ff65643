//! Property tests with fixed seeds over the same entry points as the fuzz targets
//! (`pelage::robust`, see `fuzz/`): random scene text, random OBJ text, random triangles, and
//! mutated models, sweep files, images and maps.
//! They run with every `cargo test`, so CI covers the fuzzed paths without a nightly toolchain.
//! Each property only asks that nothing panics and the invariants of `pelage::robust` hold;
//! refusing input with an error is fine.

use glam::Vec4;
use pelage::raster::CullMode;
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};

fn config(cases: u32, seed: u64) -> Config {
    Config {
        cases,
        rng_seed: RngSeed::Fixed(seed),
        failure_persistence: None,
        ..Config::default()
    }
}

/// Floats that break things: zeros of both signs, NaN, infinities, huge, tiny, and plain.
fn nasty_f32() -> impl Strategy<Value = f32> {
    prop_oneof![
        3 => -4.0f32..4.0,
        1 => Just(0.0f32),
        1 => Just(-0.0f32),
        1 => Just(f32::NAN),
        1 => Just(f32::INFINITY),
        1 => Just(f32::NEG_INFINITY),
        1 => Just(1e30f32),
        1 => Just(-1e30f32),
        1 => Just(f32::MAX),
        1 => Just(f32::MIN_POSITIVE),
        1 => Just(1e-30f32),
        1 => any::<f32>(),
    ]
}

/// A number as scene or OBJ text would write it.
fn number_text() -> impl Strategy<Value = String> {
    prop_oneof![
        nasty_f32().prop_map(|x| format!("{x:?}")),
        (-5i64..300).prop_map(|i| i.to_string()),
        Just("99999999999999999999".to_string()),
        Just("-1".to_string()),
        Just("nan".to_string()),
        Just("inf".to_string()),
        Just("1e39".to_string()),
        Just("\"text\"".to_string()),
        Just("[1, 2, 3]".to_string()),
        Just("[]".to_string()),
        Just("true".to_string()),
        Just("{ shadow = 2.0 }".to_string()),
    ]
}

const TABLES: &[&str] = &[
    "",
    "image",
    "camera",
    "mesh",
    "fur",
    "shading",
    "light",
    "wind",
    "burn",
    "[spots]",
    "[stripes]",
    "shading.weights",
    "nonsense",
];

const KEYS: &[&str] = &[
    "seed",
    "time",
    "width",
    "height",
    "background",
    "eye",
    "target",
    "up",
    "fov_y_deg",
    "near",
    "far",
    "kind",
    "major_radius",
    "minor_radius",
    "radius",
    "model_resolution",
    "scale",
    "path",
    "number_of_strands",
    "strand_resolution",
    "circle_resolution",
    "number_of_shells",
    "texture_resolution",
    "model_difference",
    "shell_spacing",
    "texture_repeat",
    "colour",
    "slope_deg",
    "curl",
    "jitter",
    "min_height",
    "base_thickness",
    "tip_thickness",
    "supersample",
    "gaussian_sigma",
    "fins",
    "fin_windows",
    "fin_height_scale",
    "ambient",
    "specular_tangents",
    "shadow_divisor",
    "weights",
    "debug_view",
    "direction",
    "strength",
    "matches",
    "start",
    "high_exponent",
    "low_exponent",
    "centre",
    "radii",
    "inner",
    "exponent",
    "inner_threshold",
    "outer_threshold",
    "axis",
    "period",
    "softness",
    "hairiness",
];

fn scene_line() -> impl Strategy<Value = String> {
    prop_oneof![
        1 => prop::sample::select(TABLES).prop_map(|t| format!("[{t}]")),
        6 => (prop::sample::select(KEYS), number_text()).prop_map(|(k, v)| format!("{k} = {v}")),
        1 => "[ -~]{0,20}",
    ]
}

fn scene_text() -> impl Strategy<Value = String> {
    prop::collection::vec(scene_line(), 0..24).prop_map(|lines| lines.join("\n"))
}

/// A reference scene with one byte replaced and the text cut short somewhere.
fn mutated_reference() -> impl Strategy<Value = String> {
    let scenes: Vec<String> = std::fs::read_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes"))
        .expect("scenes")
        .filter_map(|e| std::fs::read_to_string(e.ok()?.path()).ok())
        .collect();
    (
        prop::sample::select(scenes),
        any::<usize>(),
        any::<u8>(),
        any::<usize>(),
    )
        .prop_map(|(text, at, byte, cut)| {
            let mut bytes = text.into_bytes();
            let n = bytes.len();
            bytes[at % n] = byte;
            bytes.truncate(n - cut % (n / 4 + 1));
            String::from_utf8_lossy(&bytes).into_owned()
        })
}

fn obj_index(count: i64) -> impl Strategy<Value = String> {
    prop_oneof![
        6 => (1..=count.max(1)).prop_map(|i| i.to_string()),
        1 => (-count.max(1)..=-1).prop_map(|i| i.to_string()),
        1 => Just("0".to_string()),
        1 => (count + 1..count + 5).prop_map(|i| i.to_string()),
        1 => Just("x".to_string()),
    ]
}

fn obj_corner(count: i64) -> impl Strategy<Value = String> {
    (obj_index(count), obj_index(count), obj_index(count), 0..5u8).prop_map(|(v, t, n, form)| {
        match form {
            0 => v,
            1 => format!("{v}/{t}"),
            2 => format!("{v}//{n}"),
            3 => format!("{v}/{t}/{n}"),
            _ => format!("{v}/{t}/{n}/1"),
        }
    })
}

/// Mostly valid OBJ statements over a few positions (so faces are often degenerate or
/// repeated), with NaN, huge and malformed values mixed in.
fn obj_line(count: i64) -> impl Strategy<Value = String> {
    let coordinate = prop_oneof![
        6 => prop::sample::select(vec![0.0f32, 1.0, -1.0, 0.5, 2.0]).prop_map(|x| format!("{x}")),
        1 => number_text(),
    ];
    prop_oneof![
        4 => prop::collection::vec(coordinate.clone(), 3..=4)
            .prop_map(|c| format!("v {}", c.join(" "))),
        2 => prop::collection::vec(coordinate.clone(), 1..=3)
            .prop_map(|c| format!("vt {}", c.join(" "))),
        1 => prop::collection::vec(coordinate, 3).prop_map(|c| format!("vn {}", c.join(" "))),
        4 => prop::collection::vec(obj_corner(count), 2..=6)
            .prop_map(|c| format!("f {}", c.join(" "))),
        1 => prop::sample::select(vec![
            "o thing", "g", "s 1", "usemtl fur", "usemtl", "mtllib fur.mtl", "# comment", "",
            "l 1 2", "l 1 2 3", "p 1", "vp 0.5", "bogus 1 2 3",
        ])
        .prop_map(str::to_string),
    ]
}

fn obj_text() -> impl Strategy<Value = String> {
    (1i64..8)
        .prop_flat_map(|count| prop::collection::vec(obj_line(count), 0..30))
        .prop_map(|lines| lines.join("\n"))
}

/// A valid OBJ: `n` positions drawn from a small set (repeated vertices, zero-area and
/// non-manifold faces), UVs sometimes all equal, sometimes missing.
fn degenerate_obj() -> impl Strategy<Value = String> {
    let position = prop::sample::select(vec![
        [0.0f32, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
        [1.0, 1.0, 1.0],
        [1e18, 0.0, 0.0],
        [0.0, -1e18, 1e18],
        [1e-30, 1e-30, 0.0],
    ]);
    (
        prop::collection::vec(position, 3..10),
        0..3u8,
        prop::collection::vec(
            prop::collection::vec(any::<prop::sample::Index>(), 3..5),
            1..12,
        ),
    )
        .prop_map(|(positions, uv_mode, faces)| {
            let n = positions.len();
            let mut text = String::new();
            for (i, p) in positions.iter().enumerate() {
                text += &format!("v {:?} {:?} {:?}\n", p[0], p[1], p[2]);
                match uv_mode {
                    0 => text += "vt 0.5 0.5\n",
                    1 => text += &format!("vt {} {}\n", i % 3, i / 3),
                    _ => {}
                }
            }
            for face in faces {
                let corners: Vec<String> = face
                    .iter()
                    .map(|ix| {
                        let k = ix.index(n) + 1;
                        if uv_mode < 2 {
                            format!("{k}/{k}")
                        } else {
                            k.to_string()
                        }
                    })
                    .collect();
                text += &format!("f {}\n", corners.join(" "));
            }
            text
        })
}

fn clip_vertex() -> impl Strategy<Value = Vec4> {
    prop_oneof![
        3 => (-3.0f32..3.0, -3.0f32..3.0, -1.0f32..2.0, -0.5f32..3.0)
            .prop_map(|(x, y, z, w)| Vec4::new(x, y, z, w)),
        2 => (nasty_f32(), nasty_f32(), nasty_f32(), nasty_f32())
            .prop_map(|(x, y, z, w)| Vec4::new(x, y, z, w)),
    ]
}

fn cull() -> impl Strategy<Value = CullMode> {
    prop::sample::select(vec![CullMode::None, CullMode::Back, CullMode::Front])
}

proptest! {
    #![proptest_config(config(600, 0x5ce7e))]
    #[test]
    fn random_scene_text_never_panics(text in scene_text()) {
        pelage::robust::scene_text(&text);
    }
}

proptest! {
    #![proptest_config(config(300, 0xbadf00d))]
    #[test]
    fn mutated_reference_scenes_never_panic(text in mutated_reference()) {
        pelage::robust::scene_text(&text);
    }
}

proptest! {
    #![proptest_config(config(600, 0x0b1))]
    #[test]
    fn random_obj_text_never_panics(text in obj_text()) {
        pelage::robust::obj_bytes(text.as_bytes());
    }
}

proptest! {
    #![proptest_config(config(400, 0xde9e))]
    #[test]
    fn degenerate_meshes_have_finite_frames_shells_and_fins(text in degenerate_obj()) {
        let loaded = pelage::mesh::load_obj_bytes(text.as_bytes(), std::path::Path::new("d.obj"));
        // The one refusal a valid OBJ may meet: no face of non-zero area.
        if let Err(e) = &loaded
            && e.to_string().contains("has a non-zero area")
        {
            return Ok(());
        }
        let loaded = loaded.map_err(|e| TestCaseError::fail(format!("{e}\n{text}")))?;
        pelage::robust::check_mesh(&loaded.mesh);
        pelage::robust::shells_and_fins(&loaded.mesh);
    }
}

proptest! {
    #![proptest_config(config(3000, 0x7e1a))]
    #[test]
    fn random_triangles_clip_set_up_and_rasterize_without_nan(
        a in clip_vertex(),
        b in clip_vertex(),
        c in clip_vertex(),
        width in prop_oneof![1u32..64, Just(16384u32), 1u32..20000],
        height in prop_oneof![1u32..64, Just(16384u32), 1u32..20000],
        cull in cull(),
    ) {
        pelage::robust::triangle([a, b, c], width, height, cull);
    }
}

/// One of `seeds`, with up to `max_edits` bytes changed and perhaps cut short.
fn mutated(seeds: Vec<Vec<u8>>, max_edits: usize) -> impl Strategy<Value = Vec<u8>> {
    (
        prop::sample::select(seeds),
        proptest::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 0..max_edits),
        prop_oneof![Just(None), any::<prop::sample::Index>().prop_map(Some)],
    )
        .prop_map(|(mut bytes, edits, cut)| {
            for (at, value) in edits {
                let i = at.index(bytes.len());
                bytes[i] = value;
            }
            if let Some(cut) = cut {
                bytes.truncate(cut.index(bytes.len()));
            }
            bytes
        })
}

/// The generated tail (a glTF with a data URI) and the fox (a GLB), with bytes changed or cut.
fn mutated_model() -> impl Strategy<Value = Vec<u8>> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let tail = std::fs::read(root.join("scenes/meshes/tail/tail.gltf")).expect("tail.gltf");
    let fox = std::fs::read(root.join("scenes/meshes/fox/Fox.glb")).expect("Fox.glb");
    mutated(vec![tail, fox], 8)
}

/// A shard's `sweep.txt`, a 0 byte and its `results.csv` (as the `sweep` fuzz target takes
/// them), written by pelage, with oracle columns and without, then mutated.
fn mutated_sweep_files() -> impl Strategy<Value = Vec<u8>> {
    let row = |point: usize, value: &str, extra: bool| pelage::sweep::ResultRow {
        point,
        values: vec![value.to_string(), "[0, 1, 0]".to_string()],
        bake_ms: 3.5,
        median_frame_ms: 20.0 + point as f64,
        min_frame_ms: 19.0,
        max_frame_ms: 40.0,
        fps: 1000.0 / (20.0 + point as f64),
        fragments_shaded: 123_456,
        extra: if extra {
            vec![
                ("flip_mean".into(), "0.004".into()),
                ("psnr".into(), "inf".into()),
            ]
        } else {
            Vec::new()
        },
    };
    let names = [
        "number_of_shells".to_string(),
        "light.direction".to_string(),
    ];
    let seeds = [false, true]
        .into_iter()
        .map(|extra| {
            let rows: Vec<_> = [(0, "10"), (2, "30"), (4, "1e308")]
                .into_iter()
                .map(|(p, v)| row(p, v, extra))
                .collect();
            let manifest = pelage::sweep::Manifest {
                id: 0x9f0c_2d4e_5a6b_7c81,
                points: 6,
                shard: Some(pelage::sweep::Shard { index: 1, count: 2 }),
            };
            let mut bytes = manifest.to_text().into_bytes();
            bytes.push(0);
            bytes.extend(
                pelage::sweep::write_results(&names, &rows)
                    .expect("csv")
                    .bytes(),
            );
            bytes
        })
        .collect();
    mutated(seeds, 6)
}

/// Small images in every format `compare` is given: PNG 8 and 16-bit, OpenEXR, mutated.
fn mutated_images() -> impl Strategy<Value = Vec<u8>> {
    let (w, h) = (5, 3);
    let float: Vec<f32> = (0..w * h * 4).map(|i| (i % 7) as f32 / 6.0).collect();
    let bytes: Vec<u8> = (0..w * h * 4).map(|i| (i * 37 % 256) as u8).collect();
    mutated(
        vec![
            pelage::output::encode_png(w, h, &bytes).expect("png"),
            pelage::output::encode_png16(w, h, &float).expect("png16"),
            pelage::output::encode_exr(w, h, &float).expect("exr"),
        ],
        6,
    )
}

proptest! {
    #![proptest_config(config(400, 0x5eeb))]
    #[test]
    fn mutated_sweep_files_never_panic(bytes in mutated_sweep_files()) {
        pelage::robust::sweep_files(&bytes);
    }
}

proptest! {
    #![proptest_config(config(400, 0x1a6e))]
    #[test]
    fn mutated_images_never_panic(bytes in mutated_images()) {
        pelage::robust::image_bytes(&bytes);
        pelage::robust::map_bytes(&bytes);
    }
}

proptest! {
    #![proptest_config(config(300, 0x91f))]
    #[test]
    fn mutated_models_never_panic(bytes in mutated_model()) {
        pelage::robust::gltf_bytes(&bytes);
    }
}

/// Every input a fuzz target or property test once failed on (`fuzz/regressions/TARGET/`),
/// replayed through the same entry point.
#[test]
fn fuzz_regressions_stay_fixed() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/regressions");
    let mut replayed = 0;
    for target in ["scene", "obj", "triangle", "gltf", "sweep", "image", "map"] {
        let Ok(entries) = std::fs::read_dir(root.join(target)) else {
            continue;
        };
        for entry in entries.filter_map(Result::ok) {
            let data = std::fs::read(entry.path()).expect("read regression input");
            match target {
                "scene" => pelage::robust::scene_text(&String::from_utf8_lossy(&data)),
                "obj" => pelage::robust::obj_bytes(&data),
                "gltf" => pelage::robust::gltf_bytes(&data),
                "sweep" => pelage::robust::sweep_files(&data),
                "image" => pelage::robust::image_bytes(&data),
                "map" => pelage::robust::map_bytes(&data),
                _ => pelage::robust::triangle_bytes(&data),
            }
            replayed += 1;
        }
    }
    assert!(replayed >= 2, "{replayed} regression inputs");
}
