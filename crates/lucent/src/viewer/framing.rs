//! What the viewer's camera frames. The viewer uses lucent-gpu's one orbit camera
//! ([`OrbitCamera`], degrees and bounding-sphere radii) with the same `frame` call as
//! `lucent render`, on the bounding sphere of the loaded (normalised, undeformed) mesh; so a
//! scene file's `[camera]` means the same in both. The clip planes also enclose the deformed
//! mesh, which dents and noise may push past that sphere.

use glam::Vec3;
use lucent_core::camera::{CameraView, OrbitCamera, bounding_sphere};
use lucent_core::mesh::Mesh;
use std::sync::Arc;

/// The home view's eye distance from the centre, mesh units (the viewer's mesh has extent 1):
/// a unit-extent model fills about two thirds of the view height.
pub const HOME_DISTANCE: f32 = 2.2;

/// The viewer's home view for a mesh whose bounding sphere has `radius` (mesh units): from the
/// front, a little to the right (yaw 0.35 rad) and above (pitch 0.25 rad), [`HOME_DISTANCE`]
/// from the centre, field of view 35 degrees.
pub fn home(radius: f32) -> OrbitCamera {
    OrbitCamera {
        yaw_deg: 0.35f32.to_degrees(),
        pitch_deg: 0.25f32.to_degrees(),
        distance: Some(HOME_DISTANCE / radius),
        fov_y_deg: 35.0,
        target_offset: Vec3::ZERO,
    }
}

/// The camera and the spheres it frames.
#[derive(Debug)]
pub struct Framing {
    /// The camera, in the radii of the undeformed mesh's bounding sphere.
    pub camera: OrbitCamera,
    /// The camera a scene file asked for: the first mesh and "Reset view" start from it.
    start: Option<OrbitCamera>,
    /// The undeformed mesh whose sphere is framed (held to notice a new one).
    base: Option<Arc<Mesh>>,
    center: Vec3,
    radius: f32,
    /// The mesh drawn (held to notice a new deformation) and how far it reaches from `center`.
    shown: Option<Arc<Mesh>>,
    reach: f32,
}

/// Sphere assumed until the mesh has loaded: that of a normalised mesh about as round as the
/// default bunny's. Only the background shows meanwhile, and the camera keeps its distance in
/// mesh units when the real sphere arrives.
const PLACEHOLDER_RADIUS: f32 = 0.6;

impl Framing {
    /// Framing before any mesh, starting from the scene file's camera `start` if there is one,
    /// else from [`home`].
    pub fn new(start: Option<OrbitCamera>) -> Self {
        let radius = PLACEHOLDER_RADIUS;
        Framing {
            camera: home(radius),
            start,
            base: None,
            center: Vec3::ZERO,
            radius,
            shown: None,
            reach: radius,
        }
    }

    /// Follows the scene's undeformed mesh `base` and drawn mesh `shown`; cheap when neither
    /// changed. A new `base` is framed by its bounding sphere: the first one with the scene
    /// file's camera if given, else the camera keeps its distance and pan in mesh units (the
    /// home view is defined in them).
    pub fn update(&mut self, base: Option<&Arc<Mesh>>, shown: Option<&Arc<Mesh>>) {
        if let Some(base) = base
            && !self.base.as_ref().is_some_and(|b| Arc::ptr_eq(b, base))
        {
            let first = self.base.is_none();
            let (center, radius) = bounding_sphere(&base.positions);
            match self.start {
                Some(start) if first => self.camera = start,
                _ => {
                    let k = self.radius / radius;
                    self.camera.distance = self.camera.distance.map(|d| d * k);
                    self.camera.target_offset *= k;
                }
            }
            (self.base, self.center, self.radius) = (Some(base.clone()), center, radius);
            self.shown = None;
            self.reach = radius;
        }
        if let Some(shown) = shown
            && !self.shown.as_ref().is_some_and(|s| Arc::ptr_eq(s, shown))
        {
            let far = shown.positions.iter().map(|p| p.distance_squared(self.center)).fold(0.0f32, f32::max);
            self.reach = far.sqrt().max(self.radius);
            self.shown = Some(shown.clone());
        }
    }

    /// Back to the start: the scene file's camera, else [`home`].
    pub fn reset(&mut self) {
        self.camera = self.start.unwrap_or_else(|| home(self.radius));
    }

