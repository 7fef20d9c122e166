//! The pinhole camera and the exact ray convention shared with the Embree harness.

use glam::{DVec3, Vec3};
use serde::{Deserialize, Serialize};

use crate::ray::Ray;

/// A camera looking from `eye` toward `target`, with a vertical field of view, and a thin lens (aperture
/// radius and focus distance) for depth of field; an aperture of zero is a pinhole.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Camera {
    /// Eye position.
    pub eye: Vec3,
    /// Point looked at.
    pub target: Vec3,
    /// Up hint (need not be orthogonal to the view direction).
    pub up: Vec3,
    /// Vertical field of view in degrees.
    pub vfov_deg: f32,
    /// Lens radius; 0 gives a pinhole camera.
    pub aperture: f32,
    /// Distance to the plane in focus.
    pub focus_distance: f32,
}

/// A named viewpoint that a scene carries.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct View {
    /// Name shown in the UI and accepted by `--view`.
    pub name: String,
    /// The camera.
    pub camera: Camera,
}

/// Why a camera cannot produce rays.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CameraError {
    /// A coordinate or the field of view is NaN or infinite.
    NotFinite,
    /// `eye` equals `target`.
    NoViewDirection,
    /// `up` is parallel to the view direction (or zero).
    UpParallel,
    /// The field of view is outside (0, 180) degrees.
    Fov,
}

impl std::fmt::Display for CameraError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::NotFinite => "camera values must be finite",
            Self::NoViewDirection => "eye and target must differ",
            Self::UpParallel => "up must not be parallel to the view direction",
            Self::Fov => "field of view must be in (0, 180) degrees",
        })
    }
}

impl std::error::Error for CameraError {}

impl Camera {
    /// A pinhole camera.
    pub fn look_at(eye: Vec3, target: Vec3, up: Vec3, vfov_deg: f32) -> Self {
        let focus_distance = (target - eye).length().max(1e-3);
        Self { eye, target, up, vfov_deg, aperture: 0.0, focus_distance }
    }

    /// Checks that the camera defines a proper basis.
    pub fn validate(&self) -> Result<(), CameraError> {
        let vals = [self.eye, self.target, self.up];
        if vals.iter().any(|v| !v.is_finite()) || !self.vfov_deg.is_finite() {
            return Err(CameraError::NotFinite);
        }
        if !(self.vfov_deg > 0.0 && self.vfov_deg < 180.0) {
            return Err(CameraError::Fov);
        }
        let f = self.target.as_dvec3() - self.eye.as_dvec3();
        if f.length_squared() == 0.0 {
            return Err(CameraError::NoViewDirection);
        }
        if f.normalize().cross(self.up.as_dvec3()).length_squared() < 1e-18 {
            return Err(CameraError::UpParallel);
        }
        Ok(())
    }

    /// Precomputes the per-image constants of the ray convention for a `width x height` image.
    pub fn raster(&self, width: u32, height: u32) -> CameraRaster {
        let f = (self.target.as_dvec3() - self.eye.as_dvec3()).normalize();
        let r = f.cross(self.up.as_dvec3()).normalize();
        let u = r.cross(f);
        let s = (self.vfov_deg as f64 * std::f64::consts::PI / 360.0).tan();
        let aspect = width as f64 / height as f64;
        CameraRaster {
            eye: self.eye,
            f,
            r: r * (s * aspect),
            u: u * s,
            width: width as f64,
            height: height as f64,
            aperture: if self.aperture.is_finite() { self.aperture.max(0.0) } else { 0.0 },
            focus_distance: self.focus_distance,
        }
    }
}

/// A camera prepared for one image size.
///
/// The convention is the Embree harness's (`shared/tools/embree-bench/README.md`, "Camera"): all math in
/// double precision, pixel (0, 0) at the top left, `d = normalize(f + (2(x+0.5)/W - 1) s a r -
/// (2(y+0.5)/H - 1) s u)`, rounded to `f32` only at the end, so both tracers see bit-identical rays.
#[derive(Clone, Copy, Debug)]
pub struct CameraRaster {
    eye: Vec3,
    f: DVec3,
    r: DVec3,
    u: DVec3,
    width: f64,
    height: f64,
    aperture: f32,
    focus_distance: f32,
}

