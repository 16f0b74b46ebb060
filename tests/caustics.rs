//! Caustic light subpaths (`render::caustics`) must change an image's noise, never its
//! expected value. These checks, each on the CPU and the GPU:
//!
//! - **A mirror's caustic is the light's mirror image.** A floor lit only through a ceiling
//!   mirror (the light faces the mirror, its black back towards the floor) is lit exactly as
//!   the doubled scene without the mirror lights it (everything reflected in the mirror's
//!   plane added), by the method of images. There the path tracer finds the light by next
//!   event estimation alone, with little noise; in the mirror scene all the light comes by
//!   specular paths: `L S D E` (light tracing), `L S D D E` and longer (connections), and
//!   BSDF sampling, weighed against both. The same with a point light and a spot beside the
//!   area light: the path tracer never finds them through the mirror, so their light there
//!   comes from light subpaths alone, at weight 1.
//! - **Sunlight off a mirror is its mirror image.** A wall lit by a directional light and,
//!   through a mirror in a black floor, by its reflection, against the mirror's place as a
//!   hole with the light's image shining up through it: a directional light's subpaths
//!   start outside the scene, along lines through a disk across the mirror's target.
//! - **Glass and mirror spheres under a large light**, with caustics and without: the path
//!   tracer alone finds the caustics of a large light often enough to converge, so the two
//!   renders estimate one image. The glass sphere's caustic on the floor, seen by the back
//!   wall through the sphere, is a two-hop light subpath `L S S D S S D`.
//!   With 2 branches a camera sample, each with its light subpath, on both devices too
//!   (the splats left at full weight instead of 1/2: z 21.6).
//! - **An emissive enclosure holding glass and mirrors** (the dielectric furnace): walls
//!   that emit Le and reflect albedo a fill the enclosure with radiance Le / (1 - a), which
//!   lossless glass, a perfect mirror and a white block inside the glass leave unchanged,
//!   so every pixel sees exactly that. Light subpaths there end on the white block inside
//!   the glass, where the camera path meets them from inside too: the adjoint throughput's
//!   refraction (no squared index ratio) is right only if the image is.
//!
//! The first three compare the image means of several seeds of both renders in blocks of
//! pixels, as z scores against the seeds' spread: a wrong weight or throughput anywhere along the
//! caustic paths moves whole regions by far more than their noise (a spot's falloff left
//! out: z 14.6; a directional light's line density off by 20%: z 16.5).

use crate::common;

use common::images::{assert_same_image, renders};
use common::scenes::{add_box, add_sphere, scene, square};
use common::stats::assert_mean;
use glam::Vec3;
use meshtrace::bvh::BuildParams;
use meshtrace::render::RenderScene;
use meshtrace::scene::{
    Camera, Material, MaterialKind, Mesh, NO_NORMAL, NO_UV, PunctualLight, RenderSettings, Sky,
    Triangle,
};

/// Appends the quad a, b, c, d (a parallelogram, counter-clockwise seen from its front).
fn quad(mesh: &mut Mesh, [a, b, c, d]: [Vec3; 4], material: u32) {
    let base = mesh.positions.len() as u32;
    mesh.positions.extend([a, b, c, d]);
    for p in [[0, 1, 2], [0, 2, 3]] {
        mesh.triangles.push(Triangle {
            p: p.map(|k| base + k),
            n: [NO_NORMAL; 3],
            t: [NO_UV; 3],
            material,
        });
    }
}

/// A horizontal square of half-size `h` centred on `c`, facing up or down.
fn horizontal(c: Vec3, h: f32, up: bool) -> [Vec3; 4] {
    let [a, b, cc, d] = [
        c + Vec3::new(-h, 0.0, -h),
        c + Vec3::new(-h, 0.0, h),
        c + Vec3::new(h, 0.0, h),
        c + Vec3::new(h, 0.0, -h),
    ];
    if up { [a, b, cc, d] } else { [a, d, cc, b] }
}

const FLOOR: u32 = 0;
const LIGHT: u32 = 1;
const MIRROR: u32 = 2;
const GLASS: u32 = 3;

