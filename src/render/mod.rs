//! Assembles one frame (render stage): the opaque base mesh, then the shells layer by layer from
//! root to tip, alpha-blended, then fins at the silhouette (thesis 3.1.2, 3.1.4, 3.2).
//!
//! [`PreparedScene::new`] does the start-up work the thesis times in chapter 4.1 (build the mesh
//! and its frames, generate strands, bake shell and fin textures); [`PreparedScene::render`] draws
//! one frame from that data. Choices where the thesis is silent:
//! - The fur tile covers `1/texture_repeat` of the mesh's uv square; strand heights in tile units
//!   are set so that the tallest strand is `model_difference` long in world units, which keeps the
//!   baked tangents' proportions equal to the rendered fur's.
//! - Eye and light are taken into tangent space per vertex (the thesis's vertex shader) and
//!   renormalised per fragment.
//! - The skin under the fur is the fur colour darkened: `colour · 0.35 · (0.5 + 0.5·max(0, n·l))`.
//! - All texture reads of one fragment use the level of detail of the fur uv's derivatives.

pub mod fragment;
mod light_spot_memo;
pub mod maps;

use crate::camera::Camera;
use crate::fur::{self, FurParams};
use crate::mesh::{self, Mesh};
use crate::raster::{
    AddressMode, BlendMode, ClipVertex, CullMode, DepthCompare, DrawState, Filter, Frame,
    Framebuffer, MipFilter, RasterError, RasterStats, Sampler, Texture, texture::PairedTexels,
};
use crate::scene::{FinSelectionSetting, MeshKind, Scene, ShellSpacingSetting};
use crate::simd::SimdLevel;
use fragment::{
    BurnState, FragmentStage, FurShader, FurVaryings, LayerMaps, LayerParams, LitVaryings,
    ShadeParams, SurfaceVaryings,
};
use glam::{Vec2, Vec3, Vec4};
use maps::SurfaceMaps;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, Ordering};

