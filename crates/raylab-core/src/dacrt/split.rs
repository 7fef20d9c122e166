//! Dividing a set of triangle references in two, in place (Mora 2011's primitive subdivision): on the longest
//! axis of the triangles' centres, either at the median centre (Stokes's thesis, section 3.3) or at the best of
//! [`BINS`] equal-width bins by the surface area heuristic (as Afra 2012 and BVH builders do). With SAH each
//! half's box and centre box are the unions of its bins, so a node costs two passes over its triangles.

use serde::{Deserialize, Serialize};

use crate::aabb::Aabb;

use super::partition::partition;
use super::records::{BoundsAcc, SetBounds, TriRecord};

/// How DACRT divides triangles.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SplitRule {
    /// The median centre on the longest axis (Stokes's thesis): halves of equal size.
    Median,
    /// The best of 16 bins on the longest axis by the surface area heuristic.
    #[default]
    Sah,
}

impl SplitRule {
    /// Both rules, in the order menus list them.
    pub const ALL: [SplitRule; 2] = [SplitRule::Sah, SplitRule::Median];

    /// The name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            SplitRule::Median => "median",
            SplitRule::Sah => "sah",
        }
    }
}

impl std::str::FromStr for SplitRule {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        SplitRule::ALL
            .into_iter()
            .find(|r| r.name() == s)
            .ok_or_else(|| format!("unknown DACRT split '{s}' (valid: sah, median)"))
    }
}

/// SAH bins per node.
const BINS: usize = 16;
/// Cost of filtering a ray against a box relative to a triangle test, in the SAH.
const C_FILTER: f32 = 1.0;

/// Where a set was divided: the first `mid` triangles form the first half.
#[derive(Clone, Copy, Debug)]
pub(super) struct Split {
    /// Triangles in the first half.
    pub mid: usize,
    /// The axis divided.
    pub axis: usize,
    /// Bounds of the first half.
    pub first: SetBounds,
    /// Bounds of the second half.
    pub second: SetBounds,
}

/// Divides `tris` (whose bounds are `b`) in place into two non-empty halves; `scratch` holds each triangle's
/// bin meanwhile. `None` when there are fewer than two triangles. Sets whose centres all coincide are cut in
/// the middle of the list.
pub(super) fn divide(tris: &mut [TriRecord], b: &SetBounds, rule: SplitRule, scratch: &mut Vec<u8>) -> Option<Split> {
    let n = tris.len();
    if n < 2 {
        return None;
    }
    let extent = b.centres.extent();
    let axis = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    let (lo, width) = (b.centres.min[axis], extent[axis]);
    let measurable = width > 0.0 && width.is_finite();
    if measurable
        && rule == SplitRule::Sah
        && let Some(s) = sah_partition(tris, b, axis, lo, width, scratch)
    {
        return Some(s);
    }
    // The median, or the middle of the list when all centres fall in one bin.
    let mid = n / 2;
    if measurable && rule == SplitRule::Median {
        tris.select_nth_unstable_by(mid, |a, b| a.centre2(axis).total_cmp(&b.centre2(axis)));
    }
    let (first, second) = tris.split_at(mid);
    Some(Split { mid, axis, first: SetBounds::of(first), second: SetBounds::of(second) })
}

#[inline(always)]
fn bin_of(c: f32, lo: f32, scale: f32) -> usize {
    (((c - lo) * scale) as usize).min(BINS - 1)
}

