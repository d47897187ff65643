//! The rasterizer end to end: determinism across threads and tiles, clipping, perspective-
//! correct interpolation, depth, blending and texture level of detail.

use glam::{Mat4, Vec2, Vec3, Vec4};
use pelage::camera::{look_at, perspective};
use pelage::raster::{
    AddressMode, BlendMode, ClipVertex, CullMode, DepthCompare, DrawState, Filter, Fragment, Frame,
    Framebuffer, PixelSlot, Quad, QuadShader, QuadSlots, Sampler, Texture,
};

const BLENDED: DrawState = DrawState {
    depth_compare: DepthCompare::LessEqual,
    depth_write: false,
    blend: BlendMode::Alpha,
    cull: CullMode::None,
};

/// A small deterministic generator for test geometry.
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 40) as f32) / (1u64 << 24) as f32
    }
}

fn checker_texture(size: u32, check: u32) -> Texture {
    let texels = (0..size * size)
        .map(|i| {
            let (x, y) = (i % size / check, i / size / check);
            if (x + y).is_multiple_of(2) {
                [255, 255, 255, 255]
            } else {
                [0, 0, 0, 255]
            }
        })
        .collect();
    Texture::from_rgba8(size, size, texels).expect("texture")
}

/// The busy frame's fragment stage: the vertex colour modulated by a trilinear checker read.
fn busy_colour(texture: &Texture, f: &Fragment<'_, (Vec4, Vec2)>) -> Option<Vec4> {
    let (c, uv) = *f.varyings();
    let (dx, dy) = f.derivatives(|v| v.1);
    let t = Sampler::default().sample(texture, uv, dx, dy);
    Some(Vec4::new(c.x * t.x, c.y, c.z * (1.0 - t.y), c.w))
}

/// A quad shader that holds every lane it shades until the rasterizer asks for them
/// ([`QuadShader::finish`]), in reverse order: whatever it is handed meanwhile, the
/// rasterizer must keep each pixel's blend order.
struct Hoarder<'t>(&'t Texture);

impl QuadShader<(Vec4, Vec2)> for Hoarder<'_> {
    type Deferred<const BATCH: usize> = Vec<(PixelSlot, Vec4)>;

    fn shade_quad<const BATCH: usize>(
        &self,
        held: &mut Self::Deferred<BATCH>,
        quad: &Quad<'_, (Vec4, Vec2)>,
        mut slots: QuadSlots,
        _: impl FnMut(PixelSlot, Vec4),
    ) {
        for lane in 0..4 {
            if let Some(slot) = slots.take(lane)
                && let Some(colour) = busy_colour(self.0, &quad.fragment(lane))
            {
                held.push((slot, colour));
            }
        }
    }

    fn finish<const BATCH: usize>(
        &self,
        held: &mut Self::Deferred<BATCH>,
        mut write: impl FnMut(PixelSlot, Vec4),
    ) {
        while let Some((slot, colour)) = held.pop() {
            write(slot, colour);
        }
    }
}

/// 10,000 overlapping, alpha-blended, textured triangles with perspective and near-plane
/// crossings, submitted as `draws` consecutive draws, shaded by a per-fragment closure or by
/// [`Hoarder`].
fn busy_frame_with(
    width: u32,
    height: u32,
    tile: u32,
    draws: usize,
    state: DrawState,
    hoard: bool,
) -> Vec<u8> {
    let mut rng = Lcg(42);
    let mut vertices = Vec::new();
    let mut centre = Vec2::ZERO;
    for i in 0..30_000 {
        // Triangles about a tenth of the screen across, scattered and overlapping; some reach
        // behind the near plane.
        if i % 3 == 0 {
            centre = Vec2::new(rng.next() * 2.4 - 1.2, rng.next() * 2.4 - 1.2);
        }
        let xy = centre + Vec2::new(rng.next() - 0.5, rng.next() - 0.5) * 0.3;
        let p = Vec4::new(xy.x, xy.y, rng.next() * 1.3 - 0.15, 0.5 + rng.next());
        let colour = Vec4::new(rng.next(), rng.next(), rng.next(), 0.15 + 0.6 * rng.next());
        let uv = Vec2::new(rng.next() * 4.0, rng.next() * 4.0);
        vertices.push((Vec4::new(p.x * p.w, p.y * p.w, p.z * p.w, p.w), colour, uv));
    }
    let triangles: Vec<[u32; 3]> = (0..10_000u32)
        .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
        .collect();
    let texture = checker_texture(32, 4);
    let mut fb = Framebuffer::new(width, height, tile, Vec4::new(0.1, 0.1, 0.1, 1.0)).expect("fb");
    let mut frame = Frame::new(&mut fb);
    let vertex = |&(p, c, uv): &(Vec4, Vec4, Vec2)| ClipVertex {
        position: p,
        varyings: (c, uv),
    };
    for part in triangles.chunks(triangles.len().div_ceil(draws)) {
        if hoard {
            frame.draw_quads(&vertices, part, state, vertex, Hoarder(&texture))
        } else {
            frame.draw(&vertices, part, state, vertex, |f| busy_colour(&texture, f))
        }
        .expect("draw");
    }
    let stats = frame.finish();
    assert!(stats.fragments_written > 50_000, "{stats:?}");
    fb.to_rgba8()
}

