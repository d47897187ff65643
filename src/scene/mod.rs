//! Scenes (scene stage): TOML files parsed into a typed, range-checked [`Scene`].
//!
//! Every key has a default (the thesis's base values of chapter 4.1 where it gives one), unknown
//! keys are errors, and every value is range-checked. Errors name the file, the line and the
//! key (`scenes/x.toml:12: fur.number_of_shells = 0 is outside 1..=256`).

mod validate;

use glam::Vec3;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

pub use validate::Limits;

/// The largest `time` a scene (or an animation's last frame) may have, seconds, either sign.
pub const MAX_TIME: f32 = 1.0e6;

/// The furred torus of thesis figure 3.1, embedded so `pelage render` works with no file.
pub const DEFAULT_SCENE: &str = include_str!("../../scenes/torus.toml");
/// Largest scene file accepted, bytes (a scene is a few hundred bytes; this only stops a
/// wrong path from reading a huge file).
pub const MAX_SCENE_BYTES: u64 = 16 << 20;
/// The name errors use for the embedded scene.
pub const DEFAULT_SCENE_NAME: &str = "<embedded scenes/torus.toml>";

/// A scene that failed to load: where, and why.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{file}{}: {message}", line.map(|l| format!(":{l}")).unwrap_or_default())]
pub struct SceneError {
    /// The scene file.
    pub file: String,
    /// 1-based line of the offending key, when known.
    pub line: Option<usize>,
    /// What is wrong, naming the key.
    pub message: String,
}

/// A whole scene.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct Scene {
    /// Every random choice derives from this seed.
    pub seed: u32,
    /// Output image.
    pub image: ImageSettings,
    /// The camera.
    pub camera: CameraSettings,
    /// The furred object.
    pub mesh: MeshSettings,
    /// Fur modelling parameters (thesis 3.1, chapter 4.1 names).
    pub fur: FurSettings,
    /// Shading parameters (thesis 3.2).
    pub shading: ShadingSettings,
    /// The directional light.
    pub light: LightSettings,
    /// The instant rendered, seconds (wind and burning depend on it).
    pub time: f32,
    /// Spots (thesis 3.2.4), applied in order, a later spot over an earlier one.
    pub spots: Vec<SpotSettings>,
    /// Stripes (thesis 3.2.4, figure 3.14), applied after the spots.
    pub stripes: Vec<StripeSettings>,
    /// Wind (thesis 3.3); absent means still air.
    pub wind: Option<WindSettings>,
    /// Burning (thesis 3.4); absent means no fire.
    pub burn: Option<BurnSettings>,
    /// Length, density, direction and colour maps in mesh uv space; absent: uniform fur.
    #[serde(skip_serializing_if = "MapSettings::is_empty")]
    pub maps: MapSettings,
    /// Level of detail by distance; absent: every shell, always.
    pub lod: Option<LodSettings>,
    /// Gravity bending the fur at rest; absent: none.
    pub gravity: Option<GravitySettings>,
    /// The object moving along a path, its fur lagging on damped springs; absent: at rest.
    pub motion: Option<MotionSettings>,
    /// A glTF model's animation clip played at the scene time; absent: the rest pose.
    pub animation: Option<AnimationSettings>,
    /// Directory relative paths are resolved against (the scene file's folder).
    #[serde(skip)]
    pub base_dir: PathBuf,
}

impl Default for Scene {
    fn default() -> Self {
        Scene {
            seed: 1234,
            image: ImageSettings::default(),
            camera: CameraSettings::default(),
            mesh: MeshSettings::default(),
            fur: FurSettings::default(),
            shading: ShadingSettings::default(),
            light: LightSettings::default(),
            time: 0.0,
            spots: Vec::new(),
            stripes: Vec::new(),
            wind: None,
            burn: None,
            maps: MapSettings::default(),
            lod: None,
            gravity: None,
            motion: None,
            animation: None,
            base_dir: PathBuf::from("."),
        }
    }
}

/// `[image]`
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct ImageSettings {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Clear colour, RGB in [0, 1].
    pub background: Vec3,
}

impl Default for ImageSettings {
    fn default() -> Self {
        ImageSettings {
            width: 640,
            height: 480,
            background: Vec3::new(0.32, 0.36, 0.42),
        }
    }
}

/// `[camera]`
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct CameraSettings {
    /// Eye position.
    pub eye: Vec3,
    /// Point looked at.
    pub target: Vec3,
    /// Up direction.
    pub up: Vec3,
    /// Vertical field of view, degrees.
    pub fov_y_deg: f32,
    /// Near plane.
    pub near: f32,
    /// Far plane.
    pub far: f32,
}

impl Default for CameraSettings {
    fn default() -> Self {
        CameraSettings {
            eye: Vec3::new(0.0, 9.0, 14.0),
            target: Vec3::ZERO,
            up: Vec3::Y,
            fov_y_deg: 45.0,
            near: 0.1,
            far: 100.0,
        }
    }
}

impl CameraSettings {
    /// The camera moved along its line of sight to `distance` from its target (thesis table
    /// 4.5, figure 4.1). At distance 0 the eye sits on the target and the target moves one unit
    /// on along the same line, so the view direction is kept. A camera whose eye is already on
    /// its target has no line of sight and is returned unchanged.
    pub fn at_distance(&self, distance: f32) -> CameraSettings {
        let Some(direction) = (self.eye - self.target).try_normalize() else {
            return self.clone();
        };
        let mut moved = self.clone();
        moved.eye = self.target + (self.eye - self.target).normalize() * distance;
        if distance == 0.0 {
            moved.target = self.target - direction;
        }
        moved
    }
}

