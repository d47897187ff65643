//! What the viewer shows: the scene as the user has edited it (camera, effects, fur counts) and
//! the clock. [`ViewState::apply`] turns an [`Action`] into an edit; every edit is validated
//! like a scene file, and refused (with a message) rather than applied if it is out of range.

use super::input::Action;
use super::orbit;
use glam::Vec3;
use pelage::scene::{
    BurnSettings, DebugView, GravitySettings, LodSettings, MapSettings, MatchSetting, Scene,
    SpotKind, SpotSettings, StripeSettings, WindSettings,
};

/// The viewer's clock: the scene's own `time` plus the seconds that have run since.
#[derive(Clone, Debug, PartialEq)]
pub struct Clock {
    start: f32,
    elapsed: f64,
    running: bool,
}

impl Clock {
    /// A clock at `start` seconds, running or not.
    pub fn new(start: f32, running: bool) -> Self {
        Clock {
            start,
            elapsed: 0.0,
            running,
        }
    }

    /// The instant shown, seconds.
    pub fn now(&self) -> f32 {
        (f64::from(self.start) + self.elapsed) as f32
    }

    /// Whether time runs.
    pub fn running(&self) -> bool {
        self.running
    }

    /// Lets `seconds` pass if the clock runs.
    pub fn advance(&mut self, seconds: f64) {
        if self.running {
            self.elapsed += seconds;
        }
    }
}

/// The viewer's state.
pub struct ViewState {
    /// The scene the user wants to see (its fur may still be baking).
    pub scene: Scene,
    /// The clock.
    pub clock: Clock,
    initial: Scene,
    wind: WindSettings,
    burn: BurnSettings,
    spots: Vec<SpotSettings>,
    stripes: Vec<StripeSettings>,
    lod: LodSettings,
    gravity: GravitySettings,
    maps: MapSettings,
    limits: Option<ViewLimits>,
}

/// The budgets every edit is checked against, as `pelage render` checks a scene
/// ([`pelage::limits`]): more shells or a finer texture must not bake past them.
#[derive(Clone, Debug)]
pub struct ViewLimits {
    /// The mesh's size (the viewer does not change the mesh).
    pub mesh: pelage::limits::MeshSize,
    /// Threads and frames held.
    pub work: pelage::limits::Workload,
    /// Memory and work limits.
    pub budgets: pelage::limits::Budgets,
}

/// Spots for scenes that have none, so `s` always shows something: two light-based spots
/// (thesis 3.2.4) fixed to the object, which land on any mesh.
fn example_spots() -> Vec<SpotSettings> {
    vec![
        SpotSettings {
            kind: SpotKind::Light,
            colour: Vec3::new(0.92, 0.9, 0.86),
            direction: Vec3::new(0.6, 0.5, 0.8),
            exponent: 40.0,
            ..SpotSettings::default()
        },
        SpotSettings {
            kind: SpotKind::Light,
            colour: Vec3::new(0.62, 0.44, 0.26),
            direction: Vec3::new(-0.7, 0.6, 0.4),
            exponent: 30.0,
            ..SpotSettings::default()
        },
    ]
}

const DEBUG_VIEWS: [DebugView; 4] = [
    DebugView::None,
    DebugView::Tangents,
    DebugView::Alpha,
    DebugView::Shadow,
];

/// Whether two scenes bake to the same fur textures (same seed, mesh and fur).
pub fn same_bake(a: &Scene, b: &Scene) -> bool {
    a.seed == b.seed
        && a.mesh == b.mesh
        && a.fur == b.fur
        && a.maps == b.maps
        && a.base_dir == b.base_dir
}

impl ViewState {
    /// The state at start: the scene as loaded, the clock at its `time`.
    pub fn new(scene: Scene, running: bool) -> Self {
        let spots_from_scene = !(scene.spots.is_empty() && scene.stripes.is_empty());
        ViewState {
            clock: Clock::new(scene.time, running),
            wind: scene.wind.clone().unwrap_or_default(),
            burn: scene.burn.clone().unwrap_or_default(),
            spots: if spots_from_scene {
                scene.spots.clone()
            } else {
                example_spots()
            },
            stripes: scene.stripes.clone(),
            lod: scene.lod.clone().unwrap_or_default(),
            gravity: scene.gravity.clone().unwrap_or_default(),
            maps: scene.maps.clone(),
            initial: scene.clone(),
            scene,
            limits: None,
        }
    }

