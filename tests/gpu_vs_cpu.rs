//! The GPU renderer against the CPU reference on whole images, and GPU determinism.

use crate::common;

use common::scenes::{cornell, square};
use common::stats::{fraction_close, mean_and_sd, pixel_channels as channels, same_rays};
use common::{cpu_render, gpu_render};
use meshtrace::film::{Aov, Film};
use meshtrace::render::RenderJob;
use meshtrace::render::gpu::shader::{self, Features, ShaderChecks};
use meshtrace::render::gpu::{GpuContext, GpuRenderer};
use meshtrace::scene::RenderSettings;
use std::sync::Arc;

/// The film's exact sums, for comparisons bit for bit.
fn bits(film: &Film) -> Vec<i64> {
    film.sum.iter().flatten().copied().collect()
}

/// Different seeds: the GPU and CPU images are independent draws of the same estimator.
/// The bound: with d_i = G_i - C_i over N independent pixel channels, mean(d) has standard
/// error sd(d) / sqrt(N), so a correct renderer keeps |mean(d)| under 5 of them. The mean
/// absolute difference |G - C| is compared with that of two CPU images, |C' - C|, which
/// estimates the same quantity from noise alone; the two may differ by 5 standard errors of
/// a difference of means (sqrt(2) sd(|d|) / sqrt(N)).
#[test]
fn gpu_and_cpu_agree_within_noise() {
    let Some(ctx) = common::gpu("gpu_and_cpu_agree_within_noise") else {
        return;
    };
    let (rs, _) = cornell();
    let s = square(64, 32, 8, 1);
    let gpu = channels(&gpu_render(&ctx, &rs, &RenderJob::new(s)));
    let cpu_a = channels(&cpu_render(
        &rs,
        &RenderJob::new(RenderSettings { seed: 2, ..s }),
    ));
    let cpu_b = channels(&cpu_render(
        &rs,
        &RenderJob::new(RenderSettings { seed: 3, ..s }),
    ));
    let n = gpu.len() as f64;
    let d: Vec<f64> = gpu.iter().zip(&cpu_a).map(|(g, c)| g - c).collect();
    let (mean_d, sd_d) = mean_and_sd(&d);
    assert!(
        mean_d.abs() < 5.0 * sd_d / n.sqrt(),
        "mean difference {mean_d} vs standard error {}",
        sd_d / n.sqrt()
    );
    let abs_gc: Vec<f64> = d.iter().map(|v| v.abs()).collect();
    let abs_cc: Vec<f64> = cpu_b
        .iter()
        .zip(&cpu_a)
        .map(|(b, a)| (b - a).abs())
        .collect();
    let (m_gc, sd_gc) = mean_and_sd(&abs_gc);
    let (m_cc, _) = mean_and_sd(&abs_cc);
    let bound = m_cc + 5.0 * 2f64.sqrt() * sd_gc / n.sqrt();
    eprintln!("mean |G - C| = {m_gc:.5}, mean |C' - C| = {m_cc:.5}, bound {bound:.5}");
    assert!(
        m_gc <= bound,
        "mean |G - C| = {m_gc} exceeds the noise bound {bound}"
    );
}

/// The same seed: the GPU replays the CPU's paths, so pixels agree to float rounding except
/// where rounding sends a path another way.
#[test]
fn gpu_replays_the_cpu_paths() {
    let Some(ctx) = common::gpu("gpu_replays_the_cpu_paths") else {
        return;
    };
    let (rs, _) = cornell();
    let s = square(64, 8, 8, 5);
    let job = RenderJob::new(s);
    let (gpu_film, cpu_film) = (gpu_render(&ctx, &rs, &job), cpu_render(&rs, &job));
    let frac = fraction_close(&channels(&gpu_film), &channels(&cpu_film));
    eprintln!("{:.4}% of pixel channels agree to 1e-3", 100.0 * frac);
    assert!(frac >= 0.99, "only {frac} of pixel channels agree");
    // The same paths trace the same rays: the films' `rays` channels agree pixel for pixel
    // but where rounding sent a path another way.
    let same = same_rays(&gpu_film, &cpu_film);
    eprintln!(
        "{:.4}% of pixels traced the same rays ({} GPU, {} CPU)",
        100.0 * same,
        gpu_film.rays(),
        cpu_film.rays()
    );
    assert!(same >= 0.99, "only {same} of pixels traced the same rays");
}

