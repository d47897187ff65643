//! `pelage render --backend gpu`: one frame drawn by wgpu (feature `gpu`) from the same baked
//! data as the oracle; see [`pelage::gpu`].

use super::Failure;
use super::render::RenderArgs;
use pelage::scene::Scene;

#[cfg(feature = "gpu")]
pub fn run(scene: &Scene, args: &RenderArgs) -> Result<(), Failure> {
    use pelage::gpu::{AdapterChoice, GpuContext, GpuOptions};
    if args.frames.is_some() {
        return Err(Failure::bad_input(
            "--frames: the GPU backend renders single frames (use --time)",
        ));
    }
    let prepared = super::with_threads(args.common.threads, || {
        pelage::render::PreparedScene::new(scene)
    })??;
    let context =
        GpuContext::new(AdapterChoice::default()).map_err(|e| Failure::other(e.to_string()))?;
    let image = context
        .render(&prepared, scene.time, &GpuOptions::default())
        .map_err(|e| Failure::other(e.to_string()))?;
    super::write_png(&args.output, image.width(), image.height(), image.as_raw())?;
    eprintln!(
        "gpu: {} ({:?})",
        context.adapter_info().name,
        context.adapter_info().device_type
    );
    Ok(())
}

#[cfg(not(feature = "gpu"))]
pub fn run(_scene: &Scene, _args: &RenderArgs) -> Result<(), Failure> {
    Err(Failure::bad_input(
        "--backend gpu: this pelage was built without the `gpu` feature (cargo build --release --features gpu)",
    ))
}
