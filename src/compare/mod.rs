//! Comparing two renders (beside the pipeline: comparison): the oracle's and a GPU's (or any two
//! RGBA8 images of one size).
//!
//! [`compare_images`] measures, in this order of strictness (the tiers of the Khronos
//! conformance suite's `tcuImageCompare` and of wgpu's image tests):
//! - **exact**: pixels whose four channels are equal;
//! - **per channel**: the largest and the mean absolute difference of R, G, B and A (in 8-bit
//!   steps), and the PSNR over R, G, B (`10·log10(255² / MSE)`, infinite for identical colour);
//! - **threshold** (`tcuImageCompare`'s threshold compare): pixels where any channel differs by
//!   more than [`Tolerance::channel_threshold`];
//! - **neighbour-tolerant** (in the spirit of `bilinearCompare`, which forgives filtering and
//!   edge differences): pixels over the threshold for which no pixel of the other image in the
//!   3×3 neighbourhood is within the threshold, checked both ways (A against B's neighbours and
//!   B against A's);
//! - **perceptual**: FLIP (Andersson et al. 2020, LDR-FLIP, through NVIDIA's reference
//!   implementation in the `nv-flip` crate) at 67 pixels per degree (a 0.7 m viewing distance
//!   of a 24" 4K monitor, FLIP's default): its mean and percentiles over the error map (0 equal,
//!   1 most different). FLIP compares colour only; alpha is measured by the per-channel figures.
//!
//! A [`Tolerance`] says which figures must stay under which bound; [`Comparison::failures`]
//! lists every bound exceeded, and an empty list is a pass. [`heat_map`] draws where and how
//! much two images differ, [`flip_heat_map`] how much they differ to the eye (FLIP's error on a
//! log scale, so that the errors of a near miss are bright, not near black).

pub mod legend;
pub mod report;

use image::RgbaImage;
use serde::{Serialize, Serializer};
use std::fmt;

/// What can go wrong before two images can be compared.
#[derive(Debug, thiserror::Error)]
pub enum CompareError {
    /// The images differ in size.
    #[error("sizes differ: {a_width}×{a_height} against {b_width}×{b_height}")]
    SizeMismatch {
        /// Width of the first image.
        a_width: u32,
        /// Height of the first image.
        a_height: u32,
        /// Width of the second image.
        b_width: u32,
        /// Height of the second image.
        b_height: u32,
    },
    /// An image has no pixels.
    #[error("an image is empty (0×0)")]
    Empty,
    /// A tolerance string could not be read.
    #[error("tolerance: {0}")]
    Tolerance(String),
}

/// The documented tolerance of a correct GPU implementation against the oracle (README,
/// "Tolerances"): what `tests/gpu.rs` and `pelage sweep --backend gpu --against-oracle` judge by,
/// and what `--tolerance gpu` names.
pub const GPU_TOLERANCE: &str = "threshold=8,over=0.005,flip-mean=0.015,flip-p99=0.15,psnr=40";

/// The bounds a comparison must stay within: each criterion is checked only when it is set
/// (`Some`). The default is exact equality (threshold 0, no pixel over it).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Tolerance {
    /// A pixel is "over" when any channel differs by more than this (8-bit steps).
    pub channel_threshold: u8,
    /// Largest allowed fraction of pixels over the threshold; `None`: not checked.
    pub max_over_fraction: Option<f64>,
    /// Largest allowed fraction of pixels over the threshold with no match among the other
    /// image's 3×3 neighbours (edges and filtering forgiven); `None`: not checked.
    pub max_neighbour_over_fraction: Option<f64>,
    /// Largest allowed FLIP mean; `None`: not checked.
    pub max_flip_mean: Option<f32>,
    /// `(percentile, bound)`: the FLIP error at this percentile (0–1) must not exceed the bound.
    pub max_flip_percentile: Option<(f32, f32)>,
    /// Smallest allowed PSNR over R, G, B in dB; `None`: not checked.
    pub min_psnr: Option<f64>,
}

impl Default for Tolerance {
    fn default() -> Self {
        Tolerance::exact()
    }
}

/// The keys a tolerance string may name, for messages.
const KEYS: &str = "exact, gpu, threshold, over, neighbour-over, flip-mean, flip-pNN, psnr";

impl Tolerance {
    /// Every pixel equal in every channel.
    pub fn exact() -> Self {
        Tolerance {
            max_over_fraction: Some(0.0),
            ..Tolerance::unconstrained()
        }
    }

