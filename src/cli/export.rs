//! `pelage export SCENE -o DIR/`: everything a GPU implementation needs to draw the same frame
//! (textures, meshes, parameters, the oracle's render); see [`pelage::export`]. The folder is
//! written whole or not at all ([`StagedFolder`]).

use super::staged::{EntryRule, StagedFolder};
use super::{CommonArgs, Failure, check_workload, load_scene, spinner, with_threads};
use clap::Args;
use pelage::export::{ExportError, export};
use pelage::render::PreparedScene;
use std::path::PathBuf;

#[derive(Args)]
pub struct ExportArgs {
    #[command(flatten)]
    pub common: CommonArgs,
    /// The folder to write: created, or replaced when it holds a previous export only.
    #[arg(short, long)]
    pub output: PathBuf,
}

pub fn run(args: ExportArgs) -> Result<(), Failure> {
    let scene = load_scene(&args.common)?;
    check_workload(
        &scene,
        &args.common,
        pelage::limits::Workload {
            export: true,
            ..pelage::limits::Workload::default()
        },
    )?;
    let folder = StagedFolder::create(&args.output, export_folder_entries())?;
    let dir = folder.path().to_path_buf();
    let summary = with_threads(args.common.threads, || {
        let bar = spinner("baking fur textures");
        let prepared = PreparedScene::new(&scene)
            .map_err(|e| super::render_failure(e, &scene, &super::scene_name(&args.common)))?;
        bar.set_message("exporting");
        let result = export(&prepared, scene.time, &dir).map_err(|e| match e {
            ExportError::Render(e) => Failure::from(e),
            e @ ExportError::Write { .. } => Failure::other(e.to_string()),
        });
        bar.finish_and_clear();
        result
    })??;
    folder.commit()?;
    super::say(format!(
        "{}: {} files (scene.json, oracle.png, meshes/fur.gltf, {}textures/{})",
        args.output.display(),
        summary.files.len(),
        if summary
            .files
            .iter()
            .any(|f| f.as_path() == std::path::Path::new("meshes/character.gltf"))
        {
            "meshes/character.gltf, meshes/joints.json, "
        } else {
            ""
        },
        if cfg!(feature = "gpu") {
            ", shaders/"
        } else {
            ""
        }
    ))?;
    Ok(())
}

/// What a previous export holds at its top level.
fn export_folder_entries() -> EntryRule {
    EntryRule {
        accepts: Box::new(|name: &str| {
            matches!(
                name,
                "scene.json" | "oracle.png" | "meshes" | "textures" | "shaders"
            )
        }),
        what: "part of a previous export",
    }
}
