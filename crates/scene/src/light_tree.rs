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

    /// The infinite light that [`LightTree::sample`] picks for `u` (they are picked first, for
    /// any receiver), or `None` when `u` falls to the tree's finite lights.
    #[inline]
    pub fn pick_infinite(&self, u: f32) -> Option<u32> {
        self.pick_among_infinite(u).ok().map(|(light, _)| light)
    }

    /// The infinite light that `u` (clamped into [0, 1)) falls on and its probability, or what
    /// is left of `u` past their shares.
    #[inline]
    fn pick_among_infinite(&self, u: f32) -> Result<(u32, f32), f32> {
        let mut u = u.clamp(0.0, ONE_MINUS_EPSILON);
        for &(light, probability) in &self.infinite {
            if u < probability {
                return Ok((light, probability));
            }
            u -= probability;
        }
        Err(u)
    }

    /// Picks a light for a receiver at `p` with unit normal `n` (the zero vector for a point in
    /// a medium: no cosine bound) from one uniform number `u` ∈ [0, 1). Returns the light's
    /// index and its (discrete) probability, which [`LightTree::probability`] reproduces;
    /// `None` when no light can reach `p`.
    pub fn sample(&self, p: Vec3, n: Vec3, u: f32) -> Option<(u32, f32)> {
        let u = match self.pick_among_infinite(u) {
            Ok(pick) => return Some(pick),
            Err(rest) => rest,
        };
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
    use super::LightTree;
    use crate::light::{AreaLight, BoundingSphere, Light};
    use crate::shape::Triangle;
    use math::{Frame, Rng, Vec3};
    use spectrum::Rgb;

    #[test]
    fn nodes_are_64_bytes() {
        // docs/lights-suite.md states the tree's memory from this.
        assert_eq!(std::mem::size_of::<super::Node>(), 64);
    }

    fn sphere() -> BoundingSphere {
        BoundingSphere { center: Vec3::ZERO, radius: 10.0 }
    }

    /// A thin emitting slab like the area light of Mitsuba's `test_homo_area_light`: a tilted
    /// 2.4 × 0.72 × 0.15 box centred at `(2.2, −0.2, −0.2)`, 12 one-sided triangles with
    /// outward normals.
    fn slab() -> Vec<Light> {
        let frame = Frame::from_z(Vec3::new(0.86, 0.28, -0.43).normalize());
        let center = Vec3::new(2.2, -0.2, -0.2);
        let half = [frame.x * 1.2, frame.y * 0.36, frame.z * 0.077];
        let mut lights = Vec::new();
        for axis in 0..3 {
            for sign in [-1.0f32, 1.0] {
                let (a, b) = (half[(axis + 1) % 3], half[(axis + 2) % 3]);
                let c = center + half[axis] * sign;
                let corners = [c - a - b, c + a - b, c + a + b, c - a + b];
                for t in [[0, 1, 2], [0, 2, 3]] {
                    let mut tri = Triangle::new(corners[t[0]], corners[t[1]], corners[t[2]]);
                    if tri.normal.dot(half[axis] * sign) < 0.0 {
                        tri = Triangle::new(corners[t[0]], corners[t[2]], corners[t[1]]);
                    }
                    lights.push(Light::Area(AreaLight::new(tri, Rgb::new(18.4, 11.0, 8.75))));
                }
            }
        }
        lights
    }

    /// Points of the scene's medium sphere (centre `(0, −0.1, 0)`, radius 0.75).
    fn medium_points(rng: &mut Rng, count: usize) -> Vec<Vec3> {
        let mut points = Vec::new();
        while points.len() < count {
            let q = Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 1.5 - Vec3::splat(0.75);
            if q.length() <= 0.75 {
                points.push(q + Vec3::new(0.0, -0.1, 0.0));
            }
        }
        points
    }

    fn tree_and_power(lights: &[Light]) -> (LightTree, Vec<f32>) {
        let powers: Vec<f32> = lights.iter().map(|l| l.power(&sphere())).collect();
        let total: f32 = powers.iter().sum();
        let pick: Vec<f32> = powers.iter().map(|p| p / total).collect();
        (LightTree::build(lights, &sphere(), |i| pick[i as usize]), pick)
    }

    /// The mean luminance a light sends to a medium point per unit phase function (unoccluded):
    /// `E[L / p_ω]` over its direct samples (solid-angle measure).
    fn contribution(light: &Light, p: Vec3, rng: &mut Rng) -> f64 {
        let samples = 256;
        let sum: f64 = (0..samples)
            .filter_map(|_| light.sample_direct(p, rng.uniform2(), &sphere()))
            .filter(|d| d.direct_pdf.0 > 0.0)
            .map(|d| f64::from(d.radiance.luminance() / d.direct_pdf.0))
            .sum();
        sum / f64::from(samples)
    }

    #[test]
    fn without_a_normal_the_importance_drops_only_the_receiver_cosine() {
        // A point in a medium (n = 0): the bound is the largest over all receiver normals (the
        // cosine factor is at most one), never zero where an emitter faces the point, and the
        // same bound a normal along the direction to the light gives.
        let lights = slab();
        let mut rng = Rng::new(11, 0);
        for p in medium_points(&mut rng, 200) {
            for light in &lights {
                let b = light.bounds(&sphere()).unwrap();
                let free = b.importance(p, Vec3::ZERO);
                assert!(free.is_finite() && free >= 0.0);
                let towards = (b.bounds.center() - p).normalize();
                let along = b.importance(p, towards);
                assert!((along - free).abs() <= 1e-5 * free, "{along} against {free} at {p}");
                for _ in 0..8 {
                    let n = math::warp::uniform_sphere(rng.uniform2());
                    assert!(b.importance(p, n) <= free * (1.0 + 1e-5), "a normal raised the bound at {p}");
                }
                let faces = (b.bounds.center() - p).dot(b.axis) < 0.0;
                if faces {
                    assert!(free > 0.0, "an emitter facing {p} has importance zero");
                }
            }
        }
    }

    #[test]
    fn at_medium_points_the_frequencies_follow_probability() {
        let lights = slab();
        let (tree, _) = tree_and_power(&lights);
        let mut rng = Rng::new(12, 0);
        let samples = 100_000u32;
        for p in medium_points(&mut rng, 4) {
            let mut counts = vec![0u32; lights.len() + 1];
            for _ in 0..samples {
                match tree.sample(p, Vec3::ZERO, rng.uniform()) {
                    Some((i, pmf)) => {
                        let again = tree.probability(p, Vec3::ZERO, i);
                        assert!((pmf - again).abs() <= 1e-5 * pmf, "sample {pmf}, probability {again}");
                        counts[i as usize] += 1;
                    }
                    None => counts[lights.len()] += 1,
                }
            }
            let mut expected: Vec<f64> = (0..lights.len() as u32)
                .map(|i| f64::from(samples) * f64::from(tree.probability(p, Vec3::ZERO, i)))
                .collect();
            expected.push((f64::from(samples) - expected.iter().sum::<f64>()).max(0.0));
            let chi2 = |expected: &[f64]| {
                // Cells expected fewer than 5 times are pooled.
                let (mut statistic, mut cells, mut po, mut pe) = (0.0, 0u32, 0.0, 0.0);
                for (&o, &e) in counts.iter().zip(expected) {
                    if e < 5.0 {
                        (po, pe) = (po + f64::from(o), pe + e);
                    } else {
                        statistic += (f64::from(o) - e).powi(2) / e;
                        cells += 1;
                    }
                }
                if pe > 0.0 {
                    statistic += (po - pe).powi(2) / pe.max(1e-9);
                    cells += 1;
                }
                (statistic, f64::from(cells - 1))
            };
            // Upper 0.1 % point of χ²(k) (Wilson–Hilferty).
            let critical = |k: f64| {
                let a = 2.0 / (9.0 * k);
                k * (1.0 - a + 3.0902 * a.sqrt()).powi(3)
            };
            let (statistic, k) = chi2(&expected);
            assert!(statistic < critical(k), "χ² = {statistic} with {k} degrees of freedom at {p}");
            // Power: moving 5 % of the most likely light's mass to the least likely fails.
            let order: Vec<usize> = {
                let mut o: Vec<usize> = (0..lights.len()).filter(|&i| expected[i] >= 5.0).collect();
                o.sort_by(|&a, &b| expected[a].total_cmp(&expected[b]));
                o
            };
            let (low, top) = (order[0], order[order.len() - 1]);
            let mut wrong = expected.clone();
            wrong[low] += 0.05 * wrong[top];
            wrong[top] *= 0.95;
            let (bad, _) = chi2(&wrong);
            assert!(bad > critical(k), "a 5 % shift passes: χ² = {bad}");
        }
    }

    #[test]
    fn at_medium_points_the_tree_selects_better_than_power() {
        // The variance factor of the light choice alone, Σ c_i² / p_i / (Σ c_i)² (1 for a
        // choice in proportion to the true contributions c_i, here estimated by sampling each
        // light), averaged over points of the medium sphere beside the slab: the tree's must be
        // lower than the power selection's, and it must give every contributing light a
        // positive probability.
        let lights = slab();
        let (tree, power) = tree_and_power(&lights);
        let mut rng = Rng::new(13, 0);
        let (mut with_tree, mut with_power) = (0.0, 0.0);
        let points = medium_points(&mut rng, 60);
        for &p in &points {
            let c: Vec<f64> = lights.iter().map(|l| contribution(l, p, &mut rng)).collect();
            let total: f64 = c.iter().sum();
            assert!(total > 0.0);
            let factor = |pick: &dyn Fn(usize) -> f64| {
                c.iter().enumerate().filter(|(_, c)| **c > 0.0).map(|(i, c)| c * c / pick(i)).sum::<f64>()
                    / (total * total)
            };
            for (i, ci) in c.iter().enumerate() {
                assert!(*ci == 0.0 || tree.probability(p, Vec3::ZERO, i as u32) > 0.0, "light {i} at {p}");
            }
            with_tree += factor(&|i| f64::from(tree.probability(p, Vec3::ZERO, i as u32)));
            with_power += factor(&|i| f64::from(power[i]));
        }
        let n = points.len() as f64;
        let (with_tree, with_power) = (with_tree / n, with_power / n);
        eprintln!("selection variance factor at medium points: tree {with_tree:.3}, power {with_power:.3}");
        assert!(with_tree < 0.9 * with_power, "tree {with_tree} against power {with_power}");
    }
}
