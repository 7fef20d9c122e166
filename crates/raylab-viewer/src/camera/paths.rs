//! Camera paths: recorded while flying, saved as JSON, played back one key per traced frame so that every
//! method and setting traces exactly the same sequence of views (reproducible comparisons).

use std::path::Path;
use std::time::Instant;

use raylab_core::scene::Camera;
use serde::{Deserialize, Serialize};

/// Keys recorded per second while flying.
pub const RECORD_HZ: f64 = 30.0;

/// A recorded flight.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CameraPath {
    /// The scene it was recorded in (a reminder; playing it elsewhere is allowed).
    pub scene: String,
    /// One camera per key, [`RECORD_HZ`] keys per second of flight.
    pub keys: Vec<Camera>,
}

impl CameraPath {
    /// Writes the path as pretty JSON; the error names the file.
    pub fn save(&self, path: &Path) -> Result<(), String> {
        let json = serde_json::to_string_pretty(self).map_err(|e| format!("{}: {e}", path.display()))?;
        std::fs::write(path, json).map_err(|e| format!("cannot write {}: {e}", path.display()))
    }

    /// Reads and checks a path file: at least one key, every camera valid. The error names the file.
    pub fn load(path: &Path) -> Result<Self, String> {
        let text = std::fs::read_to_string(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
        let p: CameraPath =
            serde_json::from_str(&text).map_err(|e| format!("{}: not a camera path: {e}", path.display()))?;
        if p.keys.is_empty() {
            return Err(format!("{}: the camera path has no keys", path.display()));
        }
        if let Some((i, e)) = p.keys.iter().enumerate().find_map(|(i, c)| c.validate().err().map(|e| (i, e))) {
            return Err(format!("{}: key {i}: {e}", path.display()));
        }
        Ok(p)
    }
}

/// Records a path at [`RECORD_HZ`].
pub struct Recorder {
    started: Instant,
    path: CameraPath,
}

impl Recorder {
    /// Starts recording in `scene` at `camera`.
    pub fn start(scene: &str, camera: Camera) -> Self {
        Self { started: Instant::now(), path: CameraPath { scene: scene.to_string(), keys: vec![camera] } }
    }

    /// Adds keys up to now, repeating `camera` for the keys that fell due since the last call.
    pub fn tick(&mut self, camera: Camera) {
        let due = (self.started.elapsed().as_secs_f64() * RECORD_HZ) as usize + 1;
        while self.path.keys.len() < due {
            self.path.keys.push(camera);
        }
    }

    /// Keys so far.
    pub fn len(&self) -> usize {
        self.path.keys.len()
    }

    /// Ends the recording.
    pub fn finish(self) -> CameraPath {
        self.path
    }
}

/// Plays a path back, one key per traced frame.
pub struct Player {
    path: CameraPath,
    next: usize,
    looping: bool,
}

impl Player {
    /// Plays `path` from its first key; `looping` starts over at the end.
    pub fn new(path: CameraPath, looping: bool) -> Self {
        Self { path, next: 0, looping }
    }

    /// The camera of the next traced frame, or `None` when a non-looping path has ended.
    pub fn advance(&mut self) -> Option<Camera> {
        if self.next >= self.path.keys.len() {
            if !self.looping {
                return None;
            }
            self.next = 0;
        }
        let c = self.path.keys[self.next];
        self.next += 1;
        Some(c)
    }

    /// `(keys played, keys in all)`.
    pub fn progress(&self) -> (usize, usize) {
        (self.next, self.path.keys.len())
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    fn cam(z: f32) -> Camera {
        Camera::look_at(Vec3::new(0.0, 0.0, z), Vec3::ZERO, Vec3::Y, 50.0)
    }

    #[test]
    fn save_load_round_trip_and_playback() {
        let dir = std::env::temp_dir().join(format!("raylab-path-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("p.json");
        let p = CameraPath { scene: "atrium".into(), keys: vec![cam(1.0), cam(2.0)] };
        p.save(&file).unwrap();
        let q = CameraPath::load(&file).unwrap();
        assert_eq!(p, q);
        let mut once = Player::new(q.clone(), false);
        assert_eq!(once.advance(), Some(cam(1.0)));
        assert_eq!(once.advance(), Some(cam(2.0)));
        assert_eq!(once.advance(), None);
        let mut looped = Player::new(q, true);
        looped.advance();
        looped.advance();
        assert_eq!(looped.advance(), Some(cam(1.0)));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn bad_files_are_named_errors() {
        let dir = std::env::temp_dir().join(format!("raylab-badpath-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let missing = dir.join("missing.json");
        assert!(CameraPath::load(&missing).unwrap_err().contains("missing.json"));
        let garbage = dir.join("garbage.json");
        std::fs::write(&garbage, "{ not json").unwrap();
        assert!(CameraPath::load(&garbage).unwrap_err().contains("garbage.json"));
        let empty = dir.join("empty.json");
        std::fs::write(&empty, r#"{"scene":"x","keys":[]}"#).unwrap();
        assert!(CameraPath::load(&empty).unwrap_err().contains("no keys"));
        let bad = dir.join("bad.json");
        let mut c = cam(1.0);
        c.target = c.eye;
        CameraPath { scene: "x".into(), keys: vec![cam(1.0), c] }.save(&bad).unwrap();
        assert!(CameraPath::load(&bad).unwrap_err().contains("key 1"));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn recorder_keeps_the_start() {
        let mut r = Recorder::start("atrium", cam(1.0));
        r.tick(cam(2.0));
        assert!(r.len() >= 1);
        assert_eq!(r.finish().keys[0], cam(1.0));
    }
}
