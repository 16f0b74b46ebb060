//! Scenes for the tests: built in code (boxes, spheres, one triangle per material, a closed
//! mesh with rays that probe its seams) or the built-in Cornell box, and render settings.

use super::rand::SplitMix;
use glam::Vec3;
use meshtrace::bvh::BuildParams;
use meshtrace::render::RenderScene;
use meshtrace::scene::{Camera, Material, Mesh, NO_NORMAL, RenderSettings, Scene, Sky, Triangle};

/// The built-in Cornell box, with its own settings.
pub fn cornell() -> (RenderScene, RenderSettings) {
    let scene = meshtrace::scene::builtin::load_builtin("cornell").expect("cornell");
    let settings = scene.settings;
    (
        RenderScene::new(&scene, &BuildParams::default()).expect("BVH"),
        settings,
    )
}

/// Settings for a square image of `width` pixels, one path a camera sample (1 branch): the
/// tests of other features compare with references that trace one path a sample, and
/// tests/branches.rs checks the branches.
pub fn square(width: u32, spp: u32, max_depth: u32, seed: u32) -> RenderSettings {
    RenderSettings {
        width,
        height: width,
        spp,
        max_depth,
        seed,
        branches: Some(1),
        ..RenderSettings::default()
    }
}

/// Appends the 12 triangles of an axis-aligned box, wound so their fronts face outwards
/// (`inward = false`) or inwards.
pub fn add_box(mesh: &mut Mesh, min: Vec3, max: Vec3, material: u32, inward: bool) {
    let base = mesh.positions.len() as u32;
    for i in 0..8u32 {
        mesh.positions.push(Vec3::new(
            if i & 1 == 0 { min.x } else { max.x },
            if i & 2 == 0 { min.y } else { max.y },
            if i & 4 == 0 { min.z } else { max.z },
        ));
    }
    // Each face counter-clockwise seen from outside.
    let quads = [
        [0, 2, 3, 1], // -z
        [4, 5, 7, 6], // +z
        [0, 4, 6, 2], // -x
        [1, 3, 7, 5], // +x
        [0, 1, 5, 4], // -y
        [2, 6, 7, 3], // +y
    ];
    for q in quads {
        let [a, b, c, d] = q.map(|k| base + k);
        for t in [[a, b, c], [a, c, d]] {
            let p = if inward { [t[0], t[2], t[1]] } else { t };
            mesh.triangles.push(Triangle {
                p,
                n: [NO_NORMAL; 3],
                t: [meshtrace::scene::NO_UV; 3],
                material,
            });
        }
    }
}

/// A scene of `mesh` and `materials` (named m0, m1, ...), without a file.
pub fn scene(
    mesh: Mesh,
    materials: Vec<Material>,
    camera: Camera,
    sky: Sky,
    settings: RenderSettings,
) -> Scene {
    Scene {
        path: None,
        camera,
        sky,
        settings,
        material_names: (0..materials.len()).map(|i| format!("m{i}")).collect(),
        materials,
        textures: Default::default(),
        lights: Vec::new(),
        mesh,
        warnings: Vec::new(),
        notes: Vec::new(),
        framed: None,
        root_origin: None,
    }
}

/// Appends a smooth-shaded icosphere (normals from the centre).
pub fn add_sphere(mesh: &mut Mesh, centre: Vec3, radius: f32, level: u32, material: u32) {
    let (verts, faces) = meshtrace::scene::sphere::icosphere(level);
    let base_p = mesh.positions.len() as u32;
    let base_n = mesh.normals.len() as u32;
    for v in &verts {
        mesh.positions.push(centre + radius * *v);
        mesh.normals.push(*v);
    }
    for t in faces {
        mesh.triangles.push(Triangle {
            p: t.map(|i| base_p + i),
            n: t.map(|i| base_n + i),
            t: [meshtrace::scene::NO_UV; 3],
            material,
        });
    }
}

