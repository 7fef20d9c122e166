//! A tile of rays cut into 2x2 packets (4x2 with eight lanes, 4x4 with sixteen), the unit that frustum kernels
//! trace and cull (thesis 4.1.3-4.1.5).

use std::ops::Range;

use glam::Vec3;
use raylab_simd::{VMask, Vf32};

use super::{BatchCull, PacketHits, RayPacket};
use crate::ray::Ray;

/// Width and height in pixels of a packet of `lanes` rays: 2x2 for four lanes, 4x2 for eight, 4x4 for sixteen
/// (as square as the lanes allow, so a packet's rays stay coherent).
pub const fn packet_shape(lanes: usize) -> (usize, usize) {
    let w = if lanes >= 8 { 4 } else { 2 };
    (w, lanes / w)
}

/// The packets of a `width x height` tile, each [`Self::PACKET_W`] (`w`) pixels wide and [`Self::PACKET_H`]
/// (`h`) high; lane `i` holds pixel `(w bx + i % w, h by + i / w)`. Pixels outside the tile leave lanes empty.
///
/// Packets are stored quadrant by quadrant (top left, top right, bottom left, bottom right; the quadrants of
/// MFT, 4.1.5, split at [`Self::quadrant_split`]), row-major inside each, so a quadrant's packets are one run
/// of indices: its packets fill whole chunks of [`Vf32::LANES`] ([`crate::packet::BatchCull`]) when its
/// packet count is a multiple of the lanes, and each chunk of a tile is a compact block of pixels.
pub struct PacketTile<V: Vf32> {
    /// The packets.
    pub packets: Vec<RayPacket<V>>,
    /// Closest hits (or, for occlusion, the per-lane state) of each packet.
    pub hits: Vec<PacketHits<V>>,
    /// Per packet, the farthest current hit distance over its rays (infinite while one has none), widened
    /// by the kd-tree walks' hit slack once hits are found: a leaf that starts beyond it cannot improve any
    /// of the packet's hits. Padded with -inf to whole vectors, so
    /// [`BatchCull`] loads it a vector at a time.
    pub farthest_hit: Vec<f32>,
    /// The batched culling data, once [`PacketTile::share_origin`] has found the rays' common origin.
    pub batch: Option<BatchCull>,
    /// The last batch data, kept for its buffer while the tile holds none.
    spare_batch: Option<BatchCull>,
    /// Index of each packet's lane-0 pixel in the tile, and the tile width, to map lanes back to pixels.
    pub origin_pixel: Vec<(usize, usize)>,
    /// Packet columns and rows.
    pub cols: usize,
    /// Packet rows.
    pub rows: usize,
    /// Tile width in pixels.
    pub width: usize,
    /// Tile height in pixels.
    pub height: usize,
}

impl<V: Vf32> PacketTile<V> {
    /// Packet width in pixels ([`packet_shape`]).
    pub const PACKET_W: usize = packet_shape(V::LANES).0;
    /// Packet height in pixels ([`packet_shape`]).
    pub const PACKET_H: usize = packet_shape(V::LANES).1;

    /// Cuts `rays` (row-major, `width x height`) into packets.
    #[inline(always)]
    pub fn new(rays: &[Option<Ray>], width: usize, height: usize) -> Self {
        let mut tile = Self::empty();
        tile.refill(rays, width, height);
        tile
    }

    /// A tile without packets, to be filled by [`PacketTile::refill`].
    pub fn empty() -> Self {
        Self {
            packets: Vec::new(),
            hits: Vec::new(),
            farthest_hit: Vec::new(),
            batch: None,
            spare_batch: None,
            origin_pixel: Vec::new(),
            cols: 0,
            rows: 0,
            width: 0,
            height: 0,
        }
    }