fn busy_frame(width: u32, height: u32, tile: u32, draws: usize) -> Vec<u8> {
    busy_frame_with(width, height, tile, draws, BLENDED, false)
}

/// A shader may hold lanes across triangles: the rasterizer asks for them before a pixel is
/// handed over again, after each triangle that writes depth and at the end of each tile's
/// draw, so the pixels are those of shading each lane at once, with or without depth writes.
#[test]
fn lanes_held_across_triangles_keep_every_pixels_blend_order() {
    let (w, h) = (203, 151);
    let depth_writing = DrawState {
        depth_write: true,
        ..BLENDED
    };
    for state in [BLENDED, depth_writing] {
        for tile in [16, 64] {
            let at_once = busy_frame_with(w, h, tile, 1, state, false);
            let held = busy_frame_with(w, h, tile, 1, state, true);
            assert!(
                held == at_once,
                "{state:?}, tile {tile}: held lanes changed pixels"
            );
        }
    }
}

#[test]
fn output_is_identical_for_every_thread_count_and_tile_size() {
    let (w, h) = (203, 151);
    let reference = busy_frame(w, h, 64, 1);
    for threads in [1, 2, 3, 8] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        for tile in [8, 16, 32, 64] {
            let image = pool.install(|| busy_frame(w, h, tile, 1));
            assert!(image == reference, "threads {threads}, tile {tile} differ");
        }
    }
}

/// A large draw is set up and binned in several parallel chunks; many small draws (one chunk
/// each) of the same triangles give the same bytes, so the chunks replay in triangle order.
#[test]
fn output_is_identical_however_triangles_are_split_into_draws_and_chunks() {
    let (w, h) = (203, 151);
    let one_draw = busy_frame(w, h, 16, 1);
    for draws in [3, 40] {
        assert!(
            busy_frame(w, h, 16, draws) == one_draw,
            "{draws} draws differ from one"
        );
    }
}

fn full_screen_quad(z: f32, colour: Vec4) -> (Vec<(Vec4, Vec4)>, Vec<[u32; 3]>) {
    let v = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
        .map(|(x, y)| (Vec4::new(x, y, z, 1.0), colour))
        .to_vec();
    (v, vec![[0, 1, 2], [0, 2, 3]])
}

fn draw_layers(layers: &[(f32, Vec4)], state: DrawState) -> Framebuffer {
    let mut fb = Framebuffer::new(16, 16, 8, Vec4::new(0.0, 0.0, 0.0, 1.0)).expect("fb");
    let mut frame = Frame::new(&mut fb);
    for &(z, colour) in layers {
        let (v, t) = full_screen_quad(z, colour);
        frame
            .draw(
                &v,
                &t,
                state,
                |&(p, c): &(Vec4, Vec4)| ClipVertex {
                    position: p,
                    varyings: c,
                },
                |f| Some(*f.varyings()),
            )
            .expect("draw");
    }
    frame.finish();
    fb
}

/// A quad shader that tries to break its contract: it asks for every lane's slot, covered or
/// not, twice, and writes what it gets.
struct Greedy;

impl QuadShader<Vec4> for Greedy {
    type Deferred<const BATCH: usize> = ();

    fn shade_quad<const BATCH: usize>(
        &self,
        _: &mut (),
        quad: &Quad<'_, Vec4>,
        mut slots: QuadSlots,
        mut write: impl FnMut(PixelSlot, Vec4),
    ) {
        for _ in 0..2 {
            for (lane, colour) in quad.varyings().iter().enumerate() {
                if let Some(slot) = slots.take(lane) {
                    write(slot, *colour);
                }
            }
        }
    }
}

