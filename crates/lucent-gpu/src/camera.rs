//! A perspective orbit camera that frames an object by its bounding sphere.
//!
//! Right-handed, y up, depth 0..1 (wgpu's clip space). At yaw 0 and pitch 0 the camera sits on
//! the +z side of the object looking towards -z.

use glam::{Mat4, Vec3};

/// Where the camera sits around the object. Angles in degrees; distance in bounding-sphere
/// radii from the sphere's centre.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrbitCamera {
    /// Rotation about the +y axis, degrees; positive moves the camera towards +x. Default 0.
    pub yaw_deg: f32,
    /// Elevation above the xz-plane, degrees, clamped to -89..89. Default 15.
    pub pitch_deg: f32,
    /// Distance from the centre in bounding-sphere radii (> 1). Default: the distance at which
    /// the sphere just fits the smaller field of view with a 10% margin.
    pub distance: Option<f32>,
    /// Vertical field of view, degrees (0..180). Default 35.
    pub fov_y_deg: f32,
}

impl Default for OrbitCamera {
    fn default() -> Self {
        OrbitCamera { yaw_deg: 0.0, pitch_deg: 15.0, distance: None, fov_y_deg: 35.0 }
    }
}

/// The matrices and eye position of a framed camera, in mesh units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraView {
    /// World (mesh units) to view space.
    pub view: Mat4,
    /// View to clip space (perspective, depth 0..1).
    pub proj: Mat4,
    /// `proj * view`.
    pub view_proj: Mat4,
    /// Eye position, mesh units.
    pub eye: Vec3,
}

impl OrbitCamera {
    /// Frames the sphere (`center`, `radius` in mesh units) for an image of `aspect` =
    /// width / height.
    pub fn frame(&self, center: Vec3, radius: f32, aspect: f32) -> CameraView {
        let radius = if radius.is_finite() && radius > 0.0 { radius } else { 1.0 };
        let aspect = if aspect.is_finite() && aspect > 0.0 { aspect } else { 1.0 };
        let fov_y = self.fov_y_deg.clamp(1.0, 179.0).to_radians();
        // The narrower of the two fields of view decides the fit.
        let half_fov_x = ((fov_y * 0.5).tan() * aspect).atan();
        let half_min = (fov_y * 0.5).min(half_fov_x);
        let fit = 1.1 / half_min.sin();
        let distance = self.distance.unwrap_or(fit).max(1.001) * radius;
        let (yaw, pitch) = (self.yaw_deg.to_radians(), self.pitch_deg.clamp(-89.0, 89.0).to_radians());
        let dir = Vec3::new(yaw.sin() * pitch.cos(), pitch.sin(), yaw.cos() * pitch.cos());
        let eye = center + dir * distance;
        let view = Mat4::look_at_rh(eye, center, Vec3::Y);
        let near = (distance - radius * 1.05).max(distance * 1e-3);
        let far = distance + radius * 1.05;
        let proj = Mat4::perspective_rh(fov_y, aspect, near, far);
        CameraView { view, proj, view_proj: proj * view, eye }
    }
}

/// Centre and radius of a bounding sphere of `positions` (the box centre and the farthest
/// point from it: not minimal, but within a factor sqrt(3) and stable). `(0, 1)` when empty.
pub fn bounding_sphere(positions: &[Vec3]) -> (Vec3, f32) {
    if positions.is_empty() {
        return (Vec3::ZERO, 1.0);
    }
    let (lo, hi) = positions
        .iter()
        .fold((Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
    let c = 0.5 * (lo + hi);
    let r = positions.iter().map(|p| p.distance_squared(c)).fold(0.0f32, f32::max).sqrt();
    (c, if r > 0.0 { r } else { 1.0 })
}
