//! Equirectangular HDR environment maps: loading (`.hdr` Radiance RGBE, `.exr` OpenEXR including
//! DWAA/DWAB), projection onto nine SH coefficients (Mertens §5.3 after Ramamoorthi & Hanrahan
//! 2001) and a small float copy for the GPU's Fresnel reflection (Mertens §5.4).
//!
//! # Direction convention
//! lucent is **+Y up**, right-handed. Texel column `u ∈ [0, 1)` (left to right) and row
//! `v ∈ [0, 1]` (top to bottom) map to the unit direction
//!
//! ```text
//! θ = π v,  φ = 2π (u − ½),   d = (sin θ sin φ,  cos θ,  −sin θ cos φ)
//! u = ½ + atan2(d.x, −d.z) / 2π,   v = acos(d.y) / π
//! ```
//!
//! so the top row is the zenith (+Y), the image centre looks along −Z (the default camera's
//! forward direction) and `u = ¾` along +X: seen from inside, the panorama is not mirrored.
//! Rotating an environment by `α` about +Y (right-handed, counter-clockwise seen from above)
//! gives `L'(ω) = L(R_y(−α) ω)`.

use super::sh::Sh9;
use crate::Rgb;
use glam::Vec3;
use rayon::prelude::*;
use std::f32::consts::PI;
use std::path::Path;

/// Why an environment map could not be loaded; always names the file.
#[derive(Debug, thiserror::Error)]
pub enum EnvMapError {
    /// The file could not be read or decoded.
    #[error("{path}: cannot read environment map: {reason}")]
    Read { path: String, reason: String },
    /// The extension is not `.hdr` or `.exr`.
    #[error("{path}: unsupported environment map format (expected .hdr or .exr)")]
    Format { path: String },
    /// The image decoded but is not usable as radiance.
    #[error("{path}: {reason}")]
    Invalid { path: String, reason: String },
}

/// An equirectangular radiance map (linear, per channel; units of the file, treated as
/// W m^-2 sr^-1), row-major with row 0 at the zenith. See the module docs for the mapping.
#[derive(Clone, Debug, PartialEq)]
pub struct EnvMap {
    /// Width in texels (the full 360° of longitude).
    pub width: usize,
    /// Height in texels (180° of latitude, zenith to nadir).
    pub height: usize,
    /// `width * height` radiance texels, row-major.
    pub texels: Vec<Rgb>,
}

/// The unit direction at equirect coordinates `(u, v)` (see the module docs).
#[inline]
pub fn equirect_direction(u: f32, v: f32) -> Vec3 {
    let theta = PI * v;
    let phi = 2.0 * PI * (u - 0.5);
    let (st, ct) = theta.sin_cos();
    let (sp, cp) = phi.sin_cos();
    Vec3::new(st * sp, ct, -st * cp)
}

/// The equirect coordinates `(u ∈ [0, 1), v ∈ [0, 1])` of unit direction `d`.
#[inline]
pub fn equirect_uv(d: Vec3) -> (f32, f32) {
    let u = 0.5 + d.x.atan2(-d.z) / (2.0 * PI);
    let v = d.y.clamp(-1.0, 1.0).acos() / PI;
    (u.rem_euclid(1.0), v)
}

impl EnvMap {
    /// A map from its texels.
    ///
    /// # Panics
    /// If `texels.len() != width * height` or a side is zero.
    pub fn new(width: usize, height: usize, texels: Vec<Rgb>) -> Self {
        assert!(width > 0 && height > 0, "empty environment map");
        assert_eq!(texels.len(), width * height, "texel count");
        EnvMap { width, height, texels }
    }

