//! Construction of the binary SAH tree from primitive bounds: binned SAH over box centroids,
//! parallel with rayon for large inputs, deterministic for any thread count.
//!
//! This file owns only the build; the 8-wide tree that queries use is collapsed from its output
//! (`wide.rs`). See `docs/bvh.md`.

use glam::Vec4;
use math::{Aabb, Vec3A};
use rayon::prelude::*;

use super::binary::{BinaryTree, Node, NodePair};
use super::{BvhStats, MAX_DEPTH};

/// Largest number of primitives in a leaf. Smaller leaves are chosen whenever the SAH says so.
pub(super) const MAX_LEAF_SIZE: usize = 4;
/// Number of SAH bins per axis.
const BIN_COUNT: usize = 16;
/// Subtrees with at least this many primitives are built in parallel.
pub(super) const PARALLEL_THRESHOLD: usize = 2048;
/// Nodes with at least this many primitives compute their bins in parallel.
pub(super) const PARALLEL_BINNING_THRESHOLD: usize = 1 << 16;
/// SAH cost of traversing an interior node (testing its two child boxes), relative to
/// [`COST_INTERSECT`].
const COST_TRAVERSAL: f32 = 1.0;
/// SAH cost of intersecting one primitive.
const COST_INTERSECT: f32 = 1.0;
/// Primitive bounds are clamped to `[-BOUNDS_LIMIT, BOUNDS_LIMIT]` so that surface areas and SAH
/// costs stay free of infinities and NaNs (an infinite primitive is cut off there).
const BOUNDS_LIMIT: f32 = 1e18;

/// Builds the binary tree over primitive bounds; primitive ids are indices into `bounds`.
///
/// Leaves hold at most [`MAX_LEAF_SIZE`] primitives. Primitives whose box is empty or contains
/// a NaN can never be hit and are left out; coordinates beyond ±1e18 are clamped. An input
/// without primitives gives a tree with an empty `prims`.
pub(super) fn build_binary(bounds: &[Aabb]) -> BinaryTree {
    assert!(bounds.len() < u32::MAX as usize, "too many primitives for a BVH");
    let to_ref = |(id, b): (usize, &Aabb)| {
        // `!(min <= max)` also rejects NaN.
        if !(b.min.x <= b.max.x && b.min.y <= b.max.y && b.min.z <= b.max.z) {
            return None;
        }
        let limit = Vec3A::splat(BOUNDS_LIMIT);
        let min = Vec3A::from(b.min).clamp(-limit, limit);
        let max = Vec3A::from(b.max).clamp(-limit, limit);
        Some(PrimRef { lo: min.extend(f32::from_bits(id as u32)), hi: max })
    };
    let mut refs: Vec<PrimRef> = if bounds.len() >= PARALLEL_THRESHOLD {
        bounds.par_iter().enumerate().filter_map(to_ref).collect()
    } else {
        bounds.iter().enumerate().filter_map(to_ref).collect()
    };
    if refs.is_empty() {
        return BinaryTree { root: Node::default(), pairs: Vec::new(), prims: Vec::new(), stats: BvhStats::default() };
    }

    let n = refs.len();
    let (node_box, centroid_box) = bounds_of(&refs);
    // A subtree over k primitives has at most k − 1 interior nodes, each owning one child pair;
    // every subtree gets such a range, so parallel subtrees write disjoint slices. The holes
    // left by leaves holding several primitives are squeezed out afterwards.
    let mut sparse = vec![NodePair::default(); n - 1];
    let builder = Builder { first: 0, pair_base: 0, depth: 0 };
    let mut root = builder.build(&mut refs, node_box, centroid_box, &mut sparse);

    let mut pairs = Vec::with_capacity(n / 2 + 1);
    let mut stats = BvhStats { primitives: n, ..BvhStats::default() };
    let root_area = node_box.half_area();
    compact(&sparse, &mut root, &mut pairs, 0, root_area, &mut stats);
    drop(sparse);
    let prims = refs.iter().map(|r| r.id()).collect();
    BinaryTree { root, pairs, prims, stats }
}

/// A primitive during the build: its box, with its id in the fourth lane of the lower corner.
#[derive(Clone, Copy, Debug)]
struct PrimRef {
    lo: Vec4,
    hi: Vec3A,
}

impl PrimRef {
    #[inline(always)]
    fn min(&self) -> Vec3A {
        Vec3A::from_vec4(self.lo)
    }

