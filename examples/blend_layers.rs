//! Profiling aid: 30 full-screen alpha-blended layers (the `raster` benchmark's workload) at a
//! size given on the command line, on one thread. `valgrind --tool=callgrind` on it counts
//! instructions repeatably, whatever else the machine is doing.

use glam::Vec4;
use pelage::raster::{
    BlendMode, ClipVertex, CullMode, DepthCompare, DrawState, Frame, Framebuffer,
};

fn main() {
    let mut args = std::env::args()
        .skip(1)
        .map(|a| a.parse::<u32>().unwrap_or(0));
    let width = args.next().filter(|&w| w > 0).unwrap_or(1366);
    let height = args.next().filter(|&h| h > 0).unwrap_or(768);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("pool");
    let mut fb = match Framebuffer::new(width, height, 64, Vec4::ZERO) {
        Ok(fb) => fb,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    };
    let state = DrawState {
        depth_compare: DepthCompare::LessEqual,
        depth_write: false,
        blend: BlendMode::Alpha,
        cull: CullMode::None,
    };
    let start = std::time::Instant::now();
    pool.install(|| {
        let mut frame = Frame::new(&mut fb);
        for layer in 0..30 {
            let colour = Vec4::new(layer as f32 / 30.0, 0.5, 0.25, 0.3);
            let quad = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
                .map(|(x, y)| (Vec4::new(x, y, 0.5, 1.0), colour));
            frame
                .draw(
                    &quad,
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
    });
    let seconds = start.elapsed().as_secs_f64();
    let fragments = f64::from(width) * f64::from(height) * 30.0;
    println!(
        "{:.1} M fragments/s ({seconds:.3} s)",
        fragments / seconds / 1e6
    );
}
