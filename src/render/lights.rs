//! The lights next event estimation samples: emissive triangles, punctual and rectangle lights,
//! chosen by power, and the sky. Every function has a WGSL twin of the same name in
//! `shaders/lights.wgsl`.

use super::environment::{env_pdf, env_radiance, sample_env};
use super::sampling::{
    ONE_MINUS_EPSILON, UNIFORM_SPHERE_PDF, sample_cdf, sample_uniform_sphere,
    sample_uniform_triangle,
};
use super::surface::offset_ray_origin;
use super::tables::{
    LIGHT_DIRECTIONAL, LIGHT_EMITTER, LIGHT_RECT, LIGHT_SPOT, Light, RenderScene, SKY_EMITTER,
};
use super::texture::{alpha_test, material_at, triangle_uv};
use crate::geometry::{self, T_INF};
use crate::math::Ray;
use crate::scene::{NO_TEXTURE, Sky};
use glam::{Vec2, Vec3, Vec4};
use std::f32::consts::PI;

/// Radiance arriving along unit `dir` from outside the scene.
/// mirror: shaders/lights.wgsl `sky_radiance`
pub fn sky_radiance(scene: &RenderScene, dir: Vec3) -> Vec3 {
    match scene.sky {
        Sky::Constant(c) => c,
        Sky::Gradient { zenith, horizon } => horizon.lerp(zenith, 0.5 * (dir.y + 1.0)),
        Sky::Environment { .. } => env_radiance(scene, dir),
    }
}

/// Solid-angle probability density of light sampling choosing unit direction `dir`
/// towards the sky, its pick included: an environment map's own distribution, otherwise
/// uniform over the sphere. mirror: shaders/lights.wgsl `sky_pdf`
pub fn sky_pdf(scene: &RenderScene, dir: Vec3) -> f32 {
    match scene.sky {
        Sky::Environment { .. } => scene.sky_pmf * env_pdf(scene, dir),
        _ => scene.sky_pmf * UNIFORM_SPHERE_PDF,
    }
}

/// Probability density, in solid angle at the shading point, of light sampling choosing the
/// point at distance `dist` on triangle `tri` whose cosine towards the shading point is `cos_l`.
/// mirror: shaders/lights.wgsl `light_pdf`
#[inline]
pub fn light_pdf(scene: &RenderScene, tri: u32, dist: f32, cos_l: f32) -> f32 {
    let area = geometry::triangle_area(&scene.tris[tri as usize]);
    area_to_solid_angle(scene.shading[tri as usize].emitter_pmf, area, dist, cos_l)
}

/// [`light_pdf`]'s arithmetic, given the triangle's pick probability and area.
#[inline]
fn area_to_solid_angle(pmf: f32, area: f32, dist: f32, cos_l: f32) -> f32 {
    pmf * dist * dist / (cos_l * area)
}

/// A point on a light chosen for next event estimation, seen from a shading point.
/// mirror: shaders/lights.wgsl `LightSample` (whose field valid stands for the Option)
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    /// The shadow ray: from `origin` along unit `wi` up to `t_max`.
    pub origin: Vec3,
    pub wi: Vec3,
    pub t_max: f32,
    /// Radiance arriving along the shadow ray if nothing blocks it.
    pub le: Vec3,
    /// Solid-angle pdf of having drawn `wi`, the light's pick included; for a punctual
    /// light (`delta`) the probability of its pick.
    pub pdf: f32,
    /// A punctual light, which BSDF sampling can never hit: no MIS.
    pub delta: bool,
}

/// The light next event estimation samples, and the pair of numbers its own sampling then
/// takes. mirror: shaders/lights.wgsl `LightPick`
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightPick {
    /// The entry of `RenderScene::emitters`.
    pub index: usize,
    /// The probability of its pick.
    pub pmf: f32,
    pub u: Vec2,
}

/// Picks a light for the light pair `u`: where there are several, `u.x` picks by the emitter
/// CDF and is then rescaled within the pick's share of [0, 1), so that the points a pixel's
/// samples put on each light stay stratified (a pick number of its own would leave each
/// light a scattered subset of them). As in pbrt-v4 and Mitsuba 3, which reuse a number the
/// same way, the rescaled number keeps fewer bits the rarer its pick: 24 less log2 of
/// 1 / `pmf`. mirror: shaders/lights.wgsl `pick_light`
pub fn pick_light(scene: &RenderScene, u: Vec2) -> LightPick {
    let cdf = &scene.emitter_cdf;
    if cdf.len() == 1 {
        return LightPick {
            index: 0,
            pmf: cdf[0],
            u,
        };
    }
    let (index, lo) = sample_cdf(cdf, u.x);
    let pmf = cdf[index] - lo;
    LightPick {
        index,
        pmf,
        u: Vec2::new(((u.x - lo) / pmf).min(ONE_MINUS_EPSILON), u.y),
    }
}

