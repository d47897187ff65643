//! The `pelage` command line: render scenes to PNG, benchmark them, view them in a window.
//!
//! Exit status: 0 on success, 2 on bad input (scene, mesh, arguments), 1 on other failures
//! (an output that cannot be written).

mod cli;
#[cfg(feature = "viewer")]
mod view;

use clap::{Parser, Subcommand};
use cli::CommonArgs;
use cli::bench::BenchArgs;
use cli::render::RenderArgs;
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
    }));
    let result = match command {
        Command::Render(args) => cli::render::run(args),
        Command::Bench(args) => cli::bench::run(args),
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
