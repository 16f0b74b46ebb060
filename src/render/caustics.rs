//! Caustics: light that reaches a non-delta (diffuse or glossy) surface through a chain of
//! specular (delta) vertices, such as the focused light under a glass sphere. A path
//! tracer finds it only by BSDF sampling, from the surface under the glass, a direction
//! that happens to refract through the sphere onto the small light; so it comes as
//! fireflies. Here some camera samples also trace a light subpath, which finds it from
//! the light's side, and join it to the camera path, as bidirectional path tracing does
//! (Veach 1997, ch. 10; pbrt-v3 §16.3), for this one family of paths.
//!
//! **The light subpath** ([`trace_light_subpath`]), traced by a share
//! [`LIGHT_SUBPATH_RATE`] of the camera samples (picked by the sample's `DIM_LIGHT_SUBPATH`
//! number): a point on an emissive triangle, a direction into the cone of one of the
//! spheres that bound the scene's specular geometry ([`CausticTarget`]), then delta bounces
//! up to the first non-delta vertex, which it keeps ([`LightVertex`]); from there a BSDF
//! sample, and the next non-delta vertex too if a further specular chain leads to it (the
//! light under a glass sphere seen by the ceiling through the sphere), up to
//! [`MAX_CAUSTIC_HOPS`] vertices `L S+ D (S+ D)`. Its throughput is carried by the adjoint
//! BSDF: a refraction without the radiance's squared index ratio, and shading normals
//! corrected as Veach §5.3 says.
//!
//! **Two connections** join each kept vertex to the camera path: every non-delta vertex of
//! the camera path links to it by a shadow ray ([`caustic_link`]), and it is seen through
//! the lens ([`camera_link`]), a splat into the pixel it lands in (light tracing).
//!
//! **Weights.** A path `... x(t-1) x(t) S+ ... S+ L`, whose last direct edge joins the
//! non-delta vertices x(t-1) (or the camera) and x(t), and whose every later edge is a
//! specular chain between non-delta vertices, can be made two ways: by BSDF sampling all
//! along (the path tracer), or by a light subpath ending at x(t) joined to the camera path
//! at x(t-1). No other connection makes it (a connection is a direct edge), and next event
//! estimation never does (the last edge is a chain). The two are weighed by the power
//! heuristic ([`caustic_weight`]) on densities that both sides compute from the path
//! alone: BSDF sampling's is the density of x(t) in area seen from x(t-1), times, at each
//! later non-delta vertex, the solid-angle pdf of the direction it leaves by; the light
//! subpath's is the light point's area pdf times the emitted direction's pdf, times the
//! adjoint pdfs at its non-delta vertices, all times the light subpath rate. A chain's
//! generalised geometry term is reciprocal (cos at one end times the solid angle it
//! subtends from there is the same from the other end), so the chains enter both
//! densities as the cosines at their ends; where that is not exact (shading normals) the
//! weights still sum to one, which is all unbiasedness needs.
//!
//! Emissive triangles, rectangle lights and punctual lights (point, spot and directional)
//! start light subpaths. A punctual light's subpath is the only strategy for its paths (BSDF
//! sampling never reaches a point or a single direction), so its connections weigh 1
//! ([`link_weight`]): without light subpaths those caustics are missing, not noisy.
//! Caustics of the sky stay with BSDF sampling alone. Scenes without materials that may be delta (or
//! rendered with `caustics = false`) have no targets and trace no light subpath: their
//! renders are the path tracer's alone.
//!
//! Every function has a WGSL twin of the same name in `shaders/caustics.wgsl`.

use super::bsdf::{
    bsdf_draws_lobe, bsdf_eval, bsdf_is_delta, bsdf_pdf, bsdf_sample, bsdf_transmits,
};
use super::camera::CameraRays;
use super::lights::{LightPick, pick_light, spot_falloff, triangle_emission};
use super::rng::{self, Rng};
use super::sampling::{ONE_MINUS_EPSILON, sample_concentric_disk, sample_uniform_triangle};
use super::surface::{
    ShadingFrame, SurfaceHit, coated, geometry_agrees, offset_ray_origin, shading_frame, surface_at,
};
use super::tables::{
    CausticTarget, LIGHT_DIRECTIONAL, LIGHT_EMITTER, LIGHT_RECT, LIGHT_SPOT, Light, RenderScene,
    SKY_EMITTER,
};
use super::texture::{alpha_test, material_at};
use crate::geometry::T_INF;
use crate::math::{Ray, onb_from_normal};
use crate::scene::Material;
use glam::{Vec2, Vec3, Vec4};
use std::f32::consts::PI;

