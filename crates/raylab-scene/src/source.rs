//! Choosing a scene by built-in name or file path.

use std::path::{Path, PathBuf};

use crate::builtin::{self, Detail};
use crate::{Loaded, SceneError};

/// Where a scene comes from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum SceneSource {
    /// A built-in procedural scene.
    Builtin(String),
    /// An OBJ file.
    File(PathBuf),
}

impl SceneSource {
    /// Interprets a command-line value: a path when it ends in a known extension or contains a path
    /// separator, else a built-in name.
    pub fn parse(s: &str) -> Self {
        let looks_like_path = s.contains('/') || s.contains('\\') || Path::new(s).extension().is_some();
        if looks_like_path { Self::File(PathBuf::from(s)) } else { Self::Builtin(s.to_string()) }
    }
}

/// Loads a scene with its warnings, adding the views and lights of a sidecar file ([`crate::sidecar`]). A file
/// without lights or views gets none here; callers supply defaults.
pub fn load(source: &SceneSource) -> Result<Loaded, SceneError> {
    load_with_progress(source, &|_| {})
}

/// [`load`], reporting the share of the work done (0 to 1) to `progress` as it goes (for a progress bar).
pub fn load_with_progress(source: &SceneSource, progress: &dyn Fn(f32)) -> Result<Loaded, SceneError> {
    match source {
        SceneSource::Builtin(name) => builtin::build(name, Detail::Full)
            .map(|scene| Loaded { scene, warnings: Vec::new() })
            .ok_or_else(|| SceneError::UnknownScene { name: name.clone(), valid: builtin::names().join(", ") }),
        SceneSource::File(path) => {
            let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
            let mut loaded = match ext.as_deref() {
                Some("obj") => crate::obj::load_with_progress(path, progress),
                Some("gltf" | "glb") => crate::gltf_model::load(path),
                _ => Err(SceneError::Format { path: path.clone() }),
            }?;
            crate::sidecar::apply(path, &mut loaded.scene, &mut loaded.warnings);
            progress(1.0);
            Ok(loaded)
        }
    }
}
