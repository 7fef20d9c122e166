//! Watertight ray/triangle intersection (Woop, Benthin and Wald 2013, "Watertight Ray/Triangle
//! Intersection", JCGT 2(1)).
//!
//! The ray is sheared so that it runs along +z from the origin; the triangle's vertices are transformed the
//! same way and the 2D edge functions are evaluated at the origin. A shared edge gives exactly negated edge
//! values in both triangles (the same products, subtracted in the opposite order), so a ray through an
//! edge or a vertex of a closed mesh always hits at least one of the triangles that meet there. Edge values
//! of exactly zero are recomputed in double precision, as the paper prescribes.

use glam::Vec3;
use rayon::prelude::*;

/// Relative slack on the far test made before the division, `t_scaled <= tmax * |det|`. The quotient `t` is
/// rounded twice and that product once, so without the slack the early test could turn away a hit whose `t`
/// comes out exactly `tmax`: with `tmax` a ray's best hit, that is a tie, which closest-hit tests resolve by
/// triangle id. The exact test on `t` after the division decides.
pub(crate) const SCALED_FAR_SLACK: f32 = 1.0 + 4.0 * f32::EPSILON;

use crate::ray::Ray;
use crate::scene::Scene;

/// Per-ray constants of the watertight test, computed once before traversal.
#[derive(Clone, Copy, Debug)]
pub struct RayShear {
    origin: Vec3,
    kx: usize,
    ky: usize,
    kz: usize,
    sx: f32,
    sy: f32,
    sz: f32,
}

/// A triangle hit: distance and the barycentric weights of vertices 1 and 2.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriHit {
    /// Distance along the ray.
    pub t: f32,
    /// Weight of vertex 1.
    pub u: f32,
    /// Weight of vertex 2.
    pub v: f32,
}

impl RayShear {
    /// Precomputes the shear for `ray`. The ray's direction must not be zero.
    pub fn new(ray: &Ray) -> Self {
        // Indexing an array, not a `Vec3` (whose index is a match), keeps the axis lookups free of branches.
        let d = ray.dir.to_array();
        let a = ray.dir.abs();
        let kz = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        // Swapping keeps the triangle's winding, so U, V, W keep their signs for front faces.
        if d[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        let sz = 1.0 / d[kz];
        Self { origin: ray.origin, kx, ky, kz, sx: d[kx] * sz, sy: d[ky] * sz, sz }
    }

    /// The ray's origin.
    pub fn origin(&self) -> Vec3 {
        self.origin
    }

    /// The axis the sheared ray runs along and the two others, in the order the edge functions use.
    pub fn axes(&self) -> [usize; 3] {
        [self.kx, self.ky, self.kz]
    }

    /// The shear constants `(S_x, S_y, S_z)` of the paper.
    pub fn shear(&self) -> [f32; 3] {
        [self.sx, self.sy, self.sz]
    }

    /// Intersects the triangle `(p0, p1, p2)`; reports a hit with `tmin < t <= tmax` (the interval
    /// convention Embree uses, so both tracers agree on hits exactly at a segment's end).
    #[inline(always)]
    pub fn intersect(&self, tri: &[Vec3; 3], tmin: f32, tmax: f32) -> Option<TriHit> {
        let a = (tri[0] - self.origin).to_array();
        let b = (tri[1] - self.origin).to_array();
        let c = (tri[2] - self.origin).to_array();
        let (kx, ky, kz) = (self.kx, self.ky, self.kz);
        let ax = a[kx] - self.sx * a[kz];
        let ay = a[ky] - self.sy * a[kz];
        let bx = b[kx] - self.sx * b[kz];
        let by = b[ky] - self.sy * b[kz];
        let cx = c[kx] - self.sx * c[kz];
        let cy = c[ky] - self.sy * c[kz];
        let mut u = cx * by - cy * bx;
        let mut v = ax * cy - ay * cx;
        let mut w = bx * ay - by * ax;
        if u == 0.0 || v == 0.0 || w == 0.0 {
            let (ax, ay, bx, by, cx, cy) = (ax as f64, ay as f64, bx as f64, by as f64, cx as f64, cy as f64);
            u = (cx * by - cy * bx) as f32;
            v = (ax * cy - ay * cx) as f32;
            w = (bx * ay - by * ax) as f32;
        }
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 {
            return None;
        }
        let az = self.sz * a[kz];
        let bz = self.sz * b[kz];
        let cz = self.sz * c[kz];
        let t_scaled = u * az + v * bz + w * cz;
        let abs_det = det.abs();
        let t_signed = if det < 0.0 { -t_scaled } else { t_scaled };
        if !(t_signed > tmin * abs_det && t_signed <= tmax * abs_det * SCALED_FAR_SLACK) {
            return None;
        }
        let inv = 1.0 / det;
        let t = t_scaled * inv;
        // Guard the division against the rare overflow/rounding that moves t out of the interval.
        if !(t > tmin && t <= tmax) {
            return None;
        }
        Some(TriHit { t, u: v * inv, v: w * inv })
    }
}

/// Triangle corners in scene order, unindexed, so a kernel fetches one contiguous record per test.
#[derive(Clone, Debug, Default)]
pub struct TriangleSoup {
    verts: Vec<[Vec3; 3]>,
}

/// Triangles per rayon task when [`TriangleSoup::gather`] copies corners on the current pool.
const GATHER_CHUNK: usize = 8192;

impl TriangleSoup {
    /// Copies the corners of every scene triangle.
    pub fn from_scene(scene: &Scene) -> Self {
        Self { verts: (0..scene.triangle_count()).map(|i| scene.vertices(i)).collect() }
    }

