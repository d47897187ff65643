//! The frame-rate plot of a sweep: fps against the first parameter, one line per combination
//! of the other parameters. Drawn with tiny-skia (anti-aliased lines), labelled with the bitmap
//! font.

use super::ResultRow;
use crate::text;
use image::RgbaImage;
use tiny_skia::{Color, Paint, PathBuilder, Pixmap, Stroke, Transform};

const WIDTH: u32 = 900;
const HEIGHT: u32 = 540;
const LEFT: f32 = 70.0;
const RIGHT: f32 = 30.0;
const TOP: f32 = 40.0;
const BOTTOM: f32 = 60.0;
const INK: [u8; 4] = [30, 30, 30, 255];
/// Line colours, one per series, repeating.
const PALETTE: [[u8; 3]; 6] = [
    [31, 119, 180],
    [214, 39, 40],
    [44, 160, 44],
    [148, 103, 189],
    [255, 127, 14],
    [23, 190, 207],
];

/// Plots fps against the first parameter that takes more than one value (the first parameter
/// when none does), so that `--param number_of_spots=2 --param specular_tangents=1,3` plots
/// against the tangents. Its values are placed by number when every one is a number, else
/// evenly in point order. Rows with the same values of the other parameters form one line,
/// labelled in a legend. `None` without rows.
pub fn fps_plot(parameters: &[String], rows: &[ResultRow]) -> Option<RgbaImage> {
    if rows.is_empty() || parameters.is_empty() {
        return None;
    }
    let x_param = (0..parameters.len())
        .find(|&i| rows.iter().any(|r| r.values[i] != rows[0].values[i]))
        .unwrap_or(0);
    let numeric: Option<Vec<f64>> = rows
        .iter()
        .map(|r| {
            r.values[x_param]
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
        })
        .collect();
    // Categories: the distinct values of the axis parameter in order of appearance.
    let mut categories: Vec<&str> = Vec::new();
    for r in rows {
        if !categories.contains(&r.values[x_param].as_str()) {
            categories.push(&r.values[x_param]);
        }
    }
    let xs: Vec<f64> = match &numeric {
        Some(v) => v.clone(),
        None => rows
            .iter()
            .map(|r| {
                categories
                    .iter()
                    .position(|c| *c == r.values[x_param])
                    .unwrap_or(0) as f64
            })
            .collect(),
    };
    let (x_min, x_max) = span(&xs);
    let fps_max = rows
        .iter()
        .map(|r| r.fps)
        .filter(|f| f.is_finite())
        .fold(0.0, f64::max);
    let y_max = nice_ceiling(fps_max.max(1e-3));

    let mut pixmap = Pixmap::new(WIDTH, HEIGHT)?;
    pixmap.fill(Color::WHITE);
    let plot_w = WIDTH as f32 - LEFT - RIGHT;
    let plot_h = HEIGHT as f32 - TOP - BOTTOM;
    let to_px = |x: f64, y: f64| {
        let fx = if x_max > x_min {
            (x - x_min) / (x_max - x_min)
        } else {
            0.5
        };
        (
            LEFT + fx as f32 * plot_w,
            TOP + plot_h - (y / y_max).clamp(0.0, 1.0) as f32 * plot_h,
        )
    };
    // Grid and axes.
    let grid = paint([225, 225, 225]);
    let axis = paint([60, 60, 60]);
    for k in 0..=5 {
        let y = TOP + plot_h * k as f32 / 5.0;
        line(&mut pixmap, (LEFT, y), (LEFT + plot_w, y), &grid, 1.0);
    }
    line(&mut pixmap, (LEFT, TOP), (LEFT, TOP + plot_h), &axis, 1.5);
    line(
        &mut pixmap,
        (LEFT, TOP + plot_h),
        (LEFT + plot_w, TOP + plot_h),
        &axis,
        1.5,
    );

    // Series: rows grouped by the values of the other parameters, in order of appearance.
    let mut series: Vec<Series> = Vec::new();
    for (r, &x) in rows.iter().zip(&xs) {
        let key = others(&r.values, x_param);
        match series.iter_mut().find(|(k, _)| *k == key) {
            Some((_, points)) => points.push((x, r.fps)),
            None => series.push((key, vec![(x, r.fps)])),
        }
    }
    for (i, (_, points)) in series.iter_mut().enumerate() {
        points.sort_by(|a, b| a.0.total_cmp(&b.0));
        let colour = paint(PALETTE[i % PALETTE.len()]);
        let mut path = PathBuilder::new();
        for (k, &(x, y)) in points.iter().enumerate() {
            let (px, py) = to_px(x, y);
            if k == 0 {
                path.move_to(px, py);
            } else {
                path.line_to(px, py);
            }
        }
        if let Some(path) = path.finish() {
            let stroke = Stroke {
                width: 2.0,
                ..Stroke::default()
            };
            pixmap.stroke_path(&path, &colour, &stroke, Transform::identity(), None);
        }
        for &(x, y) in points.iter() {
            let (px, py) = to_px(x, y);
            if let Some(dot) = PathBuilder::from_circle(px, py, 3.5) {
                pixmap.fill_path(
                    &dot,
                    &colour,
                    Default::default(),
                    Transform::identity(),
                    None,
                );
            }
        }
    }

    let mut image = RgbaImage::from_raw(WIDTH, HEIGHT, pixmap.data().to_vec())?;
    // Labels: y ticks, x ticks, axis titles, legend.
    for k in 0..=5 {
        let value = y_max * k as f64 / 5.0;
        let label = format_number(value);
        let y = TOP + plot_h - plot_h * k as f32 / 5.0;
        let x = LEFT as i64 - 6 - text::text_width(&label) as i64;
        text::draw(&mut image, x, y as i64 - 3, &label, INK);
    }
    let ticks: Vec<(f64, String)> = match &numeric {
        Some(_) => {
            let mut seen: Vec<(f64, String)> = Vec::new();
            for (r, &x) in rows.iter().zip(&xs) {
                if !seen.iter().any(|(v, _)| *v == x) {
                    seen.push((x, r.values[x_param].clone()));
                }
            }
            seen
        }
        None => categories
            .iter()
            .enumerate()
            .map(|(i, c)| (i as f64, c.to_string()))
            .collect(),
    };
    // Tick labels that would overlap the previous one are skipped.
    let mut last_right = i64::MIN;
    let mut sorted_ticks = ticks;
    sorted_ticks.sort_by(|a, b| a.0.total_cmp(&b.0));
    for (x, label) in &sorted_ticks {
        let (px, _) = to_px(*x, 0.0);
        let w = text::text_width(label) as i64;
        let left = px as i64 - w / 2;
        if left > last_right + 4 {
            text::draw(&mut image, left, (TOP + plot_h) as i64 + 8, label, INK);
            last_right = left + w;
        }
    }
    let x_title = &parameters[x_param];
    let x_title_w = text::text_width(x_title) as i64;
    text::draw(
        &mut image,
        (LEFT + plot_w / 2.0) as i64 - x_title_w / 2,
        HEIGHT as i64 - 24,
        x_title,
        INK,
    );
    text::draw(&mut image, 8, 14, "FPS", INK);
    if series.len() > 1 {
        for (i, (key, _)) in series.iter().enumerate() {
            let label: Vec<String> = others(parameters, x_param)
                .iter()
                .zip(key)
                .map(|(n, v)| format!("{n}={v}"))
                .collect();
            let label = label.join(" ");
            let y = TOP as i64 + 4 + i as i64 * text::LINE_HEIGHT as i64;
            let x = (LEFT + plot_w) as i64 - 12 - text::text_width(&label) as i64;
            let [r, g, b] = PALETTE[i % PALETTE.len()];
            for dy in 0..5 {
                for dx in 0..8 {
                    let (px, py) = (x - 12 + dx, y + 1 + dy);
                    if px >= 0 && py >= 0 {
                        image.put_pixel(px as u32, py as u32, image::Rgba([r, g, b, 255]));
                    }
                }
            }
            text::draw(&mut image, x, y, &label, INK);
        }
    }
    Some(image)
}

