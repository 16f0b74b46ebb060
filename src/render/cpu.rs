//! The CPU reference path tracer: the oracle the GPU renderer is tested against.
//!
//! A unidirectional path tracer with next event estimation on emissive triangles (chosen
//! by power) combined with BSDF sampling by the power heuristic, and Russian roulette from
//! depth 5, as Mitsuba 3's `path` integrator. It is kept plain on purpose: every stage has
//! a WGSL twin of the same name in `shaders/pathtrace.wgsl`, and both draw every random
//! number from the same counter-based [`Rng`]. Parallel over tiles with rayon; no I/O.

use super::bsdf::{bsdf_eval, bsdf_is_delta, bsdf_pdf, bsdf_sample};
use super::rng::{self, Rng};
use super::sampling::{
    UNIFORM_SPHERE_PDF, power_heuristic, sample_cdf, sample_uniform_sphere, sample_uniform_triangle,
};
use super::{Checkpoints, RenderJob, RenderScene, SKY_EMITTER, TRI_SMOOTH};
use crate::bvh::{Hit, traverse_any, traverse_closest};
use crate::film::Film;
use crate::geometry::{self, T_INF};
use crate::math::{Ray, onb_from_normal};
use crate::scene::MaterialKind;
use glam::{Vec2, Vec3};
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};

/// Path depth (in bounces) from which Russian roulette may end a path.
pub const RR_DEPTH: u32 = 5;
/// Tiles are square, this many pixels on a side.
pub const TILE: u32 = 16;

/// A ray's hit point with the frames its shading needs.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceHit {
    pub p: Vec3,
    /// Geometric normal of the front face ((v1 − v0) × (v2 − v0)).
    pub ng: Vec3,
    /// Interpolated shading normal, on the same side as `ng`.
    pub ns: Vec3,
    pub material: u32,
    pub front_face: bool,
    pub tri: u32,
}

/// mirror: shaders/pathtrace.wgsl `surface_at`
pub fn surface_at(scene: &RenderScene, ray: &Ray, hit: &Hit) -> SurfaceHit {
    let tri = &scene.tris[hit.tri as usize];
    let sh = &scene.shading[hit.tri as usize];
    let ng = geometry::geometric_normal(tri);
    let mut ns = ng;
    if sh.flags & TRI_SMOOTH != 0 {
        let w = 1.0 - hit.u - hit.v;
        let n = w * Vec3::from(sh.n0) + hit.u * Vec3::from(sh.n1) + hit.v * Vec3::from(sh.n2);
        ns = n.normalize_or_zero();
        if ns.dot(ng) < 0.0 {
            ns = -ns;
        }
        if ns == Vec3::ZERO {
            ns = ng;
        }
    }
    SurfaceHit {
        p: ray.at(hit.t),
        ng,
        ns,
        material: sh.material,
        front_face: ray.dir.dot(ng) < 0.0,
        tri: hit.tri,
    }
}

/// Moves a ray origin off the surface, to the side of `ng` that `w` points to, by a margin
/// that grows with the coordinates' magnitude (float error grows with it).
/// mirror: shaders/pathtrace.wgsl `offset_ray_origin`
pub fn offset_ray_origin(p: Vec3, ng: Vec3, w: Vec3) -> Vec3 {
    let eps = 1e-5 * (1.0 + p.abs().max_element());
    if w.dot(ng) >= 0.0 {
        p + eps * ng
    } else {
        p - eps * ng
    }
}

/// Probability density, in solid angle at the shading point, of light sampling choosing the
/// point at distance `dist` on triangle `tri` whose cosine towards the shading point is `cos_l`.
/// mirror: shaders/pathtrace.wgsl `light_pdf`
pub fn light_pdf(scene: &RenderScene, tri: u32, dist: f32, cos_l: f32) -> f32 {
    let pmf = scene.shading[tri as usize].emitter_pmf;
    let area = geometry::area(&scene.tris[tri as usize]);
    pmf * dist * dist / (cos_l * area)
}

/// A point on a light chosen for next event estimation, seen from a shading point.
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    /// The shadow ray: from `origin` along unit `wi` up to `t_max`.
    pub origin: Vec3,
    pub wi: Vec3,
    pub t_max: f32,
    /// Radiance arriving along the shadow ray if nothing blocks it.
    pub le: Vec3,
    /// Solid-angle pdf of having drawn `wi`, the light's pick included.
    pub pdf: f32,
}