/// Which object carries the fur.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum MeshKind {
    /// The thesis's main object.
    #[default]
    Torus,
    /// A UV sphere.
    Sphere,
    /// An open tube.
    Cylinder,
    /// A procedural leg (thesis figure 3.11).
    Leg,
    /// A Wavefront OBJ file (`path`, relative to the scene file).
    Obj,
    /// A glTF 2.0 model, `.glb` or `.gltf` (`path`, relative to the scene file; `node` picks
    /// one node's subtree), skinned and posed at the scene time by `[animation]`.
    Gltf,
}

/// `[mesh]`
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct MeshSettings {
    /// The object.
    pub kind: MeshKind,
    /// Torus: distance from the centre to the tube's centre.
    pub major_radius: f32,
    /// Torus: tube radius.
    pub minor_radius: f32,
    /// Sphere and cylinder: radius. (The leg has its own profile; `scale` sizes it.)
    pub radius: f32,
    /// Cylinder: length.
    pub height: f32,
    /// Triangle count of procedural meshes (thesis `modelResolution`, base 500).
    pub model_resolution: u32,
    /// OBJ or glTF file, relative to the scene file.
    pub path: Option<PathBuf>,
    /// glTF: the node whose subtree's meshes carry the fur (default: every mesh of the default
    /// scene).
    pub node: Option<String>,
    /// Uniform scale applied to OBJ, glTF and leg positions (the leg is about 2 units tall at 1).
    pub scale: f32,
}

impl Default for MeshSettings {
    fn default() -> Self {
        MeshSettings {
            kind: MeshKind::Torus,
            major_radius: 6.0,
            minor_radius: 2.4,
            radius: 2.0,
            height: 4.0,
            model_resolution: 500,
            path: None,
            node: None,
            scale: 1.0,
        }
    }
}

/// How shells are spaced between the skin and `model_difference`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum ShellSpacingSetting {
    /// Equal steps.
    #[default]
    Uniform,
    /// Closer together towards the tips (thesis 3.1.4, for few shells).
    DenserNearTip,
}

/// Which mesh edges get fins.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum FinSelectionSetting {
    /// The true outline: edges between a face turned to the eye and one turned away, and border
    /// edges; each fin's opacity is how squarely it faces the eye
    /// ([`crate::mesh::fins::outline_edges`], [`crate::mesh::fins::fin_facing`]).
    #[default]
    Outline,
    /// The thesis (3.1.2.2): edges whose angle between eye vector and normal lies in
    /// `fin_windows`, faded towards the windows' ends.
    AngleWindows,
}

/// `[fur]`: names follow the thesis (chapter 4.1).
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct FurSettings {
    /// Strands in one texture tile (`numberOfStrands`, base 1000).
    pub number_of_strands: u32,
    /// Bézier segments per strand (`strandResolution`, base 20).
    pub strand_resolution: u32,
    /// Facets around a strand's cone (`circleResolution`, base 10).
    pub circle_resolution: u32,
    /// Shell layers (`numberOfShells`, base 10).
    pub number_of_shells: u32,
    /// Texels per side of a shell texture (`textureResolution`, base 128).
    pub texture_resolution: u32,
    /// Distance from the skin to the outermost shell, world units (`modelDifference`, base 1.0).
    /// Negative *thins* the object (thesis figure 3.10): the skin is moved inward along the vertex
    /// normals by the magnitude and the fur grows from there up to the original surface.
    pub model_difference: f32,
    /// Shell spacing.
    pub shell_spacing: ShellSpacingSetting,
    /// How many times the fur tile repeats along the mesh's u and v.
    pub texture_repeat: [f32; 2],
    /// Fur colour, RGB.
    pub colour: Vec3,
    /// Per-strand brightness variation, 0..1.
    pub colour_variation: f32,
    /// Strand lean from the vertical, degrees.
    pub slope_deg: f32,
    /// Extra bend of the tip, 0..1.
    pub curl: f32,
    /// Random jitter of the Bézier points, 0..1.
    pub jitter: f32,
    /// Shortest strand, as a fraction of the longest.
    pub min_height: f32,
    /// Strand radius at the root, in tile widths.
    pub base_thickness: f32,
    /// Strand radius at the tip, in tile widths.
    pub tip_thickness: f32,
    /// Supersampling factor of the bake (thesis 3.1.3).
    pub supersample: u32,
    /// Width of the Gaussian alpha falloff over height, as a fraction of the strand height.
    pub gaussian_sigma: f32,
    /// Whether fins are drawn at silhouettes.
    pub fins: bool,
    /// Which edges get fins: the outline (default) or the thesis's angle windows.
    pub fin_selection: FinSelectionSetting,
    /// Angle windows, degrees, between eye vector and normal where fins are drawn (with
    /// `fin_selection = "angle_windows"`).
    pub fin_windows: Vec<[f32; 2]>,
    /// Fin strands are this much taller than shell strands.
    pub fin_height_scale: f32,
    /// glTF models: the material's base-colour texture × factor at the root multiplies the
    /// strand colour (as a `maps.colour` map would).
    pub colour_from_mesh: bool,
}

