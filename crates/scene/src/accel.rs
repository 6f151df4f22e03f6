//! The bounding volume hierarchy (BVH) that accelerates ray queries over all primitives.
//!
//! This module owns the tree: its construction from primitive bounds (binned SAH, parallel with
//! rayon for large inputs) and its traversal for nearest hits and occlusion (any hit). It is
//! primitive-agnostic: the tree only knows each primitive's bounding box and index, and the
//! caller intersects a primitive in a closure, so triangles and analytic spheres share one tree.
//!
//! Layout: nodes are 32 bytes (`min.xyz`, index, `max.xyz`, count) and siblings are stored
//! together as a 64-byte, cache-line aligned pair, so the two child boxes of a node are tested
//! with one cache line. Leaves name a range of the primitive index array. See `docs/bvh.md`.

use arrayvec::ArrayVec;
use glam::Vec4;
use math::{Aabb, Ray, Vec3, Vec3A};
use rayon::prelude::*;

/// Largest number of primitives in a leaf. Smaller leaves are chosen whenever the SAH says so.
const MAX_LEAF_SIZE: usize = 4;
/// Number of SAH bins per axis.
const BIN_COUNT: usize = 16;
/// Largest tree depth (root = depth 0), which is also the size of the traversal stack.
const MAX_DEPTH: usize = 64;
/// Subtrees with at least this many primitives are built in parallel.
const PARALLEL_THRESHOLD: usize = 2048;
/// Nodes with at least this many primitives compute their bins in parallel.
const PARALLEL_BINNING_THRESHOLD: usize = 1 << 16;
/// SAH cost of traversing an interior node (testing its two child boxes), relative to
/// [`COST_INTERSECT`].
const COST_TRAVERSAL: f32 = 1.0;
/// SAH cost of intersecting one primitive.
const COST_INTERSECT: f32 = 1.0;
/// Factor by which a box's exit distance is enlarged so that rounding in the slab test can
/// never reject a box the ray touches (Ize 2013: `1 + 2γ₃`, rounded up).
const ROBUST_EXIT: f32 = 1.0 + 4.0 * f32::EPSILON;
/// Primitive bounds are clamped to `[-BOUNDS_LIMIT, BOUNDS_LIMIT]` so that surface areas and SAH
/// costs stay free of infinities and NaNs (an infinite primitive is cut off there).
const BOUNDS_LIMIT: f32 = 1e18;

/// A node: box corners, and either a child pair index (interior, `count == 0`), or for a leaf
/// (`count > 0`) the first entry of its range of the primitive index array, except that a leaf
/// with one primitive stores the primitive id itself.
///
/// Stored as eight words `[min.x, min.y, min.z, index, max.x, max.y, max.z, count]` (the floats
/// as bit patterns), so that the slab test can pick the near and far plane of each axis by an
/// index precomputed per ray.
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(32))]
struct Node {
    v: [u32; 8],
}

impl Node {
    fn new(min: Vec3A, max: Vec3A, index: u32, count: u32) -> Self {
        let f = f32::to_bits;
        Self { v: [f(min.x), f(min.y), f(min.z), index, f(max.x), f(max.y), f(max.z), count] }
    }

    #[inline(always)]
    fn index(&self) -> u32 {
        self.v[3]
    }

    /// The primitive of a leaf with `count == 1`, whose index field holds the primitive id.
    #[inline(always)]
    fn single_prim(&self) -> &u32 {
        &self.v[3]
    }

    #[inline(always)]
    fn count(&self) -> u32 {
        self.v[7]
    }

    #[inline(always)]
    fn is_leaf(&self) -> bool {
        self.count() != 0
    }

    fn min(&self) -> Vec3 {
        Vec3::new(f32::from_bits(self.v[0]), f32::from_bits(self.v[1]), f32::from_bits(self.v[2]))
    }

    fn max(&self) -> Vec3 {
        Vec3::new(f32::from_bits(self.v[4]), f32::from_bits(self.v[5]), f32::from_bits(self.v[6]))
    }

    fn set_index(&mut self, index: u32) {
        self.v[3] = index;
    }
}

/// Two sibling nodes in one cache line.
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(64))]
struct NodePair([Node; 2]);

