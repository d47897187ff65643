//! The shading terms of the thesis (3.2–3.4) as small pure functions.

pub mod burn;
mod numeric;
#[cfg(test)]
mod test_support;

pub mod kajiya_kay;
pub mod lighting;
pub mod projection;
pub mod shadow;
pub mod spots;
pub mod tangent_space;
pub mod wind;

pub use burn::{BURN_THRESHOLD, BurnOutcome, BurnSchedule, burn_exponent, burn_rule};
pub use kajiya_kay::{
    BANKS_EXPONENT, SpecularTangents, kajiya_kay_diffuse, kajiya_kay_specular, shift_tangent,
    specular_with_tangents,
};
pub use lighting::{
    DAMPENED_SPECULAR_MAX, DAMPENING_THRESHOLD, DEFAULT_SHADOW_WEIGHT, ShadingWeights,
    dampened_specular, final_colour,
};
pub use projection::{Axis, SINGULAR_RELATIVE_DET, project_to_uv, project_to_uv_dropping};
pub use shadow::{SHADOW_MIN_COS, shadow_change, shadow_lookup_count, shell_shadow};
pub use spots::{
    apply_spot, apply_spots, ellipsoid_spot_intensity, light_spot_intensity, spot_gradient,
    stripe_intensity,
};
pub use tangent_space::{sin_between, to_tangent_space};
pub use wind::{
    VIBRATION_RATIO, WindParams, bend_tangent, wind_displacement, wind_force, wind_uv_offset,
};
