//! The viewer's status line and key list, drawn straight into the window's `0x00RRGGBB` buffer
//! in the library's embedded font ([`pelage::font`], DejaVu Sans, anti-aliased), mixed case.

/// Width in window pixels of `text` at `px` pixels.
pub fn text_width(text: &str, px: f32) -> usize {
    pelage::font::text_width(text, px).ceil() as usize
}

/// Height in window pixels of one line of text at `px` pixels, with a little leading.
pub fn line_height(px: f32) -> usize {
    pelage::font::line_height(px).ceil() as usize + 2
}

/// A `0x00RRGGBB` window buffer.
pub struct Canvas<'a> {
    /// Pixels, row-major.
    pub pixels: &'a mut [u32],
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
}

impl Canvas<'_> {
    /// Darkens the rectangle to `keep`/256 of its brightness (a backdrop that keeps text
    /// readable over any fur). Clipped to the canvas.
    pub fn darken(&mut self, x: usize, y: usize, w: usize, h: usize, keep: u32) {
        for row in y.min(self.height)..(y + h).min(self.height) {
            for px in
                &mut self.pixels[row * self.width..][x.min(self.width)..(x + w).min(self.width)]
            {
                let channel = |shift: u32| (((*px >> shift) & 0xFF) * keep / 256) << shift;
                *px = channel(16) | channel(8) | channel(0);
            }
        }
    }

    /// Draws `text` with its top-left corner at (`x`, `y`) at `px` pixels in `colour`, blended
    /// by the glyphs' coverage. Clipped to the canvas.
    pub fn text(&mut self, x: usize, y: usize, text: &str, px: f32, colour: u32) {
        let (width, height) = (self.width, self.height);
        let pixels = &mut *self.pixels;
        pelage::font::rasterise(text, x as f32, y as f32, px, |gx, gy, coverage| {
            let (gx, gy) = (gx as usize, gy as usize);
            if gx < width && gy < height {
                let p = &mut pixels[gy * width + gx];
                let mix = |shift: u32| {
                    let under = ((*p >> shift) & 0xFF) as f32;
                    let over = ((colour >> shift) & 0xFF) as f32;
                    ((under + (over - under) * coverage).round() as u32).min(255) << shift
                };
                *p = mix(16) | mix(8) | mix(0);
            }
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_is_drawn_in_the_real_font_and_clipped() {
        let (w, h) = (120, 24);
        let mut pixels = vec![0u32; w * h];
        let mut canvas = Canvas {
            pixels: &mut pixels,
            width: w,
            height: h,
        };
        canvas.text(2, 2, "3.99 s", 14.0, 0x00FFFFFF);
        let lit: Vec<usize> = (0..w * h).filter(|&i| pixels[i] != 0).collect();
        assert!(lit.len() > 40, "{}", lit.len());
        // Anti-aliased: some pixels partly covered (grey), some fully (white).
        assert!(pixels.contains(&0x00FFFFFF));
        assert!(pixels.iter().any(|&p| p != 0 && p != 0x00FFFFFF));
        let right = lit.iter().map(|i| i % w).max().unwrap_or(0);
        assert!(right <= 2 + text_width("3.99 s", 14.0), "{right}");
        // "s" and "5" differ (the bitmap font drew lower case as capitals: "3.99S").
        let draw = |t: &str| {
            let mut px = vec![0u32; 20 * 20];
            let mut c = Canvas {
                pixels: &mut px,
                width: 20,
                height: 20,
            };
            c.text(1, 1, t, 14.0, 0x00FFFFFF);
            px
        };
        assert_ne!(draw("s"), draw("5"));
        assert_ne!(draw("s"), draw("S"));
        // Past the edges: nothing out of bounds.
        let mut canvas = Canvas {
            pixels: &mut pixels,
            width: w,
            height: h,
        };
        canvas.text(110, 18, "WWWW", 20.0, 1);
    }

    #[test]
    fn darken_scales_each_channel() {
        let mut pixels = vec![0x00FF8040u32; 4];
        let mut canvas = Canvas {
            pixels: &mut pixels,
            width: 2,
            height: 2,
        };
        canvas.darken(1, 0, 5, 1, 128);
        assert_eq!(pixels, vec![0x00FF8040, 0x007F4020, 0x00FF8040, 0x00FF8040]);
    }
}
