//! Helpers shared by the integration tests.
#![allow(dead_code)]

use pelage::scene::Scene;
use std::path::PathBuf;
use std::process::{Command, Output};

/// `scenes/NAME.toml` at another image size.
pub fn scene(name: &str, width: u32, height: u32) -> Scene {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(format!("{name}.toml"));
    let mut scene = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
    scene.image.width = width;
    scene.image.height = height;
    scene
}

/// Runs the `pelage` binary with `args`.
pub fn pelage(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_pelage"))
        .args(args)
        .output()
        .expect("pelage runs")
}

/// An empty scratch folder `TEST-NAME` under the target's temporary folder (`TEST` is the test
/// file's name, so files cannot clash), emptied if a previous run left it.
pub fn scratch(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("{}-{name}", env!("CARGO_CRATE_NAME")));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir
}
