//! Binned SAH construction (Wald 2007, "On fast Construction of SAH-based Bounding Volume
//! Hierarchies") over triangle boxes partitioned in place, laid out depth-first as
//! [`BvhNode`]s.

use super::{Bvh, BvhNode, BvhStats};
use crate::math::Aabb;
use glam::Vec3A;
use rayon::prelude::*;

/// How to build: bin count and the SAH's cost model. Leaf sizes are not fixed: a node
/// becomes a leaf when the SAH says splitting would cost more.
#[derive(Clone, Debug, PartialEq)]
pub struct BuildParams {
    /// Bins per axis for the split search, at most [`MAX_BINS`].
    pub bins: usize,
    /// Cost of visiting an interior node, relative to `intersect_cost`.
    pub traversal_cost: f32,
    /// Cost of one ray–triangle test.
    pub intersect_cost: f32,
    /// Leaves never hold more than this, whatever the SAH prefers.
    pub max_leaf_size: usize,
    /// Give a node of `n` triangles only `max(n, 4)` bins when that is fewer: most of the
    /// others would stay empty, and the sweep over them dominates small nodes.
    pub shrink_bins: bool,
    /// Nodes of at most this many triangles try every split of their centroids sorted
    /// along each axis instead of binning: exact, and cheaper than bins at that size.
    /// 0 turns it off.
    pub exact_below: usize,
    /// Nodes of at least 16384 triangles choose their split from bins of an even sample
    /// of 4096 to 8191 of them, which places the plane as well at a fraction of the cost.
    pub sample: bool,
}

impl BuildParams {
    /// The default: 16 bins per axis (fewer for small nodes), exact splits for nodes of
    /// up to 8 triangles, sampled binning for large ones. Its SAH cost stays within 1% of
    /// [`BuildParams::precise`]'s on the meshes the tests and the bench build.
    pub fn fast() -> Self {
        Self {
            bins: 16,
            traversal_cost: 1.0,
            intersect_cost: 1.0,
            max_leaf_size: 16,
            shrink_bins: true,
            exact_below: 8,
            sample: true,
        }
    }

    /// 32 bins per axis at every node, every triangle binned: a slower build, the
    /// baseline the fast one is measured against.
    pub fn precise() -> Self {
        Self {
            bins: 32,
            shrink_bins: false,
            exact_below: 0,
            sample: false,
            ..Self::fast()
        }
    }
}

impl Default for BuildParams {
    fn default() -> Self {
        Self::fast()
    }
}

/// Subtrees of at least this many triangles fork into two parallel tasks, each building
/// its own [`Part`].
const PARALLEL_THRESHOLD: usize = 4096;

/// The most bins [`BuildParams::bins`] may ask for; the bins live on the stack.
pub const MAX_BINS: usize = 32;

/// A triangle's box as the builder moves it: SIMD-friendly and partitioned in place, so
/// every pass over a node reads memory in order.
#[derive(Clone, Copy)]
struct PrimRef {
    min: Vec3A,
    max: Vec3A,
}

impl PrimRef {
    const EMPTY: PrimRef = PrimRef {
        min: Vec3A::INFINITY,
        max: Vec3A::NEG_INFINITY,
    };

    /// Twice the centroid: binning needs only its order.
    fn centroid2(&self) -> Vec3A {
        self.min + self.max
    }
}

/// A box and a box holding the doubled centroids of what it holds (the tightest one, or
/// a looser one derived from the parent's; it only places the bins).
#[derive(Clone, Copy)]
struct Bounds {
    min: Vec3A,
    max: Vec3A,
    cmin: Vec3A,
    cmax: Vec3A,
}

impl Bounds {
    const EMPTY: Bounds = Bounds {
        min: Vec3A::INFINITY,
        max: Vec3A::NEG_INFINITY,
        cmin: Vec3A::INFINITY,
        cmax: Vec3A::NEG_INFINITY,
    };

    fn grow(&mut self, r: &PrimRef) {
        self.min = self.min.min(r.min);
        self.max = self.max.max(r.max);
        let c = r.centroid2();
        self.cmin = self.cmin.min(c);
        self.cmax = self.cmax.max(c);
    }