    /// A map whose texels sample `radiance(direction)` at texel centres (for tests and
    /// procedural skies).
    pub fn from_fn(width: usize, height: usize, radiance: impl Fn(Vec3) -> Rgb + Sync) -> Self {
        let texels = (0..width * height)
            .into_par_iter()
            .map(|k| {
                let (i, j) = (k % width, k / width);
                radiance(equirect_direction(
                    (i as f32 + 0.5) / width as f32,
                    (j as f32 + 0.5) / height as f32,
                ))
            })
            .collect();
        EnvMap::new(width, height, texels)
    }

    /// Loads an equirectangular `.hdr` (Radiance RGBE) or `.exr` (OpenEXR, any compression the
    /// `exr` crate reads, DWAB included; the first RGB(A) layer) file. Rejects empty images and
    /// non-finite or negative texels, naming the file.
    pub fn load(path: &Path) -> Result<EnvMap, EnvMapError> {
        let name = path.display().to_string();
        let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
        if ext != "exr" && ext != "hdr" {
            return Err(EnvMapError::Format { path: name });
        }
        let bytes = crate::limits::read_input(path)
            .map_err(|reason| EnvMapError::Read { path: name.clone(), reason })?;
        Self::from_bytes(&bytes, &ext, &name)
    }

    /// Decodes an environment map held in memory: `ext` is `"exr"` or `"hdr"`, `name` stands
    /// for the file in errors. The header's size is checked against the decoding budget and the
    /// data's length ([`crate::limits`]) before any texel is allocated.
    pub fn from_bytes(bytes: &[u8], ext: &str, name: &str) -> Result<EnvMap, EnvMapError> {
        let decode = match ext {
            "exr" => decode_exr,
            "hdr" => decode_hdr,
            _ => return Err(EnvMapError::Format { path: name.into() }),
        };
        let (width, height, texels) = crate::limits::catch_quietly(|| decode(bytes))
            .unwrap_or_else(|panic| Err(format!("malformed file (decoder failed: {panic})")))
            .map_err(|reason| EnvMapError::Read { path: name.into(), reason })?;
        EnvMap::checked(name.into(), width, height, texels)
    }

    /// One of the light probes compiled into lucent, by name (case-insensitive): `courtyard` or
    /// `forest` (see [`BUILTIN_PROBES`]); `None` for any other name.
    pub fn builtin(name: &str) -> Option<Result<EnvMap, EnvMapError>> {
        let wanted = name.trim().to_ascii_lowercase();
        let (probe, bytes) = BUILTIN_PROBES.iter().find(|(n, _)| *n == wanted)?;
        let label = format!("built-in probe {probe}");
        Some(
            decode_exr(bytes)
                .map_err(|reason| EnvMapError::Read { path: label.clone(), reason })
                .and_then(|(w, h, texels)| EnvMap::checked(label, w, h, texels)),
        )
    }

    /// Rejects empty images and non-finite texels (naming `name`), clamps negative ones.
    fn checked(name: String, width: usize, height: usize, texels: Vec<Rgb>) -> Result<EnvMap, EnvMapError> {
        if width == 0 || height == 0 {
            return Err(EnvMapError::Invalid { path: name, reason: "image has no texels".into() });
        }
        if let Some(k) = texels.iter().position(|t| !t.is_finite()) {
            return Err(EnvMapError::Invalid {
                path: name,
                reason: format!(
                    "texel ({}, {}) is {:?}: radiance must be finite",
                    k % width,
                    k / width,
                    texels[k].to_array()
                ),
            });
        }
        // Lossy codecs (EXR's DWAA/DWAB, as in the bundled probes) ring slightly below zero in
        // dark areas; negative radiance is not physical, so clamp.
        let texels = texels.into_iter().map(|t| t.max(Rgb::ZERO)).collect();
        Ok(EnvMap::new(width, height, texels))
    }

    /// The radiance of texel `(i, j)` (column, row).
    #[inline]
    pub fn texel(&self, i: usize, j: usize) -> Rgb {
        self.texels[j * self.width + i]
    }

