//! The bookkeeping of Edge Width Soft Shadows (Tsakok 2008, chapter 5, Listing 5.1, Equation 5.1).
//!
//! A shadow ray walks from the shaded point to the light and toggles between "outside" and "inside" at each
//! surface crossing, assuming occluders are closed. Each entry paired with the following exit gives an edge
//! width, the length of the chord through the occluder; the widest chord `w` over the light's `R` gives the
//! occlusion `clamp(w / R, 0, 1)`. An entry left unpaired at the end (an open surface such as a single quad)
//! means full occlusion, so broken geometry falls back to a hard shadow.
//!
//! The traversal feeds crossings leaf by leaf: a leaf's crossings arrive in any order, so they wait in a small
//! pending list and are committed in distance order once no later leaf can hold a nearer one. The kd-tree
//! kernel and the brute-force reference share this type, so they agree by construction on everything but
//! which crossings they find.

use crate::triangle::TriangleSoup;

/// One surface crossing of a shadow ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Crossing {
    /// Distance along the ray.
    pub t: f32,
    /// Triangle id.
    pub tri: u32,
    /// True when the ray meets the triangle's front (`(v1 - v0) x (v2 - v0)` points against the ray).
    pub front: bool,
}

/// Relative distance under which crossings count as one place along the ray: a ray through an edge shared by
/// two triangles of one surface hits both at the same distance and must toggle once, and where two solids
/// touch, the exit from one and the entry into the other coincide.
const SAME_PLACE: f32 = 1e-6;

fn tolerance(t: f32) -> f32 {
    SAME_PLACE * t.abs().max(1.0)
}

/// The state of one edge-width shadow ray; reuse it across rays with [`EdgeWidth::begin`].
#[derive(Clone, Debug, Default)]
pub struct EdgeWidth {
    radius: f32,
    leak_fix: bool,
    pending: Vec<Crossing>,
    seen: Vec<u32>,
    open: Option<Crossing>,
    widest: f32,
    crossed: bool,
}

impl EdgeWidth {
    /// A state for edge width `radius` (world units) and the light-leak fix switch.
    pub fn new(radius: f32, leak_fix: bool) -> Self {
        Self { radius, leak_fix, ..Self::default() }
    }

    /// The edge width and light-leak switch this state was made for.
    pub fn settings(&self) -> (f32, bool) {
        (self.radius, self.leak_fix)
    }

    /// Resets the state for a new ray, keeping the buffers.
    pub fn begin(&mut self) {
        self.pending.clear();
        self.seen.clear();
        self.open = None;
        self.widest = 0.0;
        self.crossed = false;
    }

    /// True when triangle `tri` already gave a crossing of this ray (triangles referenced by several leaves
    /// are counted once).
    pub fn seen(&self, tri: u32) -> bool {
        self.seen.contains(&tri)
    }

    /// True when crossings wait to be committed ([`EdgeWidth::commit`] has work to do).
    #[inline]
    pub fn has_pending(&self) -> bool {
        !self.pending.is_empty()
    }

    /// Records a crossing found in the current leaf.
    pub fn add(&mut self, c: Crossing) {
        self.seen.push(c.tri);
        // Pending crossings stay sorted farthest first (by distance, then triangle id), so that groups come
        // off the end; the list holds a handful at most, so a linear insertion beats sorting at each commit.
        let at = self.pending.iter().position(|p| farther(c, *p)).unwrap_or(self.pending.len());
        self.pending.insert(at, c);
    }

    /// Commits, in distance order, the pending crossings that no later leaf can join: those well before `t`
    /// (the far end of the leaf just visited; `f32::INFINITY` at the end of the ray). Returns true once the
    /// point is known to be fully occluded, so the traversal can stop.
    ///
    /// Crossings at one place (within `SAME_PLACE`) form a group, handled the same whatever order they were
    /// found in: same-facing members are one crossing; a group with both facings is an exit and an entry
    /// (inside) or an entry and an exit (outside, a graze).
    #[inline]
    pub fn commit(&mut self, t: f32, tris: &TriangleSoup) -> bool {
        // Most leaves leave nothing pending; the call is then a check.
        if !self.pending.is_empty() {
            self.commit_pending(t, tris);
        }
        self.done()
    }

