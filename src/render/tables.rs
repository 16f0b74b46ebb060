//! The flat scene tables both renderers read, in BVH leaf order: the record types, their
//! codes, and [`RenderScene`], which holds them. This is pure data, which the stages read;
//! [`RenderScene::new`] (in `build.rs`) lays it out from a scene. The GPU renderer uploads
//! exactly these tables, so a path can be replayed on either device.

use crate::bvh::{Bvh, WideBvh};
use crate::geometry::TriVerts;
use crate::scene::{Camera, Material, Sky, Texture};
use bytemuck::{Pod, Zeroable};
use glam::Vec3;

/// Per-triangle shading data in leaf order (48 bytes): vertex normals, the material, and
/// the probability that light sampling picks this triangle.
/// mirror: shaders/types.wgsl `TriShading`
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TriShading {
    pub n0: [f32; 3],
    pub material: u32,
    pub n1: [f32; 3],
    /// Probability of choosing this triangle in next event estimation; 0 for non-emitters.
    pub emitter_pmf: f32,
    pub n2: [f32; 3],
    /// [`TRI_SMOOTH`], [`TRI_UV`], [`TRI_TANGENT`], [`TRI_COLOR`] and [`TRI_UV1`] bits.
    pub flags: u32,
}

/// [`TriShading::flags`]: the triangle has vertex normals (smooth shading).
pub const TRI_SMOOTH: u32 = 1;
/// [`TriShading::flags`]: the triangle has texture coordinates in [`RenderScene::tri_uvs`].
pub const TRI_UV: u32 = 2;
/// [`TriShading::flags`]: the triangle's material has a normal map, and the triangle has
/// tangents in [`RenderScene::tri_tangents`].
pub const TRI_TANGENT: u32 = 4;
/// [`TriShading::flags`]: the triangle has vertex colours in [`RenderScene::tri_colors`].
pub const TRI_COLOR: u32 = 8;
/// [`TriShading::flags`]: the triangle has a second texture coordinate set in
/// [`RenderScene::tri_uvs1`].
pub const TRI_UV1: u32 = 16;

/// Per-triangle vertex colours in leaf order (48 bytes): each corner's linear RGBA, which
/// multiplies the base colour and the alpha an alpha mask reads.
/// mirror: shaders/types.wgsl `TriColors`
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TriColors {
    pub c0: [f32; 4],
    pub c1: [f32; 4],
    pub c2: [f32; 4],
}

/// Per-triangle tangents in leaf order (48 bytes): each corner's unit tangent (xyz) and
/// the handedness of its bitangent (w = ±1; bitangent = w · normal × tangent).
/// mirror: shaders/types.wgsl `TriTangents`
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TriTangents {
    pub t0: [f32; 4],
    pub t1: [f32; 4],
    pub t2: [f32; 4],
}

/// Per-triangle texture coordinates in leaf order (32 bytes), v running down an image
/// from its top edge. mirror: shaders/types.wgsl `TriUvs`
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TriUvs {
    pub uv0: [f32; 2],
    pub uv1: [f32; 2],
    pub uv2: [f32; 2],
    pub _pad: [u32; 2],
}

/// A light that is not a surface as both renderers read it (80 bytes), from
/// [`PunctualLight`](crate::scene::PunctualLight). mirror: shaders/types.wgsl `Light`
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Light {
    /// A point or spot's position, or a rectangle's corner.
    pub position: [f32; 3],
    /// [`LIGHT_POINT`], [`LIGHT_SPOT`], [`LIGHT_DIRECTIONAL`] or [`LIGHT_RECT`].
    pub kind: u32,
    /// A spot's axis, the direction a directional light travels (unit), or a rectangle's
    /// first edge.
    pub direction: [f32; 3],
    /// cos of a spot's cutoff angle.
    pub cos_cutoff: f32,
    /// Radiant intensity (W/sr), a directional light's irradiance (W/m²), or a
    /// rectangle's radiance.
    pub intensity: [f32; 3],
    /// cos of a spot's full-intensity beam width.
    pub cos_beam: f32,
    /// A spot's cutoff angle (radians) and 1 / (cutoff − beam width): its falloff is linear
    /// in the angle from the axis.
    pub cutoff: f32,
    pub inv_transition: f32,
    /// 1 where shadow rays are traced to the light, 0 where it shines through everything.
    pub shadows: u32,
    /// A rectangle's area.
    pub area: f32,
    /// A rectangle's second edge: its light leaves on the side of `direction × edge`.
    pub edge: [f32; 3],
    /// The probability that next event estimation picks the light among
    /// [`RenderScene::emitters`] (0 where it is not among them): what a BSDF-sampled ray
    /// that meets a rectangle weighs its light sample by.
    pub pmf: f32,
}

/// [`Light::kind`] codes.
pub const LIGHT_POINT: u32 = 0;
pub const LIGHT_SPOT: u32 = 1;
pub const LIGHT_DIRECTIONAL: u32 = 2;
pub const LIGHT_RECT: u32 = 3;

/// The most punctual lights that next event estimation samples in full
/// ([`RenderScene::lights_in_full`]): each costs a shadow ray at every vertex.
pub const LIGHTS_IN_FULL_MAX: usize = 8;

