//! Saved views per scene, kept in `$XDG_CONFIG_HOME/raylab/bookmarks.json` (or `~/.config/...`) so they
//! survive restarts. A missing or unreadable file starts an empty list; write failures are reported.

use std::collections::BTreeMap;
use std::path::PathBuf;

use raylab_core::scene::{Camera, View};

/// Bookmarked views by scene name.
#[derive(Default)]
pub struct Bookmarks {
    file: Option<PathBuf>,
    by_scene: BTreeMap<String, Vec<View>>,
}

/// Where the bookmarks file lives, if a home or config directory is known.
fn default_file() -> Option<PathBuf> {
    let base = std::env::var_os("XDG_CONFIG_HOME")
        .filter(|s| !s.is_empty())
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".config")))?;
    Some(base.join("raylab").join("bookmarks.json"))
}

impl Bookmarks {
    /// Reads the user's bookmarks.
    pub fn load() -> Self {
        Self::from_file(default_file())
    }

    /// Reads bookmarks from `file` (none when it is missing or not a bookmarks file).
    pub fn from_file(file: Option<PathBuf>) -> Self {
        let by_scene = file
            .as_ref()
            .and_then(|f| std::fs::read_to_string(f).ok())
            .and_then(|t| serde_json::from_str::<BTreeMap<String, Vec<View>>>(&t).ok())
            .map(|mut m| {
                for views in m.values_mut() {
                    views.retain(|v| v.camera.validate().is_ok());
                }
                m
            })
            .unwrap_or_default();
        Self { file, by_scene }
    }

    /// The bookmarks of `scene`.
    pub fn for_scene(&self, scene: &str) -> &[View] {
        self.by_scene.get(scene).map_or(&[], Vec::as_slice)
    }

    /// Adds a bookmark and saves the file.
    pub fn add(&mut self, scene: &str, name: String, camera: Camera) -> Result<(), String> {
        self.by_scene.entry(scene.to_string()).or_default().push(View { name, camera });
        self.save()
    }

    /// Removes the `index`th bookmark of `scene` and saves the file.
    pub fn remove(&mut self, scene: &str, index: usize) -> Result<(), String> {
        if let Some(v) = self.by_scene.get_mut(scene)
            && index < v.len()
        {
            v.remove(index);
        }
        self.save()
    }

    fn save(&self) -> Result<(), String> {
        let Some(file) = &self.file else {
            return Err("bookmarks are kept for this session only: no HOME or XDG_CONFIG_HOME".into());
        };
        if let Some(dir) = file.parent() {
            std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
        }
        let json = serde_json::to_string_pretty(&self.by_scene).map_err(|e| e.to_string())?;
        std::fs::write(file, json).map_err(|e| format!("cannot save bookmarks to {}: {e}", file.display()))
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    #[test]
    fn bookmarks_persist_per_scene() {
        let dir = std::env::temp_dir().join(format!("raylab-bookmarks-{}", std::process::id()));
        let file = dir.join("sub").join("bookmarks.json");
        let cam = Camera::look_at(Vec3::ZERO, Vec3::Z, Vec3::Y, 45.0);
        let mut b = Bookmarks::from_file(Some(file.clone()));
        assert!(b.for_scene("atrium").is_empty());
        b.add("atrium", "door".into(), cam).unwrap();
        b.add("atrium", "gallery".into(), cam).unwrap();
        b.add("arena", "pit".into(), cam).unwrap();
        let mut again = Bookmarks::from_file(Some(file.clone()));
        assert_eq!(again.for_scene("atrium").len(), 2);
        again.remove("atrium", 0).unwrap();
        let third = Bookmarks::from_file(Some(file.clone()));
        assert_eq!(third.for_scene("atrium")[0].name, "gallery");
        assert_eq!(third.for_scene("arena").len(), 1);
        std::fs::write(&file, "garbage").unwrap();
        assert!(Bookmarks::from_file(Some(file)).for_scene("atrium").is_empty());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
