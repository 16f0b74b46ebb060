//! The seed's scene, `assets/seed/seed.toml` (see `assets/seed/README.md`): it loads with
//! exactly the expected warnings (the two MTL libraries its OBJs name but that never
//! existed), the expected triangles, materials, transforms, camera and settings; and a tiny
//! CPU render is finite, shows the sky colour where the camera sees only sky, and the
//! expected colours on the ground and in the mirror.

use glam::Vec3;
use meshtrace::bvh::BuildParams;
use meshtrace::render::cpu::render;
use meshtrace::render::{RenderJob, RenderScene};
use meshtrace::scene::obj::load_obj;
use meshtrace::scene::source::Fs;
use meshtrace::scene::sphere::{default_subdivisions, icosphere};
use meshtrace::scene::{MaterialKind, RenderSettings, Scene, Sky, load_scene};
use std::path::{Path, PathBuf};

const SPIDER_TRIANGLES: usize = 336;
const HOUSE_TRIANGLES: usize = 72;
const PLANE_TRIANGLES: usize = 2;
const SKY: Vec3 = Vec3::new(0.5, 0.7, 1.0);

fn dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/seed")
}

fn seed() -> Scene {
    let path = dir().join("seed.toml");
    load_scene(&path).unwrap_or_else(|e| panic!("{e}"))
}

/// The triangles of the ground sphere: the default subdivision of the icosphere.
fn sphere_triangles() -> usize {
    icosphere(default_subdivisions()).1.len()
}

#[test]
fn loads_with_exactly_the_missing_mtl_warnings() {
    let scene = seed();
    // spider.obj names spider.mtl; house.obj, loaded three times, names house.mtl; plane.mtl
    // exists (comments only). Nothing else may be reported (no degenerate triangles).
    let spider = |w: &String| w.contains("spider.obj") && w.contains("spider.mtl");
    let house = |w: &String| w.contains("house.obj") && w.contains("house.mtl");
    for w in &scene.warnings {
        assert!(spider(w) || house(w), "unexpected warning: {w}");
        assert!(w.contains("could not be read"), "{w}");
    }
    let n_spider = scene.warnings.iter().filter(|w| spider(w)).count();
    let n_house = scene.warnings.iter().filter(|w| house(w)).count();
    // Once per library, or once per object that reads it.
    assert_eq!(n_spider, 1, "{:?}", scene.warnings);
    assert!((1..=3).contains(&n_house), "{:?}", scene.warnings);
    eprintln!("warnings: {:#?}", scene.warnings);
}

