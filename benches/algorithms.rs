//! The algorithm comparisons of `docs/algorithms.md`: triangle tests, box tests, direction
//! samplers and BVH builders, meshtrace's against the seed's and the textbook's.
//!
//! `cargo bench --bench algorithms` times them with criterion (`target/criterion/`) and,
//! first, measures what is not a time (rays that escape a closed mesh, boxes missed, the
//! samplers' chi-square, the trees' SAH cost) into `target/algorithms/results.json`;
//! `cargo run --release --example algorithm_plots` draws the plots from both. Run as a
//! test (`cargo test --benches`), criterion runs each bench once and nothing is measured.
//!
//! The alternatives live here, not in the library: they exist only to be compared.

#[path = "algorithms/boxes.rs"]
mod boxes;
#[path = "algorithms/builders.rs"]
mod builders;
#[path = "algorithms/chi2.rs"]
mod chi2;
#[path = "algorithms/common.rs"]
mod common;
#[path = "algorithms/sampling.rs"]
mod sampling;
#[path = "algorithms/triangle.rs"]
mod triangle;

use boxes::{BoxTest, Conservative, SeedSlab, Williams};
use common::{Mesh, Rng};
use criterion::{BatchSize, BenchmarkGroup, Criterion, Throughput, measurement::WallTime};
use glam::DVec3;
use meshtrace::bvh::{
    BuildParams, Bvh, BvhNode, solid, traverse_closest, traverse_closest_counted,
};
use meshtrace::geometry::{T_INF, intersect_aabb, safe_inverse};
use meshtrace::math::{Aabb, Ray};
use rayon::prelude::*;
use serde_json::{Value, json};
use std::hint::black_box;
use std::time::Duration;
use triangle::{BaldwinWeber, MollerTrumbore, MollerTrumbore64, TriTest, Watertight};

/// Aimed rays whose traversals give the recorded candidate tests.
const CANDIDATE_RAYS: usize = 2_000;
/// Aimed rays of each traversal measure.
const TRAVERSAL_RAYS: usize = 4_096;
/// Directions per sampler timing iteration.
const DRAWS: usize = 4_096;
/// Directions per sampler chi-square test.
const CHI2_SAMPLES: usize = 1_000_000;
/// Leaf size of the object median build.
const MEDIAN_LEAF: usize = 4;

/// What the speed measures share: the mesh, meshtrace's tree over it, the rays, and the
/// triangle and box tests that traversals of the rays make, as they make them.
struct SpeedData {
    mesh: Mesh,
    bvh: Bvh,
    rays: Vec<Ray>,
    /// For each candidate ray: the ray, and its triangle tests as (leaf-order index, the
    /// ray's extent at that moment).
    tri_tests: Vec<(Ray, Vec<(u32, f32)>)>,
    /// For each candidate ray: its box tests as (node, the ray's extent at that moment).
    box_tests: Vec<(Ray, Vec<(u32, f32)>)>,
}

impl SpeedData {
    fn new() -> Self {
        let mesh = common::speed_mesh();
        let bvh = Bvh::build(&mesh.bounds(), &BuildParams::fast()).expect("the tree fits");
        let tris = mesh.tri_verts(&bvh.order);
        let candidates = common::aimed_rays(&mesh, CANDIDATE_RAYS, 1);
        let mut tri_tests = Vec::new();
        let mut box_tests = Vec::new();
        for ray in candidates {
            let sheared = meshtrace::geometry::ShearedRay::new(&ray);
            let inv_dir = safe_inverse(ray.dir);
            let (mut t_log, mut b_log) = (Vec::new(), Vec::new());
            let box_t = |i: u32, t_max: f32| {
                b_log.push((i, t_max));
                let n = &bvh.nodes[i as usize];
                intersect_aabb(ray.origin, inv_dir, n.min.into(), n.max.into(), t_max)
            };
            triangle::walk(&bvh.nodes, T_INF, box_t, |first, count, mut t_max| {
                for i in first..first + count {
                    t_log.push((i, t_max));
                    if let Some(h) = Watertight::hit(&sheared, &tris[i as usize], t_max) {
                        t_max = h.t;
                    }
                }
                t_max
            });
            tri_tests.push((ray, t_log));
            box_tests.push((ray, b_log));
        }
        Self {
            rays: common::aimed_rays(&mesh, TRAVERSAL_RAYS, 2),
            mesh,
            bvh,
            tri_tests,
            box_tests,
        }
    }