    #[inline(always)]
    fn max(&self) -> Vec3A {
        self.hi
    }

    /// Twice the box centre (the factor 2 cancels everywhere it is used).
    #[inline(always)]
    fn centroid2(&self) -> Vec3A {
        self.min() + self.hi
    }

    fn id(&self) -> u32 {
        self.lo.w.to_bits()
    }
}

/// A box with SIMD corners, used during the build.
#[derive(Clone, Copy, Debug)]
struct Box3 {
    min: Vec3A,
    max: Vec3A,
}

impl Box3 {
    const EMPTY: Box3 = Box3 { min: Vec3A::INFINITY, max: Vec3A::NEG_INFINITY };

    #[inline(always)]
    fn union(self, other: Box3) -> Box3 {
        Box3 { min: self.min.min(other.min), max: self.max.max(other.max) }
    }

    #[inline(always)]
    fn grow(self, p: Vec3A) -> Box3 {
        Box3 { min: self.min.min(p), max: self.max.max(p) }
    }

    /// Half the surface area; 0 for the empty box.
    #[inline(always)]
    fn half_area(&self) -> f32 {
        let e = (self.max - self.min).max(Vec3A::ZERO);
        e.x * e.y + e.y * e.z + e.z * e.x
    }
}

/// Box of the primitives and box of their (doubled) centroids, in parallel for large inputs.
fn bounds_of(refs: &[PrimRef]) -> (Box3, Box3) {
    let fold =
        |(b, c): (Box3, Box3), r: &PrimRef| (b.union(Box3 { min: r.min(), max: r.max() }), c.grow(r.centroid2()));
    let identity = || (Box3::EMPTY, Box3::EMPTY);
    if refs.len() >= PARALLEL_BINNING_THRESHOLD {
        refs.par_chunks(1 << 14)
            .map(|chunk| chunk.iter().fold(identity(), fold))
            .reduce(identity, |(a, b), (c, d)| (a.union(c), b.union(d)))
    } else {
        refs.iter().fold(identity(), fold)
    }
}

/// A bin of the SAH sweep: box of its primitives and their number.
#[derive(Clone, Copy, Debug)]
struct Bin {
    bounds: Box3,
    count: u32,
}

type Bins = [[Bin; BIN_COUNT]; 3];

const EMPTY_BINS: Bins = [[Bin { bounds: Box3::EMPTY, count: 0 }; BIN_COUNT]; 3];

/// Maps doubled centroids to bins: `bin = min(⌊(c − origin)·scale⌋, BIN_COUNT − 1)` per axis.
#[derive(Clone, Copy, Debug)]
struct Binning {
    origin: Vec3A,
    scale: Vec3A,
}

impl Binning {
    fn new(centroids: &Box3) -> Self {
        let extent = centroids.max - centroids.min;
        let s = |e: f32| if e > 0.0 { BIN_COUNT as f32 / e } else { 0.0 };
        Self { origin: centroids.min, scale: Vec3A::new(s(extent.x), s(extent.y), s(extent.z)) }
    }

    #[inline(always)]
    fn bins(&self, c: Vec3A) -> [usize; 3] {
        let b = ((c - self.origin) * self.scale).min(Vec3A::splat((BIN_COUNT - 1) as f32));
        [b.x as usize, b.y as usize, b.z as usize]
    }

    /// Same arithmetic as [`Binning::bins`] for one axis, so that partitioning agrees with binning.
    #[inline(always)]
    fn bin(&self, c: Vec3A, axis: usize) -> usize {
        let b = ((c[axis] - self.origin[axis]) * self.scale[axis]).min((BIN_COUNT - 1) as f32);
        b as usize
    }

    fn fill(&self, refs: &[PrimRef]) -> Bins {
        let mut bins = EMPTY_BINS;
        for r in refs {
            let b = self.bins(r.centroid2());
            let prim_box = Box3 { min: r.min(), max: r.max() };
            for axis in 0..3 {
                let bin = &mut bins[axis][b[axis]];
                bin.bounds = bin.bounds.union(prim_box);
                bin.count += 1;
            }
        }
        bins
    }

    fn fill_parallel(&self, refs: &[PrimRef]) -> Bins {
        refs.par_chunks(1 << 14).map(|chunk| self.fill(chunk)).reduce(
            || EMPTY_BINS,
            |mut a, b| {
                for (bins_a, bins_b) in a.iter_mut().zip(b.iter()) {
                    for (x, y) in bins_a.iter_mut().zip(bins_b.iter()) {
                        x.bounds = x.bounds.union(y.bounds);
                        x.count += y.count;
                    }
                }
                a
            },
        )
    }
}

