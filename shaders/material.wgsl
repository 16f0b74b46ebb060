// Materials: the record every BSDF reads. mirror: src/scene/material.rs — the struct and
// every function have Rust twins of the same name; the MAT_* kind codes and NO_TEXTURE
// are generated from the Rust constants.

// mirror: src/scene/material.rs `Material` (48 bytes). Its kind is a MAT_* code; each
// texture slot holds a texture's index, or NO_TEXTURE.
struct Material {
    albedo: vec3<f32>,
    kind: u32,
    emission: vec3<f32>,
    roughness: f32,
    ior: f32,
    albedo_texture: u32,
    emission_texture: u32,
    roughness_texture: u32,
}

// mirror: src/scene/material.rs `Material::is_emissive`
fn is_emissive(m: Material) -> bool {
    return max(max(m.emission.x, m.emission.y), m.emission.z) > 0.0;
}
