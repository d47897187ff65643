//! The `pelage` command line: render scenes to PNG, benchmark them, sweep their parameters,
//! compare and export for GPU implementations, view them in a window.
//!
//! Exit status: 0 on success, 2 on bad input (scene, mesh, arguments), 1 on other failures
//! (an output that cannot be written).

mod cli;
#[cfg(feature = "viewer")]
mod view;

use clap::{Parser, Subcommand};
use cli::CommonArgs;
use cli::bench::BenchArgs;
use cli::compare::CompareArgs;
use cli::export::ExportArgs;
use cli::render::RenderArgs;
use cli::sweep::{MergeArgs, SweepArgs};
use cli::view::ViewArgs;
use std::path::PathBuf;
use std::process::ExitCode;

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
    /// Run a parameter sweep (thesis tables 4.1–4.6): results.csv, contact sheet, fps plot.
    Sweep(SweepArgs),
    /// Merge the folders of sweep shards (--shard I/N) into one sweep folder.
    SweepMerge(MergeArgs),
    /// Compare two images (reference, test): metrics, heat map, exit 1 outside the tolerance.
    Compare(CompareArgs),
    /// Export textures, meshes, parameters and the oracle's render for a GPU implementation.
    Export(ExportArgs),
    /// Show a scene in a window, moving: orbit, toggle effects, tune the fur (h: keys).
    View(ViewArgs),
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
        backend: cli::render::Backend::Cpu,
    }));
    let result = match command {
        Command::Render(args) => cli::render::run(args),
        Command::Bench(args) => cli::bench::run(args),
        Command::Sweep(args) => cli::sweep::run(args),
        Command::SweepMerge(args) => cli::sweep::merge(args),
        Command::Compare(args) => cli::compare::run(args),
        Command::Export(args) => cli::export::run(args),
        Command::View(args) => cli::view::run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(f) => {
            eprintln!("error: {}", f.message);
            ExitCode::from(f.status)
        }
    }
}