    /// [`EdgeWidth::commit`]'s work on a non-empty pending list.
    fn commit_pending(&mut self, t: f32, tris: &TriangleSoup) {
        while let Some(&first) = self.pending.last() {
            let end = first.t + tolerance(first.t);
            if t.is_finite() && end + tolerance(end) > t {
                break;
            }
            // Most crossings are alone at their place: one toggle, without the grouping below.
            let n = self.pending.len();
            if n == 1 || self.pending[n - 2].t > end {
                self.pending.pop();
                self.toggle(first, tris);
                continue;
            }
            let (mut front, mut back): (Option<Crossing>, Option<Crossing>) = (None, None);
            while let Some(&c) = self.pending.last() {
                if c.t > end {
                    break;
                }
                self.pending.pop();
                let slot = if c.front { &mut front } else { &mut back };
                if slot.is_none_or(|s| (c.t, c.tri) < (s.t, s.tri)) {
                    *slot = Some(c);
                }
            }
            match (front, back) {
                (Some(f), Some(b)) if self.open.is_some() => {
                    self.toggle(b, tris);
                    self.toggle(f, tris);
                }
                (Some(f), Some(b)) => {
                    self.toggle(f, tris);
                    self.toggle(Crossing { t: b.t.max(f.t), ..b }, tris);
                }
                (Some(c), None) | (None, Some(c)) => self.toggle(c, tris),
                (None, None) => {}
            }
        }
    }

    /// Enters or leaves an occluder at `c`, measuring the chord on leaving.
    fn toggle(&mut self, c: Crossing, tris: &TriangleSoup) {
        self.crossed = true;
        match self.open.take() {
            None => self.open = Some(c),
            Some(entry) => {
                let width = if self.leak_fix && !share_vertex(tris.get(entry.tri), tris.get(c.tri)) {
                    f32::INFINITY
                } else {
                    c.t - entry.t
                };
                self.widest = self.widest.max(width);
            }
        }
    }

    /// True when a committed chord already reaches the radius (with a radius of zero, any crossing does).
    fn done(&self) -> bool {
        self.crossed && self.widest >= self.radius
    }

    /// The occlusion of the finished ray, in `[0, 1]` (Equation 5.1): 0 with no crossing, 1 when an entry
    /// stays unpaired or a chord reaches `R`, else the widest chord over `R`.
    pub fn occlusion(&self) -> f32 {
        if !self.crossed {
            0.0
        } else if self.open.is_some() || self.widest >= self.radius {
            1.0
        } else {
            self.widest / self.radius
        }
    }
}

/// True when crossing `a` sorts before `b` in the pending list: farther, or as far with a larger triangle id.
fn farther(a: Crossing, b: Crossing) -> bool {
    b.t.total_cmp(&a.t).then(b.tri.cmp(&a.tri)).is_lt()
}

