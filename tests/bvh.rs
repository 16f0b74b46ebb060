//! The BVH against brute force: for 100k random rays, closest hit over the tree equals the
//! closest hit over every triangle, and any-hit agrees with it; and the tree's invariants.

use crate::common;

use common::rand::hashed_unit;
use glam::Vec3;
use meshtrace::bvh::Hit;
use meshtrace::bvh::wide::{LEAF_MAX, PACK_MASKED, WIDTH};
use meshtrace::bvh::{BuildParams, Bvh, WideBvh, solid, traverse_any, traverse_closest, validate};
use meshtrace::geometry::{ShearedRay, T_INF, TriVerts, intersect_triangle};
use meshtrace::math::{Aabb, Ray};
use meshtrace::scene::{self, sphere::icosphere};
use rayon::prelude::*;

/// Deterministic uniform floats in [0, 1) for test case `i`, stream `k`.
fn rand(i: u32, k: u32) -> f32 {
    hashed_unit(1, k, i, 0x5eed)
}

fn rand3(i: u32, k: u32) -> Vec3 {
    Vec3::new(rand(i, k), rand(i, k + 1), rand(i, k + 2))
}

/// A soup of random triangles of mixed sizes plus a finely tessellated sphere.
fn generated_mesh() -> Vec<[Vec3; 3]> {
    let mut tris = Vec::new();
    for i in 0..4_000 {
        let c = rand3(i, 0) * 10.0 - 5.0;
        let size = 0.02 + 0.5 * rand(i, 3).powi(3);
        tris.push([
            c,
            c + (rand3(i, 4) - 0.5) * size,
            c + (rand3(i, 7) - 0.5) * size,
        ]);
    }
    let (v, f) = icosphere(4);
    tris.extend(
        f.iter()
            .map(|t| t.map(|k| v[k as usize] * 2.0 + Vec3::new(1.0, 0.5, -1.0))),
    );
    tris
}

/// Rays from around the bounds towards random points inside them (most hit something).
fn rays(bounds: Aabb, n: u32) -> Vec<Ray> {
    let e = bounds.extent();
    (0..n)
        .map(|i| {
            let origin = bounds.min - 0.25 * e + 1.5 * e * rand3(i, 100);
            let target = bounds.min + e * rand3(i, 103);
            Ray::new(origin, (target - origin).normalize())
        })
        .collect()
}

fn check(name: &str, corners: &[[Vec3; 3]]) {
    check_rays(name, corners, false, |bounds| rays(bounds, 100_000));
}

/// The alpha test of a masked run: a masked triangle's hits count where `u > 0.3`.
fn cutout(_tri: u32, u: f32, _v: f32) -> bool {
    u > 0.3
}

