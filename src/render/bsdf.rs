//! The BSDFs, in the local shading frame (the normal is +Z).
//!
//! Each material kind is three functions, `eval` (f times |cos|), `pdf` and `sample`,
//! dispatched by [`bsdf_eval`], [`bsdf_pdf`] and [`bsdf_sample`]; adding a material means
//! adding one arm to each. Two-sided kinds expect the caller to have turned the frame
//! towards `wo` (`wo.z > 0`); the dielectric sees both sides. Every function has a WGSL
//! twin of the same name in `shaders/bsdf.wgsl`.

use super::sampling::{ONE_MINUS_EPSILON, cosine_hemisphere_pdf, sample_cosine_hemisphere};
use super::sheen::{sheen_albedo, sheen_reflect};
use crate::math::onb_from_normal;
use crate::scene::material::{MAT_SPEC_GLOSS, MAT_THIN_WALLED};
use crate::scene::{Material, MaterialKind};
use glam::{Vec2, Vec3};
use std::f32::consts::{FRAC_1_PI, PI};

/// A sampled direction with its throughput weight `f |cos| / pdf`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample {
    pub wi: Vec3,
    pub weight: Vec3,
    /// Solid-angle pdf; for delta lobes the probability of the chosen lobe.
    pub pdf: f32,
    pub delta: bool,
    /// Relative index of refraction crossed (1 for reflection), for Russian roulette.
    pub eta: f32,
    /// The kind of scattering drawn ([`LOBE_DIFFUSE`], [`LOBE_GLOSSY`] or
    /// [`LOBE_TRANSMISSION`]), which the path counts against its bounce limits.
    pub lobe: u32,
}

/// [`BsdfSample::lobe`]: a diffuse reflection (the diffuse and sheen lobes), as Cycles
/// labels them for its `diffuse_bounces`. The shaders get these from
/// `render::gpu::shader::shared_constants`.
pub const LOBE_DIFFUSE: u32 = 0;
/// A glossy or mirror reflection (the specular lobes and the clear coat): `glossy_bounces`.
pub const LOBE_GLOSSY: u32 = 1;
/// A direction through the surface, rough or smooth: `transmission_bounces`.
pub const LOBE_TRANSMISSION: u32 = 2;

/// The lobe kind of a direction `wi` drawn for `wo` from a lobe that is diffuse or not:
/// [`LOBE_TRANSMISSION`] where it crosses the surface. mirror: shaders/bsdf.wgsl `lobe_of`
pub fn lobe_of(wo: Vec3, wi: Vec3, diffuse: bool) -> u32 {
    if wo.z * wi.z < 0.0 {
        LOBE_TRANSMISSION
    } else if diffuse {
        LOBE_DIFFUSE
    } else {
        LOBE_GLOSSY
    }
}

/// Whether the material's BSDF is a Dirac delta (next event estimation cannot help). A
/// smooth `pbr` material is, unless part of it is diffuse.
/// mirror: shaders/bsdf.wgsl `bsdf_is_delta`
pub fn bsdf_is_delta(m: &Material) -> bool {
    match m.kind {
        MaterialKind::CONDUCTOR | MaterialKind::DIELECTRIC => true,
        MaterialKind::PBR => {
            m.roughness == 0.0
                && (1.0 - m.metallic) * (1.0 - m.transmission) == 0.0
                && m.sheen_color.max_element() == 0.0
                && (m.clearcoat == 0.0 || m.clearcoat_roughness == 0.0)
        }
        _ => false,
    }
}

/// Whether [`bsdf_sample`] reads its lobe number for the material: a dielectric's choice
/// of reflection or refraction, a `pbr` material's lobe. The path draws the number only
/// then (the numbers are counter-based, so a draw skipped changes no other).
/// mirror: shaders/bsdf.wgsl `bsdf_draws_lobe`
pub fn bsdf_draws_lobe(m: &Material) -> bool {
    matches!(m.kind, MaterialKind::DIELECTRIC | MaterialKind::PBR)
}

/// Whether [`bsdf_sample`] reads its pair of direction numbers: every material but a
/// smooth conductor and a smooth dielectric, whose directions follow from `wo`.
/// mirror: shaders/bsdf.wgsl `bsdf_draws_direction`
pub fn bsdf_draws_direction(m: &Material) -> bool {
    !matches!(m.kind, MaterialKind::CONDUCTOR | MaterialKind::DIELECTRIC)
}

/// Whether the BSDF is two-sided: the caller turns the frame towards `wo`. A dielectric,
/// and a `pbr` material that transmits into a volume, tell entering from leaving instead.
/// mirror: shaders/bsdf.wgsl `bsdf_is_two_sided`
pub fn bsdf_is_two_sided(m: &Material) -> bool {
    match m.kind {
        MaterialKind::DIELECTRIC => false,
        MaterialKind::PBR => m.transmission == 0.0 || m.flags & MAT_THIN_WALLED != 0,
        _ => true,
    }
}

