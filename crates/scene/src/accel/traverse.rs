//! Ray queries on the 8-wide tree: nearest hit (front to back, with pruning) and any hit (stops
//! at the first blocker). Both are allocation-free: the traversal stack is a fixed-capacity
//! array on the call stack.
//!
//! Tie rule of the nearest hit: of several primitives hit at exactly the same distance, the one
//! with the smallest id wins, whatever the order in which the traversal meets them. A primitive
//! with a smaller id than the current best is asked for hits up to and including the current
//! distance (`t_max` one ulp above it), one with a larger id only for strictly nearer hits; so
//! every hit the callback reports is taken, which callers rely on (see `Bvh::closest_hit`).
//!
//! Leaves stored as triangle blocks (`triangle_block.rs`) are tested here, four triangles at
//! once, with the same tie rule per lane; other leaves go to the callback.

use arrayvec::ArrayVec;
use glam::Vec4;
use math::Ray;
use math::isa::Kernel;

use super::ray_box::{ROBUST_EXIT, RayBox, octant};
use super::triangle_block::{LANES, RayLanes, TRIANGLES};
use super::wide::{INTERIOR, WIDTH};
use super::{Bvh, MAX_DEPTH, TraversalCounts};

/// Capacity of the traversal stack. The wide tree is at most as deep as the binary one
/// (< [`MAX_DEPTH`]), and each node on the current path leaves at most `WIDTH − 1` siblings on
/// the stack, plus at most `WIDTH` pushed by the node being visited.
const STACK_SIZE: usize = WIDTH * MAX_DEPTH;

/// Trees with fewer nodes than this (1 MiB of nodes) are not given hints for the children they
/// push: their nodes stay in the cache, and a hint is an instruction for nothing (Mitsuba's
/// Cornell box, 3 nodes, lost 5 % of its shadow-ray rate to them; docs/bvh.md, "Hints for
/// pushed children").
pub(super) const HINT_MIN_NODES: usize = 4096;

/// A child waiting on the stack: its reference (as in [`super::wide::WideNode`]) and the
/// distance at which the ray enters its box.
#[derive(Clone, Copy, Debug, Default)]
struct Entry {
    child: u32,
    meta: u32,
    t: f32,
}

/// What a query counts; `()` counts nothing and compiles to nothing.
pub(super) trait Tally {
    /// An interior node was visited and `boxes` ray–box tests made there.
    fn node(&mut self, boxes: u64);
    /// A ray–box test outside a node visit (the binary tree's root box).
    #[cfg(any(test, feature = "binary-bvh"))]
    fn root_box(&mut self);
    /// A primitive was handed to the callback.
    fn primitive(&mut self);
}

impl Tally for () {
    #[inline(always)]
    fn node(&mut self, _boxes: u64) {}
    #[cfg(any(test, feature = "binary-bvh"))]
    #[inline(always)]
    fn root_box(&mut self) {}
    #[inline(always)]
    fn primitive(&mut self) {}
}

impl Tally for TraversalCounts {
    #[inline(always)]
    fn node(&mut self, boxes: u64) {
        self.nodes += 1;
        self.box_tests += boxes;
    }
    #[cfg(any(test, feature = "binary-bvh"))]
    #[inline(always)]
    fn root_box(&mut self) {
        self.box_tests += 1;
    }
    #[inline(always)]
    fn primitive(&mut self) {
        self.primitives += 1;
    }
}

/// The smallest `f32` above `x`, for `x > 0` finite (`+∞` stays `+∞`).
#[inline(always)]
fn next_up(x: f32) -> f32 {
    if x.is_finite() { f32::from_bits(x.to_bits() + 1) } else { x }
}

/// `best` of the nearest-hit query before anything was hit; larger than every primitive id
/// (ids index a slice of primitive boxes, so they stay below `u32::MAX`).
const NO_HIT: u32 = u32::MAX;

