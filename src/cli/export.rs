//! `pelage export SCENE -o DIR/`: everything a GPU implementation needs to draw the same frame
//! (textures, meshes, parameters, the oracle's render); see [`pelage::export`].

use super::{CommonArgs, Failure, load_scene, spinner, with_threads};
use clap::Args;
use pelage::export::{ExportError, export};
use pelage::render::PreparedScene;
use std::path::PathBuf;

#[derive(Args)]
pub struct ExportArgs {
    #[command(flatten)]
    pub common: CommonArgs,
    /// The folder to write (created if missing).
    #[arg(short, long)]
    pub output: PathBuf,
}

pub fn run(args: ExportArgs) -> Result<(), Failure> {
    let scene = load_scene(&args.common)?;
    let dir = args.output.clone();
    let summary = with_threads(args.common.threads, || {
        let bar = spinner("baking fur textures");
        let prepared = PreparedScene::new(&scene).map_err(Failure::from)?;
        bar.set_message("exporting");
        let result = export(&prepared, scene.time, &dir).map_err(|e| match e {
            ExportError::Render(e) => Failure::from(e),
            e @ ExportError::Write { .. } => Failure::other(e.to_string()),
        });
        bar.finish_and_clear();
        result
    })??;
    println!(
        "{}: {} files (scene.json, oracle.png, meshes/fur.gltf, textures/)",
        args.output.display(),
        summary.files.len()
    );
    Ok(())
}
