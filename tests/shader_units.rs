//! Every WGSL stage against its Rust twin, through the test kernels of `shaders/tests.wgsl`:
//! thousands of deterministic random cases per kernel, each compared with the CPU function
//! of the same name. Skipped without a GPU (see `common::gpu`).
//!
//! Run with `--nocapture` to see the cases, maximum errors and agreement of each kernel.

use crate::common;

use common::kernels::{
    Case, GpuBsdfSample, b, bsdf_eval_case, bsdf_eval_output, bsdf_sample_case, f, run, v3, word,
};
use common::materials::{ggx_tolerance, material_name, shape_wo};
use common::rand::SplitMix;
use common::scenes::{add_sphere, cornell, scene};
use common::stats::{Failures, Tally, Worst, rel, rel3};
use common::traversal::{Bounds, check_traversal, near_edge, plane_hit_f64, traversal_rays};
use glam::{Vec2, Vec3};
use meshtrace::bvh::{BuildParams, solid};
use meshtrace::fixed::{
    FIXED_LIMIT, FIXED_ONE, fixed_add, from_words, texel_add, to_fixed, to_words,
};
use meshtrace::geometry::{ShearedRay, T_INF, intersect_aabb, intersect_triangle, safe_inverse};
use meshtrace::math::Ray;
use meshtrace::render::bsdf::{bsdf_eval, bsdf_pdf, bsdf_sample, fresnel_dielectric};
use meshtrace::render::camera::{CameraRays, generate_camera_ray, pixel_centre_ray};
use meshtrace::render::caustics::{sample_target, target_cone, target_pdf};
use meshtrace::render::environment::{env_pdf, env_radiance, sample_env};
use meshtrace::render::gpu::GpuContext;
use meshtrace::render::integrator::{first_hit, start_light, trace_path};
use meshtrace::render::lights::pick_light;
use meshtrace::render::rng::{DIMS_PER_BOUNCE, Rng, dim_pair, pcg4d};
use meshtrace::render::sampling::{
    cosine_hemisphere_pdf, power_heuristic, sample_cdf, sample_concentric_disk,
    sample_cosine_hemisphere, sample_uniform_triangle,
};
use meshtrace::render::texture::{
    alpha_test, material_at, normal_mapped, texture_lookup, triangle_color, triangle_uv,
};
use meshtrace::render::{RenderScene, TRI_SMOOTH, TRI_TANGENT};
use meshtrace::scene::{
    Camera, Material, MaterialKind, Mesh, NO_NORMAL, RenderSettings, Sky, Triangle, load_scene,
};
use std::time::Instant;

// ---------------------------------------------------------------------------------------
// Scenes.

// The mesh scene's materials: 0 and 1 diffuse, 2 a smooth conductor, then:
/// Rough conductors of roughness `ROUGHNESS[k]` are material `M_ROUGH + k`.
const M_ROUGH: u32 = 3;
const ROUGHNESS: [f32; 5] = [0.02, 0.1, 0.3, 0.6, 1.0];
const M_DIELECTRIC: u32 = M_ROUGH + ROUGHNESS.len() as u32;
const M_EMITTERS: u32 = M_DIELECTRIC + 1;
const EMISSIONS: [[f32; 3]; 3] = [[10.0, 10.0, 10.0], [1.0, 0.5, 0.2], [50.0, 40.0, 30.0]];

fn material(kind: MaterialKind, albedo: Vec3, roughness: f32) -> Material {
    Material {
        albedo,
        roughness,
        ..Material::new(kind)
    }
}

fn mesh_materials() -> Vec<Material> {
    let mut m = vec![
        material(MaterialKind::DIFFUSE, Vec3::splat(0.8), 0.0),
        material(MaterialKind::DIFFUSE, Vec3::new(0.2, 0.5, 0.9), 0.0),
        material(MaterialKind::CONDUCTOR, Vec3::new(0.9, 0.7, 0.3), 0.0),
    ];
    for r in ROUGHNESS {
        m.push(material(
            MaterialKind::ROUGH_CONDUCTOR,
            Vec3::new(0.95, 0.6, 0.5),
            r,
        ));
    }
    m.push(material(MaterialKind::DIELECTRIC, Vec3::ONE, 0.0));
    for e in EMISSIONS {
        let mut l = material(MaterialKind::DIFFUSE, Vec3::splat(0.5), 0.0);
        l.emission = Vec3::from(e);
        m.push(l);
    }
    m
}

/// A soup of 2,500 random triangles of every material (every 40th one an emitter of one
/// of three powers), a smooth glass icosphere and a smooth rough-metal one: 4,100
/// triangles, under a gradient sky.
fn mesh_scene() -> (RenderScene, RenderSettings) {
    let mut rng = SplitMix::new(0x5eed_0001);
    let mut mesh = Mesh::default();
    for i in 0..2500 {
        let c = rng.vec3(-2.5, 2.5);
        let size = rng.range(0.05, 0.6);
        let base = mesh.positions.len() as u32;
        for _ in 0..3 {
            mesh.positions.push(c + size * rng.vec3(-1.0, 1.0));
        }
        let material = if i % 40 == 0 {
            M_EMITTERS + (i / 40) % EMISSIONS.len() as u32
        } else {
            rng.below(M_EMITTERS as usize) as u32
        };
        mesh.triangles.push(Triangle {
            p: [base, base + 1, base + 2],
            n: [NO_NORMAL; 3],
            t: [meshtrace::scene::NO_UV; 3],
            material,
        });
    }
    add_sphere(&mut mesh, Vec3::new(0.3, -0.2, 0.4), 0.9, 3, M_DIELECTRIC);
    add_sphere(&mut mesh, Vec3::new(-1.2, 1.0, -0.8), 0.6, 2, M_ROUGH + 2);
    let camera = Camera::new(
        Vec3::new(0.5, 0.8, 7.0),
        Vec3::ZERO,
        Vec3::Y,
        45.0,
        0.0,
        None,
    )
    .unwrap();
    let settings = RenderSettings {
        width: 160,
        height: 120,
        spp: 1,
        max_depth: 10,
        seed: 1234,
        ..RenderSettings::default()
    };
    let sky = Sky::Gradient {
        zenith: Vec3::new(0.3, 0.5, 0.9),
        horizon: Vec3::new(1.0, 0.9, 0.8),
    };
    let scene = scene(mesh, mesh_materials(), camera, sky, settings);
    let rs = RenderScene::new(&scene, &BuildParams::default()).expect("BVH");
    assert!(rs.tris.len() > 4000);
    assert!(rs.emitters.len() >= 50, "{} emitters", rs.emitters.len());
    assert!(rs.shading.iter().any(|s| s.flags & TRI_SMOOTH != 0));
    (rs, settings)
}

// ---------------------------------------------------------------------------------------
// The tests.

#[test]
fn rng_matches_bit_for_bit() {
    let Some(ctx) = common::gpu("rng_matches_bit_for_bit") else {
        return;
    };
    let (rs, settings) = cornell();
    let mut r = SplitMix::new(1);
    let mut cases: Vec<Case> = Vec::new();
    // Structured keys: the first pixels, samples and every (bounce, dim) a path uses.
    for pixel in 0..4u32 {
        for sample in 0..4u32 {
            for key in 0..12 * DIMS_PER_BOUNCE {
                cases.push([[pixel * 1000, sample, 0, key], [0; 4]]);
            }
        }
    }
    let edge = [
        0,
        1,
        15,
        16,
        0x7fff_ffff,
        0x8000_0000,
        u32::MAX - 1,
        u32::MAX,
    ];
    while cases.len() < 20_000 {
        let mut k = [r.u32(), r.u32(), r.u32(), r.u32()];
        if r.chance(0.1) {
            k[r.below(4)] = edge[r.below(edge.len())];
        }
        cases.push([k, [0; 4]]);
    }
    let out = run(&ctx, &rs, &settings, "test_rng", &cases);
    let mut fail = Failures::new("test_rng");
    for (c, o) in cases.iter().zip(&out) {
        let k = c[0];
        let rng = Rng::new(k[0], k[1], k[2]);
        let (bounce, dim) = (k[3] / DIMS_PER_BOUNCE, k[3] % DIMS_PER_BOUNCE);
        let h = pcg4d([k[0], k[1], k[3], k[2]]);
        let pair = rng.rng_2d(bounce, dim_pair(dim).0);
        let want = [
            [
                rng.rng_u32(bounce, dim),
                rng.rng_1d(bounce, dim).to_bits(),
                pair.x.to_bits(),
                pair.y.to_bits(),
            ],
            h,
        ];
        if *o != want {
            fail.add(|| format!("key {k:?}: GPU {o:x?}, CPU {want:x?}"));
        }
    }
    eprintln!(
        "test_rng: {} cases, {} differ (bit-exact required)",
        cases.len(),
        fail.count
    );
    fail.check(cases.len());
}

