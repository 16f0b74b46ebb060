//! Bounce limits by kind of scattering (`[render] diffuse_bounces`, `glossy_bounces`,
//! `transmission_bounces`), as Cycles counts them, against closed forms on both renderers.
//! Inside an enclosure whose walls all emit Le and scatter a fraction ρ of what they
//! receive, the light of i bounces is Le ρ^i; a limit of k lets a path scatter k + 1 times
//! and collect the emission after the last, so a pixel sees Le (1 + ρ + … + ρ^(k+1)).
//! The means are checked as `tests/analytic.rs` checks them (within 5 standard errors,
//! with the standard error small enough for a 1% bias to fail).

use crate::common;

use common::scenes::{add_box, emissive_enclosure, enclosure, square};
use common::stats::{assert_mean, assert_mean_within};
use glam::Vec3;
use meshtrace::render::RenderJob;
use meshtrace::scene::{BounceLimits, Material, MaterialKind, Mesh, RenderSettings};

/// Le (1 + ρ + … + ρ^(k+1)): the radiance of an emissive enclosure of albedo ρ when a
/// path may take k bounces of the walls' kind.
fn partial_sum(le: Vec3, rho: Vec3, k: u32) -> Vec3 {
    (0..=k + 1).map(|i| le * rho.powf(i as f32)).sum()
}

fn with_bounces(settings: RenderSettings, bounces: BounceLimits) -> RenderJob {
    RenderJob::new(RenderSettings {
        bounces,
        ..settings
    })
}

/// The diffuse emissive enclosure of `tests/analytic.rs` with `diffuse_bounces` 0 and 1:
/// direct light alone, then one indirect bounce, as in Cycles (whose dataset scripts set 1).
#[test]
fn diffuse_bounces_stop_diffuse_paths_as_cycles_counts_them() {
    let (s, _) = emissive_enclosure();
    let wall = s.materials[0];
    for k in [0, 1] {
        let job = with_bounces(
            s.settings,
            BounceLimits {
                diffuse: Some(k),
                ..BounceLimits::default()
            },
        );
        let expect = partial_sum(wall.emission, wall.albedo, k);
        for (device, film) in common::render_both_job("bounces_diffuse", &s, &job) {
            assert_mean(&format!("diffuse_bounces {k}"), device, &film, expect);
        }
    }
}

/// Glossy and transmission limits leave a diffuse enclosure's paths alone: Le / (1 − ρ).
#[test]
fn other_kinds_limits_leave_diffuse_paths_alone() {
    let (s, expect) = emissive_enclosure();
    let job = with_bounces(
        s.settings,
        BounceLimits {
            diffuse: None,
            glossy: Some(0),
            transmission: Some(0),
        },
    );
    for (device, film) in common::render_both_job("bounces_other_kinds", &s, &job) {
        assert_mean("glossy and transmission 0", device, &film, expect);
    }
}

/// A box of emissive mirrors (reflectance ρ): every path is the camera ray's chain of
/// mirror reflections, which `glossy_bounces` k cuts after k + 1 of them, whatever the
/// diffuse limit. The chain is the same for every sample but Russian roulette's, so the
/// mean is held to 0.01% as well as to its standard error.
#[test]
fn glossy_bounces_stop_mirror_chains() {
    let mut mesh = Mesh::default();
    add_box(&mut mesh, Vec3::splat(-1.0), Vec3::splat(1.0), 0, true);
    let mut mirror = Material::new(MaterialKind::CONDUCTOR);
    mirror.albedo = Vec3::new(0.8, 0.6, 0.4);
    mirror.emission = Vec3::new(0.25, 0.5, 0.75);
    let s = enclosure(mesh, mirror, square(32, 4, 64, 3));
    for k in [0, 2] {
        let job = with_bounces(
            s.settings,
            BounceLimits {
                diffuse: Some(0),
                glossy: Some(k),
                transmission: Some(0),
            },
        );
        let expect = partial_sum(mirror.emission, mirror.albedo, k);
        for (device, film) in common::render_both_job("bounces_glossy", &s, &job) {
            assert_mean_within(&format!("glossy_bounces {k}"), device, &film, expect, 1e-4);
        }
    }
}

