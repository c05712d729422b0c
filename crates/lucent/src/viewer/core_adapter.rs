//! The viewer's only contact with `lucent-core`: mesh loading, deformation, lights and the
//! solve, each behind one small function so that the viewer follows the core's API in one place.

use super::state::{Deformations, EnvChoice, LightKind, LightSpec, SolveParams, SolverMode};
use glam::Vec3;
use lucent_core::Rgb;
use lucent_core::bssrdf::Dipole;
use lucent_core::hierarchy::face_cluster;
use lucent_core::irradiance::{Environment, Light, SceneLight, ShadowCaster, face_irradiance_shadowed};
use lucent_core::mesh::deform::{self, Deformer as _};
use lucent_core::mesh::{Mesh, embedded, generate};
use lucent_core::shading::diffuse_radiance;
use lucent_core::solver::{HierarchicalSolver, Oracle, SolveStats};
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

/// Per-phase wall-clock times of one solve, milliseconds. Phases the active solver does not
/// have are 0.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Timings {
    /// Irradiance at the leaves (lights, shadows, environment).
    pub irradiance_ms: f64,
    /// Link creation or refinement (hierarchical solver).
    pub link_ms: f64,
    /// Pulling irradiance up the hierarchy.
    pub pull_ms: f64,
    /// Gathering along the links (the whole O(N^2) sum for the exact solver).
    pub gather_ms: f64,
    /// Pushing results down to the leaves and averaging them at the vertices.
    pub push_ms: f64,
}

impl Timings {
    /// Sum of the phases, milliseconds.
    pub fn total_ms(&self) -> f64 {
        self.irradiance_ms + self.link_ms + self.pull_ms + self.gather_ms + self.push_ms
    }
}

/// What one solve returns.
#[derive(Clone, Debug, Default)]
pub struct Solution {
    /// Diffuse exitant radiance `B / pi` per vertex (before the exit Fresnel factor).
    pub vertex_radiance: Vec<Rgb>,
    /// Per-phase times.
    pub timings: Timings,
    /// Number of links of the hierarchical solve; `None` for solvers without links.
    pub links: Option<usize>,
    /// Name of the solver that ran, for the UI.
    pub solver: &'static str,
    /// Figure 6.9 false colours per vertex: the clusters the picked face gathers from, coloured
    /// by hierarchy level ([`level_colour`]); `None` when that view is off or unsupported.
    pub clusters: Option<Vec<Rgb>>,
}

/// What the linked core modules can do; the panel greys out or explains what they cannot.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Capabilities {
    /// The hierarchical solver with its three modes, timings and link count.
    pub hierarchical: bool,
}

/// This build's capabilities.
pub const CAPABILITIES: Capabilities = Capabilities { hierarchical: true };

/// The mesh shown when no `--mesh` is given: the embedded Stanford bunny when the
/// hierarchical solver is linked, else a coarse sphere the O(N^2) solve handles interactively.
pub fn default_mesh() -> Mesh {
    if CAPABILITIES.hierarchical { embedded::bunny() } else { generate::icosphere(2) }
}