/// Exact film sums: every f32 class (zeros, subnormals, ties at half a unit, the clamp,
/// infinities, NaN) to fixed point, and additions across the word boundary and to
/// saturation, bit for bit.
#[test]
fn fixed_point_sums_match_bit_for_bit() {
    let Some(ctx) = common::gpu("fixed_point_sums_match_bit_for_bit") else {
        return;
    };
    let (rs, settings) = cornell();
    let mut r = SplitMix::new(17);
    let special = [
        0.0,
        -0.0,
        f32::from_bits(1),
        f32::MIN_POSITIVE,
        0.5 / FIXED_ONE,
        1.5 / FIXED_ONE,
        2.5 / FIXED_ONE,
        -2.5 / FIXED_ONE,
        1.0,
        -1.0,
        4294967296.0 / FIXED_ONE,
        4294967295.0 / FIXED_ONE,
        FIXED_LIMIT,
        -FIXED_LIMIT,
        FIXED_LIMIT * 2.0,
        f32::MAX,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::NAN,
        -f32::NAN,
    ];
    let wide = [
        0i64,
        1,
        -1,
        u32::MAX as i64,
        1 << 32,
        i64::MAX,
        i64::MIN,
        i64::MAX - 3,
        i64::MIN + 3,
    ];
    let value = |r: &mut SplitMix| -> f32 {
        match r.below(4) {
            0 => special[r.below(special.len())],
            // Random bits: every exponent and sign.
            1 => f32::from_bits(r.u32()),
            // Near a half unit, where the rounding mode shows.
            2 => {
                (r.below(1 << 20) as f32 + 0.5) / FIXED_ONE * if r.chance(0.5) { -1.0 } else { 1.0 }
            }
            _ => r.range(-1.0, 1.0) * 10f32.powf(r.range(-8.0, 12.0)),
        }
    };
    let sum = |r: &mut SplitMix| -> i64 {
        match r.below(3) {
            0 => wide[r.below(wide.len())],
            1 => r.next_u64() as i64,
            _ => to_fixed(r.range(-1e6, 1e6)),
        }
    };
    let mut cases: Vec<Case> = Vec::new();
    while cases.len() < 20_000 {
        let (v0, v1) = (value(&mut r), value(&mut r));
        let (a, b) = (to_words(sum(&mut r)), to_words(sum(&mut r)));
        cases.push([[v0.to_bits(), v1.to_bits(), a[0], a[1]], [b[0], b[1], 0, 0]]);
    }
    let out = run(&ctx, &rs, &settings, "test_fixed", &cases);
    let mut fail = Failures::new("test_fixed");
    for (c, o) in cases.iter().zip(&out) {
        let [v0, v1] = [c[0][0], c[0][1]].map(f32::from_bits);
        let (a, b) = (
            from_words([c[0][2], c[0][3]]),
            from_words([c[1][0], c[1][1]]),
        );
        let t = texel_add([a, b, a, b], [v0, v1, 0.0, 1.0]);
        let [f0, f1, s, t1] = [to_fixed(v0), to_fixed(v1), fixed_add(a, b), t[1]].map(to_words);
        let want = [[f0[0], f0[1], f1[0], f1[1]], [s[0], s[1], t1[0], t1[1]]];
        if *o != want {
            fail.add(|| format!("{v0:e}, {v1:e}, {a}, {b}: GPU {o:x?}, CPU {want:x?}"));
        }
    }
    eprintln!(
        "test_fixed: {} cases, {} differ (bit-exact required)",
        cases.len(),
        fail.count
    );
    fail.check(cases.len());
}

#[test]
fn intersect_triangle_matches() {
    let Some(ctx) = common::gpu("intersect_triangle_matches") else {
        return;
    };
    let (rs, settings) = mesh_scene();
    let mut r = SplitMix::new(2);
    let mut cases: Vec<Case> = Vec::new();
    while cases.len() < 20_000 {
        let i = r.below(rs.tris.len());
        let [a, bb, c] = rs.tris[i].corners();
        let centroid = (a + bb + c) / 3.0;
        let bary = sample_uniform_triangle(Vec2::new(r.unit(), r.unit()));
        let p = (1.0 - bary.x - bary.y) * a + bary.x * bb + bary.y * c;
        // Scaling about the centroid by s in [0, 2) puts the target inside for s <= 1.
        let mut target = centroid + r.range(0.0, 2.0) * (p - centroid);
        if r.chance(0.03) {
            // Exactly on a vertex or an edge's midpoint.
            target = [a, bb, c, 0.5 * (a + bb), 0.5 * (bb + c), 0.5 * (c + a)][r.below(6)];
        }
        let dir_unit = r.unit_vector();
        let dist = r.range(0.01, 5.0);
        let scale = r.range(0.1, 10.0);
        let mut dir = dir_unit * scale;
        let origin = target - dir_unit * dist;
        if r.chance(0.01) {
            // Parallel to the triangle's plane.
            let n = (bb - a).cross(c - a);
            dir = dir - dir.dot(n) / n.length_squared() * n;
        }
        let t_max = if r.chance(0.2) {
            r.range(0.0, 2.0 * dist / scale)
        } else {
            T_INF
        };
        cases.push([word(origin, i as u32), word(dir, b(t_max))]);
    }
    let out = run(&ctx, &rs, &settings, "test_intersect_triangle", &cases);
    let mut fail = Failures::new("test_intersect_triangle");
    let mut boundary = Tally::new("hit/miss differs within 1e-5 of an edge or t_max", 1e-3);
    let mut t_err = Worst::new("t (relative)", 1e-5);
    let mut uv_err = Worst::new("u, v (relative, abs 1e-6)", 1e-5);
    let mut hits = 0;
    for (c, o) in cases.iter().zip(&out) {
        let ray = Ray::new(v3(c[0]), v3(c[1]));
        let tri = &rs.tris[c[0][3] as usize];
        let t_max = f(c[1][3]);
        let cpu = intersect_triangle(&ShearedRay::new(&ray), tri, t_max);
        let gpu_hit = o[0][0] == 1;
        let (gt, gu, gv) = (f(o[0][1]), f(o[0][2]), f(o[0][3]));
        let show = || {
            format!(
                "ray {:?} tri {} t_max {t_max}: CPU {cpu:?}, GPU hit {gpu_hit} t {gt} u {gu} v {gv}",
                ray, c[0][3]
            )
        };
        hits += cpu.is_some() as usize;
        match cpu {
            Some(h) if gpu_hit => {
                // Grazing rays amplify rounding by 1 / cos: scale the error by cos.
                let cos = plane_hit_f64(&ray, tri).3.min(1.0);
                t_err.add(rel(h.t, gt, 0.0) * cos, show);
                uv_err.add(rel(h.u, gu, 0.1).max(rel(h.v, gv, 0.1)) * cos, show);
            }
            None if !gpu_hit => {}
            _ => {
                let (t, u, v, cos) = plane_hit_f64(&ray, tri);
                let eps = 1e-5 / cos.max(1e-6);
                let at_edge = near_edge(u, v, eps);
                let at_t = (t - t_max as f64).abs() < eps * t.abs() || t.abs() < eps;
                if at_edge || at_t {
                    boundary.add(show);
                } else {
                    fail.add(show);
                }
            }
        }
    }
    eprintln!(
        "test_intersect_triangle: {} cases, {hits} CPU hits",
        cases.len()
    );
    fail.check(cases.len());
    boundary.check("test_intersect_triangle", cases.len());
    t_err.check("test_intersect_triangle");
    uv_err.check("test_intersect_triangle");
    assert!(
        hits > cases.len() / 3 && hits < 2 * cases.len() / 3,
        "{hits}"
    );
}

#[test]
fn intersect_aabb_matches() {
    let Some(ctx) = common::gpu("intersect_aabb_matches") else {
        return;
    };
    let (rs, settings) = mesh_scene();
    let nodes = &rs.bvh.nodes;
    let mut r = SplitMix::new(3);
    let mut cases: Vec<Case> = Vec::new();
    while cases.len() < 20_000 {
        let i = r.below(nodes.len());
        let bx = nodes[i].bounds();
        let target = bx.center() + bx.extent() * r.vec3(-0.65, 0.65);
        let mut dir = r.unit_vector();
        if r.chance(0.15) {
            // Axis-parallel rays: one or two zero components.
            dir[r.below(3)] = 0.0;
            if r.chance(0.5) {
                dir[r.below(3)] = 0.0;
            }
            if dir == Vec3::ZERO {
                dir = Vec3::X;
            }
        }
        if r.chance(0.05) {
            dir[r.below(3)] = -0.0;
        }
        dir *= r.range(0.2, 5.0);
        let dist = if r.chance(0.2) {
            0.0 // starts inside the box (or on its boundary)
        } else {
            r.range(0.0, 3.0)
        };
        let origin = target - dir * dist;
        let t_max = if r.chance(0.3) {
            r.range(0.0, 2.0 * dist)
        } else {
            T_INF
        };
        cases.push([word(origin, i as u32), word(dir, b(t_max))]);
    }
    let out = run(&ctx, &rs, &settings, "test_intersect_aabb", &cases);
    let mut fail = Failures::new("test_intersect_aabb");
    let mut boundary = Tally::new("hit/miss differs where t_near ~ t_far", 1e-3);
    let mut t_err = Worst::new("t_near (relative, abs 1e-6)", 1e-5);
    let mut hits = 0;
    for (c, o) in cases.iter().zip(&out) {
        let n = &nodes[c[0][3] as usize];
        let (origin, dir, t_max) = (v3(c[0]), v3(c[1]), f(c[1][3]));
        let cpu = intersect_aabb(origin, safe_inverse(dir), n.min.into(), n.max.into(), t_max);
        let gpu = f(o[0][0]);
        let show = || {
            format!(
                "origin {origin} dir {dir} t_max {t_max} box {:?}..{:?}: CPU {cpu}, GPU {gpu}",
                n.min, n.max
            )
        };
        hits += (cpu != T_INF) as usize;
        if (cpu == T_INF) != (gpu == T_INF) {
            // f64 slab test: is the ray grazing the box, or ending at its entry?
            let inv = safe_inverse(dir).as_dvec3();
            let t0 = (Vec3::from(n.min).as_dvec3() - origin.as_dvec3()) * inv;
            let t1 = (Vec3::from(n.max).as_dvec3() - origin.as_dvec3()) * inv;
            let near = t0.min(t1).max_element().max(0.0);
            let far = t0.max(t1).min_element().min(t_max as f64);
            if (far - near).abs() <= 1e-5 * near.abs().max(1e-1) {
                boundary.add(show);
            } else {
                fail.add(show);
            }
        } else if cpu != T_INF {
            t_err.add(rel(cpu, gpu, 0.1), show);
        }
    }
    eprintln!(
        "test_intersect_aabb: {} cases, {hits} CPU hits",
        cases.len()
    );
    fail.check(cases.len());
    boundary.check("test_intersect_aabb", cases.len());
    t_err.check("test_intersect_aabb");
    assert!(
        hits > cases.len() / 4 && hits < 3 * cases.len() / 4,
        "{hits}"
    );
}

