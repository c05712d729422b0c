//! glTF 2.0 and GLB meshes (read with the `gltf` crate), and the `KHR_materials_volume`
//! parameters the HTSM renderer takes from them. Input plumbing for [`super::io`]: buffers come
//! only from the GLB chunk, `data:` URIs or files inside the model's own folder, and every
//! accessor is checked before the crate's reader (which panics on types the specification
//! forbids) touches it.

use super::Mesh;
use super::error::{MeshError, guard};
use super::texture::{MeshTexture, TextureSource};
use glam::{Mat4, Vec2, Vec3};
use std::path::Path;

/// All triangle-mode primitives of the default scene (or the first scene; or every mesh
/// untransformed when there is no scene), with each node's world transform applied.
/// Primitives of other modes (points, lines, strips, fans) are skipped.
/// With `textures`, also the UVs (the set the material's `baseColorTexture` names) when every
/// primitive has them, and the first `baseColorTexture` image.
pub(super) fn parse_gltf(
    bytes: &[u8],
    base_dir: Option<&Path>,
    textures: bool,
) -> Result<(Mesh, Option<MeshTexture>), String> {
    let gltf = read_gltf(bytes)?;
    let document = gltf.document;
    let buffers = gltf_buffers(&document, base_dir, gltf.blob)?;

    let mut mesh = Mesh::default();
    let (mut uvs, mut all_uvs, mut image) = (Vec::new(), textures, None);
    let mut add = |m: gltf::Mesh<'_>, world: Mat4| -> Result<(), String> {
        // A mirroring transform turns counter-clockwise faces clockwise (glTF spec §3.7.4).
        let flip = world.determinant() < 0.0;
        for prim in m.primitives() {
            if prim.mode() != gltf::mesh::Mode::Triangles {
                continue;
            }
            check_accessor_types(m.index(), &prim)?;
            let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d[..]));
            let Some(pos) = reader.read_positions() else {
                continue;
            };
            let base = mesh.positions.len();
            mesh.positions.extend(pos.map(|p| world.transform_point3(Vec3::from_array(p))));
            let count = (mesh.positions.len() - base) as u32;
            let indices: Vec<u32> = match reader.read_indices() {
                Some(i) => i.into_u32().collect(),
                None => (0..count).collect(),
            };
            if let Some(&bad) = indices.iter().find(|&&i| i >= count) {
                return Err(format!(
                    "glTF mesh {} has index {bad} out of range ({count} vertices)",
                    m.index()
                ));
            }
            for t in indices.chunks_exact(3) {
                let b = base as u32;
                mesh.triangles.push(if flip {
                    [b + t[0], b + t[2], b + t[1]]
                } else {
                    [b + t[0], b + t[1], b + t[2]]
                });
            }
            if !all_uvs {
                continue;
            }
            let info = prim.material().pbr_metallic_roughness().base_color_texture();
            let set = info.as_ref().map_or(0, |i| i.tex_coord());
            let tc: Option<Vec<[f32; 2]>> = reader.read_tex_coords(set).map(|r| r.into_f32().collect());
            match tc.filter(|tc| tc.len() == count as usize) {
                Some(tc) => {
                    let uv = |i: u32| Vec2::from_array(tc[i as usize]);
                    let tris = indices.chunks_exact(3).map(|t| {
                        if flip { [uv(t[0]), uv(t[2]), uv(t[1])] } else { [uv(t[0]), uv(t[1]), uv(t[2])] }
                    });
                    uvs.extend(tris);
                }
                None => all_uvs = false,
            }
            if let (None, Some(info)) = (&image, info) {
                image = Some(image_source(&info.texture().source(), &buffers, base_dir)?);
            }
        }
        Ok(())
    };

    let scene = document.default_scene().or_else(|| document.scenes().next());
    match scene {
        Some(scene) => {
            // Explicit stack with a depth bound: a (invalid) cyclic node graph must not hang.
            let max_depth = document.nodes().len();
            let mut stack: Vec<(gltf::Node<'_>, Mat4, usize)> =
                scene.nodes().map(|n| (n, Mat4::IDENTITY, 0)).collect();
            while let Some((node, parent, depth)) = stack.pop() {
                if depth > max_depth {
                    return Err("glTF node hierarchy contains a cycle".into());
                }
                let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
                if let Some(m) = node.mesh() {
                    add(m, world)?;
                }
                stack.extend(node.children().map(|c| (c, world, depth + 1)));
            }
        }
        None => {
            for m in document.meshes() {
                add(m, Mat4::IDENTITY)?;
            }
        }
    }
    let texture = (all_uvs && uvs.len() == mesh.triangles.len() && !uvs.is_empty())
        .then_some(MeshTexture { corner_uvs: uvs, image });
    Ok((mesh, texture))
}