/// What can go wrong preparing or drawing a scene.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// The mesh could not be built or loaded.
    #[error(transparent)]
    Mesh(#[from] mesh::MeshError),
    /// The fur parameters were refused.
    #[error("fur: {0}")]
    Fur(#[from] fur::FurError),
    /// The rasterizer refused a size or a draw.
    #[error("raster: {0}")]
    Raster(#[from] RasterError),
    /// A surface map could not be loaded.
    #[error(transparent)]
    Map(#[from] maps::MapError),
    /// A scene value whose effect is lost on this mesh (e.g. to f32 precision).
    #[error("{key}: {message}")]
    Scene {
        /// The dotted scene key.
        key: String,
        /// Why.
        message: String,
    },
    /// The caller's cancel flag was set while drawing ([`PreparedScene::render_framebuffer_at`]).
    #[error("the render was cancelled")]
    Cancelled,
}

/// The most stripe periods across the object an axis stripe may have: past this, a band's
/// position within its period keeps under 7 of f32's 24 bits and the bands dissolve.
pub const MAX_STRIPE_PERIODS: f32 = 65536.0;

/// Refuses an axis stripe whose period is too small for f32 to resolve over `radius` (the
/// largest distance of a skin point from the origin, where the stripe coordinate is measured).
fn check_stripes(scene: &Scene, radius: f32) -> Result<(), RenderError> {
    for (k, stripe) in scene.stripes.iter().enumerate() {
        if stripe.kind != crate::scene::StripeKind::Axis {
            continue;
        }
        let periods = radius / stripe.period();
        if periods.is_nan() || periods > MAX_STRIPE_PERIODS {
            return Err(RenderError::Scene {
                key: format!("stripes[{k}].period"),
                message: format!(
                    "stripes[{k}].period = {} is too small for this mesh: its points lie up to \
                     {radius} from the origin, {periods:.3e} periods, more than f32 can place \
                     bands in ({MAX_STRIPE_PERIODS})",
                    stripe.period()
                ),
            });
        }
    }
    Ok(())
}

impl RenderError {
    /// Whether the error comes from the user's input (exit status 2) rather than the machine.
    pub fn is_bad_input(&self) -> bool {
        !matches!(self, RenderError::Cancelled)
    }

    /// The message `pelage render` (and the Python package) gives for this error when drawing
    /// `scene`, read from the file `name` (or the embedded scene's name): mesh errors name their
    /// own file; a map or scene value at fault names the scene's line that writes its key; a
    /// fur length out of proportion to the mesh says which keys to change; the rest are
    /// prefixed by `name`.
    pub fn describe(&self, scene: &Scene, name: &str) -> String {
        match self {
            RenderError::Mesh(_) => self.to_string(),
            RenderError::Fur(fur::FurError::InvalidParameter {
                name: "max_height" | "min_height",
                ..
            }) => format!(
                "{name}: fur.model_difference = {} is out of proportion to the mesh: strands \
                 must be at most {} fur tiles long (a tile is the mesh's uv extent / \
                 fur.texture_repeat), and not vanishingly short; change mesh.scale, \
                 fur.texture_repeat or fur.model_difference",
                scene.fur.model_difference,
                fur::MAX_LENGTH
            ),
            RenderError::Map(maps::MapError { key, .. }) | RenderError::Scene { key, .. } => {
                format!("{}: {self}", with_line(name, key))
            }
            _ => format!("{name}: {self}"),
        }
    }
}

/// `name:line` when `name` is a scene file that writes `key` (errors found after parsing, such
/// as a map that cannot be read, name the line of the key at fault); `name` otherwise.
fn with_line(name: &str, key: &str) -> String {
    let text = crate::input::read_text(
        std::path::Path::new(name),
        crate::scene::MAX_SCENE_BYTES,
        "scene",
    )
    .ok();
    match text.and_then(|t| crate::scene::line_of_key(&t, key)) {
        Some(line) => format!("{name}:{line}"),
        None => name.to_string(),
    }
}

/// A shell or fin layer's two textures.
struct LayerTextures {
    colour: Texture,
    tangent: Texture,
    /// Both converted side by side for the quad stage's texture reads.
    converted: Option<PairedTexels>,
    /// Density bands (shells, with a density map).
    density: Option<Texture>,
}

fn texture(image: &fur::Rgba8Image) -> Result<Texture, RasterError> {
    Texture::from_rgba8(image.width, image.height, image.texels.clone())
}

/// A fur layer's map: its alpha is the strands' coverage, so its mip levels weight colour by it.
fn layer_texture(image: &fur::Rgba8Image) -> Result<Texture, RasterError> {
    Texture::with_mip_filter(
        image.width,
        image.height,
        image.texels.clone(),
        MipFilter::Coverage,
    )
}

impl LayerTextures {
    fn new(colour: &fur::Rgba8Image, tangent: &fur::Rgba8Image) -> Result<Self, RasterError> {
        let (colour, tangent) = (layer_texture(colour)?, layer_texture(tangent)?);
        Ok(LayerTextures {
            converted: PairedTexels::new(&colour, &tangent),
            colour,
            tangent,
            density: None,
        })
    }

    fn maps(&self, sampler: Sampler, shell: bool) -> LayerMaps<'_> {
        LayerMaps {
            colour: &self.colour,
            tangent: &self.tangent,
            converted: self.converted.as_ref(),
            density: self.density.as_ref(),
            sampler,
            shell,
        }
    }
}

/// A rendered frame.
#[derive(Clone, Debug)]
pub struct RenderedImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Row-major RGBA8, row 0 at the top.
    pub rgba8: Vec<u8>,
    /// Rasterizer counters.
    pub stats: RasterStats,
    /// Non-fatal problems met while preparing (e.g. an OBJ without UVs).
    pub warnings: Vec<String>,
}

/// What a GPU needs to skin a glTF model itself (see [`PreparedScene::skinning_at`]).
#[derive(Clone, Debug)]
pub struct Skinning {
    /// Column-major 4×4 palette matrices.
    pub palette: Vec<[f32; 16]>,
    /// Per bind vertex, palette indices and normalised weights.
    pub influences: Vec<mesh::skin::Influences>,
    /// The bind mesh (positions, normals, derivatives before posing).
    pub bind: Mesh,
}

/// A glTF model as loaded (see [`PreparedScene::character`]).
#[derive(Clone, Copy, Debug)]
pub struct CharacterView<'a> {
    /// The vertices as the file binds them (before posing and before the skin inset).
    pub bind: &'a Mesh,
    /// Hierarchy, palette and per-vertex influences.
    pub rig: &'a mesh::skin::Rig,
    /// The clip `[animation]` plays, with its `speed` and `loop`; `None`: the rest pose.
    pub clip: Option<(&'a mesh::animation::Clip, f32, bool)>,
    /// How far the posed skin is moved along its normals (`fur.skin_inset`).
    pub skin_inset: f32,
}

/// A scene with its mesh built and its fur baked, ready to draw frames.
pub struct PreparedScene {
    scene: Scene,
    mesh: Mesh,
    edges: Vec<mesh::fins::Edge>,
    warnings: Vec<String>,
    shells: Vec<LayerTextures>,
    shell_offsets: Vec<f32>,
    fin: Option<LayerTextures>,
    fin_height: f32,
    tile_world_size: Vec2,
    maps: SurfaceMaps,
    /// Centre and radius of the mesh's bounding sphere, object space (level of detail).
    bounds: (Vec3, f32),
    /// The order level of detail adds layers in.
    lod_order: Vec<u32>,
    /// A glTF model's rig and clip: the mesh is posed again for every frame.
    character: Option<Posing>,
    /// The mesh's triangles where the maps leave the skin bare, by index in `mesh.indices`
    /// ([`BARE_BY_DENSITY`], [`BARE_BY_LENGTH`]); `None` where no triangle is.
    bare: Option<Vec<u8>>,
    /// The last frame's framebuffer, cleared and drawn again by the next frame of the same
    /// shape ([`PreparedScene::cleared_framebuffer`]).
    spare_framebuffer: Mutex<Option<Framebuffer>>,
}

/// A triangle where the density map is 0 all over: every shell fragment's alpha is 0, so no
/// shell layer draws anything there.
const BARE_BY_DENSITY: u8 = 1;
/// A triangle where the length map is 0 all over: every shell above the root is cut there.
const BARE_BY_LENGTH: u8 = 2;

/// For each triangle of `body`, the cosine its fragments surely reach towards a match given by
/// direction ([`BurnState::surely_burnt_cosine`] of its vertices' rest normals; −∞ for a
/// triangle with a vertex out of range): taken once a frame, each shell layer then compares it
/// with its own bound ([`BurnState::surely_burnt_from`]) instead of normalising the normals
/// again for every match on every layer.
fn surely_burnt_cosines(body: &Mesh, burn: &BurnState) -> Vec<f32> {
    use rayon::prelude::*;
    let normal = |i: u32| body.vertices.get(i as usize).map(|v| v.rest_normal);
    body.indices
        .par_iter()
        .map(|t| match (normal(t[0]), normal(t[1]), normal(t[2])) {
            (Some(a), Some(b), Some(c)) => burn.surely_burnt_cosine([a, b, c]),
            _ => f32::NEG_INFINITY,
        })
        .collect()
}

/// [`PreparedScene::bare`]: for each triangle of `mesh`, whether the density map (and the
/// length map) read 0 everywhere on it ([`SurfaceMaps::red_is_zero_over`]).
fn bare_triangles(mesh: &Mesh, maps: &SurfaceMaps) -> Option<Vec<u8>> {
    if maps.density.is_none() && maps.length.is_none() {
        return None;
    }
    let uv = |i: u32| mesh.vertices.get(i as usize).map(|v| v.uv);
    let flags: Vec<u8> = mesh
        .indices
        .iter()
        .map(|t| {
            let (Some(a), Some(b), Some(c)) = (uv(t[0]), uv(t[1]), uv(t[2])) else {
                return 0;
            };
            let zero = |map: &Option<Texture>| {
                map.as_ref()
                    .is_some_and(|m| maps.red_is_zero_over(m, [a, b, c]))
            };
            let mut flag = 0;
            if zero(&maps.density) {
                flag |= BARE_BY_DENSITY;
            }
            if zero(&maps.length) {
                flag |= BARE_BY_LENGTH;
            }
            flag
        })
        .collect();
    flags.iter().any(|&f| f != 0).then_some(flags)
}

/// What poses a glTF model per frame (see [`crate::mesh::skin`]).
struct Posing {
    /// The vertices as the file binds them.
    bind: Mesh,
    /// Hierarchy, palette, influences.
    rig: mesh::skin::Rig,
    /// The clip `[animation]` plays, with its speed and looping; `None`: the rest pose.
    clip: Option<(mesh::animation::Clip, f32, bool)>,
    /// How far the skin is moved along its normals (`fur.skin_inset`).
    inset: f32,
    /// The spring of `[motion]` (frequency, damping), when the scene has one: the fur then lags
    /// behind each vertex's own posed motion too.
    spring: Option<(f32, f32)>,
}

/// The step at which a posed vertex's trajectory is sampled for its lag, seconds.
pub const LAG_SAMPLE_STEP: f32 = 1.0 / 30.0;
/// The longest window of a posed vertex's past that its lag reads, seconds.
pub const LAG_MAX_WINDOW: f32 = 4.0;

impl Posing {
    /// The palette at scene time `time`.
    fn palette_at(&self, time: f32) -> Vec<mesh::skin::Affine> {
        match &self.clip {
            Some((clip, speed, looping)) => {
                let t = clip.clip_time(time, *speed, *looping);
                self.rig.palette(&clip.sample(&self.rig.skeleton.rest, t))
            }
            None => self.rig.rest_palette(),
        }
    }

    /// The posed mesh at scene time `time`; `rest` (the rest pose, same vertices) gives each
    /// vertex its rest position and normal.
    fn mesh_at(&self, rest: &Mesh, time: f32) -> Mesh {
        let palette = self.palette_at(time);
        let mut posed = inset(
            mesh::skin::pose(&self.bind, &self.rig.influences, &palette),
            self.inset,
        );
        let lags = self.spring.map(|(f, d)| self.lags(time, f, d));
        for (k, (v, r)) in posed.vertices.iter_mut().zip(&rest.vertices).enumerate() {
            v.rest_position = r.rest_position;
            v.rest_normal = r.rest_normal;
            v.lag = lags.as_ref().map_or(Vec3::ZERO, |l| l[k]);
        }
        posed
    }

    /// The skinned positions at `time` (no frames: what the lag reads).
    fn positions_at(&self, time: f32) -> Vec<Vec3> {
        use rayon::prelude::*;
        let palette = self.palette_at(time);
        self.bind
            .vertices
            .par_iter()
            .zip(&self.rig.influences)
            .map(|(v, i)| i.blend(&palette).transform_point(v.position))
            .collect()
    }

    /// Each vertex's lag at `time` ([`crate::shading::spring_lag`] of its own trajectory): the
    /// skinned positions sampled every [`LAG_SAMPLE_STEP`] over the last
    /// `W = min(ln 100 / (ζω), LAG_MAX_WINDOW)` seconds (the spring's envelope falls to 1 % in
    /// `ln 100 / (ζω)`), joined linearly and starting from rest at the window's start; each
    /// velocity change `Δv_j` at sample time `s_j` adds `Δv_j·g(time − s_j)`, in sample order.
    fn lags(&self, time: f32, frequency: f32, damping: f32) -> Vec<Vec3> {
        let zeta = damping.clamp(0.01, 0.99);
        let omega = std::f32::consts::TAU * frequency.max(0.01);
        let window = (libm::logf(100.0) / (zeta * omega)).min(LAG_MAX_WINDOW);
        let steps = (window / LAG_SAMPLE_STEP).ceil().max(1.0) as usize;
        let sample = |j: usize| time - (steps - j) as f32 * LAG_SAMPLE_STEP;
        let n = self.bind.vertices.len();
        let mut lag = vec![Vec3::ZERO; n];
        let mut velocity = vec![Vec3::ZERO; n];
        let mut previous = self.positions_at(sample(0));
        for j in 0..steps {
            let next = self.positions_at(sample(j + 1));
            let g = crate::shading::spring_impulse_response(time - sample(j), frequency, damping);
            for k in 0..n {
                let v = (next[k] - previous[k]) / LAG_SAMPLE_STEP;
                lag[k] += (v - velocity[k]) * g;
                velocity[k] = v;
            }
            previous = next;
        }
        lag
    }
}

/// What bends the fur in one frame: the wind (thesis 3.3) and the lean of gravity, the object's
/// motion and combing ([`crate::shading::motion`]).
#[derive(Clone, Copy, Debug)]
struct Bending {
    /// Unit wind direction and force.
    wind: Option<(Vec3, f32)>,
    /// The lean shared by every vertex (gravity + spring lag × response), world space; `None`
    /// when the scene has neither gravity, motion nor a direction map (the thesis's wind alone).
    lean: Option<Vec3>,
    /// Whether a bent layer is pulled back along −normal to keep the strands' length (thesis
    /// 3.3); `false` only with `wind.keep_length = false` (figure 3.16).
    keep_length: bool,
    /// `motion.response`: the bend per world unit of lag (1 without `[motion]`).
    response: f32,
}

impl Bending {
    fn at(s: &Scene, time: f32) -> Bending {
        let wind = s.wind.as_ref().map(|w| w.direction_and_force(time));
        let lean = s.leans().then(|| {
            let gravity = s.gravity.as_ref().map_or(Vec3::ZERO, |g| {
                crate::shading::gravity_lean(g.direction, g.strength)
            });
            let lag = s.motion.as_ref().map_or(Vec3::ZERO, |m| {
                crate::shading::spring_lag(&m.path, time, m.frequency, m.damping) * m.response
            });
            gravity + lag
        });
        Bending {
            wind,
            lean,
            keep_length: s.wind.as_ref().is_none_or(|w| w.keep_length),
            response: s.motion.as_ref().map_or(1.0, |m| m.response),
        }
    }

    /// The part of `displacement` the vertex stage applies: the pull back along the normal
    /// ([`crate::shading::vertex_pull`]), or nothing when the length is not kept.
    fn pull(&self, displacement: Vec3, normal: Vec3) -> Vec3 {
        if self.keep_length {
            crate::shading::vertex_pull(displacement, normal)
        } else {
            Vec3::ZERO
        }
    }

    /// Whether anything moves the layers (the reverse lookup is needed).
    fn moves(&self) -> bool {
        self.wind.is_some() || self.lean.is_some()
    }

    /// The lean at a vertex (shared lean + combing), world space; zero without a lean.
    fn lean_at(&self, maps: &SurfaceMaps, v: &mesh::Vertex) -> Vec3 {
        let Some(shared) = self.lean else {
            return Vec3::ZERO;
        };
        let comb = maps.direction.as_ref().map_or(Vec3::ZERO, |m| {
            let c = crate::shading::comb_lean(maps.sample(m, v.uv));
            v.frame.tangent * c.x + v.frame.binormal * c.y
        });
        // A posed character's own motion: zero for every other mesh, which adds nothing.
        if v.lag == Vec3::ZERO {
            shared + comb
        } else {
            shared + comb + v.lag * self.response
        }
    }

    /// Displacement of a layer at `fraction` of a strand `height` long over a vertex with this
    /// `normal` and this vertex's `lean` ([`Self::lean_at`]): the thesis's wind alone
    /// ([`crate::shading::wind_displacement`]), or the wind's bend added to the lean
    /// ([`crate::shading::lean_displacement`]).
    fn displacement(&self, lean: Vec3, normal: Vec3, fraction: f32, height: f32) -> Vec3 {
        match (self.lean, self.wind) {
            (None, Some((direction, force))) => {
                crate::shading::wind_displacement(direction, normal, force, fraction, height)
            }
            (None, None) => Vec3::ZERO,
            (Some(_), wind) => {
                let wind_bend = wind.map_or(Vec3::ZERO, |(d, f)| {
                    let f = if f.is_finite() {
                        f.clamp(-1.0, 1.0)
                    } else {
                        0.0
                    };
                    d * f
                });
                crate::shading::lean_displacement(wind_bend + lean, normal, fraction, height)
            }
        }
    }
}

/// The level of detail of one frame ([`crate::shading::lod`]).
#[derive(Clone, Debug, PartialEq)]
pub struct LevelOfDetail {
    /// The fur's height on screen at the object's bounding sphere, pixels.
    pub fur_pixels: f32,
    /// The continuous number of shells.
    pub level: f32,
    /// Per layer, how many baked layers it stands for (0: not drawn).
    pub spans: Vec<f32>,
    /// Opacity factor of the fins.
    pub fin_fade: f32,
}

/// Centre of the bounding box and the largest distance from it to a vertex.
fn bounding_sphere(mesh: &Mesh) -> (Vec3, f32) {
    let (lo, hi) = mesh.vertices.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), v| (lo.min(v.position), hi.max(v.position)),
    );
    if !(lo.is_finite() && hi.is_finite()) {
        return (Vec3::ZERO, 0.0);
    }
    let centre = (lo + hi) * 0.5;
    let radius = mesh
        .vertices
        .iter()
        .map(|v| (v.position - centre).length())
        .fold(0.0f32, f32::max);
    (centre, radius)
}

