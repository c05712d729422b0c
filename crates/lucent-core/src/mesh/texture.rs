//! Colour textures on meshes (issue 18): the texture coordinates the loaders keep, the image
//! they index, and what the renderer does with them.
//!
//! Subsurface light is modulated by the texture twice: at entry (the irradiance of each face is
//! multiplied by the square root of the texture averaged over the face, before the solve) and
//! at exit (the GPU multiplies the diffuse radiance by the square root of the texture per
//! pixel). A uniformly lit flat region of one texel colour `c` then shows `sqrt(c) sqrt(c) = c`.
//! The hierarchy between the two gathers untextured transport.
//!
//! - UVs are kept per triangle corner ([`MeshTexture::corner_uvs`], parallel to
//!   `Mesh::triangles`), so welding vertices by position (OBJ, glTF) keeps the surface
//!   connected while a UV seam stays sharp. The GPU draws a copy split at the seams
//!   ([`UvSplit`]).
//! - UVs follow glTF's convention: `(0, 0)` is the top-left of the image, `v` grows down; the
//!   OBJ and PLY loaders flip `v` into it. Sampling repeats outside `[0, 1]`.
//! - Images are PNG, JPEG or Radiance HDR. 8- and 16-bit images are sRGB and are decoded to
//!   linear RGB; HDR images are linear. A file whose header states more than
//!   [`MAX_TEXTURE_SIDE`] texels on a side, or more than `limits::MAX_DECODED_BYTES` decoded,
//!   is refused before it is decoded.

use super::{Mesh, MeshError};
use glam::{Vec2, Vec3};
use std::borrow::Cow;
use std::collections::HashMap;
use std::io::Cursor;
use std::path::PathBuf;

/// Largest accepted texture side, texels.
pub const MAX_TEXTURE_SIDE: u32 = 4096;

/// Where a mesh's colour image comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum TextureSource {
    /// A file (already resolved inside the mesh file's folder).
    File(PathBuf),
    /// Bytes held in the mesh file (a glTF data URI or buffer view); `name` stands for them in
    /// messages.
    Embedded {
        /// E.g. `model.glb (image 0)`.
        name: String,
        /// The encoded image.
        bytes: Vec<u8>,
    },
}

impl TextureSource {
    /// The file or name, for messages.
    pub fn name(&self) -> String {
        match self {
            TextureSource::File(p) => p.display().to_string(),
            TextureSource::Embedded { name, .. } => name.clone(),
        }
    }
}

/// The texture coordinates of a loaded mesh and the image its material names.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshTexture {
    /// UV of each corner of each triangle, parallel to `Mesh::triangles`.
    pub corner_uvs: Vec<[Vec2; 3]>,
    /// The colour image (OBJ `map_Kd`, glTF `baseColorTexture`, PLY `comment TextureFile`);
    /// `None` when the file has UVs but names no image.
    pub image: Option<TextureSource>,
}

/// A decoded texture: linear RGB, rows top first.
#[derive(Clone, Debug, PartialEq)]
pub struct TextureImage {
    /// Width, texels.
    pub width: u32,
    /// Height, texels.
    pub height: u32,
    /// `width * height` linear RGB texels, rows top first.
    pub texels: Vec<Vec3>,
}

