//! The fur fragment closure: the thesis's fragment shader (3.2) as Rust, composed from the pure
//! terms in [`crate::shading`].
//!
//! Texture reads: the colour and tangent maps are read trilinearly at the level of detail of
//! the fur uv's coarse derivatives; each shadow lookup reads the alpha of one texel, the nearest
//! one on the mip level nearest that level of detail.

use crate::raster::texture::level_of_detail;
use crate::raster::{Fragment, Sampler, Texture, Varyings};
use crate::scene::{DebugView, Scene};
use crate::shading::{self, ShadingWeights, SpecularTangents};
use glam::{Vec2, Vec3, Vec4};

/// Alpha below which a fur texel is discarded before any shading (half of the smallest
/// non-zero 8-bit alpha).
pub const ALPHA_DISCARD: f32 = 0.5 / 255.0;

/// What the vertex stage hands the fur fragment stage.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FurVaryings {
    /// Fur texture coordinates (mesh uv × repeat).
    pub uv: Vec2,
    /// Direction towards the light, tangent space.
    pub light: Vec3,
    /// Vector towards the eye, tangent space (not normalised).
    pub eye: Vec3,
    /// The shadow lookup: uv offset towards the light over the fur above this layer.
    pub shadow: Vec2,
    /// Opacity factor: 1 on shells; on fins it fades to 0 towards the ends of the angle window.
    pub fade: f32,
}

impl Varyings for FurVaryings {
    #[inline]
    fn weighted_sum(a: &Self, wa: f32, b: &Self, wb: f32, c: &Self, wc: f32) -> Self {
        FurVaryings {
            uv: Vec2::weighted_sum(&a.uv, wa, &b.uv, wb, &c.uv, wc),
            light: Vec3::weighted_sum(&a.light, wa, &b.light, wb, &c.light, wc),
            eye: Vec3::weighted_sum(&a.eye, wa, &b.eye, wb, &c.eye, wc),
            shadow: Vec2::weighted_sum(&a.shadow, wa, &b.shadow, wb, &c.shadow, wc),
            fade: f32::weighted_sum(&a.fade, wa, &b.fade, wb, &c.fade, wc),
        }
    }
}

/// The scene's shading parameters, resolved once per frame.
#[derive(Clone, Copy, Debug)]
pub struct ShadeParams {
    /// Light colour.
    pub light_colour: Vec3,
    /// Ambient level.
    pub ambient: f32,
    /// Banks exponent on the diffuse.
    pub banks_exponent: f32,
    /// Specular exponent.
    pub specular_exponent: f32,
    /// Exponent of the dampened specular.
    pub dampened_exponent: f32,
    /// One or three tangents.
    pub tangents: SpecularTangents,
    /// Scheuermann shift.
    pub tangent_shift: f32,
    /// Weights of eq. 3.7.
    pub weights: ShadingWeights,
    /// Debug view.
    pub debug_view: DebugView,
}

impl ShadeParams {
    /// From a scene.
    pub fn from_scene(s: &Scene) -> Self {
        let w = &s.shading.weights;
        ShadeParams {
            light_colour: s.light.colour,
            ambient: s.shading.ambient,
            banks_exponent: s.shading.banks_exponent,
            specular_exponent: s.shading.specular_exponent,
            dampened_exponent: s.shading.dampened_exponent,
            tangents: if s.shading.specular_tangents == 3 {
                SpecularTangents::Three
            } else {
                SpecularTangents::One
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
        }
    }
}

/// Shades one fur fragment of a shell (or fin) layer: texture reads, Kajiya–Kay diffuse and
/// specular, dampened specular, shell self-shadow with `lookups` reads, eq. 3.7. Transparent
/// texels are discarded before any shading.
#[inline]
pub fn shade_fur(
    f: &Fragment<FurVaryings>,
    colour_map: &Texture,
    tangent_map: &Texture,
    sampler: Sampler,
    lookups: u32,
    p: &ShadeParams,
) -> Option<Vec4> {
    let v = f.varyings();
    let (ddx, ddy) = f.derivatives(|v| v.uv);
    let lod = level_of_detail(ddx, ddy, colour_map.width(), colour_map.height());
    let texel = sampler.sample_level(colour_map, v.uv, lod);
    let alpha = texel.w * v.fade;
    // NaN alpha is discarded too.
    if alpha.is_nan() || alpha < ALPHA_DISCARD {
        return None;
    }
    let encoded = sampler.sample_level(tangent_map, v.uv, lod);
    if p.debug_view == DebugView::Tangents {
        return Some(encoded.truncate().extend(alpha));
    }
    if p.debug_view == DebugView::Alpha {
        return Some(Vec4::new(1.0, 1.0, 1.0, alpha));
    }
    let tangent = (encoded.truncate() * 2.0 - Vec3::ONE).normalize_or(Vec3::Z);
    let light = v.light.normalize_or_zero();
    let eye = v.eye.normalize_or_zero();
    // The thesis checks "if the according pixel is transparent": one texel per lookup, the
    // nearest of the mip level closest to this fragment's level of detail.
    let shadow = shading::shell_shadow(
        |uv| sampler.sample_nearest_level(colour_map, uv, lod).w,
        v.uv,
        v.shadow,
        lookups,
    );
    if p.debug_view == DebugView::Shadow {
        let g = (1.0 - p.weights.shadow * shadow).clamp(0.0, 1.0);
        return Some(Vec4::new(g, g, g, alpha));
    }
    let diffuse = shading::kajiya_kay_diffuse(tangent, light, p.banks_exponent);
    let specular = shading::specular_with_tangents(
        tangent,
        Vec3::Z,
        light,
        eye,
        p.specular_exponent,
        p.tangents,
        p.tangent_shift,
    );
    let dampened = shading::dampened_specular(shading::kajiya_kay_specular(
        tangent,
        light,
        eye,
        p.dampened_exponent,
    ));
    let colour = shading::final_colour(
        texel.truncate(),
        p.light_colour,
        p.ambient,
        diffuse,
        specular,
        dampened,
        shadow,
        &p.weights,
    );
    Some(colour.extend(alpha))
}
