//! The surface a ray finds: where it hit, with the normals, material and texture
//! coordinates that shading reads ([`surface_at`]); the origin of a ray leaving it
//! ([`offset_ray_origin`]); and the frame its BSDF is evaluated in ([`shading_frame`],
//! [`geometry_agrees`]). The integrator, the lights and the caustics all shade surfaces
//! through these. Every function has a WGSL twin of the same name in
//! `shaders/surface.wgsl`.

use super::bsdf::bsdf_is_two_sided;
use super::tables::{RenderScene, TRI_SMOOTH, TRI_TANGENT};
use super::texture::{normal_mapped, triangle_color, triangle_uv};
use crate::bvh::Hit;
use crate::math::{Ray, onb_from_normal};
use crate::scene::{Material, NO_TEXTURE};
use glam::{Vec3, Vec4};

/// A ray's hit point with the frames its shading needs.
/// mirror: shaders/surface.wgsl `SurfaceHit`
#[derive(Clone, Copy, Debug)]
pub struct SurfaceHit {
    pub p: Vec3,
    /// Geometric normal of the front face ((v1 − v0) × (v2 − v0)).
    pub ng: Vec3,
    /// Interpolated shading normal (normal-mapped where the material has a map), on the
    /// same side as `ng`.
    pub ns: Vec3,
    /// The clear coat's normal: interpolated, and mapped by the coat's own normal map
    /// where the material has one (the base's map does not reach the coat).
    pub nc: Vec3,
    pub material: u32,
    pub front_face: bool,
    pub tri: u32,
    /// Texture coordinates at the hit: xy the first set, zw the second (zero for a set
    /// the triangle lacks).
    pub uv: Vec4,
    /// The vertex colour at the hit (linear RGBA; white on a triangle without colours).
    pub color: Vec4,
}

/// mirror: shaders/surface.wgsl `surface_at`
pub fn surface_at(scene: &RenderScene, ray: &Ray, hit: &Hit) -> SurfaceHit {
    let sh = &scene.shading[hit.tri as usize];
    let ng = scene.tri_normals[hit.tri as usize];
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
    let uv = triangle_uv(scene, hit.tri, hit.u, hit.v);
    let mut nc = ns;
    if sh.flags & TRI_TANGENT != 0 {
        let m = &scene.materials[sh.material as usize];
        let interpolated = ns;
        if m.normal_texture != NO_TEXTURE {
            ns = normal_mapped(
                scene,
                hit,
                uv,
                interpolated,
                ng,
                m.normal_texture,
                m.normal_scale,
            );
        }
        if m.clearcoat_normal_texture != NO_TEXTURE {
            nc = normal_mapped(
                scene,
                hit,
                uv,
                interpolated,
                ng,
                m.clearcoat_normal_texture,
                m.clearcoat_normal_scale,
            );
        }
    }
    SurfaceHit {
        p: ray.at(hit.t),
        ng,
        ns,
        nc,
        material: sh.material,
        front_face: ray.dir.dot(ng) < 0.0,
        tri: hit.tri,
        uv,
        color: triangle_color(scene, hit.tri, hit.u, hit.v),
    }
}

/// Moves a ray origin off the surface, to the side of `ng` that `w` points to, by a margin
/// that grows with the coordinates' magnitude (float error grows with it).
/// mirror: shaders/surface.wgsl `offset_ray_origin`
pub fn offset_ray_origin(p: Vec3, ng: Vec3, w: Vec3) -> Vec3 {
    let eps = 1e-5 * (1.0 + p.abs().max_element());
    if w.dot(ng) >= 0.0 {
        p + eps * ng
    } else {
        p - eps * ng
    }
}

/// The frame a BSDF is evaluated in at a hit, for light leaving along `wo_world`: a
/// two-sided BSDF's is turned towards `wo_world` (the shading normal falling back to the
/// geometric one where it faces away); a dielectric's keeps the front face's, so that it
/// knows whether it is entered or left.
/// mirror: shaders/surface.wgsl `ShadingFrame` (a mat3x3 and the normal)
#[derive(Clone, Copy, Debug)]
pub struct ShadingFrame {
    /// The geometric normal, turned as the frame is.
    pub ng: Vec3,
    pub t: Vec3,
    pub b: Vec3,
    pub ns: Vec3,
}

impl ShadingFrame {
    #[inline(always)]
    pub fn to_local(&self, w: Vec3) -> Vec3 {
        Vec3::new(w.dot(self.t), w.dot(self.b), w.dot(self.ns))
    }

    #[inline(always)]
    pub fn to_world(&self, w: Vec3) -> Vec3 {
        w.x * self.t + w.y * self.b + w.z * self.ns
    }
}

/// mirror: shaders/surface.wgsl `shading_frame`
#[inline(always)]
pub fn shading_frame(mat: &Material, si: &SurfaceHit, wo_world: Vec3) -> ShadingFrame {
    let two_sided = bsdf_is_two_sided(mat);
    let flip = two_sided && wo_world.dot(si.ng) < 0.0;
    let (ng, mut ns) = if flip {
        (-si.ng, -si.ns)
    } else {
        (si.ng, si.ns)
    };
    if two_sided && ns.dot(wo_world) <= 0.0 {
        ns = ng;
    }
    let (t, b) = onb_from_normal(ns);
    ShadingFrame { ng, t, b, ns }
}

/// `mat` with its clear coat's normal in `frame` ([`Material::coat_normal`]): the hit's
/// coat normal turned to `frame`'s side, or +Z where it lies in or behind the frame's
/// plane. Only a coat whose normal can differ from the frame's (some normal map) needs it.
/// mirror: shaders/surface.wgsl `with_coat_normal`
#[inline(always)]
pub fn with_coat_normal(mat: &Material, si: &SurfaceHit, frame: &ShadingFrame) -> Material {
    let mut out = *mat;
    let c = frame.to_local(si.nc);
    let c = if c.z < 0.0 { -c } else { c };
    out.coat_normal = if c.z > 1e-4 { c.normalize() } else { Vec3::Z };
    out
}

/// `mat` as the BSDF in `frame` reads it: with its clear coat's normal where
/// [`needs_coat_normal`], else as it is.
/// mirror: shaders/surface.wgsl `coated`
#[inline(always)]
pub fn coated(mat: &Material, si: &SurfaceHit, frame: &ShadingFrame) -> Material {
    if needs_coat_normal(mat) {
        with_coat_normal(mat, si, frame)
    } else {
        *mat
    }
}

/// Whether the material's clear coat needs its normal set per hit by [`with_coat_normal`]:
/// a coat on a material with a normal map of either layer.
/// mirror: shaders/surface.wgsl `needs_coat_normal`
#[inline(always)]
pub fn needs_coat_normal(mat: &Material) -> bool {
    mat.clearcoat > 0.0
        && (mat.normal_texture != NO_TEXTURE || mat.clearcoat_normal_texture != NO_TEXTURE)
}

/// Whether the geometry agrees with the shading frame about a pair of directions: a
/// reflection in the frame (`wi.z wo.z > 0`) must stay on `wo`'s side of the triangle, a
/// transmission must cross it. Paths where they disagree carry no light.
/// mirror: shaders/surface.wgsl `geometry_agrees`
#[inline(always)]
pub fn geometry_agrees(ng: Vec3, wo_world: Vec3, wi_world: Vec3, wo: Vec3, wi: Vec3) -> bool {
    (wi_world.dot(ng) * wo_world.dot(ng) > 0.0) == (wi.z * wo.z > 0.0)
}
