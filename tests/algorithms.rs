//! The algorithm comparisons' own code (`benches/algorithms/`, docs/algorithms.md) checked
//! where a wrong answer would mislead: the alternative triangle and box tests agree with
//! meshtrace's away from edges, the crack and box-miss counts find what they look for,
//! the chi-square tells the seed's biased sampler from the exact ones, and each builder's
//! tree holds every triangle once, with the SAH cost the library computes.

#[path = "../benches/algorithms/boxes.rs"]
#[allow(dead_code)]
mod boxes;
#[path = "../benches/algorithms/builders.rs"]
#[allow(dead_code)]
mod builders;
#[path = "../benches/algorithms/chi2.rs"]
#[allow(dead_code)]
mod chi2;
#[path = "../benches/algorithms/common.rs"]
#[allow(dead_code)]
mod common;
#[path = "../benches/algorithms/sampling.rs"]
#[allow(dead_code)]
mod sampling;
#[path = "../benches/algorithms/triangle.rs"]
#[allow(dead_code)]
mod triangle;

use boxes::{BoxTest, Conservative, SeedSlab, Williams};
use common::{Mesh, Rng};
use glam::Vec3;
use meshtrace::bvh::{BuildParams, Bvh, validate};
use meshtrace::geometry::T_INF;
use meshtrace::math::Ray;
use sampling::Target;
use triangle::{BaldwinWeber, MollerTrumbore, MollerTrumbore64, TriTest, Watertight};

/// Random triangles of sizes from 0.01 to 100, none thin (area at least a tenth of an
/// equilateral's of the same longest edge), and rays from random sides, none grazing
/// (at least 6 degrees off the plane), at points inside them (every barycentric at least
/// 0.005) or outside them (one barycentric at most -0.005): far from the edges next to
/// the tests' rounding, near enough to catch a wrong edge test.
fn triangle_cases(n: usize) -> Vec<([Vec3; 3], Ray, bool)> {
    let mut rng = Rng::new(11);
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let scale = 10f32.powi(out.len() as i32 % 5 - 2);
        let centre = 3.0 * scale * rng.direction();
        let corners = [0; 3].map(|_| centre + scale * rng.direction());
        let [a, b, c] = corners;
        let normal = (b - a).cross(c - a);
        let longest = [b - a, c - b, a - c]
            .map(Vec3::length)
            .into_iter()
            .fold(0.0, f32::max);
        if normal.length() < 0.1 * 0.87 * longest * longest {
            continue;
        }
        let inside = out.len() % 2 == 0;
        let (u, v) = rng.barycentrics(0.005);
        let (u, v) = if inside {
            (u, v)
        } else {
            (-0.005 - 0.1 * u, v)
        };
        let target = a + u * (b - a) + v * (c - a);
        let dir = rng.direction();
        if dir.dot(normal.normalize()).abs() < 0.1 {
            continue;
        }
        let origin = target - 5.0 * scale * dir;
        out.push((corners, Ray::new(origin, dir), inside));
    }
    out
}

fn hit<T: TriTest>(corners: [Vec3; 3], ray: &Ray) -> Option<meshtrace::geometry::TriHit> {
    T::hit(&T::ray(ray), &T::tri(corners), T_INF)
}

#[test]
fn alternative_triangle_tests_agree_with_the_watertight_one_away_from_edges() {
    for (corners, ray, inside) in triangle_cases(20_000) {
        let reference = hit::<Watertight>(corners, &ray);
        assert_eq!(reference.is_some(), inside, "{corners:?} {ray:?}");
        let others = [
            (MollerTrumbore::NAME, hit::<MollerTrumbore>(corners, &ray)),
            (
                MollerTrumbore64::NAME,
                hit::<MollerTrumbore64>(corners, &ray),
            ),
            (BaldwinWeber::NAME, hit::<BaldwinWeber>(corners, &ray)),
        ];
        for (name, h) in others {
            match (reference, h) {
                (None, None) => {}
                (Some(r), Some(h)) => {
                    let close = (h.t - r.t).abs() <= 1e-4 * r.t
                        && (h.u - r.u).abs() < 1e-3
                        && (h.v - r.v).abs() < 1e-3;
                    assert!(close, "{name}: {h:?} against {r:?} for {corners:?} {ray:?}");
                }
                _ => panic!("{name}: {h:?} against {reference:?} for {corners:?} {ray:?}"),
            }
        }
    }
}

/// Escapes of each kind (vertex, edge, interior, random rays) from an icosphere with test `T`.
fn icosphere_escapes<T: TriTest>(mesh: &Mesh, rays: &triangle::CrackRays) -> [u64; 4] {
    let bvh = Bvh::build(&mesh.bounds(), &BuildParams::fast()).expect("the tree fits");
    let nodes = triangle::padded(&bvh.nodes, 1e-6);
    let order = &bvh.order;
    let tris: Vec<T::Tri> = order
        .iter()
        .map(|&i| T::tri(mesh.corners(i as usize)))
        .collect();
    triangle::escapes::<T>(&nodes, &tris, rays)
}

