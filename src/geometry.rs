//! Triangles as the traversal kernels read them, and the ray–triangle and ray–box tests.
//! Both tests have WGSL twins of the same name in `shaders/geometry.wgsl`.

use crate::math::Ray;
use bytemuck::{Pod, Zeroable};
use glam::{Vec3, Vec3Swizzles};

/// "No hit" and "unbounded ray": the largest finite float, as WGSL has no infinity literal.
pub const T_INF: f32 = f32::MAX;

/// A triangle's three corners in BVH leaf order, padded to 16-byte rows as WGSL lays out
/// `array<vec4<f32>>` (48 bytes). The first padding word marks a triangle whose material
/// cuts out parts of it (1; else 0): traversals ask before counting a hit on it. The
/// second holds the bits of the index of the object the triangle belongs to (read only by
/// the `object_id` AOV).
/// mirror: shaders/geometry.wgsl `TriVerts`
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

    /// Whether hits on this triangle pass an alpha test before they count.
    #[inline(always)]
    pub fn is_masked(&self) -> bool {
        self.v0[3] != 0.0
    }

    /// Marks the triangle as [`is_masked`](Self::is_masked).
    pub fn set_masked(&mut self) {
        self.v0[3] = 1.0;
    }

    /// The index of the object the triangle belongs to.
    pub fn object(&self) -> u32 {
        self.v1[3].to_bits()
    }

    /// Sets [`object`](Self::object).
    pub fn set_object(&mut self, object: u32) {
        self.v1[3] = f32::from_bits(object);
    }

    /// The three corners. (Always inlined: on the hot paths the compiler otherwise may
    /// call `array::map` out of line, a few percent of a render.)
    #[inline(always)]
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

/// A ray prepared for the watertight triangle test (Woop, Benthin and Wald 2013,
/// "Watertight Ray/Triangle Intersection"): the axes turned so that the direction's
/// largest component is z, and the shear that maps the direction onto +z. Made once per
/// ray and used for every triangle it meets. mirror: shaders/geometry.wgsl `ShearedRay`
#[derive(Clone, Copy, Debug)]
pub struct ShearedRay {
    pub origin: Vec3,
    /// The world axis that becomes z (x and y follow it cyclically).
    pub kz: u32,
    /// (Sx, Sy, Sz): a translated, permuted point becomes (x + Sx z, y + Sy z, Sz z).
    pub shear: Vec3,
}

impl ShearedRay {
    /// mirror: shaders/geometry.wgsl `sheared_ray`
    pub fn new(ray: &Ray) -> Self {
        let dir = safe_direction(ray.dir);
        let a = dir.abs();
        let kz = if a.x > a.y {
            if a.x > a.z { 0 } else { 2 }
        } else if a.y > a.z {
            1
        } else {
            2
        };
        let d = permute(dir, kz);
        Self {
            origin: ray.origin,
            kz,
            shear: Vec3::new(-d.x / d.z, -d.y / d.z, 1.0 / d.z),
        }
    }
}

/// `v` with its axes turned cyclically so that axis `kz` comes last.
/// mirror: shaders/geometry.wgsl `permute`
#[inline]
pub fn permute(v: Vec3, kz: u32) -> Vec3 {
    match kz {
        0 => v.yzx(),
        1 => v.zxy(),
        _ => v,
    }
}

/// Watertight ray–triangle intersection for hits with `0 < t < t_max`.
///
/// The corners are moved into the ray's sheared frame, where the ray is the +z axis, and
/// the hit is decided by the signs of the three 2D edge functions. A shared edge gives
/// its two triangles edge functions of exactly opposite sign, so no ray slips between
/// them, and a hit is never reported outside the triangle, however thin it is.
/// mirror: shaders/geometry.wgsl `intersect_triangle`
#[inline]
pub fn intersect_triangle(ray: &ShearedRay, tri: &TriVerts, t_max: f32) -> Option<TriHit> {
    let s = ray.shear;
    let to_frame = |p: Vec3| Vec3::new(p.x + s.x * p.z, p.y + s.y * p.z, p.z);
    let [a0, a1, a2] = tri.corners().map(|v| v - ray.origin);
    // One branch for the three corners (`permute` of each).
    let [a0, a1, a2] = match ray.kz {
        0 => [a0.yzx(), a1.yzx(), a2.yzx()],
        1 => [a0.zxy(), a1.zxy(), a2.zxy()],
        _ => [a0, a1, a2],
    };
    let (p0, p1, p2) = (to_frame(a0), to_frame(a1), to_frame(a2));
    // A hit needs the three edge functions free of opposite signs (zero is either).
    let e0 = p1.x * p2.y - p1.y * p2.x;
    let e1 = p2.x * p0.y - p2.y * p0.x;
    if (e0 < 0.0 && e1 > 0.0) || (e0 > 0.0 && e1 < 0.0) {
        return None;
    }
    let e2 = p0.x * p1.y - p0.y * p1.x;
    if (e2 < 0.0 && (e0 > 0.0 || e1 > 0.0)) || (e2 > 0.0 && (e0 < 0.0 || e1 < 0.0)) {
        return None;
    }
    let det = e0 + e1 + e2;
    let t_scaled = e0 * (s.z * p0.z) + e1 * (s.z * p1.z) + e2 * (s.z * p2.z);
    let inv_det = 1.0 / det;
    let t = t_scaled * inv_det;
    // Out of range first (most candidates lie behind the ray or beyond the nearest hit):
    // the rounding bound below is dearer, and either test alone rejects.
    if !(t > 0.0 && t < t_max) {
        return None;
    }
    if det.abs() <= edge_rounding(ray, tri, [p0, p1, p2]) {
        // The signs are rounding noise: the ray runs in the plane of a (nearly)
        // degenerate triangle, where a "hit" could lie anywhere along it. (A zero `det`
        // always ends here.)
        return None;
    }
    Some(TriHit {
        t,
        u: e1 * inv_det,
        v: e2 * inv_det,
    })
}

