//! The fill rule, end to end: meshes that share edges cover every pixel exactly once.
//!
//! Each generated mesh covers a region larger than the viewport (its outer vertices lie outside
//! it), so every pixel of the image is inside the union; with additive blending of 1 per
//! fragment, every pixel must read exactly 1.

use glam::{Vec2, Vec4};
use pelage::raster::{
    BlendMode, ClipVertex, CullMode, DepthCompare, DrawState, Frame, Framebuffer,
};
use proptest::prelude::*;

const W: u32 = 48;
const H: u32 = 40;

/// Draws triangles given in pixel coordinates (with a per-vertex w to exercise the divide) and
/// returns the coverage count of every pixel.
fn coverage(points: &[(Vec2, f32)], triangles: &[[u32; 3]], tile: u32) -> Vec<f32> {
    let mut fb = Framebuffer::new(W, H, tile, Vec4::ZERO).expect("framebuffer");
    let mut frame = Frame::new(&mut fb);
    let state = DrawState {
        depth_compare: DepthCompare::Always,
        depth_write: false,
        blend: BlendMode::Add,
        cull: CullMode::None,
    };
    frame
        .draw(
            points,
            triangles,
            state,
            |&(p, w): &(Vec2, f32)| {
                let ndc = Vec2::new(p.x / W as f32 * 2.0 - 1.0, 1.0 - p.y / H as f32 * 2.0);
                ClipVertex {
                    position: Vec4::new(ndc.x * w, ndc.y * w, 0.5 * w, w),
                    varyings: (),
                }
            },
            |_| Some(Vec4::new(1.0, 0.0, 0.0, 0.0)),
        )
        .expect("draw");
    frame.finish();
    fb.to_rgba_f32().iter().map(|c| c.x).collect()
}

fn assert_exactly_once(counts: &[f32]) -> Result<(), TestCaseError> {
    for (i, &c) in counts.iter().enumerate() {
        prop_assert_eq!(
            c,
            1.0,
            "pixel ({}, {}) covered {} times",
            i as u32 % W,
            i as u32 / W,
            c
        );
    }
    Ok(())
}

/// Rounds to the nearest multiple of half a pixel, so that edges run through pixel centres
/// often and the fill rule is exercised, not just the interiors.
fn on_half_pixels(p: Vec2) -> Vec2 {
    (p * 2.0).round() * 0.5
}

/// Powers of two keep `x·w / w` exact, so snapping sees the intended coordinates.
fn power_of_two_w() -> impl Strategy<Value = f32> {
    prop::sample::select(vec![0.25f32, 0.5, 1.0, 2.0, 4.0])
}

