//! The GPU's traversal (`test_traverse` of `shaders/tests.wgsl`: the software BVH walk, or
//! hardware ray queries) against the CPU's software walk: random rays through a scene, the
//! f64 plane hit that says whether a case lies at an edge, and the comparison with its
//! bounds.

use super::kernels::{Case, b, f, run, v3, word};
use super::rand::SplitMix;
use super::stats::{Failures, Tally, Worst, rel};
use glam::Vec2;
use meshtrace::bvh::{traverse_any, traverse_closest};
use meshtrace::geometry::{T_INF, TriVerts};
use meshtrace::math::Ray;
use meshtrace::render::RenderScene;
use meshtrace::render::gpu::GpuContext;
use meshtrace::render::sampling::sample_uniform_triangle;
use meshtrace::scene::RenderSettings;

/// (t, u, v, cosine between ray and plane) of the ray's meeting with the triangle's plane,
/// in f64: the reference that says whether a case is close to an edge or grazing.
pub fn plane_hit_f64(ray: &Ray, tri: &TriVerts) -> (f64, f64, f64, f64) {
    let [v0, v1, v2] = tri.corners().map(|c| c.as_dvec3());
    let (o, d) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
    let e1 = v1 - v0;
    let e2 = v2 - v0;
    let p = d.cross(e2);
    let det = e1.dot(p);
    let s = o - v0;
    let u = s.dot(p) / det;
    let q = s.cross(e1);
    let v = d.dot(q) / det;
    let t = e2.dot(q) / det;
    let cos = det.abs() / (e1.cross(e2).length() * d.length()).max(f64::MIN_POSITIVE);
    (t, u, v, cos)
}

/// Whether barycentrics (u, v) lie within `eps` of the triangle's boundary.
pub fn near_edge(u: f64, v: f64, eps: f64) -> bool {
    u.abs() < eps || v.abs() < eps || (1.0 - u - v).abs() < eps || (1.0 - u).abs() < eps
}

/// Rays through a scene: aimed at random triangles, random, from outside, and short.
pub fn traversal_rays(rs: &RenderScene, r: &mut SplitMix, n: usize) -> Vec<Case> {
    let root = rs.bvh.nodes[0].bounds();
    let mut cases = Vec::with_capacity(n);
    while cases.len() < n {
        let kind = r.below(10);
        let origin = if kind < 8 {
            root.center() + root.extent() * r.vec3(-0.6, 0.6)
        } else {
            root.center() + r.unit_vector() * root.extent().length()
        };
        let dir = if kind < 5 {
            let tri = rs.tris[r.below(rs.tris.len())].corners();
            let bary = sample_uniform_triangle(Vec2::new(r.unit(), r.unit()));
            let p = (1.0 - bary.x - bary.y) * tri[0] + bary.x * tri[1] + bary.y * tri[2];
            (p - origin) * r.range(0.5, 2.0)
        } else if kind < 8 {
            r.unit_vector()
        } else {
            root.center() + root.extent() * r.vec3(-0.5, 0.5) - origin
        };
        let t_max = if r.chance(0.15) {
            r.range(0.0, 3.0)
        } else {
            T_INF
        };
        cases.push([word(origin, 0), word(dir, b(t_max))]);
    }
    cases
}

/// How closely the GPU's hits must follow the CPU's. `edge` is the distance from an edge
/// (in barycentrics, over the ray's cosine with the plane) within which the two tests may
/// decide differently; the fractions bound the cases of each kind of difference.
#[derive(Clone, Copy, Debug)]
pub struct Bounds {
    pub edge: f64,
    /// Closest hits on different sides of an edge (one reached a triangle behind it).
    pub edge_fraction: f64,
    /// Another triangle at the same t (within `same_t`, relative): a shared edge or corner.
    pub other_tri_fraction: f64,
    pub same_t: f64,
    /// Relative errors of t and of u, v on the same triangle, scaled by the cosine, of t
    /// over max(t, `t_floor`) and of u, v over max(u or v, `uv_floor`).
    pub t_rel: f64,
    pub t_floor: f32,
    pub uv_rel: f64,
    pub uv_floor: f32,
    /// Any-hit answers that differ, where the closest hits already differed at an edge.
    pub any_edge_fraction: f64,
}

