//! Pass 3, the camera pass (Shopf 2007 §4.3.1-§4.3.5, table 4.1): per visible point, the
//! hierarchical samples of the reference images (fig. 4.3), a `K`-step ray cast through the
//! density volume to each (§4.3.2, `alpha_i` with `sigma_at = sigma_a + density`, eq. 4.1), the
//! phase table (§4.3.4) and the transport model, then the lit side's surface terms. Runs once
//! per light: the first light's pass writes the HDR target, later ones add to it (additive
//! blending over the depth the first one recorded).
//!
//! Also owns what only this pass reads: the density volume (§4.2) with its mips and the
//! Henyey-Greenstein table.

use super::pipeline::{
    DepthMode, Uniforms, begin, depth_attachment, linear_sampler, mesh_pipeline, pipeline_layout,
    sampler_entry, shader, texture_entry,
};
use super::reference::ReferencePass;
use super::{DENSITY_FORMAT, HtsmError, PHASE_TABLE_SIZE, check_volume, phase_table};
use crate::context::{GpuContext, HDR_FORMAT};
use lucent_core::volume::DensityVolume;

const PHASE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R16Float;

/// Sums radiance, keeps the first pass's coverage in alpha.
const ADD_RADIANCE: wgpu::BlendState = wgpu::BlendState {
    color: wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::One,
        dst_factor: wgpu::BlendFactor::One,
        operation: wgpu::BlendOperation::Add,
    },
    alpha: wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::Zero,
        dst_factor: wgpu::BlendFactor::One,
        operation: wgpu::BlendOperation::Add,
    },
};

/// The camera pass's pipelines and its scene bind group (group 1).
pub(super) struct CameraPass {
    /// First light: clears, records depth, writes radiance.
    first: wgpu::RenderPipeline,
    /// Later lights: the recorded surface only, radiance added.
    additive: wgpu::RenderPipeline,
    scene_bind_group: wgpu::BindGroup,
    phase: wgpu::Texture,
    phase_g: Option<f32>,
    pub density_dims: [u32; 3],
    pub density_levels: u32,
}

/// Uploads `volume` as an R8Unorm 3D texture, every mip level computed on the CPU.
fn upload_density(ctx: &GpuContext, volume: &DensityVolume) -> (wgpu::Texture, u32) {
    let chain = volume.mip_chain();
    let density = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("htsm density"),
        size: wgpu::Extent3d {
            width: volume.dims[0],
            height: volume.dims[1],
            depth_or_array_layers: volume.dims[2],
        },
        mip_level_count: chain.len() as u32,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D3,
        format: DENSITY_FORMAT,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    for (level, v) in chain.iter().enumerate() {
        ctx.queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &density,
                mip_level: level as u32,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            &v.to_unorm8(),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(v.dims[0]),
                rows_per_image: Some(v.dims[1]),
            },
            wgpu::Extent3d { width: v.dims[0], height: v.dims[1], depth_or_array_layers: v.dims[2] },
        );
    }
    (density, chain.len() as u32)
}

impl CameraPass {
    pub fn new(
        ctx: &GpuContext,
        volume: &DensityVolume,
        reference: &ReferencePass,
        uniforms: &Uniforms,
    ) -> Result<CameraPass, HtsmError> {
        let device = &ctx.device;
        check_volume(volume, &device.limits())?;
        let (density, density_levels) = upload_density(ctx, volume);
        let phase = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("htsm phase table"),
            size: wgpu::Extent3d { width: PHASE_TABLE_SIZE, height: 1, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: PHASE_FORMAT,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });

