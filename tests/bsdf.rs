//! Statistical tests of the BSDFs (`src/render/bsdf.rs`, and `shaders/bsdf.wgsl` through the
//! `test_bsdf_sample` / `test_bsdf_eval` kernels), in the local shading frame (normal +Z), for
//! `diffuse`, `conductor`, `rough_conductor` (roughness 0.1, 0.3, 0.6, 1.0) and `dielectric`
//! (ior 1.5, 1.33), all with albedo 1:
//!
//! - `eval_and_pdf_are_non_negative`: `bsdf_eval` and `bsdf_pdf` are finite and >= 0 over
//!   random (wo, wi), delta kinds evaluate to 0, and every direction a non-delta BSDF
//!   reflects into has a positive pdf (it can be sampled).
//! - `non_delta_bsdfs_are_reciprocal`: f = eval / |wi.z| is symmetric in (wo, wi).
//! - `sampled_pdf_and_weight_match_eval`: each sample's pdf is `bsdf_pdf` of its direction
//!   and its weight is `bsdf_eval / pdf`; delta samples are what they should be.
//! - `chi2_*`: Pearson's chi-square goodness of fit of each non-delta sampling routine (as
//!   Mitsuba's and pbrt's BSDF tests do): 100k samples binned over (cos theta, phi) in 10 x 20
//!   cells, expected counts from integrating `bsdf_pdf` over each cell (adaptively, from
//!   16 x 16 sub-samples), for wo normal, oblique and grazing; rough conductors also in a
//!   frame about the mirror direction sized to the lobe, where narrow lobes are resolved.
//!   p > 0.01 is required family-wise (see `significance`). `chi2_detects_a_wrong_pdf`
//!   shows that a pdf 10% off (or the pdf of a 10% different roughness) fails.
//! - `white_furnace`: the directional albedo E[weight] per material and wo (see there for
//!   the dielectric's radiance scaling).
//! - `dielectric_refraction_is_reversible`: the refracted ray refracts back, with the same
//!   Fresnel term and the reciprocal radiance scaling.
//! - `gpu_*`: the same pdf-consistency, furnace and chi-square checks on the WGSL kernels,
//!   skipped without a GPU (see `common::gpu`).
//!
//! The chi-square test itself is `common::chi2`, for every material's tests to share. Every
//! random number is `common::rand::hashed_u3` (the renderer's own hash) of a stream per
//! use, so each run sees the same numbers.
//! Run with `--nocapture` to see the measured p-values, albedos and errors.

use crate::common;

use common::chi2::{Binning, chi2_of, chi2_survival, show_chi2, sidak_level};
use common::gamma::ln_gamma;
use common::kernels::{gpu_bsdf_evals, gpu_bsdf_samples};
use common::materials::{ggx_tolerance, material_name, mirror, shape_wo, spherical};
use common::rand::{hashed_u3, stream};
use common::scenes::material_table;
use common::stats::{Worst, mean_and_stderr, rel, rel3};
use glam::{Vec2, Vec3};
use meshtrace::render::bsdf::{
    bsdf_draws_direction, bsdf_draws_lobe, bsdf_eval, bsdf_is_delta, bsdf_pdf, bsdf_sample,
    fresnel_dielectric, ggx_alpha,
};
use meshtrace::render::sampling::sample_uniform_sphere;
use meshtrace::scene::{Material, MaterialKind};
use std::f64::consts::PI;

// ---------------------------------------------------------------------------------------
// Materials, directions, random numbers.

const ROUGHNESSES: [f32; 4] = [0.1, 0.3, 0.6, 1.0];
const IORS: [f32; 2] = [1.5, 1.33];
/// The seed of every random number here.
const SEED: u32 = 0x0b5d_f00d;

fn diffuse() -> Material {
    Material::diffuse(Vec3::ONE)
}

fn conductor() -> Material {
    Material::new(MaterialKind::CONDUCTOR)
}

fn rough(roughness: f32) -> Material {
    Material {
        roughness,
        ..Material::new(MaterialKind::ROUGH_CONDUCTOR)
    }
}

fn dielectric(ior: f32) -> Material {
    Material {
        ior,
        ..Material::new(MaterialKind::DIELECTRIC)
    }
}

fn all_materials() -> Vec<Material> {
    let mut m = vec![diffuse(), conductor()];
    m.extend(ROUGHNESSES.map(rough));
    m.extend(IORS.map(dielectric));
    m
}

fn non_delta_materials() -> Vec<Material> {
    all_materials()
        .into_iter()
        .filter(|m| !bsdf_is_delta(m))
        .collect()
}

/// The `i`-th triple of uniform numbers in [0, 1) of stream `s` (a [`stream`] per use, so
/// that no two tests share random numbers; a material's streams are labelled with its
/// [`material_name`]).
fn u3(s: u32, i: u32) -> [f32; 3] {
    hashed_u3(SEED, s, i)
}

/// A uniform random unit vector.
fn random_dir(s: u32, i: u32) -> Vec3 {
    let u = u3(s, i);
    sample_uniform_sphere(Vec2::new(u[0], u[1]))
}

