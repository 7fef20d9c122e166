//! Smooth vertex normals for meshes that come without them: each corner averages the area-weighted normals
//! of the faces around its position that bend less than a crease angle from its own face, so curved
//! surfaces shade smoothly and hard edges stay hard.

use std::collections::HashMap;

use glam::Vec3;

/// Default crease angle in degrees.
pub const CREASE_DEG: f32 = 60.0;

/// Per-corner normals of `triangles` (indices into `positions`): `out[3 * t + k]` for corner `k` of
/// triangle `t`. Corners at the same position (bit for bit) share faces even if indexed separately.
pub fn smooth_corner_normals(positions: &[Vec3], triangles: &[[u32; 3]], crease_deg: f32) -> Vec<Vec3> {
    let key = |p: Vec3| p.to_array().map(f32::to_bits);
    let face: Vec<Vec3> = triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| positions[i as usize]);
            (b - a).cross(c - a)
        })
        .collect();
    let mut around: HashMap<[u32; 3], Vec<u32>> = HashMap::new();
    for (ti, t) in triangles.iter().enumerate() {
        for &v in t {
            let list = around.entry(key(positions[v as usize])).or_default();
            if list.last() != Some(&(ti as u32)) {
                list.push(ti as u32);
            }
        }
    }
    let cos_crease = crease_deg.to_radians().cos();
    let mut out = Vec::with_capacity(triangles.len() * 3);
    for (ti, t) in triangles.iter().enumerate() {
        let own = face[ti].normalize_or_zero();
        for &v in t {
            let mut sum = Vec3::ZERO;
            for &o in &around[&key(positions[v as usize])] {
                let n = face[o as usize];
                if n.normalize_or_zero().dot(own) >= cos_crease {
                    sum += n;
                }
            }
            let n = sum.normalize_or_zero();
            out.push(if n == Vec3::ZERO { own } else { n });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flat_faces_keep_their_normal_and_gentle_bends_smooth() {
        // Two triangles meeting along the x axis at a 20 degree bend, and a third at 90 degrees.
        let a = 20f32.to_radians();
        let p = vec![
            Vec3::ZERO,
            Vec3::X,
            Vec3::new(0.0, 0.0, -1.0),
            Vec3::new(0.0, a.sin(), a.cos()),
            Vec3::new(0.0, -1.0, 0.0),
        ];
        let tris = [[0, 1, 2], [0, 3, 1]];
        let n = smooth_corner_normals(&p, &tris, CREASE_DEG);
        // The shared corner 0 averages both faces; each face's lone corner keeps its face normal.
        assert!((n[0] - n[3]).length() < 1e-6);
        assert!((n[2] - Vec3::Y).length() < 1e-6);
        assert!(n[0].y > 0.9 && n[0].z < 0.0, "{}", n[0]);
        // A 90-degree crease stays hard.
        let tris = [[0, 1, 2], [0, 4, 1]];
        let n = smooth_corner_normals(&p, &tris, CREASE_DEG);
        assert!((n[0] - Vec3::Y).length() < 1e-6);
        assert!((n[3] - Vec3::NEG_Z).length() < 1e-6 || (n[3] - Vec3::Z).length() < 1e-6);
    }
}
