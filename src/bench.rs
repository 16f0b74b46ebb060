//! Throughput measurements of both renderers, for `meshtrace bench`: BVH build rate, ray
//! rates for coherent, incoherent and shadow rays, and full path tracing. Each measure runs
//! once to warm up, then `repeats` times; the median and the spread are reported.

use crate::bvh::{BuildParams, Bvh, BvhError, Hit};
use crate::film::FilmError;
use crate::geometry::{T_INF, geometric_normal};
use crate::math::{Aabb, Ray, onb_from_normal};
use crate::render::camera::{CameraRays, generate_camera_ray};
use crate::render::gpu::{GpuContext, GpuError, GpuRenderer, kernels::Kernel, shader};
use crate::render::rng::Rng;
use crate::render::sampling::{sample_cosine_hemisphere, sample_uniform_triangle};
use crate::render::surface::offset_ray_origin;
use crate::render::texture::alpha_test;
use crate::render::{RenderJob, RenderScene, SKY_EMITTER, cpu};
use crate::scene::{
    Camera, Material, Mesh, NO_NORMAL, NO_UV, RenderSettings, Scene, Sky, Triangle, studio,
};
use glam::{Vec2, Vec3};
use rayon::prelude::*;
use std::path::Path;
use std::time::Instant;

/// One reported number: the median of `repeats` timed runs, with their extremes.
#[derive(Clone, Debug, PartialEq)]
pub struct Measure {
    pub scene: String,
    pub device: String,
    /// How a GPU measure found hits ("hardware" ray queries or the "software" BVH); `None`
    /// on the host and the CPU.
    pub accel: Option<&'static str>,
    pub measure: &'static str,
    pub unit: &'static str,
    pub median: f64,
    pub min: f64,
    pub max: f64,
    pub repeats: usize,
}

/// How much to measure.
#[derive(Clone, Copy, Debug)]
pub struct BenchOptions {
    pub repeats: usize,
    pub width: u32,
    pub height: u32,
    /// Samples per pixel of the path-tracing measure.
    pub spp: u32,
}

impl Default for BenchOptions {
    fn default() -> Self {
        Self {
            repeats: 5,
            width: 512,
            height: 512,
            spp: 4,
        }
    }
}

/// The benchmark rays of a scene: one camera ray per pixel of the scene's view and of a
/// narrower view that its subject fills ([`fill_view`]), a cosine-distributed bounce from
/// each primary hit, and a shadow ray from each hit towards a light (or a random point of
/// the scene where it has no emitters).
pub struct RaySets {
    pub primary: Vec<BenchRay>,
    pub primary_fill: Vec<BenchRay>,
    /// The share of `primary` and of `primary_fill` rays whose closest hit is on the
    /// subject: what the rates measure is mostly traversal of the mesh, not of empty space
    /// (or of the studio's ground).
    pub primary_hits: f64,
    pub primary_fill_hits: f64,
    pub incoherent: Vec<BenchRay>,
    pub shadow: Vec<BenchRay>,
}

/// A ray and its extent.
pub type BenchRay = (Ray, f32);

/// One jittered ray per pixel of `cam`, from the bench's own random stream.
fn camera_rays(cam: &CameraRays) -> Vec<BenchRay> {
    (0..cam.width * cam.height)
        .map(|i| {
            let rng = Rng::new(i, 0, 0x0bec);
            (
                generate_camera_ray(cam, i % cam.width, i / cam.width, &rng),
                T_INF,
            )
        })
        .collect()
}

/// The closest hit as the CPU renderer finds it.
fn closest(scene: &RenderScene, ray: &Ray, t_max: f32) -> Option<Hit> {
    scene
        .wide
        .traverse_closest(ray, t_max, |k, u, v| alpha_test(scene, k, u, v, false))
}

/// The share of `rays` whose closest hit is on a triangle that `subject` marks.
fn subject_share(scene: &RenderScene, subject: &[bool], rays: &[BenchRay]) -> f64 {
    let hits = rays
        .par_iter()
        .filter(|(r, t)| closest(scene, r, *t).is_some_and(|h| subject[h.tri as usize]))
        .count();
    hits as f64 / rays.len().max(1) as f64
}

/// The view that the subject fills: the scene's camera with its field of view narrowed by
/// steps of 0.8 until at least 85% of a 64 x 64 probe's rays hit the subject (at most 24
/// steps, 0.5% of the width). A view already that full is kept as it is.
pub fn fill_view(scene: &RenderScene, subject: &[bool], width: u32, height: u32) -> CameraRays {
    let mut cam = CameraRays::new(&scene.camera, width, height);
    for _ in 0..24 {
        let probe = camera_rays(&CameraRays {
            width: 64,
            height: 64,
            ..cam
        });
        if subject_share(scene, subject, &probe) >= 0.85 {
            break;
        }
        cam.tan_half_vfov *= 0.8;
    }
    cam
}

