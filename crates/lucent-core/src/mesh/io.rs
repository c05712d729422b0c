//! Loading meshes from OBJ, PLY (ASCII and binary), OFF, glTF and GLB files.
//!
//! This is input plumbing, not a paper section: Mertens et al. 2003 (§3) and Shopf 2007 both
//! start from a closed triangle mesh, which is what this module delivers and checks.
//!
//! - The format comes from the file extension (case-insensitive): `.obj`, `.ply`, `.off`,
//!   `.gltf`, `.glb`. Any other extension is an error that lists the supported ones.
//! - OBJ vertices come in the order of their first use by a face (`tobj`'s order; vertices no
//!   face uses are dropped); the other formats keep the file's order.
//! - Polygons are split into triangle fans (exact for convex polygons, which is what mesh
//!   files hold in practice).
//! - Vertices are kept as the file gives them, with one exception: OBJ and glTF may split a
//!   vertex by its normal or texture coordinate, which would cut the surface into unconnected
//!   pieces, so for those two formats vertices at bitwise-equal positions are welded into one
//!   (the hierarchy and the edge statistics need connectivity). PLY and OFF are index-shared
//!   formats and are taken as given.
//! - Every loaded mesh passes [`validate`](super::validate::validate): fatal problems (empty,
//!   out-of-range indices, non-finite coordinates) are errors; degenerate faces are removed
//!   and, with open or non-manifold edges and the component count, reported in a
//!   [`MeshReport`].
//! - glTF and GLB are read in `io_gltf`.
//! - No input panics the loader: malformed files are errors naming the file and the reason.
//!   The third-party parsers are additionally run under `limits::catch_quietly` as a last line
//!   of defence, so their panic text never reaches the user.

use super::Mesh;
use super::error::{MeshError, guard};
use super::texture::{MeshTexture, TextureSource};
use super::validate::{MeshReport, validate_keeping, weld_exact_duplicates};
use glam::{Vec2, Vec3};
use std::io::{BufReader, Cursor};
use std::path::Path;

/// A mesh file format, chosen from the file extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshFormat {
    /// Wavefront OBJ (text), read with `tobj`.
    Obj,
    /// Stanford PLY, ASCII or binary (either endianness), read with `ply-rs-bw`.
    Ply,
    /// Object File Format (text), read by hand.
    Off,
    /// glTF 2.0, JSON (`.gltf`, buffers embedded as data URIs or next to the file) or binary
    /// (`.glb`); both are read with the `gltf` crate.
    Gltf,
}

impl MeshFormat {
    /// The supported extensions, for messages.
    pub const SUPPORTED: &'static str = ".obj, .ply, .off, .gltf, .glb";

    /// The format for a file extension without the dot, case-insensitive.
    pub fn from_extension(ext: &str) -> Option<Self> {
        match ext.to_ascii_lowercase().as_str() {
            "obj" => Some(MeshFormat::Obj),
            "ply" => Some(MeshFormat::Ply),
            "off" => Some(MeshFormat::Off),
            "gltf" | "glb" => Some(MeshFormat::Gltf),
            _ => None,
        }
    }

    /// The format of `path`, or an error naming the file and the supported extensions.
    pub fn from_path(path: &Path) -> Result<Self, MeshError> {
        let name = path.display().to_string();
        match path.extension().and_then(|e| e.to_str()) {
            Some(ext) => Self::from_extension(ext).ok_or_else(|| {
                MeshError::invalid(
                    name,
                    format!("unknown mesh file extension '.{ext}' (supported: {})", Self::SUPPORTED),
                )
            }),
            None => Err(MeshError::invalid(
                name,
                format!("no file extension to tell the mesh format (supported: {})", Self::SUPPORTED),
            )),
        }
    }
}

