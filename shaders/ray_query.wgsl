// Traversal by hardware ray queries: the same functions as traverse.wgsl, which
// src/render/gpu/shader.rs puts in its place on a device that traces with them
// (`--accel`). GPU-only: the CPU's twin is the software walk, src/bvh/traverse.rs, and
// tests/ray_query.rs holds the two to the same hits. The scene is one BLAS of the triangles
// in leaf order (src/render/gpu/accel.rs `SceneAccel`), so a hit's primitive index is its
// `tri`, and its barycentrics weight v1 and v2 as the software test's u and v do.

struct Hit {
    t: f32,
    u: f32,
    v: f32,
    // Leaf-order triangle index, or NO_HIT.
    tri: u32,
}

// mirror: src/bvh/traverse.rs `traverse_closest`
fn traverse_closest(ray: Ray, t_max: f32, camera: bool) -> Hit {
    return query(ray, t_max, false, camera).hit;
}

// The closest hit and the query's cost: here the candidates the query stopped at, plus
// one (the driver walks its own structure, whose nodes the shader never sees).
struct CountedHit {
    hit: Hit,
    cost: u32,
}

// mirror: src/bvh/traverse.rs `traverse_closest_counted`
fn traverse_closest_counted(ray: Ray, t_max: f32, camera: bool) -> CountedHit {
    return query(ray, t_max, false, camera);
}

// mirror: src/bvh/traverse.rs `traverse_any`
fn traverse_any(ray: Ray, t_max: f32) -> bool {
    return query(ray, t_max, true, false).hit.tri != NO_HIT;
}

// The closest hit with 0 <= t <= t_max, or with `any_hit` the first found. A scene with
// masked triangles has a non-opaque BLAS: each of its hits comes here as a candidate,
// confirmed where the triangle is unmasked (TriVerts.v0.w == 0) or `alpha_test` passes, as
// the software walk's test (for the camera's ray where `camera`). Opaque hits are committed by the driver.
fn query(ray: Ray, t_max: f32, any_hit: bool, camera: bool) -> CountedHit {
    var rq: ray_query;
    let flags = select(RAY_FLAG_NONE, RAY_FLAG_TERMINATE_ON_FIRST_HIT, any_hit);
    rayQueryInitialize(&rq, scene_tlas, RayDesc(flags, 0xffu, 0.0, t_max, ray.origin, ray.dir));
    var cost = 1u;
    while rayQueryProceed(&rq) {
        cost += 1u;
        let c = rayQueryGetCandidateIntersection(&rq);
        let tri = c.primitive_index;
        if load_tri(tri).v0.w == 0.0 || alpha_test(tri, c.barycentrics.x, c.barycentrics.y, camera) {
            rayQueryConfirmIntersection(&rq);
        }
    }
    let h = rayQueryGetCommittedIntersection(&rq);
    if h.kind == RAY_QUERY_INTERSECTION_NONE {
        return CountedHit(Hit(t_max, 0.0, 0.0, NO_HIT), cost);
    }
    return CountedHit(Hit(h.t, h.barycentrics.x, h.barycentrics.y, h.primitive_index), cost);
}
