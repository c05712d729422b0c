//! The textures the mesh pass samples: the equirectangular environment map (reflection and
//! background) and the albedo map (a mesh's colour texture, issue 18), each with the bind
//! group that holds it and its sampler.

use crate::context::{GpuContext, GpuError};
use glam::Vec3;

pub(crate) fn env_bind_group(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    env: &EnvironmentMap,
    sampler: &wgpu::Sampler,
) -> wgpu::BindGroup {
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("lucent mesh environment"),
        layout,
        entries: &[
            wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&env.view) },
            wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::Sampler(sampler) },
        ],
    })
}

/// An equirectangular HDR environment map on the GPU (`Rgba16Float`, one mip). Direction
/// `d` maps to `u = atan2(d.x, -d.z) / 2pi + 1/2`, `v = acos(d.y) / pi` (v = 0 is straight up).
pub struct EnvironmentMap {
    /// The texture.
    pub texture: wgpu::Texture,
    /// A view of it.
    pub view: wgpu::TextureView,
}

impl EnvironmentMap {
    /// Uploads `width * height` RGBA radiance texels (rows top first), converted to f16.
    pub fn from_rgba_f32(
        ctx: &GpuContext,
        width: u32,
        height: u32,
        texels: &[[f32; 4]],
    ) -> Result<EnvironmentMap, GpuError> {
        ctx.check_size(width, height)?;
        if texels.len() != (width * height) as usize {
            return Err(GpuError::InvalidInput(format!(
                "environment map: {} texels for {width}x{height}",
                texels.len()
            )));
        }
        let size = wgpu::Extent3d { width, height, depth_or_array_layers: 1 };
        let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("lucent environment"),
            size,
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba16Float,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        let bytes: Vec<u8> =
            texels.iter().flatten().flat_map(|v| half::f16::from_f32(*v).to_bits().to_le_bytes()).collect();
        ctx.queue.write_texture(
            texture.as_image_copy(),
            &bytes,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(width * 8),
                rows_per_image: Some(height),
            },
            size,
        );
        let view = texture.create_view(&Default::default());
        Ok(EnvironmentMap { texture, view })
    }
}

/// A mesh's colour texture on the GPU (`Rgba16Float`, linear RGB, one mip), rows top first,
/// sampled at the mesh's UVs with repeat and bilinear filtering. The mesh pass multiplies the
/// subsurface radiance by its square root per pixel (the exit half of the texture's
/// modulation; `lucent_core::mesh::texture`). The default is 1x1 white: no change.
pub struct AlbedoMap {
    /// The texture.
    pub texture: wgpu::Texture,
    /// A view of it.
    pub view: wgpu::TextureView,
}

impl AlbedoMap {
    /// Uploads `width * height` linear RGB texels (rows top first), converted to f16.
    pub fn from_rgb(
        ctx: &GpuContext,
        width: u32,
        height: u32,
        texels: &[Vec3],
    ) -> Result<AlbedoMap, GpuError> {
        let rgba: Vec<[f32; 4]> = texels.iter().map(|c| c.extend(1.0).to_array()).collect();
        let env = EnvironmentMap::from_rgba_f32(ctx, width, height, &rgba)?;
        Ok(AlbedoMap { texture: env.texture, view: env.view })
    }
}

/// The albedo layout's bind group: `map` and the repeating bilinear `sampler`.
pub(crate) fn albedo_bind_group(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    map: &AlbedoMap,
    sampler: &wgpu::Sampler,
) -> wgpu::BindGroup {
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("lucent mesh albedo"),
        layout,
        entries: &[
            wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&map.view) },
            wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::Sampler(sampler) },
        ],
    })
}

/// The layout of a sampled 2D float texture (binding 0) and a filtering sampler (binding 1),
/// for the fragment stage: both the environment's and the albedo's.
pub(crate) fn texture_layout(device: &wgpu::Device, label: &str) -> wgpu::BindGroupLayout {
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(label),
        entries: &[
            wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: true },
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: false,
                },
                count: None,
            },
            wgpu::BindGroupLayoutEntry {
                binding: 1,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                count: None,
            },
        ],
    })
}
