//! BSDF test helpers, in the local shading frame (normal +Z): material names, directions,
//! the `wo` of random cases, and the conditioning of GGX quantities.

use glam::{DVec3, Vec3};
use meshtrace::render::bsdf::ggx_alpha;
use meshtrace::scene::{Material, MaterialKind};

/// A material's name in messages (and, in `tests/bsdf.rs`, the label of its random streams).
pub fn material_name(m: &Material) -> String {
    match m.kind {
        MaterialKind::ROUGH_CONDUCTOR => format!("rough_conductor r={}", m.roughness),
        MaterialKind::DIELECTRIC => format!("dielectric ior={}", m.ior),
        kind => kind.name().to_string(),
    }
}

/// The unit vector at polar angle `theta` and azimuth `phi` (degrees) about +Z.
pub fn spherical(theta_deg: f64, phi_deg: f64) -> Vec3 {
    let (t, p) = (theta_deg.to_radians(), phi_deg.to_radians());
    DVec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
        .as_vec3()
        .normalize()
}

/// The mirror direction of `w` about the normal.
pub fn mirror(w: Vec3) -> Vec3 {
    Vec3::new(-w.x, -w.y, w.z)
}

/// `w`, a random unit vector, made the `wo` of a random case: grazing if `grazing` (|w.z|
/// shrunk a hundredfold, renormalised), then put below the surface (z <= 0) if `below`,
/// else above it.
pub fn shape_wo(w: Vec3, grazing: bool, below: bool) -> Vec3 {
    let mut wo = w;
    if grazing {
        wo.z *= 0.01;
        wo = wo.normalize();
    }
    wo.z = if below { -wo.z.abs() } else { wo.z.abs() };
    wo
}

/// How much GGX's D(h) amplifies a relative rounding error in h.z, for h the half vector of
/// (wo, wi): |d ln D / d ln h.z| = 4 h.z^2 (1 - a^2) / (h.z^2 (a^2 - 1) + 1), ~4 / a^2 at
/// the peak (4e4 at roughness 0.1, 4e6 at the smallest alpha, 1e-3, where float32 D is only
/// good to ~10%). 0 for other kinds.
pub fn ggx_condition(m: &Material, wo: Vec3, wi: Vec3) -> f64 {
    if m.kind != MaterialKind::ROUGH_CONDUCTOR {
        return 0.0;
    }
    let h = (wo.as_dvec3() + wi.as_dvec3()).normalize();
    let a2 = (ggx_alpha(m.roughness) as f64).powi(2);
    let d = h.z * h.z * (a2 - 1.0) + 1.0;
    4.0 * h.z * h.z * (1.0 - a2) / d
}

/// The relative tolerance for comparing GGX quantities computed along different float32
/// paths: `base`, plus four rounding errors of h.z of `rounding` each (relative) amplified
/// by [`ggx_condition`]; `base` for other kinds.
pub fn ggx_tolerance(m: &Material, wo: Vec3, wi: Vec3, base: f64, rounding: f64) -> f64 {
    base + ggx_condition(m, wo, wi) * 4.0 * rounding
}
