//! The viewer's only contact with `lucent-core`: mesh loading, deformation, lights and the
//! solve, each behind one small function so that the viewer follows the core's API in one place.

use super::state::{Deformations, LightKind, LightSpec, SolveParams};
use glam::Vec3;
use lucent_core::Rgb;
use lucent_core::bssrdf::Dipole;
use lucent_core::formfactor::FormFactorOptions;
use lucent_core::irradiance::{Light, face_irradiance};
use lucent_core::mesh::Mesh;
use lucent_core::shading::diffuse_radiance;
use lucent_core::solver::exact;
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
    /// Shadowed irradiance.
    pub shadows: bool,
    /// Spherical-harmonic environment light.
    pub environment: bool,
    /// Spot-light cones.
    pub spot_lights: bool,
    /// True Perlin noise deformation (else a smooth stand-in).
    pub perlin_noise: bool,
}

/// This build's capabilities.
pub const CAPABILITIES: Capabilities = Capabilities {
    hierarchical: false,
    shadows: false,
    environment: false,
    spot_lights: false,
    perlin_noise: false,
};

/// The mesh shown when no `--mesh` is given.
pub fn default_mesh() -> Mesh {
    icosphere(2)
}

/// Loads a mesh file (naming the file in the error).
pub fn load_mesh(path: &Path) -> anyhow::Result<Mesh> {
    Ok(lucent_core::mesh::load_mesh(path)?)
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

/// `base` with the deformations applied (dents, then twist, then noise along the normal).
pub fn deform(base: &Mesh, d: &Deformations) -> Mesh {
    let mut mesh = base.clone();
    for dent in &d.dents {
        for p in &mut mesh.positions {
            let r2 = (*p - dent.center).length_squared() / (dent.radius * dent.radius);
            // Smooth bump exp(-r^2 / (2 s^2)) with s = radius / 2, cut off beyond the radius.
            if r2 < 1.0 {
                *p += dent.normal * dent.height * (-2.0 * r2).exp() * (1.0 - r2);
            }
        }
    }
    if d.twist != 0.0 {
        for p in &mut mesh.positions {
            let (s, c) = (d.twist * p.y).sin_cos();
            *p = Vec3::new(c * p.x + s * p.z, p.y, -s * p.x + c * p.z);
        }
    }
    if d.noise_amplitude != 0.0 {
        let normals = mesh.vertex_normals();
        for (p, n) in mesh.positions.iter_mut().zip(normals) {
            *p += n * d.noise_amplitude * smooth_noise(*p * 4.0 + Vec3::splat(d.noise_offset));
        }
    }
    mesh
}

/// A smooth band-limited pseudo-noise in -1..1 (a stand-in for 3D Perlin noise).
fn smooth_noise(p: Vec3) -> f32 {
    let a = (p.x * 1.7 + p.y * 0.3).sin() * (p.y * 1.3 - p.z * 0.7).sin();
    let b = (p.z * 2.1 + p.x * 0.5).sin() * (p.x * 0.9 + p.y * 1.9).cos();
    0.5 * (a + b)
}

/// The core's lights for the UI's list. A spot light is a point light whose cone is not yet
/// modelled by the core's irradiance.
pub fn core_lights(lights: &[LightSpec]) -> Vec<Light> {
    lights
        .iter()
        .map(|l| match l.kind {
            LightKind::Point | LightKind::Spot => {
                Light::Point { position: l.position, intensity: l.color * l.power }
            }
            LightKind::Directional => {
                Light::Directional { direction: l.direction, irradiance: l.color * l.power }
            }
        })
        .collect()
}

/// Solver state the worker keeps between requests (the hierarchy and links that render and
/// incremental modes reuse live here).
#[derive(Default)]
pub struct SolverSession {}

impl SolverSession {
    /// Solves for the per-vertex radiance of `mesh` under `params`.
    pub fn solve(&mut self, mesh: &Arc<Mesh>, params: &SolveParams) -> Solution {
        solve_exact(mesh, params)
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

/// The exact O(N^2) solve (every face against every face).
fn solve_exact(mesh: &Mesh, params: &SolveParams) -> Solution {
    let dipole = Dipole::for_model_scale(&params.material, mesh.extent() as f64, params.scale_m);
    let mut timings = Timings::default();

    let t = Instant::now();
    let lights = core_lights(&params.lights);
    let e = face_irradiance(mesh, &lights, params.material.eta);
    timings.irradiance_ms = ms_since(t);

    let t = Instant::now();
    let b = exact::solve(mesh, &dipole, &e, &FormFactorOptions::default());
    timings.gather_ms = ms_since(t);

    let t = Instant::now();
    let vertex_radiance = diffuse_radiance(&mesh.face_to_vertex(&b));
    timings.push_ms = ms_since(t);

    Solution { vertex_radiance, timings, links: None, solver: "exact O(N^2)", clusters: None }
}

fn ms_since(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// A unit-radius icosphere with `subdivisions` levels (20 * 4^n triangles).
fn icosphere(subdivisions: u32) -> Mesh {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let mut positions: Vec<Vec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| Vec3::new(x, y, z).normalize())
    .collect();
    let mut triangles: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        let mut midpoint = std::collections::HashMap::new();
        let mut mid = |a: u32, b: u32, positions: &mut Vec<Vec3>| -> u32 {
            *midpoint.entry((a.min(b), a.max(b))).or_insert_with(|| {
                let p = (positions[a as usize] + positions[b as usize]).normalize();
                positions.push(p);
                positions.len() as u32 - 1
            })
        };
        let mut next = Vec::with_capacity(triangles.len() * 4);
        for [a, b, c] in triangles {
            let ab = mid(a, b, &mut positions);
            let bc = mid(b, c, &mut positions);
            let ca = mid(c, a, &mut positions);
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        triangles = next;
    }
    Mesh::new(positions, triangles)
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

    #[test]
    fn icosphere_is_closed_with_euler_characteristic_two() {
        let m = icosphere(2);
        // V - E + F = 2 for a sphere; every edge is shared by two faces, so E = 3F/2.
        let (v, f) = (m.positions.len() as i64, m.triangles.len() as i64);
        assert_eq!(f, 320);
        assert_eq!(v - 3 * f / 2 + f, 2);
        // Counter-clockwise from outside: normals point away from the centre.
        assert!((0..m.triangles.len()).all(|i| m.face_normal(i).dot(m.face_centroid(i)) > 0.0));
    }
}
