//! Fin texture baking (thesis 3.1.2.2; fur bake): a side view of taller strands planted in a narrow
//! strip.
//!
//! [`bake_fin`] bakes the strip `FurParams` describes; [`bake_fin_for_shells`] (what a scene
//! draws) fits the strip's strand count and radii to the baked shell layers first, so that a
//! row of the fin shows strands as wide and as far apart as a row of the shell layer at the same
//! height ([`RunStats`]).
//!
//! The strip is `x ∈ [0, 1)` (periodic, along the silhouette edge) by `y ∈ [0, fin_width)`
//! (depth). The view is an orthographic projection onto the `(x, z)` plane looking along `+y`
//! (the viewer at `y = −∞`); the visible surface of each cone wins by depth, ties going to the
//! later strand. Fin tangents use the frame `x` = texture `u` (along the edge), `y` = depth (into
//! the fin, away from the viewer), `z` = up (texture `v`, away from the surface).

use glam::{Vec2, Vec3};

use super::bake::{ShellTextures, cones_of, gaussian_layer_weight, layer_mid_height};
use super::cone::{ConeSegment, FacetTable, GridMap, raster_capsule};
use super::image::{Rgba8Image, Sample, SampleGrid, downsample};
use super::params::{FurError, FurParams, MAX_STRANDS};
use super::strand::{Strand, generate_fin_strands};

/// A baked fin texture: colour and tangent maps sharing one alpha.
///
/// Both images are `texture_resolution × texture_resolution`. Column `u` is `x` along the edge
/// (periodic); row 0 is the root (`v = 0`, height 0) and the last row the top (height
/// `max_height`), so `v = height / max_height`. Written to a PNG as is, the fur hangs upside down.
#[derive(Debug, Clone, PartialEq)]
pub struct FinTexture {
    /// Height `H` of the fin's top row edge: the greatest height of a sampled fin strand point,
    /// tile units (`max_height · fin_height_scale` when there is no fin strand).
    pub max_height: f32,
    /// RGB: strand colour (linear); A: `covered fraction · exp(−v² / (2σ²))`, `v` the row's
    /// relative height.
    pub colour: Rgba8Image,
    /// RGB: tangent encoded as `unorm8(t·0.5 + 0.5)` in the fin frame (module doc); A: as colour.
    pub tangent: Rgba8Image,
}

/// Generates the fin strands ([`generate_fin_strands`]) and bakes their side view
/// ([`bake_fin_strands`]).
pub fn bake_fin(params: &FurParams, seed: u32) -> Result<FinTexture, FurError> {
    let strands = generate_fin_strands(params, seed)?;
    bake_fin_strands(params, &strands)
}

/// Covered texels, uncovered texels and runs of covered texels along `u` over some rows of a
/// baked texture. A texel counts as covered when at least half its subsamples were: its alpha
/// at least `0.375 ·` its row's Gaussian weight (the covered fraction steps by a quarter at
/// supersample 2, by less above). Rows wrap around in `u`, as the tile does.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct RunStats {
    /// Covered texels.
    pub covered: u64,
    /// Texels not covered.
    pub uncovered: u64,
    /// Runs of covered texels (a covered texel whose left neighbour is not).
    pub runs: u64,
}

impl RunStats {
    /// The statistics of row `row` of `image`, whose Gaussian weight is `weight`.
    pub fn of_row(image: &Rgba8Image, row: u32, weight: f32) -> Self {
        let w = image.width as usize;
        let start = row as usize * w;
        let Some(texels) = image.texels.get(start..start + w) else {
            return Self::default();
        };
        let covered = |x: usize| f32::from(texels[x][3]) / 255.0 >= 0.375 * weight;
        let mut stats = Self::default();
        for x in 0..w {
            if covered(x) {
                stats.covered += 1;
                if !covered((x + w - 1) % w) {
                    stats.runs += 1;
                }
            } else {
                stats.uncovered += 1;
            }
        }
        stats
    }

    fn add(&mut self, other: Self) {
        self.covered += other.covered;
        self.uncovered += other.uncovered;
        self.runs += other.runs;
    }

    /// Mean run of covered texels (texels): how wide the strands look along `u`.
    pub fn mean_run(&self) -> f64 {
        self.covered as f64 / self.runs.max(1) as f64
    }