    /// The direction through the centre of texel `(i, j)`.
    #[inline]
    pub fn texel_direction(&self, i: usize, j: usize) -> Vec3 {
        equirect_direction((i as f32 + 0.5) / self.width as f32, (j as f32 + 0.5) / self.height as f32)
    }

    /// Exact solid angle (sr) of one texel in row `j`: `(2π / width) (cos θ_top − cos θ_bottom)`.
    /// The rows sum to 4π.
    #[inline]
    pub fn texel_solid_angle(&self, j: usize) -> f32 {
        let h = self.height as f64;
        let t0 = std::f64::consts::PI * j as f64 / h;
        let t1 = std::f64::consts::PI * (j + 1) as f64 / h;
        (2.0 * std::f64::consts::PI / self.width as f64 * (t0.cos() - t1.cos())) as f32
    }

    /// Radiance looked up (nearest texel) in unit direction `d`.
    pub fn radiance(&self, d: Vec3) -> Rgb {
        let (u, v) = equirect_uv(d);
        let i = ((u * self.width as f32) as usize).min(self.width - 1);
        let j = ((v * self.height as f32) as usize).min(self.height - 1);
        self.texel(i, j)
    }

    /// Projects the map onto the nine SH coefficients: `L_lm = Σ_texels L Y_lm(ω) Δω` with each
    /// texel's exact solid angle (the `sin θ` weighting of equirect rows), summed in `f64`.
    pub fn project_sh(&self) -> Sh9 {
        let rows: Vec<[[f64; 3]; 9]> = (0..self.height)
            .into_par_iter()
            .map(|j| {
                let w = self.texel_solid_angle(j) as f64;
                let mut acc = [[0.0f64; 3]; 9];
                for i in 0..self.width {
                    let y = super::sh::sh_basis(self.texel_direction(i, j));
                    let l = self.texel(i, j);
                    for (a, yk) in acc.iter_mut().zip(y) {
                        for c in 0..3 {
                            a[c] += (l[c] * yk) as f64 * w;
                        }
                    }
                }
                acc
            })
            .collect();
        let mut total = [[0.0f64; 3]; 9];
        for r in rows {
            for (t, a) in total.iter_mut().zip(r) {
                for c in 0..3 {
                    t[c] += a[c];
                }
            }
        }
        Sh9::from_array(total.map(|t| t.map(|v| v as f32)))
    }

    /// A `width x height` copy, each texel the solid-angle-weighted mean of the source texels
    /// whose centres fall in it (a box filter; exact when the sizes divide). For the GPU's
    /// reflection lookups, e.g. 256 x 128 RGB `f32`, same mapping as this map.
    ///
    /// # Panics
    /// If a side is zero.
    pub fn downsampled(&self, width: usize, height: usize) -> EnvMap {
        assert!(width > 0 && height > 0, "empty target size");
        let mut sum = vec![Rgb::ZERO; width * height];
        let mut weight = vec![0.0f32; width * height];
        for j in 0..self.height {
            let w = self.texel_solid_angle(j);
            let tj = (j * height / self.height).min(height - 1);
            for i in 0..self.width {
                let ti = (i * width / self.width).min(width - 1);
                sum[tj * width + ti] += self.texel(i, j) * w;
                weight[tj * width + ti] += w;
            }
        }
        let texels = (0..width * height)
            .map(|k| {
                if weight[k] > 0.0 {
                    sum[k] / weight[k]
                } else {
                    // Target finer than the source: nearest source texel.
                    let (i, j) = (k % width, k / width);
                    self.radiance(equirect_direction(
                        (i as f32 + 0.5) / width as f32,
                        (j as f32 + 0.5) / height as f32,
                    ))
                }
            })
            .collect();
        EnvMap::new(width, height, texels)
    }

