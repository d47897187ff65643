//! Orbit, pan and zoom of the scene's camera: pure functions from a camera and an input to a
//! new camera. The orbit is spherical around `target` with `up` as the pole; the eye never comes
//! closer to the pole than [`MIN_POLAR`], so the camera stays valid for the look-at matrix.

use glam::Vec3;
use pelage::scene::CameraSettings;

/// Closest angle between the view direction and the up axis, radians (about 2.9°).
pub const MIN_POLAR: f32 = 0.05;
/// Nearest the eye may come to the target, in units of the near plane.
const MIN_DISTANCE_IN_NEAR: f32 = 2.0;
/// Farthest the eye may go from the target, as a fraction of the far plane.
const MAX_DISTANCE_IN_FAR: f32 = 0.9;

fn pole(camera: &CameraSettings) -> Vec3 {
    camera.up.try_normalize().unwrap_or(Vec3::Y)
}

/// Turns the eye around the target: `yaw` radians around the up axis (counter-clockwise seen
/// from above), then `pitch` radians towards the up axis (positive raises the eye). The
/// distance to the target is unchanged.
pub fn orbit(camera: &CameraSettings, yaw: f32, pitch: f32) -> CameraSettings {
    let up = pole(camera);
    let offset = camera.eye - camera.target;
    let distance = offset.length();
    let vertical = offset.dot(up);
    let across = offset - up * vertical;
    let heading = across
        .try_normalize()
        .unwrap_or_else(|| up.any_orthonormal_vector());
    let polar = across.length().atan2(vertical);
    let heading = heading * yaw.cos() + up.cross(heading) * yaw.sin();
    let polar = (polar - pitch).clamp(MIN_POLAR, std::f32::consts::PI - MIN_POLAR);
    CameraSettings {
        eye: camera.target + (up * polar.cos() + heading * polar.sin()) * distance,
        ..camera.clone()
    }
}

/// The camera's right and up directions on screen.
fn screen_axes(camera: &CameraSettings) -> (Vec3, Vec3) {
    let forward = (camera.target - camera.eye).normalize_or_zero();
    let right = forward.cross(pole(camera)).normalize_or_zero();
    (right, right.cross(forward))
}

/// Slides eye and target together so the point under the cursor follows a drag of (`dx`, `dy`)
/// pixels (y down) in a view `height` pixels tall.
pub fn pan(camera: &CameraSettings, dx: f32, dy: f32, height: f32) -> CameraSettings {
    let distance = (camera.eye - camera.target).length();
    let per_pixel = 2.0 * distance * (0.5 * camera.fov_y_deg.to_radians()).tan() / height.max(1.0);
    let (right, up) = screen_axes(camera);
    let shift = (up * dy - right * dx) * per_pixel;
    CameraSettings {
        eye: camera.eye + shift,
        target: camera.target + shift,
        ..camera.clone()
    }
}