/// The GPU twin of tests/properties.rs `no_ray_escapes_a_closed_mesh`: every ray of
/// [`common::scenes::closed_mesh_probe`] hits the mesh (closest and any hit), however the driver
/// contracts the arithmetic.
#[test]
fn no_ray_escapes_a_closed_mesh() {
    let Some(ctx) = common::gpu("no_ray_escapes_a_closed_mesh") else {
        return;
    };
    let probe = common::scenes::closed_mesh_probe();
    let mesh = Mesh {
        triangles: probe
            .faces
            .iter()
            .map(|&p| Triangle {
                p,
                n: [NO_NORMAL; 3],
                t: [meshtrace::scene::NO_UV; 3],
                material: 0,
            })
            .collect(),
        positions: probe.positions,
        ..Mesh::default()
    };
    let centre = probe.rays[0].0;
    let camera = Camera::new(centre + 5.0 * Vec3::Z, centre, Vec3::Y, 40.0, 0.0, None).unwrap();
    let settings = RenderSettings {
        width: 8,
        height: 8,
        spp: 1,
        max_depth: 2,
        seed: 0,
        ..RenderSettings::default()
    };
    let sky = Sky::Constant(Vec3::ONE);
    let scene = scene(mesh, mesh_materials(), camera, sky, settings);
    let rs = RenderScene::new(&scene, &BuildParams::default()).expect("BVH");
    let cases: Vec<Case> = probe
        .rays
        .iter()
        .map(|&(o, d)| [word(o, 0), word(d, b(T_INF))])
        .collect();
    let out = run(&ctx, &rs, &settings, "test_traverse", &cases);
    let escapes: Vec<&Case> = cases
        .iter()
        .zip(&out)
        .filter(|(_, o)| o[0][0] == u32::MAX || o[1][0] != 1)
        .map(|(c, _)| c)
        .collect();
    eprintln!(
        "no_ray_escapes_a_closed_mesh: {} rays from inside, {} escape on the GPU",
        cases.len(),
        escapes.len()
    );
    assert!(
        escapes.is_empty(),
        "{} rays escape, e.g. origin {} dir {}",
        escapes.len(),
        v3(escapes[0][0]),
        v3(escapes[0][1])
    );
}

/// The software walk's bounds: the WGSL twin runs the CPU's test, so only the rounding of
/// a driver's contracted arithmetic separates them.
const MIRROR: Bounds = Bounds {
    edge: 1e-5,
    edge_fraction: 1e-3,
    other_tri_fraction: 2e-3,
    same_t: 1e-5,
    t_rel: 1e-5,
    t_floor: 0.0,
    uv_rel: 1e-5,
    uv_floor: 0.1,
    any_edge_fraction: 1e-3,
};

#[test]
fn traverse_matches() {
    let Some(ctx) = common::gpu("traverse_matches") else {
        return;
    };
    let (rs, settings) = mesh_scene();
    let mut r = SplitMix::new(4);
    let cases = traversal_rays(&rs, &mut r, 20_000);
    check_traversal("test_traverse", &ctx, &rs, &settings, &cases, solid, MIRROR);
}

#[test]
fn sampling_matches() {
    let Some(ctx) = common::gpu("sampling_matches") else {
        return;
    };
    let (rs, settings) = cornell();
    let mut r = SplitMix::new(5);
    let special = [0.0, 0.25, 0.5, 0.75, 1.0 - 1.0 / 16_777_216.0, 0.5 + 1e-7];
    let mut cases: Vec<Case> = Vec::new();
    for a in special {
        for bb in special {
            cases.push([[b(a), b(bb), b(a), b(bb)], [0; 4]]);
        }
    }
    while cases.len() < 20_000 {
        let mut u = [r.unit(), r.unit(), r.unit(), r.unit()];
        if r.chance(0.05) {
            u[r.below(4)] = special[r.below(special.len())];
        }
        cases.push([u.map(b), [0; 4]]);
    }
    let out = run(&ctx, &rs, &settings, "test_sampling", &cases);
    let mut errs = [
        Worst::new("sample_concentric_disk (abs)", 1e-5),
        Worst::new("sample_uniform_triangle (abs)", 1e-5),
        Worst::new("sample_cosine_hemisphere x, y (abs)", 1e-5),
        // z = sqrt(1 - x^2 - y^2) amplifies rounding without bound at the disk's rim, where
        // z^2 is tiny; there z^2 is compared: min(|dz|, |d(z^2)|), as |d(z^2)| = |dz| (z + z').
        Worst::new("sample_cosine_hemisphere z (abs, of z or z^2)", 1e-5),
        // The pdf of the GPU's own z, by the Rust function.
        Worst::new("cosine_hemisphere_pdf (abs)", 1e-6),
    ];
    let abs = |a: &[f32], bb: &[f32]| {
        a.iter()
            .zip(bb)
            .map(|(x, y)| rel(*x, *y, 1.0))
            .fold(0.0, f64::max)
    };
    for (c, o) in cases.iter().zip(&out) {
        let u = c[0].map(f);
        let g = [o[0].map(f), o[1].map(f)];
        let d = sample_concentric_disk(Vec2::new(u[0], u[1]));
        let t = sample_uniform_triangle(Vec2::new(u[2], u[3]));
        let h = sample_cosine_hemisphere(Vec2::new(u[0], u[1]));
        let show = || format!("u {u:?}: GPU {g:?}, CPU {d} {t} {h}");
        errs[0].add(abs(&g[0][..2], &d.to_array()), show);
        errs[1].add(abs(&g[0][2..], &t.to_array()), show);
        errs[2].add(abs(&g[1][..2], &h.to_array()[..2]), show);
        let (gz, cz) = (g[1][2] as f64, h.z as f64);
        errs[3].add((gz - cz).abs().min((gz * gz - cz * cz).abs()), show);
        errs[4].add(abs(&g[1][3..], &[cosine_hemisphere_pdf(g[1][2])]), show);
    }
    eprintln!("test_sampling: {} cases", cases.len());
    for e in &errs {
        e.check("test_sampling");
    }
}

#[test]
fn light_pick_matches() {
    let Some(ctx) = common::gpu("light_pick_matches") else {
        return;
    };
    let (rs, settings) = mesh_scene();
    let mut pmfs: Vec<f32> = rs.emitter_cdf.windows(2).map(|w| w[1] - w[0]).collect();
    pmfs.sort_by(f32::total_cmp);
    assert!(
        pmfs[pmfs.len() - 1] > 10.0 * pmfs[0],
        "emitters should differ in power: {pmfs:?}"
    );
    let mut r = SplitMix::new(6);
    let mut us: Vec<f32> = vec![0.0, 1.0 - 1.0 / 16_777_216.0, 0.5];
    // Every bucket boundary exactly, and the floats either side of it.
    for &c in &rs.emitter_cdf {
        us.extend([c, f(b(c) - 1), f(b(c) + 1)].iter().filter(|&&u| u < 1.0));
    }
    while us.len() < 20_000 {
        us.push(r.unit());
    }
    let v = |i: usize| (i as f32 + 0.5) / us.len() as f32;
    let cases: Vec<Case> = (us.iter().enumerate())
        .map(|(i, &u)| [[b(u), b(v(i)), 0, 0], [0; 4]])
        .collect();
    let out = run(&ctx, &rs, &settings, "test_light_pick", &cases);
    let mut fail = Failures::new("test_light_pick");
    let mut ph = Worst::new("power_heuristic (relative)", 1e-6);
    // WGSL's division may be off by 2.5 ulp.
    let mut rescaled = Worst::new("pick_light's rescaled u (abs)", 1e-6);
    let mut picked = vec![0usize; rs.emitters.len()];
    for (i, (&u, o)) in us.iter().zip(&out).enumerate() {
        let pick = pick_light(&rs, Vec2::new(u, v(i)));
        let k = pick.index;
        assert_eq!(
            k,
            sample_cdf(&rs.emitter_cdf, u).0,
            "pick_light picks by the CDF"
        );
        assert!(
            (0.0..1.0).contains(&pick.u.x),
            "u {u}: rescaled to {}",
            pick.u.x
        );
        picked[k] += 1;
        let want_ph = power_heuristic(u, 1.0 - u);
        rescaled.add((pick.u.x - f(o[1][1])).abs() as f64, || {
            format!("u {u}: GPU {}, CPU {}", f(o[1][1]), pick.u.x)
        });
        if o[1][0] != b(pick.pmf) || o[1][2] != b(pick.u.y) {
            fail.add(|| format!("u {u}: GPU pmf and v {:?}, CPU {pick:?}", &o[1][..3]));
        }
        if o[0][0] as usize != k || o[0][1] != rs.emitters[k] {
            fail.add(|| {
                format!(
                    "u {u} ({:#x}): GPU picks {} (triangle {}), CPU {k} (triangle {})",
                    b(u),
                    o[0][0],
                    o[0][1],
                    rs.emitters[k]
                )
            });
        }
        ph.add(rel(want_ph, f(o[0][2]), 0.0), || {
            format!("u {u}: GPU {}, CPU {want_ph}", f(o[0][2]))
        });
    }
    eprintln!(
        "test_light_pick: {} cases over {} emitters, {} picks differ",
        us.len(),
        rs.emitters.len(),
        fail.count
    );
    fail.check(us.len());
    ph.check("test_light_pick");
    rescaled.check("test_light_pick");
    assert!(picked.iter().all(|&n| n > 0), "every emitter is tested");
}

