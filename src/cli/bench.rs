//! `pelage bench`: bake time and frame times of a scene.

use super::{
    CommonArgs, Failure, check_limits, load_scene, progress, render_failure, scene_name,
    with_threads,
};
use clap::Args;
use pelage::render::PreparedScene;
use std::time::Instant;

#[derive(Args)]
pub struct BenchArgs {
    #[command(flatten)]
    pub common: CommonArgs,
    /// Frames to time.
    #[arg(long, default_value_t = 10, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    pub frames: u32,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: BenchArgs) -> Result<(), Failure> {
    let scene = load_scene(&args.common)?;
    let tile = args.common.tile;
    let threads = args.common.threads;
    let report = with_threads(threads, || -> Result<String, Failure> {
        check_limits(&scene, &args.common, 1, false)?;
        let name = scene_name(&args.common);
        let start = Instant::now();
        let prepared = PreparedScene::new(&scene).map_err(|e| render_failure(e, &scene, &name))?;
        let bake_ms = start.elapsed().as_secs_f64() * 1e3;
        let bar = progress(u64::from(args.frames));
        let mut times = Vec::with_capacity(args.frames as usize);
        let mut fragments = 0;
        for _ in 0..args.frames {
            let t = Instant::now();
            let image = prepared
                .render(tile)
                .map_err(|e| render_failure(e, &scene, &name))?;
            times.push(t.elapsed().as_secs_f64() * 1e3);
            fragments = image.stats.fragments_shaded;
            bar.inc(1);
        }
        bar.finish_and_clear();
        times.sort_by(f64::total_cmp);
        let median = times[times.len() / 2];
        let (min, max) = (times[0], times[times.len() - 1]);
        let mut deviations: Vec<f64> = times.iter().map(|t| (t - median).abs()).collect();
        deviations.sort_by(f64::total_cmp);
        let mad = deviations[deviations.len() / 2];
        let fps = 1e3 / median;
        let peak = peak_memory_bytes();
        let peak_mib = peak.map(|b| b as f64 / (1024.0 * 1024.0));
        let fragments_per_s = fragments as f64 / (median / 1e3);
        let threads = rayon::current_num_threads();
        Ok(if args.json {
            format!(
                "{{\"bake_ms\":{bake_ms:.3},\"frames\":{},\"median_frame_ms\":{median:.3},\"min_frame_ms\":{min:.3},\"max_frame_ms\":{max:.3},\"mad_frame_ms\":{mad:.3},\"fps\":{fps:.3},\"peak_memory_mib\":{},\"fragments_per_frame\":{fragments},\"fragments_per_s\":{fragments_per_s:.0},\"threads\":{threads},\"tile\":{tile},\"width\":{},\"height\":{}}}",
                args.frames,
                peak_mib.map_or("null".to_string(), |m| format!("{m:.1}")),
                scene.image.width,
                scene.image.height
            )
        } else {
            format!(
                "bake {bake_ms:.1} ms\nframes {} at {}×{}, {threads} threads, tile {tile}\nmedian frame {median:.2} ms (min {min:.2}, max {max:.2}, median absolute deviation {mad:.2})\nfps {fps:.2}\nfragments shaded per frame {fragments}, {:.1} M/s\npeak memory {}",
                args.frames,
                scene.image.width,
                scene.image.height,
                fragments_per_s / 1e6,
                peak_mib.map_or("unknown on this system".to_string(), |m| format!(
                    "{m:.1} MiB"
                ))
            )
        })
    })??;
    println!("{report}");
    Ok(())
}

/// The process's peak resident memory (Linux `VmHWM`), or `None` where it cannot be read.
fn peak_memory_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}
