//! The `pelage` command line: render scenes to PNG and benchmark them.
//!
//! Exit status: 0 on success, 2 on bad input (scene, mesh, arguments), 1 on other failures
//! (an output that cannot be written).

use clap::{Args, Parser, Subcommand};
use pelage::render::{PreparedScene, RenderError};
use pelage::scene::Scene;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

#[derive(Parser)]
#[command(
    name = "pelage",
    version,
    about = "Deterministic software renderer for shell-and-fin fur"
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene (the embedded furred torus when none is given) to a PNG.
    Render(RenderArgs),
    /// Time baking and frames of a scene.
    Bench(BenchArgs),
}

#[derive(Args, Clone)]
struct CommonArgs {
    /// Scene file (TOML). Without one, the embedded default scene (thesis figure 3.1).
    scene: Option<PathBuf>,
    /// Override the image width.
    #[arg(long)]
    width: Option<u32>,
    /// Override the image height.
    #[arg(long)]
    height: Option<u32>,
    /// Worker threads (default: all cores). The image does not depend on it.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=256))]
    threads: Option<u32>,
    /// Tile size in pixels, even, 2..=1024 (default 64). The image does not depend on it.
    #[arg(long, default_value_t = pelage::raster::DEFAULT_TILE_SIZE)]
    tile: u32,
    /// Render this instant (seconds) instead of the scene's `time`.
    #[arg(long, allow_negative_numbers = true)]
    time: Option<f32>,
}

#[derive(Args)]
struct RenderArgs {
    #[command(flatten)]
    common: CommonArgs,
    /// Output PNG; with --frames, the folder the numbered frames go to.
    #[arg(short, long, default_value = "pelage.png")]
    output: PathBuf,
    /// Render an animation of N frames: frame k is the instant k / fps, written as
    /// OUTPUT/frame_0000.png, frame_0001.png, ...
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    frames: Option<u32>,
    /// Frames per second of the animation.
    #[arg(long, default_value_t = 10.0)]
    fps: f32,
    /// Also write the animation as an animated GIF to this path.
    #[arg(long, requires = "frames")]
    animation: Option<PathBuf>,
}

#[derive(Args)]
struct BenchArgs {
    #[command(flatten)]
    common: CommonArgs,
    /// Frames to time.
    #[arg(long, default_value_t = 10, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    frames: u32,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
}

/// A failure and its exit status.
struct Failure {
    message: String,
    status: u8,
}

impl From<RenderError> for Failure {
    fn from(e: RenderError) -> Self {
        let status = if e.is_bad_input() { 2 } else { 1 };
        Failure {
            message: e.to_string(),
            status,
        }
    }
}

fn load_scene(args: &CommonArgs) -> Result<Scene, Failure> {
    let bad = |message: String| Failure { message, status: 2 };
    let (mut scene, name) = match &args.scene {
        Some(path) => (
            Scene::load(path).map_err(|e| bad(e.to_string()))?,
            path.display().to_string(),
        ),
        None => (
            Scene::embedded_default().map_err(|e| bad(e.to_string()))?,
            pelage::scene::DEFAULT_SCENE_NAME.to_string(),
        ),
    };
    if let Some(w) = args.width {
        scene.image.width = w;
    }
    if let Some(h) = args.height {
        scene.image.height = h;
    }
    if let Some(t) = args.time {
        scene.time = t;
    }
    scene
        .revalidate(&name)
        .map_err(|e| bad(format!("{e} (after --width/--height/--time)")))?;
    pelage::raster::TileGrid::new(1, 1, args.tile).map_err(|e| bad(format!("--tile: {e}")))?;
    Ok(scene)
}

fn with_threads<T: Send>(
    threads: Option<u32>,
    work: impl FnOnce() -> T + Send,
) -> Result<T, Failure> {
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(n) = threads {
        builder = builder.num_threads(n as usize);
    }
    let pool = builder.build().map_err(|e| Failure {
        message: format!("cannot start worker threads: {e}"),
        status: 1,
    })?;
    Ok(pool.install(work))
}

