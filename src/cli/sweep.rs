//! `pelage sweep`: the thesis's chapter 4 experiments. Every point of the parameter product is
//! baked, rendered `--frames` times and timed; the folder gets `point_NNNN.png` per point,
//! `results.csv`, `contact_sheet.png` and the plots (`fps.png`, `frame_time.png`,
//! `fragments.png`). `pelage sweep-merge` joins shards.

use super::render::Backend;
use super::staged::{EntryRule, StagedFolder};
use super::{CommonArgs, Failure, apply_overrides, progress, scene_source, with_threads};
use clap::Args;
use pelage::render::PreparedScene;
use pelage::sweep::{self, ResultRow, ShardChoice, SweepParameter};
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Args)]
pub struct SweepArgs {
    #[command(flatten)]
    pub common: CommonArgs,
    /// NAME=V1,V2,...: a thesis parameter (model_resolution, number_of_shells,
    /// texture_resolution, number_of_strands, strand_resolution, circle_resolution,
    /// specular_tangents, shadow_divisor, number_of_spots, camera_distance, time/burn_time) or any
    /// dotted scene key (fur.model_difference, light.direction, ...). Repeat for a product.
    #[arg(long = "param", required = true)]
    pub params: Vec<String>,
    /// Output folder.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Frames timed per point (the median is reported).
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub frames: u32,
    /// Run only shard I of N (1-based): the points whose number is I − 1 modulo N. `auto`
    /// reads I and N from the job array that started pelage: Slurm (SLURM_ARRAY_TASK_ID,
    /// _MIN, _COUNT), AWS Batch (AWS_BATCH_JOB_ARRAY_INDEX, _SIZE), or a Kubernetes Indexed Job
    /// (JOB_COMPLETION_INDEX), which does not tell the count: give it as `auto/N`.
    #[arg(long, value_name = "I/N|auto|auto/N")]
    pub shard: Option<String>,
    /// Which renderer draws and is timed: the CPU oracle, or wgpu (built with `--features gpu`).
    #[arg(long, value_enum, default_value_t = Backend::Cpu)]
    pub backend: Backend,
    /// With `--backend gpu`: also render every point with the oracle and add the comparison's
    /// metrics to results.csv (and a heat map with its legend, `point_NNNN_diff.png`).
    #[arg(long)]
    pub against_oracle: bool,
    /// The tolerance `--against-oracle` judges by (see `pelage compare --tolerance`).
    #[arg(long, default_value = pelage::compare::GPU_TOLERANCE)]
    pub tolerance: String,
}

#[derive(Args)]
pub struct MergeArgs {
    /// Output folder for the merged results.csv, contact sheet and plot.
    #[arg(short, long)]
    pub output: PathBuf,
    /// The shards' output folders (each with its results.csv and point PNGs).
    #[arg(required = true)]
    pub shards: Vec<PathBuf>,
    /// Refuse a contact sheet whose memory estimate exceeds this size (8G, 512M, bytes;
    /// default 8G).
    #[arg(long, value_name = "SIZE", value_parser = super::parse_size)]
    pub max_memory: Option<u64>,
}

