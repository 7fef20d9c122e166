//! Fly-through camera control: WASD to move, Q/E (or Ctrl/Space) down and up, mouse look while the right
//! button is held, the wheel for speed, Shift for fast. An untouched camera stays bit-for-bit the scene's
//! view, so the viewer's first frame equals `raylab-bench render` of the same view.

use glam::{Quat, Vec3};
use raylab_core::aabb::Aabb;
use raylab_core::scene::Camera;

/// Movement keys currently held.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MoveKeys {
    /// W.
    pub forward: bool,
    /// S.
    pub back: bool,
    /// A.
    pub left: bool,
    /// D.
    pub right: bool,
    /// E or Space.
    pub up: bool,
    /// Q or Ctrl.
    pub down: bool,
    /// Shift: move faster.
    pub fast: bool,
}

impl MoveKeys {
    /// True when any movement key is held.
    pub fn any(&self) -> bool {
        self.forward || self.back || self.left || self.right || self.up || self.down
    }
}

/// Radians of turn per pixel of mouse motion.
const LOOK_PER_PIXEL: f32 = 0.003;
/// Closest the view direction may come to straight up or down, in radians.
const POLE_MARGIN: f32 = 0.02;
/// Speed factor while Shift is held.
const FAST: f32 = 4.0;

/// A camera that flies.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlyCamera {
    /// The camera as traced.
    pub camera: Camera,
    /// Speed in scene units per second.
    pub speed: f32,
}

impl FlyCamera {
    /// Starts at `camera`, with a speed that crosses `bounds` in about ten seconds.
    pub fn new(camera: Camera, bounds: &Aabb) -> Self {
        let span = if bounds.is_empty() { 1.0 } else { bounds.diagonal().max(1e-3) };
        Self { camera, speed: span / 10.0 }
    }

    /// The world's up direction for this camera: its up hint.
    fn world_up(&self) -> Vec3 {
        self.camera.up.normalize_or(Vec3::Y)
    }

    /// Unit view direction.
    pub fn forward(&self) -> Vec3 {
        (self.camera.target - self.camera.eye).normalize_or(Vec3::NEG_Z)
    }

    /// Moves for `dt` seconds with `keys` held; returns true when the camera moved.
    pub fn step(&mut self, keys: &MoveKeys, dt: f32) -> bool {
        if !keys.any() || dt.is_nan() || dt <= 0.0 {
            return false;
        }
        let f = self.forward();
        let up = self.world_up();
        let right = f.cross(up).normalize_or_zero();
        let axis = |p: bool, n: bool| (p as i32 - n as i32) as f32;
        let dir =
            f * axis(keys.forward, keys.back) + right * axis(keys.right, keys.left) + up * axis(keys.up, keys.down);
        let len = dir.length();
        if len == 0.0 {
            return false;
        }
        let speed = self.speed * if keys.fast { FAST } else { 1.0 };
        self.translate(dir / len * speed * dt.min(0.25))
    }

    /// Moves eye and target together by `d`; returns true when the camera changed.
    fn translate(&mut self, d: Vec3) -> bool {
        let moved = Camera { eye: self.camera.eye + d, target: self.camera.target + d, ..self.camera };
        self.accept(moved)
    }

    /// Turns by a mouse motion of `(dx, dy)` pixels (right and down positive); returns true when it turned.
    pub fn look(&mut self, dx: f32, dy: f32) -> bool {
        if (dx == 0.0 && dy == 0.0) || !dx.is_finite() || !dy.is_finite() {
            return false;
        }
        let up = self.world_up();
        let f = self.forward();
        let right = f.cross(up).normalize_or_zero();
        if right == Vec3::ZERO {
            return false;
        }
        let yawed = Quat::from_axis_angle(up, -dx * LOOK_PER_PIXEL) * f;
        // Keep the pitch away from the poles, where the view basis would flip.
        let polar = yawed.dot(up).clamp(-1.0, 1.0).acos();
        let pitch = (-dy * LOOK_PER_PIXEL).clamp(polar - std::f32::consts::PI + POLE_MARGIN, polar - POLE_MARGIN);
        let right = yawed.cross(up).normalize_or(right);
        let dir = Quat::from_axis_angle(right, pitch) * yawed;
        let dist = (self.camera.target - self.camera.eye).length().max(1e-3);
        let turned = Camera { target: self.camera.eye + dir * dist, ..self.camera };
        self.accept(turned)
    }

