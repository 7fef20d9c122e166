//! The divide-and-conquer recursion (Mora 2011; Stokes's thesis, Figure 1 and section 3.3): divide the
//! triangles in two, filter the rays against each half's box, recurse with the rays that pass, and test what is
//! left naively once a node is small. The half nearer to most rays goes first, so their closest hits shorten
//! their intervals before the other half is filtered.

use raylab_simd::{Backend, Kernel, VMask, Vf32};

use super::filter::{FilterBox, classify};
use super::partition::partition;
use super::records::{RayRecord, SetBounds, TriRecord, row_lanes};
use super::split::divide;
use super::{DacrtParams, TopNode};
use crate::packet::{PacketHits, PacketTester, RayPacket};
use crate::ray::{Hit, hit_reach};
use crate::stats::TraversalStats;
use crate::triangle::TriangleSoup;

/// Depth past which nodes are leaves whatever their size; the median and middle-of-list cuts keep real
/// recursions far shallower (a lopsided SAH cut still removes one bin's worth of triangles).
const MAX_DEPTH: u32 = 96;
/// Rays sampled to decide which half is nearer.
const ORDER_SAMPLES: usize = 16;

/// What a leaf does with the rays that reach it: closest hits, occlusion or first blockers. The rays are
/// packed into temporary SoA packets of the backend's width (as MBVH RS leaves do) and each triangle is
/// tested against a packet at once with the watertight test, bit for bit what the single-ray test reports.
pub(super) trait Answer {
    /// Tests every ray of `rays` against every triangle of `tris`, updating the rays' intervals.
    fn leaf<V: Vf32>(&mut self, soup: &TriangleSoup, rays: &mut [RayRecord], tris: &[TriRecord]);
}

/// `V::LANES` rays (or fewer, at the end) in a temporary packet, loaded by transposing their records.
#[inline(always)]
fn packet<V: Vf32>(group: &[RayRecord]) -> RayPacket<V> {
    let [ox, oy, oz, tmin] = row_lanes::<V>(group, 0);
    let [dx, dy, dz, tmax] = row_lanes::<V>(group, 1);
    RayPacket::from_lanes([ox, oy, oz], [dx, dy, dz], tmin, tmax, (1 << group.len()) - 1)
}

/// A leaf's work as a [`Kernel`], so that it runs with the backend's widest lanes (the recursion itself
/// cannot be compiled into the AVX2 entry point).
struct LeafKernel<'a, A> {
    answer: &'a mut A,
    soup: &'a TriangleSoup,
    rays: &'a mut [RayRecord],
    tris: &'a [TriRecord],
}

impl<A: Answer> Kernel for LeafKernel<'_, A> {
    type Output = ();
    #[inline(always)]
    fn run<V: Vf32>(self) {
        self.answer.leaf::<V>(self.soup, self.rays, self.tris);
    }
}

/// Closest hits, written at each ray's id.
pub(super) struct Closest<'a> {
    pub out: &'a mut [Option<Hit>],
}

impl Answer for Closest<'_> {
    #[inline(always)]
    fn leaf<V: Vf32>(&mut self, soup: &TriangleSoup, rays: &mut [RayRecord], tris: &[TriRecord]) {
        for group in rays.chunks_mut(V::LANES) {
            let p = packet::<V>(group);
            let mut hits = PacketHits::new(&p);
            let tester = PacketTester::new(&p);
            for t in tris {
                tester.intersect(&mut hits, soup.get(t.id), t.id, p.valid);
            }
            let found = hits.to_hits();
            for (r, h) in group.iter_mut().zip(found.as_ref()) {
                let &Some(h) = h else { continue };
                let best = &mut self.out[r.id as usize];
                if h.beats(*best) {
                    *best = Some(h);
                    // Boxes and triangles just past the hit stay in reach (`HIT_SLACK`): a closer hit
                    // there still wins, and a farther one loses to `Hit::beats`.
                    r.tmax = hit_reach(h.t);
                }
            }
        }
    }
}

/// The lanes of packet `p` that some triangle of `tris` blocks, and for each lane the first such triangle.
#[inline(always)]
fn blocked<V: Vf32>(p: &RayPacket<V>, soup: &TriangleSoup, tris: &[TriRecord]) -> (u32, V::Array<u32>) {
    let mut open = p.valid;
    let mut first = V::array_from_fn(|_| u32::MAX);
    let tester = PacketTester::new(p);
    for t in tris {
        let hit = tester.occlude(soup.get(t.id), open);
        if hit.any() {
            let bits = hit.bits();
            for (k, f) in first.as_mut().iter_mut().enumerate() {
                if bits >> k & 1 == 1 {
                    *f = t.id;
                }
            }
            open = open & !hit;
            if open.none() {
                break;
            }
        }
    }
    (p.valid.bits() & !open.bits(), first)
}

/// Occlusion flags, written at each ray's id; an answered ray's interval is emptied so no box takes it again.
pub(super) struct Any<'a> {
    pub out: &'a mut [bool],
}

