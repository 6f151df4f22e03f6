//! The previous traversal of the binary tree, kept only for A/B comparisons against the 4-wide
//! tree (benchmarks behind the `binary-bvh` feature, and tests). Not a production path.
//!
//! It is the traversal the renderer used before the wide tree: scalar slab tests of both
//! children of a pair, the nearer child first, and of equally near primitive hits the first one
//! found is kept.

use arrayvec::ArrayVec;
use math::{Aabb, Ray};

use super::binary::{BinaryTree, Node};
use super::ray_box::ROBUST_EXIT;
use super::traverse::Tally;
use super::{BvhStats, MAX_DEPTH, TraversalCounts, build};

/// The binary SAH tree with its own traversal (see the module documentation).
#[derive(Clone, Debug)]
pub struct BinaryBvh {
    tree: BinaryTree,
}

/// Ray data precomputed for the scalar slab test.
struct RayBoxTest {
    origin: [f32; 3],
    inverse_direction: [f32; 3],
    /// Index into [`Node::v`] of the near plane per axis (min when the direction is positive).
    near: [usize; 3],
}

impl RayBoxTest {
    #[inline(always)]
    fn new(ray: &Ray) -> Self {
        let d = ray.direction;
        let inverse_direction = [1.0 / d.x, 1.0 / d.y, 1.0 / d.z];
        let near = [
            if d.x.is_sign_negative() { 4 } else { 0 },
            if d.y.is_sign_negative() { 5 } else { 1 },
            if d.z.is_sign_negative() { 6 } else { 2 },
        ];
        Self { origin: ray.origin.to_array(), inverse_direction, near }
    }

    /// Distance at which the ray enters `node`'s box within `(0, t_max]`, or `+∞` on a miss
    /// (NaN plane distances are ignored, as in `ray_box.rs`).
    #[inline(always)]
    fn entry(&self, node: &Node, t_max: f32) -> f32 {
        let v = &node.v;
        let mut t_enter = 0.0f32;
        let mut t_exit = t_max;
        for axis in 0..3 {
            let near = self.near[axis] & 7;
            let far = near ^ 4;
            let t_near = (f32::from_bits(v[near]) - self.origin[axis]) * self.inverse_direction[axis];
            let t_far = (f32::from_bits(v[far]) - self.origin[axis]) * self.inverse_direction[axis];
            if t_near > t_enter {
                t_enter = t_near;
            }
            if t_far < t_exit {
                t_exit = t_far;
            }
        }
        if t_enter <= t_exit * ROBUST_EXIT { t_enter } else { f32::INFINITY }
    }
}

impl BinaryBvh {
    /// Builds the binary SAH tree (the same tree [`super::Bvh::build`] collapses).
    pub fn build(bounds: &[Aabb]) -> BinaryBvh {
        BinaryBvh { tree: build::build_binary(bounds) }
    }

    /// Statistics of the binary tree (the wide-node fields are 0).
    pub fn stats(&self) -> BvhStats {
        self.tree.stats
    }

    #[inline(always)]
    fn leaf_prims<'a>(&'a self, node: &'a Node) -> &'a [u32] {
        let count = node.count() as usize;
        if count == 1 {
            std::slice::from_ref(&node.v[3])
        } else {
            let first = node.index() as usize;
            &self.tree.prims[first..first + count]
        }
    }

    /// Nearest hit, with the contract of [`super::Bvh::closest_hit`] except the tie rule: of
    /// equally near hits the first one found is kept. Adds its work to `counts` .
    pub fn closest_hit_counted(
        &self,
        ray: &Ray,
        t_max: f32,
        intersect: impl FnMut(u32, &Ray, f32) -> Option<f32>,
        counts: &mut TraversalCounts,
    ) -> Option<(u32, f32)> {
        self.closest_hit_with(ray, t_max, intersect, counts)
    }