/// The share of camera samples that trace a light subpath. The light subpath's vertices
/// are few and bright, so that even this share makes their light nearly noise-free on the
/// glass-and-mirror box, where each subpath costs about six rays (BENCHMARKS.md: 1/8 and
/// 1/16 gave the best quality per second, 1 the least).
pub const LIGHT_SUBPATH_RATE: f32 = 0.125;

/// The cone of directions from `p` that meet a target: its axis, the cosine of its half
/// angle and one minus that cosine (computed without cancellation). From inside the
/// sphere, every direction (one minus the cosine is 2).
/// mirror: shaders/caustics.wgsl `TargetCone`
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TargetCone {
    pub axis: Vec3,
    pub cos_max: f32,
    pub height: f32,
}

/// mirror: shaders/caustics.wgsl `target_cone`
pub fn target_cone(sphere: &CausticTarget, p: Vec3) -> TargetCone {
    let d = Vec3::from(sphere.center) - p;
    let dist2 = d.length_squared();
    let r2 = sphere.radius * sphere.radius;
    if dist2 <= r2 {
        return TargetCone {
            axis: Vec3::Z,
            cos_max: -1.0,
            height: 2.0,
        };
    }
    let sin2 = r2 / dist2;
    let cos_max = (1.0 - sin2).sqrt();
    TargetCone {
        axis: d * (1.0 / dist2.sqrt()),
        cos_max,
        height: sin2 / (1.0 + cos_max),
    }
}

/// The solid-angle density with which [`sample_target`] at `p` draws unit `dir`: each
/// target is picked in proportion to its cone's solid angle and sampled uniformly within
/// it, so the density is the number of cones holding `dir` over their total solid angle.
/// mirror: shaders/caustics.wgsl `target_pdf`
pub fn target_pdf(scene: &RenderScene, p: Vec3, dir: Vec3) -> f32 {
    let mut total = 0.0;
    let mut count = 0.0;
    for t in &scene.caustic_targets {
        let cone = target_cone(t, p);
        total += cone.height;
        if dir.dot(cone.axis) >= cone.cos_max {
            count += 1.0;
        }
    }
    if total > 0.0 {
        count / (2.0 * PI * total)
    } else {
        0.0
    }
}

/// A direction from `p` towards the targets for the pair `u`: `u.x` picks a target by
/// its cone's solid angle and is rescaled within its share, then (`u.x`, `u.y`) is a
/// uniform point of the cone. Returns the direction and its [`target_pdf`].
/// mirror: shaders/caustics.wgsl `sample_target`
pub fn sample_target(scene: &RenderScene, p: Vec3, u: Vec2) -> (Vec3, f32) {
    let mut x = u.x * targets_height(scene, p);
    let mut cone = target_cone(&scene.caustic_targets[0], p);
    for t in &scene.caustic_targets {
        cone = target_cone(t, p);
        if x < cone.height {
            break;
        }
        x -= cone.height;
    }
    // One minus the cosine of the angle from the axis, uniform in [0, height).
    let v = (x / cone.height).clamp(0.0, 1.0) * cone.height;
    let dir = sample_cone(&cone, v, u.y);
    (dir, target_pdf(scene, p, dir))
}

/// The sum of the targets' cone heights seen from `p` (their total solid angle over 2π).
/// mirror: shaders/caustics.wgsl `targets_height`
pub fn targets_height(scene: &RenderScene, p: Vec3) -> f32 {
    let mut total = 0.0;
    for t in &scene.caustic_targets {
        total += target_cone(t, p).height;
    }
    total
}

/// The direction in `cone` at one minus cosine `v` (in [0, `cone.height`]) from its axis,
/// turned by 2π `turn` about it: uniform in the cone for uniform `v` and `turn`.
/// mirror: shaders/caustics.wgsl `sample_cone`
pub fn sample_cone(cone: &TargetCone, v: f32, turn: f32) -> Vec3 {
    let cos_t = 1.0 - v;
    let sin_t = (v * (2.0 - v)).max(0.0).sqrt();
    let phi = 2.0 * PI * turn;
    let (t, b) = onb_from_normal(cone.axis);
    (sin_t * phi.cos()) * t + (sin_t * phi.sin()) * b + cos_t * cone.axis
}

