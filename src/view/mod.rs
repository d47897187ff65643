//! `pelage view`: the fur in a window, moving, while its parameters are tuned.
//!
//! The viewer lives on the binary's side of the crate, beside the CLI: it is a front end that
//! drives the library through its public API ([`PreparedScene::render_with`] draws one bake
//! with the camera and effects of the moment), and keeping it out of the library keeps the
//! oracle free of any window-system dependency.
//!
//! Threads: the event loop (this module) reads input, edits the [`ViewState`], and shows the
//! newest finished frame, scaled up to the window, with a status line drawn over it; it never
//! waits for a frame or a bake. Frames are drawn by two [`Worker`]s: *preview* at a reduced
//! internal resolution whenever the view changes ([`schedule`]), and *refine*, which redraws a
//! view that has stopped changing at finer resolutions down to full size. Bakes (a new shell
//! count or texture resolution) and screenshots run on threads of their own; the old textures
//! are shown until the new bake is done.
//!
//! A screenshot is a full-resolution frame of exactly the scene, camera, time and bake of the
//! frame on screen, written as PNG with that scene beside it as TOML, so that `pelage render`
//! of the TOML file gives the same bytes.

mod font;
mod input;
mod orbit;
mod schedule;
mod state;
mod worker;

pub use state::ViewLimits;

use crate::cli::Failure;
use font::Canvas;
use input::{Action, Drag, KeyTracker};
use minifb::{InputCallback, Key, MouseButton, MouseMode, Window, WindowOptions};
use pelage::scene::Scene;
use rayon::ThreadPool;
use schedule::Pace;
use state::{ViewState, same_bake};
use std::collections::VecDeque;
use std::path::PathBuf;
use std::sync::mpsc::{Receiver, Sender, channel};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use worker::{Bake, Event, Frame, Job, Worker};

/// The message when there is no display to open a window on.
pub const NO_DISPLAY: &str = "pelage view needs a display and DISPLAY is not set: run it in a \
desktop session (X11, or XWayland under Wayland), or headless as `xvfb-run -a pelage view ...`";

/// How the viewer runs.
pub struct Options {
    /// Window title.
    pub title: String,
    /// Worker threads per pool (all cores when `None`).
    pub threads: Option<u32>,
    /// Tile size of the rasterizer.
    pub tile: u32,
    /// Run this many frames and exit (the clock then steps `1/fps` per frame).
    pub frames: Option<u32>,
    /// Where screenshots go (the `p` key; and on exit after `frames`).
    pub screenshot: Option<PathBuf>,
    /// Frames per second of the clock in `frames` mode.
    pub fps: f32,
    /// Start with the clock stopped.
    pub paused: bool,
    /// In `frames` mode, orbit by this many degrees per frame.
    pub orbit_deg: f32,
    /// The budgets every edit is checked against.
    pub limits: ViewLimits,
}

/// The display the window would open on, or the reason there is none.
fn display() -> Result<String, Failure> {
    match std::env::var("DISPLAY") {
        Ok(d) if !d.is_empty() => Ok(d),
        _ => Err(Failure::other(NO_DISPLAY)),
    }
}

fn pool(threads: Option<u32>, name: &'static str) -> Result<Arc<ThreadPool>, Failure> {
    let mut builder =
        rayon::ThreadPoolBuilder::new().thread_name(move |i| format!("pelage-{name}-{i}"));
    if let Some(n) = threads {
        builder = builder.num_threads(n as usize);
    }
    builder
        .build()
        .map(Arc::new)
        .map_err(|e| Failure::other(format!("cannot start worker threads: {e}")))
}