/// Statistics of a built tree.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BvhStats {
    /// Primitives in the tree (those with a non-empty, NaN-free box).
    pub primitives: usize,
    /// Nodes, interior and leaves, including the root.
    pub nodes: usize,
    /// Leaf nodes.
    pub leaves: usize,
    /// Depth of the deepest leaf (a root leaf has depth 0).
    pub max_depth: usize,
    /// Largest number of primitives in one leaf.
    pub max_leaf_size: usize,
    /// SAH cost of the tree: `Σ_interior A(n)/A(root)·C_trav + Σ_leaf A(n)/A(root)·N(n)·C_isect`
    /// with `C_trav = C_isect = 1`.
    pub sah_cost: f32,
}

/// A bounding volume hierarchy over primitives known by their bounding boxes.
///
/// Primitive ids are indices into the slice given to [`Bvh::build`]. Queries are read-only and
/// allocation-free, so one tree can be shared by all threads.
#[derive(Clone, Debug)]
pub struct Bvh {
    /// The root node; a leaf for trees of at most a few primitives.
    root: Node,
    /// Child pairs; interior nodes store the index of their pair here. Depth-first order.
    pairs: Vec<NodePair>,
    /// Primitive ids, grouped by leaf.
    prims: Vec<u32>,
    /// Statistics gathered while building.
    stats: BvhStats,
}

/// Ray data precomputed for the slab test.
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
        // Zero components give ±∞ (by the sign of the zero), which the slab test handles.
        let inverse_direction = [1.0 / d.x, 1.0 / d.y, 1.0 / d.z];
        let near = [
            if d.x.is_sign_negative() { 4 } else { 0 },
            if d.y.is_sign_negative() { 5 } else { 1 },
            if d.z.is_sign_negative() { 6 } else { 2 },
        ];
        Self { origin: ray.origin.to_array(), inverse_direction, near }
    }

    /// Distance at which the ray enters `node`'s box within `(0, t_max]`, or `+∞` on a miss.
    ///
    /// A zero direction component makes the plane distance `±∞`, or NaN (`0·∞`) when the origin
    /// lies on the plane; the comparisons below are written so that a NaN never wins, i.e. the
    /// ray counts as inside that slab, which is the correct answer for an origin on the plane.
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
            // `x > acc` is false for NaN x, so NaN is ignored.
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

impl Bvh {
    /// Builds the tree over primitive bounds; primitive ids are indices into `bounds`.
    ///
    /// Uses binned SAH with leaves of at most four primitives, and rayon for large inputs. An
    /// empty input gives a tree every query misses. Primitives whose box is empty or contains a
    /// NaN can never be hit and are left out; coordinates beyond ±1e18 are clamped.
    pub fn build(bounds: &[Aabb]) -> Bvh {
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
            return Bvh { root: Node::default(), pairs: Vec::new(), prims: Vec::new(), stats: BvhStats::default() };
        }

        let n = refs.len();
        let (node_box, centroid_box) = bounds_of(&refs);
        // A subtree over k primitives has at most k − 1 interior nodes, each owning one child pair;
        // every subtree gets such a range, so parallel subtrees write disjoint slices. The holes
        // left by leaves holding several primitives are squeezed out afterwards.
        let mut sparse = vec![NodePair::default(); n - 1];
        let builder = Builder { first: 0, pair_base: 0, depth: 0 };
        let root = builder.build(&mut refs, node_box, centroid_box, &mut sparse);

