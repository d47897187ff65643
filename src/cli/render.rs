//! `pelage render`: one instant to a PNG, or an animation to numbered PNGs and a GIF.
//!
//! Outputs never look complete when they are not: a PNG or GIF is written to a temporary
//! sibling and renamed; an animation's frames go to a [`StagedFolder`] (an existing output
//! folder that holds nothing but `frame_NNNN.png` files, a previous render, is replaced).

use super::gpu_render::GpuRequest;
use super::staged::{EntryRule, StagedFolder, parent_of};
use super::{
    CommonArgs, Failure, check_limits, load_scene, progress, render_failure, scene_name, spinner,
    with_threads, write_png,
};
use clap::Args;
use pelage::output::ImageFormat;
use pelage::render::PreparedScene;
use pelage::scene::Scene;
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct RenderArgs {
    #[command(flatten)]
    pub common: CommonArgs,
    /// Output image: .png (8-bit; 16-bit with --depth 16) or .exr (32-bit float, the values
    /// before 8-bit rounding); with --frames, the folder the numbered PNG frames go to.
    #[arg(short, long, default_value = "pelage.png")]
    pub output: PathBuf,
    /// Bits per channel of a PNG output: 8 (the reference bytes) or 16 (the float values
    /// rounded to 16 bits).
    #[arg(long, default_value_t = 8, allow_negative_numbers = true)]
    pub depth: u8,
    /// Render an animation of N frames: frame k is the instant k / fps, written as
    /// OUTPUT/frame_0000.png, frame_0001.png, ...
    #[arg(long, allow_negative_numbers = true, value_parser = clap::value_parser!(u32).range(1..=i64::from(pelage::limits::MAX_FRAMES)))]
    pub frames: Option<u32>,
    /// Frames per second of the animation.
    #[arg(long, allow_negative_numbers = true, default_value_t = 10.0)]
    pub fps: f32,
    /// Also write the animation as an animated GIF to this path.
    #[arg(long, requires = "frames")]
    pub animation: Option<PathBuf>,
    /// Which renderer draws the frame: the CPU oracle, or wgpu (built with `--features gpu`).
    #[arg(long, value_enum, default_value_t = Backend::Cpu)]
    pub backend: Backend,
    /// With --backend gpu: the API wgpu draws through, `vulkan` (default) or `gl` (OpenGL ES
    /// through EGL, Mesa's llvmpipe headless).
    #[arg(long, value_name = "API")]
    pub api: Option<String>,
    /// With --backend gpu: the adapter, by index or part of its name as `pelage gpu-info`
    /// lists them (default: the software one, lavapipe or llvmpipe, for reproducible figures;
    /// `swiftshader` where VK_ICD_FILENAMES names SwiftShader's ICD file).
    #[arg(long, value_name = "NAME|INDEX")]
    pub adapter: Option<String>,
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
    if args.frames.is_some() && args.depth != 8 {
        return Err(Failure::bad_input(
            "--depth 16: animation frames are 8-bit PNGs; render single instants (--time) for \
             16-bit PNG or EXR",
        ));
    }
    let format = if args.frames.is_some() {
        ImageFormat::Png8
    } else {
        ImageFormat::for_path(&args.output, args.depth)
            .map_err(|e| Failure::bad_input(format!("-o {e}")))?
    };
    if args.backend == Backend::Gpu {
        if format != ImageFormat::Png8 {
            return Err(Failure::bad_input(format!(
                "-o {}: the GPU backend writes 8-bit PNG",
                args.output.display()
            )));
        }
        // The same refusals as the CPU path, before any work: the output's folder, and the
        // memory and work estimates (the GPU holds the same baked textures and mesh, and the
        // bake runs on the CPU).
        if args.frames.is_none() {
            check_output_file(&args.output)?;
            with_threads(args.common.threads, || {
                check_limits(&scene, &args.common, 1, false)
            })??;
        }
        let request = GpuRequest {
            output: &args.output,
            threads: args.common.threads,
            frames: args.frames.is_some(),
            api: args.api.as_deref(),
            adapter: args.adapter.as_deref(),
        };
        return super::gpu_render::run(&scene, &request);
    }
    if args.api.is_some() || args.adapter.is_some() {
        return Err(Failure::bad_input(
            "--api and --adapter choose the GPU backend's device: add --backend gpu",
        ));
    }
    if let Some(frames) = args.frames {
        return render_animation(&scene, &args, frames, tile);
    }
    check_output_file(&args.output)?;
    let name = scene_name(&args.common);
    let image = with_threads(args.common.threads, || {
        check_limits(&scene, &args.common, 1, false)?;
        let bar = spinner("baking fur textures");
        let prepared = PreparedScene::new(&scene).map_err(|e| render_failure(e, &scene, &name))?;
        bar.set_message("rendering");
        let image = if format == ImageFormat::Png8 {
            prepared.render(tile).map(|image| (image, Vec::new()))
        } else {
            prepared.render_linear_at(scene.time, tile)
        }
        .map_err(|e| render_failure(e, &scene, &name));
        bar.finish_and_clear();
        image
    })??;
    let (image, linear) = image;
    if format == ImageFormat::Png8 {
        write_png(&args.output, image.width, image.height, &image.rgba8)?;
    } else {
        let floats: Vec<f32> = linear.iter().flat_map(|c| c.to_array()).collect();
        pelage::output::write_float_image(&args.output, format, image.width, image.height, &floats)
            .map_err(|e| Failure::other(e.to_string()))?;
    }
    for warning in &image.warnings {
        eprintln!("warning: {warning}");
    }
    let kind = match format {
        ImageFormat::Png8 => "8-bit PNG",
        ImageFormat::Png16 => "16-bit PNG",
        ImageFormat::Exr => "OpenEXR (32-bit float)",
    };
    super::say_written(
        &args.output,
        format_args!(
            "{}×{} {kind} at t = {} s",
            image.width, image.height, scene.time
        ),
    )
}

