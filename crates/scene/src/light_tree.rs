//! A light sampler that conditions on the receiving point: a binary tree over the finite
//! lights (pbrt-v4's BVH light sampler, "Physically Based Rendering" 4th ed., §12.6.3).
//!
//! Every node holds the [`LightBounds`] of the lights below it. Sampling descends from the
//! root and at each node picks a child with probability proportional to its
//! [`LightBounds::importance`] for the receiver `(p, n)`; the probability of a light is the
//! product of its branch probabilities, which [`LightTree::probability`] recomputes by walking
//! from the light's leaf up to the root. A light gets probability zero only where its bounds
//! (and so the light) cannot send light to `p`.
//!
//! Infinite lights (directional, environments) are not in the tree: the first choice is among
//! them and the tree, with the probabilities the scene-global selection gives them and the sum
//! of the finite lights' (`pick(i)` in [`LightTree::build`]), so that the share of infinite
//! against finite light is the same for both samplers and only its split among the finite
//! lights depends on the point.
//!
//! The build is O(n log n): binned splits over 12 buckets per axis with pbrt-v4's cost
//! ([`LightBounds::cost`]), each side holding at least 1/16 of the lights (so the depth is at
//! most about 11·ln n), and a median split of the centroids when no binned split qualifies.
//! One leaf per light; 2n − 1 nodes.

use math::{Aabb, Vec3};

use crate::light::{BoundingSphere, Light};
use crate::light_tree_bounds::LightBounds;

/// Buckets per axis of the binned split.
const BUCKETS: usize = 12;
/// Marks a light without a leaf.
const NONE: u32 = u32::MAX;
/// Largest `f32` below one (remapped sample numbers stay in [0, 1)).
const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// One node: the bounds of its lights, its parent, and its first child (the second follows
/// it) or, for a leaf, its light.
#[derive(Clone, Copy, Debug)]
struct Node {
    bounds: LightBounds,
    parent: u32,
    child_or_light: u32,
    leaf: bool,
}

/// The light tree with the choice between infinite lights and the tree (see the module).
#[derive(Clone, Debug, Default)]
pub struct LightTree {
    nodes: Vec<Node>,
    /// By light index: its leaf node, or [`NONE`].
    leaf_of: Vec<u32>,
    /// Infinite lights that can be picked, with their probabilities.
    infinite: Vec<(u32, f32)>,
    /// Probability of choosing the tree.
    tree_probability: f32,
}

impl LightTree {
    /// Builds the tree over the finite lights with positive power ([`Light::bounds`]);
    /// `pick(i)` is light `i`'s scene-global pick probability (e.g.
    /// [`crate::Scene::light_pick_probability`]), which sets the choice between the infinite
    /// lights and the tree. Nothing is ever picked when every `pick(i)` is zero.
    pub fn build(lights: &[Light], sphere: &BoundingSphere, pick: impl Fn(u32) -> f32) -> Self {
        let mut items: Vec<(u32, LightBounds)> =
            lights.iter().enumerate().filter_map(|(i, l)| l.bounds(sphere).map(|b| (i as u32, b))).collect();
        let finite: f64 = items.iter().map(|(i, _)| f64::from(pick(*i).max(0.0))).sum();
        let infinite: Vec<(u32, f32)> = (0..lights.len() as u32)
            .filter(|&i| !lights[i as usize].is_finite() && pick(i) > 0.0)
            .map(|i| (i, pick(i)))
            .collect();
        let total = finite + infinite.iter().map(|(_, p)| f64::from(*p)).sum::<f64>();
        let mut tree = LightTree { leaf_of: vec![NONE; lights.len()], ..Self::default() };
        if !(total > 0.0 && total.is_finite()) {
            return tree;
        }
        tree.infinite = infinite.into_iter().map(|(i, p)| (i, (f64::from(p) / total) as f32)).collect();
        if !items.is_empty() && finite > 0.0 {
            tree.tree_probability = (finite / total) as f32;
            tree.nodes.reserve(2 * items.len() - 1);
            tree.nodes.push(Node { bounds: items[0].1, parent: NONE, child_or_light: NONE, leaf: true });
            tree.build_node(&mut items, 0, NONE);
        }
        tree
    }

    /// Fills node `index` (already pushed) with the lights `items`.
    fn build_node(&mut self, items: &mut [(u32, LightBounds)], index: usize, parent: u32) {
        let bounds = items[1..].iter().fold(items[0].1, |b, (_, other)| b.union(other));
        if let [(light, _)] = items {
            self.nodes[index] = Node { bounds, parent, child_or_light: *light, leaf: true };
            self.leaf_of[*light as usize] = index as u32;
            return;
        }
        let mid = split(items, &bounds.bounds);
        let first = self.nodes.len();
        let placeholder = Node { bounds, parent: index as u32, child_or_light: NONE, leaf: true };
        self.nodes.extend([placeholder, placeholder]);
        self.nodes[index] = Node { bounds, parent, child_or_light: first as u32, leaf: false };
        let (left, right) = items.split_at_mut(mid);
        self.build_node(left, first, index as u32);
        self.build_node(right, first + 1, index as u32);
    }

