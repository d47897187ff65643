//! The fur fragment stage: the thesis's fragment shader (3.2–3.4) as Rust, composed from the
//! pure terms in [`crate::shading`], in this order:
//!
//! 1. burning (3.4): the matches' lobe intensity `I` and the burn rule for this layer; a burnt
//!    texel is discarded here, before any texture read, so burnt fur costs less (table 4.6);
//! 2. the reverse wind lookup (3.3): the texel that lands here is read at `uv − wind_uv`;
//! 3. colour and tangent maps, read trilinearly at the level of detail of the fur uv's coarse
//!    derivatives; a transparent texel is discarded before shading;
//! 4. spots, then stripes (3.2.4), blended into the strand colour, then charring by `1 − I`;
//! 5. the tangent bent by a fraction of the wind and renormalised (3.3.1);
//! 6. the shell self-shadow (3.2.2): each lookup reads the alpha of one texel, the nearest on
//!    the mip level nearest the level of detail, along the shadow offset plus the wind's;
//! 7. Kajiya–Kay diffuse and specular, the dampened specular, and eq. 3.7.
//!
//! Two implementations give the same bits: [`shade_fur`], one fragment at a time (the scalar
//! twin, the plain statement of the shader), and [`shade_fur_quad`], which the renderer runs:
//! it finds each quad's level of detail and mip levels once and hands the quad's shaded lanes
//! to a [`FurBatch`], which runs every step above on [`BATCH_LANES`] lanes of the tile's quads
//! (32 in the AVX2 copy of the hot path and 16 in the AVX-512 one, [`crate::simd`]; a batch
//! holding at most 16, 8 or 4 lanes runs the stage that wide) at once in structure-of-arrays
//! form (the texture pair's footprints with [`TrilinearPair::sample_lanes`], the alpha test as
//! a lane mask, [`shading::ShadowLanes`] for step 6, lookup `k` of every lane in one batch;
//! [`crate::shading::lanes`] for the rest). The golden tests render every scene with both.

use super::maps::SurfaceMaps;
use crate::raster::texture::{
    MipLevel, PairedTexels, TrilinearPair, footprint_squared, level_of_detail,
    level_of_detail_of_footprint,
};
use crate::raster::{Fragment, PixelSlot, Quad, QuadShader, QuadSlots, Sampler, Texture, Varyings};
use crate::scene::{
    AmbientTermSetting, DebugView, MatchSetting, PointMatch, Scene, ShadowTexelSetting,
    SpecularLobesSetting, SpotKind, StripeKind,
};
use crate::shading::{
    self, AmbientTerm, BurnOutcome, ShadingWeights, ShadowTexel, SpecularLobes, SpecularTangents,
    Vec3xN,
    lanes::{lane_mask, select_bits},
};
use glam::{Vec2, Vec3, Vec4};

/// Alpha below which a fur texel is discarded before any shading (half of the smallest
/// non-zero 8-bit alpha). The shell shadow's "transparent" is the same
/// ([`shading::SHADOW_OPAQUE_ALPHA`]).
pub const ALPHA_DISCARD: f32 = shading::SHADOW_OPAQUE_ALPHA;

/// What the vertex stage hands the fur fragment stage: what every shaded fragment reads,
/// then what only lit fragments read, so that the scalar twin interpolates each part only for
/// the fragments that need it ([`Quad::field`]); the quad stage interpolates a component of a
/// batch's lanes at a time, when read (`BatchVaryings`).
///
/// `repr(C)` of `f32` fields only (bytemuck's `Pod` checks that there is no padding), so that
/// interpolation can run over all components as one array, and a batch can address a field
/// by its first component's index.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct FurVaryings {
    /// Steps 1–4 (texture reads, alpha test, burn, spots, the shadow's lookups).
    pub surface: SurfaceVaryings,
    /// The lighting (steps 5 and 7).
    pub lit: LitVaryings,
}

/// The part of [`FurVaryings`] that every shaded fragment reads.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SurfaceVaryings {
    /// Fur texture coordinates (mesh uv × repeat).
    pub uv: Vec2,
    /// The wind's uv displacement of this layer: the texel landing here comes from `uv − wind_uv`.
    pub wind_uv: Vec2,
    /// The shadow lookup: uv offset towards the light over the fur above this layer.
    pub shadow: Vec2,
    /// Mesh uv of the skin point (where the surface maps are read).
    pub mesh_uv: Vec2,
    /// The length map's value at the vertices (1 without one), interpolated: the vertex stage
    /// scaled the layer's height by it.
    pub length: f32,
    /// Opacity factor: 1 on shells; on fins it fades to 0 towards the ends of the angle window.
    pub fade: f32,
    /// The skin normal, object space (light spots and matches are fixed to the object).
    pub normal: Vec3,
    /// The skin point under this fragment, object space (spots and stripes are fixed to it).
    pub object: Vec3,
}

/// The part of [`FurVaryings`] that only lit fragments read.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct LitVaryings {
    /// Direction towards the light, tangent space.
    pub light: Vec3,
    /// Vector towards the eye, tangent space (not normalised).
    pub eye: Vec3,
    /// The wind vector (direction × force) in tangent space.
    pub wind: Vec3,
    /// The lean of gravity, the object's motion and combing (tangent space; zero without them).
    pub lean: Vec3,
}

/// Number of `f32` components of [`FurVaryings`].
const FUR_VARYING_FLOATS: usize = size_of::<FurVaryings>() / size_of::<f32>();

/// The index of a field's first component in [`FurVaryings`] seen as `f32`s.
macro_rules! component {
    ($($field:tt)+) => {
        std::mem::offset_of!(FurVaryings, $($field)+) / size_of::<f32>()
    };
}
const UV: usize = component!(surface.uv);
const WIND_UV: usize = component!(surface.wind_uv);
const SHADOW: usize = component!(surface.shadow);
const MESH_UV: usize = component!(surface.mesh_uv);
const FADE: usize = component!(surface.fade);
const NORMAL: usize = component!(surface.normal);
const OBJECT: usize = component!(surface.object);
const LENGTH: usize = component!(surface.length);
const LIGHT: usize = component!(lit.light);
const EYE: usize = component!(lit.eye);
const WIND: usize = component!(lit.wind);
const LEAN: usize = component!(lit.lean);

/// Implements [`Varyings`] for a `repr(C)` struct of `f32` fields: component by component
/// `(a·wa + b·wb) + c·wc`, like every field's own `weighted_sum`, over the struct seen as one
/// array, which the compiler runs on packed registers.
macro_rules! pod_varyings {
    ($($t:ty),*) => {$(
        impl Varyings for $t {
            #[inline(always)]
            fn weighted_sum(a: &Self, wa: f32, b: &Self, wb: f32, c: &Self, wc: f32) -> Self {
                const FLOATS: usize = size_of::<$t>() / size_of::<f32>();
                let [a, b, c] = [a, b, c].map(bytemuck::cast_ref::<Self, [f32; FLOATS]>);
                bytemuck::cast(<[f32; FLOATS]>::weighted_sum(a, wa, b, wb, c, wc))
            }
        }
    )*};
}
pod_varyings!(FurVaryings, SurfaceVaryings, LitVaryings);

/// A spot, resolved from the scene.
#[derive(Clone, Copy, Debug)]
pub enum Spot {
    /// Inside an ellipsoid.
    Ellipsoid {
        /// Centre, object space.
        centre: Vec3,
        /// Semi-axes.
        radii: Vec3,
        /// Full-colour fraction.
        inner: f32,
        /// Colour.
        colour: Vec3,
    },
    /// A lobe of a light fixed to the object.
    Light {
        /// Towards the spot light, object space.
        direction: Vec3,
        /// Lobe exponent.
        exponent: f32,
        /// Intensity of full colour.
        inner_threshold: f32,
        /// Intensity where the ring ends.
        outer_threshold: f32,
        /// Cosines below this give weight 0 for certain (the lobe is not taken there).
        outside_below: f32,
        /// `direction` normalised once more, as [`shading::light_spot_cosine`] normalises it, so
        /// that a fragment's cosine is the dot product with its unit normal.
        cosine_direction: Vec3,
        /// Colour.
        colour: Vec3,
    },
    /// The lobe of a light at a point fixed to the object, within its reach
    /// ([`shading::point_light_intensity`]).
    PointLight {
        /// The light's position, object space.
        position: Vec3,
        /// Where it fades out ([`shading::reach_falloff`]).
        reach: f32,
        /// Lobe exponent.
        exponent: f32,
        /// Intensity of full colour.
        inner_threshold: f32,
        /// Intensity where the ring ends.
        outer_threshold: f32,
        /// Cosines below this give intensities under both thresholds for certain.
        outside_below: f32,
        /// Colour.
        colour: Vec3,
    },
    /// Periodic bands in the lobe of a light fixed to the object
    /// ([`shading::light_stripe_intensity`]).
    LightStripe {
        /// Towards the stripe light, object space.
        direction: Vec3,
        /// `direction` normalised once more, as [`shading::light_spot_cosine`] normalises it.
        cosine_direction: Vec3,
        /// Lobe exponent.
        exponent: f32,
        /// Band spacing, lobe units.
        period: f32,
        /// Core width, lobe units.
        width: f32,
        /// Blend width, lobe units.
        softness: f32,
        /// Colour.
        colour: Vec3,
    },
    /// Periodic bands across an axis.
    Stripe {
        /// Unit axis.
        axis: Vec3,
        /// Band spacing.
        period: f32,
        /// Core width.
        width: f32,
        /// Blend width.
        softness: f32,
        /// Colour.
        colour: Vec3,
    },
}

impl Spot {
    /// `(colour, weight)` of this spot at an object-space point with normal `normal`.
    #[inline]
    pub fn weight_at(&self, object: Vec3, normal: Vec3) -> (Vec3, f32) {
        self.weight_at_unit_normal(object, normal.normalize_or_zero())
    }

    /// [`Spot::weight_at`] with the normal already normalised (`normal.normalize_or_zero()`),
    /// as a fragment with several spots and matches computes it once.
    #[inline(always)]
    pub fn weight_at_unit_normal(&self, object: Vec3, unit_normal: Vec3) -> (Vec3, f32) {
        match *self {
            Spot::Ellipsoid {
                centre,
                radii,
                inner,
                colour,
            } => (
                colour,
                shading::ellipsoid_spot_intensity(object, centre, radii, inner),
            ),
            Spot::Light {
                exponent,
                inner_threshold,
                outer_threshold,
                outside_below,
                cosine_direction,
                colour,
                ..
            } => {
                // `shading::light_spot_cosine(normal, direction)`, both normalisations done.
                let cosine = unit_normal.dot(cosine_direction);
                if cosine < outside_below {
                    return (colour, 0.0);
                }
                let lobe = shading::light_spot_lobe(cosine, exponent);
                (
                    colour,
                    shading::spot_gradient(lobe, inner_threshold, outer_threshold),
                )
            }
            Spot::PointLight {
                position,
                reach,
                exponent,
                inner_threshold,
                outer_threshold,
                outside_below,
                colour,
            } => {
                // `shading::point_light_intensity`, the power skipped where the product is
                // surely 0 or under both thresholds (the gradient is then what it is at 0).
                let offset = position - object;
                let falloff = shading::reach_falloff(offset.dot(offset), reach);
                let cosine = shading::point_light_cosine(unit_normal, offset);
                let intensity = if falloff > 0.0 && cosine >= outside_below {
                    shading::light_spot_lobe(cosine, exponent) * falloff
                } else {
                    0.0
                };
                (
                    colour,
                    shading::spot_gradient(intensity, inner_threshold, outer_threshold),
                )
            }
            Spot::LightStripe {
                cosine_direction,
                exponent,
                period,
                width,
                softness,
                colour,
                ..
            } => {
                // `shading::light_stripe_intensity(normal, direction, …)`, both normalisations
                // done.
                let lobe = shading::light_spot_lobe(unit_normal.dot(cosine_direction), exponent);
                (
                    colour,
                    shading::light_stripe_band(lobe, period, width, softness),
                )
            }
            Spot::Stripe {
                axis,
                period,
                width,
                softness,
                colour,
            } => (
                colour,
                shading::stripe_intensity(object.dot(axis), period, width, softness),
            ),
        }
    }
}

impl Spot {
    /// [`Spot::weight_at_unit_normal`]'s weight for `N` lanes (a [`FurBatch`]'s), lane by lane the
    /// same bits: ellipsoids and light spots as plain loops over the lanes (a light spot's power
    /// is skipped when every lane is surely outside it), stripes lane by lane.
    #[inline(always)]
    pub fn weights_lanes<const N: usize>(
        &self,
        object: &Vec3xN<N>,
        unit_normal: &Vec3xN<N>,
    ) -> [f32; N] {
        match *self {
            Spot::Ellipsoid {
                centre,
                radii,
                inner,
                ..
            } => shading::ellipsoid_spot_intensity_lanes(object, centre, radii, inner),
            Spot::Light {
                exponent,
                inner_threshold,
                outer_threshold,
                outside_below,
                cosine_direction,
                ..
            } => {
                let cosine = unit_normal.dot(&Vec3xN::splat(cosine_direction));
                let mut outside = [0u32; N];
                for i in 0..N {
                    outside[i] = lane_mask(cosine[i] < outside_below);
                }
                if outside.iter().all(|&o| o != 0) {
                    return [0.0; N];
                }
                let lobe = shading::light_spot_lobe_lanes(cosine, exponent);
                let mut weight =
                    shading::spot_gradient_lanes(lobe, inner_threshold, outer_threshold);
                for i in 0..N {
                    weight[i] = select_bits(outside[i], 0.0, weight[i]);
                }
                weight
            }
            Spot::PointLight { .. } | Spot::LightStripe { .. } | Spot::Stripe { .. } => {
                std::array::from_fn(|i| {
                    self.weight_at_unit_normal(object.lane(i), unit_normal.lane(i))
                        .1
                })
            }
        }
    }

