//! Helpers shared by the integration tests: GPU availability, generated scenes, and
//! image statistics.
#![allow(dead_code)]

use glam::Vec3;
use meshtrace::film::Film;
use meshtrace::render::gpu::{GpuContext, GpuError, GpuRenderer};
use meshtrace::render::{RenderJob, RenderScene, cpu};
use meshtrace::scene::{Camera, Material, Mesh, NO_NORMAL, RenderSettings, Scene, Sky, Triangle};

/// The test's GPU, or `None` (after saying "skipped: no adapter") where there is none.
/// With `MESHTRACE_REQUIRE_GPU=1`, as CI sets it, a missing adapter fails the test instead,
/// so a broken driver set-up can never pass silently.
pub fn gpu(test: &str) -> Option<GpuContext> {
    let required = std::env::var("MESHTRACE_REQUIRE_GPU").is_ok_and(|v| v == "1");
    match GpuContext::new(None) {
        Ok(ctx) => Some(ctx),
        Err(GpuError::NoAdapter) if !required => {
            eprintln!("{test}: skipped: no adapter");
            None
        }
        Err(e) => panic!("{test}: MESHTRACE_REQUIRE_GPU=1 but the GPU is unusable: {e}"),
    }
}

/// The job rendered by the CPU renderer.
pub fn cpu_render(scene: &RenderScene, job: &RenderJob) -> Film {
    cpu::render(scene, job, &|_| {})
}

/// The job rendered by a fresh GPU renderer session on `ctx`.
pub fn gpu_render(ctx: &GpuContext, scene: &RenderScene, job: &RenderJob) -> Film {
    GpuRenderer::new(ctx, scene)
        .and_then(|mut r| r.render(job, &|_| {}))
        .unwrap_or_else(|e| panic!("GPU render: {e}"))
}

/// The `../shared/meshes` folder beside the checkout, if present.
pub fn shared_mesh(name: &str) -> Option<std::path::PathBuf> {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../shared/meshes")
        .join(name);
    if p.exists() {
        Some(p)
    } else {
        eprintln!("skipped: {} absent", p.display());
        None
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
                material,
            });
        }
    }
}

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
        mesh,
        warnings: Vec::new(),
    }
}

/// Mean and standard error of the mean of per-pixel values (pixels are independent).
pub fn mean_and_stderr(values: &[f32]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().map(|&v| v as f64).sum::<f64>() / n;
    let var = values
        .iter()
        .map(|&v| (v as f64 - mean).powi(2))
        .sum::<f64>()
        / (n - 1.0);
    (mean, (var / n).sqrt())
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
    let mut state = 0x9e3779b9u32;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 17;
        state ^= state << 5;
        state as f32 / u32::MAX as f32 - 0.5
    };
    targets.extend((0..20_000).map(|_| offset + Vec3::new(next(), next(), next())));
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