        let d2 = wgpu::TextureViewDimension::D2;
        let scene_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("htsm scene"),
            entries: &[
                texture_entry(0, d2, true),
                texture_entry(1, d2, true),
                texture_entry(2, d2, true),
                sampler_entry(3),
                texture_entry(4, wgpu::TextureViewDimension::D3, true),
                sampler_entry(5),
                texture_entry(6, d2, true),
                texture_entry(7, d2, true),
            ],
        });
        let refs = reference.full_views();
        let density_view = density.create_view(&Default::default());
        let phase_view = phase.create_view(&Default::default());
        let ref_sampler = linear_sampler(device, "htsm reference sampler");
        let density_sampler = linear_sampler(device, "htsm density sampler");
        let view = wgpu::BindingResource::TextureView;
        let scene_bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("htsm scene"),
            layout: &scene_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: view(&refs[0]) },
                wgpu::BindGroupEntry { binding: 1, resource: view(&refs[1]) },
                wgpu::BindGroupEntry { binding: 2, resource: view(&refs[2]) },
                wgpu::BindGroupEntry { binding: 3, resource: wgpu::BindingResource::Sampler(&ref_sampler) },
                wgpu::BindGroupEntry { binding: 4, resource: view(&density_view) },
                wgpu::BindGroupEntry {
                    binding: 5,
                    resource: wgpu::BindingResource::Sampler(&density_sampler),
                },
                wgpu::BindGroupEntry { binding: 6, resource: view(&phase_view) },
                wgpu::BindGroupEntry { binding: 7, resource: view(&refs[3]) },
            ],
        });

        let module = shader(device, "htsm camera", include_str!("../shaders/htsm_render.wgsl"));
        let layout = pipeline_layout(device, "htsm camera", &[Some(uniforms.layout()), Some(&scene_layout)]);
        let pipeline = |label: &str, depth: DepthMode, blend: Option<wgpu::BlendState>| {
            let target =
                wgpu::ColorTargetState { format: HDR_FORMAT, blend, write_mask: wgpu::ColorWrites::ALL };
            mesh_pipeline(device, label, &module, &layout, ("vs_camera", "fs_camera"), depth, &[Some(target)])
        };
        Ok(CameraPass {
            first: pipeline("htsm camera pass", DepthMode::NEAREST, None),
            additive: pipeline("htsm camera pass (added light)", DepthMode::RECORDED, Some(ADD_RADIANCE)),
            scene_bind_group,
            phase,
            phase_g: None,
            density_dims: volume.dims,
            density_levels,
        })
    }

    /// Uploads the Henyey-Greenstein table for asymmetry `g` unless it is already there.
    pub fn set_phase(&mut self, queue: &wgpu::Queue, g: f32) {
        if self.phase_g == Some(g) {
            return;
        }
        let halves: Vec<u16> = phase_table(g).iter().map(|&v| half::f16::from_f32(v).to_bits()).collect();
        queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &self.phase,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            bytemuck::cast_slice(&halves),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(2 * PHASE_TABLE_SIZE),
                rows_per_image: Some(1),
            },
            wgpu::Extent3d { width: PHASE_TABLE_SIZE, height: 1, depth_or_array_layers: 1 },
        );
        self.phase_g = Some(g);
    }

    /// Bytes of the density volume with its mips (one byte per voxel).
    pub fn volume_bytes(&self) -> u64 {
        (0..self.density_levels)
            .map(|l| self.density_dims.iter().map(|&d| (d >> l).max(1) as u64).product::<u64>())
            .sum()
    }

    /// Records light slot `light`'s camera pass into `hdr` (alpha = coverage) over `depth`.
    /// `first`: clear both and record depth; otherwise add to what is there. `last`: nothing
    /// reads the depth afterwards.
    #[allow(clippy::too_many_arguments)]
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        hdr: &wgpu::TextureView,
        depth: &wgpu::TextureView,
        (first, last): (bool, bool),
        uniforms: &Uniforms,
        light: usize,
        geometry: &super::geometry::Geometry,
    ) {
        let colour = [Some(wgpu::RenderPassColorAttachment {
            view: hdr,
            depth_slice: None,
            resolve_target: None,
            ops: wgpu::Operations {
                // Alpha 0 is "no object": the tone-map pass puts the background there.
                load: if first { wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT) } else { wgpu::LoadOp::Load },
                store: wgpu::StoreOp::Store,
            },
        })];
        let mut pass = begin(encoder, "htsm camera pass", &colour, depth_attachment(depth, first, !last));
        pass.set_pipeline(if first { &self.first } else { &self.additive });
        uniforms.bind(&mut pass, light);
        pass.set_bind_group(1, &self.scene_bind_group, &[]);
        geometry.draw(&mut pass);
    }
}
