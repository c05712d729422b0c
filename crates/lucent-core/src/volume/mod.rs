//! Scalar density volumes for the heterogeneous method (Shopf 2007, §4.2 "hybrid
//! polygonal/voxel representation", §4.3.2 "evaluating material density").
//!
//! A [`DensityVolume`] is a regular grid of densities `alpha_d` in `[0, 1]` laid over the
//! axis-aligned bounding box of a mesh: texture coordinate `(0, 0, 0)` is the box's minimum corner
//! and `(1, 1, 1)` its maximum corner, voxel `(i, j, k)` has its centre at
//! `((i + 0.5) / nx, (j + 0.5) / ny, (k + 0.5) / nz)` (the GPU convention). The density raises the
//! base absorption of the material, `sigma_at = sigma_a + alpha_d` (Shopf eq. 4.1); how a density
//! is scaled to a coefficient is the renderer's choice (see `lucent_gpu::htsm`).
//!
//! Sources: procedural marble/mineral veins and the thesis's embedded cube
//! ([`procedural`]), uniform density, raw 8/16/32-bit grids and lucent's own `LVOL` file
//! format ([`io`]); [`VolumeSpec`] parses the `--volume` strings that name them.

pub mod io;
pub mod procedural;
#[cfg(test)]
mod tests;

pub use io::{RawFormat, VolumeSpec, load_lvol, load_raw, parse_lvol, parse_raw, save_lvol};

/// The largest side accepted for a volume, in voxels: wgpu's default limit for 3D textures
/// (`max_texture_dimension_3d`), so every volume lucent accepts can be uploaded.
pub const MAX_DIM: u32 = 2048;

/// The most voxels a volume may have: the decoding budget of [`crate::limits`] at four bytes a
/// voxel (268M, e.g. 645^3 or 2048 x 2048 x 64).
pub const MAX_VOXELS: u64 = crate::limits::MAX_DECODED_BYTES / 4;

/// Why a volume could not be made or read. File errors always name the file.
#[derive(Debug, thiserror::Error)]
pub enum VolumeError {
    /// The file could not be opened or read (or is not a regular file, or is too large).
    #[error("{path}: cannot read volume: {reason}")]
    Read { path: String, reason: String },
    /// The file could not be written.
    #[error("{path}: cannot write volume: {source}")]
    Write {
        path: String,
        #[source]
        source: std::io::Error,
    },
    /// The file's length does not match its dimensions and voxel format.
    #[error("{path}: expected {expected} bytes for {what}, found {actual}")]
    Size { path: String, what: String, expected: u64, actual: u64 },
    /// The `LVOL` header is not one lucent understands.
    #[error("{path}: {reason}")]
    Header { path: String, reason: String },
    /// A voxel is not a density in `[0, 1]` (NaN, infinite or out of range).
    #[error("{path}: voxel {index} has density {value}, outside [0, 1]")]
    Value { path: String, index: usize, value: f32 },
    /// The dimensions are zero, too large, or disagree with the data.
    #[error("bad volume dimensions {dims:?}: {reason}")]
    Dims { dims: [u32; 3], reason: String },
    /// A `--volume` string that does not parse.
    #[error("bad volume spec '{spec}': {reason}")]
    Spec { spec: String, reason: String },
}

/// A scalar density grid over a mesh's bounding box.
///
/// `data[i + nx * (j + ny * k)]` is the density of voxel `(i, j, k)`, dimensionless, in `[0, 1]`
/// (0: only the base material, 1: densest). x varies fastest, as in a 3D texture upload.
#[derive(Clone, Debug, PartialEq)]
pub struct DensityVolume {
    /// Voxels along x, y and z; each in `1..=MAX_DIM`.
    pub dims: [u32; 3],
    /// Densities in `[0, 1]`, `dims[0] * dims[1] * dims[2]` of them, x fastest.
    pub data: Vec<f32>,
}

impl DensityVolume {
    /// A volume from its parts, checking the dimensions, the length and that every density is
    /// finite and in `[0, 1]`.
    pub fn new(dims: [u32; 3], data: Vec<f32>) -> Result<Self, VolumeError> {
        let n = check_dims(dims)?;
        if data.len() != n {
            return Err(VolumeError::Dims {
                dims,
                reason: format!("{} voxels expected, {} given", n, data.len()),
            });
        }
        if let Some((index, &value)) = data.iter().enumerate().find(|(_, d)| !(0.0..=1.0).contains(*d)) {
            return Err(VolumeError::Value { path: "(in memory)".into(), index, value });
        }
        Ok(DensityVolume { dims, data })
    }

    /// The same density `density` (clamped to `[0, 1]`) everywhere.
    pub fn uniform(dims: [u32; 3], density: f32) -> Result<Self, VolumeError> {
        let n = check_dims(dims)?;
        Ok(DensityVolume { dims, data: vec![density.clamp(0.0, 1.0); n] })
    }

    /// Number of voxels.
    pub fn len(&self) -> usize {
        self.data.len()
    }

