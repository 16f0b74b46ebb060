//! Render outputs (AOVs) with exact answers, on both renderers: the depth of a plane, the
//! normals of a sphere, the coverage along an edge through pixel centres, the ids of a
//! two-object scene; the EXR layout they are written in; transparent PNGs.

use crate::common;

use common::fs::TempDir;
use glam::Vec3;
use meshtrace::film::{Aov, AovValues, Film, NO_ID};
use meshtrace::render::RenderJob;
use meshtrace::render::camera::{CameraRays, generate_camera_ray};
use meshtrace::render::rng::Rng;
use meshtrace::scene::{Scene, parse_scene};

/// A scene file's text loaded from `dir` (its meshes beside it).
fn load(dir: &TempDir, text: &str) -> Scene {
    parse_scene(text, &dir.join("scene.toml")).unwrap_or_else(|e| panic!("{e}"))
}

fn render_both(
    test: &str,
    scene: &Scene,
    aovs: &[Aov],
    transparent: bool,
) -> Vec<(&'static str, Film)> {
    let job = RenderJob::new(scene.settings).with_aovs(Aov::mask(aovs), transparent);
    common::render_both_job(test, scene, &job)
}

fn f32s(film: &Film, aov: Aov) -> Vec<Vec<f32>> {
    film.aov_values(aov)
        .unwrap_or_else(|| panic!("no {} channel", aov.name()))
        .into_iter()
        .map(|v| match v {
            AovValues::F32(v) => v,
            AovValues::U32(_) => panic!("{}: not float", aov.name()),
        })
        .collect()
}

fn u32s(film: &Film, aov: Aov) -> Vec<u32> {
    match film.aov_values(aov).expect("channel").remove(0) {
        AovValues::U32(v) => v,
        AovValues::F32(_) => panic!("{}: not unsigned", aov.name()),
    }
}

/// A square quad in the z = 0 plane facing +z, from (x0, y0) to (x1, y1).
fn quad_obj(x0: f32, y0: f32, x1: f32, y1: f32) -> String {
    format!("v {x0} {y0} 0\nv {x1} {y0} 0\nv {x1} {y1} 0\nv {x0} {y1} 0\nf 1 2 3 4\n")
}

/// A plane covering x < 0, seen from 5 units up the z axis, so that the middle column of
/// pixel centres of an odd width lies on its edge: `render` is the `[render]` table's body,
/// `rest` the object's further keys and the tables after it.
fn half_plane(dir: &TempDir, render: &str, rest: &str) -> Scene {
    dir.write("half.obj", quad_obj(-100.0, -100.0, 0.0, 100.0));
    load(
        dir,
        &format!(
            "[camera]\nposition = [0.0, 0.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\n[render]\n{render}\n\
             [[objects]]\nmesh = \"half.obj\"\n{rest}\n"
        ),
    )
}

#[test]
fn depth_of_a_plane_is_its_distance_along_the_view_axis() {
    let dir = TempDir::new("aov-depth");
    dir.write("plane.obj", quad_obj(-100.0, -100.0, 100.0, 100.0));
    // The camera looks down -z from 5 units away, off-centre and turned, so that rays
    // meet the plane at many distances and angles; the depth is the same everywhere.
    let scene = load(
        &dir,
        r#"
[camera]
position = [1.0, 2.0, 5.0]
look_at = [1.0, 2.0, 0.0]
up = [1.0, 1.0, 0.0]
vfov = 90.0
[render]
width = 24
height = 16
spp = 3
[[objects]]
mesh = "plane.obj"
"#,
    );
    for (device, film) in render_both("depth", &scene, &[Aov::Depth, Aov::Alpha], false) {
        let depth = &f32s(&film, Aov::Depth)[0];
        let alpha = &f32s(&film, Aov::Alpha)[0];
        for (i, (&d, &a)) in depth.iter().zip(alpha).enumerate() {
            assert!(
                (d - 5.0).abs() <= 5e-6 * 5.0,
                "{device}: pixel {i}: depth {d}, not 5"
            );
            assert_eq!(a, 1.0, "{device}: pixel {i}: alpha");
        }
    }
}

