// BSDFs in the local shading frame (normal = +Z). mirror: src/render/bsdf.rs

struct BsdfSample {
    wi: vec3<f32>,
    weight: vec3<f32>,
    pdf: f32,
    delta: bool,
    eta: f32,
    valid: bool,
    // LOBE_DIFFUSE, LOBE_GLOSSY or LOBE_TRANSMISSION, for the path's bounce limits.
    lobe: u32,
}

fn no_sample() -> BsdfSample {
    return BsdfSample(vec3<f32>(0.0), vec3<f32>(0.0), 0.0, false, 1.0, false, LOBE_DIFFUSE);
}

// mirror: src/render/bsdf.rs `lobe_of`
fn lobe_of(wo: vec3<f32>, wi: vec3<f32>, diffuse: bool) -> u32 {
    if wo.z * wi.z < 0.0 {
        return LOBE_TRANSMISSION;
    }
    return select(LOBE_GLOSSY, LOBE_DIFFUSE, diffuse);
}

// mirror: src/render/bsdf.rs `bsdf_is_delta`
fn bsdf_is_delta(m: Material) -> bool {
    if m.kind == MAT_PBR {
        return m.roughness == 0.0 && (1.0 - m.metallic) * (1.0 - m.transmission) == 0.0
            && max(max(m.sheen_color.x, m.sheen_color.y), m.sheen_color.z) == 0.0
            && (m.clearcoat == 0.0 || m.clearcoat_roughness == 0.0);
    }
    return m.kind == MAT_CONDUCTOR || m.kind == MAT_DIELECTRIC;
}

// Whether bsdf_sample reads its lobe number. mirror: src/render/bsdf.rs `bsdf_draws_lobe`
fn bsdf_draws_lobe(m: Material) -> bool {
    return m.kind == MAT_DIELECTRIC || m.kind == MAT_PBR;
}

// Whether bsdf_sample reads its direction pair.
// mirror: src/render/bsdf.rs `bsdf_draws_direction`
fn bsdf_draws_direction(m: Material) -> bool {
    return m.kind != MAT_CONDUCTOR && m.kind != MAT_DIELECTRIC;
}

// mirror: src/render/bsdf.rs `bsdf_is_two_sided`
fn bsdf_is_two_sided(m: Material) -> bool {
    if m.kind == MAT_DIELECTRIC {
        return false;
    }
    if m.kind == MAT_PBR {
        return m.transmission == 0.0 || (m.flags & MAT_THIN_WALLED) != 0u;
    }
    return true;
}

