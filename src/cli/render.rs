//! `pelage render`: one instant to a PNG, or an animation to numbered PNGs and a GIF.

use super::{CommonArgs, Failure, load_scene, progress, spinner, with_threads, write_png};
use clap::Args;
use pelage::render::PreparedScene;
use pelage::scene::Scene;
use std::path::PathBuf;

#[derive(Args)]
pub struct RenderArgs {
    #[command(flatten)]
    pub common: CommonArgs,
    /// Output PNG; with --frames, the folder the numbered frames go to.
    #[arg(short, long, default_value = "pelage.png")]
    pub output: PathBuf,
    /// Render an animation of N frames: frame k is the instant k / fps, written as
    /// OUTPUT/frame_0000.png, frame_0001.png, ...
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    pub frames: Option<u32>,
    /// Frames per second of the animation.
    #[arg(long, default_value_t = 10.0)]
    pub fps: f32,
    /// Also write the animation as an animated GIF to this path.
    #[arg(long, requires = "frames")]
    pub animation: Option<PathBuf>,
    /// Which renderer draws the frame: the CPU oracle, or wgpu (built with `--features gpu`).
    #[arg(long, value_enum, default_value_t = Backend::Cpu)]
    pub backend: Backend,
}

/// The renderer behind `--backend`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Backend {
    /// The deterministic software oracle.
    Cpu,
    /// wgpu with the WGSL mirror of the fragment closures (feature `gpu`).
    Gpu,
}

pub fn run(args: RenderArgs) -> Result<(), Failure> {
    let scene = load_scene(&args.common)?;
    let tile = args.common.tile;
    if args.backend == Backend::Gpu {
        return super::gpu_render::run(&scene, &args);
    }
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
        return Err(Failure::bad_input(format!(
            "--fps {} must be in (0, 1000]",
            args.fps
        )));
    }
    std::fs::create_dir_all(&args.output).map_err(|e| {
        Failure::other(format!(
            "{}: cannot create the frame folder: {e}",
            args.output.display()
        ))
    })?;
    let fps = args.fps;
    let dir = args.output.clone();
    let keep_for_gif = args.animation.is_some();
    let (images, warnings) = with_threads(args.common.threads, || -> Result<_, Failure> {
        let prepared = PreparedScene::new(scene)?;
        let bar = progress(u64::from(frames));
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
        pelage::output::write_gif(path, &frames, fps).map_err(|e| Failure::other(e.to_string()))?;
    }
    Ok(())
}