impl FurSettings {
    /// The fur's length, world units: the magnitude of `model_difference`.
    pub fn fur_length(&self) -> f32 {
        self.model_difference.abs()
    }

    /// How far the skin is moved along its vertex normals before the fur grows from it:
    /// `model_difference` when negative (the object thinned), else 0.
    pub fn skin_inset(&self) -> f32 {
        self.model_difference.min(0.0)
    }
}

impl Default for FurSettings {
    fn default() -> Self {
        FurSettings {
            number_of_strands: 1000,
            strand_resolution: 20,
            circle_resolution: 10,
            number_of_shells: 10,
            texture_resolution: 128,
            model_difference: 1.0,
            shell_spacing: ShellSpacingSetting::Uniform,
            texture_repeat: [8.0, 4.0],
            colour: Vec3::new(0.36, 0.2, 0.09),
            colour_variation: 0.25,
            slope_deg: 20.0,
            curl: 0.3,
            jitter: 0.3,
            min_height: 0.7,
            base_thickness: 0.012,
            tip_thickness: 0.004,
            supersample: 2,
            gaussian_sigma: 0.6,
            fins: true,
            fin_selection: FinSelectionSetting::Outline,
            fin_windows: vec![[70.0, 110.0], [160.0, 200.0]],
            fin_height_scale: 1.2,
            colour_from_mesh: false,
        }
    }
}

/// Debug views replacing the shaded colour.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum DebugView {
    /// Normal shading.
    #[default]
    None,
    /// The strand tangents as colours (thesis figure 3.8).
    Tangents,
    /// The shell alpha as grey.
    Alpha,
    /// The shell self-shadow alone.
    Shadow,
}

/// How the three lobes of the three-tangent specular combine (thesis eq. 3.5;
/// [`crate::shading::SpecularLobes`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum SpecularLobesSetting {
    /// Their sum, as the thesis says (3.2.3), in `[0, 3]`.
    Sum,
    /// Their mean, in `[0, 1]` like one lobe: the default.
    #[default]
    Average,
}

/// Where `ψ_ambient` of eq. 3.7 stands ([`crate::shading::AmbientTerm`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum AmbientTermSetting {
    /// Eq. 3.7 as printed: `ψ_ambient = ambient`, outside the strand colour (a grey lift).
    Constant,
    /// `ψ_ambient = ambient · strandColor`: an ambient light reflected by the strand: the
    /// default.
    #[default]
    Strand,
}

/// Which equation of thesis 3.2.3 lights the fur ([`crate::shading::LightingModel`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize, Default)]
pub enum LightingSetting {
    /// Eq. 3.6 with the shadow of eq. 3.7: the dampened specular as the uncoloured last term;
    /// the default.
    #[default]
    #[serde(rename = "eq-3.6")]
    Eq36,
    /// Eq. 3.5: `(ψ_specularity1)^n` as the uncoloured last term, `n` =
    /// `shading.specular1_exponent` (thesis figure 3.13).
    #[serde(rename = "eq-3.5")]
    Eq35,
}

/// What one shell-shadow lookup adds (thesis 3.2.2; [`crate::shading::ShadowTexel`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum ShadowTexelSetting {
    /// 1 for a texel that is not transparent, 0 otherwise: the thesis's count.
    Opaque,
    /// The texel's alpha: the continuous form of the count; the default.
    #[default]
    Alpha,
}

/// Term weights of eq. 3.7.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct WeightSettings {
    /// Ambient weight.
    pub ambient: f32,
    /// Diffuse weight.
    pub diffuse: f32,
    /// Specular weight.
    pub specular: f32,
    /// Dampened specular weight.
    pub dampened: f32,
    /// Shadow weight.
    pub shadow: f32,
}

impl Default for WeightSettings {
    fn default() -> Self {
        WeightSettings {
            ambient: 1.0,
            diffuse: 1.0,
            specular: 0.5,
            dampened: 0.45,
            shadow: 0.12,
        }
    }
}

/// `[shading]`
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct ShadingSettings {
    /// Ambient level (`ψ_ambient`, times the strand colour or not: `ambient_term`).
    pub ambient: f32,
    /// Banks's exponent on the Kajiya–Kay diffuse (4.8).
    pub banks_exponent: f32,
    /// Kajiya–Kay specular exponent.
    pub specular_exponent: f32,
    /// The low exponent of the dampened specular (eq. 3.6/3.7).
    pub dampened_exponent: f32,
    /// The lighting equation: eq. 3.6/3.7 (dampened specular) or eq. 3.5.
    pub lighting: LightingSetting,
    /// `n` of eq. 3.5's `(ψ_specularity1)^n` (with `lighting = "eq-3.5"`).
    pub specular1_exponent: f32,
    /// 1 or 3 specular tangents (Scheuermann).
    pub specular_tangents: u32,
    /// With 3 tangents: the sum (thesis) or the mean of the three lobes.
    pub specular_lobes: SpecularLobesSetting,
    /// `ψ_ambient` of eq. 3.7: `ambient` alone, or `ambient · strandColour`.
    pub ambient_term: AmbientTermSetting,
    /// What each shell-shadow lookup adds: 1 if opaque (thesis), or the texel's alpha.
    pub shadow_texel: ShadowTexelSetting,
    /// How far the two extra tangents are shifted along the normal.
    pub tangent_shift: f32,
    /// n of "height/n" (table 4.4): the bottom layer makes N/n shadow lookups.
    pub shadow_divisor: u32,
    /// Term weights.
    pub weights: WeightSettings,
    /// Replace shading with a debug view.
    pub debug_view: DebugView,
}