/// A `wo` for material `m`: two-sided kinds mostly see it from above (15% from below, which
/// they must refuse); the dielectric sees both sides equally, grazing ones included.
fn random_wo(r: &mut SplitMix, kind: MaterialKind) -> Vec3 {
    let w = r.unit_vector();
    // Grazing: |wo.z| small (total internal reflection from inside the dielectric).
    let grazing = r.chance(0.1);
    let below = if kind == MaterialKind::DIELECTRIC {
        r.chance(0.5)
    } else {
        r.chance(0.15)
    };
    shape_wo(w, grazing, below)
}

/// The relative tolerance of GGX quantities: 1e-3, plus four float32 rounding errors (half
/// an ulp each) in h.z amplified by the condition number (4e6 at the smallest alpha, 1e-3,
/// where float32 D is only good to ~10%).
fn tolerance(m: &Material, wo: Vec3, wi: Vec3) -> f64 {
    ggx_tolerance(m, wo, wi, 1e-3, f32::EPSILON as f64 / 2.0)
}

#[test]
fn bsdf_sample_matches() {
    let Some(ctx) = common::gpu("bsdf_sample_matches") else {
        return;
    };
    let (rs, settings) = mesh_scene();
    let mats = &rs.materials;
    let tested: Vec<u32> = (0..M_EMITTERS).collect();
    let mut r = SplitMix::new(7);
    let mut cases: Vec<Case> = Vec::new();
    while cases.len() < 24_000 {
        let m = tested[cases.len() % tested.len()];
        let wo = random_wo(&mut r, mats[m as usize].kind);
        let u = [r.unit(), r.unit(), r.unit()];
        cases.push(bsdf_sample_case(m, wo, u));
    }
    let out = run(&ctx, &rs, &settings, "test_bsdf_sample", &cases);
    let mut fail = Failures::new("test_bsdf_sample");
    let mut boundary = Tally::new(
        "validity or lobe differs within 1e-5 of its threshold",
        1e-3,
    );
    // Per material: wi, weight, pdf, and the GPU pdf against the CPU's bsdf_pdf of the GPU wi.
    let mut errs: Vec<[Worst; 4]> = tested
        .iter()
        .map(|_| {
            [
                Worst::new("wi (abs)", 1e-4),
                Worst::new("weight (relative)", 1e-3),
                Worst::new("pdf (relative)", 1e-3),
                Worst::new("pdf vs bsdf_pdf(wo, GPU wi) (relative)", 1e-3),
            ]
        })
        .collect();
    let mut valid = 0;
    // Coverage: two-sided kinds refusing wo.z <= 0, dielectric reflection from outside,
    // refraction both ways, total internal reflection.
    let (mut refused, mut reflected, mut refracted_in, mut refracted_out, mut tir) =
        (0, 0, 0, 0, 0);
    for (c, o) in cases.iter().zip(&out) {
        let m = &mats[c[0][3] as usize];
        let wo = v3(c[0]);
        let u = c[1].map(f);
        let cpu = bsdf_sample(m, wo, u[0], Vec2::new(u[1], u[2]));
        match (m.kind, cpu) {
            (MaterialKind::DIELECTRIC, Some(s)) if s.pdf == 1.0 && wo.z < 0.0 => tir += 1,
            (MaterialKind::DIELECTRIC, Some(s)) if s.wi.z * wo.z > 0.0 => reflected += 1,
            (MaterialKind::DIELECTRIC, Some(_)) if wo.z > 0.0 => refracted_in += 1,
            (MaterialKind::DIELECTRIC, Some(_)) => refracted_out += 1,
            (_, None) if wo.z <= 0.0 => refused += 1,
            _ => {}
        }
        let GpuBsdfSample {
            wi: gwi,
            pdf: gpdf,
            weight: gweight,
            valid: gvalid,
            delta: gdelta,
            lobe: globe,
        } = GpuBsdfSample::from_output(o);
        let show = || {
            format!(
                "{:?} r {} wo {wo} u {u:?}: CPU {cpu:?}; GPU valid {gvalid} delta {gdelta} lobe {globe} wi {gwi} weight {gweight} pdf {gpdf}",
                m.kind, m.roughness
            )
        };
        valid += cpu.is_some() as usize;
        let Some(s) = cpu else {
            if gvalid {
                if m.kind == MaterialKind::ROUGH_CONDUCTOR && gwi.z.abs() < 1e-5 {
                    boundary.add(show);
                } else {
                    fail.add(show);
                }
            }
            continue;
        };
        if !gvalid {
            if m.kind == MaterialKind::ROUGH_CONDUCTOR && s.wi.z.abs() < 1e-5 {
                boundary.add(show);
            } else {
                fail.add(show);
            }
            continue;
        }
        if gdelta != s.delta || globe != s.lobe {
            fail.add(show);
            continue;
        }
        if m.kind == MaterialKind::DIELECTRIC && (gwi.z > 0.0) != (s.wi.z > 0.0) {
            // Reflection on one device, refraction on the other: u_lobe at the Fresnel term.
            let fr = fresnel_dielectric(wo.z, m.ior).0;
            if (u[0] - fr).abs() < 1e-5 {
                boundary.add(show);
            } else {
                fail.add(show);
            }
            continue;
        }
        let e = &mut errs[c[0][3] as usize];
        let tol = tolerance(m, wo, s.wi);
        e[0].add((gwi - s.wi).abs().max_element() as f64, show);
        e[1].add_tol(rel3(s.weight, gweight, 1e-6), tol, show);
        e[2].add_tol(rel(s.pdf, gpdf, 1e-6), tol, show);
        if !s.delta {
            e[3].add_tol(rel(bsdf_pdf(m, wo, gwi), gpdf, 1e-6), tol, show);
        }
    }
    eprintln!(
        "test_bsdf_sample: {} cases over {} materials, {valid} valid samples; {refused} wo below \
         refused; dielectric: {reflected} reflected, {refracted_in} refracted in, \
         {refracted_out} refracted out, {tir} totally reflected inside",
        cases.len(),
        tested.len()
    );
    assert!(refused > 100 && reflected > 100 && refracted_in > 100);
    assert!(refracted_out > 100 && tir > 20);
    fail.check(cases.len());
    boundary.check("test_bsdf_sample", cases.len());
    for (&m, e) in tested.iter().zip(&errs) {
        eprintln!("test_bsdf_sample: {}", material_name(&mats[m as usize]));
        for w in e {
            w.check("test_bsdf_sample");
        }
    }
}

#[test]
fn bsdf_eval_matches() {
    let Some(ctx) = common::gpu("bsdf_eval_matches") else {
        return;
    };
    let (rs, settings) = mesh_scene();
    let mats = &rs.materials;
    let tested: Vec<u32> = (0..M_EMITTERS).collect();
    let mut r = SplitMix::new(8);
    let mut cases: Vec<Case> = Vec::new();
    while cases.len() < 24_000 {
        let m = tested[cases.len() % tested.len()];
        let mat = &mats[m as usize];
        let wo = random_wo(&mut r, mat.kind);
        // Half the directions from the BSDF itself, so that glossy peaks are covered.
        let sampled = bsdf_sample(mat, wo, r.unit(), Vec2::new(r.unit(), r.unit()));
        let wi = match sampled {
            Some(s) if r.chance(0.5) => s.wi,
            _ => {
                let mut wi = r.unit_vector();
                if r.chance(0.8) {
                    wi.z = wi.z.abs();
                }
                wi
            }
        };
        cases.push(bsdf_eval_case(m, wo, wi));
    }
    let out = run(&ctx, &rs, &settings, "test_bsdf_eval", &cases);
    let mut errs: Vec<[Worst; 2]> = tested
        .iter()
        .map(|_| {
            [
                Worst::new("bsdf_eval (relative, abs 1e-6)", 1e-3),
                Worst::new("bsdf_pdf (relative, abs 1e-6)", 1e-3),
            ]
        })
        .collect();
    let mut nonzero = 0;
    for (c, o) in cases.iter().zip(&out) {
        let m = &mats[c[0][3] as usize];
        let (wo, wi) = (v3(c[0]), v3(c[1]));
        let fc = bsdf_eval(m, wo, wi);
        let pdf = bsdf_pdf(m, wo, wi);
        let (gf, gpdf) = bsdf_eval_output(o);
        nonzero += (fc != Vec3::ZERO) as usize;
        let show = || {
            format!(
                "{:?} r {} wo {wo} wi {wi}: CPU f {fc} pdf {pdf}; GPU f {gf} pdf {gpdf}",
                m.kind, m.roughness
            )
        };
        let tol = tolerance(m, wo, wi);
        let e = &mut errs[c[0][3] as usize];
        e[0].add_tol(rel3(fc, gf, 1e-3), tol, show);
        e[1].add_tol(rel(pdf, gpdf, 1e-3), tol, show);
    }
    eprintln!(
        "test_bsdf_eval: {} cases, {nonzero} with nonzero f",
        cases.len()
    );
    for (&m, e) in tested.iter().zip(&errs) {
        eprintln!("test_bsdf_eval: {}", material_name(&mats[m as usize]));
        for w in e {
            w.check("test_bsdf_eval");
        }
    }
}

