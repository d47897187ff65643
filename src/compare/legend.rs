//! Legends for the difference maps (beside the pipeline: comparison): a strip under the map with
//! its colour scale, the values along it and two lines saying what the colours mean, drawn in the
//! embedded font ([`crate::font`]), so that a map read on its own says what its colours mean.

use image::{Rgba, RgbaImage};

/// Which map a legend explains.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Legend {
    /// [`super::heat_map`]: the largest channel difference, 1 to 255 steps on a log scale; equal
    /// pixels dim grey.
    Heat,
    /// [`super::flip_heat_map`]: the FLIP error, 0.001 to 1 on a log scale, magma colours; the
    /// GPU tolerance's per-pixel FLIP bound marked on the scale.
    Flip,
}

/// Height in pixels of the legend strip.
pub const LEGEND_HEIGHT: u32 = 72;

/// Narrowest legend strip, pixels: a narrower map is padded on the right with the background.
pub const LEGEND_MIN_WIDTH: u32 = 320;

/// The legend strip's background.
const BACKGROUND: [u8; 4] = [24, 24, 28, 255];

/// Text size of the legend, pixels.
const TEXT_PX: f32 = 12.0;

/// The colour of `legend`'s scale at `s` in `[0, 1]` (left to right).
pub fn scale_colour(legend: Legend, s: f32) -> [u8; 4] {
    match legend {
        Legend::Heat => super::ramp(s),
        Legend::Flip => super::magma(s),
    }
}

/// The value `legend` marks on its scale, besides the ticks: (position, value). For FLIP, the
/// per-pixel bound of the GPU tolerance ([`super::GPU_TOLERANCE`]'s `flip-p99`): colours right
/// of the mark are errors that at most 1 % of a passing capture's pixels may have.
pub fn mark(legend: Legend) -> Option<(f32, f32)> {
    match legend {
        Legend::Heat => None,
        Legend::Flip => super::Tolerance::gpu()
            .max_flip_percentile
            .map(|(_, bound)| (super::flip_map_position(bound), bound)),
    }
}

/// The two lines under `legend`'s scale.
pub fn captions(legend: Legend) -> [String; 2] {
    match legend {
        Legend::Heat => [
            "largest channel difference, 8-bit steps (log)".to_string(),
            "grey: equal pixels (the reference, dimmed)".to_string(),
        ],
        Legend::Flip => [
            "FLIP error per pixel (log scale; black = equal)".to_string(),
            match mark(legend) {
                Some((_, bound)) => format!("white mark: gpu tolerance, 99 % of pixels ≤ {bound}"),
                None => String::new(),
            },
        ],
    }
}

/// The ticks of `legend`: (position along the scale in `[0, 1]`, label).
pub fn ticks(legend: Legend) -> Vec<(f32, String)> {
    match legend {
        Legend::Heat => [1u32, 2, 4, 8, 16, 32, 64, 128, 255]
            .iter()
            .map(|&d| ((d as f32).ln() / 255f32.ln(), d.to_string()))
            .collect(),
        Legend::Flip => ["0.001", "0.01", "0.1", "1"]
            .iter()
            .map(|&v| {
                let e: f32 = v.parse().expect("a number");
                (super::flip_map_position(e), v.to_string())
            })
            .collect(),
    }
}

