//! `pelage compare A.png B.png`: the metrics of [`pelage::compare`] between a reference (A) and
//! an image under test (B), a heat map of the differences, and an exit status that says whether
//! B is within tolerance of A (0), outside (1), or could not be compared (2).
//!
//! `pelage compare REF_DIR TEST_DIR -o REPORT_DIR`: every image of one folder against the image
//! of the same name in the other ([`pelage::compare::report`]), a report (`report.json`,
//! `report.html`, the images it shows under `images/`), and the same exit status over all
//! pairs (a reference without a capture counts as outside).

use super::Failure;
use clap::Args;
use pelage::compare::legend::{Legend, with_legend};
use pelage::compare::report::{Report, Row, Verdict, pair_names};
use pelage::compare::{Tolerance, compare_images, flip_heat_map, heat_map};
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct CompareArgs {
    /// The reference image (e.g. pelage's render), or a folder of them.
    pub reference: PathBuf,
    /// The image under test (e.g. a GPU capture), or a folder of them (paired by name).
    pub test: PathBuf,
    /// With two folders: the folder the report goes to (report.html, report.json, images/).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Print the metrics as one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
    /// A preset, `exact` (default: every pixel equal) or `gpu` (the README's measured GPU
    /// tier), and/or comma-separated bounds, read left to right: threshold=N (per channel,
    /// 0–255), over=F (fraction of pixels over the threshold), neighbour-over=F, flip-mean=F,
    /// flip-pNN=F (e.g. flip-p99=0.3), psnr=DB. Only the criteria named are checked.
    #[arg(long, default_value = "exact")]
    pub tolerance: String,
    /// Write a heat map of the differences (log scale of the largest channel difference) here,
    /// with its legend below.
    #[arg(long)]
    pub heatmap: Option<PathBuf>,
    /// Write FLIP's error map (magma colours) here, with its legend below.
    #[arg(long)]
    pub flip_map: Option<PathBuf>,
    /// Refuse images whose comparison would need more than this memory (8G, 512M, bytes;
    /// default 8G), estimated from their headers before they are decoded.
    #[arg(long, value_name = "SIZE", value_parser = super::parse_size)]
    pub max_memory: Option<u64>,
}

fn load(path: &Path) -> Result<image::RgbaImage, Failure> {
    pelage::input::read_image(path, "image").map_err(|e| Failure::bad_input(e.to_string()))
}

/// Refuses a pair whose comparison would need more than `max_memory`, from the sizes in the
/// images' headers, before either is decoded.
fn check_pair_memory(
    reference: &Path,
    test: &Path,
    max_memory: Option<u64>,
) -> Result<(), Failure> {
    let size = |path: &Path| {
        pelage::input::image_size(path, "image").map_err(|e| Failure::bad_input(e.to_string()))
    };
    let ((a_size, a_bytes), (b_size, b_bytes)) = (size(reference)?, size(test)?);
    let estimate = pelage::limits::compare_memory(a_size, b_size, a_bytes.saturating_add(b_bytes));
    pelage::limits::check_memory("the comparison", estimate, super::max_memory(max_memory))
        .map_err(|e| {
            super::limit_failure(
                &format!("{} and {}", reference.display(), test.display()),
                e,
            )
        })?;
    Ok(())
}

