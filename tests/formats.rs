//! Image formats: `pelage render -o x.exr` holds the framebuffer's floats before the 8-bit
//! rounding (they round to the `.png`'s bytes), `--depth 16` PNGs hold them rounded to 16 bits,
//! an extension pelage cannot write is refused naming it, and `pelage compare` reads EXR,
//! 16-bit PNG, JPEG and BMP captures.

mod common;
use common::{pelage, scratch};

use pelage::raster::framebuffer::quantise_unorm8;
use std::path::{Path, PathBuf};

fn path(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

fn render(dir: &Path, name: &str, extra: &[&str]) -> PathBuf {
    let out = dir.join(name);
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/wind.toml");
    let mut args = vec![
        "render", scene, "--width", "96", "--height", "72", "--time", "0.5", "-o",
    ];
    args.push(path(&out));
    args.extend_from_slice(extra);
    let o = pelage(&args);
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    out
}

#[test]
fn exr_and_16_bit_png_hold_the_values_before_8_bit_rounding() {
    let dir = scratch("float");
    let png = image::open(render(&dir, "a.png", &[]))
        .expect("png")
        .to_rgba8();
    let exr = image::open(render(&dir, "a.exr", &[]))
        .expect("exr")
        .to_rgba32f();
    let png16 = image::open(render(&dir, "a16.png", &["--depth", "16"])).expect("png16");
    assert!(matches!(png16, image::DynamicImage::ImageRgba16(_)));
    let png16 = png16.to_rgba16();
    assert_eq!(exr.dimensions(), (96, 72));
    let mut fractional = 0;
    for ((&f, &b), &w) in exr.as_raw().iter().zip(png.as_raw()).zip(png16.as_raw()) {
        // The float rounds to the 8-bit byte by the framebuffer's rule...
        assert_eq!(quantise_unorm8(f), b, "{f}");
        // ...and the 16-bit value to the float within half a 16-bit step and f32's rounding
        // of `65535·c` (half an ulp below 65536: 2⁻⁹ of a step; e.g. c = 0.51338214 gives
        // 33644.498 in f64 but 33644.5 in f32, so 33645).
        assert!(
            (f64::from(w) / 65535.0 - f64::from(f).clamp(0.0, 1.0)).abs()
                <= (0.5 + 1.0 / 512.0) / 65535.0,
            "{w} {f}"
        );
        if (f * 255.0).fract() != 0.0 {
            fractional += 1;
        }
    }
    // The float image carries more than the 8-bit one: most values fall between 8-bit steps.
    assert!(fractional > exr.as_raw().len() / 4, "{fractional}");
    // The 8-bit PNG is unchanged by the new formats: the same bytes as a plain render.
    let plain = render(&dir, "plain.png", &[]);
    assert_eq!(
        std::fs::read(plain).expect("plain"),
        std::fs::read(dir.join("a.png")).expect("a")
    );
}

#[test]
fn an_extension_pelage_cannot_write_is_refused_naming_it() {
    let dir = scratch("refused");
    for (name, extra, expect) in [
        ("out.jpg", &[][..], ".jpg"),
        ("out.tiff", &[][..], ".tiff"),
        ("out.exr", &["--depth", "16"][..], "--depth 16"),
        ("out.png", &["--depth", "12"][..], "--depth 12"),
    ] {
        let out = dir.join(name);
        let mut args = vec![
            "render",
            "--width",
            "32",
            "--height",
            "24",
            "-o",
            path(&out),
        ];
        args.extend_from_slice(extra);
        let o = pelage(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{name}: {err}");
        assert!(err.contains(expect), "{name}: {err}");
        assert!(!out.exists(), "{name} written");
    }
}

#[test]
fn compare_reads_exr_16_bit_png_jpeg_and_bmp_captures() {
    let dir = scratch("captures");
    let png = render(&dir, "a.png", &[]);
    let exr = render(&dir, "a.exr", &[]);
    let png16 = render(&dir, "a16.png", &["--depth", "16"]);
    let image = image::open(&png).expect("png");
    let bmp = dir.join("a.bmp");
    image.to_rgb8().save(&bmp).expect("bmp");
    let jpeg = dir.join("a.jpg");
    image.to_rgb8().save(&jpeg).expect("jpeg");
    // The EXR reads back as the PNG's bytes; the 16-bit PNG within one step.
    let o = pelage(&["compare", path(&png), path(&exr)]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
    let o = pelage(&[
        "compare",
        path(&png),
        path(&png16),
        "--tolerance",
        "threshold=1",
    ]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
    // BMP keeps every colour (the render is opaque); JPEG is lossy but close.
    let o = pelage(&["compare", path(&png), path(&bmp)]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
    let o = pelage(&["compare", path(&png), path(&jpeg), "--json"]);
    assert_eq!(o.status.code(), Some(1), "JPEG is lossy: not exact");
    let json: serde_json::Value = serde_json::from_slice(&o.stdout).expect("JSON");
    let psnr = json["psnr"].as_f64().expect("finite PSNR");
    assert!(psnr > 25.0, "{psnr}");
}