/// A `wo` for `m`: uniform over the sphere for the dielectric, over the upper hemisphere
/// for the two-sided kinds; one in ten grazing (|wo.z| shrunk a hundredfold).
fn random_wo(m: &Material, s: u32, i: u32) -> Vec3 {
    let w = random_dir(s, i);
    let grazing = u3(s ^ 0x5555_5555, i)[0] < 0.1;
    // The dielectric keeps the side drawn.
    shape_wo(
        w,
        grazing,
        m.kind == MaterialKind::DIELECTRIC && w.z.is_sign_negative(),
    )
}

fn sample(m: &Material, wo: Vec3, u: [f32; 3]) -> Option<meshtrace::render::bsdf::BsdfSample> {
    bsdf_sample(m, wo, u[0], Vec2::new(u[1], u[2]))
}

fn non_negative_finite(v: Vec3) -> bool {
    v.is_finite() && v.min_element() >= 0.0
}

/// The relative tolerance of pdfs and weights computed along different float32 paths (the
/// sampled half vector against the one rebuilt from wi): 1e-4, plus four float32 rounding
/// errors of h.z amplified by GGX's condition number (4e4 at roughness 0.1).
const BASE_TOLERANCE: f64 = 1e-4;

fn tolerance(m: &Material, wo: Vec3, wi: Vec3) -> f64 {
    ggx_tolerance(m, wo, wi, BASE_TOLERANCE, f32::EPSILON as f64)
}

// ---------------------------------------------------------------------------------------
// Pointwise properties.

#[test]
fn eval_and_pdf_are_non_negative() {
    let n = 100_000;
    for (k, m) in all_materials().iter().enumerate() {
        let s = stream("non-negative", k as u32);
        let mut unsampleable = 0;
        let mut nonzero = 0;
        for i in 0..n {
            // wo over the whole sphere: two-sided kinds must give 0 (not garbage) below.
            let mut wo = random_dir(s, i);
            if i % 10 == 0 {
                wo.z *= 1e-3;
                wo = wo.normalize();
            }
            // A quarter of the wi from the BSDF itself, so that glossy peaks are covered.
            let sampled = sample(m, wo, u3(s ^ 1, i)).map(|x| x.wi);
            let wi = match sampled {
                Some(wi) if i % 4 == 0 => wi,
                _ => random_dir(s ^ 2, i),
            };
            let f = bsdf_eval(m, wo, wi);
            let pdf = bsdf_pdf(m, wo, wi);
            let show = || format!("{}: wo {wo} wi {wi}: eval {f}, pdf {pdf}", material_name(m));
            assert!(non_negative_finite(f), "{}", show());
            assert!(pdf.is_finite() && pdf >= 0.0, "{}", show());
            if bsdf_is_delta(m) {
                assert!(f == Vec3::ZERO && pdf == 0.0, "{}", show());
            } else if f.max_element() > 0.0 {
                nonzero += 1;
                assert!(wo.z > 0.0 && wi.z > 0.0, "{}", show());
                // Every direction the BSDF reflects into must be reachable by sampling.
                if pdf <= 0.0 {
                    unsampleable += 1;
                }
            }
        }
        eprintln!(
            "non-negative: {}: {n} pairs, {nonzero} with f > 0, {unsampleable} of them with pdf 0",
            material_name(m)
        );
        assert_eq!(unsampleable, 0, "{}: f > 0 where pdf = 0", material_name(m));
    }
}

#[test]
fn non_delta_bsdfs_are_reciprocal() {
    let n = 100_000;
    for (k, m) in non_delta_materials().iter().enumerate() {
        let s = stream("reciprocity", k as u32);
        let mut worst = Worst::new(
            format!("{}: |f(wo,wi) - f(wi,wo)| / f", material_name(m)),
            1e-5,
        );
        let mut tested = 0;
        for i in 0..n {
            let wo = random_wo(m, s, i);
            let sampled = sample(m, wo, u3(s ^ 1, i)).map(|x| x.wi);
            let mut wi = match sampled {
                Some(wi) if i % 2 == 0 => wi,
                _ => random_dir(s ^ 2, i),
            };
            wi.z = wi.z.abs();
            if wi.z < 1e-4 || wo.z < 1e-4 {
                continue;
            }
            let a = bsdf_eval(m, wo, wi) / wi.z;
            let b = bsdf_eval(m, wi, wo) / wo.z;
            if a.max_element() > 0.0 || b.max_element() > 0.0 {
                tested += 1;
            }
            worst.add(rel3(a, b, 1e-30), || format!("wo {wo} wi {wi}: {a} vs {b}"));
        }
        assert!(
            tested > n / 2,
            "{}: only {tested} nonzero pairs",
            material_name(m)
        );
        worst.check("reciprocity");
    }
}