    fn union(self, o: Bounds) -> Bounds {
        Bounds {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
            cmin: self.cmin.min(o.cmin),
            cmax: self.cmax.max(o.cmax),
        }
    }

    fn of(refs: &[PrimRef]) -> Bounds {
        let mut b = Bounds::EMPTY;
        refs.iter().for_each(|r| b.grow(r));
        b
    }
}

fn area(min: Vec3A, max: Vec3A) -> f32 {
    let e = (max - min).max(Vec3A::ZERO);
    2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
}

/// Builds the tree. Large subtrees are built by parallel tasks into their own arrays,
/// which are then copied once into the depth-first layout, in parallel too.
pub fn build(bounds: &[Aabb], params: &BuildParams) -> Bvh {
    let n = bounds.len();
    let mut stats = BvhStats {
        triangles: n,
        ..Default::default()
    };
    if n == 0 {
        let nodes = vec![BvhNode::default()];
        stats.nodes = 1;
        stats.leaves = 1;
        stats.leaf_sizes = vec![1];
        return Bvh {
            nodes,
            order: Vec::new(),
            stats,
        };
    }
    let mut refs: Vec<PrimRef> = bounds
        .par_iter()
        .map(|b| PrimRef {
            min: b.min.into(),
            max: b.max.into(),
        })
        .collect();
    let mut order: Vec<u32> = (0..n as u32).into_par_iter().collect();
    let root = refs
        .par_chunks(PARALLEL_THRESHOLD)
        .map(Bounds::of)
        .reduce(|| Bounds::EMPTY, Bounds::union);
    let ctx = Context {
        params: &BuildParams {
            exact_below: params.exact_below.min(EXACT_MAX),
            ..params.clone()
        },
        bins: params.bins.clamp(2, MAX_BINS),
    };
    let part = build_part(&ctx, &mut refs, &mut order, root, 0);
    drop(refs);
    let mut nodes = bytemuck::zeroed_vec(part.len());
    let tally = part.write(&mut nodes, 0, 0, params);
    drop(part);
    let root_area = f64::from(nodes[0].bounds().area()).max(f64::from(f32::MIN_POSITIVE));
    stats.nodes = nodes.len();
    stats.leaves = tally.leaves;
    stats.leaf_sizes = tally.leaf_sizes;
    stats.depth = tally.depth;
    stats.sah_cost = (tally.cost / root_area) as f32;
    Bvh {
        nodes,
        order,
        stats,
    }
}

struct Context<'a> {
    params: &'a BuildParams,
    bins: usize,
}

#[derive(Clone, Copy)]
struct Bin {
    min: Vec3A,
    max: Vec3A,
    count: u32,
}

const EMPTY_BIN: Bin = Bin {
    min: Vec3A::INFINITY,
    max: Vec3A::NEG_INFINITY,
    count: 0,
};

/// Nodes of at least this many triangles bin them in parallel.
const PARALLEL_BINNING: usize = 1 << 16;

/// The bins of two sets of triangles, as one.
fn merge_bins<const N: usize>(mut a: [[Bin; N]; 3], b: [[Bin; N]; 3]) -> [[Bin; N]; 3] {
    for (a, b) in a.iter_mut().flatten().zip(b.iter().flatten()) {
        a.min = a.min.min(b.min);
        a.max = a.max.max(b.max);
        a.count += b.count;
    }
    a
}

/// A chosen split: the axis, the first bin of the right side, and what the bins know of
/// both sides.
struct Split {
    axis: usize,
    bin: usize,
    /// The bin scale along `axis`, which the partition's test must share with binning.
    scale: f32,
    /// `None` where the bins held only a sample of the triangles.
    sides: Option<Sides>,
}

/// The boxes of both sides of a split, from bins that held every triangle.
struct Sides {
    left: (Vec3A, Vec3A),
    right: (Vec3A, Vec3A),
    /// Triangles on the left, which the partition must reproduce: the boxes above hold
    /// exactly the triangles the bins counted.
    left_count: usize,
}

/// Nodes of at least four times this many triangles bin only this many (or up to twice
/// as many), evenly spaced: enough to place the plane as well as all of them would.
const SAMPLES: usize = 4096;

