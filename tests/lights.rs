//! Lights that are not surfaces (`[[lights]]`: point, spot, directional, rect) against their
//! closed forms, on both renderers: a camera with a tiny field of view looks straight down
//! at a Lambertian floor of albedo rho, which one light alone lights, so every pixel sees
//! rho / pi × E, E the irradiance the light gives that point: I cos / d² for a point or
//! spot (times the spot's falloff), E cos for a directional light, Lambert's polygon
//! formula for a rectangle.

use crate::common;

use common::fs::TempDir;
use common::stats::{fraction_close, pixel_channels as channels};
use common::{cpu_render, gpu_render};
use meshtrace::bvh::BuildParams;
use meshtrace::film::Film;
use meshtrace::render::{RenderJob, RenderScene};
use meshtrace::scene::{RenderSettings, load_scene};

const RHO: f32 = 0.6;

/// Samples a pixel the GPU traces where a check asks for more. The GPU replays the CPU's
/// paths from the same random numbers (tests/gpu_vs_cpu.rs), so its first samples, matched
/// pixel by pixel against the CPU's, and the CPU's whole render, matched against the closed
/// form, test both renderers; lavapipe traces an 8×8 film in one workgroup on one core,
/// about 5 s for 1,024 samples a pixel, against 0.06 s on the CPU.
const GPU_REPLAY_SPP: u32 = 16;

/// The radiance every pixel sees under `light` (a `[[lights]]` table's body) with `extra`
/// scene text, at `spp` samples a pixel, by device: the mean pixel (the view spans 0.2
/// degrees, over which the irradiance varies by under 1%; its mean is the centre's to
/// second order). Pixels may differ from the mean by `spread` of it. Above
/// [`GPU_REPLAY_SPP`] the GPU instead renders that many samples, which must replay the
/// CPU's, and only the CPU's mean comes back.
fn floor_radiance(
    name: &str,
    light: &str,
    extra: &str,
    spp: u32,
    spread: f32,
) -> Vec<(&'static str, [f32; 3])> {
    let dir = TempDir::new(name);
    dir.write(
        "floor.obj",
        "v -50 0 -50\nv 50 0 -50\nv 50 0 50\nv -50 0 50\nf 1 4 3 2\n",
    );
    let toml = format!(
        "[camera]\nposition = [0.0, 1.0, 0.0]\nlook_at = [0.0, 0.0, 0.0]\nup = [0.0, 0.0, -1.0]\n\
         vfov = 0.2\n[render]\nwidth = 8\nheight = 8\nspp = {spp}\nmax_depth = 2\n\
         [materials.floor]\ntype = \"diffuse\"\nalbedo = [{RHO}, {RHO}, {RHO}]\n\
         [[objects]]\nmesh = \"floor.obj\"\nmaterial = \"floor\"\n{extra}\n[[lights]]\n{light}\n"
    );
    let scene = load_scene(&dir.write("scene.toml", toml)).unwrap_or_else(|e| panic!("{e}"));
    let rs = RenderScene::new(&scene, &BuildParams::default()).expect("BVH");
    let job = RenderJob::new(scene.settings);
    let mean = |device: &str, film: &Film| {
        let mean = film.mean();
        let avg = mean.iter().sum::<glam::Vec3>() / mean.len() as f32;
        for p in &mean {
            assert!(
                (*p - avg).abs().max_element() <= spread * avg.max_element() + 1e-7,
                "{name} on the {device}: pixels vary: {p} against {avg}"
            );
        }
        avg.to_array()
    };
    let mut out = vec![("cpu", mean("cpu", &cpu_render(&rs, &job)))];
    if let Some(ctx) = common::gpu(name) {
        if spp <= GPU_REPLAY_SPP {
            out.push(("gpu", mean("gpu", &gpu_render(&ctx, &rs, &job))));
        } else {
            let short = RenderJob::new(RenderSettings {
                spp: GPU_REPLAY_SPP,
                ..scene.settings
            });
            let (gpu, cpu) = (gpu_render(&ctx, &rs, &short), cpu_render(&rs, &short));
            let close = fraction_close(&channels(&gpu), &channels(&cpu));
            assert!(
                close >= 0.99,
                "{name}: the GPU's first {GPU_REPLAY_SPP} samples replay the CPU's in {close} of the pixel channels"
            );
        }
    }
    out
}

fn assert_radiance(name: &str, light: &str, irradiance: [f32; 3]) {
    assert_radiance_within(name, light, "", 4, 1e-3, irradiance);
}