/// The rasterizer keeps each covered lane's first write and ignores the rest, so a faulty quad
/// shader blends nothing twice and reaches no pixel outside the triangle or behind the depth.
#[test]
fn quad_shader_writes_are_limited_to_covered_lanes_once() {
    let draw = |greedy: bool| {
        let mut fb = Framebuffer::new(21, 17, 8, Vec4::new(0.0, 0.0, 0.0, 1.0)).expect("fb");
        let mut frame = Frame::new(&mut fb);
        let (v, t) = full_screen_quad(0.2, Vec4::new(0.0, 0.0, 1.0, 1.0));
        // An opaque occluder over the left part, then a blended sliver that crosses it.
        let occluder: Vec<(Vec4, Vec4)> = v
            .iter()
            .map(|&(p, c)| (Vec4::new(p.x.min(-0.3), p.y, p.z, p.w), c))
            .collect();
        frame
            .draw(
                &occluder,
                &t,
                DrawState::default(),
                |&(p, c): &(Vec4, Vec4)| ClipVertex {
                    position: p,
                    varyings: c,
                },
                |f| Some(*f.varyings()),
            )
            .expect("occluder");
        let sliver = [
            (
                Vec4::new(-0.9, -0.8, 0.5, 1.0),
                Vec4::new(1.0, 0.0, 0.0, 0.5),
            ),
            (
                Vec4::new(0.9, -0.6, 0.5, 1.0),
                Vec4::new(0.0, 1.0, 0.0, 0.5),
            ),
            (Vec4::new(0.1, 0.7, 0.5, 1.0), Vec4::new(1.0, 1.0, 0.0, 0.5)),
        ];
        let vertex = |&(p, c): &(Vec4, Vec4)| ClipVertex {
            position: p,
            varyings: c,
        };
        if greedy {
            frame.draw_quads(&sliver, &[[0, 1, 2]], BLENDED, vertex, Greedy)
        } else {
            frame.draw(&sliver, &[[0, 1, 2]], BLENDED, vertex, |f| {
                Some(*f.varyings())
            })
        }
        .expect("sliver");
        let stats = frame.finish();
        (fb.to_rgba8(), stats)
    };
    let (greedy, greedy_stats) = draw(true);
    let (per_fragment, stats) = draw(false);
    assert!(stats.fragments_written > 20, "{stats:?}");
    assert_eq!(greedy_stats, stats);
    assert!(
        greedy == per_fragment,
        "a greedy quad shader changed pixels"
    );
}

#[test]
fn depth_test_keeps_the_nearest_whatever_the_order() {
    let near = (0.3, Vec4::new(1.0, 0.0, 0.0, 1.0));
    let far = (0.6, Vec4::new(0.0, 1.0, 0.0, 1.0));
    let opaque = DrawState::default();
    for order in [[near, far], [far, near]] {
        let fb = draw_layers(&order, opaque);
        assert_eq!(fb.colour(5, 9), Some(near.1));
        assert_eq!(fb.depth(5, 9), Some(0.3));
    }
    // Equal depth: LESS keeps the first, LEQUAL lets the later one through.
    let a = (0.5, Vec4::new(1.0, 0.0, 0.0, 1.0));
    let b = (0.5, Vec4::new(0.0, 0.0, 1.0, 1.0));
    assert_eq!(draw_layers(&[a, b], opaque).colour(3, 3), Some(a.1));
    let lequal = DrawState {
        depth_compare: DepthCompare::LessEqual,
        ..opaque
    };
    assert_eq!(draw_layers(&[a, b], lequal).colour(3, 3), Some(b.1));
}

