//! Fixed-function shading of one hit (Tsakok 2008, section 4.2.1, Listing 4.7, and chapter 4's benchmark
//! shading: "a single point light with attenuation and simple shading").
//!
//! The local colour is `albedo * (ambient + direct * N.L * attenuation * visibility)` plus, for the specular
//! kinds, a Phong highlight. With a white diffuse material and no attenuation this is exactly the Embree
//! harness's image, `0.12 + 0.88 * max(0, N.L) * visible`, so the two renderers compare pixel for pixel.
//! The secondary directions and weights (mirror reflection, refraction, Schlick's Fresnel, Beer's law) are
//! here too; the renderer traces them.

use std::sync::LazyLock;

use glam::{Vec2, Vec3};

use crate::ray::{Hit, Ray};
use crate::scene::{Material, PointLight, Scene};

/// Share of the light that reaches every lit or unlit surface.
pub const AMBIENT: f32 = 0.12;
/// Share of the light scaled by N.L and visibility.
pub const DIRECT: f32 = 1.0 - AMBIENT;

/// What shading needs to know about a hit point.
#[derive(Clone, Copy, Debug)]
pub struct Surface<'a> {
    /// The point.
    pub point: Vec3,
    /// Unit geometric normal, turned toward the side the ray came from.
    pub geometric: Vec3,
    /// Unit shading normal (interpolated, normal-mapped), on the same side as `geometric`.
    pub normal: Vec3,
    /// True when the ray hit the triangle's front, `(v1 - v0) x (v2 - v0)` pointing against it: for closed,
    /// outward-facing meshes, the ray enters the solid.
    pub entering: bool,
    /// The material.
    pub material: &'a Material,
    /// Base colour times the diffuse texture.
    pub albedo: Vec3,
}

impl<'a> Surface<'a> {
    /// The surface at `hit` along `ray`.
    #[inline(always)]
    pub fn at(scene: &'a Scene, ray: &Ray, hit: &Hit) -> Self {
        let tri = &scene.triangles[hit.tri as usize];
        let material = &scene.materials[tri.material as usize];
        let mut geometric = scene.geometric_normal(hit.tri as usize);
        let entering = geometric.dot(ray.dir) < 0.0;
        if !entering {
            geometric = -geometric;
        }
        let texture = material.diffuse_texture.and_then(|i| scene.textures.get(i as usize));
        let normal_map = material.normal_texture.and_then(|i| scene.textures.get(i as usize));
        // Most surfaces have no texture: they skip the UV interpolation.
        let uv = if texture.is_some() || normal_map.is_some() { texture_uv(scene, hit) } else { None };
        let mut normal = scene.shading_normal(hit);
        if let (Some(map), Some(uv)) = (normal_map, uv) {
            normal = normal_mapped(scene, hit.tri as usize, normal, map.sample(uv));
        }
        if normal.dot(geometric) < 0.0 {
            normal = -normal;
        }
        let albedo = match (texture, uv) {
            (Some(t), Some(uv)) => material.base_color * t.sample(uv),
            _ => material.base_color,
        };
        Self { point: ray.at(hit.t), geometric, normal, entering, material, albedo }
    }

    /// The local colour lit by `light`, of which a fraction `visibility` reaches the point; `view` is the
    /// incoming ray's direction.
    #[inline]
    pub fn local(&self, view: Vec3, light: &PointLight, visibility: f32) -> Vec3 {
        let to_light = light.position - self.point;
        let dist = to_light.length();
        let l = if dist > 0.0 { to_light / dist } else { self.normal };
        let ndl = self.normal.dot(l).max(0.0);
        let lit = visibility * light.attenuation(dist);
        let mut c = self.albedo * (AMBIENT + DIRECT * (ndl * lit) * light.color);
        if self.material.kind.has_specular() && ndl > 0.0 && lit > 0.0 {
            let r = reflect(-l, self.normal);
            let highlight = r.dot(-view).max(0.0).powf(self.material.phong_exponent);
            c += light.color * (self.material.specular_blend * highlight * lit);
        }
        c
    }
}

