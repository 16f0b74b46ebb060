//! A piece of geometry in its own space, as each loader produces it (an OBJ file, a sphere,
//! a glTF primitive) before the scene builder places it in the world mesh.

use super::Material;
use super::texture::TextureRef;
use glam::{Vec2, Vec3, Vec4};

/// One piece of geometry in its own space, as a scene object brings it: an OBJ file with
/// its materials already mapped, a sphere, or a glTF primitive. The scene builder
/// transforms it and appends it to the scene mesh.
#[derive(Debug, Default)]
pub struct MeshPart {
    /// Every vertex position the part defines (for an OBJ, every `v` line in file order,
    /// whether or not a face uses it).
    pub positions: Vec<Vec3>,
    /// Every vertex normal the part defines (for an OBJ, every `vn` line in file order).
    pub normals: Vec<Vec3>,
    /// Every texture coordinate the part defines, v running down the image from its top
    /// edge (an OBJ `vt u v` is (u, −v): OBJ runs v up from the bottom edge).
    pub texcoords: Vec<Vec2>,
    /// A second set of texture coordinates (glTF `TEXCOORD_1`), one per entry of
    /// `positions` (glTF corners index one vertex table), for textures that name that set;
    /// empty when the part has none.
    pub texcoords1: Vec<Vec2>,
    /// Vertex colours (glTF `COLOR_0`), linear RGBA, one per entry of `positions`: they
    /// multiply the base colour and its alpha; empty when the part has none.
    pub colors: Vec<Vec4>,
    /// Tangents (glTF `TANGENT`): xyz the direction of increasing u, w (±1) the handedness
    /// of the bitangent, `cross(normal, tangent.xyz) * w`.
    pub tangents: Vec<Vec4>,
    /// The triangles, in file order.
    pub triangles: Vec<PartTriangle>,
    /// The materials the triangles refer to: for an OBJ, every material of every library it
    /// loaded, in load order (a name defined twice is listed twice).
    pub materials: Vec<Material>,
    /// The MTL name of each of `materials`.
    pub material_names: Vec<String>,
    /// The textures the materials' texture slots index, before their images are read.
    pub textures: Vec<TextureRef>,
    /// Problems that did not stop loading, each one line naming the file.
    pub warnings: Vec<String>,
}

/// One triangle of a [`MeshPart`], by index into the part's own tables.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PartTriangle {
    /// Corner positions, indices into [`MeshPart::positions`].
    pub p: [u32; 3],
    /// Corner normals, indices into [`MeshPart::normals`], or `[NO_NORMAL; 3]` for a
    /// flat-shaded triangle.
    pub n: [u32; 3],
    /// Corner texture coordinates, indices into [`MeshPart::texcoords`], or `[NO_UV; 3]`
    /// when not every corner of the face has one.
    pub t: [u32; 3],
    /// Corner tangents, indices into [`MeshPart::tangents`], or `[NO_TANGENT; 3]`.
    pub g: [u32; 3],
    /// Index into [`MeshPart::materials`], or `None` for a face that names no material
    /// (or an unknown one): the scene's default material.
    pub material: Option<u32>,
}