/// A built subtree: its nodes depth-first, or, where the build forked into two tasks, its
/// root and the two parts the tasks built. [`Part::write`] joins them into one array.
enum Part {
    /// Interior nodes link to their second child by index from the first node here.
    Nodes(Vec<BvhNode>),
    Fork {
        root: BvhNode,
        children: Box<[Part; 2]>,
        len: usize,
    },
}

impl Part {
    fn len(&self) -> usize {
        match self {
            Part::Nodes(nodes) => nodes.len(),
            Part::Fork { len, .. } => *len,
        }
    }

    /// Writes the part into `out` (exactly its length), which begins at node `base` of
    /// the final array, and tallies it; its root is at `depth`.
    fn write(&self, out: &mut [BvhNode], base: u32, depth: u32, p: &BuildParams) -> Tally {
        match self {
            Part::Nodes(nodes) => {
                for (dst, src) in out.iter_mut().zip(nodes) {
                    *dst = *src;
                    if !src.is_leaf() {
                        dst.left_or_first += base;
                    }
                }
                Tally::of(nodes, depth, p)
            }
            Part::Fork { root, children, .. } => {
                let [left, right] = &**children;
                let (first, rest) = out.split_at_mut(1);
                let (lo, ro) = rest.split_at_mut(left.len());
                let right_base = base + 1 + left.len() as u32;
                first[0] = BvhNode {
                    left_or_first: right_base,
                    ..*root
                };
                let mut tally = Tally::default();
                tally.add(root, depth, p);
                let (l, r) = rayon::join(
                    || left.write(lo, base + 1, depth + 1, p),
                    || right.write(ro, right_base, depth + 1, p),
                );
                tally.merge(l).merge(r)
            }
        }
    }
}

/// Builds the subtree over `refs` (with their input indices in `ids`; the first sits at
/// leaf position `offset`), forking into parallel tasks while it is large.
fn build_part(
    ctx: &Context,
    refs: &mut [PrimRef],
    ids: &mut [u32],
    b: Bounds,
    offset: u32,
) -> Part {
    let n = refs.len();
    if n < PARALLEL_THRESHOLD {
        let mut nodes = Vec::with_capacity(2 * n - 1);
        build_nodes(ctx, refs, ids, b, offset, &mut nodes);
        return Part::Nodes(nodes);
    }
    let Some((split_at, left, right)) = split_node(ctx, refs, ids, &b) else {
        return Part::Nodes(vec![leaf_node(&b, offset, n)]);
    };
    let (lr, rr) = refs.split_at_mut(split_at);
    let (li, ri) = ids.split_at_mut(split_at);
    let right_offset = offset + split_at as u32;
    let (l, r) = rayon::join(
        || build_part(ctx, lr, li, left, offset),
        || build_part(ctx, rr, ri, right, right_offset),
    );
    Part::Fork {
        root: interior_node(&b),
        len: 1 + l.len() + r.len(),
        children: Box::new([l, r]),
    }
}

/// [`build_part`] on one thread, appending the subtree's nodes depth-first to `out`.
fn build_nodes(
    ctx: &Context,
    refs: &mut [PrimRef],
    ids: &mut [u32],
    b: Bounds,
    offset: u32,
    out: &mut Vec<BvhNode>,
) {
    let n = refs.len();
    let Some((split_at, left, right)) = split_node(ctx, refs, ids, &b) else {
        return out.push(leaf_node(&b, offset, n));
    };
    let index = out.len();
    out.push(interior_node(&b));
    let (lr, rr) = refs.split_at_mut(split_at);
    let (li, ri) = ids.split_at_mut(split_at);
    build_nodes(ctx, lr, li, left, offset, out);
    out[index].left_or_first = out.len() as u32;
    build_nodes(ctx, rr, ri, right, offset + split_at as u32, out);
}

fn leaf_node(b: &Bounds, offset: u32, n: usize) -> BvhNode {
    BvhNode {
        min: b.min.into(),
        max: b.max.into(),
        left_or_first: offset,
        count: n as u32,
    }
}

/// An interior node; its link to the second child is filled in once that is placed.
fn interior_node(b: &Bounds) -> BvhNode {
    BvhNode {
        min: b.min.into(),
        max: b.max.into(),
        left_or_first: 0,
        count: 0,
    }
}