    /// Whether this spot's weight is surely 0 at every fragment of the triangle whose corners
    /// have these object-space points and normals (fragments interpolated inside it): an
    /// ellipsoid the triangle lies outside of ([`shading::ellipsoid_surely_outside`]), or a
    /// light spot whose cosine every fragment's normal keeps below the cosine from which it
    /// has weight ([`shading::light_spot_surely_outside`]). `false` when unsure, and for the
    /// other kinds.
    pub fn surely_misses(&self, object: [Vec3; 3], normals: [Vec3; 3]) -> bool {
        match *self {
            Spot::Ellipsoid { centre, radii, .. } => {
                shading::ellipsoid_surely_outside(object, centre, radii)
            }
            Spot::Light {
                outside_below,
                cosine_direction,
                ..
            } => super::light_spot_memo::light_spot_surely_outside(
                normals,
                cosine_direction,
                outside_below,
            ),
            _ => false,
        }
    }

    /// The spot's colour.
    #[inline(always)]
    pub fn colour(&self) -> Vec3 {
        match *self {
            Spot::Ellipsoid { colour, .. }
            | Spot::Light { colour, .. }
            | Spot::PointLight { colour, .. }
            | Spot::LightStripe { colour, .. }
            | Spot::Stripe { colour, .. } => colour,
        }
    }
}

/// The burn state of a frame: the matches and their current exponent.
#[derive(Clone, Debug)]
pub struct BurnState {
    /// Unit directions of the matches given by direction, object space.
    pub directions: Vec<Vec3>,
    /// `directions` normalised once more, as [`shading::light_spot_cosine`] normalises them,
    /// so that a fragment's cosine is the dot product with its unit normal.
    pub cosine_directions: Vec<Vec3>,
    /// The matches at points, object space.
    pub points: Vec<PointMatch>,
    /// The lobe exponent at this instant.
    pub exponent: f32,
    /// Cosines below this give intensities under the burn threshold for certain.
    pub unburnt_below: f32,
    /// `burnt_from[k]`: a largest cosine (over the matches by direction) from which the fur is
    /// surely burnt away on shell `k` ([`BurnState::burnt_from_cosine`]); +∞ where nothing is
    /// sure (the root shell, which never burns).
    pub burnt_from: Vec<f32>,
}

impl BurnState {
    /// The burn of matches by direction (`directions`, normalised here) and at `points`, with
    /// lobe exponent `exponent`, on fur of `max_shell + 1` shells.
    pub fn new(
        directions: &[Vec3],
        points: Vec<PointMatch>,
        exponent: f32,
        max_shell: u32,
    ) -> Self {
        let directions: Vec<Vec3> = directions.iter().map(|d| d.normalize_or_zero()).collect();
        BurnState {
            cosine_directions: directions.iter().map(|m| m.normalize_or_zero()).collect(),
            directions,
            points,
            exponent,
            unburnt_below: shading::light_spot_cosine_below(shading::BURN_THRESHOLD, exponent),
            burnt_from: (0..=max_shell)
                .map(|layer| {
                    shading::light_spot_cosine_above(
                        shading::burnt_away_above(layer, max_shell),
                        exponent,
                    )
                })
                .collect(),
        }
    }

    /// The cosine from which fur is surely burnt away on shell `layer` of `max_shell`: a
    /// fragment whose largest cosine towards the matches by direction is at least this is
    /// [`BurnOutcome::Burnt`] by [`shading::burn_rule`], whatever its power rounds to and
    /// whatever the matches at points add (they only raise the intensity). +∞ when nothing
    /// is sure, and for a `max_shell` other than the one this state was made for.
    #[inline(always)]
    pub fn burnt_from_cosine(&self, layer: u32, max_shell: u32) -> f32 {
        if self.burnt_from.len() != max_shell as usize + 1 {
            return f32::INFINITY;
        }
        self.burnt_from
            .get(layer as usize)
            .copied()
            .unwrap_or(f32::INFINITY)
    }

    /// Whether every fragment of a triangle with these vertex normals is surely burnt away on
    /// shell `layer` of `max_shell` (so the triangle can be skipped without changing a pixel).
    /// Only matches given by direction are bounded; matches at points never skip a triangle.
    /// [`BurnState::surely_burnt_cosine`] then [`BurnState::surely_burnt_from`]: a renderer
    /// that tests a triangle on every layer takes the cosine once.
    ///
    /// Why it is safe: a fragment's normal is the renormalised convex combination of the vertex
    /// normals, whose length is at most 1, so its dot with a match `m` is at least the smallest
    /// vertex dot `c` when `c > 0`. The triangle is skipped only when `c − 1e-5` (a margin far
    /// above the rounding of the fragment's own dot products) reaches the layer's
    /// [`BurnState::burnt_from_cosine`], from which every fragment is burnt away. The root
    /// layer never burns.
    pub fn surely_burnt(&self, normals: [Vec3; 3], layer: u32, max_shell: u32) -> bool {
        self.surely_burnt_from(self.surely_burnt_cosine(normals), layer, max_shell)
    }

    /// The cosine every fragment of a triangle with these vertex normals surely reaches towards
    /// one match given by direction, less a margin: the largest over those matches of the
    /// smallest vertex dot `− 1e-5` ([`BurnState::surely_burnt`]); −∞ without such matches.
    /// It does not depend on the layer.
    pub fn surely_burnt_cosine(&self, normals: [Vec3; 3]) -> f32 {
        let unit = normals.map(|n| n.normalize_or_zero());
        self.directions
            .iter()
            .map(|&m| unit.iter().map(|n| n.dot(m)).fold(f32::INFINITY, f32::min) - 1.0e-5)
            .fold(f32::NEG_INFINITY, f32::max)
    }

    /// Whether a triangle whose [`BurnState::surely_burnt_cosine`] is `cosine` is surely burnt
    /// away on shell `layer` of `max_shell`: `cosine > 0` and at least the layer's
    /// [`BurnState::burnt_from_cosine`]. (Some match's bound passes both tests exactly when
    /// the largest bound does.)
    #[inline]
    pub fn surely_burnt_from(&self, cosine: f32, layer: u32, max_shell: u32) -> bool {
        let burnt_from = self.burnt_from_cosine(layer, max_shell);
        burnt_from <= 1.0 && cosine > 0.0 && cosine >= burnt_from
    }

    /// The spot intensity `I` of thesis 3.4 at a surface point (object space, rest pose) with
    /// this normal: the strongest match. Intensities surely under the burn threshold count as
    /// 0: the burn rule treats both alike.
    ///
    /// The matches given by direction take the lobe of their largest cosine, one power for
    /// all of them: `max(c₁, c₂, …)^e`, the lobe of the match the normal faces most
    /// (numeric conventions, "The burn's strongest match"). Each match at a point adds its
    /// [`shading::point_light_intensity`], its power taken only inside its reach.
    #[inline]
    pub fn intensity(&self, normal: Vec3, point: Vec3) -> f32 {
        self.intensity_at_unit_normal(normal.normalize_or_zero(), point)
    }

    /// [`BurnState::intensity`] with the normal already normalised (`normal.normalize_or_zero()`).
    #[inline]
    pub fn intensity_at_unit_normal(&self, unit_normal: Vec3, point: Vec3) -> f32 {
        let mut strongest = 0.0f32;
        if !self.cosine_directions.is_empty() {
            // `shading::light_spot_cosine(normal, m)`, both normalisations done.
            let cosine = self
                .cosine_directions
                .iter()
                .map(|&m| unit_normal.dot(m))
                .fold(f32::NEG_INFINITY, f32::max);
            if cosine >= self.unburnt_below {
                strongest = shading::light_spot_lobe(cosine, self.exponent);
            }
        }
        for m in &self.points {
            let offset = m.position - point;
            let falloff = shading::reach_falloff(offset.dot(offset), m.reach);
            if falloff > 0.0 {
                let cosine = shading::point_light_cosine(unit_normal, offset);
                if cosine >= self.unburnt_below {
                    strongest =
                        strongest.max(shading::light_spot_lobe(cosine, self.exponent) * falloff);
                }
            }
        }
        strongest
    }

    /// [`shading::burn_rule`] of [`BurnState::intensity_at_unit_normal`] on shell `layer` of
    /// `max_shell` for `N` lanes, lane by lane the same outcome in the lanes of `live` (the
    /// others are computed alike but left unfinished); a lane whose largest cosine towards the
    /// matches by direction reaches [`BurnState::burnt_from_cosine`] is burnt away without its
    /// power, and the power is skipped where no live lane needs it.
    #[inline(always)]
    pub fn lanes_outcome<const N: usize>(
        &self,
        unit_normals: &Vec3xN<N>,
        points: &Vec3xN<N>,
        live: u32,
        layer: u32,
        max_shell: u32,
    ) -> shading::BurnLanes<N> {
        let burnt_from = self.burnt_from_cosine(layer, max_shell);
        let (intensity, surely_burnt) =
            self.intensity_unless_burnt_lanes(unit_normals, points, live, burnt_from);
        let mut outcome = shading::burn_rule_lanes(intensity, layer, max_shell);
        outcome.burnt |= surely_burnt;
        outcome.charred &= !surely_burnt;
        outcome
    }

    /// [`BurnState::intensity_at_unit_normal`] of `N` lanes, lane by lane the same bits in the
    /// lanes of `live` (the cosines and their largest on all lanes at once, the one power of
    /// the matches by direction for all lanes, skipped where no live lane needs it, the
    /// matches at points lane by lane), and the mask of lanes surely burnt away because their
    /// largest cosine towards the matches by direction is at least `burnt_from`: their
    /// intensity is left unfinished (their power and the matches at points skipped).
    /// `burnt_from = +∞` finishes every live lane.
    #[inline(always)]
    #[allow(clippy::needless_range_loop)] // lanes as indexed loops: the form LLVM packs
    fn intensity_unless_burnt_lanes<const N: usize>(
        &self,
        unit_normals: &Vec3xN<N>,
        points: &Vec3xN<N>,
        live: u32,
        burnt_from: f32,
    ) -> ([f32; N], u32) {
        let mut strongest = [0.0f32; N];
        let mut burnt = 0u32;
        if !self.cosine_directions.is_empty() {
            let mut cosine = [f32::NEG_INFINITY; N];
            for &m in &self.cosine_directions {
                for i in 0..N {
                    let dot = (unit_normals.x[i] * m.x + unit_normals.y[i] * m.y)
                        + unit_normals.z[i] * m.z;
                    // `f32::max` as a compare and select (a NaN dot keeps the cosine, which is
                    // never NaN, as `max` does; the two may differ only in the sign of a zero
                    // cosine, which no test nor power below tells apart).
                    cosine[i] = if dot > cosine[i] { dot } else { cosine[i] };
                }
            }
            for i in 0..N {
                burnt |= lane_mask(cosine[i] >= burnt_from) & (1 << i);
            }
            let mut lit = 0u32;
            for i in 0..N {
                lit |= lane_mask(cosine[i] >= self.unburnt_below) & (1 << i);
            }
            if lit & !burnt & live != 0 {
                let lobe = shading::light_spot_lobe_lanes(cosine, self.exponent);
                for i in 0..N {
                    strongest[i] = select_bits(lane_mask(lit & (1 << i) != 0), lobe[i], 0.0);
                }
            }
        }
        if !self.points.is_empty() {
            for i in 0..N {
                if (live & !burnt) & (1 << i) == 0 {
                    continue;
                }
                let (unit_normal, point) = (unit_normals.lane(i), points.lane(i));
                for m in &self.points {
                    let offset = m.position - point;
                    let falloff = shading::reach_falloff(offset.dot(offset), m.reach);
                    if falloff > 0.0 {
                        let cosine = shading::point_light_cosine(unit_normal, offset);
                        if cosine >= self.unburnt_below {
                            strongest[i] = strongest[i]
                                .max(shading::light_spot_lobe(cosine, self.exponent) * falloff);
                        }
                    }
                }
            }
        }
        (strongest, burnt)
    }
}

