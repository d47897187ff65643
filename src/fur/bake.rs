//! Shell texture baking (thesis 3.1.2.1, 3.1.3; fur bake): each layer holds the slice of every
//! strand between two heights, rasterised top-down into the periodic tile at `supersample`×
//! resolution and box-downsampled.
//!
//! Invariant: each layer is built by exactly one rayon task, strands in generation order and each
//! strand's segments root to tip, a later write overwriting an earlier one (no collision checks,
//! thesis 3.1.3). The output is therefore byte-identical for any thread count.

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use super::cone::{ConeSegment, FacetTable, GridMap, raster_capsule, strand_cones};
use super::image::{Rgba8Image, Sample, SampleGrid, density_bands, downsample};
use super::params::{FurError, FurParams};
use super::strand::Strand;

/// One shell layer: colour and tangent maps sharing one alpha.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ShellLayer {
    /// RGB: strand colour (linear, averaged over covered subsamples); A: alpha.
    pub colour: Rgba8Image,
    /// RGB: unit tangent `t` encoded as `unorm8(t·0.5 + 0.5)` in tangent space (`x` = texture
    /// `u`, `y` = texture `v`, `z` = up, away from the surface); A: the same alpha as `colour`.
    pub tangent: Rgba8Image,
    /// With a density map ([`bake_shells_with_density`]): R, G, B, A = the alpha of the
    /// strands whose density band is at most 0, 1, 2, 3 (so A equals `colour`'s alpha).
    pub density: Option<Rgba8Image>,
}

/// All shell layers of one tile, layer 0 at the root.
#[derive(Debug, Clone, PartialEq)]
pub struct ShellTextures {
    /// Side of every layer image in texels (`texture_resolution`).
    pub resolution: u32,
    /// `H`: the greatest height reached by a sampled strand point, tile units. Layer `i` holds
    /// heights `[i·H/N, (i+1)·H/N]`.
    pub max_height: f32,
    /// `number_of_shells` layers, root first.
    pub layers: Vec<ShellLayer>,
}

/// Gaussian alpha weight of a layer whose middle is at relative height `rel = h/H` (Lengyel):
/// `exp(−rel² / (2σ²))`.
pub fn gaussian_layer_weight(rel: f32, sigma: f32) -> f32 {
    libm::expf(-(rel * rel) / (2.0 * sigma * sigma))
}

/// Relative middle height `(i + ½) / N` of shell `layer` out of `shells`.
pub fn layer_mid_height(layer: u32, shells: u32) -> f32 {
    (layer as f32 + 0.5) / shells.max(1) as f32
}

/// The sampled cones of every strand, and the greatest height they reach.
pub(crate) fn cones_of(strands: &[Strand], segments: u32) -> (Vec<Vec<ConeSegment>>, f32) {
    let cones: Vec<Vec<ConeSegment>> = strands.iter().map(|s| strand_cones(s, segments)).collect();
    let top = cones
        .iter()
        .flatten()
        .filter(|c| c.is_finite())
        .map(|c| c.p0.z.max(c.p1.z))
        .fold(0.0f32, f32::max);
    (cones, top)
}

/// Bakes `number_of_shells` shell layers from `strands` (usually from
/// [`generate_strands`](super::generate_strands)).
///
/// Per layer `i`, every strand segment is clipped to heights `[i·H/N, (i+1)·H/N]` (a part that
/// only touches the range at one height is skipped; a horizontal segment belongs to the layer its
/// height falls in, the top boundary included in the last layer). The clipped part's cone is
/// projected straight down: subsamples whose centre lies within the interpolated radius of the
/// projected axis are covered, wrapping around the tile edges; the subsample's angle around the
/// axis selects the facet whose tangent is stored (see "Cones and tangents" in [the module
/// docs](super)). After the box
/// downsample, `alpha = covered fraction · gaussian_layer_weight(layer_mid_height(i, N), σ)`.
/// When no strand point is above 0, `H = max_height`.
pub fn bake_shells(params: &FurParams, strands: &[Strand]) -> Result<ShellTextures, FurError> {
    bake(params, strands, None)
}

/// [`bake_shells`] with each layer's density bands too: strand `k` is in band
/// [`density_band`](crate::shading::density_band)`(seed, k)`, and a layer's `density` image
/// holds, per texel, the alpha its strands of bands `≤ 0, 1, 2, 3` cover (thesis-free: for
/// density maps). The colour and tangent maps are those of [`bake_shells`], byte for byte.
pub fn bake_shells_with_density(
    params: &FurParams,
    strands: &[Strand],
    seed: u32,
) -> Result<ShellTextures, FurError> {
    let bands: Vec<u32> = (0..strands.len() as u32)
        .map(|k| crate::shading::density_band(seed, k))
        .collect();
    bake(params, strands, Some(&bands))
}