// mirror: src/render/bsdf.rs `bsdf_transmits`
fn bsdf_transmits(m: Material) -> bool {
    if m.kind == MAT_DIELECTRIC {
        return true;
    }
    return m.kind == MAT_PBR && m.transmission > 0.0;
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
    if m.kind == MAT_PBR {
        return pbr_eval(m, wo, wi);
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
    if m.kind == MAT_PBR {
        return pbr_pdf(m, wo, wi);
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
        return BsdfSample(wi, m.albedo, pdf, false, 1.0, true, LOBE_DIFFUSE);
    }
    if m.kind == MAT_CONDUCTOR {
        if wo.z <= 0.0 {
            return no_sample();
        }
        return BsdfSample(vec3<f32>(-wo.x, -wo.y, wo.z), m.albedo, 1.0, true, 1.0, true, LOBE_GLOSSY);
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
        return BsdfSample(wi, m.albedo * ggx_g1(wi, alpha), pdf, false, 1.0, true, LOBE_GLOSSY);
    }
    if m.kind == MAT_DIELECTRIC {
        let fr = fresnel_dielectric(wo.z, m.ior);
        let f = fr.x;
        if u_lobe < f {
            return BsdfSample(vec3<f32>(-wo.x, -wo.y, wo.z), vec3<f32>(1.0), f, true, 1.0, true, LOBE_GLOSSY);
        }
        let eta_ti = fr.w;
        let wi = vec3<f32>(-eta_ti * wo.x, -eta_ti * wo.y, fr.y);
        return BsdfSample(wi, vec3<f32>(eta_ti * eta_ti), 1.0 - f, true, fr.z, true, LOBE_TRANSMISSION);
    }
    if m.kind == MAT_PBR {
        return pbr_sample(m, wo, u_lobe, u);
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

// ---------------------------------------------------------------------------------------
// pbr: the glTF metallic-roughness material. mirror: src/render/bsdf.rs (see there).

// mirror: src/render/bsdf.rs `mean3`
fn mean3(c: vec3<f32>) -> f32 {
    return (c.x + c.y + c.z) * (1.0 / 3.0);
}

// mirror: src/render/bsdf.rs `fresnel_schlick`
fn fresnel_schlick(f0: vec3<f32>, c: f32) -> vec3<f32> {
    let k = clamp(1.0 - c, 0.0, 1.0);
    let k5 = k * k * k * k * k;
    return f0 + (vec3<f32>(1.0) - f0) * k5;
}

// mirror: src/render/bsdf.rs `pbr_fresnel`
fn pbr_fresnel(m: Material, cos_i: f32) -> vec3<f32> {
    if (m.flags & MAT_SPEC_GLOSS) != 0u {
        return fresnel_schlick(m.specular_color, abs(cos_i)) * m.specular;
    }
    let f = fresnel_dielectric(cos_i, m.ior).x;
    let r = (m.ior - 1.0) / (m.ior + 1.0);
    let k = 1.0 - abs(cos_i);
    let k5 = k * k * k * k * k;
    let tint = (m.specular_color - vec3<f32>(1.0)) * (r * r * (1.0 - k5));
    return clamp(m.specular * (vec3<f32>(f) + tint), vec3<f32>(0.0), vec3<f32>(1.0));
}

// (metal, dielectric reflection, transmission, diffuse).
// mirror: src/render/bsdf.rs `pbr_lobe_pdfs`
fn pbr_lobe_pdfs(m: Material, wo: vec3<f32>) -> vec4<f32> {
    var fd = mean3(pbr_fresnel(m, wo.z));
    if m.roughness > 0.0 && m.specular > 0.0 {
        fd = clamp(fd, 0.05, 0.95);
    }
    let base = mean3(m.albedo);
    let dielectric = 1.0 - m.metallic;
    let outside = select(0.0, 1.0, wo.z > 0.0);
    let w = vec4<f32>(
        outside * m.metallic * mean3(fresnel_schlick(m.albedo, wo.z)),
        dielectric * fd,
        dielectric * (1.0 - fd) * m.transmission * base,
        outside * dielectric * (1.0 - fd) * (1.0 - m.transmission) * base,
    );
    let sum = w.x + w.y + w.z + w.w;
    if sum > 0.0 {
        return w / sum;
    }
    return vec4<f32>(0.0);
}

// mirror: src/render/bsdf.rs `pbr_half_vector`
fn pbr_half_vector(wo: vec3<f32>, wi: vec3<f32>, etap: f32, transmit: bool) -> vec3<f32> {
    let v = select(wo + wi, wo + wi * etap, transmit);
    let len2 = dot(v, v);
    let h = select(vec3<f32>(0.0), v * inverseSqrt(len2), len2 > 0.0);
    return select(h, -h, h.z < 0.0);
}

// mirror: src/render/bsdf.rs `pbr_etap`
fn pbr_etap(m: Material, wo: vec3<f32>) -> f32 {
    return select(1.0 / m.ior, m.ior, wo.z > 0.0);
}

// mirror: src/render/bsdf.rs `ggx_g1_abs`
fn ggx_g1_abs(w: vec3<f32>, h: vec3<f32>, alpha: f32) -> f32 {
    if dot(w, h) * w.z <= 0.0 {
        return 0.0;
    }
    let z = abs(w.z);
    let tan2 = (w.x * w.x + w.y * w.y) / (z * z);
    return 2.0 / (1.0 + sqrt(1.0 + alpha * alpha * tan2));
}

// mirror: src/render/bsdf.rs `ggx_visible_pdf`
fn ggx_visible_pdf(wo: vec3<f32>, h: vec3<f32>, alpha: f32) -> f32 {
    return ggx_g1_abs(wo, h, alpha) * ggx_d(h, alpha) * abs(dot(wo, h)) / abs(wo.z);
}

// The base layer. mirror: src/render/bsdf.rs `base_eval`
fn base_eval(m: Material, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    if wo.z == 0.0 || wi.z == 0.0 {
        return vec3<f32>(0.0);
    }
    let dielectric = 1.0 - m.metallic;
    let same_side = wo.z * wi.z > 0.0;
    var f = vec3<f32>(0.0);
    if same_side && wo.z > 0.0 {
        let weight = dielectric * (1.0 - m.transmission);
        if weight > 0.0 {
            let fo = vec3<f32>(1.0) - pbr_fresnel(m, wo.z);
            let fi = vec3<f32>(1.0) - pbr_fresnel(m, wi.z);
            f += m.albedo * fo * fi * (weight * FRAC_1_PI * wi.z);
        }
    }
    if m.roughness == 0.0 {
        return f;
    }
    let alpha = ggx_alpha(m.roughness);
    if same_side {
        let h = pbr_half_vector(wo, wi, 1.0, false);
        let micro = ggx_d(h, alpha) * ggx_g1_abs(wo, h, alpha) * ggx_g1_abs(wi, h, alpha)
            / (4.0 * abs(wo.z));
        if wo.z > 0.0 && m.metallic > 0.0 {
            f += fresnel_schlick(m.albedo, dot(wo, h)) * (m.metallic * micro);
        }
        f += pbr_fresnel(m, dot(wo, h)) * (dielectric * micro);
        return f;
    }
    let t = dielectric * m.transmission;
    if t == 0.0 {
        return f;
    }
    if (m.flags & MAT_THIN_WALLED) != 0u {
        let wr = vec3<f32>(wi.x, wi.y, -wi.z);
        let h = pbr_half_vector(wo, wr, 1.0, false);
        let micro = ggx_d(h, alpha) * ggx_g1_abs(wo, h, alpha) * ggx_g1_abs(wr, h, alpha)
            / (4.0 * abs(wo.z));
        return f + m.albedo * (vec3<f32>(1.0) - pbr_fresnel(m, dot(wo, h))) * (t * micro);
    }
    let etap = pbr_etap(m, wo);
    let h = pbr_half_vector(wo, wi, etap, true);
    let oh = dot(wo, h);
    let ih = dot(wi, h);
    if oh * wo.z <= 0.0 || ih * wi.z <= 0.0 {
        return f;
    }
    let denom = ih + oh / etap;
    let jac = abs(ih * oh) / (denom * denom * abs(wo.z));
    let micro = ggx_d(h, alpha) * ggx_g1_abs(wo, h, alpha) * ggx_g1_abs(wi, h, alpha) * jac;
    return f + m.albedo * (vec3<f32>(1.0) - pbr_fresnel(m, oh)) * (t * micro / (etap * etap));
}

// mirror: src/render/bsdf.rs `base_pdf`
fn base_pdf(m: Material, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    if wo.z == 0.0 || wi.z == 0.0 {
        return 0.0;
    }
    let p = pbr_lobe_pdfs(m, wo);
    let same_side = wo.z * wi.z > 0.0;
    var pdf = 0.0;
    if same_side && wo.z > 0.0 {
        pdf += p.w * cosine_hemisphere_pdf(wi.z);
    }
    if m.roughness == 0.0 {
        return pdf;
    }
    let alpha = ggx_alpha(m.roughness);
    if same_side {
        let h = pbr_half_vector(wo, wi, 1.0, false);
        let reflect = ggx_visible_pdf(wo, h, alpha) / (4.0 * abs(dot(wo, h)));
        return pdf + (p.x + p.y) * reflect;
    }
    if (m.flags & MAT_THIN_WALLED) != 0u {
        let wr = vec3<f32>(wi.x, wi.y, -wi.z);
        let h = pbr_half_vector(wo, wr, 1.0, false);
        return pdf + p.z * ggx_visible_pdf(wo, h, alpha) / (4.0 * abs(dot(wo, h)));
    }
    let etap = pbr_etap(m, wo);
    let h = pbr_half_vector(wo, wi, etap, true);
    let oh = dot(wo, h);
    let ih = dot(wi, h);
    if oh * wo.z <= 0.0 || ih * wi.z <= 0.0 {
        return pdf;
    }
    let denom = ih + oh / etap;
    return pdf + p.z * ggx_visible_pdf(wo, h, alpha) * abs(ih) / (denom * denom);
}

// mirror: src/render/bsdf.rs `base_sample`
fn base_sample(m: Material, wo: vec3<f32>, u_lobe: f32, u: vec2<f32>) -> BsdfSample {
    if wo.z == 0.0 {
        return no_sample();
    }
    let p = pbr_lobe_pdfs(m, wo);
    var lobe = 3u;
    if u_lobe < p.x {
        lobe = 0u;
    } else if u_lobe < p.x + p.y {
        lobe = 1u;
    } else if u_lobe < p.x + p.y + p.z {
        lobe = 2u;
    } else if !(p.w > 0.0) {
        return no_sample();
    }
    let dielectric = 1.0 - m.metallic;
    let thin = (m.flags & MAT_THIN_WALLED) != 0u;
    if m.roughness == 0.0 && lobe != 3u {
        let c = wo.z;
        let mirrored = vec3<f32>(-wo.x, -wo.y, wo.z);
        if lobe == 0u {
            return BsdfSample(mirrored, fresnel_schlick(m.albedo, c) * m.metallic / p.x, p.x, true, 1.0, true, LOBE_GLOSSY);
        }
        if lobe == 1u {
            return BsdfSample(mirrored, pbr_fresnel(m, c) * dielectric / p.y, p.y, true, 1.0, true, LOBE_GLOSSY);
        }
        let trans = m.albedo * (vec3<f32>(1.0) - pbr_fresnel(m, c)) * (dielectric * m.transmission);
        if thin {
            return BsdfSample(-wo, trans / p.z, p.z, true, 1.0, true, LOBE_TRANSMISSION);
        }
        let fr = fresnel_dielectric(c, m.ior);
        if fr.x >= 1.0 {
            return no_sample();
        }
        let eta_ti = fr.w;
        let wi = vec3<f32>(-eta_ti * wo.x, -eta_ti * wo.y, fr.y);
        return BsdfSample(wi, trans * (eta_ti * eta_ti) / p.z, p.z, true, fr.z, true, LOBE_TRANSMISSION);
    }
    var wi: vec3<f32>;
    if lobe == 3u {
        wi = sample_cosine_hemisphere(u);
    } else {
        let alpha = ggx_alpha(m.roughness);
        let side = select(-1.0, 1.0, wo.z > 0.0);
        var h = ggx_sample_visible(wo * side, alpha, u) * side;
        h = select(h, -h, h.z < 0.0);
        let reflected = 2.0 * dot(wo, h) * h - wo;
        if lobe < 2u || thin {
            if reflected.z * wo.z <= 0.0 {
                return no_sample();
            }
            wi = select(vec3<f32>(reflected.x, reflected.y, -reflected.z), reflected, lobe < 2u);
        } else {
            let etap = pbr_etap(m, wo);
            let oh = dot(wo, h);
            let n = select(h, -h, oh < 0.0);
            let cos_i = abs(oh);
            let sin2_t = max(1.0 - cos_i * cos_i, 0.0) / (etap * etap);
            if sin2_t >= 1.0 {
                return no_sample();
            }
            let cos_t = sqrt(1.0 - sin2_t);
            wi = -wo / etap + (cos_i / etap - cos_t) * n;
            if wi.z * wo.z >= 0.0 {
                return no_sample();
            }
        }
    }
    let pdf = base_pdf(m, wo, wi);
    if !(pdf > 0.0) {
        return no_sample();
    }
    var eta = 1.0;
    if wo.z * wi.z < 0.0 && !thin {
        eta = pbr_etap(m, wo);
    }
    return BsdfSample(wi, base_eval(m, wo, wi) / pdf, pdf, false, eta, true, lobe_of(wo, wi, lobe == 3u));
}

// The colour of m's diffuse lobe (Cycles' Diffuse Color pass).
// mirror: src/render/bsdf.rs `diffuse_color`
fn diffuse_color(m: Material) -> vec3<f32> {
    if m.kind == MAT_DIFFUSE {
        return m.albedo;
    }
    if m.kind == MAT_PBR {
        let base = (1.0 - m.metallic) * (1.0 - m.transmission);
        let coat = 1.0 - m.clearcoat * coat_fresnel(1.0);
        return m.albedo * (vec3<f32>(1.0) - pbr_fresnel(m, 1.0)) * (base * coat);
    }
    return vec3<f32>(0.0);
}

// The sheen and clear-coat layers over the pbr base (src/render/bsdf.rs says how they
// stack).

// mirror: src/render/bsdf.rs `has_layers`
fn has_layers(m: Material) -> bool {
    return m.clearcoat > 0.0 || max(max(m.sheen_color.x, m.sheen_color.y), m.sheen_color.z) > 0.0;
}

// mirror: src/render/bsdf.rs `coat_fresnel`
fn coat_fresnel(c: f32) -> f32 {
    let k = clamp(1.0 - abs(c), 0.0, 1.0);
    let k5 = k * k * k * k * k;
    return 0.04 + 0.96 * k5;
}

// (coat, sheen) factors of light crossing the layers along w.
// mirror: src/render/bsdf.rs `layers_pass`
fn layers_pass(m: Material, w: vec3<f32>) -> vec2<f32> {
    let coat = (1.0 - m.clearcoat * coat_fresnel(dot(m.coat_normal, w))) / sqrt(1.0 - m.clearcoat * COAT_FRESNEL_AVERAGE);
    let s = max(max(m.sheen_color.x, m.sheen_color.y), m.sheen_color.z);
    var sheen = 1.0;
    if s > 0.0 {
        sheen = 1.0 - s * sheen_albedo(abs(w.z), m.sheen_roughness);
    }
    return vec2<f32>(coat, sheen);
}

// mirror: src/render/bsdf.rs `to_coat`
fn to_coat(m: Material, w: vec3<f32>) -> vec3<f32> {
    let f = onb_from_normal(m.coat_normal);
    return vec3<f32>(dot(w, f[0]), dot(w, f[1]), dot(w, m.coat_normal));
}

// (f |cos wi|, pdf) of a rough clear coat. mirror: src/render/bsdf.rs `coat_reflect`
fn coat_reflect(m: Material, wo: vec3<f32>, wi: vec3<f32>) -> vec2<f32> {
    if m.clearcoat == 0.0 || m.clearcoat_roughness == 0.0 || wo.z <= 0.0 || wi.z <= 0.0 {
        return vec2<f32>(0.0);
    }
    let o = to_coat(m, wo);
    let i = to_coat(m, wi);
    if o.z <= 0.0 || i.z <= 0.0 {
        return vec2<f32>(0.0);
    }
    let alpha = ggx_alpha(m.clearcoat_roughness);
    let h = normalize(o + i);
    let d = ggx_d(h, alpha);
    let f = m.clearcoat * coat_fresnel(dot(o, h)) * d * ggx_g1(o, alpha) * ggx_g1(i, alpha)
        * wi.z / (4.0 * o.z * i.z);
    return vec2<f32>(f, ggx_g1(o, alpha) * d / (4.0 * o.z));
}

// (coat, sheen, base) probabilities at wo. mirror: src/render/bsdf.rs `layer_pdfs`
fn layer_pdfs(m: Material, wo: vec3<f32>) -> vec3<f32> {
    let base = pbr_lobe_pdfs(m, wo);
    let base_reflects = select(0.0, 1.0, base.x + base.y + base.z + base.w > 0.0);
    if wo.z <= 0.0 {
        return vec3<f32>(0.0, 0.0, base_reflects);
    }
    var f = coat_fresnel(dot(m.coat_normal, wo));
    if m.clearcoat_roughness > 0.0 {
        f = clamp(f, 0.25, 0.9);
    }
    let coat = m.clearcoat * f;
    let s = max(max(m.sheen_color.x, m.sheen_color.y), m.sheen_color.z);
    var sheen = 0.0;
    if s > 0.0 {
        sheen = (1.0 - coat) * s * sheen_albedo(wo.z, m.sheen_roughness);
    }
    let w = vec3<f32>(coat, sheen, (1.0 - coat - sheen) * base_reflects);
    let sum = w.x + w.y + w.z;
    if sum > 0.0 {
        return w / sum;
    }
    return vec3<f32>(0.0);
}

// mirror: src/render/bsdf.rs `pbr_eval`
fn pbr_eval(m: Material, wo: vec3<f32>, wi: vec3<f32>) -> vec3<f32> {
    let base = base_eval(m, wo, wi);
    if !has_layers(m) {
        return base;
    }
    let po = layers_pass(m, wo);
    let pi = layers_pass(m, wi);
    let sheen = sheen_reflect(m.sheen_color, m.sheen_roughness, wo, wi);
    let under = sheen + base * min(po.y, pi.y);
    return under * (po.x * pi.x) + vec3<f32>(coat_reflect(m, wo, wi).x);
}

// mirror: src/render/bsdf.rs `pbr_pdf`
fn pbr_pdf(m: Material, wo: vec3<f32>, wi: vec3<f32>) -> f32 {
    if !has_layers(m) {
        return base_pdf(m, wo, wi);
    }
    let p = layer_pdfs(m, wo);
    var sheen = 0.0;
    if wo.z > 0.0 && wi.z > 0.0 {
        sheen = cosine_hemisphere_pdf(wi.z);
    }
    return p.x * coat_reflect(m, wo, wi).y + p.y * sheen + p.z * base_pdf(m, wo, wi);
}

// mirror: src/render/bsdf.rs `pbr_sample`
fn pbr_sample(m: Material, wo: vec3<f32>, u_lobe: f32, u: vec2<f32>) -> BsdfSample {
    if !has_layers(m) {
        return base_sample(m, wo, u_lobe, u);
    }
    let p = layer_pdfs(m, wo);
    var wi: vec3<f32>;
    var lobe: u32;
    if u_lobe < p.x {
        let f = onb_from_normal(m.coat_normal);
        let o = to_coat(m, wo);
        if m.clearcoat_roughness == 0.0 {
            let mirrored = 2.0 * dot(wo, m.coat_normal) * m.coat_normal - wo;
            if o.z <= 0.0 || mirrored.z <= 0.0 {
                return no_sample();
            }
            return BsdfSample(mirrored, vec3<f32>(m.clearcoat * coat_fresnel(o.z) / p.x), p.x, true, 1.0, true, LOBE_GLOSSY);
        }
        if o.z <= 0.0 {
            return no_sample();
        }
        let h = ggx_sample_visible(o, ggx_alpha(m.clearcoat_roughness), u);
        let i = 2.0 * dot(o, h) * h - o;
        wi = i.x * f[0] + i.y * f[1] + i.z * m.coat_normal;
        lobe = lobe_of(wo, wi, false);
    } else if u_lobe < p.x + p.y {
        wi = sample_cosine_hemisphere(u);
        lobe = lobe_of(wo, wi, true);
    } else {
        if p.z <= 0.0 {
            return no_sample();
        }
        let u_base = min((u_lobe - p.x - p.y) / p.z, ONE_MINUS_EPSILON);
        let bs = base_sample(m, wo, u_base, u);
        if !bs.valid {
            return no_sample();
        }
        if bs.delta {
            let po = layers_pass(m, wo);
            let pi = layers_pass(m, bs.wi);
            let through = po.x * pi.x * min(po.y, pi.y);
            return BsdfSample(bs.wi, bs.weight * (through / p.z), bs.pdf * p.z, true, bs.eta, true, bs.lobe);
        }
        wi = bs.wi;
        lobe = bs.lobe;
    }
    let pdf = pbr_pdf(m, wo, wi);
    if !(pdf > 0.0) {
        return no_sample();
    }
    var eta = 1.0;
    if wo.z * wi.z < 0.0 && (m.flags & MAT_THIN_WALLED) == 0u {
        eta = pbr_etap(m, wo);
    }
    return BsdfSample(wi, pbr_eval(m, wo, wi) / pdf, pdf, false, eta, true, lobe);
}
