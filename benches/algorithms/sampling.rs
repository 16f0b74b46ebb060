//! Direction samplers: the seed's two ways to make a random unit vector and its diffuse
//! bounce built on them, against meshtrace's uniform-sphere and cosine-hemisphere warps
//! (`meshtrace::render::sampling`); and what their directions' distributions are.

use super::chi2::{Cells, Chi2, chi2};
use super::common::{Rng, SignedUniform};
use glam::{DVec3, Vec2};
use meshtrace::render::sampling::{sample_cosine_hemisphere, sample_uniform_sphere};
use std::f64::consts::PI;

/// The seed's fast unit vector (`Raycaster::randomUnitVector` in
/// `Step 2/include/raytracing.h`, the only one left in `Step 3/include/engine/raytracing.h`):
/// a uniform point of the cube [-1, 1)^3, normalised. Its directions crowd towards the
/// cube's corners, where the cube reaches farthest.
#[inline(always)]
pub fn seed_cube(rng: &mut impl SignedUniform) -> DVec3 {
    DVec3::new(rng.signed_f64(), rng.signed_f64(), rng.signed_f64()).normalize()
}

/// The seed's other unit vector, commented out beside the first with "the second creates
/// better results but is 18% slower": cube points drawn until one lies inside the unit
/// ball, returned as they are (the seed's callers normalise). pi/6 of the draws are kept.
#[inline(always)]
pub fn seed_rejection(rng: &mut impl SignedUniform) -> DVec3 {
    loop {
        let v = DVec3::new(rng.signed_f64(), rng.signed_f64(), rng.signed_f64());
        if v.length_squared() < 1.0 {
            return v;
        }
    }
}

/// The seed's `EPSILON` (`Step 2/include/util/std.h`).
const SEED_EPSILON: f64 = 0.000_000_1;

/// The seed's diffuse bounce (`DiffuseMaterial::scatter` in `Step 2/src/world.cpp`): the
/// normal plus a unit vector, which is cosine-distributed about the normal when the unit
/// vector is uniform. The seed replaces a result whose every component is below `EPSILON`
/// by the normal, meaning a near-zero vector; but the test is not on magnitudes, so for a
/// normal with no positive component it catches a share of ordinary directions too.
#[inline(always)]
pub fn seed_diffuse(normal: DVec3, unit: DVec3) -> DVec3 {
    let d = normal + unit.normalize();
    // The seed's Vec4 also tests w, which is 0 here.
    if d.x < SEED_EPSILON && d.y < SEED_EPSILON && d.z < SEED_EPSILON {
        normal
    } else {
        d
    }
}

/// meshtrace's uniform direction, from two of the stream's f32s.
#[inline(always)]
pub fn meshtrace_sphere(rng: &mut Rng) -> DVec3 {
    sample_uniform_sphere(Vec2::new(rng.f32(), rng.f32())).as_dvec3()
}

/// meshtrace's cosine-weighted direction about +Z (concentric disk, then up).
#[inline(always)]
pub fn meshtrace_cosine(rng: &mut Rng) -> DVec3 {
    sample_cosine_hemisphere(Vec2::new(rng.f32(), rng.f32())).as_dvec3()
}

/// Which distribution a sampler means to draw.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Target {
    /// Uniform over the sphere: 1 / (4 pi).
    Uniform,
    /// Cosine-weighted about +Z: cos theta / pi.
    Cosine,
}

impl Target {
    pub fn cells(self) -> Cells {
        match self {
            Target::Uniform => Cells::SPHERE,
            Target::Cosine => Cells::HEMISPHERE,
        }
    }

    pub fn pdf(self, w: DVec3) -> f64 {
        match self {
            Target::Uniform => 0.25 / PI,
            Target::Cosine => w.z.max(0.0) / PI,
        }
    }
}

/// A sampler under comparison: its name, the distribution it means to draw, and a draw,
/// as a unit direction in the frame where that distribution is about +Z.
pub struct Sampler {
    pub name: &'static str,
    pub target: Target,
    pub draw: fn(&mut Rng) -> DVec3,
}

