//! Fin texture baking (thesis 3.1.2.2): a side view of taller strands planted in a narrow strip.
//!
//! The strip is `x ∈ [0, 1)` (periodic, along the silhouette edge) by `y ∈ [0, fin_width)`
//! (depth). The view is an orthographic projection onto the `(x, z)` plane looking along `+y`
//! (the viewer at `y = −∞`); the visible surface of each cone wins by depth, ties going to the
//! later strand. Fin tangents use the frame `x` = texture `u` (along the edge), `y` = depth (into
//! the fin, away from the viewer), `z` = up (texture `v`, away from the surface).

use glam::{Vec2, Vec3};

use super::bake::{cones_of, gaussian_layer_weight};
use super::cone::{ConeSegment, FacetTable, GridMap, raster_capsule};
use super::image::{Rgba8Image, Sample, SampleGrid, downsample};
use super::params::{FurError, FurParams};
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