/// Picks a light ([`pick_light`]) and a point (triangle) or direction (sky) on it for the
/// light pair `u` (the vertex's `DIM_LIGHT_U` pair), as seen from surface point `p` with
/// geometric normal `ng` facing the viewer. `None` when the point faces away, and for a
/// light that next event estimation samples in full besides
/// ([`RenderScene::lights_in_full`]).
/// mirror: shaders/lights.wgsl `sample_light`
pub fn sample_light(scene: &RenderScene, p: Vec3, ng: Vec3, u: Vec2) -> Option<LightSample> {
    let pick = pick_light(scene, u);
    let (light, u) = (scene.emitters[pick.index], pick.u);
    if light == SKY_EMITTER {
        let (wi, pdf) = match scene.sky {
            Sky::Environment { .. } => sample_env(scene, u),
            _ => (sample_uniform_sphere(u), UNIFORM_SPHERE_PDF),
        };
        if pdf <= 0.0 {
            return None;
        }
        return Some(LightSample {
            origin: offset_ray_origin(p, ng, wi),
            wi,
            t_max: T_INF,
            le: sky_radiance(scene, wi),
            pdf: scene.sky_pmf * pdf,
            delta: false,
        });
    }
    if light & LIGHT_EMITTER != 0 {
        let index = light & !LIGHT_EMITTER;
        if index < scene.lights_in_full && scene.lights[index as usize].kind != LIGHT_RECT {
            return None;
        }
        return sample_punctual(scene, index, p, ng, pick.pmf, u);
    }
    let tri = &scene.tris[light as usize];
    let [a, b, c] = tri.corners();
    let bary = sample_uniform_triangle(u);
    let q = (1.0 - bary.x - bary.y) * a + bary.x * b + bary.y * c;
    let origin = offset_ray_origin(p, ng, q - p);
    let to_light = q - origin;
    let dist = to_light.length();
    let wi = to_light * (1.0 / dist);
    let cos_l = -wi.dot(scene.tri_normals[light as usize]);
    // A point that an alpha mask cuts out emits nothing.
    if !(cos_l > 0.0 && dist > 0.0)
        || (tri.is_masked() && !alpha_test(scene, light, bary.x, bary.y, false))
    {
        return None;
    }
    let le = triangle_emission(scene, light, bary);
    Some(LightSample {
        origin,
        wi,
        t_max: dist * (1.0 - 1e-4),
        le,
        pdf: area_to_solid_angle(
            scene.shading[light as usize].emitter_pmf,
            scene.emitter_areas[pick.index],
            dist,
            cos_l,
        ),
        delta: false,
    })
}

/// The radiance emitted at barycentric point `bary` of emissive triangle `light`: its
/// material's emission, or its emission texture there.
/// mirror: shaders/lights.wgsl `triangle_emission`
pub fn triangle_emission(scene: &RenderScene, light: u32, bary: Vec2) -> Vec3 {
    let material = &scene.materials[scene.shading[light as usize].material as usize];
    if material.emission_texture != NO_TEXTURE {
        // Vertex colours tint the base colour, not the emission.
        let uv = triangle_uv(scene, light, bary.x, bary.y);
        material_at(scene, material, uv, Vec4::ONE).emission
    } else {
        material.emission
    }
}