/// Loads a mesh from an OBJ, PLY, OFF, glTF or GLB file (format from the extension),
/// validates it and removes degenerate and repeated faces. See [`load_mesh_with_report`] for what was found.
pub fn load_mesh(path: &Path) -> Result<Mesh, MeshError> {
    load_mesh_with_report(path).map(|(mesh, _)| mesh)
}

/// Loads and validates a mesh like [`load_mesh`], and also returns the [`MeshReport`]:
/// degenerate faces removed, welded vertices, boundary and non-manifold edges, components.
pub fn load_mesh_with_report(path: &Path) -> Result<(Mesh, MeshReport), MeshError> {
    load_inner(path, false).map(|(mesh, report, _)| (mesh, report))
}

/// Loads a mesh like [`load_mesh_with_report`] and keeps its texture coordinates and the
/// colour image its material names, if any: OBJ (`vt` with the `.mtl` file's `map_Kd`), glTF
/// (`TEXCOORD_n` with the first material's `baseColorTexture`) or PLY (`s`,`t` with a
/// `comment TextureFile`). The image is named, not read: see [`super::texture::load_texture`].
pub fn load_textured_mesh(path: &Path) -> Result<(Mesh, MeshReport, Option<MeshTexture>), MeshError> {
    load_inner(path, true)
}

fn load_inner(path: &Path, textures: bool) -> Result<(Mesh, MeshReport, Option<MeshTexture>), MeshError> {
    let format = MeshFormat::from_path(path)?;
    let name = path.display().to_string();
    let bytes = crate::limits::read_input(path).map_err(|reason| MeshError::invalid(&name, reason))?;
    // `Path::parent` of a bare file name is "": buffers then resolve against the working folder.
    parse_mesh_inner(&bytes, format, &name, Some(path.parent().unwrap_or(Path::new(""))), textures)
}

/// Parses and validates a mesh held in memory. `name` stands for the file in error messages.
/// glTF data may only reference buffers embedded in the file (GLB chunk or data URIs).
pub fn parse_mesh(bytes: &[u8], format: MeshFormat, name: &str) -> Result<(Mesh, MeshReport), MeshError> {
    parse_mesh_inner(bytes, format, name, None, false).map(|(mesh, report, _)| (mesh, report))
}

fn parse_mesh_inner(
    bytes: &[u8],
    format: MeshFormat,
    name: &str,
    base_dir: Option<&Path>,
    textures: bool,
) -> Result<(Mesh, MeshReport, Option<MeshTexture>), MeshError> {
    let parsed = guard(name, || match format {
        MeshFormat::Obj => parse_obj(bytes, base_dir, textures),
        MeshFormat::Ply => parse_ply(bytes, base_dir, textures),
        MeshFormat::Off => parse_off(bytes).map(|m| (m, None)),
        MeshFormat::Gltf => super::io_gltf::parse_gltf(bytes, base_dir, textures),
    })?;
    let (mut mesh, mut texture) = parsed.map_err(|reason| MeshError::invalid(name, reason))?;
    let welded = match format {
        MeshFormat::Obj | MeshFormat::Gltf => weld_exact_duplicates(&mut mesh),
        MeshFormat::Ply | MeshFormat::Off => 0,
    };
    // Validation drops degenerate and repeated faces; their UVs go with them.
    let mut no_uvs = Vec::new();
    let uvs = texture.as_mut().map_or(&mut no_uvs, |t| &mut t.corner_uvs);
    let (mesh, mut report) = validate_keeping(mesh, name, uvs)?;
    if report.flipped_inside_out {
        // The faces' second and third corners were swapped; their UVs go with them.
        uvs.iter_mut().for_each(|c| c.swap(1, 2));
    }
    report.welded_vertices = welded;
    let text = match format {
        MeshFormat::Obj | MeshFormat::Off => true,
        MeshFormat::Ply => bytes.windows(12).take(256).any(|w| w == b"format ascii"),
        MeshFormat::Gltf => false,
    };
    let last_line = bytes.rsplit(|&b| b == b'\n').next().unwrap_or_default();
    report.unterminated_last_line = text && last_line.iter().any(|b| !b.is_ascii_whitespace());
    let texture = texture.filter(|t| t.corner_uvs.len() == mesh.triangles.len());
    Ok((mesh, report, texture))
}