/// A non-delta vertex of a light subpath, reached through a specular chain, which the
/// camera path connects to. `segments` is 0 for none.
/// mirror: shaders/caustics.wgsl `LightVertex`
#[derive(Clone, Copy, Debug)]
pub struct LightVertex {
    pub si: SurfaceHit,
    /// Unit direction from the vertex back along the light's last segment.
    pub wi: Vec3,
    /// Throughput: emitted radiance times the emitted cosine over the light point's and
    /// direction's pdfs (a punctual light's intensity that way over the direction's pdf),
    /// times the adjoint weights of the delta bounces.
    pub beta: Vec3,
    /// The light strategy's density for [`link_weight`]: the light subpath rate times the
    /// area pdf of the light point times the solid-angle pdf of the emitted direction,
    /// over that direction's cosine; times, at each earlier non-delta vertex of the
    /// subpath, the ratio of its light to its camera sampling density (solid-angle pdfs
    /// times the cosine of the direction drawn from). 0 for a punctual light's subpath,
    /// which no other strategy competes with.
    pub pdf: f32,
    /// Segments from the light to the vertex (at least 2), or 0 for none.
    pub segments: u32,
}

impl LightVertex {
    /// No vertex.
    pub const NONE: Self = Self {
        si: SurfaceHit {
            p: Vec3::ZERO,
            ng: Vec3::Z,
            ns: Vec3::Z,
            nc: Vec3::Z,
            material: 0,
            front_face: true,
            tri: 0,
            uv: Vec4::ZERO,
            color: Vec4::ONE,
        },
        wi: Vec3::Z,
        beta: Vec3::ZERO,
        pdf: 0.0,
        segments: 0,
    };
}

/// At most this many vertices on a light subpath: its first non-delta vertex, and those
/// it reaches from there through a further specular chain each.
pub const MAX_CAUSTIC_HOPS: usize = 2;

/// A sample's light subpath: its non-delta vertices, in the order the light reaches them.
/// mirror: shaders/caustics.wgsl `LightPath`
#[derive(Clone, Copy, Debug)]
pub struct LightPath {
    pub vertices: [LightVertex; MAX_CAUSTIC_HOPS],
    pub count: u32,
}

impl LightPath {
    /// No vertex.
    pub const NONE: Self = Self {
        vertices: [LightVertex::NONE; MAX_CAUSTIC_HOPS],
        count: 0,
    };
}

/// The first segment of a light subpath: its ray, the throughput it carries and the light
/// strategy's density so far ([`LightVertex::pdf`]'s measure; 0 for a punctual light).
/// mirror: shaders/caustics.wgsl `LightSubpathStart` (whose field valid stands for the Option)
#[derive(Clone, Copy, Debug)]
pub struct LightSubpathStart {
    pub ray: Ray,
    pub beta: Vec3,
    pub pdf: f32,
}

/// A light subpath's start on emissive triangle `light` (picked by `pick`): a point on it
/// from the pick's pair, a direction towards the targets from `DIM_CAUSTIC_DIR_U` of
/// bounce 0. `None` where the point is masked out or the direction leaves by the back.
/// mirror: shaders/caustics.wgsl `start_at_triangle`
pub fn start_at_triangle(
    scene: &RenderScene,
    light: u32,
    pick: LightPick,
    rng: &Rng,
) -> Option<LightSubpathStart> {
    let tri = &scene.tris[light as usize];
    let [a, b, c] = tri.corners();
    let bary = sample_uniform_triangle(pick.u);
    if tri.is_masked() && !alpha_test(scene, light, bary.x, bary.y, false) {
        return None;
    }
    let q = (1.0 - bary.x - bary.y) * a + bary.x * b + bary.y * c;
    let n = scene.tri_normals[light as usize];
    let (dir, pdf_dir) = sample_target(scene, q, rng.rng_2d(0, rng::DIM_CAUSTIC_DIR_U));
    let cos_m = dir.dot(n);
    if !(cos_m > 0.0 && pdf_dir > 0.0) {
        return None;
    }
    let le = triangle_emission(scene, light, bary);
    let pdf_point = LIGHT_SUBPATH_RATE * pick.pmf / scene.emitter_areas[pick.index];
    let pdf = pdf_point * pdf_dir / cos_m;
    if pdf.is_nan() || pdf <= 0.0 {
        return None;
    }
    Some(LightSubpathStart {
        ray: Ray::new(offset_ray_origin(q, n, dir), dir),
        beta: le * (cos_m / (pdf_point * pdf_dir)),
        pdf,
    })
}

