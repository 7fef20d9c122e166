//! The positions-only OBJ reader: exactly the geometry the Embree harness reads, so both trace the same
//! triangles.
//!
//! Only `v` and `f` records count. A face corner may be `i`, `i/t`, `i//n` or `i/t/n`; only the position
//! index is used, negative indices count back from the last vertex read so far, and an n-gon becomes the
//! fan `(v0, vk, vk+1)`. Faces with fewer than three corners or an out-of-range index are skipped and
//! counted, as the harness does; a malformed number is an error naming the line.

use std::path::Path;

use glam::Vec3;
use raylab_core::scene::{Material, Scene, SceneBuilder, Triangle};

use crate::SceneError;

/// What the reader skipped.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ObjReport {
    /// Face records read.
    pub faces: usize,
    /// Faces skipped (fewer than 3 corners, or an index out of range).
    pub skipped_faces: usize,
}

/// Reads `path`.
pub fn load(path: &Path) -> Result<(Scene, ObjReport), SceneError> {
    let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io { path: path.to_path_buf(), source })?;
    parse(&text, path)
}

/// Parses OBJ text; `path` is used in messages only.
pub fn parse(text: &str, path: &Path) -> Result<(Scene, ObjReport), SceneError> {
    let err = |line: usize, message: String| SceneError::Parse { path: path.to_path_buf(), line, message };
    let mut b = SceneBuilder::new();
    b.add_material(Material::diffuse("default", Vec3::ONE));
    let mut report = ObjReport::default();
    let mut corners: Vec<u32> = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line_no = n + 1;
        let mut it = line.split_whitespace();
        match it.next() {
            Some("v") => {
                let mut c = [0f32; 3];
                for v in &mut c {
                    let tok = it.next().ok_or_else(|| err(line_no, "vertex needs 3 coordinates".into()))?;
                    *v = tok.parse().map_err(|_| err(line_no, format!("bad coordinate '{tok}'")))?;
                }
                b.positions.push(Vec3::from_array(c));
            }
            Some("f") => {
                report.faces += 1;
                corners.clear();
                let mut bad = false;
                for tok in it {
                    let idx = tok.split('/').next().unwrap_or("");
                    let i: i64 = idx.parse().map_err(|_| err(line_no, format!("bad face index '{tok}'")))?;
                    let count = b.positions.len() as i64;
                    let resolved = if i < 0 { count + i } else { i - 1 };
                    if i == 0 || resolved < 0 || resolved >= count {
                        bad = true;
                    } else {
                        corners.push(resolved as u32);
                    }
                }
                if bad || corners.len() < 3 {
                    report.skipped_faces += 1;
                    continue;
                }
                for k in 1..corners.len() - 1 {
                    b.triangles.push(Triangle { v: [corners[0], corners[k], corners[k + 1]], material: 0 });
                }
            }
            _ => {}
        }
    }
    if b.triangles.is_empty() {
        return Err(SceneError::Empty {
            path: path.to_path_buf(),
            detail: format!("{} vertices, {} face records", b.positions.len(), report.faces),
        });
    }
    Ok((b.build(), report))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fans_negative_indices_and_skips() {
        let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1/1 2//3 3/4/5 4\nf -4 -3 -2\nf 1 2\nf 1 2 9\n";
        let (s, r) = parse(text, Path::new("t.obj")).unwrap();
        assert_eq!(s.triangle_count(), 3);
        assert_eq!(s.triangles[1].v, [0, 2, 3]);
        assert_eq!(s.triangles[2].v, [0, 1, 2]);
        assert_eq!(r, ObjReport { faces: 4, skipped_faces: 2 });
    }

    #[test]
    fn errors_name_file_and_line() {
        let e = parse("v 0 0 0\nv 1 x 0\n", Path::new("bad.obj")).unwrap_err().to_string();
        assert!(e.starts_with("bad.obj:2:"), "{e}");
        let e = parse("v 0 0 0\n", Path::new("none.obj")).unwrap_err().to_string();
        assert!(e.contains("none.obj") && e.contains("no usable triangles"), "{e}");
        let e = parse("v 0 0\n", Path::new("short.obj")).unwrap_err().to_string();
        assert!(e.contains("short.obj:1"), "{e}");
    }
}
