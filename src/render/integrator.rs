//! The path tracer, one bounce at a time: a unidirectional path tracer with next event
//! estimation on the lights combined with BSDF sampling by the power heuristic, and Russian
//! roulette from depth 5, as Mitsuba 3's `path` integrator.
//!
//! [`path_step`] advances a [`PathState`] by one bounce; [`trace_path`] is the loop over it.
//! The GPU runs the same steps (`shaders/integrator.wgsl`, every function a twin of the same
//! name), drawing every random number from the same counter-based [`Rng`], so a path traced
//! on either device is the same path.

use super::bsdf::{
    bsdf_draws_direction, bsdf_draws_lobe, bsdf_eval, bsdf_is_delta, bsdf_pdf, bsdf_sample,
    bsdf_transmits, diffuse_color,
};
use super::camera::CameraRays;
use super::caustics::{
    LightPath, MAX_CAUSTIC_HOPS, camera_link, camera_pdf, caustic_hit_weight, caustic_link,
    trace_light_subpath,
};
use super::lights::{
    LightSample, hit_rect, light_pdf, rect_pdf, sample_light, sample_punctual, sky_pdf,
    sky_radiance,
};
use super::rng::{self, Rng};
use super::sampling::power_heuristic;
/// Also reachable here, the path that callers outside the renderer (`crate::bench`) name.
use super::surface::{
    ShadingFrame, SurfaceHit, coated, geometry_agrees, needs_coat_normal, offset_ray_origin,
    shading_frame, surface_at, with_coat_normal,
};
use super::tables::{LIGHT_RECT, RenderScene};
use super::texture::{alpha_test, material_at};
use crate::bvh::{Hit, traverse_closest_counted};
use crate::film::NO_ID;
use crate::geometry::{T_INF, triangle_area};
use crate::math::Ray;
use crate::scene::{Material, MaterialKind};
use glam::{UVec3, Vec2, Vec3, Vec4};
use std::mem::MaybeUninit;

/// Path depth (in bounces) from which Russian roulette may end a path.
/// The shaders get it from `render::gpu::shader::shared_constants`.
pub const RR_DEPTH: u32 = 5;

/// One path between bounces: the ray it traces next and what it has gathered so far.
/// mirror: shaders/integrator.wgsl `PathState`
#[derive(Clone, Copy, Debug)]
pub struct PathState {
    pub ray: Ray,
    pub radiance: Vec3,
    /// Throughput: the product of the BSDF-sampling weights so far.
    pub beta: Vec3,
    /// Rays traced: one per segment plus one per shadow ray.
    pub rays: u32,
    /// The previous vertex's BSDF-sampling pdf, for weighting emission found by BSDF
    /// sampling, and whether that sample was a delta lobe (no MIS then).
    pub prev_pdf: f32,
    pub prev_delta: bool,
    /// Product of the relative indices of refraction crossed, for Russian roulette.
    pub eta_scale: f32,
    /// Vertices already on the path; the camera ray finds vertex 0.
    pub depth: u32,
    /// BSDF sampling's density of the path since its last direct edge, for weighing it
    /// against a light subpath that ends there ([`super::caustics`]): the density in area
    /// of the vertex x(t) that edge reached from the camera or a non-delta vertex, times
    /// the solid-angle pdf of the direction x(t) left by over its cosine, times, at each
    /// non-delta vertex reached since through a specular chain, the ratio of its camera to
    /// its light density (both solid-angle pdfs times the cosine of the direction drawn
    /// from). Kept through delta vertices; 0 where no light subpath could end the path
    /// that way, and in scenes without caustic targets.
    pub caustic_pdf: f32,
    /// Specular chains completed since x(t).
    pub caustic_hops: u32,
    /// The scatterings of each lobe kind (indexed by
    /// [`BsdfSample::lobe`](super::bsdf::BsdfSample::lobe)) the path may still take: the
    /// [`BounceLimits::budget`](crate::scene::BounceLimits::budget) less one per scattering
    /// of that kind. Where one is 0, the next surface adds its emission and the path ends.
    pub bounces_left: UVec3,
}

