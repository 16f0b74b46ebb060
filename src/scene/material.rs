//! Materials as the renderers see them: one flat struct for every BSDF type, so that the
//! CPU and GPU read the same table.

use glam::Vec3;

/// Which BSDF a material uses. The discriminants are the `kind` codes in `shaders/types.wgsl`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum MaterialKind {
    Diffuse = 0,
    Conductor = 1,
    RoughConductor = 2,
    Dielectric = 3,
}

/// A validated material. Parameters that a kind does not use keep neutral values.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    pub kind: MaterialKind,
    pub albedo: Vec3,
    /// Radiance emitted from the front face; zero for non-emitters.
    pub emission: Vec3,
    /// Perceptual roughness in [0, 1]; GGX alpha is its square.
    pub roughness: f32,
    pub ior: f32,
}

impl Material {
    /// The material of faces that name none: diffuse, albedo 0.8.
    pub fn default_diffuse() -> Self {
        Self::diffuse("default", Vec3::splat(0.8))
    }

    pub fn diffuse(name: &str, albedo: Vec3) -> Self {
        Self {
            name: name.to_string(),
            kind: MaterialKind::Diffuse,
            albedo,
            emission: Vec3::ZERO,
            roughness: 0.0,
            ior: 1.5,
        }
    }

    pub fn is_emissive(&self) -> bool {
        self.emission.max_element() > 0.0
    }
}
