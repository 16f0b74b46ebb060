//! Binned SAH construction (Wald 2007, "On fast Construction of SAH-based Bounding Volume
//! Hierarchies") over triangle boxes partitioned in place, then a depth-first compaction
//! into [`BvhNode`]s.

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
}

impl BuildParams {
    /// The default: 16 bins per axis.
    pub fn fast() -> Self {
        Self {
            bins: 16,
            traversal_cost: 1.0,
            intersect_cost: 1.0,
            max_leaf_size: 16,
            shrink_bins: true,
        }
    }

    /// 32 bins per axis at every node: a slower build, the baseline the fast one is
    /// measured against.
    pub fn precise() -> Self {
        Self {
            bins: 32,
            shrink_bins: false,
            ..Self::fast()
        }
    }
}

impl Default for BuildParams {
    fn default() -> Self {
        Self::fast()
    }
}

/// Subtrees of at least this many triangles are built in parallel.
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
    /// Twice the centroid: binning needs only its order.
    fn centroid2(&self) -> Vec3A {
        self.min + self.max
    }
}

/// A box and the box of the doubled centroids of what it holds.
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

/// Builds the tree. Each subtree of `n` triangles owns `2n - 1` node slots, enough for
/// any shape, so subtrees are written in parallel without coordination; [`compact`] then
/// lays the used slots out depth-first.
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
    let mut order: Vec<u32> = (0..n as u32).collect();
    let root = refs
        .par_chunks(PARALLEL_THRESHOLD)
        .map(Bounds::of)
        .reduce(|| Bounds::EMPTY, Bounds::union);
    let mut slots = vec![BvhNode::default(); 2 * n - 1];
    let ctx = Context {
        params,
        bins: params.bins.clamp(2, MAX_BINS),
    };
    build_node(&ctx, &mut refs, &mut order, root, 0, &mut slots);
    drop(refs);
    let nodes = compact(&slots, &mut stats, params);
    stats.nodes = nodes.len();
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

/// A chosen split: the axis and the first bin of the right side.
struct Split {
    axis: usize,
    bin: usize,
}

/// Builds the subtree over `refs` (with their input indices in `ids`; the first sits at
/// leaf position `offset`) into `slots`, whose first entry is the subtree's root.
fn build_node(
    ctx: &Context,
    refs: &mut [PrimRef],
    ids: &mut [u32],
    b: Bounds,
    offset: u32,
    slots: &mut [BvhNode],
) {
    let p = ctx.params;
    let n = refs.len();
    let leaf = |slots: &mut [BvhNode]| {
        slots[0] = BvhNode {
            min: b.min.into(),
            max: b.max.into(),
            left_or_first: offset,
            count: n as u32,
        };
    };
    if n == 1 {
        return leaf(slots);
    }
    let (split_at, left, right) = match find_split(ctx, refs, &b) {
        Some((cost, split)) if cost < p.intersect_cost * n as f32 || n > p.max_leaf_size => {
            partition(ctx, refs, ids, &b, &split)
        }
        Some(_) => return leaf(slots),
        // All centroids coincide: no plane separates them.
        None if n <= p.max_leaf_size => return leaf(slots),
        None => {
            let half = n / 2;
            (half, Bounds::of(&refs[..half]), Bounds::of(&refs[half..]))
        }
    };
    let (node, rest) = slots.split_at_mut(1);
    let (left_slots, right_slots) = rest.split_at_mut(2 * split_at - 1);
    node[0] = BvhNode {
        min: b.min.into(),
        max: b.max.into(),
        // Until `compact`: the second child's slot, relative to this one.
        left_or_first: 2 * split_at as u32,
        count: 0,
    };
    let (lr, rr) = refs.split_at_mut(split_at);
    let (li, ri) = ids.split_at_mut(split_at);
    let right_offset = offset + split_at as u32;
    if n >= PARALLEL_THRESHOLD {
        rayon::join(
            || build_node(ctx, lr, li, left, offset, left_slots),
            || build_node(ctx, rr, ri, right, right_offset, right_slots),
        );
    } else {
        build_node(ctx, lr, li, left, offset, left_slots);
        build_node(ctx, rr, ri, right, right_offset, right_slots);
    }
}