/// A glossy floor (y = 0) and back wall, and a light at y = 1 facing up, under a mirror at
/// y = 2 facing down; or, `doubled`, the same without the mirror but with the floor, wall
/// and light reflected in its plane. The camera, below the light, sees the floor, the wall
/// and the light's black back only. Both are one scene for the points below y = 2: the
/// mirror reflects every ray that would reach the reflected objects (it covers every
/// crossing of its plane by a line between them and the floor or wall). A path through the
/// mirror has one segment more than its twin in the doubled scene, so the renders let paths
/// run long (64 segments) for neither to cut off light the other keeps.
///
/// With `punctual`, a point light and a spot pointing up at the mirror join the area light
/// (their images, the spot pointing down, in the doubled scene): the path tracer cannot
/// find a point light through a mirror at all, so in the mirror scene their light on the
/// floor comes from light subpaths alone.
fn mirror_scene(doubled: bool, punctual: bool, settings: RenderSettings) -> RenderScene {
    let mut mesh = Mesh::default();
    // A wall at the back, facing the camera (+z), from the floor to y = 1.9, or in the
    // mirror's image from y = 2.1 to 4.
    let wall = |y0: f32, y1: f32| {
        [
            Vec3::new(-1.0, y0, -1.0),
            Vec3::new(1.0, y0, -1.0),
            Vec3::new(1.0, y1, -1.0),
            Vec3::new(-1.0, y1, -1.0),
        ]
    };
    quad(&mut mesh, horizontal(Vec3::ZERO, 1.0, true), FLOOR);
    quad(&mut mesh, wall(0.0, 1.9), FLOOR);
    quad(&mut mesh, horizontal(Vec3::Y, 0.25, true), LIGHT);
    if doubled {
        quad(&mut mesh, horizontal(4.0 * Vec3::Y, 1.0, false), FLOOR);
        let [a, b, c, d] = wall(2.1, 4.0);
        quad(&mut mesh, [b, a, d, c], FLOOR);
        quad(&mut mesh, horizontal(3.0 * Vec3::Y, 0.25, false), LIGHT);
    } else {
        quad(&mut mesh, horizontal(2.0 * Vec3::Y, 1.5, false), MIRROR);
    }
    let light = Material {
        emission: Vec3::new(12.0, 10.0, 8.0),
        ..Material::diffuse(Vec3::ZERO)
    };
    let mirror = Material {
        albedo: Vec3::ONE,
        ..Material::new(MaterialKind::CONDUCTOR)
    };
    // A glossy floor: at a non-delta vertex reached through the mirror, the ratio of
    // its camera and light sampling densities (`PathState::caustic_pdf`) is not 1, as it
    // is for a Lambertian one.
    let floor = Material {
        albedo: Vec3::new(0.9, 0.8, 0.7),
        roughness: 0.5,
        ..Material::new(MaterialKind::ROUGH_CONDUCTOR)
    };
    let materials = vec![floor, light, mirror];
    let camera = Camera::new(
        Vec3::new(0.0, 0.8, 1.6),
        Vec3::new(0.0, 0.4, -1.0),
        Vec3::Y,
        50.0,
        0.0,
        None,
    )
    .unwrap();
    let mut s = scene(mesh, materials, camera, Sky::Constant(Vec3::ZERO), settings);
    if punctual {
        let lights = |image: bool| {
            // Reflected in the mirror's plane, y = 2, for the image.
            let at = |p: Vec3| {
                if image {
                    Vec3::new(p.x, 4.0 - p.y, p.z)
                } else {
                    p
                }
            };
            [
                PunctualLight::Point {
                    position: at(Vec3::new(0.5, 1.2, -0.3)),
                    intensity: Vec3::new(1.0, 1.2, 1.5),
                },
                PunctualLight::Spot {
                    position: at(Vec3::new(-0.5, 1.1, 0.2)),
                    direction: if image { -Vec3::Y } else { Vec3::Y },
                    intensity: Vec3::new(16.0, 12.0, 8.0),
                    cutoff: 30f32.to_radians(),
                    beam_width: 8f32.to_radians(),
                },
            ]
        };
        s.lights = lights(false).to_vec();
        if doubled {
            s.lights.extend(lights(true));
        }
    }
    RenderScene::new(&s, &BuildParams::default()).unwrap()
}

