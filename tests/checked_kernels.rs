//! The trusted render kernel's claims, tested: renders and benchmarks compile the WGSL with
//! every runtime check off (`ShaderChecks::Trusted`), which is sound only if the kernel
//! indexes in range and divides by no zero. The checked build of the same source tests
//! each such claim where the kernel relies on it and fails the render if one does not
//! hold. Here every scene of the suite's kinds (meshes, spheres, area, punctual and sky
//! lights, an environment map, glTF materials, textures in every wrap mode, normal maps,
//! alpha masks, AOVs) renders checked with no failure and gives the trusted kernel's bits.
//!
//! (libtest starts tests in the order of their names, and the checked kernels' compiles run
//! on one core for about a minute: under a name late in the alphabet, `shader_checks`, this
//! test ran last and alone for its final 41 s of CI's suite; here it runs beside the others.)

use crate::common;

use common::fs::TempDir;
use meshtrace::bvh::BuildParams;
use meshtrace::film::{Aov, Film};
use meshtrace::render::gpu::{GpuContext, GpuRenderer};
use meshtrace::render::{RenderJob, RenderScene};
use meshtrace::scene::load_scene;
use std::path::{Path, PathBuf};

fn root(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// A textured scene made here: a floor whose albedo repeats a 5×3 checker, a wall whose
/// albedo clamps and whose normal map mirrors, and a quad cut out by an alpha mask, under
/// a point light and a constant sky; texture coordinates run well outside [0, 1].
fn textured_scene(dir: &TempDir) -> PathBuf {
    let checker: Vec<[u8; 4]> = (0..15)
        .map(|i| {
            if i % 2 == 0 {
                [230, 40, 40, 255]
            } else {
                [30, 200, 60, 255]
            }
        })
        .collect();
    dir.write_png("checker.png", 5, 3, &checker);
    let bumps: Vec<[u8; 4]> = (0..12)
        .map(|i| [100 + 12 * i as u8, 128, 230, 255])
        .collect();
    dir.write_png("bumps.png", 4, 3, &bumps);
    let mask: Vec<[u8; 4]> = (0..7)
        .map(|i| [255, 255, 255, if i % 3 == 0 { 0 } else { 255 }])
        .collect();
    dir.write_png("mask.png", 7, 1, &mask);
    dir.write(
        "floor.obj",
        "v -2 0 -2\nv 2 0 -2\nv 2 0 2\nv -2 0 2\nvt -3.3 4.1\nvt 5.7 4.1\nvt 5.7 -2.2\nvt -3.3 -2.2\n\
         f 1/1 4/4 3/3 2/2\n",
    );
    dir.write(
        "wall.obj",
        "v -2 0 -1\nv 2 0 -1\nv 2 2 -1\nv -2 2 -1\nvt -1.5 -0.5\nvt 2.5 -0.5\nvt 2.5 1.5\nvt -1.5 1.5\n\
         vn 0 0 1\nf 1/1/1 2/2/1 3/3/1 4/4/1\n",
    );
    dir.write(
        "quad.obj",
        "v -0.8 0.2 0.3\nv 0.8 0.2 0.3\nv 0.8 1.4 0.3\nv -0.8 1.4 0.3\nvt 0 0\nvt 3 0\nvt 3 1\nvt 0 1\n\
         f 1/1 2/2 3/3 4/4\n",
    );
    dir.write(
        "scene.toml",
        "[camera]\nposition = [0.3, 1.2, 3.5]\nlook_at = [0.0, 0.6, 0.0]\nvfov = 50.0\n\
         [render]\nwidth = 32\nheight = 24\nspp = 4\nmax_depth = 6\n\
         [sky]\ncolor = [0.3, 0.3, 0.3]\n\
         [materials.floor]\ntype = \"diffuse\"\nalbedo = { texture = \"checker.png\" }\n\
         [materials.wall]\ntype = \"diffuse\"\n\
         albedo = { texture = \"checker.png\", wrap = \"clamp\" }\n\
         normal_map = { texture = \"bumps.png\", wrap = \"mirror\" }\n\
         [materials.mask]\ntype = \"diffuse\"\nalbedo = { texture = \"mask.png\" }\n\
         alpha_cutoff = 0.5\n\
         [[objects]]\nmesh = \"floor.obj\"\nmaterial = \"floor\"\n\
         [[objects]]\nmesh = \"wall.obj\"\nmaterial = \"wall\"\n\
         [[objects]]\nmesh = \"quad.obj\"\nmaterial = \"mask\"\n\
         [[lights]]\ntype = \"point\"\nposition = [0.5, 1.8, 1.5]\nintensity = [3.0, 3.0, 3.0]\n",
    )
}

/// The film's exact sums, radiance and every channel, for comparisons bit for bit.
fn bits(film: &Film) -> Vec<i64> {
    let mut out: Vec<i64> = film.sum.iter().flatten().copied().collect();
    for c in &film.channels {
        out.extend(c.data.iter().flatten());
    }
    out
}

/// Renders every scene on `trusted` and on its checked twin: no check may fail, and the
/// films must agree bit for bit.
fn check_scenes(trusted: GpuContext) {
    let checked = trusted.clone().with_shader_checks();
    let dir = TempDir::new("shader checks");
    let mut scenes: Vec<PathBuf> = [
        "assets/cornell/cornell.toml",
        "assets/seed/seed.toml",
        "tests/scenes/box_area.toml",
        "tests/scenes/env_sun.toml",
        "tests/scenes/glass_dof.toml",
        "tests/scenes/gltf_room.toml",
        "tests/scenes/lights.toml",
    ]
    .iter()
    .map(|s| root(s))
    .collect();
    scenes.push(textured_scene(&dir));
    for path in &scenes {
        let name = path.display().to_string();
        let scene = load_scene(path).unwrap_or_else(|e| panic!("{name}: {e}"));
        let rs = RenderScene::new(&scene, &BuildParams::default()).expect("BVH");
        let mut settings = scene.settings;
        (settings.width, settings.height, settings.spp) = (32, 24, 4);
        let mut job = RenderJob::new(settings);
        job.aovs = Aov::mask(&Aov::ALL);
        let film = |ctx| {
            GpuRenderer::new(ctx, &rs)
                .and_then(|mut r| r.render(&job, &|_| {}))
                .unwrap_or_else(|e| panic!("{name}: {e}"))
        };
        let (a, b) = (film(&trusted), film(&checked));
        assert!(
            a.sum.iter().flatten().any(|&v| v != 0),
            "{name}: a black image"
        );
        assert!(
            bits(&a) == bits(&b),
            "{name}: the checked kernel's film differs"
        );
        eprintln!(
            "{name} ({}): checked, no failure, same bits",
            trusted.accel_name()
        );
    }
}

#[test]
fn find_every_index_in_range_and_match_the_trusted_bits() {
    if let Some(ctx) = common::gpu("checked_kernels_find_every_index_in_range") {
        check_scenes(ctx);
    }
}

/// The same with hardware ray queries, where the adapter offers them. CI's Mesa 25 step
/// leaves it out: that lavapipe takes 45 s to compile each of the two kernels, and the
/// claims are those of the shading code that the test above covers (the traversal is the
/// driver's, and ray-query tracking stays on).
#[test]
fn with_ray_queries_find_every_index_in_range_and_match_the_trusted_bits() {
    if let Some(ctx) = common::ray_query_gpu("checked_ray_query_kernels") {
        check_scenes(ctx);
    }
}
