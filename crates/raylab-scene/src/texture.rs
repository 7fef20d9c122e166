//! Reading textures with the `image` crate: PNG, JPEG, TGA and BMP; colour maps converted from sRGB to
//! linear, data maps (normal and bump maps) kept linear; size limits that refuse an image rather than abort;
//! and the visible checker placeholder, with a warning naming the file, for anything that cannot be used.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::Vec3;
use raylab_core::scene::{Texture, TextureId};

/// Largest width or height accepted.
pub const MAX_DIMENSION: u32 = 16384;
/// Largest decoded size of one image in bytes (RGBA8).
pub const MAX_IMAGE_BYTES: u64 = 256 << 20;
/// Largest decoded size of all the images of one scene.
pub const MAX_TOTAL_BYTES: u64 = 2 << 30;

/// How a texture's values are meant.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TextureUse {
    /// A colour map in sRGB (diffuse, base colour): converted to linear.
    Color,
    /// A tangent-space normal map: values kept as stored.
    Normal,
    /// A height (bump) map, turned into a normal map.
    Bump,
}

/// Loads each texture file of a scene once and collects warnings.
#[derive(Default)]
pub struct TextureSet {
    /// The textures, in [`TextureId`] order.
    pub textures: Vec<Texture>,
    /// Problems met, each naming the file.
    pub warnings: Vec<String>,
    cache: HashMap<(PathBuf, TextureUse), TextureId>,
    decoded: u64,
}

impl TextureSet {
    /// The texture for `path` used as `usage`: loaded on first use; a file that cannot be used gives the
    /// checker placeholder and a warning.
    pub fn file(&mut self, path: &Path, usage: TextureUse) -> TextureId {
        if let Some(&id) = self.cache.get(&(path.to_path_buf(), usage)) {
            return id;
        }
        let name = path.display().to_string();
        let texture = match std::fs::read(path) {
            Ok(bytes) => self.decode(&name, &bytes, usage),
            Err(e) => Err(format!("cannot read texture {name}: {e}")),
        };
        let id = self.push(&name, texture);
        self.cache.insert((path.to_path_buf(), usage), id);
        id
    }

    /// A texture from encoded bytes (a glTF buffer view or data URI), named `name` in messages.
    pub fn bytes(&mut self, name: &str, bytes: &[u8], usage: TextureUse) -> TextureId {
        let texture = self.decode(name, bytes, usage);
        self.push(name, texture)
    }

    /// A warning and the placeholder for a texture refused before reading (an unsafe path, say).
    pub fn refused(&mut self, name: &str, why: String) -> TextureId {
        self.push(name, Err(why))
    }

    fn push(&mut self, name: &str, texture: Result<Texture, String>) -> TextureId {
        let t = texture.unwrap_or_else(|why| {
            self.warnings.push(format!("{why}; using a checker placeholder"));
            Texture::placeholder(name)
        });
        self.textures.push(t);
        (self.textures.len() - 1) as TextureId
    }

    fn decode(&mut self, name: &str, bytes: &[u8], usage: TextureUse) -> Result<Texture, String> {
        let (w, h) = reader(name, bytes)?.into_dimensions().map_err(|e| format!("cannot read texture {name}: {e}"))?;
        let size = w as u64 * h as u64 * 4;
        if w > MAX_DIMENSION || h > MAX_DIMENSION || size > MAX_IMAGE_BYTES {
            return Err(format!(
                "texture {name} is {w}x{h}, over the limit of {MAX_DIMENSION} texels a side and {} MiB",
                MAX_IMAGE_BYTES >> 20
            ));
        }
        if self.decoded + size > MAX_TOTAL_BYTES {
            return Err(format!("texture {name} would take the scene's textures over {} MiB", MAX_TOTAL_BYTES >> 20));
        }
        let img = reader(name, bytes)?.decode().map_err(|e| format!("cannot decode texture {name}: {e}"))?.to_rgb8();
        self.decoded += size;
        let texels: Vec<Vec3> = img
            .pixels()
            .map(|p| {
                let v = Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32) / 255.0;
                if usage == TextureUse::Color { v.map(srgb_to_linear) } else { v }
            })
            .collect();
        let texels = if usage == TextureUse::Bump { bump_to_normals(&texels, w, h) } else { texels };
        Texture::new(name, w, h, texels).ok_or_else(|| format!("texture {name} is empty"))
    }
}

/// An image reader over `bytes` with the format guessed from its content (or, for TGA, which has no
/// signature, from `name`'s extension) and the size limits set.
fn reader<'a>(name: &str, bytes: &'a [u8]) -> Result<image::ImageReader<std::io::Cursor<&'a [u8]>>, String> {
    let mut r = image::ImageReader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| format!("cannot read texture {name}: {e}"))?;
    // TGA has no signature: fall back on the name's extension.
    if r.format().is_none()
        && let Ok(format) = image::ImageFormat::from_path(name)
    {
        r.set_format(format);
    }
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(MAX_DIMENSION);
    limits.max_image_height = Some(MAX_DIMENSION);
    limits.max_alloc = Some(MAX_IMAGE_BYTES);
    r.limits(limits);
    Ok(r)
}

