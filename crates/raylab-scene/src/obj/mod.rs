//! The full OBJ + MTL loader (tobj): polygons triangulated as fans, groups and objects, `mtllib`/`usemtl`,
//! vertex normals (smooth ones generated with a crease angle when the file has none), texture coordinates, and
//! the MTL materials mapped onto the fixed-function model (`mtl.rs`) with their textures.
//!
//! tobj reports errors without line numbers, so every line is first checked here: numbers that do not parse
//! or are not finite, faces with fewer than three corners, and indices out of range are errors naming the
//! file and line. MTL libraries and textures must lie inside the model's folder ([`crate::paths`]).

mod mtl;

use std::cell::RefCell;
use std::collections::HashMap;
use std::io::Cursor;
use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};
use raylab_core::scene::{Material, SceneBuilder, Triangle};

use crate::normals::{CREASE_DEG, smooth_corner_normals};
use crate::texture::TextureSet;
use crate::{Loaded, SceneError};

/// Loads the OBJ file at `path` with its materials and textures.
pub fn load(path: &Path) -> Result<Loaded, SceneError> {
    load_with_progress(path, &|_| {})
}

/// [`load`], reporting the share of the work done (0 to 1) to `progress`: the line check is the first 40%,
/// tobj's parse the next 40%, building the scene the rest.
pub fn load_with_progress(path: &Path, progress: &dyn Fn(f32)) -> Result<Loaded, SceneError> {
    let bytes = std::fs::read(path).map_err(|source| SceneError::Io { path: path.to_path_buf(), source })?;
    let text = std::str::from_utf8(&bytes).map_err(|e| {
        let line = bytes[..e.valid_up_to()].iter().filter(|&&b| b == b'\n').count() + 1;
        SceneError::Parse { path: path.to_path_buf(), line, message: "not UTF-8 text".into() }
    })?;
    let faces = check_lines(text, path, &|done| progress(0.4 * done))?;
    if faces == 0 {
        return Err(SceneError::Empty { path: path.to_path_buf(), detail: "no face records".into() });
    }
    let dir = path.parent().map_or_else(|| PathBuf::from("."), Path::to_path_buf);
    let root = dir.clone();
    let mut warnings = Vec::new();
    let refused: RefCell<Option<SceneError>> = RefCell::new(None);
    let mtl_warnings: RefCell<Vec<String>> = RefCell::new(Vec::new());
    let mtl_files: RefCell<Vec<PathBuf>> = RefCell::new(Vec::new());
    let options = tobj::LoadOptions { triangulate: true, single_index: true, ignore_points: true, ignore_lines: true };
    let (models, materials) = tobj::load_obj_buf(&mut Cursor::new(text.as_bytes()), &options, |name| {
        let name = name.to_string_lossy();
        let file = match crate::paths::resolve(&root, &dir, &name) {
            Ok(f) => f,
            Err(why) => {
                refused.borrow_mut().get_or_insert(SceneError::Refused { path: path.to_path_buf(), why });
                return Err(tobj::LoadError::OpenFileFailed);
            }
        };
        match std::fs::read(&file) {
            Ok(b) => {
                mtl_files.borrow_mut().push(file.clone());
                tobj::load_mtl_buf(&mut Cursor::new(mtl::normalise(&b))).inspect_err(|e| {
                    mtl_warnings
                        .borrow_mut()
                        .push(format!("{}: {e}; its materials are replaced by a grey one", file.display()));
                })
            }
            Err(e) => {
                mtl_warnings.borrow_mut().push(format!("cannot read material library {}: {e}", file.display()));
                Err(tobj::LoadError::OpenFileFailed)
            }
        }
    })
    .map_err(|e| SceneError::Parse { path: path.to_path_buf(), line: 0, message: e.to_string() })?;
    if let Some(e) = refused.into_inner() {
        return Err(e);
    }
    progress(0.8);
    warnings.extend(mtl_warnings.into_inner());
    let mtl_dir = mtl_files.borrow().first().and_then(|f| f.parent().map(Path::to_path_buf)).unwrap_or(dir.clone());

    let mut textures = TextureSet::default();
    let mut b = SceneBuilder::new();
    let tobj_materials = materials.unwrap_or_default();
    let mut ids: HashMap<usize, u32> = HashMap::new();
    let mut fallback = None;
    let any_uvs = models.iter().any(|m| !m.mesh.texcoords.is_empty());
    for model in &models {
        let mesh = &model.mesh;
        let material = match mesh.material_id.filter(|&i| i < tobj_materials.len()) {
            Some(i) => *ids.entry(i).or_insert_with(|| {
                let m = mtl::convert(&tobj_materials[i], &root, &mtl_dir, &mut textures, &mut warnings);
                b.add_material(m)
            }),
            None => *fallback.get_or_insert_with(|| b.add_material(Material::diffuse("default", Vec3::splat(0.8)))),
        };
        let base = b.positions.len() as u32;
        let positions: Vec<Vec3> = mesh.positions.chunks_exact(3).map(|p| Vec3::new(p[0], p[1], p[2])).collect();
        let tris: Vec<[u32; 3]> = mesh.indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect();
        if mesh.normals.len() == mesh.positions.len() {
            b.positions.extend(&positions);
            b.normals.extend(mesh.normals.chunks_exact(3).map(|n| Vec3::new(n[0], n[1], n[2])));
            if any_uvs {
                push_uvs(&mut b.uvs, &mesh.texcoords, positions.len());
            }
            b.triangles.extend(tris.iter().map(|t| Triangle { v: t.map(|i| base + i), material }));
        } else {
            // No normals: one vertex per corner, with the smooth normal of its crease group.
            let normals = smooth_corner_normals(&positions, &tris, CREASE_DEG);
            for (k, t) in tris.iter().enumerate() {
                let first = b.positions.len() as u32;
                for (c, &i) in t.iter().enumerate() {
                    b.positions.push(positions[i as usize]);
                    b.normals.push(normals[3 * k + c]);
                    if any_uvs {
                        let uv = mesh
                            .texcoords
                            .get(2 * i as usize..2 * i as usize + 2)
                            .map_or(Vec2::ZERO, |w| Vec2::new(w[0], w[1]));
                        b.uvs.push(uv);
                    }
                }
                b.triangles.push(Triangle { v: [first, first + 1, first + 2], material });
            }
        }
    }
    b.textures = std::mem::take(&mut textures.textures);
    warnings.append(&mut textures.warnings);
    let scene = b.build();
    if scene.triangle_count() == 0 {
        return Err(SceneError::Empty {
            path: path.to_path_buf(),
            detail: format!("{faces} face records, all degenerate or invalid"),
        });
    }
    if scene.dropped.total() > 0 {
        warnings.push(format!("{}: {} degenerate triangles dropped", path.display(), scene.dropped.total()));
    }
    Ok(Loaded { scene, warnings })
}

