// Exact film sums: 64-bit fixed-point numbers held as (low, high) pairs of 32-bit words,
// two's complement. mirror: src/fixed.rs

const FIXED_MAX: vec2<u32> = vec2<u32>(0xffffffffu, 0x7fffffffu);
const FIXED_MIN: vec2<u32> = vec2<u32>(0u, 0x80000000u);

// mirror: src/fixed.rs `to_fixed`
//
// Every step is exact: the scaling is by a power of two, `round` rounds ties to even, and
// for |x| >= 2^32 the low word x - hi * 2^32 is a multiple of x's spacing below 2^32, so it
// has at most 23 significant bits.
fn to_fixed(v: f32) -> vec2<u32> {
    // NaN by its bits: a compiler may assume floats are never NaN.
    if (bitcast<u32>(v) & 0x7fffffffu) > 0x7f800000u {
        return vec2<u32>(0u);
    }
    let x = round(clamp(v, -FIXED_LIMIT, FIXED_LIMIT) * FIXED_ONE);
    let a = abs(x);
    let hi = floor(a * (1.0 / 4294967296.0));
    let lo = a - hi * 4294967296.0;
    let m = vec2<u32>(u32(lo), u32(hi));
    if x >= 0.0 {
        return m;
    }
    // -m: invert both words and add one, carrying into the high word.
    let nlo = ~m.x + 1u;
    return vec2<u32>(nlo, ~m.y + select(0u, 1u, nlo == 0u));
}

// mirror: src/fixed.rs `fixed_add`
fn fixed_add(a: vec2<u32>, b: vec2<u32>) -> vec2<u32> {
    let lo = a.x + b.x;
    let hi = a.y + b.y + select(0u, 1u, lo < a.x);
    // Overflow: both operands of one sign, the sum of the other.
    if ((~(a.y ^ b.y) & (a.y ^ hi)) >> 31u) != 0u {
        return select(FIXED_MAX, FIXED_MIN, (a.y >> 31u) != 0u);
    }
    return vec2<u32>(lo, hi);
}

// A film texel: four fixed-point sums (x, y, z, w), two words each.
// mirror: src/fixed.rs `Texel`
struct Texel {
    xy: vec4<u32>,
    zw: vec4<u32>,
}

// mirror: src/fixed.rs `texel_add`
fn texel_add(t: Texel, v: vec4<f32>) -> Texel {
    return Texel(
        vec4<u32>(fixed_add(t.xy.xy, to_fixed(v.x)), fixed_add(t.xy.zw, to_fixed(v.y))),
        vec4<u32>(fixed_add(t.zw.xy, to_fixed(v.z)), fixed_add(t.zw.zw, to_fixed(v.w))),
    );
}
