//! The perspective orbit camera of lucent: it frames an object by its bounding sphere, for
//! `lucent render`, scene files and the interactive viewer alike.
//!
//! Right-handed, y up, depth 0..1 (wgpu's clip space). At yaw 0 and pitch 0 the camera sits on
//! the +z side of the object looking towards -z. Angles are in degrees and lengths in
//! bounding-sphere radii, so a camera means the same for a model of any size; [`OrbitCamera::frame`]
//! turns it into matrices in mesh units. The viewer's mouse controls ([`OrbitCamera::orbit`],
//! [`OrbitCamera::pan`], [`OrbitCamera::zoom`]) and picking ([`CameraView::ray`]) live here
//! too, so there is one camera to keep right.

use glam::{Mat4, Vec2, Vec3};

/// Where the camera sits around the object. Angles in degrees; lengths in bounding-sphere radii.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrbitCamera {
    /// Rotation about the +y axis, degrees; positive moves the camera towards +x. Default 0.
    pub yaw_deg: f32,
    /// Elevation above the xz-plane, degrees, clamped to -89..89. Default 15.
    pub pitch_deg: f32,
    /// Distance of the eye from the point looked at, in bounding-sphere radii. Scene files
    /// accept 1.0001..1e4 (outside the sphere); the viewer's zoom goes down to
    /// [`MIN_DISTANCE`], inside it. Default `None`: the distance at which the sphere just fits
    /// the smaller field of view with a 10% margin (see [`OrbitCamera::distance_radii`]).
    pub distance: Option<f32>,
    /// Vertical field of view, degrees (0..180, clamped to 1..179). Default 35.
    pub fov_y_deg: f32,
    /// Offset of the point looked at (and orbited about) from the sphere's centre, world axes,
    /// in bounding-sphere radii: the viewer's pan. Default zero (scene files have no pan).
    pub target_offset: Vec3,
}