#[test]
fn camera_ray_matches() {
    let Some(ctx) = common::gpu("camera_ray_matches") else {
        return;
    };
    let (mut rs, _) = cornell();
    let settings = RenderSettings {
        width: 320,
        height: 200,
        spp: 1,
        max_depth: 8,
        seed: 77,
        ..RenderSettings::default()
    };
    let pinhole = Camera::new(
        Vec3::new(0.3, 0.2, 3.9),
        Vec3::new(0.0, -0.1, 0.0),
        Vec3::Y,
        39.3,
        0.0,
        None,
    )
    .unwrap();
    let lens = Camera::new(
        Vec3::new(-1.0, 0.5, 4.5),
        Vec3::ZERO,
        Vec3::new(0.1, 1.0, 0.0),
        60.0,
        0.25,
        Some(3.0),
    )
    .unwrap();
    let ortho = Camera::new(
        Vec3::new(0.5, 2.0, 3.0),
        Vec3::new(0.0, 0.0, -1.0),
        Vec3::Y,
        40.0,
        0.0,
        None,
    )
    .unwrap()
    .orthographic(2.5);
    for (name, cam) in [
        ("pinhole", pinhole),
        ("thin lens", lens),
        ("orthographic", ortho),
    ] {
        rs.camera = cam.clone();
        let mut r = SplitMix::new(9);
        let mut cases: Vec<Case> = Vec::new();
        for (x, y) in [(0, 0), (319, 199), (0, 199), (319, 0)] {
            cases.push([[x, y, 0, 0], [0; 4]]);
        }
        while cases.len() < 12_000 {
            let (x, y) = (r.below(320) as u32, r.below(200) as u32);
            cases.push([[x, y, r.u32() % 4096, 0], [0; 4]]);
        }
        let out = run(&ctx, &rs, &settings, "test_camera_ray", &cases);
        let mut origin_err = Worst::new("origin (abs)", 1e-5);
        let mut dir_err = Worst::new("dir (abs)", 1e-5);
        for (c, o) in cases.iter().zip(&out) {
            let [x, y, sample, _] = c[0];
            let rng = Rng::new(y * settings.width + x, sample, settings.seed);
            let cam = CameraRays::new(&cam, settings.width, settings.height);
            let ray = generate_camera_ray(&cam, x, y, &rng);
            let show = || {
                format!(
                    "{name} ({x}, {y}) sample {sample}: CPU {ray:?}, GPU {:?} {:?}",
                    v3(o[0]),
                    v3(o[1])
                )
            };
            origin_err.add((v3(o[0]) - ray.origin).abs().max_element() as f64, show);
            dir_err.add((v3(o[1]) - ray.dir).abs().max_element() as f64, show);
        }
        eprintln!("test_camera_ray ({name}): {} cases", cases.len());
        origin_err.check("test_camera_ray");
        dir_err.check("test_camera_ray");
    }
}

/// Replays (pixel, sample) paths on both devices; returns the fraction whose radiance and
/// splats agree (relative 1e-3 per channel, plus abs 1e-4, and the splats' pixels) and the
/// fraction with equal ray counts.
fn replay_paths(
    ctx: &GpuContext,
    name: &str,
    rs: &RenderScene,
    settings: &RenderSettings,
    n: usize,
    seed: u64,
) -> (f64, f64) {
    let mut r = SplitMix::new(seed);
    let cases: Vec<Case> = (0..n)
        .map(|_| {
            let (x, y) = (
                r.below(settings.width as usize) as u32,
                r.below(settings.height as usize) as u32,
            );
            [[x, y, r.u32() % 1024, 0], [0; 4]]
        })
        .collect();
    let out = run(ctx, rs, settings, "test_trace_path", &cases);
    let start = Instant::now();
    let mut radiance_ok = 0;
    let mut rays_ok = 0;
    let mut nonzero = 0;
    let mut examples = Vec::new();
    let mut max_rays = 0;
    let mut splats = 0;
    for (c, o) in cases.iter().zip(&out) {
        let [x, y, sample, _] = c[0];
        let rng = Rng::new(y * settings.width + x, sample, settings.seed);
        let cam = CameraRays::new(&rs.camera, settings.width, settings.height);
        let ray = generate_camera_ray(&cam, x, y, &rng);
        // The light subpaths' splats: their values summed, and the sum of their pixels.
        let (mut splat, mut pixels) = (Vec3::ZERO, 0u32);
        let ps = trace_path(
            rs,
            &cam,
            ray,
            &rng,
            settings.max_depth,
            settings.bounces.budget(),
            settings.branches(!rs.caustic_targets.is_empty()),
            &mut |pixel, value| {
                splat += value;
                pixels = pixels.wrapping_add(pixel);
            },
        );
        let (l, rays) = (ps.radiance, ps.rays);
        let (gl, grays) = (v3(o[0]), o[0][3] as f32);
        let near = |a: Vec3, b: Vec3| {
            (0..3).all(|i| (a[i] - b[i]).abs() <= 1e-3 * a[i].abs().max(b[i].abs()) + 1e-4)
        };
        let gpu_pixels = o[1][3];
        splats += (splat != Vec3::ZERO) as usize;
        let close = near(l, gl) && near(splat, v3(o[1])) && pixels == gpu_pixels;
        radiance_ok += close as usize;
        rays_ok += (grays == rays as f32) as usize;
        nonzero += (l != Vec3::ZERO) as usize;
        max_rays = max_rays.max(rays);
        if (!close || grays != rays as f32) && examples.len() < 3 {
            examples.push(format!(
                "({x}, {y}) sample {sample}: CPU {l} {rays} rays, GPU {gl} {grays} rays"
            ));
        }
    }
    let (a, rr) = (radiance_ok as f64 / n as f64, rays_ok as f64 / n as f64);
    eprintln!(
        "test_trace_path ({name}): {n} paths ({nonzero} nonzero, {splats} with splats, up to {max_rays} rays; CPU {:.2} s): radiance and splats agree on {:.3}%, ray counts on {:.3}%",
        start.elapsed().as_secs_f64(),
        100.0 * a,
        100.0 * rr
    );
    for e in &examples {
        eprintln!("  differs: {e}");
    }
    assert!(nonzero > n / 2, "{name}: most paths should carry light");
    (a, rr)
}

#[test]
fn trace_path_matches_on_cornell() {
    let Some(ctx) = common::gpu("trace_path_matches_on_cornell") else {
        return;
    };
    let (rs, settings) = cornell();
    let (radiance, rays) = replay_paths(&ctx, "cornell", &rs, &settings, 10_000, 10);
    assert!(radiance >= 0.99, "radiance agrees on only {radiance}");
    assert!(rays >= 0.99, "ray counts agree on only {rays}");
}

#[test]
fn trace_path_matches_on_mesh_scene() {
    let Some(ctx) = common::gpu("trace_path_matches_on_mesh_scene") else {
        return;
    };
    // Glass, metals, smooth normals, many emitters and a gradient sky.
    let (rs, settings) = mesh_scene();
    let (radiance, rays) = replay_paths(&ctx, "mesh", &rs, &settings, 10_000, 11);
    assert!(radiance >= 0.99, "radiance agrees on only {radiance}");
    assert!(rays >= 0.99, "ray counts agree on only {rays}");
}

/// The box of tests/scenes/box_area.toml (an area light, glass and mirror spheres) with
/// caustic light subpaths.
const CAUSTICS_SCENE: &str = "tests/scenes/box_area.toml";
/// tests/scenes/lights.toml: light subpaths of an area light and of point, spot and
/// directional lights, through a glass sphere.
const PUNCTUAL_CAUSTICS_SCENE: &str = "tests/scenes/lights.toml";
/// tests/scenes/rect_lights.toml: rectangle lights and a sun without shadows.
const RECT_LIGHTS_SCENE: &str = "tests/scenes/rect_lights.toml";

/// Test scene `file` with caustic light subpaths.
fn caustics_scene(file: &str) -> (RenderScene, RenderSettings) {
    let mut scene = load_scene(&common::fs::root().join(file)).unwrap();
    scene.settings.caustics = true;
    let rs = RenderScene::new(&scene, &BuildParams::default()).expect("BVH");
    assert!(!rs.caustic_targets.is_empty());
    (rs, scene.settings)
}

fn trace_path_check(ctx: &GpuContext, file: &str) {
    let (rs, settings) = caustics_scene(file);
    let (radiance, rays) = replay_paths(ctx, file, &rs, &settings, 10_000, 12);
    assert!(
        radiance >= 0.99,
        "{file}: radiance and splats agree on only {radiance}"
    );
    assert!(rays >= 0.99, "{file}: ray counts agree on only {rays}");
}

#[test]
fn trace_path_matches_with_caustics() {
    let Some(ctx) = common::gpu("trace_path_matches_with_caustics") else {
        return;
    };
    trace_path_check(&ctx, CAUSTICS_SCENE);
}

#[test]
fn trace_path_matches_with_caustics_of_punctual_lights() {
    let Some(ctx) = common::gpu("trace_path_matches_with_caustics_of_punctual_lights") else {
        return;
    };
    trace_path_check(&ctx, PUNCTUAL_CAUSTICS_SCENE);
}

#[test]
fn trace_path_matches_with_rect_lights() {
    let Some(ctx) = common::gpu("trace_path_matches_with_rect_lights") else {
        return;
    };
    trace_path_check(&ctx, RECT_LIGHTS_SCENE);
}

#[test]
fn light_subpath_matches_for_rect_lights() {
    let Some(ctx) = common::gpu("light_subpath_matches_for_rect_lights") else {
        return;
    };
    light_subpath_check(&ctx, RECT_LIGHTS_SCENE);
}

#[test]
fn light_subpath_matches() {
    let Some(ctx) = common::gpu("light_subpath_matches") else {
        return;
    };
    light_subpath_check(&ctx, CAUSTICS_SCENE);
}

#[test]
fn light_subpath_matches_for_punctual_lights() {
    let Some(ctx) = common::gpu("light_subpath_matches_for_punctual_lights") else {
        return;
    };
    light_subpath_check(&ctx, PUNCTUAL_CAUSTICS_SCENE);
}

