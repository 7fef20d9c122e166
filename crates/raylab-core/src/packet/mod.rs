//! Ray packets: a few rays in structure-of-arrays form, traced together with SIMD (Tsakok 2008, 2.3.1 and
//! 4.1.2; Listings 2.5-2.6 show the SoA layout).

mod batch_cull;
mod cone;
mod disc;
mod frustum;
mod slab;
mod tile;
mod woop;

use glam::Vec3;
use raylab_simd::{VMask, Vf32};

use crate::ray::{Hit, Ray};

pub use batch_cull::BatchCull;
pub use cone::Cone;
pub use disc::Disc;
pub(crate) use frustum::SignBounds;
pub use frustum::{Bundle, Frustum};
pub use slab::{overlaps_box, slab_interval};
pub use tile::{PacketTile, packet_shape};
pub use woop::{PacketTester, intersect_packet, occlude_packet};
pub(crate) use woop::{Sheared, sheared_test};

/// Most lanes a packet may have (16, for AVX-512).
pub const MAX_LANES: usize = 16;

/// Up to [`Vf32::LANES`] rays in SoA form, with the per-lane constants of the watertight test.
#[derive(Clone, Copy, Debug)]
pub struct RayPacket<V: Vf32> {
    /// Origins, one vector per axis.
    pub org: [V; 3],
    /// Directions.
    pub dir: [V; 3],
    /// Inverse directions.
    pub inv: [V; 3],
    /// Smallest accepted distances.
    pub tmin: V,
    /// Largest accepted distances.
    pub tmax: V,
    /// Lanes that hold a ray.
    pub valid: V::Mask,
    /// True when no lane has a zero direction component (the slab tests can skip their special case).
    pub finite_inv: bool,
    /// Per lane, masks for "axis index is 0" and "axis index is 1" of `kx`, `ky`, `kz` (Woop et al.).
    pub(crate) axis_is: [[V::Mask; 2]; 3],
    /// Per lane shear constants.
    pub(crate) shear: [V; 3],
    /// `(kx, ky, kz)` when every valid lane has the same ones (the common case for coherent rays), so the
    /// watertight test can index instead of selecting per lane.
    pub(crate) uniform_axes: Option<[usize; 3]>,
}

impl<V: Vf32> RayPacket<V> {
    /// Packs `rays` (at most `V::LANES`; `None` leaves a lane empty). Invalid rays (NaN, zero direction) leave
    /// their lane empty too.
    #[inline(always)]
    pub fn new(rays: &[Option<Ray>]) -> Self {
        assert!(rays.len() <= V::LANES && V::LANES <= MAX_LANES);
        Self::gather(|i| rays.get(i).copied().flatten())
    }

    /// Packs lane `i` from `ray(i)`, straight from the caller's rays (no array of them first); a `None` lane,
    /// or one whose ray fails [`Ray::is_valid`] (checked for all lanes at once), stays empty: it holds a ray
    /// along +z, as [`Self::from_lanes`] accepts. Each ray is copied as two rows of four floats, which a
    /// register transpose turns into the packet's vectors, rather than written lane by lane.
    #[inline(always)]
    pub fn gather(ray: impl Fn(usize) -> Option<Ray>) -> Self {
        const EMPTY: [[f32; 4]; 2] = [[0.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, f32::INFINITY]];
        let mut rows = V::array_from_fn(|_| EMPTY);
        let mut present = 0u32;
        for (i, row) in rows.as_mut().iter_mut().enumerate() {
            if let Some(r) = ray(i) {
                present |= 1 << i;
                *row = [[r.origin.x, r.origin.y, r.origin.z, r.dir.x], [r.dir.y, r.dir.z, r.tmin, r.tmax]];
            }
        }
        let rows = rows.as_ref();
        let first = V::array_from_fn(|i| &rows[i][0]);
        let second = V::array_from_fn(|i| &rows[i][1]);
        let [ox, oy, oz, dx] = V::transpose_rows(first.as_ref());
        let [dy, dz, tmin, tmax] = V::transpose_rows(second.as_ref());
        // `Ray::is_valid` per lane: finite origin and direction (`|x| < inf` fails for infinities and NaN), a
        // non-zero direction, no NaN interval end.
        let (zero, inf) = (V::splat(0.0), V::splat(f32::INFINITY));
        let finite = |v: V| v.abs().lt(inf);
        let ok = finite(ox)
            & finite(oy)
            & finite(oz)
            & finite(dx)
            & finite(dy)
            & finite(dz)
            & dx.abs().max(dy.abs()).max(dz.abs()).gt(zero)
            & tmin.eq(tmin)
            & tmax.eq(tmax);
        let valid = V::Mask::from_bits(present) & ok;
        let lanes = |v: V, empty: f32| V::select(valid, v, V::splat(empty));
        let org = [lanes(ox, 0.0), lanes(oy, 0.0), lanes(oz, 0.0)];
        let dir = [lanes(dx, 0.0), lanes(dy, 0.0), lanes(dz, 1.0)];
        Self::from_lanes(org, dir, lanes(tmin, 0.0), lanes(tmax, f32::INFINITY), valid.bits())
    }