#[test]
fn normals_of_a_sphere_point_away_from_its_centre() {
    let dir = TempDir::new("aov-normal");
    let scene = load(
        &dir,
        r#"
[camera]
position = [0.0, 0.0, 4.0]
look_at = [0.0, 0.0, 0.0]
vfov = 40.0
[render]
width = 32
height = 32
spp = 1
seed = 3
[[objects]]
sphere = { center = [0.0, 0.0, 0.0], radius = 1.0, subdivisions = 7 }
"#,
    );
    let s = scene.settings;
    let cam = CameraRays::new(&scene.camera, s.width, s.height);
    for (device, film) in render_both("normal", &scene, &[Aov::Normal, Aov::Depth], false) {
        let n = f32s(&film, Aov::Normal);
        let depth = &f32s(&film, Aov::Depth)[0];
        let mut hits = 0;
        for y in 0..s.height {
            for x in 0..s.width {
                let i = (y * s.width + x) as usize;
                let normal = Vec3::new(n[0][i], n[1][i], n[2][i]);
                // The one sample's ray, and where it meets the true sphere.
                let ray = generate_camera_ray(&cam, x, y, &Rng::new(i as u32, 0, s.seed));
                let b = ray.origin.dot(ray.dir);
                let disc = b * b - (ray.origin.length_squared() - 1.0);
                // Rays that graze the tessellated sphere's rim may go either way.
                if disc.abs() < 0.05 {
                    continue;
                }
                if disc < 0.0 {
                    assert_eq!(
                        normal,
                        Vec3::ZERO,
                        "{device}: ({x}, {y}): a miss has normal 0"
                    );
                    assert_eq!(
                        depth[i],
                        f32::INFINITY,
                        "{device}: ({x}, {y}): a miss's depth"
                    );
                    continue;
                }
                hits += 1;
                let expected = (ray.origin + (-b - disc.sqrt()) * ray.dir).normalize();
                assert!(
                    (normal.length() - 1.0).abs() < 1e-5,
                    "{device}: ({x}, {y}): |n| = {}",
                    normal.length()
                );
                assert!(
                    normal.dot(expected) > (1e-3f32).cos(),
                    "{device}: ({x}, {y}): normal {normal}, expected {expected}"
                );
            }
        }
        assert!(hits > 200, "{device}: {hits} hits");
    }
}

#[test]
fn inside_a_sphere_normals_face_the_camera() {
    let dir = TempDir::new("aov-inside");
    let scene = load(
        &dir,
        r#"
[camera]
position = [0.0, 0.0, 0.0]
look_at = [0.0, 0.0, -1.0]
[render]
width = 8
height = 8
spp = 2
[[objects]]
sphere = { center = [0.0, 0.0, 0.0], radius = 2.0 }
"#,
    );
    for (device, film) in render_both("inside", &scene, &[Aov::Normal], false) {
        let n = f32s(&film, Aov::Normal);
        for (i, z) in n[2].iter().enumerate() {
            // Seen from the centre, the inward normal points back at the camera (within the
            // 30° of the image's corners from +z).
            assert!(*z > 0.85, "{device}: pixel {i}: normal z {z}");
        }
    }
}

#[test]
fn alpha_is_one_half_along_an_edge_through_pixel_centres() {
    let dir = TempDir::new("aov-alpha");
    let scene = half_plane(
        &dir,
        "width = 33\nheight = 21\nspp = 256",
        "[sky]\ncolor = [1.0, 1.0, 1.0]",
    );
    let (w, h) = (33usize, 21usize);
    let films = render_both("alpha", &scene, &[Aov::Alpha], false);
    for (device, film) in &films {
        let alpha = &f32s(film, Aov::Alpha)[0];
        let mut edge = 0.0;
        for y in 0..h {
            for x in 0..w {
                let a = alpha[y * w + x];
                match x {
                    0..16 => assert_eq!(a, 1.0, "{device}: ({x}, {y})"),
                    16 => {
                        // 256 samples: a standard error of 1/32.
                        assert!((a - 0.5).abs() < 0.15, "{device}: ({x}, {y}): alpha {a}");
                        edge += a;
                    }
                    _ => assert_eq!(a, 0.0, "{device}: ({x}, {y})"),
                }
            }
        }
        let mean = edge / h as f32;
        assert!(
            (mean - 0.5).abs() < 0.03,
            "{device}: edge column's mean alpha {mean}"
        );
    }
    // The same samples on both devices.
    if let [(_, cpu), (_, gpu)] = films.as_slice() {
        assert_eq!(f32s(cpu, Aov::Alpha), f32s(gpu, Aov::Alpha));
    }
}