/// The shadow ray of a hit: from the point, lifted by `epsilon` along the geometric normal turned toward the
/// viewer, to `target` (the light's centre or a sample on it); `None` where the surface faces away from the
/// light (no shadow ray needed: the point is unlit).
pub fn shadow_ray(surface: &Surface, light_center: Vec3, target: Vec3, epsilon: f32) -> Option<Ray> {
    let n = surface.normal;
    if n.dot(light_center - surface.point) * n.dot(surface.geometric) <= 0.0 {
        return None;
    }
    let q = surface.point + surface.geometric * epsilon;
    let v = target - q;
    let d = v.length();
    (d > 0.0 && d.is_finite()).then(|| Ray::segment(q, v / d, 0.0, d))
}

/// The shading normal of a hit, turned to the side of the surface the ray came from (two-sided shading).
pub fn facing_normal(scene: &Scene, ray: &Ray, hit: &Hit) -> Vec3 {
    Surface::at(scene, ray, hit).normal
}

/// The mirror direction of `d` about the unit normal `n`.
pub fn reflect(d: Vec3, n: Vec3) -> Vec3 {
    d - n * (2.0 * d.dot(n))
}

/// The refracted direction of unit `d` entering through unit `n` (facing against `d`) with index ratio
/// `eta = n_from / n_to`; `None` on total internal reflection.
pub fn refract(d: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    if eta == 1.0 {
        return Some(d);
    }
    let cos_i = -d.dot(n);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
    if sin2_t > 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some((d * eta + n * (eta * cos_i - cos_t)).normalize())
}

/// Schlick's approximation of the Fresnel reflectance (Ray Tracing II, "Fresnel"), for a ray meeting the
/// interface from index `n_from` into `n_to` with `cos_i` the cosine of the incidence angle. Matched indices
/// are no interface at all and reflect nothing; past the critical angle everything reflects.
pub fn schlick(cos_i: f32, n_from: f32, n_to: f32) -> f32 {
    if n_from == n_to {
        return 0.0;
    }
    let r0 = ((n_from - n_to) / (n_from + n_to)).powi(2);
    // Going into the thinner medium, the angle that matters is the transmitted one.
    let cos = if n_from > n_to {
        let sin2_t = (n_from / n_to).powi(2) * (1.0 - cos_i * cos_i).max(0.0);
        if sin2_t >= 1.0 {
            return 1.0;
        }
        (1.0 - sin2_t).sqrt()
    } else {
        cos_i
    };
    r0 + (1.0 - r0) * (1.0 - cos.clamp(0.0, 1.0)).powi(5)
}

/// Beer's law (Ray Tracing II): the share of light left after `distance` through a medium absorbing
/// `absorption` per unit length, per channel, `exp(-c * s)`.
pub fn beer(absorption: Vec3, distance: f32) -> Vec3 {
    if absorption == Vec3::ZERO {
        return Vec3::ONE;
    }
    (-absorption * distance.max(0.0)).exp()
}

/// Texture coordinates at a hit, when the scene has them.
fn texture_uv(scene: &Scene, hit: &Hit) -> Option<Vec2> {
    if scene.uvs.is_empty() {
        return None;
    }
    let t = &scene.triangles[hit.tri as usize];
    let [a, b, c] = t.v.map(|i| scene.uvs[i as usize]);
    Some(a * (1.0 - hit.u - hit.v) + b * hit.u + c * hit.v)
}