/// [`assert_radiance`] with `extra` scene text, at `spp` samples, within `tolerance` of
/// the closed form (and pixels within 5 times that of their mean).
fn assert_radiance_within(
    name: &str,
    light: &str,
    extra: &str,
    spp: u32,
    tolerance: f32,
    irradiance: [f32; 3],
) {
    let spread = (5.0 * tolerance).max(1e-2);
    for (device, l) in floor_radiance(name, light, extra, spp, spread) {
        for c in 0..3 {
            let want = RHO / std::f32::consts::PI * irradiance[c];
            assert!(
                (l[c] - want).abs() <= tolerance * want.max(1e-3),
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

/// Up to eight point, spot and directional lights are each sampled at every vertex, so that
/// one sample a pixel already gives their sum exactly (a pick of one of them a sample would
/// leave pixels at 0 or several times the mean); nine fall back to a pick, and stay right on
/// average.
#[test]
fn lights_without_area_are_sampled_in_full() {
    assert_radiance_within(
        "three lights at 1 spp",
        "type = \"point\"\nposition = [0.0, 2.0, 0.0]\nintensity = [4.0, 4.0, 4.0]",
        "[[lights]]\ntype = \"directional\"\ndirection = [0.0, -1.0, 0.0]\n\
         irradiance = [2.0, 2.0, 2.0]\n[[lights]]\ntype = \"spot\"\nposition = [0.0, 2.0, 0.0]\n\
         direction = [0.0, -1.0, 0.0]\nintensity = [4.0, 4.0, 4.0]\ncutoff_angle = 30.0",
        1,
        1e-3,
        [4.0, 4.0, 4.0],
    );
    let nine: String = (1..=8)
        .map(|k| format!("[[lights]]\ntype = \"point\"\nposition = [0.0, 2.0, 0.0]\nintensity = [{k}.0, {k}.0, {k}.0]\n"))
        .collect();
    assert_radiance_within(
        "nine lights",
        "type = \"point\"\nposition = [0.0, 2.0, 0.0]\nintensity = [9.0, 9.0, 9.0]",
        &nine,
        64,
        0.03,
        [11.25, 11.25, 11.25],
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

/// A sun with `shadows = false` shines through a quad in its way; with shadows it does not.
#[test]
fn a_directional_light_without_shadows_passes_through_what_is_in_its_way() {
    let t = 60f32.to_radians();
    // The shadow ray from the floor's centre crosses y = 0.5 at x = -0.5 tan 60°: a quad
    // 0.4 wide there, out of the camera's view, blocks it.
    let blocker = format!(
        "[[objects]]\nmesh = \"floor.obj\"\nmaterial = \"floor\"\nscale = [0.004, 1.0, 0.004]\n\
         translate = [{}, 0.5, 0.0]",
        -0.5 * t.tan()
    );
    let sun = |shadows: bool| {
        format!(
            "type = \"directional\"\ndirection = [{}, {}, 0.0]\nirradiance = [2.0, 3.0, 4.0]\n\
             shadows = {shadows}",
            t.sin(),
            -t.cos()
        )
    };
    let c = t.cos();
    assert_radiance_within(
        "sun without shadows",
        &sun(false),
        &blocker,
        4,
        1e-3,
        [2.0 * c, 3.0 * c, 4.0 * c],
    );
    assert_radiance_within("sun with shadows", &sun(true), &blocker, 4, 1e-3, [0.0; 3]);
}

/// The irradiance at the origin, facing +Y, from a polygon of uniform radiance 1 with
/// corners `v` (Lambert: half the sum over its edges of the angle each subtends times the
/// Y component of the unit normal of the plane through the edge and the point).
fn polygon_irradiance(v: &[glam::Vec3]) -> f32 {
    let mut e = 0.0;
    for i in 0..v.len() {
        let (a, b) = (v[i].normalize(), v[(i + 1) % v.len()].normalize());
        e += a.dot(b).clamp(-1.0, 1.0).acos() * a.cross(b).normalize().y;
    }
    0.5 * e.abs()
}

/// A rectangle light gives the irradiance of Lambert's polygon formula: small and high,
/// wide as the sky and low, tilted and off to the side; and nothing from behind.
#[test]
fn a_rect_light_gives_lamberts_polygon_irradiance() {
    use glam::Vec3;
    let radiance = [1.0f32, 2.0, 3.0];
    for (name, center, direction, size) in [
        (
            "rect above",
            Vec3::new(0.0, 2.0, 0.0),
            Vec3::NEG_Y,
            [1.0f32, 3.0],
        ),
        (
            "rect as wide as the sky",
            Vec3::new(0.3, 0.5, -0.2),
            Vec3::NEG_Y,
            [1000.0, 1000.0],
        ),
        (
            "rect tilted",
            Vec3::new(1.5, 1.0, 0.5),
            Vec3::new(-1.0, -0.5, 0.2),
            [0.8, 0.5],
        ),
        (
            "rect far",
            Vec3::new(0.0, 40.0, 0.0),
            Vec3::NEG_Y,
            [0.5, 0.5],
        ),
    ] {
        // The corners as the scene format places them: the width along direction × Y (X
        // when the light faces straight down), the height along direction × width.
        let n = direction.normalize();
        let u = if n.y.abs() < 0.9999 {
            n.cross(Vec3::Y).normalize()
        } else {
            Vec3::X
        };
        let (eu, ev) = (size[0] * u, size[1] * n.cross(u));
        let c = center - 0.5 * (eu + ev);
        let e = polygon_irradiance(&[c, c + eu, c + eu + ev, c + ev]);
        let light = format!(
            "type = \"rect\"\nposition = [{}, {}, {}]\ndirection = [{}, {}, {}]\n\
             size = [{}, {}]\nradiance = [1.0, 2.0, 3.0]",
            center.x, center.y, center.z, direction.x, direction.y, direction.z, size[0], size[1]
        );
        assert_radiance_within(name, &light, "", 1024, 1e-2, radiance.map(|l| l * e));
    }
    assert_radiance(
        "rect facing away",
        "type = \"rect\"\nposition = [0.0, 2.0, 0.0]\ndirection = [0.0, 1.0, 0.0]\n\
         size = [1.0, 1.0]\nradiance = [1.0, 1.0, 1.0]",
        [0.0; 3],
    );
}

/// BSDF-sampled rays meet rectangle lights, as in Cycles: a perfect mirror (reflectance 1)
/// under a rectangle shows its radiance, exactly, on both renderers (next event estimation
/// cannot sample a mirror, so before BSDF rays met them mirrors showed nothing). A camera
/// looking straight at the rectangle does not see it.
#[test]
fn a_mirror_shows_a_rect_light_that_the_camera_does_not_see() {
    let dir = TempDir::new("rect-mirror");
    dir.write(
        "floor.obj",
        "v -50 0 -50\nv 50 0 -50\nv 50 0 50\nv -50 0 50\nf 1 4 3 2\n",
    );
    for (name, look_at, facing, want) in [
        ("mirror", [0.0, 0.0, 0.0], -1.0, [1.0f32, 2.0, 3.0]),
        ("straight at it", [0.0, 2.0, 0.0], -1.0, [0.0; 3]),
    ] {
        let toml = format!(
            "[camera]\nposition = [0.0, 1.0, 0.0]\nlook_at = {look_at:?}\nup = [0.0, 0.0, -1.0]\n\
             vfov = 0.2\n[render]\nwidth = 8\nheight = 8\nspp = 4\nmax_depth = 4\n\
             [materials.mirror]\ntype = \"conductor\"\nalbedo = [1.0, 1.0, 1.0]\n\
             [[objects]]\nmesh = \"floor.obj\"\nmaterial = \"mirror\"\n\
             [[lights]]\ntype = \"rect\"\nposition = [0.0, 2.0, 0.0]\ndirection = [0.0, {facing}, 0.0]\n\
             size = [10.0, 10.0]\nradiance = [1.0, 2.0, 3.0]\n"
        );
        let scene = load_scene(&dir.write("scene.toml", toml)).unwrap_or_else(|e| panic!("{e}"));
        for (device, film) in common::render_both(name, &scene) {
            for p in film.mean() {
                for c in 0..3 {
                    assert!(
                        (p[c] - want[c]).abs() <= 1e-5 * want[c].max(1.0),
                        "{name} on the {device}: {p} against {want:?}"
                    );
                }
            }
        }
    }
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
        (
            "type = \"rect\"\nposition = [0.0, 1.0, 0.0]\ndirection = [0.0, -1.0, 0.0]\nsize = [1.0, 0.0]\nradiance = [1.0, 1.0, 1.0]",
            "lights[0].size[1]: must be positive",
        ),
        (
            "type = \"point\"\nposition = [0.0, 1.0, 0.0]\nintensity = [1.0, 1.0, 1.0]\nshadows = false",
            "lights[0].shadows: is not a parameter of point lights",
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

/// A lighting preset whose light the floor's irradiance has a closed form for: the area key
/// light straight above gives its `irradiance` at the floor's centre (where the bounding
/// sphere is centred, and where the camera looks); a uniform world gives π times its
/// radiance; the suns give the sum of their irradiances times their cosines, read from the
/// lights the preset made, which the scene file's name (its uid) and the seed draw.
#[test]
fn lighting_presets_give_their_closed_forms() {
    // A light that adds nothing, for the helper's `[[lights]]` table.
    let dark = "type = \"point\"\nposition = [0.0, 5.0, 0.0]\nintensity = [0.0, 0.0, 0.0]";
    let area = "[lighting]\npreset = \"area\"\nelevation = 90.0\nirradiance = 2.0\nworld = 0.0";
    assert_radiance_within("lighting area", dark, area, 256, 1e-2, [2.0; 3]);
    let uniform = "[lighting]\npreset = \"uniform\"\ncolor = [0.2, 0.4, 0.8]";
    let e = [0.2f32, 0.4, 0.8].map(|c| std::f32::consts::PI * c);
    assert_radiance_within("lighting uniform", dark, uniform, 1024, 1e-2, e);

    let suns = "[lighting]\npreset = \"suns\"\ncount = 3\nseed = 5\nworld = 0.0";
    let scene_with = |file: &str| {
        let dir = TempDir::new("lighting suns drawn");
        let toml = format!(
            "[camera]\nposition = [0.0, 1.0, 3.0]\nlook_at = [0.0, 0.0, 0.0]\n{suns}\n\
             [[objects]]\nsphere = {{ center = [0.0, 0.0, 0.0], radius = 1.0 }}\n"
        );
        load_scene(&dir.write(file, toml)).unwrap_or_else(|e| panic!("{e}"))
    };
    let lights = scene_with("scene.toml").lights;
    assert_eq!(lights.len(), 3);
    assert_eq!(
        scene_with("scene.toml").lights,
        lights,
        "the same uid, the same suns"
    );
    assert_ne!(
        scene_with("other.toml").lights,
        lights,
        "another uid, other suns"
    );
    let mut e = 0.0;
    for light in &lights {
        let meshtrace::scene::PunctualLight::Directional {
            direction,
            irradiance,
            shadows: true,
        } = light
        else {
            panic!("not a sun with shadows: {light:?}");
        };
        e += irradiance.x * -direction.y;
    }
    // The helper's scene file is scene.toml too: the same suns.
    assert_radiance_within("lighting suns", dark, suns, 4, 1e-3, [e; 3]);
}

/// The `hdri` preset, against the floor's closed form: a latitude-longitude image whose
/// upper half is one colour and lower half a far brighter one, at strength 2. The floor
/// sees the upper half alone, E = π · 2 · upper (the halves meet at the horizon, where the
/// cosine is 0); an image read upside down, or a strength not applied, would be far off.
#[test]
fn the_hdri_preset_lights_the_floor_from_its_upper_half() {
    let dark = "type = \"point\"\nposition = [0.0, 5.0, 0.0]\nintensity = [0.0, 0.0, 0.0]";
    let dir = TempDir::new("lighting hdri image");
    let (w, h) = (8, 64);
    let (upper, lower) = ([0.3f32, 0.2, 0.1], [5.0f32, 5.0, 5.0]);
    let texels: Vec<[f32; 4]> = (0..w * h)
        .map(|i| {
            let c = if i / w < h / 2 { upper } else { lower };
            [c[0], c[1], c[2], 1.0]
        })
        .collect();
    let sky = dir.write_exr("sky.exr", w, h, &texels);
    let hdri = format!(
        "[lighting]\npreset = \"hdri\"\nenvironment = \"{}\"\nstrength = 2.0",
        sky.display()
    );
    let e = upper.map(|c| std::f32::consts::PI * 2.0 * c);
    assert_radiance_within("lighting hdri", dark, &hdri, 1024, 1e-2, e);
}

#[test]
fn bad_lighting_is_an_error_naming_the_key() {
    let dir = TempDir::new("bad-lighting");
    for (body, needle) in [
        (
            "preset = \"suns\"\nsize = 2.0",
            "lighting.size: is not a parameter of the `suns` preset",
        ),
        (
            "preset = \"sunny\"",
            "lighting.preset: `sunny` is not a lighting preset",
        ),
        (
            "preset = \"area\"\nirradiance = -1.0",
            "lighting.irradiance: must be at least 0",
        ),
        (
            "preset = \"hdri\"\nenvironment = \"missing.hdr\"",
            "lighting.environment",
        ),
        (
            "preset = \"uniform\"\n[sky]\ncolor = [1.0, 1.0, 1.0]",
            "lighting: cannot be combined with `[sky]`",
        ),
    ] {
        let toml = format!(
            "[camera]\nposition = [0.0, 1.0, 3.0]\nlook_at = [0.0, 0.0, 0.0]\n[lighting]\n{body}\n"
        );
        let message = load_scene(&dir.write("scene.toml", toml))
            .expect_err(body)
            .to_string();
        assert!(message.contains("scene.toml"), "{body}: {message}");
        assert!(message.contains(needle), "{body}: {message}");
        assert!(!message.contains('\n'), "{message}");
    }
}