/// How a node splits: the left count and both sides' bounds, with `refs` and `ids`
/// partitioned to match; `None` when it stays a leaf.
fn split_node(
    ctx: &Context,
    refs: &mut [PrimRef],
    ids: &mut [u32],
    b: &Bounds,
) -> Option<(usize, Bounds, Bounds)> {
    match refs.len() {
        1 => None,
        n if n <= ctx.params.exact_below => exact_split(ctx.params, refs, ids, b),
        _ => binned_split(ctx, refs, ids, b),
    }
}

/// The binned split of a node, partitioned: the left count and both sides' bounds, or
/// `None` when the node should stay a leaf.
fn binned_split(
    ctx: &Context,
    refs: &mut [PrimRef],
    ids: &mut [u32],
    b: &Bounds,
) -> Option<(usize, Bounds, Bounds)> {
    let p = ctx.params;
    let n = refs.len();
    match find_split(ctx, refs, b) {
        Some((cost, split)) if cost < p.intersect_cost * n as f32 || n > p.max_leaf_size => {
            Some(partition(refs, ids, b, &split))
        }
        Some(_) => None,
        // All centroids coincide: no plane separates them.
        None if n <= p.max_leaf_size => None,
        None => {
            let half = n / 2;
            Some((half, Bounds::of(&refs[..half]), Bounds::of(&refs[half..])))
        }
    }
}

/// The most triangles [`BuildParams::exact_below`] may name.
const EXACT_MAX: usize = 8;

/// The best split of a small node over every prefix of its centroids sorted along each
/// axis, applied to `refs` and `ids` like [`binned_split`]. Every binned split is one of
/// these candidates, so the result is never worse than binning's.
fn exact_split(
    p: &BuildParams,
    refs: &mut [PrimRef],
    ids: &mut [u32],
    b: &Bounds,
) -> Option<(usize, Bounds, Bounds)> {
    let n = refs.len();
    debug_assert!((2..=EXACT_MAX).contains(&n));
    let parent_area = area(b.min, b.max).max(f32::MIN_POSITIVE);
    let splits = |cost: f32| {
        p.traversal_cost + p.intersect_cost * cost / parent_area < p.intersect_cost * n as f32
            || n > p.max_leaf_size
    };
    if let [l, r] = refs {
        // One way to split two, whatever the axis; nothing to sort or reorder.
        let cost = area(l.min, l.max) + area(r.min, r.max);
        let side = |r| Bounds::of(std::slice::from_ref(r));
        return splits(cost).then(|| (1, side(l), side(r)));
    }
    // (area-weighted cost, order along the axis, left count)
    let mut best: Option<(f32, [usize; EXACT_MAX], usize)> = None;
    let identity: [usize; EXACT_MAX] = std::array::from_fn(|i| i);
    let centroids: [Vec3A; EXACT_MAX] =
        std::array::from_fn(|i| refs.get(i).map_or(Vec3A::ZERO, PrimRef::centroid2));
    for axis in [0, 1, 2] {
        let mut order = identity;
        // Insertion sort: stable, and the fastest at this size.
        for i in 1..n {
            let mut j = i;
            while j > 0 && centroids[order[j - 1]][axis] > centroids[order[j]][axis] {
                order.swap(j - 1, j);
                j -= 1;
            }
        }
        let mut right_cost = [0.0f32; EXACT_MAX];
        let (mut min, mut max) = (Vec3A::INFINITY, Vec3A::NEG_INFINITY);
        for k in (1..n).rev() {
            min = min.min(refs[order[k]].min);
            max = max.max(refs[order[k]].max);
            right_cost[k] = area(min, max) * (n - k) as f32;
        }
        let (mut min, mut max) = (Vec3A::INFINITY, Vec3A::NEG_INFINITY);
        for k in 1..n {
            min = min.min(refs[order[k - 1]].min);
            max = max.max(refs[order[k - 1]].max);
            let cost = area(min, max) * k as f32 + right_cost[k];
            if best.as_ref().is_none_or(|(c, ..)| cost < *c) {
                best = Some((cost, order, k));
            }
        }
    }
    let (cost, order, split_at) = best?;
    if !splits(cost) {
        return None;
    }
    if order != identity {
        let mut old_refs = [PrimRef::EMPTY; EXACT_MAX];
        let mut old_ids = [0u32; EXACT_MAX];
        old_refs[..n].copy_from_slice(refs);
        old_ids[..n].copy_from_slice(ids);
        for (k, &i) in order[..n].iter().enumerate() {
            refs[k] = old_refs[i];
            ids[k] = old_ids[i];
        }
    }
    Some((
        split_at,
        Bounds::of(&refs[..split_at]),
        Bounds::of(&refs[split_at..]),
    ))
}