/// The lanes `0..WIDTH` sorted by their entry distance `t[lane]`, farthest first (lanes not
/// entered, at `+∞`, first), as keys whose low three bits are the lane.
///
/// Entry distances are `+0`, positive, or `+∞` (never negative or NaN, see
/// [`RayBox::entries`]), so their bit patterns order like the distances, and a key
/// `bits << 32 | lane` orders by distance, then lane. Sorted by Knuth's network of 19
/// compare-exchanges for eight inputs (TAOCP vol. 3, §5.3.4; checked on every order of eight
/// distinct keys by `sort_lanes_sorts_every_order`), which compile to conditional moves.
#[inline(always)]
fn sort_lanes(t: &[f32; WIDTH]) -> [u64; WIDTH] {
    let mut k: [u64; WIDTH] = std::array::from_fn(|lane| u64::from(t[lane].to_bits()) << 32 | lane as u64);
    let mut exchange = |i: usize, j: usize| {
        let (a, b) = (k[i], k[j]);
        k[i] = a.max(b);
        k[j] = a.min(b);
    };
    // Written out: a loop over a table of the pairs was not unrolled.
    exchange(0, 2);
    exchange(1, 3);
    exchange(4, 6);
    exchange(5, 7);
    exchange(0, 4);
    exchange(1, 5);
    exchange(2, 6);
    exchange(3, 7);
    exchange(0, 1);
    exchange(2, 3);
    exchange(4, 5);
    exchange(6, 7);
    exchange(2, 4);
    exchange(3, 5);
    exchange(1, 4);
    exchange(3, 6);
    exchange(1, 2);
    exchange(3, 4);
    exchange(5, 6);
    k
}

const _: () = assert!(WIDTH == 8, "sort_lanes sorts eight lanes");

/// The lanes of [`RayBox::entries`]' result whose box the ray enters (those not `+∞`), as a bit
/// mask (bit `lane`).
#[inline(always)]
fn entered_lanes(t: &[f32; WIDTH]) -> u32 {
    let half = |h: usize| Vec4::from_slice(&t[4 * h..]).cmpne(Vec4::INFINITY).bitmask();
    half(0) | half(1) << 4
}

/// [`Bvh::closest_hit_octants`] as a kernel of [`math::isa::dispatch`].
pub(super) struct ClosestHit<'a, F, T> {
    pub(super) bvh: &'a Bvh,
    pub(super) ray: &'a Ray,
    pub(super) t_max: f32,
    pub(super) intersect: F,
    pub(super) tally: &'a mut T,
}

impl<F: FnMut(u32, &Ray, f32) -> Option<f32>, T: Tally> Kernel for ClosestHit<'_, F, T> {
    type Output = Option<(u32, f32)>;
    #[inline(always)]
    fn run(self) -> Self::Output {
        self.bvh.closest_hit_octants(self.ray, self.t_max, self.intersect, self.tally)
    }
}

impl Bvh {
    /// The primitive ids of a leaf entry (`child`, `meta`). A single primitive's id is stored in
    /// the node itself, which saves the load from the index array.
    /// `child` is a copy of the entry's `child` word: borrowing the entry itself would keep the
    /// traversal's current entry in memory.
    #[inline(always)]
    fn leaf_prims<'a>(&'a self, child: &'a u32, meta: u32) -> &'a [u32] {
        if meta == 1 {
            std::slice::from_ref(child)
        } else {
            let first = *child as usize;
            &self.prims[first..first + meta as usize]
        }
    }

    /// Hints the node or triangle block of a child pushed on the stack into the cache, so that
    /// its miss overlaps the visit of its nearer siblings; only in trees of at least
    /// [`HINT_MIN_NODES`] nodes.
    #[inline(always)]
    fn hint_child(&self, child: u32, meta: u32) {
        if self.nodes.len() < HINT_MIN_NODES {
            return;
        }
        if meta == INTERIOR {
            if let Some(node) = self.nodes.get(child as usize) {
                math::prefetch::prefetch_lines(node);
            }
        } else if meta & TRIANGLES != 0
            && let Some(block) = self.blocks.get(child as usize)
        {
            math::prefetch::prefetch_lines(block);
        }
    }

