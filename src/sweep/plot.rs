//! The plots of a sweep (beside the pipeline: sweeps), drawn with `plotters` (bitmap backend) and
//! their text with [`crate::font`] (the embedded DejaVu Sans, no system font): frames per second,
//! median frame time and fragments shaded, each against the first parameter that varies, one line
//! per combination of the other parameters, with a title, axis labels with units, ticks and a
//! legend under the plot. The x axis has a tick at each value swept (`tick_stride` thins the labels
//! uniformly where they would touch); each line has its own dash pattern and marker, so that lines
//! with equal values stay visible, and the legend names such a line's twin.

use super::ResultRow;
use image::RgbaImage;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use std::collections::{HashMap, HashSet};

/// Plot size in pixels.
pub const WIDTH: u32 = 900;
/// Plot height in pixels, legend included.
pub const HEIGHT: u32 = 600;
/// Font family name the embedded font is registered under.
const FAMILY: &str = "pelage-sans";
/// Line colours, one per series, repeating.
pub const PALETTE: [[u8; 3]; 6] = [
    [31, 119, 180],
    [214, 39, 40],
    [44, 160, 44],
    [148, 103, 189],
    [255, 127, 14],
    [23, 190, 207],
];
/// Series listed in the legend before "… and N more".
const LEGEND_ROWS: usize = 6;

/// What a plot shows on its y axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Metric {
    /// Frames per second (from the median frame time).
    Fps,
    /// Median frame time, milliseconds.
    FrameTime,
    /// Fragments shaded in one frame.
    Fragments,
}

impl Metric {
    /// Every metric, in the order the sweep writes them.
    pub const ALL: [Metric; 3] = [Metric::Fps, Metric::FrameTime, Metric::Fragments];

    /// The file the sweep writes the plot to.
    pub fn file_name(self) -> &'static str {
        match self {
            Metric::Fps => "fps.png",
            Metric::FrameTime => "frame_time.png",
            Metric::Fragments => "fragments.png",
        }
    }

    /// The plot's title.
    pub fn title(self) -> &'static str {
        match self {
            Metric::Fps => "Frame rate",
            Metric::FrameTime => "Frame time",
            Metric::Fragments => "Fragments shaded",
        }
    }

    /// The y axis label, with its unit.
    pub fn axis_label(self) -> &'static str {
        match self {
            Metric::Fps => "frames per second (fps, from the median frame time)",
            Metric::FrameTime => "median frame time (ms)",
            Metric::Fragments => "fragments shaded per frame (millions)",
        }
    }

    /// The row's value on this plot's y axis.
    pub fn value(self, row: &ResultRow) -> f64 {
        match self {
            Metric::Fps => row.fps,
            Metric::FrameTime => row.median_frame_ms,
            Metric::Fragments => row.fragments_shaded as f64 / 1e6,
        }
    }
}

/// The unit of a sweep parameter, for the x axis label (`None`: a count or a choice).
pub fn parameter_unit(name: &str) -> Option<&'static str> {
    let key = name.rsplit('.').next().unwrap_or(name);
    match key {
        "texture_resolution" | "fin_texture_resolution" => Some("texels"),
        "width" | "height" => Some("pixels"),
        "time" => Some("s"),
        "fov_y_deg" => Some("degrees"),
        _ => None,
    }
}

/// Registers the embedded font with plotters once.
fn register_font() -> Result<(), String> {
    static DONE: std::sync::OnceLock<Result<(), String>> = std::sync::OnceLock::new();
    DONE.get_or_init(|| {
        plotters::style::register_font(FAMILY, FontStyle::Normal, crate::font::DEJAVU_SANS)
            .map_err(|_| "the embedded font cannot be read by plotters".to_string())
    })
    .clone()
}

/// [`metric_plot`] of frames per second (`fps.png`).
pub fn fps_plot(parameters: &[String], rows: &[ResultRow]) -> Option<RgbaImage> {
    metric_plot(parameters, rows, Metric::Fps).ok().flatten()
}