    /// Nothing checked (threshold 0 for the counts): the start of a partial tolerance.
    pub fn unconstrained() -> Self {
        Tolerance {
            channel_threshold: 0,
            max_over_fraction: None,
            max_neighbour_over_fraction: None,
            max_flip_mean: None,
            max_flip_percentile: None,
            min_psnr: None,
        }
    }

    /// The documented tier of a correct GPU implementation, [`GPU_TOLERANCE`].
    pub fn gpu() -> Self {
        Tolerance::parse(GPU_TOLERANCE).expect("GPU_TOLERANCE parses")
    }

    /// Reads a tolerance: a comma-separated list of presets and `key=value` bounds, read left
    /// to right (a later item overrides an earlier one). Presets: `exact` (every pixel equal)
    /// and `gpu` ([`GPU_TOLERANCE`]). Bounds: `threshold=N` (0–255), `over=F` (fraction of
    /// pixels over the threshold, 0–1), `neighbour-over=F`, `flip-mean=F`, `flip-pP=F` (e.g.
    /// `flip-p99=0.3`: the 99th percentile of the FLIP error at most 0.3), `psnr=DB`. Only the
    /// criteria named are checked: `flip-mean=0.015` alone checks the FLIP mean and nothing
    /// else. `threshold=N` without `over` or `neighbour-over` allows no pixel over N. An empty
    /// string is `exact`.
    pub fn parse(text: &str) -> Result<Self, CompareError> {
        let text = text.trim();
        if text.is_empty() {
            return Ok(Tolerance::exact());
        }
        let mut t = Tolerance::unconstrained();
        let bad = |m: String| CompareError::Tolerance(m);
        let (mut threshold_named, mut over_named) = (false, false);
        for item in text.split(',') {
            let item = item.trim();
            match item {
                "exact" => {
                    t = Tolerance::exact();
                    continue;
                }
                "gpu" => {
                    t = Tolerance::gpu();
                    continue;
                }
                _ => {}
            }
            let (key, value) = item.split_once('=').ok_or_else(|| {
                bad(format!(
                    "`{item}` is neither a preset (exact, gpu) nor key=value ({KEYS})"
                ))
            })?;
            let (key, value) = (key.trim(), value.trim());
            let number = |lo: f64, hi: f64| -> Result<f64, CompareError> {
                let v: f64 = value
                    .parse()
                    .map_err(|_| bad(format!("{key}={value}: not a number")))?;
                if v.is_finite() && (lo..=hi).contains(&v) {
                    Ok(v)
                } else {
                    Err(bad(format!("{key}={value} is outside {lo}..={hi}")))
                }
            };
            match key {
                "threshold" => {
                    t.channel_threshold = number(0.0, 255.0)?.round() as u8;
                    threshold_named = true;
                }
                "over" => {
                    t.max_over_fraction = Some(number(0.0, 1.0)?);
                    over_named = true;
                }
                "neighbour-over" => {
                    t.max_neighbour_over_fraction = Some(number(0.0, 1.0)?);
                    over_named = true;
                }
                "flip-mean" => t.max_flip_mean = Some(number(0.0, 1.0)? as f32),
                "psnr" => t.min_psnr = Some(number(0.0, 1000.0)?),
                k if k.starts_with("flip-p") => {
                    let p: f64 = k["flip-p".len()..]
                        .parse()
                        .ok()
                        .filter(|p: &f64| (0.0..=100.0).contains(p))
                        .ok_or_else(|| bad(format!("{k}: percentile must be 0..=100")))?;
                    t.max_flip_percentile = Some(((p / 100.0) as f32, number(0.0, 1.0)? as f32));
                }
                _ => return Err(bad(format!("unknown key `{key}` ({KEYS})"))),
            }
        }
        if threshold_named && !over_named && t.max_over_fraction.is_none() {
            t.max_over_fraction = Some(0.0);
        }
        Ok(t)
    }

    /// Whether nothing is checked (every comparison passes).
    pub fn is_unconstrained(&self) -> bool {
        self.max_over_fraction.is_none()
            && self.max_neighbour_over_fraction.is_none()
            && self.max_flip_mean.is_none()
            && self.max_flip_percentile.is_none()
            && self.min_psnr.is_none()
    }

