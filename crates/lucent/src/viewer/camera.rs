//! Orbit camera: left-drag orbits about a target, right/middle-drag pans, the wheel zooms; and
//! the ray through a pixel for picking.

use glam::{Mat4, Vec2, Vec3};

/// A camera orbiting `target` at `distance`, looking at it. Lengths in mesh units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrbitCamera {
    /// Point looked at and orbited about.
    pub target: Vec3,
    /// Azimuth about the vertical (y) axis, radians.
    pub yaw: f32,
    /// Elevation above the horizontal plane, radians, within ±(pi/2 - 0.01).
    pub pitch: f32,
    /// Distance from `target` to the eye (> 0).
    pub distance: f32,
    /// Vertical field of view, radians.
    pub fov_y: f32,
}

impl Default for OrbitCamera {
    /// Looks at the origin from the front, slightly above: a unit-extent model fills about two
    /// thirds of the view height.
    fn default() -> Self {
        OrbitCamera { target: Vec3::ZERO, yaw: 0.35, pitch: 0.25, distance: 2.2, fov_y: 35f32.to_radians() }
    }
}

/// Radians of orbit per pixel of drag.
const ORBIT_PER_PIXEL: f32 = 0.008;
/// Zoom factor per wheel line.
const ZOOM_PER_LINE: f32 = 0.9;

impl OrbitCamera {
    /// Eye position.
    pub fn eye(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        self.target + self.distance * Vec3::new(sy * cp, sp, cy * cp)
    }

    /// World-to-view matrix (right-handed, y up).
    pub fn view(&self) -> Mat4 {
        Mat4::look_at_rh(self.eye(), self.target, Vec3::Y)
    }

    /// View-to-clip matrix for `aspect` = width / height (wgpu depth range 0..1).
    pub fn projection(&self, aspect: f32) -> Mat4 {
        let near = (self.distance * 0.01).max(1e-4);
        Mat4::perspective_rh(self.fov_y, aspect.max(1e-3), near, self.distance * 10.0 + 10.0)
    }

    /// Rotates by a mouse drag of `delta` pixels.
    pub fn orbit(&mut self, delta: Vec2) {
        self.yaw -= delta.x * ORBIT_PER_PIXEL;
        let limit = std::f32::consts::FRAC_PI_2 - 0.01;
        self.pitch = (self.pitch + delta.y * ORBIT_PER_PIXEL).clamp(-limit, limit);
    }

    /// Moves the target in the view plane so the point under the cursor follows a drag of
    /// `delta` pixels in a viewport `height` pixels tall.
    pub fn pan(&mut self, delta: Vec2, height: f32) {
        let units_per_pixel = 2.0 * self.distance * (0.5 * self.fov_y).tan() / height.max(1.0);
        let inv = self.view().inverse();
        let right = inv.x_axis.truncate();
        let up = inv.y_axis.truncate();
        self.target += (-delta.x * right + delta.y * up) * units_per_pixel;
    }

    /// Zooms by `lines` wheel lines (positive: closer).
    pub fn zoom(&mut self, lines: f32) {
        self.distance = (self.distance * ZOOM_PER_LINE.powf(lines)).clamp(0.05, 100.0);
    }

    /// World-space ray `(origin, unit direction)` through the point `pixel` of a viewport of
    /// `size` pixels (origin at the viewport's top-left).
    pub fn ray(&self, pixel: Vec2, size: Vec2) -> (Vec3, Vec3) {
        let ndc = Vec2::new(2.0 * pixel.x / size.x - 1.0, 1.0 - 2.0 * pixel.y / size.y);
        let inv = (self.projection(size.x / size.y) * self.view()).inverse();
        let near = inv.project_point3(ndc.extend(0.0));
        let far = inv.project_point3(ndc.extend(1.0));
        (near, (far - near).normalize())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The ray through the viewport centre is the view axis.
    #[test]
    fn centre_ray_points_at_target() {
        let cam = OrbitCamera::default();
        let (o, d) = cam.ray(Vec2::new(400.0, 300.0), Vec2::new(800.0, 600.0));
        let to_target = (cam.target - o).normalize();
        assert!(d.dot(to_target) > 0.99999, "{d} vs {to_target}");
    }

    /// Projecting a point and casting the ray through its pixel hits the point again.
    #[test]
    fn ray_inverts_projection() {
        let cam = OrbitCamera::default();
        let size = Vec2::new(640.0, 480.0);
        let p = Vec3::new(0.2, -0.1, 0.3);
        let clip = cam.projection(size.x / size.y) * cam.view() * p.extend(1.0);
        let ndc = clip.truncate() / clip.w;
        let pixel = Vec2::new((ndc.x + 1.0) * 0.5 * size.x, (1.0 - ndc.y) * 0.5 * size.y);
        let (o, d) = cam.ray(pixel, size);
        let closest = o + d * (p - o).dot(d);
        assert!((closest - p).length() < 1e-4);
    }
}