    fn tri_test_count(&self) -> usize {
        self.tri_tests.iter().map(|(_, t)| t.len()).sum()
    }

    fn box_test_count(&self) -> usize {
        self.box_tests.iter().map(|(_, t)| t.len()).sum()
    }
}

fn main() {
    let measuring = std::env::args().any(|a| a == "--bench");
    let data = SpeedData::new();
    if measuring {
        measure(&data);
    }
    let mut c = Criterion::default()
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_millis(1500))
        .sample_size(20)
        .configure_from_args();
    triangle_benches(&mut c, &data);
    box_benches(&mut c, &data);
    sampler_benches(&mut c);
    bvh_benches(&mut c, &data);
    c.final_summary();
}

/// `T`'s triangles of the speed mesh, in the tree's leaf order.
fn leaf_tris<T: TriTest>(data: &SpeedData) -> Vec<T::Tri> {
    let corners = |&i: &u32| data.mesh.corners(i as usize);
    data.bvh.order.iter().map(|i| T::tri(corners(i))).collect()
}

/// The candidate tests of `T`, as the traversals made them.
fn bench_pairs<T: TriTest>(group: &mut BenchmarkGroup<WallTime>, data: &SpeedData) {
    let tris = leaf_tris::<T>(data);
    group.bench_function(T::NAME, |b| {
        b.iter(|| {
            let mut hits = 0u32;
            for (ray, tests) in &data.tri_tests {
                let r = T::ray(black_box(ray));
                for &(i, t_max) in tests {
                    hits += u32::from(T::hit(&r, &tris[i as usize], t_max).is_some());
                }
            }
            hits
        })
    });
}

/// Closest-hit traversals of the speed rays with `T`.
fn bench_traversal<T: TriTest>(group: &mut BenchmarkGroup<WallTime>, data: &SpeedData) {
    let tris = leaf_tris::<T>(data);
    let nodes = &data.bvh.nodes;
    group.bench_function(T::NAME, |b| {
        b.iter(|| {
            let hit = |r: &&Ray| triangle::closest::<T>(nodes, &tris, r, T_INF).is_some();
            data.rays.iter().filter(hit).count()
        })
    });
}

fn triangle_benches(c: &mut Criterion, data: &SpeedData) {
    let mut g = c.benchmark_group("triangle_pairs");
    g.throughput(Throughput::Elements(data.tri_test_count() as u64));
    bench_pairs::<Watertight>(&mut g, data);
    bench_pairs::<MollerTrumbore>(&mut g, data);
    bench_pairs::<MollerTrumbore64>(&mut g, data);
    bench_pairs::<BaldwinWeber>(&mut g, data);
    g.finish();
    let mut g = c.benchmark_group("triangle_traversal");
    g.throughput(Throughput::Elements(data.rays.len() as u64));
    // Traversals differ by a few percent: measured longer, against the machine's noise.
    g.measurement_time(Duration::from_secs(3));
    bench_traversal::<Watertight>(&mut g, data);
    bench_traversal::<MollerTrumbore>(&mut g, data);
    bench_traversal::<MollerTrumbore64>(&mut g, data);
    bench_traversal::<BaldwinWeber>(&mut g, data);
    g.finish();
}

fn bench_box_test<B: BoxTest>(group: &mut BenchmarkGroup<WallTime>, data: &SpeedData) {
    let nodes = &data.bvh.nodes;
    group.bench_function(B::NAME, |b| {
        b.iter(|| {
            let mut hits = 0u32;
            for (ray, tests) in &data.box_tests {
                let r = B::ray(black_box(ray));
                for &(i, t_max) in tests {
                    let n = &nodes[i as usize];
                    hits += u32::from(B::hit(&r, n.min.into(), n.max.into(), t_max));
                }
            }
            hits
        })
    });
}

