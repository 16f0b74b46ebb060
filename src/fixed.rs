//! Exact film sums: every sample value is rounded once to a 64-bit fixed-point number
//! (24 fraction bits), and a pixel's sums are integer additions. Integer addition is
//! associative, so sums of disjoint sample ranges add up to the same bits as one render of
//! all of them, in any order and split in any number of parts (`render --part`, `merge`),
//! on the CPU and on the GPU, which adds the same integers as pairs of 32-bit words.
//!
//! The resolution is 2⁻²⁴ ≈ 6.0e-8 per sample: a sample's rounding error is at most half
//! of that, far below the noise of any render, and its mean over many samples is zero. A
//! sample's magnitude is clamped to [`FIXED_LIMIT`] = 2³⁸ ≈ 2.7e11, and a sum saturates at
//! ±2³⁹ (±5.5e11) instead of wrapping; sums of values of one sign stay associative even
//! then. mirror: shaders/fixed.wgsl

use glam::Vec3;

/// Fraction bits of a fixed-point value.
pub const FIXED_FRACTION_BITS: u32 = 24;

/// One unit of the value, as a fixed-point number: 2^[`FIXED_FRACTION_BITS`].
pub const FIXED_ONE: f32 = (1u64 << FIXED_FRACTION_BITS) as f32;

/// The largest magnitude a sample keeps; larger ones (and infinities) are clamped to it.
pub const FIXED_LIMIT: f32 = (1u64 << 38) as f32;

/// `v` as a fixed-point number: clamped to ±[`FIXED_LIMIT`], scaled by [`FIXED_ONE`] and
/// rounded to the nearest integer, ties to even. NaN counts as 0.
/// mirror: shaders/fixed.wgsl `to_fixed`
pub fn to_fixed(v: f32) -> i64 {
    if v.is_nan() {
        return 0;
    }
    (v.clamp(-FIXED_LIMIT, FIXED_LIMIT) * FIXED_ONE).round_ties_even() as i64
}

/// `a + b`, saturating at the ends of the i64 range instead of wrapping.
/// mirror: shaders/fixed.wgsl `fixed_add`
pub fn fixed_add(a: i64, b: i64) -> i64 {
    a.saturating_add(b)
}

/// A fixed-point sum as a float (to f64 exactly up to 2^53 units, then rounded).
pub fn from_fixed(sum: i64) -> f64 {
    sum as f64 / FIXED_ONE as f64
}

/// The three components of `v` as fixed-point numbers.
pub fn to_fixed3(v: Vec3) -> [i64; 3] {
    v.to_array().map(to_fixed)
}

/// `a + b` per component.
pub fn fixed_add3(a: [i64; 3], b: [i64; 3]) -> [i64; 3] {
    [0, 1, 2].map(|k| fixed_add(a[k], b[k]))
}

/// A film texel: four fixed-point sums (the GPU holds each as two 32-bit words).
/// mirror: shaders/fixed.wgsl `Texel`
pub type Texel = [i64; 4];

/// `t` plus `v`, component by component.
/// mirror: shaders/fixed.wgsl `texel_add`
pub fn texel_add(t: Texel, v: [f32; 4]) -> Texel {
    [0, 1, 2, 3].map(|k| fixed_add(t[k], to_fixed(v[k])))
}

/// A fixed-point value as the pair of 32-bit words (low, high) the GPU holds it in.
pub fn to_words(v: i64) -> [u32; 2] {
    [v as u32, (v >> 32) as u32]
}

/// The fixed-point value of a GPU pair of 32-bit words (low, high).
pub fn from_words(w: [u32; 2]) -> i64 {
    (w[0] as u64 | (w[1] as u64) << 32) as i64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rounds_to_nearest_even_and_clamps() {
        assert_eq!(to_fixed(1.0), 1 << 24);
        assert_eq!(to_fixed(-0.5), -(1 << 23));
        // Half a unit rounds to the even neighbour.
        assert_eq!(to_fixed(0.5 / FIXED_ONE), 0);
        assert_eq!(to_fixed(1.5 / FIXED_ONE), 2);
        assert_eq!(to_fixed(-2.5 / FIXED_ONE), -2);
        assert_eq!(to_fixed(-3.5 / FIXED_ONE), -4);
        assert_eq!(to_fixed(f32::NAN), 0);
        assert_eq!(to_fixed(f32::INFINITY), 1 << 62);
        assert_eq!(to_fixed(f32::NEG_INFINITY), -(1 << 62));
    }

    #[test]
    fn sums_saturate_and_words_round_trip() {
        assert_eq!(fixed_add(i64::MAX - 1, 5), i64::MAX);
        assert_eq!(fixed_add(i64::MIN + 1, -5), i64::MIN);
        for v in [0, 1, -1, 1 << 40, -(1 << 40) - 7, i64::MAX, i64::MIN] {
            assert_eq!(from_words(to_words(v)), v);
        }
    }
}
