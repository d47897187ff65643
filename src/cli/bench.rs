//! `pelage bench`: bake time and frame times of a scene, on the oracle or (feature `gpu`) on
//! wgpu's Vulkan adapter, or both in one run, frame for frame in turn (`--race`), with the
//! ratio of their frame times.
//!
//! The same work on both sides: the fur is baked once by the oracle ([`PreparedScene::new`]);
//! the GPU gets that data uploaded once ([`pelage::gpu::GpuContext::prepare_frame`]) and then
//! only its render pass is submitted again and waited on per frame. The GPU's frame time
//! leaves out the readback, which is timed once and shown apart. Threads: `--threads N` sizes
//! the oracle's pool and lavapipe's (Mesa reads `LP_NUM_THREADS` when the Vulkan instance is
//! made, so pelage restarts itself with it set when it differs).
//!
//! Besides wall-clock time, each frame's CPU time is measured where the system says it (Linux:
//! the whole process's, every thread's, lavapipe's included): on a shared, noisy machine it is
//! the steadier figure.

use super::render::Backend;
use super::{CommonArgs, Failure, check_limits, load_scene, progress, render_failure, scene_name};
use clap::Args;
use pelage::render::PreparedScene;
use pelage::scene::Scene;
use serde::Serialize;
use std::time::Instant;

#[derive(Args)]
pub struct BenchArgs {
    #[command(flatten)]
    pub common: CommonArgs,
    /// Frames to time (with --race: frames of each backend).
    #[arg(long, default_value_t = 10, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    pub frames: u32,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
    /// Which renderer is timed: the CPU oracle, or wgpu on the Vulkan adapter (Mesa's
    /// lavapipe; built with `--features gpu`), after set-up: data uploaded once, the render
    /// pass submitted per frame, the readback timed apart.
    #[arg(long, value_enum, default_value_t = Backend::Cpu)]
    pub backend: Backend,
    /// Time the oracle and the GPU backend in one run, an oracle frame and a GPU frame in turn,
    /// and print how many times faster or slower the oracle is (feature `gpu`).
    #[arg(long, conflicts_with = "backend")]
    pub race: bool,
    /// With --backend gpu or --race: the adapter, by index or part of its name as `pelage
    /// gpu-info` lists them, `any` for wgpu's own choice (a hardware GPU where there is one);
    /// default the software one (lavapipe).
    #[arg(long, value_name = "NAME|INDEX")]
    pub adapter: Option<String>,
    /// Compare this build with another pelage binary: both run `bench` with these arguments,
    /// as child processes, round after round, and the other's CPU time a frame over this
    /// build's is printed per round, with its median and range, beside the CPU model.
    #[arg(long, value_name = "PELAGE", conflicts_with_all = ["race", "backend", "adapter"])]
    pub against: Option<std::path::PathBuf>,
    /// With --against: how many rounds (each times both builds once).
    #[arg(long, default_value_t = 6, requires = "against", value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub rounds: u32,
    /// With --against: both builds at the same time, each pinned to a core of its own (swapped
    /// every round), one thread each, instead of one after the other.
    #[arg(long, requires = "against")]
    pub together: bool,
}

/// The environment variable llvmpipe and lavapipe read for their rasterizer threads.
const LP_NUM_THREADS: &str = "LP_NUM_THREADS";

