//! glTF 2.0 files (`.gltf` with external or embedded data, and `.glb`) read into the
//! pieces a scene is built from: one [`MeshPart`] per triangle primitive instance with its
//! node's world matrix, the materials (`pbr`) with their textures, the punctual lights and
//! the first camera of the default scene.
//!
//! The `gltf` crate parses the JSON and validates its references; everything that reads
//! binary data is meshtrace's own, so that every offset, count and index is checked before
//! it is followed: `container` (GLB chunks, JSON, extensions, validation), `buffers`
//! (buffers and images: GLB, data URIs, files through the [`FileSource`]), `accessor`
//! (typed, strided and sparse accessors), `primitive` (attributes and topology), `draco`
//! (KHR_draco_mesh_compression), `deform` (morph targets and skins), `instancing` (EXT_mesh_gpu_instancing), `material`
//! and `nodes` (the node tree, cameras and lights). Each error is one line naming the file
//! and the JSON path at fault, such as
//! `room.gltf: meshes[2].primitives[0].indices: accessor 7 reads past the end of bufferView 3 …`.

mod accessor;
mod buffers;
mod container;
mod deform;
mod draco;
mod instancing;
mod material;
mod meshopt;
mod nodes;
mod primitive;

use super::part::MeshPart;
use super::source::FileSource;
use super::texture::TextureRef;
use super::{Camera, Material, PunctualLight, SceneError};
use glam::{Mat4, Vec3};
use gltf::json;
use std::path::Path;

/// What a glTF file brings to a scene, in the file's own world space (its default scene
/// with every node transform applied).
#[derive(Debug, Default)]
pub struct GltfAsset {
    /// The materials the parts' triangles index, each a `pbr` material.
    pub materials: Vec<Material>,
    /// The name of each of `materials` in messages: its glTF name, or its JSON path.
    pub material_names: Vec<String>,
    /// The textures the materials' slots index, their images already read.
    pub textures: Vec<TextureRef>,
    /// The triangle primitives of the default scene's nodes, one part per primitive and
    /// node that instantiates it.
    pub parts: Vec<GltfPart>,
    /// KHR_lights_punctual lights, in world space, in radiometric units.
    pub lights: Vec<PunctualLight>,
    /// The first camera (perspective or orthographic) of the default scene's node tree
    /// (depth first).
    pub camera: Option<Camera>,
    /// The translation of the default scene's root node where it has only one
    /// ([`Scene::root_origin`](crate::scene::Scene::root_origin)).
    pub root_origin: Option<Vec3>,
    /// Problems that did not stop loading, each one line naming the file.
    pub warnings: Vec<String>,
    /// What the file holds that a still render leaves out and that is no problem
    /// (animations), each one line naming the file: `meshtrace info` shows them.
    pub notes: Vec<String>,
}

/// One triangle primitive placed by a node.
#[derive(Debug)]
pub struct GltfPart {
    /// The primitive's geometry in its mesh's space; its triangles' materials index
    /// [`GltfAsset::materials`], and it has no materials or textures of its own.
    pub part: MeshPart,
    /// The node's world matrix.
    pub matrix: Mat4,
    /// The index of the node in the file's `nodes`: a bare file's object id.
    pub node: u32,
    /// The primitive's JSON path, `meshes[i].primitives[j]`, for messages.
    pub at: String,
}

/// Whether `path` names a glTF file (`.gltf` or `.glb`, in any case).
pub fn is_gltf(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("gltf") || e.eq_ignore_ascii_case("glb"))
}

/// Reads a glTF file and what it refers to (buffers and images, relative to its folder)
/// through `files`.
pub fn load_gltf(path: &Path, files: &dyn FileSource) -> Result<GltfAsset, SceneError> {
    let shown = super::shown(path);
    let bytes = files.read(path).map_err(|source| SceneError::Io {
        path: shown.clone(),
        source,
    })?;
    let (root, blob) = container::parse(&bytes, &shown)?;
    drop(bytes);
    let doc = Doc {
        root: &root,
        shown,
        dir: path.parent().unwrap_or(Path::new("")),
        files,
        warnings: Warnings::default(),
    };
    let buffers = buffers::Buffers::new(&doc, blob);
    container::check_extensions(&doc);
    let mut asset = nodes::load_scene(&doc, &buffers)?;
    asset.warnings = doc.warnings.finish(&doc.shown);
    Ok(asset)
}

/// The document being read, and what every step needs: the file's name for messages, its
/// folder for relative URIs, the file source and the warnings.
struct Doc<'a> {
    root: &'a json::Root,
    shown: String,
    dir: &'a Path,
    files: &'a dyn FileSource,
    warnings: Warnings,
}

impl Doc<'_> {
    /// An error at JSON path `at` of this file.
    fn error(&self, at: impl Into<String>, message: impl Into<String>) -> SceneError {
        SceneError::Gltf {
            path: self.shown.clone(),
            at: at.into(),
            message: message.into(),
        }
    }

    /// A warning at JSON path `at`: warnings of the same message are said once, with the
    /// places they apply to counted.
    fn warn(&self, at: impl Into<String>, message: impl Into<String>) {
        self.warnings.add(at.into(), message.into());
    }
}

/// `n` things in words: `no accessors`, `1 accessor`, `3 accessors`.
fn count(n: usize, noun: &str) -> String {
    match n {
        0 => format!("no {noun}s"),
        1 => format!("1 {noun}"),
        n => format!("{n} {noun}s"),
    }
}

/// A name from the file (an extension, a URI) as messages show it: on one line, cut short.
fn quoted(name: &str) -> String {
    const MAX: usize = 64;
    let cut: String = name.chars().take(MAX).collect();
    let more = if name.chars().nth(MAX).is_some() {
        "…"
    } else {
        ""
    };
    format!("{}{more}", cut.escape_debug())
}

/// Warnings grouped by message, each with the places it applies to, in first-seen order.
#[derive(Default)]
struct Warnings(std::cell::RefCell<Vec<(String, Vec<String>)>>);

impl Warnings {
    fn add(&self, at: String, message: String) {
        let mut groups = self.0.borrow_mut();
        match groups.iter_mut().find(|(m, _)| *m == message) {
            Some((_, places)) => {
                if !places.contains(&at) {
                    places.push(at);
                }
            }
            None => groups.push((message, vec![at])),
        }
    }

    /// One line per message: `file: place: message`, or with more places
    /// `file: message (place and N more)`.
    fn finish(&self, shown: &str) -> Vec<String> {
        self.0
            .borrow()
            .iter()
            .map(|(message, places)| match places.as_slice() {
                [one] => format!("{shown}: {one}: {message}"),
                [first, rest @ ..] => {
                    format!("{shown}: {message} ({first} and {} more)", rest.len())
                }
                [] => format!("{shown}: {message}"),
            })
            .collect()
    }
}