#[test]
fn sampled_pdf_and_weight_match_eval() {
    let n = 100_000;
    for (k, m) in all_materials().iter().enumerate() {
        let s = stream("pdf consistency", k as u32);
        let mut pdf_err = Worst::new(
            format!("{}: sampled pdf vs bsdf_pdf (relative)", material_name(m)),
            BASE_TOLERANCE,
        );
        let mut weight_err = Worst::new(
            format!(
                "{}: sampled weight vs eval / pdf (relative)",
                material_name(m)
            ),
            BASE_TOLERANCE,
        );
        let mut raw_pdf = 0.0f64;
        let mut valid = 0;
        for i in 0..n {
            let wo = random_wo(m, s, i);
            let u = u3(s ^ 1, i);
            let Some(x) = sample(m, wo, u) else {
                continue;
            };
            valid += 1;
            let show = || format!("{}: wo {wo} u {u:?}: {x:?}", material_name(m));
            assert!((x.wi.length() - 1.0).abs() < 1e-5, "{}", show());
            assert!(non_negative_finite(x.weight), "{}", show());
            assert!(x.pdf.is_finite() && x.pdf > 0.0, "{}", show());
            assert_eq!(x.delta, bsdf_is_delta(m), "{}", show());
            match m.kind {
                MaterialKind::CONDUCTOR => {
                    assert!(x.wi == mirror(wo) && x.weight == m.albedo && x.pdf == 1.0);
                }
                MaterialKind::DIELECTRIC => {
                    let (f, ..) = fresnel_dielectric(wo.z, m.ior);
                    let reflected = x.wi.z * wo.z > 0.0;
                    let p = if reflected { f } else { 1.0 - f };
                    assert!(rel(x.pdf, p, 1e-6) < 1e-5, "{}", show());
                    if reflected {
                        assert!(x.wi == mirror(wo), "{}", show());
                    }
                    assert!(bsdf_eval(m, wo, x.wi) == Vec3::ZERO && bsdf_pdf(m, wo, x.wi) == 0.0);
                }
                _ => {
                    assert!(x.wi.z > 0.0, "{}", show());
                    let pdf = bsdf_pdf(m, wo, x.wi);
                    let f = bsdf_eval(m, wo, x.wi);
                    let tol = tolerance(m, wo, x.wi);
                    raw_pdf = raw_pdf.max(rel(pdf, x.pdf, 1e-6));
                    pdf_err.add_tol(rel(pdf, x.pdf, 1e-6), tol, || {
                        format!("{}: bsdf_pdf {pdf}", show())
                    });
                    weight_err.add_tol(rel3(x.weight, f / x.pdf, 1e-6), tol, || {
                        format!("{}: eval {f}", show())
                    });
                }
            }
        }
        eprintln!(
            "pdf consistency: {}: {valid} of {n} samples valid; max raw relative pdf error {raw_pdf:.2e}",
            material_name(m)
        );
        assert!(valid > n / 2, "{}: {valid} valid samples", material_name(m));
        if !bsdf_is_delta(m) {
            pdf_err.check("pdf consistency");
            weight_err.check("pdf consistency");
        }
    }
}

/// The path draws a material's lobe number and direction pair only where
/// `bsdf_draws_lobe` and `bsdf_draws_direction` say that `bsdf_sample` reads them: where
/// they say it does not, changing the number changes no sample (a draw skipped is then
/// the same path). Also where they say it does, for a `pbr` material with every lobe, the
/// sample depends on the number somewhere (the predicates do not claim too much).
#[test]
fn the_draws_a_material_skips_are_the_numbers_it_ignores() {
    let pbr = Material {
        roughness: 0.4,
        metallic: 0.3,
        transmission: 0.3,
        ior: 1.5,
        ..Material::new(MaterialKind::PBR)
    };
    let mut materials = all_materials();
    materials.push(pbr);
    for m in &materials {
        let s = stream(&format!("draws {}", material_name(m)), 0);
        let (mut lobe_matters, mut direction_matters) = (false, false);
        for i in 0..2_000 {
            let wo = random_wo(m, s, i);
            let (u, v) = (u3(s ^ 1, i), u3(s ^ 2, i));
            let base = sample(m, wo, u);
            let other_lobe = sample(m, wo, [v[0], u[1], u[2]]);
            let other_direction = sample(m, wo, [u[0], v[1], v[2]]);
            lobe_matters |= base != other_lobe;
            direction_matters |= base != other_direction;
        }
        let name = material_name(m);
        assert!(
            bsdf_draws_lobe(m) || !lobe_matters,
            "{name}: bsdf_sample reads the lobe number, which the path does not draw"
        );
        assert!(
            bsdf_draws_direction(m) || !direction_matters,
            "{name}: bsdf_sample reads the direction pair, which the path does not draw"
        );
        if m.kind == MaterialKind::PBR {
            assert!(lobe_matters && direction_matters, "{name} reads both");
        }
    }
}

