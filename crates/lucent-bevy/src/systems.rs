//! The plugin's systems, once per frame after transforms propagate: attach a body's state and
//! material, take in finished solves, and start a solve where the mesh, the lights, the
//! material or the camera changed. None of them waits for a solve.

use crate::body::{Finished, Inputs, LucentBody, SolveStatus};
use crate::convert::{Weld, positions};
use crate::lights::{MappedLight, gather};
use crate::material::{LucentMaterial, ShadingUniform, vertex_records};
use crate::{SolvePool, Translucent};
use bevy::asset::RenderAssetUsages;
use bevy::camera::Camera3d;
use bevy::prelude::*;
use bevy::render::storage::ShaderBuffer;
use bevy::tasks::{block_on, poll_once};

/// Gives every new [`Translucent`] entity its state and a [`LucentMaterial`] in place of a
/// `StandardMaterial`.
pub(crate) fn attach(
    mut commands: Commands,
    new: Query<(Entity, &Mesh3d, &Translucent, &GlobalTransform), Without<LucentBody>>,
    meshes: Res<Assets<Mesh>>,
    mut materials: ResMut<Assets<LucentMaterial>>,
    mut buffers: ResMut<Assets<ShaderBuffer>>,
    mut status: Query<&mut SolveStatus>,
) {
    for (entity, mesh3d, translucent, transform) in &new {
        let Some(mesh) = meshes.get(&mesh3d.0) else { continue };
        let made = Weld::new(mesh).and_then(|(m, weld)| {
            let scale_m = translucent.scale_m.unwrap_or_else(|| world_extent(&m, transform));
            let transport = translucent.transport(scale_m)?;
            Ok((m, weld, scale_m, transport))
        });
        let (rest, weld, scale_m, transport) = match made {
            Ok(made) => made,
            Err(e) => {
                match status.get_mut(entity) {
                    Ok(mut s) => report(entity, &mut s, e),
                    Err(_) => {
                        let mut s = SolveStatus::default();
                        report(entity, &mut s, e);
                        commands.entity(entity).insert(s);
                    }
                }
                continue;
            }
        };
        let records = vertex_records(&vec![[0.0; 3]; weld.bevy_vertices()], &[]);
        let buffer = buffers.add(ShaderBuffer::new(bytemuck_records(&records), RenderAssetUsages::default()));
        let material =
            materials.add(LucentMaterial { shading: ShadingUniform::default(), per_vertex: buffer.clone() });
        commands.entity(entity).remove::<MeshMaterial3d<StandardMaterial>>().insert((
            MeshMaterial3d(material.clone()),
            SolveStatus::default(),
            LucentBody {
                mesh: mesh3d.0.id(),
                weld,
                session: None,
                rest: Some(rest),
                task: None,
                sent: None,
                scale_m,
                transport: Some((translucent.clone(), transport)),
                material,
                buffer,
            },
        ));
    }
}

/// Logs why an entity cannot be solved, once (while the reason stays the same), and keeps it in
/// its [`SolveStatus`].
fn report(entity: Entity, status: &mut SolveStatus, e: String) {
    if status.error.as_deref() != Some(e.as_str()) {
        error!("lucent: entity {entity}: {e}");
        status.error = Some(e);
    }
}

/// The mesh's largest side in the world, metres (Bevy units): its local extent times the
/// entity's largest scale.
fn world_extent(mesh: &lucent_core::mesh::Mesh, transform: &GlobalTransform) -> f32 {
    mesh.extent() * transform.scale().abs().max_element()
}

/// The per-vertex records as bytes.
fn bytemuck_records(records: &[[f32; 8]]) -> &[u8] {
    bytemuck::cast_slice(records)
}

