//! Background work, so the window's event loop never waits: frames are drawn by [`Worker`]
//! threads (each frame inside a rayon pool), bakes and screenshots run on threads of their
//! own, and every result comes back to the event loop as an [`Event`] on one channel.
//!
//! A worker holds at most one pending [`Job`]; submitting replaces it, so a worker that falls
//! behind skips to the newest view instead of drawing a queue of stale ones. A job's steps run
//! coarse to fine and stop early when a newer job is waiting.

use super::schedule::reduced_size;
use pelage::render::{PreparedScene, RenderedImage};
use pelage::scene::Scene;
use rayon::ThreadPool;
use std::path::{Path, PathBuf};
use std::sync::mpsc::Sender;
use std::sync::{Arc, Condvar, Mutex, PoisonError};
use std::time::Instant;

/// Baked fur: a prepared scene and a number telling bakes apart.
pub struct Bake {
    /// The mesh and textures.
    pub prepared: PreparedScene,
    /// 1 for the first bake, then counting up.
    pub generation: u64,
}

/// Frames to draw: one view at a sequence of internal resolutions.
pub struct Job {
    /// Increases with every job submitted to any worker; results are shown in this order.
    pub id: u64,
    /// The fur to draw with.
    pub bake: Arc<Bake>,
    /// The scene to draw (its image size is the window's), with its `time` set.
    pub scene: Scene,
    /// Divisors of the window size, coarse to fine.
    pub steps: Vec<u32>,
    /// Whether its frame times should adapt the interactive resolution.
    pub pace: bool,
}

/// A finished frame.
pub struct Frame {
    /// The job's id.
    pub id: u64,
    /// Which of the job's steps (0 first).
    pub step: usize,
    /// Its divisor of the window size.
    pub divisor: u32,
    /// Milliseconds it took to draw.
    pub ms: f64,
    /// The pixels.
    pub image: RenderedImage,
    /// The fur it was drawn with.
    pub bake: Arc<Bake>,
    /// The scene drawn, at the window's size (what a screenshot of this frame draws).
    pub scene: Scene,
    /// Whether its time should adapt the interactive resolution.
    pub pace: bool,
}

impl Frame {
    /// Frames are shown in this order: a later job, or a later step of the same job.
    pub fn order(&self) -> (u64, usize) {
        (self.id, self.step)
    }
}

/// What comes back to the event loop.
pub enum Event {
    /// A frame is ready.
    Drawn(Box<Frame>),
    /// A bake finished (or failed), for this scene's seed, mesh and fur.
    Baked(Result<Box<Bake>, String>, Box<Scene>),
    /// A screenshot was written (its message) or failed.
    Wrote(Result<String, String>),
    /// A frame failed to draw.
    Failed(String),
}

#[derive(Default)]
struct Pending {
    job: Option<Job>,
    stop: bool,
}

struct Slot {
    pending: Mutex<Pending>,
    ready: Condvar,
}

impl Slot {
    fn lock(&self) -> std::sync::MutexGuard<'_, Pending> {
        self.pending.lock().unwrap_or_else(PoisonError::into_inner)
    }
}

/// A thread that draws the newest submitted job.
pub struct Worker {
    slot: Arc<Slot>,
}

impl Worker {
    /// Starts a worker drawing in `pool` with tiles of `tile` pixels, sending frames to `events`.
    pub fn spawn(
        name: &str,
        pool: Arc<ThreadPool>,
        tile: u32,
        events: Sender<Event>,
    ) -> std::io::Result<Worker> {
        let slot = Arc::new(Slot {
            pending: Mutex::new(Pending::default()),
            ready: Condvar::new(),
        });
        let shared = Arc::clone(&slot);
        std::thread::Builder::new()
            .name(format!("pelage-view-{name}"))
            .spawn(move || work(&shared, &pool, tile, &events))?;
        Ok(Worker { slot })
    }

    /// Replaces the pending job (a job being drawn finishes its current step first).
    pub fn submit(&self, job: Job) {
        self.slot.lock().job = Some(job);
        self.slot.ready.notify_one();
    }

    /// Drops the pending job and stops the one being drawn after its current step.
    pub fn cancel(&self) {
        self.slot.lock().job = None;
    }
}

impl Drop for Worker {
    fn drop(&mut self) {
        self.slot.lock().stop = true;
        self.slot.ready.notify_one();
    }
}

fn work(slot: &Slot, pool: &ThreadPool, tile: u32, events: &Sender<Event>) {
    loop {
        let job = {
            let mut pending = slot.lock();
            loop {
                if pending.stop {
                    return;
                }
                if let Some(job) = pending.job.take() {
                    break job;
                }
                pending = slot
                    .ready
                    .wait(pending)
                    .unwrap_or_else(PoisonError::into_inner);
            }
        };
        for (step, &divisor) in job.steps.iter().enumerate() {
            if step > 0 && slot.lock().job.is_some() {
                break; // A newer view is waiting: the rest of this one is stale.
            }
            let mut scene = job.scene.clone();
            (scene.image.width, scene.image.height) =
                reduced_size(scene.image.width, scene.image.height, divisor);
            let start = Instant::now();
            let drawn = pool.install(|| job.bake.prepared.render_with(&scene, scene.time, tile));
            let ms = start.elapsed().as_secs_f64() * 1e3;
            let event = match drawn {
                Ok(image) => Event::Drawn(Box::new(Frame {
                    id: job.id,
                    step,
                    divisor,
                    ms,
                    image,
                    bake: Arc::clone(&job.bake),
                    scene: job.scene.clone(),
                    pace: job.pace,
                })),
                Err(e) => Event::Failed(e.to_string()),
            };
            if events.send(event).is_err() {
                return; // The event loop has gone.
            }
        }
    }
}

