//! The `pbr` BSDF (glTF metallic-roughness, with KHR_materials_specular, _ior,
//! _transmission and _volume) on the CPU and, through the test kernels, on the GPU:
//!
//! - its exact sub-cases: `specular` 0 is Lambertian, metallic 1 smooth white is a perfect
//!   mirror, and transmission 1 smooth into a volume is the `dielectric`;
//! - each sample's pdf and weight are `bsdf_pdf` and `bsdf_eval / pdf`;
//! - reciprocity of its reflection and of thin-walled transmission;
//! - a white furnace: the directional albedo never exceeds 1 (transmission into a volume
//!   counted without its radiance scaling);
//! - Pearson's chi-square fit of its sampling to its pdf (`common::chi2`), on both hemispheres
//!   and about narrow lobes, for wo normal, oblique and grazing (and from inside a volume),
//!   on the CPU and the GPU.

use crate::common;

use common::chi2::{Binning, chi2_of, show_chi2, sidak_level};
use common::kernels::{gpu_bsdf_evals, gpu_bsdf_samples};
use common::materials::{mirror, spherical};
use common::rand::{hashed_u3, stream};
use common::scenes::material_table;
use common::stats::{Worst, mean_and_stderr, rel3};
use glam::{Vec2, Vec3};
use meshtrace::render::bsdf::{
    BsdfSample, bsdf_eval, bsdf_is_delta, bsdf_is_two_sided, bsdf_pdf, bsdf_sample,
    fresnel_schlick, ggx_alpha, pbr_fresnel,
};
use meshtrace::render::sheen::{sheen_albedo, sheen_reflect};
use meshtrace::scene::material::{MAT_SPEC_GLOSS, MAT_THIN_WALLED};
use meshtrace::scene::{Material, MaterialKind};

/// The seed of every random number here.
const SEED: u32 = 0x0b5d_0b12;

/// A named `pbr` material.
struct Case {
    name: &'static str,
    m: Material,
}

fn pbr(f: impl FnOnce(&mut Material)) -> Material {
    let mut m = Material::new(MaterialKind::PBR);
    f(&mut m);
    m
}

