//! One still image of the Mertens 2003 methods: the scene's mesh deformed in full, solved in
//! the mode a single image wants (irradiance §5.3, subsurface solve §3, §5.2, §5.5, per-vertex
//! `B / pi` §3.2), then rasterised on the GPU (§5.4, [`crate::frame`]). `lucent render` and the
//! Python module (`crates/lucent-py`) make their images through these functions, so both give
//! the same image for the same scene.

use crate::frame::GpuFrame;
use crate::output::Frame;
use crate::scene::Scene;
use anyhow::Result;
use lucent_core::mesh::Mesh;
use lucent_core::session::{FrameSession, SolveMode, Solved};
use lucent_gpu::GpuContext;
use lucent_gpu::tonemap::ToneMap;

/// Bytes a stored link set takes per triangle, for the mode choice below: about 210 links a
/// triangle on scanned meshes (the Stanford dragon, marble at 10 cm) at 13 bytes each, with
/// room for denser materials and for the rest of a render-mode solve's peak (hierarchy,
/// irradiance, bounce rays), which is per triangle too.
const LINK_BYTES_PER_TRIANGLE: u64 = 4096;

/// The solve mode of one image when `--mode` and the scene leave it open. With bounces
/// between parts, `render`: the links are made once and each bounce is a gather over them
/// (on the fly links every bounce anew, as costly as the first solve each time), unless
/// the stored links would not fit in half the memory available; else `on-the-fly`, which
/// stores none.
pub fn one_image_mode(scene: &Scene, mesh: &Mesh) -> SolveMode {
    if scene.settings.bounces == 0 {
        return SolveMode::OnTheFly;
    }
    let need = mesh.triangles.len() as u64 * LINK_BYTES_PER_TRIANGLE;
    match available_memory() {
        Some(avail) if need > avail / 2 => {
            println!(
                "lucent: solving on the fly: the links of {} triangles (about {} MiB) would not fit in half the {} MiB available, so each bounce links anew",
                mesh.triangles.len(),
                need >> 20,
                avail >> 20
            );
            SolveMode::OnTheFly
        }
        _ => SolveMode::Render,
    }
}

/// `MemAvailable` of `/proc/meminfo`, bytes (`None` where there is none: not Linux).
fn available_memory() -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// The scene's mesh with every deformation applied in full, and a session on it in
/// [`one_image_mode`] with the eye of the camera framed for a `size` (width, height) image
/// (for view-ray single scattering). Nothing is solved yet.
pub fn session(scene: &Scene, size: (u32, u32)) -> (Mesh, FrameSession) {
    let mesh = scene.deformed(1.0);
    let mut session = scene.session(one_image_mode(scene, &mesh));
    session.set_positions(&mesh.positions);
    session.set_eye(Some(scene.camera_view(size).eye));
    (mesh, session)
}

/// Draws `solved` (the per-vertex radiance of `mesh`) with the scene's camera, lights and
/// environment (drawn behind the object with `env_background`) on `ctx`, and reads the frame
/// back: tone mapped by `tone`, or with `hdr` the linear radiance and coverage
/// ([`crate::output`]). Also returns the adapter's description.
#[allow(clippy::too_many_arguments)]
pub fn draw(
    ctx: GpuContext,
    scene: &Scene,
    size: (u32, u32),
    tone: ToneMap,
    mesh: &Mesh,
    solved: &Solved,
    env_background: bool,
    hdr: bool,
) -> Result<(Frame, String)> {
    let mut gpu = GpuFrame::new(ctx, scene, size, tone, mesh, &solved.vertex_radiance, env_background)?;
    let image = gpu.draw(None, solved, &scene.lights, hdr)?;
    Ok((image, gpu.adapter()))
}
