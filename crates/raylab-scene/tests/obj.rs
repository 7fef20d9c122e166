//! The full OBJ + MTL loader on small files written by the tests: every feature, and a specific error (file
//! and line) or warning for each kind of bad input, never a panic.

use std::path::{Path, PathBuf};

use glam::Vec3;
use raylab_core::scene::MaterialKind;
use raylab_scene::{Loaded, SceneError, obj};

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    if let Some(parent) = p.parent() {
        std::fs::create_dir_all(parent).unwrap();
    }
    std::fs::write(&p, text).unwrap();
    p
}

fn png(dir: &Path, name: &str, w: u32, h: u32, rgb: [u8; 3]) {
    let p = dir.join(name);
    std::fs::create_dir_all(p.parent().unwrap()).unwrap();
    image::RgbImage::from_pixel(w, h, image::Rgb(rgb)).save(p).unwrap();
}

fn load(dir: &Path, text: &str) -> Result<Loaded, SceneError> {
    obj::load(&write(dir, "model.obj", text))
}

const QUAD: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";

#[test]
fn polygons_groups_normals_and_uvs() {
    let dir = tempfile::tempdir().unwrap();
    let text = format!(
        "{QUAD}v 0 0 1\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\ng front\nf 1/1/1 2/2/1 3/3/1 4/4/1\no other\nf 1 2 5\n"
    );
    let s = load(dir.path(), &text).unwrap().scene;
    assert_eq!(s.triangle_count(), 3, "the quad is a fan of two, plus one triangle");
    assert_eq!(s.uvs.len(), s.positions.len());
    assert_eq!(s.normals.len(), s.positions.len());
    // The quad keeps the file's normal; the second object has none and gets its face normal.
    let quad_normal = s.normals[s.triangles[0].v[0] as usize];
    assert_eq!(quad_normal, Vec3::Z);
    let n = s.normals[s.triangles[2].v[0] as usize];
    assert!((n.abs() - Vec3::Y).length() < 1e-6, "{n}");
}

#[test]
fn smooth_normals_are_generated_with_a_crease() {
    let dir = tempfile::tempdir().unwrap();
    // A box corner: three faces at right angles keep hard normals.
    let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\n";
    let s = load(dir.path(), text).unwrap().scene;
    for t in 0..3 {
        let face = s.geometric_normal(t);
        for &v in &s.triangles[t].v {
            assert!((s.normals[v as usize] - face).length() < 1e-6);
        }
    }
}

#[test]
fn materials_map_onto_the_fixed_function_kinds() {
    let dir = tempfile::tempdir().unwrap();
    png(dir.path(), "textures/wall.png", 4, 2, [255, 128, 0]);
    png(dir.path(), "textures/bumps.png", 4, 4, [100, 100, 100]);
    png(dir.path(), "textures/normals.png", 2, 2, [128, 128, 255]);
    write(
        dir.path(),
        "materials/lib.mtl",
        "newmtl matte\nKd 0.5 0.25 1\nmap_Kd ../textures/wall.png\nbump -bm 0.5 ../textures/bumps.png\n\
         newmtl shiny\nKd 1 1 1\nKs 0.5 0.5 0.5\nNs 64\nillum 2\nnorm ../textures/normals.png\n\
         newmtl mirror\nKs 0.9 0.9 0.9\nillum 3\n\
         newmtl glass\nNi 1.33\nd 0.2\nillum 7\n\
         newmtl veil\nd 0.5\nmap_Kd -clamp on ../textures/normals.png\n",
    );
    let mut text = String::from("mtllib materials/lib.mtl\n");
    for (k, m) in ["matte", "shiny", "mirror", "glass", "veil"].iter().enumerate() {
        let o = 3 * k;
        text += &format!("v {o} 0 0\nv {} 0 0\nv {o} 1 0\nusemtl {m}\nf -3 -2 -1\n", o + 1);
    }
    let Loaded { scene, warnings } = load(dir.path(), &text).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    let m = |name: &str| scene.materials.iter().find(|m| m.name == name).unwrap();
    assert_eq!(m("matte").kind, MaterialKind::Diffuse);
    assert_eq!(m("matte").base_color, Vec3::new(0.5, 0.25, 1.0));
    let wall = &scene.textures[m("matte").diffuse_texture.unwrap() as usize];
    assert_eq!((wall.width, wall.height), (4, 2));
    assert!((wall.texels[0].x - 1.0).abs() < 1e-6 && (wall.texels[0].y - 0.2158).abs() < 1e-3, "sRGB 128 -> 0.216");
    let bumps = &scene.textures[m("matte").normal_texture.unwrap() as usize];
    assert!((bumps.texels[5] - Vec3::new(0.5, 0.5, 1.0)).length() < 1e-6, "a flat height map is a flat normal map");
    assert_eq!(m("shiny").kind, MaterialKind::Specular);
    assert_eq!((m("shiny").phong_exponent, m("shiny").specular_blend), (64.0, 0.5));
    assert!(m("shiny").normal_texture.is_some());
    assert_eq!(m("mirror").kind, MaterialKind::Reflective);
    assert!((m("mirror").reflect_blend - 0.9).abs() < 1e-6);
    assert_eq!(m("glass").kind, MaterialKind::TransparentReflective);
    assert!((m("glass").ior - 1.33).abs() < 1e-6 && (m("glass").transmit_blend - 0.8).abs() < 1e-6);
    assert_eq!(m("veil").kind, MaterialKind::Transparent);
    let clamped = &scene.textures[m("veil").diffuse_texture.unwrap() as usize];
    assert_eq!(clamped.wrap, raylab_core::scene::WrapMode::Clamp, "-clamp on");
    assert_eq!(wall.wrap, raylab_core::scene::WrapMode::Repeat);
}