    /// Scales the speed by a wheel motion of `lines` (up is faster).
    pub fn wheel(&mut self, lines: f32) {
        if lines.is_finite() {
            self.speed = (self.speed * 1.2f32.powf(lines)).clamp(1e-4, 1e7);
        }
    }

    /// Places the camera outside `bounds`, looking at its centre along the current direction, so the whole
    /// scene is in view.
    pub fn frame(&mut self, bounds: &Aabb) -> bool {
        if bounds.is_empty() {
            return false;
        }
        let c = bounds.center();
        let radius = 0.5 * bounds.diagonal().max(1e-3);
        let half = (0.5 * self.camera.vfov_deg.to_radians()).max(1e-3);
        let dist = radius / half.sin();
        let framed = Camera { eye: c - self.forward() * dist, target: c, ..self.camera };
        self.speed = radius / 5.0;
        self.accept(framed)
    }

    /// Takes `c` if it is a valid camera (finite, with a view direction not parallel to up).
    fn accept(&mut self, c: Camera) -> bool {
        if c.validate().is_ok() && c != self.camera {
            self.camera = c;
            true
        } else {
            false
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam() -> FlyCamera {
        let c = Camera::look_at(Vec3::new(0.0, 1.0, 5.0), Vec3::new(0.0, 1.0, 0.0), Vec3::Y, 60.0);
        FlyCamera::new(c, &Aabb::new(Vec3::splat(-5.0), Vec3::splat(5.0)))
    }

    #[test]
    fn no_input_keeps_the_camera_exactly() {
        let mut f = cam();
        let before = f.camera;
        assert!(!f.step(&MoveKeys::default(), 0.1));
        assert!(!f.look(0.0, 0.0));
        assert_eq!(f.camera, before);
    }

    #[test]
    fn moves_along_view_and_turns() {
        let mut f = cam();
        let keys = MoveKeys { forward: true, ..Default::default() };
        assert!(f.step(&keys, 0.1));
        assert!(f.camera.eye.z < 5.0 && (f.camera.eye.x).abs() < 1e-6);
        let strafe = MoveKeys { right: true, ..Default::default() };
        let x0 = f.camera.eye.x;
        f.step(&strafe, 0.1);
        assert!(f.camera.eye.x > x0, "D moves right");
        let d0 = f.forward();
        assert!(f.look(100.0, 0.0));
        assert!(f.forward().x > d0.x, "mouse right turns right");
    }

    #[test]
    fn pitch_never_reaches_the_pole() {
        let mut f = cam();
        for _ in 0..100 {
            f.look(0.0, -1000.0);
        }
        assert!(f.forward().dot(Vec3::Y) < 1.0 - 1e-5);
        assert!(f.camera.validate().is_ok());
    }

    #[test]
    fn framing_puts_the_box_in_view() {
        let mut f = cam();
        let b = Aabb::new(Vec3::new(100.0, 0.0, 0.0), Vec3::new(110.0, 10.0, 10.0));
        assert!(f.frame(&b));
        assert_eq!(f.camera.target, b.center());
        assert!((f.camera.eye - b.center()).length() > 0.5 * b.diagonal());
        assert!(!f.frame(&Aabb::EMPTY));
    }

    #[test]
    fn bad_input_is_ignored() {
        let mut f = cam();
        let before = f.camera;
        assert!(!f.look(f32::NAN, 1.0));
        let keys = MoveKeys { forward: true, ..Default::default() };
        assert!(!f.step(&keys, f32::NAN));
        f.wheel(f32::INFINITY);
        assert_eq!(f.camera, before);
        assert!(f.speed.is_finite());
    }
}