#[test]
fn dielectric_refraction_is_reversible() {
    for ior in IORS {
        let m = dielectric(ior);
        let s = stream("reversible", ior.to_bits());
        let name = material_name(&m);
        let mut dir_err = Worst::new(format!("{name}: |wo' - wo|"), 1e-4);
        let mut fresnel_err = Worst::new(format!("{name}: 1 - F both ways (relative)"), 1e-3);
        let mut product_err =
            Worst::new(format!("{name}: |weight(wo->wi) weight(wi->wo) - 1|"), 1e-5);
        let mut refracted = 0;
        for i in 0..50_000 {
            let wo = random_wo(&m, s, i);
            // u_lobe just below 1 picks refraction whenever there is any.
            let Some(a) = sample(&m, wo, [0.999_999, 0.5, 0.5]) else {
                panic!("{}: no sample for wo {wo}", material_name(&m));
            };
            if a.wi.z * wo.z > 0.0 {
                continue; // total internal reflection
            }
            if wo.z.abs() < 0.05 {
                // Refracted to near the critical angle, where the reversed refraction is
                // ill-conditioned (at |wo.z| = 1e-4 float rounding even turns it into total
                // internal reflection; at 1e-2 its cosine is off by 1e-3 relative).
                continue;
            }
            refracted += 1;
            let b = sample(&m, a.wi, [0.999_999, 0.5, 0.5]).unwrap();
            let show = || format!("wo {wo}: {a:?}; back: {b:?}");
            assert!(b.wi.z * a.wi.z < 0.0, "refracts back: {}", show());
            dir_err.add((b.wi - wo).abs().max_element() as f64, show);
            fresnel_err.add(rel(a.pdf, b.pdf, 1e-6), show);
            product_err.add((a.weight.x as f64 * b.weight.x as f64 - 1.0).abs(), show);
            assert!(
                (a.eta * b.eta - 1.0).abs() < 1e-6,
                "eta both ways: {}",
                show()
            );
        }
        assert!(refracted > 20_000, "{refracted} refracted");
        dir_err.check("reversibility");
        fresnel_err.check("reversibility");
        product_err.check("reversibility");
    }
}

// ---------------------------------------------------------------------------------------
// The chi-square goodness-of-fit test.

// The test itself, `Binning`, `chi2_of` and the chi-square distribution, is
// `common::chi2`.

const CHI2_SAMPLES: u32 = 100_000;
/// The chi-square tests in this file: 3 wo x (diffuse + 4 rough conductors x 2 binnings)
/// on the CPU, and 1 + 4 x 2 on the GPU.
const CHI2_TESTS: i32 = 3 * (1 + 4 * 2) + (1 + 4 * 2);
/// Each test's p-value must exceed this: a family-wise significance of 0.01, Sidak-corrected
/// for the number of tests (as pbrt-v3's BSDF chi-square tests correct theirs): with 36
/// correct tests at a per-test level of 0.01, one fails by chance with probability 30%.
/// (It happens here: rough r=1 at the oblique wo gives p = 0.0049 in `gpu_chi2`'s stream,
/// and the same on the CPU from the same numbers; other streams and 1M samples give
/// uniformly spread p-values.)
fn significance() -> f64 {
    sidak_level(0.99, CHI2_TESTS)
}

#[test]
fn chi2_survival_function_known_values() {
    // (statistic, degrees of freedom, survival), from standard tables / scipy.stats.chi2.sf.
    // Values from mpmath's regularised incomplete gamma (30 digits).
    let known = [
        (3.841_458_820_694_124, 1.0, 0.05),
        (6.634_896_601_021_214, 1.0, 0.01),
        (0.5, 3.0, 0.918_891_411_654_675_9),
        (15.0, 7.0, 0.035_999_404_763_428_78),
        (18.307_038_053_275_146, 10.0, 0.05),
        (2.0, 2.0, 0.367_879_441_171_442_3),
        (135.806_722_252_002_1, 100.0, 0.010_000_001_415_173_11),
        (50.0, 100.0, 0.999_993_046_694_752_4),
        (300.0, 200.0, 5.924_540_335_483_916e-6),
        (190.0, 199.0, 0.664_422_295_567_189_9),
        (1000.0, 1000.0, 0.494_052_853_829_239_6),
    ];
    for (x, k, want) in known {
        let got = chi2_survival(x, k);
        assert!(
            (got - want).abs() <= 1e-9 + 1e-6 * want,
            "chi2 sf({x}, {k}) = {got}, want {want}"
        );
    }
    assert!((ln_gamma(0.5) - PI.sqrt().ln()).abs() < 1e-12);
    assert!((ln_gamma(10.0) - 362_880f64.ln()).abs() < 1e-12);
}

