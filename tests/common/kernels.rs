//! Running the test kernels of `shaders/tests.wgsl` (through
//! `meshtrace::render::gpu::kernels::run_test_kernel`): a case is two `[u32; 4]` words in
//! and two out, floats as their bits. Packing and unpacking, running with a report of the
//! time taken, and the cases of the BSDF kernels.

use glam::Vec3;
use meshtrace::render::RenderScene;
use meshtrace::render::gpu::GpuContext;
use meshtrace::render::gpu::kernels::run_test_kernel;
use meshtrace::scene::RenderSettings;
use std::time::Instant;

/// Two words in, or two words out.
pub type Case = [[u32; 4]; 2];

/// A float as its bits.
pub fn b(x: f32) -> u32 {
    x.to_bits()
}

/// A float from its bits.
pub fn f(x: u32) -> f32 {
    f32::from_bits(x)
}

/// The vector in the first three lanes of a word.
pub fn v3(w: [u32; 4]) -> Vec3 {
    Vec3::new(f(w[0]), f(w[1]), f(w[2]))
}

/// A word of a vector and a fourth lane `w`.
pub fn word(v: Vec3, w: u32) -> [u32; 4] {
    [b(v.x), b(v.y), b(v.z), w]
}

/// Runs `entry` over `cases` and returns the output of each case, saying how long the GPU
/// took.
pub fn run(
    ctx: &GpuContext,
    scene: &RenderScene,
    settings: &RenderSettings,
    entry: &str,
    cases: &[Case],
) -> Vec<Case> {
    let input: Vec<[u32; 4]> = cases.iter().flatten().copied().collect();
    let start = Instant::now();
    let out = run_test_kernel(ctx, scene, settings, entry, &input)
        .unwrap_or_else(|e| panic!("{entry}: {e}"));
    eprintln!(
        "{entry}: {} cases on the GPU in {:.2} s",
        cases.len(),
        start.elapsed().as_secs_f64()
    );
    assert_eq!(out.len(), input.len(), "{entry}: output length");
    out.chunks(2).map(|c| [c[0], c[1]]).collect()
}

/// A `test_bsdf_sample` case: material index `m` (into the scene's table), wo, and the
/// sample's (u_lobe, u.x, u.y).
pub fn bsdf_sample_case(m: u32, wo: Vec3, u: [f32; 3]) -> Case {
    [word(wo, m), word(Vec3::from(u), 0)]
}

/// A `test_bsdf_eval` case: material index `m`, wo and wi.
pub fn bsdf_eval_case(m: u32, wo: Vec3, wi: Vec3) -> Case {
    [word(wo, m), word(wi, 0)]
}

/// The output of `test_bsdf_sample`.
#[derive(Clone, Copy, Debug)]
pub struct GpuBsdfSample {
    pub wi: Vec3,
    pub pdf: f32,
    pub weight: Vec3,
    pub valid: bool,
    pub delta: bool,
    /// The lobe kind (`LOBE_*`), for the bounce limits.
    pub lobe: u32,
}

impl GpuBsdfSample {
    pub fn from_output(o: &Case) -> Self {
        Self {
            wi: v3(o[0]),
            pdf: f(o[0][3]),
            weight: v3(o[1]),
            valid: o[1][3] & 1 != 0,
            delta: o[1][3] & 2 != 0,
            lobe: o[1][3] >> 2,
        }
    }
}

/// The output of `test_bsdf_eval`: (bsdf_eval, i.e. f |cos theta_i|, and bsdf_pdf).
pub fn bsdf_eval_output(o: &Case) -> (Vec3, f32) {
    (v3(o[0]), f(o[0][3]))
}

/// Runs `test_bsdf_sample` over (material index, wo, u) cases.
pub fn gpu_bsdf_samples(
    ctx: &GpuContext,
    scene: &RenderScene,
    settings: &RenderSettings,
    cases: &[(u32, Vec3, [f32; 3])],
) -> Vec<GpuBsdfSample> {
    let cases: Vec<Case> = cases
        .iter()
        .map(|&(m, wo, u)| bsdf_sample_case(m, wo, u))
        .collect();
    run(ctx, scene, settings, "test_bsdf_sample", &cases)
        .iter()
        .map(GpuBsdfSample::from_output)
        .collect()
}

/// Runs `test_bsdf_eval` over (material index, wo, wi) cases.
pub fn gpu_bsdf_evals(
    ctx: &GpuContext,
    scene: &RenderScene,
    settings: &RenderSettings,
    cases: &[(u32, Vec3, Vec3)],
) -> Vec<(Vec3, f32)> {
    let cases: Vec<Case> = cases
        .iter()
        .map(|&(m, wo, wi)| bsdf_eval_case(m, wo, wi))
        .collect();
    run(ctx, scene, settings, "test_bsdf_eval", &cases)
        .iter()
        .map(bsdf_eval_output)
        .collect()
}
