//! Named views and lights for a model file, from a small sidecar file beside it: `model.views.json` next to
//! `model.obj` (or `.gltf`, `.glb`). OBJ has no cameras or lights of its own, and a glTF may lack them.
//!
//! ```json
//! { "views": [ { "name": "nave", "eye": [-12.5, 2.5, 0], "target": [10, 5.5, 0], "up": [0, 1, 0], "fov": 65 } ],
//!   "lights": [ { "position": [0, 11, 0], "radius": 1 } ] }
//! ```
//!
//! `up` defaults to +y and `fov` to 60 degrees; a light's `color` to white and `radius` to 0. The sidecar's
//! views and lights come before the model's own, so its first view is the default. A broken sidecar is a
//! warning naming it; the model still loads.

use std::path::{Path, PathBuf};

use glam::Vec3;
use raylab_core::scene::{Camera, PointLight, Scene, View};
use serde::Deserialize;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Sidecar {
    #[serde(default)]
    views: Vec<ViewEntry>,
    #[serde(default)]
    lights: Vec<LightEntry>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ViewEntry {
    name: String,
    eye: [f32; 3],
    target: [f32; 3],
    #[serde(default = "up")]
    up: [f32; 3],
    #[serde(default = "fov")]
    fov: f32,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LightEntry {
    position: [f32; 3],
    #[serde(default = "white")]
    color: [f32; 3],
    #[serde(default)]
    radius: f32,
}

fn up() -> [f32; 3] {
    [0.0, 1.0, 0.0]
}

fn fov() -> f32 {
    60.0
}

fn white() -> [f32; 3] {
    [1.0; 3]
}

/// The sidecar path of a model file: `dir/stem.views.json`.
pub fn path_for(model: &Path) -> PathBuf {
    let stem = model.file_stem().map_or_else(|| "model".into(), |s| s.to_string_lossy().into_owned());
    model.with_file_name(format!("{stem}.views.json"))
}

/// Adds the views and lights of `model`'s sidecar, if there is one, to `scene`; problems go to `warnings`.
pub fn apply(model: &Path, scene: &mut Scene, warnings: &mut Vec<String>) {
    let path = path_for(model);
    let Ok(text) = std::fs::read_to_string(&path) else { return };
    let sidecar: Sidecar = match serde_json::from_str(&text) {
        Ok(s) => s,
        Err(e) => {
            warnings.push(format!("{}: {e}; its views are ignored", path.display()));
            return;
        }
    };
    let mut views = Vec::new();
    for v in sidecar.views {
        let camera = Camera::look_at(Vec3::from(v.eye), Vec3::from(v.target), Vec3::from(v.up), v.fov);
        match camera.validate() {
            Ok(()) => views.push(View { name: v.name, camera }),
            Err(e) => warnings.push(format!("{}: view '{}' is unusable ({e:?})", path.display(), v.name)),
        }
    }
    let mut lights = Vec::new();
    for l in sidecar.lights {
        let (p, c) = (Vec3::from(l.position), Vec3::from(l.color));
        if p.is_finite() && c.is_finite() && l.radius.is_finite() && l.radius >= 0.0 {
            lights.push(PointLight { color: c, radius: l.radius, ..PointLight::at(p) });
        } else {
            warnings.push(format!("{}: a light with non-finite or negative values is ignored", path.display()));
        }
    }
    views.append(&mut scene.views);
    scene.views = views;
    lights.append(&mut scene.lights);
    scene.lights = lights;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sidecar_views_and_lights_come_first_and_bad_ones_warn() {
        let dir = std::env::temp_dir().join(format!("raylab-sidecar-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let model = dir.join("hall.obj");
        std::fs::write(
            path_for(&model),
            r#"{ "views": [ { "name": "door", "eye": [0, 1, 5], "target": [0, 1, 0] },
                            { "name": "broken", "eye": [0, 0, 0], "target": [0, 0, 0] } ],
                 "lights": [ { "position": [0, 9, 0], "radius": 0.5 } ] }"#,
        )
        .unwrap();
        let mut scene = Scene::default();
        let mut warnings = Vec::new();
        apply(&model, &mut scene, &mut warnings);
        assert_eq!(scene.views.len(), 1);
        assert_eq!(scene.views[0].name, "door");
        assert_eq!(scene.views[0].camera.vfov_deg, 60.0);
        assert_eq!(scene.lights[0].radius, 0.5);
        assert_eq!(warnings.len(), 1, "{warnings:?}");
        std::fs::write(path_for(&model), "{ \"views\": 3 }").unwrap();
        let mut warnings = Vec::new();
        apply(&model, &mut Scene::default(), &mut warnings);
        assert!(warnings[0].contains("hall.views.json"), "{warnings:?}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