/// Which bin of each axis a doubled centroid falls in. Clamped as floats, by one SIMD min
/// and max, rather than as integers lane by lane.
#[inline]
fn bin_index(c: Vec3A, b: &Bounds, scale: Vec3A, bins: usize) -> [usize; 3] {
    let k = ((c - b.cmin) * scale).clamp(Vec3A::ZERO, Vec3A::splat((bins - 1) as f32));
    truncate(k)
}

/// `k` truncated lane by lane; `k` is in `0..MAX_BINS`. On x86-64 one instruction
/// converts all lanes, where `as` would convert them one by one and test each for
/// saturation.
#[inline]
fn truncate(k: Vec3A) -> [usize; 3] {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{__m128, _mm_cvttps_epi32};
        // SAFETY: SSE2 is part of every x86-64 target.
        let k: [i32; 4] = bytemuck::cast(unsafe { _mm_cvttps_epi32(__m128::from(k)) });
        [k[0] as usize, k[1] as usize, k[2] as usize]
    }
    #[cfg(not(target_arch = "x86_64"))]
    [k.x as usize, k.y as usize, k.z as usize]
}

/// Per-axis bin scale; an axis whose centroids all coincide gets 0 (everything in bin 0).
fn bin_scale(b: &Bounds, bins: usize) -> Vec3A {
    let extent = b.cmax - b.cmin;
    Vec3A::select(
        extent.cmpgt(Vec3A::ZERO),
        Vec3A::splat(bins as f32) / extent,
        Vec3A::ZERO,
    )
}

/// Bins for a node of `n` triangles (see [`BuildParams::shrink_bins`]).
fn bins_for(ctx: &Context, n: usize) -> usize {
    if ctx.params.shrink_bins {
        ctx.bins.min(n.max(4))
    } else {
        ctx.bins
    }
}

/// The cheapest binned split and its SAH cost.
fn find_split(ctx: &Context, refs: &[PrimRef], b: &Bounds) -> Option<(f32, Split)> {
    // The bins live on the stack and must be initialised; sizing them to the node keeps
    // that cost from dominating small nodes.
    match bins_for(ctx, refs.len()) {
        nb if nb <= 8 => find_split_in::<8>(ctx, refs, b, nb),
        nb if nb <= 16 => find_split_in::<16>(ctx, refs, b, nb),
        nb => find_split_in::<MAX_BINS>(ctx, refs, b, nb),
    }
}