/// A path about to trace its camera ray, drawn with solid-angle density `camera_pdf`
/// (kept in `prev_pdf` for the caustic weights; `prev_delta` keeps other weights off it),
/// with the scatterings of each lobe kind in `bounces`
/// ([`BounceLimits::budget`](crate::scene::BounceLimits::budget)).
/// mirror: shaders/integrator.wgsl `path_start`
pub fn path_start(ray: Ray, camera_pdf: f32, bounces: UVec3) -> PathState {
    PathState {
        ray,
        radiance: Vec3::ZERO,
        beta: Vec3::ONE,
        rays: 0,
        prev_pdf: camera_pdf,
        prev_delta: true,
        eta_scale: 1.0,
        depth: 0,
        caustic_pdf: 0.0,
        caustic_hops: 0,
        bounces_left: bounces,
    }
}

/// Whether the vertex the path has just reached is its last: it adds its emission and
/// nothing more, the path having traced `max_depth` segments or used up a lobe kind's
/// bounces. mirror: shaders/integrator.wgsl `path_ends_at_vertex`
#[inline(always)]
pub fn path_ends_at_vertex(st: &PathState, max_depth: u32) -> bool {
    st.depth + 1 >= max_depth || st.bounces_left.min_element() == 0
}

/// One bounce: [`path_vertex`], [`connect_light_path`] and [`path_continue`]. Returns
/// true when the path has ended. mirror: shaders/integrator.wgsl `path_step`
#[inline(always)]
pub fn path_step<const CAUSTICS: bool>(
    scene: &RenderScene,
    st: &mut PathState,
    light: &LightPath,
    rng: &Rng,
    max_depth: u32,
) -> bool {
    let mut textured = MaybeUninit::uninit();
    match path_vertex::<CAUSTICS>(scene, st, rng, max_depth, 1, &mut textured) {
        Some(v) => {
            if CAUSTICS {
                connect_light_path(scene, st, &v, light, max_depth);
            }
            path_continue::<CAUSTICS>(st, &v, rng)
        }
        None => true,
    }
}

/// Caustic connections: vertex `v` (where it is not delta) to each vertex of the light
/// subpath `light` that leaves the path room for the link and the subpath's segments.
/// mirror: shaders/integrator.wgsl `connect_light_path`
#[inline(always)]
pub fn connect_light_path(
    scene: &RenderScene,
    st: &mut PathState,
    v: &PathVertex,
    light: &LightPath,
    max_depth: u32,
) {
    if bsdf_is_delta(v.mat) {
        return;
    }
    for lv in &light.vertices[..light.count as usize] {
        if st.depth + 2 + lv.segments <= max_depth
            && let Some(link) = caustic_link(scene, &v.si, v.mat, &v.frame, v.wo_world, v.wo, lv)
        {
            st.rays += 1;
            if !scene.wide.traverse_any(&link.ray, link.t_max, |t, u, v| {
                alpha_test(scene, t, u, v, false)
            }) {
                st.radiance += st.beta * link.value;
            }
        }
    }
}

/// A path vertex whose BSDF is still to be sampled: what [`path_continue`] needs of it.
/// mirror: shaders/integrator.wgsl `PathVertex`
#[derive(Clone, Copy, Debug)]
pub struct PathVertex<'a> {
    pub si: SurfaceHit,
    /// The material there, its textures applied (a copy of the scene's where it has any).
    pub mat: &'a Material,
    pub frame: ShadingFrame,
    pub wo_world: Vec3,
    /// `wo_world` in `frame`.
    pub wo: Vec3,
    /// The camera's (or BSDF sampling's) density of this vertex in area, where a light
    /// subpath ending here could have been connected to the camera path; else 0.
    pub area_pdf: f32,
    /// The numbers BSDF sampling reads ([`bsdf_numbers`]).
    pub u_lobe: f32,
    pub u: Vec2,
}