    /// [`PacketTile::new`] in place, keeping the buffers: kernels that trace many small tiles one after the
    /// other (each point's light samples) would otherwise spend longer allocating them than packing the rays.
    #[inline(always)]
    pub fn refill(&mut self, rays: &[Option<Ray>], width: usize, height: usize) {
        let (pw, ph) = (Self::PACKET_W, Self::PACKET_H);
        let (cols, rows) = (width.div_ceil(pw), height.div_ceil(ph));
        (self.cols, self.rows, self.width, self.height) = (cols, rows, width, height);
        if let Some(batch) = self.batch.take() {
            self.spare_batch = Some(batch);
        }
        let n = cols * rows;
        let (packets, origin_pixel, hits, farthest_hit) =
            (&mut self.packets, &mut self.origin_pixel, &mut self.hits, &mut self.farthest_hit);
        packets.clear();
        origin_pixel.clear();
        hits.clear();
        farthest_hit.clear();
        packets.reserve(n);
        origin_pixel.reserve(n);
        hits.reserve(n);
        let (sx, sy) = quadrant_split(cols, rows);
        for (xs, ys) in [(0..sx, 0..sy), (sx..cols, 0..sy), (0..sx, sy..rows), (sx..cols, sy..rows)] {
            let (x0, x1) = (pw * xs.start, width.min(pw * xs.end));
            for by in ys.clone() {
                // The next row of packets' rays start loading while this row is packed: a tile's rays (36 KiB
                // at 32x32) come from memory when a whole frame's rays were made before tracing, and packing
                // waited on them (7-8% of a primary MFT 32x32 trace in `perf`, 4-5% with the hint).
                let next = if by + 1 < ys.end { ph * (by + 1)..ph * (by + 2) } else { 0..0 };
                for y in next {
                    if let Some(row) = rays.get(y * width + x0..y * width + x1) {
                        raylab_simd::prefetch(row);
                    }
                }
                for bx in xs.clone() {
                    let p = RayPacket::gather(|i| {
                        let (x, y) = (pw * bx + i % pw, ph * by + i / pw);
                        if x < width && y < height { rays[y * width + x] } else { None }
                    });
                    hits.push(PacketHits::new(&p));
                    farthest_hit.push(V::select(p.valid, p.tmax, V::splat(f32::NEG_INFINITY)).reduce_max());
                    packets.push(p);
                    origin_pixel.push((pw * bx, ph * by));
                }
            }
        }
        farthest_hit.resize(n.div_ceil(V::LANES) * V::LANES, f32::NEG_INFINITY);
    }

    /// Prepares batched packet/leaf culling ([`BatchCull`]) for rays that all start at `origin` (the caller
    /// has checked that they do).
    #[inline(always)]
    pub fn share_origin(&mut self, origin: Vec3) {
        self.batch = Some(match self.spare_batch.take() {
            Some(mut batch) => {
                batch.rebuild(origin, &self.packets);
                batch
            }
            None => BatchCull::new(origin, &self.packets),
        });
    }

    /// Calls `f(pixel_index, lane)` for every lane of packet `j` that holds a ray.
    #[inline(always)]
    pub fn for_each_lane(&self, j: usize, mut f: impl FnMut(usize, usize)) {
        let (x0, y0) = self.origin_pixel[j];
        let bits = self.packets[j].valid.bits();
        let pw = Self::PACKET_W;
        for i in (0..V::LANES).filter(|i| bits >> i & 1 == 1) {
            f((y0 + i / pw) * self.width + x0 + i % pw, i);
        }
    }

    /// The first packet column and row of the right and bottom quadrants: the left and top ones take the
    /// larger half of an odd count.
    #[inline(always)]
    pub fn quadrant_split(&self) -> (usize, usize) {
        quadrant_split(self.cols, self.rows)
    }

    /// Each quadrant's packets (top left, top right, bottom left, bottom right), as the run of indices the
    /// storage order gives it; an empty quadrant (one packet column or row) has an empty run. Runs rather than
    /// lists of indices cost MFT nothing to build per tile.
    #[inline(always)]
    pub fn quadrant_packets(&self) -> [Range<usize>; 4] {
        let (sx, sy) = self.quadrant_split();
        let (cols, rows) = (self.cols, self.rows);
        let ends = [sx * sy, sy * cols, sy * cols + sx * (rows - sy), cols * rows];
        [0..ends[0], ends[0]..ends[1], ends[1]..ends[2], ends[2]..ends[3]]
    }
}