/// The materials every test runs over: every lobe alone and mixed, smooth and rough.
fn cases() -> Vec<Case> {
    let gold = Vec3::new(1.0, 0.78, 0.34);
    vec![
        Case {
            name: "plastic r=0.4",
            m: pbr(|m| (m.albedo, m.roughness) = (Vec3::new(0.8, 0.5, 0.3), 0.4)),
        },
        Case {
            name: "smooth plastic",
            m: pbr(|m| m.albedo = Vec3::new(0.2, 0.6, 0.9)),
        },
        Case {
            name: "gold r=0.3",
            m: pbr(|m| (m.albedo, m.metallic, m.roughness) = (gold, 1.0, 0.3)),
        },
        Case {
            name: "half metal r=0.7 tinted specular",
            m: pbr(|m| {
                (m.albedo, m.metallic, m.roughness) = (gold, 0.5, 0.7);
                (m.specular, m.specular_color, m.ior) = (0.6, Vec3::new(1.0, 0.5, 2.0), 1.8);
            }),
        },
        Case {
            name: "rough glass r=0.3",
            m: pbr(|m| (m.transmission, m.roughness) = (1.0, 0.3)),
        },
        Case {
            name: "frosted tinted glass r=0.6 ior 1.33 half transmission",
            m: pbr(|m| {
                (m.transmission, m.roughness, m.ior) = (0.5, 0.6, 1.33);
                m.albedo = Vec3::new(0.9, 0.8, 0.7);
            }),
        },
        Case {
            name: "thin rough wall r=0.5",
            m: pbr(|m| {
                (m.transmission, m.roughness, m.flags) = (0.7, 0.5, MAT_THIN_WALLED);
            }),
        },
        Case {
            name: "thin smooth wall",
            m: pbr(|m| (m.transmission, m.flags) = (0.8, MAT_THIN_WALLED)),
        },
        Case {
            name: "clear coat r=0.2 over plastic r=0.6",
            m: pbr(|m| {
                (m.albedo, m.roughness) = (Vec3::new(0.7, 0.2, 0.1), 0.6);
                (m.clearcoat, m.clearcoat_roughness) = (1.0, 0.2);
            }),
        },
        Case {
            name: "smooth half clear coat over gold r=0.5",
            m: pbr(|m| {
                (m.albedo, m.metallic, m.roughness) = (gold, 1.0, 0.5);
                m.clearcoat = 0.5;
            }),
        },
        Case {
            name: "clear coat r=0.3 about a tilted normal",
            m: pbr(|m| {
                (m.albedo, m.roughness) = (Vec3::new(0.3, 0.5, 0.8), 0.5);
                (m.clearcoat, m.clearcoat_roughness) = (1.0, 0.3);
                m.coat_normal = Vec3::new(0.3, -0.2, 1.0).normalize();
            }),
        },
        Case {
            name: "white sheen r=0.5 over white plastic",
            m: pbr(|m| {
                (m.roughness, m.sheen_color, m.sheen_roughness) = (0.7, Vec3::ONE, 0.5);
            }),
        },
        Case {
            name: "red sheen r=0.1 under a clear coat, over cloth",
            m: pbr(|m| {
                (m.albedo, m.roughness, m.specular) = (Vec3::new(0.2, 0.2, 0.6), 1.0, 0.5);
                (m.sheen_color, m.sheen_roughness) = (Vec3::new(1.0, 0.2, 0.2), 0.1);
                (m.clearcoat, m.clearcoat_roughness) = (0.3, 0.4);
            }),
        },
        Case {
            name: "specular-glossiness F0 (0.9, 0.6, 0.3) glossiness 0.6",
            m: pbr(|m| {
                (m.albedo, m.roughness, m.flags) = (Vec3::new(0.1, 0.3, 0.2), 0.4, MAT_SPEC_GLOSS);
                m.specular_color = Vec3::new(0.9, 0.6, 0.3);
            }),
        },
    ]
}

/// The directions a case is tested from: normal, oblique, grazing, and for a volume also
/// from inside.
fn wos(m: &Material) -> Vec<(&'static str, Vec3)> {
    let mut w = vec![
        ("normal", Vec3::Z),
        ("oblique 45 deg", spherical(45.0, 30.0)),
        ("grazing 85 deg", spherical(85.0, 200.0)),
    ];
    if !bsdf_is_two_sided(m) {
        w.push(("inside 30 deg", spherical(150.0, 70.0)));
        w.push(("inside grazing 80 deg", spherical(100.0, 300.0)));
    }
    w
}

fn sample(m: &Material, wo: Vec3, u: [f32; 3]) -> Option<BsdfSample> {
    bsdf_sample(m, wo, u[0], Vec2::new(u[1], u[2]))
}

#[test]
fn specular_zero_is_lambertian() {
    let diffuse = Material::diffuse(Vec3::new(0.3, 0.6, 0.9));
    let plastic = pbr(|m| (m.albedo, m.specular, m.roughness) = (diffuse.albedo, 0.0, 0.5));
    let s = stream("specular 0", 0);
    for i in 0..10_000 {
        let [a, b, c] = hashed_u3(SEED, s, i);
        let wo = meshtrace::render::sampling::sample_cosine_hemisphere(Vec2::new(a, b));
        let wi = meshtrace::render::sampling::sample_uniform_sphere(Vec2::new(c, a));
        assert_eq!(bsdf_eval(&plastic, wo, wi), bsdf_eval(&diffuse, wo, wi));
        assert_eq!(bsdf_pdf(&plastic, wo, wi), bsdf_pdf(&diffuse, wo, wi));
        let u = hashed_u3(SEED, s + 1, i);
        let (x, y) = (sample(&plastic, wo, u), sample(&diffuse, wo, u));
        match (x, y) {
            (Some(x), Some(y)) => {
                assert_eq!((x.wi, x.pdf, x.delta, x.eta), (y.wi, y.pdf, y.delta, y.eta));
                // The weight is eval / pdf, the same up to rounding.
                assert!(rel3(x.weight, y.weight, 1e-3) < 1e-6, "{x:?} {y:?}");
            }
            (x, y) => assert_eq!(x, y, "wo {wo} u {u:?}"),
        }
    }
}

