//! Triangles as the traversal kernels read them, and the ray–triangle and ray–box tests.
//! Both tests have WGSL twins of the same name in `shaders/intersect.wgsl`.

use crate::math::Ray;
use bytemuck::{Pod, Zeroable};
use glam::Vec3;

/// "No hit" and "unbounded ray": the largest finite float, as WGSL has no infinity literal.
pub const T_INF: f32 = f32::MAX;

/// A triangle's three corners in BVH leaf order, padded to 16-byte rows as WGSL lays out
/// `array<vec4<f32>>` (48 bytes). mirror: shaders/types.wgsl `TriVerts`
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TriVerts {
    pub v0: [f32; 4],
    pub v1: [f32; 4],
    pub v2: [f32; 4],
}

impl TriVerts {
    pub fn new([a, b, c]: [Vec3; 3]) -> Self {
        Self {
            v0: a.extend(0.0).into(),
            v1: b.extend(0.0).into(),
            v2: c.extend(0.0).into(),
        }
    }

    pub fn corners(&self) -> [Vec3; 3] {
        [self.v0, self.v1, self.v2].map(|v| Vec3::new(v[0], v[1], v[2]))
    }
}

/// Where a ray meets a triangle: distance and barycentrics of v1 and v2.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriHit {
    pub t: f32,
    pub u: f32,
    pub v: f32,
}

/// Möller–Trumbore ray–triangle intersection for hits with `0 < t < t_max`.
/// mirror: shaders/intersect.wgsl `intersect_triangle`
#[inline]
pub fn intersect_triangle(ray: &Ray, tri: &TriVerts, t_max: f32) -> Option<TriHit> {
    let [v0, v1, v2] = tri.corners();
    let e1 = v1 - v0;
    let e2 = v2 - v0;
    let p = ray.dir.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 {
        return None;
    }
    let inv_det = 1.0 / det;
    let s = ray.origin - v0;
    let u = s.dot(p) * inv_det;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = ray.dir.dot(q) * inv_det;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = e2.dot(q) * inv_det;
    (t > 0.0 && t < t_max).then_some(TriHit { t, u, v })
}

/// Slab test: the distance at which the ray enters the box, or [`T_INF`] if it misses it
/// before `t_max`. `inv_dir` is [`safe_inverse`] of the ray direction.
/// mirror: shaders/intersect.wgsl `intersect_aabb`
#[inline]
pub fn intersect_aabb(origin: Vec3, inv_dir: Vec3, min: Vec3, max: Vec3, t_max: f32) -> f32 {
    let t0 = (min - origin) * inv_dir;
    let t1 = (max - origin) * inv_dir;
    let t_near = t0.min(t1).max_element().max(0.0);
    let t_far = t0.max(t1).min_element().min(t_max);
    if t_near <= t_far { t_near } else { T_INF }
}

/// `1 / d` per component, with zeros replaced by a tiny value of the same sign so that the
/// slab test never meets `0 * inf`. mirror: shaders/intersect.wgsl `safe_inverse`
#[inline]
pub fn safe_inverse(d: Vec3) -> Vec3 {
    const TINY: f32 = 1e-30;
    let fix = |x: f32| {
        if x.abs() < TINY {
            if x >= 0.0 { TINY } else { -TINY }
        } else {
            x
        }
    };
    Vec3::new(1.0 / fix(d.x), 1.0 / fix(d.y), 1.0 / fix(d.z))
}

/// The geometric normal, (v1 − v0) × (v2 − v0) normalised: it points out of the front face.
pub fn geometric_normal(tri: &TriVerts) -> Vec3 {
    let [a, b, c] = tri.corners();
    (b - a).cross(c - a).normalize()
}

pub fn area(tri: &TriVerts) -> f32 {
    let [a, b, c] = tri.corners();
    0.5 * (b - a).cross(c - a).length()
}
