//! The built-in scenes: sizes like the thesis's scenes, fast and deterministic generation, usable views and
//! lights, and no dropped triangles.

use std::time::Instant;

use raylab_scene::builtin::{self, Detail};

#[test]
fn builtins_have_the_advertised_size_views_and_lights() {
    let expected = [
        ("atrium", 60_000, 80_000),
        ("arena", 11_000, 15_000),
        ("kitchen", 95_000, 125_000),
        ("forest", 160_000, 190_000),
    ];
    for (name, lo, hi) in expected {
        let t0 = Instant::now();
        let scene = builtin::build(name, Detail::Full).unwrap();
        let secs = t0.elapsed().as_secs_f64();
        let n = scene.triangle_count();
        assert!((lo..=hi).contains(&n), "{name}: {n} triangles, expected {lo}..{hi}");
        assert!(secs < 2.0, "{name}: generated in {secs:.2} s");
        assert_eq!(scene.dropped.total(), 0, "{name}: {:?}", scene.dropped);
        assert!(!scene.views.is_empty() && !scene.lights.is_empty(), "{name}");
        for v in &scene.views {
            assert_eq!(v.camera.validate(), Ok(()), "{name}/{}", v.name);
        }
        assert_eq!(scene.normals.len(), scene.positions.len(), "{name} has per-vertex normals");
    }
}

#[test]
fn builtins_are_deterministic() {
    for name in builtin::names() {
        let a = builtin::build(name, Detail::Test).unwrap();
        let b = builtin::build(name, Detail::Test).unwrap();
        assert_eq!(a.positions, b.positions, "{name}");
        assert_eq!(a.triangles, b.triangles, "{name}");
    }
}

#[test]
fn unknown_names_list_the_builtins() {
    let e = raylab_scene::load(&raylab_scene::SceneSource::Builtin("sponzaa".into())).unwrap_err().to_string();
    for name in builtin::names() {
        assert!(e.contains(name), "{e}");
    }
}
