//! `pelage compare REF_DIR TEST_DIR -o REPORT_DIR`: images paired by name, report.json and
//! report.html (worst first, missing and extra files listed), the exit status as for one pair;
//! and the page as a real browser shows it: headless Chromium loads it, every image decodes,
//! the rows are there in order, and a screenshot is taken. Without Chromium that part is skipped
//! with a note, unless `PELAGE_REQUIRE_CHROMIUM=1` (as in CI), which makes it fail.

mod common;
use common::{pelage, scratch};

use image::{Rgba, RgbaImage};
use std::path::{Path, PathBuf};
use std::process::Command;

fn path(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// A test card: gradients with a few shapes, `w`×`h`.
fn card(w: u32, h: u32) -> RgbaImage {
    RgbaImage::from_fn(w, h, |x, y| {
        let ring = ((x as i32 - 40).pow(2) + (y as i32 - 30).pow(2)) < 400;
        Rgba([
            (x * 255 / w) as u8,
            (y * 255 / h) as u8,
            if ring { 230 } else { 60 },
            255,
        ])
    })
}

/// Two folders: `same` (equal), `shifted` (a block changed: outside any tolerance but its own),
/// `float` (the capture an EXR of the same values), `only-ref` (no capture), `only-cap` (no
/// reference), and optionally `small` (sizes differ).
fn folders(dir: &Path, with_error: bool) -> (PathBuf, PathBuf) {
    let (r, c) = (dir.join("ref"), dir.join("cap"));
    std::fs::create_dir_all(&r).expect("ref");
    std::fs::create_dir_all(&c).expect("cap");
    let a = card(96, 64);
    a.save(r.join("same.png")).expect("w");
    a.save(c.join("same.png")).expect("w");
    a.save(r.join("shifted.png")).expect("w");
    let mut b = a.clone();
    for y in 10..30 {
        for x in 50..80 {
            b.put_pixel(x, y, Rgba([255, 0, 0, 255]));
        }
    }
    b.save(c.join("shifted.png")).expect("w");
    let mut slight = a.clone();
    slight.put_pixel(5, 5, Rgba([0, 0, 0, 255]));
    a.save(r.join("slight.png")).expect("w");
    slight.save(c.join("slight.png")).expect("w");
    a.save(r.join("float.png")).expect("w");
    image::DynamicImage::ImageRgba8(a.clone())
        .to_rgba32f()
        .save(c.join("float.exr"))
        .expect("exr");
    a.save(r.join("only-ref.png")).expect("w");
    a.save(c.join("only-cap.png")).expect("w");
    std::fs::write(c.join("notes.txt"), "not an image").expect("w");
    if with_error {
        a.save(r.join("small.png")).expect("w");
        card(50, 40).save(c.join("small.png")).expect("w");
    }
    (r, c)
}

/// `pelage compare REFERENCES CAPTURES -o OUT` with `options` after it.
fn compare_folders(r: &Path, c: &Path, out: &Path, options: &[&str]) -> std::process::Output {
    let mut args = vec!["compare", path(r), path(c), "-o", path(out)];
    args.extend_from_slice(options);
    pelage(&args)
}

fn report_json(dir: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(dir.join("report.json")).expect("report.json"))
        .expect("JSON")
}