fn box_benches(c: &mut Criterion, data: &SpeedData) {
    let mut group = c.benchmark_group("box_pairs");
    group.throughput(Throughput::Elements(data.box_test_count() as u64));
    bench_box_test::<Conservative>(&mut group, data);
    bench_box_test::<SeedSlab>(&mut group, data);
    bench_box_test::<Williams>(&mut group, data);
    group.finish();
}

/// Times `DRAWS` directions of `draw` from `rng`, summed so that none is optimised away.
fn bench_sampler<R>(
    group: &mut BenchmarkGroup<WallTime>,
    name: &str,
    mut rng: R,
    mut draw: impl FnMut(&mut R) -> DVec3,
) {
    group.bench_function(name, |b| {
        b.iter(|| {
            let mut sum = DVec3::ZERO;
            for _ in 0..DRAWS {
                sum += draw(&mut rng);
            }
            sum
        })
    });
}

fn sampler_benches(c: &mut Criterion) {
    use sampling::*;
    let mut g = c.benchmark_group("samplers");
    g.throughput(Throughput::Elements(DRAWS as u64));
    let rng = || Rng::new(7);
    // The names of `sampling::samplers()`; each closure is that sampler's draw, written
    // out so that it inlines.
    bench_sampler(&mut g, "meshtrace_sphere", rng(), meshtrace_sphere);
    bench_sampler(&mut g, "seed_cube", rng(), seed_cube);
    // As the seed returns it: the caller normalises.
    bench_sampler(&mut g, "seed_rejection", rng(), seed_rejection);
    bench_sampler(&mut g, "meshtrace_cosine", rng(), meshtrace_cosine);
    bench_sampler(&mut g, "seed_diffuse_cube", rng(), |r| {
        seed_diffuse(DVec3::Z, seed_cube(r)).normalize()
    });
    bench_sampler(&mut g, "seed_diffuse_rejection", rng(), |r| {
        seed_diffuse(DVec3::Z, seed_rejection(r)).normalize()
    });
    // The seed's two unit vectors and bounces again, drawing from the seed's generator.
    let mt = || common::Mt19937::new(5489);
    bench_sampler(&mut g, "seed_cube_mt", mt(), seed_cube);
    bench_sampler(&mut g, "seed_rejection_mt", mt(), seed_rejection);
    bench_sampler(&mut g, "seed_diffuse_cube_mt", mt(), |r| {
        seed_diffuse(DVec3::Z, seed_cube(r)).normalize()
    });
    bench_sampler(&mut g, "seed_diffuse_rejection_mt", mt(), |r| {
        seed_diffuse(DVec3::Z, seed_rejection(r)).normalize()
    });
    g.finish();
}

/// A tree builder under comparison.
type Build<'a> = Box<dyn Fn(&[Aabb]) -> Bvh + 'a>;

/// The trees compared: name and build. meshtrace's builder runs in `pool`, of one thread,
/// as the others are serial.
fn builds(pool: &rayon::ThreadPool) -> Vec<(&'static str, Build<'_>)> {
    vec![
        ("seed_midpoint", Box::new(|b| builders::seed_midpoint(b).0)),
        (
            "object_median",
            Box::new(|b| builders::object_median(b, MEDIAN_LEAF)),
        ),
        (
            "sah_fast",
            Box::new(|b| {
                pool.install(|| Bvh::build(b, &BuildParams::fast()))
                    .expect("fits")
            }),
        ),
        (
            "sah_precise",
            Box::new(|b| {
                pool.install(|| Bvh::build(b, &BuildParams::precise()))
                    .expect("fits")
            }),
        ),
    ]
}

/// A pool of one thread.
fn one_thread() -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a pool of one thread")
}

