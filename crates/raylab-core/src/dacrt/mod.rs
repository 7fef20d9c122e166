//! Divide-and-conquer ray tracing (DACRT: Mora 2011, "Naive ray-tracing: a divide-and-conquer approach", with
//! Afra 2012's improvements; seed 003, Stokes 2014, section 2.5 and 3.3): rays are traced without any stored
//! acceleration structure. A set of rays and a set of triangles are divided together: the triangles are split
//! in two (`split.rs`), the rays filtered against each half's box in SIMD (`filter.rs`), and each half recursed
//! with the rays that reach it (`traverse.rs`), until few rays or few triangles are left to test naively.
//!
//! The only preparation ([`Dacrt::new`]) copies the triangles and their boxes and makes the top of the
//! division every call would begin with (sets above [`DIVIDE_ONCE_ABOVE`] triangles, a few linear passes), so
//! geometry that moves every frame costs milliseconds to "rebuild", and a call's own work starts several
//! levels down: calls of a few thousand rays (the hybrid mode's reflection and shadow rays) would otherwise
//! spend most of their time dividing the whole scene again, and, since such a set thins out to a few rays per
//! node long before the triangles do, test each of those rays against hundreds of triangles. The benchmarks
//! time that setup with every traced frame.
//! The rest of the work is amortised over the rays of one call: DACRT wants large ray sets (a whole
//! G-buffer's reflection rays, or large tiles), not single rays.

mod filter;
mod partition;
mod records;
mod split;
mod traverse;

pub use split::SplitRule;

use std::ops::Range;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use raylab_simd::Backend;
use serde::{Deserialize, Serialize};

use crate::ray::{Hit, Ray};
use crate::scene::Scene;
use crate::stats::TraversalStats;
use crate::triangle::TriangleSoup;
use records::{RayRecord, SetBounds, TriRecord};
use split::Split;
use traverse::{Answer, Any, Blocker, Closest, Walk};

/// When DACRT stops dividing and how it divides.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct DacrtParams {
    /// A node with at most this many rays is tested naively, unless the setup already divided it (calls with
    /// the SAH rule: then its division costs nothing, and following it filters the rays against boxes instead
    /// of testing them against all of the node's triangles).
    pub leaf_rays: usize,
    /// A node with at most this many triangles is tested naively.
    pub leaf_tris: usize,
    /// How triangles are divided.
    pub split: SplitRule,
}

impl Default for DacrtParams {
    fn default() -> Self {
        Self { leaf_rays: 8, leaf_tris: 8, split: SplitRule::Sah }
    }
}

impl DacrtParams {
    /// Largest leaf threshold accepted (a naive leaf's cost is rays x triangles).
    pub const MAX_LEAF: usize = 4096;
}

/// Ray sets with fewer rays than this are traced against the two [`Dacrt`] triangle groups on two threads
/// when the rayon pool has them (the hybrid mode's reflection and shadow rays, a few thousand a frame): each
/// thread then divides half of the triangles. Larger sets stay on one thread, where testing the nearer group
/// first shortens the rays before the farther one, and the renderers trace several such sets at once.
pub const FORK_BELOW: usize = 16384;

/// Sets of more triangles than this are divided once, at setup, rather than by every call: about the top
/// nine levels on scenes of 100k triangles, which every ray set would otherwise divide again. Deep enough that
/// a few thousand reflection rays, which reach nodes of this size in ones and twos, test few triangles each
/// (the hybrid mode's rays on the atrium: 173 triangle tests per ray with 4,096, 54 with 256); shallow enough
/// that the setup stays a few milliseconds, since moving geometry redoes it every frame.
pub const DIVIDE_ONCE_ABOVE: usize = 256;

/// Triangles `tris` of [`Dacrt`]'s references, bounded by `bounds`; `top` is the node of the setup's division
/// they form, if any.
#[derive(Clone, Debug)]
struct Group {
    tris: Range<usize>,
    bounds: SetBounds,
    top: Option<u32>,
}

/// A node of the division made at setup ([`DIVIDE_ONCE_ABOVE`]): the split of its triangles and its two
/// children's nodes, or `None` where the calls divide for themselves.
#[derive(Clone, Copy, Debug)]
pub(crate) struct TopNode {
    split: Option<(Split, [u32; 2])>,
}

/// Divides `refs` (bounded by `bounds`) by the SAH while they hold more than [`DIVIDE_ONCE_ABOVE`]
/// triangles, the two halves of each split on two threads where the rayon pool has them; returns the nodes
/// depth first, `refs`' own node first.
fn divide_top(refs: &mut [TriRecord], bounds: &SetBounds) -> Vec<TopNode> {
    let split = (refs.len() > DIVIDE_ONCE_ABOVE)
        .then(|| split::divide(refs, bounds, SplitRule::Sah, &mut Vec::new()))
        .flatten();
    let Some(s) = split else { return vec![TopNode { split: None }] };
    let (first, second) = refs.split_at_mut(s.mid);
    let (a, b) = rayon::join(|| divide_top(first, &s.first), || divide_top(second, &s.second));
    let shift = |nodes: Vec<TopNode>, by: u32| {
        nodes.into_iter().map(move |n| TopNode { split: n.split.map(|(s, c)| (s, c.map(|i| i + by))) })
    };
    let (first_at, second_at) = (1, 1 + a.len() as u32);
    let mut nodes = vec![TopNode { split: Some((s, [first_at, second_at])) }];
    nodes.extend(shift(a, first_at));
    nodes.extend(shift(b, second_at));
    nodes
}