/// Where a glTF image's bytes are: a buffer view, a `data:` URI, or a file inside `base_dir`
/// (read later, by `texture::load_texture`).
fn image_source(
    img: &gltf::Image<'_>,
    buffers: &[Vec<u8>],
    base_dir: Option<&Path>,
) -> Result<TextureSource, String> {
    let name = format!("glTF image {}", img.index());
    match img.source() {
        gltf::image::Source::View { view, .. } => {
            let data = buffers.get(view.buffer().index()).map(|b| &b[..]).unwrap_or_default();
            let bytes = data
                .get(view.offset()..view.offset().saturating_add(view.length()))
                .ok_or_else(|| format!("{name}: its buffer view lies outside its buffer"))?;
            Ok(TextureSource::Embedded { name, bytes: bytes.to_vec() })
        }
        gltf::image::Source::Uri { uri, .. } if uri.starts_with("data:") => {
            let bytes = read_buffer_uri(uri, None).map_err(|e| format!("{name}: {e}"))?;
            Ok(TextureSource::Embedded { name, bytes })
        }
        gltf::image::Source::Uri { uri, .. } => {
            let relative = percent_decode(uri).map_err(|e| format!("{name}: {e}"))?;
            let Some(base) = base_dir else {
                return Err(format!("{name}: external images cannot be read for a model held in memory"));
            };
            let path = crate::limits::resolve_inside(base, &relative).map_err(|e| format!("{name}: {e}"))?;
            Ok(TextureSource::File(path))
        }
    }
}

/// The data of every buffer: the GLB binary chunk, a `data:` URI, or a file named by a relative
/// URI that resolves inside `base_dir` (the glTF file's own folder). Anything else (an absolute
/// path, `..` leading out, another URI scheme, a link pointing outside) is refused, so a model
/// cannot make lucent read files beside it; with `base_dir = None` (data held in memory) only the
/// chunk and data URIs are accepted.
fn gltf_buffers(
    document: &gltf::Document,
    base_dir: Option<&Path>,
    mut blob: Option<Vec<u8>>,
) -> Result<Vec<Vec<u8>>, String> {
    let mut buffers = Vec::new();
    for buffer in document.buffers() {
        let i = buffer.index();
        let data = match buffer.source() {
            gltf::buffer::Source::Bin => {
                blob.take().ok_or_else(|| format!("glTF buffer {i} refers to a missing GLB binary chunk"))?
            }
            gltf::buffer::Source::Uri(uri) => read_buffer_uri(uri, base_dir)
                .map_err(|reason| format!("glTF buffer {i} (uri '{}'): {reason}", short(uri)))?,
        };
        if data.len() < buffer.length() {
            return Err(format!(
                "glTF buffer {i} holds {} bytes, fewer than its byteLength {}",
                data.len(),
                buffer.length()
            ));
        }
        buffers.push(data);
    }
    Ok(buffers)
}

/// At most 80 characters of a URI, for messages (data URIs are long).
fn short(uri: &str) -> String {
    match uri.char_indices().nth(80) {
        Some((k, _)) => format!("{}...", &uri[..k]),
        None => uri.to_string(),
    }
}

fn read_buffer_uri(uri: &str, base_dir: Option<&Path>) -> Result<Vec<u8>, String> {
    if let Some(data) = uri.strip_prefix("data:") {
        let (_, payload) = data.split_once(";base64,").ok_or("only base64 data URIs are supported")?;
        return base64::decode(payload).map_err(|e| format!("invalid base64 data: {e}"));
    }
    let relative = percent_decode(uri)?;
    // In memory there is no folder: refuse a path that would leave one first, by that rule.
    let Some(base) = base_dir else {
        crate::limits::check_relative(&relative)?;
        return Err("external buffers cannot be read for a model held in memory".into());
    };
    let path = crate::limits::resolve_inside(base, &relative)?;
    crate::limits::read_input(&path).map_err(|reason| format!("{}: {reason}", path.display()))
}

/// Decodes `%XX` escapes (URIs in glTF are percent-encoded).
fn percent_decode(uri: &str) -> Result<String, String> {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut k = 0;
    while k < bytes.len() {
        if bytes[k] == b'%' {
            let hex = bytes.get(k + 1..k + 3).and_then(|h| std::str::from_utf8(h).ok());
            let byte =
                hex.and_then(|h| u8::from_str_radix(h, 16).ok()).ok_or("invalid %-escape in the URI")?;
            out.push(byte);
            k += 3;
        } else {
            out.push(bytes[k]);
            k += 1;
        }
    }
    String::from_utf8(out).map_err(|_| "the URI is not UTF-8 after %-decoding".to_string())
}