/// The sheen's albedo table against a Monte Carlo integral of the lobe it tabulates, at
/// cosines and roughnesses between its grid points.
#[test]
fn sheen_albedo_table_integrates_the_lobe() {
    let mut worst = Worst::new("sheen albedo, table against integral (absolute)", 0.01);
    for (k, &(mu, roughness)) in [
        (0.9, 0.3),
        (0.5, 0.07),
        (0.2, 0.55),
        (0.05, 1.0),
        (0.7, 0.8),
        (0.33, 0.15),
    ]
    .iter()
    .enumerate()
    {
        let wo = Vec3::new((1.0f32 - mu * mu).sqrt(), 0.0, mu);
        let s = stream("sheen albedo", k as u32);
        let n = 400_000;
        let sum: f64 = (0..n)
            .map(|i| {
                let [a, b, _] = hashed_u3(SEED, s, i);
                // Uniform over the hemisphere: pdf 1 / (2 pi).
                let wi = meshtrace::render::sampling::sample_uniform_sphere(Vec2::new(a, b));
                let wi = Vec3::new(wi.x, wi.y, wi.z.abs());
                (sheen_reflect(Vec3::ONE, roughness, wo, wi).x * 2.0 * std::f32::consts::PI) as f64
            })
            .sum();
        let integral = sum / n as f64;
        let table = sheen_albedo(mu, roughness) as f64;
        eprintln!(
            "sheen albedo at cos {mu}, roughness {roughness}: table {table:.4}, integral {integral:.4}"
        );
        worst.add((table - integral).abs(), || {
            format!("cos {mu}, roughness {roughness}: table {table}, integral {integral}")
        });
    }
    worst.check("sheen albedo");
}

/// A specular-glossiness material, as the glTF reader converts it, reflects with
/// Schlick's Fresnel of its specular colour, as KHR_materials_pbrSpecularGlossiness
/// defines it.
#[test]
fn specular_glossiness_fresnel_is_schlick_of_its_specular_colour() {
    let f0 = Vec3::new(0.9, 0.6, 0.04);
    let m = pbr(|m| (m.flags, m.specular_color) = (MAT_SPEC_GLOSS, f0));
    let mut worst = Worst::new("pbr_fresnel against Schlick (absolute)", 1e-6);
    for k in 0..=50 {
        let c = 0.02 + 0.98 * k as f32 / 50.0;
        let (ours, schlick) = (pbr_fresnel(&m, c), fresnel_schlick(f0, c));
        worst.add((ours - schlick).abs().max_element() as f64, || {
            format!("cos {c}: {ours} against {schlick}")
        });
    }
    worst.check("specular-glossiness Fresnel");
}