    /// The packet of the rays already in lanes: origins, directions, intervals, and the `valid` lanes (bit `i`
    /// for lane `i`), which must hold rays with [`Ray::is_valid`]; the other lanes may hold anything finite.
    #[inline(always)]
    pub fn from_lanes(org: [V; 3], dir: [V; 3], tmin: V, tmax: V, valid: u32) -> Self {
        let [dx, dy, dz] = dir;
        let one = V::splat(1.0);
        let inv = [one / dir[0], one / dir[1], one / dir[2]];
        let inf = V::splat(f32::INFINITY);
        let finite_inv = (inv[0].abs().lt(inf) & inv[1].abs().lt(inf) & inv[2].abs().lt(inf)).bits()
            == V::Mask::from_bits(u32::MAX).bits();
        // The watertight test's per-ray constants, computed per lane with the scalar test's exact operations
        // (`RayShear::new`): kz is the axis of the largest |d| (ties to the lower axis), kx and ky follow it
        // cyclically and swap when d[kz] is negative.
        let (ax, ay, az) = (dx.abs(), dy.abs(), dz.abs());
        let kz0 = ax.ge(ay) & ax.ge(az);
        let kz1 = !kz0 & ay.ge(az);
        let kz2 = !(kz0 | kz1);
        let d_kz = V::select(kz0, dir[0], V::select(kz1, dir[1], dir[2]));
        let neg = d_kz.lt(V::splat(0.0));
        let pos = !neg;
        let kx0 = (kz2 & pos) | (kz1 & neg);
        let kx1 = (kz0 & pos) | (kz2 & neg);
        let ky0 = (kz1 & pos) | (kz2 & neg);
        let ky1 = (kz2 & pos) | (kz0 & neg);
        let sz = one / d_kz;
        let sx = V::select(kx0, dx, V::select(kx1, dy, dz)) * sz;
        let sy = V::select(ky0, dx, V::select(ky1, dy, dz)) * sz;
        let valid_mask = V::Mask::from_bits(valid);
        let axis_of = |is0: V::Mask, is1: V::Mask| {
            let (b0, b1, v) = ((is0 & valid_mask).bits(), (is1 & valid_mask).bits(), valid_mask.bits());
            if b0 == v {
                Some(0)
            } else if b1 == v {
                Some(1)
            } else if (b0 | b1) == 0 {
                Some(2)
            } else {
                None
            }
        };
        let uniform_axes = match (axis_of(kx0, kx1), axis_of(ky0, ky1), axis_of(kz0, kz1)) {
            (Some(x), Some(y), Some(z)) if valid != 0 => Some([x, y, z]),
            _ => None,
        };
        Self {
            org,
            dir,
            inv,
            finite_inv,
            tmin,
            tmax,
            valid: V::Mask::from_bits(valid),
            axis_is: [[kx0, kx1], [ky0, ky1], [kz0, kz1]],
            shear: [sx, sy, sz],
            uniform_axes,
        }
    }

    /// The ray in lane `i`.
    #[inline(always)]
    pub fn ray(&self, i: usize) -> Ray {
        // Written out rather than with a closure per vector, which may stay out of line (see `map3`).
        let (o, d) = (&self.org, &self.dir);
        let origin = Vec3::new(o[0].lane(i), o[1].lane(i), o[2].lane(i));
        Ray::segment(origin, Vec3::new(d[0].lane(i), d[1].lane(i), d[2].lane(i)), self.tmin.lane(i), self.tmax.lane(i))
    }
}

