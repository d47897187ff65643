//! pelage: a deterministic, pure-software CPU renderer for shell-and-fin fur.
//!
//! The modules follow the path the data takes, and lower stages never import higher ones:
//! [`camera`] (view and projection), [`mesh`] (load, tangent frames, shells) → [`fur`] (strands, baked shell and fin textures) →
//! [`raster`] (clip, setup, bin, rasterize tiles; knows nothing about fur) → [`shading`] (the
//! thesis's shading terms as small pure functions) → [`scene`] (TOML → typed scene) →
//! [`render`] (assembles one frame: base mesh, shells layer by layer, fins).
//!
//! The output is an oracle: the same scene gives the same bytes for any thread count, any
//! tile size and any [`simd`] level (the instruction set chosen at run time), on every run.
#![warn(missing_docs)]

pub mod camera;
pub mod compare;
pub mod export;
pub mod font;
pub mod fur;
#[cfg(feature = "gpu")]
pub mod gpu;
pub mod input;
pub mod limits;
pub mod mesh;
pub mod output;
pub mod raster;
pub mod render;
pub mod robust;
pub mod scene;
pub mod shading;
pub mod simd;
pub mod sweep;
pub mod text;