#[test]
fn has_the_seed_triangles_materials_and_transforms() {
    let scene = seed();
    let tris = &scene.mesh.triangles;
    let sphere = sphere_triangles();
    assert_eq!(
        tris.len(),
        SPIDER_TRIANGLES + 3 * HOUSE_TRIANGLES + PLANE_TRIANGLES + sphere,
        "336 spider + 3 x 72 houses + 2 plane + {sphere} sphere triangles"
    );
    // Materials: (name, kind, albedo, triangles).
    let expected = [
        (
            "ground",
            MaterialKind::DIFFUSE,
            Vec3::new(0.0, 1.0, 0.0),
            sphere,
        ),
        (
            "red",
            MaterialKind::DIFFUSE,
            Vec3::new(1.0, 0.0, 0.0),
            SPIDER_TRIANGLES + HOUSE_TRIANGLES,
        ),
        (
            "blue",
            MaterialKind::DIFFUSE,
            Vec3::new(0.0, 0.0, 1.0),
            2 * HOUSE_TRIANGLES,
        ),
        (
            "metal",
            MaterialKind::CONDUCTOR,
            Vec3::new(0.4, 1.0, 0.4),
            PLANE_TRIANGLES,
        ),
    ];
    for (name, kind, albedo, count) in expected {
        let index = scene
            .material_names
            .iter()
            .position(|n| n == name)
            .unwrap_or_else(|| panic!("material {name} missing: {:?}", scene.material_names));
        let m = &scene.materials[index];
        assert_eq!(
            (m.kind, m.albedo, m.emission),
            (kind, albedo, Vec3::ZERO),
            "{name}"
        );
        let n = tris.iter().filter(|t| t.material == index as u32).count();
        assert_eq!(n, count, "triangles of {name}");
    }
    assert!(
        !scene.materials.iter().any(|m| m.is_emissive()),
        "no lights"
    );

    // The bounds of each material's vertices place the objects.
    let bounds = |material: &str| {
        let index = scene
            .material_names
            .iter()
            .position(|n| n == material)
            .unwrap() as u32;
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for t in tris.iter().filter(|t| t.material == index) {
            for p in scene.mesh.vertices(t) {
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
        (lo, hi)
    };
    // The mirror: the YZ quad (about 19.6 x 17.6) moved to x = -5, centred at y = 0.5.
    let (lo, hi) = bounds("metal");
    assert!(
        (lo.x + 5.0).abs() < 1e-4 && (hi.x + 5.0).abs() < 1e-4,
        "{lo} {hi}"
    );
    assert!(((lo.y + hi.y) / 2.0 - 0.5).abs() < 1e-4, "{lo} {hi}");
    assert!((hi.z - lo.z - 19.636).abs() < 1e-2 && (hi.y - lo.y - 17.563).abs() < 1e-2);
    // The ground: radius 100 about (0, -100.5, -1).
    let (lo, hi) = bounds("ground");
    assert!(
        (hi.y + 0.5).abs() < 1e-3 && (lo.y + 200.5).abs() < 1e-3,
        "{lo} {hi}"
    );
    assert!(((lo.z + hi.z) / 2.0 + 1.0).abs() < 1e-3, "{lo} {hi}");
    // The houses: house.obj moved by (0, 0, -5) and (0, 0, 5) (blue), and with the spider
    // moved by (0, 1, 0), by (5, 1, 0) (red).
    let obj_bounds = |name: &str| {
        let obj = load_obj(&dir().join(name), &Fs).unwrap_or_else(|e| panic!("{e}"));
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for &p in &obj.positions {
            lo = lo.min(p);
            hi = hi.max(p);
        }
        (lo, hi)
    };
    let (house_lo, house_hi) = obj_bounds("house.obj");
    let (spider_lo, spider_hi) = obj_bounds("spider.obj");
    let close = |a: Vec3, b: Vec3| (a - b).abs().max_element() < 1e-4;
    let (lo, hi) = bounds("blue");
    let (want_lo, want_hi) = (house_lo - 5.0 * Vec3::Z, house_hi + 5.0 * Vec3::Z);
    assert!(
        close(lo, want_lo) && close(hi, want_hi),
        "blue houses span {lo}..{hi}, want {want_lo}..{want_hi}"
    );
    let (lo, hi) = bounds("red");
    let want_lo = (spider_lo + Vec3::Y).min(house_lo + Vec3::new(5.0, 1.0, 0.0));
    let want_hi = (spider_hi + Vec3::Y).max(house_hi + Vec3::new(5.0, 1.0, 0.0));
    assert!(
        close(lo, want_lo) && close(hi, want_hi),
        "spider and red house span {lo}..{hi}, want {want_lo}..{want_hi}"
    );

    let cam = &scene.camera;
    assert_eq!(cam.position, Vec3::new(6.0, 5.0, 6.0));
    assert!((cam.forward - Vec3::new(-6.0, -5.0, -6.0).normalize()).length() < 1e-6);
    assert_eq!(cam.vfov, 90.0);
    assert_eq!(
        scene.settings,
        RenderSettings {
            width: 910,
            height: 512,
            spp: 64,
            max_depth: 50,
            seed: 0,
            ..RenderSettings::default()
        }
    );
    assert_eq!(scene.sky, Sky::Constant(SKY));
}

#[test]
fn tiny_render_is_finite_and_shows_sky_ground_and_mirror() {
    let mut scene = seed();
    scene.settings.width = 32;
    scene.settings.height = 18;
    scene.settings.spp = 4;
    let rs = RenderScene::new(&scene, &BuildParams::default()).expect("BVH");
    let film = render(&rs, &RenderJob::new(scene.settings), &|_| {});
    let rays = film.rays();
    let img = film.mean();
    let px = |x: usize, y: usize| img[y * 32 + x];
    assert!(rays > 32 * 18 * 4);
    for (i, v) in img.iter().enumerate() {
        assert!(v.is_finite() && v.min_element() >= 0.0, "pixel {i}: {v}");
    }
    // Top right (x >= 22 of 32, y < 4 of 18): the camera sees only sky there, and camera
    // rays that escape return the sky colour exactly.
    for y in 0..4 {
        for x in 22..32 {
            assert!(
                (px(x, y) - SKY).abs().max_element() < 1e-6,
                "({x}, {y}): {} is not the sky",
                px(x, y)
            );
        }
    }
    // Bottom middle: the green ground, lit by the sky.
    let g = px(16, 16);
    assert!(
        g.y > 0.2 && g.x < 0.05 * g.y && g.z < 0.05 * g.y,
        "ground {g}"
    );
    // Top left: the green-tinted mirror (albedo 0.4, 1, 0.4) reflecting sky and ground.
    let m = px(2, 2);
    assert!(m.y > m.x && m.y > m.z && m.x > 0.05, "mirror {m}");
    // Somewhere red: the spider or the red house.
    assert!(
        img.iter().any(|v| v.x > 2.0 * (v.y + v.z) && v.x > 0.1),
        "no red pixel"
    );
}
