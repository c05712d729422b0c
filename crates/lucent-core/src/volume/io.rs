//! Reading and writing density volumes, and the `--volume` spec strings.
//!
//! # The `LVOL` format (lucent's own, version 1)
//!
//! All integers and floats little-endian:
//!
//! | offset | size | content |
//! |---|---|---|
//! | 0 | 4 | magic `b"LVOL"` |
//! | 4 | 4 | `u32` version, 1 |
//! | 8 | 12 | `u32` nx, ny, nz (each in `1..=MAX_DIM`) |
//! | 20 | 4·nx·ny·nz | `f32` densities in `[0, 1]`, x fastest, then y, then z |
//!
//! The file must be exactly `20 + 4·nx·ny·nz` bytes long.
//!
//! # Raw grids
//!
//! `raw:PATH:NXxNYxNZ:FORMAT` reads a headerless grid, x fastest: `u8` (density = v / 255),
//! `u16` little-endian (v / 65535) or `f32` little-endian (used as is, must be in `[0, 1]`).

use super::procedural::{Veins, embedded_cube};
use super::{DensityVolume, VolumeError, check_dims};
use std::path::{Path, PathBuf};
use std::str::FromStr;

/// Magic bytes that open an `LVOL` file.
pub const LVOL_MAGIC: [u8; 4] = *b"LVOL";
/// The `LVOL` version this code reads and writes.
pub const LVOL_VERSION: u32 = 1;
/// Bytes before the first density in an `LVOL` file.
pub const LVOL_HEADER_BYTES: usize = 20;

/// Voxel encoding of a raw grid.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RawFormat {
    /// One unsigned byte per voxel; density = v / 255.
    U8,
    /// Unsigned 16-bit little-endian; density = v / 65535.
    U16,
    /// 32-bit float little-endian; the density itself, in `[0, 1]`.
    F32,
}

impl RawFormat {
    /// Bytes per voxel.
    pub fn bytes(self) -> usize {
        match self {
            RawFormat::U8 => 1,
            RawFormat::U16 => 2,
            RawFormat::F32 => 4,
        }
    }

    fn name(self) -> &'static str {
        match self {
            RawFormat::U8 => "u8",
            RawFormat::U16 => "u16",
            RawFormat::F32 => "f32",
        }
    }
}

/// Where a density volume comes from: the parsed form of `--volume SPEC`.
///
/// | spec | meaning |
/// |---|---|
/// | `veins[:SEED[:SCALE]]` | marble/mineral veins ([`Veins`]; defaults 7 and 3) |
/// | `cube[:SIZE]` | dense cube inside a clear body (Shopf fig. 5.8); SIZE in `(0, 1]`, default 0.4 |
/// | `uniform:D` | density D in `[0, 1]` everywhere |
/// | `raw:PATH:NXxNYxNZ:u8\|u16\|f32` | headerless grid (module docs) |
/// | `file:PATH` | an `LVOL` file (module docs) |
#[derive(Clone, Debug, PartialEq)]
pub enum VolumeSpec {
    /// Procedural veins.
    Veins { seed: u32, scale: f32 },
    /// The embedded cube; `size` is its side as a fraction of the box.
    Cube { size: f32 },
    /// Uniform density.
    Uniform { density: f32 },
    /// A headerless grid.
    Raw { path: PathBuf, dims: [u32; 3], format: RawFormat },
    /// An `LVOL` file.
    File { path: PathBuf },
}

impl Default for VolumeSpec {
    /// `veins` with the default seed and scale.
    fn default() -> Self {
        let v = Veins::default();
        VolumeSpec::Veins { seed: v.seed, scale: v.scale }
    }
}

fn spec_err(spec: &str, reason: impl Into<String>) -> VolumeError {
    VolumeError::Spec { spec: spec.to_string(), reason: reason.into() }
}

fn parse_num<T: FromStr>(spec: &str, what: &str, s: &str) -> Result<T, VolumeError> {
    s.trim().parse().map_err(|_| spec_err(spec, format!("{what} '{s}' is not a number")))
}

/// Parses `NXxNYxNZ` (e.g. `64x64x32`).
pub fn parse_dims(spec: &str, s: &str) -> Result<[u32; 3], VolumeError> {
    let parts: Vec<&str> = s.split(['x', 'X']).collect();
    if parts.len() != 3 {
        return Err(spec_err(spec, format!("dimensions '{s}' are not NXxNYxNZ")));
    }
    let mut dims = [0u32; 3];
    for (d, p) in dims.iter_mut().zip(&parts) {
        *d = parse_num(spec, "dimension", p)?;
    }
    check_dims(dims).map_err(|e| spec_err(spec, e.to_string()))?;
    Ok(dims)
}

