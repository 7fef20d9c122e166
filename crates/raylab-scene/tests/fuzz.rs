//! Random and mutated files through the loaders (OBJ, MTL, glTF and GLB): whatever the bytes, loading returns a scene or an error and
//! never panics or hangs. `RAYLAB_FUZZ_CASES` sets the number of cases per target (CI runs more).

use std::path::Path;

use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};

const OBJ: &str = "mtllib m.mtl\n# a model\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\n\
g quad\nusemtl a\nf 1/1/1 2/2/1 3/3/1 4/1/1\no tri\nusemtl b\nf -4 -3 -2\nf 1//1 3//1 4//1\n";
const MTL: &str = "newmtl a\nKd 0.5 0.5 0.5\nKs 1 1 1\nNs 20\nillum 2\nmap_Kd t.png\nbump -bm 1 t.png\n\
newmtl b\nNi 1.5\nd 0.5\nillum 7\nnorm t.png\n";
/// Tokens the mutator splices in: numbers at the edges of what parses, index forms, keywords, paths.
const TOKENS: &[&str] = &[
    " ",
    "\n",
    "/",
    "//",
    "-1",
    "0",
    "99999999999",
    "-99999999999",
    "nan",
    "inf",
    "1e39",
    "-0",
    "f ",
    "v ",
    "vt ",
    "vn ",
    "usemtl ",
    "mtllib ",
    "newmtl ",
    "map_Kd ",
    "../",
    "/etc/passwd",
    "http://x/",
    "\\",
    "\0",
    "é",
    "\r\n",
];

fn cases() -> u32 {
    std::env::var("RAYLAB_FUZZ_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(300)
}

/// Applies `edits` (position, action) to `seed`: delete a byte, flip bits, or splice a token in.
fn mutate(seed: &str, edits: &[(usize, u8, usize)]) -> Vec<u8> {
    let mut b = seed.as_bytes().to_vec();
    for &(pos, action, token) in edits {
        if b.is_empty() {
            b.push(b'v');
        }
        let at = pos % b.len();
        match action % 3 {
            0 => {
                b.remove(at);
            }
            1 => b[at] ^= 1 << (token % 8),
            _ => {
                let t = TOKENS[token % TOKENS.len()].as_bytes();
                b.splice(at..at, t.iter().copied());
            }
        }
    }
    b
}

fn write_model(dir: &Path, obj: &[u8], mtl: &[u8]) -> std::path::PathBuf {
    std::fs::write(dir.join("m.mtl"), mtl).unwrap();
    let p = dir.join("m.obj");
    std::fs::write(&p, obj).unwrap();
    p
}

/// A small glTF document (a quad in a data-URI buffer, a material, a camera, a light) to mutate.
fn gltf_seed() -> String {
    let mut bin = Vec::new();
    for v in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 1.0, 0.0] {
        bin.extend(v.to_le_bytes());
    }
    for i in [0u16, 1, 2, 0, 2, 3] {
        bin.extend(i.to_le_bytes());
    }
    use base64::Engine as _;
    let uri =
        format!("data:application/octet-stream;base64,{}", base64::engine::general_purpose::STANDARD.encode(&bin));
    format!(
        r#"{{"asset":{{"version":"2.0"}},"buffers":[{{"uri":"{uri}","byteLength":60}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":12}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
{{"bufferView":1,"componentType":5123,"count":6,"type":"SCALAR"}}],
"materials":[{{"pbrMetallicRoughness":{{"baseColorFactor":[1,1,1,0.5],"metallicFactor":1}},"alphaMode":"BLEND"}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1,"material":0}}]}}],
"cameras":[{{"type":"perspective","perspective":{{"yfov":0.7,"znear":0.1}}}}],
"nodes":[{{"mesh":0,"children":[1],"scale":[2,2,2]}},{{"camera":0,"translation":[0,0,3]}}],
"scenes":[{{"nodes":[0]}}],"scene":0}}"#
    )
}

/// Wraps JSON and a binary chunk as GLB.
fn glb(json: &[u8], bin: &[u8]) -> Vec<u8> {
    let mut out = b"glTF".to_vec();
    out.extend(2u32.to_le_bytes());
    out.extend(((12 + 8 + json.len() + 8 + bin.len()) as u32).to_le_bytes());
    out.extend((json.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(json);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(bin);
    out
}

fn run_gltf(name: &str, file: &str, strategy: impl Strategy<Value = Vec<u8>>) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(file);
    let mut runner = TestRunner::new(Config { cases: cases(), failure_persistence: None, ..Config::default() });
    let result = runner.run(&strategy, |bytes| {
        std::fs::write(&path, &bytes).unwrap();
        let _ = raylab_scene::gltf_model::load(&path);
        Ok(())
    });
    if let Err(e) = result {
        panic!("{name}: {e}");
    }
}

#[test]
fn mutated_gltf_files_never_panic() {
    let seed = gltf_seed();
    run_gltf("glTF", "m.gltf", edits().prop_map(move |e| mutate(&seed, &e)));
}

#[test]
fn mutated_glb_files_never_panic() {
    let seed = gltf_seed();
    run_gltf(
        "GLB",
        "m.glb",
        (edits(), proptest::collection::vec(any::<u8>(), 0..64), any::<u16>()).prop_map(move |(e, bin, cut)| {
            let mut b = glb(&mutate(&seed, &e), &bin);
            // Sometimes cut the file short, header and all.
            if cut % 4 == 0 {
                b.truncate(cut as usize % (b.len() + 1));
            }
            b
        }),
    );
}

fn run(name: &str, strategy: impl Strategy<Value = (Vec<u8>, Vec<u8>)>) {
    let dir = tempfile::tempdir().unwrap();
    image::RgbImage::from_pixel(2, 2, image::Rgb([9, 9, 9])).save(dir.path().join("t.png")).unwrap();
    let mut runner = TestRunner::new(Config { cases: cases(), failure_persistence: None, ..Config::default() });
    let result = runner.run(&strategy, |(obj, mtl)| {
        let path = write_model(dir.path(), &obj, &mtl);
        // Either outcome is fine; a panic fails the property.
        let _ = raylab_scene::obj::load(&path);
        Ok(())
    });
    if let Err(e) = result {
        panic!("{name}: {e}");
    }
}

type Edits = Vec<(usize, u8, usize)>;

fn edits() -> impl Strategy<Value = Edits> {
    proptest::collection::vec((any::<usize>(), any::<u8>(), any::<usize>()), 1..12)
}

#[test]
fn mutated_obj_files_never_panic() {
    run("OBJ", edits().prop_map(|e| (mutate(OBJ, &e), MTL.as_bytes().to_vec())));
}

#[test]
fn mutated_mtl_files_never_panic() {
    run("MTL", edits().prop_map(|e| (OBJ.as_bytes().to_vec(), mutate(MTL, &e))));
}

#[test]
fn random_bytes_never_panic() {
    let bytes = proptest::collection::vec(any::<u8>(), 0..600);
    run("random", (bytes.clone(), bytes));
}