/// Appends a polygon as a triangle fan `(v0, v_i, v_i+1)`.
fn push_fan(polygon: &[u32], triangles: &mut Vec<[u32; 3]>) {
    for i in 1..polygon.len().saturating_sub(1) {
        triangles.push([polygon[0], polygon[i], polygon[i + 1]]);
    }
}

// ---------------------------------------------------------------------------------------------
// OBJ

fn parse_obj(
    bytes: &[u8],
    base_dir: Option<&Path>,
    textures: bool,
) -> Result<(Mesh, Option<MeshTexture>), String> {
    // `..Default` keeps this compiling if another crate enables tobj's optional fields.
    #[allow(clippy::needless_update)]
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    let mut reader = BufReader::new(Cursor::new(bytes));
    // The .mtl file is read only for a texture, and only inside the OBJ file's folder; one that
    // cannot be read leaves the mesh untextured.
    let (models, materials) = tobj::load_obj_buf(&mut reader, &options, |p| match base_dir {
        Some(base) if textures => {
            let path = p.to_str().and_then(|p| crate::limits::resolve_inside(base, p).ok());
            let bytes = path.and_then(|p| crate::limits::read_input(&p).ok());
            bytes.map_or(Err(tobj::LoadError::OpenFileFailed), |b| tobj::load_mtl_buf(&mut Cursor::new(b)))
        }
        _ => Ok(Default::default()),
    })
    .map_err(|e| format!("not a valid OBJ file: {e}"))?;
    let mut mesh = Mesh::default();
    let mut uvs = Vec::new();
    let mut image = None;
    for model in &models {
        let m = &model.mesh;
        if !m.positions.len().is_multiple_of(3) || !m.indices.len().is_multiple_of(3) {
            return Err(format!("OBJ object '{}' is malformed", model.name));
        }
        let base = mesh.positions.len() as u32;
        let count = m.positions.len() / 3;
        mesh.positions.extend(m.positions.chunks_exact(3).map(|p| Vec3::new(p[0], p[1], p[2])));
        for t in m.indices.chunks_exact(3) {
            if t.iter().any(|&i| i as usize >= count) {
                return Err(format!("OBJ object '{}' has a face index out of range", model.name));
            }
            mesh.triangles.push([base + t[0], base + t[1], base + t[2]]);
        }
        // UVs (v flipped to the image's top-left origin) when every face of every object has them.
        let (tc, ti) = (&m.texcoords, &m.texcoord_indices);
        if textures && ti.len() == m.indices.len() && ti.iter().all(|&i| (i as usize) < tc.len() / 2) {
            let uv = |i: u32| Vec2::new(tc[2 * i as usize], 1.0 - tc[2 * i as usize + 1]);
            uvs.extend(ti.chunks_exact(3).map(|t| [uv(t[0]), uv(t[1]), uv(t[2])]));
        }
        let map_kd = m.material_id.and_then(|id| materials.as_ref().ok()?.get(id)?.diffuse_texture.clone());
        if let (None, Some(file), Some(base)) = (&image, map_kd, base_dir) {
            // `map_Kd -o 0 0 0 file.png`: the file name comes last.
            let file =
                if file.starts_with('-') { file.split_whitespace().last().unwrap_or("") } else { &file };
            let path =
                crate::limits::resolve_inside(base, file).map_err(|e| format!("map_Kd '{file}': {e}"))?;
            image = Some(TextureSource::File(path));
        }
    }
    let texture = (uvs.len() == mesh.triangles.len() && !uvs.is_empty())
        .then_some(MeshTexture { corner_uvs: uvs, image });
    Ok((mesh, texture))
}