/// How opaque a fin is at a vertex: the angle between the eye vector and the normal, placed in
/// the first fin window containing it, gives 1 at the window's centre falling linearly to 0 at
/// its ends (as Lengyel fades fins in towards the silhouette). Outside every window: 0.
pub fn fin_fade(windows: &[[f32; 2]], to_eye: Vec3, normal: Vec3) -> f32 {
    let (Some(e), Some(n)) = (to_eye.try_normalize(), normal.try_normalize()) else {
        return 0.0;
    };
    let angle = libm::acosf(e.dot(n).clamp(-1.0, 1.0)).to_degrees();
    windows
        .iter()
        .find_map(|&[lo, hi]| {
            let half = 0.5 * (hi - lo);
            let centre = 0.5 * (hi + lo);
            // Angles between vectors stop at 180°: a window reaching past it folds back.
            let folded = if angle < lo && 360.0 - angle <= hi {
                360.0 - angle
            } else {
                angle
            };
            (lo..=hi).contains(&folded).then(|| {
                if half > 0.0 {
                    1.0 - (folded - centre).abs() / half
                } else {
                    1.0
                }
            })
        })
        .unwrap_or(0.0)
}

/// The part of the fur's height a fin's self-shadow reaches over, and whose shell's lookups it
/// takes: beside the shells a fin shows mostly the top of the fur (the shells cover the rest), so
/// it is shadowed as the shell a tenth of the height below the tips is (with 30 shells at
/// height/5 that shell takes no lookup). Measured on the gravity, torus and leg scenes
/// (`tests/fins.rs`), fin fur then has 0.96, 1.05 and 1.04 of the luminance of the shell fur
/// beside it; with a fifth of the height (one lookup at 30 shells) the sphere's was 0.87, with
/// the root shell's lookups over the whole height 30–55 % darker.
pub const FIN_SHADOW_REACH: f32 = 0.1;

/// A fin's axes over the edge from `a` to `b`: x along the edge, z the averaged vertex normal
/// made perpendicular to it (zero when they are parallel or degenerate).
fn fin_axes(a: &mesh::Vertex, b: &mesh::Vertex) -> (Vec3, Vec3) {
    let x = (b.position - a.position).normalize_or_zero();
    let up = (a.normal + b.normal).normalize_or_zero();
    (x, (up - x * up.dot(x)).normalize_or_zero())
}

/// A fin corner's wind or lean varying: the world vector `bend` (the wind's direction × force,
/// or the lean; none: zero) in the fin's frame, times the `fraction` of it the corner takes.
/// The fins' layer bends the tangent by the whole varying ([`fin_layer_params`]'s height
/// fraction is 1), so a fin whose roots take 0 and whose top edge takes 1 bends each fragment's
/// strand tangent as the shell at its height bends its own (thesis 3.3.1: the bend grows with
/// the height), up to the top shell's at the top edge.
fn bend_varying(bend: Option<Vec3>, frame: &mesh::frame::TangentFrame, fraction: f32) -> Vec3 {
    bend.map_or(Vec3::ZERO, |b| {
        crate::shading::to_tangent_space(b, frame) * fraction
    })
}

/// The fins' layer: they stand for the fur's full height, so they burn as the top shell does;
/// their self-shadow is that of the shell [`FIN_SHADOW_REACH`] below the tips.
fn fin_layer_params(s: &Scene) -> LayerParams {
    let n = s.fur.number_of_shells;
    LayerParams {
        index: n - 1,
        max_shell: n - 1,
        lookups: crate::shading::shadow_lookup_count(
            n,
            n - (n as f32 * FIN_SHADOW_REACH) as u32,
            s.shading.shadow_divisor,
        ),
        height_fraction: 1.0,
        lod_span: 1.0,
    }
}

/// Mean world length of one fur tile along u and v, from the mesh's dp/du, dp/dv.
fn tile_world_size(mesh: &Mesh, repeat: [f32; 2]) -> Vec2 {
    let n = mesh.vertices.len().max(1) as f64;
    let (mut su, mut sv) = (0.0f64, 0.0f64);
    for v in &mesh.vertices {
        su += f64::from(v.dpdu.length());
        sv += f64::from(v.dpdv.length());
    }
    let size = Vec2::new((su / n) as f32 / repeat[0], (sv / n) as f32 / repeat[1]);
    // A mesh without usable UVs gets a tile of unit size rather than a zero or NaN scale.
    Vec2::new(
        if size.x.is_finite() && size.x > 0.0 {
            size.x
        } else {
            1.0
        },
        if size.y.is_finite() && size.y > 0.0 {
            size.y
        } else {
            1.0
        },
    )
}

/// The object thinned (thesis 3.1.4, figure 3.10: "it thickens or thins the object"): every
/// vertex moved `inset` (≤ 0) along its vertex normal, so that fur of length `|inset|` grown from
/// there reaches the original surface. Normals, frames and uvs are unchanged; `dpdu`/`dpdv` are
/// kept too (the inset of a smooth surface changes them by a factor 1 − κ·|inset| that the
/// shading's projections do not need). No change for `inset = 0`.
fn inset(mut mesh: Mesh, inset: f32) -> Mesh {
    if inset != 0.0 {
        for v in &mut mesh.vertices {
            v.position += v.normal * inset;
        }
    }
    mesh
}

/// Scales positions and the surface derivatives; normals and frames are unchanged.
fn scaled(mut mesh: Mesh, scale: f32) -> Mesh {
    for v in &mut mesh.vertices {
        v.position *= scale;
        v.dpdu *= scale;
        v.dpdv *= scale;
    }
    mesh
}

/// The mesh at rest, its warnings, and for a glTF model what poses it per frame.
type BuiltMesh = (
    Mesh,
    Vec<String>,
    Option<Posing>,
    Option<mesh::gltf::BaseColour>,
);