#[test]
fn smooth_white_metal_is_a_perfect_mirror_and_smooth_glass_the_dielectric() {
    let metal = pbr(|m| m.metallic = 1.0);
    let mirror_ = Material::new(MaterialKind::CONDUCTOR);
    let glass = pbr(|m| (m.transmission, m.ior) = (1.0, 1.33));
    let dielectric = Material {
        ior: 1.33,
        ..Material::new(MaterialKind::DIELECTRIC)
    };
    assert!(bsdf_is_delta(&metal) && bsdf_is_delta(&glass));
    assert!(!bsdf_is_two_sided(&glass));
    let s = stream("smooth sub-cases", 0);
    let mut worst = Worst::new("smooth glass against the dielectric (relative)", 1e-5);
    for i in 0..20_000 {
        let [a, b, _] = hashed_u3(SEED, s, i);
        let wo = meshtrace::render::sampling::sample_uniform_sphere(Vec2::new(a, b));
        let u = hashed_u3(SEED, s + 1, i);
        if wo.z > 0.0 {
            assert_eq!(sample(&metal, wo, u), sample(&mirror_, wo, u), "wo {wo}");
        }
        let (x, y) = (sample(&glass, wo, u), sample(&dielectric, wo, u));
        match (x, y) {
            (Some(x), Some(y)) if x.delta == y.delta && (x.wi - y.wi).length() < 1e-6 => {
                worst.add(rel3(x.weight, y.weight, 1e-3), || {
                    format!("wo {wo}: pbr {x:?}, dielectric {y:?}")
                });
                assert_eq!(x.eta, y.eta, "wo {wo}");
            }
            (x, y) => {
                // The lobe choice may differ by rounding right at the Fresnel threshold.
                let f = meshtrace::render::bsdf::fresnel_dielectric(wo.z, 1.33).0;
                assert!(
                    (u[0] - f).abs() < 1e-5,
                    "wo {wo} u {u:?}: pbr {x:?}, dielectric {y:?}"
                );
            }
        }
    }
    worst.check("smooth glass");
}

#[test]
fn samples_have_the_pdf_and_weight_of_eval() {
    for (k, c) in cases().iter().enumerate() {
        let m = &c.m;
        let s = stream(c.name, k as u32);
        let mut pdf_err = Worst::new("pdf against bsdf_pdf (relative)", 1e-4);
        let mut weight_err = Worst::new("weight against eval / pdf (relative)", 1e-4);
        let mut valid = 0;
        for (_, wo) in wos(m) {
            for i in 0..20_000 {
                let Some(x) = sample(m, wo, hashed_u3(SEED, s, i)) else {
                    continue;
                };
                valid += 1;
                assert!(
                    x.weight.is_finite() && x.weight.min_element() >= 0.0,
                    "{x:?}"
                );
                if x.delta {
                    continue;
                }
                let pdf = bsdf_pdf(m, wo, x.wi);
                pdf_err.add(((x.pdf - pdf) / pdf).abs() as f64, || {
                    format!("{}: wo {wo}: {x:?}, bsdf_pdf {pdf}", c.name)
                });
                let w = bsdf_eval(m, wo, x.wi) / pdf;
                weight_err.add(rel3(x.weight, w, 1e-3), || {
                    format!("{}: wo {wo}: {x:?}, eval/pdf {w}", c.name)
                });
            }
        }
        assert!(valid > 10_000, "{}: {valid} samples", c.name);
        pdf_err.check(c.name);
        weight_err.check(c.name);
    }
}

#[test]
fn eval_is_positive_only_where_the_pdf_is() {
    for (k, c) in cases().iter().enumerate() {
        let m = &c.m;
        let s = stream(c.name, 100 + k as u32);
        for i in 0..20_000 {
            let [a, b, d] = hashed_u3(SEED, s, i);
            let wo = meshtrace::render::sampling::sample_uniform_sphere(Vec2::new(a, b));
            let wo = if bsdf_is_two_sided(m) {
                Vec3::new(wo.x, wo.y, wo.z.abs())
            } else {
                wo
            };
            let wi = meshtrace::render::sampling::sample_uniform_sphere(Vec2::new(d, a * b));
            let (f, pdf) = (bsdf_eval(m, wo, wi), bsdf_pdf(m, wo, wi));
            assert!(f.is_finite() && f.min_element() >= 0.0, "{}: {f}", c.name);
            assert!(pdf.is_finite() && pdf >= 0.0, "{}: {pdf}", c.name);
            if f.max_element() > 0.0 {
                assert!(pdf > 0.0, "{}: wo {wo} wi {wi}: f {f}, pdf 0", c.name);
            }
        }
    }
}