/// A jittered grid of `nx`×`ny` cells spanning [-margin, W+margin]×[-margin, H+margin]. Inner
/// vertices move by up to a quarter cell, which can make slivers but never folds the mesh.
fn grid(
    nx: u32,
    ny: u32,
    margin: f32,
    jitter: &[(f32, f32)],
    ws: &[f32],
    flip: &[bool],
) -> (Vec<(Vec2, f32)>, Vec<[u32; 3]>) {
    let (x0, y0) = (-margin, -margin);
    let (cw, ch) = (
        (W as f32 + 2.0 * margin) / nx as f32,
        (H as f32 + 2.0 * margin) / ny as f32,
    );
    let mut points = Vec::new();
    for j in 0..=ny {
        for i in 0..=nx {
            let k = (j * (nx + 1) + i) as usize;
            let inner = i > 0 && j > 0 && i < nx && j < ny;
            let (jx, jy) = if inner {
                jitter[k % jitter.len()]
            } else {
                (0.0, 0.0)
            };
            let p = Vec2::new(
                x0 + (i as f32 + jx * 0.25) * cw,
                y0 + (j as f32 + jy * 0.25) * ch,
            );
            points.push((on_half_pixels(p), ws[k % ws.len()]));
        }
    }
    let mut tris = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            let a = j * (nx + 1) + i;
            let (b, c, d) = (a + 1, a + nx + 2, a + nx + 1);
            if flip[(a as usize) % flip.len()] {
                tris.push([a, b, c]);
                tris.push([a, c, d]);
            } else {
                tris.push([a, b, d]);
                tris.push([b, c, d]);
            }
        }
    }
    (points, tris)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, rng_seed: proptest::test_runner::RngSeed::Fixed(0x5e1a6e), failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn jittered_grids_cover_every_pixel_once(
        nx in 1u32..40, ny in 1u32..40,
        margin in 0.5f32..30.0,
        jitter in prop::collection::vec((-1.0f32..1.0, -1.0f32..1.0), 1..64),
        ws in prop::collection::vec(power_of_two_w(), 1..16),
        flip in prop::collection::vec(any::<bool>(), 1..16),
        tile in prop::sample::select(vec![2u32, 8, 16, 64]),
    ) {
        let (p, t) = grid(nx, ny, margin, &jitter, &ws, &flip);
        assert_exactly_once(&coverage(&p, &t, tile))?;
    }

    #[test]
    fn sub_pixel_grids_cover_every_pixel_once(
        jitter in prop::collection::vec((-1.0f32..1.0, -1.0f32..1.0), 1..64),
        flip in prop::collection::vec(any::<bool>(), 1..16),
    ) {
        // Cells of about a third of a pixel: most triangles cover no pixel centre at all.
        let (p, t) = grid(150, 130, 1.0, &jitter, &[1.0], &flip);
        assert_exactly_once(&coverage(&p, &t, 16))?;
    }

    #[test]
    fn fans_with_slivers_cover_every_pixel_once(
        centre in (0u32..W, 0u32..H),
        spokes in 3usize..400,
        phase in 0.0f32..1.0,
        radius in 60.0f32..5000.0,
        w in power_of_two_w(),
    ) {
        // The hub sits on a pixel centre, the rim on half pixels: many spokes pass through
        // sample points.
        let hub = Vec2::new(centre.0 as f32 + 0.5, centre.1 as f32 + 0.5);
        let mut points = vec![(hub, w)];
        for k in 0..spokes {
            let a = (k as f32 + phase) / spokes as f32 * std::f32::consts::TAU;
            points.push((on_half_pixels(hub + radius * Vec2::new(a.cos(), a.sin())), w));
        }
        let n = spokes as u32;
        // With few spokes the polygon may not contain the viewport; only count when it does.
        let min_apothem = radius * (std::f32::consts::PI / spokes as f32).cos();
        prop_assume!(min_apothem > 2.0 * (W + H) as f32);
        let tris: Vec<[u32; 3]> = (0..n).map(|k| [0, 1 + k, 1 + (k + 1) % n]).collect();
        assert_exactly_once(&coverage(&points, &tris, 8))?;
    }
}

#[test]
fn huge_triangles_far_outside_the_screen_cover_every_pixel_once() {
    // Vertices at ±1e6 pixels go through guard-band clipping; the shared diagonal still
    // covers each pixel once.
    let p = [
        (Vec2::new(-1.0e6, -1.0e6), 1.0),
        (Vec2::new(1.0e6, -1.0e6), 1.0),
        (Vec2::new(1.0e6, 1.0e6), 1.0),
        (Vec2::new(-1.0e6, 1.0e6), 1.0),
    ];
    for tris in [[[0, 1, 2], [0, 2, 3]], [[0, 1, 3], [1, 2, 3]]] {
        let c = coverage(&p, &tris, 16);
        assert!(
            c.iter().all(|&v| v == 1.0),
            "{:?}",
            c.iter().filter(|&&v| v != 1.0).count()
        );
    }
}

#[test]
fn pixels_outside_the_mesh_are_never_covered() {
    // A small square in the middle: inside 1, outside 0, the boundary follows the rule.
    let p = [
        (Vec2::new(10.0, 10.0), 1.0),
        (Vec2::new(20.0, 10.0), 1.0),
        (Vec2::new(20.0, 20.0), 1.0),
        (Vec2::new(10.0, 20.0), 1.0),
    ];
    let c = coverage(&p, &[[0, 1, 2], [0, 2, 3]], 8);
    for y in 0..H {
        for x in 0..W {
            let inside = (10..20).contains(&x) && (10..20).contains(&y);
            assert_eq!(c[(y * W + x) as usize], inside as u32 as f32, "({x},{y})");
        }
    }
}