fn bvh_benches(c: &mut Criterion, data: &SpeedData) {
    let bounds = data.mesh.bounds();
    let pool = one_thread();
    let builds = builds(&pool);
    let trees: Vec<(&str, Bvh)> = builds.iter().map(|(n, f)| (*n, f(&bounds))).collect();
    let mut g = c.benchmark_group("bvh_build");
    g.throughput(Throughput::Elements(bounds.len() as u64));
    g.sample_size(10);
    for (name, build) in &builds {
        g.bench_function(*name, |b| {
            b.iter_batched(
                || (),
                |()| build(black_box(&bounds)),
                BatchSize::PerIteration,
            )
        });
    }
    g.finish();
    let mut g = c.benchmark_group("bvh_traversal");
    g.throughput(Throughput::Elements(data.rays.len() as u64));
    g.measurement_time(Duration::from_secs(3));
    for (name, bvh) in &trees {
        let tris = data.mesh.tri_verts(&bvh.order);
        g.bench_function(*name, |b| {
            b.iter(|| {
                data.rays
                    .iter()
                    .filter(|r| traverse_closest(&bvh.nodes, &tris, r, T_INF, solid).is_some())
                    .count()
            })
        });
    }
    g.finish();
}

/// The measures that are not times, and the paired time ratios of [`paired`], into
/// `target/algorithms/results.json`.
fn measure(data: &SpeedData) {
    let start = std::time::Instant::now();
    let results = json!({
        "machine": machine(),
        "speed_mesh": {
            "name": data.mesh.name,
            "triangles": data.mesh.triangles.len(),
            "candidate_rays": CANDIDATE_RAYS,
            "triangle_tests": data.tri_test_count(),
            "box_tests": data.box_test_count(),
            "traversal_rays": data.rays.len(),
        },
        "escapes": escapes(),
        "box_misses": box_misses(),
        "samplers": samplers(),
        "bvh": trees(data),
        "paired": paired(data),
    });
    let dir = common::results_dir();
    std::fs::create_dir_all(&dir).expect("the results folder can be made");
    let path = dir.join("results.json");
    let text = serde_json::to_string_pretty(&results).expect("JSON of plain values");
    std::fs::write(&path, text).expect("the results can be written");
    eprintln!(
        "algorithms: measures written to {} ({:.1} s)",
        path.display(),
        start.elapsed().as_secs_f64()
    );
}

/// The CPU's model and thread count, from `/proc/cpuinfo` where there is one.
fn machine() -> Value {
    let model = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| "unknown".into());
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    json!({ "cpu": model, "threads": threads })
}

/// Rays from inside each closed mesh that each triangle test lets through.
fn escapes() -> Value {
    fn count<T: TriTest>(
        nodes: &[BvhNode],
        mesh: &Mesh,
        bvh: &Bvh,
        rays: &triangle::CrackRays,
    ) -> Value {
        let tris: Vec<T::Tri> = bvh
            .order
            .iter()
            .map(|&i| T::tri(mesh.corners(i as usize)))
            .collect();
        json!(triangle::escapes::<T>(nodes, &tris, rays))
    }
    let meshes: Vec<Value> = common::closed_meshes()
        .iter()
        .map(|mesh| {
            let mut rng = Rng::new(3);
            let origins = mesh.interior_points(8, &mut rng);
            let rays = triangle::CrackRays::new(mesh, &origins, 4, 1 << 16, 4);
            let bvh = Bvh::build(&mesh.bounds(), &BuildParams::fast()).expect("the tree fits");
            // Boxes a millionth of the mesh's size larger: every triangle any test could
            // hit is tested.
            let nodes = triangle::padded(&bvh.nodes, 1e-6 * mesh.aabb().extent().length());
            json!({
                "mesh": mesh.name,
                "triangles": mesh.triangles.len(),
                "vertices": mesh.positions.len(),
                "origins": origins.len(),
                "kinds": triangle::CRACK_KINDS,
                "rays": rays.kinds.each_ref().map(Vec::len),
                "escapes": {
                    Watertight::NAME: count::<Watertight>(&nodes, mesh, &bvh, &rays),
                    MollerTrumbore::NAME: count::<MollerTrumbore>(&nodes, mesh, &bvh, &rays),
                    MollerTrumbore64::NAME: count::<MollerTrumbore64>(&nodes, mesh, &bvh, &rays),
                    BaldwinWeber::NAME: count::<BaldwinWeber>(&nodes, mesh, &bvh, &rays),
                },
            })
        })
        .collect();
    json!(meshes)
}