/// The scene's shading parameters and effects, resolved once per frame.
#[derive(Clone, Debug)]
pub struct ShadeParams {
    /// Light colour.
    pub light_colour: Vec3,
    /// Ambient level.
    pub ambient: f32,
    /// Exponents of the diffuse, specular and the uncoloured last term's lobe (the dampened
    /// exponent, or under eq. 3.5 the specular exponent: [`shading::LightingModel::lobe_exponent`]).
    pub exponents: shading::LightingExponents,
    /// The lighting equation: what the uncoloured last term is (eq. 3.6/3.7 or eq. 3.5).
    pub lighting: shading::LightingModel,
    /// One or three tangents (and how three combine).
    pub tangents: SpecularTangents,
    /// Where `ψ_ambient` of eq. 3.7 stands.
    pub ambient_term: AmbientTerm,
    /// What each shell-shadow lookup adds.
    pub shadow_texel: ShadowTexel,
    /// Scheuermann shift.
    pub tangent_shift: f32,
    /// Weights of eq. 3.7.
    pub weights: ShadingWeights,
    /// Debug view.
    pub debug_view: DebugView,
    /// Spots, then stripes, in scene order.
    pub spots: Vec<Spot>,
    /// Burning, when the matches are lit at this instant.
    pub burn: Option<BurnState>,
    /// How much of the wind the tangents take at the tips.
    pub wind_tangent_fraction: f32,
    /// Whether a lean (gravity, motion, combing) bends the tangents.
    pub lean: bool,
    /// The SIMD level the frame's out-of-line helpers run at (the frame's own; a speed choice,
    /// never an image one): [`crate::simd::SimdLevel::active`] unless the renderer sets it.
    pub simd: crate::simd::SimdLevel,
}

/// What differs between the layers of one frame.
#[derive(Clone, Copy, Debug)]
pub struct LayerParams {
    /// Shell index (fins count as the top shell).
    pub index: u32,
    /// Index of the top shell, `number_of_shells − 1`.
    pub max_shell: u32,
    /// Shadow lookups for this layer.
    pub lookups: u32,
    /// `index / number_of_shells`: how far up the strand this layer is.
    pub height_fraction: f32,
    /// How many baked layers this one stands for under level of detail (1 without it): its
    /// alpha becomes `1 − (1 − α)^span` ([`shading::lod_alpha`]).
    pub lod_span: f32,
}

impl ShadeParams {
    /// From a scene at `time`.
    pub fn from_scene(s: &Scene, time: f32) -> Self {
        let w = &s.shading.weights;
        let mut spots: Vec<Spot> = s
            .spots
            .iter()
            .map(|spot| {
                // A light spot's cosine below which its weight is surely 0 (by direction or
                // towards its point alike).
                let outside_below = shading::light_spot_cosine_below(
                    spot.inner_threshold.min(spot.outer_threshold),
                    spot.exponent,
                );
                match (spot.kind, spot.position.zip(spot.reach)) {
                    (SpotKind::Ellipsoid, _) => Spot::Ellipsoid {
                        centre: spot.centre,
                        radii: spot.radii,
                        inner: spot.inner,
                        colour: spot.colour,
                    },
                    (SpotKind::Light, Some((position, reach))) => Spot::PointLight {
                        position,
                        reach,
                        exponent: spot.exponent,
                        inner_threshold: spot.inner_threshold,
                        outer_threshold: spot.outer_threshold,
                        outside_below,
                        colour: spot.colour,
                    },
                    (SpotKind::Light, None) => Spot::Light {
                        direction: spot.direction.normalize_or_zero(),
                        cosine_direction: spot.direction.normalize_or_zero().normalize_or_zero(),
                        exponent: spot.exponent,
                        inner_threshold: spot.inner_threshold,
                        outer_threshold: spot.outer_threshold,
                        outside_below,
                        colour: spot.colour,
                    },
                }
            })
            .collect();
        spots.extend(s.stripes.iter().map(|stripe| match stripe.kind {
            StripeKind::Axis => Spot::Stripe {
                axis: stripe.axis().normalize_or_zero(),
                period: stripe.period(),
                width: stripe.width(),
                softness: stripe.softness(),
                colour: stripe.colour,
            },
            StripeKind::Light => Spot::LightStripe {
                direction: stripe.direction().normalize_or_zero(),
                cosine_direction: stripe.direction().normalize_or_zero().normalize_or_zero(),
                exponent: stripe.exponent(),
                period: stripe.period(),
                width: stripe.width(),
                softness: stripe.softness(),
                colour: stripe.colour,
            },
        }));
        let burn = s.burn.as_ref().and_then(|b| {
            let schedule = shading::BurnSchedule {
                start: b.start,
                high_exponent: b.high_exponent,
                low_exponent: b.low_exponent,
                spread_duration: b.spread_duration,
            };
            shading::burn_exponent(time, &schedule).map(|exponent| {
                let directions: Vec<Vec3> = b
                    .matches
                    .iter()
                    .filter_map(|m| match m {
                        MatchSetting::Direction(d) => Some(*d),
                        MatchSetting::Point(_) => None,
                    })
                    .collect();
                let points = b
                    .matches
                    .iter()
                    .filter_map(|m| match m {
                        MatchSetting::Point(p) => Some(*p),
                        MatchSetting::Direction(_) => None,
                    })
                    .collect();
                BurnState::new(
                    &directions,
                    points,
                    exponent,
                    s.fur.number_of_shells.saturating_sub(1),
                )
            })
        });
        let lighting = match s.shading.lighting {
            crate::scene::LightingSetting::Eq36 => shading::LightingModel::Eq36,
            crate::scene::LightingSetting::Eq35 => shading::LightingModel::Eq35 {
                n: s.shading.specular1_exponent,
            },
        };
        ShadeParams {
            light_colour: s.light.colour,
            ambient: s.shading.ambient,
            exponents: shading::LightingExponents {
                banks: s.shading.banks_exponent,
                specular: s.shading.specular_exponent,
                dampened: lighting
                    .lobe_exponent(s.shading.specular_exponent, s.shading.dampened_exponent),
            },
            lighting,
            tangents: if s.shading.specular_tangents == 3 {
                SpecularTangents::Three(match s.shading.specular_lobes {
                    SpecularLobesSetting::Sum => SpecularLobes::Sum,
                    SpecularLobesSetting::Average => SpecularLobes::Average,
                })
            } else {
                SpecularTangents::One
            },
            ambient_term: match s.shading.ambient_term {
                AmbientTermSetting::Constant => AmbientTerm::Constant,
                AmbientTermSetting::Strand => AmbientTerm::Strand,
            },
            shadow_texel: match s.shading.shadow_texel {
                ShadowTexelSetting::Opaque => ShadowTexel::Opaque,
                ShadowTexelSetting::Alpha => ShadowTexel::Alpha,
            },
            tangent_shift: s.shading.tangent_shift,
            weights: ShadingWeights {
                ambient: w.ambient,
                diffuse: w.diffuse,
                specular: w.specular,
                dampened: w.dampened,
                shadow: w.shadow,
            },
            debug_view: s.shading.debug_view,
            spots,
            burn,
            wind_tangent_fraction: s.wind.as_ref().map_or(0.0, |w| w.tangent_fraction),
            lean: s.leans(),
            simd: crate::simd::SimdLevel::active(),
        }
    }

    /// The burn outcome for a layer at a surface point (object space, rest pose) with this
    /// normal (Unburnt when nothing burns).
    #[inline]
    pub fn burn_outcome(&self, normal: Vec3, point: Vec3, layer: &LayerParams) -> BurnOutcome {
        self.burn_outcome_at_unit_normal(normal.normalize_or_zero(), point, layer)
    }

    /// [`ShadeParams::burn_outcome`] with the normal already normalised.
    #[inline(always)]
    pub fn burn_outcome_at_unit_normal(
        &self,
        unit_normal: Vec3,
        point: Vec3,
        layer: &LayerParams,
    ) -> BurnOutcome {
        match &self.burn {
            Some(b) => shading::burn_rule(
                b.intensity_at_unit_normal(unit_normal, point),
                layer.index,
                layer.max_shell,
            ),
            None => BurnOutcome::Unburnt,
        }
    }
}

/// The textures one fur layer reads.
#[derive(Clone, Copy)]
pub struct LayerMaps<'a> {
    /// Colour and alpha.
    pub colour: &'a Texture,
    /// Encoded tangents.
    pub tangent: &'a Texture,
    /// `colour` and `tangent` interleaved ([`PairedTexels`]), which the quad stage reads
    /// instead of the two maps (the same values); `None` reads the maps.
    pub converted: Option<&'a PairedTexels>,
    /// Density bands (shells with a density map); `None` on fins, whose alpha the density
    /// scales instead.
    pub density: Option<&'a Texture>,
    /// How they are filtered.
    pub sampler: Sampler,
    /// A shell layer (true) or the fins (false).
    pub shell: bool,
}

/// Shades one fur fragment of a shell (or fin) layer; `None` discards it. This is the scalar
/// twin of [`shade_fur_quad`], which the renderer runs: both give the same bits.
///
/// Beyond the thesis, in this order: a shell layer above the painted length is dropped
/// ([`shading::layer_within_length`]; fins are not cut, their height follows the length at
/// their corners); the density map selects strands through the density bands
/// ([`shading::density_alpha`]), on fins it scales the alpha; level of detail compensates the
/// alpha of a layer standing for several ([`shading::lod_alpha`]); the colour map tints the
/// strand colour before spots ([`shading::tint_strand`]); the lean bends the tangent after the
/// wind.
///
/// Out of line: the quad stage's copies for each SIMD level and fixed-function state would
/// otherwise each carry a copy of it, and it runs at the `scalar` level alone (the baseline).
#[inline(never)]
pub fn shade_fur(
    f: &Fragment<FurVaryings>,
    textures: LayerMaps<'_>,
    maps: &SurfaceMaps,
    layer: &LayerParams,
    p: &ShadeParams,
) -> Option<Vec4> {
    let (ddx, ddy) = f.derivatives(|v| v.surface.uv);
    let lod = level_of_detail(ddx, ddy, textures.colour.width(), textures.colour.height());
    let v = f.varyings();
    let reads = LevelReads::new(textures, lod);
    let unit_normal = v.surface.normal.normalize_or_zero();
    match surface(&v.surface, unit_normal, &reads, textures, maps, layer, p) {
        Surface::Discarded => None,
        Surface::Finished(colour) => Some(colour),
        Surface::Lit(mut lit, lookups) => {
            lit.strand = spotted_strand(lit.strand, v.surface.object, unit_normal, lit.burn, p);
            let shadow = match lookups {
                ShadowLookups::Taken(shadow) => shadow,
                ShadowLookups::Pending { uv, offset } => {
                    let level = textures.colour.nearest_level(lod);
                    shading::shell_shadow(
                        |at| textures.sampler.alpha_nearest_in(level, at),
                        uv,
                        offset,
                        layer.lookups,
                        p.shadow_texel,
                    )
                }
            };
            let lit = match shadowed(lit, shadow, p) {
                Ok(lit) => lit,
                Err(finished) => return Some(finished),
            };
            let lighting = shading::strand_lighting(
                lit.tangent(&v.lit, layer, p),
                Vec3::Z,
                v.lit.light,
                v.lit.eye,
                p.exponents,
                p.tangents,
                p.tangent_shift,
            );
            Some(lit.colour(lighting, p))
        }
    }
}

/// Whether two triangles, known by their corners' addresses, are one, compared corner by
/// corner: the array's `==` compared them as one 16-byte and one 8-byte load of addresses the
/// quad had just stored as three 8-byte words, a load the stores cannot forward to (about 2 %
/// of thesis-4-2's samples waited on it).
#[inline(always)]
fn same_triangle(a: &[usize; 3], b: &[usize; 3]) -> bool {
    a[0] == b[0] && a[1] == b[1] && a[2] == b[2]
}

/// Shades the lanes of one quad ([`QuadSlots::lanes`]): lane by lane the same bits as
/// [`shade_fur`]. The quad's level of detail (its coarse derivatives) and the mip levels it
/// picks are found here, once; its shaded lanes (their slots and interpolation weights) then
/// join `batch`, which runs the whole stage on `N` lanes at a time ([`FurBatch`]).
/// Lanes of quads at other mip levels or of another triangle go to a fresh batch: the one held
/// is run first. Where step 1 has something to test (a burn, a length map), the quad is held
/// untested instead, and the quads held are tested together, a batch's worth at a time,
/// before they join.
///
/// `#[inline(always)]`: it is the hot path, compiled into each [`crate::simd`] level's copy of
/// the rasterizer's tile replay.
#[inline(always)]
#[allow(clippy::too_many_arguments)] // the quad, where its lanes go, and the layer's state
pub fn shade_fur_quad<'a, const N: usize>(
    quad: &Quad<'_, FurVaryings>,
    slots: QuadSlots,
    batch: &mut FurBatch<'a, N>,
    textures: LayerMaps<'a>,
    maps: &SurfaceMaps,
    layer: &LayerParams,
    p: &ShadeParams,
    mut write: impl FnMut(PixelSlot, Vec4),
) {
    if slots.lanes() == 0 {
        return;
    }
    // The triangle, known by its corners' addresses: they stay in place and unchanged while
    // the batch lives (one per tile and draw, [`QuadShader::Deferred`]).
    let triangle = quad.corners().map(|c| std::ptr::from_ref(c) as usize);
    if entry_test_needed(&textures, maps, p) {
        batch.hold(quad, slots, triangle, textures, maps, layer, p, &mut write);
        return;
    }
    let untouched = QuadEntry {
        charred: 0,
        char_factor: [1.0; 4],
    };
    join_quad(
        quad, slots, &untouched, triangle, batch, textures, maps, layer, p, &mut write,
    );
}