/// `filter_width` sets the square a pixel's samples fall in: 0, its centre alone (alpha 0
/// or 1, as the dataset scripts' `filter_width` 0.01 gives); 3, three pixels across, so
/// that the columns beside the edge are covered by 5/6 and 1/6.
#[test]
fn filter_width_sets_how_far_a_pixel_sees() {
    let dir = TempDir::new("aov-filter");
    let mut scene = half_plane(
        &dir,
        "width = 33\nheight = 21\nspp = 256\nfilter_width = 0.0",
        "",
    );
    let w = 33usize;
    let films = render_both("filter 0", &scene, &[Aov::Alpha], true);
    for (device, film) in &films {
        for (i, &a) in f32s(film, Aov::Alpha)[0].iter().enumerate() {
            let want = match i % w {
                0..16 => Some(1.0),
                16 => None,
                _ => Some(0.0),
            };
            assert!(a == 0.0 || a == 1.0, "{device}: pixel {i}: alpha {a}");
            assert!(
                want.is_none_or(|v| a == v),
                "{device}: pixel {i}: alpha {a}"
            );
        }
    }
    scene.settings.filter_width = 3.0;
    for (device, film) in render_both("filter 3", &scene, &[Aov::Alpha], true) {
        let alpha = &f32s(&film, Aov::Alpha)[0];
        for (x, want) in [
            (14, 1.0),
            (15, 5.0 / 6.0),
            (16, 0.5),
            (17, 1.0 / 6.0),
            (18, 0.0),
        ] {
            let mean = (0..21).map(|y| alpha[y * w + x]).sum::<f32>() / 21.0;
            assert!(
                (mean - want).abs() < 0.03,
                "{device}: column {x}: mean alpha {mean} against {want}"
            );
        }
    }
}

#[test]
fn ids_name_the_object_and_material_under_the_pixel_centre() {
    let dir = TempDir::new("aov-ids");
    let scene = load(
        &dir,
        r#"
[camera]
position = [0.0, 0.0, 6.0]
look_at = [0.0, 0.0, 0.0]
vfov = 40.0
[render]
width = 40
height = 20
spp = 3
[materials.a]
type = "diffuse"
albedo = [0.2, 0.4, 0.6]
[materials.b]
type = "dielectric"
[[objects]]
sphere = { center = [-1.2, 0.0, 0.0], radius = 1.0 }
material = "b"
[[objects]]
sphere = { center = [1.2, 0.0, 0.0], radius = 1.0 }
material = "a"
"#,
    );
    let index = |name: &str| scene.material_names.iter().position(|n| n == name).unwrap() as u32;
    let (a, b) = (index("a"), index("b"));
    let all = [Aov::ObjectId, Aov::MaterialId, Aov::Albedo];
    for (device, film) in render_both("ids", &scene, &all, false) {
        let objects = u32s(&film, Aov::ObjectId);
        let materials = u32s(&film, Aov::MaterialId);
        let albedo = f32s(&film, Aov::Albedo);
        let at = |x: usize, y: usize| y * 40 + x;
        // The spheres' centres project to x = 20 ∓ 5.5, 4.6 pixels wide; the corners and
        // the top edge see the black sky.
        for (x, object, material, rgb) in [(14, 0, b, [1.0; 3]), (25, 1, a, [0.2, 0.4, 0.6])] {
            for y in 8..12 {
                let i = at(x, y);
                assert_eq!(
                    (objects[i], materials[i]),
                    (object, material),
                    "{device}: ({x}, {y})"
                );
                for k in 0..3 {
                    let got = albedo[k][i];
                    assert!(
                        (got - rgb[k]).abs() < 1e-6,
                        "{device}: ({x}, {y}): albedo {got}"
                    );
                }
            }
        }
        for i in [at(0, 0), at(39, 0), at(0, 19), at(39, 19), at(20, 0)] {
            assert_eq!(
                (objects[i], materials[i]),
                (NO_ID, NO_ID),
                "{device}: pixel {i}"
            );
            assert_eq!(albedo[0][i], 0.0, "{device}: pixel {i}: albedo of a miss");
        }
    }
}