    /// Places the camera as the script's `camera:YAW,PITCH,DIST` says: degrees, degrees, and
    /// the eye's distance from the point looked at in mesh units (the pan is kept).
    pub fn place(&mut self, yaw_deg: f32, pitch_deg: f32, distance: f32) {
        self.camera.yaw_deg = yaw_deg;
        self.camera.pitch_deg = pitch_deg;
        self.camera.distance = Some(distance / self.radius);
    }

    /// The camera's matrices for a view of `aspect` = width / height.
    pub fn view(&self, aspect: f32) -> CameraView {
        self.camera.frame_with_reach(self.center, self.radius, self.reach, aspect)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::viewer::core_adapter;

    /// The home view of the viewer's camera before the cameras were merged: eye 2.2 mesh units
    /// from the origin at yaw 0.35 rad and pitch 0.25 rad, looking at the origin, fov 35 degrees.
    fn old_home_eye() -> Vec3 {
        let (yaw, pitch) = (0.35f32, 0.25f32);
        2.2 * Vec3::new(yaw.sin() * pitch.cos(), pitch.sin(), yaw.cos() * pitch.cos())
    }

    /// The default bunny's home view is the old one: same eye, same point looked at, same
    /// projection of the mesh (up to the clip planes, which no visible point crosses).
    #[test]
    fn home_view_is_the_old_default() {
        let mesh = Arc::new(core_adapter::normalise(lucent_core::mesh::embedded::bunny()));
        let mut framing = Framing::new(None);
        framing.update(Some(&mesh), Some(&mesh));
        let aspect = 1.5;
        let view = framing.view(aspect);
        assert!(view.eye.distance(old_home_eye()) < 1e-5, "{}", view.eye);
        let old_view = glam::Mat4::look_at_rh(old_home_eye(), Vec3::ZERO, Vec3::Y);
        let old_proj = glam::Mat4::perspective_rh(35f32.to_radians(), aspect, 0.022, 32.0);
        let size = glam::Vec2::new(900.0, 600.0);
        for p in mesh.positions.iter().step_by(97) {
            let old = old_proj.project_point3(old_view.transform_point3(*p));
            let old_px = glam::Vec2::new((old.x + 1.0) * 0.5 * size.x, (1.0 - old.y) * 0.5 * size.y);
            let new_px = view.to_pixel(*p, size).unwrap();
            assert!(old_px.distance(new_px) < 1e-2, "{p}: {old_px} vs {new_px}");
            let depth = view.view_proj.project_point3(*p).z;
            assert!((0.0..1.0).contains(&depth), "{p} clipped: depth {depth}");
        }
        framing.camera.orbit(glam::Vec2::new(10.0, 5.0));
        framing.reset();
        assert!(framing.view(aspect).eye.distance(old_home_eye()) < 1e-5);
    }

    /// A scene file's camera is used as it is (degrees and radii, as `lucent render` frames
    /// it), and the script's distance is in mesh units.
    #[test]
    fn scene_camera_is_kept_and_script_distance_is_in_mesh_units() {
        let mesh = Arc::new(core_adapter::normalise(lucent_core::mesh::generate::icosphere(2)));
        let start = OrbitCamera { yaw_deg: 30.0, pitch_deg: 10.0, distance: Some(3.0), ..Default::default() };
        let mut framing = Framing::new(Some(start));
        framing.update(Some(&mesh), Some(&mesh));
        assert_eq!(framing.camera, start);
        let (center, radius) = bounding_sphere(&mesh.positions);
        assert_eq!(framing.view(1.2), start.frame(center, radius, 1.2));

        framing.place(10.0, 20.0, 2.3);
        let view = framing.view(1.2);
        assert!((view.eye.distance(center) - 2.3).abs() < 1e-5);
    }

    /// A mesh deformed past its rest sphere stays inside the clip planes, and the camera does
    /// not move with the deformation.
    #[test]
    fn deformed_mesh_is_not_clipped() {
        let base = Arc::new(core_adapter::normalise(lucent_core::mesh::generate::icosphere(2)));
        let mut framing = Framing::new(None);
        framing.update(Some(&base), Some(&base));
        let eye = framing.view(1.0).eye;
        let bulged = Mesh::new(base.positions.iter().map(|p| *p * 1.3).collect(), base.triangles.clone());
        framing.update(Some(&base), Some(&Arc::new(bulged.clone())));
        let view = framing.view(1.0);
        assert_eq!(view.eye, eye);
        for p in &bulged.positions {
            let z = view.view_proj.project_point3(*p).z;
            assert!((0.0..=1.0).contains(&z), "{p}: depth {z}");
        }
    }
}
