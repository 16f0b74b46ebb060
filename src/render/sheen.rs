//! KHR_materials_sheen's lobe: the "Charlie" fibre distribution and shadowing of Conty
//! Estevez and Kulla (2017), as the extension writes them, and the table of its
//! directional albedo E(cos θ, roughness) that scales the layer beneath it. Every
//! function but the table's construction has a WGSL twin of the same name in
//! `shaders/sheen.wgsl`; the GPU reads the table's values from the scene's lookup table,
//! at [`SHEEN_TABLE_OFFSET`].

use glam::Vec3;
use std::f32::consts::{FRAC_1_PI, PI};
use std::sync::OnceLock;

/// The least sheen roughness evaluated: below it the distribution's exponent 1/α makes
/// the lobe a spike that no sampling finds (the glTF Sample Viewer clamps there too).
pub const SHEEN_MIN_ROUGHNESS: f32 = 0.07;
/// The albedo table's size: cosines by roughnesses.
pub const SHEEN_TABLE_COSINES: u32 = 32;
pub const SHEEN_TABLE_ROUGHNESSES: u32 = 16;
/// Where the albedo table starts in the scene's lookup table (after the 8-bit texel
/// decoding: 256 sRGB and 256 linear values).
pub const SHEEN_TABLE_OFFSET: u32 = 512;

/// The polynomial of the shadowing fit, interpolated between its fits at roughness 0 and
/// 1 by (1 − α)². mirror: shaders/sheen.wgsl `sheen_l`
pub fn sheen_l(x: f32, alpha: f32) -> f32 {
    let t = (1.0 - alpha) * (1.0 - alpha);
    let mix = |a: f32, b: f32| a + (b - a) * t;
    let a = mix(21.5473, 25.3245);
    let b = mix(3.82987, 3.32435);
    let c = mix(0.19823, 0.16801);
    let d = mix(-1.97760, -1.27393);
    let e = mix(-4.32054, -4.85967);
    a / (1.0 + b * x.powf(c)) + d * x + e
}

/// The shadowing term Λ at cosine `cos_t`. mirror: shaders/sheen.wgsl `sheen_lambda`
pub fn sheen_lambda(cos_t: f32, alpha: f32) -> f32 {
    let c = cos_t.abs();
    if c < 0.5 {
        sheen_l(c, alpha).exp()
    } else {
        (2.0 * sheen_l(0.5, alpha) - sheen_l(1.0 - c, alpha)).exp()
    }
}

/// The Charlie distribution at a half vector of cosine `cos_h`.
/// mirror: shaders/sheen.wgsl `sheen_d`
pub fn sheen_d(cos_h: f32, alpha: f32) -> f32 {
    let inv = 1.0 / alpha;
    let sin2 = (1.0 - cos_h * cos_h).max(0.0);
    (2.0 + inv) * sin2.powf(0.5 * inv) * (0.5 * FRAC_1_PI)
}

/// The sheen lobe's f |cos wi| for colour `color` and roughness `roughness`, both
/// directions above the surface: colour · D / ((1 + Λ(wo) + Λ(wi)) 4 wo.z).
/// mirror: shaders/sheen.wgsl `sheen_reflect`
pub fn sheen_reflect(color: Vec3, roughness: f32, wo: Vec3, wi: Vec3) -> Vec3 {
    if wo.z <= 0.0 || wi.z <= 0.0 {
        return Vec3::ZERO;
    }
    let alpha = roughness.max(SHEEN_MIN_ROUGHNESS);
    let h = (wo + wi).normalize_or_zero();
    let g = 1.0 + sheen_lambda(wo.z, alpha) + sheen_lambda(wi.z, alpha);
    color * (sheen_d(h.z, alpha) / (g * 4.0 * wo.z))
}

/// The sheen's directional albedo E at cosine `cos_t` for `roughness`: the table
/// [`sheen_table`] interpolated bilinearly (roughness clamped to
/// [[`SHEEN_MIN_ROUGHNESS`], 1] as [`sheen_reflect`] clamps it).
/// mirror: shaders/sheen.wgsl `sheen_albedo`
pub fn sheen_albedo(cos_t: f32, roughness: f32) -> f32 {
    let table = sheen_table();
    let x = cos_t.clamp(0.0, 1.0) * (SHEEN_TABLE_COSINES - 1) as f32;
    let r = roughness.clamp(SHEEN_MIN_ROUGHNESS, 1.0);
    let y = (r - SHEEN_MIN_ROUGHNESS) / (1.0 - SHEEN_MIN_ROUGHNESS)
        * (SHEEN_TABLE_ROUGHNESSES - 1) as f32;
    let i = (x as u32).min(SHEEN_TABLE_COSINES - 2);
    let j = (y as u32).min(SHEEN_TABLE_ROUGHNESSES - 2);
    let (fx, fy) = (x - i as f32, y - j as f32);
    let e = |i: u32, j: u32| table[(j * SHEEN_TABLE_COSINES + i) as usize];
    let near = e(i, j) * (1.0 - fx) + e(i + 1, j) * fx;
    let far = e(i, j + 1) * (1.0 - fx) + e(i + 1, j + 1) * fx;
    near * (1.0 - fy) + far * fy
}

/// The sheen's directional albedo E(cos θ, roughness) of white sheen, row by roughness
/// (from [`SHEEN_MIN_ROUGHNESS`] to 1) and column by cosine (0 to 1): the integral of
/// [`sheen_reflect`] over the hemisphere, by the midpoint rule on 96 × 96 cells of
/// (cos θi, φ), summed in double precision. Computed once per process (a few hundredths
/// of a second), and only when a scene has sheen.
pub fn sheen_table() -> &'static [f32] {
    static TABLE: OnceLock<Vec<f32>> = OnceLock::new();
    TABLE.get_or_init(|| {
        const N: usize = 96;
        let (cosines, roughnesses) = (SHEEN_TABLE_COSINES, SHEEN_TABLE_ROUGHNESSES);
        let mut out = Vec::with_capacity((cosines * roughnesses) as usize);
        for j in 0..roughnesses {
            let roughness = SHEEN_MIN_ROUGHNESS
                + (1.0 - SHEEN_MIN_ROUGHNESS) * j as f32 / (roughnesses - 1) as f32;
            for i in 0..cosines {
                // Cosine 0 is taken just above the horizon, where the integral's limit is.
                let mu = (i as f32 / (cosines - 1) as f32).max(1e-4);
                let wo = Vec3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
                let mut sum = 0.0f64;
                for a in 0..N {
                    let mu_i = (a as f32 + 0.5) / N as f32;
                    let s = (1.0 - mu_i * mu_i).sqrt();
                    // φ over [0, π], doubled: the lobe is symmetric about wo's plane.
                    for b in 0..N {
                        let phi = PI * (b as f32 + 0.5) / N as f32;
                        let wi = Vec3::new(s * phi.cos(), s * phi.sin(), mu_i);
                        sum += sheen_reflect(Vec3::ONE, roughness, wo, wi).x as f64;
                    }
                }
                // dω = dμ dφ: cells of 1/N by π/N, doubled for φ's other half.
                out.push((sum * 2.0 * std::f64::consts::PI / (N * N) as f64) as f32);
            }
        }
        out
    })
}