impl Default for ShadingSettings {
    fn default() -> Self {
        ShadingSettings {
            ambient: 0.25,
            banks_exponent: 4.8,
            specular_exponent: 24.0,
            dampened_exponent: 4.0,
            lighting: LightingSetting::default(),
            specular1_exponent: 1.0,
            specular_tangents: 1,
            specular_lobes: SpecularLobesSetting::default(),
            ambient_term: AmbientTermSetting::default(),
            shadow_texel: ShadowTexelSetting::default(),
            tangent_shift: 0.15,
            shadow_divisor: 5,
            weights: WeightSettings::default(),
            debug_view: DebugView::None,
        }
    }
}

/// `[light]`
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct LightSettings {
    /// Direction towards the light (normalised on use).
    pub direction: Vec3,
    /// Light colour.
    pub colour: Vec3,
}

impl Default for LightSettings {
    fn default() -> Self {
        LightSettings {
            direction: Vec3::new(0.9, 0.7, 0.3),
            colour: Vec3::ONE,
        }
    }
}

/// How a spot decides where it is (thesis 3.2.4).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum SpotKind {
    /// Inside an ellipsoid in object space.
    #[default]
    Ellipsoid,
    /// Where a light fixed to the object would make a specular lobe.
    Light,
}

/// `[[spots]]`: one spot. The inner part takes the full spot colour, a ring blends back to the fur.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct SpotSettings {
    /// Geometric (ellipsoid) or light-based.
    pub kind: SpotKind,
    /// Spot colour, RGB.
    pub colour: Vec3,
    /// Ellipsoid: centre, object space.
    pub centre: Vec3,
    /// Ellipsoid: semi-axes.
    pub radii: Vec3,
    /// Ellipsoid: the full-colour inner part, as a fraction of the radii (0..=1).
    pub inner: f32,
    /// Light: direction of the light fixed to the object.
    pub direction: Vec3,
    /// Light: the light's position instead of a direction, object space (on or a little above
    /// the surface): the lobe then follows the direction towards it, and `reach` bounds it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub position: Option<Vec3>,
    /// Light at a `position`: the distance (object units) at which it fades out
    /// ([`crate::shading::reach_falloff`]); required with `position`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reach: Option<f32>,
    /// Light: exponent of the lobe (larger is smaller).
    pub exponent: f32,
    /// Light: lobe intensity from which the colour is full.
    pub inner_threshold: f32,
    /// Light: lobe intensity where the ring ends.
    pub outer_threshold: f32,
}

impl Default for SpotSettings {
    fn default() -> Self {
        SpotSettings {
            kind: SpotKind::Ellipsoid,
            colour: Vec3::new(0.85, 0.8, 0.7),
            centre: Vec3::ZERO,
            radii: Vec3::ONE,
            inner: 0.6,
            direction: Vec3::Y,
            position: None,
            reach: None,
            exponent: 20.0,
            inner_threshold: 0.7,
            outer_threshold: 0.3,
        }
    }
}

/// How a stripe decides where its bands are (thesis 3.2.4).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum StripeKind {
    /// Bands of the specular lobe of a light fixed to the object, periodic in the lobe's value
    /// (thesis 3.2.4: "we use the specular value to add spots and stripes"): the default.
    #[default]
    Light,
    /// Bands across an object-space axis, periodic in object units.
    Axis,
}

/// `[[stripes]]`: periodic bands in the lobe of a light fixed to the object (`kind = "light"`,
/// the thesis's) or across an object-space axis (`kind = "axis"`).
///
/// The keys of the other kind are refused (an `axis` on a light stripe is an error naming it),
/// so a file written when axis stripes were the only kind fails loudly instead of drawing
/// something else. Keys left out take the defaults of the stripe's kind: the accessors
/// ([`StripeSettings::period`], …) give the values in use.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct StripeSettings {
    /// Light bands (default) or axis bands.
    pub kind: StripeKind,
    /// Stripe colour.
    pub colour: Vec3,
    /// Axis only: the bands run across this object-space direction (default `[1, 0, 0]`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub axis: Option<Vec3>,
    /// Light only: direction of the light fixed to the object (default `[0, 1, 0]`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub direction: Option<Vec3>,
    /// Light only: exponent of the lobe `max(0, n̂·l̂)^exponent` (default 1).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub exponent: Option<f32>,
    /// Distance between stripe centres: lobe values (light, default 0.25) or object units
    /// (axis, default 4).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub period: Option<f32>,
    /// Width of the full-colour core, in the units of `period` (default 0.07 or 0.8).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub width: Option<f32>,
    /// Width of the blend on each side, in the units of `period` (default 0.03 or 0.3).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub softness: Option<f32>,
}

impl Default for StripeSettings {
    fn default() -> Self {
        StripeSettings {
            kind: StripeKind::default(),
            colour: Vec3::new(0.92, 0.9, 0.86),
            axis: None,
            direction: None,
            exponent: None,
            period: None,
            width: None,
            softness: None,
        }
    }
}