/// The size of the X screen the window opens on (`PELAGE_VIEW_SCREEN=WxH` stands in for it:
/// for trying a small screen); `None` when it cannot be read (the window is then image-sized).
/// The connection comes back too, to be closed only once the window is open: an X server with
/// no client left resets (Xvfb does), and a window opened during the reset fails.
fn screen_size() -> Option<(
    (usize, usize),
    Option<x11rb::rust_connection::RustConnection>,
)> {
    if let Ok(text) = std::env::var("PELAGE_VIEW_SCREEN") {
        let (w, h) = text.split_once('x')?;
        return Some(((w.trim().parse().ok()?, h.trim().parse().ok()?), None));
    }
    let (connection, number) = x11rb::connect(None).ok()?;
    let screen = x11rb::connection::Connection::setup(&connection)
        .roots
        .get(number)?;
    let size = (
        usize::from(screen.width_in_pixels),
        usize::from(screen.height_in_pixels),
    );
    Some((size, Some(connection)))
}

/// Room left on the screen for the window's frame and title bar and a desktop panel, pixels.
const SCREEN_MARGIN: (usize, usize) = (40, 80);

/// The window size for an image of `width` × `height` on a `screen`: the image's size when it
/// fits (less [`SCREEN_MARGIN`]), else scaled down to fit, keeping its aspect. The image is
/// still rendered at its own size; only the window shows it smaller.
pub fn fit_window(width: usize, height: usize, screen: Option<(usize, usize)>) -> (usize, usize) {
    let Some((sw, sh)) = screen else {
        return (width, height);
    };
    let (room_w, room_h) = (
        sw.saturating_sub(SCREEN_MARGIN.0).max(64),
        sh.saturating_sub(SCREEN_MARGIN.1).max(64),
    );
    if width <= room_w && height <= room_h {
        return (width, height);
    }
    let scale = (room_w as f64 / width as f64).min(room_h as f64 / height as f64);
    (
        ((width as f64 * scale).floor() as usize).max(1),
        ((height as f64 * scale).floor() as usize).max(1),
    )
}

/// Key presses and releases as the window system delivers them (minifb's input callback), for
/// [`KeyTracker`]: a tap shorter than a frame is still seen.
struct KeyEvents(Arc<Mutex<Vec<(Key, bool)>>>);

impl InputCallback for KeyEvents {
    fn add_char(&mut self, _: u32) {}

    fn set_key_state(&mut self, key: Key, down: bool) {
        if let Ok(mut events) = self.0.lock() {
            events.push((key, down));
        }
    }
}

/// Opens the window on `scene` and runs until it is closed (or for `options.frames` frames).
pub fn run(scene: Scene, options: Options) -> Result<(), Failure> {
    let display = display()?;
    let screen = screen_size();
    let (width, height) = fit_window(
        scene.image.width as usize,
        scene.image.height as usize,
        screen.as_ref().map(|s| s.0),
    );
    let mut window = Window::new(&options.title, width, height, WindowOptions::default())
        .map_err(|e| Failure::other(format!("cannot open a window on display {display}: {e}")))?;
    drop(screen);
    let key_events = Arc::new(Mutex::new(Vec::new()));
    window.set_input_callback(Box::new(KeyEvents(Arc::clone(&key_events))));
    let mut viewer = Viewer::new(scene, options, (width, height), key_events)?;
    match viewer.options.frames {
        Some(n) => viewer.run_frames(&mut window, n),
        None => viewer.run_interactive(&mut window),
    }
}

/// The frame on screen.
struct Shown {
    frame: Frame,
    /// When it arrived.
    at: Instant,
}

struct Viewer {
    state: ViewState,
    options: Options,
    width: usize,
    height: usize,
    refine_pool: Arc<ThreadPool>,
    sender: Sender<Event>,
    events: Receiver<Event>,
    preview: Worker,
    refine: Worker,
    bake: Option<Arc<Bake>>,
    /// The scene whose fur is being baked.
    baking: Option<Scene>,
    generation: u64,
    next_id: u64,
    /// The last scene submitted for preview, its bake generation and the job's id.
    requested: Option<(Scene, u64, u64)>,
    changed_at: Instant,
    refined: bool,
    pace: Pace,
    shown: Option<Shown>,
    /// The shown frame scaled to the window.
    base: Vec<u32>,
    buffer: Vec<u32>,
    arrivals: VecDeque<Instant>,
    help: bool,
    message: Option<(String, Instant)>,
    shots_in_flight: usize,
    shots_taken: u32,
    /// Key events since the last frame, from the window's input callback.
    key_events: Arc<Mutex<Vec<(Key, bool)>>>,
    keys: KeyTracker,
    /// Whether the window had the focus at the last frame.
    was_active: bool,
}

