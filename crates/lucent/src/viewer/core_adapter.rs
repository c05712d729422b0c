//! The viewer's only contact with `lucent-core`: normalising and deforming the mesh, and the
//! solve through the one frame session, so that the viewer follows the core's API in one place.

use super::state::{Deformations, EnvChoice, SolveParams};
use lucent_core::Rgb;
use lucent_core::irradiance::{Environment, SceneLight};
use lucent_core::mesh::Mesh;
use lucent_core::mesh::deform::{Deformation, Deformer as _};
use lucent_core::session::{FrameSession, Solved, ViewTerms};
use lucent_core::solver::{HierarchicalSolver, Progress};
use std::sync::Arc;

/// What one solve returns: the frame session's [`Solved`] and what the viewer adds to it.
#[derive(Clone, Debug, Default)]
pub struct Solution {
    /// The session's solve (per-vertex radiance and single scattering, exit lobe, timings,
    /// links).
    pub solved: Solved,
    /// Figure 6.9 false colours per vertex: the clusters the picked face gathers from, coloured
    /// by hierarchy level ([`level_colour`]); `None` when that view is off or unsupported.
    pub clusters: Option<Vec<Rgb>>,
}

/// Centres `mesh` at the origin and scales it to a bounding-box extent of 1, so that light
/// positions, dent radii and camera distances mean the same for every model. The physical size
/// comes from the model scale alone, so this changes nothing in the solution.
pub fn normalise(mut mesh: Mesh) -> Mesh {
    let (lo, hi) = mesh.bounds();
    let centre = 0.5 * (lo + hi);
    let extent = mesh.extent();
    let k = if extent > 0.0 { 1.0 / extent } else { 1.0 };
    mesh.positions.iter_mut().for_each(|p| *p = (*p - centre) * k);
    mesh
}

/// `base` with the deformations applied in order: dents (bumps of negative height along the
/// vertex normal), twist about the vertical axis through the centre of the bounding box, Perlin
/// noise along the normal (Mertens figures 6.5-6.8).
pub fn deform(base: &Mesh, d: &Deformations) -> Mesh {
    let mut mesh = base.clone();
    for dent in &d.dents {
        mesh = dent.deformed(&mesh);
    }
    if d.twist_degrees != 0.0 {
        let mut positions = Vec::new();
        Deformation::Twist { degrees: d.twist_degrees }.apply(&mesh, 1.0, &mut positions);
        mesh = Mesh::new(positions, mesh.triangles);
    }
    if d.noise.amplitude != 0.0 {
        mesh = d.noise.deformed(&mesh);
    }
    mesh
}

/// The viewer's side of the one frame session (`lucent_core::session::FrameSession`): it turns
/// the panel's [`SolveParams`] into the session's transport, settings, lights and environment,
/// and keeps the environment's SH projection (redone only when the map changes).
#[derive(Default)]
pub struct SolverSession {
    session: Option<FrameSession>,
    environment: EnvCache,
    /// Where long solves count their progress for the panel.
    progress: Option<Arc<Progress>>,
    /// The mesh texture's entry factor per face (irradiance times it before the solve), if any.
    entry: Option<Vec<lucent_core::Rgb>>,
}

/// The environment of the panel's choice, its SH projection made when the choice changes.
#[derive(Default)]
pub struct EnvCache(Option<(EnvChoice, Option<Environment>)>);

impl EnvCache {
    /// The environment of `params` (choice, rotation, strength), loaded and projected on first
    /// use. A missing or bad map is logged and lights nothing.
    pub fn get(&mut self, params: &SolveParams) -> Option<Environment> {
        let choice = params.env;
        if self.0.as_ref().is_none_or(|(c, _)| *c != choice) {
            let env = choice.load().and_then(|r| match r {
                Ok(map) => Some(Environment::from_map(&map)),
                Err(e) => {
                    log::warn!("environment {}: {e}", choice.label());
                    None
                }
            });
            self.0 = Some((choice, env));
        }
        let env = self.0.as_ref().and_then(|(_, env)| *env)?;
        Some(Environment { rotation_deg: params.env_rotation_deg, intensity: params.env_strength, ..env })
    }
}

