//! Environment maps (`[sky] environment`) with known answers, on the CPU and (where an
//! adapter exists) the GPU: the image seen directly reads as the format says (and as
//! Mitsuba 3's `envmap` reads it), a constant environment is a white furnace, sampling
//! draws directions by the density it reports, and bad `[sky]` tables are errors.
//!
//! The map `assets/env/test_16x8.exr` (tools/gen_test_envmaps.py) holds, at row i and
//! column j, ((j + 1) / 16, (i + 1) / 8, 0.5), except a sun of (8192, 4096, 2048) at
//! row 2, column 11 and black at row 5, column 0.

use crate::common;

use common::chi2::{Binning, chi2_of, show_chi2};
use common::fs::{TempDir, root};
use common::rand::SplitMix;
use common::stats::mean_and_stderr;
use glam::{Vec2, Vec3};
use meshtrace::bvh::BuildParams;
use meshtrace::render::RenderScene;
use meshtrace::render::environment::{env_pdf, sample_env};
use meshtrace::scene::load_scene;

/// The test map's texel at (`row`, `column`), as its generator writes it.
fn texel(row: i64, column: i64) -> Vec3 {
    match (row, column) {
        (2, 11) => Vec3::new(8192.0, 4096.0, 2048.0),
        (5, 0) => Vec3::ZERO,
        _ => Vec3::new((column + 1) as f32 / 16.0, (row + 1) as f32 / 8.0, 0.5),
    }
}

/// The radiance the format defines along `dir` for the test map turned by `rotate`
/// degrees: d' = R_y(−rotate) d read at u = atan2(d'.x, −d'.z) / 2π, v = acos(d'.y) / π,
/// bilinearly between texel centres along u (around) and between rows at v = i / 7.
fn expected(dir: Vec3, rotate: f32, strength: f32) -> Vec3 {
    let (s, c) = (-rotate.to_radians()).sin_cos();
    let d = Vec3::new(c * dir.x + s * dir.z, dir.y, -s * dir.x + c * dir.z).normalize();
    let u = (d.x.atan2(-d.z) / (2.0 * std::f32::consts::PI)).rem_euclid(1.0);
    let v = d.y.acos() / std::f32::consts::PI;
    let x = u * 16.0 - 0.5;
    let y = v * 7.0;
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let at = |r: f32, k: f32| texel((r as i64).min(7), (k as i64).rem_euclid(16));
    let top = at(y0, x0) * (1.0 - fx) + at(y0, x0 + 1.0) * fx;
    let bottom = at(y0 + 1.0, x0) * (1.0 - fx) + at(y0 + 1.0, x0 + 1.0) * fx;
    strength * (top * (1.0 - fy) + bottom * fy)
}

/// A scene of no objects whose one-pixel camera, of a field of view of 0.001 degrees,
/// looks along `dir` at the test map.
fn looking(dir: Vec3, rotate: f32, strength: f32) -> String {
    let map = root().join("assets/env/test_16x8.exr");
    format!(
        "[camera]\nposition = [0.0, 0.0, 0.0]\nlook_at = [{}, {}, {}]\nvfov = 0.001\n\
         [render]\nwidth = 1\nheight = 1\nspp = 4\n\
         [sky]\nenvironment = {:?}\nrotate = {rotate}\nstrength = {strength}\n",
        dir.x,
        dir.y,
        dir.z,
        map.display().to_string()
    )
}