/// Boxes of triangles that each box test misses although the ray hits the triangle.
fn box_misses() -> Value {
    let mut meshes = common::closed_meshes();
    meshes.push(common::cornell_box());
    let rows: Vec<Value> = meshes
        .iter()
        .map(|mesh| {
            let sets = boxes::must_hit_cases(mesh, 5);
            let misses = |f: fn(&[boxes::MustHit]) -> u64| sets.each_ref().map(|s| f(s));
            json!({
                "mesh": mesh.name,
                "sets": ["oblique", "axis_aligned"],
                "cases": sets.each_ref().map(Vec::len),
                "misses": {
                    Conservative::NAME: misses(boxes::false_misses::<Conservative>),
                    SeedSlab::NAME: misses(boxes::false_misses::<SeedSlab>),
                    Williams::NAME: misses(boxes::false_misses::<Williams>),
                },
            })
        })
        .collect();
    json!(rows)
}

/// Each sampler's chi-square against what it means to draw; for the uniform ones, the
/// density near the cube's corners and faces, and for the seed's cube method, the test
/// against the cube's own density and its density per cell relative to uniform.
fn samplers() -> Value {
    let list = sampling::samplers();
    let rows: Vec<Value> = list
        .par_iter()
        .enumerate()
        .map(|(k, s)| {
            let samples = sampling::draw(s, CHI2_SAMPLES, 100 + k as u64);
            let test = sampling::test_against(s.target, &samples);
            let mut row = json!({
                "name": s.name,
                "target": format!("{:?}", s.target).to_lowercase(),
                "samples": samples.len(),
                "chi2": test.chi2,
                "dof": test.dof,
                "log10_p": test.log10_p,
            });
            if s.target == sampling::Target::Uniform {
                let corners = sampling::density_near(&samples, &sampling::corner_axes(), 10.0);
                let faces = sampling::density_near(&samples, &sampling::face_axes(), 10.0);
                row["corner_density"] = json!(corners);
                row["face_density"] = json!(faces);
                let cells = chi2::Cells::SPHERE;
                let mut counts = vec![0u32; cells.len()];
                for &w in &samples {
                    if let Some(c) = cells.cell(w) {
                        counts[c] += 1;
                    }
                }
                let expected = samples.len() as f64 / cells.len() as f64;
                row["cells"] = json!({ "cos_bins": cells.cos_bins, "phi_bins": cells.phi_bins });
                row["density"] = json!(
                    counts
                        .iter()
                        .map(|&c| c as f64 / expected)
                        .collect::<Vec<_>>()
                );
            }
            if s.name == "seed_cube" {
                row["against_cube_pdf"] = json!(sampling::test_against_cube(&samples));
            }
            row
        })
        .collect();
    let down = DVec3::NEG_Z;
    let octant = DVec3::splat(-1.0).normalize();
    json!({
        "rows": rows,
        "replaced_by_normal": {
            "+z": sampling::replaced_by_normal(DVec3::Z, CHI2_SAMPLES, 9),
            "-z": sampling::replaced_by_normal(down, CHI2_SAMPLES, 9),
            "-x-y-z": sampling::replaced_by_normal(octant, CHI2_SAMPLES, 9),
        },
    })
}

/// Each tree's statistics and its traversal work for the speed rays: nodes visited plus
/// triangles tested, per ray (the `bvh_cost` AOV's count).
fn trees(data: &SpeedData) -> Value {
    let bounds = data.mesh.bounds();
    let pool = one_thread();
    let rows: Vec<Value> = builds(&pool)
        .iter()
        .map(|(name, build)| {
            let bvh = build(&bounds);
            let stats = builders::stats(&bvh.nodes, bounds.len());
            let dropped = bounds.len() - bvh.order.len();
            let tris = data.mesh.tri_verts(&bvh.order);
            let (mut hits, mut cost) = (0usize, 0u64);
            for r in &data.rays {
                let (hit, c) = traverse_closest_counted(&bvh.nodes, &tris, r, T_INF, solid);
                hits += usize::from(hit.is_some());
                cost += u64::from(c);
            }
            json!({
                "name": name,
                "sah_cost": stats.sah_cost,
                "nodes": stats.nodes,
                "leaves": stats.leaves,
                "depth": stats.depth,
                "mean_leaf": bounds.len() as f64 / stats.leaves as f64,
                "dropped": dropped,
                "hit_share": hits as f64 / data.rays.len() as f64,
                "cost_per_ray": cost as f64 / data.rays.len() as f64,
            })
        })
        .collect();
    json!(rows)
}