/// Per-call working memory: the triangle references (a permutation of the scene's, reused from call to call),
/// the moved rays and the filter's flags. `tris` keeps the setup's division (each of its nodes' triangles in
/// that node's range) as long as only calls that reuse it have permuted them.
struct Scratch {
    tris: Vec<TriRecord>,
    rays: Vec<RayRecord>,
    flags: Vec<u8>,
    keeps_setup_division: bool,
}

/// A scene prepared for divide-and-conquer tracing: its triangles, their boxes and the top of their division.
pub struct Dacrt {
    soup: TriangleSoup,
    refs: Vec<TriRecord>,
    root: SetBounds,
    /// The top of the division every call would make, made once at setup on `refs` (node 0 holds them all):
    /// calls with the SAH rule reuse it, and a small ray set is traced against the two halves of the first
    /// split on two threads ([`FORK_BELOW`]).
    top: Vec<TopNode>,
    setup_time: Duration,
    /// Working memory of finished calls, reused by the next ones (one per thread that traced).
    pool: Mutex<Vec<Scratch>>,
}

impl Dacrt {
    /// Copies the triangles of `scene` and their boxes and divides the top of them ([`DIVIDE_ONCE_ABOVE`]):
    /// a few linear passes, the whole "build", redone whenever the geometry moves.
    pub fn new(scene: &Scene) -> Self {
        let start = Instant::now();
        let soup = TriangleSoup::from_scene(scene);
        let mut refs: Vec<TriRecord> =
            soup.as_slice().iter().enumerate().map(|(i, t)| TriRecord::new(*t, i as u32)).collect();
        let root = SetBounds::of(&refs);
        let top = divide_top(&mut refs, &root);
        Self { soup, refs, root, top, setup_time: start.elapsed(), pool: Mutex::new(Vec::new()) }
    }

    /// How long [`Dacrt::new`] took.
    pub fn setup_time(&self) -> Duration {
        self.setup_time
    }

    /// Nodes of the division made at setup ([`DIVIDE_ONCE_ABOVE`]): 1 when the scene is too small to divide
    /// in advance, 0 when it is empty.
    pub fn setup_nodes(&self) -> usize {
        self.top.len()
    }

    /// Bytes of the triangle copy, their records and the setup's division.
    pub fn bytes(&self) -> usize {
        self.soup.len() * std::mem::size_of::<[glam::Vec3; 3]>()
            + self.refs.len() * std::mem::size_of::<TriRecord>()
            + self.top.len() * std::mem::size_of::<TopNode>()
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.refs.len()
    }

    /// Closest hits in `(tmin, tmax]` of all `rays` (`None` entries are skipped), written to `out`; among hits
    /// at one distance the lowest triangle id wins. The filter and the leaves run in `backend`'s lanes.
    pub fn intersect(
        &self,
        p: &DacrtParams,
        backend: Backend,
        rays: &[Option<Ray>],
        out: &mut [Option<Hit>],
        stats: &mut TraversalStats,
    ) {
        assert_eq!(rays.len(), out.len());
        out.fill(None);
        let Some(groups) = self.fork(rays.len()) else {
            return self.run(p, backend, rays, self.whole(), Closest { out }, stats);
        };
        let mut second = vec![None; rays.len()];
        self.run_forked(p, backend, rays, groups, [Closest { out: &mut *out }, Closest { out: &mut second }], stats);
        for (o, s) in out.iter_mut().zip(second) {
            if let Some(s) = s
                && s.beats(*o)
            {
                *o = Some(s);
            }
        }
    }

    /// Whether anything blocks each of `rays` in `(tmin, tmax]`, written to `out`.
    pub fn occluded(
        &self,
        p: &DacrtParams,
        backend: Backend,
        rays: &[Option<Ray>],
        out: &mut [bool],
        stats: &mut TraversalStats,
    ) {
        assert_eq!(rays.len(), out.len());
        out.fill(false);
        let Some(groups) = self.fork(rays.len()) else {
            return self.run(p, backend, rays, self.whole(), Any { out }, stats);
        };
        let mut second = vec![false; rays.len()];
        self.run_forked(p, backend, rays, groups, [Any { out: &mut *out }, Any { out: &mut second }], stats);
        for (o, s) in out.iter_mut().zip(second) {
            *o |= s;
        }
    }