/// Every sampler compared. The seed's diffuse bounce is drawn about +Z, and once about -Z
/// (a floor seen from below, a ceiling, any face turned down), where its `EPSILON` test
/// fires, mirrored into the +Z frame.
pub fn samplers() -> Vec<Sampler> {
    vec![
        Sampler {
            name: "meshtrace_sphere",
            target: Target::Uniform,
            draw: meshtrace_sphere,
        },
        Sampler {
            name: "seed_cube",
            target: Target::Uniform,
            draw: |rng| seed_cube(rng),
        },
        Sampler {
            name: "seed_rejection",
            target: Target::Uniform,
            draw: |rng| seed_rejection(rng).normalize(),
        },
        Sampler {
            name: "meshtrace_cosine",
            target: Target::Cosine,
            draw: meshtrace_cosine,
        },
        Sampler {
            name: "seed_diffuse_cube",
            target: Target::Cosine,
            draw: |rng| seed_diffuse(DVec3::Z, seed_cube(rng)).normalize(),
        },
        Sampler {
            name: "seed_diffuse_rejection",
            target: Target::Cosine,
            draw: |rng| seed_diffuse(DVec3::Z, seed_rejection(rng)).normalize(),
        },
        Sampler {
            name: "seed_diffuse_rejection_down",
            target: Target::Cosine,
            draw: |rng| {
                let d = seed_diffuse(DVec3::NEG_Z, seed_rejection(rng)).normalize();
                DVec3::new(d.x, d.y, -d.z)
            },
        },
    ]
}

/// `n` directions of `sampler` from the stream seeded `seed`.
pub fn draw(sampler: &Sampler, n: usize, seed: u64) -> Vec<DVec3> {
    let mut rng = Rng::new(seed);
    (0..n).map(|_| (sampler.draw)(&mut rng)).collect()
}

/// The chi-square test of `samples` against the distribution `target` means.
pub fn test_against(target: Target, samples: &[DVec3]) -> Chi2 {
    let cells = target.cells();
    chi2(&cells, samples, &cells.probabilities(&|w| target.pdf(w), 4))
}

/// The density of directions of a normalised uniform point of the cube [-1, 1]^3: the
/// cube's volume in the cone of a direction grows as the cube (`1 / max |w_i|`) of its
/// reach, so `r^3 / 3` over the volume 8. At a corner it is 3^1.5 = 5.2 times that at a
/// face's centre: 2.72 and 0.52 times the uniform 1 / (4 pi).
pub fn cube_pdf(w: DVec3) -> f64 {
    let m = w.abs().max_element();
    1.0 / (24.0 * m * m * m)
}

/// The chi-square test of `samples` against [`cube_pdf`].
pub fn test_against_cube(samples: &[DVec3]) -> Chi2 {
    let cells = Cells::SPHERE;
    chi2(&cells, samples, &cells.probabilities(&cube_pdf, 32))
}

/// The density of `samples` near each of `axes` (within caps of half-angle `degrees`),
/// relative to the uniform density.
pub fn density_near(samples: &[DVec3], axes: &[DVec3], degrees: f64) -> f64 {
    let cos = degrees.to_radians().cos();
    let near = samples
        .iter()
        .filter(|w| axes.iter().any(|a| w.dot(*a) > cos))
        .count() as f64;
    // Each cap holds 2 pi (1 - cos) of the sphere's 4 pi.
    let share = axes.len() as f64 * (1.0 - cos) / 2.0;
    near / (samples.len() as f64 * share)
}

/// The eight directions towards the cube's corners.
pub fn corner_axes() -> Vec<DVec3> {
    (0..8)
        .map(|k| {
            let s = |bit: i32| if k & bit == 0 { 1.0 } else { -1.0 };
            DVec3::new(s(1), s(2), s(4)).normalize()
        })
        .collect()
}

/// The six directions towards the centres of the cube's faces.
pub fn face_axes() -> Vec<DVec3> {
    vec![
        DVec3::X,
        DVec3::NEG_X,
        DVec3::Y,
        DVec3::NEG_Y,
        DVec3::Z,
        DVec3::NEG_Z,
    ]
}

/// The share of the seed's diffuse bounces about `normal` that its `EPSILON` test turns
/// into the normal itself.
pub fn replaced_by_normal(normal: DVec3, n: usize, seed: u64) -> f64 {
    let mut rng = Rng::new(seed);
    let hits = (0..n)
        .filter(|_| seed_diffuse(normal, seed_rejection(&mut rng)) == normal)
        .count();
    hits as f64 / n as f64
}
