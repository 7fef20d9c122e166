//! Clipping a triangle to a box, for the "perfect" split candidates of thesis 2.2.1 and 3.2.1.

use glam::{DVec3, Vec3};

use crate::aabb::{Aabb, coord, coord_mut};

/// Bounds of the part of triangle `tri` inside `bx`, or `None` if none of it is.
///
/// Sutherland-Hodgman clipping against the six planes in double precision, rounded outward to `f32` and
/// clamped to `bx`.
/// Where rounding empties the polygon of a triangle that touches the box, the triangle's own bounds
/// intersected with the box are returned instead, so clipping never loses a triangle that overlaps the box
/// (a larger box only costs a little tree quality).
///
/// The build clips through [`split_clipped_bounds`]; this one-box form is the reference it is tested
/// against.
#[cfg(test)]
pub fn clipped_bounds(tri: &[Vec3; 3], bx: &Aabb) -> Option<Aabb> {
    let poly = clip_to_box(tri, bx);
    let points = poly.points();
    let extent = points.first().map(|&p0| points.iter().fold((p0, p0), |(lo, hi), p| (lo.min(*p), hi.max(*p))));
    finish(tri, bx, extent)
}

/// The clipped bounds (`clipped_bounds`, the test-only one-box reference) of `tri` in the two children of `bx` split at `coord[axis] = pos`: `(left, right)`.
///
/// The triangle is clipped to `bx` once, and the polygon is then cut by the split plane in one pass over its
/// edges that collects each side's vertices and the points where edges cross the plane (the clipping
/// arithmetic, shared by both sides), instead of clipping the triangle to each child box from scratch.
pub fn split_clipped_bounds(tri: &[Vec3; 3], bx: &Aabb, axis: usize, pos: f32) -> (Option<Aabb>, Option<Aabb>) {
    let (mut lb, mut rb) = (*bx, *bx);
    *coord_mut(&mut lb.max, axis) = pos;
    *coord_mut(&mut rb.min, axis) = pos;
    let poly = clip_to_box(tri, bx);
    let points = poly.points();
    let plane = pos as f64;
    let (mut left, mut right): (Option<Extent>, Option<Extent>) = (None, None);
    let grow = |e: &mut Option<Extent>, p: DVec3| {
        *e = Some(e.map_or((p, p), |(lo, hi)| (lo.min(p), hi.max(p))));
    };
    // Edges from each vertex's predecessor to it, as in `clip_plane`.
    if let Some(&last) = points.last() {
        let mut a = last;
        for &b in points {
            let (al, bl) = (a[axis] <= plane, b[axis] <= plane);
            let (ar, br) = (a[axis] >= plane, b[axis] >= plane);
            if al {
                grow(&mut left, a);
            }
            if ar {
                grow(&mut right, a);
            }
            if al != bl || ar != br {
                let p = crossing(a, b, axis, plane);
                if al != bl {
                    grow(&mut left, p);
                }
                if ar != br {
                    grow(&mut right, p);
                }
            }
            a = b;
        }
    }
    (finish(tri, &lb, left), finish(tri, &rb, right))
}

/// The corners `(lo, hi)` of a box in double precision.
type Extent = (DVec3, DVec3);

/// A convex polygon of at most nine vertices: a triangle clipped by up to six planes.
struct Polygon {
    vertices: [DVec3; 9],
    len: usize,
}

impl Polygon {
    fn points(&self) -> &[DVec3] {
        &self.vertices[..self.len]
    }
}

