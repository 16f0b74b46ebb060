//! The scene file as written: serde types for the scene format (`docs/scene-format.md`).
//!
//! Only this module derives `Deserialize`. Unknown keys are errors, so a typo cannot
//! silently render something else. Values are checked later, in `load`, where the
//! field's path is known.

use serde::Deserialize;
use std::collections::BTreeMap;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    pub camera: CameraFile,
    #[serde(default)]
    pub render: RenderFile,
    pub sky: Option<SkyFile>,
    /// A lighting preset, instead of `[sky]`.
    pub lighting: Option<super::lighting::Lighting>,
    #[serde(default)]
    pub materials: BTreeMap<String, MaterialFile>,
    #[serde(default)]
    pub objects: Vec<ObjectFile>,
    #[serde(default)]
    pub lights: Vec<LightFile>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LightType {
    Point,
    Spot,
    Directional,
    Rect,
}

impl LightType {
    /// The name as a scene file spells it.
    pub fn name(self) -> &'static str {
        match self {
            Self::Point => "point",
            Self::Spot => "spot",
            Self::Directional => "directional",
            Self::Rect => "rect",
        }
    }
}

/// A `[[lights]]` table: a punctual light in world space.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LightFile {
    #[serde(rename = "type")]
    pub kind: LightType,
    pub position: Option<[f32; 3]>,
    pub direction: Option<[f32; 3]>,
    pub intensity: Option<[f32; 3]>,
    pub irradiance: Option<[f32; 3]>,
    pub cutoff_angle: Option<f32>,
    pub beam_width: Option<f32>,
    /// A directional light's shadows (default true).
    pub shadows: Option<bool>,
    /// A rectangle's width and height.
    pub size: Option<[f32; 2]>,
    /// A rectangle's radiance.
    pub radiance: Option<[f32; 3]>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraFile {
    pub position: [f32; 3],
    pub look_at: [f32; 3],
    pub up: Option<[f32; 3]>,
    pub vfov: Option<f32>,
    pub aperture: Option<f32>,
    pub focus_distance: Option<f32>,
    /// `perspective` (the default) or `orthographic`.
    pub projection: Option<Projection>,
    /// An orthographic camera's view height in world units.
    pub height: Option<f32>,
}

/// A camera's projection, as a scene file names it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Projection {
    Perspective,
    Orthographic,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RenderFile {
    pub width: Option<u32>,
    pub height: Option<u32>,
    pub spp: Option<u32>,
    pub max_depth: Option<u32>,
    pub seed: Option<u32>,
    pub caustics: Option<bool>,
    pub branches: Option<u32>,
    pub filter_width: Option<f32>,
    pub diffuse_bounces: Option<u32>,
    pub glossy_bounces: Option<u32>,
    pub transmission_bounces: Option<u32>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SkyFile {
    pub color: Option<[f32; 3]>,
    pub zenith: Option<[f32; 3]>,
    pub horizon: Option<[f32; 3]>,
    /// An equirectangular image, relative to the scene file.
    pub environment: Option<String>,
    /// Degrees about +Y (environment only).
    pub rotate: Option<f32>,
    /// Radiance scale (environment only).
    pub strength: Option<f32>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MaterialType {
    Diffuse,
    Conductor,
    RoughConductor,
    Dielectric,
    Pbr,
}

impl MaterialType {
    /// The name as a scene file spells it.
    pub fn name(self) -> &'static str {
        match self {
            Self::Diffuse => "diffuse",
            Self::Conductor => "conductor",
            Self::RoughConductor => "rough_conductor",
            Self::Dielectric => "dielectric",
            Self::Pbr => "pbr",
        }
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialFile {
    #[serde(rename = "type")]
    pub kind: MaterialType,
    pub albedo: Option<ColorFile>,
    pub emission: Option<ColorFile>,
    pub roughness: Option<ScalarFile>,
    pub ior: Option<f32>,
    /// `pbr` only.
    pub base_color: Option<ColorFile>,
    pub metallic: Option<ScalarFile>,
    pub specular: Option<f32>,
    pub transmission: Option<ScalarFile>,
    /// Any kind: a tangent-space normal map (`strength` scales its x and y).
    pub normal_map: Option<TextureFile>,
    /// Any kind: an alpha mask, cutting out the surface where the base colour's alpha
    /// (`alpha` times the albedo texture's alpha channel) is below `alpha_cutoff`.
    pub alpha: Option<f32>,
    pub alpha_cutoff: Option<f32>,
}

/// A colour parameter: an RGB triple, or an image texture.
#[derive(Debug, Deserialize)]
#[serde(untagged)]
pub enum ColorFile {
    Rgb([f32; 3]),
    Texture(TextureFile),
}

/// A scalar parameter: a number, or an image texture (its first channel).
#[derive(Debug, Deserialize)]
#[serde(untagged)]
pub enum ScalarFile {
    Value(f32),
    Texture(TextureFile),
}

/// `{ texture = "file.png", scale = [su, sv], wrap = "clamp", strength = s }`: an image
/// file relative to the scene file, its UV tiling, its wrap mode, and for emission a
/// radiance scale.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TextureFile {
    pub texture: String,
    pub scale: Option<[f32; 2]>,
    pub wrap: Option<WrapFile>,
    pub strength: Option<f32>,
}

/// A texture's wrap mode: one for both axes, or `[u, v]`.
#[derive(Debug, Deserialize)]
#[serde(untagged)]
pub enum WrapFile {
    Both(String),
    Each([String; 2]),
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectFile {
    pub mesh: Option<String>,
    pub sphere: Option<SphereFile>,
    pub material: Option<String>,
    pub translate: Option<[f32; 3]>,
    pub rotate: Option<[f32; 3]>,
    pub scale: Option<ScaleFile>,
    pub matrix: Option<[f32; 16]>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SphereFile {
    pub center: [f32; 3],
    pub radius: f32,
    pub subdivisions: Option<u32>,
}

#[derive(Debug, Deserialize)]
#[serde(untagged)]
pub enum ScaleFile {
    Uniform(f32),
    Axes([f32; 3]),
}
