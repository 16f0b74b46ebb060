// The lights next event estimation samples: emissive triangles, punctual lights and the sky.
// mirror: src/render/lights.rs — every function has a Rust twin of the same name.

// mirror: src/render/lights.rs `sky_radiance`
fn sky_radiance(dir: vec3<f32>) -> vec3<f32> {
    if params.sky_kind == SKY_CONSTANT {
        return params.sky_zenith;
    }
    if params.sky_kind == SKY_ENVIRONMENT {
        return env_radiance(dir);
    }
    return mix(params.sky_horizon, params.sky_zenith, 0.5 * (dir.y + 1.0));
}

// mirror: src/render/lights.rs `sky_pdf`
fn sky_pdf(dir: vec3<f32>) -> f32 {
    if params.sky_kind == SKY_ENVIRONMENT {
        return params.sky_pmf * env_pdf(dir);
    }
    return params.sky_pmf * UNIFORM_SPHERE_PDF;
}

// mirror: src/render/lights.rs `light_pdf`
fn light_pdf(tri: u32, dist: f32, cos_l: f32) -> f32 {
    let pmf = load_shading(tri).emitter_pmf;
    let area = triangle_area(load_tri(tri));
    return pmf * dist * dist / (cos_l * area);
}

// mirror: src/render/lights.rs `LightSample` (valid stands for the Option around it)
struct LightSample {
    origin: vec3<f32>,
    wi: vec3<f32>,
    t_max: f32,
    le: vec3<f32>,
    pdf: f32,
    delta: bool,
    valid: bool,
}

// mirror: src/render/lights.rs `LightPick`
struct LightPick {
    index: u32,
    pmf: f32,
    u: vec2<f32>,
}

// mirror: src/render/lights.rs `pick_light`
fn pick_light(u: vec2<f32>) -> LightPick {
    if params.num_emitters == 1u {
        return LightPick(0u, load_emitter_cdf(0u), u);
    }
    let bucket = sample_cdf(u.x);
    let index = bucket.index;
    let lo = bucket.below;
    let pmf = load_emitter_cdf(index) - lo;
    return LightPick(index, pmf, vec2<f32>(min((u.x - lo) / pmf, ONE_MINUS_EPSILON), u.y));
}

// mirror: src/render/lights.rs `sample_light`
fn sample_light(p: vec3<f32>, ng: vec3<f32>, u_pair: vec2<f32>) -> LightSample {
    var none = LightSample(vec3<f32>(0.0), vec3<f32>(0.0), 0.0, vec3<f32>(0.0), 0.0, false, false);
    let pick = pick_light(u_pair);
    let light = load_emitter(pick.index);
    let u = pick.u;
    if light == SKY_EMITTER {
        var wi = sample_uniform_sphere(u);
        var pdf = UNIFORM_SPHERE_PDF;
        if params.sky_kind == SKY_ENVIRONMENT {
            let e = sample_env(u);
            wi = e.dir;
            pdf = e.pdf;
        }
        if pdf <= 0.0 {
            return none;
        }
        return LightSample(offset_ray_origin(p, ng, wi), wi, T_INF, sky_radiance(wi), params.sky_pmf * pdf, false, true);
    }
    if (light & LIGHT_EMITTER) != 0u {
        let index = light & ~LIGHT_EMITTER;
        if index < params.lights_in_full && load_light(index).kind != LIGHT_RECT {
            return none;
        }
        return sample_punctual(index, p, ng, pick.pmf, u);
    }
    let tri = load_tri(light);
    let bary = sample_uniform_triangle(u);
    let q = (1.0 - bary.x - bary.y) * tri.v0.xyz + bary.x * tri.v1.xyz + bary.y * tri.v2.xyz;
    let origin = offset_ray_origin(p, ng, q - p);
    let to_light = q - origin;
    let dist = length(to_light);
    let wi = to_light * (1.0 / dist);
    let cos_l = -dot(wi, geometric_normal(tri));
    // A point that an alpha mask cuts out emits nothing.
    if !(cos_l > 0.0 && dist > 0.0) || (tri.v0.w != 0.0 && !alpha_test(light, bary.x, bary.y, false)) {
        return none;
    }
    let le = triangle_emission(light, bary);
    return LightSample(origin, wi, dist * (1.0 - 1e-4), le, light_pdf(light, dist, cos_l), false, true);
}