/// What step 1 of the fur stage found for a quad's lanes as they join a batch.
struct QuadEntry {
    /// Bit l: lane l is charred.
    charred: u32,
    /// Lane l's factor on the strand colour where charred.
    char_factor: [f32; 4],
}

/// A quad's lanes (`slots`, those step 1 kept) joining `batch`: [`shade_fur_quad`]'s level of
/// detail and batch keeping, for a quad of `triangle` (its corners' addresses).
#[inline(always)]
#[allow(clippy::too_many_arguments)] // the quad, where its lanes go, and the layer's state
fn join_quad<'a, const N: usize>(
    quad: &Quad<'_, FurVaryings>,
    slots: QuadSlots,
    entry: &QuadEntry,
    triangle: [usize; 3],
    batch: &mut FurBatch<'a, N>,
    textures: LayerMaps<'a>,
    maps: &SurfaceMaps,
    layer: &LayerParams,
    p: &ShadeParams,
    write: &mut impl FnMut(PixelSlot, Vec4),
) {
    // The level of detail reads the uv of lanes 0–2 (helper lanes too).
    let uv = |lane: usize| quad.field(lane, |v| &v.surface.uv);
    let footprint = quad_footprint(uv(0), uv(1), uv(2), &textures);
    let corners = || quad.corners().map(|c| *bytemuck::cast_ref(c));
    join_lanes(
        slots,
        quad.weights(),
        footprint,
        entry,
        (triangle, corners),
        batch,
        textures,
        maps,
        layer,
        p,
        write,
    );
}

/// The squared footprint ([`footprint_squared`]) of a quad whose lanes 0, 1 and 2 have these
/// texture coordinates, on the layer's colour map.
#[inline(always)]
fn quad_footprint(origin: Vec2, right: Vec2, below: Vec2, textures: &LayerMaps<'_>) -> f32 {
    let (ddx, ddy) = (
        Vec2::difference(&right, &origin),
        Vec2::difference(&below, &origin),
    );
    footprint_squared(ddx, ddy, textures.colour.width(), textures.colour.height())
}

/// A quad's lanes (`slots`, those step 1 kept; `weights` of its four lanes, its squared
/// `footprint`) joining `batch`: the mip levels the footprint picks, the batch run first
/// where it holds lanes of other levels or another triangle or has no room. The quad's
/// triangle comes as its corners' addresses (how the batch knows it) and a function that
/// copies its corners' varyings, called only where the batch takes a new triangle.
#[inline(always)]
#[allow(clippy::too_many_arguments)] // the lanes, where they go, and the layer's state
fn join_lanes<'a, const N: usize>(
    mut slots: QuadSlots,
    weights: &[[f32; 4]; 3],
    footprint: f32,
    entry: &QuadEntry,
    (triangle, corners): ([usize; 3], impl FnOnce() -> [[f32; FUR_VARYING_FLOATS]; 3]),
    batch: &mut FurBatch<'a, N>,
    textures: LayerMaps<'a>,
    maps: &SurfaceMaps,
    layer: &LayerParams,
    p: &ShadeParams,
    write: &mut impl FnMut(PixelSlot, Vec4),
) {
    // The footprint alone chooses the levels the lanes read; the level of detail itself
    // (`½·log2 ρ²`, a chain of dependent operations) is computed in the batch, all its lanes
    // at once.
    let (lower, shadow_index) = textures.colour.levels_of_footprint(footprint);
    let shadow_level = &textures.colour.levels()[shadow_index];
    // The lanes of a batch read one pair of mip levels and one shadow level: a quad at others
    // runs what the batch holds first. (One call site of the batch's run per copy of the hot
    // path keeps that copy small.)
    let lanes = slots.lanes();
    let full = batch.len + lanes.count_ones() as usize > N;
    if batch.len != 0
        && (full
            || !batch.reads(lower, shadow_level)
            || !same_triangle(&batch.varyings.triangle, &triangle))
    {
        batch.run(textures, maps, layer, p, write);
    }
    if batch.len == 0 {
        if !same_triangle(&batch.varyings.triangle, &triangle) {
            batch.varyings.triangle = triangle;
            batch.varyings.corners = corners();
        }
        batch.shadow_level = Some(shadow_level);
        batch.shadow_index = shadow_index;
        // The pair depends on the lower level alone (the textures and sampler are the draw's):
        // kept from batch to batch while that stays.
        if batch.pair_lower != Some(lower) {
            batch.pair_lower = Some(lower);
            let upper = (lower + 1).min(textures.colour.level_count() - 1);
            batch.pair = textures
                .sampler
                .trilinear_pair_at(textures.colour, textures.tangent, (lower, upper, 0.0))
                .map(|pair| match textures.converted {
                    Some(converted) => pair.with_converted(converted),
                    None => pair,
                });
        }
    }
    let i = batch.len;
    if i <= N - 4
        && let Some(whole) = slots.take_whole()
    {
        // The common quad, all four lanes shaded: joins the batch in whole rows.
        let at = i..i + 4;
        for (slot, taken) in batch.slots[at.clone()].iter_mut().zip(whole) {
            *slot = Some(taken);
        }
        for (lanes, quad_lanes) in batch.varyings.weights.iter_mut().zip(weights) {
            lanes[at.clone()].copy_from_slice(quad_lanes);
        }
        batch.footprint[at.clone()].fill(footprint);
        batch.char_factor[at].copy_from_slice(&entry.char_factor);
        batch.charred |= entry.charred << i;
        batch.len += 4;
        return;
    }
    for lane in 0..4 {
        if lanes & (1 << lane) == 0 {
            continue;
        }
        let Some(slot) = slots.take(lane) else {
            continue;
        };
        let i = batch.len;
        batch.slots[i] = Some(slot);
        for (lanes, quad_lanes) in batch.varyings.weights.iter_mut().zip(weights) {
            lanes[i] = quad_lanes[lane];
        }
        batch.footprint[i] = footprint;
        batch.char_factor[i] = entry.char_factor[lane];
        batch.charred |= ((entry.charred >> lane) & 1) << i;
        batch.len += 1;
    }
}

/// Whether step 1 of the fur stage has anything to test in this draw: a burn, or a length map
/// that cuts shells. Where it has, quads are held and tested together before they join a
/// [`FurBatch`] ([`FurBatch::hold`]).
#[inline(always)]
fn entry_test_needed(textures: &LayerMaps<'_>, maps: &SurfaceMaps, p: &ShadeParams) -> bool {
    p.burn.is_some() || (textures.shell && maps.length.is_some())
}

/// Lanes in a [`FurBatch`] on the baseline copy of the hot path ([`crate::simd::LANES`]): two
/// quads' worth; the AVX2 copy's batches hold [`crate::simd::AVX2_LANES`] and the AVX-512
/// copy's [`crate::simd::WIDE_LANES`], which plain per-lane loops turn into four 256-bit
/// instructions or single 512-bit ones.
pub const BATCH_LANES: usize = crate::simd::LANES;

/// The width of the stage that runs a wider batch holding at most this many lanes
/// ([`FurBatch::run`]); one of at most [`SMALLEST_LANES`] runs on a stage that wide.
const NARROW_LANES: usize = crate::simd::LANES;

/// The narrowest stage: one quad's lanes.
const SMALLEST_LANES: usize = 4;

/// The width of the stage that runs a 32-lane batch ([`crate::simd::AVX2_LANES`]) holding at
/// most this many lanes: the 16-lane stage, whose copy the AVX-512 level's batches use too.
const HALF_WIDE_LANES: usize = crate::simd::WIDE_LANES;

/// The lanes from which a triangle's first batch tests which spots surely miss it
/// ([`Spot::surely_misses`], about 380 instructions in f64) rather than computing every spot
/// on its lanes: the test costs about what the spots' arithmetic on this many lanes does.
const SPOTS_TEST_LANES: usize = 8;

/// Shaded fragments of a draw's quads in one tile waiting for the whole fur stage, which runs
/// on `N` lanes at once ([`BATCH_LANES`], [`crate::simd::AVX2_LANES`] at AVX2 or
/// [`crate::simd::WIDE_LANES`] at AVX-512)
/// in structure-of-arrays form: the texture pair's footprints, texel conversion and filter
/// ([`TrilinearPair::sample_lanes`]), the alpha test as a lane mask, the spots and charring, the shell shadow's lookups ([`shading::ShadowLanes`]), the lit
/// tangent, strand lighting and eq. 3.7 ([`crate::shading::lanes`]). The lanes of a batch lie
/// in one triangle, whose varyings it interpolates a component of all lanes at a time
/// (`BatchVaryings`), and read one pair of mip levels and one shadow level (each keeps its
/// own blend fraction); what is rare (density and colour maps, differently shaped maps, the
/// debug views) runs lane by lane inside the batch with the scalar terms. Step 1 (the burn,
/// the painted length) runs before lanes join: where a draw has it, quads are held and tested
/// a batch's worth at a time, on all their lanes at once, and only the lanes kept join.
///
/// Lane by lane the same bits as [`shade_fur`]: every step is the scalar twin's operations on
/// each lane, and a lane's result depends on nothing else in the batch. Lanes discarded after
/// they join run on with the others, their results dropped: the batch runs full without
/// compaction.
pub struct FurBatch<'a, const N: usize> {
    len: usize,
    /// Quads held for step 1 before they join (draws where it tests something).
    pending: PendingQuads<N>,
    /// The lower mip level index of `pair` (`None` before the first quad).
    pair_lower: Option<usize>,
    /// The mip levels the texture reads of the lanes held read (`None`: the colour and
    /// tangent maps differ in shape, each lane is sampled alone).
    pair: Option<TrilinearPair<'a>>,
    /// The mip level the shadow's lookups of the lanes held read.
    shadow_level: Option<&'a MipLevel>,
    /// The index of `shadow_level` in the colour map's chain.
    shadow_index: usize,
    slots: [Option<PixelSlot>; N],
    /// The lanes' triangle and weights, interpolated a component at a time when read.
    varyings: BatchVaryings<N>,
    /// Each lane's squared footprint (its quad's, [`footprint_squared`]), from which the batch
    /// computes the lanes' levels of detail.
    footprint: [f32; N],
    /// Bit i: lane i is charred by the burn (found by step 1 before its quad joined).
    charred: u32,
    /// Each charred lane's factor on the strand colour.
    char_factor: [f32; N],
    /// Which spots surely miss the triangle of the last batch with spots.
    spots: SpotsMissed,
}

/// Which spots surely miss a batch's triangle ([`Spot::surely_misses`]), found once a triangle.
#[derive(Clone, Copy, Default)]
struct SpotsMissed {
    /// The triangle (corner addresses).
    triangle: Option<[usize; 3]>,
    /// Whether `missed` was found for that triangle (at its first batch of more than
    /// [`SPOTS_TEST_LANES`] lanes, else at its next); until then `missed` is 0.
    tested: bool,
    /// Bit `s`: spot `s` surely misses that triangle, its weight 0 on every lane of it.
    missed: u64,
}

/// Quads of one triangle held for step 1 of the fur stage ([`FurBatch::hold`]): up to `N/4`
/// (four at most), quad `q`'s lane `l` at lane `4q + l` of `varyings`.
struct PendingQuads<const N: usize> {
    count: usize,
    varyings: BatchVaryings<N>,
    slots: [Option<QuadSlots>; MAX_HELD_QUADS],
}

/// The most quads [`FurBatch::hold`] holds: a batch's worth at [`crate::simd::AVX2_LANES`].
const MAX_HELD_QUADS: usize = 8;

impl<const N: usize> Default for PendingQuads<N> {
    /// None held.
    fn default() -> Self {
        PendingQuads {
            count: 0,
            varyings: BatchVaryings::default(),
            slots: [const { None }; MAX_HELD_QUADS],
        }
    }
}

/// What step 1 found for the quads held: bit `i` for lane `i` as [`PendingQuads`] lays them out.
struct HeldOutcome<const N: usize> {
    /// Lanes burnt away or above the painted length.
    dropped: u32,
    /// Lanes charred.
    charred: u32,
    /// Each charred lane's factor on the strand colour.
    char_factor: [f32; N],
}

impl<const N: usize> PendingQuads<N> {
    /// [`FurBatch::test_held`]'s work: the burn's outcome of all `N` lanes at once (lanes of
    /// no quad held, or not shaded, too; their results are dropped), and the painted length
    /// lane by lane.
    #[inline(always)]
    fn test(
        &self,
        length_map: Option<&Texture>,
        maps: &SurfaceMaps,
        layer: &LayerParams,
        p: &ShadeParams,
    ) -> HeldOutcome<N> {
        let mut live = 0u32;
        for (q, slots) in self.slots.iter().enumerate().take(self.count) {
            live |= slots.as_ref().map_or(0, |s| s.lanes()) << (4 * q);
        }
        let mut outcome = HeldOutcome {
            dropped: 0,
            charred: 0,
            char_factor: [1.0; N],
        };
        if let Some(burn) = &p.burn {
            // Object positions only where a match stands at a point: matches by direction read
            // the normal alone.
            let unit_normals = self.varyings.vec3(NORMAL).normalize_or_zero();
            let objects = if burn.points.is_empty() {
                Vec3xN::default()
            } else {
                self.varyings.vec3(OBJECT)
            };
            let lanes =
                burn.lanes_outcome(&unit_normals, &objects, live, layer.index, layer.max_shell);
            outcome.dropped = lanes.burnt & live;
            outcome.charred = lanes.charred & live;
            outcome.char_factor = lanes.colour_factor;
        }
        if let Some(length_map) = length_map {
            let (length, [u, v]) = (self.varyings.component(LENGTH), self.varyings.vec2(MESH_UV));
            for i in 0..N {
                if (live & !outcome.dropped) & (1 << i) != 0
                    && !shading::layer_within_length(
                        layer.height_fraction,
                        length[i],
                        maps.sample(length_map, Vec2::new(u[i], v[i])).x,
                    )
                {
                    outcome.dropped |= 1 << i;
                }
            }
        }
        outcome
    }
}