    /// The criteria checked, one phrase each, in the order of the verdict.
    pub fn criteria(&self) -> Vec<String> {
        let mut out = Vec::new();
        let t = self.channel_threshold;
        if let Some(v) = self.max_over_fraction {
            out.push(if t == 0 && v == 0.0 {
                "every pixel equal".to_string()
            } else {
                format!("pixels more than {t} steps off ≤ {}%", 100.0 * v)
            });
        }
        if let Some(v) = self.max_neighbour_over_fraction {
            out.push(format!(
                "pixels more than {t} steps off with no 3×3 neighbour match ≤ {}%",
                100.0 * v
            ));
        }
        if let Some(v) = self.max_flip_mean {
            out.push(format!("FLIP mean ≤ {v}"));
        }
        if let Some((p, v)) = self.max_flip_percentile {
            out.push(format!("FLIP {}th percentile ≤ {v}", p * 100.0));
        }
        if let Some(v) = self.min_psnr {
            out.push(format!("PSNR ≥ {v} dB"));
        }
        out
    }
}

impl fmt::Display for Tolerance {
    /// The tolerance as `parse` reads it: only the criteria checked (`none` when nothing is).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut items = Vec::new();
        if self.max_over_fraction.is_some() || self.max_neighbour_over_fraction.is_some() {
            items.push(format!("threshold={}", self.channel_threshold));
        }
        if let Some(v) = self.max_over_fraction {
            items.push(format!("over={v}"));
        }
        if let Some(v) = self.max_neighbour_over_fraction {
            items.push(format!("neighbour-over={v}"));
        }
        if let Some(v) = self.max_flip_mean {
            items.push(format!("flip-mean={v}"));
        }
        if let Some((p, v)) = self.max_flip_percentile {
            items.push(format!("flip-p{}={v}", p * 100.0));
        }
        if let Some(v) = self.min_psnr {
            items.push(format!("psnr={v}"));
        }
        if items.is_empty() {
            f.write_str("none")
        } else {
            f.write_str(&items.join(","))
        }
    }
}

/// PSNR in dB; infinite when the images are identical (JSON: the string `"inf"`).
#[derive(Clone, Copy, Debug, PartialEq, PartialOrd)]
pub struct Psnr(pub f64);

impl Serialize for Psnr {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        if self.0.is_finite() {
            s.serialize_f64(self.0)
        } else {
            s.serialize_str("inf")
        }
    }
}

impl fmt::Display for Psnr {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.0.is_finite() {
            write!(f, "{:.2} dB", self.0)
        } else {
            f.write_str("inf")
        }
    }
}

/// The FLIP figures of a comparison.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FlipStats {
    /// Mean error (FLIP's recommended single figure).
    pub mean: f32,
    /// Median (weighted percentile 0.5).
    pub median: f32,
    /// 95th percentile.
    pub p95: f32,
    /// 99th percentile.
    pub p99: f32,
    /// Largest error.
    pub max: f32,
    /// The percentile asked for by the tolerance, if any: `(percentile, value)`.
    pub checked_percentile: Option<(f32, f32)>,
}

/// Everything measured between two images, and the verdict against a tolerance.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Comparison {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width × height`.
    pub pixels: u64,
    /// Pixels equal in all four channels.
    pub exact_pixels: u64,
    /// Largest absolute difference per channel, R, G, B, A (8-bit steps).
    pub max_abs_error: [u8; 4],
    /// Mean absolute difference per channel, R, G, B, A (8-bit steps).
    pub mean_abs_error: [f64; 4],
    /// PSNR over R, G, B.
    pub psnr: Psnr,
    /// Pixels where some channel differs by more than the tolerance's threshold.
    pub over_threshold: u64,
    /// Of those, pixels with no match within the threshold among the other image's 3×3
    /// neighbours (either way round).
    pub neighbour_over_threshold: u64,
    /// FLIP error statistics.
    pub flip: FlipStats,
    /// The tolerance the verdict used.
    pub tolerance: Tolerance,
    /// The criteria the verdict checked, one phrase each ([`Tolerance::criteria`]).
    pub checked: Vec<String>,
    /// Every bound exceeded, one line each; empty when within tolerance.
    pub failures: Vec<String>,
}

impl Comparison {
    /// Whether every figure is within the tolerance.
    pub fn passed(&self) -> bool {
        self.failures.is_empty()
    }

    /// Whether the images are identical.
    pub fn is_exact(&self) -> bool {
        self.exact_pixels == self.pixels
    }

    /// Fraction of pixels over the threshold.
    pub fn over_fraction(&self) -> f64 {
        self.over_threshold as f64 / self.pixels as f64
    }

