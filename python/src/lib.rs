//! `pelage._pelage`, the native half of the Python package `pelage`: scenes checked, rendered,
//! exported and compared through the library's own functions (the same code path as the
//! `pelage` command, so the same bytes), and the shading terms of `pelage::shading` over flat
//! `float32` arrays. The Python half (`python/python/pelage/`) gives the classes, checks and
//! converts the arrays (shapes, dtypes, broadcasting), and pickles; this module trusts it for
//! nothing that could crash: every length and size is checked here again.

use numpy::ndarray::{Array1, Array3};
use numpy::{IntoPyArray, PyArray1, PyReadonlyArray1, PyReadonlyArray3, PyUntypedArrayMethods};
use pyo3::exceptions::{PyOSError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, mpsc};
use std::time::Duration;

mod shading;

/// The allocator of the `pelage` command (see its `main.rs`): the rasterizer's per-draw buffers
/// are kept for the next draw instead of going back to the kernel, which a frame through
/// Python needs as much as one through the command. It serves this module's Rust allocations
/// only (arrays handed to NumPy are freed by the same allocator, through their owner).
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

pyo3::create_exception!(
    pelage,
    SceneError,
    PyValueError,
    "A scene that cannot be read, checked or prepared: the message names the file, the line \
     when known, and the key at fault, as the pelage command prints it."
);
pyo3::create_exception!(
    pelage,
    LimitError,
    PyValueError,
    "A render, export or comparison refused before its memory is spent: its estimate exceeds \
     a limit (the message gives the estimate and the limit)."
);

/// How often a waiting render looks for Ctrl-C (and other signals) while the GIL is released.
const SIGNAL_POLL: Duration = Duration::from_millis(50);

/// A scene as the Python `Scene` holds it: its TOML text, the name errors give it, the folder
/// its relative paths start from, and the parameters set on it (`with_params`), as
/// `(name, TOML value)` pairs.
#[derive(Clone, FromPyObject)]
#[pyo3(from_item_all)]
struct SceneSource {
    text: String,
    name: String,
    base_dir: PathBuf,
    params: Vec<(String, String)>,
}

/// The `SceneError` of a scene that failed to parse or validate, with its `file`, `line` and
/// `message` as attributes.
fn scene_error(py: Python<'_>, e: &pelage::scene::SceneError) -> PyErr {
    error_with_location(py, e.to_string(), &e.file, e.line, &e.message)
}

fn error_with_location(
    py: Python<'_>,
    text: String,
    file: &str,
    line: Option<usize>,
    message: &str,
) -> PyErr {
    let err = SceneError::new_err(text);
    let value = err.value(py);
    // Attributes on a fresh exception object cannot fail short of memory exhaustion; the
    // message in `str(err)` stands alone either way.
    let _ = value.setattr("file", file);
    let _ = value.setattr("line", line);
    let _ = value.setattr("message", message);
    err
}

/// The scene of `source`: parsed and validated, its parameters written in as `pelage sweep`
/// writes a point's (`pelage::sweep::scene_at`: the same names and checks).
fn build_scene(py: Python<'_>, source: &SceneSource) -> PyResult<pelage::scene::Scene> {
    use pelage::sweep::{SweepParameter, scene_at, sweep_points};
    if source.params.is_empty() {
        return pelage::scene::Scene::parse(&source.text, &source.name, &source.base_dir)
            .map_err(|e| scene_error(py, &e));
    }
    let plain =
        |message: String| error_with_location(py, message.clone(), &source.name, None, &message);
    let mut parameters = Vec::new();
    for (name, value) in &source.params {
        // The name checked as `--param NAME=…` is (empty, too deep, not a key); the value is
        // passed whole, commas and all.
        SweepParameter::parse(&format!("{name}=0")).map_err(|e| {
            let why =
                e.0.replacen("--param ", "parameter ", 1)
                    .replace("=0\"", "\"");
            plain(format!("{}: {why}", source.name))
        })?;
        parameters.push(SweepParameter {
            name: name.clone(),
            values: vec![value.clone()],
        });
    }
    let points = sweep_points(&parameters)
        .map_err(|e| plain(format!("{}: {}", source.name, e.0.replace("--param ", ""))))?;
    let point = points
        .first()
        .ok_or_else(|| plain("no parameter given".to_string()))?;
    scene_at(&source.text, &source.name, &source.base_dir, point).map_err(|e| plain(e.0))
}

