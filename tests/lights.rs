//! Punctual lights (`[[lights]]`: point, spot, directional) against their closed forms, on
//! both renderers: a camera with a tiny field of view looks straight down at a Lambertian
//! floor of albedo rho, which a punctual light alone lights, so every pixel sees
//! rho / pi × E, E the irradiance the light gives that point: I cos / d² for a point or
//! spot (times the spot's falloff), E cos for a directional light.

mod common;

use common::fs::TempDir;
use meshtrace::scene::load_scene;

const RHO: f32 = 0.6;

/// The radiance every pixel sees under `light` (a `[[lights]]` table's body), on both
/// renderers: the mean pixel (the view spans 0.2 degrees, over which the irradiance
/// varies by under 1%; its mean is the centre's to second order).
fn floor_radiance(name: &str, light: &str) -> Vec<(&'static str, [f32; 3])> {
    let dir = TempDir::new(name);
    dir.write(
        "floor.obj",
        "v -50 0 -50\nv 50 0 -50\nv 50 0 50\nv -50 0 50\nf 1 4 3 2\n",
    );
    let toml = format!(
        "[camera]\nposition = [0.0, 1.0, 0.0]\nlook_at = [0.0, 0.0, 0.0]\nup = [0.0, 0.0, -1.0]\n\
         vfov = 0.2\n[render]\nwidth = 8\nheight = 8\nspp = 4\nmax_depth = 2\n\
         [materials.floor]\ntype = \"diffuse\"\nalbedo = [{RHO}, {RHO}, {RHO}]\n\
         [[objects]]\nmesh = \"floor.obj\"\nmaterial = \"floor\"\n[[lights]]\n{light}\n"
    );
    let scene = load_scene(&dir.write("scene.toml", toml)).unwrap_or_else(|e| panic!("{e}"));
    common::render_both(name, &scene)
        .into_iter()
        .map(|(device, film)| {
            let mean = film.mean();
            let avg = mean.iter().sum::<glam::Vec3>() / mean.len() as f32;
            for p in &mean {
                assert!(
                    (*p - avg).abs().max_element() <= 1e-2 * avg.max_element() + 1e-7,
                    "{name} on the {device}: pixels vary: {p} against {avg}"
                );
            }
            (device, avg.to_array())
        })
        .collect()
}

fn assert_radiance(name: &str, light: &str, irradiance: [f32; 3]) {
    for (device, l) in floor_radiance(name, light) {
        for c in 0..3 {
            let want = RHO / std::f32::consts::PI * irradiance[c];
            assert!(
                (l[c] - want).abs() <= 1e-3 * want.max(1e-3),
                "{name} on the {device}: channel {c}: {} against {want}",
                l[c]
            );
        }
    }
}

#[test]
fn a_point_light_gives_intensity_over_distance_squared() {
    assert_radiance(
        "point",
        "type = \"point\"\nposition = [0.0, 2.0, 0.0]\nintensity = [4.0, 8.0, 12.0]",
        [1.0, 2.0, 3.0],
    );
    // Off to the side: cos 45 deg over twice the squared height.
    let e = 8.0 * std::f32::consts::FRAC_1_SQRT_2 / 8.0;
    assert_radiance(
        "point oblique",
        "type = \"point\"\nposition = [2.0, 2.0, 0.0]\nintensity = [8.0, 8.0, 8.0]",
        [e, e, e],
    );
}

#[test]
fn a_point_light_under_the_floor_lights_nothing() {
    assert_radiance(
        "point below",
        "type = \"point\"\nposition = [0.0, -2.0, 0.0]\nintensity = [4.0, 8.0, 12.0]",
        [0.0, 0.0, 0.0],
    );
}

#[test]
fn a_spot_light_falls_off_linearly_in_angle_between_beam_width_and_cutoff() {
    // Straight down on the point: full intensity.
    assert_radiance(
        "spot on axis",
        "type = \"spot\"\nposition = [0.0, 2.0, 0.0]\ndirection = [0.0, -1.0, 0.0]\n\
         intensity = [4.0, 4.0, 4.0]\ncutoff_angle = 30.0\nbeam_width = 10.0",
        [1.0, 1.0, 1.0],
    );
    // The axis turned by 20 degrees: half-way from the beam width (10) to the cutoff (30).
    let t = 20f32.to_radians();
    assert_radiance(
        "spot in its falloff",
        &format!(
            "type = \"spot\"\nposition = [0.0, 2.0, 0.0]\ndirection = [{}, {}, 0.0]\n\
             intensity = [4.0, 4.0, 4.0]\ncutoff_angle = 30.0\nbeam_width = 10.0",
            t.sin(),
            -t.cos()
        ),
        [0.5, 0.5, 0.5],
    );
    // Turned by 40 degrees: outside the cutoff.
    let t = 40f32.to_radians();
    assert_radiance(
        "spot outside",
        &format!(
            "type = \"spot\"\nposition = [0.0, 2.0, 0.0]\ndirection = [{}, {}, 0.0]\n\
             intensity = [4.0, 4.0, 4.0]\ncutoff_angle = 30.0",
            t.sin(),
            -t.cos()
        ),
        [0.0, 0.0, 0.0],
    );
}

#[test]
fn a_directional_light_gives_irradiance_times_cosine() {
    let c = 60f32.to_radians().cos();
    assert_radiance(
        "directional",
        &format!(
            "type = \"directional\"\ndirection = [{}, {}, 0.0]\nirradiance = [2.0, 3.0, 4.0]",
            60f32.to_radians().sin(),
            -c
        ),
        [2.0 * c, 3.0 * c, 4.0 * c],
    );
}

#[test]
fn bad_lights_are_errors_naming_the_field() {
    let dir = TempDir::new("bad-lights");
    for (light, needle) in [
        (
            "type = \"point\"\nintensity = [1.0, 1.0, 1.0]",
            "lights[0].position: is required",
        ),
        (
            "type = \"point\"\nposition = [0.0, 1.0, 0.0]\nintensity = [1.0, 1.0, 1.0]\nirradiance = [1.0, 1.0, 1.0]",
            "lights[0].irradiance: is not a parameter of point lights",
        ),
        (
            "type = \"spot\"\nposition = [0.0, 1.0, 0.0]\ndirection = [0.0, 0.0, 0.0]\nintensity = [1.0, 1.0, 1.0]",
            "lights[0].direction: must not be zero",
        ),
        (
            "type = \"spot\"\nposition = [0.0, 1.0, 0.0]\ndirection = [0.0, -1.0, 0.0]\nintensity = [1.0, 1.0, 1.0]\ncutoff_angle = 10.0\nbeam_width = 20.0",
            "lights[0].beam_width",
        ),
        (
            "type = \"directional\"\ndirection = [0.0, -1.0, 0.0]\nirradiance = [-1.0, 1.0, 1.0]",
            "lights[0].irradiance: must not be negative",
        ),
        ("type = \"area\"", "scene.toml:"),
    ] {
        let toml = format!(
            "[camera]\nposition = [0.0, 1.0, 3.0]\nlook_at = [0.0, 0.0, 0.0]\n[[lights]]\n{light}\n"
        );
        let message = load_scene(&dir.write("scene.toml", toml))
            .expect_err(light)
            .to_string();
        assert!(message.contains(needle), "{light}: {message}");
        assert!(!message.contains('\n'), "{message}");
    }
}
