//! Rasterizer throughput: 30 full-screen alpha-blended layers at 1366×768 (the thesis's
//! resolution and shell count) with a trivial fragment closure, on 1 and 2 threads; and the fur
//! stage's texture pair on 8 lanes (a 128×128 colour and tangent map at level of detail 1.5,
//! trilinear), read from the maps' bytes and from the interleaved pair (`PairedTexels`).

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use glam::Vec4;
use pelage::raster::texture::{PairedTexels, TrilinearPair};
use pelage::raster::{
    BlendMode, ClipVertex, CullMode, DepthCompare, DrawState, Frame, Framebuffer, Sampler, Texture,
};
use pelage::simd::{Kernel, SimdLevel, dispatch};

const WIDTH: u32 = 1366;
const HEIGHT: u32 = 768;
const LAYERS: usize = 30;

fn blended_layers(framebuffer: &mut Framebuffer) {
    let quad = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
    let state = DrawState {
        depth_compare: DepthCompare::LessEqual,
        depth_write: false,
        blend: BlendMode::Alpha,
        cull: CullMode::None,
    };
    let mut frame = Frame::new(framebuffer);
    for layer in 0..LAYERS {
        let colour = Vec4::new(layer as f32 / LAYERS as f32, 0.5, 0.25, 0.3);
        let vertices = quad.map(|(x, y)| (Vec4::new(x, y, 0.5, 1.0), colour));
        frame
            .draw(
                &vertices,
                &[[0, 1, 2], [0, 2, 3]],
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
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("raster");
    group.sample_size(10);
    group.throughput(Throughput::Elements(
        (WIDTH * HEIGHT) as u64 * LAYERS as u64,
    ));
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        let mut fb = Framebuffer::new(WIDTH, HEIGHT, 64, Vec4::ZERO).expect("framebuffer");
        group.bench_with_input(
            BenchmarkId::new("blended_layers_30", threads),
            &threads,
            |b, _| b.iter(|| pool.install(|| blended_layers(&mut fb))),
        );
    }
    group.finish();
}

/// A 128×128 texture of hashed bytes (`seed` varies it).
fn hashed_texture(seed: u32) -> Texture {
    let texels = (0..128 * 128u32)
        .map(|i| {
            let h = (i ^ seed).wrapping_mul(0x9e37_79b9);
            h.to_le_bytes()
        })
        .collect();
    Texture::from_rgba8(128, 128, texels).expect("texture")
}

fn texture_pair(c: &mut Criterion) {
    const POINTS: usize = 4096;
    let (colour, tangent) = (hashed_texture(1), hashed_texture(2));
    let interleaved = PairedTexels::new(&colour, &tangent).expect("same shape");
    let sampler = Sampler::default();
    let bytes = sampler
        .trilinear_pair(&colour, &tangent, 1.5)
        .expect("same shape");
    let pair = bytes.with_converted(&interleaved);
    // Points spread over several repeats, as a tile's fragments are.
    let mut state = 0x2545_f491u32;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 17;
        state ^= state << 5;
        state as f32 / u32::MAX as f32 * 3.0
    };
    let points: Vec<([f32; 8], [f32; 8])> = (0..POINTS / 8)
        .map(|_| {
            (
                std::array::from_fn(|_| next()),
                std::array::from_fn(|_| next()),
            )
        })
        .collect();
    let frac = [0.5f32; 8];
    let mut group = c.benchmark_group("texture_pair");
    group.throughput(Throughput::Elements(POINTS as u64));
    // At the level the renderer runs (the AVX2 or AVX-512 copy where the CPU has it; 8 lanes,
    // so not the 16-lane batch's AVX-512 pair path).
    let level = SimdLevel::active();
    for (name, reads) in [("bytes", bytes), ("interleaved", pair)] {
        group.bench_function(BenchmarkId::new(format!("lanes_8_{level}"), name), |b| {
            b.iter(|| {
                let run = PairReads {
                    reads: &reads,
                    points: &points,
                    frac: &frac,
                };
                std::hint::black_box(dispatch(level, run))
            })
        });
    }
    group.finish();
}

/// The 8-lane samples of `points`, compiled once per SIMD level as the renderer's hot path is.
struct PairReads<'r, 'a> {
    reads: &'r TrilinearPair<'a>,
    points: &'r [([f32; 8], [f32; 8])],
    frac: &'r [f32; 8],
}

impl Kernel for PairReads<'_, '_> {
    type Output = f32;

    #[inline(always)]
    fn run<const BATCH: usize>(self) -> f32 {
        let mut sum = 0.0f32;
        for (u, v) in self.points {
            let channels = self
                .reads
                .sample_lanes(u, v, self.frac, SimdLevel::active());
            sum += channels[3][0] + channels[7][7];
        }
        sum
    }
}

criterion_group!(benches, bench, texture_pair);
criterion_main!(benches);
