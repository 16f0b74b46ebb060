// Caustics: light subpaths through the scene's specular geometry, joined to the camera
// path. mirror: src/render/caustics.rs — every function has a Rust twin of the same name.

// Whether the module has the code of caustic light subpaths (no_caustics.wgsl, which takes
// this file's place in the render kernel of a scene without caustic targets, says false).
// Where true, params.num_caustic_targets still decides.
const CAUSTICS: bool = true;

// mirror: src/render/caustics.rs `TargetCone`
struct TargetCone {
    axis: vec3<f32>,
    cos_max: f32,
    height: f32,
}

// mirror: src/render/caustics.rs `target_cone`
fn target_cone(sphere: CausticTarget, p: vec3<f32>) -> TargetCone {
    let d = sphere.center - p;
    let dist2 = dot(d, d);
    let r2 = sphere.radius * sphere.radius;
    if dist2 <= r2 {
        return TargetCone(vec3<f32>(0.0, 0.0, 1.0), -1.0, 2.0);
    }
    let sin2 = r2 / dist2;
    let cos_max = sqrt(1.0 - sin2);
    return TargetCone(d * (1.0 / sqrt(dist2)), cos_max, sin2 / (1.0 + cos_max));
}

// mirror: src/render/caustics.rs `target_pdf`
fn target_pdf(p: vec3<f32>, dir: vec3<f32>) -> f32 {
    var total = 0.0;
    var count = 0.0;
    for (var k = 0u; k < params.num_caustic_targets; k++) {
        let cone = target_cone(load_caustic_target(k), p);
        total += cone.height;
        if dot(dir, cone.axis) >= cone.cos_max {
            count += 1.0;
        }
    }
    if total > 0.0 {
        return count / (2.0 * PI * total);
    }
    return 0.0;
}

// A direction towards the targets and its target_pdf (w).
// mirror: src/render/caustics.rs `sample_target`
fn sample_target(p: vec3<f32>, u: vec2<f32>) -> vec4<f32> {
    var x = u.x * targets_height(p);
    var cone = target_cone(load_caustic_target(0u), p);
    for (var k = 0u; k < params.num_caustic_targets; k++) {
        cone = target_cone(load_caustic_target(k), p);
        if x < cone.height {
            break;
        }
        x -= cone.height;
    }
    let v = clamp(x / cone.height, 0.0, 1.0) * cone.height;
    let dir = sample_cone(cone, v, u.y);
    return vec4<f32>(dir, target_pdf(p, dir));
}

// mirror: src/render/caustics.rs `targets_height`
fn targets_height(p: vec3<f32>) -> f32 {
    var total = 0.0;
    for (var k = 0u; k < params.num_caustic_targets; k++) {
        total += target_cone(load_caustic_target(k), p).height;
    }
    return total;
}

// mirror: src/render/caustics.rs `sample_cone`
fn sample_cone(cone: TargetCone, v: f32, turn: f32) -> vec3<f32> {
    let cos_t = 1.0 - v;
    let sin_t = sqrt(max(v * (2.0 - v), 0.0));
    let phi = 2.0 * PI * turn;
    let frame = onb_from_normal(cone.axis);
    return (sin_t * cos(phi)) * frame[0] + (sin_t * sin(phi)) * frame[1] + cos_t * cone.axis;
}

// mirror: src/render/caustics.rs `LightVertex`
struct LightVertex {
    si: SurfaceHit,
    wi: vec3<f32>,
    beta: vec3<f32>,
    pdf: f32,
    segments: u32,
}

// mirror: src/render/caustics.rs `LightPath`
struct LightPath {
    vertices: array<LightVertex, MAX_CAUSTIC_HOPS>,
    count: u32,
}

fn no_light_vertex() -> LightVertex {
    let si = SurfaceHit(vec3<f32>(0.0), vec3<f32>(0.0, 0.0, 1.0), vec3<f32>(0.0, 0.0, 1.0), vec3<f32>(0.0, 0.0, 1.0), 0u, true, 0u, vec4<f32>(0.0), vec4<f32>(1.0));
    return LightVertex(si, vec3<f32>(0.0, 0.0, 1.0), vec3<f32>(0.0), 0.0, 0u);
}

fn no_light_path() -> LightPath {
    let none = no_light_vertex();
    return LightPath(array<LightVertex, MAX_CAUSTIC_HOPS>(none, none), 0u);
}