/// Loads a mesh file (naming the file in the error; warnings go to stderr).
pub fn load_mesh(path: &Path) -> anyhow::Result<Mesh> {
    crate::scene::load_mesh_file(path)
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

/// Spatial frequency of the noise deformation, noise cells per mesh unit (the mesh has extent 1).
const NOISE_FREQUENCY: f32 = 4.0;

/// `base` with the deformations applied in order: dents (bumps of negative height along the
/// vertex normal), twist about the vertical axis through the origin, Perlin noise along the
/// normal (Mertens figures 6.5-6.8).
pub fn deform(base: &Mesh, d: &Deformations) -> Mesh {
    let mut mesh = base.clone();
    for dent in &d.dents {
        mesh = deform::bump(dent.center, dent.radius, dent.height).deformed(&mesh);
    }
    if d.twist != 0.0 {
        mesh = deform::twist(Vec3::ZERO, Vec3::Y, d.twist).deformed(&mesh);
    }
    if d.noise_amplitude != 0.0 {
        let offset = Vec3::splat(d.noise_offset);
        mesh = deform::noise(d.noise_amplitude, NOISE_FREQUENCY, offset).deformed(&mesh);
    }
    mesh
}

/// Fraction of a spot cone's angle over which its edge fades out.
const SPOT_SOFT_EDGE: f32 = 0.2;

/// The core's lights for the UI's list.
pub fn core_lights(lights: &[LightSpec]) -> Vec<Light> {
    lights
        .iter()
        .map(|l| match l.kind {
            LightKind::Point => Light::Point { position: l.position, intensity: l.color * l.power },
            LightKind::Spot => Light::Spot {
                position: l.position,
                direction: l.direction,
                intensity: l.color * l.power,
                cone_angle: l.spot_angle_deg.to_radians(),
                soft_edge: SPOT_SOFT_EDGE,
            },
            LightKind::Directional => {
                Light::Directional { direction: l.direction, irradiance: l.color * l.power }
            }
        })
        .collect()
}

/// Solver state the worker keeps between requests: the shadow caster's BVH (refitted when the
/// mesh deforms) and the environment's SH projection (redone only when the map changes).
#[derive(Default)]
pub struct SolverSession {
    shadows: Option<(ShadowCaster, usize)>,
    environment: Option<(EnvChoice, Option<Environment>)>,
    hierarchical: Option<Hierarchical>,
    /// The last profile made and what it was made for: a tabulated profile costs ~50 ms, too
    /// much to redo every frame.
    profile: Option<(ProfileKey, Dipole)>,
}

/// What a [`Dipole`] is made from.
#[derive(Clone, Debug, PartialEq)]
struct ProfileKey {
    material: lucent_core::bssrdf::Material,
    extent: f32,
    scale_m: f64,
    kind: lucent_core::bssrdf::ProfileKind,
    single_scattering: bool,
}

/// The hierarchical solver with what its links were made for.
struct Hierarchical {
    solver: HierarchicalSolver,
    dipole: Dipole,
    eps: (f64, f64),
}

impl SolverSession {
    /// Solves for the per-vertex radiance of `mesh` under `params`.
    pub fn solve(&mut self, mesh: &Arc<Mesh>, params: &SolveParams) -> Solution {
        let t = Instant::now();
        let e = self.irradiance(mesh, params);
        let irradiance_ms = ms_since(t);
        let mut solution = self.solve_hierarchical(mesh, params, &e);
        solution.timings.irradiance_ms = irradiance_ms;
        solution
    }

    /// Mertens §5.5: on-the-fly traverses from scratch; render reuses the links and relinks
    /// from scratch after a geometry, material or threshold change; incremental re-evaluates
    /// only the links that the change touched.
    fn solve_hierarchical(&mut self, mesh: &Mesh, params: &SolveParams, e: &[Rgb]) -> Solution {
        let dipole = self.dipole_for(mesh, params);
        let eps = (params.epsilon1, params.epsilon2);
        let h = self.hierarchy_for(mesh, dipole.clone(), eps);
        let moved = h.solver.mesh.positions != mesh.positions;
        let changed = moved || h.dipole != dipole || h.eps != eps;
        let mut link_stats = SolveStats::default();
        let solution = match params.mode {
            SolverMode::OnTheFly => {
                move_to(&mut h.solver, mesh, moved);
                h.solver.dipole = dipole.clone();
                h.solver.solve_on_the_fly(e)
            }
            SolverMode::Render => {
                if changed || h.solver.links().is_none() {
                    move_to(&mut h.solver, mesh, moved);
                    h.solver.dipole = dipole.clone();
                    link_stats = h.solver.link();
                }
                h.solver.solve_render(e)
            }
            SolverMode::Incremental => {
                if h.dipole != dipole {
                    h.solver.set_dipole(dipole.clone());
                }
                if h.eps != eps {
                    h.solver.link();
                }
                link_stats = h.solver.update_incremental(&mesh.positions, None);
                h.solver.solve_render(e)
            }
        };
        h.dipole = dipole;
        h.eps = eps;
        let s = solution.stats;
        let clusters = params.cluster_face.and_then(|f| cluster_colours(&h.solver, f as usize));
        Solution {
            vertex_radiance: diffuse_radiance(&mesh.face_to_vertex(&solution.face_b), &h.dipole),
            timings: Timings {
                irradiance_ms: 0.0,
                link_ms: s.link_ms + link_stats.link_ms,
                pull_ms: s.pull_ms,
                gather_ms: s.gather_ms,
                push_ms: s.push_ms,
            },
            links: Some(s.links),
            solver: "hierarchical",
            clusters,
        }
    }

    /// The profile for `params` on `mesh`, made when the material, scale or profile changed.
    fn dipole_for(&mut self, mesh: &Mesh, params: &SolveParams) -> Dipole {
        let key = ProfileKey {
            material: params.material.clone(),
            extent: mesh.extent(),
            scale_m: params.scale_m,
            kind: params.profile,
            single_scattering: params.single_scattering,
        };
        if self.profile.as_ref().is_none_or(|(k, _)| *k != key) {
            let d = Dipole::profile_for_model_scale(
                &key.material,
                key.extent as f64,
                key.scale_m,
                key.kind,
                key.single_scattering,
            );
            self.profile = Some((key, d));
        }
        self.profile.as_ref().expect("made above").1.clone()
    }

    /// The solver for `mesh`'s topology, built (hierarchy and all) when the topology changed.
    fn hierarchy_for(&mut self, mesh: &Mesh, dipole: Dipole, eps: (f64, f64)) -> &mut Hierarchical {
        let kind = dipole.profile;
        let same = self.hierarchical.as_ref().is_some_and(|h| {
            h.solver.mesh.triangles == mesh.triangles && h.solver.mesh.positions.len() == mesh.positions.len()
        });
        if !same {
            let oracle =
                Oracle { eps1: eps.0 as f32, eps2: eps.1 as f32, ..Oracle::for_profile(dipole.profile) };
            let solver =
                HierarchicalSolver::new(mesh.clone(), face_cluster::build(mesh), dipole.clone(), oracle);
            self.hierarchical = Some(Hierarchical { solver, dipole, eps });
        }
        let h = self.hierarchical.as_mut().expect("set above");
        h.solver.oracle = Oracle { eps1: eps.0 as f32, eps2: eps.1 as f32, ..Oracle::for_profile(kind) };
        h
    }

    /// Fresnel-transmitted irradiance at the face midpoints (Mertens §5.3): lights, shadowed
    /// by the mesh when asked, plus the environment's SH irradiance.
    fn irradiance(&mut self, mesh: &Mesh, params: &SolveParams) -> Vec<Rgb> {
        let lights: Vec<SceneLight> = core_lights(&params.lights)
            .into_iter()
            .map(|light| SceneLight { light, shadows: params.shadows })
            .collect();
        let environment = self.environment(params.env).map(|env| Environment {
            rotation_deg: params.env_rotation_deg,
            intensity: params.env_strength,
            ..env
        });
        let entry = self.dipole_for(mesh, params).entry;
        let caster = params.shadows.then(|| self.shadow_caster(mesh));
        face_irradiance_shadowed(mesh, &lights, environment.as_ref(), &entry, caster)
    }

    fn shadow_caster(&mut self, mesh: &Mesh) -> &ShadowCaster {
        let faces = mesh.triangles.len();
        match &mut self.shadows {
            Some((caster, n)) if *n == faces => {
                caster.update(mesh);
            }
            slot => *slot = Some((ShadowCaster::new(mesh), faces)),
        }
        &self.shadows.as_ref().expect("set above").0
    }

    /// The environment for `choice`, loaded and projected on first use. A missing or bad map
    /// is logged and lights nothing.
    fn environment(&mut self, choice: EnvChoice) -> Option<Environment> {
        if self.environment.as_ref().is_none_or(|(c, _)| *c != choice) {
            let env = choice.load().and_then(|r| match r {
                Ok(map) => Some(Environment::from_map(&map)),
                Err(e) => {
                    log::warn!("environment {}: {e}", choice.label());
                    None
                }
            });
            self.environment = Some((choice, env));
        }
        self.environment.as_ref().and_then(|(_, env)| *env)
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

/// Moves the solver's mesh to `mesh`'s positions and refits the hierarchy (if `moved`).
fn move_to(solver: &mut HierarchicalSolver, mesh: &Mesh, moved: bool) {
    if moved {
        solver.mesh.positions.copy_from_slice(&mesh.positions);
        solver.hierarchy.refit(&solver.mesh);
    }
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

fn ms_since(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normalise_gives_unit_extent_centred() {
        let m = normalise(Mesh::new(vec![Vec3::new(1.0, 2.0, 3.0), Vec3::new(5.0, 3.0, 4.0)], vec![]));
        let (lo, hi) = m.bounds();
        assert!((m.extent() - 1.0).abs() < 1e-6);
        assert!((lo + hi).length() < 1e-6);
    }
}