impl<const N: usize> Default for FurBatch<'_, N> {
    /// Empty.
    fn default() -> Self {
        FurBatch {
            len: 0,
            pending: PendingQuads::default(),
            pair_lower: None,
            pair: None,
            shadow_level: None,
            shadow_index: 0,
            slots: [const { None }; N],
            varyings: BatchVaryings::default(),
            footprint: [0.0; N],
            charred: 0,
            char_factor: [0.0; N],
            spots: SpotsMissed::default(),
        }
    }
}

/// The varyings of a [`FurBatch`]'s lanes: their triangle's corners and each lane's weights.
/// Every lane of a batch lies in one triangle, so a component of all lanes is the corners'
/// component, broadcast, under the lanes' weights: per-lane arrays straight away, the
/// component by component `(a·wa + b·wb) + c·wc` of [`Quad::field`], and only the
/// components a batch reads.
struct BatchVaryings<const N: usize> {
    /// The addresses of the triangle's corners (zeros before the first).
    triangle: [usize; 3],
    /// The corners' varyings as `f32` components.
    corners: [[f32; FUR_VARYING_FLOATS]; 3],
    /// `weights[k][i]`: lane `i`'s weight of corner `k`.
    weights: [[f32; N]; 3],
}

impl<const N: usize> Default for BatchVaryings<N> {
    /// No triangle, zeros.
    fn default() -> Self {
        BatchVaryings {
            triangle: [0; 3],
            corners: [[0.0; FUR_VARYING_FLOATS]; 3],
            weights: [[0.0; N]; 3],
        }
    }
}

impl<const N: usize> BatchVaryings<N> {
    /// Component `c` ([`FurVaryings`] as `f32`s) of every lane.
    #[inline(always)]
    #[allow(clippy::needless_range_loop)] // lanes as an indexed loop: the form LLVM packs
    fn component(&self, c: usize) -> [f32; N] {
        // A plain loop, not `array::map` or `array::from_fn`: at 16 lanes LLVM left those out
        // of line, compiled for the baseline (SSE2), a call per component read.
        let (a, b, d) = (self.corners[0][c], self.corners[1][c], self.corners[2][c]);
        let [wa, wb, wd] = &self.weights;
        let mut out = [0.0f32; N];
        for i in 0..N {
            out[i] = (a * wa[i] + b * wb[i]) + d * wd[i];
        }
        out
    }

    /// The 2-vector from component `c` on, of every lane.
    #[inline(always)]
    fn vec2(&self, c: usize) -> [[f32; N]; 2] {
        [self.component(c), self.component(c + 1)]
    }

    /// The 3-vector from component `c` on, of every lane.
    #[inline(always)]
    fn vec3(&self, c: usize) -> Vec3xN<N> {
        Vec3xN {
            x: self.component(c),
            y: self.component(c + 1),
            z: self.component(c + 2),
        }
    }
}

impl<'a, const N: usize> FurBatch<'a, N> {
    /// Whether lanes reading mip levels `lower` and `lower + 1` and shadow level `level` may
    /// join the lanes held (of the same draw: the same textures).
    #[inline(always)]
    fn reads(&self, lower: usize, level: &MipLevel) -> bool {
        self.pair_lower == Some(lower)
            && self
                .shadow_level
                .is_some_and(|held| std::ptr::eq(held, level))
    }

    /// Holds a quad for step 1 of the fur stage (the scalar twin's first, before any texture
    /// read) instead of joining it: quads are tested a batch's worth at a time
    /// ([`FurBatch::test_held`]), and then join as [`shade_fur_quad`] joins them, less their
    /// lanes burnt away on this layer or above the painted length, so that a burnt or bare region
    /// costs this test alone and the batches that run are full of lanes the image shows. The
    /// quads held are of one triangle: a quad of another has them tested and joined first.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)] // the quad, where its lanes go, and the layer's state
    fn hold(
        &mut self,
        quad: &Quad<'_, FurVaryings>,
        slots: QuadSlots,
        triangle: [usize; 3],
        textures: LayerMaps<'a>,
        maps: &SurfaceMaps,
        layer: &LayerParams,
        p: &ShadeParams,
        write: &mut impl FnMut(PixelSlot, Vec4),
    ) {
        // Whole quads of a batch's worth, at most eight of them.
        const { assert!(N >= 4 && N.is_multiple_of(4) && N / 4 <= MAX_HELD_QUADS) };
        if self.pending.count != 0 && !same_triangle(&self.pending.varyings.triangle, &triangle) {
            self.join_held(textures, maps, layer, p, write);
        }
        if self.pending.count == 0 && !same_triangle(&self.pending.varyings.triangle, &triangle) {
            self.pending.varyings.triangle = triangle;
            self.pending.varyings.corners = quad.corners().map(|c| *bytemuck::cast_ref(c));
        }
        let q = self.pending.count;
        let at = 4 * q..4 * q + 4;
        for (lanes, quad_lanes) in self.pending.varyings.weights.iter_mut().zip(quad.weights()) {
            lanes[at.clone()].copy_from_slice(quad_lanes);
        }
        self.pending.slots[q] = Some(slots);
        self.pending.count += 1;
        if 4 * self.pending.count == N {
            self.join_held(textures, maps, layer, p, write);
        }
    }

    /// Tests the quads held ([`FurBatch::hold`]) and joins what they keep, in their order.
    ///
    /// Out of line (compiled for the baseline; the test itself runs at the frame's level):
    /// inlined at the three places that call it, in every copy of the hot path, frames that
    /// burn took 2–5 % more CPU (docs/performance.md, "Burning (Intel Xeon with AVX-512)").
    #[inline(never)]
    fn join_held(
        &mut self,
        textures: LayerMaps<'a>,
        maps: &SurfaceMaps,
        layer: &LayerParams,
        p: &ShadeParams,
        write: &mut impl FnMut(PixelSlot, Vec4),
    ) {
        let count = self.pending.count;
        if count == 0 {
            return;
        }
        let tested = self.test_held(textures, maps, layer, p);
        self.pending.count = 0;
        // The quads join from copies of their corners and weights (the batch they join is
        // `self`), their triangle still known by the draw's corner addresses. Their levels of
        // detail read the uv of each quad's lanes 0–2, interpolated for all lanes at once.
        let corners = self.pending.varyings.corners;
        let triangle = self.pending.varyings.triangle;
        let [u, v] = self.pending.varyings.vec2(UV);
        let lanes = |q: usize| std::array::from_fn(|l| Vec2::new(u[4 * q + l], v[4 * q + l]));
        for q in 0..count.min(N / 4) {
            let Some(mut slots) = self.pending.slots[q].take() else {
                continue;
            };
            slots.keep_lanes(!(tested.dropped >> (4 * q)));
            if slots.lanes() == 0 {
                continue;
            }
            let at = 4 * q..4 * q + 4;
            let weights: [[f32; 4]; 3] = std::array::from_fn(|k| {
                let mut row = [0.0f32; 4];
                row.copy_from_slice(&self.pending.varyings.weights[k][at.clone()]);
                row
            });
            let mut char_factor = [1.0f32; 4];
            char_factor.copy_from_slice(&tested.char_factor[at]);
            let entry = QuadEntry {
                charred: (tested.charred >> (4 * q)) & 0b1111,
                char_factor,
            };
            let [origin, right, below, _]: [Vec2; 4] = lanes(q);
            let footprint = quad_footprint(origin, right, below, &textures);
            join_lanes(
                slots,
                &weights,
                footprint,
                &entry,
                (triangle, || corners),
                self,
                textures,
                maps,
                layer,
                p,
                write,
            );
        }
    }

    /// Step 1 of the quads held: which lanes it drops (burnt away, above the painted length)
    /// and which it chars, by what factor.
    ///
    /// Runs out of line, compiled for the frame's SIMD level ([`ShadeParams::simd`], through
    /// [`crate::simd::dispatch_level`]), so that frames without a burn or length map do not
    /// carry its code in the hot path, and on all `N` lanes at once: a quad at a time, the
    /// test's chain of dependent operations (normalisation, cosines, power, rule) ran four
    /// lanes wide once a quad, a quarter of a burning frame.
    #[inline(never)]
    fn test_held(
        &self,
        textures: LayerMaps<'_>,
        maps: &SurfaceMaps,
        layer: &LayerParams,
        p: &ShadeParams,
    ) -> HeldOutcome<N> {
        struct Entry<'q, 'a, const N: usize> {
            pending: &'q PendingQuads<N>,
            length_map: Option<&'a Texture>,
            maps: &'a SurfaceMaps,
            layer: &'a LayerParams,
            p: &'a ShadeParams,
        }
        impl<const N: usize> crate::simd::LevelKernel for Entry<'_, '_, N> {
            type Output = HeldOutcome<N>;
            #[inline(always)]
            fn run(self) -> HeldOutcome<N> {
                self.pending
                    .test(self.length_map, self.maps, self.layer, self.p)
            }
        }
        let length_map = maps.length.as_ref().filter(|_| textures.shell);
        crate::simd::dispatch_level(
            p.simd,
            Entry {
                pending: &self.pending,
                length_map,
                maps,
                layer,
                p,
            },
        )
    }

    /// The whole fur stage of the lanes held, each colour written to its lane's slot (a
    /// discarded lane's slot is dropped); the batch is empty after. Lanes past `len` hold what
    /// they held before (or zeros) and run too; their results are dropped.
    ///
    /// The stage itself runs out of line (`shade_batch_at_level`), once per SIMD level, and
    /// only the writes land at each call site: inlined, the stage was copied at every call site
    /// of every fixed-function copy of the rasterizer's quad loop (nine a level), and those copies
    /// were most of the library's build time.
    #[inline(always)]
    pub fn run(
        &mut self,
        textures: LayerMaps<'a>,
        maps: &SurfaceMaps,
        layer: &LayerParams,
        p: &ShadeParams,
        write: &mut impl FnMut(PixelSlot, Vec4),
    ) {
        if self.len == 0 {
            return;
        }
        // A batch holding at most half its lanes (a small triangle's, or a triangle's last
        // lanes in a tile) runs on a narrower stage, one quad wide where it holds one quad: a
        // lane's result never depends on the batch's width, and the stage's cost grows with
        // its width, not with the lanes held.
        let shaded = if N > SMALLEST_LANES && self.len <= SMALLEST_LANES {
            self.shade_narrow::<SMALLEST_LANES>(textures, maps, layer, p)
        } else if N > NARROW_LANES && self.len <= NARROW_LANES {
            self.shade_narrow::<NARROW_LANES>(textures, maps, layer, p)
        } else if N > HALF_WIDE_LANES && self.len <= HALF_WIDE_LANES {
            self.shade_narrow::<HALF_WIDE_LANES>(textures, maps, layer, p)
        } else {
            shade_batch_at_level(self, textures, maps, layer, p)
        };
        for (i, slot) in self.slots.iter_mut().enumerate() {
            if let Some(slot) = slot.take()
                && shaded.kept & (1 << i) != 0
            {
                write(slot, shaded.colours[i]);
            }
        }
    }