// The light subpath and the rays it traced. mirror: src/render/caustics.rs
// `trace_light_subpath` (which returns them as a pair)
struct TracedLight {
    path: LightPath,
    rays: u32,
}

// mirror: src/render/caustics.rs `LightSubpathStart` (valid stands for the Option around it)
struct LightSubpathStart {
    ray: Ray,
    beta: vec3<f32>,
    pdf: f32,
    valid: bool,
}

fn no_light_subpath_start() -> LightSubpathStart {
    return LightSubpathStart(Ray(vec3<f32>(0.0), vec3<f32>(0.0, 0.0, 1.0)), vec3<f32>(0.0), 0.0, false);
}

// mirror: src/render/caustics.rs `start_at_triangle`
fn start_at_triangle(light: u32, pick: LightPick, rng: Rng) -> LightSubpathStart {
    let tri = load_tri(light);
    let bary = sample_uniform_triangle(pick.u);
    if tri.v0.w != 0.0 && !alpha_test(light, bary.x, bary.y, false) {
        return no_light_subpath_start();
    }
    let q = (1.0 - bary.x - bary.y) * tri.v0.xyz + bary.x * tri.v1.xyz + bary.y * tri.v2.xyz;
    let n = geometric_normal(tri);
    let st = sample_target(q, rng_2d(rng, 0u, DIM_CAUSTIC_DIR_U));
    let dir = st.xyz;
    let pdf_dir = st.w;
    let cos_m = dot(dir, n);
    if !(cos_m > 0.0 && pdf_dir > 0.0) {
        return no_light_subpath_start();
    }
    let le = triangle_emission(light, bary);
    let pdf_point = LIGHT_SUBPATH_RATE * pick.pmf / triangle_area(tri);
    let pdf = pdf_point * pdf_dir / cos_m;
    if !(pdf > 0.0) {
        return no_light_subpath_start();
    }
    return LightSubpathStart(Ray(offset_ray_origin(q, n, dir), dir), le * (cos_m / (pdf_point * pdf_dir)), pdf, true);
}

// mirror: src/render/caustics.rs `start_at_rect`
fn start_at_rect(l: Light, pmf: f32, u: vec2<f32>, rng: Rng) -> LightSubpathStart {
    let q = l.position + u.x * l.direction + u.y * l.edge;
    let n = normalize(cross(l.direction, l.edge));
    let st = sample_target(q, rng_2d(rng, 0u, DIM_CAUSTIC_DIR_U));
    let dir = st.xyz;
    let pdf_dir = st.w;
    let cos_m = dot(dir, n);
    let pdf_point = LIGHT_SUBPATH_RATE * pmf / l.area;
    if !(cos_m > 0.0 && pdf_dir > 0.0 && pdf_point > 0.0) {
        return no_light_subpath_start();
    }
    let pdf = pdf_point * pdf_dir / cos_m;
    if !(pdf > 0.0) {
        return no_light_subpath_start();
    }
    return LightSubpathStart(Ray(q, dir), l.intensity * (cos_m / (pdf_point * pdf_dir)), pdf, true);
}

// mirror: src/render/caustics.rs `start_at_directional`
fn start_at_directional(l: Light, pmf: f32, rng: Rng) -> LightSubpathStart {
    let d = l.direction;
    let u = rng_2d(rng, 0u, DIM_CAUSTIC_DIR_U);
    var total = 0.0;
    for (var k = 0u; k < params.num_caustic_targets; k++) {
        let t = load_caustic_target(k);
        total += t.radius * t.radius;
    }
    var x = u.x * total;
    var picked = load_caustic_target(0u);
    for (var k = 0u; k < params.num_caustic_targets; k++) {
        picked = load_caustic_target(k);
        if x < picked.radius * picked.radius {
            break;
        }
        x -= picked.radius * picked.radius;
    }
    let r2 = picked.radius * picked.radius;
    let disk = sample_concentric_disk(vec2<f32>(clamp(x / r2, 0.0, ONE_MINUS_EPSILON), u.y));
    let frame = onb_from_normal(d);
    let s = picked.center + picked.radius * (disk.x * frame[0] + disk.y * frame[1]);
    var count = 0.0;
    for (var k = 0u; k < params.num_caustic_targets; k++) {
        let c = load_caustic_target(k);
        let off = s - c.center;
        let across = off - dot(off, d) * d;
        if dot(across, across) <= c.radius * c.radius {
            count += 1.0;
        }
    }
    let pdf_line = LIGHT_SUBPATH_RATE * pmf * count / (PI * total);
    if !(pdf_line > 0.0) {
        return no_light_subpath_start();
    }
    let back = length(s - params.scene_center) + params.scene_radius;
    return LightSubpathStart(Ray(s - back * d, d), l.intensity * (1.0 / pdf_line), 0.0, true);
}