#[test]
fn bvh_cost_is_the_same_count_on_both_devices() {
    let (rs, mut settings) = common::scenes::cornell();
    settings.width = 16;
    settings.height = 16;
    settings.spp = 2;
    let job = RenderJob::new(settings).with_aovs(Aov::BvhCost.bit(), false);
    let cpu = common::cpu_render(&rs, &job);
    let cost = &f32s(&cpu, Aov::BvhCost)[0];
    // Rays through the open front that miss the box's bounds cost nothing; a ray that
    // reaches a triangle visits the root and a leaf and tests the leaf's triangles.
    assert!(cost.contains(&0.0), "{cost:?}");
    assert!(
        cost.iter().filter(|&&c| c >= 3.0).count() > cost.len() / 2,
        "{cost:?}"
    );
    if let Some(ctx) = common::gpu("bvh_cost") {
        let gpu = common::gpu_render(&ctx, &rs, &job);
        let gpu_cost = &f32s(&gpu, Aov::BvhCost)[0];
        // The same walk; a ray through an edge may end a hair apart on the two devices.
        let same = cost.iter().zip(gpu_cost).filter(|(a, b)| a == b).count();
        assert!(
            same * 100 >= cost.len() * 98,
            "{same} of {} equal",
            cost.len()
        );
    }
}

#[test]
fn exr_holds_dotted_channels_with_unsigned_ids() {
    use exr::prelude::{FlatSamples, read_all_flat_layers_from_file};
    let (rs, mut settings) = common::scenes::cornell();
    settings.width = 12;
    settings.height = 8;
    settings.spp = 2;
    let job = RenderJob::new(settings).with_aovs(Aov::mask(&Aov::ALL), false);
    let film = common::cpu_render(&rs, &job);
    let dir = TempDir::new("aov-exr");
    let read_back = |path: &std::path::Path| {
        let image = read_all_flat_layers_from_file(path)
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert_eq!(image.layer_data.len(), 1, "one part");
        let layer = &image.layer_data[0];
        assert_eq!(layer.size.0, 12);
        layer
            .channel_data
            .list
            .iter()
            .map(|c| {
                let kind = match &c.sample_data {
                    FlatSamples::F32(_) => "f32",
                    FlatSamples::U32(_) => "u32",
                    FlatSamples::F16(_) => "f16",
                };
                (c.name.to_string(), kind)
            })
            .collect::<Vec<_>>()
    };
    let aov_channels = [
        ("A", "f32"),
        ("Z", "f32"),
        ("albedo.B", "f32"),
        ("albedo.G", "f32"),
        ("albedo.R", "f32"),
        ("bvh_cost", "f32"),
        ("diffuse_color.B", "f32"),
        ("diffuse_color.G", "f32"),
        ("diffuse_color.R", "f32"),
        ("material_id", "u32"),
        ("normal.X", "f32"),
        ("normal.Y", "f32"),
        ("normal.Z", "f32"),
        ("object_id", "u32"),
    ];
    let exr = dir.join("out.exr");
    film.save(&exr).unwrap();
    let mut expected: Vec<(String, &str)> = aov_channels
        .iter()
        .chain(&[("B", "f32"), ("G", "f32"), ("R", "f32")])
        .map(|&(n, k)| (n.to_string(), k))
        .collect();
    expected.sort();
    let mut got = read_back(&exr);
    got.sort();
    assert_eq!(got, expected);
    // Beside any other output: `<stem>.aovs.exr`, the AOVs alone.
    let png = dir.join("out.png");
    film.save(&png).unwrap();
    let mut got = read_back(&dir.join("out.aovs.exr"));
    got.sort();
    let expected: Vec<(String, &str)> = aov_channels
        .iter()
        .map(|&(n, k)| (n.to_string(), k))
        .collect();
    assert_eq!(got, expected);
    assert!(image::open(&png).is_ok());
    assert_eq!(dir.entries().len(), 3, "{:?}", dir.entries());
}

