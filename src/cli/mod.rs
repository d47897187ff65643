//! What every subcommand shares: the scene arguments, loading and overriding a scene, the
//! worker pool, progress display, and the failure type that carries the exit status.

use clap::Args;
use pelage::render::RenderError;
use pelage::scene::Scene;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

pub mod bench;
pub mod compare;
pub mod export;
pub mod gpu_render;
pub mod render;
pub mod sweep;
pub mod view;

/// The arguments every scene-reading subcommand takes.
#[derive(Args, Clone)]
pub struct CommonArgs {
    /// Scene file (TOML). Without one, the embedded default scene (thesis figure 3.1).
    pub scene: Option<PathBuf>,
    /// Override the image width.
    #[arg(long)]
    pub width: Option<u32>,
    /// Override the image height.
    #[arg(long)]
    pub height: Option<u32>,
    /// Worker threads (default: all cores). The image does not depend on it.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=256))]
    pub threads: Option<u32>,
    /// Tile size in pixels, even, 2..=1024 (default 64). The image does not depend on it.
    #[arg(long, default_value_t = pelage::raster::DEFAULT_TILE_SIZE)]
    pub tile: u32,
    /// Render this instant (seconds) instead of the scene's `time`.
    #[arg(long, allow_negative_numbers = true)]
    pub time: Option<f32>,
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
            let text = std::fs::read_to_string(path).map_err(|e| {
                Failure::bad_input(format!("{}: cannot read the scene: {e}", path.display()))
            })?;
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

/// A progress bar of `len` steps on a terminal; hidden in pipes and CI.
pub fn progress(len: u64) -> indicatif::ProgressBar {
    if std::io::stderr().is_terminal() {
        indicatif::ProgressBar::new(len)
    } else {
        indicatif::ProgressBar::hidden()
    }
}