    /// Fraction of pixels over the threshold without a neighbour match.
    pub fn neighbour_over_fraction(&self) -> f64 {
        self.neighbour_over_threshold as f64 / self.pixels as f64
    }
}

impl fmt::Display for Comparison {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let e = &self.mean_abs_error;
        writeln!(f, "size            {}×{}", self.width, self.height)?;
        writeln!(
            f,
            "exact pixels    {} of {} ({:.4}%)",
            self.exact_pixels,
            self.pixels,
            100.0 * self.exact_pixels as f64 / self.pixels as f64
        )?;
        writeln!(
            f,
            "max abs error   R {} G {} B {} A {}",
            self.max_abs_error[0],
            self.max_abs_error[1],
            self.max_abs_error[2],
            self.max_abs_error[3]
        )?;
        writeln!(
            f,
            "mean abs error  R {:.4} G {:.4} B {:.4} A {:.4}",
            e[0], e[1], e[2], e[3]
        )?;
        writeln!(f, "PSNR (RGB)      {}", self.psnr)?;
        writeln!(
            f,
            "over threshold  {} ({:.4}%) with threshold {}; {} ({:.4}%) without a 3×3 neighbour match",
            self.over_threshold,
            100.0 * self.over_fraction(),
            self.tolerance.channel_threshold,
            self.neighbour_over_threshold,
            100.0 * self.neighbour_over_fraction()
        )?;
        writeln!(
            f,
            "FLIP            mean {:.5} median {:.5} p95 {:.5} p99 {:.5} max {:.5}",
            self.flip.mean, self.flip.median, self.flip.p95, self.flip.p99, self.flip.max
        )?;
        writeln!(f, "tolerance       {}", self.tolerance)?;
        if self.checked.is_empty() {
            writeln!(f, "checked         nothing (no bound given)")?;
        } else {
            writeln!(f, "checked         {}", self.checked.join("; "))?;
        }
        if self.failures.is_empty() {
            write!(
                f,
                "verdict         within tolerance ({} criteria checked)",
                self.checked.len()
            )
        } else {
            write!(
                f,
                "verdict         OUTSIDE tolerance on {} of {} criteria: {}",
                self.failures.len(),
                self.checked.len(),
                self.failures.join("; ")
            )
        }
    }
}

/// Absolute channel differences of two pixels.
#[inline]
fn abs_diff(a: &[u8; 4], b: &[u8; 4]) -> [u8; 4] {
    std::array::from_fn(|c| a[c].abs_diff(b[c]))
}

/// Whether some pixel of `other` in the 3×3 neighbourhood of (x, y) matches `p` within `t` in
/// every channel.
fn has_neighbour_match(p: &[u8; 4], other: &RgbaImage, x: u32, y: u32, t: u8) -> bool {
    let (w, h) = other.dimensions();
    for ny in y.saturating_sub(1)..=(y + 1).min(h - 1) {
        for nx in x.saturating_sub(1)..=(x + 1).min(w - 1) {
            if abs_diff(p, &other.get_pixel(nx, ny).0)
                .iter()
                .all(|&d| d <= t)
            {
                return true;
            }
        }
    }
    false
}

/// The FLIP error map (LDR-FLIP on R, G, B; values in `[0, 1]`, row-major).
pub fn flip_error_map(a: &RgbaImage, b: &RgbaImage) -> Result<Vec<f32>, CompareError> {
    check_sizes(a, b)?;
    Ok(flip_map(a, b).to_vec())
}

fn rgb(image: &RgbaImage) -> nv_flip::FlipImageRgb8 {
    let data: Vec<u8> = image.pixels().flat_map(|p| [p[0], p[1], p[2]]).collect();
    nv_flip::FlipImageRgb8::with_data(image.width(), image.height(), &data)
}

fn flip_map(a: &RgbaImage, b: &RgbaImage) -> nv_flip::FlipImageFloat {
    nv_flip::flip(rgb(a), rgb(b), nv_flip::DEFAULT_PIXELS_PER_DEGREE)
}

fn check_sizes(a: &RgbaImage, b: &RgbaImage) -> Result<(), CompareError> {
    if a.dimensions() != b.dimensions() {
        return Err(CompareError::SizeMismatch {
            a_width: a.width(),
            a_height: a.height(),
            b_width: b.width(),
            b_height: b.height(),
        });
    }
    if a.width() == 0 || a.height() == 0 {
        return Err(CompareError::Empty);
    }
    Ok(())
}

