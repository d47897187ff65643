//! `pelage render --backend gpu`: one frame drawn by wgpu (feature `gpu`) from the same baked
//! data as the oracle; see [`pelage::gpu`]. `--api` and `--adapter` choose the device;
//! `pelage gpu-info` lists the adapters.

use super::Failure;
use clap::Args;
use pelage::scene::Scene;
use std::path::Path;

/// What `pelage render --backend gpu` asks of this module, taken from the render command's
/// arguments by `cli::render` (which calls this module; this module does not look back).
// Without the `gpu` feature only the refusal is built, which reads none of the fields.
#[cfg_attr(not(feature = "gpu"), allow(dead_code))]
pub struct GpuRequest<'a> {
    /// The PNG to write.
    pub output: &'a Path,
    /// `--threads`, for the bake.
    pub threads: Option<u32>,
    /// Whether `--frames` was given (refused: the GPU backend renders single frames).
    pub frames: bool,
    /// `--api`.
    pub api: Option<&'a str>,
    /// `--adapter`.
    pub adapter: Option<&'a str>,
}

#[derive(Args)]
pub struct GpuInfoArgs {
    /// The API whose adapters to list: `vulkan`, `gl`, or `all` (default).
    #[arg(long, value_name = "API", default_value = "all")]
    pub api: String,
}

/// A GPU error as the command's failure: a device that is not there is bad input (exit 2), the
/// same for every command that draws on the GPU (`render`, `bench`, `sweep`).
#[cfg(feature = "gpu")]
pub fn gpu_failure(e: pelage::gpu::GpuError) -> Failure {
    use pelage::gpu::GpuError;
    match e {
        // A device that is not there: bad input (exit 2), one line saying what to install
        // or what exists.
        GpuError::NoAdapter(_) | GpuError::NoGlAdapter(_) | GpuError::Choice(_) => {
            Failure::bad_input(e.to_string())
        }
        _ => Failure::other(e.to_string()),
    }
}

#[cfg(feature = "gpu")]
pub fn run(scene: &Scene, args: &GpuRequest) -> Result<(), Failure> {
    use pelage::gpu::{AdapterChoice, Api, GpuContext, GpuOptions};
    if args.frames {
        return Err(Failure::bad_input(
            "--frames: the GPU backend renders single frames (use --time)",
        ));
    }
    let api = match args.api {
        Some(name) => Api::parse(name).map_err(gpu_failure)?,
        None => Api::default(),
    };
    let choice = args.adapter.map(AdapterChoice::parse).unwrap_or_default();
    let prepared =
        super::with_threads(args.threads, || pelage::render::PreparedScene::new(scene))??;
    let context = GpuContext::open(api, &choice).map_err(gpu_failure)?;
    let image = context
        .render(&prepared, scene.time, &GpuOptions::default())
        .map_err(gpu_failure)?;
    super::write_png(args.output, image.width(), image.height(), image.as_raw())?;
    eprintln!(
        "gpu: {} ({:?}, {:?})",
        context.adapter_info().name,
        context.adapter_info().device_type,
        context.adapter_info().backend
    );
    super::say_written(
        args.output,
        format_args!(
            "{}×{} 8-bit PNG at t = {} s (GPU backend)",
            image.width(),
            image.height(),
            scene.time
        ),
    )
}

#[cfg(feature = "gpu")]
pub fn info(args: GpuInfoArgs) -> Result<(), Failure> {
    use pelage::gpu::{Api, adapters};
    let apis = if args.api.trim().eq_ignore_ascii_case("all") {
        vec![Api::Vulkan, Api::Gl]
    } else {
        vec![Api::parse(&args.api).map_err(gpu_failure)?]
    };
    for api in apis {
        let list = adapters(api);
        let name = match api {
            Api::Vulkan => "vulkan",
            Api::Gl => "gl",
        };
        if list.is_empty() {
            println!("{name}: no adapter");
        }
        for (i, a) in list.iter().enumerate() {
            println!(
                "{name} {i}: {} ({:?}; driver {} {})",
                a.name, a.device_type, a.driver, a.driver_info
            );
        }
    }
    Ok(())
}

#[cfg(not(feature = "gpu"))]
const NO_GPU: &str =
    "this pelage was built without the `gpu` feature (cargo build --release --features gpu)";

#[cfg(not(feature = "gpu"))]
pub fn run(_scene: &Scene, _args: &GpuRequest) -> Result<(), Failure> {
    Err(Failure::bad_input(format!("--backend gpu: {NO_GPU}")))
}

#[cfg(not(feature = "gpu"))]
pub fn info(_args: GpuInfoArgs) -> Result<(), Failure> {
    Err(Failure::bad_input(format!("gpu-info: {NO_GPU}")))
}
