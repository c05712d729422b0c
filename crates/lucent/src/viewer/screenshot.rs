//! Screenshots: the frame (3D view and panel) is drawn again into an offscreen texture of the
//! surface's format, read back and written as a PNG. Surfaces cannot be read portably, so the
//! offscreen copy is what makes screenshots work on every backend.

use anyhow::Context as _;
use std::path::{Path, PathBuf};

/// An offscreen colour target the frame can be drawn into and read back from.
pub struct Offscreen {
    /// The texture (RENDER_ATTACHMENT | COPY_SRC).
    pub texture: wgpu::Texture,
    /// A view of it for render passes.
    pub view: wgpu::TextureView,
}

impl Offscreen {
    /// A `width` x `height` target of `format`.
    pub fn new(device: &wgpu::Device, format: wgpu::TextureFormat, width: u32, height: u32) -> Self {
        let texture = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("viewer screenshot"),
            size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let view = texture.create_view(&Default::default());
        Offscreen { texture, view }
    }

    /// Reads the texture back (waiting for the GPU) and writes it to `path` as an RGB PNG.
    pub fn save_png(&self, device: &wgpu::Device, queue: &wgpu::Queue, path: &Path) -> anyhow::Result<()> {
        let image = self.read_rgba(device, queue)?;
        let rgb = image::DynamicImage::ImageRgba8(image).into_rgb8();
        rgb.save(path).with_context(|| format!("writing the screenshot {}", path.display()))
    }

    fn read_rgba(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> anyhow::Result<image::RgbaImage> {
        let (w, h) = (self.texture.width(), self.texture.height());
        let format = self.texture.format();
        let bgra = match format {
            wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb => true,
            wgpu::TextureFormat::Rgba8Unorm | wgpu::TextureFormat::Rgba8UnormSrgb => false,
            other => anyhow::bail!("screenshots of a {other:?} surface are not supported"),
        };
        let row = w * 4;
        let padded = row.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        let staging = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("viewer screenshot staging"),
            size: (padded * h) as u64,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        let mut encoder = device.create_command_encoder(&Default::default());
        encoder.copy_texture_to_buffer(
            self.texture.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: &staging,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(padded),
                    rows_per_image: Some(h),
                },
            },
            self.texture.size(),
        );
        queue.submit([encoder.finish()]);
        let slice = staging.slice(..);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        device.poll(wgpu::PollType::wait_indefinitely()).context("waiting for the screenshot copy")?;
        rx.recv()
            .context("the screenshot read-back was dropped")?
            .context("mapping the screenshot buffer")?;
        let mut pixels = Vec::with_capacity((row * h) as usize);
        {
            let data = slice
                .get_mapped_range()
                .map_err(|e| anyhow::anyhow!("reading the screenshot buffer: {e}"))?;
            for y in 0..h as usize {
                let start = y * padded as usize;
                pixels.extend_from_slice(&data[start..start + row as usize]);
            }
        }
        staging.unmap();
        if bgra {
            pixels.chunks_exact_mut(4).for_each(|p| p.swap(0, 2));
        }
        image::RgbaImage::from_raw(w, h, pixels).context("screenshot buffer size")
    }
}

/// `lucent-YYYYMMDD-HHMMSS.png` in the current directory (UTC), with a counter if taken.
pub fn timestamped_path() -> PathBuf {
    let secs =
        std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map(|d| d.as_secs()).unwrap_or(0);
    let (y, mo, d) = civil_from_days((secs / 86_400) as i64);
    let s = secs % 86_400;
    let stem = format!("lucent-{y:04}{mo:02}{d:02}-{:02}{:02}{:02}", s / 3600, s / 60 % 60, s % 60);
    let mut path = PathBuf::from(format!("{stem}.png"));
    let mut n = 1;
    while path.exists() {
        path = PathBuf::from(format!("{stem}-{n}.png"));
        n += 1;
    }
    path
}

/// Gregorian date of a day count since 1970-01-01 (Howard Hinnant's `civil_from_days`).
fn civil_from_days(z: i64) -> (i64, u32, u32) {
    let z = z + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let m = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    (yoe + era * 400 + i64::from(m <= 2), m, d)
}

#[cfg(test)]
mod tests {
    use super::civil_from_days;

    /// Known dates: the epoch, a leap day, and 2026-11-22 (day 20779).
    #[test]
    fn civil_dates() {
        assert_eq!(civil_from_days(0), (1970, 1, 1));
        assert_eq!(civil_from_days(11_016), (2000, 2, 29));
        assert_eq!(civil_from_days(20_779), (2026, 11, 22));
    }
}