    /// Mean gap between runs (texels): how far apart the strands are.
    pub fn mean_gap(&self) -> f64 {
        self.uncovered as f64 / self.runs.max(1) as f64
    }
}

/// The run statistics of the shell layers whose middle height lies in `[lo, hi)` (fractions of
/// the shells' height), over all their rows.
pub fn shell_run_stats(shells: &ShellTextures, sigma: f32, lo: f32, hi: f32) -> RunStats {
    let n = shells.layers.len() as u32;
    let mut stats = RunStats::default();
    for (i, layer) in shells.layers.iter().enumerate() {
        let mid = layer_mid_height(i as u32, n);
        if !(lo..hi).contains(&mid) {
            continue;
        }
        let weight = gaussian_layer_weight(mid, sigma);
        for row in 0..layer.colour.height {
            stats.add(RunStats::of_row(&layer.colour, row, weight));
        }
    }
    stats
}

/// The run statistics of the fin texture's rows at the heights the shells hold at fractions
/// `[lo, hi)` of `shell_height`: a fin strand is a shell strand stretched upwards by
/// `fin_height_scale`, so the shells' height `f · shell_height` is the fin's
/// `f · shell_height · fin_height_scale`.
pub fn fin_run_stats(
    fin: &FinTexture,
    shell_height: f32,
    fin_height_scale: f32,
    sigma: f32,
    lo: f32,
    hi: f32,
) -> RunStats {
    let res = fin.colour.height;
    let scale = shell_height * fin_height_scale / fin.max_height;
    let mut stats = RunStats::default();
    for row in 0..res {
        let v = (row as f32 + 0.5) / res as f32;
        if (lo..hi).contains(&(v / scale)) {
            let weight = gaussian_layer_weight(v, sigma);
            stats.add(RunStats::of_row(&fin.colour, row, weight));
        }
    }
    stats
}

/// How the fin strip was fitted to the shells ([`bake_fin_for_shells`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FinFit {
    /// Strands planted in the strip.
    pub strands: u32,
    /// Depth of the strip, tile units: `strands / number_of_strands` (the shells' density).
    pub depth: f32,
    /// Factor on every fin strand's root radius.
    pub base_scale: f32,
    /// Factor on every fin strand's tip radius.
    pub tip_scale: f32,
}

/// The heights (fractions of the shells' height) over which [`bake_fin_for_shells`] matches the
/// strands' spacing, and the lower and upper halves over which it matches their width.
pub const FIN_FIT_HEIGHTS: [f32; 3] = [0.2, 0.5, 0.8];

/// Rounds of the fit in [`bake_fin_for_shells`].
const FIN_FIT_ROUNDS: usize = 3;

