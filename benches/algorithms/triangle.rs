//! Ray–triangle tests: meshtrace's watertight test (`meshtrace::geometry`), the seed's
//! Möller–Trumbore test in f32 and in its own f64, and Baldwin and Weber's test on a
//! precomputed transform. A closest-hit traversal of meshtrace's binary tree that takes
//! any of them, and the count of rays that escape a closed mesh through its cracks.

use glam::{DVec3, Vec3};
use meshtrace::bvh::{BvhNode, STACK_SIZE};
use meshtrace::geometry::{
    ShearedRay, T_INF, TriHit, TriVerts, intersect_aabb, intersect_triangle, safe_inverse,
};
use meshtrace::math::Ray;

/// One ray–triangle test: what it keeps of a triangle and of a ray, and the test.
pub trait TriTest {
    /// The name in the results and plots.
    const NAME: &'static str;
    /// A triangle as the test stores it.
    type Tri: Copy + Send + Sync;
    /// A ray as the test prepares it, once per ray.
    type Ray: Copy;
    fn tri(corners: [Vec3; 3]) -> Self::Tri;
    fn ray(ray: &Ray) -> Self::Ray;
    /// The hit with `0 < t < t_max` (distance, barycentrics of corners 1 and 2).
    fn hit(ray: &Self::Ray, tri: &Self::Tri, t_max: f32) -> Option<TriHit>;
}

/// meshtrace's test (Woop, Benthin and Wald 2013, with a rounding bound): the library's
/// own function and triangle layout.
pub struct Watertight;

impl TriTest for Watertight {
    const NAME: &'static str = "watertight";
    type Tri = TriVerts;
    type Ray = ShearedRay;

    fn tri(corners: [Vec3; 3]) -> TriVerts {
        TriVerts::new(corners)
    }

    fn ray(ray: &Ray) -> ShearedRay {
        ShearedRay::new(ray)
    }

    #[inline(always)]
    fn hit(ray: &ShearedRay, tri: &TriVerts, t_max: f32) -> Option<TriHit> {
        intersect_triangle(ray, tri, t_max)
    }
}

/// The seed's `EPSILON` (`Step 3/include/engine/util/std.h`), which its Möller–Trumbore
/// test compares the determinant and the distance with.
const SEED_EPSILON: f64 = 0.000_000_1;

/// Möller and Trumbore (1997) as the seed wrote it (`checkIfTriangleGotHit` in
/// `Step 3/src/engine/world.cpp`): the same operations, branches and `EPSILON`, in f32
/// as meshtrace stores its triangles.
pub struct MollerTrumbore;

impl TriTest for MollerTrumbore {
    const NAME: &'static str = "moller_trumbore";
    type Tri = TriVerts;
    type Ray = Ray;

    fn tri(corners: [Vec3; 3]) -> TriVerts {
        TriVerts::new(corners)
    }

    fn ray(ray: &Ray) -> Ray {
        *ray
    }

    #[inline(always)]
    fn hit(ray: &Ray, tri: &TriVerts, t_max: f32) -> Option<TriHit> {
        const EPS: f32 = SEED_EPSILON as f32;
        let [v0, v1, v2] = tri.corners();
        let (e1, e2) = (v1 - v0, v2 - v0);
        let h = ray.dir.cross(e2);
        let a = e1.dot(h);
        if a > -EPS && a < EPS {
            return None; // parallel to the triangle
        }
        let f = 1.0 / a;
        let s = ray.origin - v0;
        let u = f * s.dot(h);
        if !(0.0..=1.0).contains(&u) {
            return None;
        }
        let q = s.cross(e1);
        let v = f * ray.dir.dot(q);
        if v < 0.0 || u + v > 1.0 {
            return None;
        }
        let t = f * e2.dot(q);
        (t > EPS && t < t_max).then_some(TriHit { t, u, v })
    }
}

/// The seed's Möller–Trumbore in its own precision: its `PRECISION_TYPE` is `double`
/// (`Step 3/include/engine/math/vectors.h`); the corners are meshtrace's f32 ones.
pub struct MollerTrumbore64;

impl TriTest for MollerTrumbore64 {
    const NAME: &'static str = "moller_trumbore_f64";
    type Tri = [DVec3; 3];
    type Ray = (DVec3, DVec3);

    fn tri(corners: [Vec3; 3]) -> [DVec3; 3] {
        corners.map(|c| c.as_dvec3())
    }

    fn ray(ray: &Ray) -> (DVec3, DVec3) {
        (ray.origin.as_dvec3(), ray.dir.as_dvec3())
    }

