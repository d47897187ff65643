//! The contact sheet: every point's render as a thumbnail in a grid, in point order, its
//! label (the parameter values that differ between points, and the frame rate) written under it
//! in the embedded font ([`crate::font`]).

use crate::font;
use image::{RgbaImage, imageops};

/// Thumbnail width in pixels (narrower renders are kept at their size).
pub const THUMBNAIL_WIDTH: u32 = 320;
const GAP: u32 = 8;
const BACKGROUND: [u8; 4] = [24, 24, 28, 255];
const INK: [u8; 3] = [235, 235, 235];
/// Label text size, pixels.
const TEXT_PX: f32 = 14.0;

/// Height of one label line, pixels.
pub fn label_line_height() -> u32 {
    font::line_height(TEXT_PX).ceil() as u32 + 1
}

/// Builds the sheet from `(render, label lines)` in point order; `None` when there is nothing.
/// Thumbnails are scaled with a triangle filter, which is deterministic, and placed in a grid of
/// `ceil(sqrt(n))` columns.
pub fn contact_sheet(cells: &[(RgbaImage, Vec<String>)]) -> Option<RgbaImage> {
    let n = cells.len() as u32;
    if n == 0 {
        return None;
    }
    let columns = (1..=n).find(|c| c * c >= n).unwrap_or(n);
    let rows = n.div_ceil(columns);
    let width = cells
        .iter()
        .map(|(im, _)| im.width().min(THUMBNAIL_WIDTH))
        .max()
        .unwrap_or(1);
    let height = cells
        .iter()
        .map(|(im, _)| thumbnail_height(im, width))
        .max()
        .unwrap_or(1);
    let lines = cells.iter().map(|(_, l)| l.len()).max().unwrap_or(0) as u32;
    let label_height = lines * label_line_height() + 4;
    let cell_w = width + GAP;
    let cell_h = height + label_height + GAP;
    let mut sheet = RgbaImage::from_pixel(
        columns * cell_w + GAP,
        rows * cell_h + GAP,
        image::Rgba(BACKGROUND),
    );
    for (i, (render, label)) in cells.iter().enumerate() {
        let (cx, cy) = (i as u32 % columns, i as u32 / columns);
        let (x, y) = (GAP + cx * cell_w, GAP + cy * cell_h);
        let h = thumbnail_height(render, width);
        let thumb = if render.width() == width && render.height() == h {
            render.clone()
        } else {
            imageops::resize(render, width, h, imageops::FilterType::Triangle)
        };
        imageops::replace(&mut sheet, &thumb, i64::from(x), i64::from(y));
        for (k, line) in label.iter().enumerate() {
            font::draw(
                &mut sheet,
                x as f32,
                (y + height + 3 + k as u32 * label_line_height()) as f32,
                TEXT_PX,
                INK,
                line,
            );
        }
    }
    Some(sheet)
}

fn thumbnail_height(render: &RgbaImage, width: u32) -> u32 {
    let scaled = u64::from(render.height()) * u64::from(width) / u64::from(render.width().max(1));
    scaled.clamp(1, u64::from(u32::MAX)) as u32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_are_laid_out_in_a_square_grid_in_order() {
        let colours = [[255, 0, 0, 255], [0, 255, 0, 255], [0, 0, 255, 255]];
        let cells: Vec<(RgbaImage, Vec<String>)> = colours
            .iter()
            .map(|&c| {
                (
                    RgbaImage::from_pixel(640, 480, image::Rgba(c)),
                    vec!["A=1".into()],
                )
            })
            .collect();
        let sheet = contact_sheet(&cells).expect("sheet");
        // Three cells: two columns, two rows of 320×240 thumbnails.
        let cell_h = 240 + label_line_height() + 4 + GAP;
        assert_eq!(sheet.width(), 2 * (320 + GAP) + GAP);
        assert_eq!(sheet.height(), 2 * cell_h + GAP);
        let centre = |i: u32| {
            let (cx, cy) = (i % 2, i / 2);
            *sheet.get_pixel(GAP + cx * (320 + GAP) + 160, GAP + cy * cell_h + 120)
        };
        for (i, c) in colours.iter().enumerate() {
            assert_eq!(centre(i as u32).0, *c);
        }
        // The label is drawn under the first thumbnail.
        let label_row = (GAP + 240 + 3..GAP + 240 + 3 + label_line_height())
            .any(|y| (GAP..GAP + 30).any(|x| sheet.get_pixel(x, y)[0] > 180));
        assert!(label_row);
        assert!(contact_sheet(&[]).is_none());
    }
}
