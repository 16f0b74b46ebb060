// Materials: the record every BSDF reads. mirror: src/scene/material.rs — the struct and
// every function have Rust twins of the same name; the MAT_* kind codes and NO_TEXTURE
// are generated from the Rust constants.

// mirror: src/scene/material.rs `Material` (176 bytes). Its kind is a MAT_* code; each
// texture slot holds a texture's index, or NO_TEXTURE; flags hold MAT_THIN_WALLED,
// MAT_ALPHA_MASK and MAT_SPEC_GLOSS.
struct Material {
    albedo: vec3<f32>,
    kind: u32,
    emission: vec3<f32>,
    roughness: f32,
    specular_color: vec3<f32>,
    ior: f32,
    metallic: f32,
    specular: f32,
    transmission: f32,
    flags: u32,
    alpha: f32,
    alpha_cutoff: f32,
    normal_scale: f32,
    albedo_texture: u32,
    emission_texture: u32,
    roughness_texture: u32,
    metallic_texture: u32,
    transmission_texture: u32,
    normal_texture: u32,
    specular_color_texture: u32,
    specular_texture: u32,
    clearcoat: f32,
    sheen_color: vec3<f32>,
    sheen_roughness: f32,
    coat_normal: vec3<f32>,
    clearcoat_roughness: f32,
    clearcoat_texture: u32,
    clearcoat_roughness_texture: u32,
    clearcoat_normal_texture: u32,
    clearcoat_normal_scale: f32,
    sheen_color_texture: u32,
    sheen_roughness_texture: u32,
    _pad0: u32,
    _pad1: u32,
}

// mirror: src/scene/material.rs `Material::is_emissive`
fn is_emissive(m: Material) -> bool {
    return max(max(m.emission.x, m.emission.y), m.emission.z) > 0.0;
}