/// Which bin of each axis a doubled centroid falls in. Clamped as floats, by one SIMD min
/// and max, rather than as integers lane by lane.
#[inline]
fn bin_index(c: Vec3A, b: &Bounds, scale: Vec3A, bins: usize) -> [usize; 3] {
    let k = ((c - b.cmin) * scale).clamp(Vec3A::ZERO, Vec3A::splat((bins - 1) as f32));
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
    let mut bins = [[EMPTY_BIN; N]; 3];
    for r in refs {
        let k = bin_index(r.centroid2(), b, scale, nb);
        for (axis, &k) in k.iter().enumerate() {
            // k < nb <= N, and N is a power of two: the mask only drops the bounds check.
            let bin = &mut bins[axis][k & (N - 1)];
            bin.min = bin.min.min(r.min);
            bin.max = bin.max.max(r.max);
            bin.count += 1;
        }
    }
    // Costs are compared as area-weighted counts; the SAH's constants apply at the end.
    let mut best: Option<(f32, Split)> = None;
    let mut right_cost = [0.0f32; N];
    for (axis, bins) in bins.iter().enumerate() {
        if scale[axis] == 0.0 {
            continue;
        }
        let (mut min, mut max, mut count) = (Vec3A::INFINITY, Vec3A::NEG_INFINITY, 0u32);
        for k in (1..nb).rev() {
            min = min.min(bins[k].min);
            max = max.max(bins[k].max);
            count += bins[k].count;
            right_cost[k] = area(min, max) * count as f32;
        }
        let (mut min, mut max, mut count) = (Vec3A::INFINITY, Vec3A::NEG_INFINITY, 0u32);
        for k in 1..nb {
            min = min.min(bins[k - 1].min);
            max = max.max(bins[k - 1].max);
            count += bins[k - 1].count;
            if count == 0 || count as usize == refs.len() {
                continue;
            }
            let cost = area(min, max) * count as f32 + right_cost[k];
            if best.as_ref().is_none_or(|(c, _)| cost < *c) {
                best = Some((cost, Split { axis, bin: k }));
            }
        }
    }
    let parent_area = area(b.min, b.max).max(f32::MIN_POSITIVE);
    best.map(|(c, split)| (p.traversal_cost + p.intersect_cost * c / parent_area, split))
}

/// Moves the triangles left of the split to the front (ids alongside); returns their
/// count and the bounds of both sides.
fn partition(
    ctx: &Context,
    refs: &mut [PrimRef],
    ids: &mut [u32],
    b: &Bounds,
    split: &Split,
) -> (usize, Bounds, Bounds) {
    let nb = bins_for(ctx, refs.len());
    let scale = bin_scale(b, nb);
    let (axis, last) = (split.axis, (nb - 1) as f32);
    // `bin_index` on one axis only: the same arithmetic, so the counts match the bins'.
    let goes_left = |r: &PrimRef| {
        let k = ((r.centroid2()[axis] - b.cmin[axis]) * scale[axis]).clamp(0.0, last);
        (k as usize) < split.bin
    };
    let (mut left, mut right) = (Bounds::EMPTY, Bounds::EMPTY);
    let (mut i, mut j) = (0, refs.len());
    while i < j {
        if goes_left(&refs[i]) {
            left.grow(&refs[i]);
            i += 1;
        } else {
            j -= 1;
            refs.swap(i, j);
            ids.swap(i, j);
            right.grow(&refs[j]);
        }
    }
    (i, left, right)
}

/// Lays the used slots out depth-first (first child right after its parent) and fills in
/// the statistics.
fn compact(slots: &[BvhNode], stats: &mut BvhStats, p: &BuildParams) -> Vec<BvhNode> {
    let mut out: Vec<BvhNode> = Vec::with_capacity(slots.len() / 2 + 1);
    let root_area = slots[0].bounds().area().max(f32::MIN_POSITIVE);
    // (slot, depth, index in `out` of the parent whose second child this is)
    let mut stack: Vec<(usize, u32, Option<usize>)> = vec![(0, 0, None)];
    while let Some((slot, depth, parent)) = stack.pop() {
        if let Some(parent) = parent {
            out[parent].left_or_first = out.len() as u32;
        }
        let node = slots[slot];
        let index = out.len();
        out.push(node);
        stats.depth = stats.depth.max(depth);
        let rel_area = node.bounds().area() / root_area;
        if node.is_leaf() {
            stats.leaves += 1;
            stats.sah_cost += rel_area * p.intersect_cost * node.count as f32;
            let c = node.count as usize;
            if stats.leaf_sizes.len() <= c {
                stats.leaf_sizes.resize(c + 1, 0);
            }
            stats.leaf_sizes[c] += 1;
        } else {
            stats.sah_cost += rel_area * p.traversal_cost;
            // The second child is visited after the whole first subtree.
            stack.push((slot + node.left_or_first as usize, depth + 1, Some(index)));
            stack.push((slot + 1, depth + 1, None));
        }
    }
    out
}
