//! Rasterizer throughput: 30 full-screen alpha-blended layers at 1366×768 (the thesis's
//! resolution and shell count) with a trivial fragment closure, on 1 and 2 threads.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use glam::Vec4;
use pelage::raster::{
    BlendMode, ClipVertex, CullMode, DepthCompare, DrawState, Frame, Framebuffer,
};

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

criterion_group!(benches, bench);
criterion_main!(benches);