#[test]
fn blending_follows_submission_order() {
    let red = (0.5, Vec4::new(1.0, 0.0, 0.0, 0.5));
    let green = (0.5, Vec4::new(0.0, 1.0, 0.0, 0.5));
    let rg = draw_layers(&[red, green], BLENDED)
        .colour(7, 7)
        .expect("pixel");
    let gr = draw_layers(&[green, red], BLENDED)
        .colour(7, 7)
        .expect("pixel");
    // rgb = src·a + dst·(1 − a), applied red then green over opaque black; alpha accumulates
    // as a + dst·(1 − a), so it stays 1 over an opaque background.
    assert_eq!(rg, Vec4::new(0.25, 0.5, 0.0, 1.0));
    assert_eq!(gr, Vec4::new(0.5, 0.25, 0.0, 1.0));
    // Over a transparent background, coverage adds up: 0 → 0.5 → 0.75.
    let mut fb = Framebuffer::new(4, 4, 2, Vec4::ZERO).expect("fb");
    let mut frame = Frame::new(&mut fb);
    for (z, colour) in [red, green] {
        let (v, t) = full_screen_quad(z, colour);
        frame
            .draw(
                &v,
                &t,
                BLENDED,
                |&(p, c): &(Vec4, Vec4)| ClipVertex {
                    position: p,
                    varyings: c,
                },
                |f| Some(*f.varyings()),
            )
            .expect("draw");
    }
    frame.finish();
    assert_eq!(fb.colour(1, 1), Some(Vec4::new(0.25, 0.5, 0.0, 0.75)));
}

/// A ground plane y = 0 seen by a camera at height 1, extending behind the camera (so it
/// crosses the near plane) and to the horizon. Each vertex carries its world x and z.
fn ground_plane() -> (Mat4, Vec<(Vec3, Vec2)>, Vec<[u32; 3]>) {
    let eye = Vec3::new(0.0, 1.0, 0.0);
    let view = look_at(eye, Vec3::new(0.0, 0.6, -3.0), Vec3::Y);
    let proj = perspective(60f32.to_radians(), 1.0, 0.1, 200.0);
    let corners = [(-40.0, 5.0), (40.0, 5.0), (40.0, -150.0), (-40.0, -150.0)];
    let v = corners
        .iter()
        .map(|&(x, z)| (Vec3::new(x, 0.0, z), Vec2::new(x, z)))
        .collect();
    (proj * view, v, vec![[0, 1, 2], [0, 2, 3]])
}

#[test]
fn interpolation_is_perspective_correct_and_near_clipping_is_exact() {
    let (view_proj, vertices, triangles) = ground_plane();
    let (w, h) = (64u32, 64u32);
    let mut fb = Framebuffer::new(w, h, 16, Vec4::ZERO).expect("fb");
    let mut frame = Frame::new(&mut fb);
    frame
        .draw(
            &vertices,
            &triangles,
            DrawState::default(),
            |&(p, xz): &(Vec3, Vec2)| ClipVertex {
                position: view_proj * p.extend(1.0),
                varyings: xz,
            },
            |f| Some(Vec4::new(f.varyings().x, f.varyings().y, 0.0, 1.0)),
        )
        .expect("draw");
    frame.finish();
    let inverse = view_proj.inverse().as_dmat4();
    let mut checked = 0;
    for y in 0..h {
        for x in 0..w {
            let c = fb.colour(x, y).expect("pixel");
            assert!(c.is_finite(), "NaN at ({x},{y})");
            if c.w == 0.0 {
                continue;
            }
            // Independent f64 ray through the pixel centre, intersected with y = 0.
            let ndc = glam::DVec2::new(
                (x as f64 + 0.5) / w as f64 * 2.0 - 1.0,
                1.0 - (y as f64 + 0.5) / h as f64 * 2.0,
            );
            let hit_at = |ndc: glam::DVec2| {
                let a = inverse.project_point3(ndc.extend(0.0));
                let b = inverse.project_point3(ndc.extend(1.0));
                a + (b - a) * (a.y / (a.y - b.y))
            };
            let hit = hit_at(ndc);
            // Vertices snap to 1/256 pixel, so allow what a shift of 1/128 pixel changes.
            let one_row_up = hit_at(ndc + glam::DVec2::new(0.0, 2.0 / h as f64));
            let tolerance = 1e-4 * (1.0 + hit.z.abs()) + (one_row_up - hit).length() / 128.0;
            assert!(
                (f64::from(c.x) - hit.x).abs() < tolerance,
                "x at ({x},{y}): {} vs {}",
                c.x,
                hit.x
            );
            assert!(
                (f64::from(c.y) - hit.z).abs() < tolerance,
                "z at ({x},{y}): {} vs {}",
                c.y,
                hit.z
            );
            checked += 1;
        }
    }
    // The plane covers the lower part of the screen, up to the horizon.
    assert!(checked > (w * h / 3) as usize, "{checked}");
    assert_eq!(fb.colour(32, 0).map(|c| c.w), Some(0.0), "sky stays clear");
    assert_eq!(
        fb.colour(32, 63).map(|c| c.w),
        Some(1.0),
        "the plane reaches the bottom edge"
    );
}