/// Plots `metric` against the first parameter that takes more than one value (the first
/// parameter when none does), so that `--param number_of_spots=2 --param
/// specular_tangents=1,3` plots against the tangents. Its values are placed by number when
/// every one is a number, else evenly in point order (ticks labelled with the values). Rows
/// with the same values of the other parameters form one line, named in the legend under the
/// plot. `Ok(None)` without rows; an error only if plotters fails to draw.
pub fn metric_plot(
    parameters: &[String],
    rows: &[ResultRow],
    metric: Metric,
) -> Result<Option<RgbaImage>, String> {
    if rows.is_empty() || parameters.is_empty() {
        return Ok(None);
    }
    register_font()?;
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
    // Categories: the distinct values of the axis parameter in order of appearance. (Every
    // per-row step below is a lookup, never a scan: a sweep has up to MAX_POINTS rows.)
    let mut category_of: HashMap<&str, usize> = HashMap::new();
    for r in rows {
        let next = category_of.len();
        category_of
            .entry(r.values[x_param].as_str())
            .or_insert(next);
    }
    let values: Vec<f64> = match &numeric {
        Some(v) => v.clone(),
        None => rows
            .iter()
            .map(|r| category_of[r.values[x_param].as_str()] as f64)
            .collect(),
    };
    // The axis is the values' span mapped onto 0..1, computed in halves so that no finite
    // values (±1e308 among them) overflow it.
    let (x_min, x_max) = span(&values);
    let half_span = x_max / 2.0 - x_min / 2.0;
    let xs: Vec<f64> = values
        .iter()
        .map(|&v| {
            if half_span > 0.0 {
                (v / 2.0 - x_min / 2.0) / half_span
            } else {
                0.0
            }
        })
        .collect();
    let (x_lo, x_hi) = if half_span > 0.0 {
        (-0.05, 1.05)
    } else {
        (-0.5, 0.5)
    };
    let y_top = rows
        .iter()
        .map(|r| metric.value(r))
        .filter(|f| f.is_finite())
        .fold(0.0, f64::max);
    let y_hi = nice_ceiling(y_top.max(1e-3));

    // Series: rows grouped by the values of the other parameters, in order of appearance.
    let mut series: Vec<Series> = Vec::new();
    let mut series_of: HashMap<Vec<String>, usize> = HashMap::new();
    for (r, &x) in rows.iter().zip(&xs) {
        let key = others(&r.values, x_param);
        let y = metric.value(r);
        let index = *series_of.entry(key.clone()).or_insert_with(|| {
            series.push((key, Vec::new()));
            series.len() - 1
        });
        series[index].1.push((x, y));
    }
    for (_, points) in &mut series {
        points.sort_by(|a, b| a.0.total_cmp(&b.0));
    }
    let other_names = others(parameters, x_param);
    let legend_lines = series.len().min(LEGEND_ROWS) + usize::from(series.len() > LEGEND_ROWS);
    let legend_height = 16 + 22 * legend_lines as u32;
    let x_label = match parameter_unit(&parameters[x_param]) {
        Some(unit) => format!("{} ({unit})", parameters[x_param]),
        None => parameters[x_param].clone(),
    };
    // The axis's ticks: one per distinct value, at its position, labelled with the value as
    // given; a subset at a uniform stride where the labels would touch.
    let mut distinct: Vec<(f64, String)> = Vec::new();
    let mut seen: HashSet<u64> = HashSet::new();
    for (r, &x) in rows.iter().zip(&xs) {
        if seen.insert(x.to_bits()) {
            distinct.push((x, r.values[x_param].clone()));
        }
    }
    distinct.sort_by(|a, b| a.0.total_cmp(&b.0));
    let y_step = y_hi / 10.0;
    // Every text, drawn with crate::font after plotters has drawn the rest.
    let mut texts: Vec<PlotText> = Vec::new();

    let mut buffer = vec![255u8; (WIDTH * HEIGHT * 3) as usize];
    {
        let draw_error = |e: &dyn std::fmt::Display| format!("plot: {e}");
        let root = BitMapBackend::with_buffer(&mut buffer, (WIDTH, HEIGHT)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| draw_error(&e))?;
        let (upper, lower) = root.split_vertically(HEIGHT - legend_height);
        let mut chart = ChartBuilder::on(&upper)
            .margin(14)
            .margin_top(50)
            .x_label_area_size(54)
            .y_label_area_size(84)
            .build_cartesian_2d(x_lo..x_hi, 0f64..y_hi)
            .map_err(|e| draw_error(&e))?;
        // The axes only: grid lines and labels are drawn here, at the values' positions.
        chart
            .configure_mesh()
            .disable_mesh()
            .x_labels(0)
            .y_labels(0)
            .axis_style(RGBColor(90, 90, 90))
            .draw()
            .map_err(|e| draw_error(&e))?;
        let grid = RGBColor(225, 225, 225);
        let ink = RGBColor(90, 90, 90);
        let (x_range, y_range) = chart.plotting_area().get_pixel_range();
        let (plot_left, plot_bottom) = (x_range.start as f32, y_range.end as f32);
        for k in 0..=10 {
            let y = k as f64 * y_step;
            chart
                .draw_series(std::iter::once(PathElement::new(
                    vec![(x_lo, y), (x_hi, y)],
                    grid,
                )))
                .map_err(|e| draw_error(&e))?;
            let (_, py) = chart.backend_coord(&(x_lo, y));
            texts.push(PlotText::new(
                format_tick(y, y_step),
                plot_left - 8.0,
                py as f32,
                TICK_PX,
                Anchor::Right,
            ));
        }
        let pixel_x: Vec<f32> = distinct
            .iter()
            .map(|(x, _)| chart.backend_coord(&(*x, 0.0)).0 as f32)
            .collect();
        let widths: Vec<f32> = distinct
            .iter()
            .map(|(_, label)| crate::font::text_width(label, TICK_PX))
            .collect();
        let stride = tick_stride(&pixel_x, &widths, 10.0);
        for (k, ((x, label), &px)) in distinct.iter().zip(&pixel_x).enumerate() {
            chart
                .draw_series(std::iter::once(PathElement::new(
                    vec![(*x, 0.0), (*x, y_hi)],
                    grid,
                )))
                .map_err(|e| draw_error(&e))?;
            if k % stride == 0 {
                upper
                    .draw(&PathElement::new(
                        vec![
                            (px as i32, plot_bottom as i32),
                            (px as i32, plot_bottom as i32 + 5),
                        ],
                        ink,
                    ))
                    .map_err(|e| draw_error(&e))?;
                texts.push(PlotText::new(
                    label.clone(),
                    px,
                    plot_bottom + 16.0,
                    TICK_PX,
                    Anchor::Centre,
                ));
            }
        }
        // Series in order; a later one drawn over an earlier one with the same values leaves
        // the earlier visible: each has its own dash pattern and marker, markers shrinking.
        for (i, (_, points)) in series.iter().enumerate() {
            let style = SeriesStyle::of(i);
            let pixels: Vec<(i32, i32)> = points.iter().map(|p| chart.backend_coord(p)).collect();
            style.draw_line(&upper, pixels)?;
            for &p in points {
                let (px, py) = chart.backend_coord(&p);
                style
                    .draw_marker(&upper, (px, py))
                    .map_err(|e| draw_error(&e))?;
            }
        }
        // The legend, under the plot: the line's dash and marker, and the values of the other
        // parameters; a line with the same values as an earlier one says so.
        let (_, lower_y) = lower.get_base_pixel();
        for (i, (key, points)) in series.iter().take(LEGEND_ROWS).enumerate() {
            let style = SeriesStyle::of(i);
            let y = 8 + 22 * i as i32;
            style.draw_line(&lower, vec![(96, y + 8), (136, y + 8)])?;
            style
                .draw_marker(&lower, (116, y + 8))
                .map_err(|e| draw_error(&e))?;
            let mut label = series_label(metric, &other_names, key);
            if let Some(j) = (0..i).find(|&j| same_points(&series[j].1, points)) {
                label.push_str(&format!(
                    "  (same values as {})",
                    series_label(metric, &other_names, &series[j].0)
                ));
            }
            texts.push(PlotText::new(
                label,
                146.0,
                (lower_y + y + 8) as f32,
                LEGEND_PX,
                Anchor::Left,
            ));
        }
        if series.len() > LEGEND_ROWS {
            let y = 8 + 22 * LEGEND_ROWS as i32;
            texts.push(PlotText::new(
                format!("… and {} more lines", series.len() - LEGEND_ROWS),
                146.0,
                (lower_y + y + 8) as f32,
                LEGEND_PX,
                Anchor::Left,
            ));
        }
        texts.push(PlotText::new(
            format!("{} against {}", metric.title(), parameters[x_param]),
            WIDTH as f32 / 2.0,
            26.0,
            TITLE_PX,
            Anchor::Centre,
        ));
        texts.push(PlotText::new(
            x_label,
            (x_range.start + x_range.end) as f32 / 2.0,
            plot_bottom + 42.0,
            DESC_PX,
            Anchor::Centre,
        ));
        let mut y_desc = PlotText::new(
            metric.axis_label().to_string(),
            24.0,
            (y_range.start + y_range.end) as f32 / 2.0,
            DESC_PX,
            Anchor::Centre,
        );
        y_desc.rotated = true;
        texts.push(y_desc);
        root.present().map_err(|e| draw_error(&e))?;
    }
    let rgba: Vec<u8> = buffer
        .chunks_exact(3)
        .flat_map(|p| [p[0], p[1], p[2], 255])
        .collect();
    let mut image = RgbaImage::from_raw(WIDTH, HEIGHT, rgba).ok_or("plot: buffer size")?;
    for text in &texts {
        text.draw(&mut image);
    }
    Ok(Some(image))
}