/// Moves the eye along the view direction so its distance to the target is multiplied by
/// `factor` (below 1 comes closer), kept between twice the near plane and 0.9 of the far plane.
pub fn zoom(camera: &CameraSettings, factor: f32) -> CameraSettings {
    let offset = camera.eye - camera.target;
    let distance = offset.length();
    let wanted = (distance * factor).clamp(
        camera.near * MIN_DISTANCE_IN_NEAR,
        (camera.far * MAX_DISTANCE_IN_FAR).max(camera.near * MIN_DISTANCE_IN_NEAR),
    );
    if !(distance > 0.0 && wanted.is_finite()) {
        return camera.clone();
    }
    CameraSettings {
        eye: camera.target + offset * (wanted / distance),
        ..camera.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f32::consts::{FRAC_PI_2, PI, TAU};

    fn camera() -> CameraSettings {
        CameraSettings {
            eye: Vec3::new(0.0, 9.0, 14.0),
            target: Vec3::new(0.0, -0.6, 0.0),
            ..CameraSettings::default()
        }
    }

    fn close(a: Vec3, b: Vec3, tolerance: f32) -> bool {
        (a - b).length() <= tolerance
    }

    fn polar_angle(c: &CameraSettings) -> f32 {
        (c.eye - c.target).normalize().dot(c.up.normalize()).acos()
    }

    #[test]
    fn orbit_keeps_the_distance_and_a_full_turn_comes_back() {
        let c = camera();
        let d = (c.eye - c.target).length();
        let mut turned = c.clone();
        for _ in 0..36 {
            turned = orbit(&turned, TAU / 36.0, 0.0);
            assert!(((turned.eye - turned.target).length() - d).abs() < 1e-3 * d);
            assert_eq!(turned.target, c.target);
        }
        assert!(close(turned.eye, c.eye, 1e-3 * d), "{:?}", turned.eye);
    }

    #[test]
    fn a_quarter_yaw_moves_the_eye_counter_clockwise_seen_from_above() {
        let c = CameraSettings {
            eye: Vec3::new(0.0, 0.0, 10.0),
            target: Vec3::ZERO,
            ..CameraSettings::default()
        };
        let turned = orbit(&c, FRAC_PI_2, 0.0);
        assert!(
            close(turned.eye, Vec3::new(10.0, 0.0, 0.0), 1e-4),
            "{:?}",
            turned.eye
        );
    }

    #[test]
    fn pitch_raises_the_eye_and_stops_short_of_the_poles() {
        let c = camera();
        let raised = orbit(&c, 0.0, 0.2);
        assert!(polar_angle(&raised) < polar_angle(&c));
        let top = orbit(&c, 0.0, 10.0);
        assert!((polar_angle(&top) - MIN_POLAR).abs() < 1e-3);
        let bottom = orbit(&c, 0.0, -10.0);
        assert!((polar_angle(&bottom) - (PI - MIN_POLAR)).abs() < 1e-3);
        // Still a usable look-at: the view direction is not parallel to up.
        for cam in [top, bottom] {
            let f = (cam.target - cam.eye).normalize();
            assert!(f.cross(cam.up).length() > 0.04);
        }
    }

    #[test]
    fn orbit_from_the_pole_picks_a_heading_instead_of_nan() {
        let c = CameraSettings {
            eye: Vec3::new(0.0, 5.0, 0.0),
            target: Vec3::ZERO,
            ..CameraSettings::default()
        };
        let moved = orbit(&c, 0.3, -0.5);
        assert!(moved.eye.is_finite());
        assert!(((moved.eye).length() - 5.0).abs() < 1e-4);
    }

    #[test]
    fn pan_moves_eye_and_target_together_across_the_screen() {
        let c = camera();
        let moved = pan(&c, 100.0, 0.0, 480.0);
        assert!(close(moved.eye - moved.target, c.eye - c.target, 1e-4));
        let shift = moved.target - c.target;
        // Dragging right moves the camera left: the scene follows the cursor.
        assert!(shift.x < 0.0 && shift.y.abs() < 1e-5, "{shift:?}");
        // A drag of the full view height moves by the visible height at the target.
        let full = pan(&c, 0.0, 480.0, 480.0);
        let visible = 2.0 * (c.eye - c.target).length() * (22.5f32).to_radians().tan();
        assert!(((full.target - c.target).length() - visible).abs() < 1e-3 * visible);
    }

    #[test]
    fn zoom_scales_the_distance_within_the_planes() {
        let c = camera();
        let d = (c.eye - c.target).length();
        let near = zoom(&c, 0.5);
        assert!(((near.eye - near.target).length() - 0.5 * d).abs() < 1e-4 * d);
        assert!(close(
            (near.eye - near.target).normalize(),
            (c.eye - c.target).normalize(),
            1e-5
        ));
        let closest = zoom(&c, 1e-9);
        assert!(((closest.eye - closest.target).length() - 2.0 * c.near).abs() < 1e-5);
        let farthest = zoom(&c, 1e9);
        assert!(((farthest.eye - farthest.target).length() - 0.9 * c.far).abs() < 1e-2);
    }
}