impl FromStr for VolumeSpec {
    type Err = VolumeError;

    fn from_str(spec: &str) -> Result<Self, VolumeError> {
        let (kind, rest) = match spec.split_once(':') {
            Some((k, r)) => (k, Some(r)),
            None => (spec, None),
        };
        match kind.to_ascii_lowercase().as_str() {
            "veins" => {
                let d = Veins::default();
                let args: Vec<&str> = rest.map(|r| r.split(':').collect()).unwrap_or_default();
                if args.len() > 2 {
                    return Err(spec_err(spec, "expected veins[:SEED[:SCALE]]"));
                }
                let seed = match args.first() {
                    Some(s) => parse_num(spec, "seed", s)?,
                    None => d.seed,
                };
                let scale: f32 = match args.get(1) {
                    Some(s) => parse_num(spec, "scale", s)?,
                    None => d.scale,
                };
                if !(scale > 0.0 && scale <= 1e4) {
                    return Err(spec_err(
                        spec,
                        "scale must be a number in (0, 10000] (veins per volume side)",
                    ));
                }
                Ok(VolumeSpec::Veins { seed, scale })
            }
            "cube" => {
                let size: f32 = match rest {
                    Some(s) => parse_num(spec, "size", s)?,
                    None => 0.4,
                };
                if !(size > 0.0 && size <= 1.0) {
                    return Err(spec_err(spec, "cube size must be in (0, 1]"));
                }
                Ok(VolumeSpec::Cube { size })
            }
            "uniform" => {
                let s = rest.ok_or_else(|| spec_err(spec, "expected uniform:D"))?;
                let density: f32 = parse_num(spec, "density", s)?;
                if !(0.0..=1.0).contains(&density) {
                    return Err(spec_err(spec, "density must be in [0, 1]"));
                }
                Ok(VolumeSpec::Uniform { density })
            }
            "raw" => {
                let rest = rest.ok_or_else(|| spec_err(spec, "expected raw:PATH:NXxNYxNZ:FORMAT"))?;
                // The path may itself contain ':', so split the last two fields off the right.
                let mut it = rest.rsplitn(3, ':');
                let (fmt, dims, path) = match (it.next(), it.next(), it.next()) {
                    (Some(f), Some(d), Some(p)) if !p.is_empty() => (f, d, p),
                    _ => return Err(spec_err(spec, "expected raw:PATH:NXxNYxNZ:u8|u16|f32")),
                };
                let format = match fmt.to_ascii_lowercase().as_str() {
                    "u8" => RawFormat::U8,
                    "u16" => RawFormat::U16,
                    "f32" => RawFormat::F32,
                    other => {
                        return Err(spec_err(spec, format!("voxel format '{other}' is not u8, u16 or f32")));
                    }
                };
                Ok(VolumeSpec::Raw { path: PathBuf::from(path), dims: parse_dims(spec, dims)?, format })
            }
            "file" => match rest {
                Some(p) if !p.is_empty() => Ok(VolumeSpec::File { path: PathBuf::from(p) }),
                _ => Err(spec_err(spec, "expected file:PATH")),
            },
            _ => Err(spec_err(
                spec,
                "expected veins[:SEED[:SCALE]], cube[:SIZE], uniform:D, raw:PATH:NXxNYxNZ:u8|u16|f32 or file:PATH",
            )),
        }
    }
}

impl VolumeSpec {
    /// Builds the volume. Procedural sources are sampled on a `dims` grid; files bring their
    /// own dimensions and ignore `dims`.
    pub fn build(&self, dims: [u32; 3]) -> Result<DensityVolume, VolumeError> {
        match self {
            VolumeSpec::Veins { seed, scale } => {
                Veins { seed: *seed, scale: *scale, ..Veins::default() }.generate(dims)
            }
            VolumeSpec::Cube { size } => embedded_cube(dims, *size),
            VolumeSpec::Uniform { density } => DensityVolume::uniform(dims, *density),
            VolumeSpec::Raw { path, dims, format } => load_raw(path, *dims, *format),
            VolumeSpec::File { path } => load_lvol(path),
        }
    }
}