    /// The map rotated by `degrees` about +Y (see the module docs), by whole columns for a
    /// multiple of `360 / width` and nearest column otherwise.
    pub fn rotated(&self, degrees: f32) -> EnvMap {
        // L'(φ) = L(φ + α): column i shows the source column i + α/(2π) * width.
        let shift = (degrees / 360.0 * self.width as f32).round() as i64;
        let w = self.width as i64;
        let texels = (0..self.width * self.height)
            .map(|k| {
                let (i, j) = (k % self.width, k / self.width);
                let src = (i as i64 + shift).rem_euclid(w) as usize;
                self.texel(src, j)
            })
            .collect();
        EnvMap::new(self.width, self.height, texels)
    }
}

/// The light probes compiled into lucent, `(name, OpenEXR bytes)`: 1024 x 512 equirectangular,
/// DWAB-compressed, CC0 (assets/README.md gives their source and licence).
pub const BUILTIN_PROBES: [(&str, &[u8]); 2] = [
    ("courtyard", include_bytes!("../../../../assets/courtyard.exr")),
    ("forest", include_bytes!("../../../../assets/forest.exr")),
];

/// Bytes of the decoded map per texel (our `Rgb` plus the decoder's own RGBA float copy).
const DECODED_BYTES_PER_TEXEL: u128 = 32;

fn decode_exr(bytes: &[u8]) -> Result<(usize, usize, Vec<Rgb>), String> {
    use exr::prelude::*;
    // The header first: its data window sizes the texel buffer allocated below.
    let meta = exr::meta::MetaData::read_from_buffered(std::io::Cursor::new(bytes), false)
        .map_err(|e| e.to_string())?;
    // Per layer: our texels, the decoder's copy of every channel, and its block buffers (a
    // block's size comes from the tile size or scan lines, which a header may set far beyond
    // its image).
    let decoded: u128 = meta
        .headers
        .iter()
        .map(|h| {
            let bytes_per_pixel = h.channels.bytes_per_pixel as u128;
            let block_pixels = match h.blocks {
                exr::meta::BlockDescription::Tiles(t) => t.tile_size.area() as u128,
                exr::meta::BlockDescription::ScanLines => {
                    h.compression.scan_lines_per_block() as u128 * h.layer_size.width() as u128
                }
            };
            h.layer_size.area() as u128 * (DECODED_BYTES_PER_TEXEL + bytes_per_pixel)
                + 2 * block_pixels * bytes_per_pixel
        })
        .sum();
    crate::limits::plausible_expansion("the image", decoded, bytes.len())?;
    struct Pixels {
        width: usize,
        texels: Vec<Rgb>,
    }
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .rgba_channels(
            |resolution, _channels: &RgbaChannels| Pixels {
                width: resolution.width(),
                texels: vec![Rgb::ZERO; resolution.width() * resolution.height()],
            },
            |pixels: &mut Pixels, pos, (r, g, b, _a): (f32, f32, f32, f32)| {
                pixels.texels[pos.y() * pixels.width + pos.x()] = Rgb::new(r, g, b);
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_buffered(std::io::Cursor::new(bytes))
        .map_err(|e| e.to_string())?;
    let pixels = image.layer_data.channel_data.pixels;
    let size = image.layer_data.size;
    Ok((size.width(), size.height(), pixels.texels))
}

fn decode_hdr(bytes: &[u8]) -> Result<(usize, usize, Vec<Rgb>), String> {
    let header =
        image::codecs::hdr::HdrDecoder::new(std::io::Cursor::new(bytes)).map_err(|e| e.to_string())?;
    let meta = header.metadata();
    let texels = meta.width as u128 * meta.height as u128;
    crate::limits::plausible_expansion("the image", texels * DECODED_BYTES_PER_TEXEL, bytes.len())?;
    // Decode with the header already read rather than parsing the file again.
    let img = image::DynamicImage::from_decoder(header).map_err(|e| e.to_string())?.into_rgb32f();
    let (w, h) = (img.width() as usize, img.height() as usize);
    let texels = img.pixels().map(|p| Rgb::new(p.0[0], p.0[1], p.0[2])).collect();
    Ok((w, h, texels))
}