#[test]
fn reflection_and_thin_transmission_are_reciprocal() {
    let mut worst = Worst::new("f(wo, wi) against f(wi, wo) (relative)", 1e-4);
    for (k, c) in cases().iter().enumerate() {
        let m = &c.m;
        let s = stream(c.name, 200 + k as u32);
        for i in 0..20_000 {
            let [a, b, d] = hashed_u3(SEED, s, i);
            let wo = meshtrace::render::sampling::sample_cosine_hemisphere(Vec2::new(a, b));
            let wi = meshtrace::render::sampling::sample_uniform_sphere(Vec2::new(d, a * b));
            let thin = m.flags & MAT_THIN_WALLED != 0;
            if wi.z <= 1e-3 && !(thin && wi.z < -1e-3) {
                continue;
            }
            let f = bsdf_eval(m, wo, wi) / wi.z.abs();
            // Light going the other way sees the wall from wi's side: the frame turned over.
            let over = |w: Vec3| {
                if wi.z < 0.0 {
                    Vec3::new(w.x, w.y, -w.z)
                } else {
                    w
                }
            };
            let g = bsdf_eval(m, over(wi), over(wo)) / wo.z.abs();
            worst.add(rel3(f, g, 1e-3), || {
                format!("{}: wo {wo} wi {wi}: {f} {g}", c.name)
            });
        }
    }
    worst.check("reciprocity");
}

/// E[weight] per material and wo, with transmission into a volume counted without its
/// radiance scaling (1 / etap^2): must not exceed 1 beyond noise.
#[test]
fn white_furnace_never_gains_energy() {
    for (k, c) in cases().iter().enumerate() {
        let mut m = c.m;
        m.albedo = Vec3::ONE;
        for (wk, (wname, wo)) in wos(&m).into_iter().enumerate() {
            let s = stream(c.name, 300 + 10 * k as u32 + wk as u32);
            let weights: Vec<Vec3> = (0..100_000)
                .map(|i| match sample(&m, wo, hashed_u3(SEED, s, i)) {
                    Some(x) => {
                        let crossed = x.wi.z * wo.z < 0.0 && m.flags & MAT_THIN_WALLED == 0;
                        let scale = if crossed { x.eta * x.eta } else { 1.0 };
                        x.weight * scale
                    }
                    None => Vec3::ZERO,
                })
                .collect();
            // Each channel's albedo (a coloured specular lobe and a differently
            // coloured base peak in different channels).
            for ch in 0..3 {
                let values: Vec<f32> = weights.iter().map(|w| w[ch]).collect();
                let (mean, se) = mean_and_stderr(&values);
                eprintln!(
                    "furnace: {}, wo {wname}, channel {ch}: albedo {mean:.4} (se {se:.4})",
                    c.name
                );
                assert!(
                    mean <= 1.0 + 4.0 * se + 1e-4,
                    "{}, wo {wname}, channel {ch}: {mean}",
                    c.name
                );
            }
        }
    }
}

const CHI2_SAMPLES: u32 = 100_000;

/// The binnings a case is tested in: both hemispheres, and for a narrow reflection lobe the
/// cap about the mirror direction.
fn binnings(m: &Material, wo: Vec3) -> Vec<Binning> {
    let mut b = vec![Binning::local()];
    if m.transmission > 0.0 && m.roughness > 0.0 {
        b.push(Binning::around(-Vec3::Z, std::f64::consts::FRAC_PI_2));
    }
    if m.roughness > 0.0 && m.roughness < 0.5 {
        b.push(Binning::around(
            mirror(wo),
            (10.0 * ggx_alpha(m.roughness) as f64).min(std::f64::consts::FRAC_PI_2),
        ));
    }
    b
}

/// Runs the chi-square tests of every case on directions drawn by `draw` (the CPU's or
/// the GPU's samples), delta samples counted as refused.
/// Draws the directions of a material for `wo` from a stream: `None` for refused or delta.
type Draw<'a> = &'a dyn Fn(&Material, Vec3, u32) -> Vec<Option<Vec3>>;

