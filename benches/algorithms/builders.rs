//! BVH builders compared with meshtrace's binned SAH (`meshtrace::bvh`): the seed's
//! midpoint split and the object median split, written out in meshtrace's node layout so
//! that the library's own traversal walks all of them alike; and the SAH cost of a tree.

use glam::{DVec3, Vec3};
use meshtrace::bvh::{Bvh, BvhNode, BvhStats};
use meshtrace::math::Aabb;

/// A built tree before it is laid out: a leaf's triangles, or two subtrees.
enum Tree {
    Leaf(Aabb, Vec<u32>),
    Inner(Aabb, Box<[Tree; 2]>),
}

/// Lays `tree` out depth-first as meshtrace does (first child next, second child's index
/// in `left_or_first`; a leaf's triangles consecutive in `order`).
fn flatten(tree: &Tree, nodes: &mut Vec<BvhNode>, order: &mut Vec<u32>) {
    match tree {
        Tree::Leaf(b, tris) => {
            nodes.push(BvhNode {
                min: b.min.into(),
                max: b.max.into(),
                left_or_first: order.len() as u32,
                count: tris.len() as u32,
            });
            order.extend(tris);
        }
        Tree::Inner(b, kids) => {
            let index = nodes.len();
            nodes.push(BvhNode {
                min: b.min.into(),
                max: b.max.into(),
                left_or_first: 0,
                count: 0,
            });
            flatten(&kids[0], nodes, order);
            nodes[index].left_or_first = nodes.len() as u32;
            flatten(&kids[1], nodes, order);
        }
    }
}

/// The laid-out tree with meshtrace's statistics (SAH cost with unit traversal and
/// intersection costs, as `BuildParams::fast()` has them).
fn finish(tree: &Tree, triangles: usize) -> Bvh {
    let (mut nodes, mut order) = (Vec::new(), Vec::new());
    flatten(tree, &mut nodes, &mut order);
    let stats = stats(&nodes, triangles);
    Bvh {
        nodes,
        order,
        stats,
    }
}

/// What meshtrace's builder reports of a tree: node, leaf and depth counts, leaf sizes and
/// the SAH cost (the build time is left 0: the benches time builds themselves).
pub fn stats(nodes: &[BvhNode], triangles: usize) -> BvhStats {
    let mut s = BvhStats {
        triangles,
        nodes: nodes.len(),
        ..Default::default()
    };
    let mut stack = vec![(0usize, 0u32)];
    while let Some((i, depth)) = stack.pop() {
        let n = &nodes[i];
        s.depth = s.depth.max(depth);
        if n.is_leaf() {
            s.leaves += 1;
            let c = n.count as usize;
            if s.leaf_sizes.len() <= c {
                s.leaf_sizes.resize(c + 1, 0);
            }
            s.leaf_sizes[c] += 1;
        } else {
            stack.push((n.left_or_first as usize, depth + 1));
            stack.push((i + 1, depth + 1));
        }
    }
    s.sah_cost = sah_cost(nodes) as f32;
    s
}

/// The SAH cost of a tree (MacDonald and Booth 1990), as meshtrace's builder tallies it:
/// each interior node's area (one traversal step) plus each leaf's area times its
/// triangles (one test each), over the root's area: the expected cost of a ray through
/// the root's box, in triangle tests.
pub fn sah_cost(nodes: &[BvhNode]) -> f64 {
    let root = f64::from(nodes[0].bounds().area()).max(f64::from(f32::MIN_POSITIVE));
    let total: f64 = nodes
        .iter()
        .map(|n| {
            let area = f64::from(n.bounds().area());
            if n.is_leaf() {
                area * f64::from(n.count)
            } else {
                area
            }
        })
        .sum();
    total / root
}

/// The seed's box in its own precision (`double`), with its `AABB` methods
/// (`Step 3/include/engine/math/colliders.h`, `Step 3/src/engine/math/colliders.cpp`).
#[derive(Clone, Copy, Debug, PartialEq)]
struct SeedBox {
    min: DVec3,
    max: DVec3,
}

impl SeedBox {
    /// `AABB::intersects(const AABB&)`: overlap, boundaries included.
    fn intersects(&self, o: &SeedBox) -> bool {
        self.min.cmple(o.max).all() && self.max.cmpge(o.min).all()
    }

    /// `AABB::splitAlongAxis`: the two halves along `axis`, the first ending at
    /// `max - extent / 2`, the second starting at `min + extent / 2`.
    fn split_along(&self, axis: usize) -> (SeedBox, SeedBox) {
        let half = (self.max[axis] - self.min[axis]).abs() / 2.0;
        let (mut first, mut second) = (*self, *self);
        first.max[axis] = self.max[axis] - half;
        second.min[axis] = self.min[axis] + half;
        (first, second)
    }

    /// `AABB::splitByLongestAxis`: the halves along the longest axis (z on ties with it, y
    /// on a tie of x and y).
    fn split_longest(&self) -> (SeedBox, SeedBox) {
        let e = (self.max - self.min).abs();
        let axis = if e.x > e.y && e.x > e.z {
            0
        } else if e.y > e.z {
            1
        } else {
            2
        };
        self.split_along(axis)
    }

