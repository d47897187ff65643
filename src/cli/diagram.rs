//! `pelage diagram`: the thesis's strand-construction figures 3.2–3.7 drawn from the real fur
//! code (see [`pelage::fur::Figure`]), one PNG per figure.

use super::{Failure, write_png};
use clap::Args;
use pelage::fur::{DiagramOptions, Figure, MAX_DIAGRAM_RESOLUTION, draw_diagram};
use std::path::{Path, PathBuf};

#[derive(Args)]
#[command(group(clap::ArgGroup::new("which").required(true).args(["figure", "all"])))]
pub struct DiagramArgs {
    /// The thesis figure to draw: 3.2, 3.3, 3.4, 3.5, 3.6 or 3.7 (also 3-4, fig-3-4).
    #[arg(long, value_parser = parse_figure)]
    pub figure: Option<Figure>,
    /// Draw every figure into the folder -o (default diagrams/), as fig-3-2.png ... fig-3-7.png.
    #[arg(long)]
    pub all: bool,
    /// The PNG to write (default fig-3-N.png), or with --all the folder (created if missing).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Seed of the strand generator (default: the embedded scene's seed).
    #[arg(long, allow_negative_numbers = true)]
    pub seed: Option<u32>,
    /// Bézier segments per strand, instead of the figure's default.
    #[arg(long, allow_negative_numbers = true,
          value_parser = clap::value_parser!(u32).range(1..=i64::from(MAX_DIAGRAM_RESOLUTION)))]
    pub strand_resolution: Option<u32>,
    /// Facets around each cone, instead of 10.
    #[arg(long, allow_negative_numbers = true,
          value_parser = clap::value_parser!(u32).range(3..=i64::from(MAX_DIAGRAM_RESOLUTION)))]
    pub circle_resolution: Option<u32>,
}

fn parse_figure(name: &str) -> Result<Figure, String> {
    Figure::parse(name).ok_or_else(|| {
        let numbers: Vec<&str> = Figure::ALL.iter().map(|f| f.number()).collect();
        format!(
            "no diagram of thesis figure {name:?}; choose one of {}",
            numbers.join(", ")
        )
    })
}

pub fn run(args: DiagramArgs) -> Result<(), Failure> {
    let seed = match args.seed {
        Some(seed) => seed,
        None => {
            pelage::scene::Scene::embedded_default()
                .map_err(|e| Failure::other(e.to_string()))?
                .seed
        }
    };
    let options = DiagramOptions {
        seed,
        strand_resolution: args.strand_resolution,
        circle_resolution: args.circle_resolution,
    };
    let draw = |figure: Figure, path: &Path| -> Result<(), Failure> {
        let image = draw_diagram(figure, &options)
            .map_err(|e| Failure::bad_input(format!("figure {}: {e}", figure.number())))?;
        write_png(path, image.width(), image.height(), image.as_raw())?;
        super::say(path.display())?;
        Ok(())
    };
    match args.figure {
        Some(figure) => {
            let path = args
                .output
                .unwrap_or_else(|| PathBuf::from(figure.file_name()));
            pelage::output::check_extension(&path, "png")
                .map_err(|e| Failure::bad_input(format!("-o {e}")))?;
            draw(figure, &path)
        }
        None => {
            let dir = args.output.unwrap_or_else(|| PathBuf::from("diagrams"));
            std::fs::create_dir_all(&dir).map_err(|e| {
                Failure::other(format!("{}: cannot create the folder: {e}", dir.display()))
            })?;
            for figure in Figure::ALL {
                draw(figure, &dir.join(figure.file_name()))?;
            }
            Ok(())
        }
    }
}