fn chi2_all(device: &str, draw: Draw) {
    let cases = cases();
    let tests: usize = cases
        .iter()
        .map(|c| {
            wos(&c.m)
                .iter()
                .map(|&(_, wo)| binnings(&c.m, wo).len())
                .sum::<usize>()
        })
        .sum();
    let level = sidak_level(0.99, tests as i32);
    let mut failures = Vec::new();
    for (k, c) in cases.iter().enumerate() {
        if bsdf_is_delta(&c.m) {
            continue;
        }
        for (wk, (wname, wo)) in wos(&c.m).into_iter().enumerate() {
            let wis = draw(&c.m, wo, stream(c.name, 400 + 10 * k as u32 + wk as u32));
            for bin in binnings(&c.m, wo) {
                let (r, integration) = chi2_of(&wis, &bin, &|wi| bsdf_pdf(&c.m, wo, wi) as f64);
                let line = format!(
                    "chi2 {device}: {}, wo {wname}, {}: {} (integration error <= {integration:.2} sd)",
                    c.name,
                    bin.what,
                    show_chi2(&r)
                );
                eprintln!("{line}");
                if !matches!(r, Ok(ref x) if x.p > level) {
                    failures.push(line);
                }
            }
        }
    }
    assert!(
        failures.is_empty(),
        "failed (level {level:.2e}):\n{}",
        failures.join("\n")
    );
}

#[test]
fn chi2_cpu() {
    chi2_all("cpu", &|m, wo, s| {
        (0..CHI2_SAMPLES)
            .map(|i| sample(m, wo, hashed_u3(SEED, s, i)).and_then(|x| (!x.delta).then_some(x.wi)))
            .collect()
    });
}

#[test]
fn chi2_gpu() {
    let Some(ctx) = common::gpu("pbr chi2_gpu") else {
        return;
    };
    let mats: Vec<Material> = cases().iter().map(|c| c.m).collect();
    let (rs, settings) = material_table(mats.clone());
    chi2_all("gpu", &|m, wo, s| {
        let index = mats.iter().position(|x| x == m).expect("a case") as u32;
        let cases: Vec<(u32, Vec3, [f32; 3])> = (0..CHI2_SAMPLES)
            .map(|i| (index, wo, hashed_u3(SEED, s, i)))
            .collect();
        gpu_bsdf_samples(&ctx, &rs, &settings, &cases)
            .into_iter()
            .map(|g| (g.valid && !g.delta).then_some(g.wi))
            .collect()
    });
}

/// The WGSL twins against the Rust functions: samples and evaluations of every case.
#[test]
fn gpu_matches_cpu() {
    let Some(ctx) = common::gpu("pbr gpu_matches_cpu") else {
        return;
    };
    let mats: Vec<Material> = cases().iter().map(|c| c.m).collect();
    let (rs, settings) = material_table(mats.clone());
    let mut sample_cases = Vec::new();
    let mut eval_cases = Vec::new();
    for (k, c) in cases().iter().enumerate() {
        let s = stream(c.name, 500 + k as u32);
        for (_, wo) in wos(&c.m) {
            for i in 0..1_000 {
                let u = hashed_u3(SEED, s, i);
                sample_cases.push((k as u32, wo, u));
                let wi = meshtrace::render::sampling::sample_uniform_sphere(Vec2::new(u[1], u[2]));
                eval_cases.push((k as u32, wo, wi));
            }
        }
    }
    let samples = gpu_bsdf_samples(&ctx, &rs, &settings, &sample_cases);
    let mut mismatched = 0;
    let mut weight_err = Worst::new("sample weight, GPU against CPU (relative)", 1e-3);
    for (&(k, wo, u), g) in sample_cases.iter().zip(&samples) {
        let cpu = sample(&mats[k as usize], wo, u);
        match cpu {
            Some(x) if g.valid && (x.wi - g.wi).length() < 1e-3 => {
                weight_err.add(rel3(x.weight, g.weight, 1e-2), || {
                    format!(
                        "{}: wo {wo} u {u:?}: CPU {x:?}, GPU {g:?}",
                        cases()[k as usize].name
                    )
                });
            }
            None if !g.valid => {}
            _ => mismatched += 1,
        }
    }
    // A sample may take another lobe or be refused where rounding crosses a threshold.
    assert!(
        mismatched * 1000 <= sample_cases.len(),
        "{mismatched} of {} samples differ",
        sample_cases.len()
    );
    weight_err.check("pbr samples");
    let evals = gpu_bsdf_evals(&ctx, &rs, &settings, &eval_cases);
    let mut eval_err = Worst::new("eval and pdf, GPU against CPU (relative)", 1e-3);
    for (&(k, wo, wi), (f, pdf)) in eval_cases.iter().zip(&evals) {
        let m = &mats[k as usize];
        let (cf, cp) = (bsdf_eval(m, wo, wi), bsdf_pdf(m, wo, wi));
        eval_err.add(
            rel3(cf, *f, 1e-2).max(common::stats::rel(cp, *pdf, 1e-2)),
            || format!("wo {wo} wi {wi}: CPU {cf} {cp}, GPU {f} {pdf}"),
        );
    }
    eval_err.check("pbr evals");
}

