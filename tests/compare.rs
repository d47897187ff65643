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
    // Nothing differs: the heat map holds only the dimmed reference (grey); its legend strip
    // below (the colour scale) is in colour.
    let map = common::open_rgba8(&heat);
    let legend = pelage::compare::legend::LEGEND_HEIGHT;
    assert_eq!(map.height(), 90 + legend);
    let region = image::imageops::crop_imm(&map, 0, 0, 120, 90).to_image();
    assert!(region.pixels().all(|p| p[0] == p[1] && p[1] == p[2]));
    assert!(map.pixels().any(|p| p[0] != p[2]), "the legend's colours");
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
    let (ia, ib) = (common::open_rgba8(&a), common::open_rgba8(&b));
    let map = common::open_rgba8(&heat);
    for (x, y, p) in image::imageops::crop_imm(&map, 0, 0, 120, 90)
        .to_image()
        .enumerate_pixels()
    {
        let grey = p[0] == p[1] && p[1] == p[2];
        assert_eq!(
            grey,
            ia.get_pixel(x, y) == ib.get_pixel(x, y),
            "pixel {x},{y}"
        );
    }
    // The FLIP map of this failing pair is readable: where the renders differ its pixels are
    // bright (FLIP's errors here are mostly 0.01–0.2, which a linear magma scale drew near
    // black, a mean luma of about 20), and where they are equal it is black.
    let flip = common::open_rgba8(dir.join("flip.png"));
    assert_eq!(flip.height(), 90 + pelage::compare::legend::LEGEND_HEIGHT);
    let luma = |p: &image::Rgba<u8>| {
        0.2126 * f64::from(p[0]) + 0.7152 * f64::from(p[1]) + 0.0722 * f64::from(p[2])
    };
    let (mut differing, mut equal) = (Vec::new(), Vec::new());
    for (x, y, p) in image::imageops::crop_imm(&flip, 0, 0, 120, 90)
        .to_image()
        .enumerate_pixels()
    {
        if ia.get_pixel(x, y) == ib.get_pixel(x, y) {
            equal.push(luma(p));
        } else {
            differing.push(luma(p));
        }
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
    eprintln!(
        "FLIP map mean luma: differing {:.1}, equal {:.1}",
        mean(&differing),
        mean(&equal)
    );
    assert!(
        mean(&differing) > 60.0,
        "differing: {:.1}",
        mean(&differing)
    );
    assert!(
        mean(&equal) < 0.5 * mean(&differing),
        "equal: {:.1}",
        mean(&equal)
    );
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

#[test]
fn a_partial_tolerance_checks_only_what_it_names_and_says_so() {
    let dir = scratch("partial");
    let a = render_wind(&dir, "0.3");
    let b = render_wind(&dir, "0.9");
    // The renders differ (exact fails), but a FLIP-mean bound of 1 cannot.
    let o = pelage(&["compare", path(&a), path(&b), "--tolerance", "flip-mean=1"]);
    let (out, err) = text(&o);
    assert_eq!(o.status.code(), Some(0), "{out}{err}");
    assert!(out.contains("checked         FLIP mean ≤ 1\n"), "{out}");
    assert!(
        out.contains("within tolerance (1 criteria checked)"),
        "{out}"
    );
    let o = pelage(&["compare", path(&a), path(&b), "--tolerance", "exact"]);
    let (out, _) = text(&o);
    assert_eq!(o.status.code(), Some(1), "{out}");
    assert!(out.contains("checked         every pixel equal"), "{out}");
    let o = pelage(&[
        "compare",
        path(&a),
        path(&b),
        "--tolerance",
        "gpu",
        "--json",
    ]);
    let json: serde_json::Value = serde_json::from_slice(&o.stdout).expect("JSON");
    assert_eq!(json["checked"].as_array().map(Vec::len), Some(4), "{json}");
}

/// The figures of one row of the GPU tolerance table (docs/src/gpu.md), as a comparison judged by `t`.
fn judged_row(row: &str, t: &pelage::compare::Tolerance) -> Vec<String> {
    let cells: Vec<&str> = row.trim_matches('|').split('|').map(str::trim).collect();
    assert_eq!(cells.len(), 7, "{row}");
    let number = |cell: &str| -> f64 {
        cell.trim_matches('*')
            .trim_end_matches(" dB")
            .trim_end_matches('%')
            .parse()
            .unwrap_or_else(|_| panic!("{cell} in {row}"))
    };
    let pixels = 1_000_000u64;
    let fraction = |cell: &str| ((number(cell) / 100.0) * pixels as f64).round() as u64;
    let max: Vec<u8> = cells[2]
        .split('/')
        .map(|v| v.parse().expect("max error"))
        .collect();
    let over = fraction(cells[4]);
    let c = pelage::compare::Comparison {
        width: 1000,
        height: 1000,
        pixels,
        exact_pixels: fraction(cells[1]),
        max_abs_error: [max[0], max[1], max[2], 0],
        mean_abs_error: [0.0; 4],
        psnr: pelage::compare::Psnr(number(cells[3])),
        over_threshold: over,
        neighbour_over_threshold: over,
        flip: pelage::compare::FlipStats {
            mean: number(cells[5]) as f32,
            median: 0.0,
            p95: 0.0,
            p99: number(cells[6]) as f32,
            max: 1.0,
            checked_percentile: t
                .max_flip_percentile
                .map(|(p, _)| (p, number(cells[6]) as f32)),
        },
        tolerance: t.clone(),
        checked: t.criteria(),
        failures: Vec::new(),
    };
    pelage::compare::judge(&c, t)
}

#[test]
fn the_readmes_first_compare_example_catches_every_measured_mutant() {
    // The README's first `pelage compare` command must pass every honest GPU scene of the
    // tolerance tables in the book's chapter "Checking a GPU renderer" and fail every perturbed
    // shader (rows in italics: Banks 4.6 and the rest).
    let readme =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/README.md")).expect("README");
    let chapter = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/src/gpu.md"))
        .expect("docs/src/gpu.md");
    let example = readme
        .lines()
        .find(|l| l.trim_start().starts_with("pelage compare "))
        .expect("a compare example");
    let words: Vec<&str> = example.split_whitespace().collect();
    let at = words
        .iter()
        .position(|w| *w == "--tolerance")
        .expect("the example names its tolerance");
    let t = pelage::compare::Tolerance::parse(words[at + 1]).expect("tolerance parses");
    // The table counts pixels more than 8 steps off: a tolerance on the pixel count must use it.
    assert!(
        t.max_over_fraction.is_none() || t.channel_threshold == 8,
        "{t}"
    );
    // Vulkan's table, then GL's: both APIs are held to the same tier.
    for header in ["| scene | exact pixels", "| scene (GL) | exact pixels"] {
        let table: Vec<&str> = chapter
            .lines()
            .skip_while(|l| !l.starts_with(header))
            .skip(2)
            .take_while(|l| l.starts_with('|'))
            .collect();
        let mutants: Vec<&str> = table
            .iter()
            .copied()
            .filter(|r| r.starts_with("| *"))
            .collect();
        assert!(
            mutants.len() >= 5 && table.len() > mutants.len() + 20,
            "{header}: {table:?}"
        );
        assert!(mutants.iter().any(|r| r.contains("Banks 4.6")));
        for row in &table {
            let failures = judged_row(row, &t);
            if row.starts_with("| *") {
                assert!(!failures.is_empty(), "{example}: passes the mutant {row}");
            } else {
                assert!(failures.is_empty(), "{example}: fails {row}: {failures:?}");
            }
        }
        // The old example (`threshold=8,over=0.005`) lets Banks 4.6 through: this check can
        // fail.
        let old = pelage::compare::Tolerance::parse("threshold=8,over=0.005").expect("old");
        let banks = mutants
            .iter()
            .find(|r| r.contains("Banks 4.6"))
            .expect("row");
        assert!(judged_row(banks, &old).is_empty(), "{header}");
    }
}