/// Sunlight off a mirror: a wall (x = -1, facing +x) lit by a directional light that
/// travels down and left, and, through a mirror let into a black floor (y = 0), by its
/// reflection; or, as the `image`, the same without the mirror, its place a hole in the
/// floor, and a second directional light, the first's mirror image, shining up through
/// the hole. By the method of images the wall is lit alike (the floor around the hole
/// shades it as the mirror's edges bound the reflection). Paths are cut at three
/// segments, so that light the wall sends back to itself by way of the mirror, which the
/// image scene lacks, is left out of both. The camera sees the wall only. A directional
/// light's reflection is light the path tracer never finds: in the mirror scene it comes
/// from light subpaths alone.
fn sun_mirror_scene(image: bool, settings: RenderSettings) -> RenderScene {
    let mut mesh = Mesh::default();
    let wall = [
        Vec3::new(-1.0, 0.0, 1.0),
        Vec3::new(-1.0, 0.0, -1.0),
        Vec3::new(-1.0, 2.0, -1.0),
        Vec3::new(-1.0, 2.0, 1.0),
    ];
    quad(&mut mesh, wall, FLOOR);
    // The black floor, facing up, around the mirror (or hole) at x in [0.5, 1.5], |z| <= 0.5.
    let floor = |x0: f32, x1: f32, z0: f32, z1: f32| {
        [
            Vec3::new(x0, 0.0, z0),
            Vec3::new(x0, 0.0, z1),
            Vec3::new(x1, 0.0, z1),
            Vec3::new(x1, 0.0, z0),
        ]
    };
    quad(&mut mesh, floor(-1.0, 0.5, -2.0, 2.0), LIGHT);
    quad(&mut mesh, floor(0.5, 1.5, 0.5, 2.0), LIGHT);
    quad(&mut mesh, floor(0.5, 1.5, -2.0, -0.5), LIGHT);
    if !image {
        quad(&mut mesh, floor(0.5, 1.5, -0.5, 0.5), MIRROR);
    }
    let mirror = Material {
        albedo: Vec3::ONE,
        ..Material::new(MaterialKind::CONDUCTOR)
    };
    let materials = vec![
        Material::diffuse(Vec3::new(0.8, 0.7, 0.6)),
        Material::diffuse(Vec3::ZERO),
        mirror,
    ];
    let camera = Camera::new(
        Vec3::new(1.2, 1.2, 0.0),
        Vec3::new(-1.0, 1.2, 0.0),
        Vec3::Y,
        50.0,
        0.0,
        None,
    )
    .unwrap();
    let mut s = scene(mesh, materials, camera, Sky::Constant(Vec3::ZERO), settings);
    let sun = |y: f32| PunctualLight::Directional {
        direction: Vec3::new(-1.0, y, 0.0).normalize(),
        irradiance: Vec3::new(2.0, 1.8, 1.5),
        shadows: true,
    };
    s.lights = vec![sun(-1.0)];
    if image {
        s.lights.push(sun(1.0));
    }
    RenderScene::new(&s, &BuildParams::default()).unwrap()
}