    /// [`Bvh::closest_hit`], counting into `tally`.
    #[inline(always)]
    pub(super) fn closest_hit_with<T: Tally>(
        &self,
        ray: &Ray,
        t_max: f32,
        intersect: impl FnMut(u32, &Ray, f32) -> Option<f32>,
        tally: &mut T,
    ) -> Option<(u32, f32)> {
        math::isa::dispatch(ClosestHit { bvh: self, ray, t_max, intersect, tally })
    }

    /// [`Bvh::closest_hit`] without a dispatch: nothing for an empty tree or `t_max` not
    /// positive, else the copy for the ray's octant. Inlined into each instruction set's copy
    /// of the query ([`math::isa`]).
    #[inline(always)]
    pub(super) fn closest_hit_octants<T: Tally>(
        &self,
        ray: &Ray,
        t_max: f32,
        intersect: impl FnMut(u32, &Ray, f32) -> Option<f32>,
        tally: &mut T,
    ) -> Option<(u32, f32)> {
        if self.nodes.is_empty() || t_max.is_nan() || t_max <= 0.0 {
            return None;
        }
        match octant(ray) {
            0 => self.closest_hit_in::<0, T>(ray, t_max, intersect, tally),
            1 => self.closest_hit_in::<1, T>(ray, t_max, intersect, tally),
            2 => self.closest_hit_in::<2, T>(ray, t_max, intersect, tally),
            3 => self.closest_hit_in::<3, T>(ray, t_max, intersect, tally),
            4 => self.closest_hit_in::<4, T>(ray, t_max, intersect, tally),
            5 => self.closest_hit_in::<5, T>(ray, t_max, intersect, tally),
            6 => self.closest_hit_in::<6, T>(ray, t_max, intersect, tally),
            _ => self.closest_hit_in::<7, T>(ray, t_max, intersect, tally),
        }
    }

