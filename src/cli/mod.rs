//! What every subcommand shares: the scene arguments, loading and overriding a scene, the
//! worker pool, progress display, and the failure type that carries the exit status.

use clap::Args;
use pelage::render::RenderError;
use pelage::scene::Scene;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

pub mod against;
pub mod bench;
pub mod compare;
pub mod diagram;
pub mod export;
pub mod gpu_render;
pub mod render;
pub mod staged;
pub mod sweep;
pub mod view;

/// The arguments every scene-reading subcommand takes.
#[derive(Args, Clone)]
pub struct CommonArgs {
    /// Scene file (TOML). Without one, the embedded default scene (thesis figure 3.1).
    pub scene: Option<PathBuf>,
    /// Override the image width.
    #[arg(long, allow_negative_numbers = true)]
    pub width: Option<u32>,
    /// Override the image height.
    #[arg(long, allow_negative_numbers = true)]
    pub height: Option<u32>,
    /// Worker threads (default: all cores). The image does not depend on it.
    #[arg(long, allow_negative_numbers = true, value_parser = clap::value_parser!(u32).range(1..=256))]
    pub threads: Option<u32>,
    /// Tile size in pixels, even, 2..=1024 (default 64). The image does not depend on it.
    #[arg(long, allow_negative_numbers = true, default_value_t = pelage::raster::DEFAULT_TILE_SIZE)]
    pub tile: u32,
    /// Render this instant (seconds) instead of the scene's `time`.
    #[arg(long, allow_negative_numbers = true)]
    pub time: Option<f32>,
    /// Refuse renders whose memory estimate exceeds this size (8G, 512M, bytes; default 8G).
    #[arg(long, value_name = "SIZE", allow_negative_numbers = true, value_parser = parse_size)]
    pub max_memory: Option<u64>,
    /// Refuse scenes whose fur bake would take more than this many texel writes and segment
    /// tests (default 2e10, about a minute of baking on one core).
    #[arg(long, value_name = "N", allow_negative_numbers = true, value_parser = parse_work)]
    pub max_work: Option<u64>,
    /// Refuse scenes whose frame would take more than this many fragment evaluations (one per
    /// spot, stripe and burn match) and triangle set-ups (default 1e11, minutes a frame).
    #[arg(long, value_name = "N", allow_negative_numbers = true, value_parser = parse_work)]
    pub max_draw_work: Option<u64>,
}

impl CommonArgs {
    /// The arguments of a plain render of the embedded default scene.
    pub fn defaults() -> Self {
        CommonArgs {
            scene: None,
            width: None,
            height: None,
            threads: None,
            tile: pelage::raster::DEFAULT_TILE_SIZE,
            time: None,
            max_memory: None,
            max_work: None,
            max_draw_work: None,
        }
    }
}

fn parse_size(text: &str) -> Result<u64, String> {
    pelage::limits::parse_bytes(text)
}

fn parse_work(text: &str) -> Result<u64, String> {
    let value: f64 = text
        .parse()
        .map_err(|_| format!("{text:?} is not a number (e.g. 5e10)"))?;
    if !(value.is_finite() && value >= 1.0) {
        return Err(format!("{text:?} must be a number of at least 1"));
    }
    Ok(value.min(u64::MAX as f64) as u64)
}

/// A failure and its exit status.
pub struct Failure {
    /// One line for the user, naming the file, line, key or argument at fault.
    pub message: String,
    /// 2 for bad input, 1 for anything else.
    pub status: u8,
}

impl Failure {
    /// Bad input from the user: exit status 2.
    pub fn bad_input(message: impl Into<String>) -> Self {
        Failure {
            message: message.into(),
            status: 2,
        }
    }

