//! The BSDFs, in the local shading frame (the normal is +Z).
//!
//! Each material kind is three functions, `eval` (f times |cos|), `pdf` and `sample`,
//! dispatched by [`bsdf_eval`], [`bsdf_pdf`] and [`bsdf_sample`]; adding a material means
//! adding one arm to each. Two-sided kinds expect the caller to have turned the frame
//! towards `wo` (`wo.z > 0`); the dielectric sees both sides. Every function has a WGSL
//! twin of the same name in `shaders/bsdf.wgsl`.

use super::sampling::{cosine_hemisphere_pdf, sample_cosine_hemisphere};
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
}

/// Whether the material's BSDF is a Dirac delta (next event estimation cannot help).
/// mirror: shaders/bsdf.wgsl `bsdf_is_delta`
pub fn bsdf_is_delta(m: &Material) -> bool {
    matches!(m.kind, MaterialKind::CONDUCTOR | MaterialKind::DIELECTRIC)
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
                })
            }
        }
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