/// Test scene `file` with caustics on, and its settings; it must have caustic targets.
fn caustics_scene(file: &str) -> (meshtrace::render::RenderScene, RenderSettings) {
    let mut scene =
        meshtrace::scene::load_scene(&common::fs::root().join(file)).expect("test scene");
    scene.settings.caustics = true;
    let rs = meshtrace::render::RenderScene::new(&scene, &meshtrace::bvh::BuildParams::default())
        .expect("BVH");
    assert!(!rs.caustic_targets.is_empty(), "{file}: no caustic targets");
    (rs, scene.settings)
}

/// The same seed with caustic light subpaths: the GPU replays the CPU's paths and light
/// subpaths, whose splats land in other pixels, so whole images agree to float rounding.
fn replay_with_caustics(ctx: &meshtrace::render::gpu::GpuContext, file: &str) {
    let (rs, settings) = caustics_scene(file);
    let job = RenderJob::new(RenderSettings {
        spp: 16,
        ..settings
    });
    let (gpu_film, cpu_film) = (gpu_render(ctx, &rs, &job), cpu_render(&rs, &job));
    let frac = fraction_close(&channels(&gpu_film), &channels(&cpu_film));
    eprintln!(
        "{file}: {:.4}% of pixel channels agree to 1e-3",
        100.0 * frac
    );
    assert!(frac >= 0.99, "{file}: only {frac} of pixel channels agree");
    let same = same_rays(&gpu_film, &cpu_film);
    eprintln!(
        "{file}: {:.4}% of pixels traced the same rays",
        100.0 * same
    );
    assert!(
        same >= 0.99,
        "{file}: only {same} of pixels traced the same rays"
    );
}

/// tests/scenes/box_area.toml: an area light, glass and mirror spheres.
#[test]
fn gpu_replays_the_cpu_paths_with_caustics() {
    let Some(ctx) = common::gpu("gpu_replays_the_cpu_paths_with_caustics") else {
        return;
    };
    replay_with_caustics(&ctx, "tests/scenes/box_area.toml");
}

/// tests/scenes/lights.toml: light subpaths from an area light and from point, spot and
/// directional lights, through a glass sphere.
#[test]
fn gpu_replays_the_cpu_paths_with_caustics_of_punctual_lights() {
    let Some(ctx) = common::gpu("gpu_replays_the_cpu_paths_with_caustics_of_punctual_lights")
    else {
        return;
    };
    replay_with_caustics(&ctx, "tests/scenes/lights.toml");
}

/// Two GPU renders with the same seed on the same adapter are bit-identical.
#[test]
fn gpu_renders_are_deterministic() {
    let Some(ctx) = common::gpu("gpu_renders_are_deterministic") else {
        return;
    };
    let (rs, _) = cornell();
    let s = square(48, 8, 8, 9);
    let job = RenderJob::new(s);
    let a = gpu_render(&ctx, &rs, &job);
    let b = gpu_render(&ctx, &rs, &job);
    assert_eq!(bits(&a), bits(&b));
    assert_eq!(a.channels, b.channels, "ray counts");
    // With caustics, whose splats the kernel adds atomically in whatever order they come.
    let (rs, settings) = caustics_scene("tests/scenes/box_area.toml");
    let job = RenderJob::new(RenderSettings { spp: 8, ..settings });
    let (a, b) = (gpu_render(&ctx, &rs, &job), gpu_render(&ctx, &rs, &job));
    assert_eq!(bits(&a), bits(&b), "renders with caustics");
}