/// Reads and checks a scene file: `(text, name, folder)` for the Python `Scene`.
#[pyfunction]
fn load_scene(py: Python<'_>, path: PathBuf) -> PyResult<(String, String, PathBuf)> {
    pelage::scene::Scene::load(&path).map_err(|e| scene_error(py, &e))?;
    let text =
        pelage::input::read_text(&path, pelage::scene::MAX_SCENE_BYTES, "scene").map_err(|e| {
            error_with_location(
                py,
                e.to_string(),
                &path.display().to_string(),
                None,
                &e.message,
            )
        })?;
    let dir = path.parent().unwrap_or(Path::new(".")).to_path_buf();
    Ok((text, path.display().to_string(), dir))
}

/// The embedded default scene (thesis figure 3.1): `(text, name, folder)`.
#[pyfunction]
fn default_scene() -> (String, String, PathBuf) {
    (
        pelage::scene::DEFAULT_SCENE.to_string(),
        pelage::scene::DEFAULT_SCENE_NAME.to_string(),
        PathBuf::from("scenes"),
    )
}

/// Checks a scene (text and parameters); returns `(width, height, time)`.
#[pyfunction]
fn check_scene(py: Python<'_>, source: SceneSource) -> PyResult<(u32, u32, f32)> {
    let scene = build_scene(py, &source)?;
    Ok((scene.image.width, scene.image.height, scene.time))
}

/// The scene, parameters applied, as TOML text that reads back to an equal scene.
#[pyfunction]
fn scene_to_toml(py: Python<'_>, source: SceneSource) -> PyResult<String> {
    build_scene(py, &source)?
        .to_toml()
        .map_err(PyRuntimeError::new_err)
}

/// What `render` and `export` change on the scene, as the command's `--width`, `--height`,
/// `--time`, `--threads` and `--tile` do.
#[derive(Clone, Copy, FromPyObject)]
#[pyo3(from_item_all)]
struct Overrides {
    width: Option<u32>,
    height: Option<u32>,
    time: Option<f32>,
    threads: Option<u32>,
    tile: u32,
}

/// The scene with `--width`, `--height`, `--time` written in and checked again, and `--tile`
/// checked, as `pelage render` does (`apply_overrides`), then the memory and work estimates
/// checked before anything large is allocated.
fn prepared_scene(
    py: Python<'_>,
    source: &SceneSource,
    o: Overrides,
    work: pelage::limits::Workload,
) -> PyResult<pelage::scene::Scene> {
    let mut scene = build_scene(py, source)?;
    if let Some(w) = o.width {
        scene.image.width = w;
    }
    if let Some(h) = o.height {
        scene.image.height = h;
    }
    if let Some(t) = o.time {
        scene.time = t;
    }
    scene.revalidate(&source.name).map_err(|e| {
        let message = format!("{} (after width/height/time)", e.message);
        error_with_location(
            py,
            format!("{}: {message}", e.file),
            &e.file,
            None,
            &message,
        )
    })?;
    if let Some(n) = o.threads
        && !(1..=256).contains(&n)
    {
        return Err(PyValueError::new_err(format!(
            "threads = {n}: must be in 1..=256"
        )));
    }
    pelage::raster::TileGrid::new(1, 1, o.tile)
        .map_err(|e| PyValueError::new_err(format!("tile = {}: {e}", o.tile)))?;
    let mesh = pelage::limits::mesh_size(&scene).map_err(|e| {
        let message = e.to_string();
        error_with_location(py, message.clone(), &source.name, None, &message)
    })?;
    let threads = o
        .threads
        .unwrap_or_else(|| u32::try_from(rayon_threads()).unwrap_or(u32::MAX));
    let work = pelage::limits::Workload { threads, ..work };
    pelage::limits::check(&scene, mesh, &work, &pelage::limits::Budgets::default())
        .map_err(|e| LimitError::new_err(format!("{}: {e}", source.name)))?;
    Ok(scene)
}

/// The number of worker threads a pool without `threads` gets: every core.
fn rayon_threads() -> usize {
    std::thread::available_parallelism().map_or(1, usize::from)
}

/// A failure of preparing or drawing the scene named `name`, worded as `pelage render` words
/// it ([`pelage::render::RenderError::describe`]).
fn render_failure(
    py: Python<'_>,
    e: pelage::render::RenderError,
    scene: &pelage::scene::Scene,
    name: &str,
) -> PyErr {
    if let pelage::render::RenderError::Cancelled = e {
        return pyo3::exceptions::PyKeyboardInterrupt::new_err("render cancelled");
    }
    let message = e.describe(scene, name);
    error_with_location(py, message.clone(), name, None, &message)
}