/// Bakes the fin strip whose side view shows the shells' strands at their width and spacing
/// (thesis 3.1.2.2: "the same strand generation method but we limit the area and increase the
/// height"), measured on the baked shell layers as runs of covered texels along `u`
/// ([`RunStats`]) between [`FIN_FIT_HEIGHTS`]:
///
/// 1. Start from a strip one root diameter deep at the shells' density
///    (`round(number_of_strands · 2 · base_thickness)` strands), the strands' own radii.
/// 2. Three times: bake; scale the strand count by the fin's mean gap over the shells' (for
///    strands placed independently the mean gap is `1/λ`, `λ` strands per texel: more
///    strands, smaller gaps), the root radii by the shells' mean run over the fin's on the
///    lower half of the heights, the tip radii by the same ratio on the upper half (each
///    factor kept within `[0.25, 4]` per round, the radii's within `[0.25, 4]` overall, the
///    count within `1..=number_of_strands`: the strip is at most the tile deep).
/// 3. Bake with the result; the strip is `strands / number_of_strands` deep, the shells' strands
///    per unit area.
///
/// Why measured and not derived: a side view shows a strand's whole diameter where a row of a
/// shell layer cuts its section along a chord (`π/4` of the diameter on average); a layer holds
/// a slab of each strand, so a leaning strand covers more of a thick layer than of a thin one;
/// and near the tips a strand thinner than a texel is lost to the half-coverage rule in a thin
/// layer sooner than in the side view. So neither the count nor the radii carry over (a fixed
/// strip matched the 24 and 30 layers of `leg.toml` and `gravity.toml` and was 1.24–1.40× too
/// wide on the 40 of `torus.toml`). Measured, the fit leaves the fin's mean run within 15 % of
/// the shells' in each of the bands 0.2–0.4, 0.4–0.6, 0.6–0.8 of the height on all three
/// (`tests/fins.rs`). Every step is deterministic (integer counts, `f64` ratios, fixed
/// rounds). With no strands, or shells with no runs to match, the strip of step 1 is baked as
/// is.
pub fn bake_fin_for_shells(
    params: &FurParams,
    seed: u32,
    shells: &ShellTextures,
) -> Result<(FinTexture, FinFit), FurError> {
    params.validate()?;
    let [lo, mid, hi] = FIN_FIT_HEIGHTS;
    let sigma = params.gaussian_sigma;
    let shell_all = shell_run_stats(shells, sigma, lo, hi);
    let shell_low = shell_run_stats(shells, sigma, lo, mid);
    let shell_high = shell_run_stats(shells, sigma, mid, hi);
    // The strip is at most the tile deep: at most the shells' strands.
    let most = f64::from(params.number_of_strands.clamp(1, MAX_STRANDS));
    let start = (f64::from(params.number_of_strands) * 2.0 * f64::from(params.base_thickness))
        .round()
        .clamp(1.0, most);
    let mut fit = FinFit {
        strands: start as u32,
        depth: 0.0,
        base_scale: 1.0,
        tip_scale: 1.0,
    };
    let fits = params.number_of_strands > 0 && shell_all.runs > 0 && shell_all.uncovered > 0;
    // How much wider the fin's strands must be: the shells' mean run over the fin's.
    let ratio = |shell: RunStats, fin: RunStats| {
        if shell.runs > 0 && fin.runs > 0 {
            (shell.mean_run() / fin.mean_run()).clamp(0.25, 4.0) as f32
        } else {
            1.0
        }
    };
    let rounds = if fits { FIN_FIT_ROUNDS } else { 0 };
    for _ in 0..rounds {
        let fin = bake_fitted(params, seed, &fit)?;
        let stats = |lo, hi| {
            fin_run_stats(
                &fin,
                shells.max_height,
                params.fin_height_scale,
                sigma,
                lo,
                hi,
            )
        };
        let (all, low, high) = (stats(lo, hi), stats(lo, mid), stats(mid, hi));
        if all.runs > 0 {
            let gaps = (all.mean_gap() / shell_all.mean_gap()).clamp(0.25, 4.0);
            let strands = (f64::from(fit.strands) * gaps).round();
            fit.strands = strands.clamp(1.0, most) as u32;
        }
        fit.base_scale *= ratio(shell_low, low);
        fit.tip_scale *= ratio(shell_high, high);
        fit.base_scale = fit.base_scale.clamp(0.25, 4.0);
        fit.tip_scale = fit.tip_scale.clamp(0.25, 4.0);
    }
    let fin = bake_fitted(params, seed, &fit)?;
    fit.depth = strip_depth(params, fit.strands);
    Ok((fin, fit))
}

/// The strip depth holding `strands` at the shells' density, within `(0, 1]`.
fn strip_depth(params: &FurParams, strands: u32) -> f32 {
    let n = params.number_of_strands.max(1);
    ((f64::from(strands) / f64::from(n)) as f32).clamp(1e-4, 1.0)
}

fn bake_fitted(params: &FurParams, seed: u32, fit: &FinFit) -> Result<FinTexture, FurError> {
    let strip = FurParams {
        fin_strands: fit.strands,
        fin_width: strip_depth(params, fit.strands),
        ..params.clone()
    };
    let mut strands = generate_fin_strands(&strip, seed)?;
    for s in &mut strands {
        s.base_radius *= fit.base_scale;
        s.tip_radius *= fit.tip_scale;
    }
    bake_fin_strands(&strip, &strands)
}