/// Directions that read the map at chosen places, rotated and not: the image centre along
/// +Z, a quarter from the left along +X, halfway between rows 1 and 2 at 45 degrees up,
/// beside the sun, the seam at u = 0 (looking along −Z), and the black texel.
#[test]
fn an_environment_seen_directly_reads_the_image_as_the_format_says() {
    let dir = TempDir::new("env-direct");
    let views: [(Vec3, f32); 9] = [
        (Vec3::Z, 0.0),
        (Vec3::X, 0.0),
        (Vec3::X, 90.0),
        (Vec3::new(0.0, 1.0, 1.0), 0.0),
        (Vec3::new(0.3, 0.6, -0.2), 0.0),
        (Vec3::new(0.2, 0.55, 0.1), 123.4),
        (Vec3::new(0.0, 0.3, -1.0), 0.0),
        (Vec3::new(0.0, -0.6, -1.0), 35.0),
        (Vec3::new(-1.0, -0.5, 0.2), -60.0),
    ];
    for (k, (d, rotate)) in views.into_iter().enumerate() {
        let d = d.normalize();
        let strength = 1.5;
        let scene = load_scene(&dir.write("scene.toml", looking(d, rotate, strength))).unwrap();
        let want = expected(d, rotate, strength);
        for (device, film) in common::render_both("env_direct", &scene) {
            let got = film.mean()[0];
            let error = (got - want).abs().max_element() / want.max_element().max(1e-3);
            assert!(
                error < 2e-3,
                "view {k} ({d}, rotate {rotate}) on the {device}: got {got}, expected {want}"
            );
        }
    }
    // The hand-worked cases of the format's mapping: +Z reads the image centre, between
    // columns 7 and 8 and halfway down (v = 0.5, y = 3.5: rows 3 and 4); rotate = 90 puts
    // the centre at +X.
    let centre = (texel(3, 7) + texel(3, 8) + texel(4, 7) + texel(4, 8)) / 4.0;
    assert!((expected(Vec3::Z, 0.0, 1.0) - centre).abs().max_element() < 1e-5);
    assert!((expected(Vec3::X, 90.0, 1.0) - centre).abs().max_element() < 1e-5);
}

/// A constant environment of radiance 1.25 × strength 2 around two flat-shaded cubes,
/// diffuse of albedo 1: every path ends in the environment carrying throughput 1, so every
/// pixel sees 2.5, through light sampling by the environment's distribution and MIS alike.
/// (Flat faces: with two smooth-shaded icospheres of 3 subdivisions instead, the mean read
/// 2.4963 ± 0.0007, interpolated normals on facets not conserving energy exactly, which the
/// stratified samples resolve.)
#[test]
fn a_constant_environment_is_a_white_furnace() {
    let dir = TempDir::new("env-furnace");
    dir.write_exr("flat.exr", 8, 4, &[[1.25, 1.25, 1.25, 1.0]; 32]);
    dir.write(
        "cube.obj",
        "v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n\
         f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 4 8 7 3\nf 1 5 8 4\nf 2 3 7 6\n",
    );
    let toml = "[camera]\nposition = [0.3, 0.5, 4.0]\nlook_at = [0.0, 0.0, 0.0]\nvfov = 30.0\n\
        [render]\nwidth = 32\nheight = 32\nspp = 256\n\
        [sky]\nenvironment = \"flat.exr\"\nstrength = 2.0\nrotate = 20.0\n\
        [materials.white]\ntype = \"diffuse\"\nalbedo = [1.0, 1.0, 1.0]\n\
        [[objects]]\nmesh = \"cube.obj\"\nmaterial = \"white\"\nscale = 0.7\nrotate = [10.0, 30.0, 0.0]\n\
        [[objects]]\nmesh = \"cube.obj\"\nmaterial = \"white\"\nscale = 0.3\ntranslate = [0.9, 0.8, 0.6]\n";
    let scene = load_scene(&dir.write("scene.toml", toml)).unwrap();
    for (device, film) in common::render_both("env_furnace", &scene) {
        let values: Vec<f32> = film.mean().iter().map(|p| p.y).collect();
        let (m, se) = mean_and_stderr(&values);
        assert!(
            se < 0.005,
            "{device}: standard error {se} too large to test"
        );
        assert!(
            (m - 2.5).abs() < 5.0 * se + 1e-6,
            "{device}: mean {m}, expected 2.5 (se {se})"
        );
    }
}

