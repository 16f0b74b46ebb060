//! An 8-wide BVH for the CPU renderer, collapsed from the binary SAH tree: each node holds
//! the boxes of up to eight children as a struct of arrays, which one AVX2 instruction
//! sequence tests against a ray at once (a portable loop elsewhere), and the traversal
//! visits the hit children nearest first.
//!
//! A binary subtree of at most [`LEAF_MAX`] triangles becomes one leaf, over the same
//! leaf-ordered triangles, copied into packs of eight as a struct of arrays: one AVX2
//! sequence runs the watertight test on the eight triangles at once, its edge functions,
//! distance, barycentrics and rounding bound each computed in the order and rounding of the
//! scalar test, so that a lane hits exactly where `intersect_triangle` would, with the same
//! distance and barycentrics, and the traversal never reads the triangle table (the portable
//! path, on a CPU without AVX2, calls the scalar test on each lane). The wide traversal thus
//! returns the binary traversal's hit (the same triangle, distance and barycentrics), except
//! where two triangles are hit at exactly the same distance, where either may be returned.
//! The GPU keeps the binary tree (`shaders/traverse.wgsl`), which
//! [`super::traverse_closest`] mirrors.

use super::{BvhNode, Hit, STACK_SIZE};
use crate::geometry::{SLAB_SLACK, ShearedRay, T_INF, TriVerts, intersect_triangle, safe_inverse};
use crate::math::Ray;
use std::mem::MaybeUninit;

/// Children per node, and triangles per pack.
pub const WIDTH: usize = 8;

/// The bit of [`TriPack::tri`] that marks a triangle whose hits pass an alpha test first, so
/// that the traversal need not read the triangle table; the other bits are the index, which
/// stays below it ([`super::MAX_TRIANGLES`]).
pub const PACK_MASKED: u32 = 1 << 31;

/// The most triangles of a leaf: a binary subtree of at most this many becomes one leaf.
pub const LEAF_MAX: u32 = 8;

/// Up to eight triangles of a leaf as a struct of arrays: corner `c`'s axis `a` of lane `l`
/// is `v[3 * c + a][l]`, and `tri[l]` is the lane's leaf-order triangle index, with
/// [`PACK_MASKED`] set where the triangle [`is_masked`](TriVerts::is_masked), and
/// `u32::MAX` for an unused lane.
#[repr(C, align(64))]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriPack {
    pub v: [[f32; WIDTH]; 9],
    pub tri: [u32; WIDTH],
}

/// One node (256 bytes, four cache lines). Slot `k` is a child box
/// `lo[axis][k] ..= hi[axis][k]`; an interior child (`count[k] == 0`) is node `child[k]`,
/// a leaf is packs `child[k] .. child[k] + count[k]`. Unused slots have `+inf` in
/// both corners, a box that every ray misses (the inverse direction is never 0 or NaN).
#[repr(C, align(64))]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WideNode {
    pub lo: [[f32; WIDTH]; 3],
    pub hi: [[f32; WIDTH]; 3],
    pub child: [u32; WIDTH],
    pub count: [u32; WIDTH],
}

impl WideNode {
    const UNUSED: Self = Self {
        lo: [[f32::INFINITY; WIDTH]; 3],
        hi: [[f32::INFINITY; WIDTH]; 3],
        child: [0; WIDTH],
        count: [0; WIDTH],
    };

    /// The slots in use (they come first).
    pub fn len(&self) -> usize {
        (0..WIDTH)
            .take_while(|&k| self.lo[0][k] != f32::INFINITY)
            .count()
    }

    /// Whether no slot is in use (never true of a node of a built tree).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// The wide tree; node 0 is the root. An empty scene has no nodes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct WideBvh {
    pub nodes: Vec<WideNode>,
    /// The leaves' triangles, each leaf's in consecutive packs.
    pub packs: Vec<TriPack>,
}