impl Answer for Any<'_> {
    #[inline(always)]
    fn leaf<V: Vf32>(&mut self, soup: &TriangleSoup, rays: &mut [RayRecord], tris: &[TriRecord]) {
        for group in rays.chunks_mut(V::LANES) {
            let (bits, _) = blocked(&packet::<V>(group), soup, tris);
            for (k, r) in group.iter_mut().enumerate() {
                if bits >> k & 1 == 1 {
                    self.out[r.id as usize] = true;
                    r.tmax = f32::NEG_INFINITY;
                }
            }
        }
    }
}

/// The first blocker found for each ray (for the shadow cache), written at its id.
pub(super) struct Blocker<'a> {
    pub out: &'a mut [Option<u32>],
}

impl Answer for Blocker<'_> {
    #[inline(always)]
    fn leaf<V: Vf32>(&mut self, soup: &TriangleSoup, rays: &mut [RayRecord], tris: &[TriRecord]) {
        for group in rays.chunks_mut(V::LANES) {
            let (bits, first) = blocked(&packet::<V>(group), soup, tris);
            for (k, r) in group.iter_mut().enumerate() {
                if bits >> k & 1 == 1 {
                    self.out[r.id as usize] = Some(first.as_ref()[k]);
                    r.tmax = f32::NEG_INFINITY;
                }
            }
        }
    }
}

/// One recursion's shared state.
pub(super) struct Walk<'a, A> {
    pub soup: &'a TriangleSoup,
    /// The division made at setup (empty when the calls divide by another rule).
    pub top: &'a [TopNode],
    pub params: DacrtParams,
    pub answer: A,
    /// Scratch flags for the filter.
    pub flags: Vec<u8>,
    /// SIMD backend of the filter and the leaves (each runs with its widest lanes).
    pub backend: Backend,
    pub stats: TraversalStats,
}

impl<A: Answer> Walk<'_, A> {
    /// Traces `rays` against `tris` (bounded by `b`), which form node `top` of the setup's division, if any.
    pub fn recurse(
        &mut self,
        rays: &mut [RayRecord],
        tris: &mut [TriRecord],
        b: SetBounds,
        top: Option<u32>,
        depth: u32,
    ) {
        self.stats.nodes += 1;
        let p = self.params;
        let made = top.and_then(|i| self.top.get(i as usize)?.split);
        let small = tris.len() <= p.leaf_tris || (made.is_none() && rays.len() <= p.leaf_rays);
        let split = match made {
            _ if small || depth >= MAX_DEPTH => None,
            Some((s, _)) => Some(s),
            None => divide(tris, &b, p.split, &mut self.flags),
        };
        let children = made.map(|(_, c)| c);
        let Some(s) = split else {
            self.stats.leaves += 1;
            self.stats.isect_tests += (rays.len() * tris.len()) as u64;
            let leaf = LeafKernel { answer: &mut self.answer, soup: self.soup, rays, tris };
            raylab_simd::dispatch(self.backend.at_most_eight_lanes(), leaf);
            return;
        };
        let step = rays.len().div_ceil(ORDER_SAMPLES);
        let forward =
            rays.iter().step_by(step).filter(|r| r.dir[s.axis] >= 0.0).count() * 2 >= rays.len().div_ceil(step);
        let (lower, upper) = tris.split_at_mut(s.mid);
        let [first_top, second_top] = children.map_or([None; 2], |c| c.map(Some));
        let ((near, near_b, near_top), (far, far_b, far_top)) = if forward {
            ((lower, s.first, first_top), (upper, s.second, second_top))
        } else {
            ((upper, s.second, second_top), (lower, s.first, first_top))
        };
        // One pass against both boxes: [near (maybe far too) | far only | neither].
        let boxes = [FilterBox::new(&near_b.bounds), FilterBox::new(&far_b.bounds)];
        self.stats.box_tests += 2 * rays.len() as u64;
        classify(self.backend, rays, &boxes, &mut self.flags);
        let n = rays.len();
        let to_near = partition(rays, &mut self.flags[..n], |f| f & 1 != 0);
        let far_only = partition(&mut rays[to_near..], &mut self.flags[to_near..n], |f| f & 2 != 0);
        if to_near > 0 {
            self.recurse(&mut rays[..to_near], near, near_b, near_top, depth + 1);
        }
        // The near half's rays test the far box again with their shortened intervals; those that enter it go
        // to the back of their range, next to the far-only rays.
        let near_rays = &mut rays[..to_near];
        self.stats.box_tests += near_rays.len() as u64;
        classify(self.backend, near_rays, &[boxes[1]], &mut self.flags);
        let stay = partition(near_rays, &mut self.flags[..to_near], |f| f == 0);
        if stay < to_near + far_only {
            self.recurse(&mut rays[stay..to_near + far_only], far, far_b, far_top, depth + 1);
        }
    }
}