pub fn run(args: SweepArgs) -> Result<(), Failure> {
    let bad = |e: sweep::SweepError| Failure::bad_input(e.0);
    let parameters: Vec<SweepParameter> = args
        .params
        .iter()
        .map(|p| SweepParameter::parse(p))
        .collect::<Result<_, _>>()
        .map_err(bad)?;
    let shard = match args.shard.as_deref() {
        None => None,
        Some(text) => {
            let env = |name: &str| std::env::var_os(name).map(|v| v.to_string_lossy().into_owned());
            let (shard, from) = ShardChoice::parse(text)
                .and_then(|c| c.resolve(&env))
                .map_err(bad)?;
            if let Some(from) = from {
                eprintln!(
                    "pelage sweep: --shard {text} is shard {}/{} ({}: {})",
                    shard.index,
                    shard.count,
                    from.scheduler.name(),
                    from.variables
                );
            }
            Some(shard)
        }
    };
    let points = sweep::sweep_points(&parameters).map_err(bad)?;
    if args.against_oracle && args.backend != Backend::Gpu {
        return Err(Failure::bad_input(
            "--against-oracle compares the GPU backend with the oracle: add --backend gpu",
        ));
    }
    let tolerance = pelage::compare::Tolerance::parse(&args.tolerance)
        .map_err(|e| Failure::bad_input(format!("--tolerance: {e}")))?;
    let renderer = Renderer::new(args.backend)?;
    let (text, name, base_dir) = scene_source(&args.common)?;
    // Every point is checked before any is rendered, so a bad value fails at once.
    let mut scenes = Vec::new();
    for point in points
        .iter()
        .filter(|p| shard.is_none_or(|s| s.runs(p.index)))
    {
        let mut scene = sweep::scene_at(&text, &name, &base_dir, point).map_err(bad)?;
        apply_overrides(&mut scene, &args.common, &name)?;
        scenes.push((point.clone(), scene));
    }
    // So is every point's memory and bake work, and the contact sheet's memory: nothing is
    // rendered when one would not fit.
    for (point, scene) in &scenes {
        super::check_workload(scene, &args.common, pelage::limits::Workload::default()).map_err(
            |f| Failure {
                message: format!("point {} ({}): {}", point.index, point.label(), f.message),
                ..f
            },
        )?;
    }
    let sizes: Vec<(u32, u32)> = scenes
        .iter()
        .map(|(_, s)| (s.image.width, s.image.height))
        .collect();
    let max_memory = super::max_memory(args.common.max_memory);
    check_sheet(&sizes, parameters.len() + 1, max_memory, &name)?;
    let manifest = sweep::Manifest {
        id: sweep_identity(&args, &text),
        points: points.len(),
        shard,
    };
    // Written whole into a staging folder, then renamed: an earlier sweep's folder is replaced,
    // never mixed with this one's files.
    let folder = StagedFolder::create(&args.output, sweep_folder_entries())?;
    let tile = args.common.tile;
    let frames = args.frames;
    let output = folder.path().to_path_buf();
    let against_oracle = args.against_oracle;
    let scene_label = name.clone();
    let rows = with_threads(
        args.common.threads,
        || -> Result<Vec<ResultRow>, Failure> {
            let bar = progress(scenes.len() as u64);
            let mut rows = Vec::new();
            for (point, scene) in &scenes {
                bar.set_message(point.label());
                let start = Instant::now();
                let prepared = PreparedScene::new(scene)
                    .map_err(|e| super::render_failure(e, scene, &scene_label))?;
                let bake_ms = start.elapsed().as_secs_f64() * 1e3;
                let mut times = Vec::new();
                let mut last = None;
                for _ in 0..frames {
                    let t = Instant::now();
                    let image = renderer.render(&prepared, scene.time, tile)?;
                    times.push(t.elapsed().as_secs_f64() * 1e3);
                    last = Some(image);
                }
                let Some((image, fragments_shaded)) = last else {
                    return Err(Failure::other("no frame was rendered"));
                };
                let mut extra = Vec::new();
                if against_oracle {
                    let oracle = prepared.render(tile)?;
                    let oracle =
                        image::RgbaImage::from_raw(oracle.width, oracle.height, oracle.rgba8)
                            .ok_or_else(|| {
                                Failure::other("the oracle's image has the wrong size")
                            })?;
                    let c = pelage::compare::compare_images(&oracle, &image, &tolerance)
                        .map_err(|e| Failure::other(e.to_string()))?;
                    extra = oracle_columns(&c);
                    let heat = pelage::compare::heat_map(&oracle, &image)
                        .map_err(|e| Failure::other(e.to_string()))?;
                    let heat = pelage::compare::legend::with_legend(
                        &heat,
                        pelage::compare::legend::Legend::Heat,
                    );
                    super::write_png(
                        &output.join(diff_file(point.index)),
                        heat.width(),
                        heat.height(),
                        &heat,
                    )?;
                }
                super::write_png(
                    &output.join(point_file(point.index)),
                    image.width(),
                    image.height(),
                    &image,
                )?;
                times.sort_by(f64::total_cmp);
                let median = times[times.len() / 2];
                rows.push(ResultRow {
                    point: point.index,
                    values: point.values.iter().map(|(_, v)| v.clone()).collect(),
                    bake_ms,
                    median_frame_ms: median,
                    min_frame_ms: times[0],
                    max_frame_ms: times[times.len() - 1],
                    // A frame under a nanosecond (a coarse clock) counts as one: the rate
                    // stays finite, as results.csv requires.
                    fps: 1e3 / median.max(1e-6),
                    fragments_shaded,
                    extra,
                });
                bar.inc(1);
            }
            bar.finish_and_clear();
            Ok(rows)
        },
    )??;
    let names: Vec<String> = parameters.iter().map(|p| p.name.clone()).collect();
    write_summary(&output, &names, &rows, &manifest, max_memory)?;
    folder.commit()
}