impl CameraRaster {
    /// A thin-lens ray through raster position `(px, py)` from the lens point `lens` (in the unit disc, scaled
    /// by the aperture radius): it passes through the point the pinhole ray meets on the plane in focus.
    /// With no aperture it is the pinhole ray.
    pub fn lens_ray(&self, px: f64, py: f64, lens: glam::Vec2) -> Ray {
        let pin = self.primary_at(px, py);
        if self.aperture <= 0.0 || self.focus_distance.is_nan() || self.focus_distance <= 0.0 {
            return pin;
        }
        let forward = self.f.as_vec3();
        let focus = pin.origin + pin.dir * (self.focus_distance / pin.dir.dot(forward));
        let (right, up) = (self.r.normalize().as_vec3(), self.u.normalize().as_vec3());
        let origin = self.eye + (right * lens.x + up * lens.y) * self.aperture;
        Ray::new(origin, (focus - origin).normalize())
    }

    /// The matrix that takes a world point `(x, y, z, 1)` to the clip space of a rasteriser (wgpu/WebGPU: x and
    /// y in [-1, 1] with y up, depth in [0, 1)), so that a rasterised pixel centre sees exactly what
    /// [`CameraRaster::primary`] sees there (the hybrid mode's G-buffer, seed 003). Column-major, as WGSL's
    /// `mat4x4<f32>` expects. Depth is `1 - near / distance along the view axis` (an infinite far plane).
    pub fn clip_matrix(&self, near: f32) -> [[f32; 4]; 4] {
        let (r, u, f) = (self.r / self.r.length_squared(), self.u / self.u.length_squared(), self.f);
        let e = self.eye.as_dvec3();
        // Rows: x = r'.(p - e), y = u'.(p - e), z = f.(p - e) - near, w = f.(p - e).
        let rows = [
            [r.x, r.y, r.z, -r.dot(e)],
            [u.x, u.y, u.z, -u.dot(e)],
            [f.x, f.y, f.z, -f.dot(e) - near as f64],
            [f.x, f.y, f.z, -f.dot(e)],
        ];
        std::array::from_fn(|col| std::array::from_fn(|row| rows[row][col] as f32))
    }

    /// The primary ray through the centre of pixel `(x, y)`.
    pub fn primary(&self, x: u32, y: u32) -> Ray {
        self.primary_at(x as f64 + 0.5, y as f64 + 0.5)
    }

    /// The primary ray through the continuous raster position `(px, py)` (pixel centres at `+0.5`).
    pub fn primary_at(&self, px: f64, py: f64) -> Ray {
        through(self.eye, self.column(px) - self.row(py))
    }

    /// The primary rays of the whole raster with their per-column and per-row terms computed once, for
    /// renderers that make a ray for every pixel.
    pub fn grid(&self) -> PrimaryGrid {
        let (w, h) = (self.width as u32, self.height as u32);
        PrimaryGrid {
            eye: self.eye,
            columns: (0..w).map(|x| self.column(x as f64 + 0.5)).collect(),
            rows: (0..h).map(|y| self.row(y as f64 + 0.5)).collect(),
        }
    }

    /// The direction's part that depends on the raster column, `f + sx r`: the harness sums it first.
    fn column(&self, px: f64) -> DVec3 {
        let sx = 2.0 * px / self.width - 1.0;
        self.f + sx * self.r
    }

    /// The direction's part that depends on the raster row, `sy u`, subtracted from the column's.
    fn row(&self, py: f64) -> DVec3 {
        let sy = 2.0 * py / self.height - 1.0;
        sy * self.u
    }
}

/// The ray from `eye` along the unnormalised double-precision direction `d`, rounded to `f32` at the end.
#[inline]
fn through(eye: Vec3, d: DVec3) -> Ray {
    Ray::new(eye, d.normalize().as_vec3())
}

/// Every pixel centre's primary ray of one [`CameraRaster`], bit for bit [`CameraRaster::primary`], with
/// the divisions and products that depend on only the column or only the row done once per frame rather
/// than once per pixel.
#[derive(Clone, Debug)]
pub struct PrimaryGrid {
    eye: Vec3,
    columns: Vec<DVec3>,
    rows: Vec<DVec3>,
}