/// A light subpath's start at point or spot light `index` (picked with probability
/// `pmf`): a direction from the pair `DIM_CAUSTIC_DIR_U` of bounce 0, towards the targets
/// or, for a spot whose cone is the narrower, uniform in that cone (either covers every
/// direction that both carries light and meets a specular object first), carrying the
/// light's intensity that way. Its pdf is 0: BSDF sampling never reaches a point, so the
/// light subpath is the only strategy for its paths, and their weight is 1. A directional
/// light starts as [`start_at_directional`] says, a rectangle as [`start_at_rect`].
/// `None` where a spot sends nothing that way.
/// mirror: shaders/caustics.wgsl `start_at_punctual`
pub fn start_at_punctual(
    scene: &RenderScene,
    index: u32,
    pmf: f32,
    u: Vec2,
    rng: &Rng,
) -> Option<LightSubpathStart> {
    let l = &scene.lights[index as usize];
    if l.kind == LIGHT_DIRECTIONAL {
        return start_at_directional(scene, l, pmf, rng);
    }
    if l.kind == LIGHT_RECT {
        return start_at_rect(scene, l, pmf, u, rng);
    }
    let q = Vec3::from(l.position);
    let u = rng.rng_2d(0, rng::DIM_CAUSTIC_DIR_U);
    let spot = TargetCone {
        axis: Vec3::from(l.direction),
        cos_max: l.cos_cutoff,
        height: 1.0 - l.cos_cutoff,
    };
    let (dir, pdf_dir) = if l.kind == LIGHT_SPOT && spot.height < targets_height(scene, q) {
        (
            sample_cone(&spot, u.x * spot.height, u.y),
            1.0 / (2.0 * PI * spot.height),
        )
    } else {
        sample_target(scene, q, u)
    };
    let mut intensity = Vec3::from(l.intensity);
    if l.kind == LIGHT_SPOT {
        intensity *= spot_falloff(l, dir);
    }
    let pdf_dir = LIGHT_SUBPATH_RATE * pmf * pdf_dir;
    if pdf_dir.is_nan() || pdf_dir <= 0.0 || intensity == Vec3::ZERO {
        return None;
    }
    Some(LightSubpathStart {
        ray: Ray::new(q, dir),
        beta: intensity * (1.0 / pdf_dir),
        pdf: 0.0,
    })
}

/// A light subpath's start on rectangle light `l` (picked with probability `pmf`): the
/// point the pick's pair `u` puts on it, uniform in area, and a direction towards the
/// targets from the pair `DIM_CAUSTIC_DIR_U` of bounce 0, as an emissive triangle's, with
/// the same pdf: BSDF-sampled rays reach a rectangle too. `None` where the direction
/// leaves by its back.
/// mirror: shaders/caustics.wgsl `start_at_rect`
pub fn start_at_rect(
    scene: &RenderScene,
    l: &Light,
    pmf: f32,
    u: Vec2,
    rng: &Rng,
) -> Option<LightSubpathStart> {
    let (ex, ey) = (Vec3::from(l.direction), Vec3::from(l.edge));
    let q = Vec3::from(l.position) + u.x * ex + u.y * ey;
    let n = ex.cross(ey).normalize();
    let (dir, pdf_dir) = sample_target(scene, q, rng.rng_2d(0, rng::DIM_CAUSTIC_DIR_U));
    let cos_m = dir.dot(n);
    let pdf_point = LIGHT_SUBPATH_RATE * pmf / l.area;
    if !(cos_m > 0.0 && pdf_dir > 0.0 && pdf_point > 0.0) {
        return None;
    }
    let pdf = pdf_point * pdf_dir / cos_m;
    if pdf.is_nan() || pdf <= 0.0 {
        return None;
    }
    Some(LightSubpathStart {
        ray: Ray::new(q, dir),
        beta: Vec3::from(l.intensity) * (cos_m / (pdf_point * pdf_dir)),
        pdf,
    })
}