/// Whether light may cross the surface: a dielectric, or a `pbr` material with
/// transmission. Next event estimation then samples lights on both sides of it.
/// mirror: shaders/bsdf.wgsl `bsdf_transmits`
pub fn bsdf_transmits(m: &Material) -> bool {
    match m.kind {
        MaterialKind::DIELECTRIC => true,
        MaterialKind::PBR => m.transmission > 0.0,
        _ => false,
    }
}

/// f(wo, wi) |cos(wi)|. mirror: shaders/bsdf.wgsl `bsdf_eval`
pub fn bsdf_eval(m: &Material, wo: Vec3, wi: Vec3) -> Vec3 {
    match m.kind {
        MaterialKind::DIFFUSE => {
            if wo.z <= 0.0 || wi.z <= 0.0 {
                return Vec3::ZERO;
            }
            m.albedo * (FRAC_1_PI * wi.z)
        }
        MaterialKind::ROUGH_CONDUCTOR => {
            if wo.z <= 0.0 || wi.z <= 0.0 {
                return Vec3::ZERO;
            }
            let alpha = ggx_alpha(m.roughness);
            let h = (wo + wi).normalize();
            let g = ggx_g1(wo, alpha) * ggx_g1(wi, alpha);
            m.albedo * (ggx_d(h, alpha) * g / (4.0 * wo.z))
        }
        MaterialKind::PBR => pbr_eval(m, wo, wi),
        // Delta lobes (and no other kind exists).
        _ => Vec3::ZERO,
    }
}

/// The solid-angle pdf with which `bsdf_sample` draws `wi`. mirror: shaders/bsdf.wgsl `bsdf_pdf`
pub fn bsdf_pdf(m: &Material, wo: Vec3, wi: Vec3) -> f32 {
    match m.kind {
        MaterialKind::DIFFUSE => {
            if wo.z <= 0.0 {
                return 0.0;
            }
            cosine_hemisphere_pdf(wi.z)
        }
        MaterialKind::ROUGH_CONDUCTOR => {
            if wo.z <= 0.0 || wi.z <= 0.0 {
                return 0.0;
            }
            let alpha = ggx_alpha(m.roughness);
            let h = (wo + wi).normalize();
            // Visible-normal pdf D_wo(h) = G1(wo) max(0, wo.h) D(h) / wo.z, times the
            // reflection Jacobian 1 / (4 wo.h).
            ggx_g1(wo, alpha) * ggx_d(h, alpha) / (4.0 * wo.z)
        }
        MaterialKind::PBR => pbr_pdf(m, wo, wi),
        _ => 0.0,
    }
}

/// Draws `wi` given `wo`, from one number for the lobe choice and two for the direction.
/// mirror: shaders/bsdf.wgsl `bsdf_sample`
pub fn bsdf_sample(m: &Material, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
    match m.kind {
        MaterialKind::DIFFUSE => {
            if wo.z <= 0.0 {
                return None;
            }
            let wi = sample_cosine_hemisphere(u);
            let pdf = cosine_hemisphere_pdf(wi.z);
            (pdf > 0.0).then_some(BsdfSample {
                wi,
                weight: m.albedo,
                pdf,
                delta: false,
                eta: 1.0,
                lobe: LOBE_DIFFUSE,
            })
        }
        MaterialKind::CONDUCTOR => {
            if wo.z <= 0.0 {
                return None;
            }
            Some(BsdfSample {
                wi: Vec3::new(-wo.x, -wo.y, wo.z),
                weight: m.albedo,
                pdf: 1.0,
                delta: true,
                eta: 1.0,
                lobe: LOBE_GLOSSY,
            })
        }
        MaterialKind::ROUGH_CONDUCTOR => {
            if wo.z <= 0.0 {
                return None;
            }
            let alpha = ggx_alpha(m.roughness);
            let h = ggx_sample_visible(wo, alpha, u);
            let wi = 2.0 * wo.dot(h) * h - wo;
            if wi.z <= 0.0 {
                return None;
            }
            Some(BsdfSample {
                wi,
                weight: m.albedo * ggx_g1(wi, alpha),
                pdf: ggx_g1(wo, alpha) * ggx_d(h, alpha) / (4.0 * wo.z),
                delta: false,
                eta: 1.0,
                lobe: LOBE_GLOSSY,
            })
        }
        MaterialKind::DIELECTRIC => {
            let (f, cos_t, eta_it, eta_ti) = fresnel_dielectric(wo.z, m.ior);
            if u_lobe < f {
                Some(BsdfSample {
                    wi: Vec3::new(-wo.x, -wo.y, wo.z),
                    weight: Vec3::ONE,
                    pdf: f,
                    delta: true,
                    eta: 1.0,
                    lobe: LOBE_GLOSSY,
                })
            } else {
                Some(BsdfSample {
                    wi: Vec3::new(-eta_ti * wo.x, -eta_ti * wo.y, cos_t),
                    // Radiance is scaled by the squared ratio of the indices across the
                    // boundary (pbrt-v4 §9.5.2; Mitsuba's `dielectric`).
                    weight: Vec3::splat(eta_ti * eta_ti),
                    pdf: 1.0 - f,
                    delta: true,
                    eta: eta_it,
                    lobe: LOBE_TRANSMISSION,
                })
            }
        }
        MaterialKind::PBR => pbr_sample(m, wo, u_lobe, u),
        _ => None,
    }
}