/// The first half of a bounce: traces `st.ray`, adds the emission it finds and next event
/// estimation at the hit. Returns the vertex to sample the BSDF at (whose numbers it draws
/// where the path does not branch there: `branches` 1), or `None` when the path has ended.
/// mirror: shaders/integrator.wgsl `path_vertex`
#[inline(always)]
pub fn path_vertex<'a, const CAUSTICS: bool>(
    scene: &'a RenderScene,
    st: &mut PathState,
    rng: &Rng,
    max_depth: u32,
    branches: u32,
    textured: &'a mut MaybeUninit<Material>,
) -> Option<PathVertex<'a>> {
    // The CPU traverses the wide tree, which finds the hits the GPU's binary tree finds.
    let wide = &scene.wide;
    // The light pair, drawn before the traversal so that its hashes run in the traversal's
    // latency (on a miss, a delta material or the last segment it goes unused).
    let u_light = if scene.emitters.is_empty() || path_ends_at_vertex(st, max_depth) {
        Vec2::ZERO
    } else {
        rng.rng_2d(st.depth, rng::DIM_LIGHT_U)
    };
    st.rays += 1;
    let camera = st.depth == 0;
    let found = wide.traverse_closest(&st.ray, T_INF, |t, u, v| alpha_test(scene, t, u, v, camera));
    if !camera {
        add_rect_hits::<CAUSTICS>(scene, st, found.as_ref().map_or(T_INF, |h| h.t));
    }
    let Some(hit) = found else {
        let w = if st.prev_delta || scene.sky_pmf == 0.0 {
            1.0
        } else {
            power_heuristic(st.prev_pdf, sky_pdf(scene, st.ray.dir))
        };
        st.radiance += st.beta * w * sky_radiance(scene, st.ray.dir);
        return None;
    };
    let si = surface_at(scene, &st.ray, &hit);
    // A material without textures, at a point without a vertex colour, is used where it
    // lies (no copy); the WGSL copies anyway.
    // A clear coat's normal is set here too, where a normal map makes it differ from the
    // frame's (a map is a texture: the material is a copy then).
    let base = &scene.materials[si.material as usize];
    let mat: &'a Material = if base.has_texture() || si.color != Vec4::ONE {
        let mut m = material_at(scene, base, si.uv, si.color);
        if needs_coat_normal(&m) {
            m = with_coat_normal(&m, &si, &shading_frame(&m, &si, -st.ray.dir));
        }
        textured.write(m)
    } else {
        base
    };
    if mat.kind == MaterialKind::UNLIT {
        // Only camera rays find an unlit surface: its colour, as it is.
        st.radiance += st.beta * mat.albedo;
        return None;
    }
    if si.front_face && mat.is_emissive() {
        let cos_l = -st.ray.dir.dot(si.ng);
        let w = if !st.prev_delta {
            power_heuristic(st.prev_pdf, light_pdf(scene, si.tri, hit.t, cos_l))
        } else if CAUSTICS && st.caustic_pdf > 0.0 {
            let pmf = scene.shading[si.tri as usize].emitter_pmf;
            let area = triangle_area(&scene.tris[si.tri as usize]);
            caustic_hit_weight(scene, pmf, area, si.p, st.ray.dir, cos_l, st.caustic_pdf)
        } else {
            1.0
        };
        st.radiance += st.beta * w * mat.emission;
    }
    // The camera's (or BSDF sampling's) density of this vertex in area, where the previous
    // vertex is the camera (or a non-delta vertex): where a light subpath ending here
    // could have been connected to the camera path.
    let caustics = CAUSTICS;
    let area_pdf = if caustics && (st.depth == 0 || !st.prev_delta) {
        st.prev_pdf * st.ray.dir.dot(si.ng).abs() / (hit.t * hit.t)
    } else {
        0.0
    };
    // Segments so far: depth + 1. Both light sampling and continuing add one more.
    if path_ends_at_vertex(st, max_depth) {
        return None;
    }
    let wo_world = -st.ray.dir;
    let frame = shading_frame(mat, &si, wo_world);
    let ng = frame.ng;
    let wo = frame.to_local(wo_world);

    // The numbers BSDF sampling reads, drawn only where the material reads them, and
    // before next event estimation, whose shadow ray then hides their hashes' latency.
    // A vertex whose BSDF is sampled by branches of their own draws none.
    let (u_lobe, u) = if branches == 1 {
        bsdf_numbers(mat, st.depth, rng)
    } else {
        (0.0, Vec2::ZERO)
    };

    // Next event estimation: the lights sampled in full, then the one picked.
    if !bsdf_is_delta(mat) {
        for k in 0..scene.lights_in_full {
            if scene.lights[k as usize].kind != LIGHT_RECT
                && let Some(ls) = sample_punctual(scene, k, si.p, ng, 1.0, Vec2::ZERO)
            {
                add_direct(scene, st, mat, &frame, wo, &ls);
            }
        }
        if !scene.emitters.is_empty()
            && let Some(ls) = sample_light(scene, si.p, ng, u_light)
        {
            add_direct(scene, st, mat, &frame, wo, &ls);
        }
    }

    Some(PathVertex {
        si,
        mat,
        frame,
        wo_world,
        wo,
        area_pdf,
        u_lobe,
        u,
    })
}