    /// True when there are no voxels (never for a volume built by this module).
    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }

    /// Density of voxel `(i, j, k)`; indices are clamped to the grid (clamp-to-edge).
    #[inline]
    pub fn voxel(&self, i: i64, j: i64, k: i64) -> f32 {
        let [nx, ny, nz] = self.dims.map(|d| d as i64);
        let (i, j, k) = (i.clamp(0, nx - 1), j.clamp(0, ny - 1), k.clamp(0, nz - 1));
        self.data[(i + nx * (j + ny * k)) as usize]
    }

    /// Trilinearly filtered density at texture coordinate `tc` (box `[0, 1]^3`), clamp-to-edge,
    /// exactly as a linear-filtered 3D texture samples it: the CPU reference for the GPU fetch.
    pub fn sample_linear(&self, tc: glam::Vec3) -> f32 {
        let dims = glam::Vec3::new(self.dims[0] as f32, self.dims[1] as f32, self.dims[2] as f32);
        let p = tc * dims - 0.5;
        let base = p.floor();
        let f = p - base;
        let (i, j, k) = (base.x as i64, base.y as i64, base.z as i64);
        let mut acc = 0.0;
        for (dk, wk) in [(0, 1.0 - f.z), (1, f.z)] {
            for (dj, wj) in [(0, 1.0 - f.y), (1, f.y)] {
                for (di, wi) in [(0, 1.0 - f.x), (1, f.x)] {
                    acc += wi * wj * wk * self.voxel(i + di, j + dj, k + dk);
                }
            }
        }
        acc
    }

    /// Mean density over all voxels.
    pub fn mean(&self) -> f32 {
        (self.data.iter().map(|&d| d as f64).sum::<f64>() / self.data.len().max(1) as f64) as f32
    }

    /// The next coarser mip level: each side halved (rounded down, at least 1), each voxel the
    /// mean of the (up to 2x2x2) voxels it covers. Averaging is what a mip level means for a
    /// density: the mean absorption over the larger cell.
    pub fn downsample(&self) -> DensityVolume {
        let dims = self.dims.map(|d| (d / 2).max(1));
        let [nx, ny, nz] = dims;
        let mut data = Vec::with_capacity((nx * ny * nz) as usize);
        for k in 0..nz as i64 {
            for j in 0..ny as i64 {
                for i in 0..nx as i64 {
                    let (mut sum, mut count) = (0.0f32, 0u32);
                    // A side of 1 does not halve: its single voxel is reused, not duplicated.
                    for dk in 0..if self.dims[2] > 1 { 2 } else { 1 } {
                        for dj in 0..if self.dims[1] > 1 { 2 } else { 1 } {
                            for di in 0..if self.dims[0] > 1 { 2 } else { 1 } {
                                sum += self.voxel(2 * i + di, 2 * j + dj, 2 * k + dk);
                                count += 1;
                            }
                        }
                    }
                    data.push(sum / count as f32);
                }
            }
        }
        DensityVolume { dims, data }
    }

    /// The full mip chain, level 0 (this volume) first, down to 1x1x1: `floor(log2(max side)) + 1`
    /// levels, the count and sizes wgpu expects for a 3D texture (`max(1, n >> level)`).
    pub fn mip_chain(&self) -> Vec<DensityVolume> {
        let levels = mip_level_count(self.dims);
        let mut chain = Vec::with_capacity(levels as usize);
        chain.push(self.clone());
        for _ in 1..levels {
            let next = chain.last().expect("non-empty").downsample();
            chain.push(next);
        }
        chain
    }

    /// The densities quantised to 8 bits (`round(255 d)`), for an `R8Unorm` texture.
    pub fn to_unorm8(&self) -> Vec<u8> {
        self.data.iter().map(|&d| (d.clamp(0.0, 1.0) * 255.0).round() as u8).collect()
    }
}

/// Number of mip levels of a texture with these dimensions: `floor(log2(max side)) + 1`.
pub fn mip_level_count(dims: [u32; 3]) -> u32 {
    32 - dims.iter().copied().max().unwrap_or(1).max(1).leading_zeros()
}

/// Checks `dims` (each side in `1..=MAX_DIM`) and returns the voxel count.
pub(crate) fn check_dims(dims: [u32; 3]) -> Result<usize, VolumeError> {
    if dims.contains(&0) {
        return Err(VolumeError::Dims { dims, reason: "every side must be at least 1".into() });
    }
    if dims.iter().any(|&d| d > MAX_DIM) {
        return Err(VolumeError::Dims { dims, reason: format!("every side must be at most {MAX_DIM}") });
    }
    let n: usize = dims.iter().map(|&d| d as usize).product();
    if n as u64 > MAX_VOXELS {
        return Err(VolumeError::Dims {
            dims,
            reason: format!("{n} voxels, more than the {MAX_VOXELS} lucent holds (4 bytes each)"),
        });
    }
    Ok(n)
}