    /// The state with every edit checked against `limits` too.
    pub fn with_limits(self, limits: ViewLimits) -> Self {
        ViewState {
            limits: Some(limits),
            ..self
        }
    }

    /// Whether the image depends on the clock (wind blows or fire burns).
    pub fn time_matters(&self) -> bool {
        self.scene.wind.is_some() || self.scene.burn.is_some()
    }

    /// The scene at the clock's instant.
    pub fn scene_now(&self) -> Scene {
        Scene {
            time: self.clock.now(),
            ..self.scene.clone()
        }
    }

    /// Applies an edit; `view_height` is the window height in pixels (for panning). Returns a
    /// message when the edit was refused or is worth telling. Actions that are not edits of the
    /// scene (screenshot, help, quit) change nothing here.
    pub fn apply(&mut self, action: Action, view_height: f32) -> Option<String> {
        let before = self.scene.clone();
        let s = &mut self.scene;
        let mut note = None;
        match action {
            Action::Orbit { yaw, pitch } => s.camera = orbit::orbit(&s.camera, yaw, pitch),
            Action::Pan { dx, dy } => s.camera = orbit::pan(&s.camera, dx, dy, view_height),
            Action::Zoom(factor) => s.camera = orbit::zoom(&s.camera, factor),
            Action::ResetCamera => s.camera = self.initial.camera.clone(),
            Action::ToggleWind => {
                s.wind = match s.wind.take() {
                    Some(w) => {
                        self.wind = w;
                        None
                    }
                    None => Some(self.wind.clone()),
                };
            }
            Action::StartBurn => {
                let mut burn = self.burn.clone();
                burn.start = self.clock.now();
                if self.initial.burn.is_none() {
                    // No matches in the scene: one on the side facing the camera.
                    burn.matches = vec![MatchSetting::Direction(
                        (s.camera.eye - s.camera.target).normalize_or(Vec3::Y),
                    )];
                }
                if !self.clock.running() {
                    note = Some("burning starts when time runs (space)".to_string());
                }
                s.burn = Some(burn);
            }
            Action::ResetBurn => s.burn = None,
            Action::ToggleSpots => {
                if s.spots.is_empty() && s.stripes.is_empty() {
                    s.spots = self.spots.clone();
                    s.stripes = self.stripes.clone();
                } else {
                    self.spots = std::mem::take(&mut s.spots);
                    self.stripes = std::mem::take(&mut s.stripes);
                }
            }
            Action::ToggleLod => {
                s.lod = match s.lod.take() {
                    Some(l) => {
                        self.lod = l;
                        None
                    }
                    None => Some(self.lod.clone()),
                };
            }
            Action::ToggleGravity => {
                s.gravity = match s.gravity.take() {
                    Some(g) => {
                        self.gravity = g;
                        None
                    }
                    None => Some(self.gravity.clone()),
                };
            }
            Action::ToggleMaps => {
                if !s.maps.is_empty() {
                    self.maps = std::mem::take(&mut s.maps);
                } else if self.maps.is_empty() {
                    note = Some("this scene has no surface maps ([maps])".to_string());
                } else {
                    s.maps = self.maps.clone();
                }
            }
            Action::Shells(delta) => {
                s.fur.number_of_shells = s.fur.number_of_shells.saturating_add_signed(delta).max(1);
            }
            Action::TextureResolution(step) => {
                let r = s.fur.texture_resolution;
                s.fur.texture_resolution = if step > 0 { r.saturating_mul(2) } else { r / 2 };
            }
            Action::DebugView(step) => {
                let i = DEBUG_VIEWS
                    .iter()
                    .position(|v| *v == s.shading.debug_view)
                    .unwrap_or(0) as i32;
                s.shading.debug_view = DEBUG_VIEWS[(i + step).rem_euclid(4) as usize];
            }
            Action::TogglePause => self.clock.running = !self.clock.running,
            Action::RestartTime => self.clock = Clock::new(self.initial.time, self.clock.running),
            Action::Screenshot | Action::ToggleHelp | Action::Quit => {}
        }
        if let Err(e) = self.scene.revalidate("view") {
            self.scene = before;
            // "view: fur.number_of_shells = 0 is outside 1..=256" → the key and the range.
            return Some(e.message);
        }
        if let Some(l) = &self.limits
            && let Err(e) = pelage::limits::check(&self.scene, l.mesh, &l.work, &l.budgets)
        {
            self.scene = before;
            return Some(format!("refused: {e}"));
        }
        note
    }