/// Adds the emission of the rectangle lights that the BSDF-sampled ray `st.ray` meets
/// before `t_max` (its hit, if any: the lights shadow nothing and the ray goes on), weighed
/// against next event estimation by the power heuristic, or after a specular chain against
/// the light subpath that could make the same path, as emissive triangles are. The light
/// sample's density is taken from the ray's origin, the previous vertex offset from its
/// surface. mirror: shaders/integrator.wgsl `add_rect_hits`
#[inline(always)]
fn add_rect_hits<const CAUSTICS: bool>(scene: &RenderScene, st: &mut PathState, t_max: f32) {
    for l in &scene.lights[scene.first_rect_light as usize..] {
        let Some((t, cos_l)) = hit_rect(l, &st.ray, t_max) else {
            continue;
        };
        let w = if !st.prev_delta {
            power_heuristic(st.prev_pdf, l.pmf * rect_pdf(l, st.ray.origin, t, cos_l))
        } else if CAUSTICS && st.caustic_pdf > 0.0 {
            let q = st.ray.origin + t * st.ray.dir;
            caustic_hit_weight(scene, l.pmf, l.area, q, st.ray.dir, cos_l, st.caustic_pdf)
        } else {
            1.0
        };
        st.radiance += st.beta * w * Vec3::from(l.intensity);
    }
}

/// Adds light sample `ls`, seen through `mat` at the vertex whose shading frame is `frame`
/// towards `wo` (local), where its shadow ray is clear; weighted by the power heuristic
/// against BSDF sampling where a BSDF ray could have found the light too.
/// mirror: shaders/integrator.wgsl `add_direct`
#[inline(always)]
fn add_direct(
    scene: &RenderScene,
    st: &mut PathState,
    mat: &Material,
    frame: &ShadingFrame,
    wo: Vec3,
    ls: &LightSample,
) {
    // A surface that light crosses sees lights on both sides; bsdf_eval says which of them
    // it passes. Others only see those on the side of ng.
    let cos_i = ls.wi.dot(frame.ng);
    let usable = if bsdf_transmits(mat) {
        cos_i != 0.0
    } else {
        cos_i > 0.0
    };
    if !usable {
        return;
    }
    let wi = frame.to_local(ls.wi);
    let f = bsdf_eval(mat, wo, wi);
    if f == Vec3::ZERO {
        return;
    }
    st.rays += 1;
    if !scene
        .wide
        .traverse_any(&Ray::new(ls.origin, ls.wi), ls.t_max, |t, u, v| {
            alpha_test(scene, t, u, v, false)
        })
    {
        let w = if ls.delta {
            1.0
        } else {
            power_heuristic(ls.pdf, bsdf_pdf(mat, wo, wi))
        };
        st.radiance += st.beta * f * ls.le * (w / ls.pdf);
    }
}

