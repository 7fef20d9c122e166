//! MTL materials onto the fixed-function model of thesis Listing 4.7.
//!
//! | MTL | raylab |
//! |---|---|
//! | `Kd`, `map_Kd` | base colour times the diffuse texture (sRGB texture made linear) |
//! | `Ks`, `Ns` with `illum` 2 (or no `illum`) and a non-black `Ks` | Specular: highlight weight max(`Ks`), exponent `Ns` |
//! | `illum` 3 or 5 (ray-traced reflection) | Reflective: reflection weight max(`Ks`) |
//! | `d` < 1 (or `Tr` > 0) with `illum` 0-3 | Transparent: transmission 1 - `d`, index `Ni` |
//! | `illum` 4, 6, 7 or 9 (glass, refraction) | TransparentReflective: transmission 1 - `d` (0.9 when `d` is 1), index `Ni`, Fresnel reflection |
//! | `map_bump`, `bump`, `norm` | a normal map; a grey (height) image is turned into one |
//!
//! Texture options before the file name (`-bm 0.5 file.png`) are skipped, the last word being the file, except
//! `-clamp on`, which clamps the texture's coordinates instead of repeating it.

use std::path::Path;

use glam::Vec3;
use raylab_core::scene::{Material, MaterialKind, WrapMode};

use crate::texture::{TextureSet, TextureUse};

/// The raylab material for an MTL material; texture references resolve against `mtl_dir` and must stay
/// inside `root`.
pub fn convert(
    m: &tobj::Material,
    root: &Path,
    mtl_dir: &Path,
    textures: &mut TextureSet,
    warnings: &mut Vec<String>,
) -> Material {
    let v3 = |c: Option<[f32; 3]>| c.map(Vec3::from_array).filter(|v| v.is_finite());
    let base = v3(m.diffuse).unwrap_or(Vec3::splat(0.8)).clamp(Vec3::ZERO, Vec3::ONE);
    let ks = v3(m.specular).unwrap_or(Vec3::ZERO).clamp(Vec3::ZERO, Vec3::ONE).max_element();
    let ns = m.shininess.filter(|s| s.is_finite() && *s > 0.0).unwrap_or(32.0).min(10_000.0);
    let tr = m.unknown_param.get("Tr").and_then(|t| t.trim().parse::<f32>().ok()).map(|t| 1.0 - t);
    let d = m.dissolve.or(tr).filter(|d| d.is_finite()).unwrap_or(1.0).clamp(0.0, 1.0);
    let ior = m.optical_density.filter(|n| n.is_finite() && *n >= 1.0 && *n <= 5.0).unwrap_or(1.5);
    let illum = m.illumination_model.unwrap_or(if ks > 0.0 { 2 } else { 1 });
    let kind = match illum {
        4 | 6 | 7 | 9 => MaterialKind::TransparentReflective,
        _ if d < 1.0 => MaterialKind::Transparent,
        3 | 5 => MaterialKind::Reflective,
        2 if ks > 0.0 => MaterialKind::Specular,
        _ => MaterialKind::Diffuse,
    };
    let mut texture = |reference: &Option<String>, usage: TextureUse| {
        let words: Vec<&str> = reference.as_deref()?.split_whitespace().collect();
        let name = *words.last()?;
        let clamp = words.windows(2).any(|w| w[0] == "-clamp" && w[1] == "on");
        let id = match crate::paths::resolve(root, mtl_dir, name) {
            Ok(file) => textures.file(&file, usage),
            Err(why) => textures.refused(name, format!("material '{}': texture refused: {why}", m.name)),
        };
        if clamp {
            textures.textures[id as usize].wrap = WrapMode::Clamp;
        }
        Some(id)
    };
    let diffuse_texture = texture(&m.diffuse_texture, TextureUse::Color);
    let normal_texture = match m.unknown_param.get("norm") {
        Some(n) => texture(&Some(n.clone()), TextureUse::Normal),
        None => texture(&m.normal_texture, TextureUse::Bump),
    };
    if m.name.is_empty() {
        warnings.push("a material without a name".into());
    }
    Material {
        name: m.name.clone(),
        kind,
        base_color: base,
        diffuse_texture,
        normal_texture,
        phong_exponent: ns,
        specular_blend: if kind == MaterialKind::Diffuse { 0.0 } else { ks },
        reflect_blend: if kind == MaterialKind::Reflective { ks.max(0.1) } else { 0.0 },
        transmit_blend: match kind {
            MaterialKind::Transparent => 1.0 - d,
            MaterialKind::TransparentReflective if d < 1.0 => 1.0 - d,
            MaterialKind::TransparentReflective => 0.9,
            _ => 0.0,
        },
        ior,
        absorption: Vec3::ZERO,
    }
}

/// MTL text as tobj can take it: a colour statement (`Ka`, `Kd`, `Ks`, `Ke`) with one or two numbers gets the
/// missing ones from the first, as the MTL specification says, and one with none is dropped (tobj 4.0.5
/// panics on fewer than three).
pub fn normalise(bytes: &[u8]) -> Vec<u8> {
    let text = String::from_utf8_lossy(bytes);
    let mut out = String::with_capacity(text.len() + 16);
    for line in text.split_inclusive('\n') {
        let mut words = line.split_whitespace();
        let tag = words.next();
        let values: Vec<&str> = words.collect();
        let colour = matches!(tag, Some("Ka" | "Kd" | "Ks" | "Ke"));
        if colour && values.is_empty() {
            continue;
        }
        if colour && values.len() < 3 {
            let r = values[0];
            let g = values.get(1).copied().unwrap_or(r);
            out += &format!("{} {r} {g} {r}\n", tag.unwrap_or_default());
        } else {
            out += line;
        }
    }
    out.into_bytes()
}