// mirror: src/render/lights.rs `triangle_emission`
fn triangle_emission(light: u32, bary: vec2<f32>) -> vec3<f32> {
    // Vertex colours tint the base colour, not the emission.
    let uv = triangle_uv(light, bary.x, bary.y);
    return material_at(load_material(load_shading(light).material), uv, vec4<f32>(1.0)).emission;
}

// mirror: src/render/lights.rs `sample_punctual`
fn sample_punctual(index: u32, p: vec3<f32>, ng: vec3<f32>, pmf: f32, u: vec2<f32>) -> LightSample {
    var none = LightSample(vec3<f32>(0.0), vec3<f32>(0.0), 0.0, vec3<f32>(0.0), 0.0, false, false);
    let l = load_light(index);
    if l.kind == LIGHT_DIRECTIONAL {
        let wi = -l.direction;
        let t_max = select(0.0, T_INF, l.shadows != 0u);
        return LightSample(offset_ray_origin(p, ng, wi), wi, t_max, l.intensity, pmf, true, true);
    }
    if l.kind == LIGHT_RECT {
        let r = sample_rect(l, p, u);
        if !r.valid {
            return none;
        }
        let origin = offset_ray_origin(p, ng, r.q - p);
        let to_light = r.q - origin;
        let dist = length(to_light);
        if !(dist > 0.0 && r.pdf > 0.0) {
            return none;
        }
        return LightSample(origin, to_light * (1.0 / dist), dist * (1.0 - 1e-4), l.intensity, pmf * r.pdf, false, true);
    }
    let origin = offset_ray_origin(p, ng, l.position - p);
    let to_light = l.position - origin;
    let dist2 = dot(to_light, to_light);
    let dist = sqrt(dist2);
    if !(dist > 0.0) {
        return none;
    }
    let wi = to_light * (1.0 / dist);
    var le = l.intensity / dist2;
    if l.kind == LIGHT_SPOT {
        le *= spot_falloff(l, -wi);
    }
    if all(le == vec3<f32>(0.0)) {
        return none;
    }
    return LightSample(origin, wi, dist * (1.0 - 1e-4), le, pmf, true, true);
}

// A point of a rectangle light and the solid-angle density of its direction (valid stands
// for the Option around the Rust twin's pair).
struct RectSample {
    q: vec3<f32>,
    pdf: f32,
    valid: bool,
}

// A rectangle light seen from a point (valid stands for the Option around the Rust
// twin). mirror: src/render/lights.rs `RectView`
struct RectView {
    x: vec3<f32>,
    y: vec3<f32>,
    n: vec3<f32>,
    x0: f32,
    y0: f32,
    x1: f32,
    y1: f32,
    z0: f32,
    n0: vec3<f32>,
    n2: vec3<f32>,
    g: vec4<f32>,
    solid_angle: f32,
    valid: bool,
}

// mirror: src/render/lights.rs `rect_view`
fn rect_view(l: Light, p: vec3<f32>) -> RectView {
    var v: RectView;
    v.valid = false;
    let ex = l.direction;
    let ey = l.edge;
    let exl = length(ex);
    let eyl = length(ey);
    v.x = ex * (1.0 / exl);
    v.y = ey * (1.0 / eyl);
    v.n = cross(v.x, v.y);
    let d = l.position - p;
    v.z0 = dot(d, v.n);
    if !(v.z0 < 0.0) {
        return v;
    }
    v.x0 = dot(d, v.x);
    v.y0 = dot(d, v.y);
    v.x1 = v.x0 + exl;
    v.y1 = v.y0 + eyl;
    let v00 = vec3<f32>(v.x0, v.y0, v.z0);
    let v01 = vec3<f32>(v.x0, v.y1, v.z0);
    let v10 = vec3<f32>(v.x1, v.y0, v.z0);
    let v11 = vec3<f32>(v.x1, v.y1, v.z0);
    v.n0 = normalize(cross(v00, v10));
    let n1 = normalize(cross(v10, v11));
    v.n2 = normalize(cross(v11, v01));
    let n3 = normalize(cross(v01, v00));
    v.g = vec4<f32>(
        angle_between(-v.n0, n1),
        angle_between(-n1, v.n2),
        angle_between(-v.n2, n3),
        angle_between(-n3, v.n0),
    );
    v.solid_angle = v.g.x + v.g.y + v.g.z + v.g.w - 2.0 * PI;
    v.valid = true;
    return v;
}

