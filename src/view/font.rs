//! The viewer's status line and key list, drawn straight into the window's `0x00RRGGBB` buffer
//! with the library's 5×7 font ([`pelage::text`]), each font pixel a `scale`² block.

pub use pelage::text::{ADVANCE, GLYPH_WIDTH, LINE_HEIGHT, glyph};

/// Width in window pixels of `text` drawn at `scale`.
pub fn text_width(text: &str, scale: usize) -> usize {
    text.chars().count() * ADVANCE * scale
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

    /// Draws `text` with its top-left corner at (`x`, `y`), each font pixel a `scale`² block of
    /// `colour`. Clipped to the canvas.
    pub fn text(&mut self, x: usize, y: usize, text: &str, scale: usize, colour: u32) {
        for (i, c) in text.chars().enumerate() {
            let left = x + i * ADVANCE * scale;
            for (r, bits) in glyph(c).iter().enumerate() {
                for col in 0..GLYPH_WIDTH {
                    if bits & (0x10 >> col) == 0 {
                        continue;
                    }
                    for dy in 0..scale {
                        for dx in 0..scale {
                            let (px, py) = (left + col * scale + dx, y + r * scale + dy);
                            if px < self.width && py < self.height {
                                self.pixels[py * self.width + px] = colour;
                            }
                        }
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_sets_exactly_the_glyph_pixels_and_clips() {
        let mut pixels = vec![0u32; 12 * 8];
        let mut canvas = Canvas {
            pixels: &mut pixels,
            width: 12,
            height: 8,
        };
        canvas.text(0, 0, "L1", 1, 0xFFFFFF);
        // 'L': the left column and the bottom row; '1' starts six pixels to the right.
        let lit = |x: usize, y: usize| pixels[y * 12 + x] != 0;
        assert!((0..7).all(|y| lit(0, y)));
        assert!((0..5).all(|x| lit(x, 6)));
        assert!(!lit(1, 0) && !lit(5, 6));
        assert!(lit(8, 0) && lit(7, 1));
        // Drawing past the edges writes nothing out of bounds.
        let mut canvas = Canvas {
            pixels: &mut pixels,
            width: 12,
            height: 8,
        };
        canvas.text(10, 5, "WW", 2, 1);
        assert_eq!(text_width("WW", 2), 24);
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
