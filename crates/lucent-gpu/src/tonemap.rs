//! Tone mapping (Mertens 2003 §5.4: everything is computed in HDR and "a simple gamma curve per
//! pixel is applied to the final shading"): exposure, an optional filmic curve, clamp to 0..1,
//! gamma encode, and the background composited where the HDR target has no coverage.
//!
//! [`ToneMap::apply`] is the same curve on the CPU: the reference the GPU pass is tested against.

use crate::context::{GpuContext, GpuError};

/// Which curve maps exposed radiance to 0..1 before gamma encoding.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ToneOperator {
    /// Clamp to 0..1, then the gamma curve: the paper's operator.
    #[default]
    Gamma,
    /// Narkowicz's 2015 fit of the ACES filmic curve `x (2.51 x + 0.03) / (x (2.43 x + 0.59) +
    /// 0.14)`, then the gamma curve: rolls highlights off instead of clipping them.
    AcesFilmic,
}

/// Tone-mapping settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ToneMap {
    /// Multiplier applied to radiance first (> 0). Default 1.
    pub exposure: f32,
    /// Display gamma (> 0): the output is `x^(1/gamma)`. Default 2.2.
    pub gamma: f32,
    /// The curve. Default [`ToneOperator::Gamma`].
    pub operator: ToneOperator,
    /// Background colour where nothing was drawn, display-encoded 0..1. Default a dark grey
    /// (0.05, 0.05, 0.06).
    pub background: [f32; 3],
}

impl Default for ToneMap {
    fn default() -> Self {
        ToneMap { exposure: 1.0, gamma: 2.2, operator: ToneOperator::Gamma, background: [0.05, 0.05, 0.06] }
    }
}

impl ToneMap {
    /// The display value 0..1 of HDR radiance `rgb` with coverage `alpha` (0..1; 1 = object,
    /// 0 = background), exactly as `tonemap.wgsl` computes it for a linear target.
    pub fn apply(&self, rgb: [f32; 3], alpha: f32) -> [f32; 3] {
        let a = alpha.clamp(0.0, 1.0);
        let inv_gamma = 1.0 / self.gamma;
        std::array::from_fn(|i| {
            let mut c = rgb[i].max(0.0) / a.max(1e-4) * self.exposure;
            if self.operator == ToneOperator::AcesFilmic {
                c = (c * (2.51 * c + 0.03)) / (c * (2.43 * c + 0.59) + 0.14);
            }
            let c = c.clamp(0.0, 1.0).powf(inv_gamma);
            self.background[i] + (c - self.background[i]) * a
        })
    }

    /// Checks exposure and gamma (finite, > 0).
    pub(crate) fn validate(&self) -> Result<(), GpuError> {
        if !(self.exposure.is_finite() && self.exposure > 0.0) {
            return Err(GpuError::InvalidInput(format!(
                "exposure must be finite and > 0, got {}",
                self.exposure
            )));
        }
        if !(self.gamma.is_finite() && self.gamma > 0.0) {
            return Err(GpuError::InvalidInput(format!("gamma must be finite and > 0, got {}", self.gamma)));
        }
        Ok(())
    }
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ToneUniforms {
    params: [f32; 4],
    background: [f32; 4],
}

/// The tone-map pipeline: reads one single-sample HDR texture, writes a target of the format
/// given to [`ToneMapPass::new`] (linear or sRGB; for sRGB formats the shader pre-compensates
/// so the stored value is the same gamma-encoded one).
pub struct ToneMapPass {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    uniforms: wgpu::Buffer,
    srgb_target: bool,
}

impl ToneMapPass {
    /// Builds the pipeline for `target_format`.
    pub fn new(ctx: &GpuContext, target_format: wgpu::TextureFormat) -> Result<Self, GpuError> {
        let device = &ctx.device;
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("lucent tonemap.wgsl"),
            source: wgpu::ShaderSource::Wgsl(include_str!("shaders/tonemap.wgsl").into()),
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("lucent tone map"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
                wgpu::BindGroupLayoutEntry {
                    binding: 1,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: false },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                },
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("lucent tone map"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("lucent tone map"),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: Default::default(),
            depth_stencil: None,
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[Some(target_format.into())],
            }),
            multiview_mask: None,
            cache: None,
        });
        let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("lucent tone map"),
            size: std::mem::size_of::<ToneUniforms>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(GpuError::Device {
                during: "creating the tone-map pipeline".into(),
                message: e.to_string(),
            });
        }
        Ok(ToneMapPass { pipeline, layout, uniforms, srgb_target: target_format.is_srgb() })
    }

    /// A bind group reading `hdr` (a single-sample view of an HDR texture). Make one per HDR
    /// texture and keep it while the texture lives.
    pub fn bind(&self, ctx: &GpuContext, hdr: &wgpu::TextureView) -> wgpu::BindGroup {
        ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("lucent tone map"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: self.uniforms.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(hdr) },
            ],
        })
    }

    /// Writes the settings for the next [`ToneMapPass::draw`].
    pub fn prepare(&self, ctx: &GpuContext, tone: &ToneMap) -> Result<(), GpuError> {
        tone.validate()?;
        let u = ToneUniforms {
            params: [
                tone.exposure,
                1.0 / tone.gamma,
                match tone.operator {
                    ToneOperator::Gamma => 0.0,
                    ToneOperator::AcesFilmic => 1.0,
                },
                if self.srgb_target { 1.0 } else { 0.0 },
            ],
            background: [tone.background[0], tone.background[1], tone.background[2], 1.0],
        };
        ctx.queue.write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&u));
        Ok(())
    }

    /// Records the full-screen draw into `pass` (whose target is the size of the HDR texture).
    pub fn draw(&self, pass: &mut wgpu::RenderPass<'_>, bind_group: &wgpu::BindGroup) {
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, bind_group, &[]);
        pass.draw(0..3, 0..1);
    }
}