/// Runs `test_traverse` on `ctx` over `cases` and checks each against the CPU's
/// `traverse_closest` and `traverse_any` with acceptance `accept` (as `alpha_test`):
/// the same triangle with t, u, v within the bounds, or a difference of a kind and in a
/// fraction the bounds allow. Prints the figures.
pub fn check_traversal(
    name: &'static str,
    ctx: &GpuContext,
    rs: &RenderScene,
    settings: &RenderSettings,
    cases: &[Case],
    accept: impl Fn(u32, f32, f32) -> bool + Copy,
    bounds: Bounds,
) {
    let (nodes, tris) = (&rs.bvh.nodes, &rs.tris);
    let out = run(ctx, rs, settings, "test_traverse", cases);
    let mut fail = Failures::new(name);
    let mut edge = Tally::new("hit/miss differs near an edge", bounds.edge_fraction);
    let mut other_tri = Tally::new("another triangle at the same t", bounds.other_tri_fraction);
    let mut t_err = Worst::new(
        format!("t (relative, floor {})", bounds.t_floor),
        bounds.t_rel,
    );
    let mut uv_err = Worst::new(
        format!("u, v (relative, floor {})", bounds.uv_floor),
        bounds.uv_rel,
    );
    let mut any_edge = Tally::new("any-hit differs near an edge", bounds.any_edge_fraction);
    let mut hits = 0;
    let near_edge_of = |ray: &Ray, tri: u32| {
        let (_, u, v, cos) = plane_hit_f64(ray, &tris[tri as usize]);
        near_edge(u, v, bounds.edge / cos.max(1e-6))
    };
    for (c, o) in cases.iter().zip(&out) {
        let ray = Ray::new(v3(c[0]), v3(c[1]));
        let t_max = f(c[1][3]);
        let cpu = traverse_closest(nodes, tris, &ray, t_max, accept);
        let cpu_any = traverse_any(nodes, tris, &ray, t_max, accept);
        let (gtri, gt, gu, gv) = (o[0][0], f(o[0][1]), f(o[0][2]), f(o[0][3]));
        let gpu_any = o[1][0] == 1;
        let show = || {
            format!(
                "ray {ray:?} t_max {t_max}: CPU {cpu:?} any {cpu_any}; GPU tri {gtri} t {gt} u {gu} v {gv} any {gpu_any}"
            )
        };
        hits += cpu.is_some() as usize;
        match cpu {
            None if gtri == u32::MAX => {
                if gt != t_max {
                    fail.add(|| format!("miss reports t {gt}: {}", show()));
                }
            }
            Some(h) if gtri == h.tri => {
                let cos = plane_hit_f64(&ray, &tris[h.tri as usize]).3.min(1.0);
                t_err.add(rel(h.t, gt, bounds.t_floor) * cos, show);
                let f = bounds.uv_floor;
                uv_err.add(rel(h.u, gu, f).max(rel(h.v, gv, f)) * cos, show);
            }
            Some(h) if gtri != u32::MAX => {
                if rel(h.t, gt, 0.0) <= bounds.same_t {
                    other_tri.add(show);
                } else if near_edge_of(&ray, h.tri) || near_edge_of(&ray, gtri) {
                    // One device slipped through an edge the other hit, reaching another
                    // triangle behind it.
                    edge.add(show);
                } else {
                    fail.add(show);
                }
            }
            Some(h) => {
                if near_edge_of(&ray, h.tri) {
                    edge.add(show);
                } else {
                    fail.add(show);
                }
            }
            None => {
                if near_edge_of(&ray, gtri) {
                    edge.add(show);
                } else {
                    fail.add(show);
                }
            }
        }
        if cpu_any != cpu.is_some() {
            fail.add(|| format!("CPU any-hit disagrees with closest: {}", show()));
        }
        if gpu_any != cpu_any {
            // Only where the closest hit already differed at an edge.
            let edgy = cpu.is_some_and(|h| near_edge_of(&ray, h.tri))
                || (gtri != u32::MAX && near_edge_of(&ray, gtri));
            if edgy {
                any_edge.add(show);
            } else {
                fail.add(|| format!("any-hit differs: {}", show()));
            }
        }
    }
    eprintln!("{name}: {} cases, {hits} CPU hits", cases.len());
    fail.check(cases.len());
    edge.check(name, cases.len());
    other_tri.check(name, cases.len());
    any_edge.check(name, cases.len());
    t_err.check(name);
    uv_err.check(name);
    assert!(hits > cases.len() / 3, "{name}: only {hits} hits");
}
