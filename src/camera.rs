//! The camera (mesh stage): a right-handed look-at view and a perspective projection with depth in
//! [0, 1] (the wgpu/Vulkan/D3D clip convention `0 ≤ z ≤ w`).
//!
//! The matrices are written out here, rather than taken from a library, so that a GPU
//! implementation can build bit-for-bit the same ones:
//! - view: `f = normalize(target − eye)`, `s = normalize(f × up)`, `u = s × f`; rows
//!   `(s, −s·eye)`, `(u, −u·eye)`, `(−f, f·eye)`, `(0, 0, 0, 1)`.
//! - projection: `g = 1 / tan(fov_y / 2)` (libm `tanf`), `r = far / (near − far)`; columns
//!   `(g/aspect, 0, 0, 0)`, `(0, g, 0, 0)`, `(0, 0, r, −1)`, `(0, 0, r·near, 0)`.

use glam::{Mat4, Vec3, Vec4};

/// A perspective camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub eye: Vec3,
    /// Point looked at.
    pub target: Vec3,
    /// Up direction (need not be orthogonal to the view direction).
    pub up: Vec3,
    /// Vertical field of view in degrees.
    pub fov_y_deg: f32,
    /// Near plane distance (> 0).
    pub near: f32,
    /// Far plane distance (> near).
    pub far: f32,
}

impl Default for Camera {
    fn default() -> Self {
        Camera {
            eye: Vec3::new(0.0, 2.2, 3.3),
            target: Vec3::ZERO,
            up: Vec3::Y,
            fov_y_deg: 45.0,
            near: 0.1,
            far: 100.0,
        }
    }
}

/// The right-handed look-at matrix (see the module docs for the formula).
pub fn look_at(eye: Vec3, target: Vec3, up: Vec3) -> Mat4 {
    let f = (target - eye).normalize_or_zero();
    let s = f.cross(up).normalize_or_zero();
    let u = s.cross(f);
    Mat4::from_cols(
        Vec4::new(s.x, u.x, -f.x, 0.0),
        Vec4::new(s.y, u.y, -f.y, 0.0),
        Vec4::new(s.z, u.z, -f.z, 0.0),
        Vec4::new(-s.dot(eye), -u.dot(eye), f.dot(eye), 1.0),
    )
}

/// The right-handed perspective projection with depth in [0, 1] (see the module docs).
pub fn perspective(fov_y_rad: f32, aspect: f32, near: f32, far: f32) -> Mat4 {
    let g = 1.0 / libm::tanf(0.5 * fov_y_rad);
    let r = far / (near - far);
    Mat4::from_cols(
        Vec4::new(g / aspect, 0.0, 0.0, 0.0),
        Vec4::new(0.0, g, 0.0, 0.0),
        Vec4::new(0.0, 0.0, r, -1.0),
        Vec4::new(0.0, 0.0, r * near, 0.0),
    )
}

impl Camera {
    /// The view matrix.
    pub fn view(&self) -> Mat4 {
        look_at(self.eye, self.target, self.up)
    }

    /// The projection matrix for an image of the given aspect ratio (width / height).
    pub fn projection(&self, aspect: f32) -> Mat4 {
        perspective(self.fov_y_deg.to_radians(), aspect, self.near, self.far)
    }

    /// `projection · view`.
    pub fn view_projection(&self, aspect: f32) -> Mat4 {
        self.projection(aspect) * self.view()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn near_and_far_map_to_zero_and_one() {
        let p = perspective(1.0, 1.5, 0.5, 50.0);
        let near = p * Vec4::new(0.0, 0.0, -0.5, 1.0);
        let far = p * Vec4::new(0.0, 0.0, -50.0, 1.0);
        assert!((near.z / near.w).abs() < 1e-6);
        assert!((far.z / far.w - 1.0).abs() < 1e-6);
    }

    #[test]
    fn look_at_puts_the_target_on_the_negative_z_axis() {
        let v = look_at(Vec3::new(1.0, 2.0, 3.0), Vec3::new(-2.0, 0.5, 1.0), Vec3::Y);
        let t = v.transform_point3(Vec3::new(-2.0, 0.5, 1.0));
        assert!(t.x.abs() < 1e-5 && t.y.abs() < 1e-5 && t.z < 0.0, "{t:?}");
        let e = v.transform_point3(Vec3::new(1.0, 2.0, 3.0));
        assert!(e.length() < 1e-5);
    }
}
