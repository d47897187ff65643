//! The software rasterizer (raster stage). It knows nothing about fur.
//!
//! A [`Frame`] takes draw calls — vertices, triangles, a vertex closure returning clip-space
//! positions and [`Varyings`], a fragment closure returning a colour or a discard (or a
//! [`QuadShader`] shading a 2×2 quad at a time) — and rasterizes them into a tiled
//! [`Framebuffer`]. The stages, one file each:
//! [`clip`] (homogeneous clipping, guard band) → [`setup`] (fixed point, edge functions,
//! top-left rule) → [`bin`] (tiles and their triangle lists) → [`tile`] (2×2 quads,
//! interpolation, depth, blend), with [`texture`] for mip-mapped sampling.
//!
//! Output is bit-identical for any thread count and any tile size: each tile is rasterized by
//! one thread, its triangles in submission order, and no floating-point value ever depends on
//! which tile or thread computed it.

pub mod bin;
pub mod clip;
pub mod framebuffer;
pub mod pipeline;
pub mod setup;
pub mod state;
pub mod texture;
pub mod tile;
pub mod varyings;

pub use bin::{DEFAULT_TILE_SIZE, TileGrid};
pub use clip::ClipVertex;
pub use framebuffer::Framebuffer;
pub use pipeline::Frame;
pub use setup::CullMode;
pub use state::{BlendMode, DepthCompare, DrawState};
pub use texture::{AddressMode, Filter, MipFilter, Sampler, Texture};
pub use tile::{Fragment, PerFragment, PixelSlot, Quad, QuadShader, QuadSlots, RasterStats};
pub use varyings::Varyings;

/// What the rasterizer refuses.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum RasterError {
    /// An image side or pixel count outside the supported range.
    #[error("{parameter} = {value} is outside the supported range 1..={limit}")]
    ImageSize {
        /// Which parameter.
        parameter: &'static str,
        /// The value given.
        value: u64,
        /// The largest accepted value.
        limit: u64,
    },
    /// A tile size that is odd, zero or too large.
    #[error("tile size {0} must be an even number from 2 to 1024")]
    TileSize(u32),
    /// A triangle names a vertex that does not exist.
    #[error(
        "triangle {triangle} uses vertex index {index}, but the draw has {vertex_count} vertices"
    )]
    IndexOutOfRange {
        /// Position of the triangle in the draw.
        triangle: usize,
        /// The bad index.
        index: u32,
        /// Vertices supplied.
        vertex_count: usize,
    },
    /// A draw with more vertices than its triangles' corners can index.
    #[error("a draw has {count} vertices; at most {limit} are supported")]
    TooManyVertices {
        /// Vertices supplied.
        count: usize,
        /// The largest accepted count.
        limit: usize,
    },
    /// A texture with no texels or mismatched data.
    #[error("texture {width}×{height} needs {expected} texels, got {actual}")]
    TextureSize {
        /// Width.
        width: u32,
        /// Height.
        height: u32,
        /// width × height.
        expected: usize,
        /// Texels supplied.
        actual: usize,
    },
}