/// The scene file's keys reach the settings, and a request's flags replace them one by one.
#[test]
fn scene_file_and_request_set_the_limits() {
    let toml = "[camera]\nposition = [0, 0, 3]\nlook_at = [0, 0, 0]\n\
                [render]\ndiffuse_bounces = 1\nglossy_bounces = 2\n\
                [[objects]]\nsphere = { center = [0, 0, 0], radius = 1 }\n";
    let s =
        meshtrace::scene::parse_scene(toml, std::path::Path::new("limits.toml")).expect("scene");
    let file = BounceLimits {
        diffuse: Some(1),
        glossy: Some(2),
        transmission: None,
    };
    assert_eq!(s.settings.bounces, file);
    let request = meshtrace::request::RenderRequest {
        glossy_bounces: Some(0),
        transmission_bounces: Some(3),
        ..Default::default()
    };
    let settings = request.settings(s.settings).expect("settings");
    assert_eq!(
        settings.bounces,
        BounceLimits {
            diffuse: Some(1),
            glossy: Some(0),
            transmission: Some(3),
        }
    );
    assert_eq!(
        settings.bounces.budget().to_array(),
        [2, 1, 4],
        "a limit of k is k + 1 scatterings"
    );
    assert_eq!(BounceLimits::default().budget().to_array(), [u32::MAX; 3]);
}

/// Each sample's lobe kind: transmission exactly where the direction crosses the surface,
/// diffuse for the diffuse kind and the pbr base's diffuse lobe, glossy for conductors, the
/// dielectric's reflection and the specular lobes; each kind a material has is drawn.
#[test]
fn samples_name_their_lobe_kind() {
    use meshtrace::render::bsdf::{LOBE_DIFFUSE, LOBE_GLOSSY, LOBE_TRANSMISSION, bsdf_sample};
    let mut rough_metal = Material::new(MaterialKind::ROUGH_CONDUCTOR);
    rough_metal.roughness = 0.4;
    let mut plastic = Material::new(MaterialKind::PBR);
    plastic.roughness = 0.3;
    let mut glass = Material::new(MaterialKind::PBR);
    glass.roughness = 0.2;
    glass.transmission = 1.0;
    let cases: [(&str, Material, &[u32]); 6] = [
        (
            "diffuse",
            Material::diffuse(Vec3::splat(0.5)),
            &[LOBE_DIFFUSE],
        ),
        (
            "conductor",
            Material::new(MaterialKind::CONDUCTOR),
            &[LOBE_GLOSSY],
        ),
        ("rough conductor", rough_metal, &[LOBE_GLOSSY]),
        (
            "dielectric",
            Material::new(MaterialKind::DIELECTRIC),
            &[LOBE_GLOSSY, LOBE_TRANSMISSION],
        ),
        ("pbr plastic", plastic, &[LOBE_DIFFUSE, LOBE_GLOSSY]),
        ("pbr glass", glass, &[LOBE_GLOSSY, LOBE_TRANSMISSION]),
    ];
    let wo = Vec3::new(0.3, -0.2, 0.8).normalize();
    for (name, m, kinds) in cases {
        let mut seen = [0u32; 3];
        for i in 0..4096u32 {
            let u = |k: u32| ((i.wrapping_mul(2654435761) ^ (k * 40503)) % 4096) as f32 / 4096.0;
            let Some(s) = bsdf_sample(&m, wo, u(1), glam::Vec2::new(u(2), u(3))) else {
                continue;
            };
            let crosses = s.wi.z * wo.z < 0.0;
            assert_eq!(
                crosses,
                s.lobe == LOBE_TRANSMISSION,
                "{name}: wi {} labelled {}",
                s.wi,
                s.lobe
            );
            seen[s.lobe as usize] += 1;
        }
        for lobe in 0..3 {
            assert_eq!(
                seen[lobe as usize] > 0,
                kinds.contains(&lobe),
                "{name}: lobe kinds drawn {seen:?}"
            );
        }
    }
}