fn build_mesh(scene: &Scene) -> Result<BuiltMesh, RenderError> {
    let m = &scene.mesh;
    let mesh = match m.kind {
        MeshKind::Torus => {
            mesh::procedural::torus(m.major_radius, m.minor_radius, m.model_resolution)
        }
        MeshKind::Sphere => mesh::procedural::sphere(m.radius, m.model_resolution),
        MeshKind::Cylinder => mesh::procedural::cylinder(m.radius, m.height, m.model_resolution),
        MeshKind::Leg => scaled(mesh::procedural::leg(m.model_resolution), m.scale),
        MeshKind::Obj => {
            let path = m.path.clone().unwrap_or_default();
            let loaded = mesh::obj::load_obj(&scene.base_dir.join(path))?;
            let mesh = inset(scaled(loaded.mesh, m.scale), scene.fur.skin_inset());
            return Ok((at_rest(mesh), loaded.warnings, None, None));
        }
        MeshKind::Gltf => {
            let path = scene.base_dir.join(m.path.clone().unwrap_or_default());
            let loaded = mesh::gltf::load(&path, m.node.as_deref(), m.scale)
                .map_err(mesh::MeshError::from)?;
            let clip = match &scene.animation {
                Some(a) => {
                    let index = loaded
                        .clip_index(&a.choice(), &path)
                        .map_err(mesh::MeshError::from)?;
                    Some((loaded.clips[index].clone(), a.speed, a.looping))
                }
                None => None,
            };
            let posing = Posing {
                bind: loaded.bind,
                rig: loaded.rig,
                clip,
                inset: scene.fur.skin_inset(),
                spring: scene.motion.as_ref().map(|m| (m.frequency, m.damping)),
            };
            // The rest pose: what every time-independent quantity (the fur tile's size, the
            // bake) is measured on, so that a frame is the same whatever time was prepared.
            let rest = at_rest(inset(
                mesh::skin::pose(
                    &posing.bind,
                    &posing.rig.influences,
                    &posing.rig.rest_palette(),
                ),
                posing.inset,
            ));
            return Ok((rest, loaded.warnings, Some(posing), loaded.base_colour));
        }
    };
    Ok((
        at_rest(inset(mesh, scene.fur.skin_inset())),
        Vec::new(),
        None,
        None,
    ))
}

/// Every vertex's rest fields set to its position and normal as built.
fn at_rest(mut mesh: Mesh) -> Mesh {
    for v in &mut mesh.vertices {
        *v = v.at_rest();
    }
    mesh
}

/// The base colour as a colour map: each texel times the factor, rounded to the nearest byte
/// (`round(b·f)` in f32, clamped to 0..=255); a factor of 1 keeps the bytes.
fn base_colour_map(colour: &mesh::gltf::BaseColour) -> Result<Texture, RasterError> {
    let texels = colour
        .texels
        .iter()
        .map(|t| {
            let mut out = *t;
            for (o, f) in out.iter_mut().zip(colour.factor) {
                *o = (f32::from(*o) * f).round().clamp(0.0, 255.0) as u8;
            }
            out
        })
        .collect();
    Texture::from_rgba8(colour.width, colour.height, texels)
}

fn fur_params(scene: &Scene, tile: Vec2) -> FurParams {
    let f = &scene.fur;
    let tile_width = tile.x.max(tile.y);
    let max_height = f.fur_length() / tile_width;
    FurParams {
        number_of_strands: f.number_of_strands,
        strand_resolution: f.strand_resolution,
        circle_resolution: f.circle_resolution,
        number_of_shells: f.number_of_shells,
        texture_resolution: f.texture_resolution,
        supersample: f.supersample,
        min_height: max_height * f.min_height,
        max_height,
        slope_deg: f.slope_deg,
        curl: f.curl,
        jitter: f.jitter,
        base_thickness: f.base_thickness,
        tip_thickness: f.tip_thickness.min(f.base_thickness),
        colour: f.colour,
        colour_variation: f.colour_variation,
        gaussian_sigma: f.gaussian_sigma,
        fin_height_scale: f.fin_height_scale,
        ..FurParams::default()
    }
}

impl PreparedScene {
    /// Builds the mesh and bakes the fur (the thesis's start-up).
    pub fn new(scene: &Scene) -> Result<Self, RenderError> {
        crate::raster::framebuffer::check_size(scene.image.width, scene.image.height)?;
        let (mesh, warnings, character, base_colour) = build_mesh(scene)?;
        let radius = mesh
            .vertices
            .iter()
            .map(|v| v.position.length())
            .fold(0.0f32, f32::max)
            + scene.fur.fur_length();
        check_stripes(scene, radius)?;
        let tile = tile_world_size(&mesh, scene.fur.texture_repeat);
        let params = fur_params(scene, tile);
        let mut maps = SurfaceMaps::load(&scene.maps, &scene.base_dir)?;
        if scene.fur.colour_from_mesh {
            let Some(colour) = &base_colour else {
                return Err(RenderError::Mesh(mesh::MeshError::Gltf(
                    mesh::gltf::GltfError {
                        file: scene
                            .base_dir
                            .join(scene.mesh.path.clone().unwrap_or_default()),
                        pointer: None,
                        message:
                            "fur.colour_from_mesh: the model's material has no base-colour texture"
                                .into(),
                    },
                )));
            };
            maps.colour = Some(base_colour_map(colour)?);
        }
        let strands = fur::generate_strands(&params, scene.seed)?;
        let baked = if maps.density.is_some() {
            fur::bake_shells_with_density(&params, &strands, scene.seed)?
        } else {
            fur::bake_shells(&params, &strands)?
        };
        let shells = baked
            .layers
            .iter()
            .map(|l| {
                Ok(LayerTextures {
                    density: l.density.as_ref().map(texture).transpose()?,
                    ..LayerTextures::new(&l.colour, &l.tangent)?
                })
            })
            .collect::<Result<Vec<_>, RasterError>>()?;
        let spacing = match scene.fur.shell_spacing {
            ShellSpacingSetting::Uniform => mesh::shells::ShellSpacing::Uniform,
            ShellSpacingSetting::DenserNearTip => mesh::shells::ShellSpacing::DenserNearTip,
        };
        let n = scene.fur.number_of_shells;
        let shell_offsets = (0..n)
            .map(|i| mesh::shells::shell_offset(i, n, scene.fur.fur_length(), spacing))
            .collect();
        let (fin, fin_height) = if scene.fur.fins {
            let (baked_fin, _) = fur::bake_fin_for_shells(&params, scene.seed, &baked)?;
            let height =
                scene.fur.fur_length() * baked_fin.max_height / baked.max_height.max(f32::EPSILON);
            (
                Some(LayerTextures::new(&baked_fin.colour, &baked_fin.tangent)?),
                height,
            )
        } else {
            (None, 0.0)
        };
        let edges = mesh::fins::edges(&mesh);
        Ok(PreparedScene {
            scene: scene.clone(),
            bounds: bounding_sphere(&mesh),
            edges,
            warnings,
            shells,
            shell_offsets,
            fin,
            fin_height,
            tile_world_size: tile,
            lod_order: crate::shading::lod_layer_order(n),
            bare: bare_triangles(&mesh, &maps),
            mesh,
            maps,
            character,
            spare_framebuffer: Mutex::new(None),
        })
    }

    /// The scene this was prepared from.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The mesh carrying the fur, at rest (a glTF model in the pose its nodes give it without
    /// animation).
    pub fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    /// Whether the mesh is posed again for every frame (a glTF model with `[animation]`).
    pub fn poses(&self) -> bool {
        self.character.as_ref().is_some_and(|c| c.clip.is_some())
    }

