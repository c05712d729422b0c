//! The GPU side of a Mertens 2003 frame across frames (§5.4): [`GpuFrame`] keeps the device,
//! targets, mesh buffers and environment map, and uploads only what changed. The CPU side is
//! `lucent_core::session::FrameSession`. `lucent render` and the Python module draw through it.

use crate::output::{Frame, HdrImage};
use crate::scene::Scene;
use anyhow::Result;
use lucent_core::Rgb;
use lucent_core::camera::CameraView;
use lucent_core::irradiance::SceneLight;
use lucent_core::mesh::Mesh;
use lucent_core::mesh::texture::UvSplit;
use lucent_core::session::Solved;
use lucent_gpu::GpuContext;
use lucent_gpu::mesh_pass::{AlbedoMap, EnvironmentMap, GpuMesh, Shading};
use lucent_gpu::offscreen::OffscreenRenderer;
use lucent_gpu::tonemap::ToneMap;

/// The GPU side across frames.
pub struct GpuFrame {
    ctx: GpuContext,
    renderer: OffscreenRenderer,
    mesh: GpuMesh,
    /// The mesh split at its UV seams, for a textured mesh (per-vertex data is copied through it).
    split: Option<UvSplit>,
    camera: CameraView,
    shading: Shading,
    tone: ToneMap,
    // Kept alive for the mesh pass's bind groups.
    _environment: Option<EnvironmentMap>,
    _albedo: Option<AlbedoMap>,
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
        let mut renderer = OffscreenRenderer::new(&ctx, width, height)?;
        let (gpu_mesh, split, albedo) = match &scene.texture {
            Some(t) => {
                let split = UvSplit::new(mesh, &t.corner_uvs);
                let (p, n, r) =
                    (split.gather(&mesh.positions), split.gather(&normals), split.gather(radiance));
                let gpu_mesh = GpuMesh::with_uvs(&ctx, &p, &n, &r, &split.triangles, &split.uvs)?;
                let map = AlbedoMap::from_rgb(&ctx, t.image.width, t.image.height, &t.image.texels)?;
                renderer.mesh_pass_mut().set_albedo(&ctx, &map);
                (gpu_mesh, Some(split), Some(map))
            }
            None => (GpuMesh::new(&ctx, &mesh.positions, &normals, radiance, &mesh.triangles)?, None, None),
        };
        let camera = scene.camera_view((width, height));
        let mut shading = Shading {
            eta: scene.material().eta as f32,
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
        Ok(GpuFrame {
            ctx,
            renderer,
            mesh: gpu_mesh,
            split,
            camera,
            shading,
            tone,
            _environment: environment,
            _albedo: albedo,
        })
    }

    /// Draws the mesh with the per-vertex radiance of `solved`, new geometry (`mesh`, when it moved) and
    /// `lights` for the highlight, and reads the frame back: the tone-mapped image, or with
    /// `hdr` (what `--format exr` writes) the HDR radiance and coverage with nothing behind the
    /// object.
    pub fn draw(
        &mut self,
        mesh: Option<&Mesh>,
        solved: &Solved,
        lights: &[SceneLight],
        hdr: bool,
    ) -> Result<Frame> {
        let split = self.split.as_ref();
        if let Some(m) = mesh {
            let normals = m.vertex_normals();
            let (p, n) = (UvSplit::through(split, &m.positions), UvSplit::through(split, &normals));
            self.mesh.update_geometry(&self.ctx, &p, &n)?;
        }
        let radiance = UvSplit::through(split, &solved.vertex_radiance);
        self.mesh.update_radiance(&self.ctx, &radiance, &UvSplit::through(split, &solved.vertex_single))?;
        self.shading.lights = lights.iter().map(|l| l.light).collect();
        self.shading.exit_lobe = solved.exit_lobe.clone();
        self.shading.linear_single = solved.linear_single;
        if hdr {
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
