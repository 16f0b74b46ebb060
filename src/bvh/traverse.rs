//! Closest-hit and any-hit traversal with an explicit fixed stack, nearer child first.
//! mirror: shaders/traverse.wgsl

use super::{BvhNode, STACK_SIZE};
use crate::geometry::{
    ShearedRay, T_INF, TriVerts, intersect_aabb, intersect_triangle, safe_inverse,
};
use crate::math::Ray;
use glam::Vec3;

/// The closest hit: distance, barycentrics and the leaf-order triangle index (in this
/// order: the AVX2 traversal stores a hit as one four-lane vector).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct Hit {
    pub t: f32,
    pub u: f32,
    pub v: f32,
    pub tri: u32,
}

/// For traversals of scenes without cut-outs: every hit counts.
pub fn solid(_tri: u32, _u: f32, _v: f32) -> bool {
    true
}

/// The nearest intersection with `0 < t < t_max`. A hit on a triangle marked
/// [`TriVerts::is_masked`] counts only where `accept(tri, u, v)` says so (alpha cut-outs);
/// others count without asking.
/// mirror: shaders/traverse.wgsl `traverse_closest`
pub fn traverse_closest(
    nodes: &[BvhNode],
    tris: &[TriVerts],
    ray: &Ray,
    t_max: f32,
    accept: impl FnMut(u32, f32, f32) -> bool,
) -> Option<Hit> {
    closest(nodes, tris, ray, t_max, accept).0
}

/// [`traverse_closest`], and its cost: the BVH nodes it visited plus the triangles it
/// tested (the `bvh_cost` AOV).
/// mirror: shaders/traverse.wgsl `traverse_closest_counted`
pub fn traverse_closest_counted(
    nodes: &[BvhNode],
    tris: &[TriVerts],
    ray: &Ray,
    t_max: f32,
    accept: impl FnMut(u32, f32, f32) -> bool,
) -> (Option<Hit>, u32) {
    closest(nodes, tris, ray, t_max, accept)
}

/// The closest hit and the traversal's cost; inlined, so that [`traverse_closest`] does
/// not count.
#[inline(always)]
fn closest(
    nodes: &[BvhNode],
    tris: &[TriVerts],
    ray: &Ray,
    t_max: f32,
    mut accept: impl FnMut(u32, f32, f32) -> bool,
) -> (Option<Hit>, u32) {
    let sheared = ShearedRay::new(ray);
    let mut best: Option<Hit> = None;
    let mut t_best = t_max;
    let mut tested = 0u32;
    let visited = walk(nodes, ray, t_max, |first, count, _| {
        tested += count;
        for i in first..first + count {
            let tri = &tris[i as usize];
            if let Some(h) = intersect_triangle(&sheared, tri, t_best)
                && (!tri.is_masked() || accept(i, h.u, h.v))
            {
                t_best = h.t;
                best = Some(Hit {
                    t: h.t,
                    u: h.u,
                    v: h.v,
                    tri: i,
                });
            }
        }
        (false, t_best)
    });
    (best, visited + tested)
}

/// Whether anything lies on the ray with `0 < t < t_max` (shadow rays), with hits on
/// masked triangles counted as [`traverse_closest`] counts them.
/// mirror: shaders/traverse.wgsl `traverse_any`
pub fn traverse_any(
    nodes: &[BvhNode],
    tris: &[TriVerts],
    ray: &Ray,
    t_max: f32,
    mut accept: impl FnMut(u32, f32, f32) -> bool,
) -> bool {
    let sheared = ShearedRay::new(ray);
    let mut hit = false;
    walk(nodes, ray, t_max, |first, count, _| {
        hit = (first..first + count).any(|i| {
            let tri = &tris[i as usize];
            intersect_triangle(&sheared, tri, t_max)
                .is_some_and(|h| !tri.is_masked() || accept(i, h.u, h.v))
        });
        (hit, t_max)
    });
    hit
}

/// Visits the leaves the ray may reach, nearer child first. `leaf(first, count, t_max)`
/// returns whether to stop and the (possibly shortened) ray extent. Returns the number of
/// nodes visited (a count that callers who ignore it do not pay for: `walk` is inlined).
/// mirror: shaders/traverse.wgsl `walk`
#[inline]
fn walk(
    nodes: &[BvhNode],
    ray: &Ray,
    mut t_max: f32,
    mut leaf: impl FnMut(u32, u32, f32) -> (bool, f32),
) -> u32 {
    let Some(root) = nodes.first() else { return 0 };
    // An empty scene's root is a leaf of no triangles (any other root with count 0 is an
    // interior node, whose second child is never at index 0).
    if root.count == 0 && root.left_or_first == 0 {
        return 0;
    }
    let inv_dir = safe_inverse(ray.dir);
    if intersect_aabb(ray.origin, inv_dir, root.min.into(), root.max.into(), t_max) == T_INF {
        return 0;
    }
    let mut stack = [0u32; STACK_SIZE];
    let mut sp = 0usize;
    let mut node = 0u32;
    let mut visited = 0u32;
    loop {
        visited += 1;
        let n = &nodes[node as usize];
        if n.count > 0 {
            let (stop, t) = leaf(n.left_or_first, n.count, t_max);
            t_max = t;
            if stop || sp == 0 {
                return visited;
            }
            sp -= 1;
            node = stack[sp];
            continue;
        }
        let (mut a, mut b) = (node + 1, n.left_or_first);
        let box_t = |i: u32| {
            let c = &nodes[i as usize];
            intersect_aabb(
                ray.origin,
                inv_dir,
                Vec3::from(c.min),
                Vec3::from(c.max),
                t_max,
            )
        };
        let (mut ta, mut tb) = (box_t(a), box_t(b));
        if tb < ta {
            std::mem::swap(&mut ta, &mut tb);
            std::mem::swap(&mut a, &mut b);
        }
        if ta == T_INF {
            if sp == 0 {
                return visited;
            }
            sp -= 1;
            node = stack[sp];
            continue;
        }
        node = a;
        if tb != T_INF {
            stack[sp] = b;
            sp += 1;
        }
    }
}
