//! `pelage compare A.png B.png`: the metrics of [`pelage::compare`] between a reference (A) and
//! an image under test (B), a heat map of the differences, and an exit status that says whether
//! B is within tolerance of A (0), outside (1), or could not be compared (2).

use super::Failure;
use clap::Args;
use pelage::compare::{Tolerance, compare_images, flip_heat_map, heat_map};
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct CompareArgs {
    /// The reference image (e.g. pelage's render).
    pub reference: PathBuf,
    /// The image under test (e.g. a GPU capture).
    pub test: PathBuf,
    /// Print the metrics as one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
    /// A preset, `exact` (default: every pixel equal) or `gpu` (the README's measured GPU
    /// tier), and/or comma-separated bounds, read left to right: threshold=N (per channel,
    /// 0–255), over=F (fraction of pixels over the threshold), neighbour-over=F, flip-mean=F,
    /// flip-pNN=F (e.g. flip-p99=0.3), psnr=DB. Only the criteria named are checked.
    #[arg(long, default_value = "exact")]
    pub tolerance: String,
    /// Write a heat map of the differences (log scale of the largest channel difference) here.
    #[arg(long)]
    pub heatmap: Option<PathBuf>,
    /// Write FLIP's error map (magma colours) here.
    #[arg(long)]
    pub flip_map: Option<PathBuf>,
}

fn load(path: &Path) -> Result<image::RgbaImage, Failure> {
    pelage::input::read_image(path, "image").map_err(|e| Failure::bad_input(e.to_string()))
}

pub fn run(args: CompareArgs) -> Result<(), Failure> {
    let tolerance =
        Tolerance::parse(&args.tolerance).map_err(|e| Failure::bad_input(format!("--{e}")))?;
    let a = load(&args.reference)?;
    let b = load(&args.test)?;
    let comparison = compare_images(&a, &b, &tolerance).map_err(|e| {
        Failure::bad_input(format!(
            "{} and {}: {e}",
            args.reference.display(),
            args.test.display()
        ))
    })?;
    let save = |path: &Path, image: image::RgbaImage| {
        super::write_png(path, image.width(), image.height(), image.as_raw())
    };
    if let Some(path) = &args.heatmap {
        save(path, heat_map(&a, &b).expect("sizes checked"))?;
    }
    if let Some(path) = &args.flip_map {
        save(path, flip_heat_map(&a, &b).expect("sizes checked"))?;
    }
    if args.json {
        let json = serde_json::to_string_pretty(&comparison)
            .map_err(|e| Failure::other(format!("JSON: {e}")))?;
        super::say(json)?;
    } else {
        super::say(&comparison)?;
    }
    if comparison.passed() {
        Ok(())
    } else {
        Err(Failure::other(format!(
            "{} differs from {} beyond the tolerance: {}",
            args.test.display(),
            args.reference.display(),
            comparison.failures.join("; ")
        )))
    }
}