/// `map` with its legend strip below ([`LEGEND_HEIGHT`] pixels; at least
/// [`LEGEND_MIN_WIDTH`] wide, the map padded on the right). The map's pixels are unchanged
/// at the top left.
pub fn with_legend(map: &RgbaImage, legend: Legend) -> RgbaImage {
    let (w, h) = map.dimensions();
    let width = w.max(LEGEND_MIN_WIDTH);
    let mut out = RgbaImage::from_pixel(width, h + LEGEND_HEIGHT, Rgba(BACKGROUND));
    image::imageops::replace(&mut out, map, 0, 0);
    let left = match legend {
        Legend::Heat => 44u32,
        Legend::Flip => 8u32,
    };
    let top = h + 4;
    let right = width - 14;
    let bar_height = 12;
    if legend == Legend::Heat {
        // Equal pixels: the reference dimmed to a quarter of its luma, grey.
        for y in top..top + bar_height {
            for x in 8..28 {
                out.put_pixel(x, y, Rgba([64, 64, 64, 255]));
            }
        }
        crate::font::draw(
            &mut out,
            4.0,
            (top + bar_height + 3) as f32,
            10.0,
            [200, 200, 200],
            "equal",
        );
    }
    for x in left..=right {
        let s = (x - left) as f32 / (right - left) as f32;
        let colour = scale_colour(legend, s);
        for y in top..top + bar_height {
            out.put_pixel(x, y, Rgba(colour));
        }
    }
    let white = [230, 230, 230];
    for (s, label) in ticks(legend) {
        let x = left as f32 + s * (right - left) as f32;
        for y in top + bar_height..top + bar_height + 3 {
            out.put_pixel(x.round() as u32, y, Rgba([230, 230, 230, 255]));
        }
        let tw = crate::font::text_width(&label, TEXT_PX);
        let tx = (x - tw / 2.0).clamp(0.0, width as f32 - tw);
        crate::font::draw(
            &mut out,
            tx,
            (top + bar_height + 3) as f32,
            TEXT_PX,
            white,
            &label,
        );
    }
    if let Some((s, _)) = mark(legend) {
        // A white line across the bar, a little longer than it, two pixels wide.
        let x = (left as f32 + s * (right - left) as f32).round() as u32;
        for y in top.saturating_sub(3)..top + bar_height + 3 {
            for dx in 0..2 {
                if y >= h {
                    out.put_pixel(x + dx, y, Rgba([255, 255, 255, 255]));
                }
            }
        }
    }
    for (k, caption) in captions(legend).iter().enumerate() {
        crate::font::draw(
            &mut out,
            8.0,
            (top + bar_height + 19 + 16 * k as u32) as f32,
            TEXT_PX,
            white,
            caption,
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_legend_keeps_the_map_and_shows_its_scale() {
        let map = RgbaImage::from_pixel(64, 48, Rgba([1, 2, 3, 255]));
        let out = with_legend(&map, Legend::Heat);
        assert_eq!(out.dimensions(), (LEGEND_MIN_WIDTH, 48 + LEGEND_HEIGHT));
        assert!((0..48).all(|y| (0..64).all(|x| out.get_pixel(x, y).0 == [1, 2, 3, 255])));
        // The bar's ends are the ramp's ends: 1 step (blue) at the left, 255 at the right.
        let row = 48 + 8;
        assert_eq!(out.get_pixel(44, row).0, super::super::ramp(0.0));
        assert_eq!(
            out.get_pixel(LEGEND_MIN_WIDTH - 14, row).0,
            super::super::ramp(1.0)
        );
        // Text was drawn under the bar (light pixels in the label rows).
        let light = (48 + 20..48 + LEGEND_HEIGHT)
            .flat_map(|y| (0..LEGEND_MIN_WIDTH).map(move |x| (x, y)))
            .filter(|&(x, y)| out.get_pixel(x, y)[0] > 150)
            .count();
        assert!(light > 200, "{light}");
        // A wide map keeps its width.
        let wide = RgbaImage::new(500, 10);
        assert_eq!(with_legend(&wide, Legend::Flip).width(), 500);
    }

    #[test]
    fn the_ticks_sit_where_the_scale_puts_their_values() {
        let heat = ticks(Legend::Heat);
        assert_eq!(heat.first().map(|t| t.0), Some(0.0));
        assert!((heat.last().map_or(0.0, |t| t.0) - 1.0).abs() < 1e-6);
        // 16 steps: log(16)/log(255), in f64.
        let t16 = heat.iter().find(|t| t.1 == "16").map_or(0.0, |t| t.0);
        assert!((f64::from(t16) - 16f64.ln() / 255f64.ln()).abs() < 1e-6);
        assert_eq!(scale_colour(Legend::Flip, 0.0), {
            let lut = nv_flip::magma_lut().to_vec();
            [lut[0], lut[1], lut[2], 255]
        });
        // FLIP: decades a third of the scale apart, the GPU bound 0.15 between 0.1 and 1.
        let flip = ticks(Legend::Flip);
        let at = |label: &str| flip.iter().find(|t| t.1 == label).map_or(-1.0, |t| t.0);
        assert_eq!(at("0.001"), 0.0);
        assert!((at("0.01") - 1.0 / 3.0).abs() < 1e-5, "{}", at("0.01"));
        assert!((at("0.1") - 2.0 / 3.0).abs() < 1e-5, "{}", at("0.1"));
        assert_eq!(at("1"), 1.0);
        let (s, bound) = mark(Legend::Flip).expect("the GPU tolerance bounds FLIP's p99");
        assert_eq!(bound, 0.15);
        assert!(s > at("0.1") && s < 0.8, "{s}");
        assert_eq!(mark(Legend::Heat), None);
    }

    #[test]
    fn the_captions_fit_the_narrowest_legend_and_the_mark_is_drawn() {
        for legend in [Legend::Heat, Legend::Flip] {
            for caption in captions(legend) {
                let w = crate::font::text_width(&caption, TEXT_PX);
                assert!(
                    8.0 + w <= LEGEND_MIN_WIDTH as f32,
                    "{caption:?}: {w} pixels"
                );
            }
        }
        let map = RgbaImage::from_pixel(64, 48, Rgba([0, 0, 0, 255]));
        let out = with_legend(&map, Legend::Flip);
        let (s, _) = mark(Legend::Flip).expect("a mark");
        let right = LEGEND_MIN_WIDTH - 14;
        let x = (8.0 + s * (right - 8) as f32).round() as u32;
        assert_eq!(out.get_pixel(x, 48 + 10).0, [255, 255, 255, 255]);
    }
}
