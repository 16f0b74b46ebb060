// The path tracer, one bounce at a time. mirror: src/render/integrator.rs — every
// function has a Rust twin of the same name.

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
    caustic_pdf: f32,
    caustic_hops: u32,
    // The diffuse, glossy and transmission scatterings the path may still take (indexed
    // by BsdfSample::lobe).
    bounces_left: vec3<u32>,
}

// A path about to trace its camera ray, drawn with density camera_pdf, with the
// scatterings of each lobe kind its bounce limits allow.
// mirror: src/render/integrator.rs `path_start`
fn path_start(ray: Ray, camera_pdf: f32) -> PathState {
    let bounces = vec3<u32>(params.diffuse_bounces, params.glossy_bounces, params.transmission_bounces);
    return PathState(ray, vec3<f32>(0.0), vec3<f32>(1.0), 0u, camera_pdf, true, 1.0, 0u, 0.0, 0u, bounces);
}

// Whether the vertex the path has just reached is its last: it adds its emission alone.
// mirror: src/render/integrator.rs `path_ends_at_vertex`
fn path_ends_at_vertex(st: ptr<function, PathState>) -> bool {
    return (*st).depth + 1u >= params.max_depth || any((*st).bounces_left == vec3<u32>(0u));
}

// path_step's caustic connection to one light vertex.
fn connect_light_vertex(st: ptr<function, PathState>, si: SurfaceHit, mat: Material, sf: ShadingFrame, wo_world: vec3<f32>, wo: vec3<f32>, lv: LightVertex) {
    if (*st).depth + 2u + lv.segments > params.max_depth {
        return;
    }
    let link = caustic_link(si, mat, sf, wo_world, wo, lv);
    if link.valid {
        (*st).rays += 1u;
        if !traverse_any(link.ray, link.t_max) {
            (*st).radiance += (*st).beta * link.value;
        }
    }
}

// One bounce: path_vertex, connect_light_path and path_continue; true when the path has
// ended. mirror: src/render/integrator.rs `path_step`
fn path_step(st: ptr<function, PathState>, light: ptr<function, LightPath>, rng: Rng) -> bool {
    let v = path_vertex(st, rng, 1u);
    if !v.valid {
        return true;
    }
    connect_light_path(st, v, light);
    return path_continue(st, v, rng);
}

// A path vertex whose BSDF is still to be sampled. mirror: src/render/integrator.rs `PathVertex`
struct PathVertex {
    si: SurfaceHit,
    mat: Material,
    sf: ShadingFrame,
    wo_world: vec3<f32>,
    wo: vec3<f32>,
    area_pdf: f32,
    u_lobe: f32,
    u: vec2<f32>,
    // False where the path has ended (no vertex).
    valid: bool,
}

// mirror: src/render/integrator.rs `bsdf_numbers`
fn bsdf_numbers(mat: Material, depth: u32, rng: Rng, v: ptr<function, PathVertex>) {
    (*v).u_lobe = 0.0;
    if bsdf_draws_lobe(mat) {
        (*v).u_lobe = rng_1d(rng, depth, DIM_BSDF_LOBE);
    }
    (*v).u = vec2<f32>(0.0);
    if bsdf_draws_direction(mat) {
        (*v).u = rng_2d(rng, depth, DIM_BSDF_U);
    }
}

