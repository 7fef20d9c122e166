//! Rays and hit records.

use glam::Vec3;

/// A ray `origin + t * dir` for `t` in `[tmin, tmax]`.
///
/// The direction need not be normalised; distances are in units of `|dir|`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Start point.
    pub origin: Vec3,
    /// Direction.
    pub dir: Vec3,
    /// Smallest accepted hit distance.
    pub tmin: f32,
    /// Largest accepted hit distance (may be `+inf`).
    pub tmax: f32,
}

impl Ray {
    /// A ray from `origin` along `dir` over `[0, +inf]`.
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        Self { origin, dir, tmin: 0.0, tmax: f32::INFINITY }
    }

    /// A ray over `[tmin, tmax]`.
    pub fn segment(origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Self {
        Self { origin, dir, tmin, tmax }
    }

    /// The point at distance `t`.
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + self.dir * t
    }

    /// The component-wise inverse direction; a zero component gives an infinity of the same sign, which the
    /// slab and split-plane tests rely on (thesis Listing 2.2 precomputes the same).
    pub fn inv_dir(&self) -> Vec3 {
        Vec3::ONE / self.dir
    }

    /// True when every component is finite and the direction is not the zero vector.
    pub fn is_valid(&self) -> bool {
        // `&`, not `&&`: one branch-free test, since packets check every lane.
        self.origin.is_finite_mask().all()
            & self.dir.is_finite_mask().all()
            & (self.dir.abs().max_element() > 0.0)
            & !self.tmin.is_nan()
            & !self.tmax.is_nan()
    }
}

/// The closest intersection found along a ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Distance along the ray.
    pub t: f32,
    /// Index of the triangle in the scene.
    pub tri: u32,
    /// Barycentric weight of vertex 1.
    pub u: f32,
    /// Barycentric weight of vertex 2.
    pub v: f32,
}

impl Hit {
    /// True when this hit is to replace `best` as a ray's closest hit: it is nearer, or as near with a lower
    /// triangle id. That is the brute-force reference's rule (it keeps the first of equal hits in id order),
    /// and every closest-hit kernel applies it, so that two triangles met at the same distance (a shared
    /// edge, coincident faces) give every method and visiting order the same answer.
    #[inline(always)]
    pub fn beats(&self, best: Option<Hit>) -> bool {
        best.is_none_or(|b| self.t < b.t || (self.t == b.t && self.tri < b.tri))
    }
}

/// Relative slack on a ray's best hit when a closest-hit walk decides what could still hold a closer one:
/// kd-tree cells and BVH boxes that start up to 1e-4 of the distance past the best hit are still entered
/// (triangles there are tested against the best hit itself, so a farther one never wins).
///
/// The watertight test's distance to a sliver triangle that a ray only grazes can lie before every cell
/// and box that holds the triangle. On Sponza at 1024x1024 the ray of pixel (801, 213) meets two slivers
/// that share an edge: the brute-force reference keeps triangle 9894 at 7.568455, which lies in a kd-tree
/// cell starting at 7.568793, while triangle 10154 is hit at 7.568769 in the cell before it. A walk that
/// skipped everything starting beyond its best hit kept 10154 (mono and the packets did), one that happened
/// to reach 9894's cell first kept 9894 (the frustum methods and the BVHs did). With the slack every method
/// reaches both and keeps the closer, as the reference does. It costs a visit only where a hit lies that close to a
/// boundary, and nothing for any-hit walks, which have no best hit.
pub const HIT_SLACK: f32 = 1e-4;

/// The distance up to which cells may hold a closer hit than `t` ([`HIT_SLACK`]); infinities stay.
#[inline(always)]
pub fn hit_reach(t: f32) -> f32 {
    t.max(t * (1.0 + HIT_SLACK))
}