/// A timed workload: run once, it returns a checksum (so that nothing is optimised away).
type Work<'a> = Box<dyn FnMut() -> u64 + 'a>;

/// Rounds of [`ratios`].
const ROUNDS: usize = 41;

/// Each of `variants`' times over the first one's in the same round, for `ROUNDS` rounds
/// (after one to warm up) in which each runs once, the order turning each round: the
/// median and quartiles of the ratio. On a shared machine whose speed drifts between
/// criterion's benches, ratios of runs a few milliseconds apart are the steadier measure.
fn ratios(reference: &str, variants: &mut [(&str, Work)]) -> Value {
    let k = variants.len();
    let mut times = vec![Vec::with_capacity(ROUNDS); k];
    for round in 0..=ROUNDS {
        for j in 0..k {
            let i = (j + round) % k;
            let start = std::time::Instant::now();
            black_box((variants[i].1)());
            if round > 0 {
                times[i].push(start.elapsed().as_secs_f64());
            }
        }
    }
    let mut out = serde_json::Map::new();
    for (i, (name, _)) in variants.iter().enumerate() {
        let mut r: Vec<f64> = (0..ROUNDS).map(|n| times[i][n] / times[0][n]).collect();
        r.sort_by(f64::total_cmp);
        out.insert(
            name.to_string(),
            json!({ "median": r[ROUNDS / 2], "q1": r[ROUNDS / 4], "q3": r[3 * ROUNDS / 4] }),
        );
    }
    json!({ "reference": reference, "ratios": out })
}

