//! Fur modelling (thesis 3.1; fur bake): strands, cones, and baked shell and fin textures.
//!
//! The data path: [`FurParams`] → [`generate_strands`] (MT19937 from an explicit seed, one block
//! of draws per strand) → cones around each sampled Bézier segment → [`bake_shells`] (one
//! texture pair per shell layer, periodic tile) and [`bake_fin`] (a side view of a narrow strip;
//! [`bake_fin_for_shells`] fits the strip's strand count and radii to the baked shells first).
//! [`draw_diagram`] draws the thesis's strand figures 3.2–3.7 from this same code.
//!
//! Units: the shell tile is the periodic unit square `x, y ∈ [0, 1)`; heights and radii are in
//! the same unit. Tangent space: `x` = texture `u`, `y` = texture `v`, `z` = up. Images are
//! row-major from row 0 (`v = 0`); 8-bit values use [`unorm8`]; tangents are stored as
//! `unorm8(t·0.5 + 0.5)` and read back with [`tangent_from_rgb8`]. Every result is identical
//! for any rayon thread count.
//!
//! # Cones and tangents (thesis 3.1.1, figures 3.3, 3.4, 3.7)
//! A strand sampled at `strand_resolution` equal Bézier parameter steps becomes a chain of
//! truncated cones (radius linear from `base_radius` to `tip_radius` in the parameter), each with
//! `circle_resolution` = `C` flat facets. Each segment has a frame `(e1, e2)` perpendicular to its
//! axis: `e1` is `+x` made perpendicular to the axis (`+y` when the axis is within `acos 0.9` of
//! `x`), `e2 = axis × e1`; angles around the axis start at `e1` and grow towards `e2`; facet `j`
//! spans `[j, j+1)·2π/C`. The tangent of facet `j` is its slanted centre line, from the middle of
//! its base-circle chord to the middle of its top-circle chord:
//! `normalize(d + (r1 − r0)·cos(π/C)·(cos φ_j e1 + sin φ_j e2))`, `d` the segment's axis vector and
//! `φ_j = (j + ½)·2π/C`. A tapered cone thus gives tangents that vary around its circumference,
//! quantised to `C` facets (why the thesis calls `circle_resolution` the lighting resolution). A
//! texel inside the cone, exposed by slicing, takes the tangent of the outer facet at its angle.
//!
//! # Alpha
//! Straight (not premultiplied). Shell layer `i` of `N`: covered fraction ·
//! [`gaussian_layer_weight`]`((i + ½)/N, gaussian_sigma)` = `exp(−((i+½)/N)² / (2σ²))`.
//! Texels no strand covers have alpha 0 and borrow colour and tangent from covered 8-neighbours
//! (dilation, for bilinear filtering), else [`EMPTY_COLOUR`] and [`EMPTY_TANGENT`].

mod bake;
mod cone;
mod diagram;
mod fin;
mod image;
mod params;
mod strand;

pub use bake::{
    ShellLayer, ShellTextures, bake_shells, bake_shells_with_density, gaussian_layer_weight,
    layer_mid_height,
};
pub use diagram::{
    DIAGRAM_HEIGHT, DIAGRAM_SHELLS, DIAGRAM_WIDTH, DiagramOptions, Figure, MAX_DIAGRAM_RESOLUTION,
    draw_diagram,
};
pub use fin::{
    FIN_FIT_HEIGHTS, FinFit, FinTexture, RunStats, bake_fin, bake_fin_for_shells, bake_fin_strands,
    fin_run_stats, shell_run_stats,
};
pub use image::{
    EMPTY_COLOUR, EMPTY_TANGENT, Rgba8Image, tangent_from_rgb8, tangent_to_rgb8, unorm8,
};
pub use params::{
    FurError, FurParams, MAX_BAKE_RESOLUTION, MAX_LENGTH, MAX_RESOLUTION, MAX_SLOPE_DEG,
    MAX_STRANDS, MAX_SUPERSAMPLE,
};
pub use strand::{
    DRAWS_PER_STRAND, FIN_SEED_OFFSET, Strand, bezier_derivative, bezier_point, bezier_tangent,
    generate_fin_strands, generate_strands, unit_f32,
};