/// True when two triangles have a corner in common (exactly the same position).
fn share_vertex(a: &[glam::Vec3; 3], b: &[glam::Vec3; 3]) -> bool {
    a.iter().any(|p| b.contains(p))
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::scene::{SceneBuilder, Triangle};

    /// Four triangles: 0 and 1 share vertex 1, 2 and 3 share nothing with 0.
    fn soup() -> TriangleSoup {
        let mut b = SceneBuilder::new();
        b.positions = (0..12).map(|i| Vec3::new(i as f32, (i % 3) as f32, (i % 2) as f32)).collect();
        b.positions.push(Vec3::new(0.5, 7.0, 1.0));
        b.triangles = vec![
            Triangle { v: [0, 1, 2], material: 0 },
            Triangle { v: [1, 4, 12], material: 0 },
            Triangle { v: [6, 7, 8], material: 0 },
            Triangle { v: [9, 10, 11], material: 0 },
        ];
        TriangleSoup::from_scene(&b.build())
    }

    /// One leaf's crossings `(t, triangle, front)` and its far end.
    type Leaf<'a> = (&'a [(f32, u32, bool)], f32);

    fn run(radius: f32, leak_fix: bool, leaves: &[Leaf]) -> f32 {
        let tris = soup();
        let mut ew = EdgeWidth::new(radius, leak_fix);
        ew.begin();
        for (crossings, end) in leaves {
            for &(t, tri, front) in *crossings {
                ew.add(Crossing { t, tri, front });
            }
            if ew.commit(*end, &tris) {
                break;
            }
        }
        ew.commit(f32::INFINITY, &tris);
        ew.occlusion()
    }

    #[test]
    fn no_crossing_is_lit() {
        assert_eq!(run(1.0, false, &[(&[], 5.0)]), 0.0);
    }

    #[test]
    fn a_chord_shorter_than_r_is_penumbra() {
        assert_eq!(run(1.0, false, &[(&[(2.25, 1, false), (2.0, 0, true)], 5.0)]), 0.25);
    }

    #[test]
    fn pairs_carry_across_leaves_and_the_widest_wins() {
        // Entry in the first leaf, exit in the second; a second, narrower chord later.
        let leaves: &[Leaf] =
            &[(&[(1.0, 0, true)], 1.5), (&[(1.5, 1, false), (3.0, 2, true)], 4.0), (&[(3.1, 3, false)], 9.0)];
        assert_eq!(run(2.0, false, leaves), 0.25);
    }

    #[test]
    fn an_unpaired_entry_is_full_occlusion() {
        assert_eq!(run(10.0, false, &[(&[(1.0, 0, true)], 5.0)]), 1.0);
    }

    #[test]
    fn a_wide_chord_is_umbra_and_stops_early() {
        let tris = soup();
        let mut ew = EdgeWidth::new(0.5, false);
        ew.begin();
        ew.add(Crossing { t: 1.0, tri: 0, front: true });
        ew.add(Crossing { t: 2.0, tri: 1, front: false });
        assert!(ew.commit(3.0, &tris));
        assert_eq!(ew.occlusion(), 1.0);
    }

    #[test]
    fn crossings_past_the_leaf_wait_for_later_leaves() {
        // The exit at 4 is found in the first leaf but lies beyond it; the entry at 3 comes from the next leaf.
        let leaves: &[Leaf] = &[(&[(4.0, 1, false)], 2.0), (&[(3.0, 0, true)], 6.0)];
        assert_eq!(run(2.0, false, leaves), 0.5);
    }

    #[test]
    fn coincident_same_facing_crossings_toggle_once() {
        // A ray through an edge shared by two front faces, then one exit.
        let leaves: &[Leaf] = &[(&[(1.0, 0, true), (1.0, 2, true), (1.5, 1, false)], 5.0)];
        assert_eq!(run(1.0, false, leaves), 0.5);
        // A grazing ray at a silhouette meets a front and a back face at once: a chord of width zero.
        let leaves: &[Leaf] = &[(&[(1.0, 0, true), (1.0, 1, false)], 5.0)];
        assert_eq!(run(1.0, false, leaves), 0.0);
    }

    #[test]
    fn touching_solids_exit_and_enter_at_one_place_in_any_order() {
        // Inside a solid from 1.0; at 2.0 its exit face touches the next solid's entry face (two coincident
        // back faces from a shared edge, one front face); that solid is left at 2.5.
        for order in [[0, 1, 2], [1, 2, 0], [2, 0, 1]] {
            let group = [(2.0, 1, false), (2.0 + 1e-6, 3, false), (2.0, 2, true)];
            let g: Vec<_> = order.iter().map(|&k| group[k]).collect();
            let leaves: &[Leaf] = &[(&[(1.0, 0, true)], 1.5), (&g, 2.2), (&[(2.5, 0, false)], 5.0)];
            assert!((run(2.0, false, leaves) - 0.5).abs() < 1e-6, "order {order:?}");
        }
    }

    #[test]
    fn the_leak_fix_needs_a_shared_vertex() {
        let shared: &[Leaf] = &[(&[(1.0, 0, true), (1.1, 1, false)], 5.0)];
        assert!((run(1.0, true, shared) - 0.1).abs() < 1e-6);
        let apart: &[Leaf] = &[(&[(1.0, 0, true), (1.1, 3, false)], 5.0)];
        assert_eq!(run(1.0, true, apart), 1.0);
        assert!((run(1.0, false, apart) - 0.1).abs() < 1e-6);
    }

    #[test]
    fn radius_zero_is_a_hard_shadow() {
        let leaves: &[Leaf] = &[(&[(1.0, 0, true), (1.0 + 1e-3, 1, false)], 5.0)];
        assert_eq!(run(0.0, false, leaves), 1.0);
        assert_eq!(run(0.0, false, &[(&[], 5.0)]), 0.0);
    }
}
