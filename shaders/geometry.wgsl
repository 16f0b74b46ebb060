// Triangles, and the ray–triangle and ray–box tests. mirror: src/geometry.rs

// mirror: src/geometry.rs `TriVerts` (48 bytes). v0.w: 1 on a masked triangle; v1.w: the
// bits of its object index.
struct TriVerts {
    v0: vec4<f32>,
    v1: vec4<f32>,
    v2: vec4<f32>,
}

struct TriHit {
    t: f32,
    u: f32,
    v: f32,
    hit: bool,
}

// A ray prepared for the watertight triangle test: the world axis that becomes z, and the
// shear that maps the direction onto +z. mirror: src/geometry.rs `ShearedRay`
struct ShearedRay {
    origin: vec3<f32>,
    kz: u32,
    shear: vec3<f32>,
}

// mirror: src/geometry.rs `ShearedRay::new`
fn sheared_ray(ray: Ray) -> ShearedRay {
    let dir = safe_direction(ray.dir);
    let a = abs(dir);
    var kz = 2u;
    if a.x > a.y {
        if a.x > a.z {
            kz = 0u;
        }
    } else if a.y > a.z {
        kz = 1u;
    }
    let d = permute(dir, kz);
    return ShearedRay(ray.origin, kz, vec3<f32>(-d.x / d.z, -d.y / d.z, 1.0 / d.z));
}

// The axes turned cyclically so that axis kz comes last. mirror: src/geometry.rs `permute`
fn permute(v: vec3<f32>, kz: u32) -> vec3<f32> {
    return select(select(v, v.zxy, kz == 1u), v.yzx, kz == 0u);
}

fn to_ray_frame(ray: ShearedRay, v: vec3<f32>) -> vec3<f32> {
    let p = permute(v - ray.origin, ray.kz);
    return vec3<f32>(p.x + ray.shear.x * p.z, p.y + ray.shear.y * p.z, p.z);
}

// The rounding bound of the sum of the edge functions. mirror: src/geometry.rs `edge_rounding`
fn edge_rounding(ray: ShearedRay, tri: TriVerts, p0: vec3<f32>, p1: vec3<f32>, p2: vec3<f32>) -> f32 {
    let d0 = corner_rounding(ray, tri.v0.xyz);
    let d1 = corner_rounding(ray, tri.v1.xyz);
    let d2 = corner_rounding(ray, tri.v2.xyz);
    return edge_product_rounding(abs(p1), abs(p2), d1, d2)
        + edge_product_rounding(abs(p2), abs(p0), d2, d0)
        + edge_product_rounding(abs(p0), abs(p1), d0, d1);
}

fn corner_rounding(ray: ShearedRay, v: vec3<f32>) -> vec2<f32> {
    let a = abs(permute(v - ray.origin, ray.kz));
    return GAMMA_3 * vec2<f32>(a.x + abs(ray.shear.x) * a.z, a.y + abs(ray.shear.y) * a.z);
}

fn edge_product_rounding(a: vec3<f32>, b: vec3<f32>, da: vec2<f32>, db: vec2<f32>) -> f32 {
    return b.y * da.x + a.x * db.y + b.x * da.y + a.y * db.x + GAMMA_2 * (a.x * b.y + a.y * b.x);
}

// Watertight (Woop, Benthin and Wald 2013), hits with 0 < t < t_max.
// mirror: src/geometry.rs `intersect_triangle`
fn intersect_triangle(ray: ShearedRay, tri: TriVerts, t_max: f32) -> TriHit {
    var miss = TriHit(0.0, 0.0, 0.0, false);
    let p0 = to_ray_frame(ray, tri.v0.xyz);
    let p1 = to_ray_frame(ray, tri.v1.xyz);
    let p2 = to_ray_frame(ray, tri.v2.xyz);
    // A hit needs the three edge functions free of opposite signs (zero is either).
    let e0 = p1.x * p2.y - p1.y * p2.x;
    let e1 = p2.x * p0.y - p2.y * p0.x;
    if (e0 < 0.0 && e1 > 0.0) || (e0 > 0.0 && e1 < 0.0) {
        return miss;
    }
    let e2 = p0.x * p1.y - p0.y * p1.x;
    if (e2 < 0.0 && (e0 > 0.0 || e1 > 0.0)) || (e2 > 0.0 && (e0 < 0.0 || e1 < 0.0)) {
        return miss;
    }
    let det = e0 + e1 + e2;
    let sz = ray.shear.z;
    let t_scaled = e0 * (sz * p0.z) + e1 * (sz * p1.z) + e2 * (sz * p2.z);
    let inv_det = 1.0 / det;
    let t = t_scaled * inv_det;
    // Out of range first (most candidates lie behind the ray or beyond the nearest hit):
    // the rounding bound below is dearer, and either test alone rejects.
    if !(t > 0.0 && t < t_max) {
        return miss;
    }
    // Below the rounding bound the signs are noise: the ray runs in the plane of a
    // (nearly) degenerate triangle. (A zero `det` always ends here.)
    if abs(det) <= edge_rounding(ray, tri, p0, p1, p2) {
        return miss;
    }
    return TriHit(t, e1 * inv_det, e2 * inv_det, true);
}

// Conservative entry distance into the box, or T_INF. mirror: src/geometry.rs `intersect_aabb`
fn intersect_aabb(origin: vec3<f32>, inv_dir: vec3<f32>, bmin: vec3<f32>, bmax: vec3<f32>, t_max: f32) -> f32 {
    let t0 = (bmin - origin) * inv_dir;
    let t1 = (bmax - origin) * inv_dir;
    let lo = min(t0, t1);
    let hi = max(t0, t1);
    let t_near = max(max(max(lo.x, lo.y), lo.z), 0.0);
    let t_far = min(min(min(min(hi.x, hi.y), hi.z), t_max) * SLAB_SLACK, T_INF);
    return select(T_INF, t_near, t_near <= t_far);
}

// d with each zero component replaced by a tiny value of the same sign (+ for -0.0), so
// that the slab test never meets 0 * inf; the triangle test shears by the same direction.
// mirror: src/geometry.rs `safe_direction`
fn safe_direction(d: vec3<f32>) -> vec3<f32> {
    let tiny = vec3<f32>(1e-30);
    let sgn = select(vec3<f32>(-1.0), vec3<f32>(1.0), d >= vec3<f32>(0.0));
    return select(d, sgn * tiny, abs(d) < tiny);
}

// mirror: src/geometry.rs `safe_inverse`
fn safe_inverse(d: vec3<f32>) -> vec3<f32> {
    return 1.0 / safe_direction(d);
}

// mirror: src/geometry.rs `geometric_normal`
fn geometric_normal(tri: TriVerts) -> vec3<f32> {
    return normalize(cross(tri.v1.xyz - tri.v0.xyz, tri.v2.xyz - tri.v0.xyz));
}

// mirror: src/geometry.rs `triangle_area`
fn triangle_area(tri: TriVerts) -> f32 {
    return 0.5 * length(cross(tri.v1.xyz - tri.v0.xyz, tri.v2.xyz - tri.v0.xyz));
}
