//! The glTF 2.0 loader on files written by the tests (no downloaded assets): .gltf with an external .bin,
//! .glb, data URIs, the node hierarchy, strips and fans, materials, cameras and lights; and a specific error
//! for each kind of bad or hostile file.

use std::path::{Path, PathBuf};

use base64::Engine as _;
use glam::Vec3;
use raylab_core::scene::MaterialKind;
use raylab_scene::{Loaded, SceneError, gltf_model};
use serde_json::{Value, json};

/// A unit quad in the xy plane: 4 positions, normals and UVs (f32) and 6 u16 indices, packed in one buffer.
fn quad_buffer() -> Vec<u8> {
    let mut b = Vec::new();
    for p in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]] {
        p.iter().for_each(|x| b.extend(x.to_le_bytes()));
    }
    for _ in 0..4 {
        [0.0f32, 0.0, 1.0].iter().for_each(|x| b.extend(x.to_le_bytes()));
    }
    for uv in [[0.0f32, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]] {
        uv.iter().for_each(|x| b.extend(x.to_le_bytes()));
    }
    for i in [0u16, 1, 2, 0, 2, 3] {
        b.extend(i.to_le_bytes());
    }
    b
}

/// The glTF document for the quad: `buffer` is the buffer object; `extra` is merged in at the top level.
fn doc(buffer: Value, extra: Value) -> Value {
    let mut d = json!({
        "asset": { "version": "2.0" },
        "buffers": [buffer],
        "bufferViews": [
            { "buffer": 0, "byteOffset": 0, "byteLength": 48 },
            { "buffer": 0, "byteOffset": 48, "byteLength": 48 },
            { "buffer": 0, "byteOffset": 96, "byteLength": 32 },
            { "buffer": 0, "byteOffset": 128, "byteLength": 12 }
        ],
        "accessors": [
            { "bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0] },
            { "bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3" },
            { "bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC2" },
            { "bufferView": 3, "componentType": 5123, "count": 6, "type": "SCALAR" }
        ],
        "meshes": [{ "primitives": [{ "attributes": { "POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2 }, "indices": 3, "material": 0 }] }],
        "materials": [{ "name": "paint", "pbrMetallicRoughness": { "baseColorFactor": [1, 0.5, 0.25, 1], "metallicFactor": 0, "roughnessFactor": 0.9 } }],
        "nodes": [
            { "name": "parent", "translation": [10, 0, 0], "scale": [2, 2, 2], "children": [1] },
            { "name": "child", "mesh": 0, "translation": [0, 0, -1] }
        ],
        "scenes": [{ "nodes": [0] }],
        "scene": 0
    });
    if let (Value::Object(d), Value::Object(e)) = (&mut d, extra) {
        d.extend(e);
    }
    d
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::create_dir_all(p.parent().unwrap()).unwrap();
    std::fs::write(&p, bytes).unwrap();
    p
}

fn glb(json: &Value, bin: &[u8]) -> Vec<u8> {
    let mut j = serde_json::to_vec(json).unwrap();
    while !j.len().is_multiple_of(4) {
        j.push(b' ');
    }
    let mut b = bin.to_vec();
    while !b.len().is_multiple_of(4) {
        b.push(0);
    }
    let total = 12 + 8 + j.len() + 8 + b.len();
    let mut out = Vec::new();
    out.extend(b"glTF");
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((j.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(j);
    out.extend((b.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(b);
    out
}

fn data_uri(bytes: &[u8]) -> String {
    format!("data:application/octet-stream;base64,{}", base64::engine::general_purpose::STANDARD.encode(bytes))
}

fn png_bytes(rgb: [u8; 3]) -> Vec<u8> {
    let mut out = Vec::new();
    image::RgbImage::from_pixel(2, 2, image::Rgb(rgb))
        .write_to(&mut std::io::Cursor::new(&mut out), image::ImageFormat::Png)
        .unwrap();
    out
}

fn check_quad(l: &Loaded) {
    let s = &l.scene;
    assert_eq!(s.triangle_count(), 2);
    // parent: translate (10,0,0) and scale 2; child: translate (0,0,-1) in the parent's frame.
    let b = s.bounds();
    assert!(
        (b.min - Vec3::new(10.0, 0.0, -2.0)).length() < 1e-6 && (b.max - Vec3::new(12.0, 2.0, -2.0)).length() < 1e-6,
        "{b:?}"
    );
    assert_eq!(s.normals[0], Vec3::Z);
    assert_eq!(s.uvs[0], glam::Vec2::new(0.0, 0.0), "glTF v flipped to raylab's v-up");
    assert_eq!(s.materials[0].name, "paint");
    assert_eq!(s.materials[0].base_color, Vec3::new(1.0, 0.5, 0.25));
    assert_eq!(s.materials[0].kind, MaterialKind::Diffuse);
}

#[test]
fn gltf_with_an_external_bin_glb_and_data_uris_load_the_same_quad() {
    let dir = tempfile::tempdir().unwrap();
    let bin = quad_buffer();
    write(dir.path(), "data/quad.bin", &bin);
    let external = doc(json!({ "uri": "data/quad.bin", "byteLength": bin.len() }), json!({}));
    let l = gltf_model::load(&write(dir.path(), "quad.gltf", &serde_json::to_vec(&external).unwrap())).unwrap();
    check_quad(&l);
    assert!(l.warnings.is_empty(), "{:?}", l.warnings);
    let packed = doc(json!({ "byteLength": bin.len() }), json!({}));
    check_quad(&gltf_model::load(&write(dir.path(), "quad.glb", &glb(&packed, &bin))).unwrap());
    let embedded = doc(json!({ "uri": data_uri(&bin), "byteLength": bin.len() }), json!({}));
    check_quad(
        &gltf_model::load(&write(dir.path(), "embedded.gltf", &serde_json::to_vec(&embedded).unwrap())).unwrap(),
    );
    // Through the scene source too.
    let l =
        raylab_scene::load(&raylab_scene::SceneSource::parse(dir.path().join("quad.glb").to_str().unwrap())).unwrap();
    check_quad(&l);
}

#[test]
fn textures_materials_cameras_and_lights() {
    let dir = tempfile::tempdir().unwrap();
    let bin = quad_buffer();
    write(dir.path(), "tex/red.png", &png_bytes([255, 0, 0]));
    let extra = json!({
        "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_transmission", "KHR_materials_ior"],
        "images": [{ "uri": "tex/red.png" }, { "uri": data_uri(&png_bytes([128, 128, 255])) }],
        "samplers": [{ "wrapS": 33071, "wrapT": 33071 }],
        "textures": [{ "source": 0, "sampler": 0 }, { "source": 1 }],
        "materials": [
            { "name": "tiles", "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 }, "roughnessFactor": 1.0, "metallicFactor": 0 }, "normalTexture": { "index": 1 } },
            { "name": "chrome", "pbrMetallicRoughness": { "metallicFactor": 1.0, "roughnessFactor": 0.1 } },
            { "name": "glass", "extensions": { "KHR_materials_transmission": { "transmissionFactor": 0.9 }, "KHR_materials_ior": { "ior": 1.33 } } },
            { "name": "veil", "alphaMode": "BLEND", "pbrMetallicRoughness": { "baseColorFactor": [1, 1, 1, 0.25] } }
        ],
        "meshes": [
            { "primitives": [{ "attributes": { "POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2 }, "indices": 3, "material": 0 }] },
            { "primitives": [{ "attributes": { "POSITION": 0 }, "indices": 3, "material": 1 }] },
            { "primitives": [{ "attributes": { "POSITION": 0 }, "mode": 5, "material": 2 }] },
            { "primitives": [{ "attributes": { "POSITION": 0 }, "mode": 6, "material": 3 }, { "attributes": { "POSITION": 0 }, "mode": 1 }] }
        ],
        "cameras": [{ "name": "front", "type": "perspective", "perspective": { "yfov": 0.8, "znear": 0.1 } }],
        "extensions": { "KHR_lights_punctual": { "lights": [{ "type": "point", "color": [1, 0.5, 0.5], "intensity": 10 }, { "type": "directional" }] } },
        "nodes": [
            { "mesh": 0 }, { "mesh": 1, "translation": [0, 0, 1] }, { "mesh": 2, "translation": [0, 0, 2] }, { "mesh": 3, "translation": [0, 0, 3] },
            { "camera": 0, "translation": [0.5, 0.5, 5] },
            { "extensions": { "KHR_lights_punctual": { "light": 0 } }, "translation": [0, 4, 0] },
            { "extensions": { "KHR_lights_punctual": { "light": 1 } } }
        ],
        "scenes": [{ "nodes": [0, 1, 2, 3, 4, 5, 6] }]
    });
    let d = doc(json!({ "byteLength": bin.len() }), extra);
    let Loaded { scene, warnings } = gltf_model::load(&write(dir.path(), "all.glb", &glb(&d, &bin))).unwrap();
    let m = |n: &str| scene.materials.iter().find(|m| m.name == n).unwrap_or_else(|| panic!("no material {n}"));
    let tiles = m("tiles");
    let base = &scene.textures[tiles.diffuse_texture.unwrap() as usize];
    assert_eq!(base.texels[0], Vec3::X, "sRGB red is linear red");
    assert_eq!(base.wrap, raylab_core::scene::WrapMode::Clamp, "the sampler's CLAMP_TO_EDGE");
    let normal = &scene.textures[tiles.normal_texture.unwrap() as usize];
    assert!((normal.texels[0].x - 128.0 / 255.0).abs() < 1e-6, "normal maps stay linear");
    assert_eq!(m("chrome").kind, MaterialKind::Reflective);
    assert_eq!(m("glass").kind, MaterialKind::TransparentReflective);
    assert!((m("glass").ior - 1.33).abs() < 1e-6 && (m("glass").transmit_blend - 0.9).abs() < 1e-6);
    assert_eq!(m("veil").kind, MaterialKind::Transparent);
    assert!((m("veil").transmit_blend - 0.75).abs() < 1e-6);
    // quad 2 + quad 2 + strip of 4 indices (2) + fan of 4 (2); the line primitive is skipped with a warning.
    assert_eq!(scene.triangle_count(), 8);
    assert!(warnings.iter().any(|w| w.contains("point or line")), "{warnings:?}");
    assert!(warnings.iter().any(|w| w.contains("directional")), "{warnings:?}");
    assert_eq!(scene.views.len(), 1);
    assert_eq!(scene.views[0].name, "front");
    assert_eq!(scene.views[0].camera.eye, Vec3::new(0.5, 0.5, 5.0));
    assert!((scene.views[0].camera.vfov_deg - 0.8f32.to_degrees()).abs() < 1e-4);
    assert_eq!(scene.lights.len(), 1);
    assert_eq!(scene.lights[0].position, Vec3::new(0.0, 4.0, 0.0));
    assert_eq!(scene.lights[0].color, Vec3::new(1.0, 0.5, 0.5));
}

#[test]
fn a_missing_image_is_a_warning_and_a_checker() {
    let dir = tempfile::tempdir().unwrap();
    let bin = quad_buffer();
    let extra = json!({
        "images": [{ "uri": "gone.png" }, { "uri": "/etc/passwd" }],
        "textures": [{ "source": 0 }, { "source": 1 }],
        "materials": [{ "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 } }, "normalTexture": { "index": 1 } }]
    });
    let d = doc(json!({ "byteLength": bin.len() }), extra);
    let Loaded { scene, warnings } = gltf_model::load(&write(dir.path(), "m.glb", &glb(&d, &bin))).unwrap();
    assert_eq!(warnings.len(), 2, "{warnings:?}");
    assert!(warnings[0].contains("gone.png") && warnings[1].contains("absolute"), "{warnings:?}");
    assert!(scene.textures.iter().all(|t| t.width == 8));
}

fn err(dir: &Path, name: &str, bytes: &[u8]) -> String {
    match gltf_model::load(&write(dir, name, bytes)) {
        Ok(_) => panic!("{name} loaded"),
        Err(e @ (SceneError::Invalid { .. } | SceneError::Refused { .. } | SceneError::Empty { .. })) => e.to_string(),
        Err(e) => panic!("{name}: unexpected error kind {e:?}"),
    }
}

#[test]
fn bad_and_hostile_files_give_specific_errors() {
    let dir = tempfile::tempdir().unwrap();
    let bin = quad_buffer();
    let packed = |extra: Value| glb(&doc(json!({ "byteLength": bin.len() }), extra), &bin);
    let uri = |u: &str| serde_json::to_vec(&doc(json!({ "uri": u, "byteLength": bin.len() }), json!({}))).unwrap();
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        ("abs.gltf", uri("/etc/passwd"), "absolute path"),
        ("url.gltf", uri("https://example.com/x.bin"), "is a URL"),
        ("up.gltf", uri("../../x.bin"), "leaves the model's folder"),
        ("missing.gltf", uri("nothere.bin"), "nothere.bin"),
        ("magic.glb", b"GLTF\x02\0\0\0".to_vec(), "not a GLB file"),
        ("json.gltf", b"{ \"asset\": ".to_vec(), "json.gltf"),
        ("truncated.glb", glb(&doc(json!({ "byteLength": bin.len() + 100 }), json!({})), &bin), "truncated"),
        (
            "index.glb",
            packed(json!({ "accessors": [
                { "bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0] },
                { "bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3" },
                { "bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC2" },
                { "bufferView": 3, "componentType": 5123, "count": 6, "type": "SCALAR" }
            ], "bufferViews": [
                { "buffer": 0, "byteOffset": 0, "byteLength": 48 },
                { "buffer": 0, "byteOffset": 48, "byteLength": 48 },
                { "buffer": 0, "byteOffset": 96, "byteLength": 32 },
                { "buffer": 0, "byteOffset": 48, "byteLength": 12 }
            ] })),
            "out of range",
        ),
        (
            "overrun.glb",
            packed(json!({ "bufferViews": [
                { "buffer": 0, "byteOffset": 120, "byteLength": 48 },
                { "buffer": 0, "byteOffset": 48, "byteLength": 48 },
                { "buffer": 0, "byteOffset": 96, "byteLength": 32 },
                { "buffer": 0, "byteOffset": 128, "byteLength": 12 }
            ] })),
            "past its buffer",
        ),
        (
            "points.glb",
            packed(json!({ "meshes": [{ "primitives": [{ "attributes": { "POSITION": 0 }, "mode": 0 }] }] })),
            "no triangle primitives",
        ),
    ];
    let whole = packed(json!({}));
    let cases: Vec<(&str, Vec<u8>, &str)> =
        cases.into_iter().chain([("cut.glb", whole[..whole.len() / 2].to_vec(), "cut.glb")]).collect();
    for (name, bytes, want) in &cases {
        let e = err(dir.path(), name, bytes);
        assert!(e.contains(want), "{name}: '{e}' should contain '{want}'");
        assert!(e.contains(name.split('.').next().unwrap()), "{name}: the error names the file: {e}");
    }
    // NaN positions: the first coordinate's bits replaced.
    let mut nan = bin.clone();
    nan[0..4].copy_from_slice(&f32::NAN.to_le_bytes());
    let d = glb(&doc(json!({ "byteLength": nan.len() }), json!({})), &nan);
    let e = err(dir.path(), "nan.glb", &d);
    assert!(e.contains("not finite"), "{e}");
}
