// BVH traversal with a fixed stack, nearer child first. mirror: src/bvh/traverse.rs

// One stack for both traversals (they never nest). At module scope it is zero-initialised
// once per invocation; WGSL zeroes a function-local array on every call, which costs
// lavapipe more than the traversal of a small scene.
var<private> stack: array<u32, STACK_SIZE>;

// What a counting walk has done: BVH nodes visited plus triangles tested.
var<private> walk_cost: u32;

struct Hit {
    t: f32,
    u: f32,
    v: f32,
    // Leaf-order triangle index, or NO_HIT.
    tri: u32,
}

// With `camera`, the ray is the camera's, which sees unlit surfaces (the CPU's `accept`
// says so). mirror: src/bvh/traverse.rs `traverse_closest`
fn traverse_closest(ray: Ray, t_max: f32, camera: bool) -> Hit {
    return walk(ray, t_max, false, false, camera);
}

// The closest hit and the traversal's cost (the CPU's tuple).
struct CountedHit {
    hit: Hit,
    cost: u32,
}

// mirror: src/bvh/traverse.rs `traverse_closest_counted`
fn traverse_closest_counted(ray: Ray, t_max: f32, camera: bool) -> CountedHit {
    walk_cost = 0u;
    let hit = walk(ray, t_max, false, true, camera);
    return CountedHit(hit, walk_cost);
}

// mirror: src/bvh/traverse.rs `traverse_any`
fn traverse_any(ray: Ray, t_max: f32) -> bool {
    return walk(ray, t_max, true, false, false).tri != NO_HIT;
}

// The leaves the ray may reach, nearer child first: the closest hit, or with `any_hit`
// the first found. Hits on masked triangles (TriVerts.v0.w != 0) count where
// `alpha_test` passes, as the CPU's `accept`. The same visits as the CPU's single loop, arranged "while-while"
// (Aila and Laine 2009): interior nodes in an inner loop, then the leaf, so that the lanes
// of a SIMD group intersect their leaves together rather than one branch at a time (15-20%
// less time on lavapipe, BENCHMARKS.md). With `counted`, adds the nodes visited and the
// triangles tested to `walk_cost`; every call passes constants, so the compiler drops the
// counting from the others. mirror: src/bvh/traverse.rs `walk`
fn walk(ray: Ray, t_max: f32, any_hit: bool, counted: bool, camera: bool) -> Hit {
    var best = Hit(t_max, 0.0, 0.0, NO_HIT);
    let sheared = sheared_ray(ray);
    let root = load_node(0);
    if root.count == 0u && root.left_or_first == 0u {
        return best;
    }
    let inv_dir = safe_inverse(ray.dir);
    if intersect_aabb(ray.origin, inv_dir, root.min, root.max, best.t) == T_INF {
        return best;
    }
    var sp = 0u;
    var node = 0u;
    var n = root;
    loop {
        // Down the interior nodes until a leaf (the lanes of a SIMD group then intersect
        // their leaves together).
        var done = false;
        while n.count == 0u {
            if counted {
                walk_cost += 1u;
            }
            var a = node + 1u;
            var b = n.left_or_first;
            let ca = load_node(a);
            let cb = load_node(b);
            var ta = intersect_aabb(ray.origin, inv_dir, ca.min, ca.max, best.t);
            var tb = intersect_aabb(ray.origin, inv_dir, cb.min, cb.max, best.t);
            let swapped = tb < ta;
            if swapped {
                let t = ta;
                ta = tb;
                tb = t;
                let k = a;
                a = b;
                b = k;
            }
            if ta == T_INF {
                if sp == 0u {
                    done = true;
                    break;
                }
                sp -= 1u;
                node = stack[sp];
                n = load_node(node);
            } else {
                // The nearer child is already loaded: no second read of it.
                node = a;
                if swapped {
                    n = cb;
                } else {
                    n = ca;
                }
                if tb != T_INF {
                    check(sp < STACK_SIZE);
                    stack[sp] = b;
                    sp += 1u;
                }
            }
        }
        if done {
            break;
        }
        if counted {
            walk_cost += 1u + n.count;
        }
        for (var i = n.left_or_first; i < n.left_or_first + n.count; i++) {
            let tri = load_tri(i);
            let h = intersect_triangle(sheared, tri, best.t);
            // A masked triangle's hit counts only where its alpha test passes.
            if h.hit && (tri.v0.w == 0.0 || alpha_test(i, h.u, h.v, camera)) {
                best = Hit(h.t, h.u, h.v, i);
                if any_hit {
                    return best;
                }
            }
        }
        if sp == 0u {
            break;
        }
        sp -= 1u;
        node = stack[sp];
        n = load_node(node);
    }
    return best;
}