/// What decides a sweep's points and images, hashed into its `sweep.txt` id: shards of one
/// sweep share it, a sweep of another scene or other values does not.
fn sweep_identity(args: &SweepArgs, scene_text: &str) -> u64 {
    let overrides = format!(
        "{:?} {:?} {:?} {} {:?} {}",
        args.common.width,
        args.common.height,
        args.common.time.map(f32::to_bits),
        args.frames,
        args.backend,
        args.against_oracle
    );
    sweep::sweep_id(
        std::iter::once(scene_text)
            .chain(args.params.iter().map(String::as_str))
            .chain(std::iter::once(overrides.as_str())),
    )
}

/// What a sweep folder holds at its top level (a previous sweep's folder may be replaced).
fn sweep_folder_entries() -> EntryRule {
    EntryRule {
        accepts: Box::new(|name: &str| {
            let point = |rest: &str| {
                rest.strip_prefix("point_").is_some_and(|digits| {
                    digits.len() >= 4 && digits.bytes().all(|b| b.is_ascii_digit())
                })
            };
            matches!(
                name,
                "results.csv" | "contact_sheet.png" | sweep::MANIFEST_FILE
            ) || sweep::Metric::ALL.iter().any(|m| m.file_name() == name)
                || name
                    .strip_suffix("_diff.png")
                    .or_else(|| name.strip_suffix(".png"))
                    .is_some_and(point)
        }),
        what: "part of a previous sweep",
    }
}

pub fn merge(args: MergeArgs) -> Result<(), Failure> {
    let bad = |e: sweep::SweepError| Failure::bad_input(e.0);
    let mut files = Vec::new();
    let mut shards = Vec::new();
    for dir in &args.shards {
        let path = dir.join("results.csv");
        let text =
            pelage::input::read_text(&path, pelage::input::MAX_TABLE_BYTES, "shard's results")
                .map_err(|e| Failure::bad_input(e.to_string()))?;
        let name = path.display().to_string();
        let results = sweep::parse_results(&text, &name).map_err(bad)?;
        let manifest_path = dir.join(sweep::MANIFEST_FILE);
        let manifest_text = pelage::input::read_text(&manifest_path, 4096, "sweep manifest")
            .map_err(|e| {
                Failure::bad_input(format!(
                    "{e} (every sweep folder has one since this version: run the shard again)"
                ))
            })?;
        let manifest = sweep::Manifest::parse(&manifest_text, &manifest_path.display().to_string())
            .map_err(bad)?;
        shards.push((
            dir.display().to_string(),
            manifest,
            results.rows.iter().map(|r| r.point).collect::<Vec<_>>(),
        ));
        files.push((name, text));
    }
    sweep::check_shards(&shards).map_err(bad)?;
    let merged = sweep::merge_results(&files).map_err(bad)?;
    // Each point's images come from the shard that holds its row, checked before anything is
    // written: each must be there, be an image, and lie inside its shard.
    let mut holder = std::collections::HashMap::new();
    for (index, (_, _, points)) in shards.iter().enumerate() {
        holder.extend(points.iter().map(|&p| (p, index)));
    }
    let with_diff = !merged.extra_columns.is_empty();
    let mut copies = Vec::new();
    for row in &merged.rows {
        let dir = &args.shards[holder[&row.point]];
        let mut names = vec![point_file(row.point)];
        if with_diff {
            names.push(diff_file(row.point));
        }
        for name in names {
            copies.push((point_image(dir, &name, row.point)?, name));
        }
    }
    let manifest = sweep::Manifest {
        shard: None,
        ..shards[0].1.clone()
    };
    let folder = StagedFolder::create(&args.output, sweep_folder_entries())?;
    let output = folder.path().to_path_buf();
    // The point renders come along, so the merged folder is a whole sweep.
    for (source, name) in copies {
        let bytes =
            pelage::input::read(&source, pelage::input::MAX_IMAGE_FILE_BYTES, "point image")
                .map_err(|e| Failure::bad_input(e.to_string()))?;
        pelage::output::write_atomic(&output.join(&name), &bytes)
            .map_err(|e| Failure::other(e.to_string()))?;
    }
    write_summary(
        &output,
        &merged.parameters,
        &merged.rows,
        &manifest,
        super::max_memory(args.max_memory),
    )?;
    folder.commit()
}