pub fn run(args: BenchArgs) -> Result<(), Failure> {
    if let Some(other) = &args.against {
        // What follows `bench` on the command line goes to both builds as it was typed.
        let raw: Vec<std::ffi::OsString> = std::env::args_os()
            .skip_while(|a| a != "bench")
            .skip(1)
            .collect();
        return super::say(super::against::run(&args, other, &raw)?);
    }
    let gpu = args.race || args.backend == Backend::Gpu;
    if args.adapter.is_some() && !gpu {
        return Err(Failure::bad_input(
            "--adapter chooses the GPU's device: add --backend gpu or --race",
        ));
    }
    if gpu {
        gpu_built(if args.race { "--race" } else { "--backend gpu" })?;
        lavapipe_threads(args.common.threads)?;
    }
    let scene = load_scene(&args.common)?;
    let name = scene_name(&args.common);
    let pool = thread_pool(args.common.threads)?;
    let (prepared, bake_ms) = pool.install(|| -> Result<(PreparedScene, f64), Failure> {
        check_limits(&scene, &args.common, 1, false)?;
        let start = Instant::now();
        let prepared = PreparedScene::new(&scene).map_err(|e| render_failure(e, &scene, &name))?;
        Ok((prepared, start.elapsed().as_secs_f64() * 1e3))
    })?;
    let bench = Bench {
        args: &args,
        scene: &scene,
        name: &name,
        pool: &pool,
        prepared: &prepared,
        bake_ms,
    };
    let text = if gpu {
        let (gpu, oracle) = bench.gpu()?;
        match oracle {
            Some(oracle) => race_text(&oracle, &gpu, args.json)?,
            None => gpu.text(args.json)?,
        }
    } else {
        bench.oracle()?.text(args.json)?
    };
    super::say(text)?;
    Ok(())
}

/// What every timing loop needs: the arguments, the scene, its baked fur, the oracle's pool.
struct Bench<'a> {
    args: &'a BenchArgs,
    scene: &'a Scene,
    name: &'a str,
    pool: &'a rayon::ThreadPool,
    prepared: &'a PreparedScene,
    bake_ms: f64,
}