/// Bakes `scene`'s fur on a thread of its own (inside `pool`) and sends [`Event::Baked`].
pub fn spawn_bake(
    scene: Scene,
    generation: u64,
    pool: Arc<ThreadPool>,
    events: Sender<Event>,
) -> std::io::Result<()> {
    std::thread::Builder::new()
        .name("pelage-view-bake".into())
        .spawn(move || {
            let baked = pool
                .install(|| PreparedScene::new(&scene))
                .map(|prepared| {
                    Box::new(Bake {
                        prepared,
                        generation,
                    })
                })
                .map_err(|e| e.to_string());
            let _ = events.send(Event::Baked(baked, Box::new(scene)));
        })?;
    Ok(())
}

/// The scene file written beside a screenshot: `shot.png` → `shot.toml`.
pub fn scene_path(png: &Path) -> PathBuf {
    png.with_extension("toml")
}

/// The scene `bake` draws for `settings`, made to be saved in `dir`: an OBJ path relative to
/// the scene's folder becomes absolute, so the file loads from anywhere.
fn scene_to_save(bake: &Bake, settings: &Scene, dir: &Path) -> Scene {
    let mut scene = bake.prepared.with_draw_settings(settings);
    if let Some(path) = scene.mesh.path.as_mut().filter(|p| p.is_relative()) {
        let joined = scene.base_dir.join(&*path);
        *path = std::fs::canonicalize(&joined).unwrap_or(joined);
    }
    scene.base_dir = dir.to_path_buf();
    scene
}

/// Draws `settings` (at its own size and time) with `bake` in `pool` and writes the PNG to
/// `png` and the scene to [`scene_path`]`(png)`, so that `pelage render` of that scene gives the
/// same bytes. Returns a line for the user.
pub fn screenshot(
    bake: &Bake,
    settings: &Scene,
    pool: &ThreadPool,
    tile: u32,
    png: &Path,
) -> Result<String, String> {
    let toml_path = scene_path(png);
    let dir = match toml_path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let scene = scene_to_save(bake, settings, &dir);
    let body = scene.to_toml()?;
    let text = format!(
        "# Written by `pelage view` with {}: `pelage render {}` draws it byte for byte.\n{body}",
        png.display(),
        toml_path.display()
    );
    // The file must read back to exactly the scene drawn, or it would not reproduce the PNG.
    let back = Scene::parse(&text, &toml_path.display().to_string(), &dir)
        .map_err(|e| format!("the scene written would not read back: {e}"))?;
    if back != scene {
        return Err("the scene written would not read back to the scene drawn".into());
    }
    let image = pool
        .install(|| bake.prepared.render_with(&back, back.time, tile))
        .map_err(|e| e.to_string())?;
    pelage::output::write_png(png, image.width, image.height, &image.rgba8)
        .map_err(|e| e.to_string())?;
    pelage::output::write_atomic(&toml_path, text.as_bytes()).map_err(|e| e.to_string())?;
    Ok(format!(
        "wrote {} and {} ({}x{}, t = {} s)",
        png.display(),
        toml_path.display(),
        image.width,
        image.height,
        back.time
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    const OCTAHEDRON: &str = "v 1 0 0\nv -1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nv 0 0 -1\n\
        vt 0 0\nvt 1 0\nvt 0 1\nvt 1 1\n\
        f 1/1 3/2 5/3\nf 3/1 2/2 5/4\nf 2/1 4/2 5/3\nf 4/1 1/2 5/4\n\
        f 3/1 1/2 6/3\nf 2/1 3/2 6/4\nf 4/1 2/2 6/3\nf 1/1 4/2 6/4\n";

    #[test]
    fn a_screenshot_of_an_obj_scene_loads_from_another_folder_and_matches() {
        let root = std::env::temp_dir().join(format!("pelage-view-obj-{}", std::process::id()));
        let (models, shots) = (root.join("models"), root.join("shots"));
        std::fs::create_dir_all(&models).expect("dir");
        std::fs::create_dir_all(&shots).expect("dir");
        std::fs::write(models.join("octahedron.obj"), OCTAHEDRON).expect("obj");
        let text = "[image]\nwidth = 48\nheight = 32\n[camera]\neye = [0.0, 1.0, 4.0]\n\
            [mesh]\nkind = \"obj\"\npath = \"octahedron.obj\"\n\
            [fur]\nnumber_of_strands = 50\nnumber_of_shells = 3\ntexture_resolution = 16\n\
            model_difference = 0.2\n";
        let scene = Scene::parse(text, "octahedron", &models).expect("scene");
        let bake = Bake {
            prepared: PreparedScene::new(&scene).expect("bake"),
            generation: 1,
        };
        let mut settings = scene.clone();
        settings.camera.eye = glam::Vec3::new(3.0, 2.0, 2.0);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .expect("pool");
        let png = shots.join("shot.png");
        screenshot(&bake, &settings, &pool, 16, &png).expect("screenshot");
        let written = Scene::load(&scene_path(&png)).expect("the written scene loads");
        let path = written.mesh.path.clone().expect("mesh path");
        assert!(path.is_absolute(), "{}", path.display());
        let fresh = PreparedScene::new(&written)
            .expect("bake from the written scene")
            .render(64)
            .expect("render");
        let saved = image::open(&png).expect("png").to_rgba8();
        assert!(saved.as_raw() == &fresh.rgba8);
        std::fs::remove_dir_all(&root).expect("cleanup");
    }

    #[test]
    fn the_scene_goes_beside_the_png() {
        assert_eq!(
            scene_path(Path::new("a/shot.png")),
            Path::new("a/shot.toml")
        );
        assert_eq!(scene_path(Path::new("shot")), Path::new("shot.toml"));
    }
}