    /// The mesh as drawn at `time`: a glTF model posed by its clip (skinned, its frames
    /// rebuilt on the posed surface), any other mesh as it is.
    pub fn mesh_at(&self, time: f32) -> std::borrow::Cow<'_, Mesh> {
        match &self.character {
            Some(posing) if posing.clip.is_some() => {
                std::borrow::Cow::Owned(posing.mesh_at(&self.mesh, time))
            }
            _ => std::borrow::Cow::Borrowed(&self.mesh),
        }
    }

    /// The joint palette at `time` as column-major 4×4 matrices (`mesh.scale` included), and
    /// each rest vertex's four palette indices and weights: what a GPU's vertex stage skins
    /// with. `None` for meshes that are not glTF models.
    pub fn skinning_at(&self, time: f32) -> Option<Skinning> {
        let posing = self.character.as_ref()?;
        Some(Skinning {
            palette: posing
                .palette_at(time)
                .iter()
                .map(|m| m.to_cols_4x4())
                .collect(),
            influences: posing.rig.influences.clone(),
            bind: posing.bind.clone(),
        })
    }

    /// A glTF model as it was loaded, for writing it back out (`pelage export`): the bind
    /// mesh, the rig and the clip `[animation]` plays. `None` for meshes that are not glTF
    /// models.
    pub fn character(&self) -> Option<CharacterView<'_>> {
        let posing = self.character.as_ref()?;
        Some(CharacterView {
            bind: &posing.bind,
            rig: &posing.rig,
            clip: posing
                .clip
                .as_ref()
                .map(|(clip, speed, looping)| (clip, *speed, *looping)),
            skin_inset: posing.inset,
        })
    }

    /// Draws one frame at the scene's own time with the given tile size.
    pub fn render(&self, tile_size: u32) -> Result<RenderedImage, RenderError> {
        self.render_at(self.scene.time, tile_size)
    }

    /// Draws one frame at `time` (seconds) with the given tile size. Frame `k` of an animation
    /// at `fps` frames per second is `render_at(k as f32 / fps as f32, …)`.
    pub fn render_at(&self, time: f32, tile_size: u32) -> Result<RenderedImage, RenderError> {
        self.render_at_simd(time, tile_size, SimdLevel::active())
    }

    /// [`Self::render_at`] at a chosen [`SimdLevel`] (capped by what the CPU has): the same bytes
    /// at every level, only the speed differs. `Scalar` runs the fur fragment stage's scalar
    /// twin; the other levels run the quad stage. [`Self::render_at`] runs at
    /// [`SimdLevel::active`] (the environment variable `PELAGE_SIMD`).
    pub fn render_at_simd(
        &self,
        time: f32,
        tile_size: u32,
        level: SimdLevel,
    ) -> Result<RenderedImage, RenderError> {
        self.draw(&self.scene, time, tile_size, stage_at(level), level)
    }

    /// [`Self::render_at`] with the fur fragment stage's scalar twin ([`fragment::shade_fur`],
    /// one fragment at a time): the same bytes, slower. For checking the quad stage.
    pub fn render_scalar_twin_at(
        &self,
        time: f32,
        tile_size: u32,
    ) -> Result<RenderedImage, RenderError> {
        self.draw(
            &self.scene,
            time,
            tile_size,
            FragmentStage::ScalarTwin,
            SimdLevel::active(),
        )
    }

    /// [`Self::render_at`] with the framebuffer's float values too (row-major RGBA, row 0 at
    /// the top), as they are before the 8-bit rounding: for float and 16-bit outputs. The
    /// 8-bit image is the same bytes as [`Self::render_at`]'s.
    pub fn render_linear_at(
        &self,
        time: f32,
        tile_size: u32,
    ) -> Result<(RenderedImage, Vec<Vec4>), RenderError> {
        let level = SimdLevel::active();
        let (fb, stats) =
            self.draw_framebuffer(&self.scene, time, tile_size, stage_at(level), level, None)?;
        let linear = fb.to_rgba_f32();
        let image = self.finish_image(&fb, stats);
        self.keep_framebuffer(fb);
        Ok((image, linear))
    }

    /// The framebuffer [`Self::render_at`] and [`Self::render_linear_at`] round (the same
    /// draw, at the same [`SimdLevel::active`]), for callers that take its bytes
    /// ([`Framebuffer::to_rgba8`]) or its floats ([`Framebuffer::to_rgba_f32`]) themselves,
    /// such as the Python package. Another thread may set `cancel` to stop the frame early:
    /// the tiles not yet drawn are skipped and [`RenderError::Cancelled`] is returned. While
    /// `cancel` stays clear the bytes are those of [`Self::render_at`].
    pub fn render_framebuffer_at(
        &self,
        time: f32,
        tile_size: u32,
        cancel: &AtomicBool,
    ) -> Result<(Framebuffer, RasterStats), RenderError> {
        let level = SimdLevel::active();
        self.draw_framebuffer(
            &self.scene,
            time,
            tile_size,
            stage_at(level),
            level,
            Some(cancel),
        )
    }

    /// Non-fatal problems met while preparing (e.g. an OBJ without UVs), as
    /// [`RenderedImage::warnings`] carries them.
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    /// One frame of `s`, whose seed, mesh and fur are those of the bake (see [`Self::render_with`]).
    fn draw(
        &self,
        s: &Scene,
        time: f32,
        tile_size: u32,
        stage: FragmentStage,
        level: SimdLevel,
    ) -> Result<RenderedImage, RenderError> {
        let (fb, stats) = self.draw_framebuffer(s, time, tile_size, stage, level, None)?;
        let image = self.finish_image(&fb, stats);
        self.keep_framebuffer(fb);
        Ok(image)
    }

    /// A framebuffer of `width`×`height` in tiles of `tile_size`, cleared to `colour` and depth
    /// 1 (what [`Framebuffer::new`] gives): the last frame's where it has that shape and no
    /// other frame holds it, else a new one. Frame after frame (`pelage bench`, animations,
    /// the viewer, Python) the same 21 MB at 1366×768 are drawn again instead of being freed
    /// and allocated anew, which the allocator had handed back to the kernel between frames
    /// and faulted in again, page by page: 2–4 % of a frame's CPU time in the kernel.
    fn cleared_framebuffer(
        &self,
        width: u32,
        height: u32,
        tile_size: u32,
        colour: Vec4,
    ) -> Result<Framebuffer, RenderError> {
        let spare = self
            .spare_framebuffer
            .try_lock()
            .ok()
            .and_then(|mut spare| spare.take());
        match spare {
            Some(mut fb)
                if (fb.width(), fb.height(), fb.grid().tile_size) == (width, height, tile_size) =>
            {
                fb.clear(colour, 1.0);
                Ok(fb)
            }
            _ => Ok(Framebuffer::new(width, height, tile_size, colour)?),
        }
    }

    /// Keeps a drawn framebuffer for the next frame ([`Self::cleared_framebuffer`]).
    fn keep_framebuffer(&self, fb: Framebuffer) {
        if let Ok(mut spare) = self.spare_framebuffer.try_lock() {
            *spare = Some(fb);
        }
    }

    /// The 8-bit image of a drawn framebuffer.
    fn finish_image(&self, fb: &Framebuffer, stats: RasterStats) -> RenderedImage {
        RenderedImage {
            width: fb.width(),
            height: fb.height(),
            rgba8: fb.to_rgba8(),
            stats,
            warnings: self.warnings.clone(),
        }
    }

    /// [`Self::draw`]'s framebuffer, before rounding, and its counters; `cancel`, when given,
    /// stops the frame early once set ([`RenderError::Cancelled`]).
    fn draw_framebuffer(
        &self,
        s: &Scene,
        time: f32,
        tile_size: u32,
        stage: FragmentStage,
        level: SimdLevel,
        cancel: Option<&AtomicBool>,
    ) -> Result<(Framebuffer, RasterStats), RenderError> {
        let cancelled = || cancel.is_some_and(|c| c.load(Ordering::Relaxed));
        let (width, height) = (s.image.width, s.image.height);
        let mut fb =
            self.cleared_framebuffer(width, height, tile_size, s.image.background.extend(1.0))?;
        let camera = Camera {
            eye: s.camera.eye,
            target: s.camera.target,
            up: s.camera.up,
            fov_y_deg: s.camera.fov_y_deg,
            near: s.camera.near,
            far: s.camera.far,
        };
        let view_proj = camera.view_projection(width as f32 / height as f32);
        let light = s.light.direction.normalize_or_zero();
        let repeat = Vec2::from(s.fur.texture_repeat);
        let mut shade = ShadeParams::from_scene(s, time);
        shade.simd = level;
        let shade = &shade;
        let bending = Bending::at(s, time);
        let wind = bending.wind;
        // The object's offset on its path (`None` at rest: positions are left untouched).
        let moved = s
            .motion
            .as_ref()
            .map(|m| crate::shading::path_position(&m.path, time));
        let place = move |p: Vec3| match moved {
            Some(offset) => p + offset,
            None => p,
        };
        let maps = &self.maps;
        let n = s.fur.number_of_shells;
        let max_shell = n - 1;
        // A glTF model posed at this instant: every pass below grows from the posed body.
        let posed = self.mesh_at(time);
        let body: &Mesh = &posed;
        let lod = self.level_of_detail(s, body, moved.unwrap_or(Vec3::ZERO));
        let mut frame = Frame::new(&mut fb);
        frame.set_simd_level(level);
        if let Some(cancel) = cancel {
            frame.set_cancel(cancel);
        }

        // The skin: opaque, writes depth; charred where the fur burns.
        let skin_colour = s.fur.colour * 0.35;
        let debug = s.shading.debug_view != crate::scene::DebugView::None;
        let skin_layer = LayerParams {
            index: 0,
            max_shell,
            lookups: 0,
            height_fraction: 0.0,
            lod_span: 1.0,
        };
        frame.draw(
            &body.vertices,
            &body.indices,
            DrawState {
                cull: CullMode::Back,
                ..DrawState::default()
            },
            |v: &mesh::Vertex| ClipVertex {
                position: view_proj * place(v.position).extend(1.0),
                // The normal as posed lights the skin; the rest normal and position meet the
                // matches, which are fixed to the object (the same vectors for a mesh that is
                // not posed).
                varyings: (v.normal, v.rest_normal, v.rest_position),
            },
            move |f| {
                if debug {
                    return Some(Vec4::new(0.0, 0.0, 0.0, 1.0));
                }
                let (posed, rest, rest_position) = *f.varyings();
                let n = posed.normalize_or_zero();
                let colour = shade
                    .burn_outcome(rest.normalize_or_zero(), rest_position, &skin_layer)
                    .strand_colour(skin_colour);
                Some((colour * (0.5 + 0.5 * n.dot(light).max(0.0))).extend(1.0))
            },
        )?;

        // Shells, root to tip (thesis 3.1.4: layer by layer to avoid depth/alpha problems).
        let blended = DrawState {
            depth_compare: DepthCompare::LessEqual,
            depth_write: false,
            blend: BlendMode::Alpha,
            cull: CullMode::Back,
        };
        let shell_sampler = Sampler {
            address_u: AddressMode::Wrap,
            address_v: AddressMode::Wrap,
            filter: Filter::Trilinear,
        };
        // Fins at the silhouette, before the shells: every shell fragment that can show beside a
        // fin belongs to the faces turned to the eye in front of it, so it blends over the fin,
        // and the fins add fur only where the shells run out. They stand for the fur's full
        // height, so they burn as the top shell does.
        let fin_fade = lod.as_ref().map(|l| l.fin_fade);
        if let Some(fin) = &self.fin
            && fin_fade != Some(0.0)
        {
            let (vertices, triangles) =
                self.fin_geometry(body, camera.eye, light, bending, shade, moved, fin_fade);
            let fin_sampler = Sampler {
                address_u: AddressMode::Wrap,
                address_v: AddressMode::Clamp,
                filter: Filter::Trilinear,
            };
            let fin_layer = fin_layer_params(s);
            frame.draw_quads(
                &vertices,
                &triangles,
                DrawState {
                    cull: CullMode::None,
                    ..blended
                },
                |&(p, v): &(Vec3, FurVaryings)| ClipVertex {
                    position: view_proj * p.extend(1.0),
                    varyings: v,
                },
                FurShader {
                    textures: fin.maps(fin_sampler, false),
                    maps,
                    layer: fin_layer,
                    params: shade,
                    stage,
                },
            )?;
        }

        let difference = s.fur.fur_length();
        let eye = camera.eye;
        let burn_cosines = shade
            .burn
            .as_ref()
            .map(|burn| surely_burnt_cosines(body, burn));
        for (i, textures) in self.shells.iter().enumerate() {
            if cancelled() {
                return Err(RenderError::Cancelled);
            }
            let lod_span = lod.as_ref().map_or(1.0, |l| l.spans[i]);
            if lod_span <= 0.0 {
                continue;
            }
            let offset = self.shell_offsets[i];
            let layer = LayerParams {
                index: i as u32,
                max_shell,
                lookups: crate::shading::shadow_lookup_count(n, i as u32, s.shading.shadow_divisor),
                height_fraction: i as f32 / n as f32,
                lod_span,
            };
            // Triangles whose fur is surely burnt away on this layer, or bare under the maps,
            // are not drawn at all: the image is the same, and fur that is not there costs
            // nothing (thesis table 4.6).
            let kept = self.drawn_triangles(body, burn_cosines.as_deref(), shade, &layer);
            frame.draw_quads(
                &body.vertices,
                kept.as_deref().unwrap_or(&body.indices),
                blended,
                move |v: &mesh::Vertex| {
                    // A length map scales the layer's height above the skin (1 without one).
                    let length = maps.length_at(v.uv);
                    let strand_height = difference * length;
                    let offset = offset * length;
                    // Wind (thesis 3.3) and lean: the layer's displacement along the surface,
                    // more the higher it is, is applied once, in texture space (`wind_uv`, the
                    // reverse lookup); the vertices move only back along −n so the strand keeps
                    // its length.
                    let lean = bending.lean_at(maps, v);
                    let displacement =
                        bending.displacement(lean, v.normal, layer.height_fraction, strand_height);
                    let wind_uv = if bending.moves() {
                        crate::shading::wind_uv_offset(
                            displacement,
                            v.normal,
                            v.dpdu / repeat.x,
                            v.dpdv / repeat.y,
                        )
                    } else {
                        Vec2::ZERO
                    };
                    let wind_ts = wind.map_or(Vec3::ZERO, |(direction, force)| {
                        crate::shading::to_tangent_space(direction * force, &v.frame)
                    });
                    let lean = if bending.lean.is_some() {
                        crate::shading::to_tangent_space(lean, &v.frame)
                    } else {
                        Vec3::ZERO
                    };
                    let pull = bending.pull(displacement, v.normal);
                    let p = place(v.position + v.normal * offset + pull);
                    let change = crate::shading::shadow_change(
                        light,
                        v.frame.normal,
                        strand_height - offset,
                    );
                    ClipVertex {
                        position: view_proj * p.extend(1.0),
                        varyings: FurVaryings {
                            surface: SurfaceVaryings {
                                uv: v.uv * repeat,
                                wind_uv,
                                shadow: crate::shading::project_to_uv(
                                    change,
                                    v.dpdu / repeat.x,
                                    v.dpdv / repeat.y,
                                ),
                                mesh_uv: v.uv,
                                length,
                                fade: 1.0,
                                normal: v.rest_normal,
                                object: v.rest_position,
                            },
                            lit: LitVaryings {
                                light: crate::shading::to_tangent_space(light, &v.frame),
                                eye: crate::shading::to_tangent_space(eye - p, &v.frame),
                                wind: wind_ts,
                                lean,
                            },
                        },
                    }
                },
                FurShader {
                    textures: textures.maps(shell_sampler, true),
                    maps,
                    layer,
                    params: shade,
                    stage,
                },
            )?;
        }

        let stats = frame.finish();
        if cancelled() {
            return Err(RenderError::Cancelled);
        }
        Ok((fb, stats))
    }

    /// Level of detail for a frame of `s` with the object moved by `moved`: `None` without
    /// `[lod]`.
    fn level_of_detail(&self, s: &Scene, body: &Mesh, moved: Vec3) -> Option<LevelOfDetail> {
        let lod = s.lod.as_ref()?;
        // A posed model's bounds move with it; a still mesh's were measured once.
        let (centre, radius) = if std::ptr::eq(body, &self.mesh) {
            self.bounds
        } else {
            bounding_sphere(body)
        };
        // The distance to the nearest point of the bounding sphere: the fur there is the
        // largest on screen, and it must keep its look.
        let distance = (s.camera.eye - (centre + moved)).length() - radius;
        let fur_pixels = crate::shading::lod_fur_pixels(
            s.fur.fur_length(),
            distance,
            s.camera.fov_y_deg,
            s.image.height,
        );
        let level = crate::shading::lod_shell_level(
            fur_pixels,
            lod.pixels_per_shell,
            lod.min_shells,
            s.fur.number_of_shells,
        );
        Some(LevelOfDetail {
            fur_pixels,
            level,
            spans: crate::shading::lod_layer_spans(&self.lod_order, level),
            fin_fade: crate::shading::lod_fin_fade(fur_pixels, lod.fin_fade_pixels),
        })
    }

    /// The level of detail a frame of the scene at `time` is drawn with (`None` without
    /// `[lod]`).
    pub fn level_of_detail_at(&self, time: f32) -> Option<LevelOfDetail> {
        let moved = self
            .scene
            .motion
            .as_ref()
            .map_or(Vec3::ZERO, |m| crate::shading::path_position(&m.path, time));
        self.level_of_detail(&self.scene, &self.mesh_at(time), moved)
    }

    /// The mesh's triangles a shell layer draws: all but those whose fur is surely burnt away
    /// on the layer (`burn_cosines`, [`surely_burnt_cosines`] of `body`) and those where the maps
    /// leave the skin bare ([`PreparedScene::bare`]: the density map 0, on every layer; the
    /// length map 0, above the root). `None` when that is all of them. The image is the same:
    /// every fragment of a triangle left out would be discarded.
    fn drawn_triangles(
        &self,
        body: &Mesh,
        burn_cosines: Option<&[f32]>,
        shade: &ShadeParams,
        layer: &LayerParams,
    ) -> Option<Vec<[u32; 3]>> {
        let skipped = match layer.height_fraction > 0.0 {
            true => BARE_BY_DENSITY | BARE_BY_LENGTH,
            false => BARE_BY_DENSITY,
        };
        // A posed model keeps the rest mesh's triangles (and its uvs, which the flags read).
        let bare = self.bare.as_deref().filter(|bare| {
            std::ptr::eq(body, &self.mesh)
                || (bare.len() == body.indices.len() && body.indices == self.mesh.indices)
        });
        let burn = shade.burn.as_ref().zip(burn_cosines);
        if burn.is_none() && bare.is_none() {
            return None;
        }
        let burnt = |k: usize| {
            burn.is_some_and(|(burn, cosines)| {
                cosines
                    .get(k)
                    .is_some_and(|&c| burn.surely_burnt_from(c, layer.index, layer.max_shell))
            })
        };
        Some(
            body.indices
                .iter()
                .enumerate()
                .filter(|&(k, _)| !(bare.is_some_and(|bare| bare[k] & skipped != 0) || burnt(k)))
                .map(|(_, t)| *t)
                .collect(),
        )
    }

    /// Fin quads for this eye: one per silhouette edge, from the skin up to the fin height
    /// (times the length map at the corner) along the vertex normals, the top edge moved by the
    /// wind and lean like the top shell, everything moved by the object's path offset. Their
    /// frame: x along the edge (texture u), z up the averaged normal (texture v), y = z × x.
    /// `lod_fade` multiplies every corner's fade.
    #[allow(clippy::too_many_arguments)]
    fn fin_geometry(
        &self,
        body: &Mesh,
        eye: Vec3,
        light: Vec3,
        bending: Bending,
        shade: &ShadeParams,
        moved: Option<Vec3>,
        lod_fade: Option<f32>,
    ) -> (Vec<(Vec3, FurVaryings)>, Vec<[u32; 3]>) {
        let top = self.scene.fur.number_of_shells - 1;
        let maps = &self.maps;
        let wind = bending.wind.map(|(direction, force)| direction * force);
        let place = |p: Vec3| match moved {
            Some(offset) => p + offset,
            None => p,
        };
        // Silhouettes are found in object space: the eye as the unmoved object sees it.
        let object_eye = match moved {
            Some(offset) => eye - offset,
            None => eye,
        };
        let windows = mesh::fins::FinWindows {
            windows: self
                .scene
                .fur
                .fin_windows
                .iter()
                .map(|w| (w[0], w[1]))
                .collect(),
        };
        let selected = match self.scene.fur.fin_selection {
            FinSelectionSetting::Outline => {
                mesh::fins::outline_edges(body, &self.edges, object_eye)
            }
            FinSelectionSetting::AngleWindows => {
                mesh::fins::silhouette_edges(body, &self.edges, object_eye, &windows)
            }
        };
        let chains = mesh::fins::fin_chains(&self.edges, &selected);
        let vertex = |i: u32| body.vertices.get(i as usize);
        let tile = self.tile_world_size.x;
        let mut vertices = Vec::with_capacity(selected.len() * 4);
        let mut triangles = Vec::with_capacity(selected.len() * 2);
        for chain in &chains {
            // The fin texture's u runs on along the chain at the shells' scale (one tile per
            // `tile` world units), so neighbouring fins continue each other's strands; round a
            // loop, the scale is stretched to a whole number of tiles so the loop closes too.
            let length_of = |l: &mesh::fins::ChainLink| match (vertex(l.from), vertex(l.to)) {
                (Some(a), Some(b)) => (b.position - a.position).length(),
                _ => 0.0,
            };
            let total: f32 = chain.links.iter().map(length_of).sum();
            let per_length = if chain.closed && total > 0.0 {
                (total / tile).round().max(1.0) / total
            } else {
                1.0 / tile
            };
            // How squarely each fin faces the eye; a fin's opacity runs linearly between the
            // means at its two ends, shared with its neighbours, so that fins meeting at an angle
            // show no step in opacity where they join.
            let facing: Vec<f32> = chain
                .links
                .iter()
                .map(|l| match (vertex(l.from), vertex(l.to)) {
                    (Some(a), Some(b)) => {
                        let (x, z) = fin_axes(a, b);
                        let middle = place((a.position + b.position) * 0.5);
                        mesh::fins::fin_facing(x, z, eye - middle)
                    }
                    _ => 0.0,
                })
                .collect();
            let count = facing.len();
            let end_fade = |k: usize, next: bool| {
                let neighbour = match (next, chain.closed) {
                    (true, _) if k + 1 < count => Some(k + 1),
                    (true, true) => Some(0),
                    (false, _) if k > 0 => Some(k - 1),
                    (false, true) => Some(count - 1),
                    _ => None,
                };
                neighbour.map_or(facing[k], |j| 0.5 * (facing[k] + facing[j]))
            };
            let mut u = 0.0f32;
            for (k, link) in chain.links.iter().enumerate() {
                let (Some(a), Some(b)) = (vertex(link.from), vertex(link.to)) else {
                    continue;
                };
                let (from_fade, to_fade) = (end_fade(k, false), end_fade(k, true));
                let along = b.position - a.position;
                let length = along.length();
                let (u0, u1) = (u, u + length * per_length);
                u = u1;
                let (x, z) = fin_axes(a, b);
                if length == 0.0 || z == Vec3::ZERO {
                    continue;
                }
                // A fin burns like the top shell; one surely burnt away is left out.
                if shade.burn.as_ref().is_some_and(|burn| {
                    burn.surely_burnt([a.rest_normal, b.rest_normal, a.rest_normal], top, top)
                }) {
                    continue;
                }
                let frame = mesh::frame::TangentFrame {
                    tangent: x,
                    binormal: z.cross(x),
                    normal: z,
                };
                // The top corner over a skin vertex: the fin height times the painted length,
                // bent like the top shell (fins have no texture lookup to carry the bend, so
                // their top edge moves: the bend is applied once here too).
                let top_of = |v: &mesh::Vertex| {
                    let length = maps.length_at(v.uv);
                    let height = self.fin_height * length;
                    let bend =
                        bending.displacement(bending.lean_at(maps, v), v.normal, 1.0, height);
                    // Without the pull (figure 3.16) the top edge moves only sideways.
                    let bend = if bending.keep_length {
                        bend
                    } else {
                        bend - crate::shading::vertex_pull(bend, v.normal)
                    };
                    (v.position + v.normal * height + bend, length)
                };
                let (a_top, a_length) = top_of(a);
                let (b_top, b_length) = top_of(b);
                // The corners, with their share of the top shell's bend (0 at the roots, 1 at
                // the top edge, as the geometry bends).
                let corners = [
                    (a.position, a, Vec2::new(u0, 0.0), 1.0, from_fade, 0.0),
                    (b.position, b, Vec2::new(u1, 0.0), 1.0, to_fade, 0.0),
                    (b_top, b, Vec2::new(u1, 1.0), b_length, to_fade, 1.0),
                    (a_top, a, Vec2::new(u0, 1.0), a_length, from_fade, 1.0),
                ];
                // The fins' self-shadow (3.2.2 on the side view): the lookups run from each point
                // towards the light over the fin's full height, in the fin's own texture, so the
                // strands above and in front of it darken it and the sparse tips shade little.
                let height = self.fin_height * 0.5 * (a_length + b_length);
                let shadow = crate::shading::project_to_uv(
                    crate::shading::shadow_change(light, z, FIN_SHADOW_REACH * height),
                    x / per_length,
                    z * height,
                );
                let base = vertices.len() as u32;
                for (p, root, uv, length, facing, bent) in corners {
                    let p = place(p);
                    let fade = match self.scene.fur.fin_selection {
                        FinSelectionSetting::Outline => facing,
                        FinSelectionSetting::AngleWindows => {
                            fin_fade(&self.scene.fur.fin_windows, eye - p, root.normal)
                        }
                    };
                    vertices.push((
                        p,
                        FurVaryings {
                            surface: SurfaceVaryings {
                                uv,
                                wind_uv: Vec2::ZERO,
                                shadow,
                                mesh_uv: root.uv,
                                length,
                                fade: match lod_fade {
                                    Some(l) => fade * l,
                                    None => fade,
                                },
                                normal: root.rest_normal,
                                object: root.rest_position,
                            },
                            lit: LitVaryings {
                                light: crate::shading::to_tangent_space(light, &frame),
                                eye: crate::shading::to_tangent_space(eye - p, &frame),
                                wind: bend_varying(wind, &frame, bent),
                                // The lean (gravity, motion, combing) bends the fin's
                                // strands as it bends the shells' at the same height.
                                lean: bend_varying(
                                    bending.lean.is_some().then(|| bending.lean_at(maps, root)),
                                    &frame,
                                    bent,
                                ),
                            },
                        },
                    ));
                }
                triangles.push([base, base + 1, base + 2]);
                triangles.push([base, base + 2, base + 3]);
            }
        }
        (vertices, triangles)
    }

    /// Number of shell layers (root = 0).
    pub fn shell_count(&self) -> usize {
        self.shells.len()
    }

    /// The colour and tangent textures (with their mip chains) of shell layer `i`, root = 0.
    pub fn shell_textures(&self, i: usize) -> Option<(&Texture, &Texture)> {
        self.shells.get(i).map(|t| (&t.colour, &t.tangent))
    }

    /// Distance of each shell layer above the skin along the vertex normal, world units.
    pub fn shell_offsets(&self) -> &[f32] {
        &self.shell_offsets
    }

    /// The fin colour and tangent textures, when the scene has fins.
    pub fn fin_textures(&self) -> Option<(&Texture, &Texture)> {
        self.fin.as_ref().map(|t| (&t.colour, &t.tangent))
    }

    /// Height of the fins above the skin, world units.
    pub fn fin_height(&self) -> f32 {
        self.fin_height
    }

    /// The fur parameters the shells and fins were baked with (tile units).
    pub fn fur_params(&self) -> FurParams {
        fur_params(&self.scene, self.tile_world_size)
    }

    /// Mean world size of one fur tile along u and v.
    pub fn tile_world_size(&self) -> Vec2 {
        self.tile_world_size
    }

    /// The shading parameters of a frame at `time`, as the fragment closures see them.
    pub fn shade_params_at(&self, time: f32) -> ShadeParams {
        ShadeParams::from_scene(&self.scene, time)
    }

    /// The per-layer parameters of shell `i`, as the shell pass hands them to the fragment
    /// closure.
    pub fn shell_layer_params(&self, i: u32) -> LayerParams {
        let s = &self.scene;
        let n = s.fur.number_of_shells;
        LayerParams {
            index: i,
            max_shell: n - 1,
            lookups: crate::shading::shadow_lookup_count(n, i, s.shading.shadow_divisor),
            height_fraction: i as f32 / n as f32,
            lod_span: 1.0,
        }
    }

    /// The per-layer parameters the fin pass hands to the fragment closure.
    pub fn fin_layer_params(&self) -> LayerParams {
        fin_layer_params(&self.scene)
    }

    /// The fin quads drawn at `time` (chosen on the CPU per frame, as the thesis does): each
    /// vertex's object-space position with its fur varyings, and the triangles.
    pub fn fin_quads_at(&self, time: f32) -> (Vec<(Vec3, FurVaryings)>, Vec<[u32; 3]>) {
        let s = &self.scene;
        let shade = ShadeParams::from_scene(s, time);
        let moved = s
            .motion
            .as_ref()
            .map(|m| crate::shading::path_position(&m.path, time));
        let body = self.mesh_at(time);
        let lod = self.level_of_detail(s, &body, moved.unwrap_or(Vec3::ZERO));
        self.fin_geometry(
            &body,
            s.camera.eye,
            s.light.direction.normalize_or_zero(),
            Bending::at(s, time),
            &shade,
            moved,
            lod.map(|l| l.fin_fade),
        )
    }
}