/// `sample_env` draws directions with the density `env_pdf` reports, on the sunny test map
/// turned by 35 degrees: the density each draw carries is `env_pdf` of its direction (but
/// for draws within rounding of a cell's edge), and
/// 200,000 draws fit that density over 200 cells of the sphere (chi-square).
#[test]
fn environment_sampling_draws_by_its_density() {
    let dir = TempDir::new("env-chi2");
    let map = root().join("assets/env/test_16x8.exr");
    let toml = format!(
        "[camera]\nposition = [0.0, 0.0, 3.0]\nlook_at = [0.0, 0.0, 0.0]\n\
         [sky]\nenvironment = {:?}\nrotate = 35.0\n",
        map.display().to_string()
    );
    let scene = load_scene(&dir.write("scene.toml", toml)).unwrap();
    let rs = RenderScene::new(&scene, &BuildParams::default()).unwrap();
    let mut r = SplitMix::new(0xe4_0002);
    let mut draws = Vec::new();
    // A draw within rounding of a cell's edge may read back in the neighbouring cell.
    let mut differ = 0;
    for _ in 0..200_000 {
        let (d, pdf) = sample_env(&rs, Vec2::new(r.range(0.0, 1.0), r.range(0.0, 1.0)));
        if pdf > 0.0 && (env_pdf(&rs, d) - pdf).abs() > 1e-3 * pdf {
            differ += 1;
        }
        draws.push((pdf > 0.0).then_some(d));
    }
    assert!(
        differ < draws.len() / 1000,
        "{differ} of {} draws carry a density other than env_pdf's",
        draws.len()
    );
    let pdf = |w: Vec3| env_pdf(&rs, w.normalize()) as f64;
    let (result, integration) = chi2_of(
        &draws,
        &Binning::around(Vec3::Y, std::f64::consts::PI),
        &pdf,
    );
    assert!(integration < 0.1, "integration error {integration}");
    let p = result.as_ref().map(|c| c.p).unwrap_or(0.0);
    assert!(p > 1e-4, "chi-square: {}", show_chi2(&result));
}

/// A sky table is an environment or a colour, not both; `rotate` and `strength` belong to
/// an environment; the image must exist and decode, and an EXR compressed in a way the exr
/// crate cannot read (DWAA, DWAB) says so. Each is a one-line error naming the field.
#[test]
fn bad_environments_are_errors_naming_the_field() {
    let dir = TempDir::new("env-errors");
    dir.write_exr("e.exr", 2, 2, &[[1.0; 4]; 4]);
    dir.write("junk.hdr", "not an image");
    // The test map with its header's compression turned to DWAA (8) and DWAB (9).
    let exr = std::fs::read(root().join("assets/env/test_16x8.exr")).unwrap();
    let key = b"compression\0compression\0";
    let at = exr.windows(key.len()).position(|w| w == key).unwrap() + key.len() + 4;
    for (name, code) in [("dwaa.exr", 8), ("dwab.exr", 9)] {
        let mut patched = exr.clone();
        patched[at] = code;
        dir.write(name, patched);
    }
    for (sky, needles) in [
        (
            "environment = \"e.exr\"\ncolor = [1.0, 1.0, 1.0]",
            &["sky.environment", "cannot be combined"][..],
        ),
        (
            "color = [1.0, 1.0, 1.0]\nrotate = 10.0",
            &["sky.rotate", "environment"],
        ),
        (
            "zenith = [1.0, 1.0, 1.0]\nhorizon = [0.0, 0.0, 0.0]\nstrength = 2.0",
            &["sky.strength"],
        ),
        (
            "environment = \"e.exr\"\nstrength = -1.0",
            &["sky.strength", "at least 0"],
        ),
        (
            "environment = \"e.exr\"\nrotate = inf",
            &["sky.rotate", "finite"],
        ),
        (
            "environment = \"gone.hdr\"",
            &["sky.environment", "gone.hdr"],
        ),
        (
            "environment = \"junk.hdr\"",
            &["sky.environment", "junk.hdr"],
        ),
        (
            "environment = \"dwaa.exr\"",
            &["sky.environment", "dwaa.exr", "DWAA", "ZIP"],
        ),
        (
            "environment = \"dwab.exr\"",
            &["sky.environment", "dwab.exr", "DWAB"],
        ),
    ] {
        let toml = format!(
            "[camera]\nposition = [0.0, 0.0, 3.0]\nlook_at = [0.0, 0.0, 0.0]\n[sky]\n{sky}\n"
        );
        let message = load_scene(&dir.write("scene.toml", toml))
            .expect_err(sky)
            .to_string();
        assert!(!message.contains('\n'), "{message}");
        assert!(message.contains("scene.toml"), "{message}");
        for needle in needles {
            assert!(
                message.contains(needle),
                "{sky}: {message:?} lacks {needle:?}"
            );
        }
    }
}