/// How a node's primitives are divided.
enum Split {
    /// Make a leaf.
    Leaf,
    /// SAH split: primitives whose bin on `axis` is below `bin` go left.
    Binned { axis: usize, bin: usize, binning: Binning, left: Box3, right: Box3 },
    /// Split the list in the middle after ordering it along `axis` (or not at all for `None`).
    Middle { axis: Option<usize> },
}

/// Where a subtree goes: its first primitive, the global index of the first pair of its range,
/// and its depth.
#[derive(Clone, Copy, Debug)]
struct Builder {
    first: usize,
    pair_base: usize,
    depth: usize,
}

impl Builder {
    /// Builds the subtree over `refs` (whose boxes are `node_box`, centroids `centroid_box`)
    /// into `pairs` (exactly `refs.len() − 1` entries) and returns its root node.
    fn build(self, refs: &mut [PrimRef], node_box: Box3, centroid_box: Box3, pairs: &mut [NodePair]) -> Node {
        let n = refs.len();
        debug_assert_eq!(pairs.len(), n - 1);
        let split = self.choose_split(refs, &node_box, &centroid_box);
        let mid = match &split {
            Split::Leaf => {
                // A single primitive is named directly, larger leaves by their range.
                let index = if n == 1 { refs[0].id() } else { self.first as u32 };
                return Node::new(node_box.min, node_box.max, index, n as u32);
            }
            Split::Binned { axis, bin, binning, .. } => {
                let mid = partition(refs, |r| binning.bin(r.centroid2(), *axis) < *bin);
                debug_assert!(mid > 0 && mid < n);
                mid
            }
            Split::Middle { axis } => {
                let mid = n / 2;
                if let Some(axis) = *axis {
                    refs.select_nth_unstable_by(mid, |a, b| a.centroid2()[axis].total_cmp(&b.centroid2()[axis]));
                }
                mid
            }
        };
        let (left_refs, right_refs) = refs.split_at_mut(mid);
        let (left_box, left_centroids, right_box, right_centroids) = match split {
            Split::Binned { left, right, .. } => (left, centroid_bounds(left_refs), right, centroid_bounds(right_refs)),
            _ => {
                let (lb, lc) = bounds_of(left_refs);
                let (rb, rc) = bounds_of(right_refs);
                (lb, lc, rb, rc)
            }
        };
        let (head, rest) = pairs.split_at_mut(1);
        let (left_pairs, right_pairs) = rest.split_at_mut(mid - 1);
        let left_builder = Builder { first: self.first, pair_base: self.pair_base + 1, depth: self.depth + 1 };
        let right_builder = Builder { first: self.first + mid, pair_base: self.pair_base + mid, depth: self.depth + 1 };
        let (left, right) = if n >= PARALLEL_THRESHOLD {
            rayon::join(
                || left_builder.build(left_refs, left_box, left_centroids, left_pairs),
                || right_builder.build(right_refs, right_box, right_centroids, right_pairs),
            )
        } else {
            (
                left_builder.build(left_refs, left_box, left_centroids, left_pairs),
                right_builder.build(right_refs, right_box, right_centroids, right_pairs),
            )
        };
        head[0] = NodePair([left, right]);
        Node::new(node_box.min, node_box.max, self.pair_base as u32, 0)
    }

