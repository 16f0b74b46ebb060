//! From a file to a [`Scene`]: what the file is (a scene file, an OBJ, a glTF file), and
//! the environment images that light it. A scene file's values are checked by [`super::checks`],
//! its meshes put together by [`super::builder`], and a bare mesh staged by [`super::studio`].
//! Each error names the file and the line or field at fault.

use super::builder::Builder;
use super::checks::Ctx;
use super::file::SceneFile;
use super::source::{FileSource, Fs};
use super::studio::{BareOptions, load_bare_gltf, load_bare_obj};
use super::texture::load_environment;
use super::{Scene, SceneError, Sky};
use std::path::Path;

/// Lights `scene` with the equirectangular image at `path` (strength 1, not turned)
/// instead of its own sky, as `--env` asks; why not, naming the file, when it cannot be
/// read.
pub fn replace_environment(scene: &mut Scene, path: &Path) -> Result<(), String> {
    let texture = load_environment(path, &mut scene.textures, &Fs)?;
    scene.sky = Sky::Environment {
        texture,
        strength: 1.0,
        rotation: 0.0,
    };
    Ok(())
}

/// Loads a scene file (`.toml`), or a bare mesh (`.obj`, `.gltf`, `.glb`) shown in the
/// studio ([`studio`](super::studio)).
pub fn load_scene(path: &Path) -> Result<Scene, SceneError> {
    load_scene_with(path, &Fs, &BareOptions::default())
}

/// [`load_scene`] reading through `files`, so that built-in scenes load like any other.
pub fn load_scene_from(path: &Path, files: &dyn FileSource) -> Result<Scene, SceneError> {
    load_scene_with(path, files, &BareOptions::default())
}

/// [`load_scene_from`] with the options for a bare mesh. The extension (in any case) says
/// what the file is; any other is an error that lists the inputs meshtrace reads. Options
/// given for a scene file are an error: it places its meshes itself.
pub fn load_scene_with(
    path: &Path,
    files: &dyn FileSource,
    options: &BareOptions,
) -> Result<Scene, SceneError> {
    let extension = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match extension.as_deref() {
        Some("obj") => return load_bare_obj(path, files, options),
        Some("gltf" | "glb") => return load_bare_gltf(path, files, options),
        Some("toml") if options.up.is_some() => {
            return Err(SceneError::Unsupported {
                path: super::shown(path),
                message: "--up applies to a bare mesh (.obj, .gltf, .glb); a scene file \
                          turns its objects with `rotate`"
                    .into(),
            });
        }
        Some("toml") => {}
        _ => {
            return Err(SceneError::Unsupported {
                path: super::shown(path),
                message: "not an input meshtrace reads: give a scene file (.toml), an OBJ mesh \
                          (.obj) or a glTF file (.gltf, .glb)"
                    .into(),
            });
        }
    }
    let io = |source| SceneError::Io {
        path: super::shown(path),
        source,
    };
    let bytes = files.read(path).map_err(io)?;
    let text = String::from_utf8(bytes)
        .map_err(|e| io(std::io::Error::new(std::io::ErrorKind::InvalidData, e)))?;
    parse_scene_from(&text, path, files)
}

/// Parses scene-file text; `path` names it in messages and anchors its relative paths.
pub fn parse_scene(text: &str, path: &Path) -> Result<Scene, SceneError> {
    parse_scene_from(text, path, &Fs)
}

fn parse_scene_from(text: &str, path: &Path, files: &dyn FileSource) -> Result<Scene, SceneError> {
    let ctx = Ctx {
        files,
        path: super::shown(path),
        dir: path.parent().map(Path::to_path_buf).unwrap_or_default(),
    };
    let file: SceneFile = toml::from_str(text).map_err(|e| ctx.syntax(text, &e))?;
    let camera = ctx.camera(&file)?;
    let settings = ctx.settings(&file)?;
    let mut builder = Builder::default();
    if file.lighting.is_some() && file.sky.is_some() {
        return Err(ctx.invalid(
            "lighting",
            "cannot be combined with `[sky]`: a lighting preset sets the sky",
        ));
    }
    let sky = ctx.sky(&file, &mut builder.textures)?;
    for (name, m) in &file.materials {
        let mat = ctx.material(name, m, &mut builder.textures)?;
        let index = builder.add_material(name, mat);
        builder.named.insert(name.clone(), index);
    }
    for (i, object) in file.objects.iter().enumerate() {
        builder.object = i as u32;
        ctx.object(&mut builder, i, object)?;
    }
    let lights = (file.lights.iter().enumerate())
        .map(|(i, light)| ctx.light(i, light))
        .collect::<Result<Vec<_>, _>>()?;
    let mut scene = builder.finish(Some(path.to_path_buf()), camera, sky, settings);
    // A preset replaces the sky and the lights that glTF objects bring; the file's own
    // `[[lights]]` add to it.
    if let Some(lighting) = file.lighting {
        lighting.relative_to(&ctx.dir).apply(&mut scene, files)?;
    }
    scene.lights.extend(lights);
    Ok(scene)
}
