//! The environment map: radiance arriving from an equirectangular image around the scene,
//! and its importance sampling: a cell of the image drawn from a piecewise-constant
//! distribution over the cells, weighed by luminance × sin θ and built once on the host
//! with the scene's tables (`build.rs`), then a point in the cell drawn in proportion to
//! its bilinear luminance. Every function has a WGSL twin of the same name in
//! `shaders/environment.wgsl`.
//!
//! The image is read as Mitsuba 3's `envmap` reads it, so that the two agree pixel for
//! pixel: bilinearly between texel centres along u (wrapping around), and along v between
//! rows placed at v = row / (height − 1), the first row at the zenith and the last at the
//! nadir. A cell spans the texel centres of two neighbouring columns and two neighbouring
//! rows, over which the radiance is bilinear.

use super::sampling::ONE_MINUS_EPSILON;
use super::tables::RenderScene;
use super::texture::{texel, texel_span};
use crate::scene::{Texture, Wrap};
use glam::{Vec2, Vec3, Vec4};
use std::f32::consts::PI;

/// The luminance of texel (`x`, `y`) of image `t`, or 0 where that is not positive: the
/// environment's sampling weight.
/// mirror: shaders/environment.wgsl `texel_luminance`
pub fn texel_luminance(scene: &RenderScene, t: &Texture, x: u32, y: u32) -> f32 {
    let c = texel(scene, t, x, y);
    let l = 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
    if l > 0.0 { l } else { 0.0 }
}

/// The luminances at the corners of cell (`i`, `j`) of image `t`: its row `i` at columns
/// `j` and `j + 1` (around), then its row `i + 1` (the last row for an image of one row).
/// mirror: shaders/environment.wgsl `cell_corners`
pub fn cell_corners(scene: &RenderScene, t: &Texture, i: u32, j: u32) -> Vec4 {
    let k = (j + 1) % t.width;
    let below = (i + 1).min(t.height - 1);
    Vec4::new(
        texel_luminance(scene, t, j, i),
        texel_luminance(scene, t, k, i),
        texel_luminance(scene, t, j, below),
        texel_luminance(scene, t, k, below),
    )
}

/// A point of [0, 1) drawn with density proportional to the line from `a` at 0 to `b` at
/// 1 (both at least 0), from the uniform number `u`; `u` itself where both are 0.
/// mirror: shaders/environment.wgsl `sample_linear`
pub fn sample_linear(u: f32, a: f32, b: f32) -> f32 {
    if a + b <= 0.0 {
        return u;
    }
    let x = u * (a + b) / (a + (a * a + u * (b * b - a * a)).max(0.0).sqrt());
    x.clamp(0.0, ONE_MINUS_EPSILON)
}

/// The density, relative to the cell's mean, of the bilinear luminance `c` (as
/// [`cell_corners`] orders them) at (`x`, `y`) in the cell; 0 for a black cell.
/// mirror: shaders/environment.wgsl `cell_density`
pub fn cell_density(c: Vec4, x: f32, y: f32) -> f32 {
    let mean = 0.25 * (c.x + c.y + c.z + c.w);
    if mean <= 0.0 {
        return 0.0;
    }
    let top = c.x + x * (c.y - c.x);
    let bottom = c.z + x * (c.w - c.z);
    (top + y * (bottom - top)) / mean
}

/// Where unit direction `dir` reads the environment's image: (u, v), u from the left edge
/// around and v from the zenith (the top row) down, after the environment's rotation.
/// mirror: shaders/environment.wgsl `env_uv`
pub fn env_uv(scene: &RenderScene, dir: Vec3) -> Vec2 {
    let [c, s] = scene.env.rotation;
    let x = c * dir.x - s * dir.z;
    let z = s * dir.x + c * dir.z;
    let mut u = x.atan2(-z) * (0.5 / PI);
    if u < 0.0 {
        u += 1.0;
    }
    // θ = acos(y), as atan2: GPUs' acos may be off by 1e-4, which a sun 10⁴ times
    // brighter than its sky turns into visible differences.
    let theta = (x * x + z * z).sqrt().atan2(dir.y);
    Vec2::new(u, theta * (1.0 / PI))
}

/// Radiance arriving along unit `dir` from the environment: its image read bilinearly
/// (between texel centres along u, between rows at v = row / (height − 1) along v), times
/// its strength.
/// mirror: shaders/environment.wgsl `env_radiance`
pub fn env_radiance(scene: &RenderScene, dir: Vec3) -> Vec3 {
    let t = &scene.textures[scene.env.texture as usize];
    let uv = env_uv(scene, dir);
    let (xa, xb, fx) = texel_span(uv.x, t.width, Wrap::REPEAT.0);
    let y = uv.y * (t.height - 1) as f32;
    let y0 = y.floor();
    let fy = y - y0;
    let ya = (y0.max(0.0) as u32).min(t.height - 1);
    let yb = (ya + 1).min(t.height - 1);
    let top = texel(scene, t, xa, ya) * (1.0 - fx) + texel(scene, t, xb, ya) * fx;
    let bottom = texel(scene, t, xa, yb) * (1.0 - fx) + texel(scene, t, xb, yb) * fx;
    scene.env.strength * (top * (1.0 - fy) + bottom * fy).truncate()
}