impl WideBvh {
    /// Collapses a flattened binary tree over the leaf-ordered `tris`: a subtree of at most
    /// [`LEAF_MAX`] triangles becomes a leaf, and from each wide node's place in the binary
    /// tree, the interior child of largest surface area is replaced by its two children
    /// until there are eight or only leaves are left (the SAH's choice of what to test
    /// together).
    pub fn collapse(binary: &[BvhNode], tris: &[TriVerts]) -> Self {
        let Some(root) = binary.first() else {
            return Self::default();
        };
        if root.count == 0 && root.left_or_first == 0 {
            return Self::default();
        }
        // Each subtree's triangles are a contiguous range of the leaf order: its first and
        // how many (children come after their parent).
        let mut range = vec![(0u32, 0u32); binary.len()];
        for i in (0..binary.len()).rev() {
            let b = &binary[i];
            range[i] = if b.is_leaf() {
                (b.left_or_first, b.count)
            } else {
                let (l, r) = (range[i + 1], range[b.left_or_first as usize]);
                (l.0.min(r.0), l.1 + r.1)
            };
        }
        let leaf = |k: u32| binary[k as usize].is_leaf() || range[k as usize].1 <= LEAF_MAX;
        let area = |k: u32| {
            let e = binary[k as usize].bounds().extent();
            e.x * e.y + e.y * e.z + e.z * e.x
        };
        let mut out = Self {
            nodes: vec![WideNode::UNUSED],
            packs: Vec::new(),
        };
        // (wide node to fill, binary node it stands for)
        let mut work = vec![(0usize, 0u32)];
        while let Some((w, b)) = work.pop() {
            let mut kids: Vec<u32> = if leaf(b) {
                vec![b]
            } else {
                vec![b + 1, binary[b as usize].left_or_first]
            };
            while kids.len() < WIDTH {
                let widest = (0..kids.len())
                    .filter(|&i| !leaf(kids[i]))
                    .max_by(|&i, &j| area(kids[i]).total_cmp(&area(kids[j])));
                let Some(i) = widest else { break };
                let k = kids[i];
                kids[i] = k + 1;
                kids.push(binary[k as usize].left_or_first);
            }
            let mut node = WideNode::UNUSED;
            for (slot, &k) in kids.iter().enumerate() {
                let n = &binary[k as usize];
                for axis in 0..3 {
                    node.lo[axis][slot] = n.min[axis];
                    node.hi[axis][slot] = n.max[axis];
                }
                if leaf(k) {
                    let (first, count) = range[k as usize];
                    node.child[slot] = out.packs.len() as u32;
                    node.count[slot] = count.div_ceil(WIDTH as u32);
                    out.packs.extend(
                        (first..first + count).step_by(WIDTH).map(|start| {
                            pack(tris, start..(start + WIDTH as u32).min(first + count))
                        }),
                    );
                } else {
                    node.child[slot] = out.nodes.len() as u32;
                    work.push((out.nodes.len(), k));
                    out.nodes.push(WideNode::UNUSED);
                }
            }
            out.nodes[w] = node;
        }
        out
    }

    /// The nearest intersection with `0 < t < t_max`, as [`super::traverse_closest`] finds
    /// it; masked triangles count where `accept(tri, u, v)` says so. (Always inlined, as
    /// the other entry points below: a call left to the compiler's choice costs the path
    /// tracer about 1.5% of its instructions where the caller is large.)
    #[inline(always)]
    pub fn traverse_closest(
        &self,
        ray: &Ray,
        t_max: f32,
        accept: impl FnMut(u32, f32, f32) -> bool,
    ) -> Option<Hit> {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            let mut hit = Hit {
                t: 0.0,
                u: 0.0,
                v: 0.0,
                tri: 0,
            };
            // SAFETY: the CPU has AVX2, the only requirement of `closest_avx2`.
            let found = unsafe { closest_avx2(self, ray, t_max, accept, &mut hit) };
            return found.then_some(hit);
        }
        closest::<Portable>(self, ray, t_max, accept)
    }

    /// Whether anything lies on the ray with `0 < t < t_max`, as [`super::traverse_any`]
    /// decides it.
    #[inline(always)]
    pub fn traverse_any(
        &self,
        ray: &Ray,
        t_max: f32,
        accept: impl FnMut(u32, f32, f32) -> bool,
    ) -> bool {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU has AVX2, the only requirement of `any_avx2`.
            return unsafe { any_avx2(self, ray, t_max, accept) };
        }
        any::<Portable>(self, ray, t_max, accept)
    }

    /// The same traversals with the portable box and pack tests whatever the CPU, so that
    /// tests can compare the two implementations.
    pub fn portable(&self) -> PortableWide<'_> {
        PortableWide(self)
    }
}

