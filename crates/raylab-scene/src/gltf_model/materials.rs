//! glTF's metallic-roughness materials onto the fixed-function model of thesis Listing 4.7.
//!
//! | glTF | raylab |
//! |---|---|
//! | `baseColorFactor`, `baseColorTexture` | base colour times the diffuse texture (sRGB made linear) |
//! | `normalTexture` | the normal map |
//! | `metallicFactor` >= 0.5 | Reflective, reflection weight `metallic * (1 - roughness)` |
//! | `roughnessFactor` < 0.5 (dielectric) | Specular: exponent `2 / r^4 - 2` (capped at 1000), weight `0.5 (1 - r)` |
//! | otherwise | Diffuse |
//! | `alphaMode` BLEND with alpha < 1 | Transparent, transmission `1 - alpha`, index 1 (a thin sheet) |
//! | `alphaMode` MASK | opaque (cut-outs are not traced) |
//! | `KHR_materials_transmission` > 0 | TransparentReflective, transmission factor, index from `KHR_materials_ior` (1.5) |
//!
//! Metallic-roughness and occlusion textures are not read.

use glam::Vec3;
use raylab_core::scene::{Material, MaterialKind, TextureId};

/// The raylab material for a glTF material, with its textures already loaded.
pub fn convert(m: &gltf::Material, base_texture: Option<TextureId>, normal_texture: Option<TextureId>) -> Material {
    let pbr = m.pbr_metallic_roughness();
    let [r, g, b, a] = pbr.base_color_factor().map(|c| if c.is_finite() { c.clamp(0.0, 1.0) } else { 1.0 });
    let metallic = finite01(pbr.metallic_factor());
    let rough = finite01(pbr.roughness_factor());
    let transmission = m.transmission().map_or(0.0, |t| finite01(t.transmission_factor()));
    let ior = m.ior().filter(|n| n.is_finite() && *n >= 1.0 && *n <= 5.0).unwrap_or(1.5);
    let blend = m.alpha_mode() == gltf::material::AlphaMode::Blend && a < 1.0;
    let kind = if transmission > 0.0 {
        MaterialKind::TransparentReflective
    } else if blend {
        MaterialKind::Transparent
    } else if metallic >= 0.5 {
        MaterialKind::Reflective
    } else if rough < 0.5 {
        MaterialKind::Specular
    } else {
        MaterialKind::Diffuse
    };
    let exponent = (2.0 / rough.max(0.05).powi(4) - 2.0).clamp(1.0, 1000.0);
    Material {
        name: m.name().map_or_else(|| format!("material {}", m.index().map_or(-1, |i| i as i64)), str::to_string),
        kind,
        base_color: Vec3::new(r, g, b),
        diffuse_texture: base_texture,
        normal_texture,
        phong_exponent: exponent,
        specular_blend: if kind == MaterialKind::Diffuse { 0.0 } else { 0.5 * (1.0 - rough) },
        reflect_blend: if kind == MaterialKind::Reflective { (metallic * (1.0 - rough)).max(0.05) } else { 0.0 },
        transmit_blend: match kind {
            MaterialKind::TransparentReflective => transmission,
            MaterialKind::Transparent => 1.0 - a,
            _ => 0.0,
        },
        ior: if kind == MaterialKind::Transparent { 1.0 } else { ior },
        absorption: Vec3::ZERO,
    }
}

fn finite01(x: f32) -> f32 {
    if x.is_finite() { x.clamp(0.0, 1.0) } else { 0.0 }
}