impl StripeSettings {
    /// The axis in use (axis stripes).
    pub fn axis(&self) -> Vec3 {
        self.axis.unwrap_or(Vec3::X)
    }

    /// The direction of the light in use (light stripes).
    pub fn direction(&self) -> Vec3 {
        self.direction.unwrap_or(Vec3::Y)
    }

    /// The lobe exponent in use (light stripes).
    pub fn exponent(&self) -> f32 {
        self.exponent.unwrap_or(1.0)
    }

    /// The period in use: the stripe's own, or its kind's default.
    pub fn period(&self) -> f32 {
        self.period.unwrap_or(match self.kind {
            StripeKind::Light => 0.25,
            StripeKind::Axis => 4.0,
        })
    }

    /// The core width in use.
    pub fn width(&self) -> f32 {
        self.width.unwrap_or(match self.kind {
            StripeKind::Light => 0.07,
            StripeKind::Axis => 0.8,
        })
    }

    /// The blend width in use.
    pub fn softness(&self) -> f32 {
        self.softness.unwrap_or(match self.kind {
            StripeKind::Light => 0.03,
            StripeKind::Axis => 0.3,
        })
    }
}

/// `[wind]` (thesis 3.3).
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct WindSettings {
    /// Direction the wind blows towards.
    pub direction: Vec3,
    /// Gust strength (bend, as the sine of the bend angle, before limiting).
    pub strength: f32,
    /// Gusts per second.
    pub frequency: f32,
    /// How fast the elastic vibration dies within a gust.
    pub elasticity: f32,
    /// Largest bend, as the sine of the bend angle (0..=1).
    pub max_bend: f32,
    /// How much of the wind the strand tangents take at the tips (thesis 3.3.1).
    pub tangent_fraction: f32,
    /// Whether the layers are pulled back along −normal as they bend, so the strands keep
    /// their length (thesis 3.3; default `true`). `false` does the animation "solely in the
    /// fragment shader", which the thesis shows stretching the strands (figure 3.16).
    pub keep_length: bool,
}

impl WindSettings {
    /// The wind model's parameters (thesis 3.3).
    pub fn params(&self) -> crate::shading::WindParams {
        crate::shading::WindParams {
            direction: self.direction,
            strength: self.strength,
            frequency: self.frequency,
            elasticity: self.elasticity,
            max_bend: self.max_bend,
        }
    }

    /// The unit wind direction and the force at `time` (push and elastic return, thesis 3.3).
    pub fn direction_and_force(&self, time: f32) -> (Vec3, f32) {
        (
            self.direction.normalize_or_zero(),
            crate::shading::wind_force(time, &self.params()),
        )
    }
}

impl Default for WindSettings {
    fn default() -> Self {
        WindSettings {
            direction: Vec3::X,
            strength: 0.6,
            frequency: 0.5,
            elasticity: 3.0,
            max_bend: 0.6,
            tangent_fraction: 0.5,
            keep_length: true,
        }
    }
}

/// `[burn]` (thesis 3.4): matches are spot lights fixed to the object; their exponent follows a
/// schedule, so the burnt area appears at `start` and then spreads.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct BurnSettings {
    /// The matches: each a direction from the object's centre, or a point with a reach
    /// (object space).
    pub matches: Vec<MatchSetting>,
    /// When the matches light, seconds.
    pub start: f32,
    /// Exponent right after `start`: only the area nearest the match burns.
    pub high_exponent: f32,
    /// Exponent after `spread_duration`: the burnt area's final size.
    pub low_exponent: f32,
    /// Seconds from `start` over which the exponent falls.
    pub spread_duration: f32,
}

impl Default for BurnSettings {
    fn default() -> Self {
        BurnSettings {
            matches: vec![MatchSetting::Direction(Vec3::Y)],
            start: 0.0,
            high_exponent: 200.0,
            low_exponent: 4.0,
            spread_duration: 10.0,
        }
    }
}

/// One match of `[burn] matches`: `[x, y, z]`, a light fixed to the object by direction (the
/// thesis's lobe of the normal alone, which on a torus also burns the inner wall facing the
/// same way), or `{ position = [x, y, z], reach = r }`, a light at a point on or a little above
/// the surface whose lobe follows the direction towards it and fades out by `reach`
/// ([`crate::shading::point_light_intensity`]), so that one match burns one region.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(untagged)]
pub enum MatchSetting {
    /// Towards this direction (object space).
    Direction(Vec3),
    /// At this point.
    Point(PointMatch),
}

/// A match at a point: `{ position = [x, y, z], reach = r }`.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PointMatch {
    /// Where the match is held, object space (a little above the surface, so that the fur
    /// straight under it faces it).
    pub position: Vec3,
    /// The distance at which its light fades out (object units).
    pub reach: f32,
}

impl<'de> Deserialize<'de> for MatchSetting {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct MatchVisitor;
        impl<'de> serde::de::Visitor<'de> for MatchVisitor {
            type Value = MatchSetting;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str(
                    "a match: a direction [x, y, z] or a point { position = [x, y, z], reach = r }",
                )
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                seq: A,
            ) -> Result<Self::Value, A::Error> {
                Vec3::deserialize(serde::de::value::SeqAccessDeserializer::new(seq))
                    .map(MatchSetting::Direction)
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                map: A,
            ) -> Result<Self::Value, A::Error> {
                PointMatch::deserialize(serde::de::value::MapAccessDeserializer::new(map))
                    .map(MatchSetting::Point)
            }
        }
        deserializer.deserialize_any(MatchVisitor)
    }
}