pub fn run(args: CompareArgs) -> Result<(), Failure> {
    let tolerance =
        Tolerance::parse(&args.tolerance).map_err(|e| Failure::bad_input(format!("--{e}")))?;
    // A path that does not exist is named before anything else is blamed (`-o` among them).
    for path in [&args.reference, &args.test] {
        if !path.exists() {
            return Err(Failure::bad_input(format!(
                "{}: no such image or folder",
                path.display()
            )));
        }
    }
    match (args.reference.is_dir(), args.test.is_dir()) {
        (true, true) => return compare_folders(&args, &tolerance),
        (true, false) | (false, true) => {
            return Err(Failure::bad_input(format!(
                "{} and {}: compare two images or two folders, not one of each",
                args.reference.display(),
                args.test.display()
            )));
        }
        (false, false) => {}
    }
    if let Some(out) = &args.output {
        return Err(Failure::bad_input(format!(
            "-o {}: a report folder is for comparing two folders (use --heatmap for one pair)",
            out.display()
        )));
    }
    for (flag, path) in [("--heatmap", &args.heatmap), ("--flip-map", &args.flip_map)] {
        if let Some(path) = path {
            pelage::output::check_extension(path, "png")
                .map_err(|e| Failure::bad_input(format!("{flag} {e}")))?;
        }
    }
    check_pair_memory(&args.reference, &args.test, args.max_memory)?;
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
        let map = heat_map(&a, &b).expect("sizes checked");
        save(path, with_legend(&map, Legend::Heat))?;
    }
    if let Some(path) = &args.flip_map {
        let map = flip_heat_map(&a, &b).expect("sizes checked");
        save(path, with_legend(&map, Legend::Flip))?;
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

/// The image files of `folder`, by name (hidden files and sub-folders left out).
fn list_images(folder: &Path) -> Result<Vec<String>, Failure> {
    let entries = std::fs::read_dir(folder)
        .map_err(|e| Failure::bad_input(format!("{}: {e}", folder.display())))?;
    let mut names = Vec::new();
    for entry in entries {
        let entry = entry.map_err(|e| Failure::bad_input(format!("{}: {e}", folder.display())))?;
        if !entry.path().is_file() {
            continue;
        }
        match entry.file_name().into_string() {
            Ok(name) if pelage::compare::report::is_image_name(&name) => names.push(name),
            Ok(_) => {}
            Err(name) => eprintln!(
                "warning: {}: {} is not UTF-8; left out",
                folder.display(),
                name.to_string_lossy()
            ),
        }
    }
    names.sort();
    Ok(names)
}

/// One pair of the folder comparison: compared, and its images written to the report.
fn compare_pair(
    args: &CompareArgs,
    tolerance: &Tolerance,
    report: &Path,
    index: usize,
    (name, reference, capture): (String, String, String),
) -> Result<Row, Failure> {
    let mut row = Row {
        name,
        reference: reference.clone(),
        capture: capture.clone(),
        verdict: Verdict::Error,
        error: None,
        comparison: None,
        images: None,
    };
    let (reference_path, capture_path) =
        (args.reference.join(&reference), args.test.join(&capture));
    let loaded = check_pair_memory(&reference_path, &capture_path, args.max_memory)
        .and_then(|()| load(&reference_path))
        .and_then(|a| {
            let b = load(&capture_path)?;
            let c = compare_images(&a, &b, tolerance)
                .map_err(|e| Failure::bad_input(format!("{reference} and {capture}: {e}")))?;
            Ok((a, b, c))
        });
    let (a, b, comparison) = match loaded {
        Ok(v) => v,
        Err(f) => {
            row.error = Some(f.message);
            return Ok(row);
        }
    };
    let images =
        ["reference", "heat", "capture", "flip"].map(|k| format!("images/{index:04}-{k}.png"));
    let heat = with_legend(&heat_map(&a, &b).expect("sizes checked"), Legend::Heat);
    let flip = with_legend(&flip_heat_map(&a, &b).expect("sizes checked"), Legend::Flip);
    for (file, image) in images.iter().zip([&a, &heat, &b, &flip]) {
        super::write_png(
            &report.join(file),
            image.width(),
            image.height(),
            image.as_raw(),
        )?;
    }
    row.verdict = if comparison.passed() {
        Verdict::Pass
    } else {
        Verdict::Fail
    };
    row.comparison = Some(comparison);
    row.images = Some(images);
    Ok(row)
}

/// `pelage compare REF_DIR TEST_DIR -o REPORT_DIR`.
fn compare_folders(args: &CompareArgs, tolerance: &Tolerance) -> Result<(), Failure> {
    let Some(report) = &args.output else {
        return Err(Failure::bad_input(format!(
            "{} and {} are folders: name the report folder with -o REPORT_DIR",
            args.reference.display(),
            args.test.display()
        )));
    };
    if args.heatmap.is_some() || args.flip_map.is_some() || args.json {
        return Err(Failure::bad_input(
            "--heatmap, --flip-map and --json are for one pair; two folders get a report \
             (-o): report.json, report.html and every map",
        ));
    }
    let pairing = pair_names(&list_images(&args.reference)?, &list_images(&args.test)?)
        .map_err(Failure::bad_input)?;
    if report.exists() && !report.is_dir() {
        return Err(Failure::bad_input(format!(
            "-o {}: not a folder",
            report.display()
        )));
    }
    // The report replaces what its folder held: never the images it is about to compare.
    if let Ok(report_at) = std::fs::canonicalize(report) {
        for input in [&args.reference, &args.test] {
            if std::fs::canonicalize(input).is_ok_and(|at| at.starts_with(&report_at)) {
                return Err(Failure::bad_input(format!(
                    "-o {}: holds the compared folder {}, whose images the report would \
                     replace; choose another report folder",
                    report.display(),
                    input.display()
                )));
            }
        }
    }
    std::fs::create_dir_all(report.join("images"))
        .map_err(|e| Failure::other(format!("-o {}: {e}", report.display())))?;
    remove_old_images(&report.join("images"))?;
    let mut rows = Vec::new();
    for (index, pair) in pairing.pairs.into_iter().enumerate() {
        rows.push(compare_pair(args, tolerance, report, index, pair)?);
    }
    let report_data = Report::new(
        args.reference.display().to_string(),
        args.test.display().to_string(),
        tolerance,
        rows,
        pairing.missing,
        pairing.extra,
    );
    let json = serde_json::to_string_pretty(&report_data)
        .map_err(|e| Failure::other(format!("JSON: {e}")))?;
    let write = |name: &str, text: &str| {
        pelage::output::write_atomic(&report.join(name), text.as_bytes())
            .map_err(|e| Failure::other(e.to_string()))
    };
    write("report.json", &json)?;
    write("report.html", &report_data.html())?;
    for row in &report_data.rows {
        let detail = match (&row.comparison, &row.error) {
            (Some(c), _) => format!(
                "FLIP mean {:.5}, PSNR {}, {:.4}% over {}",
                c.flip.mean,
                c.psnr,
                100.0 * c.over_fraction(),
                c.tolerance.channel_threshold
            ),
            (None, Some(e)) => e.clone(),
            (None, None) => String::new(),
        };
        let verdict = match row.verdict {
            Verdict::Pass => "pass ",
            Verdict::Fail => "FAIL ",
            Verdict::Error => "ERROR",
        };
        super::say(format!("{verdict} {}  {detail}", row.name))?;
    }
    for name in &report_data.missing {
        super::say(format!("MISSING {name} (no capture)"))?;
    }
    for name in &report_data.extra {
        super::say(format!("extra {name} (no reference)"))?;
    }
    super::say(format!(
        "{}; report: {}",
        report_data.summary(),
        report.join("report.html").display()
    ))?;
    match report_data.exit_status() {
        0 => Ok(()),
        status => Err(Failure {
            message: format!(
                "{} against {}: {}",
                args.test.display(),
                args.reference.display(),
                report_data.summary()
            ),
            status,
        }),
    }
}

/// Removes the images a previous report wrote (`NNNN-reference.png` and the like), so that a
/// report folder used again holds only this report's; other files are left alone.
fn remove_old_images(folder: &Path) -> Result<(), Failure> {
    let entries = std::fs::read_dir(folder)
        .map_err(|e| Failure::other(format!("{}: {e}", folder.display())))?;
    for entry in entries.filter_map(Result::ok) {
        let name = entry.file_name().to_string_lossy().into_owned();
        let ours = name.split_once('-').is_some_and(|(n, kind)| {
            n.len() == 4
                && n.bytes().all(|b| b.is_ascii_digit())
                && ["reference.png", "heat.png", "capture.png", "flip.png"].contains(&kind)
        });
        if ours {
            std::fs::remove_file(entry.path())
                .map_err(|e| Failure::other(format!("{}: {e}", entry.path().display())))?;
        }
    }
    Ok(())
}