/// A device compiles each kernel once, for all its sessions and clones: the same entry
/// point, checks and features give the same pipeline; another entry point, checks or
/// features give another.
#[test]
fn a_device_compiles_each_kernel_once() {
    let Some(ctx) = common::gpu("a_device_compiles_each_kernel_once") else {
        return;
    };
    let plain = Features {
        textures: false,
        alpha_masks: false,
    };
    let textured = Features {
        textures: true,
        ..plain
    };
    let kernel = |ctx: &GpuContext, entry: &str, checks: ShaderChecks, features: Features| {
        ctx.pipeline(shader::test_source, entry, (1, 1), checks, features)
            .unwrap_or_else(|e| panic!("{entry}: {e}"))
    };
    let (rng, checked) = ("test_rng", ShaderChecks::Checked);
    let first = kernel(&ctx, rng, checked, plain);
    assert!(Arc::ptr_eq(
        &first,
        &kernel(&ctx.clone(), rng, checked, plain)
    ));
    for other in [
        kernel(&ctx, "test_intersect_triangle", checked, plain),
        kernel(&ctx, rng, ShaderChecks::Trusted, plain),
        kernel(&ctx, rng, checked, textured),
    ] {
        assert!(!Arc::ptr_eq(&first, &other));
    }
}

/// One renderer session renders job after job without uploading or compiling again: a
/// job rendered after another of a different size and seed gives the bits it gives in a
/// fresh session, and sample ranges dispatched one after another give the bits of one
/// render of them all.
#[test]
fn a_renderer_session_renders_many_jobs() {
    let Some(ctx) = common::gpu("a_renderer_session_renders_many_jobs") else {
        return;
    };
    let (rs, _) = cornell();
    let s = square(48, 8, 8, 4);
    let job = RenderJob::new(s);
    let fresh = gpu_render(&ctx, &rs, &job);
    assert!(
        bits(&fresh).iter().any(|&b| b != 0),
        "a black image proves nothing"
    );
    let mut session = GpuRenderer::new(&ctx, &rs).unwrap();
    let other = RenderJob::new(RenderSettings {
        width: 20,
        height: 12,
        seed: 1,
        ..s
    });
    session.render(&other, &|_| {}).unwrap();
    let again = session.render(&job, &|_| {}).unwrap();
    assert!(
        bits(&again) == bits(&fresh),
        "a reused session renders differently"
    );
    assert_eq!(again.channels, fresh.channels, "ray counts");
    session.begin(&s, 0).unwrap();
    session.dispatch(0..3, 0..s.height).unwrap();
    session.dispatch(3..8, 0..s.height).unwrap();
    let parts = session.read_film().unwrap();
    assert_eq!(parts.samples, 8);
    assert!(
        bits(&parts) == bits(&fresh),
        "dispatched ranges differ from one render"
    );
    assert_eq!(parts.channels, fresh.channels, "ray counts");
    // And the GPU replays the CPU's paths, as in gpu_replays_the_cpu_paths.
    let cpu = cpu_render(&rs, &job);
    assert!(
        fraction_close(&channels(&fresh), &channels(&cpu)) >= 0.99,
        "the GPU and CPU paths differ"
    );
}

/// A GPU film that replays the CPU's paths: 99% of pixel channels within 1e-3 of the
/// CPU's, and the two means within 1e-3 of each other.
fn assert_replays(gpu: &Film, cpu: &Film) {
    let (g, c) = (channels(gpu), channels(cpu));
    let frac = fraction_close(&g, &c);
    let (gm, cm) = (
        g.iter().sum::<f64>() / g.len() as f64,
        c.iter().sum::<f64>() / c.len() as f64,
    );
    eprintln!(
        "{:.4}% of pixel channels agree to 1e-3; mean GPU {gm}, CPU {cm}",
        100.0 * frac
    );
    assert!(frac >= 0.99, "only {frac} of pixel channels agree");
    assert!(
        (gm - cm).abs() <= 1e-3 * cm,
        "mean GPU {gm} against CPU {cm}"
    );
}

