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