/// `start_light` (the light subpath and its links to the camera) against its Rust twin
/// over 20,000 camera samples of scene `file`: the vertices' count, segments, first
/// position and throughput, and the rays traced.
fn light_subpath_check(ctx: &GpuContext, file: &str) {
    let (rs, settings) = caustics_scene(file);
    let mut r = SplitMix::new(13);
    let cases: Vec<Case> = (0..20_000)
        .map(|_| {
            let (x, y) = (
                r.below(settings.width as usize) as u32,
                r.below(settings.height as usize) as u32,
            );
            [[x, y, r.u32() % 4096, 0], [0; 4]]
        })
        .collect();
    let out = run(ctx, &rs, &settings, "test_light_subpath", &cases);
    let cam = CameraRays::new(&rs.camera, settings.width, settings.height);
    let mut counts = Tally::new("vertex count, rays and segments differ", 0.01);
    // The rect scene's 60 × 60 light starts subpaths up to 42 units from the first vertex,
    // where single precision's rounding of the ray comes to about 1e-4.
    let mut position = Worst::new("first vertex position (abs)", 2e-4);
    // A fraction, not a maximum: a spot's falloff is linear in the angle from its axis, an
    // acos that the two devices round apart, which near the cutoff (where the falloff nears
    // 0) is a relative error of the throughput above 1e-3 (7 of 2172 vertices of the
    // punctual scene, all under its spot; none of the area light's).
    let mut throughput = Tally::new(
        "first vertex throughput luminance off by > 1e-3 (rel)",
        0.01,
    );
    let mut traced = 0;
    for (c, o) in cases.iter().zip(&out) {
        let [x, y, sample, _] = c[0];
        let rng = Rng::new(y * settings.width + x, sample, settings.seed);
        let ls = start_light(&rs, &cam, &rng, settings.max_depth);
        let v = &ls.light.vertices[0];
        let cpu = [
            ls.light.count,
            ls.rays,
            v.segments,
            ls.light.vertices[1].segments,
        ];
        let show = || format!("({x}, {y}) sample {sample}: CPU {cpu:?}, GPU {:?}", o[0]);
        if cpu != o[0] {
            counts.add(show);
        }
        traced += (ls.light.count > 0) as usize;
        if ls.light.count > 0 && cpu == o[0] {
            position.add((v3(o[1]) - v.si.p).abs().max_element() as f64, show);
            let lum = v.beta.dot(Vec3::new(0.2126, 0.7152, 0.0722));
            if rel(lum, f(o[1][3]), 1e-6) > 1e-3 {
                throughput.add(show);
            }
        }
    }
    eprintln!(
        "test_light_subpath: {} cases, {traced} with a light vertex",
        cases.len()
    );
    assert!(traced > 500, "too few light subpaths to test: {traced}");
    counts.check("test_light_subpath", cases.len());
    position.check("test_light_subpath");
    throughput.check("test_light_subpath", traced);
}

/// `sample_target`, `target_pdf` and `target_cone` against their Rust twins over 20,000
/// random points (inside and outside the targets) and numbers.
#[test]
fn caustic_targets_match() {
    let Some(ctx) = common::gpu("caustic_targets_match") else {
        return;
    };
    let (rs, settings) = caustics_scene(CAUSTICS_SCENE);
    let mut r = SplitMix::new(14);
    let cases: Vec<Case> = (0..20_000)
        .map(|_| {
            let p = r.vec3(-1.6, 2.2);
            let d = r.vec3(-1.0, 1.0);
            let u = [r.range(0.0, 1.0), r.range(0.0, 1.0)];
            [word(p, b(d.z)), [b(u[0]), b(u[1]), b(d.x), b(d.y)]]
        })
        .collect();
    let out = run(&ctx, &rs, &settings, "test_caustic_targets", &cases);
    let mut dir = Worst::new("sample_target direction (abs)", 1e-5);
    let mut pdf = Worst::new("sample_target and target_pdf pdfs (rel)", 1e-4);
    let mut cone = Worst::new("target_cone cos_max and height (abs)", 1e-6);
    for (c, o) in cases.iter().zip(&out) {
        let p = v3(c[0]);
        let u = Vec2::new(f(c[1][0]), f(c[1][1]));
        let d = Vec3::new(f(c[1][2]), f(c[1][3]), f(c[0][3])).normalize();
        let (sd, spdf) = sample_target(&rs, p, u);
        let tc = target_cone(&rs.caustic_targets[0], p);
        let show = || format!("p {p}, u {u}, d {d}: CPU {sd} {spdf}, GPU {:?}", o[0]);
        dir.add((v3(o[0]) - sd).abs().max_element() as f64, show);
        pdf.add(rel(spdf, f(o[0][3]), 1e-6), show);
        pdf.add(rel(target_pdf(&rs, p, d), f(o[1][0]), 1e-6), show);
        cone.add(
            ((tc.cos_max - f(o[1][1])).abs()).max((tc.height - f(o[1][2])).abs()) as f64,
            show,
        );
    }
    eprintln!("test_caustic_targets: {} cases", cases.len());
    dir.check("test_caustic_targets");
    pdf.check("test_caustic_targets");
    cone.check("test_caustic_targets");
}

/// `texture_lookup` and `material_at` against their Rust twins over 12,000 random texture
/// coordinates (far outside [0, 1] too, so wrapping is exercised), on an sRGB PNG, a linear
/// PNG read as roughness and an EXR emission, each with its own UV scale, and on textures
/// that clamp or mirror along u or v.
#[test]
fn texture_lookup_matches() {
    let Some(ctx) = common::gpu("texture_lookup_matches") else {
        return;
    };
    let dir = common::fs::TempDir::new("texture-units");
    let mut r = SplitMix::new(0x7e47_0002);
    let ldr = |r: &mut SplitMix, n: usize| -> Vec<[u8; 4]> {
        (0..n)
            .map(|_| [0; 4].map(|_| (r.u32() >> 24) as u8))
            .collect()
    };
    dir.write_png("albedo.png", 7, 5, &ldr(&mut r, 35));
    dir.write_png("rough.png", 3, 9, &ldr(&mut r, 27));
    let hdr: Vec<[f32; 4]> = (0..16)
        .map(|_| [r.range(0.0, 5.0), r.range(0.0, 5.0), r.range(0.0, 5.0), 1.0])
        .collect();
    dir.write_exr("light.exr", 4, 4, &hdr);
    dir.write(
        "quad.obj",
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nf 1/1 2/2 3/3\n",
    );
    let toml = "[camera]\nposition = [0.0, 0.0, 3.0]\nlook_at = [0.0, 0.0, 0.0]\n\
        [materials.a]\ntype = \"diffuse\"\nalbedo = { texture = \"albedo.png\", scale = [2.0, 3.5] }\n\
        [materials.b]\ntype = \"rough_conductor\"\nalbedo = [0.9, 0.8, 0.7]\n\
        roughness = { texture = \"rough.png\", scale = [-1.0, 0.75] }\n\
        [materials.c]\ntype = \"diffuse\"\nemission = { texture = \"light.exr\", strength = 3.0 }\n\
        [materials.d]\ntype = \"diffuse\"\n\
        albedo = { texture = \"albedo.png\", scale = [1.5, -2.0], wrap = [\"mirror\", \"clamp\"] }\n\
        [materials.e]\ntype = \"diffuse\"\nalbedo = { texture = \"rough.png\", wrap = [\"clamp\", \"mirror\"] }\n\
        [[objects]]\nmesh = \"quad.obj\"\nmaterial = \"a\"\n\
        [[objects]]\nmesh = \"quad.obj\"\nmaterial = \"b\"\n\
        [[objects]]\nmesh = \"quad.obj\"\nmaterial = \"c\"\n\
        [[objects]]\nmesh = \"quad.obj\"\nmaterial = \"d\"\n\
        [[objects]]\nmesh = \"quad.obj\"\nmaterial = \"e\"\n";
    let scene = meshtrace::scene::load_scene(&dir.write("scene.toml", toml)).unwrap();
    let rs = RenderScene::new(&scene, &BuildParams::default()).unwrap();
    // Five textures, and copies of the two that clamp or mirror along v shifted for the
    // OBJ's texture coordinates, with their materials.
    assert_eq!(rs.textures.len(), 7);
    let (textures, materials) = (rs.textures.len(), rs.materials.len());
    let settings = scene.settings;
    let mut cases = Vec::new();
    while cases.len() < 12_000 {
        let uv = Vec2::new(r.range(-20.0, 20.0), r.range(-20.0, 20.0));
        let (t, m) = (r.below(textures) as u32, r.below(materials) as u32);
        cases.push([[b(uv.x), b(uv.y), t, m], [0; 4]]);
    }
    let out = run(&ctx, &rs, &settings, "test_texture", &cases);
    let mut lookup = Worst::new("texture_lookup (relative, floor 1e-3)", 1e-4);
    let mut material = Worst::new("material_at albedo, roughness (relative)", 1e-4);
    for (c, o) in cases.iter().zip(&out) {
        let [u, v, t, m] = c[0];
        let uv = Vec2::new(f(u), f(v));
        let cpu = texture_lookup(&rs, t, uv);
        let gpu = glam::Vec4::new(f(o[0][0]), f(o[0][1]), f(o[0][2]), f(o[0][3]));
        let show = || format!("texture {t} at {uv}: CPU {cpu}, GPU {gpu}");
        lookup.add(
            (0..4)
                .map(|k| rel(cpu[k], gpu[k], 1e-3))
                .fold(0.0, f64::max),
            show,
        );
        let both = glam::Vec4::new(uv.x, uv.y, uv.x, uv.y);
        let cm = material_at(&rs, &rs.materials[m as usize], both, glam::Vec4::ONE);
        let (ga, gr) = (v3(o[1]), f(o[1][3]));
        let show = || format!("material {m} at {uv}: CPU {cm:?}, GPU {ga} {gr}");
        material.add(
            rel3(cm.albedo, ga, 1e-3).max(rel(cm.roughness, gr, 1e-3)),
            show,
        );
    }
    lookup.check("test_texture");
    material.check("test_texture");
}

