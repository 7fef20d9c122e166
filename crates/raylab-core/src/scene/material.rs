//! Fixed-function materials (Tsakok 2008, section 4.2.1, Listing 4.7).
//!
//! RTTest exposes five shader types, each adding one effect to the previous: diffuse, then a Phong
//! highlight, then mirror reflection, and two transparent types. raylab keeps the same five types and the same parameters,
//! flattened into one struct so the shader reads them without branching on nested records; the fields a
//! type does not use are ignored.

use glam::Vec3;
use serde::{Deserialize, Serialize};

/// Index of a texture in [`super::Scene::textures`].
pub type TextureId = u32;

/// The five shader types of Listing 4.7.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum MaterialKind {
    /// Lambertian diffuse only (`M_D`).
    #[default]
    Diffuse,
    /// Diffuse plus a Phong highlight (`M_S`).
    Specular,
    /// Diffuse, specular and a mirror reflection (`M_R`).
    Reflective,
    /// Diffuse and refraction (`M_T`).
    Transparent,
    /// Diffuse, specular, refraction and reflection (`M_TR`).
    TransparentReflective,
}

impl MaterialKind {
    /// All five kinds, in Listing 4.7's order.
    pub const ALL: [MaterialKind; 5] = [
        MaterialKind::Diffuse,
        MaterialKind::Specular,
        MaterialKind::Reflective,
        MaterialKind::Transparent,
        MaterialKind::TransparentReflective,
    ];

    /// True for the kinds that show a Phong highlight.
    pub fn has_specular(self) -> bool {
        matches!(self, Self::Specular | Self::Reflective | Self::TransparentReflective)
    }

    /// True for the kinds that spawn a reflection ray.
    pub fn reflects(self) -> bool {
        matches!(self, Self::Reflective | Self::TransparentReflective)
    }

    /// True for the kinds that spawn a refraction ray.
    pub fn refracts(self) -> bool {
        matches!(self, Self::Transparent | Self::TransparentReflective)
    }
}

/// A surface description: one of the Listing 4.7 types and its parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Material {
    /// Name, for the UI and for error messages.
    pub name: String,
    /// Shader type.
    pub kind: MaterialKind,
    /// Base (diffuse) colour in linear RGB (`d_info::base`).
    pub base_color: Vec3,
    /// Optional diffuse colour texture, multiplied with `base_color` (`d_info::diffMap`).
    pub diffuse_texture: Option<TextureId>,
    /// Optional tangent-space normal map (`d_info::normMap`).
    pub normal_texture: Option<TextureId>,
    /// Phong exponent of the highlight (`s_info::exp`).
    pub phong_exponent: f32,
    /// Weight of the highlight (`s_info::blend`).
    pub specular_blend: f32,
    /// Weight of the reflected colour (`r_info::blend`).
    pub reflect_blend: f32,
    /// Weight of the refracted colour (`t_info::blend`).
    pub transmit_blend: f32,
    /// Index of refraction of the medium behind the surface (`t_info::refract_index`).
    pub ior: f32,
    /// Beer's-law absorption coefficient per unit distance inside a transparent medium (seed 004).
    pub absorption: Vec3,
}

impl Default for Material {
    fn default() -> Self {
        Self {
            name: "default".into(),
            kind: MaterialKind::Diffuse,
            base_color: Vec3::splat(0.8),
            diffuse_texture: None,
            normal_texture: None,
            phong_exponent: 32.0,
            specular_blend: 0.0,
            reflect_blend: 0.0,
            transmit_blend: 0.0,
            ior: 1.5,
            absorption: Vec3::ZERO,
        }
    }
}

impl Material {
    /// A named diffuse material of the given colour.
    pub fn diffuse(name: &str, base_color: Vec3) -> Self {
        Self { name: name.into(), base_color, ..Self::default() }
    }

    /// A diffuse material with a Phong highlight.
    pub fn specular(name: &str, base_color: Vec3, phong_exponent: f32, specular_blend: f32) -> Self {
        Self { kind: MaterialKind::Specular, phong_exponent, specular_blend, ..Self::diffuse(name, base_color) }
    }

    /// A mirror-like material reflecting `reflect_blend` of the incoming light.
    pub fn mirror(name: &str, base_color: Vec3, reflect_blend: f32) -> Self {
        Self {
            kind: MaterialKind::Reflective,
            reflect_blend,
            specular_blend: 0.5,
            phong_exponent: 64.0,
            ..Self::diffuse(name, base_color)
        }
    }

    /// A glass-like material: refraction with index `ior`, Fresnel reflection, optional absorption.
    pub fn glass(name: &str, tint: Vec3, ior: f32, absorption: Vec3) -> Self {
        Self {
            kind: MaterialKind::TransparentReflective,
            transmit_blend: 0.9,
            reflect_blend: 0.1,
            specular_blend: 0.5,
            phong_exponent: 128.0,
            ior,
            absorption,
            ..Self::diffuse(name, tint)
        }
    }
}