    /// Number of nodes (2n − 1 for n finite lights with positive power).
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Picks a light for a receiver at `p` with unit normal `n` (the zero vector for a point in
    /// a medium: no cosine bound) from one uniform number `u` ∈ [0, 1). Returns the light's
    /// index and its (discrete) probability, which [`LightTree::probability`] reproduces;
    /// `None` when no light can reach `p`.
    pub fn sample(&self, p: Vec3, n: Vec3, u: f32) -> Option<(u32, f32)> {
        let mut u = u.clamp(0.0, ONE_MINUS_EPSILON);
        for &(light, probability) in &self.infinite {
            if u < probability {
                return Some((light, probability));
            }
            u -= probability;
        }
        if self.nodes.is_empty() || self.tree_probability <= 0.0 {
            return None;
        }
        let mut u = (u / self.tree_probability).clamp(0.0, ONE_MINUS_EPSILON);
        let mut pmf = self.tree_probability;
        let mut node = &self.nodes[0];
        while !node.leaf {
            let first = node.child_or_light as usize;
            let left = self.nodes[first].bounds.importance(p, n);
            let right = self.nodes[first + 1].bounds.importance(p, n);
            let total = left + right;
            if total <= 0.0 {
                return None;
            }
            let p_left = left / total;
            if u < p_left {
                u = (u / p_left).min(ONE_MINUS_EPSILON);
                pmf *= p_left;
                node = &self.nodes[first];
            } else {
                u = ((u - p_left) / (1.0 - p_left)).clamp(0.0, ONE_MINUS_EPSILON);
                pmf *= right / total;
                node = &self.nodes[first + 1];
            }
        }
        Some((node.child_or_light, pmf))
    }

    /// Probability with which [`LightTree::sample`] picks light `light` for the receiver
    /// `(p, n)` (0 for lights that cannot be picked there or at all).
    pub fn probability(&self, p: Vec3, n: Vec3, light: u32) -> f32 {
        if let Some(&(_, probability)) = self.infinite.iter().find(|(i, _)| *i == light) {
            return probability;
        }
        let Some(&leaf) = self.leaf_of.get(light as usize).filter(|&&l| l != NONE) else {
            return 0.0;
        };
        let mut pmf = self.tree_probability;
        let mut node = leaf as usize;
        while node != 0 {
            let parent = self.nodes[node].parent as usize;
            let first = self.nodes[parent].child_or_light as usize;
            let sibling = if node == first { first + 1 } else { first };
            let own = self.nodes[node].bounds.importance(p, n);
            let total = own + self.nodes[sibling].bounds.importance(p, n);
            if total <= 0.0 {
                return 0.0;
            }
            pmf *= own / total;
            node = parent;
        }
        pmf
    }
}

/// Reorders `items` into two non-empty halves and returns the size of the first (see the
/// module); `bounds` is the box of all their emitting points.
fn split(items: &mut [(u32, LightBounds)], bounds: &Aabb) -> usize {
    let n = items.len();
    let centroids = items.iter().fold(Aabb::EMPTY, |b, (_, l)| b.grow(l.bounds.center()));
    let min_side = (n / 16).max(1);
    let extent = bounds.extent();
    let max_extent = extent.max_element();
    let bucket_of = |c: f32, axis: usize| {
        let (lo, hi) = (centroids.min[axis], centroids.max[axis]);
        (((c - lo) / (hi - lo) * BUCKETS as f32) as usize).min(BUCKETS - 1)
    };
    let mut best: Option<(f32, usize, usize)> = None;
    for axis in 0..3 {
        if centroids.max[axis] <= centroids.min[axis] {
            continue;
        }
        let mut buckets: [Option<LightBounds>; BUCKETS] = [None; BUCKETS];
        let mut counts = [0usize; BUCKETS];
        for (_, l) in items.iter() {
            let b = bucket_of(l.bounds.center()[axis], axis);
            counts[b] += 1;
            buckets[b] = Some(buckets[b].map_or(*l, |u| u.union(l)));
        }
        let join = |a: Option<LightBounds>, b: Option<LightBounds>| match (a, b) {
            (Some(a), Some(b)) => Some(a.union(&b)),
            (a, None) => a,
            (None, b) => b,
        };
        let mut below = [None; BUCKETS];
        let mut acc = None;
        for s in 0..BUCKETS {
            acc = join(acc, buckets[s]);
            below[s] = acc;
        }
        let (mut above, mut count_above) = (None, 0usize);
        let kr = if extent[axis] > 0.0 { max_extent / extent[axis] } else { 1.0 };
        for s in (1..BUCKETS).rev() {
            above = join(above, buckets[s]);
            count_above += counts[s];
            let count_below = n - count_above;
            if count_below < min_side || count_above < min_side {
                continue;
            }
            let (Some(lo), Some(hi)) = (below[s - 1], above) else { continue };
            let cost = kr * (lo.cost() + hi.cost());
            if cost.is_finite() && best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, s));
            }
        }
    }
    if let Some((_, axis, s)) = best {
        let mut first = 0;
        for j in 0..n {
            if bucket_of(items[j].1.bounds.center()[axis], axis) < s {
                items.swap(first, j);
                first += 1;
            }
        }
        if first > 0 && first < n {
            return first;
        }
    }
    let axis = (centroids.max - centroids.min).max_position();
    let mid = n / 2;
    items.select_nth_unstable_by(mid, |a, b| a.1.bounds.center()[axis].total_cmp(&b.1.bounds.center()[axis]));
    mid
}

#[cfg(test)]
mod tests {
    #[test]
    fn nodes_are_64_bytes() {
        // docs/lights-suite.md states the tree's memory from this.
        assert_eq!(std::mem::size_of::<super::Node>(), 64);
    }
}