impl RaySets {
    /// The rays of a `width` x `height` image of `scene`; `subject[k]` says whether
    /// leaf-order triangle `k` belongs to what the scene shows (all but a studio's ground).
    pub fn new(scene: &RenderScene, subject: &[bool], width: u32, height: u32) -> Self {
        let primary = camera_rays(&CameraRays::new(&scene.camera, width, height));
        let primary_fill = camera_rays(&fill_view(scene, subject, width, height));
        let bounds = scene.bvh.nodes.first().map_or(Aabb::EMPTY, |n| n.bounds());
        let hits: Vec<(u32, Ray, Vec3, Vec3)> = primary
            .par_iter()
            .enumerate()
            .filter_map(|(i, (ray, t))| {
                let h = closest(scene, ray, *t)?;
                let mut n = geometric_normal(&scene.tris[h.tri as usize]);
                if n.dot(ray.dir) > 0.0 {
                    n = -n;
                }
                Some((i as u32, *ray, ray.at(h.t), n))
            })
            .collect();
        let lights: Vec<u32> = scene
            .emitters
            .iter()
            .copied()
            .filter(|&e| e != SKY_EMITTER)
            .collect();
        let mut incoherent = Vec::with_capacity(hits.len());
        let mut shadow = Vec::with_capacity(hits.len());
        for &(i, _, p, n) in &hits {
            let rng = Rng::new(i, 1, 0x0bec);
            let u = Vec2::new(rng.rng_1d(0, 0), rng.rng_1d(0, 1));
            let (t, b) = onb_from_normal(n);
            let l = sample_cosine_hemisphere(u);
            let dir = l.x * t + l.y * b + l.z * n;
            incoherent.push((Ray::new(offset_ray_origin(p, n, dir), dir), T_INF));
            let target = if lights.is_empty() {
                bounds.min + bounds.extent() * Vec3::new(u.x, u.y, rng.rng_1d(0, 3))
            } else {
                let e = lights[rng.rng_u32(0, 2) as usize % lights.len()];
                let [a, b, c] = scene.tris[e as usize].corners();
                let w = sample_uniform_triangle(u);
                (1.0 - w.x - w.y) * a + w.x * b + w.y * c
            };
            let origin = offset_ray_origin(p, n, target - p);
            let d = target - origin;
            let dist = d.length();
            if dist > 0.0 {
                shadow.push((Ray::new(origin, d / dist), dist * (1.0 - 1e-4)));
            }
        }
        Self {
            primary_hits: subject_share(scene, subject, &primary),
            primary_fill_hits: subject_share(scene, subject, &primary_fill),
            primary,
            primary_fill,
            incoherent,
            shadow,
        }
    }
}

/// Runs `f` once to warm up, then `repeats` times; returns the rates `work / seconds`.
fn timed(
    repeats: usize,
    work: f64,
    mut f: impl FnMut() -> Result<f64, BenchError>,
) -> Result<Vec<f64>, BenchError> {
    f()?;
    (0..repeats.max(1))
        .map(|_| f().map(|s| work / s.max(1e-9)))
        .collect()
}

fn summarize(
    scene: &str,
    device: &str,
    measure: &'static str,
    unit: &'static str,
    mut rates: Vec<f64>,
) -> Measure {
    rates.sort_by(f64::total_cmp);
    Measure {
        scene: scene.to_string(),
        device: device.to_string(),
        accel: None,
        measure,
        unit,
        median: rates[rates.len() / 2],
        min: rates[0],
        max: rates[rates.len() - 1],
        repeats: rates.len(),
    }
}

fn ray_words(rays: &[BenchRay]) -> Vec<[u32; 4]> {
    rays.iter()
        .flat_map(|(r, t_max)| {
            [
                r.origin.extend(*t_max).to_array().map(f32::to_bits),
                r.dir.extend(0.0).to_array().map(f32::to_bits),
            ]
        })
        .collect()
}

