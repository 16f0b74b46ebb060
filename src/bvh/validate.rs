//! Structural checks of a flattened tree: what the traversal kernels assume.

use super::{Bvh, STACK_SIZE};
use crate::math::Aabb;

/// Checks that every child box lies inside its parent, every leaf box holds its triangles,
/// every triangle sits in exactly one leaf, `order` is a permutation, and the depth fits the
/// traversal stack. `tri_bounds` are in input order. Returns the first violation found.
pub fn validate(bvh: &Bvh, tri_bounds: &[Aabb]) -> Result<(), String> {
    let n = tri_bounds.len();
    if bvh.order.len() != n {
        return Err(format!(
            "order has {} entries for {n} triangles",
            bvh.order.len()
        ));
    }
    let mut seen = vec![false; n];
    for &i in &bvh.order {
        let slot = seen
            .get_mut(i as usize)
            .ok_or(format!("order names triangle {i} of {n}"))?;
        if std::mem::replace(slot, true) {
            return Err(format!("triangle {i} appears twice in order"));
        }
    }
    if n == 0 {
        return Ok(());
    }
    let mut covered = vec![false; n];
    // (node, depth)
    let mut stack = vec![(0usize, 0usize)];
    while let Some((i, depth)) = stack.pop() {
        if depth >= STACK_SIZE {
            return Err(format!(
                "node {i} is at depth {depth}, beyond the stack of {STACK_SIZE}"
            ));
        }
        let node = bvh
            .nodes
            .get(i)
            .ok_or(format!("node index {i} out of range"))?;
        let b = node.bounds();
        if node.is_leaf() {
            for k in node.left_or_first..node.left_or_first + node.count {
                let slot = covered
                    .get_mut(k as usize)
                    .ok_or(format!("leaf {i} names slot {k} of {n}"))?;
                if std::mem::replace(slot, true) {
                    return Err(format!("slot {k} is in two leaves"));
                }
                if !b.contains(&tri_bounds[bvh.order[k as usize] as usize]) {
                    return Err(format!(
                        "leaf {i} does not contain its triangle in slot {k}"
                    ));
                }
            }
        } else {
            for c in [i + 1, node.left_or_first as usize] {
                let child = bvh
                    .nodes
                    .get(c)
                    .ok_or(format!("child {c} of node {i} out of range"))?;
                if c <= i {
                    return Err(format!("child {c} of node {i} is not after it"));
                }
                if !b.contains(&child.bounds()) {
                    return Err(format!("child {c} pokes out of node {i}"));
                }
                stack.push((c, depth + 1));
            }
        }
    }
    match covered.iter().position(|&c| !c) {
        Some(k) => Err(format!("slot {k} is in no leaf")),
        None => Ok(()),
    }
}
