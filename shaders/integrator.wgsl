// The path tracer, one bounce at a time. mirror: src/render/integrator.rs — every
// function has a Rust twin of the same name.

// mirror: src/render/integrator.rs `SurfaceHit`
struct SurfaceHit {
    p: vec3<f32>,
    ng: vec3<f32>,
    ns: vec3<f32>,
    material: u32,
    front_face: bool,
    tri: u32,
    uv: vec2<f32>,
}

// mirror: src/render/integrator.rs `surface_at`
fn surface_at(ray: Ray, hit: Hit) -> SurfaceHit {
    let tri = load_tri(hit.tri);
    let sh = load_shading(hit.tri);
    let ng = geometric_normal(tri);
    var ns = ng;
    if (sh.flags & TRI_SMOOTH) != 0u {
        let w = 1.0 - hit.u - hit.v;
        let n = w * sh.n0 + hit.u * sh.n1 + hit.v * sh.n2;
        let len2 = dot(n, n);
        ns = select(vec3<f32>(0.0), n * inverseSqrt(len2), len2 > 0.0);
        if dot(ns, ng) < 0.0 {
            ns = -ns;
        }
        if all(ns == vec3<f32>(0.0)) {
            ns = ng;
        }
    }
    let uv = triangle_uv(hit.tri, hit.u, hit.v);
    if (sh.flags & TRI_TANGENT) != 0u {
        ns = normal_mapped(hit.tri, hit.u, hit.v, uv, ns, ng);
    }
    return SurfaceHit(ray.origin + hit.t * ray.dir, ng, ns, sh.material, dot(ray.dir, ng) < 0.0, hit.tri, uv);
}

// mirror: src/render/integrator.rs `offset_ray_origin`
fn offset_ray_origin(p: vec3<f32>, ng: vec3<f32>, w: vec3<f32>) -> vec3<f32> {
    let ap = abs(p);
    let eps = 1e-5 * (1.0 + max(max(ap.x, ap.y), ap.z));
    return select(p - eps * ng, p + eps * ng, dot(w, ng) >= 0.0);
}

fn max3(v: vec3<f32>) -> f32 {
    return max(max(v.x, v.y), v.z);
}

// One path between bounces. mirror: src/render/integrator.rs `PathState`
struct PathState {
    ray: Ray,
    radiance: vec3<f32>,
    beta: vec3<f32>,
    rays: u32,
    prev_pdf: f32,
    prev_delta: bool,
    eta_scale: f32,
    depth: u32,
}

// A path about to trace its camera ray. mirror: src/render/integrator.rs `path_start`
fn path_start(ray: Ray) -> PathState {
    return PathState(ray, vec3<f32>(0.0), vec3<f32>(1.0), 0u, 0.0, true, 1.0, 0u);
}