/// The numbers BSDF sampling at bounce `depth` reads from `rng` (lobe, direction), drawn
/// only where `mat` reads them. mirror: shaders/integrator.wgsl `bsdf_numbers`
#[inline(always)]
pub fn bsdf_numbers(mat: &Material, depth: u32, rng: &Rng) -> (f32, Vec2) {
    let u_lobe = if bsdf_draws_lobe(mat) {
        rng.rng_1d(depth, rng::DIM_BSDF_LOBE)
    } else {
        0.0
    };
    let u = if bsdf_draws_direction(mat) {
        rng.rng_2d(depth, rng::DIM_BSDF_U)
    } else {
        Vec2::ZERO
    };
    (u_lobe, u)
}

/// The second half of a bounce: samples the BSDF at vertex `v` for the next ray, and
/// Russian roulette. Returns true when the path has ended.
/// mirror: shaders/integrator.wgsl `path_continue`
#[inline(always)]
pub fn path_continue<const CAUSTICS: bool>(st: &mut PathState, v: &PathVertex, rng: &Rng) -> bool {
    let (si, mat, frame, wo_world, wo) = (&v.si, &v.mat, &v.frame, v.wo_world, v.wo);
    let (u_lobe, u) = (v.u_lobe, v.u);
    let caustics = CAUSTICS;
    let area_pdf = v.area_pdf;
    let Some(bs) = bsdf_sample(mat, wo, u_lobe, u) else {
        return true;
    };
    let wi_world = frame.to_world(bs.wi);
    // Reject directions that the shading normal allows but the geometry does not:
    // reflection must stay on wo's side of the surface, transmission must cross it.
    if !geometry_agrees(si.ng, wo_world, wi_world, wo, bs.wi) {
        return true;
    }
    if caustics {
        if bs.delta {
            // A specular chain goes on through a delta material, and breaks at another
            // material's delta lobe (a light subpath would not follow it).
            if !bsdf_is_delta(mat) {
                st.caustic_pdf = 0.0;
            }
        } else if !st.prev_delta || st.depth == 0 {
            // Reached directly from the previous vertex (or the camera): a new start.
            let cos = wi_world.dot(si.ng).abs();
            st.caustic_pdf = if area_pdf > 0.0 && cos > 0.0 {
                area_pdf * bs.pdf / cos
            } else {
                0.0
            };
            st.caustic_hops = 0;
        } else if st.caustic_pdf > 0.0 {
            // Reached through a specular chain: this vertex would be a light subpath's,
            // sampled from the chain's side; the ratio of its camera density to its light
            // density joins the product.
            let cos_out = wi_world.dot(si.ng).abs();
            let cos_in = wo_world.dot(si.ng).abs();
            let back = shading_frame(mat, si, wi_world);
            let mat_b = coated(mat, si, &back);
            let pdf_light = bsdf_pdf(&mat_b, back.to_local(wi_world), back.to_local(wo_world));
            st.caustic_pdf *= bs.pdf * cos_in / (pdf_light * cos_out);
            st.caustic_hops += 1;
            if !(st.caustic_pdf.is_finite() && st.caustic_hops < MAX_CAUSTIC_HOPS as u32) {
                st.caustic_pdf = 0.0;
            }
        }
    }
    st.beta *= bs.weight;
    st.prev_pdf = bs.pdf;
    st.prev_delta = bs.delta;
    st.eta_scale *= bs.eta;
    st.bounces_left[bs.lobe as usize] -= 1;
    st.depth += 1;
    if st.depth >= RR_DEPTH {
        let q = (st.beta.max_element() * st.eta_scale * st.eta_scale).min(0.95);
        if rng.rng_1d(st.depth, rng::DIM_ROULETTE) >= q {
            return true;
        }
        st.beta /= q;
    }
    if st.beta == Vec3::ZERO {
        return true;
    }
    st.ray = Ray::new(offset_ray_origin(si.p, si.ng, wi_world), wi_world);
    false
}

