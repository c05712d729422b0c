//! lucent in Bevy: translucent meshes solved by lucent's hierarchical subsurface scattering
//! (Mertens et al. 2003, *Interactive Rendering of Translucent Deformable Objects*) and drawn in
//! Bevy's pipeline with lucent's own exit term (§5.4).
//!
//! Add [`LucentPlugin`] and put a [`Translucent`] on an entity with a [`Mesh3d`]:
//!
//! ```no_run
//! use bevy::prelude::*;
//! use lucent_bevy::{LucentPlugin, Translucent};
//!
//! fn setup(mut commands: Commands, mut meshes: ResMut<Assets<Mesh>>) {
//!     commands.spawn((Mesh3d(meshes.add(Sphere::new(0.05).mesh().ico(4).unwrap())), Translucent::preset("marble")));
//!     commands.spawn((PointLight { intensity: 2000.0, ..default() }, Transform::from_xyz(0.3, 0.4, 0.3)));
//!     commands.spawn((Camera3d::default(), Transform::from_xyz(0.0, 0.05, 0.3).looking_at(Vec3::ZERO, Vec3::Y)));
//! }
//!
//! App::new().add_plugins((DefaultPlugins, LucentPlugin::default())).add_systems(Startup, setup).run();
//! ```
//!
//! Per body the plugin keeps one lucent-core `FrameSession` (§5.5). When the mesh's vertices
//! (a system editing the mesh asset: the session's deformation path, refit mode), Bevy's point,
//! spot or directional lights ([`lights`] states the unit mapping), the [`Translucent`]
//! component or the camera change, it hands the change to the session and solves it on Bevy's
//! [`bevy::tasks::AsyncComputeTaskPool`], its work on the plugin's own thread pool
//! ([`SolvePool`], [`LucentPlugin::solve_threads`]). A frame never waits: the last solve stays on screen
//! until the next is ready ([`SolveStatus`] says how long solves take). The result, `B / (c π)`
//! and view-ray single scattering per vertex, goes to a storage buffer of the body's
//! [`LucentMaterial`], whose shader adds `F_t(η, ω_o) (T(μ_o) B / (c π) + L_single)` and the
//! Fresnel-weighted highlight per pixel exactly as lucent's mesh pass does, times Bevy's
//! camera exposure.
//!
//! Not covered: Bevy's ambient light and environment maps do not light the body's interior,
//! skinned and morph-target meshes are solved in their rest pose, and the body's surface is
//! shaded only by lucent (it takes no Bevy shadow maps from other objects; it casts them).

mod body;
mod component;
mod convert;
pub mod lights;
mod material;
mod pool;
mod systems;

pub use body::SolveStatus;
pub use component::{DEFAULT_BOUNCES, Translucent, TranslucentMaterial};
pub use convert::{Weld, bevy_mesh};
pub use lucent_core;
pub use lucent_core::bssrdf::ProfileKind;
pub use material::{LUCENT_SHADER, LucentMaterial, ShadingUniform, shader_source, vertex_records};
pub use pool::{SolvePool, SolveThreads};

use bevy::asset::AssetEventSystems;
use bevy::pbr::MaterialPlugin;
use bevy::prelude::*;
use bevy::shader::Shader;
use bevy::transform::TransformSystems;

/// Solves every [`Translucent`] body with lucent and draws it (see the crate documentation).
///
/// The default keeps Bevy's frame rate while solving and solves as fast as that allows: on
/// Linux every core at nice 10 (the scheduler gives Bevy's threads the cores whenever they want
/// them, the solve the rest; docs/bevy.md has the frame and solve times of each choice),
/// elsewhere, where a thread's priority cannot be lowered alone, all cores but one.
#[derive(Clone, Copy, Debug)]
pub struct LucentPlugin {
    /// Threads the solves run on (the plugin's own rayon pool, [`SolvePool`]). Default
    /// [`SolveThreads::All`] on Linux, [`SolveThreads::LeaveOne`] elsewhere.
    pub solve_threads: SolveThreads,
    /// How far below Bevy's threads the solve threads run in the OS scheduler: a Unix nice
    /// increment, 0 (Bevy's priority)..=19. Applied on Linux only. Default 10.
    pub solve_nice: u8,
}

impl Default for LucentPlugin {
    fn default() -> Self {
        let solve_threads =
            if cfg!(target_os = "linux") { SolveThreads::All } else { SolveThreads::LeaveOne };
        LucentPlugin { solve_threads, solve_nice: 10 }
    }
}

/// The plugin's systems, in `PostUpdate` after transforms propagate and before the asset events
/// are sent: order your own systems that read [`SolveStatus`] after this set.
#[derive(SystemSet, Debug, Clone, PartialEq, Eq, Hash)]
pub struct LucentSystems;

impl Plugin for LucentPlugin {
    fn build(&self, app: &mut App) {
        app.add_plugins(MaterialPlugin::<LucentMaterial>::default());
        match SolvePool::new(self.solve_threads, self.solve_nice) {
            Ok(pool) => {
                app.insert_resource(pool);
            }
            // Without threads no solve can run; the bodies stay black (the systems need the pool).
            Err(e) => error!("lucent: {e}"),
        }
        let shader = Shader::from_wgsl(shader_source(), "lucent_bevy/lucent.wgsl");
        app.world_mut().resource_mut::<Assets<Shader>>().insert(LUCENT_SHADER.id(), shader).ok();
        app.add_systems(
            PostUpdate,
            (systems::collect, systems::attach, systems::start)
                .chain()
                .in_set(LucentSystems)
                .after(TransformSystems::Propagate)
                // The material and buffer a finished solve writes must be in this frame's asset
                // events, which the render world extracts: otherwise it shows a frame later.
                .before(AssetEventSystems),
        );
    }
}
