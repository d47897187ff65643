//! `pelage compare` as a user runs it: an image against itself is exact (PSNR infinite, exit 0);
//! two different renders exit 1 and the heat map marks where they differ; images that cannot be
//! compared (sizes differ, unreadable file) exit 2 with a message naming the file.

mod common;
use common::{pelage, scratch};

use std::path::{Path, PathBuf};
use std::process::Output;

fn text(o: &Output) -> (String, String) {
    (
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

fn path(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// Renders the wind scene (figure 3.17) small at `time`.
fn render_wind(dir: &Path, time: &str) -> PathBuf {
    let out = dir.join(format!("wind-{time}.png"));
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/wind.toml");
    let o = pelage(&[
        "render",
        scene,
        "--width",
        "120",
        "--height",
        "90",
        "--time",
        time,
        "-o",
        path(&out),
    ]);
    assert!(o.status.success(), "{}", text(&o).1);
    out
}

#[test]
fn an_image_against_itself_is_exact() {
    let dir = scratch("self");
    let a = render_wind(&dir, "0.3");
    let heat = dir.join("heat.png");
    let o = pelage(&["compare", path(&a), path(&a), "--heatmap", path(&heat)]);
    let (out, err) = text(&o);
    assert_eq!(o.status.code(), Some(0), "{out}{err}");
    assert!(out.contains("exact pixels    10800 of 10800"), "{out}");
    assert!(out.contains("PSNR (RGB)      inf"), "{out}");
    assert!(out.contains("within tolerance"), "{out}");
    let o = pelage(&["compare", path(&a), path(&a), "--json"]);
    assert_eq!(o.status.code(), Some(0));
    let json: serde_json::Value = serde_json::from_slice(&o.stdout).expect("JSON");
    assert_eq!(json["psnr"], "inf");
    assert_eq!(json["exact_pixels"], 10800);
    assert_eq!(json["max_abs_error"], serde_json::json!([0, 0, 0, 0]));
    assert_eq!(json["flip"]["mean"], 0.0);
    assert_eq!(json["failures"], serde_json::json!([]));
    // Nothing differs: the heat map holds only the dimmed reference (grey).
    let map = image::open(&heat).expect("heat map").to_rgba8();
    assert!(map.pixels().all(|p| p[0] == p[1] && p[1] == p[2]));
}

#[test]
fn two_different_renders_fail_and_the_heat_map_shows_where() {
    let dir = scratch("different");
    let a = render_wind(&dir, "0.3");
    let b = render_wind(&dir, "0.9");
    let heat = dir.join("heat.png");
    let o = pelage(&[
        "compare",
        path(&a),
        path(&b),
        "--json",
        "--heatmap",
        path(&heat),
        "--flip-map",
        path(&dir.join("flip.png")),
    ]);
    let (out, err) = text(&o);
    assert_eq!(o.status.code(), Some(1), "{out}{err}");
    assert!(err.contains("beyond the tolerance"), "{err}");
    let json: serde_json::Value = serde_json::from_slice(&o.stdout).expect("JSON");
    assert!(json["psnr"].as_f64().expect("finite PSNR") < 60.0);
    assert!(json["flip"]["mean"].as_f64().expect("FLIP") > 0.0);
    let exact = json["exact_pixels"].as_u64().expect("count");
    assert!(exact < 10800 && exact > 0, "{exact}");
    // Coloured exactly where the renders differ, grey elsewhere.
    let (ia, ib) = (
        image::open(&a).expect("a").to_rgba8(),
        image::open(&b).expect("b").to_rgba8(),
    );
    let map = image::open(&heat).expect("heat map").to_rgba8();
    for (x, y, p) in map.enumerate_pixels() {
        let grey = p[0] == p[1] && p[1] == p[2];
        assert_eq!(
            grey,
            ia.get_pixel(x, y) == ib.get_pixel(x, y),
            "pixel {x},{y}"
        );
    }
    assert!(dir.join("flip.png").exists());
    // A loose enough tolerance accepts the same pair.
    let o = pelage(&[
        "compare",
        path(&a),
        path(&b),
        "--tolerance",
        "threshold=255",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o).1);
}

#[test]
fn images_that_cannot_be_compared_exit_2_naming_the_file() {
    let dir = scratch("bad");
    let a = render_wind(&dir, "0.3");
    let small = dir.join("small.png");
    image::RgbaImage::new(10, 10).save(&small).expect("write");
    let o = pelage(&["compare", path(&a), path(&small)]);
    let err = text(&o).1;
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("sizes differ") && err.contains("small.png"),
        "{err}"
    );

    let garbage = dir.join("garbage.png");
    std::fs::write(&garbage, b"not a png").expect("write");
    let o = pelage(&["compare", path(&a), path(&garbage)]);
    let err = text(&o).1;
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("garbage.png"), "{err}");

    let absent = dir.join("absent.png");
    let o = pelage(&["compare", path(&absent), path(&a)]);
    let err = text(&o).1;
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("absent.png"), "{err}");

    let o = pelage(&["compare", path(&a), path(&a), "--tolerance", "over=7"]);
    let err = text(&o).1;
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("over=7") && !err.contains("panicked"), "{err}");
}