impl PrimaryGrid {
    /// The primary ray through the centre of pixel `(x, y)`, which must lie in the raster.
    #[inline]
    pub fn primary(&self, x: u32, y: u32) -> Ray {
        through(self.eye, self.columns[x as usize] - self.rows[y as usize])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_clip_matrix_puts_points_on_the_pixels_whose_rays_see_them() {
        let cam = Camera {
            eye: Vec3::new(1.0, 2.0, 3.0),
            target: Vec3::new(-4.0, 0.5, 9.0),
            up: Vec3::Y,
            vfov_deg: 55.0,
            aperture: 0.0,
            focus_distance: 1.0,
        };
        let (w, h) = (64u32, 48u32);
        let raster = cam.raster(w, h);
        let m = raster.clip_matrix(0.01);
        for (x, y, t) in [(0, 0, 2.0), (63, 47, 7.5), (20, 31, 30.0), (32, 24, 0.5)] {
            let p = raster.primary(x, y).at(t);
            let clip: [f32; 4] = std::array::from_fn(|row| (0..4).map(|c| m[c][row] * [p.x, p.y, p.z, 1.0][c]).sum());
            let (nx, ny, nz) = (clip[0] / clip[3], clip[1] / clip[3], clip[2] / clip[3]);
            // NDC to framebuffer: y down, pixel centres at +0.5.
            let (fx, fy) = ((nx + 1.0) * 0.5 * w as f32, (1.0 - ny) * 0.5 * h as f32);
            assert!((fx - (x as f32 + 0.5)).abs() < 1e-3 && (fy - (y as f32 + 0.5)).abs() < 1e-3, "{fx} {fy}");
            assert!((0.0..1.0).contains(&nz), "depth {nz}");
        }
    }

    #[test]
    fn the_grid_gives_every_pixel_exactly_its_primary_ray() {
        let cam = Camera {
            eye: Vec3::new(-12.5, 2.5, 0.1),
            target: Vec3::new(10.0, 5.5, -3.0),
            up: Vec3::new(0.1, 1.0, 0.0),
            vfov_deg: 65.0,
            aperture: 0.0,
            focus_distance: 1.0,
        };
        for (w, h) in [(1, 1), (7, 3), (64, 48), (1, 1000)] {
            let raster = cam.raster(w, h);
            let grid = raster.grid();
            for y in 0..h {
                for x in 0..w {
                    let (a, b) = (grid.primary(x, y), raster.primary(x, y));
                    assert_eq!(
                        (a.origin, a.dir, a.tmin, a.tmax),
                        (b.origin, b.dir, b.tmin, b.tmax),
                        "{w}x{h} ({x}, {y})"
                    );
                }
            }
        }
    }

    #[test]
    fn centre_ray_looks_at_target() {
        let cam = Camera::look_at(Vec3::ZERO, Vec3::new(0.0, 0.0, -5.0), Vec3::Y, 60.0);
        let r = cam.raster(2, 2).primary_at(1.0, 1.0);
        assert!((r.dir - Vec3::new(0.0, 0.0, -1.0)).length() < 1e-7);
        // Top-left pixel looks up and to the left.
        let tl = cam.raster(2, 2).primary(0, 0);
        assert!(tl.dir.x < 0.0 && tl.dir.y > 0.0);
    }

    #[test]
    fn validate_rejects_bad_cameras() {
        let ok = Camera::look_at(Vec3::ZERO, Vec3::X, Vec3::Y, 60.0);
        assert_eq!(ok.validate(), Ok(()));
        assert_eq!(Camera { vfov_deg: 180.0, ..ok }.validate(), Err(CameraError::Fov));
        assert_eq!(Camera { target: Vec3::ZERO, ..ok }.validate(), Err(CameraError::NoViewDirection));
        assert_eq!(Camera { up: Vec3::X, ..ok }.validate(), Err(CameraError::UpParallel));
        assert_eq!(Camera { eye: Vec3::NAN, ..ok }.validate(), Err(CameraError::NotFinite));
    }
}