fn spinner(message: &str) -> indicatif::ProgressBar {
    if !std::io::stderr().is_terminal() {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new_spinner().with_message(message.to_string());
    bar.enable_steady_tick(std::time::Duration::from_millis(100));
    bar
}

fn render(args: RenderArgs) -> Result<(), Failure> {
    let scene = load_scene(&args.common)?;
    let tile = args.common.tile;
    if let Some(frames) = args.frames {
        return render_animation(&scene, &args, frames, tile);
    }
    let image = with_threads(args.common.threads, || {
        let bar = spinner("baking fur textures");
        let prepared = PreparedScene::new(&scene)?;
        bar.set_message("rendering");
        let image = prepared.render(tile);
        bar.finish_and_clear();
        image
    })??;
    write_png(&args.output, image.width, image.height, &image.rgba8)?;
    for warning in &image.warnings {
        eprintln!("warning: {warning}");
    }
    Ok(())
}

/// Frames 0..n at t = k / fps into the output folder (and an animated GIF when asked).
fn render_animation(
    scene: &Scene,
    args: &RenderArgs,
    frames: u32,
    tile: u32,
) -> Result<(), Failure> {
    if !(args.fps.is_finite() && args.fps > 0.0 && args.fps <= 1000.0) {
        return Err(Failure {
            message: format!("--fps {} must be in (0, 1000]", args.fps),
            status: 2,
        });
    }
    std::fs::create_dir_all(&args.output).map_err(|e| Failure {
        message: format!(
            "{}: cannot create the frame folder: {e}",
            args.output.display()
        ),
        status: 1,
    })?;
    let fps = args.fps;
    let dir = args.output.clone();
    let keep_for_gif = args.animation.is_some();
    let (images, warnings) = with_threads(args.common.threads, || -> Result<_, Failure> {
        let prepared = PreparedScene::new(scene)?;
        let bar = if std::io::stderr().is_terminal() {
            indicatif::ProgressBar::new(u64::from(frames))
        } else {
            indicatif::ProgressBar::hidden()
        };
        let mut kept = Vec::new();
        let mut warnings = Vec::new();
        for k in 0..frames {
            let image = prepared.render_at(k as f32 / fps, tile)?;
            write_png(
                &dir.join(format!("frame_{k:04}.png")),
                image.width,
                image.height,
                &image.rgba8,
            )?;
            warnings = image.warnings.clone();
            if keep_for_gif {
                kept.push(image);
            }
            bar.inc(1);
        }
        bar.finish_and_clear();
        Ok((kept, warnings))
    })??;
    for warning in &warnings {
        eprintln!("warning: {warning}");
    }
    if let Some(path) = &args.animation {
        let frames: Vec<(u32, u32, Vec<u8>)> = images
            .into_iter()
            .map(|i| (i.width, i.height, i.rgba8))
            .collect();
        pelage::output::write_gif(path, &frames, fps).map_err(|e| Failure {
            message: e.to_string(),
            status: 1,
        })?;
    }
    Ok(())
}

fn write_png(path: &Path, width: u32, height: u32, rgba: &[u8]) -> Result<(), Failure> {
    pelage::output::write_png(path, width, height, rgba).map_err(|e| Failure {
        message: e.to_string(),
        status: 1,
    })
}

fn bench(args: BenchArgs) -> Result<(), Failure> {
    let scene = load_scene(&args.common)?;
    let tile = args.common.tile;
    let threads = args.common.threads;
    let report = with_threads(threads, || -> Result<String, Failure> {
        let start = Instant::now();
        let prepared = PreparedScene::new(&scene)?;
        let bake_ms = start.elapsed().as_secs_f64() * 1e3;
        let bar = if std::io::stderr().is_terminal() {
            indicatif::ProgressBar::new(u64::from(args.frames))
        } else {
            indicatif::ProgressBar::hidden()
        };
        let mut times = Vec::with_capacity(args.frames as usize);
        let mut fragments = 0;
        for _ in 0..args.frames {
            let t = Instant::now();
            let image = prepared.render(tile)?;
            times.push(t.elapsed().as_secs_f64() * 1e3);
            fragments = image.stats.fragments_shaded;
            bar.inc(1);
        }
        bar.finish_and_clear();
        times.sort_by(f64::total_cmp);
        let median = times[times.len() / 2];
        let (min, max) = (times[0], times[times.len() - 1]);
        let fps = 1e3 / median;
        let fragments_per_s = fragments as f64 / (median / 1e3);
        let threads = rayon::current_num_threads();
        Ok(if args.json {
            format!(
                "{{\"bake_ms\":{bake_ms:.3},\"frames\":{},\"median_frame_ms\":{median:.3},\"min_frame_ms\":{min:.3},\"max_frame_ms\":{max:.3},\"fps\":{fps:.3},\"fragments_per_frame\":{fragments},\"fragments_per_s\":{fragments_per_s:.0},\"threads\":{threads},\"tile\":{tile},\"width\":{},\"height\":{}}}",
                args.frames, scene.image.width, scene.image.height
            )
        } else {
            format!(
                "bake {bake_ms:.1} ms\nframes {} at {}×{}, {threads} threads, tile {tile}\nmedian frame {median:.2} ms (min {min:.2}, max {max:.2})\nfps {fps:.2}\nfragments shaded per frame {fragments}, {:.1} M/s",
                args.frames,
                scene.image.width,
                scene.image.height,
                fragments_per_s / 1e6
            )
        })
    })??;
    println!("{report}");
    Ok(())
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let command = cli.command.unwrap_or(Command::Render(RenderArgs {
        common: CommonArgs {
            scene: None,
            width: None,
            height: None,
            threads: None,
            tile: pelage::raster::DEFAULT_TILE_SIZE,
            time: None,
        },
        output: PathBuf::from("pelage.png"),
        frames: None,
        fps: 10.0,
        animation: None,
    }));
    let result = match command {
        Command::Render(args) => render(args),
        Command::Bench(args) => bench(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(f) => {
            eprintln!("error: {}", f.message);
            ExitCode::from(f.status)
        }
    }
}