// The first half of a bounce: the hit, its emission and next event estimation.
// mirror: src/render/integrator.rs `path_vertex`
fn path_vertex(st: ptr<function, PathState>, rng: Rng, branches: u32) -> PathVertex {
    var v: PathVertex;
    v.valid = false;
    // The light pair, drawn before the traversal (as on the CPU, where that hides its
    // latency; on a miss, a delta material or the last segment it goes unused).
    var u_light = vec2<f32>(0.0);
    if params.num_emitters > 0u && !path_ends_at_vertex(st) {
        u_light = rng_2d(rng, (*st).depth, DIM_LIGHT_U);
    }
    (*st).rays += 1u;
    let hit = traverse_closest((*st).ray, T_INF, (*st).depth == 0u);
    if (*st).depth != 0u {
        add_rect_hits(st, select(hit.t, T_INF, hit.tri == NO_HIT));
    }
    if hit.tri == NO_HIT {
        var w = 1.0;
        if !(*st).prev_delta && params.sky_pmf != 0.0 {
            w = power_heuristic((*st).prev_pdf, sky_pdf((*st).ray.dir));
        }
        (*st).radiance += (*st).beta * w * sky_radiance((*st).ray.dir);
        return v;
    }
    let si = surface_at((*st).ray, hit);
    var mat = material_at(load_material(si.material), si.uv, si.color);
    if mat.kind == MAT_UNLIT {
        // Only camera rays find an unlit surface: its colour, as it is.
        (*st).radiance += (*st).beta * mat.albedo;
        return v;
    }
    if si.front_face && is_emissive(mat) {
        let cos_l = -dot((*st).ray.dir, si.ng);
        var w = 1.0;
        if !(*st).prev_delta {
            w = power_heuristic((*st).prev_pdf, light_pdf(si.tri, hit.t, cos_l));
        } else if CAUSTICS && (*st).caustic_pdf > 0.0 {
            let pmf = load_shading(si.tri).emitter_pmf;
            let area = triangle_area(load_tri(si.tri));
            w = caustic_hit_weight(pmf, area, si.p, (*st).ray.dir, cos_l, (*st).caustic_pdf);
        }
        (*st).radiance += (*st).beta * w * mat.emission;
    }
    // The camera's (or BSDF sampling's) density of this vertex in area, where the previous
    // vertex is the camera (or a non-delta vertex).
    let caustics = CAUSTICS && params.num_caustic_targets != 0u;
    var area_pdf = 0.0;
    if caustics && ((*st).depth == 0u || !(*st).prev_delta) {
        area_pdf = (*st).prev_pdf * abs(dot((*st).ray.dir, si.ng)) / (hit.t * hit.t);
    }
    if path_ends_at_vertex(st) {
        return v;
    }
    let wo_world = -(*st).ray.dir;
    let sf = shading_frame(mat, si, wo_world);
    mat = coated(mat, si, sf);
    let ng = sf.ng;
    let frame = sf.m;
    let wo = wo_world * frame;

    // The numbers BSDF sampling reads, drawn only where the material reads them (before
    // next event estimation, as on the CPU, where that hides their latency), and only
    // where the path does not branch here.
    if branches == 1u {
        bsdf_numbers(mat, (*st).depth, rng, &v);
    }

    // Next event estimation: the lights sampled in full, then the one picked.
    if !bsdf_is_delta(mat) {
        for (var k = 0u; k < params.lights_in_full; k++) {
            if load_light(k).kind != LIGHT_RECT {
                add_direct(st, mat, frame, ng, wo, sample_punctual(k, si.p, ng, 1.0, vec2<f32>(0.0)));
            }
        }
        if params.num_emitters > 0u {
            add_direct(st, mat, frame, ng, wo, sample_light(si.p, ng, u_light));
        }
    }

    v.si = si;
    v.mat = mat;
    v.sf = sf;
    v.wo_world = wo_world;
    v.wo = wo;
    v.area_pdf = area_pdf;
    v.valid = true;
    return v;
}

// Adds the emission of the rectangle lights that the BSDF-sampled ray meets before t_max,
// weighed against next event estimation or the light subpath that could make the same path.
// mirror: src/render/integrator.rs `add_rect_hits`
fn add_rect_hits(st: ptr<function, PathState>, t_max: f32) {
    for (var k = params.first_rect_light; k < params.num_lights; k++) {
        let l = load_light(k);
        let h = hit_rect(l, (*st).ray, t_max);
        if !h.valid {
            continue;
        }
        var w = 1.0;
        if !(*st).prev_delta {
            w = power_heuristic((*st).prev_pdf, l.pmf * rect_pdf(l, (*st).ray.origin, h.t, h.cos_l));
        } else if CAUSTICS && (*st).caustic_pdf > 0.0 {
            let q = (*st).ray.origin + h.t * (*st).ray.dir;
            w = caustic_hit_weight(l.pmf, l.area, q, (*st).ray.dir, h.cos_l, (*st).caustic_pdf);
        }
        (*st).radiance += (*st).beta * w * l.intensity;
    }
}

// Adds light sample ls (where valid), seen through mat at the vertex whose shading frame is
// frame (geometric normal ng) towards wo (local), where its shadow ray is clear.
// mirror: src/render/integrator.rs `add_direct`
fn add_direct(st: ptr<function, PathState>, mat: Material, frame: mat3x3<f32>, ng: vec3<f32>, wo: vec3<f32>, ls: LightSample) {
    let cos_i = dot(ls.wi, ng);
    let usable = select(cos_i > 0.0, cos_i != 0.0, bsdf_transmits(mat));
    if !ls.valid || !usable {
        return;
    }
    let wi = ls.wi * frame;
    let f = bsdf_eval(mat, wo, wi);
    if all(f == vec3<f32>(0.0)) {
        return;
    }
    (*st).rays += 1u;
    if !traverse_any(Ray(ls.origin, ls.wi), ls.t_max) {
        var w = 1.0;
        if !ls.delta {
            w = power_heuristic(ls.pdf, bsdf_pdf(mat, wo, wi));
        }
        (*st).radiance += (*st).beta * f * ls.le * (w / ls.pdf);
    }
}