// ---------------------------------------------------------------------------------------------
// PLY

/// A PLY `vertex` element: `x`, `y`, `z` of any scalar type; other properties ignored.
/// Typed elements instead of the crate's map-per-element `DefaultElement` make binary files
/// about ten times faster to read.
struct PlyVertex {
    p: [f32; 3],
    /// Texture coordinate (`s`/`t`, `u`/`v` or `texture_u`/`texture_v`), bits 3 and 4 of `seen`.
    uv: [f32; 2],
    /// Bit k set when coordinate k was present.
    seen: u8,
}

impl ply_rs_bw::ply::PropertyAccess for PlyVertex {
    fn new() -> Self {
        PlyVertex { p: [0.0; 3], uv: [0.0; 2], seen: 0 }
    }
    fn set_property(
        &mut self,
        name: &str,
        property: ply_rs_bw::ply::Property,
    ) -> ply_rs_bw::ply::PropertyAccessResult {
        use ply_rs_bw::ply::PropertyAccessResult as R;
        let k = match name {
            "x" => 0,
            "y" => 1,
            "z" => 2,
            "s" | "u" | "texture_u" => 3,
            "t" | "v" | "texture_v" => 4,
            _ => return R::Ignored,
        };
        match property.to_f32_lossy() {
            Some(v) => {
                match k {
                    0..3 => self.p[k] = v,
                    _ => self.uv[k - 3] = v,
                }
                self.seen |= 1 << k;
                R::Set
            }
            None => R::UnsupportedType,
        }
    }
}

/// A PLY `face` element: the `vertex_indices` (or `vertex_index`) list of any integer type.
struct PlyFace {
    /// `int` lists are filled in place (the common case), `uint` likewise.
    signed: Vec<i32>,
    unsigned: Vec<u32>,
    /// Any other integer list, widened.
    other: Vec<i64>,
    /// Which of the three holds the indices (0 = none seen).
    which: u8,
}

fn is_index_list(name: &str) -> bool {
    name == "vertex_indices" || name == "vertex_index"
}

impl ply_rs_bw::ply::PropertyAccess for PlyFace {
    fn new() -> Self {
        PlyFace { signed: Vec::new(), unsigned: Vec::new(), other: Vec::new(), which: 0 }
    }
    fn begin_list_int(&mut self, name: &str, _len: usize) -> ply_rs_bw::ply::BeginList<'_, i32> {
        if !is_index_list(name) {
            return ply_rs_bw::ply::BeginList::UseSetter;
        }
        self.which = 1;
        ply_rs_bw::ply::BeginList::Fill(&mut self.signed)
    }
    fn begin_list_uint(&mut self, name: &str, _len: usize) -> ply_rs_bw::ply::BeginList<'_, u32> {
        if !is_index_list(name) {
            return ply_rs_bw::ply::BeginList::UseSetter;
        }
        self.which = 2;
        ply_rs_bw::ply::BeginList::Fill(&mut self.unsigned)
    }
    fn set_property(
        &mut self,
        name: &str,
        property: ply_rs_bw::ply::Property,
    ) -> ply_rs_bw::ply::PropertyAccessResult {
        use ply_rs_bw::ply::{Property as P, PropertyAccessResult as R};
        if !is_index_list(name) {
            return R::Ignored;
        }
        self.other = match property {
            P::ListChar(v) => v.into_iter().map(i64::from).collect(),
            P::ListUChar(v) => v.into_iter().map(i64::from).collect(),
            P::ListShort(v) => v.into_iter().map(i64::from).collect(),
            P::ListUShort(v) => v.into_iter().map(i64::from).collect(),
            P::ListInt(v) => v.into_iter().map(i64::from).collect(),
            P::ListUInt(v) => v.into_iter().map(i64::from).collect(),
            _ => return R::UnsupportedType,
        };
        self.which = 3;
        R::Set
    }
}