/// `γ(n)` of Pharr, Jakob and Humphreys, "Physically Based Rendering" 4th ed., 6.8.1:
/// the relative rounding bound of `n` successive floating-point operations.
const fn gamma(n: f32) -> f32 {
    let u = 0.5 * f32::EPSILON;
    n * u / (1.0 - n * u)
}

/// `γ(2)`; the shaders get it from `render::gpu::shader::shared_constants`.
pub const GAMMA_2: f32 = gamma(2.0);
/// `γ(3)`; the shaders get it from `render::gpu::shader::shared_constants`.
pub const GAMMA_3: f32 = gamma(3.0);

/// A bound on the rounding of the sum of [`intersect_triangle`]'s edge functions: that of
/// the sheared corners (`γ(3)` of their unsheared terms) carried through the products,
/// plus that of the products themselves. Only called for hits within the ray's extent, so
/// its cost is rarely paid.
/// mirror: shaders/geometry.wgsl `edge_rounding`
fn edge_rounding(ray: &ShearedRay, tri: &TriVerts, p: [Vec3; 3]) -> f32 {
    let s = ray.shear;
    let err = |v: [f32; 4]| {
        let a = permute(Vec3::new(v[0], v[1], v[2]) - ray.origin, ray.kz).abs();
        GAMMA_3 * Vec3::new(a.x + s.x.abs() * a.z, a.y + s.y.abs() * a.z, 0.0)
    };
    let d = [err(tri.v0), err(tri.v1), err(tri.v2)];
    let edge = |i: usize, j: usize| {
        let (a, b) = (p[i].abs(), p[j].abs());
        b.y * d[i].x
            + a.x * d[j].y
            + b.x * d[i].y
            + a.y * d[j].x
            + GAMMA_2 * (a.x * b.y + a.y * b.x)
    };
    edge(1, 2) + edge(2, 0) + edge(0, 1)
}

/// Relative slack of the slab test: `2 γ(3)` (PBR 4th ed., 6.8.2) bounds the rounding of
/// each slab distance. The shaders get it from `render::gpu::shader::shared_constants`.
pub const SLAB_SLACK: f32 = 1.0 + 2.0 * GAMMA_3;

/// Conservative slab test: the distance at which the ray enters the box, or [`T_INF`]
/// if it misses it before `t_max`. The exit distance is widened by the rounding bound,
/// so a box is never missed by a ray that hits a triangle inside it.
/// `inv_dir` is [`safe_inverse`] of the ray direction.
/// mirror: shaders/geometry.wgsl `intersect_aabb`
#[inline]
pub fn intersect_aabb(origin: Vec3, inv_dir: Vec3, min: Vec3, max: Vec3, t_max: f32) -> f32 {
    let t0 = (min - origin) * inv_dir;
    let t1 = (max - origin) * inv_dir;
    let t_near = t0.min(t1).max_element().max(0.0);
    let t_far = (t0.max(t1).min_element().min(t_max) * SLAB_SLACK).min(T_INF);
    if t_near <= t_far { t_near } else { T_INF }
}

/// `d` with each zero component replaced by a tiny value of the same sign (`+` for
/// `-0.0`), so that the slab test never meets `0 * inf`. The triangle test shears by the
/// same direction, so a ray that runs exactly along a box face is on the same side of it
/// in both tests. mirror: shaders/geometry.wgsl `safe_direction`
#[inline]
pub fn safe_direction(d: Vec3) -> Vec3 {
    const TINY: f32 = 1e-30;
    let fix = |x: f32| {
        if x.abs() < TINY {
            if x >= 0.0 { TINY } else { -TINY }
        } else {
            x
        }
    };
    Vec3::new(fix(d.x), fix(d.y), fix(d.z))
}

/// `1 / d` per component of [`safe_direction`]. mirror: shaders/geometry.wgsl `safe_inverse`
#[inline]
pub fn safe_inverse(d: Vec3) -> Vec3 {
    safe_direction(d).recip()
}

/// The geometric normal, (v1 − v0) × (v2 − v0) normalised: it points out of the front face.
/// mirror: shaders/geometry.wgsl `geometric_normal`
pub fn geometric_normal(tri: &TriVerts) -> Vec3 {
    let [a, b, c] = tri.corners();
    (b - a).cross(c - a).normalize()
}

/// The triangle's area, for the pdf of a uniform point on it.
/// mirror: shaders/geometry.wgsl `triangle_area`
pub fn triangle_area(tri: &TriVerts) -> f32 {
    let [a, b, c] = tri.corners();
    0.5 * (b - a).cross(c - a).length()
}