impl Viewer {
    fn new(
        scene: Scene,
        options: Options,
        (width, height): (usize, usize),
        key_events: Arc<Mutex<Vec<(Key, bool)>>>,
    ) -> Result<Self, Failure> {
        let preview_pool = pool(options.threads, "preview")?;
        let refine_pool = pool(options.threads, "refine")?;
        let (sender, events) = channel();
        let spawn_failed =
            |e: std::io::Error| Failure::other(format!("cannot start a thread: {e}"));
        let preview = Worker::spawn("preview", preview_pool, options.tile, sender.clone())
            .map_err(spawn_failed)?;
        let refine = Worker::spawn(
            "refine",
            Arc::clone(&refine_pool),
            options.tile,
            sender.clone(),
        )
        .map_err(spawn_failed)?;
        let background = pack(scene.image.background.to_array().map(|c| (c * 255.0) as u8));
        let mut viewer = Viewer {
            state: ViewState::new(scene, !options.paused).with_limits(options.limits.clone()),
            options,
            width,
            height,
            refine_pool,
            sender,
            events,
            preview,
            refine,
            bake: None,
            baking: None,
            generation: 0,
            next_id: 0,
            requested: None,
            changed_at: Instant::now(),
            refined: false,
            pace: Pace::default(),
            shown: None,
            base: vec![background; width * height],
            buffer: vec![0; width * height],
            arrivals: VecDeque::new(),
            help: false,
            message: None,
            shots_in_flight: 0,
            shots_taken: 0,
            key_events,
            keys: KeyTracker::default(),
            was_active: false,
        };
        viewer.bake_if_needed()?;
        Ok(viewer)
    }

    fn say(&mut self, message: impl Into<String>) {
        self.message = Some((message.into(), Instant::now()));
    }

    /// Starts a bake when the wanted fur differs from the baked one and none is running.
    fn bake_if_needed(&mut self) -> Result<(), Failure> {
        let wanted = &self.state.scene;
        let baked = self
            .bake
            .as_ref()
            .is_some_and(|b| same_bake(b.prepared.scene(), wanted));
        if baked || self.baking.is_some() {
            return Ok(());
        }
        self.generation += 1;
        self.baking = Some(wanted.clone());
        worker::spawn_bake(
            wanted.clone(),
            self.generation,
            Arc::clone(&self.refine_pool),
            self.sender.clone(),
        )
        .map_err(|e| Failure::other(format!("cannot start a thread: {e}")))
    }

    /// Applies an action; false when it asks to quit.
    fn act(&mut self, action: Action) -> Result<bool, Failure> {
        match action {
            Action::Quit => return Ok(false),
            Action::ToggleHelp => self.help = !self.help,
            Action::Screenshot => self.screenshot()?,
            _ => {
                if let Some(message) = self.state.apply(action, self.height as f32) {
                    self.say(message);
                }
                self.bake_if_needed()?;
            }
        }
        Ok(true)
    }

    /// Writes the frame on screen at full resolution, in the background.
    fn screenshot(&mut self) -> Result<(), Failure> {
        let Some(shown) = &self.shown else {
            self.say("nothing to capture yet: the fur is still baking");
            return Ok(());
        };
        let path = match &self.options.screenshot {
            Some(p) => p.clone(),
            None => loop {
                self.shots_taken += 1;
                let p = PathBuf::from(format!("pelage-view-{:03}.png", self.shots_taken));
                if !p.exists() {
                    break p;
                }
            },
        };
        let (bake, scene) = (Arc::clone(&shown.frame.bake), self.capture(&shown.frame));
        let (pool, tile, sender) = (
            Arc::clone(&self.refine_pool),
            self.options.tile,
            self.sender.clone(),
        );
        std::thread::Builder::new()
            .name("pelage-view-screenshot".into())
            .spawn(move || {
                let result = worker::screenshot(&bake, &scene, &pool, tile, &path);
                let _ = sender.send(Event::Wrote(result));
            })
            .map_err(|e| Failure::other(format!("cannot start a thread: {e}")))?;
        self.shots_in_flight += 1;
        self.say("writing the screenshot...");
        Ok(())
    }