/// The sRGB transfer function inverted (IEC 61966-2-1).
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) }
}

/// A tangent-space normal map from a height map (its red channel), by central differences with wrap-around.
fn bump_to_normals(height: &[Vec3], w: u32, h: u32) -> Vec<Vec3> {
    let (w, h) = (w as usize, h as usize);
    let at = |x: usize, y: usize| height[(y % h) * w + (x % w)].x;
    let strength = 2.0;
    (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let dx = at(x + 1, y) - at(x + w - 1, y);
            let dy = at(x, y + h - 1) - at(x, y + 1);
            let n = Vec3::new(-dx * strength, -dy * strength, 1.0).normalize();
            n * 0.5 + Vec3::splat(0.5)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn png(w: u32, h: u32, f: impl Fn(u32, u32) -> [u8; 3]) -> Vec<u8> {
        let img = image::RgbImage::from_fn(w, h, |x, y| image::Rgb(f(x, y)));
        let mut out = Vec::new();
        img.write_to(&mut std::io::Cursor::new(&mut out), image::ImageFormat::Png).unwrap();
        out
    }

    #[test]
    fn colour_maps_become_linear_and_data_maps_stay() {
        let bytes = png(2, 1, |x, _| if x == 0 { [188, 188, 188] } else { [128, 128, 255] });
        let mut set = TextureSet::default();
        let c = set.bytes("c.png", &bytes, TextureUse::Color);
        let n = set.bytes("n.png", &bytes, TextureUse::Normal);
        let (c, n) = (&set.textures[c as usize], &set.textures[n as usize]);
        assert!((c.texels[0].x - 0.5).abs() < 0.01, "sRGB 188 is about linear 0.5: {}", c.texels[0].x);
        assert!((n.texels[1].z - 1.0).abs() < 1e-6 && (n.texels[1].x - 128.0 / 255.0).abs() < 1e-6);
        assert!(set.warnings.is_empty());
    }

    #[test]
    fn jpeg_tga_and_bmp_decode_too() {
        for (format, name) in [
            (image::ImageFormat::Jpeg, "white.jpg"),
            (image::ImageFormat::Tga, "white.tga"),
            (image::ImageFormat::Bmp, "white.bmp"),
        ] {
            let img = image::RgbImage::from_pixel(4, 2, image::Rgb([255, 255, 255]));
            let mut bytes = Vec::new();
            img.write_to(&mut std::io::Cursor::new(&mut bytes), format).unwrap();
            let mut set = TextureSet::default();
            let id = set.bytes(name, &bytes, TextureUse::Color);
            let t = &set.textures[id as usize];
            assert_eq!((t.width, t.height), (4, 2), "{format:?}");
            assert!(t.texels.iter().all(|v| v.min_element() > 0.95), "{format:?}");
            assert!(set.warnings.is_empty(), "{format:?}: {:?}", set.warnings);
        }
    }

    #[test]
    fn flat_bump_maps_give_flat_normals() {
        let bytes = png(4, 4, |_, _| [90, 90, 90]);
        let mut set = TextureSet::default();
        let t = set.bytes("b.png", &bytes, TextureUse::Bump);
        assert!(set.textures[t as usize].texels.iter().all(|v| (*v - Vec3::new(0.5, 0.5, 1.0)).length() < 1e-6));
    }

    #[test]
    fn unreadable_textures_are_placeholders_with_a_warning() {
        let mut set = TextureSet::default();
        let missing = set.file(Path::new("/nonexistent/wall.png"), TextureUse::Color);
        let garbage = set.bytes("garbage.png", b"\\x89PNG not really", TextureUse::Color);
        assert_eq!(set.textures[missing as usize].width, 8);
        assert_eq!(set.textures[garbage as usize].width, 8);
        assert_eq!(set.warnings.len(), 2);
        assert!(set.warnings[0].contains("wall.png") && set.warnings[1].contains("garbage.png"), "{:?}", set.warnings);
        assert_eq!(set.file(Path::new("/nonexistent/wall.png"), TextureUse::Color), missing, "loaded once");
    }

    #[test]
    fn oversized_images_are_refused_not_decoded() {
        // A valid PNG header claiming 100000 x 100000 pixels.
        let mut bytes = png(1, 1, |_, _| [0, 0, 0]);
        bytes[16..20].copy_from_slice(&100_000u32.to_be_bytes());
        bytes[20..24].copy_from_slice(&100_000u32.to_be_bytes());
        let mut set = TextureSet::default();
        set.bytes("huge.png", &bytes, TextureUse::Color);
        assert!(set.warnings[0].contains("huge.png"), "{:?}", set.warnings);
    }
}
