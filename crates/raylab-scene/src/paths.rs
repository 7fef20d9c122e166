//! Resolving file references inside a model (MTL libraries, textures, glTF buffers and images) without
//! letting a model reach outside its own folder.

use std::path::{Component, Path, PathBuf};

/// Resolves `reference`, as written in a file of the model rooted at `root` (the folder of the file the
/// user opened), relative to `base` (the folder of the file that holds the reference). Absolute paths,
/// URLs and references that climb out of `root` are refused with the reason.
pub fn resolve(root: &Path, base: &Path, reference: &str) -> Result<PathBuf, String> {
    let r = reference.trim();
    if r.is_empty() {
        return Err("empty file reference".into());
    }
    if r.contains("://") || r.starts_with("data:") {
        return Err(format!("'{r}' is a URL; only files next to the model are read"));
    }
    let p = Path::new(r);
    let windows_drive = r.len() >= 2 && r.as_bytes()[1] == b':' && r.as_bytes()[0].is_ascii_alphabetic();
    if p.has_root() || p.is_absolute() || windows_drive || r.starts_with('\\') {
        return Err(format!("'{r}' is an absolute path; only paths relative to the model are read"));
    }
    // Normalise lexically against the base, then check the result stays under the root.
    let mut out = base.to_path_buf();
    for c in Path::new(&r.replace('\\', "/")).components() {
        match c {
            Component::Normal(s) => out.push(s),
            Component::CurDir => {}
            Component::ParentDir => {
                if !out.pop() {
                    return Err(format!("'{r}' leaves the model's folder"));
                }
            }
            _ => return Err(format!("'{r}' is not a relative path")),
        }
    }
    if !out.starts_with(root) {
        return Err(format!("'{r}' leaves the model's folder ({})", root.display()));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_references_resolve_and_escapes_are_refused() {
        let root = Path::new("/models/sponza");
        let base = Path::new("/models/sponza/mtl");
        assert_eq!(resolve(root, base, "../tex/a.png").unwrap(), Path::new("/models/sponza/tex/a.png"));
        assert_eq!(resolve(root, base, "b.png").unwrap(), Path::new("/models/sponza/mtl/b.png"));
        assert_eq!(resolve(root, base, "tex\\\\c.png").unwrap(), Path::new("/models/sponza/mtl/tex/c.png"));
        for bad in [
            "../../etc/passwd",
            "/etc/passwd",
            "C:\\\\x.png",
            "http://x/y.png",
            "file:///etc/passwd",
            "",
            "\\\\server\\\\x",
        ] {
            assert!(resolve(root, base, bad).is_err(), "{bad} accepted");
        }
        assert!(resolve(root, base, "../../other/x.png").unwrap_err().contains("leaves"));
        assert!(resolve(root, base, "../../sponza/x.png").is_ok(), "climbing out and back in stays inside");
    }
}