/// [`WideBvh`] traversed with the portable box and pack tests only.
pub struct PortableWide<'a>(&'a WideBvh);

impl PortableWide<'_> {
    /// [`WideBvh::traverse_closest`] without SIMD.
    pub fn traverse_closest(
        &self,
        ray: &Ray,
        t_max: f32,
        accept: impl FnMut(u32, f32, f32) -> bool,
    ) -> Option<Hit> {
        closest::<Portable>(self.0, ray, t_max, accept)
    }

    /// [`WideBvh::traverse_any`] without SIMD.
    pub fn traverse_any(
        &self,
        ray: &Ray,
        t_max: f32,
        accept: impl FnMut(u32, f32, f32) -> bool,
    ) -> bool {
        any::<Portable>(self.0, ray, t_max, accept)
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn closest_avx2(
    bvh: &WideBvh,
    ray: &Ray,
    t_max: f32,
    accept: impl FnMut(u32, f32, f32) -> bool,
    out: &mut Hit,
) -> bool {
    use std::arch::x86_64::*;
    let Some(h) = closest::<Avx2>(bvh, ray, t_max, accept) else {
        return false;
    };
    // One 16-byte store, so that the caller's copy of it is forwarded from the store
    // buffer (four 4-byte stores read back by one 16-byte load stall for them).
    let v = _mm_setr_ps(h.t, h.u, h.v, f32::from_bits(h.tri));
    // SAFETY: `Hit` is `repr(C)`, four 4-byte fields in this order, sixteen bytes in all.
    unsafe { _mm_storeu_ps((out as *mut Hit).cast(), v) };
    true
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn any_avx2(
    bvh: &WideBvh,
    ray: &Ray,
    t_max: f32,
    accept: impl FnMut(u32, f32, f32) -> bool,
) -> bool {
    any::<Avx2>(bvh, ray, t_max, accept)
}

/// Triangles `range` of `tris` as a pack.
fn pack(tris: &[TriVerts], range: std::ops::Range<u32>) -> TriPack {
    let mut p = TriPack {
        v: [[0.0; WIDTH]; 9],
        tri: [u32::MAX; WIDTH],
    };
    for (lane, i) in range.enumerate() {
        let t = &tris[i as usize];
        for (c, corner) in [t.v0, t.v1, t.v2].iter().enumerate() {
            for (axis, &x) in corner[..3].iter().enumerate() {
                p.v[3 * c + axis][lane] = x;
            }
        }
        p.tri[lane] = if t.is_masked() { i | PACK_MASKED } else { i };
    }
    p
}

/// A ray as the pack test takes it: the [`ShearedRay`], and its frame as arrays, with the
/// axes that become x, y and z and the origin in that order (which only the AVX2 test reads).
#[cfg_attr(not(target_arch = "x86_64"), allow(dead_code))]
struct TriRay {
    sheared: ShearedRay,
    axes: [usize; 3],
    origin: [f32; 3],
    shear: [f32; 3],
}

#[inline(always)]
fn tri_ray(ray: &Ray) -> TriRay {
    let sheared = ShearedRay::new(ray);
    let kz = sheared.kz as usize;
    let axes = [(kz + 1) % 3, (kz + 2) % 3, kz];
    let o = sheared.origin.to_array();
    TriRay {
        sheared,
        axes,
        origin: axes.map(|a| o[a]),
        shear: sheared.shear.to_array(),
    }
}

/// The lanes of a pack that `intersect_triangle` hits within the ray's extent, and each
/// lane's distance and barycentrics as it returns them (read only in the lanes of `mask`).
struct PackHits {
    mask: u32,
    t: [f32; WIDTH],
    u: [f32; WIDTH],
    v: [f32; WIDTH],
}

impl PackHits {
    const NONE: Self = Self {
        mask: 0,
        t: [0.0; WIDTH],
        u: [0.0; WIDTH],
        v: [0.0; WIDTH],
    };
}

/// A ray as the box test takes it.
struct BoxRay {
    origin: [f32; 3],
    inv_dir: [f32; 3],
}

/// The tests the traversal runs eight lanes at a time: a node's boxes and a pack's
/// triangles. Both implementations agree bit for bit.
trait WideTests {
    /// The slab test of a node's eight boxes against a ray: the mask of the boxes hit with
    /// `t_near <= t_far` and each box's `t_near`, computed as `geometry::intersect_aabb`
    /// does (the same rounding, and the same slack on `t_far`).
    fn hits(node: &WideNode, ray: &BoxRay, t_max: f32) -> (u32, [f32; WIDTH]);

    /// `intersect_triangle` with `t_max` on each lane of `pack`, bit for bit.
    fn pack_hits(pack: &TriPack, ray: &TriRay, t_max: f32) -> PackHits;
}

/// `minps`/`maxps` semantics, so that the portable test rounds as the SIMD one does.
#[inline(always)]
fn min(a: f32, b: f32) -> f32 {
    if a < b { a } else { b }
}

#[inline(always)]
fn max(a: f32, b: f32) -> f32 {
    if a > b { a } else { b }
}

/// The tests as loops over the lanes.
struct Portable;

impl WideTests for Portable {
    #[inline(always)]
    fn hits(node: &WideNode, ray: &BoxRay, t_max: f32) -> (u32, [f32; WIDTH]) {
        let mut near = [0.0; WIDTH];
        let mut mask = 0;
        for (k, near) in near.iter_mut().enumerate() {
            let slab = |axis: usize| {
                let t0 = (node.lo[axis][k] - ray.origin[axis]) * ray.inv_dir[axis];
                let t1 = (node.hi[axis][k] - ray.origin[axis]) * ray.inv_dir[axis];
                (min(t0, t1), max(t0, t1))
            };
            let ((nx, fx), (ny, fy), (nz, fz)) = (slab(0), slab(1), slab(2));
            let n = max(max(max(nx, ny), nz), 0.0);
            let f = min(min(min(min(fx, fy), fz), t_max) * SLAB_SLACK, T_INF);
            *near = n;
            mask |= ((n <= f) as u32) << k;
        }
        (mask, near)
    }

    /// The scalar test on each lane in use.
    #[inline(always)]
    fn pack_hits(pack: &TriPack, ray: &TriRay, t_max: f32) -> PackHits {
        let mut hits = PackHits::NONE;
        for l in (0..WIDTH).take_while(|&l| pack.tri[l] != u32::MAX) {
            let corner = |c: usize| {
                let v = |a: usize| pack.v[3 * c + a][l];
                [v(0), v(1), v(2), 0.0]
            };
            let tri = TriVerts {
                v0: corner(0),
                v1: corner(1),
                v2: corner(2),
            };
            if let Some(h) = intersect_triangle(&ray.sheared, &tri, t_max) {
                hits.mask |= 1 << l;
                (hits.t[l], hits.u[l], hits.v[l]) = (h.t, h.u, h.v);
            }
        }
        hits
    }
}

/// The tests in AVX registers, eight lanes at once.
#[cfg(target_arch = "x86_64")]
struct Avx2;

#[cfg(target_arch = "x86_64")]
impl WideTests for Avx2 {
    #[inline(always)]
    fn hits(node: &WideNode, ray: &BoxRay, t_max: f32) -> (u32, [f32; WIDTH]) {
        // SAFETY: only reached from `closest_avx2` and `any_avx2`, which run where the CPU
        // has AVX2.
        unsafe { hits_avx2(node, ray, t_max) }
    }

    #[inline(always)]
    fn pack_hits(pack: &TriPack, ray: &TriRay, t_max: f32) -> PackHits {
        // SAFETY: as for `hits`.
        unsafe { pack_hits_avx2(pack, ray, t_max) }
    }
}

/// `intersect_triangle` on eight triangles at once: the edge functions, the distance, the
/// rounding bound and the barycentrics, each computed in the scalar test's order of
/// operations (IEEE arithmetic rounds a lane as it rounds a scalar), so that a lane hits
/// where the scalar test hits, with the same bits.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn pack_hits_avx2(pack: &TriPack, ray: &TriRay, t_max: f32) -> PackHits {
    use crate::geometry::{GAMMA_2, GAMMA_3};
    use std::arch::x86_64::*;
    let [ax, ay, az] = ray.axes;
    let (sx, sy) = (_mm256_set1_ps(ray.shear[0]), _mm256_set1_ps(ray.shear[1]));
    let (ox, oy, oz) = (
        _mm256_set1_ps(ray.origin[0]),
        _mm256_set1_ps(ray.origin[1]),
        _mm256_set1_ps(ray.origin[2]),
    );
    // SAFETY: each load reads one whole `[f32; 8]` or `[u32; 8]`.
    let load = |row: &[f32; WIDTH]| unsafe { _mm256_loadu_ps(row.as_ptr()) };
    // A corner translated and permuted, (x, y, z), and then sheared: (x + Sx z, y + Sy z).
    let corner = |c: usize| {
        let x = _mm256_sub_ps(load(&pack.v[3 * c + ax]), ox);
        let y = _mm256_sub_ps(load(&pack.v[3 * c + ay]), oy);
        let z = _mm256_sub_ps(load(&pack.v[3 * c + az]), oz);
        let sheared = (
            _mm256_add_ps(x, _mm256_mul_ps(sx, z)),
            _mm256_add_ps(y, _mm256_mul_ps(sy, z)),
        );
        ((x, y, z), sheared)
    };
    let (a0, (p0x, p0y)) = corner(0);
    let (a1, (p1x, p1y)) = corner(1);
    let (a2, (p2x, p2y)) = corner(2);
    let e0 = _mm256_sub_ps(_mm256_mul_ps(p1x, p2y), _mm256_mul_ps(p1y, p2x));
    let e1 = _mm256_sub_ps(_mm256_mul_ps(p2x, p0y), _mm256_mul_ps(p2y, p0x));
    let e2 = _mm256_sub_ps(_mm256_mul_ps(p0x, p1y), _mm256_mul_ps(p0y, p1x));
    let zero = _mm256_setzero_ps();
    let lt = |e| _mm256_cmp_ps::<_CMP_LT_OQ>(e, zero);
    let gt = |e| _mm256_cmp_ps::<_CMP_GT_OQ>(e, zero);
    let (lt0, gt0, lt1, gt1, lt2, gt2) = (lt(e0), gt(e0), lt(e1), gt(e1), lt(e2), gt(e2));
    let reject = _mm256_or_ps(
        _mm256_or_ps(_mm256_and_ps(lt0, gt1), _mm256_and_ps(gt0, lt1)),
        _mm256_or_ps(
            _mm256_and_ps(lt2, _mm256_or_ps(gt0, gt1)),
            _mm256_and_ps(gt2, _mm256_or_ps(lt0, lt1)),
        ),
    );
    // t = (e0 Sz z0 + e1 Sz z1 + e2 Sz z2) / (e0 + e1 + e2), rounded as the scalar test
    // rounds it (a division is exact-rounded, as its `1 / det` is).
    let sz = _mm256_set1_ps(ray.shear[2]);
    let det = _mm256_add_ps(_mm256_add_ps(e0, e1), e2);
    let t_scaled = _mm256_add_ps(
        _mm256_add_ps(
            _mm256_mul_ps(e0, _mm256_mul_ps(sz, a0.2)),
            _mm256_mul_ps(e1, _mm256_mul_ps(sz, a1.2)),
        ),
        _mm256_mul_ps(e2, _mm256_mul_ps(sz, a2.2)),
    );
    let inv_det = _mm256_div_ps(_mm256_set1_ps(1.0), det);
    let t = _mm256_mul_ps(t_scaled, inv_det);
    let in_range = _mm256_and_ps(
        _mm256_cmp_ps::<_CMP_GT_OQ>(t, zero),
        _mm256_cmp_ps::<_CMP_LT_OQ>(t, _mm256_set1_ps(t_max)),
    );
    // SAFETY: as above.
    let tri = unsafe { _mm256_loadu_si256(pack.tri.as_ptr().cast()) };
    let unused = _mm256_castsi256_ps(_mm256_cmpeq_epi32(tri, _mm256_set1_epi32(-1)));
    let mut mask = _mm256_movemask_ps(_mm256_andnot_ps(_mm256_or_ps(reject, unused), in_range));
    if mask == 0 {
        return PackHits::NONE;
    }
    // The rounding bound of `edge_rounding`, term by term in its order.
    let abs = |x| _mm256_andnot_ps(_mm256_set1_ps(-0.0), x);
    let (g2, g3) = (_mm256_set1_ps(GAMMA_2), _mm256_set1_ps(GAMMA_3));
    let (asx, asy) = (abs(sx), abs(sy));
    let err = |(x, y, z): (__m256, __m256, __m256)| {
        let (x, y, z) = (abs(x), abs(y), abs(z));
        (
            _mm256_mul_ps(g3, _mm256_add_ps(x, _mm256_mul_ps(asx, z))),
            _mm256_mul_ps(g3, _mm256_add_ps(y, _mm256_mul_ps(asy, z))),
        )
    };
    let (p, d) = (
        [
            (abs(p0x), abs(p0y)),
            (abs(p1x), abs(p1y)),
            (abs(p2x), abs(p2y)),
        ],
        [err(a0), err(a1), err(a2)],
    );
    let edge = |i: usize, j: usize| {
        let ((pix, piy), (pjx, pjy)) = (p[i], p[j]);
        let ((dix, diy), (djx, djy)) = (d[i], d[j]);
        let mut r = _mm256_add_ps(_mm256_mul_ps(pjy, dix), _mm256_mul_ps(pix, djy));
        r = _mm256_add_ps(r, _mm256_mul_ps(pjx, diy));
        r = _mm256_add_ps(r, _mm256_mul_ps(piy, djx));
        let cross = _mm256_add_ps(_mm256_mul_ps(pix, pjy), _mm256_mul_ps(piy, pjx));
        _mm256_add_ps(r, _mm256_mul_ps(g2, cross))
    };
    let bound = _mm256_add_ps(_mm256_add_ps(edge(1, 2), edge(2, 0)), edge(0, 1));
    // The scalar test rejects `|det| <= bound`; a NaN bound rejects nothing.
    mask &= _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_NLE_UQ>(abs(det), bound));
    let mut hits = PackHits {
        mask: mask as u32,
        ..PackHits::NONE
    };
    // SAFETY: each store writes one whole `[f32; 8]`.
    unsafe {
        _mm256_storeu_ps(hits.t.as_mut_ptr(), t);
        _mm256_storeu_ps(hits.u.as_mut_ptr(), _mm256_mul_ps(e1, inv_det));
        _mm256_storeu_ps(hits.v.as_mut_ptr(), _mm256_mul_ps(e2, inv_det));
    }
    hits
}