/// The normal `n` bent by a tangent-space normal-map texel (components in `[0, 1]`, `(0.5, 0.5, 1)` = flat),
/// with the tangent frame of triangle `tri` taken from its UVs. Triangles without usable UVs keep `n`.
pub fn normal_mapped(scene: &Scene, tri: usize, n: Vec3, texel: Vec3) -> Vec3 {
    if scene.uvs.is_empty() {
        return n;
    }
    let t = &scene.triangles[tri];
    let [p0, p1, p2] = scene.vertices(tri);
    let [w0, w1, w2] = t.v.map(|i| scene.uvs[i as usize]);
    let (e1, e2, d1, d2) = (p1 - p0, p2 - p0, w1 - w0, w2 - w0);
    let det = d1.x * d2.y - d2.x * d1.y;
    if det == 0.0 || !det.is_finite() {
        return n;
    }
    let tangent = (e1 * d2.y - e2 * d1.y) / det;
    let bitangent = (e2 * d1.x - e1 * d2.x) / det;
    let tangent = (tangent - n * n.dot(tangent)).normalize_or_zero();
    if tangent == Vec3::ZERO {
        return n;
    }
    let handed = if n.cross(tangent).dot(bitangent) < 0.0 { -1.0 } else { 1.0 };
    let bitangent = n.cross(tangent) * handed;
    let m = texel * 2.0 - Vec3::ONE;
    let bent = (tangent * m.x + bitangent * m.y + n * m.z).normalize_or_zero();
    if bent == Vec3::ZERO { n } else { bent }
}

/// Linear value to an 8-bit display value with the harness's gamma of 2.2: `round(255 v^(1/2.2))` of `v`
/// clamped to `[0, 1]`, NaN to 0. Every channel of every pixel goes through this, so instead of a `powf` it
/// looks up the byte at the start of `v`'s bucket and adds one if `v` has reached the next display step;
/// the buckets are narrow enough that none holds two steps, which makes the lookup free of data-dependent
/// branches (a loop over the steps, with equal-width buckets, was about half of the per-pixel output's time,
/// much of it mispredicted exits).
#[inline]
pub fn to_display(v: f32) -> u8 {
    DISPLAY.byte(v)
}

/// An opaque display pixel of linear colour `c`: [`to_display`] of each channel, with the table looked up
/// once.
#[inline(always)]
pub fn to_display_rgba(c: Vec3) -> [u8; 4] {
    let table = &*DISPLAY;
    [table.byte(c.x), table.byte(c.y), table.byte(c.z), 255]
}

/// The display formula itself, which [`DisplayTable`] is derived from.
fn gamma_byte(v: f32) -> u8 {
    (255.0 * v.clamp(0.0, 1.0).powf(1.0 / 2.2)).round() as u8
}

/// Where [`gamma_byte`] steps up on `[0, 1]` (it never decreases there), for [`to_display`].
struct DisplayTable {
    /// Entry `k` is the smallest value that [`gamma_byte`] takes to `k + 1` or more; the last is infinite.
    steps: [f32; 256],
    /// The byte of each bucket's lower edge.
    bucket_start: Vec<u8>,
}

impl DisplayTable {
    /// Low bits of a value's bit pattern that its bucket ignores: a bucket spans 2^-7 of its value (the
    /// seven high mantissa bits), narrower than the relative gap between display steps, which is smallest
    /// at the top (1 / (255 / 2.2) of the value, about 0.9%), so no bucket holds two steps.
    const SHIFT: u32 = 16;

    /// [`gamma_byte`] of `v`, read from the table.
    #[inline(always)]
    fn byte(&self, v: f32) -> u8 {
        // Clamped to [0, 1] with NaN and -0 going to +0 (a select, no branch): 0 and 1 have buckets too, and
        // their bytes are the table's ends.
        let v = if v > 0.0 { v.min(1.0) } else { 0.0 };
        let start = self.bucket_start[Self::bucket(v)];
        start + u8::from(v >= self.steps[start as usize])
    }

    /// The bucket of a value in `(0, 1)`: its bit pattern's high bits, logarithmic in the value (positive
    /// floats order like their bit patterns).
    #[inline(always)]
    fn bucket(v: f32) -> usize {
        (v.to_bits() >> Self::SHIFT) as usize
    }

