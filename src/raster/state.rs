//! Per-draw fixed-function state (raster stage): the depth test, depth writes, blending and culling
//! a draw asks for. Shared by [`super::pipeline`] (which records it with each draw) and
//! [`super::tile`] (which applies it per fragment); it imports neither.
//!
//! Invariant: the state is plain data, copied into each draw; changing it between draws never
//! affects a draw already submitted.

use super::setup::CullMode;

/// The depth comparison of a draw: a fragment passes when `fragment_depth OP stored_depth`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum DepthCompare {
    /// Always passes (no depth test).
    Always,
    /// Passes when strictly nearer.
    #[default]
    Less,
    /// Passes when nearer or equal: lets coplanar layers drawn later win.
    LessEqual,
}

/// How a fragment's colour combines with the framebuffer.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum BlendMode {
    /// Overwrite.
    #[default]
    Replace,
    /// Colour `src·a + dst·(1 − a)`, alpha `a + dst·(1 − a)` (the "over" operator).
    Alpha,
    /// `src + dst` (one, one): counts overlaps, accumulates light.
    Add,
}

/// Per-draw fixed-function state.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DrawState {
    /// Depth test.
    pub depth_compare: DepthCompare,
    /// Whether passing fragments write their depth.
    pub depth_write: bool,
    /// Colour blending.
    pub blend: BlendMode,
    /// Face culling.
    pub cull: CullMode,
}

impl Default for DrawState {
    /// Opaque geometry: depth test `Less`, depth write on, no blending, no culling.
    fn default() -> Self {
        DrawState {
            depth_compare: DepthCompare::Less,
            depth_write: true,
            blend: BlendMode::Replace,
            cull: CullMode::None,
        }
    }
}
