//! Read-back round trips: data uploaded with `write_texture` / `create_buffer_init` must come
//! back byte for byte, for row sizes that need padding to 256 bytes and for 3D textures.
//! Needs an adapter (Mesa lavapipe or llvmpipe suffice); skips with a note if there is none
//! (fails under CI: see `lucent_gpu::test_support`).

use lucent_gpu::GpuContext;
use lucent_gpu::readback::{read_buffer, read_texture};
use lucent_gpu::test_support::adapter_or_skip;
use wgpu::util::DeviceExt;

/// A texture of `format` filled with `bytes` (tightly packed rows).
fn upload(
    ctx: &GpuContext,
    size: wgpu::Extent3d,
    dimension: wgpu::TextureDimension,
    format: wgpu::TextureFormat,
    bytes: &[u8],
) -> wgpu::Texture {
    let bpt = format.block_copy_size(None).unwrap();
    let tex = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: None,
        size,
        mip_level_count: 1,
        sample_count: 1,
        dimension,
        format,
        usage: wgpu::TextureUsages::COPY_SRC | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    ctx.queue.write_texture(
        tex.as_image_copy(),
        bytes,
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(size.width * bpt),
            rows_per_image: Some(size.height),
        },
        size,
    );
    tex
}

#[test]
fn rgba8_rows_that_need_padding_round_trip() {
    let Some(ctx) = adapter_or_skip() else { return };
    // 13 texels x 4 bytes = 52 bytes per row: padded to 256 in the copy.
    let (w, h) = (13u32, 7u32);
    let bytes: Vec<u8> = (0..w * h * 4).map(|i| (i * 7 % 251) as u8).collect();
    let size = wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 };
    let tex = upload(&ctx, size, wgpu::TextureDimension::D2, wgpu::TextureFormat::Rgba8Unorm, &bytes);
    let back = read_texture(&ctx, &tex, 0).unwrap();
    assert_eq!((back.width, back.height, back.depth), (w, h, 1));
    assert_eq!(back.bytes, bytes);
    let img = back.to_rgba_image().unwrap();
    assert_eq!(img.get_pixel(12, 6).0, bytes[(6 * w as usize + 12) * 4..][..4]);
}

#[test]
fn rgba16f_3d_texture_round_trips_as_f32() {
    let Some(ctx) = adapter_or_skip() else { return };
    let (w, h, d) = (5u32, 3u32, 4u32);
    // Values exactly representable in f16.
    let values: Vec<f32> = (0..w * h * d * 4).map(|i| i as f32 * 0.25 - 8.0).collect();
    let bytes: Vec<u8> =
        values.iter().flat_map(|v| half::f16::from_f32(*v).to_bits().to_le_bytes()).collect();
    let size = wgpu::Extent3d { width: w, height: h, depth_or_array_layers: d };
    let tex = upload(&ctx, size, wgpu::TextureDimension::D3, wgpu::TextureFormat::Rgba16Float, &bytes);
    let back = read_texture(&ctx, &tex, 0).unwrap();
    assert_eq!((back.width, back.height, back.depth), (w, h, d));
    let flat: Vec<f32> = back.to_rgba_f32().unwrap().concat();
    assert_eq!(flat, values);
}

#[test]
fn buffer_round_trips() {
    let Some(ctx) = adapter_or_skip() else { return };
    let data: Vec<u32> = (0..1000).map(|i| i * 2654435761u32).collect();
    let buf = ctx.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: None,
        contents: bytemuck::cast_slice(&data),
        usage: wgpu::BufferUsages::COPY_SRC,
    });
    let back = read_buffer(&ctx, &buf).unwrap();
    assert_eq!(back, bytemuck::cast_slice::<u32, u8>(&data));
}
