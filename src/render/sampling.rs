//! Warps from the unit square to the distributions the path tracer draws from.
//! Each function has a WGSL twin of the same name in `shaders/sampling.wgsl`.

use glam::{BVec4A, Vec2, Vec3, Vec4};
use std::f32::consts::{FRAC_1_PI, FRAC_PI_4};
use std::hint::select_unpredictable;

/// Concentric map of the square onto the unit disk (Shirley and Chiu 1997). The angle
/// within the octant is at most pi/4 from an axis, so its sine and cosine come from
/// [`sincos_octant`] (swapped in the octants about the y axis), not from a library call.
/// Both kinds of octant run the same operations on selected operands, without a branch:
/// which kind a sample falls in is a coin toss that a branch would mispredict half the time.
/// mirror: shaders/sampling.wgsl `sample_concentric_disk`
pub fn sample_concentric_disk(u: Vec2) -> Vec2 {
    let o = 2.0 * u - Vec2::ONE;
    if o.x == 0.0 && o.y == 0.0 {
        return Vec2::ZERO;
    }
    // About the y axis theta = pi/2 - phi: cos theta = sin phi, sin theta = cos phi. The
    // operands are picked by four-lane selects, which compile to bitwise masks (a scalar
    // float select becomes a branch on x86).
    let y_major = BVec4A::splat(o.x.abs() <= o.y.abs());
    let rq = Vec4::select(
        y_major,
        Vec4::new(o.y, o.x, 0.0, 0.0),
        Vec4::new(o.x, o.y, 0.0, 0.0),
    );
    let (s, c) = sincos_octant(FRAC_PI_4 * (rq.y / rq.x));
    let d = Vec4::select(
        y_major,
        Vec4::new(s, c, 0.0, 0.0),
        Vec4::new(c, s, 0.0, 0.0),
    );
    rq.x * Vec2::new(d.x, d.y)
}

/// The sine and cosine of `x` in [−pi/4, pi/4], by the minimax polynomials of Cephes'
/// `sinf` and `cosf` (within 2 × 10⁻⁷ of the true values there), in plain multiplies and
/// adds that both devices round alike: no range reduction, no library call.
/// mirror: shaders/sampling.wgsl `sincos_octant`
pub fn sincos_octant(x: f32) -> (f32, f32) {
    let z = x * x;
    let s = ((-1.951_529_6e-4 * z + 8.332_161e-3) * z - 1.666_665_5e-1) * z * x + x;
    let c = ((2.443_315_7e-5 * z - 1.388_731_6e-3) * z + 4.166_664_6e-2) * z * z - 0.5 * z + 1.0;
    (s, c)
}

/// Cosine-weighted direction about +Z; its pdf is `cos_theta / pi`. The height comes from
/// the disk point's radius (the larger of |2u − 1|'s components), not from the point, so
/// that it need not wait for the point's sine and cosine.
/// mirror: shaders/sampling.wgsl `sample_cosine_hemisphere`
pub fn sample_cosine_hemisphere(u: Vec2) -> Vec3 {
    let d = sample_concentric_disk(u);
    let o = 2.0 * u - Vec2::ONE;
    let r = o.x.abs().max(o.y.abs());
    let z = ((1.0 - r) * (1.0 + r)).max(0.0).sqrt();
    Vec3::new(d.x, d.y, z)
}

/// Pdf of `sample_cosine_hemisphere` in solid angle. mirror: shaders/sampling.wgsl `cosine_hemisphere_pdf`
pub fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    cos_theta.max(0.0) * FRAC_1_PI
}

/// A uniform direction on the unit sphere. mirror: shaders/sampling.wgsl `sample_uniform_sphere`
pub fn sample_uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * std::f32::consts::PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// The largest float below 1: where a uniform number rescaled to [0, 1) is clamped.
pub const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// The pdf of `sample_uniform_sphere`: 1 / (4 pi).
pub const UNIFORM_SPHERE_PDF: f32 = 0.25 * FRAC_1_PI;

/// Uniform barycentrics (b1, b2) on a triangle, by the square-root warp (pbrt-v3 §13.6.4).
/// mirror: shaders/sampling.wgsl `sample_uniform_triangle`
pub fn sample_uniform_triangle(u: Vec2) -> Vec2 {
    let su = u.x.sqrt();
    Vec2::new(1.0 - su, u.y * su)
}

/// The power heuristic (beta = 2) weight of a strategy with pdf `a` against one with pdf `b`.
/// mirror: shaders/sampling.wgsl `power_heuristic`
pub fn power_heuristic(a: f32, b: f32) -> f32 {
    let a2 = a * a;
    let b2 = b * b;
    if a2 + b2 == 0.0 { 0.0 } else { a2 / (a2 + b2) }
}

