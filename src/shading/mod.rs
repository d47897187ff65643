//! The shading terms of the thesis (3.2–3.4) as small pure functions (shading stage): no state, no
//! allocation, no panics, a finite result for every input. The fragment closures of `render` call
//! them line for line, in the order of the thesis's shader.
//!
//! # The terms, in the order a fragment uses them
//! | thesis | function | file |
//! |---|---|---|
//! | 3.2.1 | [`to_tangent_space`], [`sin_between`] | `tangent_space.rs` |
//! | eq. 2.5 (+ Banks 4.8) | [`kajiya_kay_diffuse`], [`BANKS_EXPONENT`] | `kajiya_kay.rs` |
//! | eq. 2.7, eq. 3.5 | [`kajiya_kay_specular`], [`shift_tangent`], [`specular_with_tangents`], [`three_lobe_specular`] ([`specular_lobe_sum`], [`specular_lobe_mean`]) | `kajiya_kay.rs` |
//! | 3.2.3 dampening | [`dampened_specular`] | `lighting.rs` |
//! | eq. 3.5's last term | [`specularity1_power`] (`(ψ_specularity1)^n`), [`uncoloured_specular`] and [`LightingModel`] (eq. 3.6 or 3.5) | `lighting.rs` |
//! | eq. 3.7 (and 3.5) | [`final_colour`], [`ShadingWeights`], [`ambient_term`] ([`ambient_constant`], [`ambient_of_strand`]) | `lighting.rs` |
//! | 3.2.2 projection | [`project_to_uv`], [`project_to_uv_dropping`] | `projection.rs` |
//! | 3.2.2 shadow | [`shadow_change`], [`shadow_lookup_count`], [`shell_shadow`], [`shadow_texel`] ([`shadow_of_opaque`], [`shadow_of_alpha`]) | `shadow.rs` |
//! | 3.2.4 spots, stripes; 3.4 matches at points | [`ellipsoid_spot_intensity`], [`light_spot_intensity`], [`point_light_intensity`] ([`point_light_cosine`], [`reach_falloff`]), [`spot_gradient`], [`apply_spot`], [`apply_spots`], [`stripe_intensity`], [`light_stripe_intensity`] | `spots.rs` |
//! | 3.3 wind | [`wind_force`], [`wind_displacement`], [`wind_uv_offset`], [`bend_tangent`] | `wind.rs` |
//! | 3.4 burning | [`burn_rule`], [`BurnOutcome`], [`burn_exponent`] | `burn.rs` |
//! | beyond: maps | [`layer_within_length`], [`density_alpha`], [`density_band`], [`comb_lean`], [`tint_strand`] | `maps.rs` |
//! | beyond: gravity, motion | [`gravity_lean`], [`path_position`], [`spring_impulse_response`], [`spring_lag`], [`lean_displacement`] | `motion.rs` |
//! | beyond: level of detail | [`lod_fur_pixels`], [`lod_shell_level`], [`lod_layer_order`], [`lod_layer_spans`], [`lod_alpha`], [`pow_whole`], [`lod_fin_fade`] | `lod.rs` |
//!
//! # Calling a term from your own test
//! Each term is a plain function, so a GPU port can check its shader line against it:
//! ```
//! use glam::Vec3;
//! use pelage::shading::{BANKS_EXPONENT, dampened_specular, kajiya_kay_diffuse};
//!
//! // A strand leaning 30° away from the light: Kajiya–Kay diffuse sin(t, l) (eq. 2.5),
//! // raised to Banks's exponent 4.8.
//! let tangent = Vec3::new(0.5, 0.0, 3f32.sqrt() / 2.0);
//! let light = Vec3::Z;
//! let ours = kajiya_kay_diffuse(tangent, light, BANKS_EXPONENT);
//! let expected = 0.5f64.powf(4.8); // sin 30° = 0.5
//! assert!((f64::from(ours) - expected).abs() < 1e-6);
//!
//! // The dampened specular of thesis 3.2.3: a gradient up to 0.6, then a constant 0.3.
//! assert_eq!(dampened_specular(0.4), 0.2);
//! assert_eq!(dampened_specular(0.9), 0.3);
//! ```
//!
//! # Numeric choices (stable: a GPU port must follow them)
//! - Everything is `f32`. Every lobe's power of a saturated base is pelage's own `pow01`
//!   (`2^(y·log2 x)` with documented polynomials, IEEE `+ − × ÷` and bit casts only, the same in
//!   `fur.wgsl`; single precision as a GPU's `pow`, within `3·(1 + |y·log2 x|)` ulp); the
//!   texture level of detail takes the same `log2`. Other transcendentals come from `libm`
//!   (`powf`, `expf`, `sinf`, `tanhf`, `floorf`, `roundf`), never from `f32` methods, so results
//!   do not depend on the platform's math library; `sqrt` is IEEE-754 correctly rounded and used
//!   directly. No fused multiply-add is written, so the order of operations in the source is the
//!   order evaluated.
//! - Direction inputs are normalised inside with `glam`'s `normalize_or_zero`: a zero vector, a
//!   vector with a NaN or infinite component, or one whose length over/underflows becomes zero,
//!   and each term documents its value for a zero direction (usually 0).
//! - Sines are `sqrt(max(0, 1 − cos²))`, as a shader computes them.
//! - Lobe exponents: NaN acts as 1, negative as 0, `+inf` is kept (`x^inf` = 0 below 1).
//! - Lobe bases and weights are saturated to `[0, 1]` with NaN → 0.
//! - Rings (spots, stripes) use the Hermite smoothstep of the linear ring coordinate.
//! - Eq. 3.7 clamps each channel to `[0, 1]`; a NaN channel becomes 0.
//! - Four departures from the thesis's words are scene keys, both forms here, defaults with
//!   their reasons in the docs of each (and the README, "Where pelage departs from the
//!   thesis"): the three lobes of eq. 3.5 averaged or summed ([`SpecularLobes`], default the
//!   mean); `ψ_ambient` times the strand colour or alone ([`AmbientTerm`], default times the
//!   strand colour); a shadow lookup adding its alpha or 1 when the texel is not transparent,
//!   alpha ≥ [`SHADOW_OPAQUE_ALPHA`] ([`ShadowTexel`], default the alpha); stripes as bands of
//!   the lobe of a light fixed to the object ([`light_stripe_intensity`], the default, the
//!   thesis's) or across an axis ([`stripe_intensity`]).
//! - The lighting equation is a scene key too ([`LightingModel`]): eq. 3.6/3.7, the thesis's
//!   final system, by default, or eq. 3.5, whose last term `(ψ_specularity1)^n` replaces the
//!   dampened specular (`n` default 1, the caption of figure 3.13's "actual specularity").
//!
//! # How the tests check the numbers
//! Each term is compared with an f64 reimplementation written separately in its test (sines
//! from cross products rather than `1 − cos²`, Cramer or normal equations in f64, …) over
//! fixed-seed random inputs from a small LCG (`test_support.rs`), plus edge cases (parallel
//! vectors, zero and NaN inputs, exact boundaries). Bounds are absolute and stated next to each
//! test; the main ones:
//! - sine of an angle: `1e-6·(1 + 1/sin)` (the `1 − cos²` route loses precision near
//!   parallel vectors); powers propagate it to first order, `p·x^(p−1)·dx + 1e-6`;
//! - linear combinations (tangent space, eq. 3.7, shadow change): `1e-6` times the magnitude
//!   of the terms;
//! - projection: `1e-5·(1 + |a| + |b|)·cond`, `cond = |dP/du||dP/dv| / |det|`;
//! - ramps: `1e-6` plus the smoothstep slope (1.5 / ring width) times the error of the
//!   distance; the burn schedule: `1e-5` relative; the dampening: exact.