/// Reads and decodes `source`, refusing (from the header alone) images over the budget. Errors
/// are one line naming the image file.
pub fn load_texture(source: &TextureSource) -> Result<TextureImage, MeshError> {
    let name = source.name();
    let fail = |reason: String| MeshError::invalid(&name, reason);
    let read;
    let bytes: &[u8] = match source {
        TextureSource::File(p) => {
            read = crate::limits::read_input(p).map_err(fail)?;
            &read
        }
        TextureSource::Embedded { bytes, .. } => bytes,
    };
    let reader = || {
        image::ImageReader::new(Cursor::new(bytes))
            .with_guessed_format()
            .map_err(|e| format!("cannot read the texture: {e}"))
    };
    let (w, h) = reader()
        .map_err(fail)?
        .into_dimensions()
        .map_err(|e| fail(format!("not a readable texture image: {e}")))?;
    if w == 0 || h == 0 || w > MAX_TEXTURE_SIDE || h > MAX_TEXTURE_SIDE {
        return Err(fail(format!(
            "texture is {w}x{h} texels; at most {MAX_TEXTURE_SIDE}x{MAX_TEXTURE_SIDE} (and at least 1x1) are accepted"
        )));
    }
    // Decoded as f32 RGBA (16 bytes a texel), and kept as f32 RGB (12).
    // (No expansion-ratio check: flat texture regions compress far beyond any fixed ratio.)
    let decoded = w as u64 * h as u64 * 28;
    if decoded > crate::limits::MAX_DECODED_BYTES {
        let budget = crate::limits::MAX_DECODED_BYTES;
        return Err(fail(format!(
            "texture would take {decoded} bytes decoded, more than the {budget}-byte budget"
        )));
    }
    let image = crate::limits::catch_quietly(|| reader().and_then(|r| r.decode().map_err(|e| e.to_string())))
        .and_then(|r| r)
        .map_err(|e| fail(format!("corrupt texture image: {e}")))?;
    let linear = matches!(image.color(), image::ColorType::Rgb32F | image::ColorType::Rgba32F);
    let rgba = image.to_rgba32f();
    let to_linear = |c: f32| {
        if linear {
            c.max(0.0)
        } else if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    let texels =
        rgba.pixels().map(|p| Vec3::new(to_linear(p[0]), to_linear(p[1]), to_linear(p[2]))).collect();
    Ok(TextureImage { width: w, height: h, texels })
}

impl TextureImage {
    /// The texture at `uv` (bilinear, repeating).
    pub fn sample(&self, uv: Vec2) -> Vec3 {
        let (w, h) = (self.width as i64, self.height as i64);
        let x = uv.x.rem_euclid(1.0) * w as f32 - 0.5;
        let y = uv.y.rem_euclid(1.0) * h as f32 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let at = |i: i64, j: i64| self.texels[(j.rem_euclid(h) * w + i.rem_euclid(w)) as usize];
        let (i, j) = (x0 as i64, y0 as i64);
        let top = at(i, j).lerp(at(i + 1, j), fx);
        let bottom = at(i, j + 1).lerp(at(i + 1, j + 1), fx);
        top.lerp(bottom, fy)
    }

    /// The entry factor of each face: `sqrt(texture)` averaged over the face's UV triangle (36
    /// stratified samples), the square root that with the per-pixel exit factor makes a flat
    /// uniformly lit region show the texel's colour.
    pub fn entry_factors(&self, corner_uvs: &[[Vec2; 3]]) -> Vec<Vec3> {
        const N: u32 = 8;
        corner_uvs
            .iter()
            .map(|[a, b, c]| {
                let (mut sum, mut count) = (Vec3::ZERO, 0.0);
                for i in 0..N {
                    for j in 0..N - i {
                        // Barycentric centres of a regular grid of sub-triangles.
                        let (s, t) = ((i as f32 + 1.0 / 3.0) / N as f32, (j as f32 + 1.0 / 3.0) / N as f32);
                        let uv = *a + (*b - *a) * s + (*c - *a) * t;
                        sum += self.sample(uv).max(Vec3::ZERO).map(f32::sqrt);
                        count += 1.0;
                    }
                }
                sum / count
            })
            .collect()
    }
}

/// A mesh split at its UV seams for drawing: vertex `k` of the split is vertex `source[k]` of
/// the mesh with texture coordinate `uvs[k]`.
#[derive(Clone, Debug, PartialEq)]
pub struct UvSplit {
    /// The mesh vertex each split vertex copies.
    pub source: Vec<u32>,
    /// The texture coordinate of each split vertex.
    pub uvs: Vec<Vec2>,
    /// The mesh's triangles, indexing split vertices.
    pub triangles: Vec<[u32; 3]>,
}

impl UvSplit {
    /// Splits `mesh` where `corner_uvs` (parallel to its triangles) differ at a vertex.
    pub fn new(mesh: &Mesh, corner_uvs: &[[Vec2; 3]]) -> UvSplit {
        assert_eq!(corner_uvs.len(), mesh.triangles.len(), "one UV triple per triangle");
        let mut index: HashMap<(u32, [u32; 2]), u32> = HashMap::new();
        let mut split = UvSplit { source: Vec::new(), uvs: Vec::new(), triangles: Vec::new() };
        for (t, uvs) in mesh.triangles.iter().zip(corner_uvs) {
            let tri = std::array::from_fn(|k| {
                let key = (t[k], uvs[k].to_array().map(f32::to_bits));
                *index.entry(key).or_insert_with(|| {
                    split.source.push(t[k]);
                    split.uvs.push(uvs[k]);
                    split.source.len() as u32 - 1
                })
            });
            split.triangles.push(tri);
        }
        split
    }

    /// Per-vertex values of the mesh copied to the split vertices.
    pub fn gather<T: Copy>(&self, values: &[T]) -> Vec<T> {
        if values.is_empty() {
            // Per-vertex data that is absent (no single scattering, say) stays absent.
            return Vec::new();
        }
        self.source.iter().map(|&v| values[v as usize]).collect()
    }

    /// Per-vertex `values` as a GPU mesh takes them: gathered through `split` where the mesh
    /// has one (a textured mesh), else as they are.
    pub fn through<'a, T: Copy>(split: Option<&UvSplit>, values: &'a [T]) -> Cow<'a, [T]> {
        match split {
            Some(s) => Cow::Owned(s.gather(values)),
            None => Cow::Borrowed(values),
        }
    }
}

/// A mesh's texture ready to render: UVs per triangle corner and the decoded image.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// UV of each corner of each triangle, parallel to `Mesh::triangles`.
    pub corner_uvs: Vec<[Vec2; 3]>,
    /// The colour image, linear RGB.
    pub image: TextureImage,
}

impl MeshTexture {
    /// Decodes the image ([`load_texture`]): `None` when the mesh names none.
    pub fn load(self) -> Result<Option<Texture>, MeshError> {
        let Some(source) = &self.image else { return Ok(None) };
        let image = load_texture(source)?;
        Ok(Some(Texture { corner_uvs: self.corner_uvs, image }))
    }
}

impl Texture {
    /// The entry factor of each face ([`TextureImage::entry_factors`]).
    pub fn entry_factors(&self) -> Vec<Vec3> {
        self.image.entry_factors(&self.corner_uvs)
    }
}
