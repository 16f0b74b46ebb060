// BSDFs in the local shading frame (normal = +Z). mirror: src/render/bsdf.rs

struct BsdfSample {
    wi: vec3<f32>,
    weight: vec3<f32>,
    pdf: f32,
    delta: bool,
    eta: f32,
    valid: bool,
}

fn no_sample() -> BsdfSample {
    return BsdfSample(vec3<f32>(0.0), vec3<f32>(0.0), 0.0, false, 1.0, false);
}

// mirror: src/render/bsdf.rs `bsdf_is_delta`
fn bsdf_is_delta(m: Material) -> bool {
    return m.kind == MAT_CONDUCTOR || m.kind == MAT_DIELECTRIC;
}

// f(wo, wi) |cos(wi)|. mirror: src/render/bsdf.rs `bsdf_eval`
fn bsdf_eval(m: Material, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    if m.kind == MAT_DIFFUSE {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return vec3<f32>(0.0);
        }
        return m.albedo * (FRAC_1_PI * wi.z);
    }
    if m.kind == MAT_ROUGH_CONDUCTOR {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return vec3<f32>(0.0);
        }
        let alpha = ggx_alpha(m.roughness);
        let h = normalize(wo + wi);
        let g = ggx_g1(wo, alpha) * ggx_g1(wi, alpha);
        return m.albedo * (ggx_d(h, alpha) * g / (4.0 * wo.z));
    }
    return vec3<f32>(0.0);
}

// mirror: src/render/bsdf.rs `bsdf_pdf`
fn bsdf_pdf(m: Material, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    if m.kind == MAT_DIFFUSE {
        if wo.z <= 0.0 {
            return 0.0;
        }
        return cosine_hemisphere_pdf(wi.z);
    }
    if m.kind == MAT_ROUGH_CONDUCTOR {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let alpha = ggx_alpha(m.roughness);
        let h = normalize(wo + wi);
        return ggx_g1(wo, alpha) * ggx_d(h, alpha) / (4.0 * wo.z);
    }
    return 0.0;
}

// mirror: src/render/bsdf.rs `bsdf_sample`
fn bsdf_sample(m: Material, wo: vec3<f32>, u_lobe: f32, u: vec2<f32>) -> BsdfSample {
    if m.kind == MAT_DIFFUSE {
        if wo.z <= 0.0 {
            return no_sample();
        }
        let wi = sample_cosine_hemisphere(u);
        let pdf = cosine_hemisphere_pdf(wi.z);
        if pdf <= 0.0 {
            return no_sample();
        }
        return BsdfSample(wi, m.albedo, pdf, false, 1.0, true);
    }
    if m.kind == MAT_CONDUCTOR {
        if wo.z <= 0.0 {
            return no_sample();
        }
        return BsdfSample(vec3<f32>(-wo.x, -wo.y, wo.z), m.albedo, 1.0, true, 1.0, true);
    }
    if m.kind == MAT_ROUGH_CONDUCTOR {
        if wo.z <= 0.0 {
            return no_sample();
        }
        let alpha = ggx_alpha(m.roughness);
        let h = ggx_sample_visible(wo, alpha, u);
        let wi = 2.0 * dot(wo, h) * h - wo;
        if wi.z <= 0.0 {
            return no_sample();
        }
        let pdf = ggx_g1(wo, alpha) * ggx_d(h, alpha) / (4.0 * wo.z);
        return BsdfSample(wi, m.albedo * ggx_g1(wi, alpha), pdf, false, 1.0, true);
    }
    if m.kind == MAT_DIELECTRIC {
        let fr = fresnel_dielectric(wo.z, m.ior);
        let f = fr.x;
        if u_lobe < f {
            return BsdfSample(vec3<f32>(-wo.x, -wo.y, wo.z), vec3<f32>(1.0), f, true, 1.0, true);
        }
        let eta_ti = fr.w;
        let wi = vec3<f32>(-eta_ti * wo.x, -eta_ti * wo.y, fr.y);
        return BsdfSample(wi, vec3<f32>(eta_ti * eta_ti), 1.0 - f, true, fr.z, true);
    }
    return no_sample();
}

// mirror: src/render/bsdf.rs `ggx_alpha`
fn ggx_alpha(roughness: f32) -> f32 {
    return max(roughness * roughness, 1e-3);
}

// mirror: src/render/bsdf.rs `ggx_d`
fn ggx_d(h: vec3<f32>, alpha: f32) -> f32 {
    if h.z <= 0.0 {
        return 0.0;
    }
    // (h.z^2 (a^2 - 1) + 1) rewritten for a unit h, which avoids cancellation near the peak.
    let a2 = alpha * alpha;
    let d = h.x * h.x + h.y * h.y + a2 * h.z * h.z;
    return a2 / (PI * d * d);
}

// mirror: src/render/bsdf.rs `ggx_g1`
fn ggx_g1(w: vec3<f32>, alpha: f32) -> f32 {
    if w.z <= 0.0 {
        return 0.0;
    }
    let tan2 = (w.x * w.x + w.y * w.y) / (w.z * w.z);
    return 2.0 / (1.0 + sqrt(1.0 + alpha * alpha * tan2));
}

// mirror: src/render/bsdf.rs `ggx_sample_visible`
fn ggx_sample_visible(wo: vec3<f32>, alpha: f32, u: vec2<f32>) -> vec3<f32> {
    let vh = normalize(vec3<f32>(alpha * wo.x, alpha * wo.y, wo.z));
    let lensq = vh.x * vh.x + vh.y * vh.y;
    var t1 = vec3<f32>(1.0, 0.0, 0.0);
    if lensq > 0.0 {
        t1 = vec3<f32>(-vh.y, vh.x, 0.0) / sqrt(lensq);
    }
    let t2 = cross(vh, t1);
    let r = sqrt(u.x);
    let phi = 2.0 * PI * u.y;
    let p1 = r * cos(phi);
    let s = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - s) * sqrt(max(1.0 - p1 * p1, 0.0)) + s * r * sin(phi);
    let nh = p1 * t1 + p2 * t2 + sqrt(max(1.0 - p1 * p1 - p2 * p2, 0.0)) * vh;
    return normalize(vec3<f32>(alpha * nh.x, alpha * nh.y, max(nh.z, 1e-6)));
}

// (F, signed cosine of the refracted ray, eta_it, eta_ti).
// mirror: src/render/bsdf.rs `fresnel_dielectric`
fn fresnel_dielectric(cos_i: f32, eta: f32) -> vec4<f32> {
    let outside = cos_i >= 0.0;
    let eta_it = select(1.0 / eta, eta, outside);
    let eta_ti = 1.0 / eta_it;
    let cos_t_sqr = 1.0 - eta_ti * eta_ti * (1.0 - cos_i * cos_i);
    if cos_t_sqr <= 0.0 {
        return vec4<f32>(1.0, 0.0, eta_it, eta_ti);
    }
    let ci = abs(cos_i);
    let ct = sqrt(cos_t_sqr);
    let a_s = (ci - eta_it * ct) / (ci + eta_it * ct);
    let a_p = (ct - eta_it * ci) / (ct + eta_it * ci);
    let f = 0.5 * (a_s * a_s + a_p * a_p);
    return vec4<f32>(f, select(ct, -ct, outside), eta_it, eta_ti);
}