/// The image `name` of point `point` in the shard folder `dir`, checked for merging: it exists,
/// its header reads as an image, and it resolves to a file inside the shard (a link to a file
/// elsewhere would copy that file's bytes into the merged sweep).
fn point_image(dir: &Path, name: &str, point: usize) -> Result<std::path::PathBuf, Failure> {
    let path = dir.join(name);
    let fail = |why: String| {
        Failure::bad_input(format!(
            "{}: point {point}'s image {why}; run that shard again",
            path.display()
        ))
    };
    let resolved = path.canonicalize().map_err(|e| match e.kind() {
        std::io::ErrorKind::NotFound => fail("is missing".into()),
        _ => fail(format!("cannot be read: {e}")),
    })?;
    let shard = dir
        .canonicalize()
        .map_err(|e| fail(format!("cannot be read: {e}")))?;
    if !resolved.starts_with(&shard) {
        return Err(fail(format!(
            "is a link to {}, outside the shard",
            resolved.display()
        )));
    }
    pelage::input::image_size(&resolved, "point image")
        .map_err(|e| fail(format!("is not an image ({})", e.message)))?;
    Ok(resolved)
}

/// Refuses a contact sheet of renders of `sizes`, labelled with `label_lines` lines each, that
/// would need more memory than `max_memory` (see [`pelage::limits::contact_sheet_memory`]);
/// `name` says whose sheet it is.
fn check_sheet(
    sizes: &[(u32, u32)],
    label_lines: usize,
    max_memory: u64,
    name: &str,
) -> Result<(), Failure> {
    let Some(layout) = sweep::SheetLayout::new(sizes, label_lines) else {
        return Ok(());
    };
    let (w, h) = layout.sheet_size();
    let thumbnails = sizes.iter().fold(0u64, |sum, &size| {
        let (w, h) = layout.thumbnail_size(size);
        sum.saturating_add(u64::from(w) * u64::from(h))
    });
    let largest = sizes
        .iter()
        .map(|&(w, h)| u64::from(w) * u64::from(h))
        .max()
        .unwrap_or(0);
    let estimate = pelage::limits::contact_sheet_memory(w.saturating_mul(h), thumbnails, largest);
    pelage::limits::check_memory("the contact sheet", estimate, max_memory)
        .map(|_| ())
        .map_err(|e| {
            let flag = "--max-memory";
            Failure::bad_input(format!(
                "{name}: {e} ({} points in a {w}×{h} sheet); raise the limit with {flag} or \
                 sweep fewer points",
                sizes.len()
            ))
        })
}

/// The metrics `--against-oracle` adds to a row.
fn oracle_columns(c: &pelage::compare::Comparison) -> Vec<(String, String)> {
    let max_rgb = c.max_abs_error[..3].iter().copied().max().unwrap_or(0);
    [
        (
            "oracle_exact_pct",
            format!(
                "{:.3}",
                100.0 * c.exact_pixels as f64 / c.pixels.max(1) as f64
            ),
        ),
        ("oracle_max_error", max_rgb.to_string()),
        (
            "oracle_psnr_db",
            if c.psnr.0.is_finite() {
                format!("{:.2}", c.psnr.0)
            } else {
                "inf".into()
            },
        ),
        (
            "oracle_over_threshold_pct",
            format!("{:.4}", 100.0 * c.over_fraction()),
        ),
        ("oracle_flip_mean", format!("{:.5}", c.flip.mean)),
        ("oracle_flip_p99", format!("{:.5}", c.flip.p99)),
        ("oracle_within_tolerance", c.passed().to_string()),
    ]
    .into_iter()
    .map(|(n, v)| (n.to_string(), v))
    .collect()
}

/// The renderer a sweep times: the oracle, or one GPU context for the whole sweep.
enum Renderer {
    Cpu,
    #[cfg(feature = "gpu")]
    Gpu(Box<pelage::gpu::GpuContext>),
}

impl Renderer {
    fn new(backend: Backend) -> Result<Self, Failure> {
        match backend {
            Backend::Cpu => Ok(Renderer::Cpu),
            #[cfg(feature = "gpu")]
            Backend::Gpu => pelage::gpu::GpuContext::new(pelage::gpu::AdapterChoice::default())
                .map(|c| Renderer::Gpu(Box::new(c)))
                .map_err(super::gpu_render::gpu_failure),
            #[cfg(not(feature = "gpu"))]
            Backend::Gpu => Err(Failure::bad_input(
                "--backend gpu: this pelage was built without the `gpu` feature (cargo build --release --features gpu)",
            )),
        }
    }