/// Bins `tris` on `axis`, picks the cheapest boundary by the SAH and partitions at it; the halves' bounds
/// are the unions of their bins. `None` when every triangle falls in one bin.
fn sah_partition(
    tris: &mut [TriRecord],
    b: &SetBounds,
    axis: usize,
    lo: f32,
    width: f32,
    bin_of_tri: &mut Vec<u8>,
) -> Option<Split> {
    let scale = BINS as f32 / width;
    let mut acc = [BoundsAcc::EMPTY; BINS];
    let mut counts = [0u32; BINS];
    bin_of_tri.clear();
    for t in tris.iter() {
        let k = bin_of(t.centre2(axis), lo, scale);
        acc[k] = acc[k].grow(t);
        counts[k] += 1;
        bin_of_tri.push(k as u8);
    }
    let bins = acc.map(BoundsAcc::bounds);
    let mut right_area = [0.0f32; BINS];
    let mut acc = bins[BINS - 1];
    let mut right_n = [0u32; BINS];
    right_n[BINS - 1] = counts[BINS - 1];
    right_area[BINS - 1] = acc.bounds.surface_area();
    for k in (1..BINS - 1).rev() {
        acc = acc.union(bins[k]);
        right_n[k] = right_n[k + 1] + counts[k];
        right_area[k] = acc.bounds.surface_area();
    }
    let area = b.bounds.surface_area().max(f32::MIN_POSITIVE);
    let (mut left, mut left_n) = (bins[0], 0u32);
    let mut best: Option<(usize, f32)> = None;
    for k in 0..BINS - 1 {
        if k > 0 {
            left = left.union(bins[k]);
        }
        left_n += counts[k];
        if left_n == 0 || right_n[k + 1] == 0 {
            continue;
        }
        let cost =
            C_FILTER + (left.bounds.surface_area() * left_n as f32 + right_area[k + 1] * right_n[k + 1] as f32) / area;
        if best.is_none_or(|(_, c)| cost < c) {
            best = Some((k, cost));
        }
    }
    let (bin, _) = best?;
    let mid = partition(tris, bin_of_tri, |k| k as usize <= bin);
    let union = |r: std::ops::Range<usize>| bins[r].iter().fold(EMPTY_SET, |a, &b| a.union(b));
    Some(Split { mid, axis, first: union(0..bin + 1), second: union(bin + 1..BINS) })
}

/// Bounds of no triangle.
const EMPTY_SET: SetBounds = SetBounds { bounds: Aabb::EMPTY, centres: Aabb::EMPTY };

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    fn tris(centres: &[f32]) -> Vec<TriRecord> {
        centres
            .iter()
            .enumerate()
            .map(|(i, &c)| {
                let p = Vec3::new(c, 0.0, 0.0);
                TriRecord::new([p - Vec3::splat(0.1), p + Vec3::new(0.1, 0.0, 0.1), p + Vec3::splat(0.1)], i as u32)
            })
            .collect()
    }

    #[test]
    fn both_rules_give_disjoint_non_empty_halves_with_tight_bounds() {
        let centres: Vec<f32> = (0..100).map(|i| ((i * 37) % 100) as f32 + if i < 10 { 500.0 } else { 0.0 }).collect();
        for rule in SplitRule::ALL {
            let mut t = tris(&centres);
            let b = SetBounds::of(&t);
            let s = divide(&mut t, &b, rule, &mut Vec::new()).unwrap();
            assert!(s.mid > 0 && s.mid < t.len(), "{rule:?}");
            assert_eq!(s.axis, 0);
            let split = t[..s.mid].iter().map(|r| r.centre2(0)).fold(f32::MIN, f32::max);
            assert!(t[s.mid..].iter().all(|r| r.centre2(0) >= split), "{rule:?}: halves overlap");
            assert_eq!(s.first.bounds, SetBounds::of(&t[..s.mid]).bounds);
            assert_eq!(s.second.bounds, SetBounds::of(&t[s.mid..]).bounds);
            let mut ids: Vec<u32> = t.iter().map(|r| r.id).collect();
            ids.sort_unstable();
            assert!(ids.iter().copied().eq(0..100), "a permutation");
        }
        let mut t = tris(&centres);
        let s = divide(&mut t, &SetBounds::of(&tris(&centres)), SplitRule::Median, &mut Vec::new()).unwrap();
        assert_eq!(s.mid, 50);
    }

    #[test]
    fn coincident_centres_are_cut_in_the_middle_and_single_triangles_are_not_divided() {
        let mut t = tris(&[3.0; 9]);
        let b = SetBounds::of(&t);
        let s = divide(&mut t, &b, SplitRule::Sah, &mut Vec::new()).unwrap();
        assert_eq!(s.mid, 4);
        let mut one = tris(&[1.0]);
        assert!(divide(&mut one, &SetBounds::of(&tris(&[1.0])), SplitRule::Sah, &mut Vec::new()).is_none());
    }

    #[test]
    fn names_parse() {
        for r in SplitRule::ALL {
            assert_eq!(r.name().parse::<SplitRule>(), Ok(r));
        }
        assert!("middle".parse::<SplitRule>().unwrap_err().contains("sah, median"));
    }
}