#[test]
fn transparent_png_has_coverage_alpha_and_no_sky_in_its_colour() {
    let dir = TempDir::new("aov-transparent");
    let scene = half_plane(
        &dir,
        "width = 9\nheight = 5\nspp = 16\nmax_depth = 2",
        "material = \"white\"\n[sky]\ncolor = [0.5, 0.5, 0.5]\n\
         [materials.white]\ntype = \"diffuse\"\nalbedo = [1.0, 1.0, 1.0]",
    );
    for (device, film) in render_both("transparent", &scene, &[], true) {
        assert!(film.aov_values(Aov::Alpha).is_some());
        let png = dir.join(format!("{device}.png"));
        film.save(&png).unwrap();
        // The 16-bit PNG has the same pixels to within half an 8-bit step, alpha included.
        let deep = dir.join(format!("{device}16.png"));
        film.save_as(
            &deep,
            meshtrace::film::BitDepth::Sixteen,
            &Default::default(),
        )
        .unwrap();
        let deep = image::open(&deep).unwrap();
        assert_eq!(deep.color(), image::ColorType::Rgba16);
        let eight = image::open(&png).unwrap().into_rgba8();
        for (p, q) in deep.into_rgba16().pixels().zip(eight.pixels()) {
            for c in 0..4 {
                let as_eight = p[c] as f64 / 65535.0 * 255.0;
                assert!(
                    (as_eight - q[c] as f64).abs() <= 0.5 + 1e-9,
                    "{device}: {p:?} vs {q:?}"
                );
            }
        }
        let img = image::open(&png).unwrap().into_rgba8();
        for (x, y, p) in img.enumerate_pixels() {
            match x {
                // A white Lambertian plane under a sky of 0.5 seen once (max_depth 2):
                // half the sky's hemisphere reaches it, 0.5 / 2 ... in straight colour.
                0..4 => {
                    assert_eq!(p[3], 255, "{device}: ({x}, {y})");
                    assert!(p[0] > 100, "{device}: ({x}, {y}): lit by the sky: {p:?}");
                }
                4 => assert!(p[3] > 0 && p[3] < 255, "{device}: ({x}, {y}): {p:?}"),
                _ => assert_eq!(
                    p.0,
                    [0, 0, 0, 0],
                    "{device}: ({x}, {y}): the sky seen directly"
                ),
            }
        }
        // Only the PNG: no AOV file was asked for.
        assert!(!dir.join(format!("{device}.aovs.exr")).exists());
    }
    // Paths of one segment see only emitters: here only the sky, which a transparent render
    // leaves out, so every pixel is black however much of it the plane covers.
    let mut unlit = scene.clone();
    unlit.settings.max_depth = 1;
    for (device, film) in render_both("transparent", &unlit, &[], true) {
        assert!(
            film.sum.iter().all(|&s| s == [0; 3]),
            "{device}: {:?}",
            film.sum
        );
    }
}