    fn to_aabb(self) -> Aabb {
        // Unions of f32 boxes, so exact.
        Aabb {
            min: self.min.as_vec3(),
            max: self.max.as_vec3(),
        }
    }
}

/// A triangle as the seed's builder holds it (`TriangleBVHObject`): its index and box.
#[derive(Clone, Copy, Debug)]
struct SeedObject {
    index: u32,
    aabb: SeedBox,
}

/// `TriangleBVHPartitionedSpace`: what went to each side.
#[derive(Default)]
struct Space {
    left: Vec<SeedObject>,
    right: Vec<SeedObject>,
}

impl Space {
    /// The seed's `operator==`: the same sizes and the same boxes, in order.
    fn same(&self, o: &Space) -> bool {
        let boxes = |a: &[SeedObject], b: &[SeedObject]| {
            a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.aabb == y.aabb)
        };
        boxes(&self.left, &o.left) && boxes(&self.right, &o.right)
    }
}

/// `TriangleBVHTree::partition`: each object goes to the first box it touches (the left
/// one where it touches both), or to neither.
fn partition(boxes: (SeedBox, SeedBox), objects: &[SeedObject]) -> Space {
    let mut space = Space::default();
    for o in objects {
        if boxes.0.intersects(&o.aabb) {
            space.left.push(*o);
        } else if boxes.1.intersects(&o.aabb) {
            space.right.push(*o);
        }
    }
    space
}

/// The seed's midpoint build (`TriangleBVHTree::addObjectsRecursively` in
/// `Step 3/src/engine/math/bvh.cpp`; the seed kept it for triangles but traced its scenes
/// through the same builder over whole objects, `BVHTree`), in f64 as the seed: a node's
/// box is split in half along its longest axis, each triangle goes to the half it touches
/// (the first where it touches both), and only single triangles become leaves, unless no
/// split makes progress. Where a side is empty the seed makes a node of one child with the
/// same box; here that child takes its place, which spares its traversal one box test.
/// Also returns how many triangles the seed's partition dropped (none touched either half).
pub fn seed_midpoint(bounds: &[Aabb]) -> (Bvh, usize) {
    let objects: Vec<SeedObject> = bounds
        .iter()
        .enumerate()
        .map(|(i, b)| SeedObject {
            index: i as u32,
            aabb: SeedBox {
                min: b.min.as_dvec3(),
                max: b.max.as_dvec3(),
            },
        })
        .collect();
    let tree = seed_node(&objects, &Space::default());
    let bvh = finish(&tree, bounds.len());
    let dropped = bounds.len() - bvh.order.len();
    (bvh, dropped)
}

fn seed_node(objects: &[SeedObject], prev: &Space) -> Tree {
    let world = objects
        .iter()
        .skip(1)
        .fold(objects[0].aabb, |w, o| SeedBox {
            min: w.min.min(o.aabb.min),
            max: w.max.max(o.aabb.max),
        });
    let leaf = || Tree::Leaf(world.to_aabb(), objects.iter().map(|o| o.index).collect());
    if objects.len() <= 1 {
        return leaf();
    }
    let split = world.split_longest();
    let mut space = partition(split, objects);
    if prev.same(&space) {
        // No progress: try the halves the other way round, then each axis in turn.
        space = partition((split.1, split.0), objects);
        if prev.same(&space) {
            for axis in 0..3 {
                space = partition(world.split_along(axis), objects);
                if !prev.same(&space) {
                    break;
                }
            }
        }
    }
    if prev.same(&space) {
        return leaf();
    }
    let left = (!space.left.is_empty()).then(|| seed_node(&space.left, &space));
    let right = (!space.right.is_empty()).then(|| seed_node(&space.right, &space));
    match (left, right) {
        (Some(l), Some(r)) => Tree::Inner(world.to_aabb(), Box::new([l, r])),
        (Some(only), None) | (None, Some(only)) => only,
        (None, None) => leaf(),
    }
}

/// The object median build: a node's triangles are split in two equal halves by their
/// centroids along the longest axis of the centroids' box, down to leaves of at most
/// `max_leaf`. Balanced, and quick, but blind to the boxes' sizes and overlaps.
pub fn object_median(bounds: &[Aabb], max_leaf: usize) -> Bvh {
    let mut refs: Vec<(u32, Aabb, Vec3)> = bounds
        .iter()
        .enumerate()
        .map(|(i, b)| (i as u32, *b, b.center()))
        .collect();
    let tree = median_node(&mut refs, max_leaf);
    finish(&tree, bounds.len())
}

fn median_node(refs: &mut [(u32, Aabb, Vec3)], max_leaf: usize) -> Tree {
    let bounds = refs.iter().fold(Aabb::EMPTY, |b, r| b.union(r.1));
    if refs.len() <= max_leaf {
        return Tree::Leaf(bounds, refs.iter().map(|r| r.0).collect());
    }
    let centroids = refs.iter().fold(Aabb::EMPTY, |b, r| b.grow(r.2)).extent();
    let axis = centroids.max_position();
    let mid = refs.len() / 2;
    refs.select_nth_unstable_by(mid, |a, b| a.2[axis].total_cmp(&b.2[axis]));
    let (l, r) = refs.split_at_mut(mid);
    Tree::Inner(
        bounds,
        Box::new([median_node(l, max_leaf), median_node(r, max_leaf)]),
    )
}
