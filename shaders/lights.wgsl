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
        return sample_punctual(light & ~LIGHT_EMITTER, p, ng, pick.pmf);
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
fn sample_punctual(index: u32, p: vec3<f32>, ng: vec3<f32>, pmf: f32) -> LightSample {
    var none = LightSample(vec3<f32>(0.0), vec3<f32>(0.0), 0.0, vec3<f32>(0.0), 0.0, false, false);
    let l = load_light(index);
    if l.kind == LIGHT_DIRECTIONAL {
        let wi = -l.direction;
        return LightSample(offset_ray_origin(p, ng, wi), wi, T_INF, l.intensity, pmf, true, true);
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