/// The values of the other parameters, and the (x, fps) points with those values.
type Series = (Vec<String>, Vec<(f64, f64)>);

/// All of `items` but the one at `axis`, in order.
fn others(items: &[String], axis: usize) -> Vec<String> {
    items
        .iter()
        .enumerate()
        .filter(|&(i, _)| i != axis)
        .map(|(_, v)| v.clone())
        .collect()
}

fn paint(rgb: [u8; 3]) -> Paint<'static> {
    let mut p = Paint::default();
    p.set_color_rgba8(rgb[0], rgb[1], rgb[2], 255);
    p.anti_alias = true;
    p
}

fn line(pixmap: &mut Pixmap, from: (f32, f32), to: (f32, f32), paint: &Paint, width: f32) {
    let mut path = PathBuilder::new();
    path.move_to(from.0, from.1);
    path.line_to(to.0, to.1);
    if let Some(path) = path.finish() {
        let stroke = Stroke {
            width,
            ..Stroke::default()
        };
        pixmap.stroke_path(&path, paint, &stroke, Transform::identity(), None);
    }
}

fn span(xs: &[f64]) -> (f64, f64) {
    let min = xs.iter().copied().fold(f64::INFINITY, f64::min);
    let max = xs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    (min, max)
}

/// The smallest of 1, 2, 2.5, 5 × 10^k at or above `v`.
fn nice_ceiling(v: f64) -> f64 {
    let magnitude = 10f64.powf(v.log10().floor());
    [1.0, 2.0, 2.5, 5.0, 10.0]
        .iter()
        .map(|m| m * magnitude)
        .find(|&c| c >= v)
        .unwrap_or(10.0 * magnitude)
}