    /// Anything else that went wrong (an output that cannot be written): exit status 1.
    pub fn other(message: impl Into<String>) -> Self {
        Failure {
            message: message.into(),
            status: 1,
        }
    }
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

/// Prints one line on standard output. A reader that has gone away (a closed pipe, as in
/// `pelage compare a.png b.png | head -1`) is normal for a command-line tool: the rest of the
/// output is dropped and the command ends with its own status; any other write error is one.
pub fn say(text: impl std::fmt::Display) -> Result<(), Failure> {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    match writeln!(out, "{text}").and_then(|()| out.flush()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => {
            Err(Failure::other(format!("standard output: {e}")))
        }
        _ => Ok(()),
    }
}

/// The name errors use for the scene of `args`.
pub fn scene_name(args: &CommonArgs) -> String {
    match &args.scene {
        Some(path) => path.display().to_string(),
        None => pelage::scene::DEFAULT_SCENE_NAME.to_string(),
    }
}

/// A failure of preparing or drawing `scene`, worded by [`RenderError::describe`] (the Python
/// package words it the same way).
pub fn render_failure(e: RenderError, scene: &Scene, name: &str) -> Failure {
    Failure {
        message: e.describe(scene, name),
        status: if e.is_bad_input() { 2 } else { 1 },
    }
}

/// The scene named on the command line (or the embedded default), with the overrides applied
/// and validated again.
pub fn load_scene(args: &CommonArgs) -> Result<Scene, Failure> {
    let bad = Failure::bad_input;
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
    apply_overrides(&mut scene, args, &name)?;
    Ok(scene)
}

/// The scene's text, its name for messages, and the folder its relative paths start from.
pub fn scene_source(args: &CommonArgs) -> Result<(String, String, PathBuf), Failure> {
    match &args.scene {
        Some(path) => {
            let text = pelage::input::read_text(path, pelage::scene::MAX_SCENE_BYTES, "scene")
                .map_err(|e| Failure::bad_input(e.to_string()))?;
            let dir = path.parent().unwrap_or(Path::new(".")).to_path_buf();
            Ok((text, path.display().to_string(), dir))
        }
        None => Ok((
            pelage::scene::DEFAULT_SCENE.to_string(),
            pelage::scene::DEFAULT_SCENE_NAME.to_string(),
            PathBuf::from("scenes"),
        )),
    }
}

/// `--width`, `--height` and `--time` written into the scene, which is then checked again;
/// `--tile` is checked too.
pub fn apply_overrides(scene: &mut Scene, args: &CommonArgs, name: &str) -> Result<(), Failure> {
    let bad = Failure::bad_input;
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
        .revalidate(name)
        .map_err(|e| bad(format!("{e} (after --width/--height/--time)")))?;
    pelage::raster::TileGrid::new(1, 1, args.tile).map_err(|e| bad(format!("--tile: {e}")))?;
    Ok(())
}

/// Checks the scene against the memory and bake-work limits (see `pelage::limits`) before
/// anything large is allocated. `frames` are rendered; `keep_frames` when all are held for a
/// GIF. An OBJ mesh is scanned here, so its malformed lines are reported before any work.
pub fn check_limits(
    scene: &Scene,
    args: &CommonArgs,
    frames: u32,
    keep_frames: bool,
) -> Result<(), Failure> {
    check_workload(
        scene,
        args,
        pelage::limits::Workload {
            frames,
            keep_frames,
            ..pelage::limits::Workload::default()
        },
    )
    .map(|_| ())
}

/// [`check_limits`] for any workload (an export, a sweep's point); the thread count is taken
/// from `--threads` (all cores without it). Returns the estimate.
pub fn check_workload(
    scene: &Scene,
    args: &CommonArgs,
    work: pelage::limits::Workload,
) -> Result<pelage::limits::MemoryEstimate, Failure> {
    use pelage::limits;
    let mesh = limits::mesh_size(scene).map_err(|e| Failure::bad_input(e.to_string()))?;
    let threads = match args.threads {
        Some(n) => n,
        None => u32::try_from(rayon::current_num_threads()).unwrap_or(u32::MAX),
    };
    let work = limits::Workload { threads, ..work };
    limits::check(scene, mesh, &work, &budgets(args))
        .map_err(|e| limit_failure(&scene_name(args), e))
}

/// The limits `args` set (`--max-memory`, `--max-work`, `--max-draw-work`), defaults for the
/// others.
pub fn budgets(args: &CommonArgs) -> pelage::limits::Budgets {
    let d = pelage::limits::Budgets::default();
    pelage::limits::Budgets {
        memory: args.max_memory.unwrap_or(d.memory),
        bake_work: args.max_work.unwrap_or(d.bake_work),
        draw_work: args.max_draw_work.unwrap_or(d.draw_work),
    }
}

/// `--max-memory`, or the default limit.
pub fn max_memory(flag: Option<u64>) -> u64 {
    flag.unwrap_or(pelage::limits::DEFAULT_MAX_MEMORY)
}

/// A refusal by a limit, for `name` (the scene or the files at fault), naming the flag that
/// raises it.
pub fn limit_failure(name: &str, e: pelage::limits::LimitError) -> Failure {
    let flag = e.flag();
    Failure::bad_input(format!("{name}: {e}; raise the limit with {flag}"))
}

/// Runs `work` on a pool of `threads` workers (all cores when `None`).
pub fn with_threads<T: Send>(
    threads: Option<u32>,
    work: impl FnOnce() -> T + Send,
) -> Result<T, Failure> {
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(n) = threads {
        builder = builder.num_threads(n as usize);
    }
    let pool = builder
        .build()
        .map_err(|e| Failure::other(format!("cannot start worker threads: {e}")))?;
    Ok(pool.install(work))
}

/// A spinner with a message on a terminal; hidden in pipes and CI.
pub fn spinner(message: &str) -> indicatif::ProgressBar {
    if !std::io::stderr().is_terminal() {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new_spinner().with_message(message.to_string());
    bar.enable_steady_tick(std::time::Duration::from_millis(100));
    bar
}

/// Writes a PNG atomically (temporary file, then rename).
pub fn write_png(path: &Path, width: u32, height: u32, rgba: &[u8]) -> Result<(), Failure> {
    pelage::output::write_png(path, width, height, rgba).map_err(|e| Failure::other(e.to_string()))
}

/// Says on standard output what was written to `path` (`PATH: what`); nothing when the image
/// itself went to standard output (`-o -`).
pub fn say_written(path: &Path, what: impl std::fmt::Display) -> Result<(), Failure> {
    if pelage::output::is_stdout(path) {
        return Ok(());
    }
    say(format!("{}: {what}", path.display()))
}

/// A progress bar of `len` steps on a terminal; hidden in pipes and CI.
pub fn progress(len: u64) -> indicatif::ProgressBar {
    if std::io::stderr().is_terminal() {
        indicatif::ProgressBar::new(len)
    } else {
        indicatif::ProgressBar::hidden()
    }
}