    /// [`Bvh::closest_hit`] for a tree with nodes, `t_max > 0`, and a ray in octant `OCTANT`
    /// ([`octant`]).
    #[inline(always)]
    fn closest_hit_in<const OCTANT: usize, T: Tally>(
        &self,
        ray: &Ray,
        t_max: f32,
        mut intersect: impl FnMut(u32, &Ray, f32) -> Option<f32>,
        tally: &mut T,
    ) -> Option<(u32, f32)> {
        let test = RayBox::new(ray);
        let lanes = RayLanes::sharing_origin(&test, ray);
        let mut t_best = t_max;
        // The tie rule's limit for ids smaller than `best`: `next_up(t_best)` once something was
        // hit; before, `t_max` itself, since a hit must be nearer than `t_max` (every id is
        // smaller than the sentinel `NO_HIT`).
        let mut t_tie = t_max;
        let mut best = NO_HIT;
        let mut stack: ArrayVec<Entry, STACK_SIZE> = ArrayVec::new();
        let mut current = Entry { child: 0, meta: INTERIOR, t: 0.0 };
        loop {
            if current.meta == INTERIOR {
                let node = &self.nodes[current.child as usize];
                tally.node(WIDTH as u64);
                let t = test.entries::<OCTANT>(node, t_best);
                let entered = entered_lanes(&t);
                let entry = |lane: usize| Entry { child: node.child[lane], meta: node.meta[lane], t: t[lane] };
                let rest = entered & entered.wrapping_sub(1);
                if entered == 0 {
                    // Nothing entered: pop below.
                } else if rest == 0 {
                    // One child entered (the common case): visit it now.
                    current = entry(entered.trailing_zeros() as usize % WIDTH);
                    continue;
                } else if rest & (rest - 1) == 0 {
                    // Two: the nearer now, the farther later; of two at the same distance the
                    // later lane comes first, as in the sort below.
                    let a = entry(entered.trailing_zeros() as usize % WIDTH);
                    let b = entry(rest.trailing_zeros() as usize % WIDTH);
                    let (near, far) = if a.t < b.t { (a, b) } else { (b, a) };
                    self.hint_child(far.child, far.meta);
                    stack.push(far);
                    current = near;
                    continue;
                } else {
                    // Three or more: all lanes sorted by entry distance, farthest first
                    // (the lanes not entered, at `+∞`, come first and are left out); the nearest
                    // is visited now, the others later (nearer ones first).
                    // The nearest by a tree of minima (three steps), so that the next node's
                    // load need not wait for the whole sorting network.
                    let k: [u64; WIDTH] = std::array::from_fn(|lane| u64::from(t[lane].to_bits()) << 32 | lane as u64);
                    let nearest = (k[0].min(k[1]).min(k[2].min(k[3]))).min(k[4].min(k[5]).min(k[6].min(k[7])));
                    let sorted = sort_lanes(&t);
                    let count = entered.count_ones() as usize;
                    for &key in &sorted[WIDTH - count..WIDTH - 1] {
                        let e = entry(key as usize % WIDTH);
                        self.hint_child(e.child, e.meta);
                        stack.push(e);
                    }
                    current = entry(nearest as usize % WIDTH);
                    continue;
                }
            } else if current.meta & TRIANGLES != 0 {
                let block = &self.blocks[current.child as usize];
                let distances = block.distances(&lanes);
                for _ in 0..current.meta & !TRIANGLES {
                    tally.primitive();
                }
                // Only hits nearer than `next_up(t_best)` can pass the tie rule's limit below (a
                // miss is `+∞`, which passes no limit); usually there are none.
                let mut lanes_hit = distances.cmplt(Vec4::splat(t_tie)).bitmask();
                while lanes_hit != 0 {
                    let lane = lanes_hit.trailing_zeros() as usize % LANES;
                    lanes_hit &= lanes_hit - 1;
                    let (t, prim) = (distances.to_array()[lane], block.ids[lane]);
                    let limit = if prim < best { t_tie } else { t_best };
                    if t < limit {
                        t_best = t;
                        t_tie = next_up(t);
                        best = prim;
                    }
                }
            } else {
                let child = current.child;
                for &prim in self.leaf_prims(&child, current.meta) {
                    tally.primitive();
                    // The tie rule (module doc): smaller ids may also hit at exactly `t_best`.
                    let limit = if prim < best { t_tie } else { t_best };
                    if let Some(t) = intersect(prim, ray, limit).filter(|&t| t < limit) {
                        t_best = t;
                        t_tie = next_up(t);
                        best = prim;
                    }
                }
            }
            // Pop the next child that may still hold a nearer hit (or an equally near one).
            loop {
                let Some(entry) = stack.pop() else {
                    return (best != NO_HIT).then_some((best, t_best));
                };
                if entry.t <= t_best * ROBUST_EXIT {
                    current = entry;
                    break;
                }
            }
        }
    }

    /// [`Bvh::any_hit`], counting into `tally`.
    #[inline(always)]
    pub(super) fn any_hit_with<T: Tally>(
        &self,
        ray: &Ray,
        t_max: f32,
        occluded: impl FnMut(u32, &Ray, f32) -> bool,
        tally: &mut T,
    ) -> bool {
        if self.nodes.is_empty() || t_max.is_nan() || t_max <= 0.0 {
            return false;
        }
        // Not run through `math::isa::dispatch`: with AVX-512 or AVX2 the shadow rays of
        // Mitsuba's Cornell box took 17 % and 10 % longer, and those of matpreview and a
        // 1M-triangle mesh gained 1 % (docs/bvh.md, "Instruction sets chosen at run time").
        match octant(ray) {
            0 => self.any_hit_in::<0, T>(ray, t_max, occluded, tally),
            1 => self.any_hit_in::<1, T>(ray, t_max, occluded, tally),
            2 => self.any_hit_in::<2, T>(ray, t_max, occluded, tally),
            3 => self.any_hit_in::<3, T>(ray, t_max, occluded, tally),
            4 => self.any_hit_in::<4, T>(ray, t_max, occluded, tally),
            5 => self.any_hit_in::<5, T>(ray, t_max, occluded, tally),
            6 => self.any_hit_in::<6, T>(ray, t_max, occluded, tally),
            _ => self.any_hit_in::<7, T>(ray, t_max, occluded, tally),
        }
    }

