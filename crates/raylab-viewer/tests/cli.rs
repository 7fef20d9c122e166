//! Bad command lines and files: a clear error naming the flag or file, exit code 1, before any window opens
//! (so these run without a display or GPU).

use std::process::Command;

fn raylab(args: &[&str]) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_raylab")).args(args).output().expect("the viewer starts");
    (out.status.code().unwrap_or(-1), String::from_utf8_lossy(&out.stderr).into_owned())
}

#[test]
fn bad_input_is_a_named_error() {
    let dir = tempfile::tempdir().unwrap();
    let garbage = dir.path().join("garbage.json");
    std::fs::write(&garbage, "not a path").unwrap();
    let garbage = garbage.to_str().unwrap();
    let cases: [(&[&str], &str); 9] = [
        (&["--scene", "no/such/file.obj", "--frames", "1", "--headless"], "file.obj"),
        (&["--scene", "nowhere", "--frames", "1", "--headless"], "nowhere"),
        (&["--method", "reference"], "--method reference"),
        (&["--method", "warp"], "warp"),
        (&["--screenshot", "x.png"], "--screenshot needs --frames"),
        (&["--headless"], "--headless needs --frames"),
        (&["--scale", "10"], "--scale"),
        (&["--width", "0"], "--width"),
        (&["--play", garbage, "--frames", "1", "--headless"], "garbage.json"),
    ];
    for (args, needle) in cases {
        let (code, err) = raylab(args);
        assert_ne!(code, 0, "{args:?} should fail");
        assert!(err.contains(needle), "{args:?}: the error should name '{needle}':\n{err}");
    }
}
