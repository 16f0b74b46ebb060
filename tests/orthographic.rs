//! The orthographic camera, on both renderers: parallel rays, so a square covers the same
//! pixels at any distance, and exactly the pixels its size in view units gives; its
//! depth is its distance along the view axis everywhere; a glTF orthographic camera reads
//! `ymag`; scene files refuse a perspective camera's fields on it.

use crate::common;

use common::fs::TempDir;
use meshtrace::film::{Aov, AovValues, Film};
use meshtrace::render::RenderJob;
use meshtrace::render::camera::{CameraRays, generate_camera_ray};
use meshtrace::render::rng::Rng;
use meshtrace::scene::{Scene, parse_scene};

fn load(dir: &TempDir, text: &str) -> Scene {
    parse_scene(text, &dir.join("scene.toml")).unwrap_or_else(|e| panic!("{e}"))
}

fn channel(film: &Film, aov: Aov) -> Vec<f32> {
    match film.aov_values(aov).expect("the channel").remove(0) {
        AovValues::F32(v) => v,
        AovValues::U32(_) => panic!("not float"),
    }
}

/// An orthographic view 2 units high of a unit square at `distance`, 32×32 pixels: the
/// square spans pixels 8 to 24 along both axes, edges on pixel boundaries.
fn square_at(dir: &TempDir, distance: f32) -> Scene {
    dir.write(
        "square.obj",
        "v -0.5 -0.5 0\nv 0.5 -0.5 0\nv 0.5 0.5 0\nv -0.5 0.5 0\nf 1 2 3 4\n",
    );
    load(
        dir,
        &format!(
            r#"
[camera]
position = [0.0, 0.0, {distance}]
look_at = [0.0, 0.0, 0.0]
projection = "orthographic"
height = 2.0
[render]
width = 32
height = 32
spp = 4
[[objects]]
mesh = "square.obj"
"#
        ),
    )
}

#[test]
fn a_square_covers_the_same_pixels_at_any_distance() {
    let dir = TempDir::new("ortho-square");
    for distance in [3.0, 300.0] {
        let scene = square_at(&dir, distance);
        let job =
            RenderJob::new(scene.settings).with_aovs(Aov::mask(&[Aov::Alpha, Aov::Depth]), false);
        for (device, film) in common::render_both_job("ortho-square", &scene, &job) {
            let alpha = channel(&film, Aov::Alpha);
            let depth = channel(&film, Aov::Depth);
            for y in 0..32 {
                for x in 0..32 {
                    let i = y * 32 + x;
                    let inside = (8..24).contains(&x) && (8..24).contains(&y);
                    let want = if inside { 1.0 } else { 0.0 };
                    assert_eq!(
                        alpha[i], want,
                        "{device}, distance {distance}: pixel ({x}, {y}) alpha"
                    );
                    if inside {
                        assert!(
                            (depth[i] - distance).abs() <= 1e-5 * distance,
                            "{device}, distance {distance}: pixel ({x}, {y}) depth {}",
                            depth[i]
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn rays_are_parallel_and_start_across_the_view() {
    let dir = TempDir::new("ortho-rays");
    let scene = square_at(&dir, 10.0);
    let cam = CameraRays::new(&scene.camera, 64, 32);
    for (px, py) in [(0, 0), (63, 31), (17, 5)] {
        let ray = generate_camera_ray(&cam, px, py, &Rng::new(py * 64 + px, 3, 0));
        assert_eq!(ray.dir, scene.camera.forward);
        // Twice as wide as high: x spans [-2, 2], y [-1, 1], on the plane z = 10.
        assert!((ray.origin.z - 10.0).abs() < 1e-6);
        let (x, y) = (ray.origin.x, ray.origin.y);
        assert!(
            x >= -2.0 + px as f32 / 16.0 && x <= -2.0 + (px + 1) as f32 / 16.0,
            "{x}"
        );
        assert!(
            y <= 1.0 - py as f32 / 16.0 && y >= 1.0 - (py + 1) as f32 / 16.0,
            "{y}"
        );
    }
}

#[test]
fn a_gltf_orthographic_camera_reads_ymag() {
    let mut g = common::gltf::Asset::new();
    g.triangle(serde_json::json!({}));
    let camera = g.push(
        "cameras",
        serde_json::json!({"type": "orthographic",
            "orthographic": {"xmag": 3.0, "ymag": 1.5, "znear": 0.1, "zfar": 100.0}}),
    );
    let node = g.node(serde_json::json!({"camera": camera, "translation": [0.0, 0.0, 4.0]}));
    g.scene(&[0, node]);
    let dir = TempDir::new("ortho-gltf");
    let path = dir.write("a.gltf", g.embedded());
    let scene = meshtrace::scene::load_scene(&path).unwrap_or_else(|e| panic!("{e}"));
    assert!(scene.camera.is_orthographic());
    assert_eq!(scene.camera.ortho_height, 3.0);
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
}

#[test]
fn scene_files_refuse_a_perspective_field_on_an_orthographic_camera() {
    let dir = TempDir::new("ortho-errors");
    let base = "[camera]\nposition = [0.0, 0.0, 3.0]\nlook_at = [0.0, 0.0, 0.0]\n";
    for (extra, field) in [
        (
            "projection = \"orthographic\"\n",
            "camera.height: is required",
        ),
        (
            "projection = \"orthographic\"\nheight = 2.0\nvfov = 30.0\n",
            "camera.vfov: does not apply",
        ),
        (
            "projection = \"orthographic\"\nheight = 2.0\naperture = 0.1\n",
            "camera.aperture: does not apply",
        ),
        (
            "projection = \"orthographic\"\nheight = -1.0\n",
            "camera.height: must be positive",
        ),
        (
            "height = 2.0\n",
            "camera.height: is an orthographic camera's",
        ),
    ] {
        let text = format!("{base}{extra}");
        let e = parse_scene(&text, &dir.join("e.toml"))
            .map(|_| ())
            .expect_err("an error")
            .to_string();
        assert!(e.contains(field), "{extra:?}: {e}");
        assert!(!e.contains('\n'), "{e}");
    }
}
