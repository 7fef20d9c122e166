//! The compact records DACRT moves around (Afra 2012, as Stokes's thesis section 3.3 describes them): a ray
//! carries what filtering and the leaves need and is moved whole, so every pass reads rays linearly; a
//! triangle reference carries its box (for partitioning and for the children's boxes) and the id of its full
//! record, which only leaves fetch.

use glam::{Vec3, Vec4};

use raylab_simd::Vf32;

use crate::aabb::Aabb;
use crate::ray::Ray;

/// A ray as DACRT stores it: 48 bytes, moved (not indexed) by every filter pass. Its three 16-byte rows
/// ([`RayRecord::rows`]) are what the filter transposes into SIMD lanes.
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C, align(16))]
pub(super) struct RayRecord {
    /// Start point.
    pub org: Vec3,
    /// Smallest accepted hit distance.
    pub tmin: f32,
    /// Direction (unnormalised, as given).
    pub dir: Vec3,
    /// Largest accepted hit distance: the closest hit so far, or `-inf` once an occlusion query is answered,
    /// which makes every later box test fail.
    pub tmax: f32,
    /// Component-wise inverse direction (infinite for zero components).
    pub inv: Vec3,
    /// Index of the ray in the caller's slice, where its result goes.
    pub id: u32,
}

impl RayRecord {
    /// The record of `ray`, the `id`-th of the caller's rays.
    pub fn new(ray: &Ray, id: u32) -> Self {
        Self { org: ray.origin, tmin: ray.tmin, dir: ray.dir, tmax: ray.tmax, inv: ray.inv_dir(), id }
    }

    /// The record as three rows of four floats: `[org, tmin]`, `[dir, tmax]` and `[inv, id bits]`.
    #[inline(always)]
    pub fn rows(&self) -> &[[f32; 4]; 3] {
        bytemuck::cast_ref(self)
    }
}

/// Row `i` of the rays of `block` ([`RayRecord::rows`]) transposed into lanes, one vector per field; a short
/// block repeats its first ray in the missing lanes.
#[inline(always)]
pub(super) fn row_lanes<V: Vf32>(block: &[RayRecord], i: usize) -> [V; 4] {
    let rs = V::array_from_fn(|k| &block[k.min(block.len() - 1)].rows()[i]);
    V::transpose_rows(rs.as_ref())
}

/// A triangle as DACRT moves it: its box and its id in the scene (32 bytes). Division, which every set pays
/// for near the top of the recursion, reads only boxes; the leaves fetch the corners by id.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
pub(super) struct TriRecord {
    /// Lower corner of the triangle's box.
    pub min: Vec3,
    /// Scene index of the triangle.
    pub id: u32,
    /// Upper corner of the triangle's box.
    pub max: Vec3,
    _pad: u32,
}

impl TriRecord {
    /// The record of triangle `id` with corners `v`.
    pub fn new(v: [Vec3; 3], id: u32) -> Self {
        Self { min: v[0].min(v[1]).min(v[2]), id, max: v[0].max(v[1]).max(v[2]), _pad: 0 }
    }

    /// Twice the box centre on `axis` (the partitions only compare centres, so the halving is skipped).
    #[inline(always)]
    pub fn centre2(&self, axis: usize) -> f32 {
        self.min[axis] + self.max[axis]
    }
}

/// The box and centre box of a set of triangle references.
#[derive(Clone, Copy, Debug)]
pub(super) struct SetBounds {
    /// Union of the triangles' boxes.
    pub bounds: Aabb,
    /// Bounds of the doubled centres ([`TriRecord::centre2`]).
    pub centres: Aabb,
}

impl SetBounds {
    /// Bounds of `tris`.
    pub fn of(tris: &[TriRecord]) -> Self {
        tris.iter().fold(BoundsAcc::EMPTY, |a, t| a.grow(t)).bounds()
    }

    /// The union of two bounds.
    pub fn union(self, o: SetBounds) -> Self {
        SetBounds { bounds: self.bounds.union(o.bounds), centres: self.centres.union(o.centres) }
    }
}

/// [`SetBounds`] being accumulated in SIMD lanes (w unused): box min and max, doubled-centre min and max.
/// Division bins every triangle of a set, so this is DACRT's busiest loop on small ray sets.
#[derive(Clone, Copy, Debug)]
pub(super) struct BoundsAcc([Vec4; 4]);

impl BoundsAcc {
    /// Bounds of nothing.
    pub const EMPTY: BoundsAcc = BoundsAcc([Vec4::INFINITY, Vec4::NEG_INFINITY, Vec4::INFINITY, Vec4::NEG_INFINITY]);

    /// These bounds grown by one triangle.
    #[inline(always)]
    pub fn grow(self, t: &TriRecord) -> Self {
        let (lo, hi) = (t.min.extend(0.0), t.max.extend(0.0));
        let centre2 = lo + hi;
        let [a, b, c, d] = self.0;
        BoundsAcc([a.min(lo), b.max(hi), c.min(centre2), d.max(centre2)])
    }

    /// The accumulated bounds.
    pub fn bounds(self) -> SetBounds {
        let [a, b, c, d] = self.0;
        SetBounds { bounds: Aabb::new(a.truncate(), b.truncate()), centres: Aabb::new(c.truncate(), d.truncate()) }
    }
}