/// `tri` clipped to the planes of `bx` its own bounds cross (most small triangles cross none or one).
fn clip_to_box(tri: &[Vec3; 3], bx: &Aabb) -> Polygon {
    let (mut buf_a, mut buf_b) = ([DVec3::ZERO; 9], [DVec3::ZERO; 9]);
    // Each clip reads one buffer and writes the other; the two swap roles instead of copying back.
    let (mut poly, mut tmp) = (&mut buf_a, &mut buf_b);
    for (p, v) in poly.iter_mut().zip(tri) {
        *p = v.as_dvec3();
    }
    let mut n = 3;
    let own = Aabb::from_points(tri.iter().copied());
    let (lo, hi) = (bx.min.as_dvec3(), bx.max.as_dvec3());
    for axis in 0..3 {
        for (lower, plane) in [(true, lo[axis]), (false, hi[axis])] {
            let crosses =
                if lower { (coord(&own.min, axis) as f64) < plane } else { (coord(&own.max, axis) as f64) > plane };
            if crosses && n > 0 {
                n = clip_plane(&poly[..n], tmp, axis, plane, lower);
                std::mem::swap(&mut poly, &mut tmp);
            }
        }
    }
    Polygon { vertices: *poly, len: n }
}

/// A clipped polygon's extent rounded outward and clamped to `bx`; with no polygon left (rounding emptied
/// it), the triangle's own bounds clamped to `bx`, or `None` where they miss it.
fn finish(tri: &[Vec3; 3], bx: &Aabb, extent: Option<Extent>) -> Option<Aabb> {
    let Some((lo, hi)) = extent else {
        let fallback = Aabb::from_points(tri.iter().copied()).intersection(*bx);
        return (!fallback.is_empty()).then_some(fallback);
    };
    let lo = Vec3::new(round_down(lo.x), round_down(lo.y), round_down(lo.z));
    let hi = Vec3::new(round_up(hi.x), round_up(hi.y), round_up(hi.z));
    Some(Aabb::new(lo, hi).intersection(*bx))
}

/// Where the edge from `a` to `b` crosses `coord[axis] = plane` (exactly on the plane along `axis`).
fn crossing(a: DVec3, b: DVec3, axis: usize, plane: f64) -> DVec3 {
    let s = (plane - a[axis]) / (b[axis] - a[axis]);
    let mut p = a + (b - a) * s;
    p[axis] = plane;
    p
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
            out[n] = crossing(a, b, axis, plane);
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

    /// True when `a` and `b` are both `None`, or boxes whose corners differ by at most one `f32` step.
    fn within_an_ulp(a: Option<Aabb>, b: Option<Aabb>) -> bool {
        let close = |x: f32, y: f32| x == y || x.next_up() == y || x.next_down() == y;
        match (a, b) {
            (None, None) => true,
            (Some(a), Some(b)) => (0..3).all(|k| close(a.min[k], b.min[k]) && close(a.max[k], b.max[k])),
            _ => false,
        }
    }

    #[test]
    fn splitting_once_gives_the_bounds_of_clipping_to_each_child() {
        // Triangles of every size against a box and its split, pseudo-random but fixed.
        let mut x = 0x2545_f491u32;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            (x >> 8) as f32 / (1 << 24) as f32
        };
        let bx = Aabb::new(Vec3::new(-1.0, -2.0, 0.5), Vec3::new(3.0, 1.0, 2.5));
        let mut checked = 0;
        for i in 0..3000 {
            let scale = [0.1, 1.0, 6.0][i % 3];
            let centre = Vec3::new(next() * 6.0 - 2.0, next() * 5.0 - 3.0, next() * 4.0 - 0.5);
            let tri = [0, 1, 2].map(|_| centre + (Vec3::new(next(), next(), next()) - 0.5) * scale);
            let axis = i % 3;
            let pos = bx.min[axis] + (bx.max[axis] - bx.min[axis]) * next();
            let (mut lb, mut rb) = (bx, bx);
            lb.max[axis] = pos;
            rb.min[axis] = pos;
            let (l, r) = split_clipped_bounds(&tri, &bx, axis, pos);
            assert!(within_an_ulp(l, clipped_bounds(&tri, &lb)), "left, triangle {i}");
            assert!(within_an_ulp(r, clipped_bounds(&tri, &rb)), "right, triangle {i}");
            checked += (l.is_some() && r.is_some()) as usize;
        }
        assert!(checked > 300, "only {checked} triangles straddled the split");
    }
}