/// Takes in every finished solve: its radiance into the body's buffer, its exit lobe and lights
/// into the material, the session back into the body.
pub(crate) fn collect(
    mut bodies: Query<(&mut LucentBody, &Translucent, &mut SolveStatus)>,
    mut materials: ResMut<Assets<LucentMaterial>>,
    mut buffers: ResMut<Assets<ShaderBuffer>>,
) {
    for (mut body, translucent, mut status) in &mut bodies {
        let Some(task) = body.task.as_mut() else { continue };
        let Some(Finished { session, solved, inputs, ms, done }) = block_on(poll_once(task)) else {
            continue;
        };
        body.task = None;
        let eta = session.transport().material.eta as f32;
        body.session = Some(session);
        let records = vertex_records(
            &body.weld.spread(&solved.vertex_radiance),
            &body.weld.spread(&solved.vertex_single),
        );
        if let Some(mut buffer) = buffers.get_mut(&body.buffer) {
            *buffer = ShaderBuffer::new(bytemuck_records(&records), RenderAssetUsages::default());
        }
        if let Some(mut material) = materials.get_mut(&body.material) {
            let highlight = (translucent.specular, translucent.shininess);
            material.shading = ShadingUniform::new(eta, highlight, &inputs.world_lights, &solved);
        }
        let mean = solved.vertex_radiance.iter().map(|r| r.max_element()).sum::<f32>()
            / solved.vertex_radiance.len().max(1) as f32;
        debug!(
            "lucent: solve of {} faces in {ms:.0} ms, mean B/(c pi) {mean:.4e}, lights {:?}",
            solved.face_b.len(),
            inputs.lights
        );
        status.solves += 1;
        status.last_ms = ms;
        status.last_done = Some(done);
        status.solving = false;
        status.error = None;
    }
}

/// The camera the view terms follow: the first active 3D camera.
fn eye(cameras: &Query<(&Camera, &GlobalTransform), With<Camera3d>>) -> Option<Vec3> {
    cameras.iter().find(|(c, _)| c.is_active).map(|(_, t)| t.translation())
}

/// Starts a solve for every idle body whose inputs changed since its last solve.
#[allow(clippy::too_many_arguments)]
pub(crate) fn start(
    mut commands: Commands,
    mut bodies: Query<(Entity, &mut LucentBody, &Translucent, &Mesh3d, &GlobalTransform, &mut SolveStatus)>,
    meshes: Res<Assets<Mesh>>,
    points: Query<(&PointLight, &GlobalTransform)>,
    spots: Query<(&SpotLight, &GlobalTransform)>,
    suns: Query<(&DirectionalLight, &GlobalTransform)>,
    cameras: Query<(&Camera, &GlobalTransform), With<Camera3d>>,
    pool: Option<Res<SolvePool>>,
) {
    // No pool: the plugin logged why at start; nothing can solve.
    let Some(pool) = pool else { return };
    let world_lights = gather(&points, &spots, &suns);
    let eye = eye(&cameras);
    for (entity, mut body, translucent, mesh3d, transform, mut status) in &mut bodies {
        if body.task.is_some() {
            continue;
        }
        let Some(mesh) = meshes.get(&mesh3d.0) else { continue };
        if mesh3d.0.id() != body.mesh || !body.weld.same_topology(mesh) {
            // A new mesh: a new session (attach starts it over).
            commands.entity(entity).remove::<LucentBody>();
            continue;
        }
        let Some(inputs) = inputs(&mut body, translucent, mesh, transform, &world_lights, eye) else {
            continue;
        };
        let inputs = match inputs {
            Ok(inputs) => inputs,
            Err(e) => {
                report(entity, &mut status, e);
                continue;
            }
        };
        if body.sent.as_ref() != Some(&inputs) {
            status.solving = true;
            body.start(inputs, &pool);
        }
    }
}

/// The body's inputs now, `None` if its mesh has no positions, or an error for its material.
fn inputs(
    body: &mut LucentBody,
    translucent: &Translucent,
    mesh: &Mesh,
    transform: &GlobalTransform,
    world_lights: &[MappedLight],
    eye: Option<Vec3>,
) -> Option<Result<Inputs, String>> {
    let positions = body.weld.lucent_positions(positions(mesh).ok()?);
    let transport = match &body.transport {
        Some((t, transport)) if t == translucent => transport.clone(),
        _ => {
            let scale_m = translucent.scale_m.unwrap_or(body.scale_m);
            match translucent.transport(scale_m) {
                Ok(transport) => {
                    body.transport = Some((translucent.clone(), transport.clone()));
                    transport
                }
                Err(e) => return Some(Err(e)),
            }
        }
    };
    let affine = transform.affine();
    let local_from_world = affine.inverse();
    let eye = eye.map(|e| {
        let l = local_from_world.transform_point3(e);
        glam::Vec3::new(l.x, l.y, l.z)
    });
    Some(Ok(Inputs {
        positions,
        lights: world_lights.iter().map(|l| l.to_local(&affine)).collect(),
        world_lights: world_lights.to_vec(),
        transport,
        settings: translucent.settings(),
        eye,
    }))
}
