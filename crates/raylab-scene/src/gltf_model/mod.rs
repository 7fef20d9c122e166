//! The glTF 2.0 loader (the `gltf` crate): `.gltf` with external `.bin` files, `.glb`, and embedded data
//! URIs; the node hierarchy with its transforms; triangle primitives (strips and fans converted, points and
//! lines skipped with a warning); materials mapped onto the fixed-function model (`materials.rs`); cameras as
//! named views and `KHR_lights_punctual` lights.
//!
//! Every accessor is checked against its buffer before it is read (`data::check_accessor`), every index
//! against its vertex count, and every external reference must lie in the model's folder, so a hostile file
//! gets an error naming it, never a panic.

mod data;
mod materials;

use std::collections::HashMap;
use std::path::Path;

use glam::{Mat4, Vec2, Vec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;
use raylab_core::scene::{Camera, Material, PointLight, SceneBuilder, TextureId, Triangle, View, WrapMode};

use crate::texture::{TextureSet, TextureUse};
use crate::{Loaded, SceneError};

/// Loads the `.gltf` or `.glb` file at `path`.
pub fn load(path: &Path) -> Result<Loaded, SceneError> {
    let bytes = std::fs::read(path).map_err(|source| SceneError::Io { path: path.to_path_buf(), source })?;
    let invalid = |message: String| SceneError::Invalid { path: path.to_path_buf(), message };
    let is_glb = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("glb"));
    if is_glb && !bytes.starts_with(b"glTF") {
        let magic: Vec<String> = bytes.iter().take(4).map(|b| format!("{b:02x}")).collect();
        return Err(invalid(format!("not a GLB file: magic bytes {} instead of 'glTF'", magic.join(" "))));
    }
    let (json, blob) = if bytes.starts_with(b"glTF") {
        let glb = gltf::Glb::from_slice(&bytes).map_err(|e| invalid(e.to_string()))?;
        (glb.json.into_owned(), glb.bin.map(|b| b.into_owned()))
    } else {
        (bytes.clone(), None)
    };
    let root: gltf::json::Root = gltf::json::deserialize::from_slice(&json).map_err(|e| invalid(e.to_string()))?;
    // gltf-json 1.4.1's validation indexes the POSITION accessor before checking it exists.
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let pos = prim.attributes.get(&gltf::json::validation::Checked::Valid(gltf::Semantic::Positions));
            if pos.is_some_and(|i| i.value() >= root.accessors.len()) {
                return Err(invalid(format!("mesh {m} primitive {p}: POSITION accessor out of range")));
            }
        }
    }
    let doc = gltf::Document::from_json(root).map_err(|e| invalid(e.to_string()))?;
    let root = path.parent().unwrap_or(Path::new(".")).to_path_buf();
    let mut warnings = Vec::new();

    let mut buffers = Vec::new();
    for buffer in doc.buffers() {
        let data = match buffer.source() {
            gltf::buffer::Source::Bin => blob
                .clone()
                .ok_or_else(|| invalid(format!("buffer {} refers to a missing GLB binary chunk", buffer.index())))?,
            gltf::buffer::Source::Uri(uri) => data::uri_bytes(uri, &root).map_err(|why| {
                match why.contains("URL") || why.contains("absolute") || why.contains("leaves") {
                    true => SceneError::Refused { path: path.to_path_buf(), why },
                    false => invalid(format!("buffer {}: {why}", buffer.index())),
                }
            })?,
        };
        if data.len() < buffer.length() {
            return Err(invalid(format!(
                "buffer {} holds {} bytes, the file says {} (truncated?)",
                buffer.index(),
                data.len(),
                buffer.length()
            )));
        }
        buffers.push(data);
    }

    let mut textures = TextureSet::default();
    let mut images: HashMap<(usize, TextureUse, WrapMode), TextureId> = HashMap::new();
    let mut image = |texture: gltf::Texture, usage: TextureUse, textures: &mut TextureSet| -> TextureId {
        let img = texture.source();
        // One wrap mode per texture here: the sampler's S mode.
        let wrap = match texture.sampler().wrap_s() {
            gltf::texture::WrappingMode::ClampToEdge => WrapMode::Clamp,
            gltf::texture::WrappingMode::MirroredRepeat => WrapMode::Mirror,
            gltf::texture::WrappingMode::Repeat => WrapMode::Repeat,
        };
        *images.entry((img.index(), usage, wrap)).or_insert_with(|| {
            let name = img.name().map_or_else(|| format!("{} image {}", path.display(), img.index()), str::to_string);
            let id = match img.source() {
                gltf::image::Source::View { view, .. } => {
                    let data = buffers
                        .get(view.buffer().index())
                        .and_then(|b| b.get(view.offset()..view.offset() + view.length()));
                    match data {
                        Some(d) => textures.bytes(&name, d, usage),
                        None => textures.refused(&name, format!("image {name}: its buffer view is out of range")),
                    }
                }
                gltf::image::Source::Uri { uri, .. } => match data::uri_bytes(uri, &root) {
                    Ok(d) => textures.bytes(&name, &d, usage),
                    Err(why) => textures.refused(&name, format!("image {name}: {why}")),
                },
            };
            textures.textures[id as usize].wrap = wrap;
            id
        })
    };

    let mut b = SceneBuilder::new();
    let mut material_ids: HashMap<Option<usize>, u32> = HashMap::new();
    let scene =
        doc.default_scene().or_else(|| doc.scenes().next()).ok_or_else(|| invalid("the file has no scene".into()))?;
    let mut stack: Vec<(gltf::Node, Mat4)> = scene.nodes().map(|n| (n, Mat4::IDENTITY)).collect();
    let mut visited = 0usize;
    let mut skipped_modes = 0usize;
    while let Some((node, parent)) = stack.pop() {
        visited += 1;
        if visited > 1_000_000 {
            return Err(invalid("the node hierarchy is too deep or cyclic".into()));
        }
        let local = Mat4::from_cols_array_2d(&node.transform().matrix());
        let world = parent * local;
        if !world.is_finite() {
            warnings.push(format!("node {} has a non-finite transform and is skipped", node.index()));
            continue;
        }
        stack.extend(node.children().map(|c| (c, world)));
        if let Some(cam) = node.camera()
            && let gltf::camera::Projection::Perspective(p) = cam.projection()
        {
            let eye = world.transform_point3(Vec3::ZERO);
            let forward = world.transform_vector3(Vec3::NEG_Z);
            let up = world.transform_vector3(Vec3::Y);
            let name = cam.name().or(node.name()).map_or_else(|| format!("camera {}", cam.index()), str::to_string);
            let camera = Camera::look_at(eye, eye + forward, up, p.yfov().to_degrees());
            match camera.validate() {
                Ok(()) => b.views.push(View { name, camera }),
                Err(e) => warnings.push(format!("camera '{name}' is unusable ({e:?}) and is skipped")),
            }
        }
        if let Some(light) = node.light() {
            let c = Vec3::from_array(light.color());
            let position = world.transform_point3(Vec3::ZERO);
            match light.kind() {
                gltf::khr_lights_punctual::Kind::Directional => {
                    warnings.push(format!("directional light {} is not supported and is skipped", light.index()))
                }
                _ if c.is_finite() && position.is_finite() => {
                    b.lights.push(PointLight { color: c, ..PointLight::at(position) })
                }
                _ => warnings.push(format!("light {} is not finite and is skipped", light.index())),
            }
        }
        let Some(mesh) = node.mesh() else { continue };
        let normal_matrix = world.inverse().transpose();
        for prim in mesh.primitives() {
            let mode = prim.mode();
            if !matches!(mode, Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan) {
                skipped_modes += 1;
                continue;
            }
            let what = format!("mesh {} primitive {}", mesh.index(), prim.index());
            let pos_acc =
                prim.get(&gltf::Semantic::Positions).ok_or_else(|| invalid(format!("{what} has no positions")))?;
            data::check_accessor(&pos_acc, &buffers, &[DataType::F32], Dimensions::Vec3)
                .map_err(|e| invalid(format!("{what}: {e}")))?;
            let reader = prim.reader(|buf| buffers.get(buf.index()).map(Vec::as_slice));
            let positions: Vec<Vec3> =
                reader.read_positions().map(|it| it.map(Vec3::from_array).collect()).unwrap_or_default();
            if let Some(p) = positions.iter().find(|p| !p.is_finite()) {
                return Err(invalid(format!("{what}: position {p} is not finite")));
            }
            let normals: Option<Vec<Vec3>> = match prim.get(&gltf::Semantic::Normals) {
                Some(acc) => {
                    data::check_accessor(&acc, &buffers, &[DataType::F32], Dimensions::Vec3)
                        .map_err(|e| invalid(format!("{what}: {e}")))?;
                    reader.read_normals().map(|it| it.map(Vec3::from_array).collect())
                }
                None => None,
            };
            let uvs: Option<Vec<Vec2>> = match prim.get(&gltf::Semantic::TexCoords(0)) {
                Some(acc) => {
                    data::check_accessor(
                        &acc,
                        &buffers,
                        &[DataType::F32, DataType::U8, DataType::U16],
                        Dimensions::Vec2,
                    )
                    .map_err(|e| invalid(format!("{what}: {e}")))?;
                    // glTF's v runs down the image, raylab's up.
                    reader.read_tex_coords(0).map(|t| t.into_f32().map(|[u, v]| Vec2::new(u, 1.0 - v)).collect())
                }
                None => None,
            };
            let indices: Vec<u32> = match prim.indices() {
                Some(acc) => {
                    data::check_accessor(
                        &acc,
                        &buffers,
                        &[DataType::U8, DataType::U16, DataType::U32],
                        Dimensions::Scalar,
                    )
                    .map_err(|e| invalid(format!("{what}: {e}")))?;
                    reader.read_indices().map(|i| i.into_u32().collect()).unwrap_or_default()
                }
                None => (0..positions.len() as u32).collect(),
            };
            if let Some(i) = indices.iter().find(|&&i| i as usize >= positions.len()) {
                return Err(invalid(format!("{what}: index {i} out of range ({} vertices)", positions.len())));
            }
            let tris = triangles(mode, &indices);
            let gm = prim.material();
            let material = match material_ids.get(&gm.index()) {
                Some(&id) => id,
                None => {
                    let pbr = gm.pbr_metallic_roughness();
                    let base = pbr.base_color_texture().map(|t| image(t.texture(), TextureUse::Color, &mut textures));
                    let normal = gm.normal_texture().map(|t| image(t.texture(), TextureUse::Normal, &mut textures));
                    let m =
                        if gm.index().is_some() { materials::convert(&gm, base, normal) } else { Material::default() };
                    let id = b.add_material(m);
                    material_ids.insert(gm.index(), id);
                    id
                }
            };
            let base = b.positions.len() as u32;
            b.positions.extend(positions.iter().map(|&p| world.transform_point3(p)));
            match normals.filter(|n| n.len() == positions.len()) {
                Some(n) => b.normals.extend(n.iter().map(|&v| normal_matrix.transform_vector3(v).normalize_or_zero())),
                None => {
                    // No normals: face normals, as the glTF specification asks (flat shading).
                    let mut n = vec![Vec3::ZERO; positions.len()];
                    for t in &tris {
                        let [p0, p1, p2] = t.map(|i| positions[i as usize]);
                        let f = (p1 - p0).cross(p2 - p0);
                        for &i in t {
                            n[i as usize] += f;
                        }
                    }
                    b.normals.extend(n.iter().map(|&v| normal_matrix.transform_vector3(v).normalize_or_zero()));
                }
            }
            match uvs.filter(|u| u.len() == positions.len()) {
                Some(u) => b.uvs.extend(u),
                None => b.uvs.extend(std::iter::repeat_n(Vec2::ZERO, positions.len())),
            }
            b.triangles.extend(tris.iter().map(|t| Triangle { v: t.map(|i| base + i), material }));
        }
    }
    if skipped_modes > 0 {
        warnings.push(format!("{}: {skipped_modes} point or line primitives skipped", path.display()));
    }
    b.textures = std::mem::take(&mut textures.textures);
    warnings.append(&mut textures.warnings);
    let scene = b.build();
    if scene.triangle_count() == 0 {
        return Err(SceneError::Empty { path: path.to_path_buf(), detail: "no triangle primitives".into() });
    }
    if scene.dropped.total() > 0 {
        warnings.push(format!("{}: {} degenerate triangles dropped", path.display(), scene.dropped.total()));
    }
    Ok(Loaded { scene, warnings })
}

/// The triangles of a primitive's index list in `mode` (strips alternate winding; fans share the first index).
fn triangles(mode: Mode, idx: &[u32]) -> Vec<[u32; 3]> {
    match mode {
        Mode::TriangleStrip => (0..idx.len().saturating_sub(2))
            .map(|k| if k % 2 == 0 { [idx[k], idx[k + 1], idx[k + 2]] } else { [idx[k + 1], idx[k], idx[k + 2]] })
            .collect(),
        Mode::TriangleFan => (1..idx.len().saturating_sub(1)).map(|k| [idx[0], idx[k], idx[k + 1]]).collect(),
        _ => idx.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strips_and_fans_become_triangles() {
        assert_eq!(triangles(Mode::TriangleStrip, &[0, 1, 2, 3]), vec![[0, 1, 2], [2, 1, 3]]);
        assert_eq!(triangles(Mode::TriangleFan, &[0, 1, 2, 3]), vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(triangles(Mode::Triangles, &[0, 1, 2, 3]), vec![[0, 1, 2]]);
        assert!(triangles(Mode::TriangleStrip, &[0, 1]).is_empty());
    }
}
