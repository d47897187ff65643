//! `pelage view` as CI and a user run it, and the library call it rests on.
//!
//! The window tests need a display. Without one they say so and pass, unless
//! `PELAGE_REQUIRE_DISPLAY=1` (CI runs them under `xvfb-run` with it), where no display fails.

mod common;

use glam::Vec3;
use pelage::render::PreparedScene;
use pelage::scene::{BurnSettings, DebugView, Scene, SpotKind, SpotSettings, WindSettings};
use std::path::Path;

/// A small, quick scene: everything the viewer toggles is cheap to draw here.
const SMALL: &str = r#"
seed = 77
[image]
width = 120
height = 90
[camera]
eye = [0.0, 9.0, 14.0]
target = [0.0, -0.6, 0.0]
[mesh]
kind = "torus"
model_resolution = 200
[fur]
number_of_strands = 300
number_of_shells = 6
texture_resolution = 32
model_difference = 0.6
texture_repeat = [12.0, 5.0]
"#;

fn small() -> Scene {
    Scene::parse(SMALL, "small", Path::new(".")).expect("small scene")
}

#[test]
fn render_with_other_draw_settings_equals_a_fresh_bake_of_them() {
    let baked = small();
    let prepared = PreparedScene::new(&baked).expect("bake");
    let mut other = baked.clone();
    other.image.width = 97;
    other.image.height = 61;
    other.image.background = Vec3::new(0.1, 0.2, 0.3);
    other.camera.eye = Vec3::new(-8.0, 4.0, 10.5);
    other.camera.target = Vec3::new(0.5, 0.0, -0.2);
    other.light.direction = Vec3::new(-0.3, 0.9, 0.2);
    other.shading.weights.shadow = 0.4;
    other.wind = Some(WindSettings::default());
    other.burn = Some(BurnSettings {
        start: 0.2,
        ..BurnSettings::default()
    });
    other.spots = vec![SpotSettings {
        kind: SpotKind::Light,
        direction: Vec3::new(0.6, 0.5, 0.8),
        ..SpotSettings::default()
    }];
    // Fur that differs is ignored: the bake's is drawn.
    other.fur.number_of_shells = 3;
    let expected_scene = prepared.with_draw_settings(&other);
    assert_eq!(expected_scene.fur, baked.fur);
    let fresh = PreparedScene::new(&expected_scene).expect("fresh bake");
    for (view, time) in [
        (DebugView::None, 0.0),
        (DebugView::None, 1.7),
        (DebugView::Tangents, 0.9),
        (DebugView::Shadow, 3.0),
    ] {
        other.shading.debug_view = view;
        let mut expected_scene = expected_scene.clone();
        expected_scene.shading.debug_view = view;
        let fresh = if view == DebugView::None {
            fresh.render_at(time, 16).expect("fresh")
        } else {
            PreparedScene::new(&expected_scene)
                .expect("bake")
                .render_at(time, 64)
                .expect("fresh")
        };
        let reused = prepared.render_with(&other, time, 32).expect("reused");
        assert_eq!((reused.width, reused.height), (97, 61));
        assert!(reused.rgba8 == fresh.rgba8, "{view:?} at {time}");
    }
    // Drawing with the prepared scene's own settings is `render_at`.
    assert!(
        prepared.render_with(&baked, 0.0, 64).expect("a").rgba8
            == prepared.render_at(0.0, 64).expect("b").rgba8
    );
}

#[cfg(feature = "viewer")]
mod window {
    use super::*;
    use std::path::PathBuf;
    use std::process::{Command, Output};