/// Runs `work` on a worker thread with a pool of `threads` rayon workers, the GIL released,
/// and waits for it, looking for signals every [`SIGNAL_POLL`]: on Ctrl-C the cancel flag is
/// set (the renderer skips the tiles left) and `KeyboardInterrupt` is raised at once, without
/// waiting for the worker, which ends by itself.
fn run_interruptible<T: Send + 'static>(
    py: Python<'_>,
    threads: Option<u32>,
    work: impl FnOnce(&AtomicBool) -> T + Send + 'static,
) -> PyResult<T> {
    let cancel = Arc::new(AtomicBool::new(false));
    let (sender, receiver) = mpsc::channel();
    let flag = Arc::clone(&cancel);
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(n) = threads {
        builder = builder.num_threads(n as usize);
    }
    let pool = builder
        .build()
        .map_err(|e| PyRuntimeError::new_err(format!("cannot start worker threads: {e}")))?;
    std::thread::Builder::new()
        .name("pelage-render".into())
        .spawn(move || {
            let result = pool.install(|| work(&flag));
            // The caller may have gone (Ctrl-C): nobody to tell.
            let _ = sender.send(result);
        })
        .map_err(|e| PyRuntimeError::new_err(format!("cannot start a render thread: {e}")))?;
    let mut receiver = receiver;
    loop {
        // The receiver goes into the GIL-free closure and comes back (it is Send, not Sync).
        let (received, back) = py.detach(move || (receiver.recv_timeout(SIGNAL_POLL), receiver));
        receiver = back;
        match received {
            Ok(result) => return Ok(result),
            Err(mpsc::RecvTimeoutError::Timeout) => {
                if let Err(interrupt) = py.check_signals() {
                    cancel.store(true, Ordering::Relaxed);
                    return Err(interrupt);
                }
            }
            Err(mpsc::RecvTimeoutError::Disconnected) => {
                return Err(PyRuntimeError::new_err(
                    "the render thread stopped without a result (a bug in pelage)",
                ));
            }
        }
    }
}

/// What a render gives back: 8-bit bytes or the float framebuffer, with the warnings.
enum Pixels {
    Rgba8(Vec<u8>),
    Float(Vec<f32>),
}

/// Renders a scene as `pelage render` does: an `H×W×4` `uint8` array (the PNG's bytes), or
/// with `float32` the framebuffer before rounding (the `.exr` output's values); and the
/// warnings met while preparing.
#[pyfunction]
fn render<'py>(
    py: Python<'py>,
    source: SceneSource,
    overrides: Overrides,
    float32: bool,
) -> PyResult<(Bound<'py, PyAny>, Vec<String>)> {
    let scene = prepared_scene(
        py,
        &source,
        overrides,
        pelage::limits::Workload {
            frames: 1,
            ..pelage::limits::Workload::default()
        },
    )?;
    let (width, height) = (scene.image.width as usize, scene.image.height as usize);
    let tile = overrides.tile;
    let drawn = {
        let scene = scene.clone();
        run_interruptible(py, overrides.threads, move |cancel| {
            let prepared = pelage::render::PreparedScene::new(&scene)?;
            let (framebuffer, _) = prepared.render_framebuffer_at(scene.time, tile, cancel)?;
            let pixels = if float32 {
                Pixels::Float(
                    framebuffer
                        .to_rgba_f32()
                        .iter()
                        .flat_map(|c| c.to_array())
                        .collect(),
                )
            } else {
                Pixels::Rgba8(framebuffer.to_rgba8())
            };
            Ok::<_, pelage::render::RenderError>((pixels, prepared.warnings().to_vec()))
        })?
    };
    let (pixels, warnings) = drawn.map_err(|e| render_failure(py, e, &scene, &source.name))?;
    let shape = (height, width, 4);
    let array = match pixels {
        Pixels::Rgba8(bytes) => Array3::from_shape_vec(shape, bytes)
            .map_err(|e| PyRuntimeError::new_err(e.to_string()))?
            .into_pyarray(py)
            .into_any(),
        Pixels::Float(floats) => Array3::from_shape_vec(shape, floats)
            .map_err(|e| PyRuntimeError::new_err(e.to_string()))?
            .into_pyarray(py)
            .into_any(),
    };
    Ok((array, warnings))
}