/// A light subpath's start from directional light `l` (picked with probability `pmf`): a
/// line along its direction through the disk that faces it across one of the targets
/// (picked in proportion to the disks' areas by the first number of the pair
/// `DIM_CAUSTIC_DIR_U` of bounce 0, rescaled, then a point of the disk), starting outside
/// [`RenderScene::scene_sphere`], so that whatever lies in the light's way still shades
/// the target. Every line that meets a specular object crosses its target's disk, and the
/// line's density across it is the number of disks it crosses over their total area. It
/// carries the light's irradiance over that density; its pdf is 0, as a point light's:
/// BSDF sampling never finds a directional light.
/// mirror: shaders/caustics.wgsl `start_at_directional`
pub fn start_at_directional(
    scene: &RenderScene,
    l: &Light,
    pmf: f32,
    rng: &Rng,
) -> Option<LightSubpathStart> {
    let d = Vec3::from(l.direction);
    let u = rng.rng_2d(0, rng::DIM_CAUSTIC_DIR_U);
    let mut total = 0.0;
    for t in &scene.caustic_targets {
        total += t.radius * t.radius;
    }
    let mut x = u.x * total;
    let mut picked = scene.caustic_targets[0];
    for t in &scene.caustic_targets {
        picked = *t;
        if x < t.radius * t.radius {
            break;
        }
        x -= t.radius * t.radius;
    }
    let r2 = picked.radius * picked.radius;
    let disk = sample_concentric_disk(Vec2::new((x / r2).clamp(0.0, ONE_MINUS_EPSILON), u.y));
    let (t, b) = onb_from_normal(d);
    let s = Vec3::from(picked.center) + picked.radius * (disk.x * t + disk.y * b);
    let mut count = 0.0;
    for k in &scene.caustic_targets {
        let off = s - Vec3::from(k.center);
        let across = off - off.dot(d) * d;
        if across.length_squared() <= k.radius * k.radius {
            count += 1.0;
        }
    }
    let pdf_line = LIGHT_SUBPATH_RATE * pmf * count / (PI * total);
    if pdf_line.is_nan() || pdf_line <= 0.0 {
        return None;
    }
    let (center, radius) = scene.scene_sphere;
    let back = (s - center).length() + radius;
    Some(LightSubpathStart {
        ray: Ray::new(s - back * d, d),
        beta: Vec3::from(l.intensity) * (1.0 / pdf_line),
        pdf: 0.0,
    })
}

/// The power-heuristic weight of a connection to light vertex `lv` against BSDF sampling,
/// whose density for the same path is `pdf_bsdf` (in `LightVertex::pdf`'s measure): 1 for
/// a punctual light's vertex (`lv.pdf` 0), which BSDF sampling cannot make.
/// mirror: shaders/caustics.wgsl `link_weight`
pub fn link_weight(pdf_bsdf: f32, lv: &LightVertex) -> f32 {
    if lv.pdf > 0.0 {
        caustic_weight(pdf_bsdf / lv.pdf)
    } else {
        1.0
    }
}

