//! The bunny example's keyboard: `M` cycles the material of every [`Translucent`] body, `D`
//! toggles the bulge, `Space` pauses the light. A file of its own so that the headless test
//! (`tests/headless.rs`) can check, without a window, that `M` changes the component.

use bevy::prelude::*;
use lucent_bevy::{Translucent, TranslucentMaterial};

/// The materials `M` cycles through, with the names the example logs.
pub fn materials() -> Vec<(&'static str, TranslucentMaterial)> {
    let preset = |n: &str| TranslucentMaterial::Preset(n.into());
    vec![
        ("marble", preset("marble")),
        ("skin1", preset("skin1")),
        ("ketchup", preset("ketchup")),
        ("wax", preset("wax")),
        ("skimmilk", preset("skimmilk")),
        (
            "jade (albedo 0.35,0.8,0.45; scatter 2,6,3 mm)",
            TranslucentMaterial::Colour {
                albedo: [0.35, 0.8, 0.45],
                scatter_distance_mm: [2.0, 6.0, 3.0],
                eta: 1.6,
            },
        ),
    ]
}

/// What the keys set.
#[derive(Resource, Default)]
pub struct Controls {
    /// Index into [`materials`] of the bodies' material.
    pub material: usize,
    /// The light stands still.
    pub paused: bool,
    /// The bulge breathes.
    pub bulge: bool,
}

/// Reads the keys pressed this frame: `M` sets every body's material to the next of
/// [`materials`] (the plugin solves it in the body's session: the material path), `D` and
/// `Space` toggle the bulge and the light's pause.
pub fn keys(
    input: Res<ButtonInput<KeyCode>>,
    mut controls: ResMut<Controls>,
    mut bodies: Query<&mut Translucent>,
) {
    if input.just_pressed(KeyCode::Space) {
        controls.paused = !controls.paused;
    }
    if input.just_pressed(KeyCode::KeyD) {
        controls.bulge = !controls.bulge;
    }
    if input.just_pressed(KeyCode::KeyM) {
        let all = materials();
        controls.material = (controls.material + 1) % all.len();
        info!("material: {}", all[controls.material].0);
        for mut t in &mut bodies {
            t.material = all[controls.material].1.clone();
        }
    }
}