/// Text sizes, pixels ([`crate::font`]'s size).
const TITLE_PX: f32 = 24.0;
/// Axis descriptions.
const DESC_PX: f32 = 16.0;
/// Tick labels.
const TICK_PX: f32 = 14.0;
/// Legend entries.
const LEGEND_PX: f32 = 14.0;

/// Where a text's `x` is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Anchor {
    Left,
    Centre,
    Right,
}

/// A line of text of the plot, drawn in the embedded font after plotters is done (plotters's
/// own text drops each glyph's side bearing, which spaces letters unevenly).
#[derive(Clone, Debug)]
struct PlotText {
    text: String,
    x: f32,
    /// The middle of its capitals.
    y: f32,
    px: f32,
    anchor: Anchor,
    /// Turned a quarter counter-clockwise, read bottom to top (the y axis's description).
    rotated: bool,
}

impl PlotText {
    fn new(text: String, x: f32, y: f32, px: f32, anchor: Anchor) -> Self {
        PlotText {
            text,
            x,
            y,
            px,
            anchor,
            rotated: false,
        }
    }

    /// Draws the text, dark grey, into `image` (white where rotated text goes).
    fn draw(&self, image: &mut RgbaImage) {
        use ab_glyph::{Font as _, ScaleFont as _};
        const INK: [u8; 3] = [30, 30, 30];
        let width = crate::font::text_width(&self.text, self.px);
        let ascent = crate::font::font()
            .as_scaled(ab_glyph::PxScale::from(self.px))
            .ascent();
        let cap = crate::font::cap_height(self.px);
        let shift = match self.anchor {
            Anchor::Left => 0.0,
            Anchor::Centre => width / 2.0,
            Anchor::Right => width,
        };
        if !self.rotated {
            let top = self.y + cap / 2.0 - ascent;
            crate::font::draw(image, self.x - shift, top, self.px, INK, &self.text);
            return;
        }
        // Drawn level on white, turned, and laid over the plot by the darker of the two.
        let (w, h) = (
            width.ceil() as u32 + 4,
            crate::font::line_height(self.px).ceil() as u32 + 4,
        );
        let mut level = RgbaImage::from_pixel(w, h, image::Rgba([255, 255, 255, 255]));
        crate::font::draw(&mut level, 2.0, 2.0, self.px, INK, &self.text);
        let turned = image::imageops::rotate270(&level);
        let (left, top) = (
            (self.x - h as f32 / 2.0).round() as i64,
            (self.y - w as f32 / 2.0).round() as i64,
        );
        for (x, y, p) in turned.enumerate_pixels() {
            let (tx, ty) = (left + i64::from(x), top + i64::from(y));
            if tx >= 0 && ty >= 0 && (tx as u32) < image.width() && (ty as u32) < image.height() {
                let q = image.get_pixel_mut(tx as u32, ty as u32);
                for c in 0..3 {
                    q[c] = q[c].min(p[c]);
                }
            }
        }
    }
}