    /// Copies the corners of the scene triangles `ids`, in that order (a structure's leaf order, so a leaf's
    /// triangles lie side by side). Ids past the scene's triangles (padding) get NaN corners, which no ray hits.
    pub fn gather(scene: &Scene, ids: &[u32]) -> Self {
        let n = scene.triangle_count();
        let pad = [Vec3::NAN; 3];
        let corners = |&i: &u32| if (i as usize) < n { scene.vertices(i as usize) } else { pad };
        Self { verts: ids.par_iter().with_min_len(GATHER_CHUNK).map(corners).collect() }
    }

    /// A soup of the given corners (tests build small scenes this way).
    #[cfg(test)]
    pub(crate) fn from_corners(verts: Vec<[Vec3; 3]>) -> Self {
        Self { verts }
    }

    /// The corners of triangle `i`.
    #[inline]
    pub fn get(&self, i: u32) -> &[Vec3; 3] {
        &self.verts[i as usize]
    }

    /// Starts loading the corners of triangle `i` into the caches: both cache lines when its 36 bytes
    /// straddle a line boundary. A hint only; it changes no result.
    #[inline(always)]
    pub fn prefetch(&self, i: u32) {
        let [first, _, last] = &self.verts[i as usize];
        raylab_simd::prefetch(std::slice::from_ref(first));
        raylab_simd::prefetch(std::slice::from_ref(last));
    }

    /// The corners of triangles `range`, side by side.
    #[inline]
    pub fn slice(&self, range: std::ops::Range<usize>) -> &[[Vec3; 3]] {
        &self.verts[range]
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.verts.len()
    }

    /// True when there are no triangles.
    pub fn is_empty(&self) -> bool {
        self.verts.is_empty()
    }

    /// All triangles.
    pub fn as_slice(&self) -> &[[Vec3; 3]] {
        &self.verts
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri() -> [Vec3; 3] {
        [Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0)]
    }

    #[test]
    fn hits_front_and_back_with_barycentrics() {
        for dz in [-1.0, 1.0] {
            let r = Ray::new(Vec3::new(0.25, 0.5, -dz * 2.0), Vec3::new(0.0, 0.0, dz));
            let h = RayShear::new(&r).intersect(&tri(), 0.0, f32::INFINITY).expect("hit");
            assert_eq!(h.t, 2.0);
            assert!((h.u - 0.25).abs() < 1e-6 && (h.v - 0.5).abs() < 1e-6, "{h:?}");
        }
    }

    #[test]
    fn respects_the_interval() {
        let r = Ray::new(Vec3::new(0.25, 0.25, -2.0), Vec3::Z);
        let s = RayShear::new(&r);
        assert!(s.intersect(&tri(), 0.0, 1.9).is_none());
        assert!(s.intersect(&tri(), 0.0, 2.0).is_some(), "t == tmax is accepted");
        assert!(s.intersect(&tri(), 2.0, 5.0).is_none(), "t == tmin is rejected");
        let behind = Ray::new(Vec3::new(0.25, 0.25, 2.0), Vec3::Z);
        assert!(RayShear::new(&behind).intersect(&tri(), 0.0, f32::INFINITY).is_none());
    }

    #[test]
    fn misses_outside_and_parallel() {
        let s = RayShear::new(&Ray::new(Vec3::new(0.8, 0.8, -1.0), Vec3::Z));
        assert!(s.intersect(&tri(), 0.0, f32::INFINITY).is_none());
        let par = RayShear::new(&Ray::new(Vec3::new(-1.0, 0.2, 0.0), Vec3::X));
        assert!(par.intersect(&tri(), 0.0, f32::INFINITY).is_none(), "edge-on triangles are not hit");
    }

    #[test]
    fn shared_edge_and_vertex_never_leak() {
        // A quad split along its diagonal, and a fan of 8 triangles around a centre vertex: rays through the
        // diagonal and the centre must hit at least one triangle.
        let quad = [
            [Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(1.0, 1.0, 0.0)],
            [Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 1.0, 0.0), Vec3::new(0.0, 1.0, 0.0)],
        ];
        // Interior points of the diagonal only: its two ends are corners on the open quad's outer boundary.
        for i in 1..64 {
            let p = i as f32 / 64.0;
            let r = Ray::new(Vec3::new(p, p, 1.0) + Vec3::new(0.3, -0.2, 0.0), Vec3::new(-0.3, 0.2, -1.0));
            let s = RayShear::new(&r);
            assert!(quad.iter().any(|t| s.intersect(t, 0.0, f32::INFINITY).is_some()), "leak at {p}");
        }
        let centre = Vec3::new(0.1, 0.7, 0.3);
        let fan: Vec<[Vec3; 3]> = (0..8)
            .map(|k| {
                let a0 = k as f32 * std::f32::consts::TAU / 8.0;
                let a1 = (k + 1) as f32 * std::f32::consts::TAU / 8.0;
                [centre, centre + Vec3::new(a0.cos(), a0.sin(), 0.1), centre + Vec3::new(a1.cos(), a1.sin(), 0.1)]
            })
            .collect();
        for dir in [Vec3::new(0.3, 0.1, -1.0), Vec3::new(-0.7, 0.2, -1.0), Vec3::new(0.0, 0.0, -1.0)] {
            let r = Ray::new(centre - dir * 3.0, dir);
            let s = RayShear::new(&r);
            assert!(fan.iter().any(|t| s.intersect(t, 0.0, f32::INFINITY).is_some()), "vertex leak {dir}");
        }
    }
}