impl Bench<'_> {
    /// One oracle frame, drawn on the pool; the fragments it shaded.
    fn oracle_frame(&self) -> Result<u64, Failure> {
        let image = self
            .pool
            .install(|| self.prepared.render(self.args.common.tile))
            .map_err(|e| render_failure(e, self.scene, self.name))?;
        Ok(image.stats.fragments_shaded)
    }

    /// `pelage bench --backend cpu`: the oracle's frames.
    fn oracle(&self) -> Result<Report, Failure> {
        let bar = progress(u64::from(self.args.frames));
        let mut samples = Samples::default();
        let mut fragments = 0;
        let mut posing = Vec::new();
        for _ in 0..self.args.frames {
            fragments = samples.time(|| self.oracle_frame())?;
            // A posed character: its posing (skinning, frames on the posed surface) timed
            // again alone, on the same pool, for the share of the frame it takes.
            if self.prepared.poses() {
                let start = Instant::now();
                let posed = self.pool.install(|| self.prepared.mesh_at(self.scene.time));
                std::hint::black_box(&posed);
                posing.push(start.elapsed().as_secs_f64() * 1e3);
            }
            bar.inc(1);
        }
        bar.finish_and_clear();
        let mut report = self.report(&samples, Some(fragments));
        if !posing.is_empty() {
            report.posing_ms = Some(round(Spread::of(&posing).median, 3));
        }
        Ok(report)
    }

    /// The oracle's report of `samples` (the GPU's fields are filled in by the caller).
    fn report(&self, samples: &Samples, fragments: Option<u64>) -> Report {
        let wall = Spread::of(&samples.wall_ms);
        let cpu =
            (samples.cpu_ms.len() == samples.wall_ms.len()).then(|| Spread::of(&samples.cpu_ms));
        let fps = 1e3 / wall.median;
        Report {
            backend: "cpu",
            adapter: None,
            bake_ms: round(self.bake_ms, 3),
            setup_ms: None,
            frames: self.args.frames,
            median_frame_ms: round(wall.median, 3),
            min_frame_ms: round(wall.min, 3),
            max_frame_ms: round(wall.max, 3),
            mad_frame_ms: round(wall.mad, 3),
            fps: round(fps, 3),
            median_cpu_ms: cpu.as_ref().map(|c| round(c.median, 3)),
            min_cpu_ms: cpu.as_ref().map(|c| round(c.min, 3)),
            max_cpu_ms: cpu.as_ref().map(|c| round(c.max, 3)),
            readback_ms: None,
            posing_ms: None,
            peak_memory_mib: peak_memory_bytes().map(|b| round(b as f64 / (1024.0 * 1024.0), 1)),
            fragments_per_frame: fragments,
            fragments_per_s: fragments.map(|f| (f as f64 / (wall.median / 1e3)).round() as u64),
            threads: self.pool.current_num_threads(),
            tile: Some(self.args.common.tile),
            width: self.scene.image.width,
            height: self.scene.image.height,
        }
    }

    /// `--backend gpu` (the GPU's report) and `--race` (the GPU's and the oracle's, their
    /// frames in turn).
    #[cfg(feature = "gpu")]
    fn gpu(&self) -> Result<(Report, Option<Report>), Failure> {
        use super::gpu_render::gpu_failure;
        use pelage::gpu::{AdapterChoice, GpuContext, GpuOptions};
        let choice = self.args.adapter.as_deref().map(AdapterChoice::parse);
        let context = GpuContext::new(choice.unwrap_or_default()).map_err(gpu_failure)?;
        let start = Instant::now();
        let frame = context
            .prepare_frame(self.prepared, self.scene.time, &GpuOptions::default())
            .map_err(gpu_failure)?;
        // One untimed frame: lavapipe compiles shader variants at their first draw.
        frame.draw().map_err(gpu_failure)?;
        let setup_ms = start.elapsed().as_secs_f64() * 1e3;
        let race = self.args.race;
        if race {
            // The oracle's first frame, untimed too (first touches of its buffers).
            self.oracle_frame()?;
        }
        let per_frame = if race { 2 } else { 1 };
        let bar = progress(u64::from(self.args.frames) * per_frame);
        let (mut gpu, mut oracle) = (Samples::default(), Samples::default());
        let mut fragments = 0;
        for _ in 0..self.args.frames {
            if race {
                fragments = oracle.time(|| self.oracle_frame())?;
                bar.inc(1);
            }
            gpu.time(|| frame.draw().map_err(gpu_failure))?;
            bar.inc(1);
        }
        bar.finish_and_clear();
        let start = Instant::now();
        frame.read_back().map_err(gpu_failure)?;
        let readback_ms = start.elapsed().as_secs_f64() * 1e3;
        let info = context.adapter_info();
        let threads = std::env::var(LP_NUM_THREADS)
            .ok()
            .and_then(|v| v.trim().parse().ok())
            .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
        let gpu = Report {
            backend: "gpu",
            adapter: Some(format!("{} ({:?})", info.name, info.device_type)),
            setup_ms: Some(round(setup_ms, 3)),
            readback_ms: Some(round(readback_ms, 3)),
            // The GPU does not say how many fragments it shaded.
            fragments_per_frame: None,
            fragments_per_s: None,
            threads,
            tile: None,
            ..self.report(&gpu, None)
        };
        let oracle = race.then(|| self.report(&oracle, Some(fragments)));
        Ok((gpu, oracle))
    }

    #[cfg(not(feature = "gpu"))]
    fn gpu(&self) -> Result<(Report, Option<Report>), Failure> {
        Err(no_gpu("--backend gpu"))
    }
}

/// Fails with one line when this pelage has no GPU backend.
#[cfg(not(feature = "gpu"))]
fn gpu_built(flag: &str) -> Result<(), Failure> {
    Err(no_gpu(flag))
}

/// The one line that says this pelage has no GPU backend.
#[cfg(not(feature = "gpu"))]
fn no_gpu(flag: &str) -> Failure {
    Failure::bad_input(format!(
        "{flag}: this pelage was built without the `gpu` feature (cargo build --release --features gpu)"
    ))
}

#[cfg(feature = "gpu")]
fn gpu_built(_flag: &str) -> Result<(), Failure> {
    Ok(())
}