impl PreparedScene {
    /// The scene's surface maps (length, density, direction, colour).
    pub fn maps(&self) -> &SurfaceMaps {
        &self.maps
    }

    /// The density bands of shell layer `i` (with a density map).
    pub fn shell_density(&self, i: usize) -> Option<&Texture> {
        self.shells.get(i).and_then(|t| t.density.as_ref())
    }

    /// The lean every vertex shares at `time` (gravity + spring lag × response, world space;
    /// combing adds to it per vertex); `None` when the scene has neither gravity, motion nor a
    /// direction map.
    pub fn shared_lean_at(&self, time: f32) -> Option<Vec3> {
        Bending::at(&self.scene, time).lean
    }

    /// The object's offset on its path at `time` (`None` without `[motion]`).
    pub fn object_offset_at(&self, time: f32) -> Option<Vec3> {
        self.scene
            .motion
            .as_ref()
            .map(|m| crate::shading::path_position(&m.path, time))
    }
}

/// The fur fragment stage a level runs: the scalar twin at `Scalar`, the quad stage above.
fn stage_at(level: SimdLevel) -> FragmentStage {
    match level {
        SimdLevel::Scalar => FragmentStage::ScalarTwin,
        _ => FragmentStage::Quad,
    }
}

impl PreparedScene {
    /// `settings` with this bake's seed, mesh, fur and base folder: the scene that
    /// [`Self::render_with`] draws, which [`PreparedScene::new`] would bake to the same textures.
    pub fn with_draw_settings(&self, settings: &Scene) -> Scene {
        Scene {
            seed: self.scene.seed,
            mesh: self.scene.mesh.clone(),
            fur: self.scene.fur.clone(),
            base_dir: self.scene.base_dir.clone(),
            ..settings.clone()
        }
    }

