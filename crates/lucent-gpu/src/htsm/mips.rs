//! Pass 2, the reference images' mip chains (Shopf 2007 §4.3.1): each level by 2x2 averaging
//! of the one above, all images at once. Level 0 stores colour premultiplied by coverage, so the
//! averages stay premultiplied and the camera pass divides by alpha to average covered texels
//! only (texture coordinates and deformation offsets of the silhouette are not pulled towards
//! the clear colour).

use super::REFERENCE_FORMAT;
use super::pipeline::{begin, cleared, fullscreen_pipeline, pipeline_layout, texture_entry};
use super::reference::{REFERENCE_IMAGES, ReferencePass};

/// The mip pipeline and one bind group per source level.
pub(super) struct MipPass {
    pipeline: wgpu::RenderPipeline,
    /// `bind_groups[k]` reads level `k` to write level `k + 1`.
    bind_groups: Vec<wgpu::BindGroup>,
}

impl MipPass {
    pub fn new(device: &wgpu::Device, reference: &ReferencePass) -> MipPass {
        let d2 = wgpu::TextureViewDimension::D2;
        let entries: Vec<wgpu::BindGroupLayoutEntry> =
            (0..REFERENCE_IMAGES as u32).map(|i| texture_entry(i, d2, false)).collect();
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("htsm mip source"),
            entries: &entries,
        });
        // Not prefixed with htsm_common.wgsl: the mip pass needs no uniforms.
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("htsm mip"),
            source: wgpu::ShaderSource::Wgsl(include_str!("../shaders/htsm_mip.wgsl").into()),
        });
        let targets: Vec<Option<wgpu::ColorTargetState>> =
            (0..REFERENCE_IMAGES).map(|_| Some(REFERENCE_FORMAT.into())).collect();
        let pipeline = fullscreen_pipeline(
            device,
            "htsm mip pass",
            &module,
            &pipeline_layout(device, "htsm mip", &[Some(&layout)]),
            "fs_mip",
            &targets,
        );
        let bind_groups = (0..reference.levels.saturating_sub(1) as usize)
            .map(|level| {
                let views = &reference.level_views[level];
                let entries: Vec<wgpu::BindGroupEntry> = views
                    .iter()
                    .enumerate()
                    .map(|(i, v)| wgpu::BindGroupEntry {
                        binding: i as u32,
                        resource: wgpu::BindingResource::TextureView(v),
                    })
                    .collect();
                device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("htsm mip source"),
                    layout: &layout,
                    entries: &entries,
                })
            })
            .collect();
        MipPass { pipeline, bind_groups }
    }

    /// Records the chain, one level at a time.
    pub fn encode(&self, encoder: &mut wgpu::CommandEncoder, reference: &ReferencePass) {
        for (level, bind_group) in self.bind_groups.iter().enumerate() {
            let colour = reference.level_views[level + 1].each_ref().map(cleared);
            let mut pass = begin(encoder, "htsm mip pass", &colour, None);
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, bind_group, &[]);
            pass.draw(0..3, 0..1);
        }
    }
}