/// With `--threads N`, makes sure lavapipe will start N rasterizer threads: Mesa reads
/// `LP_NUM_THREADS` once, when the Vulkan instance is made. Changing the environment of a
/// running process is `unsafe` in Rust, so where the variable is not already `N` pelage runs
/// itself again with it set (on Unix in place, as the same process).
fn lavapipe_threads(threads: Option<u32>) -> Result<(), Failure> {
    let Some(n) = threads else {
        return Ok(());
    };
    let wanted = n.to_string();
    if std::env::var(LP_NUM_THREADS).ok().as_deref() == Some(wanted.as_str()) {
        return Ok(());
    }
    let exe = std::env::current_exe()
        .map_err(|e| Failure::other(format!("cannot find the pelage executable: {e}")))?;
    let mut command = std::process::Command::new(exe);
    command
        .args(std::env::args_os().skip(1))
        .env(LP_NUM_THREADS, &wanted);
    let cannot = |e: std::io::Error| {
        Failure::other(format!(
            "cannot run pelage again with {LP_NUM_THREADS}={n}: {e}"
        ))
    };
    #[cfg(unix)]
    {
        use std::os::unix::process::CommandExt;
        Err(cannot(command.exec()))
    }
    #[cfg(not(unix))]
    {
        let status = command.status().map_err(cannot)?;
        std::process::exit(status.code().unwrap_or(1));
    }
}

/// A pool of `threads` workers (all cores when `None`), for the oracle's bake and frames.
fn thread_pool(threads: Option<u32>) -> Result<rayon::ThreadPool, Failure> {
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(n) = threads {
        builder = builder.num_threads(n as usize);
    }
    builder
        .build()
        .map_err(|e| Failure::other(format!("cannot start worker threads: {e}")))
}

/// Wall-clock and CPU time of each frame, in milliseconds.
#[derive(Default)]
struct Samples {
    wall_ms: Vec<f64>,
    /// Empty where the system does not say the process's CPU time.
    cpu_ms: Vec<f64>,
}

impl Samples {
    /// Runs `frame`, adding its times.
    fn time<T>(&mut self, frame: impl FnOnce() -> Result<T, Failure>) -> Result<T, Failure> {
        let cpu = process_cpu_ms();
        let start = Instant::now();
        let out = frame()?;
        self.wall_ms.push(start.elapsed().as_secs_f64() * 1e3);
        if let (Some(before), Some(after)) = (cpu, process_cpu_ms()) {
            self.cpu_ms.push(after - before);
        }
        Ok(out)
    }
}

/// Median, extremes and median absolute deviation of some times.
struct Spread {
    median: f64,
    min: f64,
    max: f64,
    mad: f64,
}

impl Spread {
    /// The spread of `times` (at least one).
    fn of(times: &[f64]) -> Spread {
        let mut sorted = times.to_vec();
        sorted.sort_by(f64::total_cmp);
        let median = sorted.get(sorted.len() / 2).copied().unwrap_or(f64::NAN);
        let mut deviations: Vec<f64> = sorted.iter().map(|t| (t - median).abs()).collect();
        deviations.sort_by(f64::total_cmp);
        Spread {
            median,
            min: sorted.first().copied().unwrap_or(f64::NAN),
            max: sorted.last().copied().unwrap_or(f64::NAN),
            mad: deviations
                .get(deviations.len() / 2)
                .copied()
                .unwrap_or(f64::NAN),
        }
    }
}

