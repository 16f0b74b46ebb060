//! Binned SAH construction (Wald 2007, "On fast Construction of SAH-based Bounding Volume
//! Hierarchies"), then a depth-first flattening into [`BvhNode`]s.

use super::{Bvh, BvhNode, BvhStats};
use crate::math::Aabb;
use glam::Vec3;

/// How to build: bin count and the SAH's cost model. Leaf sizes are not fixed: a node
/// becomes a leaf when the SAH says splitting would cost more.
#[derive(Clone, Debug, PartialEq)]
pub struct BuildParams {
    /// Bins per axis for the split search.
    pub bins: usize,
    /// Cost of visiting an interior node, relative to `intersect_cost`.
    pub traversal_cost: f32,
    /// Cost of one ray–triangle test.
    pub intersect_cost: f32,
    /// Leaves never hold more than this, whatever the SAH prefers.
    pub max_leaf_size: usize,
}

impl BuildParams {
    /// The default: 16 bins per axis.
    pub fn fast() -> Self {
        Self {
            bins: 16,
            traversal_cost: 1.0,
            intersect_cost: 1.0,
            max_leaf_size: 16,
        }
    }

    /// 32 bins per axis: a slower build, the baseline the fast one is measured against.
    pub fn precise() -> Self {
        Self {
            bins: 32,
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

enum Node {
    Leaf {
        bounds: Aabb,
        first: u32,
        count: u32,
    },
    Interior {
        bounds: Aabb,
        children: Box<[Node; 2]>,
    },
}

struct Input<'a> {
    bounds: &'a [Aabb],
    centroids: Vec<Vec3>,
    params: &'a BuildParams,
}

pub fn build(bounds: &[Aabb], params: &BuildParams) -> Bvh {
    let input = Input {
        bounds,
        centroids: bounds.iter().map(Aabb::center).collect(),
        params,
    };
    let mut order: Vec<u32> = (0..bounds.len() as u32).collect();
    let root = if bounds.is_empty() {
        Node::Leaf {
            bounds: Aabb {
                min: Vec3::ZERO,
                max: Vec3::ZERO,
            },
            first: 0,
            count: 0,
        }
    } else {
        build_node(&input, &mut order, 0)
    };
    let mut nodes = Vec::with_capacity(2 * bounds.len().max(1));
    let mut stats = BvhStats {
        triangles: bounds.len(),
        ..Default::default()
    };
    let root_area = node_bounds(&root).area().max(f32::MIN_POSITIVE);
    flatten(&root, &mut nodes, &mut stats, 0, root_area, params);
    stats.nodes = nodes.len();
    Bvh {
        nodes,
        order,
        stats,
    }
}

fn node_bounds(n: &Node) -> Aabb {
    match n {
        Node::Leaf { bounds, .. } | Node::Interior { bounds, .. } => *bounds,
    }
}

#[derive(Clone, Copy)]
struct Bin {
    bounds: Aabb,
    count: u32,
}

/// Builds the subtree over `order` (whose first element sits at leaf position `offset`).
fn build_node(input: &Input, order: &mut [u32], offset: u32) -> Node {
    let p = input.params;
    let mut bounds = Aabb::EMPTY;
    let mut cbounds = Aabb::EMPTY;
    for &i in order.iter() {
        bounds = bounds.union(input.bounds[i as usize]);
        cbounds = cbounds.grow(input.centroids[i as usize]);
    }
    let n = order.len();
    let leaf = || Node::Leaf {
        bounds,
        first: offset,
        count: n as u32,
    };
    if n == 1 {
        return leaf();
    }
    let best = find_split(input, order, &cbounds);
    let leaf_cost = p.intersect_cost * n as f32;
    let split_at = match best {
        Some((cost, axis, bin)) if cost < leaf_cost || n > p.max_leaf_size => {
            let scale = p.bins as f32 / cbounds.extent()[axis];
            let bin_of =
                |c: Vec3| (((c[axis] - cbounds.min[axis]) * scale) as usize).min(p.bins - 1);
            partition(order, |&i| bin_of(input.centroids[i as usize]) < bin)
        }
        Some(_) => return leaf(),
        // All centroids coincide: no plane separates them.
        None if n <= p.max_leaf_size => return leaf(),
        None => n / 2,
    };
    let (left, right) = order.split_at_mut(split_at);
    let right_offset = offset + split_at as u32;
    let (l, r) = if n >= PARALLEL_THRESHOLD {
        rayon::join(
            || build_node(input, left, offset),
            || build_node(input, right, right_offset),
        )
    } else {
        (
            build_node(input, left, offset),
            build_node(input, right, right_offset),
        )
    };
    Node::Interior {
        bounds,
        children: Box::new([l, r]),
    }
}

/// The cheapest binned split as (SAH cost, axis, first bin of the right side).
fn find_split(input: &Input, order: &[u32], cbounds: &Aabb) -> Option<(f32, usize, usize)> {
    let p = input.params;
    let nb = p.bins;
    let extent = cbounds.extent();
    let empty = Bin {
        bounds: Aabb::EMPTY,
        count: 0,
    };
    let mut bins = vec![[empty; 3]; nb];
    let scale = Vec3::splat(nb as f32) / extent;
    for &i in order {
        let c = input.centroids[i as usize];
        let b = input.bounds[i as usize];
        let idx = ((c - cbounds.min) * scale).as_uvec3();
        for axis in 0..3 {
            let k = (idx[axis] as usize).min(nb - 1);
            let bin = &mut bins[k][axis];
            bin.bounds = bin.bounds.union(b);
            bin.count += 1;
        }
    }
    let parent_area = {
        let mut a = Aabb::EMPTY;
        for &i in order {
            a = a.union(input.bounds[i as usize]);
        }
        a.area()
    };
    let mut best: Option<(f32, usize, usize)> = None;
    let mut right_area = vec![0.0f32; nb];
    let mut right_count = vec![0u32; nb];
    for axis in 0..3 {
        if extent[axis].is_nan() || extent[axis] <= 0.0 {
            continue;
        }
        let (mut acc, mut cnt) = (Aabb::EMPTY, 0);
        for k in (1..nb).rev() {
            acc = acc.union(bins[k][axis].bounds);
            cnt += bins[k][axis].count;
            right_area[k] = acc.area();
            right_count[k] = cnt;
        }
        let (mut acc, mut cnt) = (Aabb::EMPTY, 0);
        for k in 1..nb {
            acc = acc.union(bins[k - 1][axis].bounds);
            cnt += bins[k - 1][axis].count;
            if cnt == 0 || right_count[k] == 0 {
                continue;
            }
            let cost = p.traversal_cost
                + p.intersect_cost
                    * (acc.area() * cnt as f32 + right_area[k] * right_count[k] as f32)
                    / parent_area;
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, k));
            }
        }
    }
    best
}