    /// The scene a screenshot of `frame` writes: the frame's, with the clock's time where the
    /// frame did not depend on it (no wind, no fire), so the file records the time on screen.
    fn capture(&self, frame: &Frame) -> Scene {
        let mut scene = frame.scene.clone();
        if scene.wind.is_none() && scene.burn.is_none() {
            scene.time = self.state.clock.now();
        }
        scene
    }

    /// Handles one event from the workers.
    fn handle(&mut self, event: Event) -> Result<(), Failure> {
        match event {
            Event::Drawn(frame) => {
                if frame.pace {
                    self.pace.observe(frame.divisor, frame.ms);
                }
                if self
                    .shown
                    .as_ref()
                    .is_none_or(|s| frame.order() > s.frame.order())
                {
                    scale_into(&frame.image, &mut self.base, self.width, self.height);
                    let now = Instant::now();
                    self.arrivals.push_back(now);
                    self.shown = Some(Shown {
                        frame: *frame,
                        at: now,
                    });
                }
            }
            Event::Baked(Ok(bake), _) => {
                self.bake = Some(Arc::new(*bake));
                self.baking = None;
                self.bake_if_needed()?;
            }
            Event::Baked(Err(e), scene) => {
                self.baking = None;
                let Some(current) = &self.bake else {
                    return Err(Failure::bad_input(e));
                };
                // Back to the fur that is baked; the other edits stay.
                let baked = current.prepared.scene();
                self.state.scene = Scene {
                    seed: baked.seed,
                    mesh: baked.mesh.clone(),
                    fur: baked.fur.clone(),
                    ..self.state.scene.clone()
                };
                self.say(format!(
                    "cannot bake {} shells of {}: {e}",
                    scene.fur.number_of_shells, scene.fur.texture_resolution
                ));
            }
            Event::Wrote(result) => {
                self.shots_in_flight = self.shots_in_flight.saturating_sub(1);
                match result {
                    Ok(m) => {
                        eprintln!("{m}");
                        self.say(m);
                    }
                    Err(e) => {
                        eprintln!("error: {e}");
                        self.say(format!("screenshot failed: {e}"));
                    }
                }
            }
            Event::Failed(e) => self.say(format!("frame failed: {e}")),
        }
        Ok(())
    }

    fn drain(&mut self) -> Result<(), Failure> {
        while let Ok(event) = self.events.try_recv() {
            self.handle(event)?;
        }
        Ok(())
    }

    /// The scene to draw now: with the clock's time when time matters, else the scene's own
    /// (so a running clock does not redraw a still scene).
    fn scene_to_draw(&self) -> Scene {
        if self.state.time_matters() {
            self.state.scene_now()
        } else {
            self.state.scene.clone()
        }
    }

    fn job(&mut self, bake: &Arc<Bake>, scene: Scene, steps: Vec<u32>, pace: bool) -> Job {
        self.next_id += 1;
        Job {
            id: self.next_id,
            bake: Arc::clone(bake),
            scene,
            steps,
            pace,
        }
    }