/// `[f(a[0]), f(a[1]), f(a[2])]`. Kernels use it instead of `<[T; 3]>::map`: code that handles vectors must
/// be inlined into the SIMD entry point to be compiled for its instruction set (see `raylab_simd::dispatch`),
/// and the standard library's array and iterator helpers are not always inlined.
#[inline(always)]
pub(crate) fn map3<T: Copy, U>(a: [T; 3], f: impl Fn(T) -> U) -> [U; 3] {
    [f(a[0]), f(a[1]), f(a[2])]
}

/// Closest hits of a packet, per lane.
#[derive(Clone, Copy, Debug)]
pub struct PacketHits<V: Vf32> {
    /// Hit distance, or the ray's `tmax` where nothing was hit yet.
    pub t: V,
    /// Barycentric weight of vertex 1.
    pub u: V,
    /// Barycentric weight of vertex 2.
    pub v: V,
    /// Triangle id per lane as the bits of an `f32` (`u32::MAX` where nothing was hit): kept in a vector so a
    /// hit updates it with one select, like the distances, instead of a store per lane.
    pub tri: V,
    /// Lanes that hit something.
    pub hit: V::Mask,
}

/// A packet's hits spilled from vectors to per-lane arrays ([`PacketHits::lanes`]).
pub struct HitLanes<V: Vf32> {
    t: V::Array<f32>,
    u: V::Array<f32>,
    v: V::Array<f32>,
    tri: V::Array<f32>,
    bits: u32,
}

impl<V: Vf32> HitLanes<V> {
    /// The hit of lane `i`, if it has one.
    #[inline(always)]
    pub fn get(&self, i: usize) -> Option<Hit> {
        (self.bits >> i & 1 == 1).then(|| Hit {
            t: self.t.as_ref()[i],
            tri: self.tri.as_ref()[i].to_bits(),
            u: self.u.as_ref()[i],
            v: self.v.as_ref()[i],
        })
    }
}

impl<V: Vf32> PacketHits<V> {
    /// No hits yet: `t` starts at each ray's `tmax`.
    #[inline(always)]
    pub fn new(p: &RayPacket<V>) -> Self {
        Self {
            t: p.tmax,
            u: V::splat(0.0),
            v: V::splat(0.0),
            tri: V::splat(f32::from_bits(u32::MAX)),
            hit: V::Mask::from_bits(0),
        }
    }

    /// The hits of all lanes at once (cheaper than [`PacketHits::get`] per lane).
    #[inline(always)]
    pub fn to_hits(&self) -> V::Array<Option<Hit>> {
        let lanes = self.lanes();
        V::array_from_fn(|i| lanes.get(i))
    }

    /// The lanes spilled to arrays once, to be read one by one ([`HitLanes::get`]): writing a tile's hits
    /// straight to their pixels this way skips the array of [`PacketHits::to_hits`].
    #[inline(always)]
    pub fn lanes(&self) -> HitLanes<V> {
        let spill = |x: V| {
            let mut a = V::array_from_fn(|_| 0.0);
            x.write_to(a.as_mut());
            a
        };
        HitLanes { t: spill(self.t), u: spill(self.u), v: spill(self.v), tri: spill(self.tri), bits: self.hit.bits() }
    }

    /// The hit of lane `i`.
    #[inline(always)]
    pub fn get(&self, i: usize) -> Option<Hit> {
        (self.hit.bits() >> i & 1 == 1).then(|| Hit {
            t: self.t.lane(i),
            tri: self.tri.lane(i).to_bits(),
            u: self.u.lane(i),
            v: self.v.lane(i),
        })
    }
}

/// [`crate::ray::hit_reach`] lane by lane: how far past each lane's best hit cells may still hold a closer one.
#[inline(always)]
pub fn hit_reach_lanes<V: Vf32>(t: V) -> V {
    t.max(t * V::splat(1.0 + crate::ray::HIT_SLACK))
}

/// `a . b` per lane, summed in glam's order (`Vec3::dot`), so a lane's result is the scalar one to the bit.
#[inline(always)]
pub(crate) fn dot3<V: Vf32>(a: &[V; 3], b: &[V; 3]) -> V {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