fn find_split_in<const N: usize>(
    ctx: &Context,
    refs: &[PrimRef],
    b: &Bounds,
    nb: usize,
) -> Option<(f32, Split)> {
    let p = ctx.params;
    let scale = bin_scale(b, nb);
    let fill = |bins: &mut [[Bin; N]; 3], refs: &mut dyn Iterator<Item = &PrimRef>| {
        for r in refs {
            let k = bin_index(r.centroid2(), b, scale, nb);
            for (axis, &k) in k.iter().enumerate() {
                // k < nb <= N, a power of two: the mask only drops the bounds check.
                let bin = &mut bins[axis][k & (N - 1)];
                bin.min = bin.min.min(r.min);
                bin.max = bin.max.max(r.max);
                bin.count += 1;
            }
        }
    };
    // Large nodes bin an even sample of their triangles; the rest bin in parallel at the
    // top, or the first levels would leave threads idle.
    let sampled = ctx.params.sample && refs.len() >= 4 * SAMPLES;
    let stride = if sampled { refs.len() / SAMPLES } else { 1 };
    let mut bins = [[EMPTY_BIN; N]; 3];
    if !sampled && refs.len() >= PARALLEL_BINNING {
        bins = refs
            .par_chunks(PARALLEL_BINNING / 4)
            .map(|chunk| {
                let mut bins = [[EMPTY_BIN; N]; 3];
                fill(&mut bins, &mut chunk.iter());
                bins
            })
            .reduce(|| [[EMPTY_BIN; N]; 3], merge_bins);
    } else {
        fill(&mut bins, &mut refs.iter().step_by(stride));
    }
    // Costs are compared as area-weighted counts; the SAH's constants apply at the end.
    // The three axes sweep together, one SIMD lane each.
    let n = refs.len().div_ceil(stride) as u32;
    let mut right_cost = [Vec3A::ZERO; N];
    let mut side = Side::EMPTY;
    for k in (1..nb).rev() {
        side.grow([&bins[0][k], &bins[1][k], &bins[2][k]]);
        right_cost[k] = side.cost();
    }
    let (mut best, mut best_bin) = (Vec3A::INFINITY, [0usize; 3]);
    let mut side = Side::EMPTY;
    for k in 1..nb {
        side.grow([&bins[0][k - 1], &bins[1][k - 1], &bins[2][k - 1]]);
        // A plane with everything on one side splits nothing.
        let valid = side.count.map(|c| c != 0 && c != n);
        let cost = side.cost() + right_cost[k];
        for axis in 0..3 {
            if valid[axis] && cost[axis] < best[axis] {
                best[axis] = cost[axis];
                best_bin[axis] = k;
            }
        }
    }
    // The first axis wins ties, as a sweep axis by axis would have it.
    let axis = (0..3).fold(0, |a, i| if best[i] < best[a] { i } else { a });
    let (cost, bin) = (best[axis], best_bin[axis]);
    if cost == f32::INFINITY {
        return None;
    }
    let union = |bins: &[Bin]| {
        bins.iter()
            .fold((Vec3A::INFINITY, Vec3A::NEG_INFINITY), |(min, max), b| {
                (min.min(b.min), max.max(b.max))
            })
    };
    let parent_area = area(b.min, b.max).max(f32::MIN_POSITIVE);
    let split = Split {
        axis,
        bin,
        scale: scale[axis],
        sides: (!sampled).then(|| Sides {
            left: union(&bins[axis][..bin]),
            right: union(&bins[axis][bin..nb]),
            left_count: bins[axis][..bin].iter().map(|b| b.count as usize).sum(),
        }),
    };
    // A sample's costs count each triangle for `stride`.
    let cost = cost * (refs.len() as f32 / n as f32);
    Some((
        p.traversal_cost + p.intersect_cost * cost / parent_area,
        split,
    ))
}

/// One side of a plane in each axis's sweep: the union of the bins passed so far.
struct Side {
    min: [Vec3A; 3],
    max: [Vec3A; 3],
    count: [u32; 3],
}

impl Side {
    const EMPTY: Side = Side {
        min: [Vec3A::INFINITY; 3],
        max: [Vec3A::NEG_INFINITY; 3],
        count: [0; 3],
    };

    fn grow(&mut self, bins: [&Bin; 3]) {
        for (axis, bin) in bins.into_iter().enumerate() {
            self.min[axis] = self.min[axis].min(bin.min);
            self.max[axis] = self.max[axis].max(bin.max);
            self.count[axis] += bin.count;
        }
    }

    /// Area times count for each axis's side, in the lane of that axis.
    fn cost(&self) -> Vec3A {
        let [e0, e1, e2] = std::array::from_fn(|a| (self.max[a] - self.min[a]).max(Vec3A::ZERO));
        let x = Vec3A::new(e0.x, e1.x, e2.x);
        let y = Vec3A::new(e0.y, e1.y, e2.y);
        let z = Vec3A::new(e0.z, e1.z, e2.z);
        let count = Vec3A::new(
            self.count[0] as f32,
            self.count[1] as f32,
            self.count[2] as f32,
        );
        2.0 * (x * y + y * z + z * x) * count
    }
}

