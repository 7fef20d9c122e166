//! Textures in linear RGB with bilinear filtering (thesis 4.2.1: "texture lookups for diffuse and normal maps
//! using bilinear filtering").

use glam::{Vec2, Vec3};
use serde::{Deserialize, Serialize};

/// What happens to texture coordinates outside `[0, 1]`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum WrapMode {
    /// The texture tiles (OBJ and glTF's default).
    #[default]
    Repeat,
    /// Coordinates stick to the edge texels.
    Clamp,
    /// The texture tiles, every other copy mirrored.
    Mirror,
}

/// A texture in linear RGB, row-major from the top-left texel; `v = 0` is the bottom row, as in OBJ and
/// OpenGL.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// Name or path, for messages.
    pub name: String,
    /// Width in texels (at least 1).
    pub width: u32,
    /// Height in texels (at least 1).
    pub height: u32,
    /// `width * height` linear RGB texels.
    pub texels: Vec<Vec3>,
    /// Addressing outside `[0, 1]`, both axes.
    pub wrap: WrapMode,
}

impl Texture {
    /// A texture from its texels; `None` when the size is zero or does not match.
    pub fn new(name: &str, width: u32, height: u32, texels: Vec<Vec3>) -> Option<Self> {
        (width > 0 && height > 0 && texels.len() == width as usize * height as usize).then(|| Self {
            name: name.into(),
            width,
            height,
            texels,
            wrap: WrapMode::Repeat,
        })
    }

    /// An 8x8 magenta and black checker, the visible stand-in for a texture that could not be read.
    pub fn placeholder(name: &str) -> Self {
        let texels =
            (0..64).map(|i| if (i % 8 + i / 8) % 2 == 0 { Vec3::new(1.0, 0.0, 1.0) } else { Vec3::ZERO }).collect();
        Self { name: name.into(), width: 8, height: 8, texels, wrap: WrapMode::Repeat }
    }

    /// The texel at integer coordinates (column, row from the top), wrapped.
    fn texel(&self, x: i64, y: i64) -> Vec3 {
        let x = wrap(x, self.width, self.wrap);
        let y = wrap(y, self.height, self.wrap);
        self.texels[y * self.width as usize + x]
    }

    /// Bilinearly filtered colour at `uv`; texel centres sit at half-integer coordinates. Non-finite
    /// coordinates read texel (0, 0).
    pub fn sample(&self, uv: Vec2) -> Vec3 {
        let uv = if uv.is_finite() { uv } else { Vec2::ZERO };
        // Keep the coordinate small before converting, so huge UVs neither overflow nor lose all precision.
        let x = (uv.x as f64).rem_euclid(2.0) * self.width as f64 - 0.5;
        let y = (1.0 - (uv.y as f64).rem_euclid(2.0)) * self.height as f64 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = ((x - x0) as f32, (y - y0) as f32);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let top = self.texel(x0, y0).lerp(self.texel(x0 + 1, y0), fx);
        let bottom = self.texel(x0, y0 + 1).lerp(self.texel(x0 + 1, y0 + 1), fx);
        top.lerp(bottom, fy)
    }
}

/// A texel index in `0..n` for any integer coordinate.
fn wrap(i: i64, n: u32, mode: WrapMode) -> usize {
    let n = n as i64;
    (match mode {
        WrapMode::Repeat => i.rem_euclid(n),
        WrapMode::Clamp => i.clamp(0, n - 1),
        WrapMode::Mirror => {
            let m = i.rem_euclid(2 * n);
            if m < n { m } else { 2 * n - 1 - m }
        }
    }) as usize
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp() -> Texture {
        // 2x1: black on the left, white on the right.
        Texture::new("ramp", 2, 1, vec![Vec3::ZERO, Vec3::ONE]).unwrap()
    }

    #[test]
    fn texel_centres_return_texels_and_midpoints_blend() {
        let mut t = ramp();
        t.wrap = WrapMode::Clamp;
        assert_eq!(t.sample(Vec2::new(0.25, 0.5)), Vec3::ZERO);
        assert_eq!(t.sample(Vec2::new(0.75, 0.5)), Vec3::ONE);
        assert_eq!(t.sample(Vec2::new(0.5, 0.5)), Vec3::splat(0.5));
        assert_eq!(t.sample(Vec2::new(0.0, 0.5)), Vec3::ZERO, "clamped at the edge");
    }

    #[test]
    fn wrap_modes_differ_at_the_border() {
        let mut t = ramp();
        // At u = 0 repeat blends the right edge (white) with the left texel.
        assert_eq!(t.sample(Vec2::new(0.0, 0.5)), Vec3::splat(0.5));
        assert_eq!(t.sample(Vec2::new(1.25, 0.5)), Vec3::ZERO, "repeats every unit");
        t.wrap = WrapMode::Mirror;
        assert_eq!(t.sample(Vec2::new(0.0, 0.5)), Vec3::ZERO);
        assert_eq!(t.sample(Vec2::new(1.25, 0.5)), Vec3::ONE, "the second copy is mirrored");
    }

    #[test]
    fn rows_run_from_the_top_with_v_up() {
        let t = Texture::new("v", 1, 2, vec![Vec3::X, Vec3::Y]).unwrap();
        assert_eq!(t.sample(Vec2::new(0.5, 0.75)), Vec3::X, "v near 1 reads the top row");
        assert_eq!(t.sample(Vec2::new(0.5, 0.25)), Vec3::Y);
    }

    #[test]
    fn bad_input_is_safe() {
        assert!(Texture::new("empty", 0, 4, vec![]).is_none());
        assert!(Texture::new("short", 2, 2, vec![Vec3::ONE]).is_none());
        let t = ramp();
        for uv in [Vec2::new(f32::NAN, 0.0), Vec2::new(f32::INFINITY, 1.0), Vec2::new(-1e30, 1e30)] {
            assert!(t.sample(uv).is_finite());
        }
        let p = Texture::placeholder("missing.png");
        assert_eq!((p.width, p.height), (8, 8));
    }
}