/// GGX alpha from perceptual roughness, kept off zero where the distribution degenerates.
/// mirror: shaders/bsdf.wgsl `ggx_alpha`
pub fn ggx_alpha(roughness: f32) -> f32 {
    (roughness * roughness).max(1e-3)
}

/// The GGX (Trowbridge–Reitz) normal distribution D(h). mirror: shaders/bsdf.wgsl `ggx_d`
pub fn ggx_d(h: Vec3, alpha: f32) -> f32 {
    if h.z <= 0.0 {
        return 0.0;
    }
    // (h.z^2 (a^2 - 1) + 1) rewritten for a unit h, which avoids cancellation near the peak.
    let a2 = alpha * alpha;
    let d = h.x * h.x + h.y * h.y + a2 * h.z * h.z;
    a2 / (PI * d * d)
}

/// Smith's masking function G1 for GGX. mirror: shaders/bsdf.wgsl `ggx_g1`
pub fn ggx_g1(w: Vec3, alpha: f32) -> f32 {
    if w.z <= 0.0 {
        return 0.0;
    }
    let tan2 = (w.x * w.x + w.y * w.y) / (w.z * w.z);
    2.0 / (1.0 + (1.0 + alpha * alpha * tan2).sqrt())
}

/// A microfacet normal drawn from the distribution of normals visible from `wo`
/// (Heitz 2018, "Sampling the GGX Distribution of Visible Normals").
/// mirror: shaders/bsdf.wgsl `ggx_sample_visible`
pub fn ggx_sample_visible(wo: Vec3, alpha: f32, u: Vec2) -> Vec3 {
    let vh = Vec3::new(alpha * wo.x, alpha * wo.y, wo.z).normalize();
    let lensq = vh.x * vh.x + vh.y * vh.y;
    let t1 = if lensq > 0.0 {
        Vec3::new(-vh.y, vh.x, 0.0) / lensq.sqrt()
    } else {
        Vec3::X
    };
    let t2 = vh.cross(t1);
    let r = u.x.sqrt();
    let phi = 2.0 * PI * u.y;
    let p1 = r * phi.cos();
    let s = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * r * phi.sin();
    let nh = p1 * t1 + p2 * t2 + (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt() * vh;
    Vec3::new(alpha * nh.x, alpha * nh.y, nh.z.max(1e-6)).normalize()
}

/// Unpolarised Fresnel reflectance of a smooth dielectric boundary of relative index `eta`
/// (inside over outside) for incident cosine `cos_i` (negative from inside).
/// Returns (F, signed cosine of the refracted ray, eta_it, eta_ti), as Mitsuba's
/// `fresnel`. mirror: shaders/bsdf.wgsl `fresnel_dielectric`
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> (f32, f32, f32, f32) {
    let outside = cos_i >= 0.0;
    let eta_it = if outside { eta } else { 1.0 / eta };
    let eta_ti = 1.0 / eta_it;
    let cos_t_sqr = 1.0 - eta_ti * eta_ti * (1.0 - cos_i * cos_i);
    if cos_t_sqr <= 0.0 {
        return (1.0, 0.0, eta_it, eta_ti);
    }
    let ci = cos_i.abs();
    let ct = cos_t_sqr.sqrt();
    let a_s = (ci - eta_it * ct) / (ci + eta_it * ct);
    let a_p = (ct - eta_it * ci) / (ct + eta_it * ci);
    let f = 0.5 * (a_s * a_s + a_p * a_p);
    (f, if outside { -ct } else { ct }, eta_it, eta_ti)
}

// ---------------------------------------------------------------------------------------
// pbr: the glTF metallic-roughness material.
//
// A mix, by `metallic`, of a metal (GGX reflection with Schlick's Fresnel of the base
// colour) and a dielectric: GGX reflection with the exact Fresnel of `ior` (its F0 tinted
// by `specular_color` and the whole scaled by `specular`, as KHR_materials_specular says)
// over a base that is Lambertian (weight 1 - transmission) or transmits (weight
// transmission, tinted by the base colour): refracting into a volume, or straight through
// a thin wall. Roughness 0 makes the reflections and the transmission deltas.
//
// Appendix B of the glTF specification weighs the diffuse base by 1 - F(wo.h), which gains
// energy at grazing angles (a white base then reflects more than it receives); here the
// base is weighed by (1 - F(n.wo)) (1 - F(n.wi)), which keeps the BSDF reciprocal and
// below unit albedo, and is exactly Lambertian when `specular` is 0.
//
// The lobes are chosen by probabilities that depend on wo only (`pbr_lobe_pdfs`), so that
// `base_pdf` is the sum of the non-delta lobes' pdfs weighed by them.
//
// Over this base lie two optional layers, as glTF stacks them: KHR_materials_sheen (the
// Charlie lobe of `sheen.rs`, the base scaled by min(1 − S E(wo), 1 − S E(wi)) for S the
// sheen colour's largest channel), and over it KHR_materials_clearcoat (a GGX dielectric
// of IOR 1.5 about its own normal, the layers below scaled by (1 − c F(nc.wo))
// (1 − c F(nc.wi)) / (1 − c F_avg) for coat weight c). The extension's single factor
// 1 − c F(nc.wo) is not reciprocal; the product is, and its normalisation keeps the energy
// that a white diffuse base under the coat would otherwise lose.
// `pbr_eval`, `pbr_pdf` and `pbr_sample` are the whole stack; without layers, exactly
// the base.

/// The mean of a colour's channels.
/// mirror: shaders/bsdf.wgsl `mean3`
pub fn mean3(c: Vec3) -> f32 {
    (c.x + c.y + c.z) * (1.0 / 3.0)
}

/// Schlick's Fresnel of a conductor of reflectance `f0` at cosine `c`.
/// mirror: shaders/bsdf.wgsl `fresnel_schlick`
pub fn fresnel_schlick(f0: Vec3, c: f32) -> Vec3 {
    let k = (1.0 - c).clamp(0.0, 1.0);
    let k5 = k * k * k * k * k;
    f0 + (Vec3::ONE - f0) * k5
}

/// The dielectric layer's reflectance at incident cosine `cos_i` (negative from inside a
/// volume): the exact Fresnel of the IOR, with KHR_materials_specular's tint of F0 by
/// `specular_color` (fading out at grazing angles, where F90 is untinted) and its scale
/// by `specular`; for a specular-glossiness material ([`MAT_SPEC_GLOSS`]), Schlick's of
/// F0 = `specular_color`. mirror: shaders/bsdf.wgsl `pbr_fresnel`
pub fn pbr_fresnel(m: &Material, cos_i: f32) -> Vec3 {
    if m.flags & MAT_SPEC_GLOSS != 0 {
        return fresnel_schlick(m.specular_color, cos_i.abs()) * m.specular;
    }
    let f = fresnel_dielectric(cos_i, m.ior).0;
    let r = (m.ior - 1.0) / (m.ior + 1.0);
    let k = 1.0 - cos_i.abs();
    let k5 = k * k * k * k * k;
    let tint = (m.specular_color - Vec3::ONE) * (r * r * (1.0 - k5));
    (m.specular * (Vec3::splat(f) + tint)).clamp(Vec3::ZERO, Vec3::ONE)
}

/// The probabilities of choosing each lobe at `wo`: metal, dielectric reflection,
/// transmission, diffuse; from the lobes' approximate albedos. From inside a volume only
/// the interface (reflection and transmission) exists. All zero when nothing reflects.
/// mirror: shaders/bsdf.wgsl `pbr_lobe_pdfs`
pub fn pbr_lobe_pdfs(m: &Material, wo: Vec3) -> [f32; 4] {
    // A rough interface reflects and transmits at every angle (its microfacets see wo at
    // other angles than the macro surface), so neither lobe may be left unsampled.
    let fd = mean3(pbr_fresnel(m, wo.z));
    let fd = if m.roughness > 0.0 && m.specular > 0.0 {
        fd.clamp(0.05, 0.95)
    } else {
        fd
    };
    let base = mean3(m.albedo);
    let dielectric = 1.0 - m.metallic;
    let outside = if wo.z > 0.0 { 1.0 } else { 0.0 };
    let w = [
        outside * m.metallic * mean3(fresnel_schlick(m.albedo, wo.z)),
        dielectric * fd,
        dielectric * (1.0 - fd) * m.transmission * base,
        outside * dielectric * (1.0 - fd) * (1.0 - m.transmission) * base,
    ];
    let sum = w[0] + w[1] + w[2] + w[3];
    if sum > 0.0 {
        w.map(|x| x / sum)
    } else {
        [0.0; 4]
    }
}

/// The half vector of a reflection (`transmit` false) or of a refraction between `wo` and
/// `wi` (for relative IOR `etap`, wi's side over wo's), on the side of +Z.
/// mirror: shaders/bsdf.wgsl `pbr_half_vector`
pub fn pbr_half_vector(wo: Vec3, wi: Vec3, etap: f32, transmit: bool) -> Vec3 {
    let h = if transmit { wo + wi * etap } else { wo + wi };
    let h = h.normalize_or_zero();
    if h.z < 0.0 { -h } else { h }
}

/// The relative IOR a ray from `wo`'s side meets: ior entering from outside, its inverse
/// leaving. mirror: shaders/bsdf.wgsl `pbr_etap`
pub fn pbr_etap(m: &Material, wo: Vec3) -> f32 {
    if wo.z > 0.0 { m.ior } else { 1.0 / m.ior }
}

/// The base layer's f |cos wi| (its non-delta lobes). mirror: shaders/bsdf.wgsl `base_eval`
pub fn base_eval(m: &Material, wo: Vec3, wi: Vec3) -> Vec3 {
    if wo.z == 0.0 || wi.z == 0.0 {
        return Vec3::ZERO;
    }
    let dielectric = 1.0 - m.metallic;
    let same_side = wo.z * wi.z > 0.0;
    let mut f = Vec3::ZERO;
    if same_side && wo.z > 0.0 {
        // Diffuse base: (1 - F(n.wo)) (1 - F(n.wi)) base / pi.
        let weight = dielectric * (1.0 - m.transmission);
        if weight > 0.0 {
            let fo = Vec3::ONE - pbr_fresnel(m, wo.z);
            let fi = Vec3::ONE - pbr_fresnel(m, wi.z);
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
            / (4.0 * wo.z.abs());
        if wo.z > 0.0 && m.metallic > 0.0 {
            f += fresnel_schlick(m.albedo, wo.dot(h)) * (m.metallic * micro);
        }
        f += pbr_fresnel(m, wo.dot(h)) * (dielectric * micro);
        return f;
    }
    // Across the surface: the transmission lobe.
    let t = dielectric * m.transmission;
    if t == 0.0 {
        return f;
    }
    if m.flags & MAT_THIN_WALLED != 0 {
        // A thin wall: the reflection lobe mirrored through the surface.
        let wr = Vec3::new(wi.x, wi.y, -wi.z);
        let h = pbr_half_vector(wo, wr, 1.0, false);
        let micro = ggx_d(h, alpha) * ggx_g1_abs(wo, h, alpha) * ggx_g1_abs(wr, h, alpha)
            / (4.0 * wo.z.abs());
        return f + m.albedo * (Vec3::ONE - pbr_fresnel(m, wo.dot(h))) * (t * micro);
    }
    // Refraction into (or out of) a volume (Walter et al. 2007), in radiance units.
    let etap = pbr_etap(m, wo);
    let h = pbr_half_vector(wo, wi, etap, true);
    let (oh, ih) = (wo.dot(h), wi.dot(h));
    if oh * wo.z <= 0.0 || ih * wi.z <= 0.0 {
        return f;
    }
    let denom = ih + oh / etap;
    let jac = (ih * oh).abs() / (denom * denom * wo.z.abs());
    let micro = ggx_d(h, alpha) * ggx_g1_abs(wo, h, alpha) * ggx_g1_abs(wi, h, alpha) * jac;
    f + m.albedo * (Vec3::ONE - pbr_fresnel(m, oh)) * (t * micro / (etap * etap))
}

/// Smith's G1 for GGX seen along `w` against microfacet normal `h`: zero where `w` sees
/// the back of the microfacet. mirror: shaders/bsdf.wgsl `ggx_g1_abs`
pub fn ggx_g1_abs(w: Vec3, h: Vec3, alpha: f32) -> f32 {
    if w.dot(h) * w.z <= 0.0 {
        return 0.0;
    }
    let z = w.z.abs();
    let tan2 = (w.x * w.x + w.y * w.y) / (z * z);
    2.0 / (1.0 + (1.0 + alpha * alpha * tan2).sqrt())
}

/// The pdf of the visible normal `h` seen from `wo` (either side).
/// mirror: shaders/bsdf.wgsl `ggx_visible_pdf`
pub fn ggx_visible_pdf(wo: Vec3, h: Vec3, alpha: f32) -> f32 {
    ggx_g1_abs(wo, h, alpha) * ggx_d(h, alpha) * wo.dot(h).abs() / wo.z.abs()
}

/// The pdf with which `base_sample` draws `wi` through a non-delta lobe.
/// mirror: shaders/bsdf.wgsl `base_pdf`
pub fn base_pdf(m: &Material, wo: Vec3, wi: Vec3) -> f32 {
    if wo.z == 0.0 || wi.z == 0.0 {
        return 0.0;
    }
    let p = pbr_lobe_pdfs(m, wo);
    let same_side = wo.z * wi.z > 0.0;
    let mut pdf = 0.0;
    if same_side && wo.z > 0.0 {
        pdf += p[3] * cosine_hemisphere_pdf(wi.z);
    }
    if m.roughness == 0.0 {
        return pdf;
    }
    let alpha = ggx_alpha(m.roughness);
    if same_side {
        let h = pbr_half_vector(wo, wi, 1.0, false);
        let reflect = ggx_visible_pdf(wo, h, alpha) / (4.0 * wo.dot(h).abs());
        return pdf + (p[0] + p[1]) * reflect;
    }
    if m.flags & MAT_THIN_WALLED != 0 {
        let wr = Vec3::new(wi.x, wi.y, -wi.z);
        let h = pbr_half_vector(wo, wr, 1.0, false);
        return pdf + p[2] * ggx_visible_pdf(wo, h, alpha) / (4.0 * wo.dot(h).abs());
    }
    let etap = pbr_etap(m, wo);
    let h = pbr_half_vector(wo, wi, etap, true);
    let (oh, ih) = (wo.dot(h), wi.dot(h));
    if oh * wo.z <= 0.0 || ih * wi.z <= 0.0 {
        return pdf;
    }
    let denom = ih + oh / etap;
    pdf + p[2] * ggx_visible_pdf(wo, h, alpha) * ih.abs() / (denom * denom)
}

/// Draws `wi` from one of the base layer's lobes, chosen by `u_lobe`.
/// mirror: shaders/bsdf.wgsl `base_sample`
pub fn base_sample(m: &Material, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
    if wo.z == 0.0 {
        return None;
    }
    let p = pbr_lobe_pdfs(m, wo);
    let lobe = if u_lobe < p[0] {
        0
    } else if u_lobe < p[0] + p[1] {
        1
    } else if u_lobe < p[0] + p[1] + p[2] {
        2
    } else if p[3] > 0.0 {
        3
    } else {
        return None;
    };
    let dielectric = 1.0 - m.metallic;
    let thin = m.flags & MAT_THIN_WALLED != 0;
    if m.roughness == 0.0 && lobe != 3 {
        // The delta lobes: mirror reflection, straight or refracted transmission.
        let c = wo.z;
        let (wi, weight, eta) = match lobe {
            0 => (
                Vec3::new(-wo.x, -wo.y, wo.z),
                fresnel_schlick(m.albedo, c) * m.metallic,
                1.0,
            ),
            1 => (
                Vec3::new(-wo.x, -wo.y, wo.z),
                pbr_fresnel(m, c) * dielectric,
                1.0,
            ),
            _ => {
                let trans =
                    m.albedo * (Vec3::ONE - pbr_fresnel(m, c)) * (dielectric * m.transmission);
                if thin {
                    (-wo, trans, 1.0)
                } else {
                    let (f, cos_t, eta_it, eta_ti) = fresnel_dielectric(c, m.ior);
                    if f >= 1.0 {
                        return None;
                    }
                    (
                        Vec3::new(-eta_ti * wo.x, -eta_ti * wo.y, cos_t),
                        trans * (eta_ti * eta_ti),
                        eta_it,
                    )
                }
            }
        };
        return Some(BsdfSample {
            wi,
            weight: weight / p[lobe],
            pdf: p[lobe],
            delta: true,
            eta,
            lobe: if lobe == 2 {
                LOBE_TRANSMISSION
            } else {
                LOBE_GLOSSY
            },
        });
    }
    let wi = if lobe == 3 {
        sample_cosine_hemisphere(u)
    } else {
        let alpha = ggx_alpha(m.roughness);
        let side = if wo.z > 0.0 { 1.0 } else { -1.0 };
        let h = ggx_sample_visible(wo * side, alpha, u) * side;
        let h = if h.z < 0.0 { -h } else { h };
        let reflected = 2.0 * wo.dot(h) * h - wo;
        if lobe < 2 || thin {
            // A reflection must stay on wo's side (a thin wall's then crosses over).
            if reflected.z * wo.z <= 0.0 {
                return None;
            }
            if lobe < 2 {
                reflected
            } else {
                Vec3::new(reflected.x, reflected.y, -reflected.z)
            }
        } else {
            // Refraction about the microfacet normal on wo's side (Snell's law).
            let etap = pbr_etap(m, wo);
            let oh = wo.dot(h);
            let n = if oh < 0.0 { -h } else { h };
            let cos_i = oh.abs();
            let sin2_t = (1.0 - cos_i * cos_i).max(0.0) / (etap * etap);
            if sin2_t >= 1.0 {
                return None;
            }
            let cos_t = (1.0 - sin2_t).sqrt();
            let wi = -wo / etap + (cos_i / etap - cos_t) * n;
            // A refraction must cross the macro surface.
            if wi.z * wo.z >= 0.0 {
                return None;
            }
            wi
        }
    };
    let pdf = base_pdf(m, wo, wi);
    // (Also refuses a NaN pdf.)
    if pdf.is_nan() || pdf <= 0.0 {
        return None;
    }
    let eta = if wo.z * wi.z < 0.0 && !thin {
        pbr_etap(m, wo)
    } else {
        1.0
    };
    Some(BsdfSample {
        wi,
        weight: base_eval(m, wo, wi) / pdf,
        pdf,
        delta: false,
        eta,
        lobe: lobe_of(wo, wi, lobe == 3),
    })
}

// ---------------------------------------------------------------------------------------
// The sheen and clear-coat layers over the pbr base.

/// The colour of `m`'s diffuse lobe (Cycles' Diffuse Color pass): a `diffuse` material's
/// albedo; a `pbr` material's base colour where it is a dielectric that does not transmit
/// ((1 − metallic)(1 − transmission)), times the light that its specular layer and clear
/// coat let through at normal incidence (Cycles dims its diffuse closure by the layers'
/// albedo above it); nothing for the kinds without a diffuse lobe (conductors,
/// `dielectric`, `unlit`). mirror: shaders/bsdf.wgsl `diffuse_color`
pub fn diffuse_color(m: &Material) -> Vec3 {
    match m.kind {
        MaterialKind::DIFFUSE => m.albedo,
        MaterialKind::PBR => {
            let base = (1.0 - m.metallic) * (1.0 - m.transmission);
            let coat = 1.0 - m.clearcoat * coat_fresnel(1.0);
            m.albedo * (Vec3::ONE - pbr_fresnel(m, 1.0)) * (base * coat)
        }
        _ => Vec3::ZERO,
    }
}

/// Whether a `pbr` material has a sheen or a clear coat over its base.
/// mirror: shaders/bsdf.wgsl `has_layers`
pub fn has_layers(m: &Material) -> bool {
    m.clearcoat > 0.0 || m.sheen_color.max_element() > 0.0
}

/// The clear coat's Fresnel reflectance at cosine `c`: Schlick's with F0 0.04 (IOR 1.5),
/// as KHR_materials_clearcoat specifies. mirror: shaders/bsdf.wgsl `coat_fresnel`
pub fn coat_fresnel(c: f32) -> f32 {
    let k = (1.0 - c.abs()).clamp(0.0, 1.0);
    let k5 = k * k * k * k * k;
    0.04 + 0.96 * k5
}

/// The clear coat's Fresnel reflectance averaged over the cosine-weighted hemisphere:
/// 2 ∫ F(μ) μ dμ = F0 + (1 − F0) / 21 for [`coat_fresnel`].
pub const COAT_FRESNEL_AVERAGE: f32 = 0.04 + 0.96 / 21.0;

/// The factors of light that crosses the layers over the base along `w`: the coat's
/// (1 − c F(|nc.w|)) / √(1 − c F_avg), and the sheen's 1 − S E(|w.z|). The coat's pair,
/// multiplied, is the reciprocal albedo scaling of Kelemen and Szirmay-Kalos: it keeps a
/// white Lambertian base under the coat at unit albedo, as the extension's single factor
/// 1 − c F(nc.wo) does.
/// mirror: shaders/bsdf.wgsl `layers_pass`
pub fn layers_pass(m: &Material, w: Vec3) -> (f32, f32) {
    let coat = (1.0 - m.clearcoat * coat_fresnel(m.coat_normal.dot(w)))
        / (1.0 - m.clearcoat * COAT_FRESNEL_AVERAGE).sqrt();
    let s = m.sheen_color.max_element();
    let sheen = if s > 0.0 {
        1.0 - s * sheen_albedo(w.z.abs(), m.sheen_roughness)
    } else {
        1.0
    };
    (coat, sheen)
}

/// `w` in the clear coat's frame (its normal is +Z there).
/// mirror: shaders/bsdf.wgsl `to_coat`
pub fn to_coat(m: &Material, w: Vec3) -> Vec3 {
    let (t, b) = onb_from_normal(m.coat_normal);
    Vec3::new(w.dot(t), w.dot(b), w.dot(m.coat_normal))
}

/// The clear coat's f |cos wi| (wi's cosine to the shading normal) and the pdf of
/// sampling its visible normals, for a rough coat; zero for a smooth one (a delta).
/// mirror: shaders/bsdf.wgsl `coat_reflect`
pub fn coat_reflect(m: &Material, wo: Vec3, wi: Vec3) -> (f32, f32) {
    if m.clearcoat == 0.0 || m.clearcoat_roughness == 0.0 || wo.z <= 0.0 || wi.z <= 0.0 {
        return (0.0, 0.0);
    }
    let (o, i) = (to_coat(m, wo), to_coat(m, wi));
    if o.z <= 0.0 || i.z <= 0.0 {
        return (0.0, 0.0);
    }
    let alpha = ggx_alpha(m.clearcoat_roughness);
    let h = (o + i).normalize();
    let d = ggx_d(h, alpha);
    let f = m.clearcoat * coat_fresnel(o.dot(h)) * d * ggx_g1(o, alpha) * ggx_g1(i, alpha) * wi.z
        / (4.0 * o.z * i.z);
    (f, ggx_g1(o, alpha) * d / (4.0 * o.z))
}

/// The probabilities of drawing from the coat, the sheen and the base at `wo`: the coat
/// by its weight times its Fresnel (kept within [0.25, 0.9] where rough, so that its
/// highlights are found), the sheen by its albedo, the base by what is left; from below
/// the surface, the base alone. All zero when nothing reflects.
/// mirror: shaders/bsdf.wgsl `layer_pdfs`
pub fn layer_pdfs(m: &Material, wo: Vec3) -> [f32; 3] {
    let base = pbr_lobe_pdfs(m, wo);
    let base_reflects = if base[0] + base[1] + base[2] + base[3] > 0.0 {
        1.0
    } else {
        0.0
    };
    if wo.z <= 0.0 {
        return [0.0, 0.0, base_reflects];
    }
    let f = coat_fresnel(m.coat_normal.dot(wo));
    let f = if m.clearcoat_roughness > 0.0 {
        f.clamp(0.25, 0.9)
    } else {
        f
    };
    let coat = m.clearcoat * f;
    let s = m.sheen_color.max_element();
    let sheen = if s > 0.0 {
        (1.0 - coat) * s * sheen_albedo(wo.z, m.sheen_roughness)
    } else {
        0.0
    };
    let w = [coat, sheen, (1.0 - coat - sheen) * base_reflects];
    let sum = w[0] + w[1] + w[2];
    if sum > 0.0 {
        w.map(|x| x / sum)
    } else {
        [0.0; 3]
    }
}

/// f |cos wi| of the whole `pbr` stack (its non-delta lobes).
/// mirror: shaders/bsdf.wgsl `pbr_eval`
pub fn pbr_eval(m: &Material, wo: Vec3, wi: Vec3) -> Vec3 {
    let base = base_eval(m, wo, wi);
    if !has_layers(m) {
        return base;
    }
    let (coat_o, sheen_o) = layers_pass(m, wo);
    let (coat_i, sheen_i) = layers_pass(m, wi);
    let sheen = sheen_reflect(m.sheen_color, m.sheen_roughness, wo, wi);
    let under = sheen + base * sheen_o.min(sheen_i);
    under * (coat_o * coat_i) + Vec3::splat(coat_reflect(m, wo, wi).0)
}

/// The pdf with which [`pbr_sample`] draws `wi` through a non-delta lobe.
/// mirror: shaders/bsdf.wgsl `pbr_pdf`
pub fn pbr_pdf(m: &Material, wo: Vec3, wi: Vec3) -> f32 {
    if !has_layers(m) {
        return base_pdf(m, wo, wi);
    }
    let p = layer_pdfs(m, wo);
    let sheen = if wo.z > 0.0 && wi.z > 0.0 {
        cosine_hemisphere_pdf(wi.z)
    } else {
        0.0
    };
    p[0] * coat_reflect(m, wo, wi).1 + p[1] * sheen + p[2] * base_pdf(m, wo, wi)
}

/// Draws `wi` from the coat, the sheen or the base, chosen by `u_lobe` (which the base
/// reuses, rescaled, for its own lobes).
/// mirror: shaders/bsdf.wgsl `pbr_sample`
pub fn pbr_sample(m: &Material, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<BsdfSample> {
    if !has_layers(m) {
        return base_sample(m, wo, u_lobe, u);
    }
    let p = layer_pdfs(m, wo);
    let (wi, lobe) = if u_lobe < p[0] {
        let (t, b) = onb_from_normal(m.coat_normal);
        let o = to_coat(m, wo);
        if m.clearcoat_roughness == 0.0 {
            // A smooth coat: the mirror direction about its normal.
            let wi = 2.0 * wo.dot(m.coat_normal) * m.coat_normal - wo;
            if o.z <= 0.0 || wi.z <= 0.0 {
                return None;
            }
            return Some(BsdfSample {
                wi,
                weight: Vec3::splat(m.clearcoat * coat_fresnel(o.z) / p[0]),
                pdf: p[0],
                delta: true,
                eta: 1.0,
                lobe: LOBE_GLOSSY,
            });
        }
        if o.z <= 0.0 {
            return None;
        }
        let h = ggx_sample_visible(o, ggx_alpha(m.clearcoat_roughness), u);
        let i = 2.0 * o.dot(h) * h - o;
        let wi = i.x * t + i.y * b + i.z * m.coat_normal;
        (wi, lobe_of(wo, wi, false))
    } else if u_lobe < p[0] + p[1] {
        let wi = sample_cosine_hemisphere(u);
        (wi, lobe_of(wo, wi, true))
    } else {
        if p[2] <= 0.0 {
            return None;
        }
        let u_base = ((u_lobe - p[0] - p[1]) / p[2]).min(ONE_MINUS_EPSILON);
        let bs = base_sample(m, wo, u_base, u)?;
        if bs.delta {
            let (coat_o, sheen_o) = layers_pass(m, wo);
            let (coat_i, sheen_i) = layers_pass(m, bs.wi);
            let pass = coat_o * coat_i * sheen_o.min(sheen_i);
            return Some(BsdfSample {
                weight: bs.weight * (pass / p[2]),
                pdf: bs.pdf * p[2],
                ..bs
            });
        }
        (bs.wi, bs.lobe)
    };
    let pdf = pbr_pdf(m, wo, wi);
    // (Also refuses a NaN pdf.)
    if pdf.is_nan() || pdf <= 0.0 {
        return None;
    }
    let eta = if wo.z * wi.z < 0.0 && m.flags & MAT_THIN_WALLED == 0 {
        pbr_etap(m, wo)
    } else {
        1.0
    };
    Some(BsdfSample {
        wi,
        weight: pbr_eval(m, wo, wi) / pdf,
        pdf,
        delta: false,
        eta,
        lobe,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_diffuse_colour_is_the_base_under_its_layers() {
        let base = Vec3::new(0.8, 0.1, 0.1);
        let with = |kind, f: &dyn Fn(&mut Material)| {
            let mut m = Material {
                albedo: base,
                ..Material::new(kind)
            };
            f(&mut m);
            diffuse_color(&m)
        };
        let close = |a: Vec3, b: Vec3| (a - b).abs().max_element() < 1e-6;
        assert_eq!(with(MaterialKind::DIFFUSE, &|_| {}), base);
        for kind in [
            MaterialKind::CONDUCTOR,
            MaterialKind::ROUGH_CONDUCTOR,
            MaterialKind::DIELECTRIC,
            MaterialKind::UNLIT,
        ] {
            assert_eq!(with(kind, &|_| {}), Vec3::ZERO, "{}", kind.name());
        }
        // IOR 1.5: F0 = 0.04 at normal incidence, and the coat's is 0.04 too.
        let pbr = MaterialKind::PBR;
        assert!(close(with(pbr, &|_| {}), base * 0.96));
        assert!(close(with(pbr, &|m| m.metallic = 0.25), base * 0.72));
        assert!(close(with(pbr, &|m| m.transmission = 0.5), base * 0.48));
        assert!(close(with(pbr, &|m| m.clearcoat = 1.0), base * 0.96 * 0.96));
        assert!(close(with(pbr, &|m| m.specular = 0.0), base));
    }
}