/// Bakes the side view of `strands` at `texture_resolution · supersample` and box-downsamples.
///
/// A subsample (centre `q` in the `(x, z)` plane) is covered by a segment when `q` lies within
/// the interpolated radius of the segment's projected axis. Its surface point is on the cone's
/// cross-section circle, on the side facing the viewer: with `f = |offset| / r`, the direction
/// `f·side + sqrt(1 − f²)·towards_viewer` (both perpendicular to the axis). That direction
/// selects the facet whose tangent is stored; its `y` gives the depth.
pub fn bake_fin_strands(params: &FurParams, strands: &[Strand]) -> Result<FinTexture, FurError> {
    params.validate()?;
    let (cones, top) = cones_of(strands, params.strand_resolution);
    let h = if top > 0.0 {
        top
    } else {
        params.max_height * params.fin_height_scale
    };
    let ss = params.supersample as usize;
    let res = params.texture_resolution as usize;
    let side = res * ss;
    let map = GridMap {
        nx: side,
        ny: side,
        sx: 1.0 / side as f32,
        sy: h / side as f32,
        wrap_y: false,
    };
    let table = FacetTable::new(params.circle_resolution);
    let mut grid = SampleGrid::new(side, side);
    for (index, strand) in cones.iter().enumerate() {
        for seg in strand.iter().filter(|s| s.is_finite()) {
            draw_side(&mut grid, &map, &table, seg, index as u32);
        }
    }
    let colours: Vec<Vec3> = strands.iter().map(|s| s.colour).collect();
    let sigma = params.gaussian_sigma;
    let weight = |row: usize| gaussian_layer_weight((row as f32 + 0.5) / res as f32, sigma);
    let (colour, tangent) = downsample(&grid, ss, &colours, weight, false);
    Ok(FinTexture {
        max_height: h,
        colour,
        tangent,
    })
}

fn draw_side(
    grid: &mut SampleGrid,
    map: &GridMap,
    table: &FacetTable,
    seg: &ConeSegment,
    index: u32,
) {
    let side_view = |p: Vec3| Vec2::new(p.x, p.z);
    let axis = seg.axis;
    let d = seg.p1 - seg.p0;
    let toward_viewer = -Vec3::Y - axis * (-Vec3::Y).dot(axis);
    raster_capsule(
        map,
        side_view(seg.p0),
        side_view(seg.p1),
        seg.r0,
        seg.r1,
        |cell, t, off| {
            let r = seg.r0 + (seg.r1 - seg.r0) * t;
            let offset = Vec3::new(off.x, 0.0, off.y);
            let across = offset - axis * offset.dot(axis);
            let f = if r > 0.0 {
                (across.length() / r).min(1.0)
            } else {
                0.0
            };
            let side = across.normalize_or_zero();
            let front = (toward_viewer - side * toward_viewer.dot(side)).normalize_or_zero();
            let mut dir = side * f + front * libm::sqrtf(1.0 - f * f);
            if dir == Vec3::ZERO {
                dir = seg.e1;
            }
            let depth = seg.p0.y + d.y * t + r * dir.y;
            let j = seg.facet(dir, table);
            if let Some(s) = grid.samples.get_mut(cell)
                && depth <= s.depth
            {
                *s = Sample {
                    strand: index,
                    tangent: seg.facet_tangent(j, table),
                    depth,
                };
            }
        },
    );
}

#[cfg(test)]
mod tests {
    use super::super::image::tangent_from_rgb8;
    use super::*;

    fn vertical(x: f32, y: f32, h: f32, r: f32, colour: Vec3) -> Strand {
        super::super::strand::vertical_strand(x, y, h, r, colour)
    }

    #[test]
    fn side_view_of_vertical_strands() {
        let p = FurParams {
            texture_resolution: 32,
            supersample: 2,
            ..FurParams::default()
        };
        let red = Vec3::X;
        let blue = Vec3::Z;
        // Blue is behind red (larger y) at the same x; a lone red one near the right edge.
        let strands = [
            vertical(0.25, 0.01, 1.0, 0.04, red),
            vertical(0.25, 0.04, 0.5, 0.04, blue),
            vertical(0.99, 0.02, 0.5, 0.03, red),
        ];
        let fin = bake_fin_strands(&p, &strands).expect("bake");
        assert!((fin.max_height - 1.0).abs() < 1e-6);
        // Root row 0, column 8 (x ≈ 0.27): red in front, opaque.
        let c = fin.colour.get(8, 0).unwrap_or_default();
        assert_eq!([c[0], c[1], c[2]], [255, 0, 0]);
        assert!(c[3] > 200);
        // Tangent straight up.
        let t = fin.tangent.get(8, 10).unwrap_or_default();
        assert!(tangent_from_rgb8([t[0], t[1], t[2]]).z > 0.999);
        // Top rows: only the tall strand, with the Gaussian making them fainter than the root.
        let top = fin.colour.get(8, 31).unwrap_or_default();
        assert!(top[3] > 0 && top[3] < c[3]);
        // Wrap-around: the strand at x = 0.99, r = 0.03 reaches column 0 but not row 20.
        assert!(fin.colour.get(0, 2).unwrap_or_default()[3] > 0);
        assert_eq!(fin.colour.get(0, 20).unwrap_or_default()[3], 0);
        assert_eq!(fin.colour.get(16, 2).unwrap_or_default()[3], 0);
    }

