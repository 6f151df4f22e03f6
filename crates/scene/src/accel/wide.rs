//! The 4-wide node layout that queries traverse, and its construction by collapsing the binary
//! SAH tree.
//!
//! A wide node holds the boxes of up to four children in structure-of-arrays form (one `[f32; 4]`
//! per axis and per corner), so that one slab test handles all four lanes with SIMD arithmetic
//! (`ray_box.rs`). Collapsing: a wide node starts with the two children of a binary node and
//! repeatedly replaces the interior child with the largest surface area by its own two children
//! until it has four children or only leaves (Wald et al. 2008, "Getting rid of packets").

use arrayvec::ArrayVec;

use super::binary::{BinaryTree, Node};

/// Number of children of a wide node.
pub(super) const WIDTH: usize = 4;

/// [`WideNode::meta`] of an interior child; its `child` is a node index.
pub(super) const INTERIOR: u32 = u32::MAX;

/// A node with up to [`WIDTH`] children; 128 bytes, two cache lines.
///
/// * `slabs[axis][c][lane]`: the child boxes, `c = 0` the lower corner, `c = 1` the upper one
///   (axis major, so that the slab test finds a ray's near and far plane of an axis at offsets
///   that differ only by the ray's corner choice, computed once per ray).
///   An unused lane has the inverted box `(+∞, −∞)`, which no NaN-free ray enters.
/// * `meta[lane]`: [`INTERIOR`], or the number of primitives of a leaf child (0 for an unused
///   lane, which is then a leaf without primitives: nothing to test even if a ray with NaNs
///   "enters" its box).
/// * `child[lane]`: the node index of an interior child; for a leaf the first entry of its range
///   of the primitive index array, except that a leaf of one primitive holds the primitive id.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub(super) struct WideNode {
    pub(super) slabs: [[[f32; WIDTH]; 2]; 3],
    pub(super) meta: [u32; WIDTH],
    pub(super) child: [u32; WIDTH],
}

impl WideNode {
    const EMPTY: WideNode = WideNode {
        slabs: [[[f32::INFINITY; WIDTH], [f32::NEG_INFINITY; WIDTH]]; 3],
        meta: [0; WIDTH],
        child: [0; WIDTH],
    };

    fn set_box(&mut self, lane: usize, node: &Node) {
        let (min, max) = (node.min(), node.max());
        for axis in 0..3 {
            self.slabs[axis][0][lane] = min[axis];
            self.slabs[axis][1][lane] = max[axis];
        }
    }
}

/// The wide tree: nodes in depth-first order, node 0 the root.
pub(super) struct WideTree {
    pub(super) nodes: Vec<WideNode>,
    /// Depth of the deepest wide node (the root has depth 0).
    pub(super) max_depth: usize,
}

/// Collapses `tree` (which must have primitives) into wide nodes. A root that is a leaf becomes
/// a wide root with that single leaf child. The wide tree is never deeper than the binary one.
pub(super) fn collapse(tree: &BinaryTree) -> WideTree {
    let mut wide = WideTree { nodes: Vec::with_capacity(tree.pairs.len() / 3 + 1), max_depth: 0 };
    if tree.root.is_leaf() {
        let mut root = WideNode::EMPTY;
        set_child(&mut root, 0, &tree.root, 0);
        wide.nodes.push(root);
    } else {
        emit(tree, &tree.root, 0, &mut wide);
    }
    wide
}

/// Appends the wide node for binary interior node `node` and, depth first, those of its
/// interior descendants; returns its index.
fn emit(tree: &BinaryTree, node: &Node, depth: usize, wide: &mut WideTree) -> u32 {
    wide.max_depth = wide.max_depth.max(depth);
    let index = wide.nodes.len();
    wide.nodes.push(WideNode::EMPTY);
    let mut children: ArrayVec<Node, WIDTH> = tree.children(node).iter().copied().collect();
    while children.len() < WIDTH {
        // The interior child with the largest surface area (the first of equal ones) opens up.
        let mut widest: Option<(usize, f32)> = None;
        for (i, c) in children.iter().enumerate() {
            if !c.is_leaf() && widest.is_none_or(|(_, area)| c.half_area() > area) {
                widest = Some((i, c.half_area()));
            }
        }
        let Some((i, _)) = widest else { break };
        let [left, right] = *tree.children(&children[i]);
        children[i] = left;
        children.insert(i + 1, right);
    }
    let mut result = WideNode::EMPTY;
    for (lane, c) in children.iter().enumerate() {
        let child_index = if c.is_leaf() { c.index() } else { emit(tree, c, depth + 1, wide) };
        set_child(&mut result, lane, c, child_index);
    }
    wide.nodes[index] = result;
    index as u32
}

fn set_child(node: &mut WideNode, lane: usize, child: &Node, child_index: u32) {
    node.set_box(lane, child);
    node.meta[lane] = if child.is_leaf() { child.count() } else { INTERIOR };
    node.child[lane] = child_index;
}