/// [`Avx2`]'s test, as a function of its own so that the intrinsics inline into it.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
fn hits_avx2(node: &WideNode, ray: &BoxRay, t_max: f32) -> (u32, [f32; WIDTH]) {
    use std::arch::x86_64::*;
    // SAFETY (the loads and the store): each covers one whole `[f32; 8]`.
    let (nx, fx) = unsafe { slab_avx2(&node.lo[0], &node.hi[0], ray.origin[0], ray.inv_dir[0]) };
    let (ny, fy) = unsafe { slab_avx2(&node.lo[1], &node.hi[1], ray.origin[1], ray.inv_dir[1]) };
    let (nz, fz) = unsafe { slab_avx2(&node.lo[2], &node.hi[2], ray.origin[2], ray.inv_dir[2]) };
    let n = _mm256_max_ps(
        _mm256_max_ps(_mm256_max_ps(nx, ny), nz),
        _mm256_setzero_ps(),
    );
    let far = _mm256_min_ps(
        _mm256_min_ps(_mm256_min_ps(fx, fy), fz),
        _mm256_set1_ps(t_max),
    );
    let f = _mm256_min_ps(
        _mm256_mul_ps(far, _mm256_set1_ps(SLAB_SLACK)),
        _mm256_set1_ps(T_INF),
    );
    let mask = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(n, f)) as u32;
    let mut near = [0.0; WIDTH];
    unsafe { _mm256_storeu_ps(near.as_mut_ptr(), n) };
    (mask, near)
}