#[cfg(test)]
mod tests {
    use super::*;

    /// Composites straight-alpha RGBA over mid grey.
    fn over_grey(c: [u8; 4]) -> [u8; 3] {
        let a = c[3] as f32 / 255.0;
        let mix = |v: u8| (v as f32 * a + 96.0 * (1.0 - a)).round() as u8;
        [mix(c[0]), mix(c[1]), mix(c[2])]
    }

    /// Writes `$CARGO_TARGET_DIR/shell_layers.png` (or `target/`): top row the colour of layers
    /// 0, N/2, N−1 and the fin (flipped so the root is at the bottom), bottom row their tangents
    /// (RGB as stored, alpha ignored). Look at it; it is not a golden.
    #[test]
    #[ignore = "writes a debug image to look at"]
    fn write_debug_png() {
        let p = FurParams::default();
        let strands = generate_strands(&p, 1234).expect("valid");
        let shells = bake_shells(&p, &strands).expect("bake");
        let fin = bake_fin(&p, 1234).expect("bake");
        let n = shells.layers.len();
        let r = p.texture_resolution;
        let mut panels: Vec<(&Rgba8Image, &Rgba8Image, bool)> = [0, n / 2, n - 1]
            .iter()
            .map(|&i| (&shells.layers[i].colour, &shells.layers[i].tangent, false))
            .collect();
        panels.push((&fin.colour, &fin.tangent, true));
        let gap = 4;
        let w = panels.len() as u32 * (r + gap);
        let mut img =
            ::image::RgbImage::from_pixel(w, 2 * (r + gap), ::image::Rgb([255, 255, 255]));
        for (k, (colour, tangent, flip)) in panels.iter().enumerate() {
            for y in 0..r {
                for x in 0..r {
                    let sy = if *flip { r - 1 - y } else { y };
                    let c = colour.get(x, sy).unwrap_or_default();
                    let t = tangent.get(x, sy).unwrap_or_default();
                    let px = k as u32 * (r + gap) + x;
                    img.put_pixel(px, y, ::image::Rgb(over_grey(c)));
                    img.put_pixel(px, r + gap + y, ::image::Rgb([t[0], t[1], t[2]]));
                }
            }
        }
        let dir = std::env::var("CARGO_TARGET_DIR").unwrap_or_else(|_| "target".into());
        let path = std::path::Path::new(&dir).join("shell_layers.png");
        let scaled = ::image::imageops::resize(
            &img,
            w * 2,
            4 * (r + gap),
            ::image::imageops::FilterType::Nearest,
        );
        scaled.save(&path).expect("write png");
        eprintln!("wrote {}", path.display());
    }

    /// Bake timings of thesis-sized configurations (run in release).
    #[test]
    #[ignore = "timing; run with --release"]
    fn bake_timing() {
        for (strands, shells, circle) in [(3000u32, 30u32, 20u32), (10_000, 30, 50)] {
            let p = FurParams {
                number_of_strands: strands,
                number_of_shells: shells,
                circle_resolution: circle,
                strand_resolution: 20,
                texture_resolution: 128,
                ..FurParams::default()
            };
            let start = std::time::Instant::now();
            let s = generate_strands(&p, 1).expect("valid");
            let t = bake_shells(&p, &s).expect("bake");
            let f = bake_fin(&p, 1).expect("bake");
            eprintln!(
                "{strands} strands, {shells} shells, circle {circle}, 128², supersample {}: {:.3} s ({} layers, fin {}×{})",
                p.supersample,
                start.elapsed().as_secs_f64(),
                t.layers.len(),
                f.colour.width,
                f.colour.height
            );
        }
    }
}