/// Paired time ratios of the comparisons whose differences the machine's drift could
/// hide: the samplers (the seed's rejection method against its cube method, for unit
/// vectors and diffuse bounces, with either generator; meshtrace's warps beside them),
/// the triangle and box tests on the recorded candidates (against meshtrace's), the builds
/// (against the fast SAH build), the triangle tests in traversals
/// (against the watertight test) and the trees' traversals (against the fast SAH tree).
fn paired(data: &SpeedData) -> Value {
    use sampling::*;
    const N: usize = 16_384;
    fn draws<'a, R: 'a>(mut rng: R, mut draw: impl FnMut(&mut R) -> DVec3 + 'a) -> Work<'a> {
        Box::new(move || {
            let mut sum = DVec3::ZERO;
            for _ in 0..N {
                sum += draw(&mut rng);
            }
            black_box(sum).x.to_bits()
        })
    }
    let (split, mt) = (|| Rng::new(7), || common::Mt19937::new(5489));
    // (Closures written out, not made by a helper from function pointers: an indirect
    // call would not inline, and timings this short measure the inlining.)
    let samplers = json!({
        "unit": ratios(
            "seed_cube",
            &mut [
                ("seed_cube", draws(split(), seed_cube)),
                ("seed_rejection", draws(split(), seed_rejection)),
                ("meshtrace_sphere", draws(split(), meshtrace_sphere)),
            ],
        ),
        "bounce": ratios(
            "seed_diffuse_cube",
            &mut [
                ("seed_diffuse_cube", draws(split(), |r| seed_diffuse(DVec3::Z, seed_cube(r)).normalize())),
                ("seed_diffuse_rejection", draws(split(), |r| seed_diffuse(DVec3::Z, seed_rejection(r)).normalize())),
                ("meshtrace_cosine", draws(split(), meshtrace_cosine)),
            ],
        ),
        "unit_mt": ratios(
            "seed_cube_mt",
            &mut [
                ("seed_cube_mt", draws(mt(), seed_cube)),
                ("seed_rejection_mt", draws(mt(), seed_rejection)),
            ],
        ),
        "bounce_mt": ratios(
            "seed_diffuse_cube_mt",
            &mut [
                ("seed_diffuse_cube_mt", draws(mt(), |r| seed_diffuse(DVec3::Z, seed_cube(r)).normalize())),
                ("seed_diffuse_rejection_mt", draws(mt(), |r| seed_diffuse(DVec3::Z, seed_rejection(r)).normalize())),
            ],
        ),
    });
    fn traversal<'a, T: TriTest>(data: &'a SpeedData) -> Work<'a>
    where
        T::Tri: 'a,
    {
        let tris = leaf_tris::<T>(data);
        Box::new(move || {
            let hit = |r: &&Ray| triangle::closest::<T>(&data.bvh.nodes, &tris, r, T_INF).is_some();
            data.rays.iter().filter(hit).count() as u64
        })
    }
    let triangles = ratios(
        Watertight::NAME,
        &mut [
            (Watertight::NAME, traversal::<Watertight>(data)),
            (MollerTrumbore::NAME, traversal::<MollerTrumbore>(data)),
            (MollerTrumbore64::NAME, traversal::<MollerTrumbore64>(data)),
            (BaldwinWeber::NAME, traversal::<BaldwinWeber>(data)),
        ],
    );
    let bounds = data.mesh.bounds();
    let pool = one_thread();
    let mut trees: Vec<(&str, Work)> = builds(&pool)
        .iter()
        .map(|(name, build)| {
            let bvh = build(&bounds);
            let tris = data.mesh.tri_verts(&bvh.order);
            let work: Work = Box::new(move || {
                let hit = |r: &&Ray| traverse_closest(&bvh.nodes, &tris, r, T_INF, solid).is_some();
                data.rays.iter().filter(hit).count() as u64
            });
            (*name, work)
        })
        .collect();
    // The fast SAH tree first: the reference.
    trees.rotate_left(2);
    let trees = ratios("sah_fast", &mut trees);
    fn pairs<'a, T: TriTest>(data: &'a SpeedData) -> Work<'a>
    where
        T::Tri: 'a,
    {
        let tris = leaf_tris::<T>(data);
        Box::new(move || {
            let mut hits = 0u64;
            // Eight passes: one is too short (0.2 ms) to time steadily.
            for _ in 0..8 {
                for (ray, tests) in &data.tri_tests {
                    let r = T::ray(black_box(ray));
                    for &(i, t_max) in tests {
                        hits += u64::from(T::hit(&r, &tris[i as usize], t_max).is_some());
                    }
                }
            }
            hits
        })
    }
    let triangle_pairs = ratios(
        Watertight::NAME,
        &mut [
            (Watertight::NAME, pairs::<Watertight>(data)),
            (MollerTrumbore::NAME, pairs::<MollerTrumbore>(data)),
            (MollerTrumbore64::NAME, pairs::<MollerTrumbore64>(data)),
            (BaldwinWeber::NAME, pairs::<BaldwinWeber>(data)),
        ],
    );
    fn box_pairs<'a, B: BoxTest + 'a>(data: &'a SpeedData) -> Work<'a> {
        Box::new(move || {
            let mut hits = 0u64;
            for _ in 0..4 {
                for (ray, tests) in &data.box_tests {
                    let r = B::ray(black_box(ray));
                    for &(i, t_max) in tests {
                        let n = &data.bvh.nodes[i as usize];
                        hits += u64::from(B::hit(&r, n.min.into(), n.max.into(), t_max));
                    }
                }
            }
            hits
        })
    }
    let boxes = ratios(
        Conservative::NAME,
        &mut [
            (Conservative::NAME, box_pairs::<Conservative>(data)),
            (SeedSlab::NAME, box_pairs::<SeedSlab>(data)),
            (Williams::NAME, box_pairs::<Williams>(data)),
        ],
    );
    let builds = builds(&pool);
    let mut build_work: Vec<(&str, Work)> = builds
        .iter()
        .map(|(name, build)| {
            let bounds = &bounds;
            let work: Work = Box::new(move || build(bounds).nodes.len() as u64);
            (*name, work)
        })
        .collect();
    build_work.rotate_left(2);
    let builds = ratios("sah_fast", &mut build_work);
    json!({
        "samplers": samplers,
        "triangle_pairs": triangle_pairs,
        "triangle_traversal": triangles,
        "box_pairs": boxes,
        "bvh_build": builds,
        "bvh_traversal": trees,
    })
}