/// Traces the sample's light subpath, of at most `max_segments` segments: a light point and
/// a direction (towards the targets) from the pairs `DIM_CAUSTIC_LIGHT_U` and
/// `DIM_CAUSTIC_DIR_U` of bounce 0, then delta bounces, the one at vertex j taking its lobe
/// number from `DIM_CAUSTIC_LOBE` of bounce j, up to the first non-delta vertex, which it
/// keeps. From there it samples the adjoint BSDF (lobe and pair from the same dimensions
/// of its bounce) and keeps the next non-delta vertex too if a specular chain leads to it,
/// up to [`MAX_CAUSTIC_HOPS`] vertices. The subpath ends where it misses, meets a
/// non-delta surface right after a non-delta vertex (or the light), or where the light
/// picked is the sky ([`start_at_triangle`] and [`start_at_punctual`] start it). Returns the vertices and the rays traced.
/// mirror: shaders/caustics.wgsl `trace_light_subpath`
pub fn trace_light_subpath(scene: &RenderScene, rng: &Rng, max_segments: u32) -> (LightPath, u32) {
    let mut path = LightPath::NONE;
    if scene.caustic_targets.is_empty() || scene.emitters.is_empty() || max_segments < 2 {
        return (path, 0);
    }
    if rng.rng_1d(0, rng::DIM_LIGHT_SUBPATH) >= LIGHT_SUBPATH_RATE {
        return (path, 0);
    }
    let pick = pick_light(scene, rng.rng_2d(0, rng::DIM_CAUSTIC_LIGHT_U));
    let light = scene.emitters[pick.index];
    let Some(start) = (if light == SKY_EMITTER {
        None
    } else if light & LIGHT_EMITTER != 0 {
        start_at_punctual(scene, light & !LIGHT_EMITTER, pick.pmf, pick.u, rng)
    } else {
        start_at_triangle(scene, light, pick, rng)
    }) else {
        return (path, 0);
    };
    let (mut beta, mut pdf, mut ray) = (start.beta, start.pdf, start.ray);
    let mut rays = 0;
    // Delta vertices since the last non-delta one (or the light).
    let mut chain = 0;
    for segment in 1..=max_segments {
        rays += 1;
        let Some(hit) = scene
            .wide
            .traverse_closest(&ray, T_INF, |t, u, v| alpha_test(scene, t, u, v, false))
        else {
            break;
        };
        let si = surface_at(scene, &ray, &hit);
        let mat = material_at(
            scene,
            &scene.materials[si.material as usize],
            si.uv,
            si.color,
        );
        let delta = bsdf_is_delta(&mat);
        if !delta && chain == 0 {
            break;
        }
        let wo_world = -ray.dir;
        if !delta {
            path.vertices[path.count as usize] = LightVertex {
                si,
                wi: wo_world,
                beta,
                pdf,
                segments: segment,
            };
            path.count += 1;
            chain = 0;
            if path.count as usize == MAX_CAUSTIC_HOPS {
                break;
            }
        } else {
            chain += 1;
        }
        if segment == max_segments {
            break;
        }
        // A bounce sampled from the side the light came from.
        let frame = shading_frame(&mat, &si, wo_world);
        let mat = coated(&mat, &si, &frame);
        let wo = frame.to_local(wo_world);
        let u_lobe = if bsdf_draws_lobe(&mat) {
            rng.rng_1d(segment, rng::DIM_CAUSTIC_LOBE)
        } else {
            0.0
        };
        let u = if delta {
            Vec2::ZERO
        } else {
            rng.rng_2d(segment, rng::DIM_CAUSTIC_DIR_U)
        };
        let Some(bs) = bsdf_sample(&mat, wo, u_lobe, u) else {
            break;
        };
        // A delta lobe of a material that also has others ends the subpath, as it breaks
        // the chain in the camera path's bookkeeping too.
        if bs.delta != delta {
            break;
        }
        let wi_world = frame.to_world(bs.wi);
        if !geometry_agrees(si.ng, wo_world, wi_world, wo, bs.wi) {
            break;
        }
        // The adjoint weight: without the radiance scaling of a refraction (the squared
        // relative index, which `bsdf_sample` applies), and with the shading-normal
        // correction |wo.ns| |wi.ng| / (|wo.ng| |wi.ns|).
        let cos_in = wo_world.dot(si.ng).abs();
        let cos_out = wi_world.dot(si.ng).abs();
        let denom = cos_in * wi_world.dot(frame.ns).abs();
        if denom.is_nan() || denom <= 0.0 {
            break;
        }
        let correction = wo_world.dot(frame.ns).abs() * cos_out / denom;
        beta *= bs.weight * (bs.eta * bs.eta * correction);
        if !delta && pdf > 0.0 {
            // The ratio of this vertex's light density to its camera density, as
            // `PathState::caustic_pdf` takes it, the other way round. (A punctual light's
            // subpath keeps its pdf of 0: no other strategy makes its paths.)
            let back = shading_frame(&mat, &si, wi_world);
            let mat_b = coated(&mat, &si, &back);
            let pdf_camera = bsdf_pdf(&mat_b, back.to_local(wi_world), back.to_local(wo_world));
            pdf *= bs.pdf * cos_in / (pdf_camera * cos_out);
            if !(pdf > 0.0 && pdf.is_finite()) {
                break;
            }
        }
        if beta == Vec3::ZERO {
            break;
        }
        ray = Ray::new(offset_ray_origin(si.p, si.ng, wi_world), wi_world);
    }
    (path, rays)
}

/// The power-heuristic weight of a strategy of density `a` against one of density `b`,
/// given as their ratio `b / a`: 1 where `b` is zero.
/// mirror: shaders/caustics.wgsl `caustic_weight`
pub fn caustic_weight(ratio: f32) -> f32 {
    let w = 1.0 / (1.0 + ratio * ratio);
    if w.is_nan() { 0.0 } else { w }
}

/// A camera vertex's connection to a light vertex: the shadow ray, and what it adds to the
/// path's radiance, before the path's throughput, if nothing blocks it.
/// mirror: shaders/caustics.wgsl `CausticLink` (whose field valid stands for the Option)
#[derive(Clone, Copy, Debug)]
pub struct CausticLink {
    pub ray: Ray,
    pub t_max: f32,
    pub value: Vec3,
}

