//! Scenes with known answers, rendered on the CPU and (where an adapter exists) the GPU:
//! the white furnace, an emissive enclosure whose radiance is Le / (1 - albedo), and an
//! emitter seen directly.
//!
//! Noise bounds: pixels are independent, so the image mean of a pixel channel is normal
//! with standard error `sd / sqrt(pixels)`; each test asserts the expected value lies
//! within 5 standard errors (a false alarm once in ~3.5 million runs), and that the standard
//! error is small enough for a 1% bias to fail.

use crate::common;

use common::scenes::{add_box, emissive_enclosure, scene, square};
use common::stats::assert_mean;
use glam::Vec3;
use meshtrace::scene::{Camera, Material, Mesh, Sky};

/// An open box (five faces) holding a cube, all diffuse of albedo 1, under a constant sky:
/// whatever the geometry, every path ends in the sky carrying throughput 1, so every pixel
/// sees exactly the sky radiance.
#[test]
fn white_furnace_returns_the_sky_radiance() {
    let sky = Vec3::new(0.7, 0.5, 0.3);
    let mut mesh = Mesh::default();
    add_box(
        &mut mesh,
        Vec3::new(-1.0, -1.0, -1.0),
        Vec3::new(1.0, 1.0, 1.0),
        0,
        true,
    );
    // Open the +z side towards the camera: drop the two triangles of that face.
    mesh.triangles.remove(2);
    mesh.triangles.remove(2);
    add_box(&mut mesh, Vec3::splat(-0.4), Vec3::splat(0.3), 0, false);
    let camera = Camera::new(
        Vec3::new(0.3, 0.2, 4.0),
        Vec3::ZERO,
        Vec3::Y,
        40.0,
        0.0,
        None,
    )
    .unwrap();
    let s = scene(
        mesh,
        vec![Material::diffuse(Vec3::ONE)],
        camera,
        Sky::Constant(sky),
        square(48, 64, 1000, 7),
    );
    for (device, film) in common::render_both("white_furnace", &s) {
        assert_mean("white furnace", device, &film, sky);
    }
}

/// The emissive enclosure (`common::scenes::emissive_enclosure`): radiance Le / (1 -
/// albedo) everywhere. This exercises next event estimation and both MIS weights: any error
/// in them biases the result.
#[test]
fn emissive_enclosure_returns_le_over_one_minus_albedo() {
    let (s, expect) = emissive_enclosure();
    for (device, film) in common::render_both("emissive_enclosure", &s) {
        assert_mean("emissive enclosure", device, &film, expect);
    }
}

/// An emitter that fills the view renders its exact radiance, whatever the path depth, and
/// its back face emits nothing.
#[test]
fn emitter_seen_directly_returns_its_radiance() {
    let le = Vec3::new(2.0, 3.5, 0.25);
    let mut mesh = Mesh::default();
    add_box(
        &mut mesh,
        Vec3::new(-10.0, -10.0, -1.0),
        Vec3::new(10.0, 10.0, -0.5),
        0,
        false,
    );
    let mut light = Material::diffuse(Vec3::ZERO);
    light.emission = le;
    for (max_depth, from_behind) in [(1, false), (8, false), (8, true)] {
        let (pos, look) = if from_behind {
            (Vec3::new(0.0, 0.0, -3.0), Vec3::new(0.0, 0.0, -10.0))
        } else {
            (Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO)
        };
        // From behind, the camera sits inside the slab's far side... so use a single quad.
        let mut m = mesh.clone();
        if from_behind {
            m = Mesh::default();
            // A quad at z = -5 whose front faces -z (away from a camera at z = -3 looking at -z).
            let base = 0;
            m.positions.extend([
                Vec3::new(-10.0, -10.0, -5.0),
                Vec3::new(-10.0, 10.0, -5.0),
                Vec3::new(10.0, 10.0, -5.0),
                Vec3::new(10.0, -10.0, -5.0),
            ]);
            for t in [[0, 1, 2], [0, 2, 3]] {
                m.triangles.push(meshtrace::scene::Triangle {
                    p: t.map(|k| base + k),
                    n: [meshtrace::scene::NO_NORMAL; 3],
                    t: [meshtrace::scene::NO_UV; 3],
                    material: 0,
                });
            }
        }
        let camera = Camera::new(pos, look, Vec3::Y, 30.0, 0.0, None).unwrap();
        let s = scene(
            m,
            vec![light],
            camera,
            Sky::Constant(Vec3::ZERO),
            square(16, 4, max_depth, 7),
        );
        let expect = if from_behind { Vec3::ZERO } else { le };
        for (device, film) in common::render_both("direct_emitter", &s) {
            for (i, p) in film.mean().iter().enumerate() {
                assert_eq!(
                    *p, expect,
                    "{device}, max_depth {max_depth}, behind {from_behind}: pixel {i}"
                );
            }
        }
    }
}

/// The emissive enclosure with its albedo from a texture: a uniform 8-bit grey image, so
/// the albedo is the sRGB decoding of its value and the answer is still Le / (1 - albedo).
/// (The scene is written as files, so the texture goes through the loader, the texel table
/// and the lookup of each renderer.)
#[test]
fn textured_emissive_enclosure_returns_le_over_one_minus_albedo() {
    let dir = common::fs::TempDir::new("textured-enclosure");
    let grey = 128u8;
    dir.write_png("grey.png", 3, 2, &[[grey, grey, grey, 255]; 6]);
    // A cube seen from inside: every face wound to face inwards, one texture coordinate.
    let mut obj = String::from("vt 0.3 0.7\n");
    for i in 0..8 {
        let c = |bit: i32| if i & bit == 0 { -1.0 } else { 1.0 };
        obj += &format!("v {} {} {}\n", c(1), c(2), c(4));
    }
    for q in [
        [1, 2, 4, 3],
        [5, 7, 8, 6],
        [1, 3, 7, 5],
        [2, 6, 8, 4],
        [1, 5, 6, 2],
        [3, 4, 8, 7],
    ] {
        obj += &format!("f {}/1 {}/1 {}/1 {}/1\n", q[0], q[1], q[2], q[3]);
    }
    dir.write("cube.obj", obj);
    let emission = Vec3::new(0.5, 0.75, 0.25);
    let toml = format!(
        "[camera]\nposition = [0.5, 0.5, 0.9]\nlook_at = [-0.3, -0.4, -1.0]\nvfov = 70.0\n\
         [render]\nwidth = 48\nheight = 48\nspp = 64\nmax_depth = 64\nseed = 7\n\
         [materials.wall]\ntype = \"diffuse\"\nalbedo = {{ texture = \"grey.png\" }}\n\
         emission = [{}, {}, {}]\n\
         [[objects]]\nmesh = \"cube.obj\"\nmaterial = \"wall\"\n",
        emission.x, emission.y, emission.z
    );
    let s = meshtrace::scene::load_scene(&dir.write("scene.toml", toml)).unwrap();
    let albedo = meshtrace::film::srgb8_to_linear(grey);
    let expect = emission / (1.0 - albedo);
    for (device, film) in common::render_both("textured_emissive_enclosure", &s) {
        assert_mean("textured emissive enclosure", device, &film, expect);
    }
}
