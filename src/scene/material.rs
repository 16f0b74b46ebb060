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
    /// The glTF 2.0 metallic-roughness BRDF (its specification's Appendix B) with
    /// KHR_materials_specular, _ior, _transmission and _volume.
    pub const PBR: Self = Self(4);

    /// Every kind with its name in scene files.
    pub const ALL: [(Self, &'static str); 5] = [
        (Self::DIFFUSE, "diffuse"),
        (Self::CONDUCTOR, "conductor"),
        (Self::ROUGH_CONDUCTOR, "rough_conductor"),
        (Self::DIELECTRIC, "dielectric"),
        (Self::PBR, "pbr"),
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

/// [`Material::flags`]: a `pbr` surface that transmits is a thin wall, which light crosses
/// without bending, rather than the boundary of a solid (glTF without KHR_materials_volume).
pub const MAT_THIN_WALLED: u32 = 1;
/// [`Material::flags`]: where the base colour's alpha is below `alpha_cutoff`, rays pass
/// through the surface (glTF `alphaMode` MASK).
pub const MAT_ALPHA_MASK: u32 = 2;

/// A validated material (112 bytes). Parameters that its kind does not use keep neutral
/// values. Each parameter that a texture may modulate has a texture slot: the index of
/// that texture in the scene's texture table, or [`NO_TEXTURE`].
/// mirror: shaders/material.wgsl `Material`
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct Material {
    /// Diffuse albedo, the conductors' reflectance at every angle, or `pbr`'s base colour.
    pub albedo: Vec3,
    pub kind: MaterialKind,
    /// Radiance emitted from the front face; zero for non-emitters.
    pub emission: Vec3,
    /// Perceptual roughness in [0, 1]; GGX alpha is its square.
    pub roughness: f32,
    /// `pbr`: KHR_materials_specular's colour factor, which tints the dielectric F0.
    pub specular_color: Vec3,
    /// Index of refraction inside over outside (dielectrics, `pbr`).
    pub ior: f32,
    /// `pbr`: metalness in [0, 1].
    pub metallic: f32,
    /// `pbr`: KHR_materials_specular's factor, which scales the dielectric reflection.
    pub specular: f32,
    /// `pbr`: the fraction of the dielectric's diffuse part that is transmitted instead.
    pub transmission: f32,
    /// [`MAT_THIN_WALLED`], [`MAT_ALPHA_MASK`].
    pub flags: u32,
    /// The base colour's alpha factor, and the cut-off of an alpha mask.
    pub alpha: f32,
    pub alpha_cutoff: f32,
    /// The strength of the normal map's XY (glTF `normalTexture.scale`).
    pub normal_scale: f32,
    /// Texture slots: albedo/base colour (its alpha for masks), emission, roughness,
    /// metallic, transmission, and the tangent-space normal map.
    pub albedo_texture: u32,
    pub emission_texture: u32,
    pub roughness_texture: u32,
    pub metallic_texture: u32,
    pub transmission_texture: u32,
    pub normal_texture: u32,
    pub _pad: [u32; 3],
}

impl Material {
    /// A material of `kind` with neutral parameters: white, black emission, smooth, glass
    /// IOR, not metallic, full dielectric specular, opaque.
    pub fn new(kind: MaterialKind) -> Self {
        Self {
            albedo: Vec3::ONE,
            kind,
            emission: Vec3::ZERO,
            roughness: 0.0,
            specular_color: Vec3::ONE,
            ior: 1.5,
            metallic: 0.0,
            specular: 1.0,
            transmission: 0.0,
            flags: 0,
            alpha: 1.0,
            alpha_cutoff: 0.5,
            normal_scale: 1.0,
            albedo_texture: NO_TEXTURE,
            emission_texture: NO_TEXTURE,
            roughness_texture: NO_TEXTURE,
            metallic_texture: NO_TEXTURE,
            transmission_texture: NO_TEXTURE,
            normal_texture: NO_TEXTURE,
            _pad: [0; 3],
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
        let mut m = *self;
        m.texture_slots_mut().iter().any(|t| **t != NO_TEXTURE)
    }

    /// Every texture slot (`NO_TEXTURE` where the parameter reads none).
    pub fn texture_slots_mut(&mut self) -> [&mut u32; 6] {
        [
            &mut self.albedo_texture,
            &mut self.emission_texture,
            &mut self.roughness_texture,
            &mut self.metallic_texture,
            &mut self.transmission_texture,
            &mut self.normal_texture,
        ]
    }

    /// mirror: shaders/material.wgsl `is_emissive`
    pub fn is_emissive(&self) -> bool {
        self.emission.max_element() > 0.0
    }
}