fn push_uvs(out: &mut Vec<Vec2>, texcoords: &[f32], n: usize) {
    if texcoords.len() == 2 * n {
        out.extend(texcoords.chunks_exact(2).map(|w| Vec2::new(w[0], w[1])));
    } else {
        out.extend(std::iter::repeat_n(Vec2::ZERO, n));
    }
}

/// Checks every record tobj will read and returns the number of faces; the first problem is an error naming
/// the file and line.
fn check_lines(text: &str, path: &Path, progress: &dyn Fn(f32)) -> Result<usize, SceneError> {
    let err = |line: usize, message: String| SceneError::Parse { path: path.to_path_buf(), line, message };
    let (mut v, mut vt, mut vn, mut faces) = (0i64, 0i64, 0i64, 0usize);
    let (mut read, total) = (0usize, text.len().max(1));
    for (n, line) in text.lines().enumerate() {
        let no = n + 1;
        read += line.len() + 1;
        if n % 65_536 == 0 {
            progress(read as f32 / total as f32);
        }
        let mut it = line.split_whitespace();
        let Some(tag) = it.next() else { continue };
        let numbers = |it: std::str::SplitWhitespace, want: usize, what: &str| -> Result<(), SceneError> {
            let mut count = 0;
            for tok in it.take(want) {
                let x: f32 = tok.parse().map_err(|_| err(no, format!("bad {what} coordinate '{tok}'")))?;
                if !x.is_finite() {
                    return Err(err(no, format!("{what} coordinate '{tok}' is not finite")));
                }
                count += 1;
            }
            if count < want { Err(err(no, format!("{what} needs {want} coordinates, found {count}"))) } else { Ok(()) }
        };
        match tag {
            "v" => {
                numbers(it, 3, "vertex")?;
                v += 1;
            }
            "vt" => {
                numbers(it, 1, "texture")?;
                vt += 1;
            }
            "vn" => {
                numbers(it, 3, "normal")?;
                vn += 1;
            }
            "f" => {
                faces += 1;
                let mut corners = 0;
                for tok in it {
                    corners += 1;
                    for (k, (part, count, what)) in tok
                        .split('/')
                        .zip([(v, "vertex"), (vt, "texture"), (vn, "normal")])
                        .map(|(p, (c, w))| (p, c, w))
                        .enumerate()
                    {
                        if part.is_empty() && k > 0 {
                            continue;
                        }
                        let i: i64 = part.parse().map_err(|_| err(no, format!("bad face index '{tok}'")))?;
                        let resolved = if i < 0 { count + i } else { i - 1 };
                        if i == 0 || resolved < 0 || resolved >= count {
                            return Err(err(no, format!("{what} index {i} out of range (1..={count} so far)")));
                        }
                    }
                }
                if corners < 3 {
                    return Err(err(no, format!("a face needs at least 3 corners, found {corners}")));
                }
            }
            _ => {}
        }
    }
    Ok(faces)
}