/// A camera sample's light subpath (where the scene has caustic targets), the rays it and
/// its links to the camera traced, and where those links land: the pixels and values of
/// the splats (zero values for none).
/// mirror: shaders/integrator.wgsl `LightStart`
#[derive(Clone, Copy, Debug)]
pub struct LightStart {
    pub light: LightPath,
    pub rays: u32,
    pub splat_pixels: [u32; MAX_CAUSTIC_HOPS],
    pub splats: [Vec3; MAX_CAUSTIC_HOPS],
}

impl LightStart {
    /// No light subpath.
    pub const NONE: Self = Self {
        light: LightPath::NONE,
        rays: 0,
        splat_pixels: [0; MAX_CAUSTIC_HOPS],
        splats: [Vec3::ZERO; MAX_CAUSTIC_HOPS],
    };
}

/// Traces the sample's light subpath and links each of its vertices to the camera, through
/// the lens point of that vertex's `DIM_LENS_U` pair.
/// mirror: shaders/integrator.wgsl `start_light`
#[inline(always)]
pub fn start_light(scene: &RenderScene, cam: &CameraRays, rng: &Rng, max_depth: u32) -> LightStart {
    let mut out = LightStart::NONE;
    if scene.caustic_targets.is_empty() {
        return out;
    }
    (out.light, out.rays) = trace_light_subpath(scene, rng, max_depth - 1);
    for k in 0..out.light.count as usize {
        let lv = &out.light.vertices[k];
        let u_lens = rng.rng_2d(lv.segments, rng::DIM_LENS_U);
        if let Some(link) = camera_link(scene, cam, lv, u_lens) {
            out.rays += 1;
            if !scene.wide.traverse_any(&link.ray, link.t_max, |t, u, v| {
                alpha_test(scene, t, u, v, false)
            }) {
                (out.splat_pixels[k], out.splats[k]) = (link.pixel, link.value);
            }
        }
    }
    out
}

/// What one camera sample adds to the film: its path's radiance estimate and the rays it
/// traced (its light subpaths' included). Its light subpaths' splats go to the caller's
/// `splat` as they are made.
#[derive(Clone, Copy, Debug)]
pub struct PathSample {
    pub radiance: Vec3,
    pub rays: u32,
}

/// One camera sample of `branches` branches: the camera ray's first vertex
/// ([`path_vertex`]: its emission and next event estimation), then each branch
/// ([`branch_start`]): its first step at that vertex, with its own BSDF numbers
/// ([`branch_numbers`]), then [`path_step`]s to its end. The sample's radiance is the
/// first vertex's plus the mean of the branches'. (In a scene without caustic targets, the
/// path's caustic bookkeeping is compiled out.)
/// mirror: shaders/integrator.wgsl `trace_path`
#[allow(clippy::too_many_arguments)]
pub fn trace_path(
    scene: &RenderScene,
    cam: &CameraRays,
    ray: Ray,
    rng: &Rng,
    max_depth: u32,
    bounces: UVec3,
    branches: u32,
    splat: &mut impl FnMut(u32, Vec3),
) -> PathSample {
    if scene.caustic_targets.is_empty() {
        camera_sample::<false>(scene, cam, ray, rng, max_depth, bounces, branches, splat)
    } else {
        camera_sample::<true>(scene, cam, ray, rng, max_depth, bounces, branches, splat)
    }
}