/// Index of the first CDF entry greater than `u`, and the entry below it (0 for the
/// first): the discrete sample of a distribution whose inclusive CDF (last entry 1) is
/// `cdf`, and where its bucket starts. A binary search whose steps depend only on the
/// length: each halves the range by conditional moves, not a branch (which a random `u`
/// would mispredict at every step). mirror: shaders/sampling.wgsl `sample_cdf`
pub fn sample_cdf(cdf: &[f32], u: f32) -> (usize, f32) {
    // The answer lies in base .. base + n; the last entry is never at or below u.
    // The entry below is kept as its bits: an integer select is a conditional move, a
    // float select a branch on x86.
    let (mut base, mut n, mut below) = (0usize, cdf.len(), 0u32);
    while n > 1 {
        let half = n / 2;
        let c = cdf[base + half - 1];
        base = select_unpredictable(c <= u, base + half, base);
        below = select_unpredictable(c <= u, c.to_bits(), below);
        n -= half;
    }
    (base, f32::from_bits(below))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::rng::Rng;

    fn u2(rng: &Rng, i: u32) -> Vec2 {
        Vec2::new(rng.rng_1d(i, 0), rng.rng_1d(i, 1))
    }

    #[test]
    fn disk_samples_lie_in_the_disk_with_uniform_density() {
        let rng = Rng::new(0, 0, 1);
        let n = 50_000;
        let mut inner = 0;
        for i in 0..n {
            let p = sample_concentric_disk(u2(&rng, i));
            assert!(p.length() <= 1.0 + 1e-6);
            inner += (p.length() < 0.5) as u32;
        }
        // A quarter of a uniform disk's area lies within radius 1/2; binomial sd is ~0.002.
        let frac = inner as f32 / n as f32;
        assert!((frac - 0.25).abs() < 0.01, "{frac}");
    }

    #[test]
    fn octant_sine_and_cosine_are_within_two_ten_millionths() {
        let n = 200_000;
        let mut worst: f64 = 0.0;
        for i in 0..=n {
            let x = FRAC_PI_4 * (2.0 * i as f32 / n as f32 - 1.0);
            let (s, c) = sincos_octant(x);
            let x = x as f64;
            worst = worst
                .max((s as f64 - x.sin()).abs())
                .max((c as f64 - x.cos()).abs());
        }
        assert!(worst < 2e-7, "{worst}");
    }

    #[test]
    fn cosine_hemisphere_has_mean_cos_two_thirds() {
        let rng = Rng::new(0, 0, 2);
        let n = 50_000;
        let mean: f32 = (0..n)
            .map(|i| sample_cosine_hemisphere(u2(&rng, i)).z)
            .sum::<f32>()
            / n as f32;
        // E[cos] under p = cos/pi is 2/3; sd of cos is ~0.24, so the standard error is ~0.001.
        assert!((mean - 2.0 / 3.0).abs() < 0.006, "{mean}");
    }

    #[test]
    fn triangle_barycentrics_are_uniform() {
        let rng = Rng::new(0, 0, 3);
        let n = 50_000;
        let mut mean = Vec2::ZERO;
        for i in 0..n {
            let b = sample_uniform_triangle(u2(&rng, i));
            assert!(b.x >= 0.0 && b.y >= 0.0 && b.x + b.y <= 1.0 + 1e-6);
            mean += b;
        }
        mean /= n as f32;
        // The centroid has barycentrics (1/3, 1/3).
        assert!(
            (mean - Vec2::splat(1.0 / 3.0)).abs().max_element() < 0.006,
            "{mean}"
        );
    }

    #[test]
    fn cdf_sampling_picks_the_right_bucket() {
        let cdf = [0.25, 0.25, 0.75, 1.0];
        assert_eq!(sample_cdf(&cdf, 0.0), (0, 0.0));
        assert_eq!(sample_cdf(&cdf, 0.2499), (0, 0.0));
        assert_eq!(sample_cdf(&cdf, 0.25), (2, 0.25)); // the empty bucket 1 is never chosen
        assert_eq!(sample_cdf(&cdf, 0.7), (2, 0.25));
        assert_eq!(sample_cdf(&cdf, 0.75), (3, 0.75));
        assert_eq!(sample_cdf(&cdf, 0.9999), (3, 0.75));
    }

    #[test]
    fn cdf_sampling_counts_the_entries_at_or_below_u_and_returns_the_last() {
        let rng = Rng::new(0, 0, 4);
        for len in 1..40u32 {
            // Some buckets empty (repeated entries), the last entry 1.
            let mut cdf: Vec<f32> = (0..len)
                .map(|i| (rng.rng_1d(len, i) * 8.0).floor() / 8.0)
                .collect();
            cdf.sort_by(f32::total_cmp);
            *cdf.last_mut().unwrap() = 1.0;
            for k in 0..200 {
                let u = rng.rng_1d(1000 + len, k);
                let index = cdf.iter().filter(|&&c| c <= u).count();
                let below = if index > 0 { cdf[index - 1] } else { 0.0 };
                assert_eq!(sample_cdf(&cdf, u), (index, below), "{cdf:?}, u = {u}");
            }
        }
    }
}
