//! `pelage view`: the interactive window (feature `viewer`, on by default).

use super::{CommonArgs, Failure, load_scene};
use clap::Args;
use std::path::PathBuf;

#[derive(Args)]
pub struct ViewArgs {
    #[command(flatten)]
    pub common: CommonArgs,
    /// Run this many frames and exit (for automated checks): the clock steps 1/fps per frame,
    /// every frame is drawn before the next, and the frame rate is printed on stderr.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    pub frames: Option<u32>,
    /// Where the screenshot goes: written after the last of --frames, or by the `p` key
    /// (default pelage-view-NNN.png). The scene drawn is written beside it as .toml.
    #[arg(long)]
    pub screenshot: Option<PathBuf>,
    /// Frames per second of the clock with --frames.
    #[arg(long, default_value_t = 30.0)]
    pub fps: f32,
    /// Start with the clock stopped (space starts it).
    #[arg(long)]
    pub paused: bool,
    /// With --frames, orbit the camera by this many degrees per frame.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub orbit: f32,
}

/// The viewer's workload: a preview and a refining pool of `--threads` each, and the window's
/// and a screenshot's copy of the frame (counted as two kept frames).
fn view_workload() -> pelage::limits::Workload {
    pelage::limits::Workload {
        frames: 2,
        keep_frames: true,
        ..pelage::limits::Workload::default()
    }
}

#[cfg(feature = "viewer")]
pub fn run(args: ViewArgs) -> Result<(), Failure> {
    let scene = load_scene(&args.common)?;
    let threads = match args.common.threads {
        Some(n) => n,
        None => u32::try_from(rayon::current_num_threads()).unwrap_or(u32::MAX),
    };
    let limits = crate::view::ViewLimits {
        mesh: pelage::limits::mesh_size(&scene).map_err(|e| Failure::bad_input(e.to_string()))?,
        work: pelage::limits::Workload {
            threads: threads.saturating_mul(2),
            ..view_workload()
        },
        budgets: super::budgets(&args.common),
    };
    pelage::limits::check(&scene, limits.mesh, &limits.work, &limits.budgets)
        .map_err(|e| super::limit_failure(&super::scene_name(&args.common), e))?;
    if !(args.fps.is_finite() && args.fps > 0.0 && args.fps <= 1000.0) {
        return Err(Failure::bad_input(format!(
            "--fps {} must be in (0, 1000]",
            args.fps
        )));
    }
    if !args.orbit.is_finite() {
        return Err(Failure::bad_input(
            "--orbit must be a finite number of degrees",
        ));
    }
    let name = match &args.common.scene {
        Some(p) => p.display().to_string(),
        None => pelage::scene::DEFAULT_SCENE_NAME.to_string(),
    };
    crate::view::run(
        scene,
        crate::view::Options {
            title: format!("pelage view: {name}"),
            threads: args.common.threads,
            tile: args.common.tile,
            frames: args.frames,
            screenshot: args.screenshot,
            fps: args.fps,
            paused: args.paused,
            orbit_deg: args.orbit,
            limits,
        },
    )
}

#[cfg(not(feature = "viewer"))]
pub fn run(args: ViewArgs) -> Result<(), Failure> {
    let scene = load_scene(&args.common)?;
    super::check_workload(&scene, &args.common, view_workload())?;
    Err(Failure::other(
        "this pelage was built without the viewer: rebuild with the cargo feature `viewer` \
         (on by default)",
    ))
}