    #[inline(always)]
    fn closest_hit_with(
        &self,
        ray: &Ray,
        t_max: f32,
        mut intersect: impl FnMut(u32, &Ray, f32) -> Option<f32>,
        counts: &mut impl Tally,
    ) -> Option<(u32, f32)> {
        if self.tree.prims.is_empty() || t_max.is_nan() || t_max <= 0.0 {
            return None;
        }
        let test = RayBoxTest::new(ray);
        counts.root_box();
        if test.entry(&self.tree.root, t_max) == f32::INFINITY {
            return None;
        }
        let mut t_best = t_max;
        let mut best = None;
        let mut stack: ArrayVec<(&Node, f32), MAX_DEPTH> = ArrayVec::new();
        let mut node = &self.tree.root;
        loop {
            if node.is_leaf() {
                for &prim in self.leaf_prims(node) {
                    counts.primitive();
                    if let Some(t) = intersect(prim, ray, t_best).filter(|&t| t < t_best) {
                        t_best = t;
                        best = Some(prim);
                    }
                }
            } else {
                counts.node(2);
                let [left, right] = self.tree.children(node);
                let t_left = test.entry(left, t_best);
                let t_right = test.entry(right, t_best);
                if t_left != f32::INFINITY {
                    if t_right != f32::INFINITY {
                        let (near, far, t_far) =
                            if t_left <= t_right { (left, right, t_right) } else { (right, left, t_left) };
                        stack.push((far, t_far));
                        node = near;
                    } else {
                        node = left;
                    }
                    continue;
                } else if t_right != f32::INFINITY {
                    node = right;
                    continue;
                }
            }
            loop {
                let Some((next, t_enter)) = stack.pop() else {
                    return best.map(|prim| (prim, t_best));
                };
                if t_enter <= t_best * ROBUST_EXIT {
                    node = next;
                    break;
                }
            }
        }
    }

    /// Whether anything blocks `ray` before `t_max`, with the contract of
    /// [`super::Bvh::any_hit`]. Adds its work to `counts` (as above).
    pub fn any_hit_counted(
        &self,
        ray: &Ray,
        t_max: f32,
        occluded: impl FnMut(u32, &Ray, f32) -> bool,
        counts: &mut TraversalCounts,
    ) -> bool {
        self.any_hit_with(ray, t_max, occluded, counts)
    }

    #[inline(always)]
    fn any_hit_with(
        &self,
        ray: &Ray,
        t_max: f32,
        mut occluded: impl FnMut(u32, &Ray, f32) -> bool,
        counts: &mut impl Tally,
    ) -> bool {
        if self.tree.prims.is_empty() || t_max.is_nan() || t_max <= 0.0 {
            return false;
        }
        let test = RayBoxTest::new(ray);
        counts.root_box();
        if test.entry(&self.tree.root, t_max) == f32::INFINITY {
            return false;
        }
        let mut stack: ArrayVec<&Node, MAX_DEPTH> = ArrayVec::new();
        let mut node = &self.tree.root;
        loop {
            if node.is_leaf() {
                for &prim in self.leaf_prims(node) {
                    counts.primitive();
                    if occluded(prim, ray, t_max) {
                        return true;
                    }
                }
            } else {
                counts.node(2);
                let [left, right] = self.tree.children(node);
                let t_left = test.entry(left, t_max);
                let t_right = test.entry(right, t_max);
                if t_left != f32::INFINITY {
                    if t_right != f32::INFINITY {
                        let (near, far) = if t_left <= t_right { (left, right) } else { (right, left) };
                        stack.push(far);
                        node = near;
                    } else {
                        node = left;
                    }
                    continue;
                } else if t_right != f32::INFINITY {
                    node = right;
                    continue;
                }
            }
            let Some(next) = stack.pop() else { return false };
            node = next;
        }
    }

    /// Nearest hit without counting (for timing).
    #[inline]
    pub fn closest_hit(
        &self,
        ray: &Ray,
        t_max: f32,
        intersect: impl FnMut(u32, &Ray, f32) -> Option<f32>,
    ) -> Option<(u32, f32)> {
        self.closest_hit_with(ray, t_max, intersect, &mut ())
    }

    /// Any hit without counting (for timing).
    #[inline]
    pub fn any_hit(&self, ray: &Ray, t_max: f32, occluded: impl FnMut(u32, &Ray, f32) -> bool) -> bool {
        self.any_hit_with(ray, t_max, occluded, &mut ())
    }
}
