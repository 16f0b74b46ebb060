//! Scenes: the validated, render-ready description of what to draw.
//!
//! `file` holds the serde types of the TOML format; `load` turns a file (or a bare OBJ or
//! glTF file) into a [`Scene`], checking every value and naming the file and field of any
//! error; `obj`/`mtl` and `gltf` read the meshes.
//! Nothing here knows about BVHs or devices.

pub mod builtin;
pub mod camera;
pub mod file;
pub mod gltf;
pub mod light;
pub mod load;
pub mod material;
pub mod mtl;
pub mod obj;
pub mod sphere;
pub mod studio;
pub mod tangents;
pub mod texture;

pub use camera::Camera;
pub use light::PunctualLight;
pub use load::{load_scene, load_scene_from, parse_scene};
pub use material::{Material, MaterialKind, NO_TEXTURE};
pub use texture::{Texture, TextureFormat, Textures, Wrap};

use glam::{Vec2, Vec3, Vec4};
use std::path::PathBuf;

/// Index value of a triangle corner that has no vertex normal.
pub const NO_NORMAL: u32 = u32::MAX;

/// Index value of a triangle corner that has no texture coordinate.
pub const NO_UV: u32 = u32::MAX;

/// Index value of a triangle corner that has no tangent.
pub const NO_TANGENT: u32 = u32::MAX;

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

/// How to render: the `[render]` table, after command-line overrides.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    /// Longest path in segments from the camera (1 = emitters seen directly).
    pub max_depth: u32,
    pub seed: u32,
    /// Whether some camera samples also trace light subpaths through the scene's specular
    /// materials, joined to the camera paths (`render::caustics`): caustics with far less
    /// noise. Off, the render is the path tracer's alone, as Mitsuba 3's `path` renders.
    pub caustics: bool,
    /// How many paths each camera sample branches into at its first hit
    /// (`render::integrator`): the samples of indirect light per camera sample. Each
    /// costs about a path less its camera ray and first vertex. `None`: [`Self::branches`]
    /// decides.
    pub branches: Option<u32>,
}

/// Whether renders trace caustic light subpaths unless told otherwise.
pub const CAUSTICS_DEFAULT: bool = true;

/// Branches at the first hit unless told otherwise, in a render without caustic light
/// subpaths (BENCHMARKS.md: the quality per second of 1, 2, 4 and 8 on the benchmark
/// scenes).
pub const BRANCHES_DEFAULT: u32 = 4;

/// The most branches a setting may ask for.
pub const MAX_BRANCHES: u32 = 64;

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            width: 640,
            height: 480,
            spp: 64,
            max_depth: 8,
            seed: 0,
            caustics: CAUSTICS_DEFAULT,
            branches: None,
        }
    }
}

impl RenderSettings {
    /// The branches of each camera sample: as set, else [`BRANCHES_DEFAULT`] in a render
    /// that traces no caustic light subpaths and 1 in one that does. There each branch
    /// traces a light subpath of its own and costs nearly a whole sample, so that
    /// branching no longer pays (BENCHMARKS.md, the glass-and-mirror box).
    pub fn branches(&self, light_subpaths: bool) -> u32 {
        self.branches
            .unwrap_or(if light_subpaths { 1 } else { BRANCHES_DEFAULT })
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
    /// For a bare mesh shown in the studio: the bounds of the mesh the studio camera frames
    /// (the ground left out), for other views framed alike (`meshtrace batch`'s turntables).
    /// `None` for a scene file.
    pub framed: Option<crate::math::Aabb>,
}

/// A path as error messages show it: on one line whatever characters it holds.
pub fn shown(path: &std::path::Path) -> String {
    path.display().to_string().escape_debug().to_string()
}

/// Why a scene could not be loaded. Each message is one line naming the file and the
/// line or field at fault.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("{path}: {source}")]
    Io {
        path: String,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}:{line}:{column}: {message}")]
    Syntax {
        path: String,
        line: usize,
        column: usize,
        message: String,
    },
    #[error("{path}: {field}: {message}")]
    Invalid {
        path: String,
        field: String,
        message: String,
    },
    /// An image that cannot be read as a texture.
    #[error("{path}: {message}")]
    Image { path: String, message: String },
    /// A problem with a glTF file at `at`: a JSON path such as
    /// `meshes[2].primitives[0].indices`, or a part of a `.glb` container.
    #[error("{path}: {at}: {message}")]
    Gltf {
        path: String,
        at: String,
        message: String,
    },
    /// A file that is none of the inputs meshtrace reads.
    #[error("{path}: {message}")]
    Unsupported { path: String, message: String },
    /// A problem with an OBJ file or an MTL library it loads (`path` names the file at
    /// fault), at `line` when one line is at fault; whole-mesh problems have no line.
    #[error("{path}{}: {message}", at_line(*.line))]
    Obj {
        path: String,
        line: Option<usize>,
        message: String,
    },
}

/// The `:{line}` of an error message, or nothing when the line is not known.
fn at_line(line: Option<usize>) -> String {
    line.map(|l| format!(":{l}")).unwrap_or_default()
}
