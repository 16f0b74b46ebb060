// Counter-based random numbers: Owen-scrambled Sobol points padded by pairs of dimensions
// (the DIM_* constants are generated from the Rust ones).
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

// mirror: src/render/rng.rs `sobol`
fn sobol(index: u32, dim: u32) -> u32 {
    if dim == 0u {
        return reverseBits(index);
    }
    var x = 0u;
    var d = 0x80000000u;
    // The second dimension's generator matrix: each column is the one before shifted by
    // one bit and XORed with itself (Pascal's triangle modulo 2), from 0x80000000.
    for (var bit = 0u; bit < 32u; bit++) {
        if ((index >> bit) & 1u) != 0u {
            x ^= d;
        }
        d ^= d >> 1u;
    }
    return x;
}

// mirror: src/render/rng.rs `owen_scramble`
fn owen_scramble(x: u32, seed: u32) -> u32 {
    return reverseBits(owen_hash(reverseBits(x), seed));
}

// mirror: src/render/rng.rs `sobol_reversed`
fn sobol_reversed(index: u32, dim: u32) -> u32 {
    if dim == 0u {
        return index;
    }
    return reverseBits(sobol(index, dim));
}

// mirror: src/render/rng.rs `owen_hash`
fn owen_hash(x_in: u32, seed: u32) -> u32 {
    var x = x_in + seed;
    x ^= x * 0x6c50b47cu;
    x ^= x * 0xb82f1e52u;
    x ^= x * 0xc7afe638u;
    x ^= x * 0x8d22f6e6u;
    return x;
}

// mirror: src/render/rng.rs `dim_pair`
fn dim_pair(dim: u32) -> vec2<u32> {
    if dim == DIM_PIXEL_Y || dim == DIM_LENS_V || dim == DIM_LIGHT_V || dim == DIM_BSDF_V
        || dim == DIM_CAUSTIC_LIGHT_V || dim == DIM_CAUSTIC_DIR_V {
        return vec2<u32>(dim - 1u, 1u);
    }
    return vec2<u32>(dim, 0u);
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
    let pc = dim_pair(dim);
    let seeds = pcg4d(vec4<u32>(rng.pixel, bounce * DIMS_PER_BOUNCE + pc.x, rng.seed, 0x5eedu));
    let index = owen_scramble(rng.sample, seeds.x);
    return reverseBits(owen_hash(sobol_reversed(index, pc.y), seeds[1u + pc.y]));
}

// mirror: src/render/rng.rs `Rng::rng_2d`
fn rng_2d(rng: Rng, bounce: u32, dim: u32) -> vec2<f32> {
    let seeds = pcg4d(vec4<u32>(rng.pixel, bounce * DIMS_PER_BOUNCE + dim, rng.seed, 0x5eedu));
    let index = owen_scramble(rng.sample, seeds.x);
    return vec2<f32>(
        u32_to_unit(reverseBits(owen_hash(index, seeds.y))),
        u32_to_unit(reverseBits(owen_hash(sobol_reversed(index, 1u), seeds.z))));
}

// mirror: src/render/rng.rs `Rng::rng_1d`
fn rng_1d(rng: Rng, bounce: u32, dim: u32) -> f32 {
    return u32_to_unit(rng_u32(rng, bounce, dim));
}