/// How a map is addressed outside `[0, 1]` (and between its edge texel centres).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum MapAddressSetting {
    /// Coordinates clamp to the edge texels.
    #[default]
    Clamp,
    /// The map repeats (for uv seams a map must cross, like a torus's).
    Wrap,
}

/// `[maps]`: PNG images in mesh uv space (`u` across, `v = 0` on the first row), paths relative
/// to the scene file. Each is optional; absent means the thesis's uniform fur.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize, Default)]
#[serde(deny_unknown_fields, default)]
pub struct MapSettings {
    /// Fur length (red channel, 0..1 of `model_difference`).
    pub length: Option<PathBuf>,
    /// Fraction of strands kept (red channel, 0..1).
    pub density: Option<PathBuf>,
    /// Combing direction: red, green = tangent-space `u`, `v` components as `c·2 − 1`; the
    /// vector's length is the lean (sine of the angle); 128, 128 = upright.
    pub direction: Option<PathBuf>,
    /// Multiplies the strand colour (RGB).
    pub colour: Option<PathBuf>,
    /// Addressing of every map along `u` and `v`.
    pub address: [MapAddressSetting; 2],
}

impl MapSettings {
    /// Whether no map is given.
    pub fn is_empty(&self) -> bool {
        self.length.is_none()
            && self.density.is_none()
            && self.direction.is_none()
            && self.colour.is_none()
    }
}

/// `[lod]`: fewer shells as the fur gets smaller on screen.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct LodSettings {
    /// Screen height of the fur, pixels, that one drawn shell stands for.
    pub pixels_per_shell: f32,
    /// Fewest shells drawn.
    pub min_shells: u32,
    /// Fins fade out between these on-screen fur heights, pixels (gone below the first, whole
    /// above the second).
    pub fin_fade_pixels: [f32; 2],
}

impl Default for LodSettings {
    fn default() -> Self {
        LodSettings {
            pixels_per_shell: 3.0,
            min_shells: 4,
            fin_fade_pixels: [1.0, 3.0],
        }
    }
}

/// `[gravity]`: bends the fur at rest.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct GravitySettings {
    /// Direction of gravity, world space.
    pub direction: Vec3,
    /// Bend where the fur stands at right angles to gravity, as the sine of the bend angle.
    pub strength: f32,
}

impl Default for GravitySettings {
    fn default() -> Self {
        GravitySettings {
            direction: Vec3::NEG_Y,
            strength: 0.4,
        }
    }
}

/// `[motion]`: the object follows a path; its fur tips lag behind on damped springs.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct MotionSettings {
    /// Keyframes `[t, x, y, z]`: the object's offset at time `t`, linear in between, held before
    /// the first and after the last. Times must increase.
    pub path: Vec<[f32; 4]>,
    /// Natural frequency of the strands' spring, Hz.
    pub frequency: f32,
    /// Damping ratio of the spring (0 < ζ < 1: it swings back past rest and settles).
    pub damping: f32,
    /// Tip lag per unit of spring displacement, as a bend (sine of the angle) per world unit.
    pub response: f32,
}

impl Default for MotionSettings {
    fn default() -> Self {
        MotionSettings {
            path: Vec::new(),
            frequency: 1.5,
            damping: 0.2,
            response: 1.0,
        }
    }
}

/// Which clip `[animation]` plays: its name in the file, or its index from 0.
#[derive(Clone, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(untagged)]
pub enum ClipSetting {
    /// The clip's index, counting from 0.
    Index(u32),
    /// The clip's name.
    Name(String),
}

/// `[animation]`: a clip of the glTF model, sampled at the scene time (`--time`, frame
/// `k/fps`, `sweep --param time=…`).
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct AnimationSettings {
    /// The clip: a name, or an index from 0.
    pub clip: ClipSetting,
    /// Clip seconds per scene second.
    pub speed: f32,
    /// Whether the clip repeats (otherwise it holds its last pose).
    #[serde(rename = "loop")]
    pub looping: bool,
}

impl Default for AnimationSettings {
    fn default() -> Self {
        AnimationSettings {
            clip: ClipSetting::Index(0),
            speed: 1.0,
            looping: true,
        }
    }
}

impl AnimationSettings {
    /// The clip as the glTF loader takes it.
    pub fn choice(&self) -> crate::mesh::gltf::ClipChoice {
        match &self.clip {
            ClipSetting::Index(i) => crate::mesh::gltf::ClipChoice::Index(*i as usize),
            ClipSetting::Name(n) => crate::mesh::gltf::ClipChoice::Name(n.clone()),
        }
    }
}

/// The keys of `[mesh]` that shape a mesh of `kind` (besides `kind` itself).
fn mesh_keys(kind: MeshKind) -> &'static [&'static str] {
    match kind {
        MeshKind::Torus => &["major_radius", "minor_radius", "model_resolution"],
        MeshKind::Sphere => &["radius", "model_resolution"],
        MeshKind::Cylinder => &["radius", "height", "model_resolution"],
        MeshKind::Leg => &["model_resolution", "scale"],
        MeshKind::Obj => &["path", "scale"],
        MeshKind::Gltf => &["path", "node", "scale"],
    }
}

