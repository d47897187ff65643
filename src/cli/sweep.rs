//! `pelage sweep`: the thesis's chapter 4 experiments. Every point of the parameter product is
//! baked, rendered `--frames` times and timed; the folder gets `point_NNNN.png` per point,
//! `results.csv`, `contact_sheet.png` and `fps.png`. `pelage sweep-merge` joins shards.

use super::render::Backend;
use super::{CommonArgs, Failure, apply_overrides, progress, scene_source, with_threads};
use clap::Args;
use pelage::render::PreparedScene;
use pelage::sweep::{self, ResultRow, Shard, SweepParameter};
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
    /// Run only shard I of N (1-based): the points whose number is I − 1 modulo N.
    #[arg(long)]
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
}

pub fn run(args: SweepArgs) -> Result<(), Failure> {
    let bad = |e: sweep::SweepError| Failure::bad_input(e.0);
    let parameters: Vec<SweepParameter> = args
        .params
        .iter()
        .map(|p| SweepParameter::parse(p))
        .collect::<Result<_, _>>()
        .map_err(bad)?;
    let shard = args
        .shard
        .as_deref()
        .map(Shard::parse)
        .transpose()
        .map_err(bad)?;
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
    create_folder(&args.output)?;
    let tile = args.common.tile;
    let frames = args.frames;
    let output = args.output.clone();
    let against_oracle = args.against_oracle;
    let rows = with_threads(
        args.common.threads,
        || -> Result<Vec<ResultRow>, Failure> {
            let bar = progress(scenes.len() as u64);
            let mut rows = Vec::new();
            for (point, scene) in &scenes {
                bar.set_message(point.label());
                let start = Instant::now();
                let prepared = PreparedScene::new(scene)?;
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
                        &output.join(format!("point_{:04}_diff.png", point.index)),
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
                    fps: 1e3 / median,
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
    write_summary(&args.output, &names, &rows)
}

pub fn merge(args: MergeArgs) -> Result<(), Failure> {
    let mut files = Vec::new();
    for dir in &args.shards {
        let path = dir.join("results.csv");
        let text =
            pelage::input::read_text(&path, pelage::input::MAX_TABLE_BYTES, "shard's results")
                .map_err(|e| Failure::bad_input(e.to_string()))?;
        files.push((path.display().to_string(), text));
    }
    let (names, rows) = sweep::merge_results(&files).map_err(|e| Failure::bad_input(e.0))?;
    create_folder(&args.output)?;
    // The point renders come along, so the merged folder is a whole sweep.
    for row in &rows {
        let file = point_file(row.point);
        let target = args.output.join(&file);
        if let Some(source) = args
            .shards
            .iter()
            .map(|d| d.join(&file))
            .find(|p| p.is_file())
            && !same_file(&source, &target)
        {
            let bytes =
                pelage::input::read(&source, pelage::input::MAX_IMAGE_FILE_BYTES, "point image")
                    .map_err(|e| Failure::bad_input(e.to_string()))?;
            pelage::output::write_atomic(&target, &bytes)
                .map_err(|e| Failure::other(e.to_string()))?;
        }
    }
    write_summary(&args.output, &names, &rows)
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
                .map_err(|e| Failure::other(e.to_string())),
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

fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    }
}

fn point_file(index: usize) -> String {
    format!("point_{index:04}.png")
}

fn create_folder(dir: &Path) -> Result<(), Failure> {
    std::fs::create_dir_all(dir).map_err(|e| {
        Failure::other(format!(
            "{}: cannot create the output folder: {e}",
            dir.display()
        ))
    })
}

/// results.csv, the contact sheet (from the point PNGs in `dir`) and the fps plot.
fn write_summary(dir: &Path, names: &[String], rows: &[ResultRow]) -> Result<(), Failure> {
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
    let mut cells = Vec::new();
    for row in rows {
        let path = dir.join(point_file(row.point));
        let Ok(image) = pelage::input::read_image(&path, "point image") else {
            eprintln!(
                "warning: {}: missing or unreadable, left off the contact sheet",
                path.display()
            );
            continue;
        };
        let mut label: Vec<String> = labelled
            .iter()
            .map(|&i| format!("{} = {}", names[i], row.values[i]))
            .collect();
        label.push(format!(
            "{:.2} fps, {:.1} ms a frame",
            row.fps, row.median_frame_ms
        ));
        cells.push((image, label));
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