/// A geometry-only render (camera rays alone) fills every AOV with the bits of the full
/// render's (the same camera rays find the same first hits), on each renderer; its image is
/// the first surface's albedo where the camera rays hit (their albedo sum over all samples),
/// and it traces one ray a sample.
#[test]
fn geometry_only_renders_the_aovs_of_the_full_render() {
    let dir = TempDir::new("aov-geometry");
    dir.write("plane.obj", quad_obj(-1.0, -1.0, 1.0, 1.0));
    let scene = load(
        &dir,
        r#"
[camera]
position = [0.3, 0.2, 3.0]
look_at = [0.0, 0.0, 0.0]
vfov = 50.0
[render]
width = 20
height = 14
spp = 5
[materials.red]
type = "diffuse"
albedo = [0.7, 0.2, 0.1]
[[objects]]
mesh = "plane.obj"
material = "red"
[[objects]]
mesh = "plane.obj"
translate = [0.5, 0.4, 0.5]
scale = 0.4
[sky]
color = [1.0, 1.0, 1.0]
"#,
    );
    let all = Aov::ALL;
    let job = RenderJob::new(scene.settings).with_aovs(Aov::mask(&all), false);
    let full = common::render_both_job("geometry: full", &scene, &job);
    let geometry = common::render_both_job("geometry", &scene, &job.clone().with_geometry(true));
    let mut hits = 0;
    for ((device, f), (_, g)) in full.iter().zip(&geometry) {
        for aov in all {
            assert_eq!(
                g.channel(aov.name()).unwrap().data,
                f.channel(aov.name()).unwrap().data,
                "{device}: {}",
                aov.name()
            );
        }
        let albedo = g.channel(Aov::Albedo.name()).unwrap();
        // A diffuse surface's diffuse colour is its albedo, summed alike.
        for film in [f, g] {
            let diffuse = film.channel(Aov::DiffuseColor.name()).unwrap();
            let albedo = film.channel(Aov::Albedo.name()).unwrap();
            assert_eq!(diffuse.data, albedo.data, "{device}: diffuse_color");
        }
        for (i, (sum, a)) in g.sum.iter().zip(&albedo.data).enumerate() {
            // The albedo channel's first three sums are the hits' albedo sums.
            assert_eq!(&sum[..], &a[..3], "{device}: pixel {i}");
            hits += usize::from(a[3] != 0);
        }
        let rays = &g.channel(Film::RAYS).unwrap().data;
        let one_a_sample = meshtrace::fixed::to_fixed(5.0);
        assert!(rays.iter().all(|r| r[0] == one_a_sample), "{device}: rays");
        assert_ne!(g.sum, f.sum, "{device}: the full render's radiance is lit");
    }
    assert!(hits > 100, "{hits} pixels hit");
}

/// A transparent render skips the pixels whose camera rays cannot meet the scene
/// (`CameraRays::window`) and gives them what tracing would: the same bits in every
/// channel as a render that traces them all (the BVH cost AOV makes it trace every ray),
/// on both renderers, with a mix of materials and a pixel window well inside the image.
#[test]
fn a_transparent_render_skips_pixels_outside_the_scene_with_the_same_bits() {
    let dir = TempDir::new("aov-window");
    let scene = load(
        &dir,
        r#"
[camera]
position = [0.3, 0.4, 4.0]
look_at = [0.0, 0.0, 0.0]
vfov = 50.0
[render]
width = 48
height = 36
spp = 8
max_depth = 4
[sky]
color = [0.5, 0.6, 0.7]
[materials.white]
type = "diffuse"
albedo = [0.8, 0.8, 0.8]
[materials.gold]
type = "rough_conductor"
albedo = [0.95, 0.75, 0.35]
roughness = 0.3
[[objects]]
sphere = { center = [-0.6, 0.2, 0.0], radius = 0.35 }
material = "white"
[[objects]]
sphere = { center = [0.4, -0.3, 0.2], radius = 0.3 }
material = "gold"
[[lights]]
type = "point"
position = [2.0, 3.0, 2.0]
intensity = [20.0, 20.0, 20.0]
"#,
    );
    let rs = meshtrace::render::RenderScene::new(&scene, &meshtrace::bvh::BuildParams::default())
        .unwrap();
    let cam = CameraRays::new(&scene.camera, 48, 36).with_window(&rs.bounds());
    let [x0, y0, x1, y1] = cam.window;
    assert!(
        x0 > 0 && y0 > 0 && x1 < 48 && y1 < 36 && (x1 - x0) * (y1 - y0) < 48 * 36 / 2,
        "{:?}",
        cam.window
    );
    let ids = [Aov::ObjectId, Aov::Depth, Aov::Normal];
    let skipping = render_both("window", &scene, &ids, true);
    let tracing = render_both(
        "window",
        &scene,
        &[ids.as_slice(), &[Aov::BvhCost]].concat(),
        true,
    );
    for ((device, a), (_, b)) in skipping.iter().zip(&tracing) {
        assert!(a.sum == b.sum, "{device}: radiance differs");
        for channel in &a.channels {
            let other = b.channels.iter().find(|c| c.name == channel.name).unwrap();
            assert!(
                other.data == channel.data,
                "{device}: {} differs",
                channel.name
            );
        }
        assert!(a.aov_values(Aov::Alpha).is_some());
    }
}
