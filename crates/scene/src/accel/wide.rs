//! The 8-wide node layout that queries traverse, and its construction by collapsing the binary
//! SAH tree.
//!
//! A wide node holds the boxes of up to eight children in structure-of-arrays form (one
//! `[f32; 8]` per axis and per corner), so that the slab test handles the lanes four at a time
//! with SIMD arithmetic (`ray_box.rs`). Collapsing: every wide node is a binary interior node
//! whose children are up to eight of its descendants, chosen by dynamic programming so that the
//! summed surface area of all wide nodes (the SAH's expected node visits per ray) is least
//! ([`CollapsePlan`]).

use arrayvec::ArrayVec;

use super::binary::{BinaryTree, Node};

/// Number of children of a wide node.
pub(super) const WIDTH: usize = 8;

/// [`WideNode::meta`] of an interior child; its `child` is a node index.
pub(super) const INTERIOR: u32 = u32::MAX;

/// A node with up to [`WIDTH`] children; 256 bytes, four cache lines.
///
/// Eight and not four children: a query's time goes mostly into the chain of dependent steps
/// from a node to the next (load, slab test, choice of the child), and eight lanes halve the
/// depth of the tree while their two groups of four are tested side by side. Measured against
/// the 4-wide nodes in docs/bvh.md ("8-wide nodes").
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
        let plan = CollapsePlan::new(tree);
        emit(tree, &plan, &tree.root, 0, &mut wide);
    }
    wide
}

/// Appends the wide node for binary interior node `node` and, depth first, those of its
/// interior descendants; returns its index.
fn emit(tree: &BinaryTree, plan: &CollapsePlan, node: &Node, depth: usize, wide: &mut WideTree) -> u32 {
    wide.max_depth = wide.max_depth.max(depth);
    let index = wide.nodes.len();
    wide.nodes.push(WideNode::EMPTY);
    let mut children: ArrayVec<Node, WIDTH> = ArrayVec::new();
    let [left, right] = *tree.children(node);
    let left_slots = plan.inside_split(node.index());
    plan.frontier(tree, &left, left_slots, &mut children);
    plan.frontier(tree, &right, WIDTH - left_slots, &mut children);
    let mut result = WideNode::EMPTY;
    for (lane, c) in children.iter().enumerate() {
        let child_index = if c.is_leaf() { c.index() } else { emit(tree, plan, c, depth + 1, wide) };
        set_child(&mut result, lane, c, child_index);
    }
    wide.nodes[index] = result;
    index as u32
}

/// Which binary nodes become wide nodes: the choice that minimises the summed surface area of
/// the wide nodes, i.e. the SAH's expected number of wide nodes a ray visits (the leaves, and
/// so the primitive tests, are those of the binary tree whatever the choice).
///
/// Dynamic programming over the binary tree, by child pair (every interior node has its own
/// pair): `cost[p][k − 1]` is the least summed area of the wide nodes inside the subtree of the
/// node whose children are pair `p`, when that subtree may fill `k` lanes of the wide node
/// above it: with one lane the node itself becomes a wide node (its area, plus its two
/// children sharing all lanes); with `k ≥ 2` it may also be opened, its children sharing the
/// `k` lanes. `split[p][k − 1]` records the choice for `k ≥ 2`: the lanes given to the left
/// child, or 0 when the node stays closed; `split[p][0]` holds the left child's lanes inside
/// the wide node the node becomes. (A greedy collapse, which always opened the widest interior
/// child, visited more nodes.)
struct CollapsePlan {
    cost: Vec<[f64; WIDTH]>,
    split: Vec<[u8; WIDTH]>,
}

impl CollapsePlan {
    fn new(tree: &BinaryTree) -> Self {
        let mut plan =
            CollapsePlan { cost: vec![[0.0; WIDTH]; tree.pairs.len()], split: vec![[0; WIDTH]; tree.pairs.len()] };
        plan.solve(tree, &tree.root);
        plan
    }

    /// Fills the tables for interior node `node`'s pair and the pairs below it.
    fn solve(&mut self, tree: &BinaryTree, node: &Node) {
        let pair = node.index() as usize;
        let [left, right] = *tree.children(node);
        for child in [&left, &right] {
            if !child.is_leaf() {
                self.solve(tree, child);
            }
        }
        // The best way for the two children to share `k` lanes (each needs at least one).
        let share = |plan: &CollapsePlan, k: usize| -> (f64, usize) {
            let mut best = (f64::INFINITY, 0);
            for left_lanes in 1..k {
                let c = plan.subtree_cost(&left, left_lanes) + plan.subtree_cost(&right, k - left_lanes);
                if c < best.0 {
                    best = (c, left_lanes);
                }
            }
            best
        };
        let (inside, inside_split) = share(self, WIDTH);
        let closed = node.half_area() as f64 + inside;
        self.cost[pair][0] = closed;
        self.split[pair][0] = inside_split as u8;
        for k in 2..=WIDTH {
            let (opened, left_lanes) = share(self, k);
            // Opening wins only when strictly cheaper (a flat node of zero area stays closed).
            let (c, s) = if opened < closed { (opened, left_lanes) } else { (closed, 0) };
            self.cost[pair][k - 1] = c;
            self.split[pair][k - 1] = s as u8;
        }
    }

    /// The least summed area of the wide nodes in `node`'s subtree when it may fill `lanes`
    /// lanes of the wide node above it (a leaf fills one lane and adds nothing).
    fn subtree_cost(&self, node: &Node, lanes: usize) -> f64 {
        if node.is_leaf() { 0.0 } else { self.cost[node.index() as usize][lanes - 1] }
    }

    /// The lanes given to the left child of the interior node whose children are `pair`, when
    /// its subtree may fill `lanes ≥ 2` lanes (0: the node stays closed).
    fn split(&self, pair: u32, lanes: usize) -> usize {
        self.split[pair as usize][lanes - 1] as usize
    }

    /// The lanes given to the left child of the interior node whose children are `pair` inside
    /// the wide node it becomes.
    fn inside_split(&self, pair: u32) -> usize {
        self.split[pair as usize][0] as usize
    }

    /// Appends the children that `node`'s subtree contributes to the wide node above it when it
    /// may fill `lanes` lanes: itself, or (when opened) its children's contributions.
    fn frontier(&self, tree: &BinaryTree, node: &Node, lanes: usize, out: &mut ArrayVec<Node, WIDTH>) {
        let left_lanes = if node.is_leaf() || lanes == 1 { 0 } else { self.split(node.index(), lanes) };
        if left_lanes == 0 {
            out.push(*node);
            return;
        }
        let [left, right] = *tree.children(node);
        self.frontier(tree, &left, left_lanes, out);
        self.frontier(tree, &right, lanes - left_lanes, out);
    }
}

fn set_child(node: &mut WideNode, lane: usize, child: &Node, child_index: u32) {
    node.set_box(lane, child);
    node.meta[lane] = if child.is_leaf() { child.count() } else { INTERIOR };
    node.child[lane] = child_index;
}
