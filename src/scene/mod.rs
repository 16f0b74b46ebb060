//! Scenes: the validated, render-ready description of what to draw.
//!
//! `file` holds the serde types of the TOML format; `load` turns a file (or a bare OBJ or
//! glTF file) into a [`Scene`], checking every value and naming the file and field of any
//! error; `obj`/`mtl` and `gltf` read the meshes.
//! Nothing here knows about BVHs or devices.

pub mod builder;
pub mod builtin;
pub mod camera;
pub mod checks;
pub mod error;
pub mod file;
pub mod gltf;
pub mod light;
pub mod lighting;
pub mod lines;
pub mod load;
pub mod material;
pub mod mtl;
pub mod obj;
pub mod part;
pub mod settings;
pub mod source;
pub mod sphere;
pub mod studio;
pub mod tangents;
pub mod texture;

pub use camera::Camera;
pub use error::{SceneError, shown};
pub use light::PunctualLight;
pub use load::{load_scene, load_scene_from, parse_scene};
pub use material::{Material, MaterialKind, NO_TEXTURE};
pub use settings::{
    BRANCHES_DEFAULT, BounceLimits, CAUSTICS_DEFAULT, MAX_BRANCHES, MAX_PIXELS, RenderSettings,
};
pub use texture::{Texture, TextureFormat, Textures, Wrap};

use glam::{Vec2, Vec3, Vec4};
use std::path::{Path, PathBuf};

/// Index value of a triangle corner that has no vertex normal.
pub const NO_NORMAL: u32 = u32::MAX;

/// Index value of a triangle corner that has no texture coordinate.
pub const NO_UV: u32 = u32::MAX;

/// Index value of a triangle corner that has no tangent.
pub const NO_TANGENT: u32 = u32::MAX;

/// Index value of a triangle corner that has no vertex colour.
pub const NO_COLOR: u32 = u32::MAX;

/// One triangle of the scene mesh, by index into [`Mesh::positions`] and [`Mesh::normals`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Triangle {
    pub p: [u32; 3],
    /// Vertex normal indices, or `[NO_NORMAL; 3]` for flat shading.
    pub n: [u32; 3],
    /// Texture coordinate indices into [`Mesh::texcoords`], or `[NO_UV; 3]`.
    pub t: [u32; 3],
    pub material: u32,
}

/// Every triangle of the scene in world space, sharing vertices as the files did.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    /// Texture coordinates, v running down an image from its top edge.
    pub texcoords: Vec<Vec2>,
    pub triangles: Vec<Triangle>,
    /// Unit tangents in world space (glTF `TANGENT`), w (±1) the bitangent's handedness:
    /// bitangent = `cross(normal, tangent.xyz) * w`.
    pub tangents: Vec<Vec4>,
    /// Per triangle, parallel to [`Mesh::triangles`], its corners' indices into
    /// [`Mesh::tangents`] or `[NO_TANGENT; 3]`; empty when no triangle has tangents. (A
    /// table beside the triangles rather than a field of [`Triangle`], so that meshes built
    /// in code need not say that they have none.)
    pub tangent_corners: Vec<[u32; 3]>,
    /// Per triangle, parallel to [`Mesh::triangles`], its corners' second texture
    /// coordinate set (glTF `TEXCOORD_1`), indices into [`Mesh::texcoords`] or
    /// `[NO_UV; 3]`; empty when no triangle has one. Textures whose record names set 1
    /// read it.
    pub uv1_corners: Vec<[u32; 3]>,
    /// Vertex colours (glTF `COLOR_0`), linear RGBA in [0, 1]: they multiply the base
    /// colour and the alpha an alpha mask reads.
    pub colors: Vec<Vec4>,
    /// Per triangle, parallel to [`Mesh::triangles`], its corners' indices into
    /// [`Mesh::colors`] or `[NO_COLOR; 3]`; empty when no triangle has colours.
    pub color_corners: Vec<[u32; 3]>,
    /// Per triangle, parallel to [`Mesh::triangles`], the object it belongs to (the index
    /// of its scene file's `[[objects]]` entry, or of a bare glTF file's node); empty in
    /// a mesh built in code, whose triangles all belong to object 0.
    pub objects: Vec<u32>,
}