/// One backend's figures; `--json` prints it as it is. The oracle and the GPU have the same
/// fields; those that one of them lacks are `null` (the GPU's fragments and tile, the
/// oracle's adapter, set-up and readback).
#[derive(Serialize)]
struct Report {
    /// `cpu` (the oracle) or `gpu`.
    backend: &'static str,
    /// The GPU adapter's name and kind.
    adapter: Option<String>,
    /// The fur bake (the oracle's, shared by the GPU).
    bake_ms: f64,
    /// The GPU's set-up: uploads, pipelines, one untimed frame.
    setup_ms: Option<f64>,
    frames: u32,
    median_frame_ms: f64,
    min_frame_ms: f64,
    max_frame_ms: f64,
    mad_frame_ms: f64,
    fps: f64,
    /// CPU time of the whole process per frame (every thread).
    median_cpu_ms: Option<f64>,
    min_cpu_ms: Option<f64>,
    max_cpu_ms: Option<f64>,
    /// The GPU's readback of one frame, not in its frame times.
    readback_ms: Option<f64>,
    /// A glTF character's posing (skinning and frames on the posed surface), median of each
    /// frame's posing timed again alone; part of the frame times.
    posing_ms: Option<f64>,
    peak_memory_mib: Option<f64>,
    fragments_per_frame: Option<u64>,
    fragments_per_s: Option<u64>,
    threads: usize,
    tile: Option<u32>,
    width: u32,
    height: u32,
}

impl Report {
    /// The report as text, or as JSON.
    fn text(&self, json: bool) -> Result<String, Failure> {
        if json {
            return to_json(self);
        }
        let mut lines = Vec::new();
        match &self.adapter {
            Some(adapter) => lines.push(format!("backend gpu: {adapter}")),
            None => lines.push("backend cpu (the oracle)".to_string()),
        }
        lines.push(format!("bake {:.1} ms", self.bake_ms));
        if let Some(setup) = self.setup_ms {
            lines.push(format!(
                "set-up {setup:.1} ms (uploads, pipelines, one untimed frame)"
            ));
        }
        let tile = self.tile.map_or(String::new(), |t| format!(", tile {t}"));
        lines.push(format!(
            "frames {} at {}×{}, {} threads{tile}",
            self.frames, self.width, self.height, self.threads
        ));
        lines.push(format!(
            "median frame {:.2} ms (min {:.2}, max {:.2}, median absolute deviation {:.2})",
            self.median_frame_ms, self.min_frame_ms, self.max_frame_ms, self.mad_frame_ms
        ));
        if let (Some(median), Some(min), Some(max)) =
            (self.median_cpu_ms, self.min_cpu_ms, self.max_cpu_ms)
        {
            lines.push(format!(
                "CPU time per frame, all threads: median {median:.2} ms (min {min:.2}, max {max:.2})"
            ));
        }
        lines.push(format!("fps {:.2}", self.fps));
        match (self.fragments_per_frame, self.fragments_per_s) {
            (Some(f), Some(per_s)) => lines.push(format!(
                "fragments shaded per frame {f}, {:.1} M/s",
                per_s as f64 / 1e6
            )),
            _ => lines.push("fragments shaded per frame: not counted on the GPU".to_string()),
        }
        if let Some(posing) = self.posing_ms {
            lines.push(format!(
                "posing (skinning, frames on the posed surface) {posing:.2} ms a frame, {:.1} % of the median frame (timed again alone)",
                100.0 * posing / self.median_frame_ms
            ));
        }
        if let Some(readback) = self.readback_ms {
            lines.push(format!(
                "readback {readback:.1} ms (not in the frame times)"
            ));
        }
        lines.push(format!(
            "peak memory {}",
            self.peak_memory_mib
                .map_or("unknown on this system".to_string(), |m| format!(
                    "{m:.1} MiB"
                ))
        ));
        Ok(lines.join("\n"))
    }
}

/// The result of `--race`: both reports and how their frame times compare.
#[derive(Serialize)]
struct Race<'a> {
    oracle: &'a Report,
    gpu: &'a Report,
    /// The GPU's median frame time over the oracle's: above 1 the oracle is faster.
    wall_ratio: f64,
    /// The same of the median CPU times, where measured.
    cpu_ratio: Option<f64>,
    /// The wall-clock ratio in words.
    summary: String,
    /// The CPU-time ratio in words.
    cpu_summary: Option<String>,
}