        let mut pairs = Vec::with_capacity(n / 2 + 1);
        let mut root = root;
        let mut stats = BvhStats { primitives: n, ..BvhStats::default() };
        let root_area = node_box.half_area();
        compact(&sparse, &mut root, &mut pairs, 0, root_area, &mut stats);
        drop(sparse);
        let prims = refs.iter().map(|r| r.id()).collect();
        Bvh { root, pairs, prims, stats }
    }

    /// Bounds of all primitives in the tree ([`Aabb::EMPTY`] for an empty tree).
    pub fn bounds(&self) -> Aabb {
        if self.prims.is_empty() { Aabb::EMPTY } else { Aabb::new(self.root.min(), self.root.max()) }
    }

    /// Statistics of the tree: node count, depth, leaf sizes, SAH cost.
    pub fn stats(&self) -> BvhStats {
        self.stats
    }

    /// Nearest hit along `ray` closer than `t_max`.
    ///
    /// Calls `intersect(prim, ray, t)`, which must return `Some(t_hit)` for a hit with
    /// `0 < t_hit < t`, where `t` is the nearest distance found so far (initially `t_max`).
    /// Returns the primitive and distance of the nearest hit. Of equally near hits the first one
    /// found is kept, since a later one must be strictly closer to replace it.
    pub fn closest_hit(
        &self,
        ray: &Ray,
        t_max: f32,
        mut intersect: impl FnMut(u32, &Ray, f32) -> Option<f32>,
    ) -> Option<(u32, f32)> {
        if self.prims.is_empty() || t_max.is_nan() || t_max <= 0.0 {
            return None;
        }
        let test = RayBoxTest::new(ray);
        if test.entry(&self.root, t_max) == f32::INFINITY {
            return None;
        }
        let mut t_best = t_max;
        let mut best = None;
        // ArrayVec: a fixed-capacity stack that is not initialised up front (zeroing a 1 KiB
        // array per ray cost ~10 % of a VCM iteration on the reference scenes).
        let mut stack: ArrayVec<(&Node, f32), MAX_DEPTH> = ArrayVec::new();
        let mut node = &self.root;
        loop {
            if node.is_leaf() {
                for &prim in self.leaf_prims(node) {
                    if let Some(t) = intersect(prim, ray, t_best).filter(|&t| t < t_best) {
                        t_best = t;
                        best = Some(prim);
                    }
                }
            } else {
                let [left, right] = &self.pairs[node.index() as usize].0;
                let t_left = test.entry(left, t_best);
                let t_right = test.entry(right, t_best);
                if t_left != f32::INFINITY {
                    if t_right != f32::INFINITY {
                        // Both hit: visit the nearer first, come back for the other.
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
            // Pop the next node that may still hold a nearer hit.
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

    /// The primitive ids of a leaf. A single primitive's id is stored in the node itself, which
    /// saves the load from the index array.
    #[inline(always)]
    fn leaf_prims<'a>(&'a self, node: &'a Node) -> &'a [u32] {
        let count = node.count() as usize;
        if count == 1 {
            std::slice::from_ref(node.single_prim())
        } else {
            let first = node.index() as usize;
            &self.prims[first..first + count]
        }
    }

    /// Whether anything blocks `ray` before `t_max` (shadow rays); stops at the first blocker.
    ///
    /// Calls `occluded(prim, ray, t_max)`, which must return true if the primitive intersects
    /// the ray at some `t` in `(0, t_max)`.
    pub fn any_hit(&self, ray: &Ray, t_max: f32, mut occluded: impl FnMut(u32, &Ray, f32) -> bool) -> bool {
        if self.prims.is_empty() || t_max.is_nan() || t_max <= 0.0 {
            return false;
        }
        let test = RayBoxTest::new(ray);
        if test.entry(&self.root, t_max) == f32::INFINITY {
            return false;
        }
        let mut stack: ArrayVec<&Node, MAX_DEPTH> = ArrayVec::new();
        let mut node = &self.root;
        loop {
            if node.is_leaf() {
                for &prim in self.leaf_prims(node) {
                    if occluded(prim, ray, t_max) {
                        return true;
                    }
                }
            } else {
                let [left, right] = &self.pairs[node.index() as usize].0;
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
    let area = Box3 { min: Vec3A::from(node.min()), max: Vec3A::from(node.max()) }.half_area();
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

#[cfg(test)]
mod tests {
    use super::*;
    use math::Rng;

    /// Möller–Trumbore, accepting `0 < t < t_max`.
    fn intersect_triangle(tri: &[Vec3; 3], ray: &Ray, t_max: f32) -> Option<f32> {
        crate::shape::Triangle::new(tri[0], tri[1], tri[2]).intersect(ray, t_max)
    }

    fn triangle_bounds(tris: &[[Vec3; 3]]) -> Vec<Aabb> {
        tris.iter().map(|t| Aabb::from_points(t.iter().copied())).collect()
    }

    fn brute_closest(tris: &[[Vec3; 3]], ray: &Ray, t_max: f32) -> Option<(u32, f32)> {
        let mut best = None;
        let mut t_best = t_max;
        for (i, tri) in tris.iter().enumerate() {
            if let Some(t) = intersect_triangle(tri, ray, t_best) {
                t_best = t;
                best = Some((i as u32, t));
            }
        }
        best
    }

    fn brute_any(tris: &[[Vec3; 3]], ray: &Ray, t_max: f32) -> bool {
        tris.iter().any(|tri| intersect_triangle(tri, ray, t_max).is_some())
    }

    fn random_vec(rng: &mut Rng, scale: f32) -> Vec3 {
        Vec3::new(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5) * scale
    }

    fn random_direction(rng: &mut Rng) -> Vec3 {
        loop {
            let v = random_vec(rng, 2.0);
            if v.length_squared() > 1e-4 && v.length_squared() <= 1.0 {
                return v.normalize();
            }
        }
    }

    /// Checks the BVH against brute force for `rays`; ties (equal `t`) may pick another triangle
    /// that hits at exactly the same distance.
    fn check(tris: &[[Vec3; 3]], bvh: &Bvh, rays: &[(Ray, f32)]) -> usize {
        let mut hits = 0;
        for (ray, t_max) in rays {
            let expected = brute_closest(tris, ray, *t_max);
            let got = bvh.closest_hit(ray, *t_max, |p, r, t| intersect_triangle(&tris[p as usize], r, t));
            match (expected, got) {
                (None, None) => {}
                (Some((pe, te)), Some((pg, tg))) => {
                    assert_eq!(te.to_bits(), tg.to_bits(), "t differs for {ray:?}");
                    if pe != pg {
                        let t_other = intersect_triangle(&tris[pg as usize], ray, f32::INFINITY);
                        assert_eq!(t_other, Some(te), "different primitive for {ray:?}");
                    }
                    hits += 1;
                }
                _ => panic!("closest hit mismatch for {ray:?}, t_max {t_max}: {expected:?} vs {got:?}"),
            }
            let expected_any = brute_any(tris, ray, *t_max);
            let got_any = bvh.any_hit(ray, *t_max, |p, r, t| intersect_triangle(&tris[p as usize], r, t).is_some());
            assert_eq!(expected_any, got_any, "any hit mismatch for {ray:?}");
        }
        hits
    }

    fn random_soup(rng: &mut Rng, n: usize, size: f32) -> Vec<[Vec3; 3]> {
        (0..n)
            .map(|_| {
                let c = random_vec(rng, 10.0);
                [c + random_vec(rng, size), c + random_vec(rng, size), c + random_vec(rng, size)]
            })
            .collect()
    }

    fn random_rays(rng: &mut Rng, n: usize) -> Vec<(Ray, f32)> {
        (0..n)
            .map(|i| {
                let t_max = if i % 3 == 0 { f32::INFINITY } else { rng.uniform() * 15.0 };
                (Ray::new(random_vec(rng, 14.0), random_direction(rng)), t_max)
            })
            .collect()
    }

    #[test]
    fn accel_matches_brute_force_on_random_soups() {
        let mut rng = Rng::for_stream(1, 0, 0);
        for (n, size) in [(2, 3.0), (7, 2.0), (100, 1.5), (1000, 1.0), (5000, 0.5)] {
            let tris = random_soup(&mut rng, n, size);
            let bvh = Bvh::build(&triangle_bounds(&tris));
            let stats = bvh.stats();
            assert_eq!(stats.primitives, n);
            assert!(stats.max_leaf_size <= MAX_LEAF_SIZE);
            assert_eq!(stats.nodes, 2 * stats.leaves - 1);
            let rays = random_rays(&mut rng, 2000);
            let hits = check(&tris, &bvh, &rays);
            assert!(hits >= if n < 100 { 1 } else { 50 }, "too few hits ({hits}) to be a meaningful test");
        }
    }

    #[test]
    fn accel_large_soup_parallel_build() {
        let mut rng = Rng::for_stream(2, 0, 0);
        let tris = random_soup(&mut rng, 200_000, 0.2);
        let bvh = Bvh::build(&triangle_bounds(&tris));
        let stats = bvh.stats();
        assert!(stats.max_depth < MAX_DEPTH);
        // Same tree, whatever the thread count: the build is deterministic.
        let again = Bvh::build(&triangle_bounds(&tris));
        assert_eq!(again.prims, bvh.prims);
        let rays = random_rays(&mut rng, 300);
        assert!(check(&tris, &bvh, &rays) > 50);
    }

    /// Every word of a tree: the root, the child pairs, the primitive ids.
    fn tree_words(bvh: &Bvh) -> Vec<u32> {
        let nodes = std::iter::once(&bvh.root).chain(bvh.pairs.iter().flat_map(|p| p.0.iter()));
        nodes.flat_map(|n| n.v).chain(bvh.prims.iter().copied()).collect()
    }

    /// A closed UV sphere of radius 1 with `rings × segments × 2` triangles (its pole rings are
    /// degenerate slivers, as in real meshes).
    fn uv_sphere(rings: usize, segments: usize) -> Vec<[Vec3; 3]> {
        let point = |i: usize, j: usize| {
            let (theta, phi) =
                (std::f32::consts::PI * i as f32 / rings as f32, std::f32::consts::TAU * j as f32 / segments as f32);
            Vec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos())
        };
        let mut tris = Vec::with_capacity(2 * rings * segments);
        for i in 0..rings {
            for j in 0..segments {
                let (a, b, c, d) = (point(i, j), point(i, j + 1), point(i + 1, j), point(i + 1, j + 1));
                tris.push([a, c, d]);
                tris.push([a, d, b]);
            }
        }
        tris
    }

    #[test]
    fn accel_parallel_build_is_identical_with_one_and_two_threads() {
        // 81,920 triangles: above both the parallel subtree threshold and the parallel binning
        // threshold, so the two-thread build splits work at both levels.
        let tris = uv_sphere(160, 256);
        assert!(tris.len() >= PARALLEL_BINNING_THRESHOLD && tris.len() >= PARALLEL_THRESHOLD);
        let bounds = triangle_bounds(&tris);
        let build = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| Bvh::build(&bounds))
        };
        let (one, two) = (build(1), build(2));
        assert_eq!(one.stats(), two.stats());
        assert_eq!(one.stats().primitives, tris.len());
        let (a, b) = (tree_words(&one), tree_words(&two));
        assert_eq!(a.len(), b.len());
        let first_difference = a.iter().zip(&b).position(|(x, y)| x != y);
        assert_eq!(first_difference, None, "the trees differ at word {first_difference:?}");
        // And the tree is right: rays from outside at the sphere find the brute-force hits.
        let mut rng = Rng::for_stream(4, 0, 0);
        let rays: Vec<(Ray, f32)> = (0..300)
            .map(|_| {
                let origin = random_direction(&mut rng) * 3.0;
                let target = random_vec(&mut rng, 1.0);
                (Ray::new(origin, (target - origin).normalize()), f32::INFINITY)
            })
            .collect();
        assert!(check(&tris, &two, &rays) > 150);
    }

    #[test]
    fn accel_empty_tree_misses() {
        let bvh = Bvh::build(&[]);
        let ray = Ray::new(Vec3::ZERO, Vec3::X);
        assert_eq!(bvh.closest_hit(&ray, f32::INFINITY, |_, _, _| panic!("no primitives")), None);
        assert!(!bvh.any_hit(&ray, f32::INFINITY, |_, _, _| panic!("no primitives")));
        assert_eq!(bvh.bounds(), Aabb::EMPTY);
        assert_eq!(bvh.stats().nodes, 0);
        // Primitives with empty or NaN boxes are left out.
        let bvh = Bvh::build(&[Aabb::EMPTY, Aabb::new(Vec3::NAN, Vec3::ONE)]);
        assert!(!bvh.any_hit(&ray, f32::INFINITY, |_, _, _| panic!("no primitives")));
    }

    #[test]
    fn accel_single_primitive() {
        let tris = vec![[Vec3::new(1.0, -1.0, -1.0), Vec3::new(1.0, 1.0, -1.0), Vec3::new(1.0, 0.0, 1.0)]];
        let bvh = Bvh::build(&triangle_bounds(&tris));
        assert_eq!(bvh.bounds(), triangle_bounds(&tris)[0]);
        assert_eq!(bvh.stats().nodes, 1);
        let hit = bvh.closest_hit(&Ray::new(Vec3::ZERO, Vec3::X), f32::INFINITY, |p, r, t| {
            intersect_triangle(&tris[p as usize], r, t)
        });
        assert_eq!(hit, Some((0, 1.0)));
        let shadow = |t_max| {
            bvh.any_hit(&Ray::new(Vec3::ZERO, Vec3::X), t_max, |p, r, t| {
                intersect_triangle(&tris[p as usize], r, t).is_some()
            })
        };
        assert!(shadow(2.0));
        assert!(!shadow(1.0));
        assert!(bvh.closest_hit(&Ray::new(Vec3::ZERO, -Vec3::X), f32::INFINITY, |_, _, _| None).is_none());
    }

    #[test]
    fn accel_many_identical_primitives() {
        let tri = [Vec3::new(-1.0, -1.0, 2.0), Vec3::new(1.0, -1.0, 2.0), Vec3::new(0.0, 1.0, 2.0)];
        let tris = vec![tri; 1000];
        let bvh = Bvh::build(&triangle_bounds(&tris));
        let stats = bvh.stats();
        assert!(stats.max_leaf_size <= MAX_LEAF_SIZE);
        assert!(stats.max_depth < MAX_DEPTH);
        let ray = Ray::new(Vec3::ZERO, Vec3::Z);
        let mut calls = 0;
        let hit = bvh.closest_hit(&ray, f32::INFINITY, |p, r, t| {
            calls += 1;
            intersect_triangle(&tris[p as usize], r, t)
        });
        assert_eq!(hit.map(|h| h.1), Some(2.0));
        assert_eq!(calls, 1000, "every copy is visited: none is strictly closer");
        // Identical points (all centroids and boxes equal, zero area).
        let points = vec![Aabb::new(Vec3::ONE, Vec3::ONE); 777];
        let bvh = Bvh::build(&points);
        assert!(bvh.stats().max_leaf_size <= MAX_LEAF_SIZE);
        let ray = Ray::new(Vec3::ZERO, Vec3::ONE.normalize());
        let mut seen = vec![false; points.len()];
        assert!(!bvh.any_hit(&ray, f32::INFINITY, |p, _, _| {
            seen[p as usize] = true;
            false
        }));
        assert!(seen.iter().all(|s| *s), "every primitive is reachable");
    }

    /// Axis-aligned geometry on an integer grid and rays with zero direction components whose
    /// origins lie exactly on box planes: the slab test's `0·∞` cases.
    #[test]
    fn accel_axis_aligned_rays() {
        let mut rng = Rng::for_stream(3, 0, 0);
        let grid = |rng: &mut Rng| (rng.uniform() * 9.0).floor() - 4.0;
        let mut tris = Vec::new();
        for _ in 0..400 {
            let p = Vec3::new(grid(&mut rng), grid(&mut rng), grid(&mut rng));
            let axis = (rng.uniform() * 3.0) as usize;
            let (a, b) = match axis {
                0 => (Vec3::Y, Vec3::Z),
                1 => (Vec3::Z, Vec3::X),
                _ => (Vec3::X, Vec3::Y),
            };
            // Axis-aligned (flat box) triangles and skewed ones touching grid planes.
            tris.push([p, p + a, p + b]);
            tris.push([p, p + a + Vec3::ONE * 0.5, p + b * 2.0]);
        }
        let bvh = Bvh::build(&triangle_bounds(&tris));
        let mut rays = Vec::new();
        let dirs = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
        for i in 0..3000 {
            let mut o = Vec3::new(grid(&mut rng), grid(&mut rng), grid(&mut rng));
            // Some origins off the grid on some axes.
            if i % 2 == 0 {
                o += Vec3::new(rng.uniform(), rng.uniform(), 0.0) * 0.999;
            }
            let d = if i % 3 == 0 {
                // Zero in one component, including negative zero.
                let mut d = Vec3::new(rng.uniform() - 0.5, rng.uniform() - 0.5, if i % 2 == 0 { 0.0 } else { -0.0 });
                if d.length_squared() == 0.0 {
                    d = Vec3::X;
                }
                d.normalize()
            } else {
                dirs[i % 6]
            };
            rays.push((Ray::new(o, d), if i % 4 == 0 { 3.0 } else { f32::INFINITY }));
        }
        let hits = check(&tris, &bvh, &rays);
        assert!(hits > 200, "{hits}");
    }
}