    /// Submits a preview when the view changed, or the refinement once it has settled.
    fn request(&mut self, force: bool) -> Option<u64> {
        let bake = Arc::clone(self.bake.as_ref()?);
        let scene = self.scene_to_draw();
        let unchanged = self
            .requested
            .as_ref()
            .is_some_and(|(s, g, _)| *g == bake.generation && *s == scene);
        if !unchanged || force {
            self.refine.cancel();
            let job = self.job(&bake, scene.clone(), vec![self.pace.divisor()], true);
            let id = job.id;
            self.preview.submit(job);
            self.requested = Some((scene, bake.generation, id));
            self.changed_at = Instant::now();
            self.refined = false;
            return Some(id);
        }
        let (_, _, id) = self.requested.as_ref()?;
        let shown = self.shown.as_ref()?;
        let settled = self.changed_at.elapsed().as_millis() >= schedule::SETTLE_MS;
        if !self.refined && settled && shown.frame.id >= *id && shown.frame.divisor > 1 {
            let steps = schedule::refine_steps(shown.frame.divisor);
            let job = self.job(&bake, scene, steps, false);
            self.refine.submit(job);
            self.refined = true;
        }
        None
    }

    /// Frames per second over the last second, and the last frame's milliseconds.
    fn rate(&mut self) -> f64 {
        let now = Instant::now();
        while self
            .arrivals
            .front()
            .is_some_and(|t| now.duration_since(*t) > Duration::from_secs(1))
        {
            self.arrivals.pop_front();
        }
        self.arrivals.len() as f64
    }

    /// The window's pixels: the shown frame, the status line and the key list.
    fn compose(&mut self) {
        self.buffer.copy_from_slice(&self.base);
        let arriving = self.rate() > 0.0;
        let px = if self.width >= 1200 { 22.0 } else { 14.0 };
        let mut lines = Vec::new();
        let first = match &self.shown {
            Some(s) => {
                let (w, h) = (s.frame.image.width, s.frame.image.height);
                let rate = rate_text(s.frame.ms, arriving);
                format!(
                    "{rate}  at 1/{} size, {w}×{h}{}",
                    s.frame.divisor,
                    if s.at.elapsed() < Duration::from_millis(300) && s.frame.step > 0 {
                        " refined"
                    } else {
                        ""
                    }
                )
            }
            None => "Baking fur textures…".to_string(),
        };
        let baking = self.baking.as_ref().map(|s| {
            format!(
                "  baking {} shells of {}…",
                s.fur.number_of_shells, s.fur.texture_resolution
            )
        });
        lines.push(format!("{first}{}  H: keys", baking.unwrap_or_default()));
        lines.extend(wrap(
            &self.state.describe(),
            px,
            self.width.saturating_sub(8),
        ));
        if let Some((m, at)) = &self.message
            && at.elapsed() < Duration::from_secs(5)
        {
            lines.push(m.clone());
        }
        let mut canvas = Canvas {
            pixels: &mut self.buffer,
            width: self.width,
            height: self.height,
        };
        draw_lines(&mut canvas, 0, &lines, px);
        if self.help {
            let mut help = vec!["Keys".to_string()];
            help.extend(input::KEYS.iter().map(|(k, d)| format!("{k}:  {d}")));
            let top = (lines.len() + 1) * font::line_height(px);
            draw_lines(&mut canvas, top, &help, px);
        }
    }

    fn show(&mut self, window: &mut Window) -> Result<(), Failure> {
        self.compose();
        window
            .update_with_buffer(&self.buffer, self.width, self.height)
            .map_err(|e| Failure::other(format!("cannot draw into the window: {e}")))
    }

    /// The actions of this frame's keys and mouse.
    fn input(&mut self, window: &Window, drag: &mut Option<(Drag, (f32, f32))>) -> Vec<Action> {
        let events = match self.key_events.lock() {
            Ok(mut events) => std::mem::take(&mut *events),
            Err(_) => Vec::new(),
        };
        // Focus lost: releases may never come, so no key counts as held any more.
        let active = window.is_active();
        if self.was_active && !active {
            self.keys.clear();
        }
        self.was_active = active;
        let mut actions = self.keys.events(events);
        let held = if window.get_mouse_down(MouseButton::Left) {
            Some(Drag::Orbit)
        } else if window.get_mouse_down(MouseButton::Right)
            || window.get_mouse_down(MouseButton::Middle)
        {
            Some(Drag::Pan)
        } else {
            None
        };
        let position = window.get_mouse_pos(MouseMode::Pass);
        *drag = match (held, position, *drag) {
            (Some(kind), Some(to), Some((was, from))) if kind == was => {
                actions.extend(input::drag_action(kind, from, to, self.width as f32));
                Some((kind, to))
            }
            (Some(kind), Some(to), _) => Some((kind, to)),
            _ => None,
        };
        if let Some((_, notches)) = window.get_scroll_wheel() {
            actions.extend(input::wheel_action(notches));
        }
        actions
    }