/// The smallest stride `k` such that labelling every `k`-th tick (the first, then every `k`
/// further) leaves at least `gap` pixels between labels `widths` wide centred at `positions`
/// (sorted, pixels). 1 when every label fits.
fn tick_stride(positions: &[f32], widths: &[f32], gap: f32) -> usize {
    let n = positions.len().min(widths.len());
    (1..n.max(1))
        .find(|&k| {
            (k..n).step_by(k).all(|i| {
                let j = i - k;
                positions[j] + widths[j] / 2.0 + gap <= positions[i] - widths[i] / 2.0
            })
        })
        .unwrap_or(n.max(1))
}

/// A line's look: colour, dash pattern and marker, distinct for the first
/// [`PALETTE`]`.len()` lines.
#[derive(Clone, Copy, Debug, PartialEq)]
struct SeriesStyle {
    index: usize,
    /// Dash length and gap, pixels (a gap of 0: solid).
    dash: (u32, u32),
    /// Marker half size, pixels: shrinking with the index, so that a later marker on top of
    /// an earlier one leaves a ring of it showing.
    size: i32,
}

impl SeriesStyle {
    fn of(index: usize) -> Self {
        const DASHES: [(u32, u32); 6] = [(1, 0), (10, 5), (3, 4), (14, 4), (6, 6), (2, 3)];
        SeriesStyle {
            index,
            dash: DASHES[index % DASHES.len()],
            size: (7 - 2 * (index % PALETTE.len()) as i32).max(3),
        }
    }