    /// [`FurBatch::run`]'s stage of the lanes held (at most `M` of them, `M` below `N`) by a
    /// batch `M` lanes wide: the same lanes, the same bits, the stage's work on `M` lanes.
    /// The batch holds no lane after; what it keeps of the spots' test carries over.
    fn shade_narrow<const M: usize>(
        &mut self,
        textures: LayerMaps<'a>,
        maps: &SurfaceMaps,
        layer: &LayerParams,
        p: &ShadeParams,
    ) -> BatchColours<N> {
        debug_assert!(M < N && self.len <= M);
        let first = |lanes: &[f32; N]| -> [f32; M] { std::array::from_fn(|i| lanes[i]) };
        let mut narrow = FurBatch::<'a, M> {
            len: self.len,
            pending: PendingQuads::default(),
            pair_lower: self.pair_lower,
            pair: self.pair,
            shadow_level: self.shadow_level,
            shadow_index: self.shadow_index,
            slots: [const { None }; M],
            varyings: BatchVaryings {
                triangle: self.varyings.triangle,
                corners: self.varyings.corners,
                weights: self.varyings.weights.each_ref().map(first),
            },
            footprint: first(&self.footprint),
            charred: self.charred,
            char_factor: first(&self.char_factor),
            spots: self.spots,
        };
        self.len = 0;
        self.charred = 0;
        let shaded = shade_batch_at_level(&mut narrow, textures, maps, layer, p);
        self.spots = narrow.spots;
        let mut colours = [Vec4::ZERO; N];
        colours[..M].copy_from_slice(&shaded.colours);
        BatchColours {
            kept: shaded.kept,
            colours,
        }
    }

    /// The fur stage of the lanes held ([`FurBatch::run`]'s work but the writes): the colour
    /// of every lane, with the lanes kept. The batch holds no lane after.
    #[allow(clippy::needless_range_loop)] // lanes as indexed loops: the form LLVM packs
    #[inline(always)]
    fn shade_lanes(
        &mut self,
        textures: LayerMaps<'a>,
        maps: &SurfaceMaps,
        layer: &LayerParams,
        p: &ShadeParams,
    ) -> BatchColours<N> {
        let len = self.len;
        self.len = 0;
        // Lanes still alive: bit i for lane i (`len` is at most 32, the masks' bits).
        const { assert!(N <= 32) };
        let alive = ((1u64 << len) - 1) as u32;
        let varyings = &self.varyings;
        let sampler = textures.sampler;
        // Step 2: the texel that lands here is read at uv − wind_uv.
        let ([uv_u, uv_v], wind_uv) = (varyings.vec2(UV), varyings.vec2(WIND_UV));
        let (mut u, mut v) = ([0.0f32; N], [0.0f32; N]);
        for i in 0..N {
            (u[i], v[i]) = (uv_u[i] - wind_uv[0][i], uv_v[i] - wind_uv[1][i]);
        }
        let mesh_uv = |i: usize, [u, v]: &[[f32; N]; 2]| Vec2::new(u[i], v[i]);
        // Each lane's level of detail, and its fraction between the pair's levels: the
        // lower level is the batch's, `⌊λ⌋` of every lane clamped to the chain
        // (`Texture::levels_of_footprint`), so `λ − lower` is `trilinear_indices`' fraction.
        let lower = self.pair_lower.unwrap_or(0);
        let top = textures.colour.level_count() - 1;
        let blends = lower < top;
        let (top, lower) = (top as f32, lower as f32);
        let (mut lod, mut frac) = ([0.0f32; N], [0.0f32; N]);
        for i in 0..N {
            lod[i] = level_of_detail_of_footprint(self.footprint[i]);
            // `clamp` without its NaN case: λ is never NaN.
            let clamped = lod[i].max(0.0).min(top);
            let f = clamped - lower;
            frac[i] = if f != 0.0 && blends { f } else { 0.0 };
        }
        // Step 1 ran before the lanes joined (`FurBatch::hold`): the lanes held are not burnt away nor
        // above the painted length; the charred ones are marked.
        let (charred, char_factor) = (self.charred, self.char_factor);
        self.charred = 0;
        // Step 3: the colour and tangent maps.
        let texels = match &self.pair {
            Some(pair) => pair.sample_lanes(&u, &v, &frac, p.simd),
            None => {
                let mut texels = [[0.0f32; N]; 8];
                for i in 0..len {
                    let uv = Vec2::new(u[i], v[i]);
                    let (colour, tangent) =
                        sampler.sample_level_pair(textures.colour, textures.tangent, uv, lod[i]);
                    let both = colour.to_array().into_iter().chain(tangent.to_array());
                    for (channel, value) in texels.iter_mut().zip(both) {
                        channel[i] = value;
                    }
                }
                texels
            }
        };
        // The alpha test (NaN alpha is discarded too).
        let mut coverage = texels[3];
        let mut density = [0.0f32; N];
        if let Some(density_map) = &maps.density {
            let at = varyings.vec2(MESH_UV);
            for i in 0..len {
                let d = maps.sample(density_map, mesh_uv(i, &at)).x;
                density[i] = d;
                coverage[i] = match textures.density {
                    Some(bands) => shading::density_alpha(
                        sampler.sample_level(bands, Vec2::new(u[i], v[i]), lod[i]),
                        d,
                    ),
                    None => texels[3][i] * d.clamp(0.0, 1.0),
                };
            }
        }
        let fade = varyings.component(FADE);
        let mut alpha = [0.0f32; N];
        for i in 0..N {
            alpha[i] = coverage[i] * fade[i];
        }
        if layer.lod_span != 1.0 {
            for a in &mut alpha {
                *a = shading::lod_alpha(*a, layer.lod_span);
            }
        }
        let mut passed = 0u32;
        for i in 0..N {
            passed |= lane_mask(alpha[i] >= ALPHA_DISCARD) & (1 << i);
        }
        let lit = alive & passed;
        // The colour of every lane (lanes not kept too: their values are dropped).
        let lanes = |colour: &dyn Fn(usize) -> Vec4| BatchColours {
            kept: lit,
            colours: std::array::from_fn(colour),
        };
        if lit == 0 {
            return BatchColours {
                kept: 0,
                colours: [Vec4::ZERO; N],
            };
        }
        match p.debug_view {
            DebugView::Tangents => {
                return lanes(&|i| Vec4::new(texels[4][i], texels[5][i], texels[6][i], alpha[i]));
            }
            DebugView::Alpha => return lanes(&|i| Vec4::new(1.0, 1.0, 1.0, alpha[i])),
            _ => {}
        }
        let mut strand = Vec3xN {
            x: texels[0],
            y: texels[1],
            z: texels[2],
        };
        if let Some(tint) = &maps.colour {
            let at = varyings.vec2(MESH_UV);
            for i in 0..len {
                let tinted = shading::tint_strand(
                    strand.lane(i),
                    maps.sample(tint, mesh_uv(i, &at)).truncate(),
                );
                (strand.x[i], strand.y[i], strand.z[i]) = tinted.into();
            }
        }
        // Step 6: the shell shadow, lookup k of every lane in one batch. Wind moves the fur
        // above this layer further, so its displacement adds to the lookup (3.3.1).
        let shadow_uv = varyings.vec2(SHADOW);
        let mut offset_u = [0.0f32; N];
        let mut offset_v = [0.0f32; N];
        for i in 0..N {
            (offset_u[i], offset_v[i]) = (
                shadow_uv[0][i] + wind_uv[0][i],
                shadow_uv[1][i] + wind_uv[1][i],
            );
        }
        let mut shadow = [0.0f32; N];
        match (&maps.density, textures.density) {
            (Some(_), Some(bands)) => {
                // The density bands' lookups, one lane at a time.
                for i in 0..len {
                    if lit & (1 << i) == 0 {
                        continue;
                    }
                    let level = bands.nearest_level(lod[i]);
                    let d = density[i];
                    shadow[i] = shading::shell_shadow(
                        |at| shading::density_alpha(sampler.sample_nearest_in(level, at), d),
                        Vec2::new(u[i], v[i]),
                        Vec2::new(offset_u[i], offset_v[i]),
                        layer.lookups,
                        p.shadow_texel,
                    );
                }
            }
            _ => {
                if layer.lookups > 0
                    && let Some(level) = self.shadow_level
                {
                    let lookup = match textures.converted {
                        Some(converted) => sampler
                            .nearest_lookup(level)
                            .with_converted(converted, self.shadow_index),
                        None => sampler.nearest_lookup(level),
                    };
                    // Plain loops (`array::from_fn` stayed out of line at 16 lanes).
                    let (mut uvs, mut offsets) = ([Vec2::ZERO; N], [Vec2::ZERO; N]);
                    for i in 0..N {
                        uvs[i] = Vec2::new(u[i], v[i]);
                        offsets[i] = Vec2::new(offset_u[i], offset_v[i]);
                    }
                    // `shading::shell_shadow_lanes`, step by step.
                    let mut sums =
                        shading::ShadowLanes::new(uvs, offsets, layer.lookups, p.shadow_texel);
                    // Up to four lookups read before any is added (the same sum, in the same
                    // order): their reads overlap instead of each waiting on the last.
                    let mut k = 1;
                    while k <= layer.lookups {
                        let chunk = (layer.lookups - k + 1).min(4) as usize;
                        let mut alphas = [[0.0f32; N]; 4];
                        for (j, alpha) in alphas.iter_mut().enumerate().take(chunk) {
                            let (u, v) = sums.point(k + j as u32);
                            *alpha = lookup.alpha_lanes(u, v, p.simd);
                        }
                        for alpha in &alphas[..chunk] {
                            sums.add(*alpha);
                        }
                        k += chunk as u32;
                    }
                    shadow = sums.shadow;
                }
            }
        }
        if p.debug_view == DebugView::Shadow {
            return lanes(&|i| {
                let g = (1.0 - p.weights.shadow * shadow[i]).clamp(0.0, 1.0);
                Vec4::new(g, g, g, alpha[i])
            });
        }
        // Step 4: the spots, then the burn's charring.
        if !p.spots.is_empty() {
            // Spots that surely miss the batch's triangle give every lane the weight 0 without
            // their arithmetic (found once a triangle), and where all do, the lanes' points and
            // normals are not interpolated. The test costs about what the spots' arithmetic
            // on a batch of `SPOTS_TEST_LANES` does, so a triangle's first batch with no more
            // lanes (a small triangle's, whose lanes rarely fill a second, run by a narrow
            // stage) computes every spot instead, their weights 0 where the test would have
            // skipped them (the same bits); the test then runs at the triangle's next batch,
            // if any.
            let new_triangle = self.spots.triangle != Some(varyings.triangle);
            if new_triangle {
                self.spots = SpotsMissed {
                    triangle: Some(varyings.triangle),
                    ..SpotsMissed::default()
                };
            }
            if !self.spots.tested && (len > SPOTS_TEST_LANES || !new_triangle) {
                self.spots.tested = true;
                let corner = |c: usize| {
                    varyings
                        .corners
                        .map(|v| Vec3::new(v[c], v[c + 1], v[c + 2]))
                };
                let (object, normals) = (corner(OBJECT), corner(NORMAL));
                self.spots.missed = p.spots.iter().enumerate().fold(0, |missed, (s, spot)| {
                    let misses = s < 64 && spot.surely_misses(object, normals);
                    missed | (u64::from(misses) << (s % 64))
                });
            }
            let missed = self.spots.missed;
            let some_hit = (0..p.spots.len()).any(|s| s >= 64 || missed & (1 << s) == 0);
            let (object, unit_normals) = if some_hit {
                let object = varyings.vec3(OBJECT);
                (object, varyings.vec3(NORMAL).normalize_or_zero())
            } else {
                (Vec3xN::splat(Vec3::ZERO), Vec3xN::splat(Vec3::ZERO))
            };
            for (s, spot) in p.spots.iter().enumerate() {
                let weights = if s < 64 && missed & (1 << s) != 0 {
                    [0.0; N]
                } else {
                    spot.weights_lanes(&object, &unit_normals)
                };
                strand = shading::apply_spot_lanes(&strand, spot.colour(), weights);
            }
        }
        if charred != 0 {
            for i in 0..N {
                let m = lane_mask(charred & (1 << i) != 0);
                let f = char_factor[i];
                strand.x[i] = select_bits(m, strand.x[i] * f, strand.x[i]);
                strand.y[i] = select_bits(m, strand.y[i] * f, strand.y[i]);
                strand.z[i] = select_bits(m, strand.z[i] * f, strand.z[i]);
            }
        }
        // Steps 5 and 7.
        let encoded_tangent = Vec3xN {
            x: texels[4],
            y: texels[5],
            z: texels[6],
        };
        let wind = varyings.vec3(WIND);
        let lean = varyings.vec3(LEAN);
        // The interpolated light and eye go to the lighting as they are: it normalises them
        // (docs/conventions.md, "Lighting inputs").
        let light = varyings.vec3(LIGHT);
        let eye = varyings.vec3(EYE);
        let lighting = shading::strand_lighting_lanes(
            &lit_tangents_lanes(&encoded_tangent, &wind, &lean, layer, p),
            &Vec3xN::splat(Vec3::Z),
            &light,
            &eye,
            p.exponents,
            p.tangents,
            p.tangent_shift,
        );
        let colours = shading::final_colour_lanes(
            &strand,
            p.light_colour,
            p.ambient,
            lighting.diffuse,
            lighting.specular,
            shading::uncoloured_specular_lanes(lighting.specular_to_dampen, p.lighting),
            shadow,
            &p.weights,
            p.ambient_term,
        );
        let mut kept = BatchColours {
            kept: lit,
            colours: [Vec4::ZERO; N],
        };
        for i in 0..N {
            kept.colours[i] = colours.lane(i).extend(alpha[i]);
        }
        kept
    }
}

/// The colours a [`FurBatch`]'s stage gives its lanes: bit `i` of `kept` for lane `i` kept
/// (not discarded), its colour `colours[i]`.
struct BatchColours<const N: usize> {
    kept: u32,
    colours: [Vec4; N],
}

/// [`FurBatch::shade_lanes`] out of line, compiled for the frame's SIMD level
/// ([`ShadeParams::simd`], through [`crate::simd::dispatch_level`]): one copy a level and batch
/// width, called once a batch. Every level gives the same bits.
#[inline(never)]
fn shade_batch_at_level<'a, const N: usize>(
    batch: &mut FurBatch<'a, N>,
    textures: LayerMaps<'a>,
    maps: &SurfaceMaps,
    layer: &LayerParams,
    p: &ShadeParams,
) -> BatchColours<N> {
    struct Stage<'q, 'a, const N: usize> {
        batch: &'q mut FurBatch<'a, N>,
        textures: LayerMaps<'a>,
        maps: &'q SurfaceMaps,
        layer: &'q LayerParams,
        p: &'q ShadeParams,
    }
    impl<const N: usize> crate::simd::LevelKernel for Stage<'_, '_, N> {
        type Output = BatchColours<N>;
        #[inline(always)]
        fn run(self) -> BatchColours<N> {
            self.batch
                .shade_lanes(self.textures, self.maps, self.layer, self.p)
        }
    }
    crate::simd::dispatch_level(
        p.simd,
        Stage {
            batch,
            textures,
            maps,
            layer,
            p,
        },
    )
}