fn format_number(v: f64) -> String {
    if v == v.round() && v.abs() < 1e9 {
        format!("{v:.0}")
    } else if v.abs() >= 0.1 {
        format!("{v:.1}")
    } else {
        format!("{v:.3}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(point: usize, values: &[&str], fps: f64) -> ResultRow {
        ResultRow {
            point,
            values: values.iter().map(|v| v.to_string()).collect(),
            bake_ms: 1.0,
            median_frame_ms: 1000.0 / fps,
            min_frame_ms: 1000.0 / fps,
            max_frame_ms: 1000.0 / fps,
            fps,
            fragments_shaded: 1,
            extra: Vec::new(),
        }
    }

    fn coloured_pixels(image: &RgbaImage, rgb: [u8; 3]) -> Vec<(u32, u32)> {
        image
            .enumerate_pixels()
            .filter(|(_, _, p)| p.0[..3] == rgb)
            .map(|(x, y, _)| (x, y))
            .collect()
    }

    #[test]
    fn a_falling_curve_falls_from_left_to_right() {
        let parameters = vec!["number_of_shells".to_string()];
        let rows = [
            row(0, &["10"], 40.0),
            row(1, &["50"], 20.0),
            row(2, &["100"], 5.0),
        ];
        let image = fps_plot(&parameters, &rows).expect("plot");
        assert_eq!((image.width(), image.height()), (WIDTH, HEIGHT));
        let line = coloured_pixels(&image, PALETTE[0]);
        assert!(!line.is_empty());
        let left = line.iter().filter(|p| p.0 < WIDTH / 3).map(|p| p.1).min();
        let right = line
            .iter()
            .filter(|p| p.0 > 2 * WIDTH / 3)
            .map(|p| p.1)
            .min();
        // Image rows grow downwards: higher fps is nearer the top on the left.
        assert!(left < right, "{left:?} {right:?}");
        assert!(fps_plot(&parameters, &[]).is_none());
    }

    #[test]
    fn other_parameters_make_separate_lines_and_words_become_categories() {
        let parameters = vec!["mode".to_string(), "texture_resolution".to_string()];
        let rows = [
            row(0, &["low", "128"], 30.0),
            row(1, &["low", "256"], 20.0),
            row(2, &["high", "128"], 25.0),
            row(3, &["high", "256"], 10.0),
        ];
        let image = fps_plot(&parameters, &rows).expect("plot");
        assert!(!coloured_pixels(&image, PALETTE[0]).is_empty());
        assert!(!coloured_pixels(&image, PALETTE[1]).is_empty());
        assert!(coloured_pixels(&image, PALETTE[2]).is_empty());
    }

    #[test]
    fn a_single_valued_first_parameter_is_not_the_axis() {
        let parameters = vec![
            "number_of_spots".to_string(),
            "specular_tangents".to_string(),
        ];
        // fps falls with the tangents: plotted against them, one line falls left to right.
        let rows = [row(0, &["2", "1"], 30.0), row(1, &["2", "3"], 10.0)];
        let image = fps_plot(&parameters, &rows).expect("plot");
        let pixels = coloured_pixels(&image, PALETTE[0]);
        let (left, right) = (
            pixels.iter().filter(|p| p.0 < WIDTH / 3).map(|p| p.1).min(),
            pixels
                .iter()
                .filter(|p| p.0 > 2 * WIDTH / 3)
                .map(|p| p.1)
                .min(),
        );
        assert!(left.is_some() && right.is_some(), "{left:?} {right:?}");
        assert!(left < right, "{left:?} {right:?}");
        assert!(coloured_pixels(&image, PALETTE[1]).is_empty());
    }

    #[test]
    fn ceilings_are_round() {
        assert_eq!(nice_ceiling(38.0), 50.0);
        assert_eq!(nice_ceiling(0.21), 0.25);
        assert_eq!(nice_ceiling(100.0), 100.0);
        assert_eq!(nice_ceiling(1.5), 2.0);
    }
}
