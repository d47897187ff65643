//! `pelage export`: the folder holds the textures, meshes, parameters and the oracle's render a
//! GPU implementation needs, and re-reading `scene.json` gives the scene's values.

mod common;

use pelage::scene::Scene;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;

fn scratch(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("export-{name}"));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn read_json(path: &Path) -> Value {
    serde_json::from_slice(&std::fs::read(path).expect("read")).expect("valid JSON")
}

fn f32s(v: &Value) -> Vec<f32> {
    v.as_array()
        .expect("array")
        .iter()
        .map(|x| x.as_f64().expect("number") as f32)
        .collect()
}

#[test]
fn export_holds_everything_and_the_json_gives_the_scene_back() {
    let dir = scratch("spots");
    let scene_path = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/spots.toml");
    let o = Command::new(env!("CARGO_BIN_EXE_pelage"))
        .args([
            "export",
            scene_path,
            "--width",
            "96",
            "--height",
            "72",
            "-o",
            dir.to_str().expect("utf-8"),
        ])
        .output()
        .expect("pelage runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));

    let mut scene = Scene::load(Path::new(scene_path)).expect("scene");
    scene.image.width = 96;
    scene.image.height = 72;
    let json = read_json(&dir.join("scene.json"));
    let s = &json["scene"];
    assert_eq!(s["seed"], scene.seed);
    assert_eq!(s["image"]["width"], 96);
    assert_eq!(f32s(&s["camera"]["eye"]), scene.camera.eye.to_array());
    assert_eq!(
        s["fur"]["number_of_shells"], scene.fur.number_of_shells,
        "shell count"
    );
    assert_eq!(
        s["fur"]["model_difference"].as_f64().expect("f") as f32,
        scene.fur.model_difference
    );
    assert_eq!(
        s["shading"]["banks_exponent"].as_f64().expect("f") as f32,
        scene.shading.banks_exponent
    );
    assert_eq!(
        s["shading"]["weights"]["shadow"].as_f64().expect("f") as f32,
        scene.shading.weights.shadow
    );
    assert_eq!(
        f32s(&s["light"]["direction"]),
        scene.light.direction.to_array()
    );
    assert_eq!(
        s["spots"].as_array().expect("spots").len(),
        scene.spots.len()
    );
    assert_eq!(
        json["frame"]["spots"].as_array().expect("spots").len(),
        scene.spots.len() + scene.stripes.len()
    );
    let aspect = 96.0 / 72.0;
    let camera = pelage::export::camera(&scene);
    assert_eq!(
        f32s(&json["camera"]["view_projection"]),
        camera.view_projection(aspect).to_cols_array()
    );

    // One layer entry and two textures (with mips) per shell, the fin textures, the render.
    let n = scene.fur.number_of_shells as usize;
    let layers = json["layers"].as_array().expect("layers");
    assert_eq!(layers.len(), n);
    for (i, layer) in layers.iter().enumerate() {
        assert_eq!(layer["index"], i);
        for key in ["colour_texture", "tangent_texture"] {
            let file = dir.join(layer[key].as_str().expect("file"));
            let img = common::open_rgba8(&file);
            assert_eq!(img.width(), scene.fur.texture_resolution);
        }
    }
    assert!(dir.join("textures/mips/shell_00_colour_1.png").exists());
    assert!(
        dir.join(json["fin"]["colour_texture"].as_str().expect("fin"))
            .exists()
    );
    let render = common::open_rgba8(dir.join("oracle.png"));
    assert_eq!(render.dimensions(), (96, 72));

    // The oracle's render in the export is the render of the scene.
    let prepared = pelage::render::PreparedScene::new(&scene).expect("prepare");
    let direct = prepared.render(64).expect("render");
    assert_eq!(render.as_raw(), &direct.rgba8);

    // The glTF: skin, one mesh per shell, fins; its buffer as long as it says.
    let gltf = read_json(&dir.join("meshes/fur.gltf"));
    let names: Vec<&str> = gltf["meshes"]
        .as_array()
        .expect("meshes")
        .iter()
        .map(|m| m["name"].as_str().expect("name"))
        .collect();
    assert_eq!(names[0], "skin");
    assert_eq!(names[n], format!("shell_{:02}", n - 1));
    let attributes = &gltf["meshes"][0]["primitives"][0]["attributes"];
    for key in [
        "POSITION",
        "NORMAL",
        "TANGENT",
        "TEXCOORD_0",
        "_DPDU",
        "_DPDV",
    ] {
        assert!(attributes[key].is_u64(), "{key} missing");
    }
    let bin = std::fs::read(dir.join("meshes/fur.bin")).expect("bin");
    assert_eq!(gltf["buffers"][0]["byteLength"], bin.len());
    let vertices = gltf["accessors"][attributes["POSITION"].as_u64().expect("i") as usize]["count"]
        .as_u64()
        .expect("count");
    assert_eq!(vertices as usize, prepared.mesh().vertices.len());
}

fn export_to(dir: &Path) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_pelage"))
        .args(["export", "--width", "48", "--height", "36", "-o"])
        .arg(dir)
        .output()
        .expect("pelage runs")
}