/// Glass and mirror spheres on a floor before a back wall, and a glass block holding two
/// diffuse blocks (a light subpath ends inside a dielectric and the camera path meets it
/// there), under a large light.
fn spheres_scene(settings: RenderSettings) -> RenderScene {
    let mut mesh = Mesh::default();
    quad(&mut mesh, horizontal(Vec3::ZERO, 1.5, true), FLOOR);
    quad(
        &mut mesh,
        [
            Vec3::new(-1.5, 0.0, -1.0),
            Vec3::new(1.5, 0.0, -1.0),
            Vec3::new(1.5, 2.5, -1.0),
            Vec3::new(-1.5, 2.5, -1.0),
        ],
        FLOOR,
    );
    quad(
        &mut mesh,
        horizontal(Vec3::new(0.0, 2.5, 0.2), 0.8, false),
        LIGHT,
    );
    add_sphere(&mut mesh, Vec3::new(0.35, 0.45, 0.0), 0.45, 3, GLASS);
    add_sphere(&mut mesh, Vec3::new(-0.6, 0.35, -0.3), 0.35, 3, MIRROR);
    // A glass block holding two diffuse blocks that light each other inside it.
    add_box(
        &mut mesh,
        Vec3::new(-1.4, 0.01, 0.3),
        Vec3::new(-0.5, 0.6, 0.9),
        GLASS,
        false,
    );
    add_box(
        &mut mesh,
        Vec3::new(-1.3, 0.05, 0.4),
        Vec3::new(-1.0, 0.3, 0.8),
        FLOOR,
        false,
    );
    add_box(
        &mut mesh,
        Vec3::new(-0.9, 0.05, 0.4),
        Vec3::new(-0.6, 0.45, 0.8),
        FLOOR,
        false,
    );
    let light = Material {
        emission: Vec3::splat(3.0),
        ..Material::diffuse(Vec3::ZERO)
    };
    let mirror = Material {
        albedo: Vec3::splat(0.9),
        ..Material::new(MaterialKind::CONDUCTOR)
    };
    let glass = Material::new(MaterialKind::DIELECTRIC);
    let materials = vec![Material::diffuse(Vec3::splat(0.7)), light, mirror, glass];
    let camera = Camera::new(
        Vec3::new(0.0, 1.4, 2.8),
        Vec3::new(0.0, 0.5, 0.0),
        Vec3::Y,
        45.0,
        0.0,
        None,
    )
    .unwrap();
    let s = scene(mesh, materials, camera, Sky::Constant(Vec3::ZERO), settings);
    RenderScene::new(&s, &BuildParams::default()).unwrap()
}

/// A camera under water: inside a box of water (dielectric, IOR 1.33), looking at its
/// floor, which a small light above the water lights through the surface. Light subpaths
/// end on that floor inside the water and are seen from there: their throughput's
/// refraction (the adjoint's, without the radiance's squared index ratio) decides the
/// image.
fn pool_scene(settings: RenderSettings) -> RenderScene {
    let mut mesh = Mesh::default();
    add_box(
        &mut mesh,
        Vec3::new(-1.5, 0.0, -1.5),
        Vec3::new(1.5, 1.2, 1.5),
        GLASS,
        false,
    );
    quad(
        &mut mesh,
        horizontal(Vec3::new(0.0, 0.05, 0.0), 1.4, true),
        FLOOR,
    );
    quad(
        &mut mesh,
        horizontal(Vec3::new(0.3, 2.5, -0.2), 0.3, false),
        LIGHT,
    );
    let light = Material {
        emission: Vec3::splat(20.0),
        ..Material::diffuse(Vec3::ZERO)
    };
    let water = Material {
        ior: 1.33,
        ..Material::new(MaterialKind::DIELECTRIC)
    };
    let materials = vec![
        Material::diffuse(Vec3::new(0.8, 0.7, 0.6)),
        light,
        Material::diffuse(Vec3::ZERO),
        water,
    ];
    let camera = Camera::new(
        Vec3::new(0.0, 0.8, 1.2),
        Vec3::new(0.0, 0.0, -0.3),
        Vec3::Y,
        60.0,
        0.0,
        None,
    )
    .unwrap();
    let s = scene(mesh, materials, camera, Sky::Constant(Vec3::ZERO), settings);
    RenderScene::new(&s, &BuildParams::default()).unwrap()
}

fn mirror_check(gpu: Option<&meshtrace::render::gpu::GpuContext>, punctual: bool) {
    let s = RenderSettings {
        caustics: true,
        ..square(32, if gpu.is_some() { 32 } else { 64 }, 64, 0)
    };
    let mirror = mirror_scene(false, punctual, s);
    assert!(
        !mirror.caustic_targets.is_empty(),
        "the mirror must be a caustic target"
    );
    let doubled = mirror_scene(true, punctual, s);
    assert!(doubled.caustic_targets.is_empty());
    let test = renders(&mirror, s, 0..16, gpu);
    let reference = renders(&doubled, RenderSettings { spp: 512, ..s }, 100..108, None);
    let device = if gpu.is_some() { "GPU" } else { "CPU" };
    let lights = if punctual {
        "area, point and spot lights"
    } else {
        "area light"
    };
    assert_same_image(
        &format!("mirror, {lights} ({device}), against its doubled scene"),
        &test,
        &reference,
        8,
    );
}

