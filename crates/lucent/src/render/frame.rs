//! One frame of the Mertens 2003 path, split so that an animation reuses what it can:
//! [`FrameSolver`] keeps the shadow BVH (refitted) and the hierarchical solver with its links
//! (§5.5: made once, updated per frame); [`GpuFrame`] keeps the device, targets, mesh buffers and
//! environment map, and uploads only what changed.

use super::output::{Frame, HdrImage};
use super::setup::Scene;
use crate::cli::{ImageFormat, Method, SolveMode};
use anyhow::{Result, bail};
use lucent_core::Rgb;
use lucent_core::formfactor::FormFactorOptions;
use lucent_core::irradiance::{SceneLight, ShadowCaster, face_irradiance_shadowed, interreflection};
use lucent_core::mesh::Mesh;
use lucent_core::shading;
use lucent_core::solver::{self, HierarchicalSolver, Oracle};
use lucent_gpu::GpuContext;
use lucent_gpu::camera::CameraView;
use lucent_gpu::mesh_pass::{EnvironmentMap, GpuMesh, Shading};
use lucent_gpu::offscreen::OffscreenRenderer;
use lucent_gpu::tonemap::ToneMap;
use std::time::Instant;

/// What one solve produced and what it took.
pub struct Solved {
    /// Diffuse exitant radiance `B / pi` per vertex (before the exit Fresnel factor).
    pub vertex_radiance: Vec<Rgb>,
    /// Irradiance at the leaves (lights, shadow rays, environment), milliseconds.
    pub irradiance_ms: f64,
    /// Link creation or update (hierarchical render and incremental modes), milliseconds.
    pub link_ms: f64,
    /// Pull, gather and push (or the whole O(N^2) exact solve) and the vertex average, ms.
    pub solve_ms: f64,
    /// Links of the hierarchical solve (`None` for the exact solver).
    pub links: Option<usize>,
}

impl Solved {
    /// Everything on the CPU, milliseconds.
    pub fn total_ms(&self) -> f64 {
        self.irradiance_ms + self.link_ms + self.solve_ms
    }
}

/// The CPU side across frames: shadow caster and solver state.
pub struct FrameSolver<'a> {
    scene: &'a Scene,
    method: Method,
    mode: SolveMode,
    caster: Option<ShadowCaster>,
    caster_positions: Vec<glam::Vec3>,
    hierarchical: Option<HierarchicalSolver>,
    /// Whether the caster shadows lights and the environment (it may exist for bounces alone).
    shadows: bool,
}

impl<'a> FrameSolver<'a> {
    /// A solver for `scene`'s rest mesh (the hierarchy is built on it once), refining with
    /// `oracle`.
    pub fn new(scene: &'a Scene, method: Method, mode: SolveMode, oracle: Oracle) -> Result<Self> {
        if method == Method::Htsm {
            bail!("--method htsm has no per-face solve");
        }
        let hierarchical = (method == Method::Hierarchical).then(|| {
            let h = match &scene.hierarchy {
                Some(h) => h.clone(),
                None => lucent_core::hierarchy::face_cluster::build(&scene.mesh),
            };
            let mut s = HierarchicalSolver::new(scene.mesh.clone(), h, scene.dipole.clone(), oracle);
            s.ff_opts = FormFactorOptions::default();
            s
        });
        let shadows = scene.lights.iter().any(|l| l.shadows)
            || (scene.environment.is_some() && scene.environment_shadows);
        Ok(FrameSolver {
            scene,
            method,
            mode,
            caster: (shadows || scene.bounces > 0).then(|| ShadowCaster::new(&scene.mesh)),
            caster_positions: scene.mesh.positions.clone(),
            hierarchical,
            shadows,
        })
    }

    /// Solves `mesh` (the rest mesh or a deformation of it: same topology) under `lights` and
    /// the scene's environment.
    pub fn solve(&mut self, mesh: &Mesh, lights: &[SceneLight]) -> Result<Solved> {
        let t = Instant::now();
        if let Some(c) = &mut self.caster
            && self.caster_positions != mesh.positions
        {
            c.update(mesh);
            self.caster_positions.clone_from(&mesh.positions);
        }
        let env = self.scene.environment.as_ref().map(|e| &e.environment);
        let caster = self.caster.as_ref().filter(|_| self.shadows);
        let e = face_irradiance_shadowed(mesh, lights, env, &self.scene.dipole.entry, caster);
        let irradiance_ms = ms_since(t);

        let t = Instant::now();
        let (mut b, link_ms, links) = self.solve_once(mesh, &e);
        // Each bounce: the light the last solve sent out, caught by facing parts, solved again
        // (the solve is linear in the irradiance; render and incremental modes reuse the links).
        let mut last = b.clone();
        for _ in 0..self.scene.bounces {
            let Some(c) = &self.caster else { break };
            let e2 = interreflection::bounced_irradiance(mesh, c, &last, &self.scene.dipole);
            last = self.solve_once(mesh, &e2).0;
            b.iter_mut().zip(&last).for_each(|(b, l)| *b += *l);
        }
        let vertex_radiance = shading::diffuse_radiance(&mesh.face_to_vertex(&b), &self.scene.dipole);
        let solve_ms = (ms_since(t) - link_ms).max(0.0);
        Ok(Solved { vertex_radiance, irradiance_ms, link_ms, solve_ms, links })
    }