#[test]
fn triangles_behind_the_camera_or_with_nan_draw_nothing() {
    let mut fb = Framebuffer::new(32, 32, 8, Vec4::ZERO).expect("fb");
    let mut frame = Frame::new(&mut fb);
    let behind = [
        Vec4::new(-1.0, -1.0, -0.5, -1.0),
        Vec4::new(1.0, -1.0, -0.5, -1.0),
        Vec4::new(0.0, 1.0, -0.5, -1.0),
    ];
    let nan = [
        Vec4::new(f32::NAN, 0.0, 0.5, 1.0),
        Vec4::new(1.0, -1.0, 0.5, 1.0),
        Vec4::new(0.0, 1.0, 0.5, 1.0),
    ];
    let zero_w = [
        Vec4::ZERO,
        Vec4::new(1.0, -1.0, 0.5, 0.0),
        Vec4::new(0.0, 1.0, 0.5, 0.0),
    ];
    for tri in [behind, nan, zero_w] {
        frame
            .draw(
                &tri,
                &[[0, 1, 2]],
                DrawState::default(),
                |&p: &Vec4| ClipVertex {
                    position: p,
                    varyings: (),
                },
                |_| Some(Vec4::ONE),
            )
            .expect("draw");
    }
    let stats = frame.finish();
    assert_eq!(stats.fragments_written, 0);
    assert!(fb.to_rgba8().iter().all(|&b| b == 0));
}

#[test]
fn out_of_range_indices_are_an_error_not_a_panic() {
    let mut fb = Framebuffer::new(8, 8, 8, Vec4::ZERO).expect("fb");
    let mut frame = Frame::new(&mut fb);
    let err = frame
        .draw(
            &[Vec4::ZERO; 3],
            &[[0, 1, 7]],
            DrawState::default(),
            |&p: &Vec4| ClipVertex {
                position: p,
                varyings: (),
            },
            |_| None,
        )
        .unwrap_err();
    assert!(err.to_string().contains("vertex index 7"), "{err}");
}

#[test]
fn level_of_detail_rises_towards_the_horizon_on_a_tilted_checkerboard() {
    let (view_proj, vertices, triangles) = ground_plane();
    let texture = checker_texture(64, 8);
    let sampler = Sampler {
        address_u: AddressMode::Wrap,
        address_v: AddressMode::Wrap,
        filter: Filter::Trilinear,
    };
    let (w, h) = (96u32, 96u32);
    let mut fb = Framebuffer::new(w, h, 32, Vec4::ZERO).expect("fb");
    let mut frame = Frame::new(&mut fb);
    frame
        .draw(
            &vertices,
            &triangles,
            DrawState::default(),
            |&(p, xz): &(Vec3, Vec2)| ClipVertex {
                position: view_proj * p.extend(1.0),
                varyings: xz * 0.5,
            },
            |f| {
                let uv = *f.varyings();
                let (dx, dy) = f.derivatives(|v| *v);
                let lod = pelage::raster::texture::level_of_detail(dx, dy, 64, 64);
                Some(Vec4::new(
                    sampler.sample(&texture, uv, dx, dy).x,
                    lod,
                    0.0,
                    1.0,
                ))
            },
        )
        .expect("draw");
    frame.finish();
    let column: Vec<Vec4> = (0..h)
        .filter_map(|y| fb.colour(w / 2, y))
        .filter(|c| c.w == 1.0)
        .collect();
    let lods: Vec<f32> = column.iter().map(|c| c.y).collect();
    // Rows run from the horizon (top) to the camera (bottom): detail falls monotonically.
    for pair in lods.windows(2) {
        assert!(pair[0] >= pair[1] - 1e-4, "{lods:?}");
    }
    assert!(lods[lods.len() - 1] < 1.0 && lods[0] > 4.0, "{lods:?}");
    // Near the camera the checks are crisp, far away they average to grey.
    let near: Vec<f32> = (h - 12..h)
        .map(|y| fb.colour(w / 2 - 20, y).expect("pixel").x)
        .collect();
    assert!(
        near.iter().any(|&v| v > 0.9) && near.iter().any(|&v| v < 0.1),
        "{near:?}"
    );
    let far = column.iter().take(3).map(|c| c.x).collect::<Vec<_>>();
    assert!(far.iter().all(|&v| (v - 0.5).abs() < 0.1), "{far:?}");
}
