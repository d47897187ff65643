//! The plots of a sweep, drawn with `plotters` (bitmap backend; text in the embedded DejaVu Sans
//! through `ab_glyph`, no system font): frames per second, median frame time and fragments
//! shaded, each against the first parameter that varies, one line per combination of the
//! other parameters, with a title, axis labels with units, ticks and a legend under the plot.

use super::ResultRow;
use image::RgbaImage;
use plotters::prelude::*;

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
    // Categories: the distinct values of the axis parameter in order of appearance.
    let mut categories: Vec<String> = Vec::new();
    for r in rows {
        if !categories.contains(&r.values[x_param]) {
            categories.push(r.values[x_param].clone());
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
    let pad = if x_max > x_min {
        (x_max - x_min) * 0.05
    } else {
        0.5
    };
    let (x_lo, x_hi) = (x_min - pad, x_max + pad);
    let y_top = rows
        .iter()
        .map(|r| metric.value(r))
        .filter(|f| f.is_finite())
        .fold(0.0, f64::max);
    let y_hi = nice_ceiling(y_top.max(1e-3));

    // Series: rows grouped by the values of the other parameters, in order of appearance.
    let mut series: Vec<Series> = Vec::new();
    for (r, &x) in rows.iter().zip(&xs) {
        let key = others(&r.values, x_param);
        let y = metric.value(r);
        match series.iter_mut().find(|(k, _)| *k == key) {
            Some((_, points)) => points.push((x, y)),
            None => series.push((key, vec![(x, y)])),
        }
    }
    for (_, points) in &mut series {
        points.sort_by(|a, b| a.0.total_cmp(&b.0));
    }
    let other_names = others(parameters, x_param);
    let legend_lines = series.len().min(LEGEND_ROWS) + usize::from(series.len() > LEGEND_ROWS);
    let legend_height = 16 + 20 * legend_lines as u32;
    let x_label = match parameter_unit(&parameters[x_param]) {
        Some(unit) => format!("{} ({unit})", parameters[x_param]),
        None => parameters[x_param].clone(),
    };

    let mut buffer = vec![255u8; (WIDTH * HEIGHT * 3) as usize];
    {
        let draw_error = |e: &dyn std::fmt::Display| format!("plot: {e}");
        let root = BitMapBackend::with_buffer(&mut buffer, (WIDTH, HEIGHT)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| draw_error(&e))?;
        let (upper, lower) = root.split_vertically(HEIGHT - legend_height);
        let title = format!("{} against {}", metric.title(), parameters[x_param]);
        let mut chart = ChartBuilder::on(&upper)
            .caption(title, (FAMILY, 24))
            .margin(14)
            .x_label_area_size(54)
            .y_label_area_size(84)
            .build_cartesian_2d(x_lo..x_hi, 0f64..y_hi)
            .map_err(|e| draw_error(&e))?;
        let category_label = |x: &f64| -> String {
            let i = x.round();
            if (x - i).abs() < 1e-6 && i >= 0.0 {
                categories.get(i as usize).cloned().unwrap_or_default()
            } else {
                String::new()
            }
        };
        let y_label = |y: &f64| format_tick(*y, y_hi / 40.0);
        let x_span = (x_hi - x_lo).max(1e-9);
        let number_label = |x: &f64| format_tick(*x, x_span / 40.0);
        let mut mesh = chart.configure_mesh();
        mesh.x_desc(x_label.as_str())
            .y_desc(metric.axis_label())
            .label_style((FAMILY, 14))
            .axis_desc_style((FAMILY, 16))
            .y_label_formatter(&y_label)
            .light_line_style(RGBColor(240, 240, 240))
            .bold_line_style(RGBColor(215, 215, 215));
        if numeric.is_none() {
            mesh.x_labels(categories.len().max(2) * 2 + 1)
                .x_label_formatter(&category_label);
        } else {
            mesh.x_label_formatter(&number_label);
        }
        mesh.draw().map_err(|e| draw_error(&e))?;
        for (i, (_, points)) in series.iter().enumerate() {
            let [r, g, b] = PALETTE[i % PALETTE.len()];
            let colour = RGBColor(r, g, b);
            chart
                .draw_series(LineSeries::new(
                    points.iter().copied(),
                    colour.stroke_width(2),
                ))
                .map_err(|e| draw_error(&e))?;
            chart
                .draw_series(points.iter().map(|&p| Circle::new(p, 4, colour.filled())))
                .map_err(|e| draw_error(&e))?;
        }
        // The legend, under the plot: a swatch and the values of the other parameters.
        let font = (FAMILY, 14).into_font().color(&BLACK);
        for (i, (key, _)) in series.iter().take(LEGEND_ROWS).enumerate() {
            let [r, g, b] = PALETTE[i % PALETTE.len()];
            let y = 8 + 20 * i as i32;
            lower
                .draw(&Rectangle::new(
                    [(98, y + 5), (126, y + 9)],
                    RGBColor(r, g, b).filled(),
                ))
                .map_err(|e| draw_error(&e))?;
            let label = if other_names.is_empty() {
                metric.title().to_string()
            } else {
                other_names
                    .iter()
                    .zip(key)
                    .map(|(n, v)| format!("{n} = {v}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            };
            lower
                .draw(&Text::new(label, (134, y), font.clone()))
                .map_err(|e| draw_error(&e))?;
        }
        if series.len() > LEGEND_ROWS {
            let y = 8 + 20 * LEGEND_ROWS as i32;
            lower
                .draw(&Text::new(
                    format!("… and {} more lines", series.len() - LEGEND_ROWS),
                    (134, y),
                    font.clone(),
                ))
                .map_err(|e| draw_error(&e))?;
        }
        root.present().map_err(|e| draw_error(&e))?;
    }
    let rgba: Vec<u8> = buffer
        .chunks_exact(3)
        .flat_map(|p| [p[0], p[1], p[2], 255])
        .collect();
    Ok(RgbaImage::from_raw(WIDTH, HEIGHT, rgba))
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

/// The smallest of 1, 2, 2.5, 5 × 10^k at or above `v`.
fn nice_ceiling(v: f64) -> f64 {
    let magnitude = 10f64.powf(v.log10().floor());
    [1.0, 2.0, 2.5, 5.0, 10.0]
        .iter()
        .map(|m| m * magnitude)
        .find(|&c| c >= v)
        .unwrap_or(10.0 * magnitude)
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
    }
}
