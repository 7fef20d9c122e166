//! Ray packets: a few rays in structure-of-arrays form, traced together with SIMD (Tsakok 2008, 2.3.1 and
//! 4.1.2; Listings 2.5-2.6 show the SoA layout).

mod tile;
mod woop;

use glam::Vec3;
use raylab_simd::{VMask, Vf32};

use crate::ray::{Hit, Ray};
use crate::triangle::RayShear;

pub use tile::{Frustum, PacketTile, overlaps_box};
pub use woop::{intersect_packet, occlude_packet};

/// Most lanes a packet may have (8 for AVX).
pub const MAX_LANES: usize = 8;

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
    /// The rays themselves, for the exact scalar fallback of the watertight test.
    pub(crate) rays: [Ray; MAX_LANES],
}

impl<V: Vf32> RayPacket<V> {
    /// Packs `rays` (at most `V::LANES`; `None` leaves a lane empty). Invalid rays (NaN, zero direction) leave
    /// their lane empty too.
    pub fn new(rays: &[Option<Ray>]) -> Self {
        assert!(rays.len() <= V::LANES && V::LANES <= MAX_LANES);
        let filler = Ray::new(Vec3::ZERO, Vec3::Z);
        let mut lanes = [filler; MAX_LANES];
        // Per field, the lane values; one pass over the lanes fills them all.
        let mut f = [[0.0f32; MAX_LANES]; 14];
        let mut valid = 0u32;
        let mut axis_bits = [[0u32; 2]; 3];
        let mut finite_inv = true;
        for i in 0..V::LANES {
            if let Some(r) = rays.get(i).copied().flatten().filter(|r| r.is_valid()) {
                lanes[i] = r;
                valid |= 1 << i;
            }
            let r = &lanes[i];
            let inv = Vec3::ONE / r.dir;
            finite_inv &= inv.is_finite();
            let shear = RayShear::new(r);
            for (j, &k) in shear.axes().iter().enumerate() {
                axis_bits[j][0] |= ((k == 0) as u32) << i;
                axis_bits[j][1] |= ((k == 1) as u32) << i;
            }
            let [sx, sy, sz] = shear.shear();
            let values = [
                r.origin.x, r.origin.y, r.origin.z, r.dir.x, r.dir.y, r.dir.z, inv.x, inv.y, inv.z, r.tmin, r.tmax, sx,
                sy, sz,
            ];
            for (field, v) in f.iter_mut().zip(values) {
                field[i] = v;
            }
        }
        let v = |k: usize| V::from_slice(&f[k][..V::LANES]);
        let m = |bits: [u32; 2]| [V::Mask::from_bits(bits[0]), V::Mask::from_bits(bits[1])];
        Self {
            org: [v(0), v(1), v(2)],
            dir: [v(3), v(4), v(5)],
            inv: [v(6), v(7), v(8)],
            finite_inv,
            tmin: v(9),
            tmax: v(10),
            valid: V::Mask::from_bits(valid),
            axis_is: [m(axis_bits[0]), m(axis_bits[1]), m(axis_bits[2])],
            shear: [v(11), v(12), v(13)],
            rays: lanes,
        }
    }

    /// The ray in lane `i`.
    pub fn ray(&self, i: usize) -> &Ray {
        &self.rays[i]
    }
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
    /// Triangle id per lane (`u32::MAX` where nothing was hit).
    pub tri: [u32; MAX_LANES],
    /// Lanes that hit something.
    pub hit: V::Mask,
}

impl<V: Vf32> PacketHits<V> {
    /// No hits yet: `t` starts at each ray's `tmax`.
    pub fn new(p: &RayPacket<V>) -> Self {
        Self { t: p.tmax, u: V::splat(0.0), v: V::splat(0.0), tri: [u32::MAX; MAX_LANES], hit: V::Mask::from_bits(0) }
    }

    /// The hit of lane `i`.
    pub fn get(&self, i: usize) -> Option<Hit> {
        (self.hit.bits() >> i & 1 == 1).then(|| Hit {
            t: self.t.lane(i),
            tri: self.tri[i],
            u: self.u.lane(i),
            v: self.v.lane(i),
        })
    }
}