/// Every tree's closest and any hit on `corners` against brute force, for the rays
/// `make_rays` gives for the triangles' bounds. With `masked`, every third triangle (in
/// leaf order) is masked, and its hits count where [`cutout`] passes.
fn check_rays(
    name: &str,
    corners: &[[Vec3; 3]],
    masked: bool,
    make_rays: impl FnOnce(Aabb) -> Vec<Ray>,
) {
    let bounds: Vec<Aabb> = corners.iter().map(|c| Aabb::from_points(c)).collect();
    let bvh = Bvh::build(&bounds, &BuildParams::default()).expect("the tree fits the stack");
    validate(&bvh, &bounds).unwrap_or_else(|e| panic!("{name}: {e}"));
    let tris: Vec<TriVerts> = (bvh.order.iter().enumerate())
        .map(|(k, &i)| {
            let mut t = TriVerts::new(corners[i as usize]);
            if masked && k % 3 == 0 {
                t.set_masked();
            }
            t
        })
        .collect();
    let accept: fn(u32, f32, f32) -> bool = if masked { cutout } else { solid };
    let wide = WideBvh::collapse(&bvh.nodes, &tris);
    validate_wide(&wide, &tris).unwrap_or_else(|e| panic!("{name}: {e}"));
    let all = bounds.iter().fold(Aabb::EMPTY, |a, b| a.union(*b));
    let rays = make_rays(all);
    // Bounding spheres (inflated by 1e-4 of the scene size) let the brute force skip
    // triangles whose sphere the ray's line misses, a test that can never reject a hit.
    let pad = 1e-4 * all.extent().length();
    let spheres: Vec<(Vec3, f32)> = tris
        .iter()
        .map(|t| {
            let [a, b, c] = t.corners();
            let center = (a + b + c) / 3.0;
            let r = (a - center)
                .length()
                .max((b - center).length())
                .max((c - center).length())
                + pad;
            (center, r * r)
        })
        .collect();
    let mismatches: Vec<String> = rays
        .par_iter()
        .enumerate()
        .filter_map(|(i, ray)| {
            let mut best: Option<(f32, u32)> = None;
            for (k, t) in tris.iter().enumerate() {
                let (center, r2) = spheres[k];
                // The distance from the centre to the line's closest point, not
                // |oc|^2 - along^2, which cancels catastrophically for far origins.
                let oc = center - ray.origin;
                let along = oc.dot(ray.dir);
                let off_line = (oc - along * ray.dir).length_squared();
                if off_line > r2 || (along < 0.0 && oc.length_squared() > r2) {
                    continue;
                }
                if let Some(h) =
                    intersect_triangle(&ShearedRay::new(ray), t, best.map_or(T_INF, |b| b.0))
                    && (!t.is_masked() || accept(k as u32, h.u, h.v))
                {
                    best = Some((h.t, k as u32));
                }
            }
            let same = |hit: Option<Hit>| match (best, hit) {
                (None, None) => true,
                // The same distance from a different triangle: a ray through a shared edge.
                (Some((t, k)), Some(h)) => h.tri == k || h.t == t,
                _ => false,
            };
            // The binary tree (the GPU's), the wide one (the CPU's) and its portable test.
            let hits = [
                traverse_closest(&bvh.nodes, &tris, ray, T_INF, accept),
                wide.traverse_closest(ray, T_INF, accept),
                wide.portable().traverse_closest(ray, T_INF, accept),
            ];
            let anys = [
                traverse_any(&bvh.nodes, &tris, ray, T_INF, accept),
                wide.traverse_any(ray, T_INF, accept),
                wide.portable().traverse_any(ray, T_INF, accept),
            ];
            // The wide tree's hit on the binary tree's triangle has its distance and
            // barycentrics bit for bit; its SIMD and portable tests agree entirely.
            let bits = |h: Hit| [h.t, h.u, h.v].map(f32::to_bits);
            let exact = match (hits[0], hits[1]) {
                (Some(a), Some(b)) if a.tri == b.tri => bits(a) == bits(b),
                _ => true,
            };
            let all_same = hits.iter().all(|&h| same(h)) && exact && hits[1] == hits[2];
            let any_ok = anys.iter().all(|&a| a == best.is_some());
            (!all_same || !any_ok).then(|| {
                format!(
                    "ray {i}: brute force {best:?}, binary/wide/portable {hits:?}, any-hit {anys:?}"
                )
            })
        })
        .collect();
    let hits = rays.len();
    assert!(
        mismatches.is_empty(),
        "{name}: {} of {hits} rays disagree, first: {}",
        mismatches.len(),
        mismatches[0]
    );
    // A shorter ray must stop at the hit: any-hit with t_max just short of the closest hit is false.
    for ray in rays.iter().take(10_000) {
        if let Some(h) = traverse_closest(&bvh.nodes, &tris, ray, T_INF, accept) {
            assert!(
                !traverse_any(&bvh.nodes, &tris, ray, h.t * 0.999, accept),
                "{name}: any-hit beyond t_max"
            );
            assert!(
                !wide.traverse_any(ray, h.t * 0.999, accept),
                "{name}: wide any-hit beyond t_max"
            );
            assert!(
                wide.traverse_closest(ray, h.t * 0.999, accept).is_none(),
                "{name}: wide closest hit beyond t_max"
            );
            assert!(traverse_any(
                &bvh.nodes,
                &tris,
                ray,
                h.t * 1.001 + 1e-6,
                accept
            ));
        }
    }
}

#[test]
fn closest_hit_matches_brute_force_on_a_generated_mesh() {
    check("generated", &generated_mesh());
}

/// Masked triangles count only where their alpha test passes, in every traversal; the wide
/// tree knows them from its packs alone.
#[test]
fn masked_triangles_count_where_their_alpha_test_passes() {
    check_rays("generated, masked", &generated_mesh(), true, |b| {
        rays(b, 20_000)
    });
}