/// The bit of an entry of [`RenderScene::emitters`] that marks a punctual light: the other
/// bits are its index in [`RenderScene::lights`].
pub const LIGHT_EMITTER: u32 = 1 << 31;

/// The entry of [`RenderScene::emitters`] that stands for the sky.
/// The shaders get it from `render::gpu::shader::shared_constants`.
pub const SKY_EMITTER: u32 = u32::MAX;

/// Everything an integrator reads, as flat tables in BVH leaf order.
#[derive(Clone, Debug)]
pub struct RenderScene {
    pub bvh: Bvh,
    /// The same tree collapsed to eight children a node, which the CPU renderer traverses
    /// (the GPU traverses `bvh`).
    pub wide: WideBvh,
    pub tris: Vec<TriVerts>,
    /// Each triangle's unit geometric normal, as `geometry::geometric_normal` gives it:
    /// derived data of the CPU renderer, which would otherwise take a square root and a
    /// division at every hit (the shaders recompute it).
    pub tri_normals: Vec<Vec3>,
    pub shading: Vec<TriShading>,
    /// Texture coordinates of every triangle, or empty when the scene has no textures.
    pub tri_uvs: Vec<TriUvs>,
    /// Tangents of every triangle, or empty when no triangle has a normal map.
    pub tri_tangents: Vec<TriTangents>,
    /// The second texture coordinate set of every triangle (zero where it has none), or
    /// empty when the scene has no textures or no triangle has a second set.
    pub tri_uvs1: Vec<TriUvs>,
    /// Vertex colours of every triangle (zero where it has none), or empty when no
    /// triangle has colours.
    pub tri_colors: Vec<TriColors>,
    pub materials: Vec<Material>,
    /// The textures material slots index, and their texels.
    pub textures: Vec<Texture>,
    pub texels: Vec<u32>,
    /// Texel values of 8-bit channels: entries 0–255 decode sRGB, 256–511 are linear
    /// (`k / 255`). The shaders read the same table, so both renderers decode alike.
    /// Where a material has sheen, the sheen's albedo table follows
    /// (`sheen::sheen_table`, which the CPU reads where it lies).
    pub texel_lut: Vec<f32>,
    /// Point, spot, directional and rectangle lights, the rectangles last (from
    /// `first_rect_light`), so that BSDF-sampled rays test them alone.
    pub lights: Vec<Light>,
    /// The index of the first rectangle light in `lights` (its length where there is none).
    pub first_rect_light: u32,
    /// The lights next event estimation picks from: leaf-order indices of emissive
    /// triangles, then punctual lights ([`LIGHT_EMITTER`] | index), then [`SKY_EMITTER`]
    /// if the sky is not black; and their inclusive CDF.
    pub emitters: Vec<u32>,
    pub emitter_cdf: Vec<f32>,
    /// The area of each entry of `emitters` that is a triangle (zero for the others), as
    /// `geometry::triangle_area` gives it: derived data of the CPU renderer, which would
    /// otherwise recompute it at every light sample (the shaders recompute it); the
    /// triangle's normal is in `tri_normals`.
    pub emitter_areas: Vec<f32>,
    /// Probability that next event estimation picks the sky (sampled uniformly over the
    /// sphere): 0 for a black sky, 1 with no emissive triangles, else 1/2.
    pub sky_pmf: f32,
    /// How many of `lights`, from the first, next event estimation samples in full at
    /// every vertex, each with a shadow ray of its own, besides the one emitter it picks:
    /// all of them where there are at most [`LIGHTS_IN_FULL_MAX`], else none. A point, spot
    /// or directional light has no area, so a sample of it is exact but for its shadow
    /// ray, and picking among such lights is then the only noise they add (most of the
    /// noise of a dataset's object under a point light and a grey world). Rect lights,
    /// which have area, are left to the pick. The others are among the emitters only where
    /// caustic light subpaths are traced, which start on them; a pick of one then adds
    /// nothing.
    pub lights_in_full: u32,
    pub camera: Camera,
    pub sky: Sky,
    /// The environment map's parameters (all zero for another sky).
    pub env: Environment,
    /// The environment's sampling distribution, which `env_distribution` (in
    /// `render/build.rs`) lays out; empty for another sky.
    pub env_cdf: Vec<f32>,
    /// Spheres around the specular geometry, which caustic light subpaths aim at
    /// (`caustic_targets` in `render/build.rs`); empty where no material may be delta or
    /// the scene's settings turn caustics off, and then no light subpath is traced.
    pub caustic_targets: Vec<CausticTarget>,
    /// A sphere around every triangle (centre, radius), outside which a directional light's
    /// light subpaths start
    /// ([`start_at_directional`](super::caustics::start_at_directional)).
    pub scene_sphere: (Vec3, f32),
}

/// An environment map as both renderers read it: its texture record, strength, the cosine
/// and sine of its rotation about +Y, and the number of cells of its sampling
/// distribution along u and v (the image's columns, and the spans between its rows).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Environment {
    pub texture: u32,
    pub strength: f32,
    pub rotation: [f32; 2],
    pub cells: [u32; 2],
}

/// A sphere around specular geometry, which light subpaths aim at (16 bytes).
/// mirror: shaders/types.wgsl `CausticTarget`
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct CausticTarget {
    pub center: [f32; 3],
    pub radius: f32,
}