/// Long dispatches are not cut short. Mesa's lavapipe ends an invocation's loops once
/// they have run 65535 iterations in all, which 512 paths of a Cornell-box pixel pass: the
/// kernel detects the cut and leaves the pixel as it was, and the renderer sends the range
/// again in halves, so the image still replays the CPU's paths. (Without that, half of the
/// box's radiance went missing at 682 spp in one dispatch, silently.) On a hardware GPU
/// nothing is cut and the check holds as it is.
#[test]
fn long_dispatches_replay_the_cpu_paths() {
    let Some(ctx) = common::gpu("long_dispatches_replay_the_cpu_paths") else {
        return;
    };
    let (rs, _) = cornell();
    let s = square(24, 512, 8, 3);
    let job = RenderJob::new(s);
    let mut session = GpuRenderer::new(&ctx, &rs).unwrap();
    session.set_max_samples_per_dispatch(u32::MAX);
    let gpu = session.render(&job, &|_| {}).unwrap();
    let cpu = cpu_render(&rs, &job);
    assert_eq!(gpu.samples, 512);
    assert_replays(&gpu, &cpu);
}

/// Long dispatches of a render with caustics: a dispatch that the driver cuts short is
/// undone, splats included (their pixels may lie anywhere), and sent again in halves, so
/// the image still replays the CPU's paths and no splat counts twice.
#[test]
fn long_dispatches_with_caustics_replay_the_cpu_paths() {
    let Some(ctx) = common::gpu("long_dispatches_with_caustics_replay_the_cpu_paths") else {
        return;
    };
    let (rs, settings) = caustics_scene("tests/scenes/box_area.toml");
    let s = RenderSettings {
        width: 24,
        height: 18,
        spp: 512,
        ..settings
    };
    let job = RenderJob::new(s);
    let mut session = GpuRenderer::new(&ctx, &rs).unwrap();
    session.set_max_samples_per_dispatch(u32::MAX);
    let gpu = session.render(&job, &|_| {}).unwrap();
    let cpu = cpu_render(&rs, &job);
    assert_replays(&gpu, &cpu);
}

/// Renders of disjoint sample ranges merge into the full render, bit for bit, on the CPU
/// and on the GPU, AOVs included.
#[test]
fn sample_ranges_merge_into_the_full_render() {
    let (rs, _) = cornell();
    let s = square(32, 8, 8, 4);
    let aovs = Aov::mask(&Aov::ALL);
    let job =
        |range: std::ops::Range<u32>| RenderJob::new(s).with_aovs(aovs, false).with_samples(range);
    let gpu = common::gpu("sample_ranges_merge_into_the_full_render (GPU half)");
    type Render<'a> = Box<dyn Fn(&RenderJob) -> Film + 'a>;
    let mut renderers: Vec<(&str, Render)> = vec![("CPU", Box::new(|j| cpu_render(&rs, j)))];
    if let Some(ctx) = &gpu {
        renderers.push(("GPU", Box::new(|j| gpu_render(ctx, &rs, j))));
    }
    for (name, render) in renderers {
        let full = render(&job(0..8));
        let mut merged = render(&job(5..8));
        merged.merge(&render(&job(0..2)));
        merged.merge(&render(&job(2..5)));
        assert_eq!(merged.samples, full.samples, "{name}");
        assert!(
            merged == full,
            "{name}: the merged parts differ from the full render"
        );
    }
}

/// The same seed on Blender's vertex-coloured plane and on its plane with a texture on
/// the second UV map (tests/data/gltf/corpus), in the studio: the GPU replays the CPU's
/// paths through COLOR_0 and TEXCOORD_1.
#[test]
fn gpu_replays_the_cpu_paths_through_vertex_colors_and_a_second_uv_map() {
    let Some(ctx) =
        common::gpu("gpu_replays_the_cpu_paths_through_vertex_colors_and_a_second_uv_map")
    else {
        return;
    };
    for name in ["vertex_colors", "second_uv_map"] {
        let path = common::fs::data(&format!("gltf/corpus/{name}.glb"));
        let scene = meshtrace::scene::load_scene(&path).expect("corpus file");
        let rs =
            meshtrace::render::RenderScene::new(&scene, &meshtrace::bvh::BuildParams::default())
                .expect("BVH");
        assert!(
            rs.shading.iter().any(|s| s.flags
                & (meshtrace::render::TRI_COLOR | meshtrace::render::TRI_UV1)
                != 0),
            "{name}: neither colours nor a second set"
        );
        let job = RenderJob::new(square(48, 8, 6, 7));
        eprintln!("{name}:");
        assert_replays(&gpu_render(&ctx, &rs, &job), &cpu_render(&rs, &job));
    }
}