/// Triangles and rays in one tilted plane (up to rounding): there the edge functions are
/// rounding noise, and the watertight test's rounding bound rejects most "hits". The wide
/// tree's SIMD test must reject exactly the lanes the scalar test rejects.
#[test]
fn rays_in_the_plane_of_the_triangles_hit_what_the_scalar_test_hits() {
    let (a, b) = (
        Vec3::new(1.0, 0.3, -0.2).normalize(),
        Vec3::new(0.1, 0.8, 0.5).normalize(),
    );
    let at = |x: f32, y: f32| a * x + b * y;
    let corners: Vec<[Vec3; 3]> = (0..3000)
        .map(|i| {
            let (x, y, s) = (10.0 * rand(i, 0) - 5.0, 10.0 * rand(i, 1) - 5.0, rand(i, 2));
            let corner = |k| at(x + s * (rand(i, k) - 0.5), y + s * (rand(i, k + 1) - 0.5));
            [at(x, y), corner(3), corner(5)]
        })
        .collect();
    check_rays("in-plane", &corners, false, |_| {
        (0..20_000)
            .map(|i| {
                let origin = at(14.0 * rand(i, 200) - 7.0, 14.0 * rand(i, 201) - 7.0);
                let target = at(10.0 * rand(i, 202) - 5.0, 10.0 * rand(i, 203) - 5.0);
                Ray::new(origin, (target - origin).normalize())
            })
            .collect()
    });
}

/// Nodes of 16384 triangles or more choose their split from a sample: the tree must still
/// hold every triangle where its boxes say, and cost about what binning all of them does.
#[test]
fn sampled_splits_keep_the_tree_exact_and_cheap() {
    let (v, f) = icosphere(5);
    let mut corners: Vec<[Vec3; 3]> = f
        .iter()
        .map(|t| t.map(|k| v[k as usize] * 3.0 + Vec3::new(-1.0, 0.0, 2.0)))
        .collect();
    corners.extend(generated_mesh());
    assert!(corners.len() >= 4 * 4096, "the root must be sampled");
    check_rays("sphere and soup", &corners, false, |b| rays(b, 20_000));
    let bounds: Vec<Aabb> = corners.iter().map(|c| Aabb::from_points(c)).collect();
    let fast = Bvh::build(&bounds, &BuildParams::default()).unwrap().stats;
    let precise = Bvh::build(&bounds, &BuildParams::precise()).unwrap().stats;
    eprintln!(
        "SAH cost: {} sampled, 16 bins; {} with 32 bins everywhere (ratio {:.4})",
        fast.sah_cost,
        precise.sah_cost,
        fast.sah_cost / precise.sah_cost
    );
    assert!(fast.sah_cost <= precise.sah_cost * 1.05);
}

#[test]
fn closest_hit_matches_brute_force_on_the_stanford_bunny() {
    let Some(path) = common::fs::shared_mesh("stanford-bunny.obj") else {
        return;
    };
    // The bunny's own triangles: the studio's ground would take most of the rays.
    let scene = common::studio::without_ground(scene::load_scene(&path).expect("the bunny loads"));
    let corners: Vec<[Vec3; 3]> = scene
        .mesh
        .triangles
        .iter()
        .map(|t| scene.mesh.vertices(t))
        .collect();
    assert!(corners.len() > 69_000);
    check("bunny", &corners);
}

#[test]
fn sah_leaves_vary_in_size_and_the_tree_costs_less_than_a_flat_list() {
    let corners = generated_mesh();
    let bounds: Vec<Aabb> = corners.iter().map(|c| Aabb::from_points(c)).collect();
    let bvh = Bvh::build(&bounds, &BuildParams::default()).unwrap();
    let s = &bvh.stats;
    // The SAH chooses leaf sizes: more than one size occurs, none beyond the cap.
    assert!(
        s.leaf_sizes.iter().filter(|&&n| n > 0).count() > 1,
        "{:?}",
        s.leaf_sizes
    );
    assert!(s.leaf_sizes.len() <= BuildParams::default().max_leaf_size + 1);
    assert_eq!(
        s.leaf_sizes
            .iter()
            .enumerate()
            .map(|(k, n)| k * n)
            .sum::<usize>(),
        corners.len()
    );
    // One leaf holding everything would cost N; a good tree costs a tiny fraction of that.
    assert!(
        s.sah_cost < corners.len() as f32 / 200.0,
        "SAH cost {}",
        s.sah_cost
    );
    // 32 bins may only do slightly better than 16.
    let precise = Bvh::build(&bounds, &BuildParams::precise()).unwrap();
    eprintln!(
        "SAH cost: {} with 16 bins, {} with 32 (ratio {:.4})",
        s.sah_cost,
        precise.stats.sah_cost,
        s.sah_cost / precise.stats.sah_cost
    );
    assert!(
        s.sah_cost <= precise.stats.sah_cost * 1.05,
        "{} vs {}",
        s.sah_cost,
        precise.stats.sah_cost
    );
}