    fn colour(&self) -> RGBColor {
        let [r, g, b] = PALETTE[self.index % PALETTE.len()];
        RGBColor(r, g, b)
    }

    /// The line through `points` (pixels of `area`), two pixels wide, in its dash pattern.
    fn draw_line<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, plotters::coord::Shift>,
        points: Vec<(i32, i32)>,
    ) -> Result<(), String> {
        let style = self.colour().stroke_width(2);
        let (on, off) = self.dash;
        let result = if off == 0 {
            area.draw(&PathElement::new(points, style))
        } else {
            area.draw(&DashedPathElement::new(points, on, off, style))
        };
        result.map_err(|e| format!("plot: {e}"))
    }

    /// The line's marker at pixel `at` of `area`: circle, square, triangle, diamond, cross,
    /// and a ring, in turn.
    fn draw_marker<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, plotters::coord::Shift>,
        at: (i32, i32),
    ) -> Result<(), String> {
        let s = self.size;
        let fill = self.colour().filled();
        let error = |e: &dyn std::fmt::Display| format!("plot: {e}");
        let result = match self.index % 6 {
            0 => area.draw(&Circle::new(at, s, fill)),
            1 => area.draw(&Rectangle::new(
                [(at.0 - s, at.1 - s), (at.0 + s, at.1 + s)],
                fill,
            )),
            2 => area.draw(&Polygon::new(
                vec![
                    (at.0, at.1 - s - 1),
                    (at.0 + s, at.1 + s),
                    (at.0 - s, at.1 + s),
                ],
                fill,
            )),
            3 => area.draw(&Polygon::new(
                vec![
                    (at.0, at.1 - s),
                    (at.0 + s, at.1),
                    (at.0, at.1 + s),
                    (at.0 - s, at.1),
                ],
                fill,
            )),
            4 => area.draw(&Cross::new(at, s, self.colour().stroke_width(2))),
            _ => area.draw(&Circle::new(at, s, self.colour().stroke_width(2))),
        };
        result.map_err(|e| error(&e))
    }
}

/// The legend's name of a line: the values of the other parameters (the metric's title when
/// there are none).
fn series_label(metric: Metric, names: &[String], key: &[String]) -> String {
    if names.is_empty() {
        metric.title().to_string()
    } else {
        names
            .iter()
            .zip(key)
            .map(|(n, v)| format!("{n} = {v}"))
            .collect::<Vec<_>>()
            .join(", ")
    }
}