fn debug_kind(kind: MeshKind) -> &'static str {
    match kind {
        MeshKind::Torus => "torus",
        MeshKind::Sphere => "sphere",
        MeshKind::Cylinder => "cylinder",
        MeshKind::Leg => "leg",
        MeshKind::Obj => "obj",
        MeshKind::Gltf => "gltf",
    }
}

/// A `[mesh]` key the text sets that has no effect under the mesh's kind (a `path` on a torus,
/// a `radius` on an OBJ), as `mesh.KEY`. A value equal to the default is let through: a scene
/// written back by pelage (`to_toml`, the viewer's screenshots) lists every key.
fn unused_mesh_key(source: &toml::Table, mesh: &MeshSettings) -> Option<String> {
    let given = source.get("mesh")?.as_table()?;
    let defaults = toml::Value::try_from(MeshSettings::default()).ok()?;
    let used = mesh_keys(mesh.kind);
    given
        .iter()
        .filter(|(name, _)| name.as_str() != "kind" && !used.contains(&name.as_str()))
        .find(|(name, value)| {
            !defaults
                .get(name.as_str())
                .is_some_and(|d| same_as_f32(d, value))
        })
        .map(|(name, _)| format!("mesh.{name}"))
}

/// Whether two TOML values are equal as the scene reads them: numbers as f32 (the text's `2.4`
/// and the default `2.4f32` written back differ as f64).
fn same_as_f32(a: &toml::Value, b: &toml::Value) -> bool {
    let number = |v: &toml::Value| match v {
        toml::Value::Float(f) => Some(*f as f32),
        toml::Value::Integer(i) => Some(*i as f32),
        _ => None,
    };
    match (number(a), number(b)) {
        (Some(x), Some(y)) => x == y,
        _ => a == b,
    }
}

/// The first array in the scene text longer than the value it was read into (the key, the
/// number of values given and taken), found by comparing the text's arrays with the parsed
/// scene written back: a fixed-size value (a vector, a colour, a pair) takes exactly its size.
fn longer_arrays(source: &toml::Table, scene: &Scene) -> Option<(String, usize, usize)> {
    let typed = toml::Value::try_from(scene).ok()?;
    fn walk(
        source: &toml::Value,
        typed: &toml::Value,
        key: &str,
    ) -> Option<(String, usize, usize)> {
        match (source, typed) {
            (toml::Value::Table(s), toml::Value::Table(t)) => s.iter().find_map(|(name, value)| {
                let key = if key.is_empty() {
                    name.clone()
                } else {
                    format!("{key}.{name}")
                };
                t.get(name).and_then(|typed| walk(value, typed, &key))
            }),
            (toml::Value::Array(s), toml::Value::Array(t)) => {
                if s.len() > t.len() {
                    return Some((key.to_string(), s.len(), t.len()));
                }
                s.iter()
                    .zip(t)
                    .enumerate()
                    .find_map(|(k, (s, t))| walk(s, t, &format!("{key}[{k}]")))
            }
            _ => None,
        }
    }
    source
        .iter()
        .find_map(|(name, value)| typed.get(name).and_then(|t| walk(value, t, name)))
}

impl Scene {
    /// Whether something beyond the wind bends the fur (gravity, motion or a direction map):
    /// layers then move by the combined lean ([`crate::shading::motion`]).
    pub fn leans(&self) -> bool {
        self.gravity.is_some() || self.motion.is_some() || self.maps.direction.is_some()
    }

    /// Parses and validates scene text; `file` names it in errors, `base_dir` resolves paths.
    pub fn parse(text: &str, file: &str, base_dir: &Path) -> Result<Scene, SceneError> {
        let mut scene: Scene = toml::from_str(text).map_err(|e| {
            let line = e.span().map(|s| line_of_offset(text, s.start));
            let message = e.message().trim().replace('\n', " ");
            // Name the key when the line holds one (serde's messages name only the type).
            let key = line.and_then(|l| validate::key_at_line(text, l));
            // The guess first, the full list after it: "unknown field `number_of_shell`; did
            // you mean `number_of_shells`? (expected one of …)".
            let message = match (
                validate::suggestion(&message),
                message.split_once(", expected"),
            ) {
                (Some(guess), Some((head, list))) => format!("{head}; {guess} (expected{list})"),
                (Some(guess), None) => format!("{message}; {guess}"),
                (None, _) => message,
            };
            SceneError {
                file: file.to_string(),
                line,
                message: match key {
                    Some(key) if !message.contains(&key) => format!("{key}: {message}"),
                    _ => message,
                },
            }
        })?;
        scene.base_dir = base_dir.to_path_buf();
        // Fixed-size values take exactly their size: `direction = [1, 0, 0, 9]` would otherwise
        // be read as its first three numbers (serde stops reading), the rest silently dropped.
        // The text as plain TOML, for the checks the typed scene cannot make (it parsed, so
        // this does too).
        let source: toml::Table = text.parse().unwrap_or_default();
        if let Some((key, given, taken)) = longer_arrays(&source, &scene) {
            return Err(SceneError {
                file: file.to_string(),
                line: validate::line_of_key(text, &key),
                message: format!("{key} takes exactly {taken} values, {given} are given"),
            });
        }
        if let Some(key) = unused_mesh_key(&source, &scene.mesh) {
            return Err(SceneError {
                file: file.to_string(),
                line: validate::line_of_key(text, &key),
                message: format!(
                    "{key} has no effect on a mesh of kind \"{}\"; remove it",
                    debug_kind(scene.mesh.kind)
                ),
            });
        }
        validate::validate(&scene, &Limits::default()).map_err(|(key, message)| SceneError {
            file: file.to_string(),
            line: validate::line_of_key(text, &key),
            message,
        })?;
        Ok(scene)
    }