/// Compares `a` (the reference) with `b` (the image under test) and judges the result
/// against `tolerance`. Fails only when the images differ in size or are empty.
pub fn compare_images(
    a: &RgbaImage,
    b: &RgbaImage,
    tolerance: &Tolerance,
) -> Result<Comparison, CompareError> {
    check_sizes(a, b)?;
    let (width, height) = a.dimensions();
    let pixels = u64::from(width) * u64::from(height);
    let t = tolerance.channel_threshold;
    let mut exact_pixels = 0u64;
    let mut max_abs_error = [0u8; 4];
    let mut sum_abs = [0u64; 4];
    let mut sum_sq_rgb = 0u64;
    let mut over_threshold = 0u64;
    let mut neighbour_over_threshold = 0u64;
    for (x, y, pa) in a.enumerate_pixels() {
        let pb = b.get_pixel(x, y);
        let d = abs_diff(&pa.0, &pb.0);
        if d == [0; 4] {
            exact_pixels += 1;
            continue;
        }
        for c in 0..4 {
            max_abs_error[c] = max_abs_error[c].max(d[c]);
            sum_abs[c] += u64::from(d[c]);
        }
        sum_sq_rgb += d[..3]
            .iter()
            .map(|&v| u64::from(v) * u64::from(v))
            .sum::<u64>();
        if d.iter().any(|&v| v > t) {
            over_threshold += 1;
            if !has_neighbour_match(&pa.0, b, x, y, t) || !has_neighbour_match(&pb.0, a, x, y, t) {
                neighbour_over_threshold += 1;
            }
        }
    }
    let mean_abs_error = sum_abs.map(|s| s as f64 / pixels as f64);
    let psnr = if sum_sq_rgb == 0 {
        Psnr(f64::INFINITY)
    } else {
        let mse = sum_sq_rgb as f64 / (3.0 * pixels as f64);
        Psnr(10.0 * (255.0f64 * 255.0 / mse).log10())
    };
    let flip = if exact_pixels == pixels {
        // FLIP of identical images is 0 everywhere; skip the filtering.
        FlipStats {
            mean: 0.0,
            median: 0.0,
            p95: 0.0,
            p99: 0.0,
            max: 0.0,
            checked_percentile: tolerance.max_flip_percentile.map(|(p, _)| (p, 0.0)),
        }
    } else {
        let map = flip_map(a, b);
        let mut pool = nv_flip::FlipPool::from_image(&map);
        FlipStats {
            mean: pool.mean(),
            median: pool.get_percentile(0.5, true),
            p95: pool.get_percentile(0.95, true),
            p99: pool.get_percentile(0.99, true),
            max: pool.max_value(),
            checked_percentile: tolerance
                .max_flip_percentile
                .map(|(p, _)| (p, pool.get_percentile(p, true))),
        }
    };
    let mut c = Comparison {
        width,
        height,
        pixels,
        exact_pixels,
        max_abs_error,
        mean_abs_error,
        psnr,
        over_threshold,
        neighbour_over_threshold,
        flip,
        tolerance: tolerance.clone(),
        checked: tolerance.criteria(),
        failures: Vec::new(),
    };
    c.failures = judge(&c, tolerance);
    Ok(c)
}

/// Every bound of `t` that `c`'s figures exceed, one line each (empty: within tolerance).
pub fn judge(c: &Comparison, t: &Tolerance) -> Vec<String> {
    let mut failures = Vec::new();
    if let Some(max) = t.max_over_fraction
        && c.over_fraction() > max
    {
        failures.push(format!(
            "{:.4}% of pixels differ by more than {} (allowed {:.4}%)",
            100.0 * c.over_fraction(),
            t.channel_threshold,
            100.0 * max
        ));
    }
    if let Some(max) = t.max_neighbour_over_fraction
        && c.neighbour_over_fraction() > max
    {
        failures.push(format!(
            "{:.4}% of pixels have no 3×3 neighbour within {} (allowed {:.4}%)",
            100.0 * c.neighbour_over_fraction(),
            t.channel_threshold,
            100.0 * max
        ));
    }
    if let Some(max) = t.max_flip_mean
        && c.flip.mean > max
    {
        failures.push(format!("FLIP mean {:.5} > {max}", c.flip.mean));
    }
    if let (Some((p, max)), Some((_, value))) = (t.max_flip_percentile, c.flip.checked_percentile)
        && value > max
    {
        failures.push(format!(
            "FLIP {}th percentile {value:.5} > {max}",
            p * 100.0
        ));
    }
    if let Some(min) = t.min_psnr
        && c.psnr.0 < min
    {
        failures.push(format!("PSNR {} < {min} dB", c.psnr));
    }
    failures
}

