//! Ray–box tests: meshtrace's conservative slab test (`meshtrace::geometry`), the seed's
//! slab test, and Williams et al.'s test with precomputed signs; and the count of boxes
//! each misses although the ray hits the triangle inside.

use super::common::{Mesh, Rng};
use glam::Vec3;
use meshtrace::geometry::{
    ShearedRay, T_INF, TriVerts, intersect_aabb, intersect_triangle, safe_inverse,
};
use meshtrace::math::{Aabb, Ray};

/// One ray–box test: what it prepares of a ray, and whether the ray meets the box
/// `min..=max` within `0..t_max`.
pub trait BoxTest {
    const NAME: &'static str;
    type Ray: Copy;
    fn ray(ray: &Ray) -> Self::Ray;
    fn hit(ray: &Self::Ray, min: Vec3, max: Vec3, t_max: f32) -> bool;
}

/// meshtrace's test: slabs from [`safe_inverse`] (no `0 * inf`), the exit distance widened
/// by its rounding bound, entry and exit compared inclusively.
pub struct Conservative;

impl BoxTest for Conservative {
    const NAME: &'static str = "conservative_slab";
    type Ray = (Vec3, Vec3);

    fn ray(ray: &Ray) -> (Vec3, Vec3) {
        (ray.origin, safe_inverse(ray.dir))
    }

    #[inline(always)]
    fn hit(&(origin, inv): &(Vec3, Vec3), min: Vec3, max: Vec3, t_max: f32) -> bool {
        intersect_aabb(origin, inv, min, max, t_max) != T_INF
    }
}

/// C++'s `std::max(a, b)`: `a < b ? b : a` (a NaN in `b` is dropped, one in `a` kept).
#[inline(always)]
fn cpp_max(a: f32, b: f32) -> f32 {
    if a < b { b } else { a }
}

/// C++'s `std::min(a, b)`: `b < a ? b : a`.
#[inline(always)]
fn cpp_min(a: f32, b: f32) -> f32 {
    if b < a { b } else { a }
}

/// The seed's `AABB::simpleSlabRayAABBMethod` (`Step 3/src/engine/math/colliders.cpp`), in
/// f32: the plain inverse direction, the slabs axis by axis with C++'s `std::min` and
/// `std::max`, and a hit only when the exit lies strictly beyond the entry.
pub struct SeedSlab;

impl BoxTest for SeedSlab {
    const NAME: &'static str = "seed_slab";
    type Ray = (Vec3, Vec3);

    fn ray(ray: &Ray) -> (Vec3, Vec3) {
        (ray.origin, ray.dir.recip())
    }

    #[inline(always)]
    fn hit(&(o, inv): &(Vec3, Vec3), min: Vec3, max: Vec3, t_max: f32) -> bool {
        let (mut tmin, mut tmax) = (0.0f32, t_max);
        for axis in 0..3 {
            let t1 = (min[axis] - o[axis]) * inv[axis];
            let t2 = (max[axis] - o[axis]) * inv[axis];
            tmin = cpp_max(tmin, cpp_min(t1, t2));
            tmax = cpp_min(tmax, cpp_max(t1, t2));
        }
        tmin = cpp_max(tmin, 0.0);
        tmax > tmin
    }
}

/// Williams, Barrus, Morley and Shirley (2005), "An Efficient and Robust Ray-Box
/// Intersection Algorithm": the signs of the inverse direction pick each slab's near and
/// far plane, and the test leaves as soon as two slabs' intervals are disjoint.
pub struct Williams;

impl BoxTest for Williams {
    const NAME: &'static str = "williams";
    /// Origin, inverse direction, and for each axis whether its inverse is negative.
    type Ray = (Vec3, Vec3, [usize; 3]);

    fn ray(ray: &Ray) -> Self::Ray {
        let inv = ray.dir.recip();
        let sign = [0, 1, 2].map(|a| usize::from(inv[a] < 0.0));
        (ray.origin, inv, sign)
    }

    #[inline(always)]
    fn hit(&(o, inv, sign): &Self::Ray, min: Vec3, max: Vec3, t_max: f32) -> bool {
        let b = [min, max];
        let mut tmin = (b[sign[0]].x - o.x) * inv.x;
        let mut tmax = (b[1 - sign[0]].x - o.x) * inv.x;
        let tymin = (b[sign[1]].y - o.y) * inv.y;
        let tymax = (b[1 - sign[1]].y - o.y) * inv.y;
        if tmin > tymax || tymin > tmax {
            return false;
        }
        if tymin > tmin {
            tmin = tymin;
        }
        if tymax < tmax {
            tmax = tymax;
        }
        let tzmin = (b[sign[2]].z - o.z) * inv.z;
        let tzmax = (b[1 - sign[2]].z - o.z) * inv.z;
        if tmin > tzmax || tzmin > tmax {
            return false;
        }
        if tzmin > tmin {
            tmin = tzmin;
        }
        if tzmax < tmax {
            tmax = tzmax;
        }
        tmin < t_max && tmax > 0.0
    }
}

/// A ray and a box it must hit: the tight box of a triangle that the watertight test says
/// the ray hits.
#[derive(Clone, Copy, Debug)]
pub struct MustHit {
    pub ray: Ray,
    pub min: Vec3,
    pub max: Vec3,
}

/// How many of `cases` test `B` misses (with the ray unbounded).
pub fn false_misses<B: BoxTest>(cases: &[MustHit]) -> u64 {
    cases
        .iter()
        .filter(|c| !B::hit(&B::ray(&c.ray), c.min, c.max, T_INF))
        .count() as u64
}

/// The cases of [`false_misses`] for every triangle of `mesh`, in two sets. Oblique: from
/// a random point at the mesh's size from the triangle, towards each corner, a point of
/// each edge and a point inside. Axis-aligned: the same seven points, from along the axis
/// nearest the triangle's normal, exactly (two direction components are 0, and a corner
/// lies on the box's faces). Only the rays that the watertight test says hit are kept.
pub fn must_hit_cases(mesh: &Mesh, seed: u64) -> [Vec<MustHit>; 2] {
    let mut rng = Rng::new(seed);
    let size = mesh.aabb().extent().length();
    let mut out: [Vec<MustHit>; 2] = Default::default();
    for t in 0..mesh.triangles.len() {
        let corners = mesh.corners(t);
        let tri = TriVerts::new(corners);
        let [a, b, c] = corners;
        let n = (b - a).cross(c - a);
        if n == Vec3::ZERO {
            continue;
        }
        let (u, v) = rng.barycentrics(0.05);
        let mut points = vec![a, b, c, a + u * (b - a) + v * (c - a)];
        for (p, q) in [(a, b), (b, c), (c, a)] {
            points.push(p + rng.f32() * (q - p));
        }
        let box_ = Aabb::from_points(&corners);
        let axis = n.abs().max_position();
        let mut along = Vec3::ZERO;
        along[axis] = n[axis].signum();
        for p in points {
            let oblique = p + size * rng.direction();
            for (set, origin) in [(0, oblique), (1, p + size * along)] {
                let dir = if set == 0 {
                    (p - origin).normalize()
                } else {
                    -along
                };
                let ray = Ray::new(origin, dir);
                if intersect_triangle(&ShearedRay::new(&ray), &tri, T_INF).is_some() {
                    out[set].push(MustHit {
                        ray,
                        min: box_.min,
                        max: box_.max,
                    });
                }
            }
        }
    }
    out
}