/// Why a scene could not be measured.
#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    #[error(transparent)]
    Gpu(#[from] GpuError),
    #[error(transparent)]
    Bvh(#[from] BvhError),
    #[error(transparent)]
    Write(#[from] FilmError),
}

/// Writes the scene's triangles (leaf order, nine floats each) and each ray set's rays
/// (origin, `t_max`, direction, 0: eight floats each), little-endian, as
/// `NAME.triangles.f32` and `NAME.VIEW.rays.f32` in `dir`, for comparisons with other
/// ray tracers on exactly the same work.
fn write_rays(
    dir: &Path,
    name: &str,
    scene: &RenderScene,
    views: &[(&str, &[BenchRay])],
) -> Result<(), FilmError> {
    let tris: Vec<f32> = scene
        .tris
        .iter()
        .flat_map(|t| t.corners().into_iter().flat_map(|c| c.to_array()))
        .collect();
    crate::film::write_bytes(
        &dir.join(format!("{name}.triangles.f32")),
        bytemuck::cast_slice(&tris),
    )?;
    for (view, rays) in views {
        let words = ray_words(rays);
        crate::film::write_bytes(
            &dir.join(format!("{name}.{view}.rays.f32")),
            bytemuck::cast_slice(&words),
        )?;
    }
    Ok(())
}

/// Measures one scene on the CPU and, when `gpu` is given, on that device. With
/// `rays_out`, also writes the ray sets there ([`write_rays`]): the two primary views, the
/// diffuse bounces and the shadow rays.
pub fn bench_scene(
    name: &str,
    scene: &Scene,
    gpu: Option<&GpuContext>,
    cpu: bool,
    opts: &BenchOptions,
    rays_out: Option<&Path>,
) -> Result<Vec<Measure>, BenchError> {
    let mut out = Vec::new();
    let bounds: Vec<Aabb> = scene
        .mesh
        .triangles
        .iter()
        .map(|t| Aabb::from_points(&scene.mesh.vertices(t)))
        .collect();
    let tris = bounds.len() as f64;
    let mut sah = 0.0;
    let builds = timed(opts.repeats, tris / 1e6, || {
        let start = Instant::now();
        let bvh = Bvh::build(&bounds, &BuildParams::default())?;
        sah = bvh.stats.sah_cost as f64;
        Ok(start.elapsed().as_secs_f64())
    })?;
    out.push(summarize(name, "host", "bvh_build", "Mtris/s", builds));
    out.push(summarize(name, "host", "sah_cost", "cost", vec![sah]));

    let rs = RenderScene::new(scene, &BuildParams::default())?;
    // Everything but a studio's ground is the subject.
    let ground = scene
        .material_names
        .iter()
        .position(|n| n == studio::GROUND_MATERIAL);
    let subject: Vec<bool> = rs
        .bvh
        .order
        .iter()
        .map(|&i| Some(scene.mesh.triangles[i as usize].material as usize) != ground)
        .collect();
    let rays = RaySets::new(&rs, &subject, opts.width, opts.height);
    out.push(summarize(
        name,
        "host",
        "primary_hits",
        "fraction",
        vec![rays.primary_hits],
    ));
    out.push(summarize(
        name,
        "host",
        "primary_fill_hits",
        "fraction",
        vec![rays.primary_fill_hits],
    ));
    if let Some(dir) = rays_out {
        write_rays(
            dir,
            name,
            &rs,
            &[
                ("primary", &rays.primary),
                ("primary_fill", &rays.primary_fill),
                ("incoherent", &rays.incoherent),
                ("shadow", &rays.shadow),
            ],
        )?;
    }
    let sets: [(&'static str, &[BenchRay], bool); 4] = [
        ("primary_rays", &rays.primary[..], false),
        ("primary_fill_rays", &rays.primary_fill[..], false),
        ("incoherent_rays", &rays.incoherent[..], false),
        ("shadow_rays", &rays.shadow[..], true),
    ];
    let settings = RenderSettings {
        width: opts.width,
        height: opts.height,
        spp: opts.spp,
        max_depth: scene.settings.max_depth,
        seed: 0,
        caustics: scene.settings.caustics,
        branches: scene.settings.branches,
        filter_width: scene.settings.filter_width,
        bounces: scene.settings.bounces,
    };
    let job = RenderJob::new(settings);
    let samples = opts.width as f64 * opts.height as f64 * opts.spp as f64;
    if cpu {
        for (measure, set, any) in sets {
            let n = set.len() as f64 / 1e6;
            let rates = timed(opts.repeats, n, || {
                let start = Instant::now();
                let hits: usize = set
                    .par_iter()
                    .map(|(r, t)| {
                        if any {
                            rs.wide
                                .traverse_any(r, *t, |k, u, v| alpha_test(&rs, k, u, v, false))
                                as usize
                        } else {
                            closest(&rs, r, *t).is_some() as usize
                        }
                    })
                    .sum();
                std::hint::black_box(hits);
                Ok(start.elapsed().as_secs_f64())
            })?;
            out.push(summarize(name, "cpu", measure, "Mrays/s", rates));
        }
        let mut path_rays = 0u64;
        let rates = timed(opts.repeats, samples / 1e6, || {
            let start = Instant::now();
            path_rays = cpu::render(&rs, &job, &|_| {}).rays();
            Ok(start.elapsed().as_secs_f64())
        })?;
        push_path(&mut out, name, "cpu", rates, path_rays as f64 / samples);
    }
    if let Some(ctx) = gpu {
        let first = out.len();
        let mut renderer = GpuRenderer::new(ctx, &rs)?;
        let checks = shader::ShaderChecks::Trusted;
        for (measure, set, any) in sets {
            let entry = if any { "bench_any" } else { "bench_closest" };
            let kernel = Kernel::new(&renderer, &settings, shader::bench_source, checks, entry)?;
            let words = ray_words(set);
            let n = set.len() as f64 / 1e6;
            let rates = timed(opts.repeats, n, || {
                Ok(kernel.run(&words, set.len(), set.len())?.1)
            })?;
            out.push(summarize(name, "gpu", measure, "Mrays/s", rates));
        }
        let mut path_rays = 0u64;
        let rates = timed(opts.repeats, samples / 1e6, || {
            let start = Instant::now();
            path_rays = renderer.render(&job, &|_| {})?.rays();
            Ok(start.elapsed().as_secs_f64())
        })?;
        push_path(&mut out, name, "gpu", rates, path_rays as f64 / samples);
        let accel = if ctx.ray_query {
            "hardware"
        } else {
            "software"
        };
        for m in &mut out[first..] {
            m.accel = Some(accel);
        }
    }
    Ok(out)
}

/// Path tracing in Msamples/s, and in Mrays/s from the rays each sample traced.
fn push_path(
    out: &mut Vec<Measure>,
    scene: &str,
    device: &str,
    rates: Vec<f64>,
    rays_per_sample: f64,
) {
    let rays = rates.iter().map(|r| r * rays_per_sample).collect();
    out.push(summarize(
        scene,
        device,
        "path_samples",
        "Msamples/s",
        rates,
    ));
    out.push(summarize(scene, device, "path_rays", "Mrays/s", rays));
}

/// A generated height field of `2 n^2` triangles: rolling hills under a white sky, framed
/// from the front, for measuring large meshes without shipping one.
pub fn terrain(n: u32) -> Scene {
    let mut mesh = Mesh::default();
    let size = 10.0;
    for j in 0..=n {
        for i in 0..=n {
            let (x, z) = (
                size * (i as f32 / n as f32 - 0.5),
                size * (j as f32 / n as f32 - 0.5),
            );
            let y = 0.6 * (1.3 * x).sin() * (0.9 * z).cos()
                + 0.25 * (3.7 * x + 2.1 * z).sin()
                + 0.05 * (17.0 * x).sin() * (13.0 * z).cos();
            mesh.positions.push(Vec3::new(x, y, z));
        }
    }
    let idx = |i: u32, j: u32| j * (n + 1) + i;
    for j in 0..n {
        for i in 0..n {
            let (a, b, c, d) = (idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1));
            for p in [[a, d, c], [a, c, b]] {
                mesh.triangles.push(Triangle {
                    p,
                    n: [NO_NORMAL; 3],
                    t: [NO_UV; 3],
                    material: 0,
                });
            }
        }
    }
    let bounds = Aabb::from_points(&mesh.positions);
    Scene {
        path: None,
        camera: Camera::framing(&bounds).expect("the terrain is small and centred"),
        sky: Sky::Constant(Vec3::ONE),
        settings: RenderSettings::default(),
        materials: vec![Material::diffuse(Vec3::splat(0.7))],
        material_names: vec!["ground".into()],
        textures: Default::default(),
        lights: Vec::new(),
        mesh,
        warnings: Vec::new(),
        notes: Vec::new(),
        framed: None,
        root_origin: None,
    }
}

/// The measures as a JSON array: one object per (scene, device, measure).
pub fn to_json(measures: &[Measure]) -> String {
    let esc = |s: &str| s.replace('\\', "\\\\").replace('"', "\\\"");
    let rows: Vec<String> = measures
        .iter()
        .map(|m| {
            format!(
                "  {{\"scene\": \"{}\", \"device\": \"{}\", \"measure\": \"{}\", \"unit\": \"{}\", \"median\": {}, \"min\": {}, \"max\": {}, \"repeats\": {}, \"accel\": {}}}",
                esc(&m.scene),
                esc(&m.device),
                m.measure,
                m.unit,
                m.median,
                m.min,
                m.max,
                m.repeats,
                m.accel.map_or("null".to_string(), |a| format!("\"{a}\""))
            )
        })
        .collect();
    format!("[\n{}\n]", rows.join(",\n"))
}