fn bake(
    params: &FurParams,
    strands: &[Strand],
    bands: Option<&[u32]>,
) -> Result<ShellTextures, FurError> {
    params.validate()?;
    let (cones, top) = cones_of(strands, params.strand_resolution);
    let h = if top > 0.0 { top } else { params.max_height };
    let n = params.number_of_shells;
    let ss = params.supersample as usize;
    let side = params.texture_resolution as usize * ss;
    let map = GridMap {
        nx: side,
        ny: side,
        sx: 1.0 / side as f32,
        sy: 1.0 / side as f32,
        wrap_y: true,
    };
    let table = FacetTable::new(params.circle_resolution);
    let colours: Vec<Vec3> = strands.iter().map(|s| s.colour).collect();
    let layers = (0..n)
        .into_par_iter()
        .map(|i| {
            let z0 = h * i as f32 / n as f32;
            let z1 = h * (i + 1) as f32 / n as f32;
            let grid = rasterise_layer(&cones, &map, &table, z0, z1, i + 1 == n);
            let w = gaussian_layer_weight(layer_mid_height(i, n), params.gaussian_sigma);
            let (colour, tangent) = downsample(&grid, ss, &colours, |_| w, true);
            let density = bands.map(|bands| density_bands(&grid, ss, bands, w));
            ShellLayer {
                colour,
                tangent,
                density,
            }
        })
        .collect();
    Ok(ShellTextures {
        resolution: params.texture_resolution,
        max_height: h,
        layers,
    })
}

/// The part `[lo, hi]` (segment parameters) of a segment inside heights `[z0, z1]`, if it has
/// positive length (or is a horizontal segment at a height in `[z0, z1)`, `[z0, z1]` for the
/// last layer).
pub(crate) fn clip_to_slab(c: &ConeSegment, z0: f32, z1: f32, last: bool) -> Option<(f32, f32)> {
    let (za, zb) = (c.p0.z, c.p1.z);
    let dz = zb - za;
    if dz == 0.0 {
        let inside = za >= z0 && (za < z1 || (last && za <= z1));
        return inside.then_some((0.0, 1.0));
    }
    let s0 = (z0 - za) / dz;
    let s1 = (z1 - za) / dz;
    let lo = s0.min(s1).max(0.0);
    let hi = s0.max(s1).min(1.0);
    (hi > lo).then_some((lo, hi))
}

fn rasterise_layer(
    cones: &[Vec<ConeSegment>],
    map: &GridMap,
    table: &FacetTable,
    z0: f32,
    z1: f32,
    last: bool,
) -> SampleGrid {
    let mut grid = SampleGrid::new(map.nx, map.ny);
    for (index, strand) in cones.iter().enumerate() {
        let index = index as u32;
        for seg in strand {
            if !seg.is_finite() || seg.p0.z.max(seg.p1.z) < z0 || seg.p0.z.min(seg.p1.z) > z1 {
                continue;
            }
            let Some((lo, hi)) = clip_to_slab(seg, z0, z1, last) else {
                continue;
            };
            let d = seg.p1 - seg.p0;
            let (a, b) = (seg.p0 + d * lo, seg.p0 + d * hi);
            let dr = seg.r1 - seg.r0;
            let (ra, rb) = (seg.r0 + dr * lo, seg.r0 + dr * hi);
            raster_capsule(
                map,
                a.truncate(),
                b.truncate(),
                ra,
                rb,
                |cell, _t, off: Vec2| {
                    let j = seg.facet(off.extend(0.0), table);
                    if let Some(s) = grid.samples.get_mut(cell) {
                        *s = Sample {
                            strand: index,
                            tangent: seg.facet_tangent(j, table),
                            depth: 0.0,
                        };
                    }
                },
            );
        }
    }
    grid
}

#[cfg(test)]
mod tests {
    use super::super::image::tangent_from_rgb8;
    use super::super::strand::generate_strands;
    use super::*;

    fn small() -> FurParams {
        FurParams {
            number_of_strands: 200,
            number_of_shells: 6,
            texture_resolution: 32,
            ..FurParams::default()
        }
    }

    fn bytes(t: &ShellTextures) -> Vec<u8> {
        t.layers
            .iter()
            .flat_map(|l| [l.colour.as_bytes(), l.tangent.as_bytes()])
            .flatten()
            .collect()
    }

    fn vertical(x: f32, y: f32, h: f32, r: f32) -> Strand {
        super::super::strand::vertical_strand(x, y, h, r, Vec3::new(1.0, 0.5, 0.25))
    }