/// Picks a light by the emitter CDF and a point (triangle) or direction (sky) on it, as
/// seen from surface point `p` with geometric normal `ng` facing the viewer. `None` when
/// the point faces away. mirror: shaders/pathtrace.wgsl `sample_light`
pub fn sample_light(
    scene: &RenderScene,
    p: Vec3,
    ng: Vec3,
    rng: &Rng,
    depth: u32,
) -> Option<LightSample> {
    let k = sample_cdf(&scene.emitter_cdf, rng.rng_1d(depth, rng::DIM_LIGHT_PICK));
    let light = scene.emitters[k];
    let u = Vec2::new(
        rng.rng_1d(depth, rng::DIM_LIGHT_U),
        rng.rng_1d(depth, rng::DIM_LIGHT_V),
    );
    if light == SKY_EMITTER {
        let wi = sample_uniform_sphere(u);
        return Some(LightSample {
            origin: offset_ray_origin(p, ng, wi),
            wi,
            t_max: T_INF,
            le: scene.sky.radiance(wi),
            pdf: scene.sky_pmf * UNIFORM_SPHERE_PDF,
        });
    }
    let tri = &scene.tris[light as usize];
    let [a, b, c] = tri.corners();
    let bary = sample_uniform_triangle(u);
    let q = (1.0 - bary.x - bary.y) * a + bary.x * b + bary.y * c;
    let origin = offset_ray_origin(p, ng, q - p);
    let to_light = q - origin;
    let dist = to_light.length();
    let wi = to_light / dist;
    let cos_l = -wi.dot(geometry::geometric_normal(tri));
    if !(cos_l > 0.0 && dist > 0.0) {
        return None;
    }
    Some(LightSample {
        origin,
        wi,
        t_max: dist * (1.0 - 1e-4),
        le: scene.materials[scene.shading[light as usize].material as usize].emission,
        pdf: light_pdf(scene, light, dist, cos_l),
    })
}

/// One path's radiance estimate and the number of rays it traced.
/// mirror: shaders/pathtrace.wgsl `trace_path`
pub fn trace_path(scene: &RenderScene, mut ray: Ray, rng: &Rng, max_depth: u32) -> (Vec3, u32) {
    let nodes = &scene.bvh.nodes;
    let tris = &scene.tris;
    let mut radiance = Vec3::ZERO;
    let mut beta = Vec3::ONE;
    let mut rays = 0u32;
    // The previous vertex's BSDF-sampling pdf, for weighting emission found by BSDF sampling.
    let mut prev_pdf = 0.0f32;
    let mut prev_delta = true;
    let mut eta_scale = 1.0f32;
    // `depth` counts the vertices already on the path; the camera ray finds vertex 0.
    let mut depth = 0u32;
    loop {
        rays += 1;
        let Some(hit) = traverse_closest(nodes, tris, &ray, T_INF) else {
            let w = if prev_delta || scene.sky_pmf == 0.0 {
                1.0
            } else {
                power_heuristic(prev_pdf, scene.sky_pmf * UNIFORM_SPHERE_PDF)
            };
            radiance += beta * w * scene.sky.radiance(ray.dir);
            break;
        };
        let si = surface_at(scene, &ray, &hit);
        let mat = &scene.materials[si.material as usize];
        if si.front_face && mat.is_emissive() {
            let w = if prev_delta {
                1.0
            } else {
                let cos_l = -ray.dir.dot(si.ng);
                power_heuristic(prev_pdf, light_pdf(scene, si.tri, hit.t, cos_l))
            };
            radiance += beta * w * mat.emission;
        }
        // Segments so far: depth + 1. Both light sampling and continuing add one more.
        if depth + 1 >= max_depth {
            break;
        }
        let wo_world = -ray.dir;
        // Two-sided kinds turn the frame towards the viewer; the dielectric keeps the front
        // face's frame so that it knows whether it is entered or left.
        let flip = mat.kind != MaterialKind::Dielectric && wo_world.dot(si.ng) < 0.0;
        let (ng, mut ns) = if flip {
            (-si.ng, -si.ns)
        } else {
            (si.ng, si.ns)
        };
        if mat.kind != MaterialKind::Dielectric && ns.dot(wo_world) <= 0.0 {
            ns = ng;
        }
        let (t, b) = onb_from_normal(ns);
        let to_local = |w: Vec3| Vec3::new(w.dot(t), w.dot(b), w.dot(ns));
        let to_world = |w: Vec3| w.x * t + w.y * b + w.z * ns;
        let wo = to_local(wo_world);

        // Next event estimation.
        if !bsdf_is_delta(mat) && !scene.emitters.is_empty() {
            if let Some(ls) = sample_light(scene, si.p, ng, rng, depth) {
                if ls.wi.dot(ng) > 0.0 {
                    let wi = to_local(ls.wi);
                    let f = bsdf_eval(mat, wo, wi);
                    if f != Vec3::ZERO {
                        rays += 1;
                        if !traverse_any(nodes, tris, &Ray::new(ls.origin, ls.wi), ls.t_max) {
                            let w = power_heuristic(ls.pdf, bsdf_pdf(mat, wo, wi));
                            radiance += beta * f * ls.le * (w / ls.pdf);
                        }
                    }
                }
            }
        }

        // BSDF sampling.
        let Some(bs) = bsdf_sample(
            mat,
            wo,
            rng.rng_1d(depth, rng::DIM_BSDF_LOBE),
            Vec2::new(
                rng.rng_1d(depth, rng::DIM_BSDF_U),
                rng.rng_1d(depth, rng::DIM_BSDF_V),
            ),
        ) else {
            break;
        };
        let wi_world = to_world(bs.wi);
        // Reject directions that the shading normal allows but the geometry does not:
        // reflection must stay on wo's side of the surface, transmission must cross it.
        let reflect = bs.wi.z * wo.z > 0.0;
        if (wi_world.dot(si.ng) * wo_world.dot(si.ng) > 0.0) != reflect {
            break;
        }
        beta *= bs.weight;
        prev_pdf = bs.pdf;
        prev_delta = bs.delta;
        eta_scale *= bs.eta;
        depth += 1;
        if depth >= RR_DEPTH {
            let q = (beta.max_element() * eta_scale * eta_scale).min(0.95);
            if rng.rng_1d(depth, rng::DIM_ROULETTE) >= q {
                break;
            }
            beta /= q;
        }
        if beta == Vec3::ZERO {
            break;
        }
        ray = Ray::new(offset_ray_origin(si.p, si.ng, wi_world), wi_world);
    }
    (radiance, rays)
}

