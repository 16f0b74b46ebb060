// Counter-based random numbers (the DIM_* constants are generated from the Rust ones).
// mirror: src/render/rng.rs

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