impl Default for OrbitCamera {
    fn default() -> Self {
        OrbitCamera {
            yaw_deg: 0.0,
            pitch_deg: 15.0,
            distance: None,
            fov_y_deg: 35.0,
            target_offset: Vec3::ZERO,
        }
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

/// Nearest eye distance the zoom allows, bounding-sphere radii (inside the sphere: close-ups of
/// a part of the model).
pub const MIN_DISTANCE: f32 = 0.05;
/// Farthest eye distance the zoom allows, bounding-sphere radii.
pub const MAX_DISTANCE: f32 = 200.0;
/// Orbit per pixel of drag, degrees (0.008 rad: half a turn across about 390 pixels).
pub const ORBIT_DEG_PER_PIXEL: f32 = 0.008 * 180.0 / std::f32::consts::PI;
/// Distance factor per wheel line (positive lines move closer).
pub const ZOOM_PER_LINE: f32 = 0.9;
/// The clip planes enclose the framed sphere with this much room (relative to its radius).
const CLIP_MARGIN: f32 = 1.05;

impl OrbitCamera {
    /// Frames the sphere (`center`, `radius` in mesh units) for an image of `aspect` =
    /// width / height. Non-finite or non-positive `radius` or `aspect` count as 1.
    pub fn frame(&self, center: Vec3, radius: f32, aspect: f32) -> CameraView {
        self.frame_with_reach(center, radius, radius, aspect)
    }

    /// As [`OrbitCamera::frame`], with the near and far planes placed to enclose the sphere of
    /// radius `reach` (mesh units, at least `radius`) about `center` instead of the framed
    /// sphere: for a mesh that deforms beyond the rest sphere that positions the camera (the
    /// viewer's dents and noise), so the view neither jumps nor clips.
    pub fn frame_with_reach(&self, center: Vec3, radius: f32, reach: f32, aspect: f32) -> CameraView {
        let radius = if radius.is_finite() && radius > 0.0 { radius } else { 1.0 };
        let reach = if reach.is_finite() { reach.max(radius) } else { radius };
        let aspect = sane_aspect(aspect);
        let fov_y = self.fov_y_rad();
        let distance = self.distance_radii(aspect) * radius;
        let dir = self.eye_direction();
        let offset = self.target_offset * radius;
        let target = center + offset;
        let eye = target + dir * distance;
        let view = Mat4::look_at_rh(eye, target, Vec3::Y);
        // Depth of the sphere's centre along the view axis: the distance itself unless panned.
        let depth = distance + offset.dot(dir);
        let near = (depth - reach * CLIP_MARGIN).max(distance * 1e-3);
        // Only a pan that puts the whole sphere behind the eye needs the floor.
        let far = (depth + reach * CLIP_MARGIN).max(near + distance * 1e-3);
        let proj = Mat4::perspective_rh(fov_y, aspect, near, far);
        CameraView { view, proj, view_proj: proj * view, eye }
    }

    /// The eye's distance from the point looked at, bounding-sphere radii, for an image of
    /// `aspect` = width / height: `distance`, or when `None` the fit (the sphere with a 10%
    /// margin just fills the narrower field of view); at least [`MIN_DISTANCE`].
    pub fn distance_radii(&self, aspect: f32) -> f32 {
        let fit = || {
            let half_fov_y = 0.5 * self.fov_y_rad();
            // The narrower of the two fields of view decides the fit.
            let half_fov_x = (half_fov_y.tan() * sane_aspect(aspect)).atan();
            1.1 / half_fov_y.min(half_fov_x).sin()
        };
        self.distance.unwrap_or_else(fit).max(MIN_DISTANCE)
    }

    /// Turns the camera about the point looked at by a mouse drag of `delta_px` pixels (x right,
    /// y down): dragging right turns the object right (yaw decreases), dragging down raises the
    /// eye. [`ORBIT_DEG_PER_PIXEL`] per pixel; pitch stays within -89..89 degrees.
    pub fn orbit(&mut self, delta_px: Vec2) {
        self.yaw_deg -= delta_px.x * ORBIT_DEG_PER_PIXEL;
        self.pitch_deg = (self.pitch_deg + delta_px.y * ORBIT_DEG_PER_PIXEL).clamp(-89.0, 89.0);
    }

    /// Moves the point looked at in the view plane so that the point under the cursor (at the
    /// depth of that point) follows a drag of `delta_px` pixels in a viewport of `viewport_px`
    /// pixels (x right, y down).
    pub fn pan(&mut self, delta_px: Vec2, viewport_px: Vec2) {
        let aspect = viewport_px.x / viewport_px.y.max(1.0);
        let radii_per_pixel =
            2.0 * self.distance_radii(aspect) * (0.5 * self.fov_y_rad()).tan() / viewport_px.y.max(1.0);
        // The view's right and up axes, as `Mat4::look_at_rh` builds them.
        let forward = -self.eye_direction();
        let right = forward.cross(Vec3::Y).normalize();
        let up = right.cross(forward);
        self.target_offset += (-delta_px.x * right + delta_px.y * up) * radii_per_pixel;
    }

    /// Zooms by `lines` wheel lines (positive: closer), [`ZOOM_PER_LINE`] each, within
    /// [`MIN_DISTANCE`]..[`MAX_DISTANCE`]. An auto-fit camera (`distance` `None`) starts from its
    /// fit for `aspect` (the viewport's width / height) and keeps the result.
    pub fn zoom(&mut self, lines: f32, aspect: f32) {
        let d = self.distance_radii(aspect) * ZOOM_PER_LINE.powf(lines);
        self.distance = Some(d.clamp(MIN_DISTANCE, MAX_DISTANCE));
    }

    fn fov_y_rad(&self) -> f32 {
        self.fov_y_deg.clamp(1.0, 179.0).to_radians()
    }

    /// Unit vector from the point looked at towards the eye.
    fn eye_direction(&self) -> Vec3 {
        let (yaw, pitch) = (self.yaw_deg.to_radians(), self.pitch_deg.clamp(-89.0, 89.0).to_radians());
        Vec3::new(yaw.sin() * pitch.cos(), pitch.sin(), yaw.cos() * pitch.cos())
    }
}

fn sane_aspect(aspect: f32) -> f32 {
    if aspect.is_finite() && aspect > 0.0 { aspect } else { 1.0 }
}

impl CameraView {
    /// The world-space ray `(origin, unit direction)` through the point `pixel` of an image of
    /// `size` pixels (origin at the top-left, y down; the image's aspect must be the one the
    /// view was framed for). The origin lies on the near plane, so the ray meets only what the
    /// image can show: for picking.
    pub fn ray(&self, pixel: Vec2, size: Vec2) -> (Vec3, Vec3) {
        let size = size.max(Vec2::ONE);
        let ndc = Vec2::new(2.0 * pixel.x / size.x - 1.0, 1.0 - 2.0 * pixel.y / size.y);
        let inv = self.view_proj.inverse();
        let near = inv.project_point3(ndc.extend(0.0));
        let far = inv.project_point3(ndc.extend(1.0));
        (near, (far - near).normalize())
    }

    /// Where `point` (mesh units) lands in an image of `size` pixels (origin at the top-left,
    /// y down), or `None` when it is behind the eye. Not clipped to the image.
    pub fn to_pixel(&self, point: Vec3, size: Vec2) -> Option<Vec2> {
        let clip = self.view_proj * point.extend(1.0);
        if clip.w <= 0.0 {
            return None;
        }
        let ndc = clip.truncate() / clip.w;
        Some(Vec2::new((ndc.x + 1.0) * 0.5 * size.x, (1.0 - ndc.y) * 0.5 * size.y))
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A camera away from the defaults: off-centre sphere, explicit distance, panned.
    fn panned() -> (OrbitCamera, Vec3, f32) {
        let cam = OrbitCamera {
            yaw_deg: 20.0,
            pitch_deg: 14.0,
            distance: Some(3.5),
            target_offset: Vec3::new(0.1, -0.2, 0.05),
            ..Default::default()
        };
        (cam, Vec3::new(1.0, 2.0, -0.5), 0.6)
    }

    /// The ray through the image centre is the view axis: it points at the target.
    #[test]
    fn centre_ray_points_at_target() {
        let (cam, center, radius) = panned();
        let view = cam.frame(center, radius, 800.0 / 600.0);
        let (o, d) = view.ray(Vec2::new(400.0, 300.0), Vec2::new(800.0, 600.0));
        let target = center + cam.target_offset * radius;
        let to_target = (target - o).normalize();
        assert!(d.dot(to_target) > 0.99999, "{d} vs {to_target}");
        assert!((view.eye.distance(target) - 3.5 * radius).abs() < 1e-4);
    }

    /// Projecting a point and casting the ray through its pixel hits the point again.
    #[test]
    fn ray_inverts_projection() {
        let (cam, center, radius) = panned();
        let size = Vec2::new(640.0, 480.0);
        let view = cam.frame(center, radius, size.x / size.y);
        let p = center + Vec3::new(0.2, -0.1, 0.3);
        let pixel = view.to_pixel(p, size).unwrap();
        let (o, d) = view.ray(pixel, size);
        let closest = o + d * (p - o).dot(d);
        assert!((closest - p).length() < 1e-4, "{closest} vs {p}");
        assert!(view.to_pixel(view.eye - (center - view.eye), size).is_none(), "behind the eye");
    }

    /// Without a pan the framing is the one `lucent render` has always used: the eye at the
    /// fitted distance from the centre, the clip planes just around the sphere.
    #[test]
    fn unpanned_frame_keeps_the_renderer_framing() {
        let cam = OrbitCamera::default();
        let (center, radius) = (Vec3::new(0.5, 0.0, 1.0), 2.0);
        let view = cam.frame(center, radius, 1.5);
        let fit = 1.1 / 17.5f32.to_radians().sin();
        assert!((view.eye.distance(center) - fit * radius).abs() < 1e-4);
        // Depth 0 and 1 at the sphere's near and far margins on the view axis.
        let axis = (center - view.eye).normalize();
        for (k, want) in [(-CLIP_MARGIN, 0.0), (CLIP_MARGIN, 1.0)] {
            let p = view.view_proj.project_point3(center + axis * radius * k);
            assert!((p.z - want).abs() < 1e-4, "{k}: depth {}", p.z);
        }
    }

    /// A pan drags the point under the cursor with it, whatever the orbit and zoom.
    #[test]
    fn pan_follows_the_cursor() {
        let (mut cam, center, radius) = panned();
        let size = Vec2::new(800.0, 500.0);
        let before = cam.frame(center, radius, size.x / size.y);
        let target = center + cam.target_offset * radius;
        let start = before.to_pixel(target, size).unwrap();
        let delta = Vec2::new(37.0, -21.0);
        cam.pan(delta, size);
        let after = cam.frame(center, radius, size.x / size.y);
        let moved = after.to_pixel(target, size).unwrap();
        assert!((moved - (start + delta)).length() < 1e-2, "{moved} vs {}", start + delta);
        let shift = (cam.target_offset - panned().0.target_offset) * radius;
        assert!((after.eye - before.eye - shift).length() < 1e-5, "the eye moves with the target");
    }

    /// Orbiting turns about the target and keeps the pitch short of the poles; zooming an
    /// auto-fit camera starts from its fit and stays within the limits.
    #[test]
    fn orbit_and_zoom() {
        let (mut cam, center, radius) = panned();
        let target = center + cam.target_offset * radius;
        cam.orbit(Vec2::new(100.0, 0.0));
        assert!((cam.yaw_deg - (20.0 - 100.0 * ORBIT_DEG_PER_PIXEL)).abs() < 1e-4);
        assert!((cam.frame(center, radius, 1.0).eye.distance(target) - 3.5 * radius).abs() < 1e-4);
        cam.orbit(Vec2::new(0.0, 1e5));
        assert_eq!(cam.pitch_deg, 89.0);

        let mut fit = OrbitCamera::default();
        let d0 = fit.distance_radii(2.0);
        fit.zoom(1.0, 2.0);
        assert!((fit.distance.unwrap() - d0 * ZOOM_PER_LINE).abs() < 1e-5);
        fit.zoom(1e4, 2.0);
        assert_eq!(fit.distance, Some(MIN_DISTANCE));
        fit.zoom(-1e4, 2.0);
        assert_eq!(fit.distance, Some(MAX_DISTANCE));
    }

    /// Inside the sphere (a close zoom) and with a reach beyond it, the planes stay ordered and
    /// in front of the eye.
    #[test]
    fn clip_planes_for_close_and_deformed_views() {
        let cam = OrbitCamera { distance: Some(MIN_DISTANCE), ..Default::default() };
        let view = cam.frame_with_reach(Vec3::ZERO, 1.0, 1.3, 1.0);
        let (o, d) = view.ray(Vec2::splat(50.0), Vec2::splat(100.0));
        assert!(o.distance(view.eye) < 1e-3 && d.is_normalized());
        // A point 1.3 radii behind the centre (a deformed bump) is inside the far plane.
        let p = view.view_proj.project_point3(-view.eye.normalize() * 1.3);
        assert!(p.z < 1.0, "depth {}", p.z);
    }
}
