//! Branched paths (`render::integrator`: each camera sample's first vertex sampled by
//! `branches` paths of their own, averaged) must change an image's noise, never its
//! expected value, on either device:
//!
//! - the Cornell box with 4 branches against the same box with 1 (the plain path tracer)
//!   at 16 times the samples, compared as block means of several seeds (z scores against
//!   the seeds' spread). The branches' weight 10% low with more than one branch fails it
//!   at z −22 (a block) on the CPU and −18.6 on the GPU;
//! - the same on the GPU;
//! - glass and mirror spheres with caustic light subpaths and 2 branches (each branch
//!   traces a light subpath of its own, whose splats weigh 1/2) against the path tracer
//!   alone, on the CPU and the GPU.
//!
//! And the branches share their sample's camera ray and first vertex: 4 branches trace
//! more rays than 1 camera sample and fewer than 4.

use crate::common;

use common::images::{assert_same_image, renders};
use common::scenes::{cornell, square};
use meshtrace::render::RenderJob;
use meshtrace::scene::RenderSettings;

/// A 32×32 Cornell box with `branches` branches at `spp` camera samples.
fn cornell_settings(spp: u32, branches: u32) -> RenderSettings {
    RenderSettings {
        branches: Some(branches),
        ..square(32, spp, 8, 0)
    }
}

fn cornell_check(gpu: Option<&meshtrace::render::gpu::GpuContext>) {
    let (rs, _) = cornell();
    let branched = cornell_settings(if gpu.is_some() { 8 } else { 16 }, 4);
    let plain = cornell_settings(256, 1);
    let test = renders(&rs, branched, 0..8, gpu);
    let reference = renders(&rs, plain, 100..108, None);
    let device = if gpu.is_some() { "GPU" } else { "CPU" };
    assert_same_image(
        &format!("Cornell box, 4 branches ({device}), against 1 branch"),
        &test,
        &reference,
        8,
    );
}

#[test]
fn branched_paths_keep_the_expected_image() {
    cornell_check(None);
}

#[test]
fn branched_paths_keep_the_expected_image_on_the_gpu() {
    let Some(ctx) = common::gpu("branched_paths_keep_the_expected_image_on_the_gpu") else {
        return;
    };
    cornell_check(Some(&ctx));
}

/// Each branch after the first traces at least its own path's rays: 4 branches of one
/// camera sample trace more rays than 1, and fewer than 4 whole samples (the camera ray and
/// the first vertex's shadow ray are shared).
#[test]
fn branches_share_the_camera_ray_and_first_vertex() {
    let (rs, _) = cornell();
    let rays = |spp, branches| {
        let job = RenderJob::new(cornell_settings(spp, branches));
        common::cpu_render(&rs, &job).rays() as f64
    };
    let (one, four, four_samples) = (rays(8, 1), rays(8, 4), rays(32, 1));
    eprintln!("rays: 8 spp {one}, 8 spp x 4 branches {four}, 32 spp {four_samples}");
    assert!(
        four > 2.0 * one,
        "4 branches traced {four} rays, 1 traced {one}"
    );
    assert!(
        four < 0.95 * four_samples,
        "4 branches traced {four} rays, as many as 4 samples ({four_samples})"
    );
}