pub mod burn;
pub(crate) mod numeric;
#[cfg(test)]
pub(crate) mod test_support;

pub mod kajiya_kay;
pub mod lanes;
pub mod lighting;
pub mod lod;
pub mod maps;
pub mod motion;
pub mod projection;
pub mod shadow;
pub mod spots;
pub mod tangent_space;
pub mod wind;

pub use burn::{
    BURN_THRESHOLD, BurnLanes, BurnOutcome, BurnSchedule, burn_exponent, burn_rule,
    burn_rule_lanes, burnt_away_above,
};
pub use kajiya_kay::{
    BANKS_EXPONENT, LightingExponents, SpecularLobes, SpecularTangents, StrandLighting,
    StrandLightingLanes, kajiya_kay_diffuse, kajiya_kay_specular, shift_tangent,
    specular_lobe_mean, specular_lobe_sum, specular_with_tangents, strand_lighting,
    strand_lighting_lanes, three_lobe_specular,
};
pub use lanes::{LANES, Vec3x4, Vec3x8, Vec3xN};
pub use lighting::{
    AmbientTerm, DAMPENED_SPECULAR_MAX, DAMPENING_THRESHOLD, DEFAULT_SHADOW_WEIGHT, LightingModel,
    ShadingWeights, ambient_constant, ambient_of_strand, ambient_term, dampened_specular,
    dampened_specular_lanes, final_colour, final_colour_lanes, specularity1_power,
    specularity1_power_lanes, uncoloured_specular, uncoloured_specular_lanes,
};
pub use lod::{
    lod_alpha, lod_fin_fade, lod_fur_pixels, lod_layer_order, lod_layer_spans, lod_shell_level,
    pow_whole,
};
pub use maps::{
    DENSITY_BANDS, comb_lean, density_alpha, density_band, layer_within_length, tint_strand,
};
pub use motion::{
    gravity_lean, lean_displacement, path_position, spring_impulse_response, spring_lag,
};
pub use projection::{Axis, SINGULAR_RELATIVE_DET, project_to_uv, project_to_uv_dropping};
pub use shadow::{
    SHADOW_MIN_COS, SHADOW_OPAQUE_ALPHA, ShadowLanes, ShadowTexel, shadow_change,
    shadow_lookup_count, shadow_of_alpha, shadow_of_opaque, shadow_texel, shell_shadow,
    shell_shadow_lanes, shell_shadow_x4,
};
pub use spots::{
    apply_spot, apply_spot_lanes, apply_spots, ellipsoid_spot_intensity,
    ellipsoid_spot_intensity_lanes, ellipsoid_surely_outside, light_spot_cosine,
    light_spot_cosine_above, light_spot_cosine_below, light_spot_intensity, light_spot_lobe,
    light_spot_lobe_lanes, light_spot_surely_outside, light_stripe_band, light_stripe_intensity,
    point_light_cosine, point_light_intensity, reach_falloff, spot_gradient, spot_gradient_lanes,
    stripe_intensity,
};
pub use tangent_space::{sin_between, to_tangent_space};
pub use wind::{
    VIBRATION_RATIO, WindParams, bend_tangent, bend_tangent_lanes, vertex_pull, wind_displacement,
    wind_force, wind_uv_offset,
};