// mirror: src/render/caustics.rs `start_at_punctual`
fn start_at_punctual(index: u32, pmf: f32, u_pick: vec2<f32>, rng: Rng) -> LightSubpathStart {
    let l = load_light(index);
    if l.kind == LIGHT_DIRECTIONAL {
        return start_at_directional(l, pmf, rng);
    }
    if l.kind == LIGHT_RECT {
        return start_at_rect(l, pmf, u_pick, rng);
    }
    let u = rng_2d(rng, 0u, DIM_CAUSTIC_DIR_U);
    let spot = TargetCone(l.direction, l.cos_cutoff, 1.0 - l.cos_cutoff);
    var st: vec4<f32>;
    if l.kind == LIGHT_SPOT && spot.height < targets_height(l.position) {
        st = vec4<f32>(sample_cone(spot, u.x * spot.height, u.y), 1.0 / (2.0 * PI * spot.height));
    } else {
        st = sample_target(l.position, u);
    }
    let dir = st.xyz;
    var intensity = l.intensity;
    if l.kind == LIGHT_SPOT {
        intensity *= spot_falloff(l, dir);
    }
    let pdf_dir = LIGHT_SUBPATH_RATE * pmf * st.w;
    if !(pdf_dir > 0.0) || all(intensity == vec3<f32>(0.0)) {
        return no_light_subpath_start();
    }
    return LightSubpathStart(Ray(l.position, dir), intensity * (1.0 / pdf_dir), 0.0, true);
}

// mirror: src/render/caustics.rs `trace_light_subpath`
fn trace_light_subpath(rng: Rng, max_segments: u32) -> TracedLight {
    var path = no_light_path();
    if !CAUSTICS || params.num_caustic_targets == 0u || params.num_emitters == 0u || max_segments < 2u {
        return TracedLight(path, 0u);
    }
    if rng_1d(rng, 0u, DIM_LIGHT_SUBPATH) >= LIGHT_SUBPATH_RATE {
        return TracedLight(path, 0u);
    }
    let pick = pick_light(rng_2d(rng, 0u, DIM_CAUSTIC_LIGHT_U));
    let light = load_emitter(pick.index);
    if light == SKY_EMITTER {
        return TracedLight(path, 0u);
    }
    var start: LightSubpathStart;
    if (light & LIGHT_EMITTER) != 0u {
        start = start_at_punctual(light & ~LIGHT_EMITTER, pick.pmf, pick.u, rng);
    } else {
        start = start_at_triangle(light, pick, rng);
    }
    if !start.valid {
        return TracedLight(path, 0u);
    }
    var beta = start.beta;
    var pdf = start.pdf;
    var ray = start.ray;
    var rays = 0u;
    var chain = 0u;
    for (var segment = 1u; segment <= max_segments; segment++) {
        rays += 1u;
        let hit = traverse_closest(ray, T_INF, false);
        if hit.tri == NO_HIT {
            break;
        }
        let si = surface_at(ray, hit);
        let mat = material_at(load_material(si.material), si.uv, si.color);
        let delta = bsdf_is_delta(mat);
        if !delta && chain == 0u {
            break;
        }
        let wo_world = -ray.dir;
        if !delta {
            path.vertices[path.count] = LightVertex(si, wo_world, beta, pdf, segment);
            path.count += 1u;
            chain = 0u;
            if path.count == MAX_CAUSTIC_HOPS {
                break;
            }
        } else {
            chain += 1u;
        }
        if segment == max_segments {
            break;
        }
        let frame = shading_frame(mat, si, wo_world);
        let mat_c = coated(mat, si, frame);
        let wo = wo_world * frame.m;
        var u_lobe = 0.0;
        if bsdf_draws_lobe(mat) {
            u_lobe = rng_1d(rng, segment, DIM_CAUSTIC_LOBE);
        }
        var u = vec2<f32>(0.0);
        if !delta {
            u = rng_2d(rng, segment, DIM_CAUSTIC_DIR_U);
        }
        let bs = bsdf_sample(mat_c, wo, u_lobe, u);
        if !bs.valid || bs.delta != delta {
            break;
        }
        let wi_world = frame.m * bs.wi;
        if !geometry_agrees(si.ng, wo_world, wi_world, wo, bs.wi) {
            break;
        }
        let cos_in = abs(dot(wo_world, si.ng));
        let cos_out = abs(dot(wi_world, si.ng));
        let denom = cos_in * abs(dot(wi_world, frame.m[2]));
        if !(denom > 0.0) {
            break;
        }
        let correction = abs(dot(wo_world, frame.m[2])) * cos_out / denom;
        beta *= bs.weight * (bs.eta * bs.eta * correction);
        if !delta && pdf > 0.0 {
            let back = shading_frame(mat, si, wi_world);
            let pdf_camera = bsdf_pdf(coated(mat, si, back), wi_world * back.m, wo_world * back.m);
            pdf *= bs.pdf * cos_in / (pdf_camera * cos_out);
            if !(pdf > 0.0 && pdf <= T_INF) {
                break;
            }
        }
        if all(beta == vec3<f32>(0.0)) {
            break;
        }
        ray = Ray(offset_ray_origin(si.p, si.ng, wi_world), wi_world);
    }
    return TracedLight(path, rays);
}

