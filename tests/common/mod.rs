//! Helpers shared by the integration tests. Here: the GPU (or its absence) and rendering a
//! job on either device; and by subject:
//!
//! - [`cli`]: running the binary; the checks every failed run must pass.
//! - [`fs`]: the checkout's paths, fixtures, shared meshes, temporary directories.
//! - [`gltf`]: glTF files built in tests (JSON, embedded or external buffers, GLB).
//! - [`rand`]: deterministic random inputs (SplitMix64, and hashed random access).
//! - [`scenes`]: scenes built in code, the built-in Cornell box, render settings.
//! - [`stats`]: means and standard errors, relative errors, error and failure trackers.
//! - [`images`]: renders of several seeds compared block by block as z scores.
//! - [`materials`]: BSDF test helpers (material names, directions, GGX conditioning).
//! - [`chi2`]: the chi-square goodness-of-fit test of sampled directions.
//! - [`luts`]: Blender's LUTs for the Filmic and AgX views, or a skip without them.
//! - [`gamma`]: ln Gamma and the regularised incomplete gamma function (in logs), for the
//!   chi-square p-values here and in the algorithm benches.
//! - [`kernels`]: running the WGSL test kernels (case packing, bits, BSDF cases).
//! - [`traversal`]: the GPU's traversal against the CPU's over random rays, with bounds.
//!
//! The suite (`tests/main.rs`) and the binaries of their own (`ray_query`, `denoise`) each
//! compile all of it, hence `dead_code` is allowed.
#![allow(dead_code)]

pub mod chi2;
pub mod cli;
pub mod fs;
pub mod gamma;
pub mod gltf;
pub mod images;
pub mod kernels;
pub mod luts;
pub mod materials;
pub mod rand;
pub mod scenes;
pub mod stats;
pub mod studio;
pub mod traversal;

use meshtrace::film::Film;
use meshtrace::render::gpu::{Accel, GpuContext, GpuError, GpuRenderer};
use meshtrace::render::{RenderJob, RenderScene, cpu};
use std::sync::OnceLock;

/// The test binary's GPU, tracing with the software BVH (the WGSL twin of the CPU's walk),
/// or `None` (after saying "skipped: no adapter") where there is none. With
/// `MESHTRACE_REQUIRE_GPU=1`, as CI sets it, a missing adapter fails the test instead, so a
/// broken driver set-up can never pass silently.
///
/// Every test of a binary gets a clone of one context, which shares its compiled kernels:
/// lavapipe finishes compiling a kernel at its first dispatch (about 3 s with Mesa's disk
/// cache warm, up to a minute cold), so a context per test paid that in every test.
pub fn gpu(test: &str) -> Option<GpuContext> {
    static SHARED: OnceLock<Result<GpuContext, String>> = OnceLock::new();
    shared(
        &SHARED,
        test,
        Accel::Software,
        "MESHTRACE_REQUIRE_GPU",
        "the GPU",
    )
}

/// The test binary's GPU tracing with hardware ray queries, as [`gpu`] shares it, or `None`
/// (after saying why) where there is no adapter or it offers no ray queries. With
/// `MESHTRACE_REQUIRE_RAY_QUERY=1`, as CI sets it for its Mesa 25 lavapipe step, either
/// fails the test instead.
pub fn ray_query_gpu(test: &str) -> Option<GpuContext> {
    static SHARED: OnceLock<Result<GpuContext, String>> = OnceLock::new();
    shared(
        &SHARED,
        test,
        Accel::Hardware,
        "MESHTRACE_REQUIRE_RAY_QUERY",
        "ray queries",
    )
}

/// A clone of the context in `cell`, opened with `accel` by the first test that asks, or
/// `None` after saying why the test skips: a missing adapter (or ray queries), which fails
/// instead where `require` is set to 1.
fn shared(
    cell: &OnceLock<Result<GpuContext, String>>,
    test: &str,
    accel: Accel,
    require: &str,
    what: &str,
) -> Option<GpuContext> {
    let opened = cell.get_or_init(|| {
        let required = std::env::var(require).is_ok_and(|v| v == "1");
        match GpuContext::new(None, accel) {
            Ok(ctx) => Ok(ctx),
            Err(GpuError::NoAdapter) if !required => Err("no adapter".into()),
            Err(e @ GpuError::NoRayQuery(_)) if !required => Err(e.to_string()),
            Err(e) => panic!("{test}: {require}=1 but {what} is unusable: {e}"),
        }
    });
    match opened {
        Ok(ctx) => Some(ctx.clone()),
        Err(why) => {
            eprintln!("{test}: skipped: {why}");
            None
        }
    }
}

/// `job` of `scene` on the CPU and, where there is a GPU (see [`gpu`]), on the GPU: the
/// films with their device's name.
pub fn render_both_job(
    test: &str,
    scene: &meshtrace::scene::Scene,
    job: &RenderJob,
) -> Vec<(&'static str, Film)> {
    let rs = RenderScene::new(scene, &meshtrace::bvh::BuildParams::default()).expect("BVH");
    let mut out = vec![("cpu", cpu_render(&rs, job))];
    if let Some(ctx) = gpu(test) {
        out.push(("gpu", gpu_render(&ctx, &rs, job)));
    }
    out
}

/// [`render_both_job`] of the scene's own settings.
pub fn render_both(test: &str, scene: &meshtrace::scene::Scene) -> Vec<(&'static str, Film)> {
    render_both_job(test, scene, &RenderJob::new(scene.settings))
}

/// The job rendered by the CPU renderer.
pub fn cpu_render(scene: &RenderScene, job: &RenderJob) -> Film {
    cpu::render(scene, job, &|_| {})
}

/// The job rendered by a fresh GPU renderer session on `ctx`.
pub fn gpu_render(ctx: &GpuContext, scene: &RenderScene, job: &RenderJob) -> Film {
    GpuRenderer::new(ctx, scene)
        .and_then(|mut r| r.render(job, &|_| {}))
        .unwrap_or_else(|e| panic!("GPU render: {e}"))
}