/// Which implementation of the fur fragment stage a frame runs. Both give the same bits; the
/// golden tests render every scene with both.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FragmentStage {
    /// [`shade_fur_quad`]: a quad at a time (what the renderer runs).
    #[default]
    Quad,
    /// [`shade_fur`] on each lane alone: the scalar twin, the plain statement of the shader.
    ScalarTwin,
}

/// The fur fragment stage of one layer as a [`QuadShader`].
#[derive(Clone, Copy)]
pub struct FurShader<'a> {
    /// The layer's textures and sampler.
    pub textures: LayerMaps<'a>,
    /// The surface maps.
    pub maps: &'a SurfaceMaps,
    /// The layer.
    pub layer: LayerParams,
    /// The frame's shading parameters.
    pub params: &'a ShadeParams,
    /// Which implementation runs.
    pub stage: FragmentStage,
}

impl<'a> QuadShader<FurVaryings> for FurShader<'a> {
    type Deferred<const N: usize> = FurBatch<'a, N>;

    #[inline(always)]
    fn shade_quad<const N: usize>(
        &self,
        batch: &mut FurBatch<'a, N>,
        quad: &Quad<'_, FurVaryings>,
        mut slots: QuadSlots,
        mut write: impl FnMut(PixelSlot, Vec4),
    ) {
        let (textures, maps, layer, params) = (self.textures, self.maps, &self.layer, self.params);
        match self.stage {
            FragmentStage::Quad => {
                shade_fur_quad(quad, slots, batch, textures, maps, layer, params, write)
            }
            FragmentStage::ScalarTwin => {
                for lane in 0..4 {
                    if slots.lanes() & (1 << lane) != 0
                        && let Some(colour) =
                            shade_fur(&quad.fragment(lane), textures, maps, layer, params)
                        && let Some(slot) = slots.take(lane)
                    {
                        write(slot, colour);
                    }
                }
            }
        }
    }

    #[inline(always)]
    fn finish<const N: usize>(
        &self,
        batch: &mut FurBatch<'a, N>,
        mut write: impl FnMut(PixelSlot, Vec4),
    ) {
        batch.join_held(
            self.textures,
            self.maps,
            &self.layer,
            self.params,
            &mut write,
        );
        batch.run(
            self.textures,
            self.maps,
            &self.layer,
            self.params,
            &mut write,
        );
    }
}

/// How far [`surface`] took a fragment.
enum Surface {
    /// Discarded (burnt, above the painted length, transparent).
    Discarded,
    /// A debug view's colour, final.
    Finished(Vec4),
    /// Ready for the spots, the shell shadow (its `shadow` still 0) and strand lighting.
    Lit(LitSurface, ShadowLookups),
}

/// The shell shadow of one fragment (step 6), as [`surface`] leaves it.
#[derive(Clone, Copy)]
enum ShadowLookups {
    /// Already summed (the density bands' lookups, one fragment at a time).
    Taken(f32),
    /// Lookups of the layer's shadow level still to take, from `uv` along `offset`
    /// ([`shading::shell_shadow`]); the quad stage takes its lanes' together.
    Pending { uv: Vec2, offset: Vec2 },
}

/// What eq. 3.7 needs of one fragment besides its varyings (the wind, lean, light and eye
/// vectors are read from those): the tangent still encoded, the colour, alpha and shadow.
#[derive(Clone, Copy)]
struct LitSurface {
    alpha: f32,
    /// The strand colour: after [`surface`], the texel's (tinted); then spots and the burn's
    /// charring ([`spotted_strand`], [`Spot::weights_lanes`]).
    strand: Vec3,
    burn: BurnOutcome,
    shadow: f32,
    encoded_tangent: Vec3,
}

/// Step 5: the strand tangent decoded from its texel, bent by a fraction of the wind that
/// grows up the strand (3.3.1) and then by the lean.
#[inline(always)]
fn lit_tangent(
    encoded: Vec3,
    wind: Vec3,
    lean: Vec3,
    layer: &LayerParams,
    p: &ShadeParams,
) -> Vec3 {
    let tangent = (encoded * 2.0 - Vec3::ONE).normalize_or(Vec3::Z);
    let tangent = if p.wind_tangent_fraction > 0.0 {
        shading::bend_tangent(
            tangent,
            wind,
            layer.height_fraction * p.wind_tangent_fraction,
        )
    } else {
        tangent
    };
    if p.lean {
        shading::bend_tangent(tangent, lean, layer.height_fraction)
    } else {
        tangent
    }
}

/// [`lit_tangent`] on `N` lanes, lane by lane the same bits.
#[inline(always)]
fn lit_tangents_lanes<const N: usize>(
    encoded: &Vec3xN<N>,
    wind: &Vec3xN<N>,
    lean: &Vec3xN<N>,
    layer: &LayerParams,
    p: &ShadeParams,
) -> Vec3xN<N> {
    let tangent = encoded
        .scale_minus_one(2.0)
        .normalize_or(&Vec3xN::splat(Vec3::Z));
    let tangent = if p.wind_tangent_fraction > 0.0 {
        shading::bend_tangent_lanes(
            &tangent,
            wind,
            layer.height_fraction * p.wind_tangent_fraction,
        )
    } else {
        tangent
    };
    if p.lean {
        shading::bend_tangent_lanes(&tangent, lean, layer.height_fraction)
    } else {
        tangent
    }
}

impl LitSurface {
    /// [`lit_tangent`] of this fragment with varyings `v`.
    #[inline(always)]
    fn tangent(&self, v: &LitVaryings, layer: &LayerParams, p: &ShadeParams) -> Vec3 {
        lit_tangent(self.encoded_tangent, v.wind, v.lean, layer, p)
    }

    /// The uncoloured last term (the dampened specular of 3.2.3, or eq. 3.5's
    /// `(ψ_specularity1)^n`) and eq. 3.7, with this fragment's alpha.
    #[inline(always)]
    fn colour(&self, lighting: shading::StrandLighting, p: &ShadeParams) -> Vec4 {
        let dampened = shading::uncoloured_specular(lighting.specular_to_dampen, p.lighting);
        shading::final_colour(
            self.strand,
            p.light_colour,
            p.ambient,
            lighting.diffuse,
            lighting.specular,
            dampened,
            self.shadow,
            &p.weights,
            p.ambient_term,
        )
        .extend(self.alpha)
    }
}

/// What a layer's texture reads at one level of detail share, chosen once for the lanes of a
/// quad: the mip levels of the colour and tangent maps.
struct LevelReads<'a> {
    lod: f32,
    /// `None` when the colour and tangent maps differ in shape (then read one by one).
    surface: Option<TrilinearPair<'a>>,
}

impl<'a> LevelReads<'a> {
    /// The reads at `lod`.
    #[inline(always)]
    fn new(textures: LayerMaps<'a>, lod: f32) -> Self {
        let sampler = textures.sampler;
        LevelReads {
            lod,
            surface: sampler.trilinear_pair(textures.colour, textures.tangent, lod),
        }
    }
}

/// Steps 1–4 of the module's list for one fragment at the level of detail of `reads` but the
/// spots and charring ([`spotted_strand`]), and where its shell shadow (step 6) looks.
/// `unit_normal` is `v.normal.normalize_or_zero()`, which the burn lobes read (the quad stage
/// passes zero when the frame has no burn).
#[inline(always)]
#[allow(clippy::too_many_arguments)] // the fragment, what its quad shares, and the layer's state
fn surface(
    v: &SurfaceVaryings,
    unit_normal: Vec3,
    reads: &LevelReads<'_>,
    textures: LayerMaps<'_>,
    maps: &SurfaceMaps,
    layer: &LayerParams,
    p: &ShadeParams,
) -> Surface {
    let burn = p.burn_outcome_at_unit_normal(unit_normal, v.object, layer);
    if burn == BurnOutcome::Burnt {
        return Surface::Discarded;
    }
    if textures.shell
        && let Some(length_map) = &maps.length
        && !shading::layer_within_length(
            layer.height_fraction,
            v.length,
            maps.sample(length_map, v.mesh_uv).x,
        )
    {
        return Surface::Discarded;
    }
    let LayerMaps {
        colour: colour_map,
        tangent: tangent_map,
        sampler,
        ..
    } = textures;
    let lod = reads.lod;
    let uv = v.uv - v.wind_uv;
    let (texel, encoded) = match &reads.surface {
        Some(pair) => pair.sample(uv),
        None => sampler.sample_level_pair(colour_map, tangent_map, uv, lod),
    };
    let density = maps.density.as_ref().map(|m| maps.sample(m, v.mesh_uv).x);
    let coverage = match (density, textures.density) {
        (Some(d), Some(bands)) => shading::density_alpha(sampler.sample_level(bands, uv, lod), d),
        (Some(d), None) => texel.w * d.clamp(0.0, 1.0),
        (None, _) => texel.w,
    };
    let alpha = shading::lod_alpha(coverage * v.fade, layer.lod_span);
    // NaN alpha is discarded too.
    if alpha.is_nan() || alpha < ALPHA_DISCARD {
        return Surface::Discarded;
    }
    if p.debug_view == DebugView::Tangents {
        return Surface::Finished(encoded.truncate().extend(alpha));
    }
    if p.debug_view == DebugView::Alpha {
        return Surface::Finished(Vec4::new(1.0, 1.0, 1.0, alpha));
    }
    let mut strand = texel.truncate();
    if let Some(tint) = &maps.colour {
        strand = shading::tint_strand(strand, maps.sample(tint, v.mesh_uv).truncate());
    }
    // The thesis checks "if the according pixel is transparent": one texel per lookup. Wind
    // moves the fur above this layer further, so its displacement adds to the lookup (3.3.1).
    // The level is chosen once for all lookups of this fragment.
    let offset = v.shadow + v.wind_uv;
    let shadow = match (density, textures.density) {
        (Some(d), Some(bands)) => {
            let level = bands.nearest_level(lod);
            ShadowLookups::Taken(shading::shell_shadow(
                |at| shading::density_alpha(sampler.sample_nearest_in(level, at), d),
                uv,
                offset,
                layer.lookups,
                p.shadow_texel,
            ))
        }
        _ => ShadowLookups::Pending { uv, offset },
    };
    Surface::Lit(
        LitSurface {
            alpha,
            strand,
            burn,
            shadow: 0.0,
            encoded_tangent: encoded.truncate(),
        },
        shadow,
    )
}

/// Step 4's spots, then the charring by `1 − I`, on one fragment's strand colour: the scalar
/// statement of what a [`FurBatch`] does with [`Spot::weights_lanes`] on eight lanes.
#[inline(always)]
fn spotted_strand(
    strand: Vec3,
    object: Vec3,
    unit_normal: Vec3,
    burn: BurnOutcome,
    p: &ShadeParams,
) -> Vec3 {
    let mut strand = strand;
    for spot in &p.spots {
        let (colour, weight) = spot.weight_at_unit_normal(object, unit_normal);
        strand = shading::apply_spot(strand, colour, weight);
    }
    burn.strand_colour(strand)
}