// mirror: src/render/caustics.rs `caustic_weight`
fn caustic_weight(ratio: f32) -> f32 {
    let w = 1.0 / (1.0 + ratio * ratio);
    // NaN by its bits: a compiler may assume floats are never NaN.
    if (bitcast<u32>(w) & 0x7fffffffu) > 0x7f800000u {
        return 0.0;
    }
    return w;
}

// mirror: src/render/caustics.rs `link_weight`
fn link_weight(pdf_bsdf: f32, lv: LightVertex) -> f32 {
    if lv.pdf > 0.0 {
        return caustic_weight(pdf_bsdf / lv.pdf);
    }
    return 1.0;
}

// mirror: src/render/caustics.rs `CausticLink` (valid stands for the Option around it)
struct CausticLink {
    ray: Ray,
    t_max: f32,
    value: vec3<f32>,
    valid: bool,
}

fn no_caustic_link() -> CausticLink {
    return CausticLink(Ray(vec3<f32>(0.0), vec3<f32>(0.0, 0.0, 1.0)), 0.0, vec3<f32>(0.0), false);
}

// mirror: src/render/caustics.rs `caustic_link`
fn caustic_link(si: SurfaceHit, mat: Material, frame: ShadingFrame, wo_world: vec3<f32>, wo: vec3<f32>, lv: LightVertex) -> CausticLink {
    let d = lv.si.p - si.p;
    let dist2 = dot(d, d);
    if !(dist2 > 0.0) {
        return no_caustic_link();
    }
    let wc = d * (1.0 / sqrt(dist2));
    let cos_i = dot(wc, frame.ng);
    let usable = select(cos_i > 0.0, cos_i != 0.0, bsdf_transmits(mat));
    if !usable {
        return no_caustic_link();
    }
    let wi = wc * frame.m;
    let f = bsdf_eval(mat, wo, wi);
    if all(f == vec3<f32>(0.0)) || !geometry_agrees(si.ng, wo_world, wc, wo, wi) {
        return no_caustic_link();
    }
    let seen = light_vertex_seen(lv, wc);
    if !seen.valid {
        return no_caustic_link();
    }
    let pdf_bsdf = bsdf_pdf(mat, wo, wi) / dist2 * seen.pdf;
    let w = link_weight(pdf_bsdf, lv);
    let origin = offset_ray_origin(si.p, si.ng, wc);
    let to = seen.end - origin;
    let dist = length(to);
    if !(dist > 0.0) {
        return no_caustic_link();
    }
    return CausticLink(Ray(origin, to * (1.0 / dist)), dist * (1.0 - 1e-4), f * seen.value * (w / dist2), true);
}

// mirror: src/render/caustics.rs `SeenLightVertex` (valid stands for the Option around it)
struct SeenLightVertex {
    value: vec3<f32>,
    pdf: f32,
    end: vec3<f32>,
    valid: bool,
}