    /// Draws this bake with another scene's draw-time settings (image size, camera, shading,
    /// light, spots, stripes, wind, burn) at `time`, without baking again; `settings`' seed,
    /// mesh and fur are ignored. The image is byte-identical to
    /// `PreparedScene::new(&self.with_draw_settings(settings))?.render_at(time, tile_size)`: an
    /// interactive viewer moves the camera or toggles effects on one bake.
    pub fn render_with(
        &self,
        settings: &Scene,
        time: f32,
        tile_size: u32,
    ) -> Result<RenderedImage, RenderError> {
        self.draw(
            &self.with_draw_settings(settings),
            time,
            tile_size,
            stage_at(SimdLevel::active()),
            SimdLevel::active(),
        )
    }
}

#[cfg(test)]
mod cancel_tests {
    use super::*;

    fn small_scene() -> Scene {
        let text = "[image]\nwidth = 48\nheight = 32\n[mesh]\nkind = \"sphere\"\n\
                    [camera]\neye = [0.0, 1.0, 4.0]\n\
                    [fur]\nnumber_of_strands = 100\nnumber_of_shells = 4\ntexture_resolution = 16\n";
        Scene::parse(text, "<test>", std::path::Path::new(".")).expect("scene")
    }

    #[test]
    fn a_clear_cancel_flag_changes_no_byte() {
        let prepared = PreparedScene::new(&small_scene()).expect("prepared");
        let flag = AtomicBool::new(false);
        for tile in [2, 16, 64] {
            let (fb, _) = prepared
                .render_framebuffer_at(0.0, tile, &flag)
                .expect("render");
            let (image, linear) = prepared.render_linear_at(0.0, tile).expect("render");
            assert_eq!(fb.to_rgba8(), image.rgba8);
            assert_eq!(fb.to_rgba_f32(), linear);
        }
    }