/// The tree is the same whatever the number of threads that build it: subtrees are built
/// in parallel, but each writes only the node slots it owns.
#[test]
fn build_is_independent_of_the_thread_count() {
    let (v, f) = icosphere(6);
    let mut corners: Vec<[Vec3; 3]> = f.iter().map(|t| t.map(|k| v[k as usize])).collect();
    corners.extend(generated_mesh());
    let bounds: Vec<Aabb> = corners.iter().map(|c| Aabb::from_points(c)).collect();
    let build = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| Bvh::build(&bounds, &BuildParams::default()).unwrap())
    };
    let (one, four) = (build(1), build(4));
    assert!(one.nodes.len() > 10_000);
    assert!(one.nodes == four.nodes, "the trees differ");
    assert_eq!(one.order, four.order);
}

/// The wide tree's invariants: every slot's box holds what the slot leads to, the leaves'
/// packs hold each triangle once (its corners, in lanes that come first), every interior
/// slot's node is reached once, and each node's slots in use come first.
fn validate_wide(wide: &WideBvh, tris: &[TriVerts]) -> Result<(), String> {
    let mut covered = vec![false; tris.len()];
    let mut reached = vec![false; wide.nodes.len()];
    let mut stack = vec![(
        0usize,
        Aabb::from_points(&[Vec3::splat(f32::MIN), Vec3::splat(f32::MAX)]),
    )];
    while let Some((i, parent)) = stack.pop() {
        if std::mem::replace(&mut reached[i], true) {
            return Err(format!("wide node {i} is reached twice"));
        }
        let node = &wide.nodes[i];
        let len = node.len();
        if len == 0 || (len..WIDTH).any(|k| node.lo[0][k] != f32::INFINITY) {
            return Err(format!("wide node {i} has {len} slots, not first"));
        }
        for k in 0..len {
            let b = Aabb {
                min: Vec3::new(node.lo[0][k], node.lo[1][k], node.lo[2][k]),
                max: Vec3::new(node.hi[0][k], node.hi[1][k], node.hi[2][k]),
            };
            if !parent.contains(&b) {
                return Err(format!("wide node {i} slot {k} pokes out of its parent"));
            }
            if node.count[k] == 0 {
                stack.push((node.child[k] as usize, b));
                continue;
            }
            let packs = node.child[k] as usize..(node.child[k] + node.count[k]) as usize;
            let lanes: Vec<(usize, usize)> = packs
                .flat_map(|p| (0..WIDTH).map(move |l| (p, l)))
                .collect();
            if lanes.len() > LEAF_MAX.next_multiple_of(WIDTH as u32) as usize {
                return Err(format!(
                    "wide node {i} slot {k} has {} packs",
                    node.count[k]
                ));
            }
            let used = lanes
                .iter()
                .take_while(|&&(p, l)| wide.packs[p].tri[l] != u32::MAX)
                .count();
            if used == 0
                || lanes[used..]
                    .iter()
                    .any(|&(p, l)| wide.packs[p].tri[l] != u32::MAX)
            {
                return Err(format!(
                    "wide node {i} slot {k}: lanes in use do not come first"
                ));
            }
            for &(p, l) in &lanes[..used] {
                let pack = &wide.packs[p];
                let t = (pack.tri[l] & !PACK_MASKED) as usize;
                if (pack.tri[l] & PACK_MASKED != 0) != tris.get(t).is_some_and(|t| t.is_masked()) {
                    return Err(format!(
                        "pack {p} lane {l}: the mask bit is not triangle {t}'s"
                    ));
                }
                let slot = covered
                    .get_mut(t)
                    .ok_or(format!("pack {p} names triangle {t}"))?;
                if std::mem::replace(slot, true) {
                    return Err(format!("triangle slot {t} is in two wide leaves"));
                }
                let corners = tris[t].corners();
                for (c, corner) in corners.iter().enumerate() {
                    if (0..3).any(|a| pack.v[3 * c + a][l] != corner[a]) {
                        return Err(format!("pack {p} lane {l} does not hold triangle {t}"));
                    }
                }
                if !b.contains(&Aabb::from_points(&corners)) {
                    return Err(format!("wide node {i} slot {k} does not hold triangle {t}"));
                }
            }
        }
    }
    if let Some(i) = reached.iter().position(|r| !r) {
        return Err(format!("wide node {i} is never reached"));
    }
    match covered.iter().position(|c| !c) {
        Some(t) => Err(format!("triangle slot {t} is in no wide leaf")),
        None => Ok(()),
    }
}