/// Moves the elements satisfying `pred` to the front; returns how many there are.
fn partition(v: &mut [u32], pred: impl Fn(&u32) -> bool) -> usize {
    let mut i = 0;
    for j in 0..v.len() {
        if pred(&v[j]) {
            v.swap(i, j);
            i += 1;
        }
    }
    i
}

fn flatten(
    node: &Node,
    out: &mut Vec<BvhNode>,
    stats: &mut BvhStats,
    depth: u32,
    root_area: f32,
    p: &BuildParams,
) {
    stats.depth = stats.depth.max(depth);
    let index = out.len();
    let b = node_bounds(node);
    out.push(BvhNode {
        min: b.min.into(),
        max: b.max.into(),
        left_or_first: 0,
        count: 0,
    });
    let rel_area = b.area() / root_area;
    match node {
        Node::Leaf { first, count, .. } => {
            out[index].left_or_first = *first;
            out[index].count = *count;
            stats.leaves += 1;
            stats.sah_cost += rel_area * p.intersect_cost * *count as f32;
            let c = *count as usize;
            if stats.leaf_sizes.len() <= c {
                stats.leaf_sizes.resize(c + 1, 0);
            }
            stats.leaf_sizes[c] += 1;
        }
        Node::Interior { children, .. } => {
            stats.sah_cost += rel_area * p.traversal_cost;
            flatten(&children[0], out, stats, depth + 1, root_area, p);
            out[index].left_or_first = out.len() as u32;
            flatten(&children[1], out, stats, depth + 1, root_area, p);
        }
    }
}