/// One axis of [`hits_avx2`]: each box's entry and exit distance along it.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn slab_avx2(
    lo: &[f32; WIDTH],
    hi: &[f32; WIDTH],
    origin: f32,
    inv_dir: f32,
) -> (std::arch::x86_64::__m256, std::arch::x86_64::__m256) {
    use std::arch::x86_64::*;
    let o = _mm256_set1_ps(origin);
    let inv = _mm256_set1_ps(inv_dir);
    // SAFETY: the caller's; `lo` and `hi` are eight floats each.
    let (lo, hi) = unsafe { (_mm256_loadu_ps(lo.as_ptr()), _mm256_loadu_ps(hi.as_ptr())) };
    let t0 = _mm256_mul_ps(_mm256_sub_ps(lo, o), inv);
    let t1 = _mm256_mul_ps(_mm256_sub_ps(hi, o), inv);
    (_mm256_min_ps(t0, t1), _mm256_max_ps(t0, t1))
}

/// A child waiting on the stack: a node or a leaf, and where the ray enters its box.
#[derive(Clone, Copy)]
struct Entry {
    child: u32,
    count: u32,
    t: f32,
}

/// Each level pushes at most `WIDTH - 1` children, and the wide tree is no deeper than the
/// binary one.
const STACK: usize = (WIDTH - 1) * STACK_SIZE + 1;