    fn new() -> Self {
        let steps = std::array::from_fn(|k| {
            if k == 255 {
                return f32::INFINITY;
            }
            // Non-negative floats order like their bit patterns: bisect the patterns of [0, 1].
            let (mut lo, mut hi) = (0u32, 1.0f32.to_bits());
            while lo < hi {
                let mid = lo + (hi - lo) / 2;
                if gamma_byte(f32::from_bits(mid)) as usize > k { hi = mid } else { lo = mid + 1 }
            }
            f32::from_bits(lo)
        });
        let buckets = Self::bucket(1.0) + 1;
        let bucket_start = (0..buckets).map(|b| gamma_byte(f32::from_bits((b as u32) << Self::SHIFT))).collect();
        Self { steps, bucket_start }
    }
}

static DISPLAY: LazyLock<DisplayTable> = LazyLock::new(DisplayTable::new);

#[cfg(test)]
mod tests {
    use super::*;

    /// The step lookup gives the formula's byte: at and just below every step, across `[0, 1]` at a stride
    /// of bit patterns, at both ends of every bucket, and for values outside `[0, 1]`.
    #[test]
    fn display_bytes_match_the_gamma_formula() {
        for (k, &step) in DISPLAY.steps[..255].iter().enumerate() {
            assert_eq!(to_display(step), gamma_byte(step), "step {}", k + 1);
            assert_eq!(gamma_byte(step) as usize, k + 1, "step {} is reached", k + 1);
            let below = f32::from_bits(step.to_bits() - 1);
            assert_eq!(to_display(below), gamma_byte(below), "below step {}", k + 1);
        }
        for bits in (0..=1.0f32.to_bits()).step_by(4099) {
            let v = f32::from_bits(bits);
            assert_eq!(to_display(v), gamma_byte(v), "{v}");
        }
        // A bucket's last value is where a second step inside it would show.
        let width = 1u32 << DisplayTable::SHIFT;
        for b in 1..DISPLAY.bucket_start.len() as u32 {
            for v in [f32::from_bits(b * width), f32::from_bits(b * width + width - 1)] {
                assert_eq!(to_display(v), gamma_byte(v), "bucket {b}: {v}");
            }
        }
        for v in [-1.0, -0.0, 0.0, 1.0, 1.5, f32::INFINITY, f32::NEG_INFINITY, f32::NAN, f32::MIN_POSITIVE] {
            assert_eq!(to_display(v), gamma_byte(v), "{v}");
        }
    }

    /// One triangle in the z = 0 plane facing +z, u along +x and v along +y, with a 2x1 diffuse texture
    /// (red, green) and a normal map.
    fn textured(normal_texel: Vec3) -> Scene {
        use crate::scene::{SceneBuilder, Texture, Triangle};
        let mut b = SceneBuilder::new();
        b.positions = vec![Vec3::ZERO, Vec3::X, Vec3::Y];
        b.uvs = vec![Vec2::ZERO, Vec2::X, Vec2::Y];
        b.triangles = vec![Triangle { v: [0, 1, 2], material: 0 }];
        b.textures = vec![
            Texture::new("albedo", 2, 1, vec![Vec3::X, Vec3::Y]).unwrap(),
            Texture::new("normals", 1, 1, vec![normal_texel]).unwrap(),
        ];
        b.materials = vec![Material {
            diffuse_texture: Some(0),
            normal_texture: Some(1),
            ..Material::diffuse("textured", Vec3::splat(0.5))
        }];
        b.build()
    }

    #[test]
    fn diffuse_textures_tint_the_base_colour_and_flat_normal_maps_change_nothing() {
        let scene = textured(Vec3::new(0.5, 0.5, 1.0));
        let ray = Ray::new(Vec3::new(0.1, 0.1, 1.0), Vec3::NEG_Z);
        let hit = Hit { t: 1.0, tri: 0, u: 0.1, v: 0.1 };
        let s = Surface::at(&scene, &ray, &hit);
        assert!((s.normal - Vec3::Z).length() < 1e-6);
        // u = 0.1 lies left of the first texel's centre (0.25): with repeat, it blends in a little green.
        assert!(s.albedo.x > 0.3 && s.albedo.y > 0.0 && s.albedo.y < s.albedo.x && s.albedo.z == 0.0, "{}", s.albedo);
    }