    /// One line of the current parameters for the status line.
    pub fn describe(&self) -> String {
        let s = &self.scene;
        let on = |b: bool| if b { "on" } else { "off" };
        let view = match s.shading.debug_view {
            DebugView::None => "shaded",
            DebugView::Tangents => "tangents",
            DebugView::Alpha => "alpha",
            DebugView::Shadow => "shadow",
        };
        format!(
            "t {:.2} s{}  shells {}  texture {}  wind {}  burn {}  spots {}  LOD {}  gravity {}  \
             maps {}  {view}",
            self.clock.now(),
            if self.clock.running() {
                ""
            } else {
                " (paused)"
            },
            s.fur.number_of_shells,
            s.fur.texture_resolution,
            on(s.wind.is_some()),
            on(s.burn.is_some()),
            on(!s.spots.is_empty() || !s.stripes.is_empty()),
            on(s.lod.is_some()),
            on(s.gravity.is_some()),
            if s.maps.is_empty() && self.maps.is_empty() {
                "none"
            } else {
                on(!s.maps.is_empty())
            },
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state() -> ViewState {
        ViewState::new(Scene::embedded_default().expect("default"), true)
    }

    #[test]
    fn the_clock_runs_only_when_running_and_restarts_at_the_scene_time() {
        let mut s = state();
        s.clock.advance(0.5);
        assert_eq!(s.clock.now(), 0.5);
        s.apply(Action::TogglePause, 480.0);
        s.clock.advance(2.0);
        assert_eq!(s.clock.now(), 0.5);
        s.apply(Action::RestartTime, 480.0);
        assert_eq!(s.clock.now(), 0.0);
        assert!(!s.clock.running());
    }

    #[test]
    fn wind_toggles_and_keeps_its_settings() {
        let mut s = state();
        assert!(s.scene.wind.is_none() && !s.time_matters());
        s.apply(Action::ToggleWind, 480.0);
        assert_eq!(s.scene.wind, Some(WindSettings::default()));
        assert!(s.time_matters());
        s.apply(Action::ToggleWind, 480.0);
        assert!(s.scene.wind.is_none());
    }

    #[test]
    fn burning_starts_now_facing_the_camera_and_resets() {
        let mut s = state();
        s.clock.advance(1.25);
        s.apply(Action::StartBurn, 480.0);
        let burn = s.scene.burn.clone().expect("burning");
        assert_eq!(burn.start, 1.25);
        let towards_eye = (s.scene.camera.eye - s.scene.camera.target).normalize();
        assert!(
            matches!(burn.matches[0], MatchSetting::Direction(d) if (d - towards_eye).length() < 1e-6)
        );
        s.apply(Action::ResetBurn, 480.0);
        assert!(s.scene.burn.is_none());
    }

    #[test]
    fn spots_toggle_off_and_back_and_scenes_without_spots_get_examples() {
        // The embedded torus has the thesis's 12 spots: off, then back as they were.
        let mut s = state();
        let own = s.scene.spots.clone();
        assert_eq!(own.len(), 12);
        s.apply(Action::ToggleSpots, 480.0);
        assert!(s.scene.spots.is_empty());
        s.apply(Action::ToggleSpots, 480.0);
        assert_eq!(s.scene.spots, own);
        // A scene without spots gets two examples.
        let mut bare = Scene::embedded_default().expect("default");
        bare.spots.clear();
        let mut s = ViewState::new(bare, true);
        assert!(s.scene.spots.is_empty());
        s.apply(Action::ToggleSpots, 480.0);
        assert_eq!(s.scene.spots.len(), 2);
        let shown = s.scene.spots.clone();
        s.apply(Action::ToggleSpots, 480.0);
        assert!(s.scene.spots.is_empty());
        s.apply(Action::ToggleSpots, 480.0);
        assert_eq!(s.scene.spots, shown);
    }

    #[test]
    fn shells_and_texture_resolution_stay_in_range_with_a_message() {
        let mut s = state();
        let shells = s.scene.fur.number_of_shells;
        assert_eq!(s.apply(Action::Shells(1), 480.0), None);
        assert_eq!(s.scene.fur.number_of_shells, shells + 1);
        s.apply(Action::Shells(-1000), 480.0);
        assert_eq!(s.scene.fur.number_of_shells, 1);
        let message = s.apply(Action::Shells(1000), 480.0).expect("refused");
        assert!(message.contains("fur.number_of_shells"), "{message}");
        assert_eq!(s.scene.fur.number_of_shells, 1);
        for _ in 0..10 {
            s.apply(Action::TextureResolution(-1), 480.0);
        }
        assert_eq!(s.scene.fur.texture_resolution, 4);
        assert!(!same_bake(&s.scene, &s.initial));
    }

    #[test]
    fn edits_past_the_memory_limit_are_refused_and_undone() {
        let scene = Scene::embedded_default().expect("default");
        let mesh = pelage::limits::mesh_size(&scene).expect("procedural");
        let work = pelage::limits::Workload::default();
        let start = pelage::limits::estimate_memory(&scene, mesh, &work).total();
        let mut s = ViewState::new(scene, true).with_limits(ViewLimits {
            mesh,
            work,
            budgets: pelage::limits::Budgets {
                memory: 2 * start,
                bake_work: u64::MAX,
                draw_work: u64::MAX,
            },
        });
        let resolution = s.scene.fur.texture_resolution;
        // Doubling the texture resolution four times is 256 times the shell textures.
        let mut refused = None;
        for _ in 0..4 {
            refused = refused.or(s.apply(Action::TextureResolution(1), 480.0));
        }
        let message = refused.expect("an edit past the limit is refused");
        assert!(message.contains("needs about"), "{message}");
        assert!(message.contains("more than the limit"), "{message}");
        let kept = s.scene.fur.texture_resolution;
        assert!(kept >= resolution && kept < 16 * resolution, "{kept}");
        assert!(
            pelage::limits::estimate_memory(&s.scene, mesh, &work).total() <= 2 * start,
            "the refused edit was undone"
        );
    }

    #[test]
    fn debug_views_cycle_both_ways() {
        let mut s = state();
        s.apply(Action::DebugView(1), 480.0);
        assert_eq!(s.scene.shading.debug_view, DebugView::Tangents);
        s.apply(Action::DebugView(-1), 480.0);
        s.apply(Action::DebugView(-1), 480.0);
        assert_eq!(s.scene.shading.debug_view, DebugView::Shadow);
    }

    #[test]
    fn camera_moves_do_not_need_a_bake_and_reset_returns() {
        let mut s = state();
        s.apply(
            Action::Orbit {
                yaw: 0.3,
                pitch: 0.1,
            },
            480.0,
        );
        s.apply(Action::Pan { dx: 10.0, dy: 5.0 }, 480.0);
        s.apply(Action::Zoom(0.8), 480.0);
        assert_ne!(s.scene.camera, s.initial.camera);
        assert!(same_bake(&s.scene, &s.initial));
        s.apply(Action::ResetCamera, 480.0);
        assert_eq!(s.scene.camera, s.initial.camera);
        assert!(s.describe().contains("shells 40"), "{}", s.describe());
    }

    #[test]
    fn lod_gravity_and_maps_toggle_and_keep_their_settings() {
        let mut s = state();
        assert!(s.scene.lod.is_none() && s.scene.gravity.is_none());
        s.apply(Action::ToggleLod, 480.0);
        assert_eq!(s.scene.lod, Some(LodSettings::default()));
        s.apply(Action::ToggleGravity, 480.0);
        assert_eq!(s.scene.gravity, Some(GravitySettings::default()));
        assert!(
            s.describe().contains("LOD on  gravity on  maps none"),
            "{}",
            s.describe()
        );
        s.apply(Action::ToggleLod, 480.0);
        s.apply(Action::ToggleGravity, 480.0);
        assert!(s.scene.lod.is_none() && s.scene.gravity.is_none());
        // No maps in the scene: a note, nothing changes.
        let note = s.apply(Action::ToggleMaps, 480.0).expect("note");
        assert!(note.contains("no surface maps"), "{note}");
        // A scene with maps: off (a different bake), then back as they were.
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/painted-length.toml");
        let scene = Scene::load(std::path::Path::new(path)).expect("scene");
        assert!(!scene.maps.is_empty());
        let mut s = ViewState::new(scene, true);
        let own = s.scene.maps.clone();
        s.apply(Action::ToggleMaps, 480.0);
        assert!(s.scene.maps.is_empty());
        assert!(!same_bake(&s.scene, &s.initial));
        assert!(s.describe().contains("maps off"));
        s.apply(Action::ToggleMaps, 480.0);
        assert_eq!(s.scene.maps, own);
    }
}