#[test]
fn crack_count_finds_moller_trumbore_leaks_and_none_through_the_watertight_test() {
    let mesh = common::icosphere(3);
    assert!(mesh.is_closed());
    let origins = mesh.interior_points(2, &mut Rng::new(1));
    let rays = triangle::CrackRays::new(&mesh, &origins, 4, 1000, 2);
    assert_eq!(icosphere_escapes::<Watertight>(&mesh, &rays), [0; 4]);
    let [vertex, edge, interior, random] = icosphere_escapes::<MollerTrumbore>(&mesh, &rays);
    assert!(vertex > 0 && edge > 0, "{vertex} {edge}");
    assert_eq!((interior, random), (0, 0));
}

#[test]
fn an_open_mesh_is_not_closed() {
    let mut mesh = common::icosphere(1);
    assert!(mesh.is_closed());
    mesh.triangles.pop();
    assert!(!mesh.is_closed());
    let mut flipped = common::icosphere(1);
    flipped.triangles[0].swap(1, 2);
    assert!(!flipped.is_closed());
}

#[test]
fn box_tests_agree_on_clear_hits_and_misses() {
    let mut rng = Rng::new(5);
    for k in 0..20_000 {
        let centre = rng.direction() * 3.0;
        let half = Vec3::new(rng.f32(), rng.f32(), rng.f32()) + 0.1;
        let (min, max) = (centre - half, centre + half);
        let origin = centre + 10.0 * rng.direction();
        // Through the middle half of the box, or well clear of it.
        let hits = k % 2 == 0;
        let offset = if hits {
            0.5 * half * Vec3::new(rng.f32(), rng.f32(), rng.f32())
        } else {
            let away = (centre - origin).normalize().any_orthonormal_vector();
            3.0 * half.length() * away
        };
        let ray = Ray::new(origin, (centre + offset - origin).normalize());
        let check = |name: &str, got: bool| assert_eq!(got, hits, "{name}: {ray:?} {min} {max}");
        check(
            Conservative::NAME,
            Conservative::hit(&Conservative::ray(&ray), min, max, T_INF),
        );
        check(
            SeedSlab::NAME,
            SeedSlab::hit(&SeedSlab::ray(&ray), min, max, T_INF),
        );
        check(
            Williams::NAME,
            Williams::hit(&Williams::ray(&ray), min, max, T_INF),
        );
        // From inside, always a hit.
        let inside = Ray::new(centre + 0.5 * offset.clamp(-half, half), ray.dir);
        assert!(Conservative::hit(
            &Conservative::ray(&inside),
            min,
            max,
            T_INF
        ));
        assert!(SeedSlab::hit(&SeedSlab::ray(&inside), min, max, T_INF));
        assert!(Williams::hit(&Williams::ray(&inside), min, max, T_INF));
        // Behind the ray, nothing.
        let back = Ray::new(origin, -ray.dir);
        assert!(!SeedSlab::hit(&SeedSlab::ray(&back), min, max, T_INF));
        assert!(!Williams::hit(&Williams::ray(&back), min, max, T_INF));
    }
}

#[test]
fn box_miss_count_finds_the_seed_slab_misses_and_none_of_the_conservative_test() {
    let cases = boxes::must_hit_cases(&common::cornell_box(), 1);
    assert!(cases.iter().all(|c| c.len() > 50));
    for set in &cases {
        assert_eq!(boxes::false_misses::<Conservative>(set), 0);
    }
    // The walls' boxes are flat: entry equals exit, which the seed's strict test refuses.
    assert!(boxes::false_misses::<SeedSlab>(&cases[0]) > 0);
}

#[test]
fn chi_square_tail_matches_known_quantiles() {
    // P(X >= x) for chi-square with k degrees of freedom: 3.841 (k = 1) and 18.307
    // (k = 10) are the 5% points, 6.635 (k = 1) the 1% point.
    for (x, k, p) in [(3.841, 1.0, 0.05), (18.307, 10.0, 0.05), (6.635, 1.0, 0.01)] {
        let got = chi2::ln_gamma_q(0.5 * k, 0.5 * x).exp();
        assert!(
            (got - p).abs() < 1e-4 * p.max(1e-3) * 10.0,
            "{x} {k}: {got}"
        );
    }
    // Far in the tail the log stays finite: Q(400, 50000) is about e^-47000.
    let far = chi2::ln_gamma_q(400.0, 50_000.0);
    assert!(far.is_finite() && far < -40_000.0, "{far}");
}

