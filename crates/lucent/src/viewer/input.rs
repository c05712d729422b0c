//! Mouse and keyboard over the 3D view: camera control, denting by click-drag, triangle
//! picking. egui sees every event first; only what it does not consume arrives here.

use super::pick::{self, Picker};
use super::state::{Tool, ViewState};
use glam::Vec2;
use lucent_core::camera::{CameraView, OrbitCamera};
use lucent_core::mesh::Mesh;
use lucent_core::mesh::deform::Bump;
use std::sync::Arc;
use std::time::Instant;
use winit::event::{ElementState, MouseButton, MouseScrollDelta};

/// Radius of a new dent, mesh units (the mesh has extent 1).
const DENT_RADIUS: f32 = 0.12;
/// How fast a dent deepens while the button is held, mesh units per second.
const DENT_RATE: f32 = 0.06;
/// Deepest dent, mesh units.
const DENT_MAX: f32 = 0.08;

/// A dent being made by a held button.
#[derive(Clone, Copy, Debug)]
struct DentDrag {
    index: usize,
    started: Instant,
}

/// Pointer state between events.
#[derive(Debug, Default)]
pub struct Input {
    /// Cursor position in physical pixels of the window.
    cursor: Vec2,
    orbiting: bool,
    panning: bool,
    dent: Option<DentDrag>,
    /// The mesh's BVH, kept between clicks.
    picker: Picker,
}

/// The 3D viewport in physical pixels: (top-left, size).
pub type ViewportRect = (Vec2, Vec2);

impl Input {
    /// True while a drag needs frames drawn continuously (a dent growing).
    pub fn animating(&self) -> bool {
        self.dent.is_some()
    }

    /// A button press or release over the 3D view; `camera` is framed for the viewport.
    pub fn button(
        &mut self,
        button: MouseButton,
        pressed: ElementState,
        view: ViewportRect,
        camera: &CameraView,
        state: &mut ViewState,
        mesh: Option<&Arc<Mesh>>,
    ) {
        let down = pressed == ElementState::Pressed;
        match button {
            MouseButton::Left if !down => {
                self.orbiting = false;
                self.dent = None;
            }
            MouseButton::Left => {
                let hit = mesh.and_then(|m| {
                    let (o, d) = camera.ray(self.cursor - view.0, view.1);
                    self.picker.pick(m, o, d)
                });
                match (state.tool, hit) {
                    (Tool::Dent, Some(h)) => {
                        state.deform.dents.push(Bump { center: h.point, radius: DENT_RADIUS, height: 0.0 });
                        self.dent =
                            Some(DentDrag { index: state.deform.dents.len() - 1, started: Instant::now() });
                    }
                    (Tool::PickTriangle, Some(h)) => state.picked_face = Some(h.face),
                    _ => self.orbiting = true,
                }
            }
            MouseButton::Right | MouseButton::Middle => self.panning = down,
            _ => {}
        }
    }

    /// Cursor motion (physical pixels): orbit or pan while a button is held.
    pub fn moved(&mut self, to: Vec2, view: ViewportRect, camera: &mut OrbitCamera) {
        let delta = to - self.cursor;
        self.cursor = to;
        if self.orbiting {
            camera.orbit(delta);
        } else if self.panning {
            camera.pan(delta, view.1);
        }
    }

    /// Mouse wheel over the 3D view: zoom.
    pub fn wheel(&mut self, delta: MouseScrollDelta, view: ViewportRect, camera: &mut OrbitCamera) {
        let lines = match delta {
            MouseScrollDelta::LineDelta(_, y) => y,
            MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
        };
        camera.zoom(lines, view.1.x / view.1.y.max(1.0));
    }

    /// Per frame: a held dent deepens with time.
    pub fn update(&mut self, state: &mut ViewState) {
        if let Some(drag) = self.dent {
            match state.deform.dents.get_mut(drag.index) {
                Some(d) => d.height = -(drag.started.elapsed().as_secs_f32() * DENT_RATE).min(DENT_MAX),
                None => self.dent = None,
            }
        }
    }

    /// Forgets held buttons (focus lost, pointer left the window); keeps the picking tree.
    pub fn release_all(&mut self) {
        *self = Input { cursor: self.cursor, picker: std::mem::take(&mut self.picker), ..Default::default() };
    }
}

/// A dent made by a script at the surface point nearest `p`, at full depth.
pub fn scripted_dent(mesh: &Mesh, p: glam::Vec3) -> Option<Bump> {
    pick::nearest_vertex(mesh, p).map(|center| Bump { center, radius: DENT_RADIUS * 1.5, height: -DENT_MAX })
}
