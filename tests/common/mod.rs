//! Helpers shared by the integration tests.
#![allow(dead_code)]

use pelage::scene::Scene;
use std::path::PathBuf;

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
