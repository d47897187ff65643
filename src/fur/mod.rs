//! Fur modelling (thesis 3.1): strands, cones, and baked shell and fin textures.
//!
//! The data path: [`FurParams`] → [`generate_strands`] (MT19937 from an explicit seed, one block
//! of draws per strand) → cones around each sampled Bézier segment → [`bake_shells`] (one
//! texture pair per shell layer, periodic tile) and [`bake_fin`] (a side view of a narrow strip).
//!
//! Units: the shell tile is the periodic unit square `x, y ∈ [0, 1)`; heights and radii are in
//! the same unit. Tangent space: `x` = texture `u`, `y` = texture `v`, `z` = up. Images are
//! row-major from row 0 (`v = 0`); 8-bit values use [`unorm8`]; tangents are stored as
//! `unorm8(t·0.5 + 0.5)` and read back with [`tangent_from_rgb8`]. Every result is identical
//! for any rayon thread count.

mod bake;
mod cone;
mod fin;
mod image;
mod params;
mod strand;

pub use bake::{ShellLayer, ShellTextures, bake_shells, gaussian_layer_weight, layer_mid_height};
pub use fin::{FinTexture, bake_fin, bake_fin_strands};
pub use image::{
    EMPTY_COLOUR, EMPTY_TANGENT, Rgba8Image, tangent_from_rgb8, tangent_to_rgb8, unorm8,
};
pub use params::{
    FurError, FurParams, MAX_BAKE_RESOLUTION, MAX_LENGTH, MAX_RESOLUTION, MAX_SLOPE_DEG,
    MAX_STRANDS, MAX_SUPERSAMPLE,
};
pub use strand::{
    DRAWS_PER_STRAND, FIN_SEED_OFFSET, Strand, bezier_derivative, bezier_point, bezier_tangent,
    generate_fin_strands, generate_strands, unit_f32,
};