#[test]
fn surface_maps_match() {
    let Some(ctx) = common::gpu("surface_maps_match") else {
        return;
    };
    let dir = common::fs::TempDir::new("surface-map-units");
    let mut r = SplitMix::new(0x7e47_0003);
    let ldr = |r: &mut SplitMix, n: usize| -> Vec<[u8; 4]> {
        (0..n)
            .map(|_| [0; 4].map(|_| (r.u32() >> 24) as u8))
            .collect()
    };
    dir.write_png("base.png", 5, 6, &ldr(&mut r, 30));
    dir.write_png("normal.png", 7, 3, &ldr(&mut r, 21));
    dir.write_png("metal.png", 4, 4, &ldr(&mut r, 16));
    dir.write_png("glass.png", 3, 5, &ldr(&mut r, 15));
    // A curved patch with vertex normals and texture coordinates, some of them mirrored:
    // MikkTSpace gives its tangents.
    let mut obj = String::new();
    for j in 0..4 {
        for i in 0..4 {
            let (x, y) = (i as f32 / 3.0, j as f32 / 3.0);
            let z = 0.3 * (2.0 * x).sin() * (1.5 * y).cos();
            obj += &format!(
                "v {x} {y} {z}\nvn {} {} 1\nvt {} {}\n",
                -0.6 * x,
                0.4 * y,
                if i % 2 == 0 { x } else { 1.0 - x },
                y
            );
        }
    }
    for j in 0..3 {
        for i in 0..3 {
            let k = 1 + i + 4 * j;
            let [a, b, c, d] = [k, k + 1, k + 5, k + 4];
            obj += &format!("f {a}/{a}/{a} {b}/{b}/{b} {c}/{c}/{c} {d}/{d}/{d}\n");
        }
    }
    dir.write("patch.obj", obj);
    let toml = "[camera]\nposition = [0.0, 0.0, 3.0]\nlook_at = [0.0, 0.0, 0.0]\n\
        [materials.a]\ntype = \"pbr\"\nbase_color = { texture = \"base.png\", scale = [1.5, 2.0] }\n\
        metallic = { texture = \"metal.png\" }\ntransmission = { texture = \"glass.png\", scale = [3.0, 1.0] }\n\
        normal_map = { texture = \"normal.png\", scale = [2.0, -1.0], strength = 0.7 }\n\
        alpha = 0.9\nalpha_cutoff = 0.45\n\
        [materials.b]\ntype = \"diffuse\"\nalbedo = [0.5, 0.5, 0.5]\n\
        normal_map = { texture = \"normal.png\" }\n\
        [[objects]]\nmesh = \"patch.obj\"\nmaterial = \"a\"\n\
        [[objects]]\nmesh = \"patch.obj\"\nmaterial = \"b\"\ntranslate = [2.0, 0.0, 0.0]\n";
    let scene = meshtrace::scene::load_scene(&dir.write("scene.toml", toml)).unwrap();
    let rs = RenderScene::new(&scene, &BuildParams::default()).unwrap();
    let tris = rs.tris.len() as u32;
    assert!(rs.shading.iter().all(|s| s.flags & TRI_TANGENT != 0));
    let settings = scene.settings;
    let mut cases = Vec::new();
    while cases.len() < 12_000 {
        let tri = r.below(tris as usize) as u32;
        let (b1, b2) = (r.range(0.0, 1.0), r.range(0.0, 1.0));
        let (b1, b2) = if b1 + b2 > 1.0 {
            (1.0 - b1, 1.0 - b2)
        } else {
            (b1, b2)
        };
        let ng = meshtrace::geometry::geometric_normal(&rs.tris[tri as usize]);
        let n = (ng + Vec3::new(r.range(-0.5, 0.5), r.range(-0.5, 0.5), r.range(-0.5, 0.5)))
            .normalize();
        cases.push([[tri, b(b1), b(b2), 0], [b(n.x), b(n.y), b(n.z), 0]]);
    }
    let out = run(&ctx, &rs, &settings, "test_surface_maps", &cases);
    let mut normal = Worst::new("normal_mapped (relative, floor 1e-3)", 1e-4);
    // Texels decode alike, but bilinear weights may differ in the last bit: a case whose
    // alpha lies within rounding of the cut-off may go either way.
    let mut alpha = Tally::new("alpha_test disagrees", 1e-3);
    let mut factors = Worst::new("material_at metallic, transmission (relative)", 1e-4);
    for (c, o) in cases.iter().zip(&out) {
        let [tri, b1, b2, _] = c[0];
        let (b1, b2) = (f(b1), f(b2));
        let n = v3(c[1]);
        let uv = triangle_uv(&rs, tri, b1, b2);
        let ng = meshtrace::geometry::geometric_normal(&rs.tris[tri as usize]);
        let m = &rs.materials[rs.shading[tri as usize].material as usize];
        let hit = meshtrace::bvh::Hit {
            t: 0.0,
            u: b1,
            v: b2,
            tri,
        };
        let cpu = normal_mapped(&rs, &hit, uv, n, ng, m.normal_texture, m.normal_scale);
        let gpu = v3(o[0]);
        normal.add(rel3(cpu, gpu, 1e-3), || {
            format!("triangle {tri} at ({b1}, {b2}), n {n}: CPU {cpu}, GPU {gpu}")
        });
        let passes = alpha_test(&rs, tri, b1, b2, false);
        if passes != (o[0][3] == 1) {
            alpha.add(|| {
                format!(
                    "triangle {tri} at ({b1}, {b2}): CPU {passes}, GPU {}",
                    o[0][3]
                )
            });
        }
        let m = material_at(
            &rs,
            &rs.materials[rs.shading[tri as usize].material as usize],
            uv,
            triangle_color(&rs, tri, b1, b2),
        );
        let (gm, gt) = (f(o[1][0]), f(o[1][1]));
        factors.add(
            rel(m.metallic, gm, 1e-3).max(rel(m.transmission, gt, 1e-3)),
            || {
                format!(
                    "triangle {tri} at {uv}: CPU {} {}, GPU {gm} {gt}",
                    m.metallic, m.transmission
                )
            },
        );
    }
    normal.check("test_surface_maps");
    alpha.check("test_surface_maps", cases.len());
    factors.check("test_surface_maps");
}

/// `triangle_uv`, `triangle_color`, `material_at` and `alpha_test` on a glTF triangle pair
/// with COLOR_0 (alpha below and above the cut-off) and a base colour texture on
/// TEXCOORD_1, against their Rust twins at 12,000 random barycentric points.
#[test]
fn vertex_colors_and_second_set_match() {
    let Some(ctx) = common::gpu("vertex_colors_and_second_set_match") else {
        return;
    };
    use common::gltf::Asset;
    use serde_json::json;
    let mut r = SplitMix::new(0x7e47_0009);
    let mut a = Asset::new();
    let texels: Vec<[u8; 4]> = (0..20)
        .map(|_| [0; 4].map(|_| (r.u32() >> 24) as u8))
        .collect();
    let image = a.view(&common::gltf::png(4, 5, &texels), None);
    a.push(
        "images",
        json!({ "bufferView": image, "mimeType": "image/png" }),
    );
    a.push("textures", json!({ "source": 0 }));
    let p = a.positions(&[
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
    ]);
    let t0 = a.floats(&[0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 1.0], "VEC2");
    let t1 = a.floats(&[0.3, -0.7, 2.1, 0.4, 1.2, 1.9, -0.5, 0.8], "VEC2");
    let c = a.floats(
        &[
            1.0, 0.2, 0.1, 0.2, 0.1, 0.9, 0.3, 0.9, 0.5, 0.5, 0.5, 0.6, 0.9, 0.9, 0.2, 1.0,
        ],
        "VEC4",
    );
    let i = a.indices(&[0, 1, 2, 0, 2, 3]);
    a.mesh(
        json!({ "attributes": { "POSITION": p, "TEXCOORD_0": t0, "TEXCOORD_1": t1,
        "COLOR_0": c }, "indices": i, "material": 0 }),
    );
    let node = a.node(json!({ "mesh": 0 }));
    a.scene(&[node]);
    a.json["materials"] = json!([{ "alphaMode": "MASK", "alphaCutoff": 0.4,
        "pbrMetallicRoughness": { "baseColorFactor": [0.9, 0.7, 0.5, 0.8],
            "baseColorTexture": { "index": 0, "texCoord": 1 } } }]);
    let dir = common::fs::TempDir::new("colour-units");
    let scene = meshtrace::scene::load_scene(&dir.write("a.gltf", a.embedded())).unwrap();
    let rs = RenderScene::new(&scene, &BuildParams::default()).unwrap();
    let tris = rs.tris.len();
    let mut cases = Vec::new();
    while cases.len() < 12_000 {
        let tri = r.below(tris) as u32;
        let (b1, b2) = (r.range(0.0, 1.0), r.range(0.0, 1.0));
        let (b1, b2) = if b1 + b2 > 1.0 {
            (1.0 - b1, 1.0 - b2)
        } else {
            (b1, b2)
        };
        cases.push([[tri, b(b1), b(b2), 0], [0; 4]]);
    }
    let out = run(&ctx, &rs, &scene.settings, "test_surface_colors", &cases);
    let mut albedo = Worst::new("material_at albedo with colour (relative)", 1e-4);
    let mut uvs = Worst::new("triangle_uv (relative, floor 1e-3)", 1e-5);
    let mut alpha = Tally::new("alpha_test disagrees", 1e-3);
    let mut masked = 0;
    for (c, o) in cases.iter().zip(&out) {
        let [tri, b1, b2, _] = c[0];
        let (b1, b2) = (f(b1), f(b2));
        let uv = triangle_uv(&rs, tri, b1, b2);
        let m = material_at(
            &rs,
            &rs.materials[rs.shading[tri as usize].material as usize],
            uv,
            triangle_color(&rs, tri, b1, b2),
        );
        let ga = v3(o[0]);
        albedo.add(rel3(m.albedo, ga, 1e-3), || {
            format!("triangle {tri} at ({b1}, {b2}): CPU {}, GPU {ga}", m.albedo)
        });
        let gu = glam::Vec4::new(f(o[1][0]), f(o[1][1]), f(o[1][2]), f(o[1][3]));
        uvs.add(
            (0..4).map(|k| rel(uv[k], gu[k], 1e-3)).fold(0.0, f64::max),
            || format!("triangle {tri} at ({b1}, {b2}): CPU {uv}, GPU {gu}"),
        );
        let passes = alpha_test(&rs, tri, b1, b2, false);
        masked += usize::from(!passes);
        if passes != (o[0][3] == 1) {
            alpha.add(|| {
                format!(
                    "triangle {tri} at ({b1}, {b2}): CPU {passes}, GPU {}",
                    o[0][3]
                )
            });
        }
    }
    eprintln!(
        "test_surface_colors: {} cases, {masked} masked out",
        cases.len()
    );
    assert!(
        masked > 100 && masked < cases.len() - 100,
        "{masked} masked out"
    );
    albedo.check("test_surface_colors");
    uvs.check("test_surface_colors");
    alpha.check("test_surface_colors", cases.len());
}

