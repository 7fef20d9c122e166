//! Built-in procedural scenes, so raylab runs with no files at all. Each is deterministic, generated in well
//! under a second, and carries a default view and light. They stand in for the thesis's benchmark scenes
//! (Tsakok 2008, Figure 4.1): `atrium` for Sponza, `arena` for the Quake III map, `kitchen` for the
//! transformed kitchen and `forest` for Fairy Forest.

mod arena;
mod atrium;
mod forest;
mod kitchen;

use raylab_core::scene::Scene;

/// How much geometry a built-in scene gets.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Detail {
    /// The benchmark version (tens to hundreds of thousands of triangles).
    #[default]
    Full,
    /// A small version with the same layout, for tests against the brute-force reference.
    Test,
}

impl Detail {
    /// `full` for [`Detail::Full`], `test` for [`Detail::Test`].
    pub fn pick(self, full: u32, test: u32) -> u32 {
        match self {
            Detail::Full => full,
            Detail::Test => test,
        }
    }
}

/// A built-in scene's name and summary.
pub struct BuiltinInfo {
    /// The name the CLI and the viewer accept.
    pub name: &'static str,
    /// One line on what it is.
    pub summary: &'static str,
    build: fn(Detail) -> Scene,
}

/// The built-in scenes; the first is the default.
pub const BUILTINS: [BuiltinInfo; 4] = [
    BuiltinInfo {
        name: "atrium",
        summary: "Sponza-style atrium: two storeys of arcades, columns, drapes, mirror ball, glass block (~78k tris)",
        build: atrium::build,
    },
    BuiltinInfo {
        name: "arena",
        summary: "Quake-III-like arena: few, large, mostly axis-aligned polygons (~13k tris)",
        build: arena::build,
    },
    BuiltinInfo {
        name: "kitchen",
        summary: "kitchen with many non-axis-aligned objects, the whole scene rotated off the axes (~102k tris)",
        build: kitchen::build,
    },
    BuiltinInfo {
        name: "forest",
        summary: "forest floor with dense small-triangle detail: trees, leaves, grass (~180k tris)",
        build: forest::build,
    },
];

/// The names of the built-in scenes.
pub fn names() -> Vec<&'static str> {
    BUILTINS.iter().map(|b| b.name).collect()
}

/// Builds the built-in scene `name`, or `None` if there is none of that name.
pub fn build(name: &str, detail: Detail) -> Option<Scene> {
    BUILTINS.iter().find(|b| b.name == name).map(|b| (b.build)(detail))
}