/// The shadow ray and arriving radiance of light `index`, picked with probability `pmf`,
/// seen from `p`: a point or spot light's intensity over the squared distance (a spot's
/// times its falloff), a directional light's irradiance, or a rectangle's radiance at the
/// point `u` draws on it ([`sample_rect`]), with that point's solid-angle density (times
/// `pmf`): BSDF-sampled rays reach a rectangle too ([`hit_rect`]), and the two are weighed
/// by the power heuristic. A light without shadows gets a shadow ray of length 0, which
/// nothing blocks. `None` where it sends no light.
/// mirror: shaders/lights.wgsl `sample_punctual`
pub fn sample_punctual(
    scene: &RenderScene,
    index: u32,
    p: Vec3,
    ng: Vec3,
    pmf: f32,
    u: Vec2,
) -> Option<LightSample> {
    let l = &scene.lights[index as usize];
    let intensity = Vec3::from(l.intensity);
    if l.kind == LIGHT_DIRECTIONAL {
        let wi = -Vec3::from(l.direction);
        return Some(LightSample {
            origin: offset_ray_origin(p, ng, wi),
            wi,
            t_max: if l.shadows != 0 { T_INF } else { 0.0 },
            le: intensity,
            pdf: pmf,
            delta: true,
        });
    }
    if l.kind == LIGHT_RECT {
        let (q, pdf) = sample_rect(l, p, u)?;
        let origin = offset_ray_origin(p, ng, q - p);
        let to_light = q - origin;
        let dist = to_light.length();
        if !(dist > 0.0 && pdf > 0.0) {
            return None;
        }
        return Some(LightSample {
            origin,
            wi: to_light * (1.0 / dist),
            t_max: dist * (1.0 - 1e-4),
            le: intensity,
            pdf: pmf * pdf,
            delta: false,
        });
    }
    let position = Vec3::from(l.position);
    let origin = offset_ray_origin(p, ng, position - p);
    let to_light = position - origin;
    let dist2 = to_light.length_squared();
    let dist = dist2.sqrt();
    if dist.is_nan() || dist <= 0.0 {
        return None;
    }
    let wi = to_light * (1.0 / dist);
    let mut le = intensity / dist2;
    if l.kind == LIGHT_SPOT {
        le *= spot_falloff(l, -wi);
    }
    if le == Vec3::ZERO {
        return None;
    }
    Some(LightSample {
        origin,
        wi,
        t_max: dist * (1.0 - 1e-4),
        le,
        pdf: pmf,
        delta: true,
    })
}

/// Rectangle light `l` seen from a point: its frame (unit edges `x`, `y` and the normal
/// `n` of its emitting side), the point's coordinates in that frame relative to the corner
/// (`x0`..`x1` and `y0`..`y1` span the rectangle, at height `z0` < 0), and the spherical
/// rectangle it subtends: the normals of its four great-circle edges, its inner angles and
/// its solid angle. mirror: shaders/lights.wgsl `RectView`
#[derive(Clone, Copy, Debug)]
pub struct RectView {
    pub x: Vec3,
    pub y: Vec3,
    pub n: Vec3,
    pub x0: f32,
    pub y0: f32,
    pub x1: f32,
    pub y1: f32,
    pub z0: f32,
    pub n0: Vec3,
    pub n2: Vec3,
    pub g: [f32; 4],
    pub solid_angle: f32,
}

/// Rectangle light `l` seen from `p` ([`RectView`]); `None` where `p` is behind its
/// emitting side. mirror: shaders/lights.wgsl `rect_view`
pub fn rect_view(l: &Light, p: Vec3) -> Option<RectView> {
    let (s, ex, ey) = (
        Vec3::from(l.position),
        Vec3::from(l.direction),
        Vec3::from(l.edge),
    );
    let (exl, eyl) = (ex.length(), ey.length());
    let (x, y) = (ex * (1.0 / exl), ey * (1.0 / eyl));
    let n = x.cross(y);
    let d = s - p;
    let z0 = d.dot(n);
    // The light leaves on the side of n: p must be there, so z0 < 0.
    if z0.is_nan() || z0 >= 0.0 {
        return None;
    }
    let (x0, y0) = (d.dot(x), d.dot(y));
    let (x1, y1) = (x0 + exl, y0 + eyl);
    let v00 = Vec3::new(x0, y0, z0);
    let v01 = Vec3::new(x0, y1, z0);
    let v10 = Vec3::new(x1, y0, z0);
    let v11 = Vec3::new(x1, y1, z0);
    let n0 = v00.cross(v10).normalize();
    let n1 = v10.cross(v11).normalize();
    let n2 = v11.cross(v01).normalize();
    let n3 = v01.cross(v00).normalize();
    let g = [
        angle_between(-n0, n1),
        angle_between(-n1, n2),
        angle_between(-n2, n3),
        angle_between(-n3, n0),
    ];
    let solid_angle = g[0] + g[1] + g[2] + g[3] - 2.0 * PI;
    Some(RectView {
        x,
        y,
        n,
        x0,
        y0,
        x1,
        y1,
        z0,
        n0,
        n2,
        g,
        solid_angle,
    })
}

/// Whether [`sample_rect`] draws uniformly in area, not in solid angle, for a rectangle
/// seen as `view`: under 10⁻³ sr, where the two agree and the spherical form loses
/// precision. mirror: shaders/lights.wgsl `rect_by_area`
pub fn rect_by_area(view: &RectView) -> bool {
    view.solid_angle.is_nan() || view.solid_angle < 1e-3
}