/// Writes what a GPU port needs to draw the scene's frame (`pelage export`) into `folder`;
/// returns the files written, relative to it.
#[pyfunction]
fn export(
    py: Python<'_>,
    source: SceneSource,
    overrides: Overrides,
    folder: PathBuf,
) -> PyResult<Vec<String>> {
    let scene = prepared_scene(
        py,
        &source,
        overrides,
        pelage::limits::Workload {
            export: true,
            ..pelage::limits::Workload::default()
        },
    )?;
    std::fs::create_dir_all(&folder)
        .map_err(|e| PyOSError::new_err(format!("{}: {e}", folder.display())))?;
    let done = {
        let scene = scene.clone();
        let folder = folder.clone();
        run_interruptible(py, overrides.threads, move |_| {
            let prepared = pelage::render::PreparedScene::new(&scene)
                .map_err(pelage::export::ExportError::Render)?;
            pelage::export::export(&prepared, scene.time, &folder)
        })?
    };
    match done {
        Ok(summary) => Ok(summary
            .files
            .iter()
            .map(|f| f.display().to_string())
            .collect()),
        Err(pelage::export::ExportError::Render(e)) => {
            Err(render_failure(py, e, &scene, &source.name))
        }
        Err(e) => Err(PyOSError::new_err(e.to_string())),
    }
}

/// Reads an image file (PNG, JPEG, BMP, EXR…) as `pelage compare` does, into an `H×W×4`
/// `uint8` array; refused before decoding when it would need more than the default memory
/// limit.
#[pyfunction]
fn read_image<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyAny>> {
    let not_found = |e: pelage::input::InputError| {
        let missing = !path.exists();
        let message = e.to_string();
        if missing {
            pyo3::exceptions::PyFileNotFoundError::new_err(message)
        } else {
            PyValueError::new_err(message)
        }
    };
    let ((w, h), bytes) = pelage::input::image_size(&path, "image").map_err(not_found)?;
    let estimate = pelage::limits::compare_memory((w, h), (w, h), bytes.saturating_mul(2));
    pelage::limits::check_memory(
        "the comparison",
        estimate,
        pelage::limits::DEFAULT_MAX_MEMORY,
    )
    .map_err(|e| LimitError::new_err(format!("{}: {e}", path.display())))?;
    let image = pelage::input::read_image(&path, "image").map_err(not_found)?;
    let (w, h) = image.dimensions();
    Array3::from_shape_vec((h as usize, w as usize, 4), image.into_raw())
        .map_err(|e| PyRuntimeError::new_err(e.to_string()))
        .map(|a| a.into_pyarray(py).into_any())
}

/// Reads an image file's float values (an `.exr` from `pelage render -o x.exr`) into an
/// `H×W×4` `float32` array, as the `image` crate decodes it (for tests against the command's
/// float output).
#[pyfunction]
fn read_float_image<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyAny>> {
    let ((w, h), _) = pelage::input::image_size(&path, "image")
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    let pixels = u64::from(w) * u64::from(h);
    if pixels > pelage::raster::framebuffer::MAX_PIXELS {
        return Err(LimitError::new_err(format!(
            "{}: {w}×{h} is more than {} pixels",
            path.display(),
            pelage::raster::framebuffer::MAX_PIXELS
        )));
    }
    let image = pelage::image::open(&path)
        .map_err(|e| PyValueError::new_err(format!("{}: {e}", path.display())))?
        .into_rgba32f();
    Array3::from_shape_vec((h as usize, w as usize, 4), image.into_raw())
        .map_err(|e| PyRuntimeError::new_err(e.to_string()))
        .map(|a| a.into_pyarray(py).into_any())
}

/// Writes an `H×W×4` `uint8` array as an 8-bit PNG (atomically, as the command does).
#[pyfunction]
fn write_png(path: PathBuf, pixels: PyReadonlyArray3<'_, u8>) -> PyResult<()> {
    let image = rgba_image(&pixels, "pixels")?;
    pelage::output::write_png(&path, image.width(), image.height(), image.as_raw())
        .map_err(|e| PyOSError::new_err(e.to_string()))
}

