//! Copying textures and buffers back to the CPU.
//!
//! A texture-to-buffer copy needs rows padded to `wgpu::COPY_BYTES_PER_ROW_ALIGNMENT` (256
//! bytes); these functions hide that and return tightly packed rows, top row first.

use crate::context::{GpuContext, GpuError};

/// Texels read back from one mip level of a texture, rows tightly packed.
#[derive(Clone, Debug, PartialEq)]
pub struct TexelData {
    /// Width of the mip level, in texels.
    pub width: u32,
    /// Height of the mip level, in texels.
    pub height: u32,
    /// Depth (3D textures) or array layers; 1 for a plain 2D texture.
    pub depth: u32,
    /// The texture's format (for depth-stencil formats, the depth aspect was read).
    pub format: wgpu::TextureFormat,
    /// Bytes per texel.
    pub bytes_per_texel: u32,
    /// `depth * height * width * bytes_per_texel` bytes: slice by slice, row by row, top first.
    pub bytes: Vec<u8>,
}

impl TexelData {
    /// The texels of an `Rgba16Float` texture as `f32` RGBA.
    pub fn to_rgba_f32(&self) -> Result<Vec<[f32; 4]>, GpuError> {
        match self.format {
            wgpu::TextureFormat::Rgba16Float => Ok(self
                .bytes
                .chunks_exact(8)
                .map(|t| {
                    let h = |i: usize| {
                        half::f16::from_bits(u16::from_le_bytes([t[2 * i], t[2 * i + 1]])).to_f32()
                    };
                    [h(0), h(1), h(2), h(3)]
                })
                .collect()),
            wgpu::TextureFormat::Rgba32Float => Ok(self
                .bytes
                .chunks_exact(16)
                .map(|t| {
                    let f =
                        |i: usize| f32::from_le_bytes([t[4 * i], t[4 * i + 1], t[4 * i + 2], t[4 * i + 3]]);
                    [f(0), f(1), f(2), f(3)]
                })
                .collect()),
            f => Err(GpuError::InvalidInput(format!(
                "to_rgba_f32: texture format {f:?} is not a float RGBA format"
            ))),
        }
    }

    /// The texels of a single-channel 32-bit float texture (`R32Float`, `Depth32Float`).
    pub fn to_f32(&self) -> Result<Vec<f32>, GpuError> {
        if self.bytes_per_texel != 4
            || !matches!(
                self.format,
                wgpu::TextureFormat::R32Float
                    | wgpu::TextureFormat::Depth32Float
                    | wgpu::TextureFormat::Depth32FloatStencil8
            )
        {
            return Err(GpuError::InvalidInput(format!(
                "to_f32: texture format {:?} is not a 32-bit float format",
                self.format
            )));
        }
        Ok(self.bytes.chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect())
    }

    /// An `Rgba8Unorm`/`Rgba8UnormSrgb` 2D texture as an image (bytes unchanged).
    pub fn to_rgba_image(&self) -> Result<image::RgbaImage, GpuError> {
        if !matches!(self.format, wgpu::TextureFormat::Rgba8Unorm | wgpu::TextureFormat::Rgba8UnormSrgb)
            || self.depth != 1
        {
            return Err(GpuError::InvalidInput(format!(
                "to_rgba_image: texture format {:?} (depth {}) is not a 2D RGBA8 format",
                self.format, self.depth
            )));
        }
        image::RgbaImage::from_raw(self.width, self.height, self.bytes.clone())
            .ok_or_else(|| GpuError::Readback("RGBA8 read-back has the wrong length".into()))
    }
}

/// `bytes_per_row` rounded up to the copy alignment (256 bytes).
pub fn padded_bytes_per_row(unpadded: u32) -> u32 {
    let align = wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    unpadded.div_ceil(align) * align
}

/// Reads mip level `mip_level` of `texture` (all its depth slices or array layers) to the CPU.
/// Blocks until the GPU has finished the work submitted so far. The texture needs
/// `TextureUsages::COPY_SRC`; compressed formats are not supported.
pub fn read_texture(
    ctx: &GpuContext,
    texture: &wgpu::Texture,
    mip_level: u32,
) -> Result<TexelData, GpuError> {
    let format = texture.format();
    let aspect =
        if format.has_depth_aspect() { wgpu::TextureAspect::DepthOnly } else { wgpu::TextureAspect::All };
    let aspect_opt = if format.has_depth_aspect() { Some(aspect) } else { None };
    let bytes_per_texel = format
        .block_copy_size(aspect_opt)
        .filter(|_| format.block_dimensions() == (1, 1))
        .ok_or_else(|| GpuError::InvalidInput(format!("cannot read back texture format {format:?}")))?;
    if mip_level >= texture.mip_level_count() {
        return Err(GpuError::InvalidInput(format!(
            "mip level {mip_level} does not exist (texture has {})",
            texture.mip_level_count()
        )));
    }
    let size = texture.size().mip_level_size(mip_level, texture.dimension());
    let (width, height, depth) = (size.width, size.height, size.depth_or_array_layers);
    let unpadded = width * bytes_per_texel;
    let padded = padded_bytes_per_row(unpadded);
    let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("lucent read-back"),
        size: padded as u64 * height as u64 * depth as u64,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("lucent read-back") });
    encoder.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo { texture, mip_level, origin: wgpu::Origin3d::ZERO, aspect },
        wgpu::TexelCopyBufferInfo {
            buffer: &staging,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded),
                rows_per_image: Some(height),
            },
        },
        size,
    );
    ctx.queue.submit([encoder.finish()]);
    let mapped = map_read(ctx, &staging)?;
    let mut bytes = Vec::with_capacity((unpadded * height * depth) as usize);
    for row in mapped.chunks_exact(padded as usize) {
        bytes.extend_from_slice(&row[..unpadded as usize]);
    }
    Ok(TexelData { width, height, depth, format, bytes_per_texel, bytes })
}

/// Reads a whole buffer to the CPU (via a staging copy). `buffer` needs
/// `BufferUsages::COPY_SRC` and a size that is a multiple of 4.
pub fn read_buffer(ctx: &GpuContext, buffer: &wgpu::Buffer) -> Result<Vec<u8>, GpuError> {
    let size = buffer.size();
    if !size.is_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT) {
        return Err(GpuError::InvalidInput(format!(
            "read_buffer: size {size} is not a multiple of {}",
            wgpu::COPY_BUFFER_ALIGNMENT
        )));
    }
    let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("lucent read-back"),
        size,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("lucent read-back") });
    encoder.copy_buffer_to_buffer(buffer, 0, &staging, 0, size);
    ctx.queue.submit([encoder.finish()]);
    map_read(ctx, &staging)
}

/// Maps a `MAP_READ` buffer, waits, copies its contents out and unmaps it.
fn map_read(ctx: &GpuContext, staging: &wgpu::Buffer) -> Result<Vec<u8>, GpuError> {
    let (tx, rx) = std::sync::mpsc::channel();
    staging.map_async(wgpu::MapMode::Read, .., move |r| {
        let _ = tx.send(r);
    });
    ctx.wait("read-back")?;
    rx.recv()
        .map_err(|_| GpuError::Readback("the map callback never ran".into()))?
        .map_err(|e| GpuError::Readback(e.to_string()))?;
    let out = {
        let view = staging.get_mapped_range(..).map_err(|e| GpuError::Readback(e.to_string()))?;
        view.to_vec()
    };
    staging.unmap();
    Ok(out)
}
