//! `HtsmRenderer::encode_into`: the frame drawn into a caller's texture (a window's surface).

use super::*;
use lucent_gpu::htsm::HtsmError;

fn target(ctx: &GpuContext, size: u32, format: wgpu::TextureFormat) -> wgpu::Texture {
    ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("test target"),
        size: wgpu::Extent3d { width: size, height: size, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    })
}

#[test]
fn encoding_into_a_callers_texture_gives_the_read_back_image() {
    let Some(ctx) = adapter_or_skip() else { return };
    let mesh = ellipsoid(0.5);
    let volume = VolumeSpec::default().build([32, 22, 16]).unwrap();
    let mut r = HtsmRenderer::new(&ctx, &mesh, &volume, 128).unwrap();
    let v = view(&mesh, 64);
    let params = HtsmParams::default();
    let expected = r.render(&ctx, &v, &params).unwrap();
    for (format, tolerance) in
        [(wgpu::TextureFormat::Rgba8Unorm, 0u8), (wgpu::TextureFormat::Rgba8UnormSrgb, 1)]
    {
        let texture = target(&ctx, 64, format);
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        r.encode_into(&ctx, &mut encoder, &texture.create_view(&Default::default()), format, &v, &params)
            .unwrap_or_else(|e| panic!("{format:?}: {e}"));
        ctx.queue.submit([encoder.finish()]);
        ctx.check("test").unwrap();
        let got = read_texture(&ctx, &texture, 0).unwrap().to_rgba_image().unwrap();
        let worst = got.as_raw().iter().zip(expected.as_raw()).map(|(a, b)| a.abs_diff(*b)).max().unwrap();
        assert!(worst <= tolerance, "{format:?}: differs by up to {worst}");
    }
    // A target of another size is refused before anything is recorded.
    let texture = target(&ctx, 32, wgpu::TextureFormat::Rgba8Unorm);
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    let err = r
        .encode_into(
            &ctx,
            &mut encoder,
            &texture.create_view(&Default::default()),
            texture.format(),
            &v,
            &params,
        )
        .unwrap_err();
    assert!(matches!(err, HtsmError::Param(_)), "{err}");
}