    fn run_interactive(&mut self, window: &mut Window) -> Result<(), Failure> {
        window.set_target_fps(60);
        let mut drag = None;
        let mut last = Instant::now();
        'frames: while window.is_open() {
            let now = Instant::now();
            self.state
                .clock
                .advance(now.duration_since(last).as_secs_f64());
            last = now;
            for action in self.input(window, &mut drag) {
                if !self.act(action)? {
                    break 'frames;
                }
            }
            self.drain()?;
            self.request(false);
            self.show(window)?;
        }
        if self.shots_in_flight > 0 {
            eprintln!("finishing the screenshot...");
        }
        while self.shots_in_flight > 0 {
            match self.events.recv() {
                Ok(event) => self.handle(event)?,
                Err(_) => break,
            }
        }
        Ok(())
    }

    /// Waits for events until `done` holds.
    fn wait(&mut self, done: impl Fn(&Viewer) -> bool) -> Result<(), Failure> {
        while !done(self) {
            let event = self
                .events
                .recv()
                .map_err(|_| Failure::other("the render threads stopped"))?;
            self.handle(event)?;
        }
        Ok(())
    }

    /// `--frames N`: N frames, each drawn and shown before the clock steps `1/fps`, then the
    /// screenshot; reports the frame rate on stderr.
    fn run_frames(&mut self, window: &mut Window, frames: u32) -> Result<(), Failure> {
        let fps = self.options.fps;
        if !(fps.is_finite() && fps > 0.0 && fps <= 1000.0) {
            return Err(Failure::bad_input(format!(
                "--fps {fps} must be in (0, 1000]"
            )));
        }
        window.set_target_fps(0);
        self.wait(|v| v.bake.is_some())?;
        let start = Instant::now();
        let mut times = Vec::new();
        for k in 0..frames {
            if !window.is_open() {
                break;
            }
            if k > 0 {
                self.state.clock.advance(1.0 / f64::from(fps));
                if self.options.orbit_deg != 0.0 {
                    self.act(Action::Orbit {
                        yaw: self.options.orbit_deg.to_radians(),
                        pitch: 0.0,
                    })?;
                }
            }
            if let Some(id) = self.request(true) {
                self.wait(|v| v.shown.as_ref().is_some_and(|s| s.frame.id >= id))?;
            }
            if let Some(s) = &self.shown {
                times.push((s.frame.ms, s.frame.divisor));
            }
            self.show(window)?;
        }
        let seconds = start.elapsed().as_secs_f64();
        let mut ms: Vec<f64> = times.iter().map(|t| t.0).collect();
        ms.sort_by(f64::total_cmp);
        let divisors: Vec<String> = times.iter().map(|t| format!("1/{}", t.1)).collect();
        eprintln!(
            "pelage view: {} frames in {seconds:.2} s, {:.1} frames/s in a {}x{} window; \
             median frame {:.1} ms; internal resolution per frame: {}",
            times.len(),
            times.len() as f64 / seconds.max(1e-9),
            self.width,
            self.height,
            ms.get(ms.len() / 2).copied().unwrap_or(0.0),
            divisors.join(" ")
        );
        if let (Some(path), Some(shown)) = (self.options.screenshot.clone(), &self.shown) {
            let message = worker::screenshot(
                &shown.frame.bake,
                &self.capture(&shown.frame),
                &self.refine_pool,
                self.options.tile,
                &path,
            )
            .map_err(Failure::other)?;
            eprintln!("{message}");
        }
        Ok(())
    }
}