/// A heat map of the differences, the size of the images: identical pixels show the reference
/// as a dim grey (its luma at a quarter, for orientation); differing pixels are coloured by
/// their largest channel difference `d` on a log scale, `log(d)/log(255)`, from dark blue
/// (d = 1) through magenta and orange to yellow-white (d = 255), so a one-step difference
/// is as visible as a large one. Opaque.
pub fn heat_map(a: &RgbaImage, b: &RgbaImage) -> Result<RgbaImage, CompareError> {
    check_sizes(a, b)?;
    let (w, h) = a.dimensions();
    let mut out = RgbaImage::new(w, h);
    for (x, y, pa) in a.enumerate_pixels() {
        let pb = b.get_pixel(x, y);
        let d = abs_diff(&pa.0, &pb.0).into_iter().max().unwrap_or(0);
        let px = if d == 0 {
            let luma =
                (u32::from(pa[0]) * 54 + u32::from(pa[1]) * 183 + u32::from(pa[2]) * 19) >> 8;
            let g = (luma / 4) as u8;
            [g, g, g, 255]
        } else {
            let s = (f32::from(d)).ln() / 255f32.ln();
            ramp(s)
        };
        out.put_pixel(x, y, image::Rgba(px));
    }
    Ok(out)
}

/// The heat-map colour ramp at `s` in `[0, 1]`.
fn ramp(s: f32) -> [u8; 4] {
    const STOPS: [[f32; 3]; 5] = [
        [40.0, 40.0, 200.0],
        [170.0, 40.0, 200.0],
        [240.0, 60.0, 60.0],
        [250.0, 170.0, 30.0],
        [255.0, 255.0, 210.0],
    ];
    let x = s.clamp(0.0, 1.0) * (STOPS.len() - 1) as f32;
    let i = (x as usize).min(STOPS.len() - 2);
    let f = x - i as f32;
    let c: [f32; 3] = std::array::from_fn(|k| STOPS[i][k] + (STOPS[i + 1][k] - STOPS[i][k]) * f);
    [c[0] as u8, c[1] as u8, c[2] as u8, 255]
}

/// The smallest FLIP error [`flip_heat_map`] tells apart from equal: the black end of its
/// scale (FLIP errors this small are invisible).
pub const FLIP_MAP_MIN: f32 = 0.001;

/// Where [`flip_heat_map`] puts the FLIP error `e` on its colour scale, in `[0, 1]`: a log
/// scale, `log10(e / FLIP_MAP_MIN) / log10(1 / FLIP_MAP_MIN)`, so that 0.001 → 0, 0.01 → ⅓,
/// 0.1 → ⅔ and 1 → 1; errors at or below [`FLIP_MAP_MIN`] (and equal pixels, error 0) → 0.
///
/// On a linear scale the errors of a failing GPU capture (mostly 0.01–0.2) drew near black;
/// here the GPU tolerance's per-pixel bound (`flip-p99=0.15`) sits at 0.73, an orange.
pub fn flip_map_position(e: f32) -> f32 {
    if e.is_nan() || e <= FLIP_MAP_MIN {
        return 0.0;
    }
    (libm::log10f(e / FLIP_MAP_MIN) / libm::log10f(1.0 / FLIP_MAP_MIN)).clamp(0.0, 1.0)
}

/// FLIP's magma colour map (the FLIP paper's, through `nv-flip`) at `s` in `[0, 1]`: black,
/// purple, red-pink, orange, pale yellow. Perceptually ordered: brighter is larger.
pub fn magma(s: f32) -> [u8; 4] {
    static LUT: std::sync::OnceLock<Vec<u8>> = std::sync::OnceLock::new();
    let lut = LUT.get_or_init(|| nv_flip::magma_lut().to_vec());
    let i = (s.clamp(0.0, 1.0) * 255.0).round() as usize * 3;
    [lut[i], lut[i + 1], lut[i + 2], 255]
}