    /// [`Bvh::any_hit`] for a tree with nodes, `t_max > 0`, and a ray in octant `OCTANT`
    /// ([`octant`]).
    #[inline(always)]
    fn any_hit_in<const OCTANT: usize, T: Tally>(
        &self,
        ray: &Ray,
        t_max: f32,
        mut occluded: impl FnMut(u32, &Ray, f32) -> bool,
        tally: &mut T,
    ) -> bool {
        let test = RayBox::new(ray);
        let lanes = RayLanes::sharing_origin(&test, ray);
        let mut stack: ArrayVec<u32, STACK_SIZE> = ArrayVec::new();
        let mut node_index = 0u32;
        loop {
            let node = &self.nodes[node_index as usize];
            tally.node(WIDTH as u64);
            let t = test.entries::<OCTANT>(node, t_max);
            let mut entered = entered_lanes(&t);
            while entered != 0 {
                let lane = entered.trailing_zeros() as usize % WIDTH;
                entered &= entered - 1;
                let entry = Entry { child: node.child[lane], meta: node.meta[lane], t: t[lane] };
                if entry.meta == INTERIOR {
                    self.hint_child(entry.child, entry.meta);
                    stack.push(entry.child);
                    continue;
                }
                if entry.meta & TRIANGLES != 0 {
                    for _ in 0..entry.meta & !TRIANGLES {
                        tally.primitive();
                    }
                    let distances = self.blocks[entry.child as usize].distances(&lanes);
                    if distances.cmplt(Vec4::splat(t_max)).any() {
                        return true;
                    }
                    continue;
                }
                // Leaves are tested at once: any blocker ends the query.
                let child = entry.child;
                for &prim in self.leaf_prims(&child, entry.meta) {
                    tally.primitive();
                    if occluded(prim, ray, t_max) {
                        return true;
                    }
                }
            }
            let Some(next) = stack.pop() else { return false };
            node_index = next;
        }
    }
}

#[cfg(test)]
mod sort_tests {
    use super::*;

    /// `sort_lanes` puts every order of eight distinct keys farthest first, which makes its
    /// network a sorting network (keys are always distinct: the lane is part of the key); and
    /// random distances with ties and misses come out as a full sort orders them.
    #[test]
    fn sort_lanes_sorts_every_order() {
        fn check(t: [f32; WIDTH]) {
            let mut expected: Vec<u64> =
                (0..WIDTH).map(|lane| u64::from(t[lane].to_bits()) << 32 | lane as u64).collect();
            expected.sort_unstable_by(|a, b| b.cmp(a));
            assert_eq!(sort_lanes(&t).to_vec(), expected, "distances {t:?}");
        }
        // Heap's algorithm over the permutations of 1..=8.
        let mut order: [f32; WIDTH] = std::array::from_fn(|i| (i + 1) as f32);
        let mut c = [0usize; WIDTH];
        check(order);
        let mut i = 0;
        let mut permutations = 1;
        while i < WIDTH {
            if c[i] < i {
                order.swap(if i % 2 == 0 { 0 } else { c[i] }, i);
                check(order);
                permutations += 1;
                c[i] += 1;
                i = 0;
            } else {
                c[i] = 0;
                i += 1;
            }
        }
        assert_eq!(permutations, 40_320);
        let mut rng = math::Rng::for_stream(3, 0, 0);
        for _ in 0..1000 {
            check(std::array::from_fn(|_| match (rng.uniform() * 4.0) as u32 {
                0 => f32::INFINITY,
                1 => 0.5,
                _ => rng.uniform(),
            }));
        }
    }
}