/// Step 6's result for one fragment: the shadow debug view's grey (final), or the fragment
/// ready for strand lighting with its shadow.
#[inline(always)]
fn shadowed(mut lit: LitSurface, shadow: f32, p: &ShadeParams) -> Result<LitSurface, Vec4> {
    if p.debug_view == DebugView::Shadow {
        let g = (1.0 - p.weights.shadow * shadow).clamp(0.0, 1.0);
        return Err(Vec4::new(g, g, g, lit.alpha));
    }
    lit.shadow = shadow;
    Ok(lit)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shading::test_support::Lcg;

    /// A fragment's varyings as floats, each uniform in [−50, 50).
    fn random_varying_floats(rng: &mut Lcg) -> [f32; FUR_VARYING_FLOATS] {
        let mut floats = [0.0f32; FUR_VARYING_FLOATS];
        floats.iter_mut().for_each(|f| *f = rng.range(-50.0, 50.0));
        floats
    }

    #[test]
    fn varyings_interpolate_field_by_field() {
        let mut rng = Lcg::new(17);
        let random = |rng: &mut Lcg| bytemuck::cast::<_, FurVaryings>(random_varying_floats(rng));
        for _ in 0..500 {
            let (a, b, c) = (random(&mut rng), random(&mut rng), random(&mut rng));
            let w = [
                rng.range(-1.0, 2.0),
                rng.range(-1.0, 2.0),
                rng.range(-1.0, 2.0),
            ];
            let got = FurVaryings::weighted_sum(&a, w[0], &b, w[1], &c, w[2]);
            let v2 = |f: fn(&FurVaryings) -> Vec2| {
                Vec2::weighted_sum(&f(&a), w[0], &f(&b), w[1], &f(&c), w[2])
            };
            let v3 = |f: fn(&FurVaryings) -> Vec3| {
                Vec3::weighted_sum(&f(&a), w[0], &f(&b), w[1], &f(&c), w[2])
            };
            let s = |f: fn(&FurVaryings) -> f32| (f(&a) * w[0] + f(&b) * w[1]) + f(&c) * w[2];
            let expected = FurVaryings {
                surface: SurfaceVaryings {
                    uv: v2(|v| v.surface.uv),
                    wind_uv: v2(|v| v.surface.wind_uv),
                    shadow: v2(|v| v.surface.shadow),
                    mesh_uv: v2(|v| v.surface.mesh_uv),
                    length: s(|v| v.surface.length),
                    fade: s(|v| v.surface.fade),
                    normal: v3(|v| v.surface.normal),
                    object: v3(|v| v.surface.object),
                },
                lit: LitVaryings {
                    light: v3(|v| v.lit.light),
                    eye: v3(|v| v.lit.eye),
                    wind: v3(|v| v.lit.wind),
                    lean: v3(|v| v.lit.lean),
                },
            };
            let bits = |v: &FurVaryings| bytemuck::cast::<_, [u32; FUR_VARYING_FLOATS]>(*v);
            assert_eq!(bits(&got), bits(&expected));
            // Each part alone (what `Quad::field` interpolates) gives the same bits.
            let parts = FurVaryings {
                surface: SurfaceVaryings::weighted_sum(
                    &a.surface, w[0], &b.surface, w[1], &c.surface, w[2],
                ),
                lit: LitVaryings::weighted_sum(&a.lit, w[0], &b.lit, w[1], &c.lit, w[2]),
            };
            assert_eq!(bits(&parts), bits(&expected));
        }
    }

    #[test]
    fn a_batch_interpolates_each_lane_as_the_whole_lane() {
        batch_lanes_are_whole_lanes::<BATCH_LANES>();
        batch_lanes_are_whole_lanes::<{ crate::simd::WIDE_LANES }>();
        batch_lanes_are_whole_lanes::<{ crate::simd::AVX2_LANES }>();
    }

    fn batch_lanes_are_whole_lanes<const N: usize>() {
        let mut rng = Lcg::new(29);
        let random = random_varying_floats;
        for _ in 0..200 {
            let corners = [random(&mut rng), random(&mut rng), random(&mut rng)];
            let weights: [[f32; N]; 3] =
                std::array::from_fn(|_| std::array::from_fn(|_| rng.range(-1.0, 2.0)));
            let batch = BatchVaryings {
                triangle: [1, 2, 3],
                corners,
                weights,
            };
            let corner = corners.map(bytemuck::cast::<_, FurVaryings>);
            for i in 0..N {
                let whole = FurVaryings::weighted_sum(
                    &corner[0],
                    weights[0][i],
                    &corner[1],
                    weights[1][i],
                    &corner[2],
                    weights[2][i],
                );
                let floats = bytemuck::cast::<_, [f32; FUR_VARYING_FLOATS]>(whole);
                for (c, value) in floats.iter().enumerate() {
                    assert_eq!(batch.component(c)[i].to_bits(), value.to_bits());
                }
                // The named components are the fields they name.
                let v2 = |c: usize| {
                    let [x, y] = batch.vec2(c);
                    Vec2::new(x[i], y[i])
                };
                let s = &whole.surface;
                assert_eq!(v2(UV), s.uv);
                assert_eq!(v2(WIND_UV), s.wind_uv);
                assert_eq!(v2(SHADOW), s.shadow);
                assert_eq!(v2(MESH_UV), s.mesh_uv);
                assert_eq!(batch.component(LENGTH)[i], s.length);
                assert_eq!(batch.component(FADE)[i], s.fade);
                assert_eq!(batch.vec3(NORMAL).lane(i), s.normal);
                assert_eq!(batch.vec3(OBJECT).lane(i), s.object);
                let l = &whole.lit;
                assert_eq!(batch.vec3(LIGHT).lane(i), l.light);
                assert_eq!(batch.vec3(EYE).lane(i), l.eye);
                assert_eq!(batch.vec3(WIND).lane(i), l.wind);
                assert_eq!(batch.vec3(LEAN).lane(i), l.lean);
            }
        }
    }

    /// Normals of every kind: random, tiny, huge, zero, NaN.
    fn normals(rng: &mut Lcg) -> Vec<Vec3> {
        let mut v: Vec<Vec3> = (0..2000)
            .map(|_| rng.cube() * rng.range(0.1, 3.0))
            .collect();
        v.extend([
            Vec3::ZERO,
            Vec3::splat(1e-30),
            Vec3::splat(3e38),
            Vec3::splat(f32::NAN),
            Vec3::Y,
        ]);
        v
    }

    /// A burn of `directions` random matches by direction and `points` at points, with a random
    /// exponent, on 30 shells.
    fn random_burn(rng: &mut Lcg, directions: usize, points: usize) -> BurnState {
        let directions: Vec<Vec3> = (0..directions)
            .map(|_| rng.cube().normalize_or_zero())
            .collect();
        let points: Vec<PointMatch> = (0..points)
            .map(|_| PointMatch {
                position: rng.cube() * 3.0,
                reach: rng.range(0.5, 6.0),
            })
            .collect();
        let exponent = rng.range(0.5, 400.0);
        BurnState::new(&directions, points, exponent, 29)
    }

    #[test]
    fn burn_intensity_lanes_are_the_scalar_intensity_bit_for_bit() {
        let mut rng = Lcg::new(57);
        for round in 0..200 {
            let burn = random_burn(&mut rng, round % 7, round % 3);
            let mut normals = Vec3xN::<16>::default();
            let mut objects = Vec3xN::<16>::default();
            for i in 0..16 {
                // A few exact zeros and opposite normals among the random ones.
                let n = match i {
                    0 => Vec3::ZERO,
                    1 => -burn.cosine_directions.first().copied().unwrap_or(Vec3::X),
                    _ => rng.cube().normalize_or_zero(),
                };
                let o = rng.cube() * 3.0;
                (normals.x[i], normals.y[i], normals.z[i]) = n.into();
                (objects.x[i], objects.y[i], objects.z[i]) = o.into();
            }
            let (lanes, _) =
                burn.intensity_unless_burnt_lanes(&normals, &objects, u32::MAX, f32::INFINITY);
            for (i, lane) in lanes.iter().enumerate() {
                let scalar = burn.intensity_at_unit_normal(normals.lane(i), objects.lane(i));
                assert_eq!(lane.to_bits(), scalar.to_bits(), "round {round} lane {i}");
            }
        }
    }

    #[test]
    fn burn_outcome_lanes_are_the_rule_of_the_scalar_intensity_on_every_shell() {
        let mut rng = Lcg::new(59);
        let max_shell = 29;
        for round in 0..120 {
            let burn = random_burn(&mut rng, 1 + round % 6, round % 3);
            for layer in 0..=max_shell {
                // Normals whose cosine towards the first match lies a few ulps around the
                // layer's burnt bound, and random ones.
                let m = burn.cosine_directions[0];
                let side = m.any_orthonormal_vector();
                let bound = burn.burnt_from_cosine(layer, max_shell);
                let mut normals = Vec3xN::<16>::default();
                let mut objects = Vec3xN::<16>::default();
                for i in 0..16 {
                    let n = if bound <= 1.0 && i < 12 {
                        let mut c = bound;
                        for _ in 0..rng.range(0.0, 6.0) as usize {
                            c = if i % 3 == 0 {
                                c.next_down()
                            } else {
                                c.next_up()
                            };
                        }
                        let c = c.min(1.0);
                        (m * c + side * (1.0 - c * c).max(0.0).sqrt()).normalize_or_zero()
                    } else {
                        rng.cube().normalize_or_zero()
                    };
                    let o = rng.cube() * 3.0;
                    (normals.x[i], normals.y[i], normals.z[i]) = n.into();
                    (objects.x[i], objects.y[i], objects.z[i]) = o.into();
                }
                let lanes = burn.lanes_outcome(&normals, &objects, u32::MAX, layer, max_shell);
                assert_eq!(lanes.burnt & lanes.charred, 0);
                for i in 0..16 {
                    let intensity = burn.intensity_at_unit_normal(normals.lane(i), objects.lane(i));
                    let scalar = shading::burn_rule(intensity, layer, max_shell);
                    assert_eq!(
                        lanes.outcome(i),
                        scalar,
                        "round {round} layer {layer} lane {i}"
                    );
                }
            }
        }
        // Another number of shells than the state was made for: nothing is taken as sure.
        let burn = BurnState::new(&[Vec3::X], vec![], 3.0, max_shell);
        assert!(burn.burnt_from_cosine(20, max_shell) < 1.0);
        assert_eq!(burn.burnt_from_cosine(20, 30), f32::INFINITY);
        assert_eq!(burn.burnt_from_cosine(0, max_shell), f32::INFINITY);
    }

    #[test]
    fn a_match_at_a_point_burns_one_region_of_a_torus_where_a_direction_burns_two() {
        // A torus of radii 6 and 2.4 in the xz plane: the outer equator at +x and the inner wall
        // at −x both face +x.
        let (outer, inner) = (Vec3::new(8.4, 0.0, 0.0), Vec3::new(-3.6, 0.0, 0.0));
        let burn = |directions: Vec<Vec3>, points: Vec<PointMatch>| {
            BurnState::new(&directions, points, 6.0, 29)
        };
        let by_direction = burn(vec![Vec3::X], vec![]);
        assert_eq!(by_direction.intensity(Vec3::X, outer), 1.0);
        assert_eq!(by_direction.intensity(Vec3::X, inner), 1.0);
        let at_point = burn(
            vec![],
            vec![PointMatch {
                position: outer + Vec3::X * 2.0,
                reach: 6.0,
            }],
        );
        let under = at_point.intensity(Vec3::X, outer);
        assert!(
            (under - (1.0f32 - 4.0 / 36.0).powi(2)).abs() < 1e-6,
            "{under}"
        );
        assert_eq!(at_point.intensity(Vec3::X, inner), 0.0);
        // Beside the match on the same surface the burn is weaker, and it spreads as the
        // exponent falls.
        let normal = Vec3::new(1.0, 0.0, 0.3).normalize();
        let beside = outer + Vec3::new(-0.1, 0.0, 1.0);
        assert!(at_point.intensity(normal, beside) < under);
        let wider = BurnState::new(&[], at_point.points.clone(), 2.0, 29);
        assert!(wider.intensity(normal, beside) > at_point.intensity(normal, beside));
    }

    #[test]
    fn spots_and_burn_with_the_unit_normal_equal_the_plain_formulas() {
        let mut rng = Lcg::new(23);
        let direction = Vec3::new(0.3, 0.8, -0.5).normalize_or_zero();
        let spot = Spot::Light {
            direction,
            exponent: 20.0,
            inner_threshold: 0.6,
            outer_threshold: 0.3,
            outside_below: shading::light_spot_cosine_below(0.3, 20.0),
            cosine_direction: direction.normalize_or_zero(),
            colour: Vec3::ONE,
        };
        let matches: Vec<Vec3> = (0..6).map(|_| rng.cube().normalize_or_zero()).collect();
        let points: Vec<PointMatch> = (0..3)
            .map(|_| PointMatch {
                position: rng.cube() * 2.0,
                reach: rng.range(0.5, 3.0),
            })
            .collect();
        let burn = BurnState::new(&matches, points.clone(), 7.5, 29);
        for normal in normals(&mut rng) {
            let point = rng.cube() * 2.0;
            // The plain statement: light_spot_cosine normalises both vectors itself.
            let cosine = shading::light_spot_cosine(normal, direction);
            let lobe = shading::light_spot_lobe(cosine, 20.0);
            let weight = shading::spot_gradient(lobe, 0.6, 0.3);
            let got = spot.weight_at_unit_normal(Vec3::ZERO, normal.normalize_or_zero());
            assert_eq!(got.1.to_bits(), weight.to_bits(), "{normal}");
            assert_eq!(
                spot.weight_at(Vec3::ZERO, normal).1.to_bits(),
                weight.to_bits()
            );
            // The matches by direction: the lobe of the largest cosine; at points, each its
            // point light intensity.
            let largest = matches
                .iter()
                .map(|&m| shading::light_spot_cosine(normal, m))
                .fold(f32::NEG_INFINITY, f32::max);
            let intensity = points
                .iter()
                .map(|m| {
                    shading::point_light_intensity(
                        normal.normalize_or_zero(),
                        point,
                        m.position,
                        m.reach,
                        7.5,
                    )
                })
                .fold(shading::light_spot_lobe(largest, 7.5), f32::max);
            let got = burn.intensity_at_unit_normal(normal.normalize_or_zero(), point);
            // Lobes surely under the threshold count as 0, so they agree where it matters.
            let burnt = |i: f32| i >= shading::BURN_THRESHOLD;
            assert_eq!(burnt(got), burnt(intensity), "{normal}");
            if burnt(intensity) {
                assert_eq!(got.to_bits(), intensity.to_bits(), "{normal}");
            }
            assert_eq!(burn.intensity(normal, point).to_bits(), got.to_bits());
        }
    }
}
