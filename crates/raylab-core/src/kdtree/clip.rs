//! Clipping a triangle to a box, for the "perfect" split candidates of thesis 2.2.1 and 3.2.1.

use glam::{DVec3, Vec3};

use crate::aabb::Aabb;

/// Bounds of the part of triangle `tri` inside `bx`, or `None` if none of it is.
///
/// Sutherland-Hodgman clipping against the six planes in double precision, rounded outward to `f32` and
/// clamped to `bx`.
/// Where rounding empties the polygon of a triangle that touches the box, the triangle's own bounds
/// intersected with the box are returned instead, so clipping never loses a triangle that overlaps the box
/// (a larger box only costs a little tree quality).
pub fn clipped_bounds(tri: &[glam::Vec3; 3], bx: &Aabb) -> Option<Aabb> {
    let (mut buf_a, mut buf_b) = ([DVec3::ZERO; 9], [DVec3::ZERO; 9]);
    // Each clip reads one buffer and writes the other; the two swap roles instead of copying back.
    let (mut poly, mut tmp) = (&mut buf_a, &mut buf_b);
    for (p, v) in poly.iter_mut().zip(tri) {
        *p = v.as_dvec3();
    }
    let mut n = 3;
    let own = Aabb::from_points(tri.iter().copied());
    let (lo, hi) = (bx.min.as_dvec3(), bx.max.as_dvec3());
    // Only the planes the triangle crosses can cut it; most small triangles cross just the split plane.
    for axis in 0..3 {
        for (lower, plane) in [(true, lo[axis]), (false, hi[axis])] {
            let crosses = if lower { (own.min[axis] as f64) < plane } else { (own.max[axis] as f64) > plane };
            if crosses && n > 0 {
                n = clip_plane(&poly[..n], tmp, axis, plane, lower);
                std::mem::swap(&mut poly, &mut tmp);
            }
        }
    }
    if n == 0 {
        let fallback = Aabb::from_points(tri.iter().copied()).intersection(*bx);
        return (!fallback.is_empty()).then_some(fallback);
    }
    let (mut lo, mut hi) = (poly[0], poly[0]);
    for p in &poly[1..n] {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    let lo = Vec3::new(round_down(lo.x), round_down(lo.y), round_down(lo.z));
    let hi = Vec3::new(round_up(hi.x), round_up(hi.y), round_up(hi.z));
    Some(Aabb::new(lo, hi).intersection(*bx))
}

/// The largest `f32` not above `x`: clipped bounds are rounded outward, never inward, so that no sliver of
/// a triangle falls outside the box that claims to hold it.
fn round_down(x: f64) -> f32 {
    let f = x as f32;
    if f as f64 > x { f.next_down() } else { f }
}

/// The smallest `f32` not below `x`.
fn round_up(x: f64) -> f32 {
    let f = x as f32;
    if (f as f64) < x { f.next_up() } else { f }
}

/// Keeps the part of `input` on the inner side of `coord[axis] = plane` (`>=` for a lower plane, `<=` for an
/// upper one); returns the number of vertices written to `out`.
fn clip_plane(input: &[DVec3], out: &mut [DVec3; 9], axis: usize, plane: f64, lower: bool) -> usize {
    let inside = |p: &DVec3| {
        if lower { p[axis] >= plane } else { p[axis] <= plane }
    };
    let Some(&last) = input.last() else {
        return 0;
    };
    let mut n = 0;
    // Edges from each vertex's predecessor to it (the polygon starts one vertex later than `input`, the same
    // points), which spares a modulo per vertex.
    let mut a = last;
    for &b in input {
        let (ia, ib) = (inside(&a), inside(&b));
        if ia {
            out[n] = a;
            n += 1;
        }
        if ia != ib && n < out.len() {
            let s = (plane - a[axis]) / (b[axis] - a[axis]);
            let mut p = a + (b - a) * s;
            p[axis] = plane;
            out[n] = p;
            n += 1;
        }
        a = b;
    }
    n
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clipping_tightens_bounds() {
        // The triangle's own box spans y in [0, 2]; clipped to x <= 0.5 only y in [0, 1] remains.
        let tri = [Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 2.0, 0.0), Vec3::new(0.0, 0.0, 1.0)];
        let bx = Aabb::new(Vec3::splat(-1.0), Vec3::new(0.5, 3.0, 3.0));
        let b = clipped_bounds(&tri, &bx).unwrap();
        assert!((b.max.y - 1.0).abs() < 1e-6 && b.max.x == 0.5, "{b:?}");
        let outside = Aabb::new(Vec3::splat(5.0), Vec3::splat(6.0));
        assert_eq!(clipped_bounds(&tri, &outside), None);
    }
}
