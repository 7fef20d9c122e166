//! Random and mutated files through the loaders: whatever the bytes, loading returns a scene or an error and
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
