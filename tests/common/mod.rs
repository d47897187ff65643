//! Helpers shared by the integration tests.
#![allow(dead_code)]

use pelage::render::PreparedScene;
use pelage::scene::Scene;
use std::path::{Path, PathBuf};
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

/// Reads an image file as RGBA8 through the library's own decoder ([`pelage::input::read_image`]),
/// panicking with the file's name. Not `image::open`: that is generic over the reader, so every
/// test crate calling it would compile every codec again (about 10 s of CPU each in a release
/// build); the library's copy is compiled once.
pub fn open_rgba8(path: impl AsRef<Path>) -> image::RgbaImage {
    pelage::input::read_image(path.as_ref(), "test image").unwrap_or_else(|e| panic!("{e}"))
}

/// [`open_rgba8`] on a file's bytes already read.
pub fn decode_rgba8(bytes: &[u8]) -> image::RgbaImage {
    pelage::input::decode_image(bytes, Path::new("<bytes>"), "test image")
        .unwrap_or_else(|e| panic!("{e}"))
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

/// The scene's image at tile size `tile`, after checking that the fur fragment stage's scalar
/// twin gives the same bytes (`what` names the render in the failure).
pub fn render_checking_twin(scene: &Scene, tile: u32, what: &str) -> Vec<u8> {
    let prepared = PreparedScene::new(scene).expect("scene prepares");
    let image = prepared.render(tile).expect("scene renders").rgba8;
    let twin = prepared
        .render_scalar_twin_at(scene.time, tile)
        .expect("scene renders")
        .rgba8;
    let differing = differing_pixels(&image, &twin);
    assert_eq!(
        differing, 0,
        "{what}: the scalar twin differs in {differing} pixels"
    );
    image
}

/// How many RGBA8 pixels of two images of one size differ.
pub fn differing_pixels(a: &[u8], b: &[u8]) -> usize {
    assert_eq!(a.len(), b.len(), "images of different sizes");
    a.chunks(4).zip(b.chunks(4)).filter(|(p, q)| p != q).count()
}