/// Paths traced per pass over the image: a pass is the unit of cancellation and checkpoints.
pub const PATHS_PER_PASS: u64 = 1 << 20;

/// Renders the job's sample range with rayon over tiles, in passes of a few samples per
/// pixel over the whole image. `progress` is told of every finished tile's sample count; it
/// runs on worker threads. Stops early, after a whole pass, when the job is cancelled; the
/// film's `samples` says how many samples it holds. Returns the film and the rays traced.
pub fn render(
    scene: &RenderScene,
    job: &RenderJob,
    progress: &(dyn Fn(u64) + Sync),
) -> (Film, u64) {
    let s = &job.settings;
    let (w, h) = (s.width, s.height);
    let tiles: Vec<(u32, u32)> = (0..h.div_ceil(TILE))
        .flat_map(|ty| (0..w.div_ceil(TILE)).map(move |tx| (tx * TILE, ty * TILE)))
        .collect();
    let rays = AtomicU64::new(0);
    let step = (PATHS_PER_PASS / (w as u64 * h as u64)).max(1) as u32;
    let mut film = Film::new(w, h);
    let mut checkpoints = Checkpoints::new(job);
    let mut start = job.samples.start;
    while start < job.samples.end && !job.cancelled() {
        let end = (start + step).min(job.samples.end);
        let film_ref = &film;
        let done: Vec<((u32, u32), Vec<Vec3>)> = tiles
            .par_iter()
            .map(|&(x0, y0)| {
                let (x1, y1) = ((x0 + TILE).min(w), (y0 + TILE).min(h));
                let mut sums = Vec::with_capacity(((x1 - x0) * (y1 - y0)) as usize);
                let mut tile_rays = 0u64;
                for y in y0..y1 {
                    for x in x0..x1 {
                        let sum = film_ref.sum[(y * w + x) as usize];
                        let (sum, r) = render_pixel(scene, job, x, y, start..end, sum);
                        sums.push(sum);
                        tile_rays += r;
                    }
                }
                rays.fetch_add(tile_rays, Ordering::Relaxed);
                progress(sums.len() as u64 * (end - start) as u64);
                ((x0, y0), sums)
            })
            .collect();
        for ((x0, y0), sums) in done {
            let tw = (x0 + TILE).min(w) - x0;
            for (i, sum) in sums.into_iter().enumerate() {
                let (x, y) = (x0 + i as u32 % tw, y0 + i as u32 / tw);
                film.sum[(y * w + x) as usize] = sum;
            }
        }
        film.samples += end - start;
        start = end;
        if start < job.samples.end && checkpoints.due() {
            checkpoints.write(&film);
        }
    }
    (film, rays.into_inner())
}

/// `sum` plus one pixel's samples over `samples`, added in sample order in f32 as the GPU
/// adds them; non-finite samples are dropped. Returns the sum and the rays traced.
/// mirror: shaders/render.wgsl `render`
pub fn render_pixel(
    scene: &RenderScene,
    job: &RenderJob,
    x: u32,
    y: u32,
    samples: std::ops::Range<u32>,
    mut sum: Vec3,
) -> (Vec3, u64) {
    let s = &job.settings;
    let pixel = y * s.width + x;
    let mut rays = 0u64;
    for sample in samples {
        let rng = Rng::new(pixel, sample, s.seed);
        let ray = scene
            .camera
            .generate_camera_ray(x, y, s.width, s.height, &rng);
        let (l, r) = trace_path(scene, ray, &rng, s.max_depth);
        rays += r as u64;
        if l.is_finite() {
            sum += l;
        }
    }
    (sum, rays)
}
