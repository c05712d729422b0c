//! The Stanford bunny in marble (10 cm tall) on a plane, with a point light orbiting it; lucent
//! solves the subsurface light off the frame (its own thread pool) while the frames keep coming.
//!
//! `cargo run --release -p lucent-bevy --example bunny`
//!
//! Keys: `M` cycles the material (marble, skin1, ketchup, wax, skimmilk, a green jade by colour
//! and distance), `D` toggles a slow bulge of the mesh (the session's deformation path), `Space`
//! pauses the light. Every finished solve is logged with its time.
//!
//! `LUCENT_BEVY_SCREENSHOT=out.png` saves a screenshot after the third solve and 15 s and exits (the
//! README's image: `xvfb-run -a -s "-screen 0 1280x800x24"` with Mesa's lavapipe).

use bevy::prelude::*;
use bevy::render::view::screenshot::{Screenshot, save_to_disk};
use lucent_bevy::{LucentPlugin, LucentSystems, SolveStatus, Translucent, bevy_mesh};

mod keys;
use keys::{Controls, keys};

/// The example's state.
#[derive(Resource, Default)]
struct Demo {
    time: f32,
    /// The bunny's rest positions (the bulge deforms from them).
    rest: Vec<[f32; 3]>,
    logged: u64,
    /// Frames since the screenshot was asked for (None: not yet).
    since_screenshot: Option<u32>,
}

#[derive(Component)]
struct Orbiting;

fn main() {
    App::new()
        .add_plugins((
            DefaultPlugins.set(WindowPlugin {
                primary_window: Some(Window { title: "lucent in Bevy".into(), ..default() }),
                ..default()
            }),
            LucentPlugin::default(),
        ))
        .init_resource::<Demo>()
        .init_resource::<Controls>()
        .add_systems(Startup, setup)
        .add_systems(Update, (keys, orbit, deform))
        .add_systems(PostUpdate, report.after(LucentSystems))
        .run();
}

fn setup(
    mut commands: Commands,
    mut meshes: ResMut<Assets<Mesh>>,
    mut standard: ResMut<Assets<StandardMaterial>>,
    mut demo: ResMut<Demo>,
) {
    // The bunny is about 10 units tall: scaled to 10 cm, standing on y = 0.
    let bunny = bevy_mesh(&lucent_bevy::lucent_core::mesh::embedded::bunny());
    if let Some(bevy::mesh::VertexAttributeValues::Float32x3(p)) = bunny.attribute(Mesh::ATTRIBUTE_POSITION) {
        demo.rest = p.clone();
    }
    commands.spawn((
        Mesh3d(meshes.add(bunny)),
        Translucent::preset("marble"),
        Transform::from_scale(Vec3::splat(0.01)).with_translation(Vec3::new(0.0, -0.0033, 0.0)),
    ));
    commands.spawn((
        Mesh3d(meshes.add(Plane3d::default().mesh().size(0.6, 0.6))),
        MeshMaterial3d(standard.add(StandardMaterial {
            base_color: Color::srgb(0.5, 0.48, 0.45),
            perceptual_roughness: 0.8,
            ..default()
        })),
    ));
    commands.spawn((
        PointLight {
            intensity: 1500.0,
            color: Color::WHITE,
            shadow_maps_enabled: true,
            range: 5.0,
            ..default()
        },
        Transform::from_xyz(0.15, 0.18, 0.1),
        Orbiting,
    ));
    commands.spawn((
        Camera3d::default(),
        // Bevy's default curve needs the `tonemapping_luts` feature, which this build leaves out.
        bevy::core_pipeline::tonemapping::Tonemapping::AcesFitted,
        Transform::from_xyz(-0.02, 0.11, 0.26).looking_at(Vec3::new(0.0, 0.045, 0.0), Vec3::Y),
    ));
}

/// The light circles the bunny once every 12 seconds.
fn orbit(
    time: Res<Time>,
    controls: Res<Controls>,
    mut demo: ResMut<Demo>,
    mut lights: Query<&mut Transform, With<Orbiting>>,
) {
    if controls.paused {
        return;
    }
    demo.time += time.delta_secs();
    let a = demo.time * std::f32::consts::TAU / 12.0;
    for mut t in &mut lights {
        t.translation = Vec3::new(0.18 * a.cos(), 0.18, 0.18 * a.sin());
    }
}

/// With `D`, a bulge that breathes on the bunny's back: a system editing the mesh asset, which
/// the plugin takes as a deformation.
fn deform(
    demo: Res<Demo>,
    controls: Res<Controls>,
    bodies: Query<&Mesh3d, With<Translucent>>,
    mut meshes: ResMut<Assets<Mesh>>,
) {
    if !controls.bulge || demo.rest.is_empty() {
        return;
    }
    let centre = Vec3::new(-1.0, 7.0, -1.0);
    let height = 0.8 * (0.5 + 0.5 * (demo.time * 1.5).sin());
    for mesh3d in &bodies {
        let Some(mut mesh) = meshes.get_mut(&mesh3d.0) else { continue };
        let moved: Vec<[f32; 3]> = demo
            .rest
            .iter()
            .map(|&p| {
                let v = Vec3::from(p);
                let w = (-(v - centre).length_squared() / 4.0).exp();
                (v + (v - centre).normalize_or_zero() * height * w).to_array()
            })
            .collect();
        mesh.insert_attribute(Mesh::ATTRIBUTE_POSITION, moved);
        mesh.compute_smooth_normals();
    }
}

/// Logs every finished solve; with `LUCENT_BEVY_SCREENSHOT`, saves the third and exits.
fn report(
    mut commands: Commands,
    mut demo: ResMut<Demo>,
    mut controls: ResMut<Controls>,
    bodies: Query<&SolveStatus>,
    mut exit: MessageWriter<AppExit>,
    time: Res<Time>,
) {
    for s in &bodies {
        if s.solves > demo.logged {
            demo.logged = s.solves;
            info!("solve {} took {:.0} ms off the frame", s.solves, s.last_ms);
        }
    }
    let Ok(path) = std::env::var("LUCENT_BEVY_SCREENSHOT") else { return };
    match demo.since_screenshot {
        // Bevy compiles its pipelines in the background: on a software driver the first frames
        // show nothing for some seconds.
        None if demo.logged >= 3 && time.elapsed_secs() > 15.0 => {
            controls.paused = true;
            demo.since_screenshot = Some(0);
            commands.spawn(Screenshot::primary_window()).observe(save_to_disk(path));
        }
        // Exit once the screenshot is written (its file appears some frames later).
        Some(n) if std::path::Path::new(&path).exists() || n > 5000 => {
            exit.write(AppExit::Success);
        }
        Some(n) => demo.since_screenshot = Some(n + 1),
        None => {}
    }
}
