//! What `lucent render` writes: a tone-mapped PNG, or a linear-radiance OpenEXR of the HDR frame
//! before exposure, tone curve and gamma. Both are written atomically (a temporary file beside
//! the target, then a rename), so readers never see a partial file and an error leaves the
//! target untouched.
//!
//! The EXR holds four 32-bit float channels: R, G, B are the radiance the shader computes (the
//! same units as the lights' irradiance over steradians; Mertens eq. 3 per pixel for the
//! homogeneous methods, Shopf table 4.1 for HTSM), *premultiplied* by A, the pixel's coverage of
//! the object from the rasteriser (the fraction of the 4 MSAA samples that hit the mesh for the
//! homogeneous methods, 0 or 1 for HTSM). Nothing but the object is in it: the background is
//! radiance 0 with alpha 0 even where the PNG shows the environment map behind the object. The
//! GPU target is half float, so values carry about 3 significant digits.

use anyhow::{Context, Result, bail};
use std::io::Write;
use std::path::{Path, PathBuf};

/// The HDR frame as rendered: `width * height` RGBA pixels, rows top first, RGB radiance
/// premultiplied by A = coverage (0..1).
#[derive(Clone, Debug, PartialEq)]
pub struct HdrImage {
    /// Width, pixels.
    pub width: u32,
    /// Height, pixels.
    pub height: u32,
    /// RGBA per pixel: radiance (premultiplied) and coverage.
    pub pixels: Vec<[f32; 4]>,
}

/// One rendered frame in the format it will be written in.
pub enum Frame {
    /// The tone-mapped image.
    Ldr(image::RgbaImage),
    /// The linear-radiance frame.
    Hdr(HdrImage),
}

impl Frame {
    /// Writes the frame to `out` in its format, atomically.
    pub fn write(&self, out: &Path) -> Result<()> {
        match self {
            Frame::Ldr(img) => write_png_atomically(img, out),
            Frame::Hdr(hdr) => write_exr_atomically(hdr, out),
        }
    }
}

/// The directory a file `out` goes into (`.` for a bare file name).
pub fn output_dir(out: &Path) -> PathBuf {
    match out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// Encodes `image` as PNG and writes it to `out` atomically.
pub fn write_png_atomically(image: &image::RgbaImage, out: &Path) -> Result<()> {
    let mut png = Vec::new();
    image
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .context("encoding the PNG")?;
    write_atomically(&png, out)
}

/// Encodes `hdr` as a 32-bit float RGBA OpenEXR and writes it to `out` atomically.
pub fn write_exr_atomically(hdr: &HdrImage, out: &Path) -> Result<()> {
    write_atomically(&encode_exr(hdr)?, out)
}

/// The OpenEXR file of `hdr` in memory (scan lines, the `exr` crate's default compression).
pub fn encode_exr(hdr: &HdrImage) -> Result<Vec<u8>> {
    use exr::prelude::{Image, SpecificChannels, Vec2, WritableImage};
    let (w, h) = (hdr.width as usize, hdr.height as usize);
    if hdr.pixels.len() != w * h {
        bail!("EXR: {} pixels for {w}x{h}", hdr.pixels.len());
    }
    let channels = SpecificChannels::rgba(|Vec2(x, y): Vec2<usize>| {
        let [r, g, b, a] = hdr.pixels[y * w + x];
        (r, g, b, a)
    });
    let mut bytes = Vec::new();
    Image::from_channels((w, h), channels)
        .write()
        .to_buffered(std::io::Cursor::new(&mut bytes))
        .map_err(|e| anyhow::anyhow!("encoding the EXR: {e}"))?;
    Ok(bytes)
}

/// Writes `bytes` into a temporary file next to `out`, then renames it over `out`.
fn write_atomically(bytes: &[u8], out: &Path) -> Result<()> {
    let name =
        out.file_name().with_context(|| format!("{}: not a file name", out.display()))?.to_string_lossy();
    let tmp = output_dir(out).join(format!(".{name}.{}.tmp", std::process::id()));
    let result = (|| -> std::io::Result<()> {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, out)
    })();
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(e).with_context(|| format!("{}: cannot write the image", out.display()));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The encoded file reads back bit for bit through the `exr` crate's reader.
    #[test]
    fn exr_round_trips() {
        let pixels: Vec<[f32; 4]> =
            (0..6).map(|i| [i as f32 * 0.5, 1e-3 * i as f32, 7.25, (i % 2) as f32]).collect();
        let hdr = HdrImage { width: 3, height: 2, pixels };
        let path = std::env::temp_dir().join(format!("lucent-exr-roundtrip-{}.exr", std::process::id()));
        write_exr_atomically(&hdr, &path).unwrap();
        let read = exr::prelude::read_first_rgba_layer_from_file(
            &path,
            |res, _| vec![[0.0f32; 4]; res.width() * res.height()],
            |v: &mut Vec<[f32; 4]>, p, (r, g, b, a): (f32, f32, f32, f32)| {
                v[p.y() * 3 + p.x()] = [r, g, b, a]
            },
        )
        .map(|img| img.layer_data.channel_data.pixels);
        let _ = std::fs::remove_file(&path);
        assert_eq!(read.unwrap(), hdr.pixels);
    }
}
