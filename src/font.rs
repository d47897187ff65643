//! Text in a real font (beside the pipeline): DejaVu Sans (embedded, `assets/fonts/DejaVuSans.ttf`,
//! Bitstream Vera licence, `assets/fonts/LICENSE`) rasterised by `ab_glyph`, with anti-aliased
//! coverage. The comparison report's legends, the strand diagrams and the viewer's status line use
//! it; the sweep's plots use the same font through `plotters`. No system font is read, so the pixels are the same
//! everywhere.

use ab_glyph::{Font as _, FontRef, PxScale, ScaleFont as _, point};
use image::RgbaImage;

/// The embedded font file.
pub const DEJAVU_SANS: &[u8] = include_bytes!("../assets/fonts/DejaVuSans.ttf");

/// The embedded font, parsed once.
pub fn font() -> &'static FontRef<'static> {
    static FONT: std::sync::OnceLock<FontRef<'static>> = std::sync::OnceLock::new();
    FONT.get_or_init(|| FontRef::try_from_slice(DEJAVU_SANS).expect("the embedded font parses"))
}

/// Width in pixels of `text` at a font size of `px` pixels (advances and kerning).
pub fn text_width(text: &str, px: f32) -> f32 {
    let font = font();
    let scaled = font.as_scaled(PxScale::from(px));
    let mut width = 0.0;
    let mut previous = None;
    for c in text.chars() {
        let id = scaled.glyph_id(c);
        if let Some(p) = previous {
            width += scaled.kern(p, id);
        }
        width += scaled.h_advance(id);
        previous = Some(id);
    }
    width
}

/// Calls `plot(x, y, coverage)` for every pixel `text` covers at `px` pixels, its top-left at
/// (`x`, `y`) (the top of the line: the baseline lies one ascent below). Coverage is in `[0, 1]`;
/// pixels left of or above zero are skipped.
pub fn rasterise(text: &str, x: f32, y: f32, px: f32, mut plot: impl FnMut(u32, u32, f32)) {
    let font = font();
    let scale = PxScale::from(px);
    let scaled = font.as_scaled(scale);
    let baseline = y + scaled.ascent();
    let mut caret = x;
    let mut previous = None;
    for c in text.chars() {
        let id = scaled.glyph_id(c);
        if let Some(p) = previous {
            caret += scaled.kern(p, id);
        }
        let glyph = id.with_scale_and_position(scale, point(caret, baseline));
        caret += scaled.h_advance(id);
        previous = Some(id);
        if let Some(outline) = font.outline_glyph(glyph) {
            let bounds = outline.px_bounds();
            outline.draw(|gx, gy, coverage| {
                let (px, py) = (bounds.min.x + gx as f32, bounds.min.y + gy as f32);
                if px >= 0.0 && py >= 0.0 {
                    plot(px as u32, py as u32, coverage.clamp(0.0, 1.0));
                }
            });
        }
    }
}

/// The height in pixels of a line of text at `px` pixels (ascent − descent).
pub fn line_height(px: f32) -> f32 {
    let font = font();
    let scaled = font.as_scaled(PxScale::from(px));
    scaled.ascent() - scaled.descent()
}

/// The height in pixels of a capital letter at `px` pixels (the top of "H" above the baseline),
/// for placing text by the top of its capitals rather than the top of its line.
pub fn cap_height(px: f32) -> f32 {
    let font = font();
    let scaled = font.as_scaled(PxScale::from(px));
    // The highest point of the outline, in font units (y up); "H" is straight lines only.
    let top = font.outline(font.glyph_id('H')).map(|o| {
        o.curves
            .iter()
            .flat_map(|c| match *c {
                ab_glyph::OutlineCurve::Line(a, b) => vec![a.y, b.y],
                ab_glyph::OutlineCurve::Quad(a, b, c) => vec![a.y, b.y, c.y],
                ab_glyph::OutlineCurve::Cubic(a, b, c, d) => vec![a.y, b.y, c.y, d.y],
            })
            .fold(0.0f32, f32::max)
    });
    top.map_or(scaled.ascent(), |t| t * scaled.v_scale_factor())
}

/// Draws `text` into `image` in `colour`, blended by coverage, its top-left at (`x`, `y`).
/// Clipped to the image.
pub fn draw(image: &mut RgbaImage, x: f32, y: f32, px: f32, colour: [u8; 3], text: &str) {
    let (w, h) = image.dimensions();
    rasterise(text, x, y, px, |px, py, coverage| {
        if px < w && py < h {
            let p = image.get_pixel_mut(px, py);
            for c in 0..3 {
                let blended = f32::from(p[c]) + (f32::from(colour[c]) - f32::from(p[c])) * coverage;
                p[c] = blended.round().clamp(0.0, 255.0) as u8;
            }
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_is_drawn_where_it_is_measured() {
        let mut image = RgbaImage::from_pixel(200, 40, image::Rgba([255, 255, 255, 255]));
        draw(&mut image, 10.0, 5.0, 20.0, [0, 0, 0], "Frame 3.99 s");
        let width = text_width("Frame 3.99 s", 20.0);
        assert!(width > 80.0 && width < 160.0, "{width}");
        let dark: Vec<(u32, u32)> = image
            .enumerate_pixels()
            .filter(|(_, _, p)| p[0] < 128)
            .map(|(x, y, _)| (x, y))
            .collect();
        assert!(dark.len() > 100);
        let (min_x, max_x) = (
            dark.iter().map(|d| d.0).min().unwrap(),
            dark.iter().map(|d| d.0).max().unwrap(),
        );
        assert!((10..=13).contains(&min_x), "{min_x}");
        assert!((max_x as f32) <= 10.0 + width + 1.0, "{max_x} {width}");
        assert!(
            dark.iter()
                .all(|d| d.1 >= 5 && (d.1 as f32) < 5.0 + line_height(20.0))
        );
    }

    #[test]
    fn lower_case_differs_from_upper_case() {
        // The bitmap font drew "s" as "S"; this one does not.
        let draw_one = |t: &str| {
            let mut image = RgbaImage::from_pixel(30, 30, image::Rgba([0, 0, 0, 255]));
            draw(&mut image, 2.0, 2.0, 22.0, [255, 255, 255], t);
            image
        };
        assert_ne!(draw_one("s"), draw_one("S"));
        assert_ne!(draw_one("5"), draw_one("S"));
    }

    #[test]
    fn capitals_are_about_three_quarters_of_the_size() {
        // DejaVu Sans: capitals 1493 font units high, and a pixel size is ascent − descent,
        // 1901 + 483 units.
        let cap = cap_height(20.0);
        assert!((cap - 20.0 * 1493.0 / 2384.0).abs() < 0.05, "{cap}");
        assert!(cap < line_height(20.0));
    }
}