// Caustic connections: vertex v (where it is not delta) to each vertex of the light subpath
// that leaves the path room for the link and the subpath's segments.
// mirror: src/render/integrator.rs `connect_light_path`
fn connect_light_path(st: ptr<function, PathState>, v: PathVertex, light: ptr<function, LightPath>) {
    if !(CAUSTICS && params.num_caustic_targets != 0u) || bsdf_is_delta(v.mat) {
        return;
    }
    for (var k = 0u; k < (*light).count; k++) {
        connect_light_vertex(st, v.si, v.mat, v.sf, v.wo_world, v.wo, (*light).vertices[k]);
    }
}

// The second half of a bounce: BSDF sampling at v and Russian roulette; true when the path
// has ended. mirror: src/render/integrator.rs `path_continue`
fn path_continue(st: ptr<function, PathState>, v: PathVertex, rng: Rng) -> bool {
    let si = v.si;
    let mat = v.mat;
    let wo_world = v.wo_world;
    let wo = v.wo;
    let frame = v.sf.m;
    let area_pdf = v.area_pdf;
    let caustics = CAUSTICS && params.num_caustic_targets != 0u;
    // BSDF sampling.
    let bs = bsdf_sample(mat, wo, v.u_lobe, v.u);
    if !bs.valid {
        return true;
    }
    let wi_world = frame * bs.wi;
    if !geometry_agrees(si.ng, wo_world, wi_world, wo, bs.wi) {
        return true;
    }
    if caustics {
        if bs.delta {
            if !bsdf_is_delta(mat) {
                (*st).caustic_pdf = 0.0;
            }
        } else if !(*st).prev_delta || (*st).depth == 0u {
            let c = abs(dot(wi_world, si.ng));
            (*st).caustic_pdf = 0.0;
            if area_pdf > 0.0 && c > 0.0 {
                (*st).caustic_pdf = area_pdf * bs.pdf / c;
            }
            (*st).caustic_hops = 0u;
        } else if (*st).caustic_pdf > 0.0 {
            let cos_out = abs(dot(wi_world, si.ng));
            let cos_in = abs(dot(wo_world, si.ng));
            let back = shading_frame(mat, si, wi_world);
            let pdf_light = bsdf_pdf(coated(mat, si, back), wi_world * back.m, wo_world * back.m);
            (*st).caustic_pdf *= bs.pdf * cos_in / (pdf_light * cos_out);
            (*st).caustic_hops += 1u;
            if !((*st).caustic_pdf <= T_INF && (*st).caustic_hops < MAX_CAUSTIC_HOPS) {
                (*st).caustic_pdf = 0.0;
            }
        }
    }
    (*st).beta *= bs.weight;
    (*st).prev_pdf = bs.pdf;
    (*st).prev_delta = bs.delta;
    (*st).eta_scale *= bs.eta;
    (*st).bounces_left[bs.lobe] -= 1u;
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

// mirror: src/render/integrator.rs `LightStart`
struct LightStart {
    light: LightPath,
    rays: u32,
    splat_pixels: array<u32, MAX_CAUSTIC_HOPS>,
    splats: array<vec3<f32>, MAX_CAUSTIC_HOPS>,
}

// mirror: src/render/integrator.rs `start_light`
fn start_light(rng: Rng) -> LightStart {
    var out: LightStart;
    out.light = no_light_path();
    out.rays = 0u;
    if !CAUSTICS || params.num_caustic_targets == 0u {
        return out;
    }
    let traced = trace_light_subpath(rng, params.max_depth - 1u);
    out.light = traced.path;
    out.rays = traced.rays;
    for (var k = 0u; k < out.light.count; k++) {
        let link = seen_camera_link(out.light.vertices[k], rng);
        out.rays += link.rays;
        out.splat_pixels[k] = link.pixel;
        out.splats[k] = link.value;
    }
    return out;
}

// start_light's link of one light vertex to the camera: the rays it traced and, where the
// vertex is seen, its splat (a zero value otherwise).
struct SeenLink {
    rays: u32,
    pixel: u32,
    value: vec3<f32>,
}

fn seen_camera_link(lv: LightVertex, rng: Rng) -> SeenLink {
    var out = SeenLink(0u, 0u, vec3<f32>(0.0));
    let link = camera_link(lv, rng_2d(rng, lv.segments, DIM_LENS_U));
    if link.valid {
        out.rays = 1u;
        if !traverse_any(link.ray, link.t_max) {
            out.pixel = link.pixel;
            out.value = link.value;
        }
    }
    return out;
}

// What a camera sample adds to the film: its radiance and rays, and for the tests its
// light subpaths' splats, summed (their values, and the pixels of those that land).
// mirror: src/render/integrator.rs `PathSample` (whose splats go to a closure instead)
struct PathSample {
    radiance: vec3<f32>,
    rays: u32,
    splat_sum: vec3<f32>,
    splat_pixel_sum: u32,
}

// The shader tests' camera sample; the render kernel (render.wgsl) runs the same steps in
// its loop of persistent paths. mirror: src/render/integrator.rs `trace_path`
fn trace_path(ray: Ray, rng: Rng) -> PathSample {
    var st = path_start(ray, camera_pdf(ray.dir));
    var v = path_vertex(&st, rng, params.branches);
    var out = PathSample(st.radiance, st.rays, vec3<f32>(0.0), 0u);
    if !(CAUSTICS && params.num_caustic_targets != 0u) && !v.valid {
        return out;
    }
    var sum = vec3<f32>(0.0);
    for (var j = 0u; j < params.branches; j++) {
        var b = branch_start(st, rng, j, params.branches);
        for (var k = 0u; k < MAX_CAUSTIC_HOPS; k++) {
            if any(b.ls.splats[k] != vec3<f32>(0.0)) {
                out.splat_sum += b.ls.splats[k];
                out.splat_pixel_sum += b.ls.splat_pixels[k];
            }
        }
        var light = b.ls.light;
        var bst = b.st;
        if v.valid {
            branch_numbers(&v, st.depth, b.rng, params.branches);
            connect_light_path(&bst, v, &light);
            if !path_continue(&bst, v, b.rng) {
                loop {
                    if path_step(&bst, &light, b.rng) {
                        break;
                    }
                }
            }
        }
        sum += bst.radiance;
        out.rays += bst.rays;
    }
    out.radiance += sum * params.branch_weight;
    return out;
}

// mirror: src/render/integrator.rs `branch_sample`
fn branch_sample(sample: u32, j: u32, k: u32) -> u32 {
    return sample * k + j;
}

// A branch of a camera sample before its first step: its path (the camera sample's up to
// its first vertex, with no radiance yet and its light subpath's rays), its light subpath
// with its splats (weighted as one of the sample's branches) and its stream. Its first step
// is connect_light_path and path_continue at the sample's first vertex, with its own BSDF
// numbers there (branch_numbers). mirror: src/render/integrator.rs `Branch`
struct Branch {
    st: PathState,
    ls: LightStart,
    rng: Rng,
}

// Branch j of the k of the camera sample of stream rng, whose path base reached its first
// vertex. The branch draws from the stream of its branch_sample index, and traces its light
// subpath there (start_light). mirror: src/render/integrator.rs `branch_start`
fn branch_start(base: PathState, rng: Rng, j: u32, k: u32) -> Branch {
    let branch_rng = Rng(rng.pixel, branch_sample(rng.sample, j, k), rng.seed);
    var b: Branch;
    b.ls = start_light(branch_rng);
    b.st = base;
    b.st.radiance = vec3<f32>(0.0);
    b.st.rays = b.ls.rays;
    b.rng = branch_rng;
    for (var i = 0u; i < MAX_CAUSTIC_HOPS; i++) {
        b.ls.splats[i] *= params.branch_weight;
    }
    return b;
}

// Gives the camera sample's first vertex v (at bounce depth) the BSDF numbers of the
// branch of stream rng of k, where the sample branches; with one branch path_vertex drew
// them from the sample's own stream, which is the branch's.
// mirror: src/render/integrator.rs `branch_numbers`
fn branch_numbers(v: ptr<function, PathVertex>, depth: u32, rng: Rng, k: u32) {
    if k > 1u {
        bsdf_numbers((*v).mat, depth, rng, v);
    }
}

// What the AOVs read of a camera ray's first hit. mirror: src/render/integrator.rs `FirstHit`
struct FirstHit {
    hit: bool,
    p: vec3<f32>,
    normal: vec3<f32>,
    albedo: vec3<f32>,
    diffuse: vec3<f32>,
    material: u32,
    object: u32,
    cost: u32,
}

// The first hit of a camera ray, for the AOVs. mirror: src/render/integrator.rs `first_hit`
fn first_hit(ray: Ray) -> FirstHit {
    let counted = traverse_closest_counted(ray, T_INF, true);
    let hit = counted.hit;
    if hit.tri == NO_HIT {
        return FirstHit(false, vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), NO_ID, NO_ID, counted.cost);
    }
    let si = surface_at(ray, hit);
    let mat = material_at(load_material(si.material), si.uv, si.color);
    let normal = select(si.ns, -si.ns, dot(si.ns, ray.dir) > 0.0);
    let albedo = select(mat.albedo, vec3<f32>(1.0), mat.kind == MAT_DIELECTRIC);
    // TriVerts.v1.w holds the bits of the triangle's object index.
    let object = bitcast<u32>(load_tri(hit.tri).v1.w);
    return FirstHit(true, si.p, normal, albedo, diffuse_color(mat), si.material, object, counted.cost);
}