/// Lines of text at the top-left from row `top` at `px` pixels, over a darkened backdrop.
fn draw_lines(canvas: &mut Canvas, top: usize, lines: &[String], px: f32) {
    let pad = 4;
    let width = lines
        .iter()
        .map(|l| font::text_width(l, px))
        .max()
        .unwrap_or(0);
    let line = font::line_height(px);
    let height = lines.len() * line;
    canvas.darken(0, top, width + 2 * pad, height + pad, 90);
    for (i, text) in lines.iter().enumerate() {
        let y = top + pad + i * line;
        canvas.text(pad, y, text, px, 0x00F0F0E8);
    }
}

/// `text`'s fields (separated by two spaces) in lines no wider than `width` pixels at `px`
/// (a field wider than that gets a line of its own).
fn wrap(text: &str, px: f32, width: usize) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    for field in text.split("  ").filter(|f| !f.is_empty()) {
        match lines.last_mut() {
            Some(line) if font::text_width(&format!("{line}  {field}"), px) <= width => {
                line.push_str("  ");
                line.push_str(field);
            }
            _ => lines.push(field.to_string()),
        }
    }
    lines
}

/// The frame rate and frame time of the status line: both from the same frame time, so that
/// they agree (`fps × ms = 1000`); `still` when no new frame arrived in the last second.
pub fn rate_text(frame_ms: f64, arriving: bool) -> String {
    if !(frame_ms.is_finite() && frame_ms > 0.0) {
        return "no frame time yet".to_string();
    }
    let fps = 1000.0 / frame_ms;
    let digits = if fps < 10.0 { 1 } else { 0 };
    if arriving {
        format!("{fps:.digits$} fps ({frame_ms:.1} ms a frame)")
    } else {
        format!("still; last frame {frame_ms:.1} ms ({fps:.digits$} fps)")
    }
}

/// An opaque colour as `0x00RRGGBB`.
fn pack([r, g, b]: [u8; 3]) -> u32 {
    (u32::from(r) << 16) | (u32::from(g) << 8) | u32::from(b)
}

/// Per output coordinate: the two source coordinates around its centre and the weight of the
/// second in 1/256 (bilinear, edges clamped).
fn taps(out: usize, source: usize) -> Vec<(usize, usize, u32)> {
    (0..out)
        .map(|i| {
            let x = ((i as f32 + 0.5) * source as f32 / out as f32 - 0.5).max(0.0);
            let x0 = (x as usize).min(source - 1);
            let weight = ((x - x0 as f32) * 256.0) as u32;
            (x0, (x0 + 1).min(source - 1), weight.min(256))
        })
        .collect()
}

