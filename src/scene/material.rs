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
    /// KHR_materials_specular, _ior, _transmission, _volume, _clearcoat and _sheen.
    pub const PBR: Self = Self(4);
    /// glTF's KHR_materials_unlit: the base colour is what the camera sees; every other
    /// ray passes through the surface (as Blender's importer builds it).
    pub const UNLIT: Self = Self(5);

    /// Every kind with its name in scene files.
    pub const ALL: [(Self, &'static str); 6] = [
        (Self::DIFFUSE, "diffuse"),
        (Self::CONDUCTOR, "conductor"),
        (Self::ROUGH_CONDUCTOR, "rough_conductor"),
        (Self::DIELECTRIC, "dielectric"),
        (Self::PBR, "pbr"),
        (Self::UNLIT, "unlit"),
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
/// [`Material::flags`]: a `pbr` material of KHR_materials_pbrSpecularGlossiness: its
/// dielectric reflects with Schlick's Fresnel of F0 = `specular_color` (in place of the
/// IOR's), and its roughness texture holds glossiness, so that roughness is 1 − glossiness.
pub const MAT_SPEC_GLOSS: u32 = 4;

/// A validated material (176 bytes). Parameters that its kind does not use keep neutral
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
    /// Texture slots: albedo/base colour (its alpha for masks), emission, roughness
    /// (or glossiness), metallic, transmission, the tangent-space normal map, and
    /// KHR_materials_specular's colour (RGB) and factor.
    pub albedo_texture: u32,
    pub emission_texture: u32,
    pub roughness_texture: u32,
    pub metallic_texture: u32,
    pub transmission_texture: u32,
    pub normal_texture: u32,
    pub specular_color_texture: u32,
    pub specular_texture: u32,
    /// `pbr`: KHR_materials_clearcoat's weight in [0, 1] (0: no coat).
    pub clearcoat: f32,
    /// `pbr`: KHR_materials_sheen's colour (black: no sheen) and perceptual roughness.
    pub sheen_color: Vec3,
    pub sheen_roughness: f32,
    /// `pbr`: the clear coat's normal in the shading frame: +Z, unless the coat's own
    /// normal differs from the base's at a hit (a normal map on either; set per hit).
    pub coat_normal: Vec3,
    /// `pbr`: the clear coat's perceptual roughness.
    pub clearcoat_roughness: f32,
    /// Texture slots of the clear coat's weight, roughness and normal map.
    pub clearcoat_texture: u32,
    pub clearcoat_roughness_texture: u32,
    pub clearcoat_normal_texture: u32,
    /// The strength of the clear coat's normal map's XY.
    pub clearcoat_normal_scale: f32,
    /// Texture slots of the sheen's colour and roughness.
    pub sheen_color_texture: u32,
    pub sheen_roughness_texture: u32,
    pub _pad: [u32; 2],
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
            specular_color_texture: NO_TEXTURE,
            specular_texture: NO_TEXTURE,
            clearcoat: 0.0,
            sheen_color: Vec3::ZERO,
            sheen_roughness: 0.0,
            coat_normal: Vec3::Z,
            clearcoat_roughness: 0.0,
            clearcoat_texture: NO_TEXTURE,
            clearcoat_roughness_texture: NO_TEXTURE,
            clearcoat_normal_texture: NO_TEXTURE,
            clearcoat_normal_scale: 1.0,
            sheen_color_texture: NO_TEXTURE,
            sheen_roughness_texture: NO_TEXTURE,
            _pad: [0; 2],
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
    pub fn texture_slots_mut(&mut self) -> [&mut u32; 13] {
        [
            &mut self.albedo_texture,
            &mut self.emission_texture,
            &mut self.roughness_texture,
            &mut self.metallic_texture,
            &mut self.transmission_texture,
            &mut self.normal_texture,
            &mut self.specular_color_texture,
            &mut self.specular_texture,
            &mut self.clearcoat_texture,
            &mut self.clearcoat_roughness_texture,
            &mut self.clearcoat_normal_texture,
            &mut self.sheen_color_texture,
            &mut self.sheen_roughness_texture,
        ]
    }

    /// The normal map whose tangent frame the material's triangles need: the base's, else
    /// the clear coat's (`NO_TEXTURE` for neither). Where both exist, the coat's map is read
    /// with the tangents of the base's texture coordinate set.
    pub fn tangent_map(&self) -> u32 {
        if self.normal_texture != NO_TEXTURE {
            self.normal_texture
        } else {
            self.clearcoat_normal_texture
        }
    }

    /// Whether some rays pass through the surface, so that traversal asks before counting a
    /// hit on it: an alpha mask, and an unlit surface, which only camera rays see.
    pub fn is_masked(&self) -> bool {
        self.flags & MAT_ALPHA_MASK != 0 || self.kind == MaterialKind::UNLIT
    }

    /// mirror: shaders/material.wgsl `is_emissive`
    pub fn is_emissive(&self) -> bool {
        self.emission.max_element() > 0.0
    }
}