    fn scratch(name: &str) -> PathBuf {
        let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("view-{name}"));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("scratch dir");
        dir
    }

    fn pelage(args: &[&str], display: Option<&str>) -> Output {
        let mut command = Command::new(env!("CARGO_BIN_EXE_pelage"));
        command.args(args).env_remove("WAYLAND_DISPLAY");
        match display {
            Some(d) => command.env("DISPLAY", d),
            None => command.env_remove("DISPLAY"),
        };
        command.output().expect("pelage runs")
    }

    fn stderr(o: &Output) -> String {
        String::from_utf8_lossy(&o.stderr).into_owned()
    }

    /// The display to test on; `None` (skip) only when CI has not asked for one.
    fn display() -> Option<String> {
        let display = std::env::var("DISPLAY").ok().filter(|d| !d.is_empty());
        if display.is_none() {
            assert!(
                std::env::var("PELAGE_REQUIRE_DISPLAY").as_deref() != Ok("1"),
                "PELAGE_REQUIRE_DISPLAY=1 but DISPLAY is not set: run under xvfb-run"
            );
            eprintln!(
                "SKIPPED: {} needs a display (run it under xvfb-run; .ci/setup installs xvfb)",
                std::thread::current().name().unwrap_or("a test")
            );
        }
        display
    }

    #[test]
    fn without_a_display_it_says_so_and_exits_1() {
        let o = pelage(&["view", "--frames", "2"], None);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{err}");
        assert!(err.contains("needs a display"), "{err}");
        assert!(err.contains("xvfb-run"), "{err}");
        assert!(!err.contains("panicked"), "{err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    }

    #[test]
    fn a_display_that_cannot_be_opened_is_an_error_not_a_panic() {
        let o = pelage(&["view", "--frames", "2"], Some(":9731"));
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{err}");
        assert!(
            err.contains("cannot open a window on display :9731"),
            "{err}"
        );
        assert!(!err.contains("panicked"), "{err}");
    }

    #[test]
    fn a_bad_scene_is_bad_input_before_any_window() {
        let dir = scratch("bad");
        let path = dir.join("bad.toml");
        std::fs::write(&path, "[fur]\nnumber_of_shells = 0\n").expect("write");
        let o = pelage(&["view", path.to_str().expect("utf-8")], None);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(err.contains("fur.number_of_shells"), "{err}");
    }

    /// Runs `pelage view` for some frames with a screenshot, then `pelage render` of the scene
    /// it wrote, and compares the bytes.
    fn screenshot_matches_render(name: &str, scene_text: &str, extra: &[&str]) -> Scene {
        let display = display();
        let dir = scratch(name);
        let scene = dir.join("scene.toml");
        std::fs::write(&scene, scene_text).expect("write scene");
        let shot = dir.join("shot.png");
        let mut args = vec![
            "view",
            scene.to_str().expect("utf-8"),
            "--screenshot",
            shot.to_str().expect("utf-8"),
        ];
        args.extend_from_slice(extra);
        let Some(display) = display else {
            return small();
        };
        let o = pelage(&args, Some(&display));
        let err = stderr(&o);
        assert!(o.status.success(), "{err}");
        assert!(err.contains("frames/s"), "{err}");
        let written = dir.join("shot.toml");
        let reference = dir.join("reference.png");
        let r = pelage(
            &[
                "render",
                written.to_str().expect("utf-8"),
                "-o",
                reference.to_str().expect("utf-8"),
            ],
            None,
        );
        assert!(r.status.success(), "{}", stderr(&r));
        let (a, b) = (
            std::fs::read(&shot).expect("screenshot"),
            std::fs::read(&reference).expect("reference"),
        );
        assert!(
            a == b,
            "{name}: the screenshot differs from `pelage render` of its scene"
        );
        Scene::load(&written).expect("written scene")
    }

    #[test]
    fn a_screenshot_is_byte_identical_to_pelage_render_of_its_scene() {
        // A still scene: the file records the clock's time all the same (two steps of 1/30 s).
        let still = screenshot_matches_render("still", SMALL, &["--frames", "3"]);
        if display().is_some() {
            assert_eq!(still.camera, small().camera);
            assert!(
                (still.time - 2.0 / 30.0).abs() < 1e-6,
                "time {}",
                still.time
            );
        }
        // Wind, fire and spots at a moving time, the camera orbiting: the scene written records
        // the camera and instant of the last frame.
        let effects = format!(
            "{}\n[wind]\nstrength = 0.8\n[burn]\nmatches = [[0.0, 1.0, 0.3]]\nstart = 0.1\n\
             [[spots]]\nkind = \"light\"\ndirection = [0.6, 0.5, 0.8]\n",
            SMALL.replacen("seed = 77", "seed = 77\ntime = 0.2", 1)
        );
        let moved = screenshot_matches_render(
            "effects",
            &effects,
            &["--frames", "4", "--fps", "10", "--orbit", "12"],
        );
        if display().is_some() {
            assert!((moved.time - 0.5).abs() < 1e-6, "time {}", moved.time);
            assert_ne!(moved.camera.eye, small().camera.eye);
            assert!(moved.wind.is_some() && moved.burn.is_some());
        }
    }

    /// The window's size from the viewer's closing report ("... in a WxH window ...").
    fn window_size(err: &str) -> (u32, u32) {
        let size = err
            .split(" in a ")
            .nth(1)
            .and_then(|t| t.split(' ').next())
            .unwrap_or_else(|| panic!("no window size in {err}"));
        let (w, h) = size.split_once('x').expect("WxH");
        (w.parse().expect("w"), h.parse().expect("h"))
    }

    #[test]
    fn a_window_larger_than_the_screen_is_scaled_down_and_the_image_keeps_its_size() {
        let Some(display) = display() else {
            return;
        };
        let dir = scratch("fit");
        let scene = dir.join("scene.toml");
        std::fs::write(&scene, SMALL).expect("write scene");
        let shot = dir.join("shot.png");
        let args = [
            "view",
            scene.to_str().expect("utf-8"),
            "--width",
            "1366",
            "--height",
            "768",
            "--frames",
            "2",
            "--screenshot",
            shot.to_str().expect("utf-8"),
        ];
        // A 1280×800 screen (stood in for by PELAGE_VIEW_SCREEN): the window fits inside it
        // with room for a title bar, same shape; the screenshot is the full 1366×768 image.
        let o = Command::new(env!("CARGO_BIN_EXE_pelage"))
            .args(args)
            .env("DISPLAY", &display)
            .env("PELAGE_VIEW_SCREEN", "1280x800")
            .output()
            .expect("pelage runs");
        let err = stderr(&o);
        assert!(o.status.success(), "{err}");
        let (w, h) = window_size(&err);
        assert!(w <= 1240 && h <= 720, "{w}x{h}: {err}");
        assert!(
            (f64::from(w) / f64::from(h) - 1366.0 / 768.0).abs() < 0.01,
            "{w}x{h}"
        );
        let image = crate::common::open_rgba8(&shot);
        assert_eq!((image.width(), image.height()), (1366, 768));
        // The real screen, read over the X protocol: xvfb-run's is 1280×1024, narrower than
        // the image, so the window is scaled down there too.
        if std::env::var("PELAGE_REQUIRE_DISPLAY").as_deref() == Ok("1") {
            let o = pelage(&args, Some(&display));
            let err = stderr(&o);
            assert!(o.status.success(), "{err}");
            let (w, _) = window_size(&err);
            assert!(w < 1366, "{w}: {err}");
        }
    }

    #[test]
    fn a_12_ms_key_tap_is_not_lost() {
        // `q` pressed for 12 ms (shorter than a 60 Hz frame) through the X test extension
        // (xdotool): the viewer must see it and quit. Acting on key state polled once a frame
        // lost such taps. Needs xdotool; CI (PELAGE_REQUIRE_DISPLAY=1) installs it.
        let Some(display) = display() else {
            return;
        };
        let has_xdotool = Command::new("xdotool")
            .arg("version")
            .output()
            .is_ok_and(|o| o.status.success());
        if !has_xdotool {
            assert!(
                std::env::var("PELAGE_REQUIRE_DISPLAY").as_deref() != Ok("1"),
                "PELAGE_REQUIRE_DISPLAY=1 but xdotool is missing: apt-get install xdotool"
            );
            eprintln!(
                "SKIPPED: {} needs xdotool (run .ci/setup)",
                std::thread::current().name().unwrap_or("a test")
            );
            return;
        }
        let dir = scratch("tap");
        let scene = dir.join("tap-scene.toml");
        std::fs::write(&scene, SMALL).expect("write scene");
        let mut viewer = Command::new(env!("CARGO_BIN_EXE_pelage"))
            .args(["view", scene.to_str().expect("utf-8")])
            .env("DISPLAY", &display)
            .stderr(std::process::Stdio::piped())
            .spawn()
            .expect("pelage view starts");
        let xdotool = |args: &[&str]| {
            Command::new("xdotool")
                .args(args)
                .env("DISPLAY", &display)
                .output()
                .expect("xdotool runs")
        };
        let found = xdotool(&["search", "--sync", "--onlyvisible", "--name", "tap-scene"]);
        let window = String::from_utf8_lossy(&found.stdout)
            .lines()
            .next()
            .unwrap_or("")
            .to_string();
        if window.is_empty() {
            let _ = viewer.kill();
            panic!("the viewer's window did not appear");
        }
        xdotool(&["windowfocus", "--sync", &window]);
        // Let the viewer reach its frame loop, then tap.
        std::thread::sleep(std::time::Duration::from_millis(500));
        xdotool(&["keydown", "q", "sleep", "0.012", "keyup", "q"]);
        let start = std::time::Instant::now();
        let status = loop {
            if let Some(status) = viewer.try_wait().expect("wait") {
                break Some(status);
            }
            if start.elapsed() > std::time::Duration::from_secs(10) {
                let _ = viewer.kill();
                let _ = viewer.wait();
                break None;
            }
            std::thread::sleep(std::time::Duration::from_millis(20));
        };
        let status = status.expect("a 12 ms tap of q was lost: the viewer kept running");
        assert!(status.success(), "{status}");
    }
}