    #[inline(always)]
    fn hit(&(origin, dir): &(DVec3, DVec3), tri: &[DVec3; 3], t_max: f32) -> Option<TriHit> {
        let [v0, v1, v2] = *tri;
        let (e1, e2) = (v1 - v0, v2 - v0);
        let h = dir.cross(e2);
        let a = e1.dot(h);
        if a > -SEED_EPSILON && a < SEED_EPSILON {
            return None;
        }
        let f = 1.0 / a;
        let s = origin - v0;
        let u = f * s.dot(h);
        if !(0.0..=1.0).contains(&u) {
            return None;
        }
        let q = s.cross(e1);
        let v = f * dir.dot(q);
        if v < 0.0 || u + v > 1.0 {
            return None;
        }
        let t = f * e2.dot(q);
        (t > SEED_EPSILON && t < f64::from(t_max)).then_some(TriHit {
            t: t as f32,
            u: u as f32,
            v: v as f32,
        })
    }
}

/// Baldwin and Weber (2016), "Fast Ray-Triangle Intersections by Coordinate
/// Transformation" (JCGT 5(3)): each triangle stores the affine map that takes it to the
/// unit triangle in the plane z = 0 (12 floats, as many bytes as meshtrace's corners), so
/// a test is one plane distance, one point and two dot products.
pub struct BaldwinWeber;

/// The rows of Baldwin and Weber's map: `x' = rows[0] . (p, 1)` is the barycentric of
/// corner 1, `y' = rows[1] . (p, 1)` that of corner 2, `z' = rows[2] . (p, 1)` the
/// (scaled) distance from the plane. A degenerate triangle gets zero rows and is never hit.
#[derive(Clone, Copy, Debug)]
pub struct BwTri {
    pub rows: [[f32; 4]; 3],
}

impl BwTri {
    /// The precomputation of the paper's listing 1, choosing the largest component of the
    /// normal as the one divided by.
    pub fn new([v0, v1, v2]: [Vec3; 3]) -> Self {
        let (e1, e2) = (v1 - v0, v2 - v0);
        let n = e1.cross(e2);
        let (c20, c10) = (v2.cross(v0), v1.cross(v0));
        let d = -v0.dot(n);
        let a = n.abs();
        let rows = if a.x > a.y && a.x > a.z {
            [
                [0.0, e2.z / n.x, -e2.y / n.x, c20.x / n.x],
                [0.0, -e1.z / n.x, e1.y / n.x, -c10.x / n.x],
                [1.0, n.y / n.x, n.z / n.x, d / n.x],
            ]
        } else if a.y > a.z {
            [
                [-e2.z / n.y, 0.0, e2.x / n.y, c20.y / n.y],
                [e1.z / n.y, 0.0, -e1.x / n.y, -c10.y / n.y],
                [n.x / n.y, 1.0, n.z / n.y, d / n.y],
            ]
        } else if a.z > 0.0 {
            [
                [e2.y / n.z, -e2.x / n.z, 0.0, c20.z / n.z],
                [-e1.y / n.z, e1.x / n.z, 0.0, -c10.z / n.z],
                [n.x / n.z, n.y / n.z, 1.0, d / n.z],
            ]
        } else {
            [[0.0; 4]; 3]
        };
        Self { rows }
    }
}

impl TriTest for BaldwinWeber {
    const NAME: &'static str = "baldwin_weber";
    type Tri = BwTri;
    type Ray = Ray;

    fn tri(corners: [Vec3; 3]) -> BwTri {
        BwTri::new(corners)
    }

    fn ray(ray: &Ray) -> Ray {
        *ray
    }

    /// The paper's listing 2.
    #[inline(always)]
    fn hit(ray: &Ray, tri: &BwTri, t_max: f32) -> Option<TriHit> {
        let [r0, r1, r2] = tri.rows;
        let (o, d) = (ray.origin, ray.dir);
        let trans_s = r2[0] * o.x + r2[1] * o.y + r2[2] * o.z + r2[3];
        let trans_d = r2[0] * d.x + r2[1] * d.y + r2[2] * d.z;
        let t = -trans_s / trans_d;
        // (Written so that a NaN, from a degenerate triangle's zero rows, is no hit.)
        if !(t > 0.0 && t < t_max) {
            return None;
        }
        let w = o + t * d;
        let u = r0[0] * w.x + r0[1] * w.y + r0[2] * w.z + r0[3];
        let v = r1[0] * w.x + r1[1] * w.y + r1[2] * w.z + r1[3];
        (u >= 0.0 && v >= 0.0 && u + v < 1.0).then_some(TriHit { t, u, v })
    }
}