/// The connection of the camera vertex `si` (material `mat`, seen along `wo_world`, its
/// BSDF frame `frame` and `wo` in it) to light vertex `lv`: both BSDFs, the geometry term
/// (with the adjoint's shading-normal correction at the light vertex) and the light
/// subpath's throughput, weighed against BSDF sampling from the camera vertex by
/// [`caustic_weight`]. `None` where no light passes.
/// mirror: shaders/caustics.wgsl `caustic_link`
pub fn caustic_link(
    scene: &RenderScene,
    si: &SurfaceHit,
    mat: &Material,
    frame: &ShadingFrame,
    wo_world: Vec3,
    wo: Vec3,
    lv: &LightVertex,
) -> Option<CausticLink> {
    let d = lv.si.p - si.p;
    let dist2 = d.length_squared();
    if dist2.is_nan() || dist2 <= 0.0 {
        return None;
    }
    let wc = d * (1.0 / dist2.sqrt());
    let cos_i = wc.dot(frame.ng);
    let usable = if bsdf_transmits(mat) {
        cos_i != 0.0
    } else {
        cos_i > 0.0
    };
    if !usable {
        return None;
    }
    let wi = frame.to_local(wc);
    let f = bsdf_eval(mat, wo, wi);
    if f == Vec3::ZERO || !geometry_agrees(si.ng, wo_world, wc, wo, wi) {
        return None;
    }
    let seen = light_vertex_seen(scene, lv, wc)?;
    // BSDF sampling's density for this path, in the measure of `LightVertex::pdf`.
    let pdf_bsdf = bsdf_pdf(mat, wo, wi) / dist2 * seen.pdf;
    let w = link_weight(pdf_bsdf, lv);
    let origin = offset_ray_origin(si.p, si.ng, wc);
    let to = seen.end - origin;
    let dist = to.length();
    if dist.is_nan() || dist <= 0.0 {
        return None;
    }
    Some(CausticLink {
        ray: Ray::new(origin, to * (1.0 / dist)),
        t_max: dist * (1.0 - 1e-4),
        value: f * seen.value * (w / dist2),
    })
}

/// A light vertex as a connection along unit `wc` (towards the vertex) sees it, the part
/// that [`caustic_link`] and [`camera_link`] share.
/// mirror: shaders/caustics.wgsl `SeenLightVertex` (whose field valid stands for the Option)
#[derive(Clone, Copy, Debug)]
pub struct SeenLightVertex {
    /// The light the vertex sends back along `wc`, over the squared distance still to
    /// divide by: its BSDF times its throughput times cos(wc) over cos(its light's
    /// direction).
    pub value: Vec3,
    /// The adjoint of that density: the vertex's BSDF-sampling pdf of its light's
    /// direction, seen from `wc`, times cos(wc) over cos(that direction); times the
    /// connecting side's own pdf over the squared distance, the density with which BSDF
    /// sampling makes the path, in the measure of [`LightVertex::pdf`].
    pub pdf: f32,
    /// Where the shadow ray ends: the vertex moved off its surface towards the connection.
    pub end: Vec3,
}

/// The light vertex `lv` seen along unit `wc`; `None` where it sends no light that way.
/// mirror: shaders/caustics.wgsl `light_vertex_seen`
pub fn light_vertex_seen(
    scene: &RenderScene,
    lv: &LightVertex,
    wc: Vec3,
) -> Option<SeenLightVertex> {
    let base = &scene.materials[lv.si.material as usize];
    let mat_l = material_at(scene, base, lv.si.uv, lv.si.color);
    let wo_l_world = -wc;
    let frame_l = shading_frame(&mat_l, &lv.si, wo_l_world);
    let mat_l = coated(&mat_l, &lv.si, &frame_l);
    let wo_l = frame_l.to_local(wo_l_world);
    let wi_l = frame_l.to_local(lv.wi);
    let f_l = bsdf_eval(&mat_l, wo_l, wi_l);
    if f_l == Vec3::ZERO || !geometry_agrees(lv.si.ng, wo_l_world, lv.wi, wo_l, wi_l) {
        return None;
    }
    let cos_c = wc.dot(lv.si.ng).abs();
    let cos_k = lv.wi.dot(lv.si.ng).abs();
    if cos_k.is_nan() || cos_k <= 0.0 {
        return None;
    }
    let ratio = cos_c / cos_k;
    Some(SeenLightVertex {
        value: f_l * lv.beta * ratio,
        pdf: bsdf_pdf(&mat_l, wo_l, wi_l) * ratio,
        end: offset_ray_origin(lv.si.p, lv.si.ng, wo_l_world),
    })
}

