//! The SIMD level is a speed choice, never an image choice: scenes render to the same bytes at
//! every level this machine has (`pelage::simd`; the fur stage's batches hold 32 lanes at
//! `avx2`, 16 at `avx512`, 8 on the baseline), through the same cap `PELAGE_SIMD` sets, and
//! the `pelage` binary refuses an unknown level with exit status 2 and gives identical files at
//! every level.

mod common;
use common::{pelage, scene, scratch};

use pelage::render::PreparedScene;
use pelage::simd::SimdLevel;

/// Scenes that between them take every path of the fragment stage: shadows and wind, spots,
/// burning, density and length maps, three tangents, eq. 3.5, level of detail, fins.
const SCENES: &[(&str, f32)] = &[
    ("thesis-4-2", 0.0),
    ("spots", 0.0),
    ("burn", 3.0),
    ("density", 0.0),
    ("painted-length", 0.0),
    ("specular", 0.0),
    ("specular-eq35", 0.0),
    ("lod-flyaway", 2.0),
    ("face", 0.0),
];

#[test]
fn every_level_renders_the_same_bytes() {
    let levels = SimdLevel::available();
    eprintln!("levels on this machine: {levels:?}");
    for &(name, time) in SCENES {
        let s = scene(name, 160, 120);
        let prepared = PreparedScene::new(&s).expect("prepares");
        let reference = prepared
            .render_at_simd(time, 32, SimdLevel::Sse2)
            .expect("renders")
            .rgba8;
        for &level in &levels {
            let image = prepared
                .render_at_simd(time, 32, level)
                .expect("renders")
                .rgba8;
            let differing = common::differing_pixels(&image, &reference);
            assert_eq!(differing, 0, "{name} at {level}: {differing} pixels differ");
        }
    }
}

#[test]
fn a_cap_above_the_cpu_runs_the_best_it_has() {
    assert_eq!(SimdLevel::Avx512.capped(), SimdLevel::detected());
    assert_eq!(SimdLevel::available().last(), Some(&SimdLevel::detected()));
    let s = scene("torus", 64, 48);
    let prepared = PreparedScene::new(&s).expect("prepares");
    let best = prepared
        .render_at_simd(0.0, 64, SimdLevel::detected())
        .expect("renders");
    let above = prepared
        .render_at_simd(0.0, 64, SimdLevel::Avx512)
        .expect("renders");
    assert!(best.rgba8 == above.rgba8);
}

/// Runs `pelage` with `PELAGE_SIMD` set.
fn pelage_at(level: &str, args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_pelage"))
        .env("PELAGE_SIMD", level)
        .args(args)
        .output()
        .expect("pelage runs")
}

#[test]
fn the_binary_gives_the_same_file_at_every_level() {
    let dir = scratch("levels");
    let mut files = Vec::new();
    for level in ["scalar", "sse2", "avx2", "avx512", "baseline", ""] {
        let out = dir.join(format!("{level}.png"));
        let o = pelage_at(
            level,
            &[
                "render",
                "--width",
                "120",
                "--height",
                "90",
                "-o",
                out.to_str().expect("utf-8 path"),
            ],
        );
        assert!(
            o.status.success(),
            "{level}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        files.push(std::fs::read(&out).expect("png"));
    }
    assert!(files.iter().all(|f| f == &files[0]), "levels differ");
    // Without the variable: the same as with it unset.
    let plain = dir.join("plain.png");
    let o = pelage(&[
        "render",
        "--width",
        "120",
        "--height",
        "90",
        "-o",
        plain.to_str().expect("utf-8 path"),
    ]);
    assert!(o.status.success());
    assert!(std::fs::read(&plain).expect("png") == files[0]);
}

/// A render of the default scene at 120×90 with the given environment, as PNG bytes.
fn render_with(env: &[(&str, &str)], name: &str) -> Vec<u8> {
    let out = scratch("batch-lanes").join(format!("{name}.png"));
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_pelage"))
        .envs(env.iter().copied())
        .args(["render", "--width", "120", "--height", "90", "-o"])
        .arg(&out)
        .output()
        .expect("pelage runs");
    assert!(
        o.status.success(),
        "{name}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    std::fs::read(&out).expect("png")
}

#[test]
fn sixteen_lane_batches_give_the_same_file_at_every_level() {
    // `PELAGE_BATCH_LANES=16` runs 16-lane batches on the baseline copy too (avx512 runs them
    // anyway, avx2 runs 32 and sse2 8 without it): a lane's result never depends on the
    // batch's width.
    let reference = render_with(&[("PELAGE_SIMD", "sse2")], "eight");
    for level in ["sse2", "avx2", "avx512"] {
        let wide = render_with(
            &[("PELAGE_SIMD", level), ("PELAGE_BATCH_LANES", "16")],
            &format!("sixteen-{level}"),
        );
        assert!(wide == reference, "16-lane batches at {level} differ");
    }
}

#[test]
fn an_unknown_batch_width_is_refused_with_exit_status_2() {
    let out = scratch("batch-lanes-unknown").join("x.png");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_pelage"))
        .env("PELAGE_BATCH_LANES", "32")
        .args(["render", "-o"])
        .arg(&out)
        .output()
        .expect("pelage runs");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("PELAGE_BATCH_LANES=\"32\""), "{err}");
    assert!(err.contains("expected 16"), "{err}");
    assert!(!out.exists());
}

#[test]
fn an_unknown_level_is_refused_with_exit_status_2() {
    let out = scratch("unknown").join("x.png");
    let o = pelage_at(
        "avx1024",
        &["render", "-o", out.to_str().expect("utf-8 path")],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("PELAGE_SIMD=\"avx1024\""), "{err}");
    assert!(err.contains("scalar, sse2, avx2 or avx512"), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(!out.exists());
}
