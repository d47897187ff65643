//! The `pelage` command line: render scenes to PNG, benchmark them, sweep their parameters,
//! compare and export for GPU implementations, view them in a window.
//!
//! Exit status: 0 on success, 2 on bad input (scene, mesh, arguments, a scene over a resource
//! limit, an unknown `PELAGE_SIMD` level or `PELAGE_BATCH_LANES` width), 1 on other failures (an output that cannot be written), 101 on a panic (a bug).

mod cli;
#[cfg(feature = "viewer")]
mod view;

use clap::{Parser, Subcommand};
use cli::CommonArgs;
use cli::bench::BenchArgs;
use cli::compare::CompareArgs;
use cli::diagram::DiagramArgs;
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
    /// List the GPU adapters wgpu finds (feature `gpu`): the indices and names `render
    /// --backend gpu --adapter` takes.
    GpuInfo(cli::gpu_render::GpuInfoArgs),
    /// Draw the thesis's strand figures 3.2–3.7 (strand, cones, thickness, slope, shells,
    /// inner and outer part) from the real fur code.
    Diagram(DiagramArgs),
    /// Print a shell completion script (bash, zsh, fish, elvish, powershell) on standard output.
    Completions {
        /// The shell to complete for.
        shell: clap_complete::Shell,
    },
}

/// Exit status of an internal error (a panic: a bug in pelage, never bad input).
const EXIT_BUG: u8 = 101;

/// The pipeline allocates its set-up buffers per draw (tens of MB a frame) and frees them at
/// each flush; glibc's allocator handed that memory back to the kernel and faulted it in again,
/// draw after draw (5.7 % of a frame's CPU time in the kernel on the 100,000-triangle torus).
/// mimalloc keeps it for the next draw (docs/performance.md, "Memory kept between draws").
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// Mesa's Vulkan drivers print `error: XDG_RUNTIME_DIR is invalid or not set in the
/// environment.` twice when a headless run (CI, a container, `ssh` without a login session) has
/// no runtime folder, although nothing is wrong. Without one, pelage points `XDG_RUNTIME_DIR` at
/// a private folder of its own (`$TMPDIR/pelage-runtime-UID`, mode 0700), which Mesa accepts; an
/// existing value is left alone, as is a folder of that name that another user owns or others
/// can read.
#[cfg(all(feature = "gpu", unix))]
fn quiet_runtime_dir() {
    use std::os::unix::fs::{DirBuilderExt, MetadataExt, PermissionsExt};
    let current = std::env::var_os("XDG_RUNTIME_DIR").map(PathBuf::from);
    if current.is_some_and(|dir| dir.is_absolute() && dir.is_dir()) {
        return;
    }
    let Ok(uid) = std::fs::metadata("/proc/self").map(|m| m.uid()) else {
        return;
    };
    let dir = std::env::temp_dir().join(format!("pelage-runtime-{uid}"));
    let _ = std::fs::DirBuilder::new().mode(0o700).create(&dir);
    let ours = std::fs::symlink_metadata(&dir)
        .is_ok_and(|m| m.is_dir() && m.uid() == uid && m.permissions().mode() & 0o077 == 0);
    if ours {
        // SAFETY: called first thing in `main`, before any thread is started (no other thread
        // can read or write the environment at the same time).
        unsafe { std::env::set_var("XDG_RUNTIME_DIR", &dir) };
    }
}

fn main() -> ExitCode {
    // Last line of defence: a panic prints one line, no backtrace, and exits 101. Bad input
    // never gets here; it is answered with its own message and exit status 2.
    std::panic::set_hook(Box::new(|info| {
        let message = info
            .payload()
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| info.payload().downcast_ref::<String>().cloned())
            .unwrap_or_default();
        let location = info
            .location()
            .map(|l| format!(" at {}:{}", l.file(), l.line()))
            .unwrap_or_default();
        let message = message.lines().next().unwrap_or("").to_string();
        eprintln!("error: internal error (a bug in pelage, please report it): {message}{location}");
    }));
    #[cfg(all(feature = "gpu", unix))]
    quiet_runtime_dir();
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => return argument_error(e),
    };
    // An unknown `PELAGE_SIMD` or `PELAGE_BATCH_LANES` is bad input, refused before any work (the library alone would
    // ignore it and run the best level).
    if let Err(e) = pelage::simd::SimdLevel::from_env() {
        eprintln!("error: {e}");
        return ExitCode::from(2);
    }
    if let Err(e) = pelage::simd::wide_batches_from_env() {
        eprintln!("error: {e}");
        return ExitCode::from(2);
    }
    let command = cli.command.unwrap_or(Command::Render(RenderArgs {
        common: CommonArgs::defaults(),
        output: PathBuf::from("pelage.png"),
        depth: 8,
        frames: None,
        fps: 10.0,
        animation: None,
        backend: cli::render::Backend::Cpu,
        api: None,
        adapter: None,
    }));
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| match command {
        Command::Render(args) => cli::render::run(args),
        Command::Bench(args) => cli::bench::run(args),
        Command::Sweep(args) => cli::sweep::run(args),
        Command::SweepMerge(args) => cli::sweep::merge(args),
        Command::Compare(args) => cli::compare::run(args),
        Command::Export(args) => cli::export::run(args),
        Command::View(args) => cli::view::run(args),
        Command::Diagram(args) => cli::diagram::run(args),
        Command::Completions { shell } => completions(shell),
        Command::GpuInfo(args) => cli::gpu_render::info(args),
    }));
    match result {
        Ok(Ok(())) => ExitCode::SUCCESS,
        Ok(Err(f)) => {
            eprintln!("error: {}", f.message);
            ExitCode::from(f.status)
        }
        Err(_) => ExitCode::from(EXIT_BUG),
    }
}

/// The completion script for `shell`, on standard output (a closed pipe is not an error).
fn completions(shell: clap_complete::Shell) -> Result<(), cli::Failure> {
    use clap::CommandFactory;
    let mut script = Vec::new();
    clap_complete::generate(shell, &mut Cli::command(), "pelage", &mut script);
    pelage::output::write_atomic(std::path::Path::new("-"), &script)
        .map_err(|e| cli::Failure::other(e.to_string()))
}

/// Help and version go to stdout as clap prints them; a bad argument is one line on stderr
/// (clap's first line, which names the argument) and exit status 2.
fn argument_error(e: clap::Error) -> ExitCode {
    use clap::error::ErrorKind;
    match e.kind() {
        ErrorKind::DisplayHelp
        | ErrorKind::DisplayVersion
        | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand => {
            let _ = e.print();
            ExitCode::from(u8::try_from(e.exit_code()).unwrap_or(2))
        }
        _ => {
            // clap's message without its usage and tips, on one line.
            let rendered = e.render().to_string();
            let message: Vec<&str> = rendered
                .lines()
                .map(str::trim)
                .take_while(|l| {
                    !(l.starts_with("Usage:")
                        || l.starts_with("tip:")
                        || l.starts_with("For more information"))
                })
                .filter(|l| !l.is_empty())
                .collect();
            let message = message.join(" ");
            let message = message.strip_prefix("error: ").unwrap_or(&message);
            eprintln!("error: {message} (see pelage --help)");
            ExitCode::from(2)
        }
    }
}