/// A traversal stack that is not initialised: entries are read only below `len`.
struct Stack {
    entries: [MaybeUninit<Entry>; STACK],
    len: usize,
}

impl Stack {
    #[inline(always)]
    fn new() -> Self {
        Self {
            entries: [const { MaybeUninit::uninit() }; STACK],
            len: 0,
        }
    }

    #[inline(always)]
    fn push(&mut self, e: Entry) {
        self.entries[self.len] = MaybeUninit::new(e);
        self.len += 1;
    }

    #[inline(always)]
    fn pop(&mut self) -> Option<Entry> {
        self.len = self.len.checked_sub(1)?;
        // SAFETY: every slot below the old length was written by `push`.
        Some(unsafe { self.entries[self.len].assume_init() })
    }
}

#[inline(always)]
fn box_ray(ray: &Ray) -> BoxRay {
    BoxRay {
        origin: ray.origin.to_array(),
        inv_dir: safe_inverse(ray.dir).to_array(),
    }
}

#[inline(always)]
fn entry(node: &WideNode, k: usize, t: f32) -> Entry {
    Entry {
        child: node.child[k],
        count: node.count[k],
        t,
    }
}

#[inline(always)]
fn closest<B: WideTests>(
    bvh: &WideBvh,
    ray: &Ray,
    t_max: f32,
    mut accept: impl FnMut(u32, f32, f32) -> bool,
) -> Option<Hit> {
    if bvh.nodes.is_empty() {
        return None;
    }
    let tr = tri_ray(ray);
    let r = box_ray(ray);
    let mut best = None;
    let mut t_best = t_max;
    let mut stack = Stack::new();
    let mut cur = Entry {
        child: 0,
        count: 0,
        t: 0.0,
    };
    loop {
        if cur.count > 0 {
            for pack in &bvh.packs[cur.child as usize..(cur.child + cur.count) as usize] {
                let hits = B::pack_hits(pack, &tr, t_best);
                let mut lanes = hits.mask;
                // In lane order, each against the nearest hit so far, as the scalar test
                // would be called.
                while lanes != 0 {
                    let l = lanes.trailing_zeros() as usize;
                    lanes &= lanes - 1;
                    let (t, u, v) = (hits.t[l], hits.u[l], hits.v[l]);
                    let i = pack.tri[l] & !PACK_MASKED;
                    if t < t_best && (pack.tri[l] & PACK_MASKED == 0 || accept(i, u, v)) {
                        t_best = t;
                        best = Some(Hit { t, u, v, tri: i });
                    }
                }
            }
        } else {
            let node = &bvh.nodes[cur.child as usize];
            let (mut mask, near) = B::hits(node, &r, t_best);
            if mask != 0 {
                let first = mask.trailing_zeros() as usize;
                mask &= mask - 1;
                if mask == 0 {
                    cur = entry(node, first, near[first]);
                    continue;
                }
                // Two or more: sort by entry distance, go on with the nearest and push the
                // others farthest first.
                let mut order = [0usize; WIDTH];
                let mut n = 0;
                let mut m = mask | (1 << first);
                while m != 0 {
                    let k = m.trailing_zeros() as usize;
                    m &= m - 1;
                    let mut j = n;
                    while j > 0 && near[order[j - 1]] < near[k] {
                        order[j] = order[j - 1];
                        j -= 1;
                    }
                    order[j] = k;
                    n += 1;
                }
                for &k in &order[..n - 1] {
                    stack.push(entry(node, k, near[k]));
                }
                let k = order[n - 1];
                cur = entry(node, k, near[k]);
                continue;
            }
        }
        // The next child whose box still starts before the nearest hit (with the slab
        // test's slack, so that no box the test would accept is skipped).
        let bound = min(t_best * SLAB_SLACK, T_INF);
        loop {
            let Some(e) = stack.pop() else {
                return best;
            };
            if e.t <= bound {
                cur = e;
                break;
            }
        }
    }
}