// One bounce; true when the path has ended. mirror: src/render/integrator.rs `path_step`
fn path_step(st: ptr<function, PathState>, rng: Rng) -> bool {
    // The light pair, drawn before the traversal (as on the CPU, where that hides its
    // latency; on a miss, a delta material or the last segment it goes unused).
    var u_light = vec2<f32>(0.0);
    if params.num_emitters > 0u && (*st).depth + 1u < params.max_depth {
        u_light = rng_2d(rng, (*st).depth, DIM_LIGHT_U);
    }
    (*st).rays += 1u;
    let hit = traverse_closest((*st).ray, T_INF);
    if hit.tri == NO_HIT {
        var w = 1.0;
        if !(*st).prev_delta && params.sky_pmf != 0.0 {
            w = power_heuristic((*st).prev_pdf, sky_pdf((*st).ray.dir));
        }
        (*st).radiance += (*st).beta * w * sky_radiance((*st).ray.dir);
        return true;
    }
    let si = surface_at((*st).ray, hit);
    let mat = material_at(load_material(si.material), si.uv);
    if si.front_face && is_emissive(mat) {
        var w = 1.0;
        if !(*st).prev_delta {
            let cos_l = -dot((*st).ray.dir, si.ng);
            w = power_heuristic((*st).prev_pdf, light_pdf(si.tri, hit.t, cos_l));
        }
        (*st).radiance += (*st).beta * w * mat.emission;
    }
    if (*st).depth + 1u >= params.max_depth {
        return true;
    }
    let wo_world = -(*st).ray.dir;
    let two_sided = bsdf_is_two_sided(mat);
    let flip = two_sided && dot(wo_world, si.ng) < 0.0;
    let ng = select(si.ng, -si.ng, flip);
    var ns = select(si.ns, -si.ns, flip);
    if two_sided && dot(ns, wo_world) <= 0.0 {
        ns = ng;
    }
    let frame = onb_from_normal(ns);
    let wo = wo_world * frame;

    // The numbers BSDF sampling reads, drawn only where the material reads them (before
    // next event estimation, as on the CPU, where that hides their latency).
    var u_lobe = 0.0;
    if bsdf_draws_lobe(mat) {
        u_lobe = rng_1d(rng, (*st).depth, DIM_BSDF_LOBE);
    }
    var u = vec2<f32>(0.0);
    if bsdf_draws_direction(mat) {
        u = rng_2d(rng, (*st).depth, DIM_BSDF_U);
    }

    // Next event estimation.
    if !bsdf_is_delta(mat) && params.num_emitters > 0u {
        let ls = sample_light(si.p, ng, u_light);
        let cos_i = dot(ls.wi, ng);
        let usable = select(cos_i > 0.0, cos_i != 0.0, bsdf_transmits(mat));
        if ls.valid && usable {
            let wi = ls.wi * frame;
            let f = bsdf_eval(mat, wo, wi);
            if any(f != vec3<f32>(0.0)) {
                (*st).rays += 1u;
                if !traverse_any(Ray(ls.origin, ls.wi), ls.t_max) {
                    var w = 1.0;
                    if !ls.delta {
                        w = power_heuristic(ls.pdf, bsdf_pdf(mat, wo, wi));
                    }
                    (*st).radiance += (*st).beta * f * ls.le * (w / ls.pdf);
                }
            }
        }
    }

    // BSDF sampling.
    let bs = bsdf_sample(mat, wo, u_lobe, u);
    if !bs.valid {
        return true;
    }
    let wi_world = frame * bs.wi;
    let reflect = bs.wi.z * wo.z > 0.0;
    if (dot(wi_world, si.ng) * dot(wo_world, si.ng) > 0.0) != reflect {
        return true;
    }
    (*st).beta *= bs.weight;
    (*st).prev_pdf = bs.pdf;
    (*st).prev_delta = bs.delta;
    (*st).eta_scale *= bs.eta;
    (*st).depth += 1u;
    if (*st).depth >= RR_DEPTH {
        let q = min(max3((*st).beta) * (*st).eta_scale * (*st).eta_scale, 0.95);
        if rng_1d(rng, (*st).depth, DIM_ROULETTE) >= q {
            return true;
        }
        (*st).beta /= q;
    }
    if all((*st).beta == vec3<f32>(0.0)) {
        return true;
    }
    (*st).ray = Ray(offset_ray_origin(si.p, si.ng, wi_world), wi_world);
    return false;
}

// One path's radiance (xyz) and the number of rays it traced (w).
// mirror: src/render/integrator.rs `trace_path`
fn trace_path(ray: Ray, rng: Rng) -> vec4<f32> {
    var st = path_start(ray);
    loop {
        if path_step(&st, rng) {
            break;
        }
    }
    return vec4<f32>(st.radiance, f32(st.rays));
}

// What the AOVs read of a camera ray's first hit. mirror: src/render/integrator.rs `FirstHit`
struct FirstHit {
    hit: bool,
    p: vec3<f32>,
    normal: vec3<f32>,
    albedo: vec3<f32>,
    material: u32,
    object: u32,
    cost: u32,
}

// The first hit of a camera ray, for the AOVs. mirror: src/render/integrator.rs `first_hit`
fn first_hit(ray: Ray) -> FirstHit {
    let counted = traverse_closest_counted(ray, T_INF);
    let hit = counted.hit;
    if hit.tri == NO_HIT {
        return FirstHit(false, vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), NO_ID, NO_ID, counted.cost);
    }
    let si = surface_at(ray, hit);
    let mat = material_at(load_material(si.material), si.uv);
    let normal = select(si.ns, -si.ns, dot(si.ns, ray.dir) > 0.0);
    let albedo = select(mat.albedo, vec3<f32>(1.0), mat.kind == MAT_DIELECTRIC);
    // TriVerts.v1.w holds the bits of the triangle's object index.
    let object = bitcast<u32>(load_tri(hit.tri).v1.w);
    return FirstHit(true, si.p, normal, albedo, si.material, object, counted.cost);
}