    #[test]
    fn identical_for_any_thread_count() {
        let p = small();
        let strands = generate_strands(&p, 11).expect("valid");
        let bake_with = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .map(|pool| pool.install(|| bake_shells(&p, &strands)))
        };
        let one = bake_with(1).expect("pool").expect("bake");
        let three = bake_with(3).expect("pool").expect("bake");
        assert_eq!(one.layers.len(), 6);
        assert_eq!(bytes(&one), bytes(&three));
    }

    #[test]
    fn same_seed_same_bytes_other_seed_differs() {
        let p = small();
        let bake = |seed| {
            let s = generate_strands(&p, seed).expect("valid");
            bytes(&bake_shells(&p, &s).expect("bake"))
        };
        let a = bake(5);
        assert_eq!(a, bake(5));
        assert_ne!(a, bake(6));
    }

    #[test]
    fn wraps_around_the_tile_edge() {
        let p = FurParams {
            texture_resolution: 64,
            supersample: 1,
            number_of_shells: 4,
            ..FurParams::default()
        };
        // Root at x = 0.999, radius 0.02 ≈ 1.3 texels: must reach texel column 0.
        let strands = [vertical(0.999, 0.5, 1.0, 0.02)];
        let t = bake_shells(&p, &strands).expect("bake");
        let layer = &t.layers[0];
        let row = 32; // v ≈ 0.5
        let alpha = |x| layer.colour.get(x, row).map(|c| c[3]).unwrap_or(0);
        assert!(alpha(0) > 0, "column 0 not covered");
        assert!(alpha(63) > 0, "column 63 not covered");
        assert_eq!(alpha(5), 0);
        assert_eq!(alpha(58), 0);
    }

    #[test]
    fn vertical_strand_slices_are_discs_with_up_tangent() {
        let p = FurParams {
            texture_resolution: 64,
            supersample: 2,
            number_of_shells: 5,
            ..FurParams::default()
        };
        let r = 0.05;
        let strands = [vertical(0.5, 0.25, 1.0, r)];
        let t = bake_shells(&p, &strands).expect("bake");
        assert!((t.max_height - 1.0).abs() < 1e-6);
        let texel = 1.0 / 64.0;
        for layer in &t.layers {
            for y in 0..64u32 {
                for x in 0..64u32 {
                    let c = layer.colour.get(x, y).unwrap_or_default();
                    let centre = Vec2::new((x as f32 + 0.5) * texel, (y as f32 + 0.5) * texel);
                    let d = centre.distance(Vec2::new(0.5, 0.25));
                    if d < r - texel {
                        assert!(c[3] > 0, "inside texel ({x},{y}) empty");
                        assert_eq!([c[0], c[1], c[2]], [255, 128, 64]);
                        let tan = layer.tangent.get(x, y).unwrap_or_default();
                        assert_eq!(tan[3], c[3]);
                        let v = tangent_from_rgb8([tan[0], tan[1], tan[2]]);
                        assert!(v.z > 0.999, "tangent {v}");
                    } else if d > r + texel {
                        assert_eq!(c[3], 0, "outside texel ({x},{y}) covered");
                    }
                }
            }
        }
        // Full coverage: alpha is exactly the Gaussian weight.
        for (i, layer) in t.layers.iter().enumerate() {
            let a = layer.colour.get(32, 16).unwrap_or_default()[3];
            let w = gaussian_layer_weight(layer_mid_height(i as u32, 5), p.gaussian_sigma);
            assert_eq!(a, super::super::image::unorm8(w));
        }
    }

    #[test]
    fn tapered_vertical_cone_tangents_point_inwards_by_facet() {
        let p = FurParams {
            texture_resolution: 64,
            supersample: 1,
            number_of_shells: 4,
            circle_resolution: 8,
            ..FurParams::default()
        };
        let mut s = vertical(0.5, 0.5, 1.0, 0.1);
        s.tip_radius = 0.0;
        let t = bake_shells(&p, &[s]).expect("bake");
        let tan = |x: u32, y: u32| {
            let c = t.layers[0].tangent.get(x, y).unwrap_or_default();
            assert!(c[3] > 0, "({x},{y}) not covered");
            tangent_from_rgb8([c[0], c[1], c[2]])
        };
        // Texel centres east (+u) and north (+v) of the axis at (0.5, 0.5) = texel edge 32.
        let east = tan(36, 32);
        let north = tan(32, 36);
        let west = tan(27, 32);
        assert!(east.x < -0.05 && east.z > 0.9, "{east}");
        assert!(north.y < -0.05 && north.z > 0.9, "{north}");
        assert!(west.x > 0.05, "{west}");
        // Quantised to facets: a nearby texel in the same facet has the same tangent.
        assert_eq!(tan(37, 32), east);
    }

    #[test]
    fn alpha_decreases_with_height() {
        let p = FurParams {
            number_of_strands: 600,
            number_of_shells: 8,
            texture_resolution: 48,
            ..FurParams::default()
        };
        let strands = generate_strands(&p, 3).expect("valid");
        let t = bake_shells(&p, &strands).expect("bake");
        let sum: Vec<f64> = t
            .layers
            .iter()
            .map(|l| l.colour.texels.iter().map(|c| c[3] as f64).sum::<f64>())
            .collect();
        let half = sum.len() / 2;
        let lower: f64 = sum[..half].iter().sum();
        let upper: f64 = sum[half..].iter().sum();
        assert!(sum[0] > 0.0 && upper < 0.5 * lower, "{sum:?}");
        assert!(sum[7] < 0.1 * sum[0], "{sum:?}");
        // The most opaque texel of each layer (fully covered) shows the Gaussian weight.
        let max: Vec<u8> = t
            .layers
            .iter()
            .map(|l| l.colour.texels.iter().map(|c| c[3]).max().unwrap_or(0))
            .collect();
        for w in max.windows(2) {
            assert!(w[1] < w[0], "{max:?}");
        }
    }

    #[test]
    fn leaning_tapered_strand_tangents_follow_the_lean() {
        let p = FurParams {
            number_of_strands: 1,
            slope_deg: 40.0,
            jitter: 0.0,
            curl: 0.0,
            texture_resolution: 64,
            number_of_shells: 4,
            ..FurParams::default()
        };
        let strands = generate_strands(&p, 9).expect("valid");
        let lean = strands[0].lean;
        let t = bake_shells(&p, &strands).expect("bake");
        let layer = &t.layers[2];
        let mut n = 0;
        let mut distinct = Vec::new();
        for (c, tan) in layer.colour.texels.iter().zip(&layer.tangent.texels) {
            if c[3] > 0 {
                let v = tangent_from_rgb8([tan[0], tan[1], tan[2]]);
                assert!(v.truncate().dot(lean) > 0.2, "{v} vs lean {lean}");
                if !distinct.contains(tan) {
                    distinct.push(*tan);
                }
                n += 1;
            }
        }
        assert!(n > 0);
        // A tapered cone: tangents differ around the circumference.
        assert!(distinct.len() > 1);
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(12))]
        /// Any valid small configuration bakes; no layer is more opaque than its Gaussian weight.
        #[test]
        fn alpha_bounded_by_gaussian(
            seed in proptest::prelude::any::<u32>(),
            strands in 0u32..150,
            shells in 1u32..7,
            res in 1u32..24,
            ss in 1u32..4,
            circle in 3u32..40,
            segments in 1u32..30,
            slope in 0.0f32..85.0,
            curl in -2.0f32..2.0,
            jitter in 0.0f32..1.0,
            sigma in 0.05f32..3.0,
        ) {
            let p = FurParams {
                number_of_strands: strands,
                number_of_shells: shells,
                texture_resolution: res,
                supersample: ss,
                circle_resolution: circle,
                strand_resolution: segments,
                slope_deg: slope,
                curl,
                jitter,
                gaussian_sigma: sigma,
                ..FurParams::default()
            };
            let s = generate_strands(&p, seed).expect("valid");
            let t = bake_shells(&p, &s).expect("bake");
            proptest::prop_assert_eq!(t.layers.len(), shells as usize);
            for (i, layer) in t.layers.iter().enumerate() {
                let w = super::super::image::unorm8(gaussian_layer_weight(
                    layer_mid_height(i as u32, shells),
                    sigma,
                ));
                proptest::prop_assert_eq!(layer.colour.texels.len(), (res * res) as usize);
                for (c, tan) in layer.colour.texels.iter().zip(&layer.tangent.texels) {
                    proptest::prop_assert!(c[3] <= w);
                    proptest::prop_assert_eq!(c[3], tan[3]);
                }
            }
        }
    }

    #[test]
    fn empty_and_invalid() {
        let p = small();
        let t = bake_shells(&p, &[]).expect("bake");
        assert_eq!(t.max_height, p.max_height);
        assert!(
            t.layers
                .iter()
                .all(|l| l.colour.texels.iter().all(|c| c[3] == 0))
        );
        let bad = FurParams {
            number_of_shells: 0,
            ..p
        };
        assert!(matches!(
            bake_shells(&bad, &[]),
            Err(FurError::InvalidParameter {
                name: "number_of_shells",
                ..
            })
        ));
        // A strand with NaN does not panic and covers nothing.
        let mut s = vertical(0.5, 0.5, 1.0, 0.02);
        s.control[2].x = f32::NAN;
        let t = bake_shells(&small(), &[s]).expect("bake");
        assert_eq!(t.layers.len(), 6);
    }
}
