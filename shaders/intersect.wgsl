// Ray–triangle and ray–box tests. mirror: src/geometry.rs

struct TriHit {
    t: f32,
    u: f32,
    v: f32,
    hit: bool,
}

// Möller–Trumbore, hits with 0 < t < t_max. mirror: src/geometry.rs `intersect_triangle`
fn intersect_triangle(ray: Ray, tri: TriVerts, t_max: f32) -> TriHit {
    var miss = TriHit(0.0, 0.0, 0.0, false);
    let v0 = tri.v0.xyz;
    let e1 = tri.v1.xyz - v0;
    let e2 = tri.v2.xyz - v0;
    let p = cross(ray.dir, e2);
    let det = dot(e1, p);
    if det == 0.0 {
        return miss;
    }
    let inv_det = 1.0 / det;
    let s = ray.origin - v0;
    let u = dot(s, p) * inv_det;
    if !(u >= 0.0 && u <= 1.0) {
        return miss;
    }
    let q = cross(s, e1);
    let v = dot(ray.dir, q) * inv_det;
    if v < 0.0 || u + v > 1.0 {
        return miss;
    }
    let t = dot(e2, q) * inv_det;
    if t > 0.0 && t < t_max {
        return TriHit(t, u, v, true);
    }
    return miss;
}

// Entry distance into the box, or T_INF. mirror: src/geometry.rs `intersect_aabb`
fn intersect_aabb(origin: vec3<f32>, inv_dir: vec3<f32>, bmin: vec3<f32>, bmax: vec3<f32>, t_max: f32) -> f32 {
    let t0 = (bmin - origin) * inv_dir;
    let t1 = (bmax - origin) * inv_dir;
    let lo = min(t0, t1);
    let hi = max(t0, t1);
    let t_near = max(max(max(lo.x, lo.y), lo.z), 0.0);
    let t_far = min(min(min(hi.x, hi.y), hi.z), t_max);
    return select(T_INF, t_near, t_near <= t_far);
}

// 1 / d per component, with zeros replaced by a tiny value of the same sign so that the
// slab test never meets 0 * inf. mirror: src/geometry.rs `safe_inverse`
fn safe_inverse(d: vec3<f32>) -> vec3<f32> {
    let tiny = vec3<f32>(1e-30);
    let sgn = select(vec3<f32>(-1.0), vec3<f32>(1.0), d >= vec3<f32>(0.0));
    return 1.0 / select(d, sgn * tiny, abs(d) < tiny);
}
