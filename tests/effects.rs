//! The effects over time: burning only ever removes fur, animations are time-addressable.

mod common;
use common::scene;

use pelage::render::PreparedScene;
use std::path::PathBuf;
use std::process::Command;

#[test]
fn a_burn_only_ever_removes_fur() {
    let scene = scene("burn", 160, 120);
    let burn = scene.burn.clone().expect("the burn scene burns");
    let prepared = PreparedScene::new(&scene).expect("prepares");
    let written = |t: f32| {
        prepared
            .render_at(t, 64)
            .expect("renders")
            .stats
            .fragments_written
    };
    // Before the matches light nothing burns: the count is that of the unburnt fur.
    let unburnt = written(burn.start - 0.25);
    assert_eq!(written(0.0), unburnt);
    // While the burnt area spreads, every frame draws strictly fewer fur texels than the one
    // before; afterwards the count stays put.
    let mut previous = unburnt;
    let steps = 8;
    for k in 1..=steps {
        let t = burn.start + burn.spread_duration * k as f32 / steps as f32;
        let now = written(t);
        assert!(
            now < previous,
            "t = {t}: {now} texels drawn, {previous} before"
        );
        previous = now;
    }
    assert_eq!(written(burn.start + 2.0 * burn.spread_duration), previous);
    // The roots remain: a fully spread burn still draws the skin and the burnt stubs.
    assert!(previous > unburnt / 10, "{previous} of {unburnt}");
}

#[test]
fn wind_moves_the_fur_and_lets_it_return() {
    let scene = scene("wind", 160, 120);
    let prepared = PreparedScene::new(&scene).expect("prepares");
    let at = |t: f32| prepared.render_at(t, 64).expect("renders").rgba8;
    let (start, gust, back) = (at(0.0), at(0.5), at(1.5));
    assert_ne!(start, gust, "the fur moves in a gust");
    assert_ne!(gust, back, "and swings back");
    // The wind repeats every 1/frequency = 2 s: a whole period later the phase is exactly 0
    // again and so is every pixel.
    assert_eq!(start, at(2.0));
    let mut still = scene.clone();
    still.wind = None;
    let calm = PreparedScene::new(&still)
        .expect("prepares")
        .render_at(0.5, 64)
        .expect("renders")
        .rgba8;
    assert_ne!(calm, gust);
}

#[test]
fn frame_k_of_a_sequence_is_a_render_at_k_over_fps() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("effects-frames");
    let _ = std::fs::remove_dir_all(&dir);
    let scene_path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/burn.toml");
    let gif = dir.join("burn.gif");
    let status = Command::new(env!("CARGO_BIN_EXE_pelage"))
        .args([
            "render",
            scene_path.to_str().expect("path"),
            "--width",
            "96",
            "--height",
            "72",
        ])
        .args([
            "--frames",
            "4",
            "--fps",
            "0.5",
            "-o",
            dir.to_str().expect("path"),
        ])
        .args(["--animation", gif.to_str().expect("path")])
        .status()
        .expect("pelage runs");
    assert!(status.success());
    let single = dir.join("single.png");
    let status = Command::new(env!("CARGO_BIN_EXE_pelage"))
        .args([
            "render",
            scene_path.to_str().expect("path"),
            "--width",
            "96",
            "--height",
            "72",
        ])
        .args(["--time", "6", "-o", single.to_str().expect("path")])
        .status()
        .expect("pelage runs");
    assert!(status.success());
    // Frame 3 at 0.5 fps is the instant 3 / 0.5 = 6 s.
    let frame = std::fs::read(dir.join("frame_0003.png")).expect("frame 3");
    assert_eq!(frame, std::fs::read(&single).expect("single"));
    assert_ne!(
        frame,
        std::fs::read(dir.join("frame_0000.png")).expect("frame 0")
    );
    assert!(!dir.join("frame_0004.png").exists());
    // The animated GIF holds the four frames.
    let file = std::fs::File::open(&gif).expect("gif");
    let decoder =
        image::codecs::gif::GifDecoder::new(std::io::BufReader::new(file)).expect("decodes");
    let frames = image::AnimationDecoder::into_frames(decoder)
        .collect_frames()
        .expect("frames");
    assert_eq!(frames.len(), 4);
}