fn read_file(path: &Path) -> Result<Vec<u8>, VolumeError> {
    crate::limits::read_input(path)
        .map_err(|reason| VolumeError::Read { path: path.display().to_string(), reason })
}

/// Checks every density is finite and in `[0, 1]`, naming the file otherwise.
fn check_values(path: &Path, data: &[f32]) -> Result<(), VolumeError> {
    match data.iter().enumerate().find(|(_, d)| !(0.0..=1.0).contains(*d)) {
        Some((index, &value)) => Err(VolumeError::Value { path: path.display().to_string(), index, value }),
        None => Ok(()),
    }
}

/// Reads a headerless grid of `dims` voxels in `format` (module docs). The file must be exactly
/// the right size.
pub fn load_raw(path: &Path, dims: [u32; 3], format: RawFormat) -> Result<DensityVolume, VolumeError> {
    parse_raw(&read_file(path)?, dims, format, path)
}

/// Decodes a headerless grid held in memory; `path` names it in errors.
pub fn parse_raw(
    bytes: &[u8],
    dims: [u32; 3],
    format: RawFormat,
    path: &Path,
) -> Result<DensityVolume, VolumeError> {
    let n = check_dims(dims)?;
    let expected = (n * format.bytes()) as u64;
    if bytes.len() as u64 != expected {
        return Err(VolumeError::Size {
            path: path.display().to_string(),
            what: format!("{}x{}x{} {} voxels", dims[0], dims[1], dims[2], format.name()),
            expected,
            actual: bytes.len() as u64,
        });
    }
    let data: Vec<f32> = match format {
        RawFormat::U8 => bytes.iter().map(|&v| v as f32 / 255.0).collect(),
        RawFormat::U16 => {
            bytes.chunks_exact(2).map(|c| u16::from_le_bytes([c[0], c[1]]) as f32 / 65535.0).collect()
        }
        RawFormat::F32 => {
            bytes.chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect()
        }
    };
    check_values(path, &data)?;
    Ok(DensityVolume { dims, data })
}

/// Reads an `LVOL` file (module docs).
pub fn load_lvol(path: &Path) -> Result<DensityVolume, VolumeError> {
    parse_lvol(&read_file(path)?, path)
}

/// Decodes an `LVOL` file held in memory; `path` names it in errors.
pub fn parse_lvol(bytes: &[u8], path: &Path) -> Result<DensityVolume, VolumeError> {
    let header_err = |reason: String| VolumeError::Header { path: path.display().to_string(), reason };
    if bytes.len() < LVOL_HEADER_BYTES {
        return Err(header_err(format!(
            "too short for an LVOL header ({} bytes, need {LVOL_HEADER_BYTES})",
            bytes.len()
        )));
    }
    if bytes[0..4] != LVOL_MAGIC {
        return Err(header_err("not an LVOL file (magic bytes are not 'LVOL')".into()));
    }
    let word = |o: usize| u32::from_le_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]);
    let version = word(4);
    if version != LVOL_VERSION {
        return Err(header_err(format!("LVOL version {version} is not supported (only {LVOL_VERSION})")));
    }
    let dims = [word(8), word(12), word(16)];
    let n = check_dims(dims).map_err(|e| header_err(e.to_string()))?;
    let expected = (LVOL_HEADER_BYTES + 4 * n) as u64;
    if bytes.len() as u64 != expected {
        return Err(VolumeError::Size {
            path: path.display().to_string(),
            what: format!("an LVOL file of {}x{}x{} voxels", dims[0], dims[1], dims[2]),
            expected,
            actual: bytes.len() as u64,
        });
    }
    let data: Vec<f32> = bytes[LVOL_HEADER_BYTES..]
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    check_values(path, &data)?;
    Ok(DensityVolume { dims, data })
}

/// Writes `volume` as an `LVOL` file (module docs).
pub fn save_lvol(path: &Path, volume: &DensityVolume) -> Result<(), VolumeError> {
    let mut bytes = Vec::with_capacity(LVOL_HEADER_BYTES + 4 * volume.data.len());
    bytes.extend_from_slice(&LVOL_MAGIC);
    bytes.extend_from_slice(&LVOL_VERSION.to_le_bytes());
    for d in volume.dims {
        bytes.extend_from_slice(&d.to_le_bytes());
    }
    for v in &volume.data {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    std::fs::write(path, bytes)
        .map_err(|source| VolumeError::Write { path: path.display().to_string(), source })
}