/// `--race`'s output: both backends' times, then the ratios in words.
fn race_text(oracle: &Report, gpu: &Report, json: bool) -> Result<String, Failure> {
    let name = gpu_name(gpu);
    let wall_ratio = gpu.median_frame_ms / oracle.median_frame_ms;
    let cpu_ratio = match (gpu.median_cpu_ms, oracle.median_cpu_ms) {
        (Some(g), Some(o)) if o > 0.0 => Some(g / o),
        _ => None,
    };
    let race = Race {
        oracle,
        gpu,
        wall_ratio: round(wall_ratio, 4),
        cpu_ratio: cpu_ratio.map(|r| round(r, 4)),
        summary: in_words(wall_ratio, &name),
        cpu_summary: cpu_ratio.map(|r| in_words(r, &name)),
    };
    if json {
        return to_json(&race);
    }
    let row = |label: &str, r: &Report| {
        let cpu = match (r.median_cpu_ms, r.min_cpu_ms, r.max_cpu_ms) {
            (Some(m), Some(lo), Some(hi)) => {
                format!("; CPU median {m:.2} ms (min {lo:.2}, max {hi:.2})")
            }
            _ => String::new(),
        };
        format!(
            "{label:<9} median {:.2} ms (min {:.2}, max {:.2}){cpu}",
            r.median_frame_ms, r.min_frame_ms, r.max_frame_ms
        )
    };
    let mut lines = vec![
        format!(
            "race at {}×{}: {} frames each, an oracle frame and a GPU frame in turn; oracle {} threads, tile {}; {} ({} threads)",
            oracle.width,
            oracle.height,
            oracle.frames,
            oracle.threads,
            oracle.tile.unwrap_or_default(),
            gpu.adapter.as_deref().unwrap_or("gpu"),
            gpu.threads
        ),
        format!(
            "bake {:.1} ms (shared); GPU set-up {:.1} ms, readback {:.1} ms (not in its frame times)",
            oracle.bake_ms,
            gpu.setup_ms.unwrap_or_default(),
            gpu.readback_ms.unwrap_or_default()
        ),
        row("oracle", oracle),
        row(&name, gpu),
        format!("frame time: {}", race.summary),
    ];
    if let Some(cpu) = &race.cpu_summary {
        lines.push(format!("CPU time: {cpu}"));
    }
    Ok(lines.join("\n"))
}

/// The GPU's short name: `lavapipe` for Mesa's CPU Vulkan driver (its adapter is named after
/// llvmpipe), else the adapter's name.
fn gpu_name(gpu: &Report) -> String {
    match gpu.adapter.as_deref() {
        Some(a) if a.contains("llvmpipe") => "lavapipe".to_string(),
        Some(a) => a.split(" (").next().unwrap_or(a).to_string(),
        None => "gpu".to_string(),
    }
}

/// "oracle is 1.23× faster than NAME" for a ratio GPU/oracle of 1.23.
fn in_words(ratio: f64, name: &str) -> String {
    if ratio >= 1.0 {
        format!("oracle is {ratio:.2}× faster than {name}")
    } else {
        format!("oracle is {:.2}× slower than {name}", 1.0 / ratio)
    }
}

fn to_json(value: &impl Serialize) -> Result<String, Failure> {
    serde_json::to_string(value).map_err(|e| Failure::other(format!("cannot write JSON: {e}")))
}

/// `x` rounded to `digits` decimals (JSON prints the shortest form, so 12.345, not
/// 12.345000000000001).
fn round(x: f64, digits: i32) -> f64 {
    let scale = 10f64.powi(digits);
    (x * scale).round() / scale
}

/// The process's CPU time (every thread, user and system) in milliseconds, or `None` where
/// the system does not say it.
#[cfg(target_os = "linux")]
fn process_cpu_ms() -> Option<f64> {
    let t = rustix::time::clock_gettime(rustix::time::ClockId::ProcessCPUTime);
    Some(t.tv_sec as f64 * 1e3 + t.tv_nsec as f64 / 1e6)
}

#[cfg(not(target_os = "linux"))]
fn process_cpu_ms() -> Option<f64> {
    None
}

/// The process's peak resident memory (Linux `VmHWM`), or `None` where it cannot be read.
fn peak_memory_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}
