//! `pelage export`: the folder holds the textures, meshes, parameters and the oracle's render a
//! GPU implementation needs, and re-reading `scene.json` gives the scene's values.

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
            let img = image::open(&file).expect("texture PNG").to_rgba8();
            assert_eq!(img.width(), scene.fur.texture_resolution);
        }
    }
    assert!(dir.join("textures/mips/shell_00_colour_1.png").exists());
    assert!(
        dir.join(json["fin"]["colour_texture"].as_str().expect("fin"))
            .exists()
    );
    let render = image::open(dir.join("oracle.png"))
        .expect("render")
        .to_rgba8();
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