    /// `B` per face for irradiance `e` by the scene's method: `(B, link ms, links)`.
    fn solve_once(&mut self, mesh: &Mesh, e: &[Rgb]) -> (Vec<Rgb>, f64, Option<usize>) {
        match (self.method, &mut self.hierarchical) {
            (Method::Hierarchical, Some(s)) => solve_hierarchical(s, self.mode, mesh, e),
            _ => {
                let opts = FormFactorOptions::default();
                (solver::exact::solve(mesh, &self.scene.dipole, e, &opts), 0.0, None)
            }
        }
    }
}

/// Mertens §5.5 over frames: on-the-fly refines from scratch each time; render mode keeps the
/// links while the geometry stays put and relinks when it moves; incremental mode links once
/// and re-evaluates only the links that the deformation touched. Returns `(B per face, link
/// ms, links)`.
fn solve_hierarchical(
    s: &mut HierarchicalSolver,
    mode: SolveMode,
    mesh: &Mesh,
    e: &[Rgb],
) -> (Vec<Rgb>, f64, Option<usize>) {
    let moved = s.mesh.positions != mesh.positions;
    let t = Instant::now();
    let mut link_ms = 0.0;
    let sol = match mode {
        SolveMode::OnTheFly => {
            if moved {
                s.set_positions(&mesh.positions);
            }
            s.solve_on_the_fly(e)
        }
        SolveMode::Render => {
            if moved || s.links().is_none() {
                s.set_positions(&mesh.positions);
                s.link();
            }
            link_ms = ms_since(t);
            s.solve_render(e)
        }
        SolveMode::Incremental => {
            if s.links().is_none() {
                // Links on the rest pose first, so that the update below is incremental.
                s.link();
            }
            let st = s.update_incremental(&mesh.positions, None);
            log::info!("incremental update: {} links, {:.1} ms", st.links, st.total_ms);
            link_ms = ms_since(t);
            s.solve_render(e)
        }
    };
    log::info!("hierarchical ({mode:?}): {} links, {:.1} ms", sol.stats.links, sol.stats.total_ms);
    (sol.face_b, link_ms, Some(sol.stats.links))
}

/// The GPU side across frames.
pub struct GpuFrame {
    ctx: GpuContext,
    renderer: OffscreenRenderer,
    mesh: GpuMesh,
    camera: CameraView,
    shading: Shading,
    tone: ToneMap,
    // Kept alive for the mesh pass's bind group.
    _environment: Option<EnvironmentMap>,
}

impl GpuFrame {
    /// Targets of `width` x `height`, `mesh` uploaded with `radiance`, the environment map (if
    /// any) set for the reflection (unless the scene has no surface term) and, with
    /// `env_background`, drawn behind the mesh, and the camera framed on the scene's rest mesh
    /// (fixed over an animation).
    pub fn new(
        ctx: GpuContext,
        scene: &Scene,
        (width, height): (u32, u32),
        tone: ToneMap,
        mesh: &Mesh,
        radiance: &[Rgb],
        env_background: bool,
    ) -> Result<Self> {
        let normals = mesh.vertex_normals();
        let gpu_mesh = GpuMesh::new(&ctx, &mesh.positions, &normals, radiance, &mesh.triangles)?;
        let mut renderer = OffscreenRenderer::new(&ctx, width, height)?;
        let (center, radius) = lucent_gpu::camera::bounding_sphere(&scene.mesh.positions);
        let camera = scene.camera.frame(center, radius, width as f32 / height as f32);
        let mut shading = Shading {
            eta: scene.material.eta as f32,
            lights: scene.plain_lights(),
            specular: if scene.surface { 1.0 } else { 0.0 },
            ..Default::default()
        };
        let environment = match &scene.environment {
            Some(env) => {
                let (w, h) = (env.reflection.width as u32, env.reflection.height as u32);
                let map = EnvironmentMap::from_rgba_f32(&ctx, w, h, &env.reflection_rgba())?;
                renderer.mesh_pass_mut().set_environment(&ctx, &map);
                if scene.surface {
                    shading.environment = env.environment.intensity;
                }
                if env_background {
                    shading.background = env.environment.intensity;
                }
                Some(map)
            }
            None => None,
        };
        Ok(GpuFrame { ctx, renderer, mesh: gpu_mesh, camera, shading, tone, _environment: environment })
    }

    /// Draws the mesh with new per-vertex `radiance`, new geometry (`mesh`, when it moved) and
    /// `lights` for the highlight, and reads the frame back: the tone-mapped image, or for
    /// [`ImageFormat::Exr`] the HDR radiance and coverage with nothing behind the object.
    pub fn draw(
        &mut self,
        mesh: Option<&Mesh>,
        radiance: &[Rgb],
        lights: &[SceneLight],
        format: ImageFormat,
    ) -> Result<Frame> {
        if let Some(m) = mesh {
            self.mesh.update_geometry(&self.ctx, &m.positions, &m.vertex_normals())?;
        }
        self.mesh.update_radiance(&self.ctx, radiance)?;
        self.shading.lights = lights.iter().map(|l| l.light).collect();
        if format == ImageFormat::Exr {
            // The background would cover alpha and bleed into the object's edge pixels.
            let shading = Shading { background: 0.0, ..self.shading.clone() };
            self.renderer.render(&self.ctx, &self.mesh, &self.camera, &shading, &self.tone)?;
            let (width, height) = self.renderer.size();
            let pixels = self.renderer.read_hdr(&self.ctx)?;
            return Ok(Frame::Hdr(HdrImage { width, height, pixels }));
        }
        self.renderer.render(&self.ctx, &self.mesh, &self.camera, &self.shading, &self.tone)?;
        Ok(Frame::Ldr(self.renderer.read_image(&self.ctx)?))
    }

    /// The adapter, for the summary line.
    pub fn adapter(&self) -> String {
        self.ctx.describe()
    }
}

fn ms_since(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}