    /// Reads, parses and validates a scene file.
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        let error = |line, message| SceneError {
            file: path.display().to_string(),
            line,
            message,
        };
        let bytes = crate::input::read(path, MAX_SCENE_BYTES, "scene")
            .map_err(|e| error(None, e.message))?;
        let text = String::from_utf8(bytes).map_err(|e| {
            let good = &e.as_bytes()[..e.utf8_error().valid_up_to()];
            let line = good.iter().filter(|&&b| b == b'\n').count() + 1;
            error(Some(line), "not valid UTF-8 text".into())
        })?;
        let dir = path.parent().unwrap_or(Path::new("."));
        Scene::parse(&text, &path.display().to_string(), dir)
    }

    /// The embedded default scene (thesis figure 3.1).
    pub fn embedded_default() -> Result<Scene, SceneError> {
        Scene::parse(DEFAULT_SCENE, DEFAULT_SCENE_NAME, Path::new("scenes"))
    }

    /// Checks the scene again (after a caller changed fields, e.g. from the command line).
    pub fn revalidate(&self, file: &str) -> Result<(), SceneError> {
        validate::validate(self, &Limits::default()).map_err(|(_, message)| SceneError {
            file: file.to_string(),
            line: None,
            message,
        })
    }
}

/// The 1-based line of a dotted scene key (`maps.length`, `spots[1].radii`) in scene text, for
/// errors found after parsing (a map that cannot be read); `None` when it is not written.
pub fn line_of_key(text: &str, dotted: &str) -> Option<usize> {
    validate::line_of_key(text, dotted)
}

fn line_of_offset(text: &str, offset: usize) -> usize {
    text[..offset.min(text.len())].matches('\n').count() + 1
}

impl Scene {
    /// The scene as TOML text that [`Scene::parse`] reads back to an equal scene: every `f32` is
    /// written with enough digits to come back bit for bit, absent wind and burn are left out,
    /// and `base_dir` is not written (a relative OBJ path stays relative to wherever the text is
    /// saved: make it absolute first if the file goes elsewhere).
    pub fn to_toml(&self) -> Result<String, String> {
        toml::to_string(self).map_err(|e| format!("cannot write the scene as TOML: {e}"))
    }
}

#[cfg(test)]
mod serialise_tests {
    use super::*;

    fn round_trip(scene: &Scene) -> Scene {
        let text = scene.to_toml().expect("serialise");
        Scene::parse(&text, "round-trip", &scene.base_dir).unwrap_or_else(|e| panic!("{e}\n{text}"))
    }

    #[test]
    fn every_scene_file_round_trips() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
        for entry in std::fs::read_dir(&dir).expect("scenes/") {
            let path = entry.expect("entry").path();
            if path.extension().is_some_and(|e| e == "toml") {
                let scene = Scene::load(&path).expect("load");
                assert_eq!(round_trip(&scene), scene, "{}", path.display());
            }
        }
    }

    #[test]
    fn awkward_floats_and_every_table_round_trip_bit_for_bit() {
        let mut scene = Scene::embedded_default().expect("default");
        scene.time = 1.0 / 3.0;
        scene.camera.eye = Vec3::new(0.1, -1.0e-7, 13.999_999);
        scene.camera.target = Vec3::new(f32::MIN_POSITIVE, 2.0 / 3.0, -0.6);
        scene.fur.model_difference = f32::from_bits(0.6f32.to_bits() + 1);
        scene.wind = Some(WindSettings::default());
        scene.burn = Some(BurnSettings {
            start: 0.1 + 0.2,
            matches: vec![
                MatchSetting::Direction(Vec3::new(0.1, 1.0, -1.0 / 3.0)),
                MatchSetting::Point(PointMatch {
                    position: Vec3::new(1.0 / 7.0, 2.5, -6.0),
                    reach: 0.1 + 0.2,
                }),
            ],
            ..BurnSettings::default()
        });
        scene.spots = vec![
            SpotSettings::default(),
            SpotSettings {
                kind: SpotKind::Light,
                ..SpotSettings::default()
            },
            SpotSettings {
                kind: SpotKind::Light,
                position: Some(Vec3::new(0.0, 2.0 / 3.0, 6.1)),
                reach: Some(2.0 / 3.0),
                ..SpotSettings::default()
            },
        ];
        scene.stripes = vec![
            StripeSettings::default(),
            StripeSettings {
                kind: StripeKind::Axis,
                axis: Some(Vec3::new(1.0, 0.0, 1.0 / 3.0)),
                period: Some(4.0 / 3.0),
                ..StripeSettings::default()
            },
        ];
        scene.shading.debug_view = DebugView::Shadow;
        scene.mesh.kind = MeshKind::Obj;
        scene.mesh.path = Some(PathBuf::from("meshes/thing.obj"));
        let back = round_trip(&scene);
        assert_eq!(back, scene);
        assert_eq!(back.camera.eye.y.to_bits(), scene.camera.eye.y.to_bits());
        assert_eq!(back.time.to_bits(), scene.time.to_bits());
    }
}