/// The weight of emission that BSDF sampling found at the end of a specular chain, against
/// the light subpath that could have made the same path: `pdf_bsdf` is the path's
/// [`PathState::caustic_pdf`](super::integrator::PathState::caustic_pdf), and the light
/// point lies at `p` on an emitter of area `area` (a triangle, a rectangle) that light
/// subpaths start on with pick probability `pmf`, the path arriving along unit `dir` with
/// cosine `cos_l` to its normal. mirror: shaders/caustics.wgsl `caustic_hit_weight`
pub fn caustic_hit_weight(
    scene: &RenderScene,
    pmf: f32,
    area: f32,
    p: Vec3,
    dir: Vec3,
    cos_l: f32,
    pdf_bsdf: f32,
) -> f32 {
    if pmf == 0.0 || cos_l.is_nan() || cos_l <= 0.0 {
        return 1.0;
    }
    let pdf_light = LIGHT_SUBPATH_RATE * pmf / area * target_pdf(scene, p, -dir) / cos_l;
    caustic_weight(pdf_light / pdf_bsdf)
}

/// The solid-angle density, over the whole image, with which the camera draws a primary
/// ray leaving the lens along unit `dir`: uniform over the image plane at unit distance
/// (area 4 tan²(vfov/2) × aspect), so 1 / (that area × cos³θ) from the viewing axis. One
/// camera sample per pixel and sample means the whole image, where each light subpath
/// may land, is the measure a light subpath's splat competes with.
/// mirror: shaders/caustics.wgsl `camera_pdf`
pub fn camera_pdf(cam: &CameraRays, dir: Vec3) -> f32 {
    let cos = dir.dot(cam.forward);
    if cos.is_nan() || cos <= 0.0 {
        return 0.0;
    }
    let area = 4.0 * cam.tan_half_vfov * cam.tan_half_vfov * cam.aspect;
    1.0 / (area * cos * cos * cos)
}

/// A light vertex seen through the lens: the pixel it lands in, the shadow ray, and what
/// it adds to that pixel's sum if nothing blocks the ray (the film divides sums by the
/// samples per pixel, and there is one light subpath per camera sample).
/// mirror: shaders/caustics.wgsl `CameraLink` (whose field valid stands for the Option)
#[derive(Clone, Copy, Debug)]
pub struct CameraLink {
    pub pixel: u32,
    pub ray: Ray,
    pub t_max: f32,
    pub value: Vec3,
}

/// The connection of light vertex `lv` to the camera, through the lens point that the
/// pair `u_lens` picks (`DIM_LENS_U` of the vertex's bounce), weighed against BSDF sampling
/// from a camera ray's first hit by [`caustic_weight`] with [`camera_pdf`] as the camera's
/// density. `None` where the vertex is outside the image or no light passes.
/// mirror: shaders/caustics.wgsl `camera_link`
pub fn camera_link(
    scene: &RenderScene,
    cam: &CameraRays,
    lv: &LightVertex,
    u_lens: Vec2,
) -> Option<CameraLink> {
    let lens = if cam.aperture > 0.0 {
        let d = 0.5 * cam.aperture * sample_concentric_disk(u_lens);
        d.x * cam.right + d.y * cam.up
    } else {
        Vec3::ZERO
    };
    let origin = cam.position + lens;
    let d = lv.si.p - origin;
    let depth = d.dot(cam.forward);
    if depth.is_nan() || depth <= 0.0 {
        return None;
    }
    // Where the ray from the lens point through the vertex crosses the plane in focus,
    // as `generate_camera_ray` maps a pixel sample to it (at unit distance for a pinhole).
    let s = if cam.aperture > 0.0 {
        lens * (1.0 / cam.focus_distance) + d * (1.0 / depth)
    } else {
        d * (1.0 / depth)
    };
    let x = (s.dot(cam.right) / (cam.tan_half_vfov * cam.aspect) + 1.0) * 0.5 * cam.width as f32;
    let y = (1.0 - s.dot(cam.up) / cam.tan_half_vfov) * 0.5 * cam.height as f32;
    if !(x >= 0.0 && x < cam.width as f32 && y >= 0.0 && y < cam.height as f32) {
        return None;
    }
    let dist2 = d.length_squared();
    let dist = dist2.sqrt();
    let wc = d * (1.0 / dist);
    let seen = light_vertex_seen(scene, lv, wc)?;
    let importance = camera_pdf(cam, wc);
    let pdf_bsdf = importance / dist2 * seen.pdf;
    let w = link_weight(pdf_bsdf, lv);
    let to = seen.end - origin;
    let len = to.length();
    if len.is_nan() || len <= 0.0 {
        return None;
    }
    Some(CameraLink {
        pixel: y as u32 * cam.width + x as u32,
        ray: Ray::new(origin, to * (1.0 / len)),
        t_max: len * (1.0 - 1e-4),
        value: seen.value * (importance * w / dist2),
    })
}