/// A point of rectangle light `l` for the pair `u`, as seen from `p`, and the solid-angle
/// density of its direction: uniform in the solid angle the rectangle subtends (Ureña,
/// Fajardo and King 2013, "An area-preserving parametrization for spherical rectangles", as
/// pbrt-v4 writes it), so that a light as wide as the sky is sampled as well as a small
/// one; uniform in area where [`rect_by_area`]. `None` where `p` is behind the emitting
/// side. mirror: shaders/lights.wgsl `sample_rect`
pub fn sample_rect(l: &Light, p: Vec3, u: Vec2) -> Option<(Vec3, f32)> {
    let v = rect_view(l, p)?;
    if rect_by_area(&v) {
        let q = Vec3::from(l.position) + u.x * Vec3::from(l.direction) + u.y * Vec3::from(l.edge);
        let to = q - p;
        let dist2 = to.length_squared();
        let cos_l = -to.dot(v.n) / dist2.sqrt();
        return Some((q, dist2 / (cos_l * l.area)));
    }
    let [g0, g1, g2, g3] = v.g;
    let (b0, b1) = (v.n0.z, v.n2.z);
    let au = u.x * (g0 + g1 - 2.0 * PI) + (u.x - 1.0) * (g2 + g3);
    let fu = (au.cos() * b0 - b1) / au.sin();
    let sign = if fu >= 0.0 { 1.0 } else { -1.0 };
    let cu = (sign / (fu * fu + b0 * b0).sqrt()).clamp(-ONE_MINUS_EPSILON, ONE_MINUS_EPSILON);
    let xu = (-(cu * v.z0) / (1.0 - cu * cu).max(0.0).sqrt()).clamp(v.x0, v.x1);
    let dd = (xu * xu + v.z0 * v.z0).sqrt();
    let h0 = v.y0 / (dd * dd + v.y0 * v.y0).sqrt();
    let h1 = v.y1 / (dd * dd + v.y1 * v.y1).sqrt();
    let hv = h0 + u.y * (h1 - h0);
    let hv2 = hv * hv;
    let yv = if hv2 < 1.0 - 1e-4 {
        hv * dd / (1.0 - hv2).sqrt()
    } else {
        v.y1
    };
    Some((p + xu * v.x + yv * v.y + v.z0 * v.n, 1.0 / v.solid_angle))
}

/// The solid-angle density with which [`sample_rect`] draws, from `p`, the direction to the
/// point of rectangle light `l` at distance `dist` whose cosine towards `p` is `cos_l`.
/// mirror: shaders/lights.wgsl `rect_pdf`
pub fn rect_pdf(l: &Light, p: Vec3, dist: f32, cos_l: f32) -> f32 {
    match rect_view(l, p) {
        None => 0.0,
        Some(view) if rect_by_area(&view) => dist * dist / (cos_l * l.area),
        Some(view) => 1.0 / view.solid_angle,
    }
}

/// Where `ray` meets the emitting side of rectangle light `l` before `t_max`: the distance
/// and the cosine there between the ray and the light's normal, reversed.
/// mirror: shaders/lights.wgsl `hit_rect`
pub fn hit_rect(l: &Light, ray: &Ray, t_max: f32) -> Option<(f32, f32)> {
    let (ex, ey) = (Vec3::from(l.direction), Vec3::from(l.edge));
    let n = ex.cross(ey).normalize();
    let cos_l = -ray.dir.dot(n);
    if cos_l.is_nan() || cos_l <= 0.0 {
        return None;
    }
    let to = Vec3::from(l.position) - ray.origin;
    let t = -to.dot(n) / cos_l;
    if !(t > 0.0 && t < t_max) {
        return None;
    }
    let q = ray.origin + t * ray.dir - Vec3::from(l.position);
    let (a, b) = (
        q.dot(ex) / ex.length_squared(),
        q.dot(ey) / ey.length_squared(),
    );
    ((0.0..=1.0).contains(&a) && (0.0..=1.0).contains(&b)).then_some((t, cos_l))
}

/// The angle between unit vectors `a` and `b`, accurate near 0 and π (where acos of their
/// dot product is not). As atan2 rather than pbrt's asin form: Mesa's asin is good to only
/// about 10⁻⁴, which put lavapipe's solid angles 1% from the CPU's.
/// mirror: shaders/lights.wgsl `angle_between`
pub fn angle_between(a: Vec3, b: Vec3) -> f32 {
    a.cross(b).length().atan2(a.dot(b))
}

/// A spot light's intensity scale in unit direction `d` from it: 1 within the beam width
/// of its axis, 0 beyond the cutoff, linear in the angle between (Mitsuba's `spot`).
/// mirror: shaders/lights.wgsl `spot_falloff`
pub fn spot_falloff(l: &Light, d: Vec3) -> f32 {
    let c = d.dot(Vec3::from(l.direction));
    if c <= l.cos_cutoff {
        0.0
    } else if c >= l.cos_beam {
        1.0
    } else {
        (l.cutoff - c.acos()) * l.inv_transition
    }
}