/// Scales an RGBA8 image to fill `width` × `height` as `0x00RRGGBB`: a copy at the same size,
/// bilinear when the image is smaller (a reduced preview).
fn scale_into(image: &pelage::render::RenderedImage, out: &mut [u32], width: usize, height: usize) {
    let (sw, sh) = (image.width as usize, image.height as usize);
    if sw == 0 || sh == 0 || image.rgba8.len() < sw * sh * 4 {
        return;
    }
    let texel = |x: usize, y: usize, c: usize| u32::from(image.rgba8[(y * sw + x) * 4 + c]);
    let (columns, rows) = (taps(width, sw), taps(height, sh));
    for (row, &(y0, y1, wy)) in out.chunks_exact_mut(width).zip(&rows) {
        for (px, &(x0, x1, wx)) in row.iter_mut().zip(&columns) {
            let channel = |c: usize| {
                let top = texel(x0, y0, c) * (256 - wx) + texel(x1, y0, c) * wx;
                let bottom = texel(x0, y1, c) * (256 - wx) + texel(x1, y1, c) * wx;
                ((top * (256 - wy) + bottom * wy + (1 << 15)) >> 16).min(255) as u8
            };
            *px = pack([channel(0), channel(1), channel(2)]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pelage::raster::RasterStats;
    use pelage::render::RenderedImage;

    fn image(width: u32, height: u32, rgba8: Vec<u8>) -> RenderedImage {
        RenderedImage {
            width,
            height,
            rgba8,
            stats: RasterStats::default(),
            warnings: Vec::new(),
        }
    }

    #[test]
    fn same_size_frames_are_copied_exactly() {
        let pixels: Vec<u8> = (0..3 * 2 * 4).map(|i| (i * 11) as u8).collect();
        let mut out = vec![0; 6];
        scale_into(&image(3, 2, pixels.clone()), &mut out, 3, 2);
        for (i, px) in out.iter().enumerate() {
            let p = &pixels[i * 4..];
            assert_eq!(*px, pack([p[0], p[1], p[2]]));
        }
    }

    #[test]
    fn smaller_frames_are_scaled_up_bilinearly_with_clamped_edges() {
        // Red then blue, scaled ×4 across: pure at the outer quarters, mixed between.
        let mut out = vec![0; 8];
        scale_into(
            &image(2, 1, vec![255, 0, 0, 255, 0, 0, 255, 255]),
            &mut out,
            8,
            1,
        );
        assert_eq!(out[0], 0xFF0000);
        assert_eq!(out[1], 0xFF0000);
        assert_eq!(out[6], 0x0000FF);
        assert_eq!(out[7], 0x0000FF);
        let red = |px: u32| px >> 16;
        assert!(
            red(out[2]) > red(out[3]) && red(out[3]) > red(out[4]) && red(out[4]) > red(out[5])
        );
        assert_eq!(red(out[3]) + (out[3] & 0xFF), 255);
    }

    #[test]
    fn the_frame_rate_agrees_with_the_frame_time() {
        for ms in [4.0, 16.7, 33.3, 70.0, 250.0, 1500.0] {
            let text = rate_text(ms, true);
            let fps: f64 = text
                .split(' ')
                .next()
                .and_then(|v| v.parse().ok())
                .expect("a number first");
            // The shown rate, rounded as shown, is 1000 / the shown time.
            let shown_ms: f64 = text
                .split('(')
                .nth(1)
                .and_then(|t| t.split(' ').next())
                .and_then(|v| v.parse().ok())
                .expect("the time");
            assert!((fps - 1000.0 / shown_ms).abs() <= 0.5 + 1e-9, "{text}");
            assert!(text.contains("ms a frame"), "{text}");
        }
        assert!(rate_text(40.0, false).starts_with("still"));
        assert_eq!(rate_text(0.0, true), "no frame time yet");
    }

    #[test]
    fn a_window_too_large_for_the_screen_is_scaled_down_keeping_its_aspect() {
        // 1366×768 on a 1280×800 screen: narrower and shorter than the screen, same shape.
        let (w, h) = fit_window(1366, 768, Some((1280, 800)));
        assert!(
            w <= 1280 - SCREEN_MARGIN.0 && h <= 800 - SCREEN_MARGIN.1,
            "{w}×{h}"
        );
        assert!(
            ((w as f64 / h as f64) - 1366.0 / 768.0).abs() < 0.01,
            "{w}×{h}"
        );
        // A window that fits keeps the image's size; no screen known: the image's size.
        assert_eq!(fit_window(640, 480, Some((1280, 800))), (640, 480));
        assert_eq!(fit_window(4000, 3000, None), (4000, 3000));
    }

    #[test]
    fn a_long_status_line_wraps_at_its_fields() {
        let text = "t 4.88 s  shells 30  texture 128  wind on  burn off  spots off  LOD off";
        let wide = wrap(text, 14.0, 2000);
        assert_eq!(wide, vec![text.to_string()]);
        let narrow = wrap(text, 14.0, 200);
        assert!(narrow.len() > 1, "{narrow:?}");
        assert!(narrow.iter().all(|l| font::text_width(l, 14.0) <= 200));
        assert_eq!(narrow.join("  "), text);
    }
}
