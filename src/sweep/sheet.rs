//! The contact sheet (beside the pipeline: sweeps): every point's render as a thumbnail in a grid,
//! in point order, its label (the parameter values that differ between points, and the frame rate)
//! written under it in the embedded font ([`crate::font`]).

use crate::font;
use image::{RgbaImage, imageops};
use std::borrow::Cow;

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

/// Where the cells of a contact sheet go: `columns × rows` cells of a thumbnail
/// `thumbnail_width` wide (the widest render, at most `THUMBNAIL_WIDTH`) and at most
/// `thumbnail_height` high, a label of `label_lines` under each. Computed from the renders'
/// sizes alone, so a sheet's memory is known before any render exists.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SheetLayout {
    /// Cells across.
    pub columns: u32,
    /// Cells down.
    pub rows: u32,
    /// Width of every thumbnail.
    pub thumbnail_width: u32,
    /// Height of the tallest thumbnail.
    pub thumbnail_height: u32,
    /// Label height under each thumbnail.
    pub label_height: u32,
}

impl SheetLayout {
    /// The layout of renders of `sizes` (width, height) in point order, each labelled with
    /// `label_lines` lines; `None` when there is nothing. The grid has `ceil(sqrt(n))` columns.
    pub fn new(sizes: &[(u32, u32)], label_lines: usize) -> Option<Self> {
        let n = u32::try_from(sizes.len()).ok()?;
        if n == 0 {
            return None;
        }
        let columns = (1..=n)
            .find(|&c| u64::from(c) * u64::from(c) >= u64::from(n))
            .unwrap_or(n);
        let thumbnail_width = sizes
            .iter()
            .map(|&(w, _)| w.min(THUMBNAIL_WIDTH))
            .max()
            .unwrap_or(1);
        let thumbnail_height = sizes
            .iter()
            .map(|&size| thumbnail_height(size, thumbnail_width))
            .max()
            .unwrap_or(1);
        let lines = u32::try_from(label_lines).unwrap_or(u32::MAX);
        Some(SheetLayout {
            columns,
            rows: n.div_ceil(columns),
            thumbnail_width,
            thumbnail_height,
            label_height: lines.saturating_mul(label_line_height()).saturating_add(4),
        })
    }

    /// The sheet's width and height in pixels.
    pub fn sheet_size(&self) -> (u64, u64) {
        let cell_w = u64::from(self.thumbnail_width) + u64::from(GAP);
        let cell_h =
            u64::from(self.thumbnail_height) + u64::from(self.label_height) + u64::from(GAP);
        (
            u64::from(self.columns) * cell_w + u64::from(GAP),
            u64::from(self.rows) * cell_h + u64::from(GAP),
        )
    }

    /// The size of the thumbnail of a render of `size`.
    pub fn thumbnail_size(&self, size: (u32, u32)) -> (u32, u32) {
        (
            self.thumbnail_width,
            thumbnail_height(size, self.thumbnail_width),
        )
    }

    /// The thumbnail of `render` (scaled with a triangle filter, which is deterministic; the
    /// render itself when it has the thumbnail's size already).
    pub fn thumbnail<'r>(&self, render: &'r RgbaImage) -> Cow<'r, RgbaImage> {
        let (w, h) = self.thumbnail_size(render.dimensions());
        if render.dimensions() == (w, h) {
            Cow::Borrowed(render)
        } else {
            Cow::Owned(imageops::resize(
                render,
                w,
                h,
                imageops::FilterType::Triangle,
            ))
        }
    }
}

/// Builds the sheet from `(render, label lines)` in point order; `None` when there is nothing.
/// Thumbnails are scaled with a triangle filter, which is deterministic, and placed in a grid of
/// `ceil(sqrt(n))` columns ([`SheetLayout`]). Renders already scaled by
/// [`SheetLayout::thumbnail`] give the same sheet, so a caller can keep thumbnails only.
pub fn contact_sheet(cells: &[(RgbaImage, Vec<String>)]) -> Option<RgbaImage> {
    let sizes: Vec<(u32, u32)> = cells.iter().map(|(im, _)| im.dimensions()).collect();
    let lines = cells.iter().map(|(_, l)| l.len()).max().unwrap_or(0);
    let layout = SheetLayout::new(&sizes, lines)?;
    let (sheet_w, sheet_h) = layout.sheet_size();
    let mut sheet = RgbaImage::from_pixel(
        u32::try_from(sheet_w).ok()?,
        u32::try_from(sheet_h).ok()?,
        image::Rgba(BACKGROUND),
    );
    let cell_w = layout.thumbnail_width + GAP;
    let cell_h = layout.thumbnail_height + layout.label_height + GAP;
    for (i, (render, label)) in cells.iter().enumerate() {
        let (cx, cy) = (i as u32 % layout.columns, i as u32 / layout.columns);
        let (x, y) = (GAP + cx * cell_w, GAP + cy * cell_h);
        let thumb = layout.thumbnail(render);
        imageops::replace(&mut sheet, thumb.as_ref(), i64::from(x), i64::from(y));
        for (k, line) in label.iter().enumerate() {
            font::draw(
                &mut sheet,
                x as f32,
                (y + layout.thumbnail_height + 3 + k as u32 * label_line_height()) as f32,
                TEXT_PX,
                INK,
                line,
            );
        }
    }
    Some(sheet)
}

fn thumbnail_height((w, h): (u32, u32), width: u32) -> u32 {
    let scaled = u64::from(h) * u64::from(width) / u64::from(w.max(1));
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
        // Thumbnails made first give the same sheet, and the layout knows its size.
        let layout = SheetLayout::new(&[(640, 480); 3], 1).expect("layout");
        let thumbnails: Vec<(RgbaImage, Vec<String>)> = cells
            .iter()
            .map(|(im, l)| (layout.thumbnail(im).into_owned(), l.clone()))
            .collect();
        assert_eq!(thumbnails[0].0.dimensions(), (320, 240));
        assert_eq!(contact_sheet(&thumbnails).expect("sheet"), sheet);
        assert_eq!(
            layout.sheet_size(),
            (u64::from(sheet.width()), u64::from(sheet.height()))
        );
    }
}