#[test]
fn chi_square_of_a_known_sample() {
    // One band of four quarters of phi; 10, 20, 30 and 40 samples where 25 are expected
    // in each: chi2 = (225 + 25 + 25 + 225) / 25 = 20 with 3 degrees of freedom, whose
    // tail beyond 20 is 1.6974e-4.
    let cells = chi2::Cells {
        cos_min: -1.0,
        cos_bins: 1,
        phi_bins: 4,
    };
    let mut samples = Vec::new();
    for (quarter, count) in [10, 20, 30, 40].into_iter().enumerate() {
        let phi = (quarter as f64 + 0.5) * std::f64::consts::FRAC_PI_2;
        samples.extend(std::iter::repeat_n(
            glam::DVec3::new(phi.cos(), phi.sin(), 0.3).normalize(),
            count,
        ));
    }
    let c = chi2::chi2(&cells, &samples, &[0.25; 4]);
    assert!((c.chi2 - 20.0).abs() < 1e-9 && c.dof == 3, "{c:?}");
    assert!((10f64.powf(c.log10_p) - 1.6974e-4).abs() < 1e-7, "{c:?}");
}

/// log10 of the p-value of `n` directions of sampler `name` against what it means to draw.
fn log10_p(name: &str, n: usize) -> f64 {
    let samplers = sampling::samplers();
    let s = samplers.iter().find(|s| s.name == name).expect("a sampler");
    sampling::test_against(s.target, &sampling::draw(s, n, 21)).log10_p
}

#[test]
fn chi_square_rejects_the_seed_cube_method_and_accepts_the_exact_samplers() {
    const N: usize = 200_000;
    assert!(log10_p("seed_cube", N) < -100.0);
    assert!(log10_p("seed_diffuse_cube", N) < -100.0);
    assert!(log10_p("seed_diffuse_rejection_down", N) < -100.0);
    for exact in [
        "seed_rejection",
        "meshtrace_sphere",
        "meshtrace_cosine",
        "seed_diffuse_rejection",
    ] {
        let p = log10_p(exact, N);
        assert!(p > -4.0, "{exact}: log10 p {p}");
    }
    // The bias is the cube's density, exactly.
    let s = sampling::samplers();
    let cube = s.iter().find(|s| s.name == "seed_cube").expect("a sampler");
    let against_cube = sampling::test_against_cube(&sampling::draw(cube, N, 22));
    assert!(against_cube.log10_p > -4.0, "{against_cube:?}");
    assert_eq!(
        s.iter()
            .find(|s| s.name == "seed_rejection")
            .map(|s| s.target),
        Some(Target::Uniform)
    );
}

#[test]
fn the_seeds_generator_is_mt19937() {
    // The C++ standard's check: the 10000th output of a default-seeded mt19937.
    let mut mt = common::Mt19937::new(5489);
    let last = (0..10_000).map(|_| mt.next_u32()).last();
    assert_eq!(last, Some(4_123_659_995));
    let mut mt = common::Mt19937::new(1);
    for _ in 0..10_000 {
        let x = common::SignedUniform::signed_f64(&mut mt);
        assert!((-1.0..1.0).contains(&x), "{x}");
    }
}

#[test]
fn cube_density_integrates_to_one() {
    let cells = chi2::Cells::SPHERE;
    let total: f64 = cells.probabilities(&sampling::cube_pdf, 32).iter().sum();
    assert!((total - 1.0).abs() < 1e-4, "{total}");
}

#[test]
fn every_builder_holds_every_triangle_once_and_the_sah_cost_is_the_librarys() {
    let mut soup = Mesh {
        name: "soup".into(),
        positions: Vec::new(),
        triangles: Vec::new(),
    };
    let mut rng = Rng::new(8);
    for t in 0..3_000u32 {
        let centre = 5.0 * rng.direction() * rng.f32();
        soup.positions
            .extend([0; 3].map(|_| centre + 0.2 * rng.f32() * rng.direction()));
        soup.triangles.push([3 * t, 3 * t + 1, 3 * t + 2]);
    }
    for mesh in [common::icosphere(4), common::cornell_box(), soup] {
        let bounds = mesh.bounds();
        let (seed, dropped) = builders::seed_midpoint(&bounds);
        assert_eq!(dropped, 0, "{}", mesh.name);
        let median = builders::object_median(&bounds, 4);
        let sah = Bvh::build(&bounds, &BuildParams::fast()).expect("the tree fits");
        for (name, bvh) in [("seed", &seed), ("median", &median), ("sah", &sah)] {
            validate(bvh, &bounds).unwrap_or_else(|e| panic!("{} {name}: {e}", mesh.name));
        }
        let ours = builders::stats(&sah.nodes, bounds.len());
        let relative = (ours.sah_cost - sah.stats.sah_cost).abs() / sah.stats.sah_cost;
        assert!(relative < 1e-5, "{}: {ours:?} {:?}", mesh.name, sah.stats);
        assert_eq!(ours.leaves, sah.stats.leaves);
        assert_eq!(ours.depth, sah.stats.depth);
        assert!(median.nodes.iter().all(|n| n.count <= 4));
    }
}