/// The closest hit of `ray` among `tris` (in the tree's leaf order), walking `nodes` as
/// meshtrace's `traverse_closest` does (nearer child first, fixed stack, the library's
/// conservative box test) but with test `T`: the distance and the leaf-order index.
pub fn closest<T: TriTest>(
    nodes: &[BvhNode],
    tris: &[T::Tri],
    ray: &Ray,
    t_max: f32,
) -> Option<(f32, u32)> {
    let prepared = T::ray(ray);
    let inv_dir = safe_inverse(ray.dir);
    let mut best = None;
    let box_t = |i: u32, t_max: f32| {
        let n = &nodes[i as usize];
        intersect_aabb(ray.origin, inv_dir, n.min.into(), n.max.into(), t_max)
    };
    walk(nodes, t_max, box_t, |first, count, t_max| {
        let mut t_best = t_max;
        for i in first..first + count {
            if let Some(h) = T::hit(&prepared, &tris[i as usize], t_best) {
                t_best = h.t;
                best = Some((h.t, i));
            }
        }
        t_best
    });
    best
}

/// Visits the leaves a ray may reach, nearer child first (meshtrace's `bvh::traverse`
/// walk, which is private): `box_t(node, t_max)` is the ray's entry distance into the
/// box of node `node` ([`T_INF`] for a miss), and `leaf(first, count, t_max)` returns the ray's
/// new extent after a leaf.
#[inline(always)]
pub fn walk(
    nodes: &[BvhNode],
    mut t_max: f32,
    mut box_t: impl FnMut(u32, f32) -> f32,
    mut leaf: impl FnMut(u32, u32, f32) -> f32,
) {
    if nodes.is_empty() || box_t(0, t_max) == T_INF {
        return;
    }
    let mut stack = [0u32; STACK_SIZE];
    let (mut sp, mut node) = (0usize, 0u32);
    loop {
        let n = &nodes[node as usize];
        if n.count > 0 {
            t_max = leaf(n.left_or_first, n.count, t_max);
        } else {
            let (mut a, mut b) = (node + 1, n.left_or_first);
            let (mut ta, mut tb) = (box_t(a, t_max), box_t(b, t_max));
            if tb < ta {
                std::mem::swap(&mut ta, &mut tb);
                std::mem::swap(&mut a, &mut b);
            }
            if ta != T_INF {
                if tb != T_INF {
                    stack[sp] = b;
                    sp += 1;
                }
                node = a;
                continue;
            }
        }
        if sp == 0 {
            return;
        }
        sp -= 1;
        node = stack[sp];
    }
}

/// The rays that stress a closed mesh's cracks, from points inside it: towards every
/// vertex, towards points on every edge, and (the controls) towards points inside every
/// triangle, away from its edges, and in uniformly random directions, as a renderer's
/// rays leave a point.
pub struct CrackRays {
    /// Rays aimed at vertices, at edge points, at triangle interiors, and random ones.
    pub kinds: [Vec<Ray>; 4],
}

/// The names of [`CrackRays::kinds`].
pub const CRACK_KINDS: [&str; 4] = ["vertex", "edge", "interior", "random"];

impl CrackRays {
    /// From each of `origins`: a ray to every vertex, to `per_edge` random points of every
    /// edge, to one random point of every triangle, and `random` in random directions.
    pub fn new(
        mesh: &super::common::Mesh,
        origins: &[Vec3],
        per_edge: usize,
        random: usize,
        seed: u64,
    ) -> Self {
        let mut rng = super::common::Rng::new(seed);
        let edges = mesh.edges();
        let aim = |o: Vec3, p: Vec3| Ray::new(o, (p - o).normalize());
        let mut kinds: [Vec<Ray>; 4] = Default::default();
        for &o in origins {
            kinds[0].extend(mesh.positions.iter().map(|&v| aim(o, v)));
            for &[a, b] in &edges {
                let (a, b) = (mesh.positions[a as usize], mesh.positions[b as usize]);
                for _ in 0..per_edge {
                    let s = rng.f32();
                    kinds[1].push(aim(o, a + s * (b - a)));
                }
            }
            for t in 0..mesh.triangles.len() {
                let [a, b, c] = mesh.corners(t);
                let (u, v) = rng.barycentrics(0.05);
                kinds[2].push(aim(o, a + u * (b - a) + v * (c - a)));
            }
            kinds[3].extend((0..random).map(|_| Ray::new(o, rng.direction())));
        }
        Self { kinds }
    }
}

/// `nodes` with every box grown by `pad` on each side: the escape counts must see every
/// triangle a ray could hit, whatever the test's own rounding.
pub fn padded(nodes: &[BvhNode], pad: f32) -> Vec<BvhNode> {
    nodes
        .iter()
        .map(|n| BvhNode {
            min: (Vec3::from(n.min) - pad).into(),
            max: (Vec3::from(n.max) + pad).into(),
            ..*n
        })
        .collect()
}

/// How many rays of each kind of `rays` find no hit at all with test `T`.
pub fn escapes<T: TriTest>(nodes: &[BvhNode], tris: &[T::Tri], rays: &CrackRays) -> [u64; 4] {
    use rayon::prelude::*;
    rays.kinds.each_ref().map(|kind| {
        kind.par_iter()
            .filter(|r| closest::<T>(nodes, tris, r, T_INF).is_none())
            .count() as u64
    })
}