#[test]
fn folders_are_compared_pair_by_pair_worst_first() {
    let dir = scratch("folders");
    let (r, c) = folders(&dir, false);
    let out = dir.join("report");
    let o = compare_folders(&r, &c, &out, &[]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    // A reference without a capture and two pairs outside exact: exit 1.
    assert_eq!(o.status.code(), Some(1), "{stdout}");
    assert!(stdout.contains("MISSING only-ref.png"), "{stdout}");
    assert!(stdout.contains("extra only-cap.png"), "{stdout}");
    let json = report_json(&out);
    let rows = json["rows"].as_array().expect("rows");
    let names: Vec<&str> = rows
        .iter()
        .map(|r| r["name"].as_str().expect("name"))
        .collect();
    // Worst first: the big change, then the one pixel, then the equal pairs by name.
    assert_eq!(names, ["shifted", "slight", "float", "same"]);
    let verdicts: Vec<&str> = rows
        .iter()
        .map(|r| r["verdict"].as_str().expect("v"))
        .collect();
    assert_eq!(verdicts, ["fail", "fail", "pass", "pass"]);
    assert_eq!(rows[2]["capture"], "float.exr");
    assert_eq!(json["missing"], serde_json::json!(["only-ref.png"]));
    assert_eq!(json["extra"], serde_json::json!(["only-cap.png"]));
    assert_eq!(
        (json["passed"].as_u64(), json["failed"].as_u64()),
        (Some(2), Some(2))
    );
    // Every image the rows name is there, and the heat map carries its legend below the map.
    for row in rows {
        for image in row["images"].as_array().expect("images") {
            assert!(out.join(image.as_str().expect("path")).is_file(), "{image}");
        }
    }
    let heat = common::open_rgba8(out.join(rows[0]["images"][1].as_str().expect("heat")));
    assert_eq!(
        heat.dimensions(),
        (
            pelage::compare::legend::LEGEND_MIN_WIDTH,
            64 + pelage::compare::legend::LEGEND_HEIGHT
        )
    );
    let html = std::fs::read_to_string(out.join("report.html")).expect("html");
    assert_eq!(html.matches("<tr class=\"row ").count(), 4);
    // The images scale to the page (the browser check below measures it at 1400 pixels).
    assert!(html.contains("img{display:block;max-width:100%;height:auto}"));
    assert!(html.contains("div.images{display:flex;flex-wrap:wrap;"));
    assert!(html.find("data-name=\"shifted\"") < html.find("data-name=\"same\""));

    // A tolerance that forgives the one pixel but not the block; without the reference that
    // has no capture, only the block fails: still 1. A partial tolerance loose enough for
    // everything: 0.
    std::fs::remove_file(r.join("only-ref.png")).expect("rm");
    let o = compare_folders(&r, &c, &out, &["--tolerance", "threshold=8,over=0.001"]);
    assert_eq!(o.status.code(), Some(1));
    let json = report_json(&out);
    assert_eq!(
        (json["passed"].as_u64(), json["failed"].as_u64()),
        (Some(3), Some(1))
    );
    let o = compare_folders(&r, &c, &out, &["--tolerance", "psnr=5"]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
    // The report folder used again holds only this report's images (2 pairs × 4), and what
    // else it held is kept.
    std::fs::write(out.join("images/notes.txt"), "mine").expect("write");
    for name in ["slight.png", "float.png"] {
        std::fs::remove_file(r.join(name)).expect("rm");
    }
    let again = compare_folders(&r, &c, &out, &["--tolerance", "psnr=5"]);
    assert_eq!(again.status.code(), Some(0));
    let images = std::fs::read_dir(out.join("images"))
        .expect("images")
        .count();
    assert_eq!(images, 2 * 4 + 1);
}

#[test]
fn every_pair_of_a_folder_is_held_to_the_memory_limit_before_decoding() {
    let dir = scratch("memory");
    let (r, c) = folders(&dir, false);
    let out = dir.join("report");
    // 96×64 images need about 0.7 MB each pair; 100K is below that, so every pair is refused
    // from its headers, named in its row, and the run exits 2.
    let o = compare_folders(&r, &c, &out, &["--max-memory", "100K"]);
    assert_eq!(
        o.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let json = report_json(&out);
    let rows = json["rows"].as_array().expect("rows");
    assert!(!rows.is_empty(), "{json}");
    for row in rows {
        assert_eq!(row["verdict"], "error", "{row}");
        let error = row["error"].as_str().unwrap_or_default();
        assert!(error.contains("--max-memory"), "{row}");
    }
    // The default limit lets the same folders through.
    let o = compare_folders(&r, &c, &out, &[]);
    assert_eq!(o.status.code(), Some(1));
}

#[test]
fn a_pair_that_cannot_be_compared_makes_exit_2_and_bad_calls_are_refused() {
    let dir = scratch("errors");
    let (r, c) = folders(&dir, true);
    let out = dir.join("report");
    let o = compare_folders(&r, &c, &out, &[]);
    assert_eq!(o.status.code(), Some(2));
    let json = report_json(&out);
    assert_eq!(json["rows"][0]["name"], "small");
    assert_eq!(json["rows"][0]["verdict"], "error");
    assert!(
        json["rows"][0]["error"]
            .as_str()
            .is_some_and(|e| e.contains("sizes differ")),
        "{json}"
    );
    // Two folders without -o; a folder against a file; -o for one pair.
    let o = pelage(&["compare", path(&r), path(&c)]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("-o REPORT_DIR"));
    let o = pelage(&["compare", path(&r), path(&c.join("same.png"))]);
    assert_eq!(o.status.code(), Some(2));
    let o = pelage(&[
        "compare",
        path(&r.join("same.png")),
        path(&c.join("same.png")),
        "-o",
        path(&out),
    ]);
    assert_eq!(o.status.code(), Some(2));
}

/// Chromium's command, when it is installed.
fn chromium() -> Option<String> {
    ["chromium", "chromium-browser", "google-chrome"]
        .into_iter()
        .find(|c| {
            Command::new(c)
                .arg("--version")
                .output()
                .is_ok_and(|o| o.status.success())
        })
        .map(str::to_string)
}

fn headless(browser: &str, profile: &Path) -> Command {
    let mut c = Command::new(browser);
    c.args([
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-quic",
        "--no-first-run",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        "--virtual-time-budget=5000",
    ])
    .arg(format!("--user-data-dir={}", profile.display()));
    c
}

#[test]
fn the_report_page_loads_in_headless_chromium_with_its_rows_and_images() {
    let Some(browser) = chromium() else {
        assert!(
            std::env::var("PELAGE_REQUIRE_CHROMIUM").as_deref() != Ok("1"),
            "PELAGE_REQUIRE_CHROMIUM=1 but no chromium: apt-get install chromium"
        );
        eprintln!(
            "SKIPPED: {} needs chromium (run .ci/setup)",
            std::thread::current().name().unwrap_or("a test")
        );
        return;
    };
    let dir = scratch("chromium");
    let (r, c) = folders(&dir, true);
    // A pair too wide to sit three abreast in a 1400-pixel window.
    let wide = card(900, 600);
    wide.save(r.join("wide.png")).expect("w");
    wide.save(c.join("wide.png")).expect("w");
    let out = dir.join("report");
    compare_folders(&r, &c, &out, &[]);
    let page = format!("file://{}", path(&out.join("report.html")));
    let o = headless(&browser, &dir.join("profile-dom"))
        .arg("--window-size=1400,900")
        .arg("--dump-dom")
        .arg(&page)
        .output()
        .expect("chromium runs");
    let dom = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // The page's script ran after every image was fetched: 5 compared pairs × 3 images, all
    // decoded by the browser (the EXR capture's copy is a PNG it can show).
    assert!(dom.contains("data-images-loaded=\"15/15\""), "{dom}");
    // At 1400 pixels nothing runs off the right edge; the small pairs' images sit side by
    // side, the wide pair's under each other.
    assert!(dom.contains("data-overflow=\"0\""), "{dom}");
    assert!(dom.contains("data-side-by-side=\"4/5\""), "{dom}");
    let rows: Vec<&str> = dom
        .split("<tr class=\"row ")
        .skip(1)
        .map(|s| s.split('"').next().unwrap_or(""))
        .collect();
    assert_eq!(
        rows,
        ["error", "fail", "fail", "pass", "pass", "pass"],
        "{dom}"
    );
    assert!(dom.contains("only-ref.png") && dom.contains("only-cap.png"));
    let shot = dir.join("shot.png");
    let o = headless(&browser, &dir.join("profile-shot"))
        .arg("--window-size=1200,900")
        .arg(format!("--screenshot={}", path(&shot)))
        .arg(&page)
        .output()
        .expect("chromium runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let shot = common::open_rgba8(&shot);
    assert_eq!(shot.dimensions(), (1200, 900));
    // Not a blank page: the verdict cells' colours are there (pass green, fail red).
    let has = |c: [u8; 3]| {
        shot.pixels()
            .any(|p| p[0] == c[0] && p[1] == c[1] && p[2] == c[2])
    };
    assert!(has([0xd0, 0xf0, 0xd0]) && has([0xf8, 0xd0, 0xd0]));
}