impl Mesh {
    pub fn vertices(&self, t: &Triangle) -> [Vec3; 3] {
        t.p.map(|i| self.positions[i as usize])
    }

    /// The object triangle `i` belongs to ([`Mesh::objects`]).
    pub fn object(&self, i: usize) -> u32 {
        self.objects.get(i).copied().unwrap_or(0)
    }

    /// The second-set texture coordinate indices of triangle `i`: `[NO_UV; 3]` where it
    /// has none.
    pub fn uv1_indices(&self, i: usize) -> [u32; 3] {
        self.uv1_corners.get(i).copied().unwrap_or([NO_UV; 3])
    }

    /// The colour indices of triangle `i`: `[NO_COLOR; 3]` where it has none.
    pub fn color_indices(&self, i: usize) -> [u32; 3] {
        self.color_corners.get(i).copied().unwrap_or([NO_COLOR; 3])
    }

    /// The tangent indices of triangle `i`: `[NO_TANGENT; 3]` where it has none.
    pub fn tangent_indices(&self, i: usize) -> [u32; 3] {
        self.tangent_corners
            .get(i)
            .copied()
            .unwrap_or([NO_TANGENT; 3])
    }
}

/// Radiance of rays that leave the scene (`render::lights::sky_radiance` evaluates it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Sky {
    Constant(Vec3),
    /// `lerp(horizon, zenith, 0.5 * (dir.y + 1))` for a unit direction.
    Gradient {
        zenith: Vec3,
        horizon: Vec3,
    },
    /// An equirectangular image of incoming radiance (`texture`, an index into the scene's
    /// texture records) times `strength`, turned by `rotation` radians about +Y: the
    /// direction d reads the image at d' = R_y(−rotation) d, as Mitsuba 3's `envmap`.
    Environment {
        texture: u32,
        strength: f32,
        rotation: f32,
    },
}

impl Sky {
    /// Whether the sky sends no light at all. An environment whose image is black is
    /// found so only once its sampling distribution is built
    /// (`render::RenderScene::sky_pmf`).
    pub fn is_black(&self) -> bool {
        match *self {
            Sky::Constant(c) => c == Vec3::ZERO,
            Sky::Gradient { zenith, horizon } => zenith == Vec3::ZERO && horizon == Vec3::ZERO,
            Sky::Environment { strength, .. } => strength == 0.0,
        }
    }
}

/// A loaded scene, ready to be built into an acceleration structure and rendered.
#[derive(Clone, Debug)]
pub struct Scene {
    /// Where it came from, for messages; `None` for scenes built in memory.
    pub path: Option<PathBuf>,
    pub camera: Camera,
    pub sky: Sky,
    pub settings: RenderSettings,
    /// The material table: triangles index it.
    pub materials: Vec<Material>,
    /// `material_names[i]` names `materials[i]` in messages (its scene-file or MTL name).
    pub material_names: Vec<String>,
    /// The textures material slots index, with their texels.
    pub textures: Textures,
    /// Point, spot and directional lights.
    pub lights: Vec<PunctualLight>,
    pub mesh: Mesh,
    /// Problems that did not stop loading (a missing MTL file, dropped degenerate triangles).
    pub warnings: Vec<String>,
    /// What the input holds that a still render leaves out and that is no problem (a glTF
    /// file's animations), each one line naming the file: `meshtrace info` shows them,
    /// `render` does not.
    pub notes: Vec<String>,
    /// For a bare mesh shown in the studio: the bounds of the mesh the studio camera frames
    /// (the ground left out), for other views framed alike (`meshtrace batch`'s turntables).
    /// `None` for a scene file.
    pub framed: Option<crate::math::Aabb>,
    /// For a bare glTF file whose default scene has one root node: that node's
    /// translation, turned up as the mesh is. Blender's importer makes the node an object
    /// with its origin there, and the dataset scripts scale that object about it, which
    /// changes the offset they record (`batch::preset::Normalisation::root`). `None`
    /// otherwise.
    pub root_origin: Option<Vec3>,
}

/// An input's uid, as the dataset scripts name an object: its file name up to the first
/// dot.
pub fn uid(input: &Path) -> String {
    let name = input
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    name.split('.').next().unwrap_or_default().to_string()
}