    /// The first blocker found along each of `rays` (not necessarily the nearest), for the shadow cache.
    pub fn occluders(
        &self,
        p: &DacrtParams,
        backend: Backend,
        rays: &[Option<Ray>],
        out: &mut [Option<u32>],
        stats: &mut TraversalStats,
    ) {
        assert_eq!(rays.len(), out.len());
        out.fill(None);
        let Some(groups) = self.fork(rays.len()) else {
            return self.run(p, backend, rays, self.whole(), Blocker { out }, stats);
        };
        let mut second = vec![None; rays.len()];
        self.run_forked(p, backend, rays, groups, [Blocker { out: &mut *out }, Blocker { out: &mut second }], stats);
        for (o, s) in out.iter_mut().zip(second) {
            *o = o.or(s);
        }
    }

    /// True when triangle `tri` blocks `ray`.
    pub fn blocks(&self, ray: &Ray, tri: u32) -> bool {
        ray.is_valid()
            && (tri as usize) < self.soup.len()
            && crate::triangle::RayShear::new(ray).intersect(self.soup.get(tri), ray.tmin, ray.tmax).is_some()
    }

    /// The groups to trace a set of `rays` rays against on two threads, when the current rayon pool has them
    /// and the set is small enough that dividing the triangles, not the rays' own work, is most of its cost.
    fn fork(&self, rays: usize) -> Option<[Group; 2]> {
        (rays < FORK_BELOW && rayon::current_num_threads() > 1).then_some(())?;
        let (s, [a, b]) = self.top.first()?.split?;
        Some([
            Group { tris: 0..s.mid, bounds: s.first, top: Some(a) },
            Group { tris: s.mid..self.refs.len(), bounds: s.second, top: Some(b) },
        ])
    }

    /// All triangles as one group.
    fn whole(&self) -> Group {
        Group { tris: 0..self.refs.len(), bounds: self.root, top: (!self.top.is_empty()).then_some(0) }
    }

    /// Traces `rays` against each of the two `groups` on its own thread, each answer into its own output;
    /// the callers merge the outputs.
    fn run_forked<A: Answer + Send>(
        &self,
        p: &DacrtParams,
        backend: Backend,
        rays: &[Option<Ray>],
        groups: [Group; 2],
        [first, second]: [A; 2],
        stats: &mut TraversalStats,
    ) {
        let (mut a, mut b) = (TraversalStats::default(), TraversalStats::default());
        rayon::join(
            || self.run(p, backend, rays, groups[0].clone(), first, &mut a),
            || self.run(p, backend, rays, groups[1].clone(), second, &mut b),
        );
        // Each ray was counted by both groups.
        b.rays = 0;
        b.packets = 0;
        *stats += a;
        *stats += b;
    }

    /// Traces `rays` against the triangles of `group`.
    fn run<A: Answer>(
        &self,
        p: &DacrtParams,
        backend: Backend,
        rays: &[Option<Ray>],
        group: Group,
        answer: A,
        stats: &mut TraversalStats,
    ) {
        let mut scratch = self.take_scratch();
        scratch.rays.clear();
        scratch.rays.extend(
            rays.iter().enumerate().filter_map(|(i, r)| r.filter(Ray::is_valid).map(|r| RayRecord::new(&r, i as u32))),
        );
        stats.rays += scratch.rays.len() as u64;
        stats.packets += scratch.rays.len() as u64;
        // The SAH rule reuses the setup's division and a part of the triangles is one of its nodes: both need
        // the references as the setup left them, which a call by another rule may have permuted.
        let reuses = p.split == SplitRule::Sah;
        if (reuses || group.tris.len() != self.refs.len()) && !scratch.keeps_setup_division {
            scratch.tris.copy_from_slice(&self.refs);
        }
        scratch.keeps_setup_division = reuses;
        if !scratch.rays.is_empty() && !group.tris.is_empty() {
            let mut walk = Walk {
                soup: &self.soup,
                top: if reuses { &self.top } else { &[] },
                params: *p,
                answer,
                flags: std::mem::take(&mut scratch.flags),
                backend,
                stats: TraversalStats::default(),
            };
            let Scratch { tris, rays, .. } = &mut scratch;
            walk.stats.box_tests += rays.len() as u64;
            let filter_box = filter::FilterBox::new(&group.bounds.bounds);
            let k = filter::filter(walk.backend, rays, &filter_box, &mut walk.flags);
            if k > 0 {
                walk.recurse(&mut rays[..k], &mut tris[group.tris], group.bounds, group.top, 0);
            }
            scratch.flags = walk.flags;
            *stats += walk.stats;
        }
        self.pool.lock().unwrap_or_else(|e| e.into_inner()).push(scratch);
    }

    fn take_scratch(&self) -> Scratch {
        let reused = self.pool.lock().unwrap_or_else(|e| e.into_inner()).pop();
        reused.unwrap_or_else(|| Scratch {
            tris: self.refs.clone(),
            rays: Vec::new(),
            flags: Vec::new(),
            keeps_setup_division: true,
        })
    }
}

impl std::fmt::Debug for Dacrt {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Dacrt").field("triangles", &self.refs.len()).finish()
    }
}