/// The FLIP error map, opaque: each pixel's error placed on the log scale of
/// [`flip_map_position`] and coloured with [`magma`]; black where the images are equal or
/// differ by at most [`FLIP_MAP_MIN`].
pub fn flip_heat_map(a: &RgbaImage, b: &RgbaImage) -> Result<RgbaImage, CompareError> {
    check_sizes(a, b)?;
    let rgba: Vec<u8> = flip_map(a, b)
        .to_vec()
        .into_iter()
        .flat_map(|e| magma(flip_map_position(e)))
        .collect();
    Ok(RgbaImage::from_raw(a.width(), a.height(), rgba).expect("size matches"))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn solid(w: u32, h: u32, c: [u8; 4]) -> RgbaImage {
        RgbaImage::from_pixel(w, h, image::Rgba(c))
    }

    #[test]
    fn the_flip_map_scale_is_logarithmic_and_bright_where_a_capture_fails() {
        assert_eq!(flip_map_position(0.0), 0.0);
        assert_eq!(flip_map_position(f32::NAN), 0.0);
        assert_eq!(flip_map_position(FLIP_MAP_MIN), 0.0);
        for (e, s) in [(0.01f64, 1.0 / 3.0), (0.1, 2.0 / 3.0), (1.0, 1.0)] {
            let expected = (e / 0.001).log10() / 3.0;
            assert!((f64::from(flip_map_position(e as f32)) - expected).abs() < 1e-5);
            assert!((expected - s).abs() < 1e-12);
        }
        assert_eq!(flip_map_position(2.0), 1.0);
        // Brighter is larger, and the GPU tolerance's per-pixel bound is far from black.
        let luma = |c: [u8; 4]| 0.2126 * c[0] as f32 + 0.7152 * c[1] as f32 + 0.0722 * c[2] as f32;
        let mut previous = -1.0;
        for k in 0..=100 {
            let l = luma(magma(k as f32 / 100.0));
            assert!(l >= previous, "{k}: {l} < {previous}");
            previous = l;
        }
        assert!(luma(magma(flip_map_position(0.15))) > 100.0);
        assert_eq!(magma(0.0), magma(flip_map_position(0.0)));
    }

    #[test]
    fn identical_images_are_exact_with_infinite_psnr() {
        let a = solid(8, 6, [10, 20, 30, 255]);
        let c = compare_images(&a, &a, &Tolerance::exact()).unwrap();
        assert!(c.is_exact() && c.passed());
        assert_eq!(c.psnr.0, f64::INFINITY);
        assert_eq!(c.max_abs_error, [0; 4]);
        assert_eq!(c.flip.mean, 0.0);
    }

    #[test]
    fn one_step_difference_is_measured_and_judged() {
        let a = solid(10, 10, [100, 100, 100, 255]);
        let mut b = a.clone();
        b.put_pixel(3, 4, image::Rgba([101, 100, 98, 255]));
        let c = compare_images(&a, &b, &Tolerance::exact()).unwrap();
        assert_eq!(c.exact_pixels, 99);
        assert_eq!(c.max_abs_error, [1, 0, 2, 0]);
        assert!((c.mean_abs_error[2] - 0.02).abs() < 1e-12);
        // MSE over RGB = (1 + 4) / 300.
        let expected = 10.0 * (255.0f64 * 255.0 / (5.0 / 300.0)).log10();
        assert!((c.psnr.0 - expected).abs() < 1e-9);
        assert_eq!(c.over_threshold, 1);
        assert!(!c.passed());
        let loose = Tolerance::parse("threshold=2").unwrap();
        assert!(compare_images(&a, &b, &loose).unwrap().passed());
        let fraction = Tolerance::parse("over=0.01").unwrap();
        assert!(compare_images(&a, &b, &fraction).unwrap().passed());
    }

    #[test]
    fn a_shifted_edge_is_forgiven_by_the_neighbour_compare() {
        let mut a = solid(12, 12, [0, 0, 0, 255]);
        let mut b = a.clone();
        for y in 0..12 {
            for x in 0..12 {
                if x >= 6 {
                    a.put_pixel(x, y, image::Rgba([255, 255, 255, 255]));
                }
                if x >= 7 {
                    b.put_pixel(x, y, image::Rgba([255, 255, 255, 255]));
                }
            }
        }
        let c = compare_images(&a, &b, &Tolerance::exact()).unwrap();
        assert_eq!(c.over_threshold, 12);
        assert_eq!(c.neighbour_over_threshold, 0);
        // A lone bright pixel has no neighbour match.
        let mut d = a.clone();
        d.put_pixel(2, 2, image::Rgba([255, 0, 0, 255]));
        let c = compare_images(&a, &d, &Tolerance::exact()).unwrap();
        assert_eq!(c.neighbour_over_threshold, 1);
        assert!(c.flip.max > 0.1);
    }

    #[test]
    fn sizes_must_match() {
        let a = solid(4, 4, [0; 4]);
        let b = solid(4, 5, [0; 4]);
        assert!(matches!(
            compare_images(&a, &b, &Tolerance::exact()),
            Err(CompareError::SizeMismatch { .. })
        ));
    }

    #[test]
    fn tolerance_strings() {
        let t =
            Tolerance::parse("threshold=3, over=0.01,flip-mean=0.05,flip-p99=0.4,psnr=30").unwrap();
        assert_eq!(t.channel_threshold, 3);
        assert_eq!(t.max_flip_percentile, Some((0.99, 0.4)));
        assert_eq!(Tolerance::parse(&t.to_string()).unwrap(), t);
        assert_eq!(Tolerance::parse("exact").unwrap(), Tolerance::exact());
        assert_eq!(Tolerance::parse("").unwrap(), Tolerance::exact());
        assert_eq!(Tolerance::parse("gpu").unwrap().to_string(), GPU_TOLERANCE);
        assert_eq!(Tolerance::parse("gpu").unwrap(), Tolerance::gpu());
        // A preset then an override, read left to right.
        let t = Tolerance::parse("gpu,psnr=35").unwrap();
        assert_eq!(t.min_psnr, Some(35.0));
        assert_eq!(t.max_flip_mean, Some(0.015));
        // Threshold alone allows no pixel over it.
        let t = Tolerance::parse("threshold=4").unwrap();
        assert_eq!((t.channel_threshold, t.max_over_fraction), (4, Some(0.0)));
        assert_eq!(Tolerance::parse(&t.to_string()).unwrap(), t);
        assert!(Tolerance::parse("over=2").is_err());
        assert!(Tolerance::parse("gpus").is_err());
        assert!(Tolerance::parse("colour=1").is_err());
        assert!(Tolerance::parse("threshold").is_err());
    }

    #[test]
    fn a_partial_tolerance_checks_only_what_it_names() {
        // One pixel 40 steps off out of 10,000: exact fails, but a FLIP-mean bound alone
        // (FLIP mean of one pixel in 10,000 is tiny) passes, and says it checked only that.
        let a = solid(100, 100, [100, 100, 100, 255]);
        let mut b = a.clone();
        b.put_pixel(50, 50, image::Rgba([140, 100, 100, 255]));
        let t = Tolerance::parse("flip-mean=0.015").unwrap();
        assert_eq!(t.max_over_fraction, None);
        let c = compare_images(&a, &b, &t).unwrap();
        assert!(c.passed(), "{c}");
        assert_eq!(c.checked, vec!["FLIP mean ≤ 0.015".to_string()]);
        let text = c.to_string();
        assert!(text.contains("checked         FLIP mean ≤ 0.015"), "{text}");
        assert!(
            text.contains("within tolerance (1 criteria checked)"),
            "{text}"
        );
        let strict = compare_images(&a, &b, &Tolerance::exact()).unwrap();
        assert!(!strict.passed());
        assert!(
            strict
                .to_string()
                .contains("OUTSIDE tolerance on 1 of 1 criteria")
        );
        // A PSNR bound alone: one pixel 40 steps off in one channel of 30,000 values.
        let psnr = compare_images(&a, &b, &Tolerance::parse("psnr=60").unwrap()).unwrap();
        assert!(psnr.passed(), "{psnr}");
        let psnr = compare_images(&a, &b, &Tolerance::parse("psnr=70").unwrap()).unwrap();
        assert_eq!(psnr.failures.len(), 1, "{psnr}");
        // Nothing named: nothing checked, said so.
        let none = compare_images(&a, &b, &Tolerance::unconstrained()).unwrap();
        assert!(none.passed() && none.checked.is_empty());
        assert!(none.to_string().contains("checked         nothing"));
        assert_eq!(Tolerance::unconstrained().to_string(), "none");
    }

    #[test]
    fn heat_map_marks_only_differences() {
        let a = solid(4, 4, [200, 200, 200, 255]);
        let mut b = a.clone();
        b.put_pixel(1, 1, image::Rgba([200, 201, 200, 255]));
        let m = heat_map(&a, &b).unwrap();
        assert_eq!(m.get_pixel(0, 0).0, [50, 50, 50, 255]);
        assert_eq!(m.get_pixel(1, 1).0, ramp(0.0));
    }
}
