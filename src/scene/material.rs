//! The material record: one `#[repr(C)]` struct for every BSDF kind, which the CPU reads
//! as it is and the GPU reads as the same bytes (`Material` in `shaders/material.wgsl`).
//! Material names stay in the [`Scene`](super::Scene), beside the table.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

/// Which BSDF a material uses: a `u32` code, compared as the shaders compare it
/// (`MAT_DIFFUSE`, … in WGSL, generated from [`MaterialKind::ALL`]).
#[repr(transparent)]
#[derive(Clone, Copy, PartialEq, Eq, Hash, Pod, Zeroable)]
pub struct MaterialKind(pub u32);

impl MaterialKind {
    pub const DIFFUSE: Self = Self(0);
    pub const CONDUCTOR: Self = Self(1);
    pub const ROUGH_CONDUCTOR: Self = Self(2);
    pub const DIELECTRIC: Self = Self(3);

    /// Every kind with its name in scene files.
    pub const ALL: [(Self, &'static str); 4] = [
        (Self::DIFFUSE, "diffuse"),
        (Self::CONDUCTOR, "conductor"),
        (Self::ROUGH_CONDUCTOR, "rough_conductor"),
        (Self::DIELECTRIC, "dielectric"),
    ];

    /// The kind's name in scene files, or `unknown` for a code that names none.
    pub fn name(self) -> &'static str {
        Self::ALL
            .iter()
            .find(|(k, _)| *k == self)
            .map_or("unknown", |(_, n)| n)
    }
}

impl std::fmt::Debug for MaterialKind {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        write!(f, "{} ({})", self.name(), self.0)
    }
}

/// The value of a texture slot that holds no texture (the shaders get it from
/// `render::gpu::shader::shared_constants`).
pub const NO_TEXTURE: u32 = u32::MAX;

/// A validated material (48 bytes). Parameters that its kind does not use keep neutral
/// values. Each parameter that a texture may modulate has a texture slot: the index of
/// that texture in the scene's texture table, or [`NO_TEXTURE`].
/// mirror: shaders/material.wgsl `Material`
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct Material {
    /// Diffuse albedo, or the conductors' reflectance at every angle.
    pub albedo: Vec3,
    pub kind: MaterialKind,
    /// Radiance emitted from the front face; zero for non-emitters.
    pub emission: Vec3,
    /// Perceptual roughness in [0, 1]; GGX alpha is its square.
    pub roughness: f32,
    /// Index of refraction inside over outside (dielectrics).
    pub ior: f32,
    pub albedo_texture: u32,
    pub emission_texture: u32,
    pub roughness_texture: u32,
}

impl Material {
    /// A material of `kind` with neutral parameters: white, black emission, smooth, glass IOR.
    pub fn new(kind: MaterialKind) -> Self {
        Self {
            albedo: Vec3::ONE,
            kind,
            emission: Vec3::ZERO,
            roughness: 0.0,
            ior: 1.5,
            albedo_texture: NO_TEXTURE,
            emission_texture: NO_TEXTURE,
            roughness_texture: NO_TEXTURE,
        }
    }

    /// The material of faces that name none: diffuse, albedo 0.8.
    pub fn default_diffuse() -> Self {
        Self::diffuse(Vec3::splat(0.8))
    }

    pub fn diffuse(albedo: Vec3) -> Self {
        Self {
            albedo,
            ..Self::new(MaterialKind::DIFFUSE)
        }
    }

    /// Whether any parameter reads a texture.
    pub fn has_texture(&self) -> bool {
        [
            self.albedo_texture,
            self.emission_texture,
            self.roughness_texture,
        ]
        .iter()
        .any(|&t| t != NO_TEXTURE)
    }

    /// mirror: shaders/material.wgsl `is_emissive`
    pub fn is_emissive(&self) -> bool {
        self.emission.max_element() > 0.0
    }
}