/// `env_radiance`, `env_pdf` and `sample_env` against their Rust twins on an environment
/// map with a sun 10⁴ times brighter than its sky, turned by 35 degrees: 12,000 random
/// directions and uniform pairs. A direction within float rounding of a cell boundary may
/// land in the neighbouring cell on one side, so the densities may differ on a few cases.
#[test]
fn environment_matches() {
    let Some(ctx) = common::gpu("environment_matches") else {
        return;
    };
    let dir = common::fs::TempDir::new("env-units");
    let mut r = SplitMix::new(0xe4_0001);
    let (w, h) = (24u32, 12u32);
    let texels: Vec<[f32; 4]> = (0..w * h)
        .map(|k| {
            let sun = if k == 3 * w + 17 { 1e4 } else { 1.0 };
            [0; 4].map(|_| sun * r.range(0.05, 1.0))
        })
        .collect();
    dir.write_exr("env.exr", w, h, &texels);
    let toml = "[camera]\nposition = [0.0, 0.0, 3.0]\nlook_at = [0.0, 0.0, 0.0]\n\
        [sky]\nenvironment = \"env.exr\"\nrotate = 35.0\nstrength = 0.7\n";
    let scene = meshtrace::scene::load_scene(&dir.write("scene.toml", toml)).unwrap();
    let rs = RenderScene::new(&scene, &BuildParams::default()).unwrap();
    let settings = scene.settings;
    let mut cases = Vec::new();
    while cases.len() < 12_000 {
        let d = Vec3::new(r.range(-1.0, 1.0), r.range(-1.0, 1.0), r.range(-1.0, 1.0));
        if !(0.01..=1.0).contains(&d.length_squared()) {
            continue;
        }
        let u = Vec2::new(r.range(0.0, 1.0), r.range(0.0, 1.0));
        cases.push([word(d.normalize(), 0), word(u.extend(0.0), 0)]);
    }
    let out = run(&ctx, &rs, &settings, "test_environment", &cases);
    // Near the sun a rounding of the texture coordinates moves the radiance by up to 10⁴
    // times that rounding: rare cases differ by up to 1%.
    let mut radiance = Worst::new("env_radiance (relative, floor 1e-3)", 1e-2);
    let mut radiance_close = Tally::new("env_radiance differing by more than 1e-4", 0.005);
    let mut pdf = Tally::new("env_pdf differing by more than 1e-4", 0.002);
    let mut sample = Worst::new("sample_env direction", 1e-4);
    let mut sample_pdf = Worst::new("sample_env pdf (relative)", 1e-4);
    for (c, o) in cases.iter().zip(&out) {
        let d = v3(c[0]);
        let u = v3(c[1]).truncate();
        let l = env_radiance(&rs, d);
        let p = env_pdf(&rs, d);
        let (sd, sp) = sample_env(&rs, u);
        let show = || format!("{d}: CPU {l} {p}, GPU {} {}", v3(o[0]), f(o[0][3]));
        radiance.add(rel3(l, v3(o[0]), 1e-3), show);
        if rel3(l, v3(o[0]), 1e-3) > 1e-4 {
            radiance_close.add(show);
        }
        if rel(p, f(o[0][3]), 1e-3) > 1e-4 {
            pdf.add(show);
        }
        let show = || format!("u {u}: CPU {sd} {sp}, GPU {} {}", v3(o[1]), f(o[1][3]));
        sample.add((sd - v3(o[1])).abs().max_element() as f64, show);
        sample_pdf.add(rel(sp, f(o[1][3]), 1e-3), show);
    }
    radiance.check("test_environment");
    radiance_close.check("test_environment", cases.len());
    pdf.check("test_environment", cases.len());
    sample.check("test_environment");
    sample_pdf.check("test_environment");
}

/// `first_hit` (the AOVs' camera hit) against its Rust twin on every pixel-centre ray of
/// the Cornell box.
#[test]
fn first_hit_matches() {
    let Some(ctx) = common::gpu("first_hit_matches") else {
        return;
    };
    // The glTF-free scene with several objects and materials: the Cornell box.
    let (rs, _) = cornell();
    let settings = RenderSettings {
        width: 160,
        height: 100,
        spp: 1,
        max_depth: 8,
        seed: 0,
        ..RenderSettings::default()
    };
    let cases: Vec<Case> = (0..settings.height)
        .flat_map(|y| (0..settings.width).map(move |x| [[x, y, 0, 0], [0; 4]]))
        .collect();
    let out = run(&ctx, &rs, &settings, "test_first_hit", &cases);
    let cam = CameraRays::new(&rs.camera, settings.width, settings.height);
    let mut differ = Tally::new("hit, ids or cost differ (rays through edges)", 5e-3);
    let mut normal_err = Worst::new("normal (abs)", 1e-5);
    let mut depth_err = Worst::new("depth (relative)", 1e-5);
    let mut hits = 0;
    for (c, o) in cases.iter().zip(&out) {
        let [x, y, _, _] = c[0];
        let fh = first_hit(&rs, &pixel_centre_ray(&cam, x, y));
        let show = || format!("({x}, {y}): CPU {fh:?}, GPU {o:?}");
        let cpu = [fh.hit as u32, fh.cost, fh.material, fh.object];
        if cpu != o[0] {
            differ.add(show);
            continue;
        }
        if !fh.hit {
            continue;
        }
        hits += 1;
        normal_err.add((v3(o[1]) - fh.normal).abs().max_element() as f64, show);
        let depth = (fh.p - cam.position).dot(cam.forward);
        depth_err.add(rel(depth, f(o[1][3]), 0.0), show);
    }
    eprintln!("test_first_hit: {} cases, {hits} hits", cases.len());
    differ.check("test_first_hit", cases.len());
    normal_err.check("test_first_hit");
    depth_err.check("test_first_hit");
    assert!(hits > cases.len() / 2, "{hits}");
}

/// The colours `first_hit` reads for the AOVs, the albedo and the diffuse colour (the
/// `pbr` material's layers dim it), against their Rust twins on every pixel-centre ray of
/// the corpus's five spheres of glTF materials (a clear coat, sheen, unlit and bare bases).
#[test]
fn first_hit_colours_match() {
    let Some(ctx) = common::gpu("first_hit_colours_match") else {
        return;
    };
    let scene = load_scene(&common::fs::data("gltf/corpus/materials.glb")).unwrap();
    let rs = RenderScene::new(&scene, &BuildParams::default()).expect("BVH");
    let settings = RenderSettings {
        width: 96,
        height: 48,
        spp: 1,
        ..scene.settings
    };
    let cases: Vec<Case> = (0..settings.height)
        .flat_map(|y| (0..settings.width).map(move |x| [[x, y, 0, 0], [0; 4]]))
        .collect();
    let out = run(&ctx, &rs, &settings, "test_first_hit_colours", &cases);
    let cam = CameraRays::new(&rs.camera, settings.width, settings.height);
    let mut differ = Tally::new("hit or material differ (rays through edges)", 5e-3);
    let mut albedo_err = Worst::new("albedo (abs)", 1e-6);
    let mut diffuse_err = Worst::new("diffuse colour (abs)", 1e-6);
    let mut kinds = std::collections::BTreeSet::new();
    for (c, o) in cases.iter().zip(&out) {
        let [x, y, _, _] = c[0];
        let fh = first_hit(&rs, &pixel_centre_ray(&cam, x, y));
        let show = || format!("({x}, {y}): CPU {fh:?}, GPU {o:?}");
        if [fh.hit as u32, fh.material] != [o[0][3], o[1][3]] {
            differ.add(show);
            continue;
        }
        if fh.hit {
            kinds.insert(fh.material);
            albedo_err.add((v3(o[0]) - fh.albedo).abs().max_element() as f64, show);
            diffuse_err.add((v3(o[1]) - fh.diffuse).abs().max_element() as f64, show);
        }
    }
    eprintln!(
        "test_first_hit_colours: {} cases, materials {kinds:?}",
        cases.len()
    );
    differ.check("test_first_hit_colours", cases.len());
    albedo_err.check("test_first_hit_colours");
    diffuse_err.check("test_first_hit_colours");
    // The five spheres and the studio's floor.
    assert_eq!(kinds.len(), 6, "every sphere is hit: {kinds:?}");
}