#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn camera_sample<const CAUSTICS: bool>(
    scene: &RenderScene,
    cam: &CameraRays,
    ray: Ray,
    rng: &Rng,
    max_depth: u32,
    bounces: UVec3,
    branches: u32,
    splat: &mut impl FnMut(u32, Vec3),
) -> PathSample {
    let camera_pdf = if CAUSTICS {
        camera_pdf(cam, ray.dir)
    } else {
        0.0
    };
    let mut st = path_start(ray, camera_pdf, bounces);
    let mut textured = MaybeUninit::uninit();
    let mut v = path_vertex::<CAUSTICS>(scene, &mut st, rng, max_depth, branches, &mut textured);
    let mut out = PathSample {
        radiance: st.radiance,
        rays: st.rays,
    };
    // Without light subpaths, a path that ended at its first vertex has no branches.
    if !CAUSTICS && v.is_none() {
        return out;
    }
    let mut sum = Vec3::ZERO;
    for j in 0..branches {
        let mut b = branch_start::<CAUSTICS>(scene, cam, &st, rng, j, branches, max_depth);
        for (&pixel, &value) in b.ls.splat_pixels.iter().zip(&b.ls.splats) {
            if value != Vec3::ZERO {
                splat(pixel, value);
            }
        }
        if let Some(v) = v.as_mut() {
            branch_numbers(v, st.depth, &b.rng, branches);
            if CAUSTICS {
                connect_light_path(scene, &mut b.st, v, &b.ls.light, max_depth);
            }
            if !path_continue::<CAUSTICS>(&mut b.st, v, &b.rng) {
                while !path_step::<CAUSTICS>(scene, &mut b.st, &b.ls.light, &b.rng, max_depth) {}
            }
        }
        sum += b.st.radiance;
        out.rays += b.st.rays;
    }
    out.radiance += sum * branch_weight(branches);
    out
}

/// The weight of one of `branches` branches in its sample: their mean's factor.
/// (The GPU gets it from `Params::branch_weight`.)
pub fn branch_weight(branches: u32) -> f32 {
    1.0 / branches as f32
}

/// The sample index of branch `j` of camera sample `sample` that branches `k` ways: the
/// branches of a pixel's samples take consecutive indices, so that they are stratified
/// together as `k` times as many samples would be (and with `k` 1 the sample's own).
/// mirror: shaders/integrator.wgsl `branch_sample`
#[inline(always)]
pub fn branch_sample(sample: u32, j: u32, k: u32) -> u32 {
    sample.wrapping_mul(k).wrapping_add(j)
}

/// A branch of a camera sample before its first step: its path (the camera sample's up to
/// its first vertex, with no radiance yet and its light subpath's rays), its light subpath
/// with its splats (weighted as one of the sample's branches) and the random stream it
/// draws from. Its first step is [`connect_light_path`] and [`path_continue`] at the
/// sample's first vertex, with its own BSDF numbers there ([`branch_numbers`]).
/// mirror: shaders/integrator.wgsl `Branch`
#[derive(Clone, Copy, Debug)]
pub struct Branch<'a> {
    pub st: PathState,
    pub ls: LightStart,
    pub rng: Rng<'a>,
}

/// Branch `j` of the `k` of the camera sample of stream `rng`, whose path `base` reached
/// its first vertex. The branch draws from the stream of its [`branch_sample`] index, and
/// traces its light subpath there ([`start_light`], in a scene with caustic targets).
/// mirror: shaders/integrator.wgsl `branch_start`
#[inline(always)]
pub fn branch_start<'a, const CAUSTICS: bool>(
    scene: &RenderScene,
    cam: &CameraRays,
    base: &PathState,
    rng: &Rng<'a>,
    j: u32,
    k: u32,
    max_depth: u32,
) -> Branch<'a> {
    let mut branch_rng = *rng;
    branch_rng.set_sample(branch_sample(rng.sample(), j, k));
    let mut b = Branch {
        st: PathState {
            radiance: Vec3::ZERO,
            rays: 0,
            ..*base
        },
        ls: if CAUSTICS {
            start_light(scene, cam, &branch_rng, max_depth)
        } else {
            LightStart::NONE
        },
        rng: branch_rng,
    };
    b.st.rays = b.ls.rays;
    for s in &mut b.ls.splats {
        *s *= branch_weight(k);
    }
    b
}