    fn choose_split(&self, refs: &[PrimRef], node_box: &Box3, centroid_box: &Box3) -> Split {
        let n = refs.len();
        if n == 1 {
            return Split::Leaf;
        }
        let extent = centroid_box.max - centroid_box.min;
        if extent.max_element() <= 0.0 {
            // All centroids coincide: no split separates them.
            return if n <= MAX_LEAF_SIZE { Split::Leaf } else { Split::Middle { axis: None } };
        }
        // Depth guard: splitting in the middle from here on must still fit in MAX_DEPTH.
        let levels_needed = (usize::BITS - (n - 1).leading_zeros()) as usize;
        if self.depth + levels_needed >= MAX_DEPTH - 1 {
            return Split::Middle { axis: Some(largest_axis(extent)) };
        }

        let binning = Binning::new(centroid_box);
        let bins = if n >= PARALLEL_BINNING_THRESHOLD { binning.fill_parallel(refs) } else { binning.fill(refs) };
        // Best split over all axes: cost = A(L)·N(L) + A(R)·N(R) (half areas).
        let mut best: Option<(f32, usize, usize, Box3, Box3)> = None;
        for (axis, bins) in bins.iter().enumerate() {
            if extent[axis] <= 0.0 {
                continue;
            }
            let mut right_cost = [0.0f32; BIN_COUNT];
            let mut right_boxes = [Box3::EMPTY; BIN_COUNT];
            let mut acc = Box3::EMPTY;
            let mut count = 0u32;
            for i in (1..BIN_COUNT).rev() {
                acc = acc.union(bins[i].bounds);
                count += bins[i].count;
                right_boxes[i] = acc;
                right_cost[i] = acc.half_area() * count as f32;
            }
            let mut acc = Box3::EMPTY;
            let mut count = 0u32;
            for i in 1..BIN_COUNT {
                acc = acc.union(bins[i - 1].bounds);
                count += bins[i - 1].count;
                if count == 0 || count as usize == n {
                    continue;
                }
                let cost = acc.half_area() * count as f32 + right_cost[i];
                if best.is_none_or(|b| cost < b.0) {
                    best = Some((cost, axis, i, acc, right_boxes[i]));
                }
            }
        }
        let Some((cost, axis, bin, left, right)) = best else {
            // Centroids too close to separate by binning.
            return if n <= MAX_LEAF_SIZE { Split::Leaf } else { Split::Middle { axis: Some(largest_axis(extent)) } };
        };
        if n <= MAX_LEAF_SIZE {
            // Both costs multiplied by the node's area, so a flat node needs no division.
            let area = node_box.half_area();
            let split_cost = COST_TRAVERSAL * area + COST_INTERSECT * cost;
            let leaf_cost = COST_INTERSECT * n as f32 * area;
            if leaf_cost <= split_cost {
                return Split::Leaf;
            }
        }
        Split::Binned { axis, bin, binning, left, right }
    }
}

fn largest_axis(v: Vec3A) -> usize {
    if v.x >= v.y && v.x >= v.z {
        0
    } else if v.y >= v.z {
        1
    } else {
        2
    }
}

fn centroid_bounds(refs: &[PrimRef]) -> Box3 {
    if refs.len() >= PARALLEL_BINNING_THRESHOLD {
        refs.par_chunks(1 << 14)
            .map(|chunk| chunk.iter().fold(Box3::EMPTY, |b, r| b.grow(r.centroid2())))
            .reduce(|| Box3::EMPTY, Box3::union)
    } else {
        refs.iter().fold(Box3::EMPTY, |b, r| b.grow(r.centroid2()))
    }
}

/// Reorders `items` so that those satisfying `left` come first; returns their number.
fn partition(items: &mut [PrimRef], left: impl Fn(&PrimRef) -> bool) -> usize {
    let mut i = 0;
    let mut j = items.len();
    loop {
        while i < j && left(&items[i]) {
            i += 1;
        }
        while i < j && !left(&items[j - 1]) {
            j -= 1;
        }
        if i >= j {
            return i;
        }
        items.swap(i, j - 1);
        i += 1;
        j -= 1;
    }
}

/// Copies the pairs reachable from `node` from the sparse build array into `out` in depth-first
/// order, rewriting child indices, and accumulates statistics.
fn compact(
    sparse: &[NodePair],
    node: &mut Node,
    out: &mut Vec<NodePair>,
    depth: usize,
    root_area: f32,
    stats: &mut BvhStats,
) {
    stats.nodes += 1;
    let area = node.half_area();
    let relative = if root_area > 0.0 { area / root_area } else { 1.0 };
    if node.is_leaf() {
        stats.leaves += 1;
        stats.max_depth = stats.max_depth.max(depth);
        stats.max_leaf_size = stats.max_leaf_size.max(node.count() as usize);
        stats.sah_cost += relative * COST_INTERSECT * node.count() as f32;
        return;
    }
    stats.sah_cost += relative * COST_TRAVERSAL;
    let new_index = out.len();
    let mut pair = sparse[node.index() as usize];
    out.push(pair);
    for child in &mut pair.0 {
        compact(sparse, child, out, depth + 1, root_area, stats);
    }
    out[new_index] = pair;
    node.set_index(new_index as u32);
}
