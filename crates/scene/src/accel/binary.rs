//! The binary SAH tree that the builder produces and the 4-wide tree is collapsed from.
//!
//! Layout: nodes are 32 bytes (`min.xyz`, index, `max.xyz`, count) and siblings are stored
//! together as a 64-byte, cache-line aligned pair. Leaves name a range of the primitive index
//! array. Only the build and the collapse read this tree; its own traversal is kept for A/B
//! benchmarks behind the `binary-bvh` feature (`binary_traverse.rs`).

use math::{Vec3, Vec3A};

use super::BvhStats;

/// A node: box corners, and either a child pair index (interior, `count == 0`), or for a leaf
/// (`count > 0`) the first entry of its range of the primitive index array, except that a leaf
/// with one primitive stores the primitive id itself.
///
/// Stored as eight words `[min.x, min.y, min.z, index, max.x, max.y, max.z, count]` (the floats
/// as bit patterns), so that a slab test can pick the near and far plane of each axis by an
/// index precomputed per ray.
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(32))]
pub(super) struct Node {
    pub(super) v: [u32; 8],
}

impl Node {
    pub(super) fn new(min: Vec3A, max: Vec3A, index: u32, count: u32) -> Self {
        let f = f32::to_bits;
        Self { v: [f(min.x), f(min.y), f(min.z), index, f(max.x), f(max.y), f(max.z), count] }
    }

    /// Child pair index (interior), first entry of the leaf's range, or for a leaf of one
    /// primitive the primitive id.
    #[inline(always)]
    pub(super) fn index(&self) -> u32 {
        self.v[3]
    }

    /// Number of primitives of a leaf; 0 for an interior node.
    #[inline(always)]
    pub(super) fn count(&self) -> u32 {
        self.v[7]
    }

    #[inline(always)]
    pub(super) fn is_leaf(&self) -> bool {
        self.count() != 0
    }

    pub(super) fn min(&self) -> Vec3 {
        Vec3::new(f32::from_bits(self.v[0]), f32::from_bits(self.v[1]), f32::from_bits(self.v[2]))
    }

    pub(super) fn max(&self) -> Vec3 {
        Vec3::new(f32::from_bits(self.v[4]), f32::from_bits(self.v[5]), f32::from_bits(self.v[6]))
    }

    /// Half the surface area of the box (0 for a flat or point box).
    pub(super) fn half_area(&self) -> f32 {
        let e = (self.max() - self.min()).max(Vec3::ZERO);
        e.x * e.y + e.y * e.z + e.z * e.x
    }

    pub(super) fn set_index(&mut self, index: u32) {
        self.v[3] = index;
    }
}

/// Two sibling nodes in one cache line.
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(64))]
pub(super) struct NodePair(pub(super) [Node; 2]);

/// A built binary tree: the root, the child pairs in depth-first order, the primitive ids
/// grouped by leaf, and the statistics of the tree. A tree without primitives has no pairs and
/// an empty `prims`.
#[derive(Clone, Debug)]
pub(super) struct BinaryTree {
    pub(super) root: Node,
    pub(super) pairs: Vec<NodePair>,
    pub(super) prims: Vec<u32>,
    pub(super) stats: BvhStats,
}

impl BinaryTree {
    /// The two children of interior node `node`.
    #[inline(always)]
    pub(super) fn children(&self, node: &Node) -> &[Node; 2] {
        &self.pairs[node.index() as usize].0
    }
}