/// Whether two lines have the same points (values equal to a part in 10⁹).
fn same_points(a: &[(f64, f64)], b: &[(f64, f64)]) -> bool {
    let close = |u: f64, v: f64| (u - v).abs() <= 1e-9 * u.abs().max(v.abs());
    a.len() == b.len()
        && a.iter()
            .zip(b)
            .all(|(p, q)| close(p.0, q.0) && close(p.1, q.1))
}

/// The values of the other parameters, and the (x, y) points with those values.
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

fn span(xs: &[f64]) -> (f64, f64) {
    let min = xs.iter().copied().fold(f64::INFINITY, f64::min);
    let max = xs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    (min, max)
}

/// The smallest of 1, 2, 2.5, 5 × 10^k at or above `v`; `v` itself where that would not be
/// finite (values near `f64::MAX`), so that the axis always has a finite top.
fn nice_ceiling(v: f64) -> f64 {
    let magnitude = 10f64.powf(v.log10().floor());
    [1.0, 2.0, 2.5, 5.0, 10.0]
        .iter()
        .map(|m| m * magnitude)
        .find(|&c| c >= v)
        .filter(|c| c.is_finite())
        .unwrap_or(v)
}

/// A tick label of `v` with as many decimals as a tick spacing of about `step` needs, trailing
/// zeros dropped (`0.05`, `1.5`, `20`).
fn format_tick(v: f64, step: f64) -> String {
    let decimals = if step > 0.0 && step.is_finite() {
        (-step.log10()).ceil().clamp(0.0, 6.0) as usize
    } else {
        0
    };
    let text = format!("{v:.decimals$}");
    let text = if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        text
    };
    if text == "-0" { "0".to_string() } else { text }
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
    fn every_metric_is_plotted_with_its_own_scale() {
        let parameters = vec!["texture_resolution".to_string()];
        let rows = [row(0, &["64"], 40.0), row(1, &["128"], 10.0)];
        let plots: Vec<RgbaImage> = Metric::ALL
            .iter()
            .map(|&m| {
                metric_plot(&parameters, &rows, m)
                    .expect("draws")
                    .expect("plot")
            })
            .collect();
        // Frame time rises where fps falls: the line's top-most pixel in the left third is
        // above the right third's for fps, below it for frame time.
        let top = |image: &RgbaImage, left: bool| {
            coloured_pixels(image, PALETTE[0])
                .iter()
                .filter(|p| {
                    if left {
                        p.0 < WIDTH / 3
                    } else {
                        p.0 > 2 * WIDTH / 3
                    }
                })
                .filter(|p| p.1 < HEIGHT - 60)
                .map(|p| p.1)
                .min()
        };
        assert!(top(&plots[0], true) < top(&plots[0], false));
        assert!(top(&plots[1], true) > top(&plots[1], false));
        assert_ne!(plots[0], plots[2]);
        assert_eq!(parameter_unit("fur.texture_resolution"), Some("texels"));
        // Text is drawn (dark anti-aliased pixels of the title, labels and ticks).
        let dark = plots[0]
            .pixels()
            .filter(|p| p[0] < 80 && p[1] < 80 && p[2] < 80)
            .count();
        assert!(dark > 1500, "{dark}");
    }

    #[test]
    fn lines_with_the_same_values_stay_visible_and_the_legend_says_so() {
        // Two lines with the same fragment counts: the second drawn over the first used to hide
        // it; now its dashes and smaller markers leave the first showing in the plot itself.
        let parameters = vec![
            "texture_resolution".to_string(),
            "specular_tangents".to_string(),
        ];
        let rows = [
            row(0, &["64", "1"], 30.0),
            row(1, &["64", "3"], 30.0),
            row(2, &["128", "1"], 20.0),
            row(3, &["128", "3"], 20.0),
        ];
        let image = fps_plot(&parameters, &rows).expect("plot");
        let plot_area = |rgb: [u8; 3]| {
            coloured_pixels(&image, rgb)
                .into_iter()
                .filter(|p| p.1 < HEIGHT - 80)
                .count()
        };
        let (first, second) = (plot_area(PALETTE[0]), plot_area(PALETTE[1]));
        assert!(first > 150, "first line: {first} pixels");
        assert!(second > 150, "second line: {second} pixels");
        let series: Vec<Vec<(f64, f64)>> = vec![vec![(64.0, 30.0), (128.0, 20.0)]; 2];
        assert!(same_points(&series[0], &series[1]));
        assert!(!same_points(&series[0], &[(64.0, 30.0), (128.0, 21.0)]));
        assert_ne!(SeriesStyle::of(0).dash, SeriesStyle::of(1).dash);
        assert!(SeriesStyle::of(1).size < SeriesStyle::of(0).size);
    }

    #[test]
    fn tick_labels_sit_at_the_points_every_one_or_at_a_uniform_stride() {
        // Points 100 pixels apart, labels 40 wide: every one.
        let wide: Vec<f32> = (0..5).map(|i| 100.0 * i as f32).collect();
        assert_eq!(tick_stride(&wide, &[40.0; 5], 10.0), 1);
        // 10 pixels apart, 20 wide, 10 between: every third (30 pixels apart).
        let close: Vec<f32> = (0..30).map(|i| 10.0 * i as f32).collect();
        assert_eq!(tick_stride(&close, &[20.0; 30], 10.0), 3);
        // Uneven positions (powers of two on a linear axis): the crowded start decides.
        let powers = [32.0, 64.0, 128.0, 256.0, 512.0].map(|v: f32| v * 0.5);
        assert_eq!(tick_stride(&powers, &[24.0; 5], 10.0), 2);
        assert_eq!(tick_stride(&[5.0], &[100.0], 10.0), 1);
        assert_eq!(tick_stride(&[], &[], 10.0), 1);
    }

    #[test]
    fn tick_labels_have_the_decimals_their_spacing_needs() {
        assert_eq!(format_tick(0.45, 0.5 / 40.0), "0.45");
        assert_eq!(format_tick(0.4, 0.5 / 40.0), "0.4");
        assert_eq!(format_tick(35.0, 50.0 / 40.0), "35");
        assert_eq!(format_tick(0.025, 0.25 / 40.0), "0.025");
        assert_eq!(format_tick(-0.0001, 1.0), "0");
    }

    #[test]
    fn ceilings_are_round() {
        assert_eq!(nice_ceiling(38.0), 50.0);
        assert_eq!(nice_ceiling(0.21), 0.25);
        assert_eq!(nice_ceiling(100.0), 100.0);
        assert_eq!(nice_ceiling(1.5), 2.0);
        assert_eq!(nice_ceiling(1.7e308), 1.7e308, "finite near f64::MAX");
    }

    #[test]
    fn the_largest_finite_values_are_placed_on_the_axis() {
        // ±1e308 on the x axis and 1.7e308 on the y axis: the ranges stay finite.
        let rows = [
            row(0, &["-1e308"], 1.0),
            row(1, &["1e308"], 1.7e308),
            row(2, &["0"], 3.0),
        ];
        let image = metric_plot(&["x".to_string()], &rows, Metric::Fps)
            .expect("drawn")
            .expect("a plot");
        assert!(!coloured_pixels(&image, PALETTE[0]).is_empty());
    }

    #[test]
    fn the_most_points_a_sweep_has_plot_in_one_pass() {
        // 100,000 rows, 1,000 lines of 100 values: grouping, categories and ticks are lookups
        // (this took minutes when each row scanned the ones before it).
        let rows: Vec<ResultRow> = (0..crate::sweep::MAX_POINTS)
            .map(|p| {
                let (a, b) = (p / 1000, p % 1000);
                row(p, &[&format!("v{a}"), &b.to_string()], 1.0 + b as f64)
            })
            .collect();
        let names = ["a".to_string(), "b".to_string()];
        let image = metric_plot(&names, &rows, Metric::Fps)
            .expect("drawn")
            .expect("a plot");
        assert_eq!(image.dimensions(), (WIDTH, HEIGHT));
    }
}