/// The first packet column and row of the right and bottom quadrants of a tile of `cols x rows` packets: the
/// left and top quadrants take the larger half.
#[inline(always)]
const fn quadrant_split(cols: usize, rows: usize) -> (usize, usize) {
    (cols.div_ceil(2), rows.div_ceil(2))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rays of a `width x height` tile, some missing, so packets have empty lanes.
    fn tile_rays(width: usize, height: usize, seed: f32) -> Vec<Option<Ray>> {
        (0..width * height)
            .map(|i| {
                let f = i as f32 + seed;
                let dir = Vec3::new((f * 0.37).sin(), (f * 0.11).cos(), 1.0).normalize();
                (i % 7 != 3).then(|| Ray::segment(Vec3::new(seed, 1.0, -2.0), dir, 0.0, 10.0 + f))
            })
            .collect()
    }

    /// A tile refilled after holding a larger and a smaller one equals the tile cut anew from the same rays
    /// (a [`raylab_simd::Kernel`], so every backend's lane type is checked).
    struct RefillEqualsNew;

    impl raylab_simd::Kernel for RefillEqualsNew {
        type Output = ();
        fn run<V: Vf32>(self) {
            let mut kept = PacketTile::<V>::empty();
            for (w, h, seed) in [(16, 16, 0.5), (4, 4, 1.5), (5, 3, 2.5), (0, 0, 3.5), (9, 6, 4.5)] {
                let rays = tile_rays(w, h, seed);
                kept.refill(&rays, w, h);
                kept.share_origin(Vec3::new(seed, 1.0, -2.0));
                kept.refill(&rays, w, h);
                let new = PacketTile::<V>::new(&rays, w, h);
                let dims = |t: &PacketTile<V>| (t.cols, t.rows, t.width, t.height);
                assert_eq!(dims(&kept), dims(&new), "{w}x{h}");
                assert!(kept.batch.is_none(), "{w}x{h}: a refill drops the old batch data");
                assert_eq!(kept.origin_pixel, new.origin_pixel, "{w}x{h}");
                assert_eq!(kept.farthest_hit, new.farthest_hit, "{w}x{h}");
                assert_eq!((kept.packets.len(), kept.hits.len()), (new.packets.len(), new.hits.len()));
                for (j, (a, b)) in kept.packets.iter().zip(&new.packets).enumerate() {
                    assert_eq!(a.valid.bits(), b.valid.bits(), "{w}x{h} packet {j}");
                    for i in (0..V::LANES).filter(|i| a.valid.bits() >> i & 1 == 1) {
                        assert_eq!(a.ray(i), b.ray(i), "{w}x{h} packet {j} lane {i}");
                        assert_eq!(kept.hits[j].t.lane(i), new.hits[j].t.lane(i), "{w}x{h} packet {j} lane {i}");
                    }
                }
            }
        }
    }

    /// Each quadrant's packets are one run of indices, row by row inside it, the runs in quadrant order
    /// covering the tile, whole chunks in even tiles.
    struct QuadrantOrder;

    impl raylab_simd::Kernel for QuadrantOrder {
        type Output = ();
        fn run<V: Vf32>(self) {
            let (pw, ph) = (PacketTile::<V>::PACKET_W, PacketTile::<V>::PACKET_H);
            for (w, h) in [(16, 16), (32, 32), (8, 8), (5, 3), (9, 6), (40, 24), (1, 1), (20, 7)] {
                let t = PacketTile::<V>::new(&tile_rays(w, h, 0.5), w, h);
                assert_eq!(t.packets.len(), t.cols * t.rows, "{w}x{h}");
                let (sx, sy) = t.quadrant_split();
                let (cx, cy) = (sx * pw, sy * ph);
                let mut next = 0;
                let rects = [(0, 0, cx, cy), (cx, 0, w, cy), (0, cy, cx, h), (cx, cy, w, h)];
                for (run, (x0, y0, x1, y1)) in t.quadrant_packets().into_iter().zip(rects) {
                    assert_eq!(run.start, next, "{w}x{h}: quadrant at ({x0}, {y0}) follows the one before");
                    let inside = (y0..y1).step_by(ph).flat_map(|y| (x0..x1).step_by(pw).map(move |x| (x, y)));
                    let want: Vec<_> = inside.collect();
                    let got: Vec<_> = run.clone().map(|j| t.origin_pixel[j]).collect();
                    assert_eq!(got, want, "{w}x{h}: the packets of the quadrant at ({x0}, {y0}), row by row");
                    next = run.end;
                    if t.cols.is_multiple_of(2) && t.rows.is_multiple_of(2) && (sx * sy).is_multiple_of(V::LANES) {
                        assert_eq!(run.start % V::LANES, 0, "{w}x{h}: quadrants of whole chunks");
                    }
                }
                assert_eq!(next, t.packets.len(), "{w}x{h}: the quadrants cover the tile");
            }
        }
    }

    #[test]
    fn packets_are_stored_quadrant_by_quadrant_on_every_backend() {
        for backend in raylab_simd::Backend::available() {
            raylab_simd::dispatch(backend, QuadrantOrder);
        }
    }

    #[test]
    fn refilled_tiles_equal_new_ones_on_every_backend() {
        for backend in raylab_simd::Backend::available() {
            raylab_simd::dispatch(backend, RefillEqualsNew);
        }
    }
}