#[test]
fn a_missing_texture_is_a_warning_and_a_checker() {
    let dir = tempfile::tempdir().unwrap();
    write(
        dir.path(),
        "m.mtl",
        "newmtl a\nmap_Kd gone.png\nnewmtl b\nmap_Kd /etc/passwd\nnewmtl c\nmap_Kd ../../outside.png\n",
    );
    let text = format!("mtllib m.mtl\n{QUAD}usemtl a\nf 1 2 3\nusemtl b\nf 1 3 4\nusemtl c\nf 2 3 4\n");
    let Loaded { scene, warnings } = load(dir.path(), &text).unwrap();
    assert_eq!(warnings.len(), 3, "{warnings:?}");
    assert!(warnings[0].contains("gone.png"));
    assert!(warnings[1].contains("/etc/passwd") && warnings[1].contains("absolute"));
    assert!(warnings[2].contains("outside.png") && warnings[2].contains("leaves"));
    assert!(scene.textures.iter().all(|t| t.width == 8), "checker placeholders");
}

#[test]
fn a_missing_material_library_is_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let Loaded { scene, warnings } =
        load(dir.path(), &format!("mtllib nowhere.mtl\n{QUAD}usemtl x\nf 1 2 3\n")).unwrap();
    assert_eq!(scene.triangle_count(), 1);
    assert!(warnings.iter().any(|w| w.contains("nowhere.mtl")), "{warnings:?}");
}

/// Each kind of bad file: the error names the file and, for line errors, the line.
#[test]
fn bad_files_give_specific_errors() {
    let dir = tempfile::tempdir().unwrap();
    let cases: &[(&str, &str)] = &[
        ("v 0 0 0\nv 1 x 0\n", "model.obj:2: bad vertex coordinate 'x'"),
        ("v 0 0 nan\n", "model.obj:1: vertex coordinate 'nan' is not finite"),
        ("v 0 0 inf\n", "model.obj:1: vertex coordinate 'inf' is not finite"),
        ("v 0 0\n", "model.obj:1: vertex needs 3 coordinates"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n", "model.obj:4: vertex index 9 out of range"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/5 2 3\n", "model.obj:4: texture index 5 out of range"),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1//2 2 3\n", "model.obj:4: normal index 2 out of range"),
        ("v 0 0 0\nv 1 0 0\nf 1 2\n", "model.obj:3: a face needs at least 3 corners"),
        ("v 0 0 0\nf 0 1 1\n", "model.obj:2: vertex index 0 out of range"),
        ("v 0 0 0\nv 1 0 0\nv 2 0 0\n", "model.obj: no usable triangles"),
        ("v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n", "model.obj: no usable triangles"),
        ("# nothing\n", "model.obj: no usable triangles"),
        ("mtllib /etc/lib.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "absolute path"),
        ("mtllib ../up.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "leaves the model's folder"),
        ("mtllib http://example.com/x.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "is a URL"),
    ];
    for (text, want) in cases {
        let err = load(dir.path(), text).err().unwrap_or_else(|| panic!("{text:?} loaded"));
        // The kind of error: a line for malformed records, empty for no triangles, refused for references.
        let kind_ok = match &err {
            SceneError::Parse { line, .. } => *line > 0 && want.starts_with("model.obj:"),
            SceneError::Empty { .. } => want.contains("no usable triangles"),
            SceneError::Refused { .. } => ["absolute path", "leaves", "URL"].iter().any(|w| want.contains(w)),
            _ => false,
        };
        let e = err.to_string();
        assert!(kind_ok, "{text:?}: unexpected error kind {err:?}");
        assert!(e.contains(want), "{text:?}: error '{e}' should contain '{want}'");
        assert!(e.contains("model.obj"), "{e}");
    }
    let e = obj::load(&dir.path().join("absent.obj")).unwrap_err();
    assert!(matches!(e, SceneError::Io { .. }) && e.to_string().contains("absent.obj"), "{e}");
    std::fs::write(dir.path().join("binary.obj"), [0x76, 0x20, 0xff, 0xfe, 0x0a]).unwrap();
    let e = obj::load(&dir.path().join("binary.obj")).unwrap_err().to_string();
    assert!(e.contains("binary.obj:1") && e.contains("UTF-8"), "{e}");
}

/// A sidecar beside the model names views (picked with `--view` and listed in the viewer) and lights.
#[test]
fn a_sidecar_file_adds_named_views_and_lights() {
    let dir = tempfile::tempdir().unwrap();
    let model = write(dir.path(), "hall.obj", &format!("{QUAD}f 1 2 3 4\n"));
    write(
        dir.path(),
        "hall.views.json",
        r#"{ "views": [ { "name": "door", "eye": [0.5, 0.5, 3], "target": [0.5, 0.5, 0], "fov": 40 } ], "lights": [ { "position": [0, 0, 2], "radius": 0.25 } ] }"#,
    );
    let source = raylab_scene::SceneSource::parse(model.to_str().unwrap());
    let Loaded { scene, warnings } = raylab_scene::load(&source).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    assert_eq!(scene.view("door").unwrap().camera.vfov_deg, 40.0);
    assert_eq!(scene.lights[0].radius, 0.25);
}