/// Refuses an output path that cannot take a file, before any work: a folder, or a file in a
/// folder that does not exist.
fn check_output_file(path: &Path) -> Result<(), Failure> {
    if pelage::output::is_stdout(path) {
        return Ok(());
    }
    let path =
        &pelage::output::resolve_output(path).map_err(|e| Failure::bad_input(format!("-o {e}")))?;
    if path.is_dir() {
        return Err(Failure::bad_input(format!(
            "-o {}: is a folder (an image file name is expected; use --frames for a folder)",
            path.display()
        )));
    }
    let Some(name) = path.file_name() else {
        return Err(Failure::bad_input(format!(
            "-o {}: not a file name",
            path.display()
        )));
    };
    if name.len() > pelage::output::MAX_FILE_NAME_BYTES {
        return Err(Failure::bad_input(format!(
            "-o {}: the file name is {} bytes, longer than the {} a file system allows",
            path.display(),
            name.len(),
            pelage::output::MAX_FILE_NAME_BYTES
        )));
    }
    let parent = parent_of(path);
    if !parent.is_dir() {
        return Err(Failure::bad_input(format!(
            "-o {}: the folder {} does not exist",
            path.display(),
            parent.display()
        )));
    }
    Ok(())
}

/// What a frame folder from a previous render holds: `frame_NNNN.png` files, and the GIF when
/// it was written inside.
fn frame_folder_entries(gif: Option<String>) -> EntryRule {
    EntryRule {
        accepts: Box::new(move |name: &str| is_frame_file(name) || Some(name) == gif.as_deref()),
        what: "a frame of a previous render",
    }
}

/// Whether `name` is a frame file this command writes: `frame_` digits `.png`.
fn is_frame_file(name: &str) -> bool {
    name.strip_prefix("frame_")
        .and_then(|r| r.strip_suffix(".png"))
        .is_some_and(|d| !d.is_empty() && d.bytes().all(|b| b.is_ascii_digit()))
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
    // Frame k is the instant k / fps: the last one must lie in the scene's time range.
    let last = frames.saturating_sub(1) as f32 / args.fps;
    if !(last.is_finite() && last <= pelage::scene::MAX_TIME) {
        return Err(Failure::bad_input(format!(
            "--fps {}: frame {} would be at {last} s, past the largest time, {} s; raise --fps \
             or render fewer --frames",
            args.fps,
            frames.saturating_sub(1),
            pelage::scene::MAX_TIME
        )));
    }
    // The GIF may go inside the frame folder, which exists only once the frames are written.
    let gif_inside = args
        .animation
        .as_deref()
        .filter(|gif| parent_of(gif) == args.output.as_path());
    if let Some(gif) = &args.animation {
        pelage::output::check_extension(gif, "gif")
            .map_err(|e| Failure::bad_input(format!("--animation {e}")))?;
    }
    if let Some(gif) = &args.animation
        && gif_inside.is_none()
    {
        check_output_file(gif).map_err(|f| Failure {
            message: f.message.replacen("-o ", "--animation ", 1),
            ..f
        })?;
    }
    let keep_name = gif_inside
        .and_then(|g| g.file_name())
        .map(|n| n.to_string_lossy().into_owned());
    if let Some(name) = keep_name.as_deref().filter(|n| is_frame_file(n)) {
        return Err(Failure::bad_input(format!(
            "--animation {name}: inside the frame folder it would overwrite a frame; choose \
             another name"
        )));
    }
    let fps = args.fps;
    let keep_for_gif = args.animation.is_some();
    let name = scene_name(&args.common);
    with_threads(args.common.threads, || {
        check_limits(scene, &args.common, frames, keep_for_gif)
    })??;
    let folder = StagedFolder::create(&args.output, frame_folder_entries(keep_name))?;
    let dir = folder.path().to_path_buf();
    let (images, warnings) = with_threads(args.common.threads, || -> Result<_, Failure> {
        let prepared = PreparedScene::new(scene).map_err(|e| render_failure(e, scene, &name))?;
        let bar = progress(u64::from(frames));
        let mut kept = Vec::new();
        let mut warnings = Vec::new();
        for k in 0..frames {
            let image = prepared
                .render_at(k as f32 / fps, tile)
                .map_err(|e| render_failure(e, scene, &name))?;
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
    folder.commit()?;
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
    super::say_written(
        &args.output,
        format_args!(
            "{frames} frames (frame_0000.png to frame_{:04}.png) at {fps} fps",
            frames.saturating_sub(1)
        ),
    )?;
    if let Some(path) = &args.animation {
        super::say_written(path, format_args!("animated GIF of {frames} frames"))?;
    }
    Ok(())
}