    /// Frames drawn on the last frame's framebuffer (`PreparedScene::cleared_framebuffer`),
    /// after a frame of another background, another size, another tile size and a cancelled
    /// frame, are the bytes of a fresh bake's first frame.
    #[test]
    fn a_kept_framebuffer_draws_the_bytes_of_a_new_one() {
        let scene = small_scene();
        let mut dark = scene.clone();
        dark.image.background = glam::Vec3::new(0.9, 0.1, 0.3);
        let mut wide = scene.clone();
        wide.image.width = 64;
        let fresh = |s: &Scene, tile| {
            PreparedScene::new(s)
                .expect("prepared")
                .render_at(0.0, tile)
                .expect("render")
                .rgba8
        };
        let prepared = PreparedScene::new(&scene).expect("prepared");
        let cancel = AtomicBool::new(true);
        for (s, tile) in [
            (&scene, 16),
            (&dark, 16),
            (&scene, 16),
            (&wide, 16),
            (&wide, 8),
            (&wide, 8),
        ] {
            let again = prepared.render_with(s, 0.0, tile).expect("render");
            assert_eq!(again.rgba8, fresh(s, tile));
        }
        assert!(prepared.render_framebuffer_at(0.0, 8, &cancel).is_err());
        let (image, linear) = prepared.render_linear_at(0.3, 16).expect("render");
        let new = PreparedScene::new(&scene).expect("prepared");
        assert_eq!((image.rgba8, linear), {
            let (image, linear) = new.render_linear_at(0.3, 16).expect("render");
            (image.rgba8, linear)
        });
    }

    #[test]
    fn a_set_cancel_flag_stops_the_render() {
        let prepared = PreparedScene::new(&small_scene()).expect("prepared");
        let flag = AtomicBool::new(true);
        let result = prepared.render_framebuffer_at(0.0, 16, &flag);
        assert!(matches!(result, Err(RenderError::Cancelled)));
        assert!(!RenderError::Cancelled.is_bad_input());
    }
}

#[cfg(test)]
mod bare_tests {
    use super::*;
    use std::path::Path;

    /// A 16×4 map whose red is 0 on the columns `zero` (wrapping), 255 elsewhere, as a PNG in
    /// `dir`.
    fn write_map(dir: &Path, name: &str, zero: std::ops::Range<u32>) {
        let image = image::RgbaImage::from_fn(16, 4, |x, _| {
            let r = if zero.contains(&x) { 0 } else { 255 };
            image::Rgba([r, r, r, 255])
        });
        image.save(dir.join(name)).expect("writes the map");
    }

    fn scene(dir: &Path, maps: &str) -> Scene {
        let text = format!(
            "[image]\nwidth = 160\nheight = 120\n[mesh]\nkind = \"torus\"\n\
             [camera]\neye = [0.0, 6.0, 12.0]\n\
             [fur]\nnumber_of_strands = 300\nnumber_of_shells = 8\ntexture_resolution = 32\n\
             [maps]\n{maps}\naddress = [\"wrap\", \"clamp\"]\n"
        );
        Scene::parse(&text, "<test>", dir).expect("scene")
    }

    #[test]
    fn triangles_bare_under_the_maps_are_left_out_without_changing_a_byte() {
        let dir = std::env::temp_dir().join(format!("pelage-bare-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        write_map(&dir, "density.png", 0..8);
        write_map(&dir, "length.png", 6..14);
        for maps in [
            "density = \"density.png\"",
            "length = \"length.png\"",
            "density = \"density.png\"\nlength = \"length.png\"",
        ] {
            let mut prepared = PreparedScene::new(&scene(&dir, maps)).expect("prepared");
            let bare = prepared.bare.clone().expect("some triangles are bare");
            let drawn = prepared.render(16).expect("renders");
            prepared.bare = None;
            let all = prepared.render(16).expect("renders");
            assert_eq!(drawn.rgba8, all.rgba8, "{maps}");
            assert!(
                drawn.stats.triangles < all.stats.triangles,
                "{maps}: {} triangles drawn against {}",
                drawn.stats.triangles,
                all.stats.triangles
            );
            assert!(drawn.stats.fragments_shaded < all.stats.fragments_shaded);
            assert_eq!(drawn.stats.fragments_written, all.stats.fragments_written);
            // Only triangles whose uvs lie well inside the zero columns are flagged.
            assert!(bare.contains(&0));
        }
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_map_zero_only_in_part_of_a_triangles_reach_leaves_it_drawn() {
        let maps = SurfaceMaps::none();
        let texels: Vec<[u8; 4]> = (0..16u32 * 4)
            .map(|i| {
                if i % 16 == 6 {
                    [255, 0, 0, 255]
                } else {
                    [0; 4]
                }
            })
            .collect();
        let map = Texture::from_rgba8(16, 4, texels).expect("texture");
        // Column 6 covers u in [6/16, 7/16); a bilinear sample reads it within a texel of it.
        let tri = |u0: f32, u1: f32| [Vec2::new(u0, 0.2), Vec2::new(u1, 0.2), Vec2::new(u0, 0.8)];
        assert!(maps.red_is_zero_over(&map, tri(0.0, 3.0 / 16.0)));
        assert!(!maps.red_is_zero_over(&map, tri(0.0, 5.0 / 16.0)));
        assert!(!maps.red_is_zero_over(&map, tri(7.5 / 16.0, 0.6)));
        assert!(maps.red_is_zero_over(&map, tri(9.5 / 16.0, 0.9)));
        assert!(!maps.red_is_zero_over(&map, tri(f32::NAN, 0.1)));
        // A reach over more texels than a triangle's check reads is drawn, even on zeros.
        let zeros = Texture::from_rgba8(128, 128, vec![[0; 4]; 128 * 128]).expect("texture");
        assert!(maps.red_is_zero_over(&zeros, tri(0.1, 0.3)));
        assert!(!maps.red_is_zero_over(&zeros, tri(0.0, 0.9)));
        // Clamped, a coordinate far outside reads the edge column.
        assert!(maps.red_is_zero_over(&map, tri(-5.0, -4.0)));
    }
}