/// Moves the triangles left of the split to the front (ids alongside); returns their
/// count and the bounds of both sides. Where the bins held every triangle, the boxes come
/// from them and each side's centroid bounds are the parent's clipped to (twice) that
/// side's box, which holds every centroid of it: looser than a pass over the triangles
/// would find, and that pass is saved. After a sampled split, a pass measures both sides.
fn partition(
    refs: &mut [PrimRef],
    ids: &mut [u32],
    b: &Bounds,
    split: &Split,
) -> (usize, Bounds, Bounds) {
    let (axis, scale, cmin, bin) = (
        split.axis,
        split.scale,
        b.cmin[split.axis],
        split.bin as f32,
    );
    // `bin_index` on one axis with the same arithmetic, so the counts match the bins'.
    // Its clamp and truncation change nothing here: below 0 stays below `bin`, above the
    // last bin stays at or above it, and truncation keeps `k < bin` for whole `bin`.
    let goes_left = |r: &PrimRef| ((r.min[axis] + r.max[axis]) - cmin) * scale < bin;
    let left = if refs.len() <= BRANCH_FREE_PARTITION {
        // Swap every triangle, advance by the test: no branch on data to mispredict.
        let mut j = 0;
        for i in 0..refs.len() {
            let left = goes_left(&refs[i]);
            refs.swap(i, j);
            ids.swap(i, j);
            j += usize::from(left);
        }
        j
    } else {
        // Hoare's scheme moves only the triangles on the wrong side.
        let (mut i, mut j) = (0, refs.len());
        loop {
            while i < j && goes_left(&refs[i]) {
                i += 1;
            }
            while i < j && !goes_left(&refs[j - 1]) {
                j -= 1;
            }
            if i + 1 >= j {
                break i;
            }
            refs.swap(i, j - 1);
            ids.swap(i, j - 1);
            i += 1;
            j -= 1;
        }
    };
    let Some(sides) = &split.sides else {
        let (l, r) = refs.split_at(left);
        let (lb, rb) = rayon::join(|| Bounds::of(l), || Bounds::of(r));
        return (left, lb, rb);
    };
    let side = |(min, max): (Vec3A, Vec3A)| Bounds {
        min,
        max,
        cmin: b.cmin.max(2.0 * min),
        cmax: b.cmax.min(2.0 * max),
    };
    debug_assert_eq!(left, sides.left_count, "partition and bins disagree");
    (left, side(sides.left), side(sides.right))
}

/// Nodes of at most this many triangles partition without branches: in small nodes the
/// sides interleave and a branch on each test mispredicts often (5-8% faster on the
/// bunny, neutral on the terrain, whose order is coherent).
const BRANCH_FREE_PARTITION: usize = 256;

/// What [`BvhStats`] counts, over one part of the tree; parts are tallied in parallel as
/// they are written, then merged.
#[derive(Default)]
struct Tally {
    leaves: usize,
    leaf_sizes: Vec<usize>,
    depth: u32,
    /// SAH cost times the root's area.
    cost: f64,
}

impl Tally {
    fn add(&mut self, node: &BvhNode, depth: u32, p: &BuildParams) {
        self.depth = self.depth.max(depth);
        let area = f64::from(node.bounds().area());
        if node.is_leaf() {
            self.leaves += 1;
            self.cost += area * f64::from(p.intersect_cost) * f64::from(node.count);
            let c = node.count as usize;
            if self.leaf_sizes.len() <= c {
                self.leaf_sizes.resize(c + 1, 0);
            }
            self.leaf_sizes[c] += 1;
        } else {
            self.cost += area * f64::from(p.traversal_cost);
        }
    }

    /// The tally of `nodes`, a depth-first subtree whose root is at `depth`.
    fn of(nodes: &[BvhNode], depth: u32, p: &BuildParams) -> Tally {
        let mut tally = Tally::default();
        let mut stack: Vec<(usize, u32)> = vec![(0, depth)];
        while let Some((index, depth)) = stack.pop() {
            let node = &nodes[index];
            tally.add(node, depth, p);
            if !node.is_leaf() {
                stack.push((node.left_or_first as usize, depth + 1));
                stack.push((index + 1, depth + 1));
            }
        }
        tally
    }

    fn merge(mut self, o: Tally) -> Tally {
        self.leaves += o.leaves;
        if self.leaf_sizes.len() < o.leaf_sizes.len() {
            self.leaf_sizes.resize(o.leaf_sizes.len(), 0);
        }
        for (a, b) in self.leaf_sizes.iter_mut().zip(&o.leaf_sizes) {
            *a += b;
        }
        self.depth = self.depth.max(o.depth);
        self.cost += o.cost;
        self
    }
}