/// The wo of the chi-square tests: at the normal, oblique and grazing.
fn chi2_wos() -> [(&'static str, Vec3); 3] {
    [
        ("normal", Vec3::Z),
        ("oblique 45 deg", spherical(45.0, 30.0)),
        ("grazing 85 deg", spherical(85.0, 200.0)),
    ]
}

/// The binnings a material is tested in: local, and for rough conductors about the lobe.
fn binnings(m: &Material, wo: Vec3) -> Vec<Binning> {
    let mut b = vec![Binning::local()];
    if m.kind == MaterialKind::ROUGH_CONDUCTOR {
        b.push(Binning::lobe(wo, ggx_alpha(m.roughness)));
    }
    b
}

/// CHI2_SAMPLES CPU samples of `m` for `wo`, from stream `s`.
fn cpu_samples(m: &Material, wo: Vec3, s: u32) -> Vec<Option<Vec3>> {
    (0..CHI2_SAMPLES)
        .map(|i| sample(m, wo, u3(s, i)).map(|x| x.wi))
        .collect()
}

/// Runs every chi-square test of `m` on the CPU and checks each p-value against
/// `significance()`.
fn chi2_material(m: &Material) {
    let mut failures = Vec::new();
    for (k, (name, wo)) in chi2_wos().into_iter().enumerate() {
        let wis = cpu_samples(m, wo, stream(&material_name(m), k as u32));
        let refused = wis.iter().filter(|w| w.is_none()).count();
        for bin in binnings(m, wo) {
            let (r, integration) = chi2_of(&wis, &bin, &|wi| bsdf_pdf(m, wo, wi) as f64);
            let line = format!(
                "chi2: {}, wo {name}, {}: {} ({refused} refused; integration error <= {integration:.2} sd)",
                material_name(m),
                bin.what,
                show_chi2(&r)
            );
            eprintln!("{line}");
            if !matches!(r, Ok(ref c) if c.p > significance()) {
                failures.push(line);
            }
        }
    }
    assert!(failures.is_empty(), "failed:\n{}", failures.join("\n"));
}

#[test]
fn chi2_diffuse() {
    chi2_material(&diffuse());
}

#[test]
fn chi2_rough_conductor_0_1() {
    chi2_material(&rough(0.1));
}

#[test]
fn chi2_rough_conductor_0_3() {
    chi2_material(&rough(0.3));
}

#[test]
fn chi2_rough_conductor_0_6() {
    chi2_material(&rough(0.6));
}

#[test]
fn chi2_rough_conductor_1_0() {
    chi2_material(&rough(1.0));
}

/// The test has power: the same samples against a pdf 10% too large, or against the pdf of
/// a roughness 10% off, fail with p < 1e-6 (or samples where none are expected).
#[test]
fn chi2_detects_a_wrong_pdf() {
    let cases = [
        (diffuse(), diffuse(), 1.1, Vec3::Z),
        (rough(0.3), rough(0.3), 1.1, spherical(45.0, 30.0)),
        (rough(0.6), rough(0.6), 1.1, spherical(85.0, 200.0)),
        (rough(0.3), rough(0.33), 1.0, spherical(45.0, 30.0)),
        (rough(0.1), rough(0.11), 1.0, Vec3::Z),
    ];
    for (k, (sampled, assumed, scale, wo)) in cases.into_iter().enumerate() {
        let wis = cpu_samples(&sampled, wo, stream("power", k as u32));
        let bins = binnings(&sampled, wo);
        let bin = bins.last().unwrap();
        let (r, _) = chi2_of(&wis, bin, &|wi| scale * bsdf_pdf(&assumed, wo, wi) as f64);
        eprintln!(
            "chi2 power: samples of {}, pdf of {} x {scale}, wo {wo}, {}: {r:?}",
            material_name(&sampled),
            material_name(&assumed),
            bin.what
        );
        if let Ok(c) = r {
            assert!(c.p < 1e-6, "a wrong pdf passed: {c:?}");
        }
    }
}

// ---------------------------------------------------------------------------------------
// White furnace.

/// The angles (degrees) of the furnace's wo; beyond 90 only for the dielectric (from inside).
const FURNACE_THETAS: [f64; 8] = [0.0, 15.0, 30.0, 45.0, 60.0, 75.0, 85.0, 89.0];
const FURNACE_INSIDE: [f64; 4] = [100.0, 130.0, 150.0, 175.0];
const FURNACE_SAMPLES: u32 = 100_000;

/// The radiance scaling a sample's weight carries: (eta_wo_side / eta_wi_side)^2 for a
/// refraction (`eta` is eta_wi_side / eta_wo_side), 1 otherwise. Dividing it out gives the
/// weight of the unscaled ("importance") BSDF, whose albedo F + (1 - F) is exactly 1.
fn radiance_scaling(wo: Vec3, wi: Vec3, eta: f32) -> f32 {
    if wi.z * wo.z < 0.0 {
        1.0 / (eta * eta)
    } else {
        1.0
    }
}

/// The directional albedo by quadrature of `bsdf_eval` over the sphere, in polar
/// coordinates (theta', phi') about the mirror direction with theta' = pi s^2, so that
/// narrow lobes get many nodes: 2000 x 512 midpoint nodes.
fn albedo_quadrature(m: &Material, wo: Vec3) -> f64 {
    let n = mirror(wo).as_dvec3().normalize();
    let (t, b) = n.any_orthonormal_pair();
    let (ns, np) = (2000, 512);
    let mut sum = 0.0;
    for i in 0..ns {
        let s = (i as f64 + 0.5) / ns as f64;
        let theta = PI * s * s;
        let jac = theta.sin() * 2.0 * PI * s / ns as f64 * (2.0 * PI / np as f64);
        for j in 0..np {
            let phi = (j as f64 + 0.5) / np as f64 * 2.0 * PI;
            let d = theta.sin() * (phi.cos() * t + phi.sin() * b) + theta.cos() * n;
            sum += bsdf_eval(m, wo, d.as_vec3().normalize()).x as f64 * jac;
        }
    }
    sum
}

/// The wo of the furnace for `m`.
fn furnace_wos(m: &Material) -> Vec<(f64, Vec3)> {
    let mut thetas = FURNACE_THETAS.to_vec();
    if m.kind == MaterialKind::DIELECTRIC {
        thetas.extend(FURNACE_INSIDE);
    }
    thetas
        .into_iter()
        .map(|t| (t, spherical(t, 40.0 + t)))
        .collect()
}

/// One furnace measurement: albedo (E[weight]), its standard error, the albedo with the
/// radiance scaling divided out, and the fraction of samples that reflected.
#[derive(Debug)]
struct Furnace {
    albedo: f64,
    se: f64,
    unscaled: f64,
    unscaled_se: f64,
    reflected: f64,
}

/// The furnace statistics of samples (wo, sample or None).
fn furnace_of(wo: Vec3, samples: &[Option<(Vec3, Vec3, f32)>]) -> Furnace {
    let weights: Vec<f64> = samples
        .iter()
        .map(|s| s.map_or(0.0, |(_, w, _)| w.x as f64))
        .collect();
    let unscaled: Vec<f64> = samples
        .iter()
        .map(|s| {
            s.map_or(0.0, |(wi, w, eta)| {
                (w.x / radiance_scaling(wo, wi, eta)) as f64
            })
        })
        .collect();
    let reflected = samples
        .iter()
        .filter(|s| s.is_some_and(|(wi, ..)| wi.z * wo.z > 0.0))
        .count() as f64
        / samples.len() as f64;
    let (albedo, se) = mean_and_stderr(&weights);
    let (unscaled, unscaled_se) = mean_and_stderr(&unscaled);
    Furnace {
        albedo,
        se,
        unscaled,
        unscaled_se,
        reflected,
    }
}

/// Checks one furnace measurement of `m` at `wo`; `quadrature` (for non-delta kinds) is the
/// albedo from integrating `bsdf_eval`. Returns the report line.
fn check_furnace(
    m: &Material,
    theta: f64,
    wo: Vec3,
    f: &Furnace,
    quadrature: Option<f64>,
) -> String {
    let line = format!(
        "furnace: {} theta {theta:>5.1}: albedo {:.5} +- {:.5}{}{}",
        material_name(m),
        f.albedo,
        f.se,
        if m.kind == MaterialKind::DIELECTRIC {
            format!(
                ", without radiance scaling {:.5} +- {:.1e}, reflected {:.4} (Fresnel {:.4})",
                f.unscaled,
                f.unscaled_se,
                f.reflected,
                fresnel_dielectric(wo.z, m.ior).0
            )
        } else {
            String::new()
        },
        quadrature.map_or(String::new(), |q| format!(", quadrature of eval {q:.5}"))
    );
    let noise = 4.0 * f.se;
    match m.kind {
        MaterialKind::DIFFUSE | MaterialKind::CONDUCTOR => {
            assert!((f.albedo - 1.0).abs() <= 0.01, "{line}");
        }
        MaterialKind::ROUGH_CONDUCTOR => {
            // Single-scattering microfacets lose energy; they must never gain it.
            assert!(f.albedo <= 1.0 + noise, "{line}");
            let q = quadrature.unwrap();
            assert!((f.albedo - q).abs() <= noise + 2e-3, "{line}");
        }
        MaterialKind::DIELECTRIC => {
            // Radiance weights: F + (1 - F) (eta_wo_side / eta_wi_side)^2, below 1 from
            // outside and above 1 from inside (radiance is compressed into the smaller
            // solid angle of the optically denser side); the unscaled BSDF conserves energy
            // exactly, and reflects with probability F.
            let (fr, _, _, eta_ti) = fresnel_dielectric(wo.z, m.ior);
            let (fr, eta_ti) = (fr as f64, eta_ti as f64);
            let want = fr + (1.0 - fr) * eta_ti * eta_ti;
            assert!(
                (f.albedo - want).abs() <= noise + 1e-4,
                "{line}: want {want}"
            );
            if wo.z > 0.0 {
                assert!(f.albedo <= 1.0 + noise, "{line}");
            }
            assert!((f.unscaled - 1.0).abs() <= 1e-5, "{line}");
            let binomial = (fr * (1.0 - fr) / FURNACE_SAMPLES as f64).sqrt();
            assert!((f.reflected - fr).abs() <= 4.0 * binomial + 1e-5, "{line}");
        }
        kind => panic!("no furnace rule for {kind:?}"),
    }
    line
}

/// Directional albedo E[weight] of every material at every furnace wo, with albedo 1
/// (100k samples each): within 1% of 1 for diffuse and conductor (it is exactly 1); <= 1 (+
/// 4 standard errors) for rough conductors, whose single-scattering GGX loses energy (down
/// to 0.31 at roughness 1, normal incidence: 1 - ln 2, analytically), and equal to the
/// quadrature of their `bsdf_eval` within noise.
///
/// The dielectric: a refraction's weight carries the radiance scaling
/// (eta_wo_side / eta_wi_side)^2 (radiance is compressed into the narrower cone of the
/// denser side), so E[weight] = F + (1 - F) (eta_wo_side / eta_wi_side)^2 is below 1 seen
/// from outside but up to ior^2 (1 - F) > 1 seen from inside: radiance is not energy, and
/// is not conserved across the boundary. What must be conserved is the flux, i.e. the
/// unscaled (adjoint, "importance") BSDF: dividing the scaling out gives F + (1 - F) = 1
/// for every sample. So the test checks E[weight] against that formula, E[weight] <= 1 from
/// outside, E[weight / scaling] = 1, and that reflection is chosen with probability F.
#[test]
fn white_furnace() {
    for (k, m) in all_materials().iter().enumerate() {
        for (theta, wo) in furnace_wos(m) {
            let s = stream("furnace", (k as u32) << 8 | theta as u32);
            let samples: Vec<Option<(Vec3, Vec3, f32)>> = (0..FURNACE_SAMPLES)
                .map(|i| sample(m, wo, u3(s, i)).map(|x| (x.wi, x.weight, x.eta)))
                .collect();
            for x in samples.iter().flatten() {
                assert!(
                    x.1.x == x.1.y && x.1.y == x.1.z,
                    "{}: grey weights",
                    material_name(m)
                );
            }
            let f = furnace_of(wo, &samples);
            let q = (!bsdf_is_delta(m)).then(|| albedo_quadrature(m, wo));
            eprintln!("{}", check_furnace(m, theta, wo, &f, q));
        }
    }
}

// ---------------------------------------------------------------------------------------
// The WGSL kernels.

/// GPU samples per material and furnace wo.
const GPU_FURNACE_SAMPLES: u32 = 4_000;

/// The WGSL `bsdf_sample` against the WGSL `bsdf_eval`/`bsdf_pdf` (pdf and weight
/// consistency of every non-delta sample, zero eval of delta samples), and the white
/// furnace on GPU samples (also against the CPU's albedo from the same random numbers).
#[test]
fn gpu_pdf_consistency_and_furnace() {
    let Some(ctx) = common::gpu("gpu_pdf_consistency_and_furnace") else {
        return;
    };
    let (rs, settings) = material_table(all_materials());
    let mats = all_materials();
    assert_eq!(
        rs.materials, mats,
        "the material table is uploaded as given"
    );
    // (material, theta, wo, u) per case, grouped by (material, wo).
    let mut groups = Vec::new();
    let mut cases = Vec::new();
    for (k, m) in mats.iter().enumerate() {
        for (theta, wo) in furnace_wos(m) {
            let s = stream("gpu furnace", (k as u32) << 8 | theta as u32);
            let start = cases.len();
            cases.extend((0..GPU_FURNACE_SAMPLES).map(|i| (k as u32, wo, u3(s, i))));
            groups.push((k, theta, wo, start..cases.len()));
        }
    }
    let t0 = std::time::Instant::now();
    let out = gpu_bsdf_samples(&ctx, &rs, &settings, &cases);
    // Evaluate every valid sample's direction.
    let eval_cases: Vec<(u32, Vec3, Vec3)> = cases
        .iter()
        .zip(&out)
        .filter(|(_, g)| g.valid)
        .map(|(&(m, wo, _), g)| (m, wo, g.wi))
        .collect();
    let evals = gpu_bsdf_evals(&ctx, &rs, &settings, &eval_cases);
    eprintln!(
        "gpu: {} sample cases, {} eval cases in {:.2} s",
        cases.len(),
        eval_cases.len(),
        t0.elapsed().as_secs_f64()
    );
    let mut errs: Vec<[Worst; 2]> = mats
        .iter()
        .map(|m| {
            [
                Worst::new(
                    format!("{}: sampled pdf vs bsdf_pdf (relative)", material_name(m)),
                    BASE_TOLERANCE,
                ),
                Worst::new(
                    format!("{}: weight vs eval / pdf (relative)", material_name(m)),
                    BASE_TOLERANCE,
                ),
            ]
        })
        .collect();
    let mut e = evals.iter();
    for (&(m, wo, u), g) in cases.iter().zip(&out) {
        if !g.valid {
            continue;
        }
        let (f, pdf) = *e.next().unwrap();
        let mat = &mats[m as usize];
        let show = || {
            format!(
                "{}: wo {wo} u {u:?}: {g:?}; eval {f} pdf {pdf}",
                material_name(mat)
            )
        };
        assert!(
            non_negative_finite(g.weight) && non_negative_finite(f),
            "{}",
            show()
        );
        assert!(
            g.pdf.is_finite() && g.pdf > 0.0 && pdf.is_finite() && pdf >= 0.0,
            "{}",
            show()
        );
        assert!((g.wi.length() - 1.0).abs() < 1e-5, "{}", show());
        assert_eq!(g.delta, bsdf_is_delta(mat), "{}", show());
        if g.delta {
            assert!(f == Vec3::ZERO && pdf == 0.0, "{}", show());
            continue;
        }
        let tol = tolerance(mat, wo, g.wi);
        errs[m as usize][0].add_tol(rel(pdf, g.pdf, 1e-6), tol, show);
        errs[m as usize][1].add_tol(rel3(g.weight, f / g.pdf, 1e-6), tol, show);
    }
    for (m, e) in mats.iter().zip(&errs) {
        if !bsdf_is_delta(m) {
            e[0].check("gpu");
            e[1].check("gpu");
        }
    }
    for (k, theta, wo, range) in groups {
        let m = &mats[k];
        let samples: Vec<Option<(Vec3, Vec3, f32)>> = out[range.clone()]
            .iter()
            .map(|g| {
                // The kernel does not return eta; it follows from the side wi is on.
                let (_, _, eta_it, _) = fresnel_dielectric(wo.z, m.ior);
                let eta = if g.wi.z * wo.z < 0.0 { eta_it } else { 1.0 };
                g.valid.then_some((g.wi, g.weight, eta))
            })
            .collect();
        let gpu = furnace_of(wo, &samples);
        let cpu: Vec<Option<(Vec3, Vec3, f32)>> = cases[range]
            .iter()
            .map(|&(_, wo, u)| sample(m, wo, u).map(|x| (x.wi, x.weight, x.eta)))
            .collect();
        let cpu = furnace_of(wo, &cpu);
        let line = format!(
            "gpu furnace: {} theta {theta:>5.1}: albedo {:.5} +- {:.5} (CPU, same numbers: {:.5}){}",
            material_name(m),
            gpu.albedo,
            gpu.se,
            cpu.albedo,
            if m.kind == MaterialKind::DIELECTRIC {
                format!(", without radiance scaling {:.5}", gpu.unscaled)
            } else {
                String::new()
            }
        );
        eprintln!("{line}");
        // The same random numbers: the albedos may differ only where a sample lands on a
        // threshold (validity, Fresnel lobe choice) by rounding, a few samples at most.
        assert!((gpu.albedo - cpu.albedo).abs() <= 2e-3, "{line}");
        let noise = 4.0 * gpu.se;
        match m.kind {
            MaterialKind::DIFFUSE | MaterialKind::CONDUCTOR => {
                assert!((gpu.albedo - 1.0).abs() <= 0.01, "{line}")
            }
            MaterialKind::ROUGH_CONDUCTOR => assert!(gpu.albedo <= 1.0 + noise, "{line}"),
            MaterialKind::DIELECTRIC => {
                assert!((gpu.unscaled - 1.0).abs() <= 1e-5, "{line}");
                if wo.z > 0.0 {
                    assert!(gpu.albedo <= 1.0 + noise, "{line}");
                }
            }
            kind => panic!("no furnace rule for {kind:?}"),
        }
    }
}

/// The chi-square test of the WGSL sampling routines of every non-delta material at the
/// oblique wo (CHI2_SAMPLES GPU samples each), against the CPU `bsdf_pdf` (which the
/// shader's `bsdf_pdf` matches: `gpu_pdf_consistency_and_furnace`, `tests/shader_units.rs`).
#[test]
fn gpu_chi2() {
    let Some(ctx) = common::gpu("gpu_chi2") else {
        return;
    };
    let (rs, settings) = material_table(all_materials());
    let mats = all_materials();
    let wo = chi2_wos()[1].1;
    let tested: Vec<usize> = (0..mats.len())
        .filter(|&k| !bsdf_is_delta(&mats[k]))
        .collect();
    let mut cases = Vec::new();
    for &k in &tested {
        let s = stream("gpu chi2", k as u32);
        cases.extend((0..CHI2_SAMPLES).map(|i| (k as u32, wo, u3(s, i))));
    }
    let t0 = std::time::Instant::now();
    let out = gpu_bsdf_samples(&ctx, &rs, &settings, &cases);
    eprintln!(
        "gpu chi2: {} samples in {:.2} s",
        out.len(),
        t0.elapsed().as_secs_f64()
    );
    let mut failures = Vec::new();
    for (j, &k) in tested.iter().enumerate() {
        let m = &mats[k];
        let n = CHI2_SAMPLES as usize;
        let wis: Vec<Option<Vec3>> = out[j * n..(j + 1) * n]
            .iter()
            .map(|g| g.valid.then_some(g.wi))
            .collect();
        // The CPU's samples from the same random numbers, for comparison.
        let s = stream("gpu chi2", k as u32);
        let cpu = cpu_samples(m, wo, s);
        for bin in binnings(m, wo) {
            let pdf = |wi| bsdf_pdf(m, wo, wi) as f64;
            let (r, _) = chi2_of(&wis, &bin, &pdf);
            let (c, _) = chi2_of(&cpu, &bin, &pdf);
            let line = format!(
                "gpu chi2: {}, wo oblique 45 deg, {}: {} (CPU, same numbers: {})",
                material_name(m),
                bin.what,
                show_chi2(&r),
                show_chi2(&c)
            );
            eprintln!("{line}");
            if !matches!(r, Ok(ref c) if c.p > significance()) {
                failures.push(line);
            }
        }
    }
    assert!(failures.is_empty(), "failed:\n{}", failures.join("\n"));
}