#[inline(always)]
fn any<B: WideTests>(
    bvh: &WideBvh,
    ray: &Ray,
    t_max: f32,
    mut accept: impl FnMut(u32, f32, f32) -> bool,
) -> bool {
    if bvh.nodes.is_empty() {
        return false;
    }
    let tr = tri_ray(ray);
    let r = box_ray(ray);
    let mut stack = Stack::new();
    let mut cur = Entry {
        child: 0,
        count: 0,
        t: 0.0,
    };
    loop {
        if cur.count > 0 {
            for pack in &bvh.packs[cur.child as usize..(cur.child + cur.count) as usize] {
                let hits = B::pack_hits(pack, &tr, t_max);
                let mut lanes = hits.mask;
                while lanes != 0 {
                    let l = lanes.trailing_zeros() as usize;
                    lanes &= lanes - 1;
                    let i = pack.tri[l] & !PACK_MASKED;
                    if pack.tri[l] & PACK_MASKED == 0 || accept(i, hits.u[l], hits.v[l]) {
                        return true;
                    }
                }
            }
        } else {
            let node = &bvh.nodes[cur.child as usize];
            let (mut mask, near) = B::hits(node, &r, t_max);
            while mask != 0 {
                let k = mask.trailing_zeros() as usize;
                mask &= mask - 1;
                stack.push(entry(node, k, near[k]));
            }
        }
        let Some(e) = stack.pop() else {
            return false;
        };
        cur = e;
    }
}
