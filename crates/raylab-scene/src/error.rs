//! Errors of scene loading.

use std::path::PathBuf;

/// Why a scene could not be produced. Every variant names the file (and line) or the name at fault.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// No built-in scene has this name.
    #[error("unknown scene '{name}' (built-in scenes: {valid}; or give a path to an .obj file)")]
    UnknownScene {
        /// The name asked for.
        name: String,
        /// The built-in names.
        valid: String,
    },
    /// The file could not be read.
    #[error("cannot read {}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// The file is not valid for its format.
    #[error("{}:{line}: {message}", path.display())]
    Parse {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// The file parsed but holds no usable triangle.
    #[error("{}: no usable triangles ({detail})", path.display())]
    Empty {
        /// The file.
        path: PathBuf,
        /// What was found instead.
        detail: String,
    },
    /// The file is not valid for its (non-line-based) format; the message says where.
    #[error("{}: {message}", path.display())]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// The file refers to another file it may not read (absolute, a URL, or outside the model's folder).
    #[error("{}: {why}", path.display())]
    Refused {
        /// The file holding the reference.
        path: PathBuf,
        /// Why it was refused.
        why: String,
    },
    /// The file's extension is not a supported format.
    #[error("{}: unsupported scene format (supported: .obj, .gltf, .glb)", path.display())]
    Format {
        /// The file.
        path: PathBuf,
    },
}
