//! The bounding volume hierarchy over the scene's triangles.
//!
//! `build` makes a binned-SAH tree and lays it out depth-first as the 32-byte
//! [`BvhNode`]s that both the CPU and the GPU traverse, `traverse` holds the closest-hit
//! and any-hit kernels, and `validate` checks the invariants the kernels rely on. `wide`
//! collapses the tree into the 8-wide one that the CPU renderer traverses.
//! This module does no I/O.

mod build;
mod traverse;
mod validate;
pub mod wide;

pub use build::{BuildParams, MAX_BINS};
pub use traverse::{Hit, solid, traverse_any, traverse_closest, traverse_closest_counted};
pub use validate::validate;
pub use wide::WideBvh;

use crate::math::Aabb;
use bytemuck::{Pod, Zeroable};

/// Entries of the fixed traversal stack on both devices; deeper trees are refused.
pub const STACK_SIZE: usize = 64;

/// One node of the flattened tree (32 bytes). An interior node (`count == 0`) has its
/// first child right after it and its second at `left_or_first`; a leaf holds triangles
/// `left_or_first .. left_or_first + count` of the leaf-ordered triangle array.
/// mirror: shaders/types.wgsl `BvhNode`
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct BvhNode {
    pub min: [f32; 3],
    pub left_or_first: u32,
    pub max: [f32; 3],
    pub count: u32,
}

impl BvhNode {
    pub fn is_leaf(&self) -> bool {
        self.count > 0
    }

    pub fn bounds(&self) -> Aabb {
        Aabb {
            min: self.min.into(),
            max: self.max.into(),
        }
    }
}

/// A built, flattened BVH.
#[derive(Clone, Debug)]
pub struct Bvh {
    pub nodes: Vec<BvhNode>,
    /// `order[i]` is the input index of the triangle stored at leaf position `i`.
    pub order: Vec<u32>,
    pub stats: BvhStats,
}

/// What `meshtrace info` reports about a tree.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BvhStats {
    pub triangles: usize,
    pub nodes: usize,
    pub leaves: usize,
    /// Longest root-to-leaf path in edges.
    pub depth: u32,
    /// The tree's SAH cost, with traversal and intersection costs of `BuildParams`.
    pub sah_cost: f32,
    /// `leaf_sizes[k]` leaves hold `k` triangles.
    pub leaf_sizes: Vec<usize>,
    pub build_seconds: f64,
}

/// Why a tree cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum BvhError {
    #[error(
        "the BVH is {depth} levels deep but traversal stacks hold {STACK_SIZE}; the mesh has extreme clustering of degenerate geometry"
    )]
    TooDeep { depth: u32 },
    #[error("the scene has {triangles} triangles; meshtrace renders at most {MAX_TRIANGLES}")]
    TooMany { triangles: usize },
}

/// The most triangles a tree takes: their indices stay below bit 31, which marks masked
/// triangles in the wide tree's packs (`wide::PACK_MASKED`) and punctual lights in the
/// emitter table.
pub const MAX_TRIANGLES: usize = (1 << 31) - 1;

impl Bvh {
    /// Builds a tree over triangle bounds; the input order is kept in [`Bvh::order`].
    pub fn build(bounds: &[Aabb], params: &BuildParams) -> Result<Self, BvhError> {
        if bounds.len() > MAX_TRIANGLES {
            return Err(BvhError::TooMany {
                triangles: bounds.len(),
            });
        }
        let start = std::time::Instant::now();
        let mut bvh = build::build(bounds, params);
        bvh.stats.build_seconds = start.elapsed().as_secs_f64();
        if bvh.stats.depth as usize >= STACK_SIZE {
            return Err(BvhError::TooDeep {
                depth: bvh.stats.depth,
            });
        }
        Ok(bvh)
    }
}