    #[test]
    fn run_stats_count_runs_around_the_row() {
        // One row of 8 texels, weight 0.8: covered where alpha ≥ 0.3 (76.5 of 255).
        let mut image = Rgba8Image::new(8, 2, [0; 4]);
        for (x, a) in [(0, 255), (1, 77), (2, 76), (4, 200), (7, 90)] {
            image.texels[x] = [0, 0, 0, a];
        }
        let s = RunStats::of_row(&image, 0, 0.8);
        // Covered 0, 1, 4, 7; texel 7 joins 0 and 1 across the wrap: runs {7, 0, 1} and {4}.
        assert_eq!(
            s,
            RunStats {
                covered: 4,
                uncovered: 4,
                runs: 2
            }
        );
        assert_eq!(s.mean_run(), 2.0);
        assert_eq!(s.mean_gap(), 2.0);
        assert_eq!(RunStats::of_row(&image, 1, 0.8).runs, 0);
        assert_eq!(RunStats::of_row(&image, 5, 0.8), RunStats::default());
    }

    #[test]
    fn fitted_fin_has_the_shells_runs() {
        let p = FurParams {
            number_of_strands: 3000,
            texture_resolution: 64,
            number_of_shells: 20,
            max_height: 0.4,
            min_height: 0.28,
            ..FurParams::default()
        };
        let strands = super::super::strand::generate_strands(&p, 5).expect("valid");
        let shells = super::super::bake::bake_shells(&p, &strands).expect("bake");
        let (fin, fit) = bake_fin_for_shells(&p, 5, &shells).expect("bake");
        assert_eq!(
            (fin.clone(), fit),
            bake_fin_for_shells(&p, 5, &shells).expect("bake")
        );
        let [lo, _, hi] = FIN_FIT_HEIGHTS;
        let sigma = p.gaussian_sigma;
        let shell_run = shell_run_stats(&shells, sigma, lo, hi).mean_run();
        let run = |f: &FinTexture| {
            fin_run_stats(f, shells.max_height, p.fin_height_scale, sigma, lo, hi).mean_run()
        };
        let fitted = run(&fin) / shell_run;
        let fixed = run(&bake_fin(&p, 5).expect("bake")) / shell_run;
        assert!(
            (fitted - 1.0).abs() < 0.15,
            "fitted {fitted:.2}, fixed {fixed:.2}"
        );
        assert!(
            (fitted - 1.0).abs() < (fixed - 1.0).abs(),
            "{fitted} {fixed}"
        );
        assert!(
            fit.strands > 0 && fit.depth > 0.0 && fit.depth <= 1.0,
            "{fit:?}"
        );
        assert!((fit.depth - fit.strands as f32 / 3000.0).abs() < 1e-6);
        for scale in [fit.base_scale, fit.tip_scale] {
            assert!((0.25..=4.0).contains(&scale), "{fit:?}");
        }
        // Nothing to match: the starting strip, radii as drawn.
        let bare = FurParams {
            number_of_strands: 0,
            ..p.clone()
        };
        let empty = super::super::bake::bake_shells(&bare, &[]).expect("bake");
        let (_, fit) = bake_fin_for_shells(&bare, 5, &empty).expect("bake");
        assert_eq!((fit.base_scale, fit.tip_scale, fit.strands), (1.0, 1.0, 1));
    }

    #[test]
    fn fin_is_deterministic_and_seeded() {
        let p = FurParams {
            texture_resolution: 32,
            ..FurParams::default()
        };
        let a = bake_fin(&p, 1).expect("bake");
        assert_eq!(a, bake_fin(&p, 1).expect("bake"));
        assert_ne!(a, bake_fin(&p, 2).expect("bake"));
        assert!(a.max_height > p.max_height);
        let covered = a.colour.texels.iter().filter(|c| c[3] > 0).count();
        assert!(covered > 32 * 32 / 10, "{covered}");
        let bad = FurParams {
            fin_width: f32::NAN,
            ..p
        };
        assert!(bake_fin(&bad, 1).is_err());
    }
}