    #[test]
    fn normal_maps_bend_the_normal_along_the_uv_tangents() {
        let ray = Ray::new(Vec3::new(0.2, 0.2, 1.0), Vec3::NEG_Z);
        let hit = Hit { t: 1.0, tri: 0, u: 0.2, v: 0.2 };
        // Texel (1, 0.5, 0.5) is the tangent-space +u direction: the normal turns to +x.
        let along_u = textured(Vec3::new(1.0, 0.5, 0.5));
        let s = Surface::at(&along_u, &ray, &hit);
        assert!((s.normal - Vec3::X).length() < 1e-5, "{}", s.normal);
        let tilted = Vec3::new(0.5, 1.0, 1.0);
        let scene = textured(tilted);
        let s = Surface::at(&scene, &ray, &hit);
        let want = Vec3::new(0.0, 1.0, 1.0).normalize();
        assert!((s.normal - want).length() < 1e-5, "{}", s.normal);
        // The bent normal changes the lighting as N.L predicts.
        let light = PointLight::at(Vec3::new(0.2, 10.2, 0.0));
        let lit = s.local(ray.dir, &light, 1.0);
        let ndl = want.dot(Vec3::Y);
        assert!((lit.y - s.albedo.y * (AMBIENT + DIRECT * ndl)).abs() < 1e-5);
    }

    #[test]
    fn reflection_mirrors_about_the_normal() {
        assert_eq!(reflect(Vec3::new(1.0, -1.0, 0.0), Vec3::Y), Vec3::new(1.0, 1.0, 0.0));
    }

    #[test]
    fn refraction_follows_snell_and_reflects_totally_past_the_critical_angle() {
        let d = Vec3::new(1.0, -1.0, 0.0).normalize();
        let t = refract(d, Vec3::Y, 1.0 / 1.5).unwrap();
        let (sin_i, sin_t) = (d.x, t.x);
        assert!((sin_i / sin_t - 1.5).abs() < 1e-5, "Snell: sin_i / sin_t = n2 / n1");
        assert_eq!(refract(d, Vec3::Y, 1.0).unwrap(), d, "matched indices do not bend");
        // From glass into air at 45 degrees: past the critical angle of about 41.8 degrees.
        assert!(refract(d, Vec3::Y, 1.5).is_none());
        assert!(refract(Vec3::NEG_Y, Vec3::Y, 1.5).is_some(), "normal incidence always passes");
    }

    #[test]
    fn schlick_matches_its_end_points() {
        let r0 = (0.5f32 / 2.5).powi(2);
        assert!((schlick(1.0, 1.0, 1.5) - r0).abs() < 1e-6, "normal incidence gives R0 = 4%");
        assert!((schlick(0.0, 1.0, 1.5) - 1.0).abs() < 1e-6, "grazing incidence reflects everything");
        assert_eq!(schlick(0.3, 1.5, 1.5), 0.0);
        assert_eq!(schlick(0.5, 1.5, 1.0), 1.0, "inside glass at 60 degrees: total internal reflection");
        let inside = schlick(0.99, 1.5, 1.0);
        assert!(inside > r0 && inside < 0.05);
    }

    #[test]
    fn beer_decays_exponentially_with_distance() {
        let c = Vec3::new(0.5, 1.0, 0.0);
        assert_eq!(beer(c, 0.0), Vec3::ONE);
        let two = beer(c, 2.0);
        assert!((two.x - (-1.0f32).exp()).abs() < 1e-6 && (two.y - (-2.0f32).exp()).abs() < 1e-6 && two.z == 1.0);
        assert!((beer(c, 4.0).x - two.x * two.x).abs() < 1e-6, "twice as thick, squared");
    }
}