fn parse_ply(
    bytes: &[u8],
    base_dir: Option<&Path>,
    textures: bool,
) -> Result<(Mesh, Option<MeshTexture>), String> {
    use ply_rs_bw::parser::{Parser, Reader};
    use ply_rs_bw::ply::DefaultElement;

    let invalid = |e: ply_rs_bw::parser::ParseError| format!("not a valid PLY file: {e}");
    let mut reader = Reader::new(BufReader::new(Cursor::new(bytes)));
    let header = Parser::<DefaultElement>::new().read_header(&mut reader).map_err(invalid)?;
    let (mut vertices, mut faces) = (None, None);
    // Elements must be read in header order; others (edges, materials) are read and dropped.
    for (name, def) in header.elements.iter() {
        match name.as_str() {
            "vertex" => {
                vertices = Some(
                    Parser::<PlyVertex>::new()
                        .read_payload_for_element(&mut reader, def, &header)
                        .map_err(invalid)?,
                )
            }
            "face" => {
                faces = Some(
                    Parser::<PlyFace>::new()
                        .read_payload_for_element(&mut reader, def, &header)
                        .map_err(invalid)?,
                )
            }
            _ => {
                Parser::<DefaultElement>::new()
                    .read_payload_for_element(&mut reader, def, &header)
                    .map_err(invalid)?;
            }
        }
    }
    let vertices = vertices.ok_or("PLY file has no 'vertex' element")?;
    let faces = faces.ok_or("PLY file has no 'face' element")?;

    let mut positions = Vec::with_capacity(vertices.len());
    for (i, v) in vertices.iter().enumerate() {
        if v.seen & 0b111 != 0b111 {
            let missing = ["x", "y", "z"][(!v.seen).trailing_zeros().min(2) as usize];
            return Err(format!("PLY vertex {i} has no '{missing}' property"));
        }
        positions.push(Vec3::from_array(v.p));
    }
    let mut triangles = Vec::with_capacity(faces.len());
    let mut polygon = Vec::new();
    for (i, f) in faces.iter().enumerate() {
        polygon.clear();
        let bad = |k: i64| format!("PLY face {i} has an invalid vertex index {k}");
        match f.which {
            1 => {
                for &k in &f.signed {
                    polygon.push(u32::try_from(k).map_err(|_| bad(k.into()))?);
                }
            }
            2 => polygon.extend_from_slice(&f.unsigned),
            3 => {
                for &k in &f.other {
                    polygon.push(u32::try_from(k).map_err(|_| bad(k))?);
                }
            }
            _ => return Err(format!("PLY face {i} has no 'vertex_indices' or 'vertex_index' list")),
        }
        if polygon.len() < 3 {
            return Err(format!("PLY face {i} has {} vertices (at least 3 needed)", polygon.len()));
        }
        push_fan(&polygon, &mut triangles);
    }
    let mut texture = None;
    if textures && !vertices.is_empty() && vertices.iter().all(|v| v.seen & 0b11000 == 0b11000) {
        // v flipped to the image's top-left origin; indices are checked by validation.
        let uv = |i: u32| vertices.get(i as usize).map_or(Vec2::ZERO, |v| Vec2::new(v.uv[0], 1.0 - v.uv[1]));
        let corner_uvs = triangles.iter().map(|t| t.map(uv)).collect();
        // MeshLab's convention: `comment TextureFile name.png`.
        let file = header.comments.iter().find_map(|c| c.trim().strip_prefix("TextureFile ").map(str::trim));
        let image = match (file, base_dir) {
            (Some(file), Some(base)) => Some(TextureSource::File(
                crate::limits::resolve_inside(base, file)
                    .map_err(|e| format!("TextureFile '{file}': {e}"))?,
            )),
            _ => None,
        };
        texture = Some(MeshTexture { corner_uvs, image });
    }
    Ok((Mesh::new(positions, triangles), texture))
}