impl SolverSession {
    /// A session whose long solves count their progress on `progress`.
    pub fn with_progress(progress: Arc<Progress>) -> Self {
        SolverSession { progress: Some(progress), ..Default::default() }
    }

    /// Sets the texture's entry factor per face of the meshes solved from now on (their
    /// topology is the loaded mesh's: deformations move vertices only).
    pub fn set_entry_factors(&mut self, entry: Option<Vec<lucent_core::Rgb>>) {
        self.entry = entry;
        self.session = None;
    }

    /// Solves for the per-vertex radiance of `mesh` (the session's rest mesh or a deformation
    /// of it; a new topology starts a new session) under `params`.
    pub fn solve(&mut self, mesh: &Arc<Mesh>, params: &SolveParams) -> Solution {
        let environment = self.environment.get(params);
        let (transport, settings) = (params.transport.clone(), params.settings);
        let same_topology = self.session.as_ref().is_some_and(|s| {
            s.mesh().triangles == mesh.triangles && s.mesh().positions.len() == mesh.positions.len()
        });
        if !same_topology {
            let mut session = FrameSession::new((**mesh).clone(), None, transport.clone(), settings);
            session.set_progress(self.progress.clone());
            // Orbiting the camera re-evaluates closed forms, no ray (`shading::view_basis`).
            session.set_view_terms(ViewTerms::Split);
            session.set_entry_factors(self.entry.clone().filter(|e| e.len() == mesh.triangles.len()));
            self.session = Some(session);
        }
        let session = self.session.as_mut().expect("made above");
        session.set_positions(&mesh.positions);
        session.set_transport(transport);
        session.set_settings(settings);
        session.set_lights(
            params
                .lights
                .iter()
                .map(|&light| SceneLight { light, shadows: settings.environment_shadows })
                .collect(),
        );
        session.set_environment(environment);
        session.set_eye(params.eye);
        let solved = session.solve().clone();
        let clusters = params
            .cluster_face
            .and_then(|f| session.hierarchical().and_then(|s| cluster_colours(s, f as usize)));
        Solution { solved, clusters }
    }
}

/// A distinct display colour for hierarchy level `level` (0 = root), for the figure 6.9 view.
pub fn level_colour(level: usize) -> Rgb {
    const PALETTE: [[f32; 3]; 8] = [
        [0.90, 0.10, 0.10],
        [0.95, 0.55, 0.05],
        [0.90, 0.85, 0.10],
        [0.20, 0.75, 0.20],
        [0.10, 0.70, 0.80],
        [0.15, 0.30, 0.90],
        [0.60, 0.20, 0.85],
        [0.90, 0.40, 0.70],
    ];
    Rgb::from_array(PALETTE[level % PALETTE.len()])
}

/// Figure 6.9: per-vertex colours showing the clusters that face `face` gathers from (the
/// links of its leaf and of every ancestor), each coloured by its hierarchy level; faces it
/// does not gather from are dark grey, the face itself white. Needs stored links.
fn cluster_colours(solver: &HierarchicalSolver, face: usize) -> Option<Vec<Rgb>> {
    let links = solver.links()?;
    let h = &solver.hierarchy;
    let mesh = &solver.mesh;
    let mut colours = vec![Rgb::splat(0.08); mesh.triangles.len()];
    let mut r = *h.face_node.get(face)? as usize;
    loop {
        for link in links.links_of(r) {
            let e = &h.nodes[link.emitter];
            let c = level_colour(e.level as usize);
            for leaf in e.leaf_start..e.leaf_end {
                colours[h.leaf_faces[leaf as usize] as usize] = c;
            }
        }
        let parent = h.nodes[r].parent;
        if parent as usize >= h.nodes.len() {
            break;
        }
        r = parent as usize;
    }
    colours[face] = Rgb::ONE;
    Some(mesh.face_to_vertex(&colours))
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn normalise_gives_unit_extent_centred() {
        let m = normalise(Mesh::new(vec![Vec3::new(1.0, 2.0, 3.0), Vec3::new(5.0, 3.0, 4.0)], vec![]));
        let (lo, hi) = m.bounds();
        assert!((m.extent() - 1.0).abs() < 1e-6);
        assert!((lo + hi).length() < 1e-6);
    }
}