/// The gltf crate's reader assumes the types the specification requires and panics on others:
/// positions must be float VEC3 and indices unsigned integer scalars.
fn check_accessor_types(mesh: usize, prim: &gltf::Primitive<'_>) -> Result<(), String> {
    use gltf::accessor::{DataType, Dimensions};
    let where_ = || format!("glTF mesh {mesh} primitive {}", prim.index());
    if let Some(a) = prim.get(&gltf::Semantic::Positions)
        && (a.data_type() != DataType::F32 || a.dimensions() != Dimensions::Vec3)
    {
        return Err(format!(
            "{}: POSITION must be float VEC3, not {:?} {:?}",
            where_(),
            a.data_type(),
            a.dimensions()
        ));
    }
    if let Some(a) = prim.indices()
        && (!matches!(a.data_type(), DataType::U8 | DataType::U16 | DataType::U32)
            || a.dimensions() != Dimensions::Scalar)
    {
        return Err(format!(
            "{}: indices must be unsigned integer scalars, not {:?} {:?}",
            where_(),
            a.data_type(),
            a.dimensions()
        ));
    }
    for (semantic, a) in prim.attributes() {
        let gltf::Semantic::TexCoords(_) = semantic else { continue };
        let ok = match a.data_type() {
            DataType::F32 => true,
            DataType::U8 | DataType::U16 => a.normalized(),
            _ => false,
        };
        if !ok || a.dimensions() != Dimensions::Vec2 {
            return Err(format!(
                "{}: TEXCOORD must be float or normalized unsigned VEC2, not {:?} {:?}",
                where_(),
                a.data_type(),
                a.dimensions()
            ));
        }
    }
    let texcoords =
        prim.attributes().filter(|(s, _)| matches!(s, gltf::Semantic::TexCoords(_))).map(|(_, a)| a);
    for a in prim.get(&gltf::Semantic::Positions).into_iter().chain(prim.indices()).chain(texcoords) {
        let (Some(view), count) = (a.view(), a.count()) else { continue };
        let stride = view.stride().unwrap_or(a.size());
        let needed = (a.offset() as u128) + (stride as u128) * (count.max(1) as u128 - 1) + a.size() as u128;
        if count > 0 && needed > view.length() as u128 {
            return Err(format!(
                "{}: accessor {} needs {needed} bytes of its buffer view, which has {}",
                where_(),
                a.index(),
                view.length()
            ));
        }
    }
    Ok(())
}

/// Parses and validates glTF JSON or GLB. gltf-json 1.4.1's validation indexes the accessor
/// array with a primitive's POSITION index unchecked (a panic on a bad file), so that index is
/// checked first.
pub(super) fn read_gltf(bytes: &[u8]) -> Result<gltf::Gltf, String> {
    let invalid = |e: gltf::Error| format!("not a valid glTF file: {e}");
    let raw = gltf::Gltf::from_slice_without_validation(bytes).map_err(invalid)?;
    let root = raw.document.into_json();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            for (semantic, accessor) in &prim.attributes {
                if accessor.value() >= root.accessors.len() {
                    return Err(format!(
                        "not a valid glTF file: meshes[{m}].primitives[{p}] attribute {semantic:?} refers to missing accessor {}",
                        accessor.value()
                    ));
                }
            }
        }
    }
    Ok(gltf::Gltf { document: gltf::Document::from_json(root).map_err(invalid)?, blob: raw.blob })
}

/// The `KHR_materials_volume` parameters of the first material of a glTF/GLB file:
/// `(attenuation_color, attenuation_distance)`, the colour (linear RGB in [0, 1]) that white
/// light becomes after travelling `attenuation_distance` (mesh units; `+inf` when absent, the
/// extension's default) through the medium. `None` when the file has no material or the first
/// material has no volume extension. Used by the HTSM renderer (Shopf 2007) to derive
/// extinction from the asset.
pub fn load_gltf_volume_params(path: &Path) -> Result<Option<([f32; 3], f32)>, MeshError> {
    let name = path.display().to_string();
    let bytes = crate::limits::read_input(path).map_err(|reason| MeshError::invalid(&name, reason))?;
    guard(&name, || {
        let gltf = read_gltf(&bytes).map_err(|reason| MeshError::invalid(&name, reason))?;
        Ok(gltf
            .document
            .materials()
            .next()
            .and_then(|m| m.volume())
            .map(|v| (v.attenuation_color(), v.attenuation_distance())))
    })?
}