/// Light reaches a transmitting surface from both sides, and next event estimation must
/// sample it there too: a sheet under a constant white sky, seen head-on through a tiny
/// field of view with paths of two segments, renders the BSDF's albedo for wo = the
/// normal, E[bsdf_sample weight], on both renderers. (With lights sampled on the viewer's
/// side alone, the sky behind the sheet was counted only by BSDF sampling, at its MIS
/// weight: the sheets came out 1%, 2% and 16% dark, 10, 8 and 64 standard errors.)
#[test]
fn lights_behind_a_transmitting_surface_are_sampled() {
    use common::scenes::{scene, square};
    use meshtrace::scene::{Camera, Mesh, NO_NORMAL, NO_UV, Sky, Triangle};
    for c in cases()
        .iter()
        .filter(|c| c.m.transmission > 0.0 && c.m.roughness > 0.0)
    {
        let m = c.m;
        // The albedo seen from the camera's side (wo = +Z): the mean sample weight.
        let s = stream(c.name, 900);
        let weights: Vec<f32> = (0..200_000)
            .map(|i| sample(&m, Vec3::Z, hashed_u3(SEED, s, i)).map_or(0.0, |x| x.weight.x))
            .collect();
        let (albedo, albedo_se) = mean_and_stderr(&weights);
        let mut mesh = Mesh::default();
        for p in [[-9.0, -9.0], [9.0, -9.0], [9.0, 9.0], [-9.0, 9.0]] {
            mesh.positions.push(Vec3::new(p[0], p[1], 0.0));
        }
        for p in [[0, 1, 2], [0, 2, 3]] {
            mesh.triangles.push(Triangle {
                p,
                n: [NO_NORMAL; 3],
                t: [NO_UV; 3],
                material: 0,
            });
        }
        let camera = Camera::new(
            Vec3::new(0.0, 0.0, 2.0),
            Vec3::ZERO,
            Vec3::Y,
            0.5,
            0.0,
            None,
        )
        .unwrap();
        let settings = square(8, 512, 2, 5);
        let sc = scene(mesh, vec![m], camera, Sky::Constant(Vec3::ONE), settings);
        let films = common::render_both("lights_behind_a_transmitting_surface_are_sampled", &sc);
        for (device, film) in films {
            // Pixels are independent estimates; their spread gives the error of the mean.
            let values: Vec<f32> = film.mean().iter().map(|p| p.x).collect();
            let (mean, se) = mean_and_stderr(&values);
            let tolerance = 4.0 * (se * se + albedo_se * albedo_se).sqrt() + 1e-4;
            eprintln!(
                "{} on the {device}: {mean:.4} (se {se:.4}) against albedo {albedo:.4} (se {albedo_se:.4})",
                c.name
            );
            assert!(
                (mean - albedo).abs() <= tolerance,
                "{} on the {device}: renders {mean}, albedo {albedo} (tolerance {tolerance})",
                c.name
            );
        }
    }
}
