//! Tangent frames: the T, B, N basis that takes world vectors into the fur texture's space
//! (thesis 3.2.1, eq. 3.1–3.3).

use glam::Vec3;

/// An orthonormal basis at a surface point: `tangent` follows the texture's u axis, `binormal`
/// its v axis, `normal` points out of the surface. Tangent-space coordinates of a world vector
/// `w` are `(w·tangent, w·binormal, w·normal)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TangentFrame {
    /// Unit vector along increasing texture u.
    pub tangent: Vec3,
    /// Unit vector along increasing texture v.
    pub binormal: Vec3,
    /// Unit outward surface normal.
    pub normal: Vec3,
}