/// Gives the camera sample's first vertex `v` (at bounce `depth`) the BSDF numbers of the
/// branch of stream `rng` of `k`, where the sample branches; with one branch
/// [`path_vertex`] drew them from the sample's own stream, which is the branch's.
/// mirror: shaders/integrator.wgsl `branch_numbers`
#[inline(always)]
pub fn branch_numbers(v: &mut PathVertex, depth: u32, rng: &Rng, k: u32) {
    if k > 1 {
        (v.u_lobe, v.u) = bsdf_numbers(v.mat, depth, rng);
    }
}

/// What the AOVs read of a camera ray's first hit.
/// mirror: shaders/integrator.wgsl `FirstHit`
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FirstHit {
    /// Whether the ray hit a surface; the other fields but `cost` are zero (ids [`NO_ID`])
    /// where it did not.
    pub hit: bool,
    pub p: Vec3,
    /// The shading normal (normal maps applied), turned to face the ray.
    pub normal: Vec3,
    /// The reflectance: albedo or base colour with its texture, 1 for `dielectric`.
    pub albedo: Vec3,
    /// The colour of the diffuse lobe ([`diffuse_color`]).
    pub diffuse: Vec3,
    pub material: u32,
    pub object: u32,
    /// BVH nodes visited plus triangles tested.
    pub cost: u32,
}

impl FirstHit {
    /// A ray that met nothing, at no cost.
    pub const MISS: FirstHit = FirstHit {
        hit: false,
        p: Vec3::ZERO,
        normal: Vec3::ZERO,
        albedo: Vec3::ZERO,
        diffuse: Vec3::ZERO,
        material: NO_ID,
        object: NO_ID,
        cost: 0,
    };
}

/// The first hit of camera ray `ray`, for the AOVs: a counting traversal, then the surface
/// and its material as [`path_step`] finds them. Draws no random numbers.
/// mirror: shaders/integrator.wgsl `first_hit`
pub fn first_hit(scene: &RenderScene, ray: &Ray) -> FirstHit {
    let (hit, cost) =
        traverse_closest_counted(&scene.bvh.nodes, &scene.tris, ray, T_INF, |t, u, v| {
            alpha_test(scene, t, u, v, true)
        });
    first_hit_at(scene, ray, hit, cost)
}

/// [`first_hit`] without the BVH cost (0): the CPU's faster traversal of the wide tree,
/// which finds the same hit, for the AOVs of renders that do not ask for `bvh_cost`
/// (every transparent or denoised render has AOVs, and this traversal is its second per
/// sample).
pub fn first_hit_uncounted(scene: &RenderScene, ray: &Ray) -> FirstHit {
    let hit = scene
        .wide
        .traverse_closest(ray, T_INF, |t, u, v| alpha_test(scene, t, u, v, true));
    first_hit_at(scene, ray, hit, 0)
}

/// What the AOVs read of `hit`, camera ray `ray`'s closest hit (if any), found at BVH cost
/// `cost`.
fn first_hit_at(scene: &RenderScene, ray: &Ray, hit: Option<Hit>, cost: u32) -> FirstHit {
    let Some(hit) = hit else {
        return FirstHit {
            cost,
            ..FirstHit::MISS
        };
    };
    let si = surface_at(scene, ray, &hit);
    let mat = material_at(
        scene,
        &scene.materials[si.material as usize],
        si.uv,
        si.color,
    );
    FirstHit {
        hit: true,
        p: si.p,
        normal: if si.ns.dot(ray.dir) > 0.0 {
            -si.ns
        } else {
            si.ns
        },
        albedo: if mat.kind == MaterialKind::DIELECTRIC {
            Vec3::ONE
        } else {
            mat.albedo
        },
        diffuse: diffuse_color(&mat),
        material: si.material,
        object: scene.tris[hit.tri as usize].object(),
        cost,
    }
}
