//! Writes the surface maps the example scenes use (`scenes/maps/*.png`): run
//! `cargo run --example surface_maps` to regenerate them (the committed files are its output).
//!
//! - `half-length.png`: fur length 0.3 on the half `u < 0.5` of the mesh, 1 on the other, with
//!   ramps of 1/32 between them (length map, red channel).
//! - `half-tint.png`: the short half greyer (colour map: red × 0.55, green × 0.75).
//! - `density-falloff.png`: density `0.5 + 0.5·cos(2πu)`: full at `u = 0`, none at `u = 0.5`.
//! - `swirl.png`: 4 × 2 swirls: the combing direction turns around each cell's centre, leaning
//!   most halfway out (direction map, red and green = `u`, `v` as `c·2 − 1`).

use image::{Rgba, RgbaImage};
use std::path::Path;

fn unorm8(x: f64) -> u8 {
    (x.clamp(0.0, 1.0) * 255.0 + 0.5).floor() as u8
}

fn smoothstep(a: f64, b: f64, x: f64) -> f64 {
    let t = ((x - a) / (b - a)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// 1 on the long half, 0 on the short half `u < 0.5`, with ramps around `u = 0` and `0.5`.
fn long_half(u: f64) -> f64 {
    let ramp = 1.0 / 64.0;
    smoothstep(0.5 - ramp, 0.5 + ramp, u) * (1.0 - smoothstep(1.0 - ramp, 1.0 + ramp, u))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/maps");
    std::fs::create_dir_all(&dir)?;

    let (w, h) = (256u32, 8u32);
    let centre = |i: u32, n: u32| (f64::from(i) + 0.5) / f64::from(n);
    let length = RgbaImage::from_fn(w, h, |x, _| {
        let u = centre(x, w);
        // Wrapped at u = 0/1: the short half starts at the seam.
        let long = long_half(u).max(1.0 - smoothstep(-1.0 / 64.0, 1.0 / 64.0, u.min(1.0 - u)));
        let v = unorm8(0.3 + 0.7 * long);
        Rgba([v, v, v, 255])
    });
    length.save(dir.join("half-length.png"))?;
    let tint = RgbaImage::from_fn(w, h, |x, _| {
        let u = centre(x, w);
        let long = long_half(u).max(1.0 - smoothstep(-1.0 / 64.0, 1.0 / 64.0, u.min(1.0 - u)));
        // The short half greyer: red and green taken down, blue kept.
        let short = 1.0 - long;
        Rgba([
            unorm8(1.0 - 0.45 * short),
            unorm8(1.0 - 0.25 * short),
            255,
            255,
        ])
    });
    tint.save(dir.join("half-tint.png"))?;

    let density = RgbaImage::from_fn(w, h, |x, _| {
        let u = centre(x, w);
        let v = unorm8(0.5 + 0.5 * (std::f64::consts::TAU * u).cos());
        Rgba([v, v, v, 255])
    });
    density.save(dir.join("density-falloff.png"))?;

    let (sw, sh) = (256u32, 128u32);
    let swirl = RgbaImage::from_fn(sw, sh, |x, y| {
        // Cells of 64 × 64 texels; within a cell, coordinates in [−1, 1].
        let cx = (f64::from(x % 64) + 0.5) / 32.0 - 1.0;
        let cy = (f64::from(y % 64) + 0.5) / 32.0 - 1.0;
        let r = (cx * cx + cy * cy).sqrt();
        // Around the centre (counter-clockwise), turning slightly inwards; strongest at r = ½.
        let strength = 0.9 * (std::f64::consts::PI * r.min(1.0)).sin();
        let (tx, ty) = if r > 0.0 {
            (-cy / r, cx / r)
        } else {
            (0.0, 0.0)
        };
        let (ix, iy) = if r > 0.0 {
            (-cx / r, -cy / r)
        } else {
            (0.0, 0.0)
        };
        let (dx, dy) = (0.9 * tx + 0.3 * ix, 0.9 * ty + 0.3 * iy);
        Rgba([
            unorm8(0.5 + 0.5 * strength * dx),
            unorm8(0.5 + 0.5 * strength * dy),
            128,
            255,
        ])
    });
    swirl.save(dir.join("swirl.png"))?;
    println!("wrote {}", dir.display());
    Ok(())
}