/// The export folder is written whole or not at all: a previous export is replaced, a folder
/// holding anything else is refused before work starts (and left as it was), and no temporary
/// folder is left behind.
#[test]
fn export_replaces_a_previous_export_and_refuses_foreign_folders() {
    let dir = scratch("staged");
    let o = export_to(&dir);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = export_to(&dir);
    assert!(
        o.status.success(),
        "re-export: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(dir.join("oracle.png").is_file() && dir.join("scene.json").is_file());

    std::fs::write(dir.join("notes.txt"), "mine").expect("write");
    let o = export_to(&dir);
    assert_eq!(o.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains("notes.txt"), "{stderr}");
    assert_eq!(std::fs::read(dir.join("notes.txt")).expect("kept"), b"mine");

    let parent = dir.parent().expect("parent");
    let leftovers: Vec<_> = std::fs::read_dir(parent)
        .expect("list")
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(".export-staged"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
}

fn export_scene(name: &str, extra: &[&str]) -> (PathBuf, Value) {
    let dir = scratch(name);
    let scene_path = format!("{}/scenes/{name}.toml", env!("CARGO_MANIFEST_DIR"));
    let o = Command::new(env!("CARGO_BIN_EXE_pelage"))
        .arg("export")
        .arg(&scene_path)
        .args(["--width", "96", "--height", "72"])
        .args(extra)
        .arg("-o")
        .arg(&dir)
        .output()
        .expect("pelage runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let json = read_json(&dir.join("scene.json"));
    (dir, json)
}

/// Level of detail and motion: the spans of the exported instant (summing to the number of
/// shells, as many layers drawn as the level says), the level, the fin fade, the object's
/// offset and the shared lean.
#[test]
fn export_gives_the_level_of_detail_lean_and_offset_of_the_instant() {
    let (_, json) = export_scene("lod-flyaway", &["--time", "2"]);
    let scene = Scene::load(Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/lod-flyaway.toml"
    )))
    .expect("scene");
    let n = scene.fur.number_of_shells as usize;
    let spans: Vec<f64> = json["layers"]
        .as_array()
        .expect("layers")
        .iter()
        .map(|l| l["lod_span"].as_f64().expect("lod_span"))
        .collect();
    assert_eq!(spans.len(), n);
    let total: f64 = spans.iter().sum();
    assert!((total - n as f64).abs() < 1e-3, "spans sum to {total}");
    let lod = &json["frame"]["level_of_detail"];
    let level = lod["level"].as_f64().expect("level");
    assert!((4.0..n as f64).contains(&level), "far away: {level}");
    let drawn = spans.iter().filter(|&&s| s > 0.0).count();
    assert_eq!(drawn, level.ceil() as usize);
    assert!(lod["fur_pixels"].as_f64().expect("fur_pixels") > 0.0);
    let fin_fade = lod["fin_fade"].as_f64().expect("fin_fade");
    assert!((0.0..=1.0).contains(&fin_fade));
    let motion = scene.motion.as_ref().expect("motion");
    assert_eq!(
        f32s(&json["frame"]["object_offset"]),
        pelage::shading::path_position(&motion.path, 2.0).to_array()
    );
    assert_eq!(f32s(&json["frame"]["lean"]).len(), 3);
    assert_eq!(json["scene"]["lod"]["min_shells"], 4);
}

/// Maps: the surface maps as pelage reads them, and each shell's density bands with mips.
#[test]
fn export_holds_the_surface_maps_and_density_bands() {
    let (dir, json) = export_scene("density", &[]);
    let map = common::open_rgba8(dir.join(json["maps"]["files"]["density"].as_str().expect("map")));
    let source = common::open_rgba8(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/maps/density-falloff.png"
    ));
    assert_eq!(map.as_raw(), source.as_raw());
    assert!(json["maps"]["files"]["length"].is_null());
    for layer in json["layers"].as_array().expect("layers") {
        let bands = common::open_rgba8(dir.join(layer["density_texture"].as_str().expect("bands")));
        let colour =
            common::open_rgba8(dir.join(layer["colour_texture"].as_str().expect("colour")));
        assert_eq!(bands.dimensions(), colour.dimensions());
        // A: the strands of every band, the colour map's alpha.
        assert!(
            bands
                .pixels()
                .zip(colour.pixels())
                .all(|(b, c)| b[3] == c[3])
        );
    }
    assert!(dir.join("textures/mips/shell_00_density_1.png").exists());
}