// mirror: src/render/caustics.rs `light_vertex_seen`
fn light_vertex_seen(lv: LightVertex, wc: vec3<f32>) -> SeenLightVertex {
    let none = SeenLightVertex(vec3<f32>(0.0), 0.0, vec3<f32>(0.0), false);
    let base = material_at(load_material(lv.si.material), lv.si.uv, lv.si.color);
    let wo_l_world = -wc;
    let frame_l = shading_frame(base, lv.si, wo_l_world);
    let mat_l = coated(base, lv.si, frame_l);
    let wo_l = wo_l_world * frame_l.m;
    let wi_l = lv.wi * frame_l.m;
    let f_l = bsdf_eval(mat_l, wo_l, wi_l);
    if all(f_l == vec3<f32>(0.0)) || !geometry_agrees(lv.si.ng, wo_l_world, lv.wi, wo_l, wi_l) {
        return none;
    }
    let cos_c = abs(dot(wc, lv.si.ng));
    let cos_k = abs(dot(lv.wi, lv.si.ng));
    if !(cos_k > 0.0) {
        return none;
    }
    let ratio = cos_c / cos_k;
    return SeenLightVertex(f_l * lv.beta * ratio, bsdf_pdf(mat_l, wo_l, wi_l) * ratio, offset_ray_origin(lv.si.p, lv.si.ng, wo_l_world), true);
}

// mirror: src/render/caustics.rs `caustic_hit_weight`
fn caustic_hit_weight(pmf: f32, area: f32, p: vec3<f32>, dir: vec3<f32>, cos_l: f32, pdf_bsdf: f32) -> f32 {
    if pmf == 0.0 || !(cos_l > 0.0) {
        return 1.0;
    }
    let pdf_light = LIGHT_SUBPATH_RATE * pmf / area * target_pdf(p, -dir) / cos_l;
    return caustic_weight(pdf_light / pdf_bsdf);
}

// mirror: src/render/caustics.rs `camera_pdf`
fn camera_pdf(dir: vec3<f32>) -> f32 {
    let c = dot(dir, params.cam_forward);
    if !(c > 0.0) {
        return 0.0;
    }
    let area = 4.0 * params.tan_half_vfov * params.tan_half_vfov * params.aspect;
    return 1.0 / (area * c * c * c);
}

// mirror: src/render/caustics.rs `CameraLink` (valid stands for the Option around it)
struct CameraLink {
    pixel: u32,
    ray: Ray,
    t_max: f32,
    value: vec3<f32>,
    valid: bool,
}

fn no_camera_link() -> CameraLink {
    return CameraLink(0u, Ray(vec3<f32>(0.0), vec3<f32>(0.0, 0.0, 1.0)), 0.0, vec3<f32>(0.0), false);
}

// mirror: src/render/caustics.rs `camera_link`
fn camera_link(lv: LightVertex, u_lens: vec2<f32>) -> CameraLink {
    var lens = vec3<f32>(0.0);
    if params.aperture > 0.0 {
        let d = 0.5 * params.aperture * sample_concentric_disk(u_lens);
        lens = d.x * params.cam_right + d.y * params.cam_up;
    }
    let origin = params.cam_position + lens;
    let d = lv.si.p - origin;
    let depth = dot(d, params.cam_forward);
    if !(depth > 0.0) {
        return no_camera_link();
    }
    var s = d * (1.0 / depth);
    if params.aperture > 0.0 {
        s = lens * (1.0 / params.focus_distance) + d * (1.0 / depth);
    }
    let x = (dot(s, params.cam_right) / (params.tan_half_vfov * params.aspect) + 1.0) * 0.5 * f32(params.width);
    let y = (1.0 - dot(s, params.cam_up) / params.tan_half_vfov) * 0.5 * f32(params.height);
    if !(x >= 0.0 && x < f32(params.width) && y >= 0.0 && y < f32(params.height)) {
        return no_camera_link();
    }
    let dist2 = dot(d, d);
    let dist = sqrt(dist2);
    let wc = d * (1.0 / dist);
    let seen = light_vertex_seen(lv, wc);
    if !seen.valid {
        return no_camera_link();
    }
    let importance = camera_pdf(wc);
    let pdf_bsdf = importance / dist2 * seen.pdf;
    let w = link_weight(pdf_bsdf, lv);
    let to = seen.end - origin;
    let len = length(to);
    if !(len > 0.0) {
        return no_camera_link();
    }
    let pixel = u32(y) * params.width + u32(x);
    return CameraLink(pixel, Ray(origin, to * (1.0 / len)), len * (1.0 - 1e-4), seen.value * (importance * w / dist2), true);
}