// mirror: src/render/lights.rs `rect_by_area`
fn rect_by_area(v: RectView) -> bool {
    return !(v.solid_angle >= 1e-3);
}

// mirror: src/render/lights.rs `sample_rect`
fn sample_rect(l: Light, p: vec3<f32>, u: vec2<f32>) -> RectSample {
    let v = rect_view(l, p);
    if !v.valid {
        return RectSample(vec3<f32>(0.0), 0.0, false);
    }
    if rect_by_area(v) {
        let q = l.position + u.x * l.direction + u.y * l.edge;
        let to = q - p;
        let dist2 = dot(to, to);
        let cos_l = -dot(to, v.n) / sqrt(dist2);
        return RectSample(q, dist2 / (cos_l * l.area), true);
    }
    let b0 = v.n0.z;
    let b1 = v.n2.z;
    let au = u.x * (v.g.x + v.g.y - 2.0 * PI) + (u.x - 1.0) * (v.g.z + v.g.w);
    let fu = (cos(au) * b0 - b1) / sin(au);
    let cu = clamp(select(-1.0, 1.0, fu >= 0.0) / sqrt(fu * fu + b0 * b0), -ONE_MINUS_EPSILON, ONE_MINUS_EPSILON);
    let xu = clamp(-(cu * v.z0) / sqrt(max(1.0 - cu * cu, 0.0)), v.x0, v.x1);
    let dd = sqrt(xu * xu + v.z0 * v.z0);
    let h0 = v.y0 / sqrt(dd * dd + v.y0 * v.y0);
    let h1 = v.y1 / sqrt(dd * dd + v.y1 * v.y1);
    let hv = h0 + u.y * (h1 - h0);
    let hv2 = hv * hv;
    var yv = v.y1;
    if hv2 < 1.0 - 1e-4 {
        yv = hv * dd / sqrt(1.0 - hv2);
    }
    return RectSample(p + xu * v.x + yv * v.y + v.z0 * v.n, 1.0 / v.solid_angle, true);
}

// mirror: src/render/lights.rs `rect_pdf`
fn rect_pdf(l: Light, p: vec3<f32>, dist: f32, cos_l: f32) -> f32 {
    let v = rect_view(l, p);
    if !v.valid {
        return 0.0;
    }
    if rect_by_area(v) {
        return dist * dist / (cos_l * l.area);
    }
    return 1.0 / v.solid_angle;
}

// Where a ray meets the emitting side of a rectangle light before t_max: the distance and
// the cosine there (valid stands for the Option around the Rust twin's pair).
struct RectHit {
    t: f32,
    cos_l: f32,
    valid: bool,
}

// mirror: src/render/lights.rs `hit_rect`
fn hit_rect(l: Light, ray: Ray, t_max: f32) -> RectHit {
    let none = RectHit(0.0, 0.0, false);
    let n = normalize(cross(l.direction, l.edge));
    let cos_l = -dot(ray.dir, n);
    if !(cos_l > 0.0) {
        return none;
    }
    let t = -dot(l.position - ray.origin, n) / cos_l;
    if !(t > 0.0 && t < t_max) {
        return none;
    }
    let q = ray.origin + t * ray.dir - l.position;
    let a = dot(q, l.direction) / dot(l.direction, l.direction);
    let b = dot(q, l.edge) / dot(l.edge, l.edge);
    if !(a >= 0.0 && a <= 1.0 && b >= 0.0 && b <= 1.0) {
        return none;
    }
    return RectHit(t, cos_l, true);
}

// mirror: src/render/lights.rs `angle_between`
fn angle_between(a: vec3<f32>, b: vec3<f32>) -> f32 {
    return atan2(length(cross(a, b)), dot(a, b));
}

// mirror: src/render/lights.rs `spot_falloff`
fn spot_falloff(l: Light, d: vec3<f32>) -> f32 {
    let c = dot(d, l.direction);
    if c <= l.cos_cutoff {
        return 0.0;
    }
    if c >= l.cos_beam {
        return 1.0;
    }
    return (l.cutoff - acos(c)) * l.inv_transition;
}
