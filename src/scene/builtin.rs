//! Scenes built into the binary, from `assets/`, so that `meshtrace render` works anywhere.

use super::source::FileSource;
use super::{Scene, SceneError, load_scene_from};
use std::path::Path;

/// Every file of the built-in scenes, by its path under `assets/`.
const FILES: &[(&str, &str)] = &[
    (
        "cornell/cornell.toml",
        include_str!("../../assets/cornell/cornell.toml"),
    ),
    (
        "cornell/light.obj",
        include_str!("../../assets/cornell/light.obj"),
    ),
    (
        "cornell/floor.obj",
        include_str!("../../assets/cornell/floor.obj"),
    ),
    (
        "cornell/ceiling.obj",
        include_str!("../../assets/cornell/ceiling.obj"),
    ),
    (
        "cornell/back.obj",
        include_str!("../../assets/cornell/back.obj"),
    ),
    (
        "cornell/green_wall.obj",
        include_str!("../../assets/cornell/green_wall.obj"),
    ),
    (
        "cornell/red_wall.obj",
        include_str!("../../assets/cornell/red_wall.obj"),
    ),
    (
        "cornell/small_box.obj",
        include_str!("../../assets/cornell/small_box.obj"),
    ),
    (
        "cornell/large_box.obj",
        include_str!("../../assets/cornell/large_box.obj"),
    ),
];

/// The built-in scenes: (name, scene file).
pub const SCENES: &[(&str, &str)] = &[("cornell", "cornell/cornell.toml")];

/// The scene `meshtrace render` draws when given none.
pub const DEFAULT: &str = "cornell";

struct Embedded;

impl FileSource for Embedded {
    fn read(&self, path: &Path) -> std::io::Result<Vec<u8>> {
        let key = path.to_string_lossy().replace('\\', "/");
        let key = key.strip_prefix("builtin:").unwrap_or(&key);
        FILES
            .iter()
            .find(|(name, _)| *name == key)
            .map(|(_, text)| text.as_bytes().to_vec())
            .ok_or_else(|| {
                std::io::Error::new(std::io::ErrorKind::NotFound, "no such built-in file")
            })
    }
}

/// Loads a built-in scene by name (see [`SCENES`]).
pub fn load_builtin(name: &str) -> Result<Scene, SceneError> {
    let Some((_, file)) = SCENES.iter().find(|(n, _)| *n == name) else {
        let names: Vec<&str> = SCENES.iter().map(|(n, _)| *n).collect();
        return Err(SceneError::Invalid {
            path: format!("builtin:{name}"),
            field: "scene".into(),
            message: format!("no such built-in scene; there are: {}", names.join(", ")),
        });
    };
    load_scene_from(Path::new(file), &Embedded)
}