// ---------------------------------------------------------------------------------------------
// OFF

/// Object File Format: `OFF` header (optionally prefixed `C`, `N`, `ST`, e.g. `COFF`, `NOFF`:
/// extra per-vertex values are ignored), counts `V F E`, `V` lines `x y z ...`, `F` lines
/// `n i_1 ... i_n [colour]`. `#` starts a comment. Binary OFF and dimensions other than 3
/// (`4OFF`, `nOFF`) are rejected.
fn parse_off(bytes: &[u8]) -> Result<Mesh, String> {
    let text = std::str::from_utf8(bytes).map_err(|_| "not a text OFF file (invalid UTF-8)")?;
    // Non-empty lines with comments stripped, with their 1-based line numbers.
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.split('#').next().unwrap_or("").trim()))
        .filter(|(_, l)| !l.is_empty());

    let (_, header) = lines.next().ok_or("empty file (expected an OFF header)")?;
    let mut tokens = header.split_whitespace();
    let keyword = tokens.next().unwrap_or("");
    let prefix = keyword
        .strip_suffix("OFF")
        .ok_or_else(|| format!("not an OFF file (first word is '{keyword}', expected 'OFF')"))?;
    if !prefix.trim_start_matches("ST").chars().all(|c| c == 'C' || c == 'N') {
        return Err(format!("unsupported OFF variant '{keyword}'"));
    }
    let mut rest: Vec<&str> = tokens.collect();
    if rest.first() == Some(&"BINARY") {
        return Err("binary OFF is not supported".into());
    }
    if rest.is_empty() {
        let (_, counts) = lines.next().ok_or("truncated OFF file: missing counts line")?;
        rest = counts.split_whitespace().collect();
    }
    let count = |i: usize, what: &str| -> Result<usize, String> {
        rest.get(i)
            .ok_or_else(|| format!("truncated OFF header: missing {what} count"))?
            .parse::<usize>()
            .map_err(|_| format!("invalid OFF {what} count '{}'", rest[i]))
    };
    let nv = count(0, "vertex")?;
    let nf = count(1, "face")?;

    // Never trust the counts for allocation: a garbage header must not exhaust memory.
    let cap = |n: usize| n.min(bytes.len() / 4 + 1);
    let mut positions = Vec::with_capacity(cap(nv));
    for i in 0..nv {
        let (ln, l) = lines.next().ok_or_else(|| format!("truncated OFF file: {i} of {nv} vertices"))?;
        let mut xyz = [0.0f32; 3];
        let mut t = l.split_whitespace();
        for c in &mut xyz {
            let s = t.next().ok_or_else(|| format!("line {ln}: vertex {i} has fewer than 3 coordinates"))?;
            *c = s.parse().map_err(|_| format!("line {ln}: invalid coordinate '{s}'"))?;
        }
        positions.push(Vec3::from_array(xyz));
    }
    let mut triangles = Vec::with_capacity(cap(nf));
    let mut polygon = Vec::new();
    for i in 0..nf {
        let (ln, l) = lines.next().ok_or_else(|| format!("truncated OFF file: {i} of {nf} faces"))?;
        let mut t = l.split_whitespace();
        let n: usize =
            t.next().unwrap_or("").parse().map_err(|_| format!("line {ln}: invalid face vertex count"))?;
        if n < 3 {
            return Err(format!("line {ln}: face {i} has {n} vertices (at least 3 needed)"));
        }
        polygon.clear();
        for _ in 0..n {
            let s = t.next().ok_or_else(|| format!("line {ln}: face {i} lists fewer than {n} indices"))?;
            polygon.push(s.parse::<u32>().map_err(|_| format!("line {ln}: invalid vertex index '{s}'"))?);
        }
        push_fan(&polygon, &mut triangles);
    }
    Ok(Mesh::new(positions, triangles))
}
