//! What the headless test and the `frame_times` example share: a Bevy app without a window,
//! and the test's scene (the embedded bunny in marble at 10 cm under one directional light,
//! seen by the camera `lucent render` frames by default) rendering into an `Rgba32Float` image
//! that is read back to the CPU every frame.

// Each includer uses a part.
#![allow(dead_code)]

use bevy::camera::{Exposure, Hdr, RenderTarget};
use bevy::core_pipeline::tonemapping::{DebandDither, Tonemapping};
use bevy::prelude::*;
use bevy::render::gpu_readback::{Readback, ReadbackComplete};
use bevy::render::render_resource::{TextureFormat, TextureUsages};
use bevy::window::ExitCondition;
use lucent_bevy::lucent_core::camera::{CameraView, OrbitCamera, bounding_sphere};
use lucent_bevy::lucent_core::mesh::embedded;
use lucent_bevy::{LucentPlugin, Translucent, bevy_mesh};
use std::sync::{Arc, Mutex};

pub const WIDTH: u32 = 256;
pub const HEIGHT: u32 = 192;
/// The direction the light travels (`lucent render --light dir:...`): from the front, above
/// and to the right.
pub const LIGHT: [f32; 3] = [-0.5, -0.6, -1.0];

/// Linear RGBA per pixel, rows from the top.
pub type Pixels = Vec<[f32; 4]>;

/// The bytes of the newest read-back image, taken by whoever reads them.
pub type Latest = Arc<Mutex<Option<Vec<u8>>>>;

/// A headless Bevy app with `plugin` (no window, no winit), its plugins finished.
pub fn headless_app(plugin: LucentPlugin) -> App {
    let mut app = App::new();
    app.add_plugins((
        DefaultPlugins
            .set(WindowPlugin { primary_window: None, exit_condition: ExitCondition::DontExit, ..default() })
            .disable::<bevy::winit::WinitPlugin>(),
        plugin,
    ));
    while app.plugins_state() == bevy::app::PluginsState::Adding {
        bevy::tasks::tick_global_task_pools_on_main_thread();
    }
    app.finish();
    app.cleanup();
    app
}

/// lucent's default camera on the embedded bunny at the test's aspect.
pub fn lucent_view() -> CameraView {
    let (center, radius) = bounding_sphere(&embedded::bunny().positions);
    OrbitCamera::default().frame(center, radius, WIDTH as f32 / HEIGHT as f32)
}

/// The bunny, the light and lucent's camera `view` in `app`, the target image read back every
/// frame into the returned slot.
pub fn scene(app: &mut App, view: &CameraView) -> Latest {
    let world = app.world_mut();
    let mut target = Image::new_target_texture(WIDTH, HEIGHT, TextureFormat::Rgba32Float, None);
    // Read back to the CPU.
    target.texture_descriptor.usage |= TextureUsages::COPY_SRC;
    let image = world.resource_mut::<Assets<Image>>().add(target);
    let mesh = world.resource_mut::<Assets<Mesh>>().add(bevy_mesh(&embedded::bunny()));
    world.spawn((Mesh3d(mesh), Translucent::preset("marble").with_scale(0.1), Transform::IDENTITY));
    let light = Transform::default().looking_to(Vec3::from(LIGHT), Vec3::Y);
    world.spawn((DirectionalLight { illuminance: 1.0, color: Color::WHITE, ..default() }, light));
    let world_from_view = Mat4::from_cols_array(&view.view.inverse().to_cols_array());
    world.spawn((
        Camera3d::default(),
        Camera { clear_color: ClearColorConfig::Custom(Color::NONE), ..default() },
        RenderTarget::Image(image.clone().into()),
        Projection::Perspective(PerspectiveProjection {
            fov: OrbitCamera::default().fov_y_deg.to_radians(),
            ..default()
        }),
        Transform::from_matrix(world_from_view),
        // Linear radiance as the shader writes it: exposure 1, no tone curve, no dither.
        (Hdr, Tonemapping::None, DebandDither::Disabled, Msaa::Off, Exposure { ev100: -(1.2f32).log2() }),
    ));
    let latest: Latest = Arc::default();
    let sink = latest.clone();
    world.spawn(Readback::texture(image)).observe(move |event: On<ReadbackComplete>| {
        *sink.lock().unwrap() = Some(event.data.clone());
    });
    latest
}

/// `Rgba32Float` texels (rows of 256 pixels are 4,096 bytes: no row padding).
pub fn decode(bytes: &[u8]) -> Pixels {
    let f =
        |i: usize| f32::from_le_bytes([bytes[4 * i], bytes[4 * i + 1], bytes[4 * i + 2], bytes[4 * i + 3]]);
    (0..(WIDTH * HEIGHT) as usize).map(|p| [f(4 * p), f(4 * p + 1), f(4 * p + 2), f(4 * p + 3)]).collect()
}