/// Solid-angle probability density of [`sample_env`] drawing unit direction `dir` (0 at
/// the poles, where no cell has area).
/// mirror: shaders/environment.wgsl `env_pdf`
pub fn env_pdf(scene: &RenderScene, dir: Vec3) -> f32 {
    let t = &scene.textures[scene.env.texture as usize];
    let [nx, ny] = scene.env.cells;
    let uv = env_uv(scene, dir);
    let sin_theta = (1.0 - dir.y * dir.y).max(0.0).sqrt();
    if sin_theta <= 0.0 {
        return 0.0;
    }
    let mut x = uv.x * nx as f32 - 0.5;
    if x < 0.0 {
        x += nx as f32;
    }
    let y = uv.y * ny as f32;
    let j = (x.max(0.0) as u32).min(nx - 1);
    let i = (y.max(0.0) as u32).min(ny - 1);
    let within = cell_density(
        cell_corners(scene, t, i, j),
        (x - j as f32).clamp(0.0, 1.0),
        (y - i as f32).clamp(0.0, 1.0),
    );
    let p = cdf_step(scene, 0, i) * cdf_step(scene, ny + i * nx, j) * within;
    p * (nx * ny) as f32 / (2.0 * PI * PI * sin_theta)
}

/// The probability of bucket `k` of the inclusive CDF that starts at `env_cdf[start]`.
/// mirror: shaders/environment.wgsl `cdf_step`
pub fn cdf_step(scene: &RenderScene, start: u32, k: u32) -> f32 {
    let at = (start + k) as usize;
    let prev = if k > 0 { scene.env_cdf[at - 1] } else { 0.0 };
    scene.env_cdf[at] - prev
}

/// The bucket of the inclusive CDF `env_cdf[start..start + n]` that holds `u`, and where
/// in the bucket `u` falls, in [0, 1).
/// mirror: shaders/environment.wgsl `search_cdf`
pub fn search_cdf(scene: &RenderScene, start: u32, n: u32, u: f32) -> (u32, f32) {
    let (mut lo, mut hi) = (0u32, n - 1);
    while lo < hi {
        let mid = (lo + hi) / 2;
        if scene.env_cdf[(start + mid) as usize] <= u {
            lo = mid + 1;
        } else {
            hi = mid;
        }
    }
    let p = cdf_step(scene, start, lo);
    let prev = scene.env_cdf[(start + lo) as usize] - p;
    let within = if p > 0.0 { (u - prev) / p } else { 0.5 };
    (lo, within.clamp(0.0, ONE_MINUS_EPSILON))
}

/// A direction drawn from the environment's distribution with the uniform numbers `u`,
/// and its solid-angle density ([`env_pdf`]; 0 where the draw lands on a pole): a cell by
/// the CDFs, then a point in it with density proportional to its bilinear luminance (the
/// radiance's own interpolation), so that radiance over density barely varies in a cell.
/// mirror: shaders/environment.wgsl `sample_env`
pub fn sample_env(scene: &RenderScene, u: Vec2) -> (Vec3, f32) {
    let t = &scene.textures[scene.env.texture as usize];
    let [nx, ny] = scene.env.cells;
    let (i, fy) = search_cdf(scene, 0, ny, u.y);
    let (j, fx) = search_cdf(scene, ny + i * nx, nx, u.x);
    let c = cell_corners(scene, t, i, j);
    let y = sample_linear(fy, c.x + c.y, c.z + c.w);
    let x = sample_linear(fx, c.x + y * (c.z - c.x), c.y + y * (c.w - c.y));
    let mut eu = (j as f32 + x + 0.5) / nx as f32;
    if eu >= 1.0 {
        eu -= 1.0;
    }
    let ev = (i as f32 + y) / ny as f32;
    let (sin_theta, cos_theta) = (PI * ev).sin_cos();
    let (sin_phi, cos_phi) = (2.0 * PI * eu).sin_cos();
    let dx = sin_theta * sin_phi;
    let dz = -sin_theta * cos_phi;
    let [rc, rs] = scene.env.rotation;
    let dir = Vec3::new(rc * dx + rs * dz, cos_theta, -rs * dx + rc * dz);
    if sin_theta <= 0.0 {
        return (dir, 0.0);
    }
    let p = cdf_step(scene, 0, i) * cdf_step(scene, ny + i * nx, j) * cell_density(c, x, y);
    (dir, p * (nx * ny) as f32 / (2.0 * PI * PI * sin_theta))
}