    /// One frame and the fragments the oracle shaded for it (0 on the GPU, which does not say).
    fn render(
        &self,
        prepared: &PreparedScene,
        time: f32,
        tile: u32,
    ) -> Result<(image::RgbaImage, u64), Failure> {
        match self {
            Renderer::Cpu => {
                let image = prepared.render_at(time, tile)?;
                let fragments = image.stats.fragments_shaded;
                let rgba = image::RgbaImage::from_raw(image.width, image.height, image.rgba8)
                    .ok_or_else(|| Failure::other("the rendered image has the wrong size"))?;
                Ok((rgba, fragments))
            }
            #[cfg(feature = "gpu")]
            Renderer::Gpu(context) => context
                .render(prepared, time, &pelage::gpu::GpuOptions::default())
                .map(|image| (image, 0))
                .map_err(|e| Failure::other(e.to_string())),
        }
    }
}

fn point_file(index: usize) -> String {
    format!("point_{index:04}.png")
}

/// The heat map against the oracle of point `index` (`--against-oracle`).
fn diff_file(index: usize) -> String {
    format!("point_{index:04}_diff.png")
}

/// results.csv, the contact sheet (from the point PNGs in `dir`) and the fps plot. The sheet's
/// memory is checked against `max_memory` from the images' headers, and each image is scaled
/// to its thumbnail as soon as it is read, so only the thumbnails are held.
fn write_summary(
    dir: &Path,
    names: &[String],
    rows: &[ResultRow],
    manifest: &sweep::Manifest,
    max_memory: u64,
) -> Result<(), Failure> {
    pelage::output::write_atomic(
        &dir.join(sweep::MANIFEST_FILE),
        manifest.to_text().as_bytes(),
    )
    .map_err(|e| Failure::other(e.to_string()))?;
    let csv = sweep::write_results(names, rows).map_err(|e| Failure::other(e.0))?;
    pelage::output::write_atomic(&dir.join("results.csv"), csv.as_bytes())
        .map_err(|e| Failure::other(e.to_string()))?;
    // Each thumbnail is labelled with the values that differ between points (all of them when
    // there is only one point) and its frame rate and time.
    let differing: Vec<usize> = (0..names.len())
        .filter(|&i| rows.iter().any(|r| r.values[i] != rows[0].values[i]))
        .collect();
    let labelled: Vec<usize> = if differing.is_empty() {
        (0..names.len()).collect()
    } else {
        differing
    };
    let mut found = Vec::new();
    for row in rows {
        let path = dir.join(point_file(row.point));
        match pelage::input::image_size(&path, "point image") {
            Ok((size, _)) => found.push((row, path, size)),
            Err(_) => eprintln!(
                "warning: {}: missing or unreadable, left off the contact sheet",
                path.display()
            ),
        }
    }
    let sizes: Vec<(u32, u32)> = found.iter().map(|&(_, _, size)| size).collect();
    let label_lines = labelled.len() + 1;
    check_sheet(&sizes, label_lines, max_memory, &dir.display().to_string())?;
    let mut cells = Vec::new();
    if let Some(layout) = sweep::SheetLayout::new(&sizes, label_lines) {
        for (row, path, _) in found {
            let Ok(image) = pelage::input::read_image(&path, "point image") else {
                eprintln!(
                    "warning: {}: missing or unreadable, left off the contact sheet",
                    path.display()
                );
                continue;
            };
            let thumbnail = layout.thumbnail(&image).into_owned();
            drop(image);
            let mut label: Vec<String> = labelled
                .iter()
                .map(|&i| format!("{} = {}", names[i], row.values[i]))
                .collect();
            label.push(format!(
                "{:.2} fps, {:.1} ms a frame",
                row.fps, row.median_frame_ms
            ));
            cells.push((thumbnail, label));
        }
    }
    if let Some(sheet) = sweep::contact_sheet(&cells) {
        super::write_png(
            &dir.join("contact_sheet.png"),
            sheet.width(),
            sheet.height(),
            &sheet,
        )?;
    }
    for metric in sweep::Metric::ALL {
        if let Some(plot) = sweep::metric_plot(names, rows, metric).map_err(Failure::other)? {
            super::write_png(
                &dir.join(metric.file_name()),
                plot.width(),
                plot.height(),
                &plot,
            )?;
        }
    }
    Ok(())
}