#[test]
fn a_mirrors_caustic_is_the_lights_mirror_image() {
    mirror_check(None, false);
}

#[test]
fn a_mirrors_caustic_is_the_lights_mirror_image_on_the_gpu() {
    let Some(ctx) = common::gpu("a_mirrors_caustic_is_the_lights_mirror_image_on_the_gpu") else {
        return;
    };
    mirror_check(Some(&ctx), false);
}

/// Point and spot lights seen through the mirror: light the path tracer alone never finds.
#[test]
fn a_mirrors_caustics_of_point_and_spot_lights_are_their_mirror_images() {
    mirror_check(None, true);
}

#[test]
fn a_mirrors_caustics_of_point_and_spot_lights_are_their_mirror_images_on_the_gpu() {
    let Some(ctx) = common::gpu(
        "a_mirrors_caustics_of_point_and_spot_lights_are_their_mirror_images_on_the_gpu",
    ) else {
        return;
    };
    mirror_check(Some(&ctx), true);
}

fn sun_mirror_check(gpu: Option<&meshtrace::render::gpu::GpuContext>) {
    let s = RenderSettings {
        caustics: true,
        ..square(32, if gpu.is_some() { 32 } else { 64 }, 3, 0)
    };
    let mirror = sun_mirror_scene(false, s);
    assert!(
        !mirror.caustic_targets.is_empty(),
        "the mirror must be a caustic target"
    );
    let test = renders(&mirror, s, 0..16, gpu);
    let reference = renders(
        &sun_mirror_scene(true, s),
        RenderSettings { spp: 256, ..s },
        100..104,
        None,
    );
    let device = if gpu.is_some() { "GPU" } else { "CPU" };
    assert_same_image(
        &format!("sunlight off a mirror ({device}) against its image"),
        &test,
        &reference,
        8,
    );
}

#[test]
fn sunlight_off_a_mirror_is_its_mirror_image() {
    sun_mirror_check(None);
}

#[test]
fn sunlight_off_a_mirror_is_its_mirror_image_on_the_gpu() {
    let Some(ctx) = common::gpu("sunlight_off_a_mirror_is_its_mirror_image_on_the_gpu") else {
        return;
    };
    sun_mirror_check(Some(&ctx));
}

/// The path tracer alone, with the same scene: no targets, no light subpaths.
fn without_caustics(s: RenderSettings) -> RenderScene {
    spheres_scene(RenderSettings {
        caustics: false,
        ..s
    })
}

#[test]
fn caustics_keep_the_expected_image_of_glass_and_mirror_spheres() {
    let s = RenderSettings {
        caustics: true,
        ..square(32, 64, 8, 0)
    };
    let with = spheres_scene(s);
    assert!(
        !with.caustic_targets.is_empty(),
        "the spheres are caustic targets"
    );
    let test = renders(&with, s, 0..6, None);
    let reference = renders(
        &without_caustics(s),
        RenderSettings { spp: 1024, ..s },
        20..26,
        None,
    );
    assert_same_image("glass and mirror spheres (CPU)", &test, &reference, 8);
}

#[test]
fn caustics_keep_the_expected_image_of_glass_and_mirror_spheres_on_the_gpu() {
    let Some(ctx) =
        common::gpu("caustics_keep_the_expected_image_of_glass_and_mirror_spheres_on_the_gpu")
    else {
        return;
    };
    let s = RenderSettings {
        caustics: true,
        ..square(32, 64, 8, 0)
    };
    let test = renders(&spheres_scene(s), s, 0..4, Some(&ctx));
    let reference = renders(
        &without_caustics(s),
        RenderSettings { spp: 1024, ..s },
        20..26,
        None,
    );
    assert_same_image("glass and mirror spheres (GPU)", &test, &reference, 8);
}

