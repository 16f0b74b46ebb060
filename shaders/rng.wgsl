// Counter-based random numbers. mirror: src/render/rng.rs

const DIM_PIXEL_X: u32 = 0u;
const DIM_PIXEL_Y: u32 = 1u;
const DIM_LENS_U: u32 = 2u;
const DIM_LENS_V: u32 = 3u;
const DIM_LIGHT_PICK: u32 = 4u;
const DIM_LIGHT_U: u32 = 5u;
const DIM_LIGHT_V: u32 = 6u;
const DIM_BSDF_LOBE: u32 = 7u;
const DIM_BSDF_U: u32 = 8u;
const DIM_BSDF_V: u32 = 9u;
const DIM_ROULETTE: u32 = 10u;
const DIMS_PER_BOUNCE: u32 = 16u;

// mirror: src/render/rng.rs `pcg4d`
fn pcg4d(v_in: vec4<u32>) -> vec4<u32> {
    var v = v_in * 1664525u + 1013904223u;
    v.x += v.y * v.w;
    v.y += v.z * v.x;
    v.z += v.x * v.y;
    v.w += v.y * v.z;
    v = v ^ (v >> vec4<u32>(16u));
    v.x += v.y * v.w;
    v.y += v.z * v.x;
    v.z += v.x * v.y;
    v.w += v.y * v.z;
    return v;
}

// mirror: src/render/rng.rs `u32_to_unit`
fn u32_to_unit(x: u32) -> f32 {
    return f32(x >> 8u) * (1.0 / 16777216.0);
}

// mirror: src/render/rng.rs `Rng`
struct Rng {
    pixel: u32,
    sample: u32,
    seed: u32,
}

// mirror: src/render/rng.rs `Rng::rng_u32`
fn rng_u32(rng: Rng, bounce: u32, dim: u32) -> u32 {
    return pcg4d(vec4<u32>(rng.pixel, rng.sample, bounce * DIMS_PER_BOUNCE + dim, rng.seed)).x;
}

// mirror: src/render/rng.rs `Rng::rng_1d`
fn rng_1d(rng: Rng, bounce: u32, dim: u32) -> f32 {
    return u32_to_unit(rng_u32(rng, bounce, dim));
}