/// A scene whose material table is `materials`, as given (one small triangle each), under a
/// white sky, for the test kernels to read materials from.
pub fn material_table(materials: Vec<Material>) -> (RenderScene, RenderSettings) {
    let mut mesh = Mesh::default();
    for i in 0..materials.len() as u32 {
        let base = mesh.positions.len() as u32;
        let o = Vec3::new(i as f32, 0.0, 0.0);
        mesh.positions.extend([
            o,
            o + Vec3::new(0.5, 0.0, 0.0),
            o + Vec3::new(0.0, 0.5, 0.0),
        ]);
        mesh.triangles.push(Triangle {
            p: [base, base + 1, base + 2],
            n: [NO_NORMAL; 3],
            t: [meshtrace::scene::NO_UV; 3],
            material: i,
        });
    }
    let camera = Camera::new(
        Vec3::new(3.0, 0.0, 10.0),
        Vec3::new(3.0, 0.0, 0.0),
        Vec3::Y,
        40.0,
        0.0,
        None,
    )
    .unwrap();
    let settings = RenderSettings {
        width: 16,
        height: 16,
        spp: 1,
        max_depth: 4,
        seed: 0,
        ..RenderSettings::default()
    };
    let s = scene(mesh, materials, camera, Sky::Constant(Vec3::ONE), settings);
    (
        RenderScene::new(&s, &BuildParams::default()).expect("BVH"),
        settings,
    )
}

/// A closed icosphere (level 4) far from the origin, where rounding is coarse, and the rays
/// that probe it from inside: from two interior points towards every vertex, every edge
/// midpoint (where neighbouring triangles meet) and 20,000 random points. A watertight
/// triangle test lets none of them escape.
pub struct ClosedMeshProbe {
    pub positions: Vec<Vec3>,
    pub faces: Vec<[u32; 3]>,
    /// (origin, direction) of every ray.
    pub rays: Vec<(Vec3, Vec3)>,
}

pub fn closed_mesh_probe() -> ClosedMeshProbe {
    let (v, faces) = meshtrace::scene::sphere::icosphere(4);
    let (scale, offset) = (Vec3::new(1.7, 0.9, 1.3), Vec3::new(1000.25, -3.5, 7.0));
    let positions: Vec<Vec3> = v.iter().map(|&p| p * scale + offset).collect();
    let mut targets = positions.clone();
    for t in &faces {
        for k in 0..3 {
            let (a, b) = (t[k] as usize, t[(k + 1) % 3] as usize);
            targets.push(0.5 * (positions[a] + positions[b]));
        }
    }
    let mut rng = SplitMix::new(0x9e37_79b9);
    targets.extend((0..20_000).map(|_| offset + rng.vec3(-0.5, 0.5)));
    let rays = [offset, offset + Vec3::new(0.1, -0.2, 0.05)]
        .iter()
        .flat_map(|&o| targets.iter().map(move |&t| (o, t - o)))
        .filter(|&(_, d)| d != Vec3::ZERO)
        .collect();
    ClosedMeshProbe {
        positions,
        faces,
        rays,
    }
}

/// The camera inside a closed box whose walls all emit Le and reflect albedo (a second box
/// inside it): radiance L solves L = Le + albedo L, so L = Le / (1 - albedo) everywhere,
/// through closest hits, shadow rays and both MIS weights. Returns the scene (48 x 48, 64
/// spp, paths up to 64 segments) and that radiance.
pub fn emissive_enclosure() -> (Scene, Vec3) {
    let mut mesh = Mesh::default();
    add_box(&mut mesh, Vec3::splat(-1.0), Vec3::splat(1.0), 0, true);
    add_box(
        &mut mesh,
        Vec3::new(-0.5, -1.0, -0.5),
        Vec3::new(0.0, -0.2, 0.1),
        0,
        false,
    );
    let mut wall = Material::diffuse(Vec3::new(0.5, 0.25, 0.75));
    wall.emission = Vec3::new(0.5, 0.75, 0.25);
    let expect = wall.emission / (Vec3::ONE - wall.albedo);
    (enclosure(mesh, wall, square(48, 64, 64, 7)), expect)
}

/// `mesh` (an enclosure about the origin, within ±1) all of `material`, seen from inside
/// by a 70° camera, under a black sky, rendered with `settings`.
pub fn enclosure(mesh: Mesh, material: Material, settings: RenderSettings) -> Scene {
    let camera = Camera::new(
        Vec3::new(0.5, 0.5, 0.9),
        Vec3::new(-0.3, -0.4, -1.0),
        Vec3::Y,
        70.0,
        0.0,
        None,
    )
    .expect("camera");
    scene(
        mesh,
        vec![material],
        camera,
        Sky::Constant(Vec3::ZERO),
        settings,
    )
}