/// Glass and mirror spheres with caustics and 2 branches a camera sample (each tracing a
/// light subpath of its own, its splats weighed 1/2) against the path tracer alone.
fn branched_spheres_check(gpu: Option<&meshtrace::render::gpu::GpuContext>) {
    let s = RenderSettings {
        caustics: true,
        branches: Some(2),
        ..square(32, if gpu.is_some() { 16 } else { 32 }, 8, 0)
    };
    let test = renders(&spheres_scene(s), s, 0..6, gpu);
    let plain = RenderSettings {
        spp: 1024,
        branches: Some(1),
        ..s
    };
    let reference = renders(&without_caustics(plain), plain, 20..26, None);
    let device = if gpu.is_some() { "GPU" } else { "CPU" };
    assert_same_image(
        &format!("glass and mirror spheres, 2 branches ({device})"),
        &test,
        &reference,
        8,
    );
}

#[test]
fn branched_caustics_keep_the_expected_image_of_glass_and_mirror_spheres() {
    branched_spheres_check(None);
}

#[test]
fn branched_caustics_keep_the_expected_image_of_glass_and_mirror_spheres_on_the_gpu() {
    let Some(ctx) = common::gpu(
        "branched_caustics_keep_the_expected_image_of_glass_and_mirror_spheres_on_the_gpu",
    ) else {
        return;
    };
    branched_spheres_check(Some(&ctx));
}

/// The dielectric furnace (see the top of the file): flat glass and mirror blocks, and a
/// white block inside a glass one, in an enclosure of emissive walls. Flat faces, so that
/// no shading normal loses energy; paths up to 256 segments, which Russian roulette ends
/// long before.
#[test]
fn an_emissive_enclosure_holding_glass_and_mirrors_keeps_its_radiance() {
    let mut mesh = Mesh::default();
    add_box(&mut mesh, Vec3::splat(-1.0), Vec3::splat(1.0), 0, true);
    add_box(
        &mut mesh,
        Vec3::new(-0.8, -0.95, -0.7),
        Vec3::new(-0.1, -0.2, 0.0),
        1,
        false,
    );
    add_box(
        &mut mesh,
        Vec3::new(-0.6, -0.8, -0.5),
        Vec3::new(-0.3, -0.5, -0.2),
        3,
        false,
    );
    add_box(
        &mut mesh,
        Vec3::new(0.1, -0.95, -0.6),
        Vec3::new(0.6, -0.4, -0.1),
        2,
        false,
    );
    add_box(
        &mut mesh,
        Vec3::new(-0.3, 0.2, -0.8),
        Vec3::new(0.4, 0.7, -0.4),
        1,
        false,
    );
    let wall = Material {
        emission: Vec3::new(0.5, 0.75, 0.25),
        ..Material::diffuse(Vec3::new(0.5, 0.25, 0.75))
    };
    let expect = wall.emission / (Vec3::ONE - wall.albedo);
    let glass = Material::new(MaterialKind::DIELECTRIC);
    let mirror = Material {
        albedo: Vec3::ONE,
        ..Material::new(MaterialKind::CONDUCTOR)
    };
    let camera = Camera::new(
        Vec3::new(0.6, 0.5, 0.9),
        Vec3::new(-0.2, -0.4, -0.6),
        Vec3::Y,
        70.0,
        0.0,
        None,
    )
    .unwrap();
    let settings = RenderSettings {
        caustics: true,
        ..square(48, 64, 256, 7)
    };
    let materials = vec![wall, glass, mirror, Material::diffuse(Vec3::ONE)];
    let s = scene(mesh, materials, camera, Sky::Constant(Vec3::ZERO), settings);
    for (device, film) in common::render_both("glass_furnace", &s) {
        assert_mean(
            "glass and mirrors in an emissive enclosure",
            device,
            &film,
            expect,
        );
    }
}

#[test]
fn caustics_keep_the_expected_image_seen_from_under_water() {
    let s = RenderSettings {
        caustics: true,
        ..square(32, 64, 8, 0)
    };
    let test = renders(&pool_scene(s), s, 0..16, None);
    let off = RenderSettings {
        caustics: false,
        spp: 512,
        ..s
    };
    let reference = renders(&pool_scene(off), off, 100..108, None);
    assert_same_image("under water (CPU)", &test, &reference, 8);
}