/// An `H×W×4` C-contiguous `uint8` array as an image (the Python side has made it so).
fn rgba_image(array: &PyReadonlyArray3<'_, u8>, what: &str) -> PyResult<pelage::image::RgbaImage> {
    let shape = array.shape();
    let (h, w) = (shape[0], shape[1]);
    if shape[2] != 4 || h == 0 || w == 0 {
        return Err(PyValueError::new_err(format!(
            "{what}: an H×W×4 array is expected, got shape {shape:?}"
        )));
    }
    let bytes = array
        .as_slice()
        .map_err(|_| PyValueError::new_err(format!("{what}: the array is not contiguous")))?;
    let (w32, h32) = (u32::try_from(w), u32::try_from(h));
    let (Ok(w32), Ok(h32)) = (w32, h32) else {
        return Err(PyValueError::new_err(format!(
            "{what}: {w}×{h} is too large"
        )));
    };
    pelage::image::RgbaImage::from_raw(w32, h32, bytes.to_vec())
        .ok_or_else(|| PyValueError::new_err(format!("{what}: wrong number of bytes")))
}

/// Compares a capture with a reference as `pelage compare` does: `(metrics as JSON, the text
/// the command prints, the heat map as an H×W×4 array, passed)`.
#[pyfunction]
fn compare<'py>(
    py: Python<'py>,
    reference: PyReadonlyArray3<'py, u8>,
    capture: PyReadonlyArray3<'py, u8>,
    tolerance: &str,
) -> PyResult<(String, String, Bound<'py, PyAny>, bool)> {
    let tolerance = pelage::compare::Tolerance::parse(tolerance)
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    let a = rgba_image(&reference, "reference")?;
    let b = rgba_image(&capture, "capture")?;
    let estimate = pelage::limits::compare_memory(a.dimensions(), b.dimensions(), 0);
    pelage::limits::check_memory(
        "the comparison",
        estimate,
        pelage::limits::DEFAULT_MAX_MEMORY,
    )
    .map_err(|e| LimitError::new_err(e.to_string()))?;
    let measured = py.detach(move || {
        let comparison = pelage::compare::compare_images(&a, &b, &tolerance)?;
        let heat = pelage::compare::heat_map(&a, &b)?;
        Ok::<_, pelage::compare::CompareError>((comparison, heat))
    });
    let (comparison, heat) = measured.map_err(|e| PyValueError::new_err(e.to_string()))?;
    let json = serde_json::to_string(&comparison)
        .map_err(|e| PyRuntimeError::new_err(format!("JSON: {e}")))?;
    let (w, h) = heat.dimensions();
    let heat = Array3::from_shape_vec((h as usize, w as usize, 4), heat.into_raw())
        .map_err(|e| PyRuntimeError::new_err(e.to_string()))?
        .into_pyarray(py)
        .into_any();
    Ok((json, comparison.to_string(), heat, comparison.passed()))
}

/// A flat `float32` result as a NumPy array.
fn floats<'py>(py: Python<'py>, values: Vec<f32>) -> Bound<'py, PyArray1<f32>> {
    Array1::from_vec(values).into_pyarray(py)
}

/// A C-contiguous `float32` input as a slice, `per_item` values for each of `count` items.
fn slice_of<'a>(
    array: &'a PyReadonlyArray1<'_, f32>,
    name: &str,
    count: usize,
    per_item: usize,
) -> PyResult<&'a [f32]> {
    let values = array
        .as_slice()
        .map_err(|_| PyValueError::new_err(format!("{name}: the array is not contiguous")))?;
    if Some(values.len()) != count.checked_mul(per_item) {
        return Err(PyValueError::new_err(format!(
            "{name}: {} values, {count}×{per_item} expected",
            values.len()
        )));
    }
    Ok(values)
}

/// The native module.
#[pymodule]
fn _pelage(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("SceneError", py.get_type::<SceneError>())?;
    m.add("LimitError", py.get_type::<LimitError>())?;
    m.add("GPU_TOLERANCE", pelage::compare::GPU_TOLERANCE)?;
    m.add("DEFAULT_TILE_SIZE", pelage::raster::DEFAULT_TILE_SIZE)?;
    m.add_function(wrap_pyfunction!(load_scene, m)?)?;
    m.add_function(wrap_pyfunction!(default_scene, m)?)?;
    m.add_function(wrap_pyfunction!(check_scene, m)?)?;
    m.add_function(wrap_pyfunction!(scene_to_toml, m)?)?;
    m.add_function(wrap_pyfunction!(render, m)?)?;
    m.add_function(wrap_pyfunction!(export, m)?)?;
    m.add_function(wrap_pyfunction!(read_image, m)?)?;
    m.add_function(wrap_pyfunction!(read_float_image, m)?)?;
    m.add_function(wrap_pyfunction!(write_png, m)?)?;
    m.add_function(wrap_pyfunction!(compare, m)?)?;
    shading::register(m)?;
    Ok(())
}
