//! The range-search structure of vertex merging: a hashed uniform grid over the light vertices
//! of one iteration, answering "which stored points lie within the merge radius `r` of this
//! camera vertex?".
//!
//! This module owns [`HashGrid`]: its parallel, deterministic build (a two-level counting sort
//! of point indices by bucket) and its radius query. It knows nothing about paths or vertices;
//! points are plain positions identified by their index in the slice given to
//! [`HashGrid::build`].
//!
//! The VCM engine builds the *lean* variant ([`HashGrid::build_lean`], same slots, no copy of
//! the positions) in both of its modes: it permutes its records into slot order, so a query
//! reads each position from the record it may merge with, at the speed of the sorted copy and
//! with 44 bytes per vertex less in the memory estimate (docs/memory.md). [`HashGrid::build`] remains the general build,
//! and the reference the lean build's tests compare with.
//!
//! A query can be *planned* ahead ([`HashGrid::plan`]: the buckets of its cells, computed
//! once) so that its caller can ask for its memory early with two prefetch hints
//! ([`HashGrid::prefetch_buckets`], then [`HashGrid::prefetch_slots`]) and then run it with
//! the same plan ([`HashGrid::for_each_slot_near`]); docs/performance.md, "Prefetching the
//! merge queries", measures what that saves.
//!
//! # Layout
//!
//! Space is cut into cubic cells of edge slightly more than `2r` (`2r·(1 + 10⁻³)`, so that float
//! rounding can never push a point out of the cells a query looks at). A cell `(x, y, z)` is
//! hashed into one of `B` buckets, `B` the smallest power of two `≥` the number of points. The
//! indices of the points are counting-sorted by bucket into one flat `Vec<u32>`, with a
//! `Vec<u32>` of `B + 1` bucket start offsets, so a bucket is one contiguous slice; a copy of the
//! positions in the same order sits beside it, so a query reads positions sequentially and
//! never touches the caller's slice. Different cells may share a bucket: a query checks the
//! distance of every point of a bucket, and visits each distinct bucket once.
//!
//! A query looks at the cells overlapping the box `query ± r` (enlarged by `5·10⁻⁴ r`). As a
//! cell is wider than that box, these are at most two cells per axis, i.e. the `2×2×2` block
//! made of the query's own cell and, on each axis, the neighbour on the side of the half of
//! the cell the query lies in. The cell bounds are computed by applying to `query ∓ r` exactly
//! the (monotone) float computation used for the points, so no point within `r` can be missed.
//! (Only when points are spread over more than ~10⁷ cells can rounding widen that block; past
//! `3×3×3` cells the query then scans every point, still exactly.)
//!
//! # Build
//!
//! The build is parallel (rayon) and does not depend on the number of threads: the bounding
//! box is a min/max reduction, and the sort is stable, so each bucket lists its points in
//! increasing index order whatever the scheduling. The sort has two levels: a first pass
//! scatters `(bucket, index)` pairs and their positions into at most 256 partitions by the high bits of the bucket
//! (chunks of the input write to disjoint sub-slices), then each partition, now small enough to
//! stay in cache, is counting-sorted by the low bits on its own. Every allocation is kept
//! between builds.
//!
//! # Measured
//!
//! `cargo run --release -p render --example hash_grid_bench` on a 2 vCPU machine (Xeon
//! 2.5 GHz), 1,000,000 points on five faces of a box of edge 2.5 (a fifth in two blobs),
//! `r = 0.0066`, `2^20` buckets, 44 MB held (of which 24 MB build scratch): build 47 ms on one
//! thread, 28 ms on two; 262,144 random queries on the same faces: 1.1 M queries/s on one
//! thread, 2.0–2.4 M/s on two, 6.15 points found per query. Reading the caller's positions
//! through the indices instead of the sorted copy made queries 1.6× slower; interleaving index
//! and position in one 16-byte record made no measurable difference.

use math::{Aabb, Vec3};
use rayon::prelude::*;

/// Number of points per chunk in the parallel passes over the input.
const CHUNK: usize = 1 << 16;
/// Points per chunk in the lean build's parallel passes, which read each point from the
/// caller's records (64 bytes apart in the VCM engine): smaller than [`CHUNK`], of which a
/// typical iteration's 10⁵–10⁶ points make only 2–16, too few to keep every thread busy.
const LEAN_CHUNK: usize = 1 << 13;
/// Points whose positions the lean build's keys pass reads before it hashes them (12 KiB).
const KEY_BLOCK: usize = 1 << 10;
/// log2 of the largest number of first-level partitions.
const PARTITION_BITS: u32 = 8;
/// Cell edge over `2r`: slightly more than one, so the enlarged query box spans at most two
/// cells per axis.
const CELL_SCALE: f32 = 1.001;
/// Half-edge of the query box over `r`: slightly more than one, so that rounding in the
/// distance test cannot accept a point outside the box.
const SEARCH_SCALE: f32 = 1.0005;
/// The block of cells a query looks at normally has at most `3×3×3` cells (`2×2×2` in
/// practice); beyond that (absurd spreads of points) a query scans all points.
const MAX_QUERY_CELLS: usize = 27;
/// Records of a bucket that [`HashGrid::prefetch_slots`] asks for: a query's buckets hold about
/// four points on SmallVCM's scenes, and the hardware prefetcher follows a sequential read.
const PREFETCHED_PER_BUCKET: usize = 2;
/// How far ahead the lean build's counting sort prefetches the bucket of a key.
const SORT_AHEAD: usize = 16;

/// The map from positions to cells and buckets, fixed by one build.
#[derive(Clone, Copy, Debug)]
struct CellMap {
    /// Smallest corner of the bounding box of the points.
    origin: Vec3,
    /// One over the cell edge.
    inv_cell: f32,
    /// Largest cell coordinate on each axis.
    max_cell: [u32; 3],
    /// Scaled coordinates of the largest corner of the bounding box.
    max_scaled: Vec3,
    /// Number of buckets minus one (the bucket count is a power of two).
    bucket_mask: u32,
}

impl CellMap {
    /// Position in cell units from the origin. Monotone in each coordinate, and the same
    /// computation for points and query bounds.
    #[inline]
    fn scaled(&self, p: Vec3) -> Vec3 {
        (p - self.origin) * self.inv_cell
    }

    /// Cell coordinate on `axis` of a non-negative scaled coordinate `s` (monotone in `s`).
    #[inline]
    fn cell(&self, s: f32, axis: usize) -> u32 {
        (s as u32).min(self.max_cell[axis])
    }

    /// Bucket of the cell `(x, y, z)`. Cells are grouped in blocks of 4×4×4 whose 64 cells get
    /// consecutive buckets (in Morton order): the 2×2×2 cells of a query, and the queries of
    /// neighbouring camera vertices, then read nearby memory. Blocks are spread by a hash.
    #[inline]
    fn bucket(&self, x: u32, y: u32, z: u32) -> u32 {
        let low = morton_low(x) | morton_low(y) << 1 | morton_low(z) << 2;
        (block_hash(x >> 2, y >> 2, z >> 2) << 6 | low) & self.bucket_mask
    }

    /// Bucket of a (finite) point.
    #[inline]
    fn bucket_of(&self, p: Vec3) -> u32 {
        let s = self.scaled(p);
        self.bucket(self.cell(s.x, 0), self.cell(s.y, 1), self.cell(s.z, 2))
    }
}

/// Bits 0 and 1 of a cell coordinate spread to bits 0 and 3: a cell's place in its 4×4×4 block
/// is `morton_low(x) | morton_low(y) << 1 | morton_low(z) << 2` (Morton order).
#[inline]
fn morton_low(c: u32) -> u32 {
    (c & 1) | (c & 2) << 2
}

/// The hash of the 4×4×4 block `(x, y, z)` (cell coordinates over 4): the coordinates packed
/// (beyond 21 bits they overlap; that is only a collision), mixed with the SplitMix64 finaliser,
/// high bits kept.
#[inline]
fn block_hash(x: u32, y: u32, z: u32) -> u32 {
    let mut h = u64::from(x) ^ (u64::from(y) << 21) ^ (u64::from(z) << 42);
    h = (h ^ (h >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    h = (h ^ (h >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    h ^= h >> 31;
    (h >> 32) as u32
}

/// The buckets one query looks at, planned by [`HashGrid::plan`] for the grid it came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GridQuery {
    /// The query visits nothing.
    Nothing,
    /// The distinct buckets of its (at most 2×2×2) cells, `ids[..count]`, in query order.
    Buckets {
        /// Bucket numbers.
        ids: [u32; 8],
        /// How many of `ids` are used.
        count: usize,
    },
    /// Wider than two cells on some axis, or a grid of fewer than 64 buckets: the query lists
    /// its buckets itself (rare).
    General,
}

/// A hashed uniform grid over points, cell size (about) `2r`, built for one radius `r`.
///
/// Build it with [`HashGrid::build`] (reusing one grid across iterations keeps its
/// allocations), then query it with [`HashGrid::for_each_in_radius`].
#[derive(Clone, Debug)]
pub struct HashGrid {
    /// Query radius of the last build (0 when nothing is indexed).
    radius: f32,
    /// `radius²`, the bound of the distance test.
    radius_sq: f32,
    /// Half-edge of the box of cells a query looks at.
    search_extent: f32,
    /// Cells and buckets of the last build.
    map: CellMap,
    /// `B + 1` offsets into `indices`: bucket `b` is `starts[b]..starts[b + 1]`. Empty when
    /// nothing is indexed.
    starts: Vec<u32>,
    /// Point indices sorted by bucket (stable: increasing within a bucket).
    indices: Vec<u32>,
    /// `positions[indices[i]]`, for sequential reads in queries.
    sorted_positions: Vec<Vec3>,
    /// Scratch: bucket of each input point.
    keys: Vec<u32>,
    /// Scratch: `(bucket << 32) | index`, grouped by partition.
    pairs: Vec<u64>,
    /// Scratch: the positions matching `pairs`.
    pair_positions: Vec<Vec3>,
    /// Scratch: per chunk, number of points in each partition.
    chunk_counts: Vec<u32>,
    /// Upper bound of the number of buckets (tests use it to force collisions).
    bucket_limit: usize,
}

impl Default for HashGrid {
    fn default() -> Self {
        Self::new()
    }
}

impl HashGrid {
    /// An empty grid: every query visits nothing until [`HashGrid::build`] is called.
    pub fn new() -> Self {
        Self {
            radius: 0.0,
            radius_sq: 0.0,
            search_extent: 0.0,
            map: CellMap {
                origin: Vec3::ZERO,
                inv_cell: 0.0,
                max_cell: [0; 3],
                max_scaled: Vec3::ZERO,
                bucket_mask: 0,
            },
            starts: Vec::new(),
            indices: Vec::new(),
            sorted_positions: Vec::new(),
            keys: Vec::new(),
            pairs: Vec::new(),
            pair_positions: Vec::new(),
            chunk_counts: Vec::new(),
            bucket_limit: usize::MAX,
        }
    }

    /// An empty grid that will never use more than `max_buckets` buckets (rounded down to a
    /// power of two), to force hash collisions in tests.
    #[cfg(test)]
    fn with_bucket_limit(max_buckets: usize) -> Self {
        Self { bucket_limit: max_buckets.max(1), ..Self::new() }
    }

    /// Rebuilds the grid over `positions` (a point's index is its position in the slice) for
    /// queries of radius `radius`.
    ///
    /// Runs on the current rayon pool; the result does not depend on the number of threads.
    /// Points with a non-finite coordinate are skipped. A radius that is not a positive finite
    /// number indexes nothing (every query then visits nothing).
    ///
    /// # Panics
    ///
    /// If `positions` has `2³¹` points or more (indices are stored as `u32`).
    pub fn build(&mut self, positions: &[Vec3], radius: f32) {
        let n = positions.len();
        assert!(n < 1 << 31, "HashGrid: too many points ({n})");
        self.clear();
        if n == 0 || !(radius.is_finite() && radius > 0.0) {
            return;
        }

        let bounds = positions
            .par_chunks(CHUNK)
            .map(|chunk| chunk.iter().filter(|p| p.is_finite()).fold(Aabb::EMPTY, |b, &p| b.grow(p)))
            .reduce(|| Aabb::EMPTY, Aabb::union);
        if bounds.is_empty() {
            return;
        }

        let bucket_count = self.set_map(bounds, n, radius);
        let bucket_bits = bucket_count.trailing_zeros();
        let map = self.map;

        // First level: partitions by the high bits of the bucket, plus a last partition for
        // skipped (non-finite) points, whose key is `bucket_count`.
        let partition_bits = bucket_bits.min(PARTITION_BITS);
        let low_bits = bucket_bits - partition_bits;
        let partitions = (1usize << partition_bits) + 1;
        let skipped_key = bucket_count as u32;
        let chunks = n.div_ceil(CHUNK);

        self.keys.resize(n, 0);
        self.chunk_counts.resize(chunks * partitions, 0);
        positions
            .par_chunks(CHUNK)
            .zip(self.keys.par_chunks_mut(CHUNK))
            .zip(self.chunk_counts.par_chunks_mut(partitions))
            .for_each(|((points, keys), counts)| {
                for (p, key) in points.iter().zip(keys) {
                    *key = if p.is_finite() { map.bucket_of(*p) } else { skipped_key };
                    counts[(*key >> low_bits) as usize] += 1;
                }
            });

        // Cut `pairs` into one slice per (partition, chunk), partition-major, and hand each chunk
        // its slices: the scatter is then stable and free of shared writes.
        let mut partition_sizes = vec![0usize; partitions];
        for counts in self.chunk_counts.chunks(partitions) {
            for (size, &count) in partition_sizes.iter_mut().zip(counts) {
                *size += count as usize;
            }
        }
        self.pairs.resize(n, 0);
        self.pair_positions.resize(n, Vec3::ZERO);
        let mut per_chunk: Vec<Vec<(&mut [u64], &mut [Vec3])>> =
            (0..chunks).map(|_| Vec::with_capacity(partitions)).collect();
        let mut rest: (&mut [u64], &mut [Vec3]) = (&mut self.pairs, &mut self.pair_positions);
        for part in 0..partitions {
            for (chunk, slices) in per_chunk.iter_mut().enumerate() {
                let size = self.chunk_counts[chunk * partitions + part] as usize;
                let (pairs, pairs_tail) = std::mem::take(&mut rest.0).split_at_mut(size);
                let (points, points_tail) = std::mem::take(&mut rest.1).split_at_mut(size);
                slices.push((pairs, points));
                rest = (pairs_tail, points_tail);
            }
        }
        per_chunk
            .into_par_iter()
            .zip(self.keys.par_chunks(CHUNK))
            .zip(positions.par_chunks(CHUNK))
            .enumerate()
            .for_each(|(chunk, ((mut slices, keys), points))| {
                let base = (chunk * CHUNK) as u64;
                let mut cursors = vec![0usize; partitions];
                for (i, (&key, &p)) in keys.iter().zip(points).enumerate() {
                    let part = (key >> low_bits) as usize;
                    let (pairs, points) = &mut slices[part];
                    pairs[cursors[part]] = (u64::from(key) << 32) | (base + i as u64);
                    points[cursors[part]] = p;
                    cursors[part] += 1;
                }
            });

        // Second level: each partition sorts its own range of points and fills its own range of
        // bucket starts.
        let stored = n - partition_sizes[partitions - 1];
        self.indices.resize(stored, 0);
        self.sorted_positions.resize(stored, Vec3::ZERO);
        self.starts.resize(bucket_count + 1, 0);
        self.starts[bucket_count] = stored as u32;

        let mut jobs = Vec::with_capacity(partitions - 1);
        let mut pairs: &[u64] = &self.pairs[..stored];
        let mut points: &[Vec3] = &self.pair_positions[..stored];
        let mut indices: &mut [u32] = &mut self.indices;
        let mut sorted: &mut [Vec3] = &mut self.sorted_positions;
        let mut base = 0usize;
        for (starts, &size) in self.starts[..bucket_count].chunks_mut(1 << low_bits).zip(&partition_sizes) {
            let (in_pairs, in_points, out_indices, out_sorted);
            (in_pairs, pairs) = pairs.split_at(size);
            (in_points, points) = points.split_at(size);
            (out_indices, indices) = std::mem::take(&mut indices).split_at_mut(size);
            (out_sorted, sorted) = std::mem::take(&mut sorted).split_at_mut(size);
            jobs.push((base as u32, (in_pairs, in_points), starts, (out_indices, out_sorted)));
            base += size;
        }
        let low_mask = (1u32 << low_bits) - 1;
        jobs.into_par_iter().for_each(|(base, input, starts, output)| {
            sort_partition(base, low_mask, input, starts, output);
        });
    }

    /// Sets the cells, buckets and radius of a build over `n` points within `bounds`; returns
    /// the bucket count.
    fn set_map(&mut self, bounds: Aabb, n: usize, radius: f32) -> usize {
        // The clamps keep extreme radii free of NaNs; the cell function stays monotone, which
        // is all the query needs.
        let cell_size = (2.0 * radius * CELL_SCALE).min(f32::MAX);
        let inv_cell = (1.0 / cell_size).min(f32::MAX);
        let bucket_count = n.next_power_of_two().min(prev_power_of_two(self.bucket_limit));
        let mut map = CellMap {
            origin: bounds.min,
            inv_cell,
            max_cell: [u32::MAX; 3],
            max_scaled: Vec3::ZERO,
            bucket_mask: (bucket_count - 1) as u32,
        };
        map.max_scaled = map.scaled(bounds.max);
        map.max_cell = [0, 1, 2].map(|axis| map.max_scaled[axis] as u32);
        self.map = map;
        self.radius = radius;
        self.radius_sq = radius * radius;
        self.search_extent = (radius * SEARCH_SCALE).min(f32::MAX);
        bucket_count
    }

    /// Rebuilds the grid like [`HashGrid::build`] over the `n` points `position(0..n)`, but keeps
    /// no copy of the positions and sorts with one key per point as its only scratch (4 bytes
    /// per point besides the sorted indices, against 36 for [`HashGrid::build`]): the memory-
    /// efficient mode. The slots, bucket by bucket in increasing index order, are those
    /// [`HashGrid::build`] gives for the same positions. Queries must then hand the positions
    /// back in slot order: [`HashGrid::for_each_slot_near`]. The scatter is sequential (a
    /// counting sort; measured in docs/memory.md).
    ///
    /// # Panics
    ///
    /// If `n ≥ 2³¹`.
    pub fn build_lean(&mut self, n: usize, position: impl Fn(usize) -> Vec3 + Sync, radius: f32) {
        assert!(n < 1 << 31, "HashGrid: too many points ({n})");
        self.clear();
        self.sorted_positions = Vec::new();
        self.pairs = Vec::new();
        self.pair_positions = Vec::new();
        self.chunk_counts = Vec::new();
        if n == 0 || !(radius.is_finite() && radius > 0.0) {
            return;
        }
        let bounds = (0..n)
            .into_par_iter()
            .step_by(LEAN_CHUNK)
            .map(|first| {
                (first..(first + LEAN_CHUNK).min(n))
                    .map(&position)
                    .filter(|p| p.is_finite())
                    .fold(Aabb::EMPTY, Aabb::grow)
            })
            .reduce(|| Aabb::EMPTY, Aabb::union);
        if bounds.is_empty() {
            return;
        }
        let bucket_count = self.set_map(bounds, n, radius);
        let map = self.map;
        let skipped = bucket_count as u32;
        self.keys.resize(n, 0);
        self.keys.par_chunks_mut(LEAN_CHUNK).enumerate().for_each(|(chunk, keys)| {
            // The positions of a block first, then their keys: the loop that only reads keeps
            // many record loads in flight, the hashing then runs on cached values.
            let mut block = [Vec3::ZERO; KEY_BLOCK];
            for (b, keys) in keys.chunks_mut(KEY_BLOCK).enumerate() {
                let first = chunk * LEAN_CHUNK + b * KEY_BLOCK;
                for (offset, p) in block[..keys.len()].iter_mut().enumerate() {
                    *p = position(first + offset);
                }
                for (key, p) in keys.iter_mut().zip(&block) {
                    *key = if p.is_finite() { map.bucket_of(*p) } else { skipped };
                }
            }
        });
        // Counting sort: `starts[b]` counts bucket b, becomes its end by a running sum, and is
        // moved back to its start while the points are placed from the last one (stable).
        // Both passes over the keys jump around `starts`: the entry of the key `SORT_AHEAD`
        // places ahead is prefetched (`keys` ≤ `bucket_count`, so every key indexes `starts`).
        self.starts.resize(bucket_count + 1, 0);
        for (index, &key) in self.keys.iter().enumerate() {
            if let Some(&ahead) = self.keys.get(index + SORT_AHEAD) {
                crate::prefetch::prefetch(&self.starts[ahead as usize]);
            }
            self.starts[key as usize] += 1;
        }
        let stored = n - self.starts[bucket_count] as usize;
        let mut end = 0;
        for start in &mut self.starts[..bucket_count] {
            end += *start;
            *start = end;
        }
        self.starts[bucket_count] = stored as u32;
        self.indices.resize(stored, 0);
        for (index, &key) in self.keys.iter().enumerate().rev() {
            if let Some(&ahead) = index.checked_sub(SORT_AHEAD).map(|i| &self.keys[i]) {
                crate::prefetch::prefetch(&self.starts[ahead as usize]);
            }
            if key != skipped {
                let slot = &mut self.starts[key as usize];
                *slot -= 1;
                self.indices[*slot as usize] = index as u32;
            }
        }
        self.keys = Vec::new();
    }

    /// Whether the grid holds the points' positions ([`HashGrid::build`]) or needs them from the
    /// caller ([`HashGrid::build_lean`]).
    pub fn keeps_positions(&self) -> bool {
        self.indices.is_empty() || !self.sorted_positions.is_empty()
    }

    /// Calls `visit(slot)` for every stored point within `radius` (clamped to the build radius)
    /// of `query` whose index lies in `indices` (all when `None`); `plan` is
    /// [`HashGrid::plan`]`(query)`. The positions come from the
    /// grid's own sorted copy after [`HashGrid::build`]; a [`HashGrid::build_lean`] grid keeps
    /// none and reads the position of slot `s` as `position(s)` (the caller's data in slot order).
    pub fn for_each_slot_near(
        &self,
        (query, plan): (Vec3, &GridQuery),
        radius: f32,
        indices: Option<std::ops::Range<u32>>,
        position: impl Fn(usize) -> Vec3,
        mut visit: impl FnMut(usize),
    ) {
        let radius_sq = (radius * radius).min(self.radius_sq);
        match (indices, self.keeps_positions()) {
            (None, true) => self.for_each_slot(query, plan, radius_sq, visit),
            (indices, kept) => self.for_each_bucket(query, plan, |start, end| {
                let (first, last) = match &indices {
                    None => (start, end),
                    Some(range) => self.index_range(start, end, range),
                };
                if kept {
                    self.visit_slice(first, last, query, radius_sq, &mut visit);
                } else {
                    for slot in first..last {
                        if (position(slot) - query).length_squared() <= radius_sq {
                            visit(slot);
                        }
                    }
                }
            }),
        }
    }

    /// The slots `first..last` within bucket slots `start..end` whose indices lie in `range`.
    #[inline]
    fn index_range(&self, start: usize, end: usize, range: &std::ops::Range<u32>) -> (usize, usize) {
        let bucket = &self.indices[start..end];
        let first = bucket.partition_point(|&i| i < range.start);
        let last = first + bucket[first..].partition_point(|&i| i < range.end);
        (start + first, start + last)
    }

    /// Forgets the indexed points (keeps the allocations).
    fn clear(&mut self) {
        self.radius = 0.0;
        self.radius_sq = 0.0;
        self.search_extent = 0.0;
        self.starts.clear();
        self.indices.clear();
        self.sorted_positions.clear();
        self.keys.clear();
        self.pairs.clear();
        self.pair_positions.clear();
        self.chunk_counts.clear();
    }

    /// Calls `visit(index)` for every stored point within the build radius `r` of `query`
    /// (`|p − query|² <= r²`), each exactly once, in no particular order (but the same order for
    /// the same build and query).
    ///
    /// Looks at the (normally `2×2×2`) cells overlapping the ball, and at each distinct bucket
    /// of those cells once, so collisions never double count. A query outside the points'
    /// bounding box, or with a NaN coordinate, visits nothing.
    #[inline]
    pub fn for_each_in_radius(&self, query: Vec3, mut visit: impl FnMut(usize)) {
        self.for_each_slot(query, &self.plan(query), self.radius_sq, |slot| visit(self.indices[slot] as usize));
    }

    /// The stored point indices in slot order (bucket by bucket). Data laid out in this order
    /// is read contiguously by [`HashGrid::for_each_slot_within`].
    pub fn sorted_indices(&self) -> &[u32] {
        &self.indices
    }

    /// Like [`HashGrid::for_each_in_radius`] but for a radius `radius ≤` the build radius (it is
    /// clamped to it), and passing the point's *slot*: its position in
    /// [`HashGrid::sorted_indices`].
    pub fn for_each_slot_within(&self, query: Vec3, radius: f32, visit: impl FnMut(usize)) {
        let radius_sq = (radius * radius).min(self.radius_sq);
        self.for_each_slot(query, &self.plan(query), radius_sq, visit);
    }

    /// Like [`HashGrid::for_each_slot_within`], restricted to the points whose index (in the
    /// slice given to [`HashGrid::build`]) lies in `indices`. A bucket lists its points in
    /// increasing index order, so the range is found by two binary searches per bucket and
    /// points outside it are never distance-tested: laying out the points of several groups
    /// one group after another gives one grid that answers queries per group.
    pub fn for_each_slot_within_indices(
        &self,
        query: Vec3,
        radius: f32,
        indices: std::ops::Range<u32>,
        mut visit: impl FnMut(usize),
    ) {
        let radius_sq = (radius * radius).min(self.radius_sq);
        self.for_each_bucket(query, &self.plan(query), |start, end| {
            let (first, last) = self.index_range(start, end, &indices);
            self.visit_slice(first, last, query, radius_sq, &mut visit);
        });
    }

    /// Visits the slots of the points within `sqrt(radius_sq)` (at most the build radius).
    #[inline]
    fn for_each_slot(&self, query: Vec3, plan: &GridQuery, radius_sq: f32, mut visit: impl FnMut(usize)) {
        let mut ranges = [(0u32, 0u32); MAX_QUERY_CELLS];
        // Scanning every bucket in slot order is scanning every slot.
        let count = self.query_buckets(query, plan, &mut ranges);
        let ranges = match count {
            Some(count) => &ranges[..count],
            None => &[(0, self.sorted_positions.len() as u32)][..],
        };
        for &(start, end) in ranges {
            self.visit_slice(start as usize, end as usize, query, radius_sq, &mut visit);
        }
    }

    /// Calls `visit(start, end)` with the slot range of every distinct non-empty bucket a query
    /// at `query` must look at (each range lies within one bucket), in the order of the cells
    /// (`x` fastest, then `y`, then `z`; a bucket at its first cell).
    #[inline]
    fn for_each_bucket(&self, query: Vec3, plan: &GridQuery, mut visit: impl FnMut(usize, usize)) {
        let mut ranges = [(0u32, 0u32); MAX_QUERY_CELLS];
        let count = match self.query_buckets(query, plan, &mut ranges) {
            Some(count) => count,
            None => {
                // Only when float precision is exhausted (points spread over > ~10⁷ cells):
                // every bucket, in slot order.
                for bucket in self.starts.windows(2) {
                    if bucket[0] < bucket[1] {
                        visit(bucket[0] as usize, bucket[1] as usize);
                    }
                }
                return;
            }
        };
        for &(start, end) in &ranges[..count] {
            visit(start as usize, end as usize);
        }
    }

    /// The cells a query at `query` looks at (per axis the first and last), or `None` when it
    /// visits nothing (no points, a NaN coordinate, or outside the points' bounding box).
    #[inline]
    fn query_cells(&self, query: Vec3) -> Option<[(u32, u32); 3]> {
        if self.indices.is_empty() || !query.is_finite() {
            return None;
        }
        let map = &self.map;
        let lo = map.scaled(query - Vec3::splat(self.search_extent));
        let hi = map.scaled(query + Vec3::splat(self.search_extent));
        let mut cells = [(0u32, 0u32); 3];
        for (axis, range) in cells.iter_mut().enumerate() {
            // Every point p has 0 <= scaled(p) <= max_scaled; monotonicity does the rest.
            if !(hi[axis] >= 0.0 && lo[axis] <= map.max_scaled[axis]) {
                return None;
            }
            *range = (map.cell(lo[axis].max(0.0), axis), map.cell(hi[axis], axis));
        }
        Some(cells)
    }

    /// Plans the query at `query`: the buckets of its cells, computed once for the prefetch
    /// hints ([`HashGrid::prefetch_buckets`], [`HashGrid::prefetch_slots`]) and the query itself
    /// ([`HashGrid::for_each_slot_near`]).
    #[inline]
    pub fn plan(&self, query: Vec3) -> GridQuery {
        let Some(cells) = self.query_cells(query) else { return GridQuery::Nothing };
        let map = &self.map;
        // With at least 64 buckets a bucket keeps its cell's 6 low (Morton) bits, which hold
        // bits 0 and 1 of every coordinate: cells whose coordinates differ by 1 or 2 on some
        // axis never share a bucket. So when every axis spans at most two cells (the normal
        // case) the buckets are distinct, and each 4×4×4 block's hash is computed once.
        let [(x0, x1), (y0, y1), (z0, z1)] = cells;
        if x1 - x0 > 1 || y1 - y0 > 1 || z1 - z0 > 1 || map.bucket_mask < 63 {
            return GridQuery::General;
        }
        let mut ids = [0u32; 8];
        let mut count = 0;
        let (bx0, bx1) = (x0 >> 2, x1 >> 2);
        let (low_x0, low_x1) = (morton_low(x0), morton_low(x1));
        // The cells' (y, z) rows in query order (z outer, y inner), over slices rather than
        // `RangeInclusive`s (scene 1 `vcm`, 256², two iterations: 3,081 M → 3,059 M
        // instructions, images identical).
        let (ys, zs) = ([y0, y1], [z0, z1]);
        let (rows_y, rows_z) = (1 + usize::from(y1 != y0), 1 + usize::from(z1 != z0));
        // The block hashes of the last row's (y, z) block; no block has coordinate `u32::MAX`.
        let mut row = (u32::MAX, u32::MAX, 0, 0);
        for &z in &zs[..rows_z] {
            for &y in &ys[..rows_y] {
                let (by, bz) = (y >> 2, z >> 2);
                if (row.0, row.1) != (by, bz) {
                    let h0 = block_hash(bx0, by, bz);
                    let h1 = if bx1 == bx0 { h0 } else { block_hash(bx1, by, bz) };
                    row = (by, bz, h0, h1);
                }
                let low_yz = morton_low(y) << 1 | morton_low(z) << 2;
                ids[count] = (row.2 << 6 | low_x0 | low_yz) & map.bucket_mask;
                count += 1;
                if x1 != x0 {
                    ids[count] = (row.3 << 6 | low_x1 | low_yz) & map.bucket_mask;
                    count += 1;
                }
            }
        }
        GridQuery::Buckets { ids, count }
    }

    /// Prefetch hint, the first of two stages ahead of a query: the bucket starts of its
    /// cells. It changes no result; issued early enough (the camera pass issues it as soon as
    /// a hit is found), the query's first cache miss is over when the query comes.
    #[inline]
    pub fn prefetch_buckets(&self, plan: &GridQuery) {
        if let GridQuery::Buckets { ids, count } = plan {
            for &bucket in &ids[..*count] {
                if let Some(start) = self.starts.get(bucket as usize) {
                    crate::prefetch::prefetch(start);
                }
            }
        }
    }

    /// Prefetch hint, the second stage: the first two records of `data` (the caller's records
    /// in slot order) in every bucket of the query, which the query will distance-test. Reads
    /// the bucket starts, so it should come a while after [`HashGrid::prefetch_buckets`].
    #[inline]
    pub fn prefetch_slots<T>(&self, plan: &GridQuery, data: &[T]) {
        if let GridQuery::Buckets { ids, count } = plan {
            for &bucket in &ids[..*count] {
                let bucket = bucket as usize;
                let (Some(&start), Some(&end)) = (self.starts.get(bucket), self.starts.get(bucket + 1)) else {
                    continue;
                };
                let (start, end) = (start as usize, end as usize);
                if let Some(first) = data.get(start..end.min(start + PREFETCHED_PER_BUCKET)) {
                    crate::prefetch::prefetch_lines(first);
                }
            }
        }
    }

    /// Writes to `ranges` the slot ranges of the distinct non-empty buckets of the cells a query
    /// at `query` (planned as `plan`) looks at (in [`HashGrid::for_each_bucket`]'s order) and
    /// returns their number, or `None` when the query must scan every bucket (more than
    /// [`MAX_QUERY_CELLS`] cells).
    #[inline]
    fn query_buckets(
        &self,
        query: Vec3,
        plan: &GridQuery,
        ranges: &mut [(u32, u32); MAX_QUERY_CELLS],
    ) -> Option<usize> {
        let mut count = 0;
        let mut push = |bucket: u32| {
            let (start, end) = (self.starts[bucket as usize], self.starts[bucket as usize + 1]);
            if start < end {
                ranges[count] = (start, end);
                count += 1;
            }
        };
        match plan {
            GridQuery::Nothing => return Some(0),
            GridQuery::Buckets { ids, count: n } => {
                ids[..*n].iter().for_each(|&bucket| push(bucket));
                return Some(count);
            }
            GridQuery::General => {}
        }
        let Some(cells) = self.query_cells(query) else { return Some(0) };
        let cell_count: u64 = cells.iter().map(|&(first, last)| u64::from(last - first) + 1).product();
        if cell_count > MAX_QUERY_CELLS as u64 {
            return None;
        }
        let mut buckets = [0u32; MAX_QUERY_CELLS];
        let mut distinct = 0;
        for z in cells[2].0..=cells[2].1 {
            for y in cells[1].0..=cells[1].1 {
                for x in cells[0].0..=cells[0].1 {
                    let bucket = self.map.bucket(x, y, z);
                    if !buckets[..distinct].contains(&bucket) {
                        buckets[distinct] = bucket;
                        distinct += 1;
                        push(bucket);
                    }
                }
            }
        }
        Some(count)
    }

    #[inline]
    fn visit_slice(&self, start: usize, end: usize, query: Vec3, radius_sq: f32, visit: &mut impl FnMut(usize)) {
        for (offset, p) in self.sorted_positions[start..end].iter().enumerate() {
            if (*p - query).length_squared() <= radius_sq {
                visit(start + offset);
            }
        }
    }

    /// The query radius of the last build (0 when nothing is indexed, e.g. after an unusable
    /// radius).
    pub fn radius(&self) -> f32 {
        self.radius
    }

    /// Number of indexed points: those of the last build with finite coordinates (0 if its
    /// radius was unusable).
    pub fn len(&self) -> usize {
        self.indices.len()
    }

    /// True when no point is indexed.
    pub fn is_empty(&self) -> bool {
        self.indices.is_empty()
    }

    /// Heap bytes held (capacities, including the scratch kept for the next build).
    pub fn memory_bytes(&self) -> usize {
        use std::mem::size_of;
        self.starts.capacity() * size_of::<u32>()
            + self.indices.capacity() * size_of::<u32>()
            + self.sorted_positions.capacity() * size_of::<Vec3>()
            + self.keys.capacity() * size_of::<u32>()
            + self.pairs.capacity() * size_of::<u64>()
            + self.pair_positions.capacity() * size_of::<Vec3>()
            + self.chunk_counts.capacity() * size_of::<u32>()
    }
}

/// The largest power of two `<= x` (`x >= 1`).
fn prev_power_of_two(x: usize) -> usize {
    1 << (usize::BITS - 1 - x.leading_zeros())
}

/// Stable counting sort of one partition's `(bucket << 32) | index` pairs (with their positions)
/// by the low bucket bits: writes the partition's indices and sorted positions, and its bucket
/// `starts` (offset by `base`, the partition's first slot).
fn sort_partition(
    base: u32,
    low_mask: u32,
    (pairs, points): (&[u64], &[Vec3]),
    starts: &mut [u32],
    (indices, sorted): (&mut [u32], &mut [Vec3]),
) {
    starts.fill(0);
    for &pair in pairs {
        starts[((pair >> 32) as u32 & low_mask) as usize] += 1;
    }
    // Bucket ends, then filled backwards so each bucket keeps its input order and its counter
    // ends at the bucket's start.
    let mut end = 0;
    for s in starts.iter_mut() {
        end += *s;
        *s = end;
    }
    for (&pair, &p) in pairs.iter().zip(points).rev() {
        let slot = &mut starts[((pair >> 32) as u32 & low_mask) as usize];
        *slot -= 1;
        indices[*slot as usize] = pair as u32;
        sorted[*slot as usize] = p;
    }
    for s in starts.iter_mut() {
        *s += base;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use math::Rng;

    fn uniform_points(n: usize, seed: u64, min: Vec3, max: Vec3) -> Vec<Vec3> {
        (0..n)
            .map(|i| {
                let mut rng = Rng::for_stream(seed, 0, i as u64);
                min + (max - min) * Vec3::from(rng.uniform3())
            })
            .collect()
    }

    /// Points around a few centres (dense cores) plus points on two axis planes.
    fn clustered_points(n: usize, seed: u64) -> Vec<Vec3> {
        let centres = [Vec3::new(0.1, 0.2, 0.3), Vec3::new(0.8, 0.7, 0.1), Vec3::new(0.5, 0.5, 0.9)];
        (0..n)
            .map(|i| {
                let mut rng = Rng::for_stream(seed, 1, i as u64);
                let u = Vec3::from(rng.uniform3());
                match i % 4 {
                    0 => Vec3::new(u.x, u.y, 0.25),
                    1 => Vec3::new(0.6, u.y, u.z),
                    _ => {
                        let c = centres[i % 3];
                        let spread = 0.05 * rng.uniform() * rng.uniform();
                        c + (u - 0.5) * spread
                    }
                }
            })
            .collect()
    }

    fn brute_force(points: &[Vec3], query: Vec3, radius: f32) -> Vec<usize> {
        let r2 = radius * radius;
        (0..points.len()).filter(|&i| (points[i] - query).length_squared() <= r2).collect()
    }

    fn visited(grid: &HashGrid, query: Vec3) -> Vec<usize> {
        let mut found = Vec::new();
        grid.for_each_in_radius(query, |i| found.push(i));
        found
    }

    /// Queries: random in (and a little around) the box, at the points, at points offset by
    /// exactly `±r` along an axis, and on cell boundaries and cell centres.
    fn queries(grid: &HashGrid, points: &[Vec3], radius: f32, seed: u64) -> Vec<Vec3> {
        let mut rng = Rng::for_stream(seed, 2, 0);
        let mut out = Vec::new();
        let min = points.iter().fold(Vec3::INFINITY, |a, &p| a.min(p));
        let max = points.iter().fold(Vec3::NEG_INFINITY, |a, &p| a.max(p));
        for _ in 0..300 {
            out.push(min - 0.05 + (max - min + 0.1) * Vec3::from(rng.uniform3()));
        }
        for k in 0..300 {
            let p = points[(rng.next_u32() as usize) % points.len()];
            let mut offset = Vec3::ZERO;
            offset[k % 3] = if k % 2 == 0 { radius } else { -radius };
            out.push(p);
            out.push(p + offset);
        }
        let cell = 1.0 / grid.map.inv_cell;
        for _ in 0..300 {
            let p = points[(rng.next_u32() as usize) % points.len()];
            let c = ((p - grid.map.origin) * grid.map.inv_cell).floor();
            let half = Vec3::from(rng.uniform3()).round() * 0.5;
            out.push(grid.map.origin + (c + half) * cell);
            out.push(grid.map.origin + c * cell);
        }
        out
    }

    fn check_against_brute_force(grid: &HashGrid, points: &[Vec3], radius: f32, queries: &[Vec3]) -> usize {
        let mut total = 0;
        for &q in queries {
            let mut got = visited(grid, q);
            got.sort_unstable();
            let len = got.len();
            got.dedup();
            assert_eq!(got.len(), len, "duplicates at {q}");
            assert_eq!(got, brute_force(points, q, radius), "query {q}");
            total += len;
        }
        total
    }

    #[test]
    fn hash_grid_matches_brute_force_uniform() {
        for (n, radius) in [(1, 0.1), (7, 0.3), (5_000, 0.06), (20_000, 0.04)] {
            let points = uniform_points(n, 11, Vec3::new(-1.0, 0.0, 2.0), Vec3::new(1.0, 0.5, 3.0));
            let mut grid = HashGrid::new();
            grid.build(&points, radius);
            assert_eq!(grid.len(), n);
            assert_eq!(grid.radius(), radius);
            let qs = queries(&grid, &points, radius, 5);
            let found = check_against_brute_force(&grid, &points, radius, &qs);
            assert!(n < 100 || found > qs.len(), "test too sparse: {found}");
        }
    }

    #[test]
    fn hash_grid_matches_brute_force_clustered() {
        let points = clustered_points(30_000, 3);
        for radius in [0.002, 0.01, 0.05] {
            let mut grid = HashGrid::new();
            grid.build(&points, radius);
            let qs = queries(&grid, &points, radius, 6);
            let found = check_against_brute_force(&grid, &points, radius, &qs);
            assert!(found > qs.len(), "test too sparse: {found}");
        }
    }

    #[test]
    fn hash_grid_many_chunks_and_partitions() {
        // Several input chunks and all 256 partitions in use.
        let points = clustered_points(3 * CHUNK + 123, 9);
        let radius = 0.004;
        let mut grid = HashGrid::new();
        grid.build(&points, radius);
        assert_eq!(grid.len(), points.len());
        let qs: Vec<Vec3> = queries(&grid, &points, radius, 7).into_iter().step_by(4).collect();
        check_against_brute_force(&grid, &points, radius, &qs);
        // Every bucket lists its points in increasing index order.
        for bucket in grid.starts.windows(2) {
            let slice = &grid.indices[bucket[0] as usize..bucket[1] as usize];
            assert!(slice.windows(2).all(|w| w[0] < w[1]));
        }
    }

    #[test]
    fn hash_grid_collisions_never_double_count() {
        let points = clustered_points(4_000, 4);
        let radius = 0.02;
        for limit in [1, 2, 3, 8] {
            let mut grid = HashGrid::with_bucket_limit(limit);
            grid.build(&points, radius);
            assert!(grid.starts.len() <= limit + 1);
            let qs = queries(&grid, &points, radius, 8);
            check_against_brute_force(&grid, &points, radius, &qs);
        }
    }

    /// The buckets of a query as the first implementation listed them: every cell of the block
    /// hashed on its own, in `x`, `y`, `z` order, each bucket at its first cell, the empty ones
    /// dropped (they visit nothing); `None` for the scan-everything fallback.
    fn reference_buckets(grid: &HashGrid, query: Vec3) -> Option<Vec<(u32, u32)>> {
        let map = &grid.map;
        if grid.indices.is_empty() || !query.is_finite() {
            return Some(Vec::new());
        }
        let lo = map.scaled(query - Vec3::splat(grid.search_extent));
        let hi = map.scaled(query + Vec3::splat(grid.search_extent));
        let mut cells = [(0u32, 0u32); 3];
        for (axis, range) in cells.iter_mut().enumerate() {
            if !(hi[axis] >= 0.0 && lo[axis] <= map.max_scaled[axis]) {
                return Some(Vec::new());
            }
            *range = (map.cell(lo[axis].max(0.0), axis), map.cell(hi[axis], axis));
        }
        if cells.iter().map(|&(a, b)| u64::from(b - a) + 1).product::<u64>() > MAX_QUERY_CELLS as u64 {
            return None;
        }
        let mut buckets = Vec::new();
        for z in cells[2].0..=cells[2].1 {
            for y in cells[1].0..=cells[1].1 {
                for x in cells[0].0..=cells[0].1 {
                    let bucket = map.bucket(x, y, z);
                    if !buckets.contains(&bucket) {
                        buckets.push(bucket);
                    }
                }
            }
        }
        let ranges = buckets.iter().map(|&b| (grid.starts[b as usize], grid.starts[b as usize + 1]));
        Some(ranges.filter(|&(start, end)| start < end).collect())
    }

    /// A plan lists the distinct buckets of the query's cells in the reference order when they
    /// are at most 2×2×2 on a grid of at least 64 buckets, `Nothing` for queries that visit
    /// nothing and `General` otherwise; the prefetch hints accept every plan and any record
    /// slice, also one shorter than the grid's slots.
    #[test]
    fn plans_list_the_query_buckets_and_hints_accept_any_plan() {
        let points = clustered_points(4_000, 4);
        for (limit, radius) in [(usize::MAX, 0.02), (32, 0.02), (usize::MAX, 0.003)] {
            let mut grid = HashGrid::with_bucket_limit(limit);
            grid.build(&points, radius);
            let mut qs = queries(&grid, &points, radius, 12);
            qs.extend([Vec3::NAN, Vec3::splat(-5.0), Vec3::splat(1e30)]);
            let mut kinds = [0; 3];
            for q in qs {
                let plan = grid.plan(q);
                kinds[match plan {
                    GridQuery::Nothing => 0,
                    GridQuery::Buckets { .. } => 1,
                    GridQuery::General => 2,
                }] += 1;
                match plan {
                    GridQuery::Buckets { ids, count } => {
                        assert!(limit >= 64, "query {q}: a grid of {limit} buckets gets no bucket list");
                        let mut expected: Vec<(u32, u32)> = ids[..count]
                            .iter()
                            .map(|&b| (grid.starts[b as usize], grid.starts[b as usize + 1]))
                            .collect();
                        expected.retain(|&(start, end)| start < end);
                        assert_eq!(Some(expected), reference_buckets(&grid, q), "query {q}");
                        let mut distinct = ids[..count].to_vec();
                        distinct.sort_unstable();
                        distinct.dedup();
                        assert_eq!(distinct.len(), count, "query {q}: repeated buckets");
                    }
                    GridQuery::Nothing => assert_eq!(reference_buckets(&grid, q), Some(Vec::new()), "query {q}"),
                    GridQuery::General => assert!(limit < 64, "query {q}: general plan on a large grid"),
                }
                grid.prefetch_buckets(&plan);
                for records in [&points[..], &points[..10], &[]] {
                    grid.prefetch_slots(&plan, records);
                }
            }
            // Every kind of plan was met (at least the three added queries visit nothing).
            assert!(kinds[0] >= 3, "limit {limit}: {kinds:?}");
            assert!(if limit >= 64 { kinds[1] > 0 } else { kinds[2] > 0 }, "limit {limit}: {kinds:?}");
        }
    }

    /// A query lists the same bucket ranges in the same order as [`reference_buckets`] (merged
    /// values are summed in visit order, so images depend on it), with and without collisions
    /// and for the fallback.
    #[test]
    fn query_buckets_keep_the_reference_order() {
        let clustered = clustered_points(4_000, 4);
        let mut spread = uniform_points(2_000, 3, Vec3::ZERO, Vec3::ONE);
        spread.extend(uniform_points(2_000, 4, Vec3::splat(1e7), Vec3::splat(1e7 + 8.0)));
        spread.push(Vec3::splat(-1e8));
        spread.extend(uniform_points(500, 5, Vec3::splat(3.9), Vec3::splat(4.1)));
        for (points, radius, limit) in [
            (&clustered, 0.02, usize::MAX),
            (&clustered, 0.003, usize::MAX),
            (&clustered, 0.02, 64),
            (&clustered, 0.02, 32),
            (&clustered, 0.02, 4),
            (&spread, 0.05, usize::MAX),
        ] {
            let mut grid = HashGrid::with_bucket_limit(limit);
            grid.build(points, radius);
            let mut qs = queries(&grid, points, radius, 12);
            qs.extend([Vec3::splat(4.0), Vec3::new(4.0, 3.95, 4.02), Vec3::NAN, Vec3::splat(-5.0)]);
            for q in qs {
                let mut ranges = [(0, 0); MAX_QUERY_CELLS];
                let got = grid.query_buckets(q, &grid.plan(q), &mut ranges).map(|n| ranges[..n].to_vec());
                assert_eq!(got, reference_buckets(&grid, q), "query {q}, radius {radius}, limit {limit}");
            }
        }
    }

    #[test]
    fn hash_grid_empty_and_degenerate() {
        let mut grid = HashGrid::new();
        assert!(grid.is_empty());
        assert!(visited(&grid, Vec3::ZERO).is_empty());
        grid.build(&[], 0.1);
        assert!(grid.is_empty());
        assert!(visited(&grid, Vec3::ZERO).is_empty());

        let points = uniform_points(100, 1, Vec3::ZERO, Vec3::ONE);
        for radius in [0.0, -1.0, f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            grid.build(&points, radius);
            assert!(grid.is_empty());
            assert!(visited(&grid, points[3]).is_empty());
        }

        // Extreme but valid radii.
        for radius in [1e-30, f32::MIN_POSITIVE, 1e30, f32::MAX] {
            grid.build(&points, radius);
            for q in [points[0], Vec3::splat(0.5), Vec3::splat(-1e30)] {
                let mut got = visited(&grid, q);
                got.sort_unstable();
                assert_eq!(got, brute_force(&points, q, radius), "radius {radius}, query {q}");
            }
        }

        // Non-finite points are skipped.
        let mut with_nan = points.clone();
        with_nan[10] = Vec3::new(f32::NAN, 0.0, 0.0);
        with_nan[20] = Vec3::new(0.0, f32::INFINITY, 0.0);
        grid.build(&with_nan, 0.2);
        assert_eq!(grid.len(), 98);
        let mut got = visited(&grid, Vec3::splat(0.5));
        got.sort_unstable();
        assert_eq!(got, brute_force(&with_nan, Vec3::splat(0.5), 0.2));

        // All points identical, and a single point.
        let same = vec![Vec3::splat(2.0); 50];
        grid.build(&same, 0.1);
        assert_eq!(visited(&grid, Vec3::splat(2.05)).len(), 50);
        grid.build(&same[..1], 0.1);
        assert_eq!(visited(&grid, Vec3::splat(2.0)), vec![0]);
    }

    #[test]
    fn hash_grid_queries_outside_and_nan() {
        let points = uniform_points(2_000, 2, Vec3::ZERO, Vec3::ONE);
        let mut grid = HashGrid::new();
        grid.build(&points, 0.05);
        for q in [
            Vec3::splat(-1.0),
            Vec3::new(0.5, 0.5, 7.0),
            Vec3::new(-1e38, 0.5, 0.5),
            Vec3::splat(f32::MAX),
            Vec3::new(f32::INFINITY, 0.5, 0.5),
            Vec3::new(0.5, f32::NEG_INFINITY, 0.5),
            Vec3::new(0.5, 0.5, f32::NAN),
            Vec3::NAN,
        ] {
            assert!(visited(&grid, q).is_empty(), "{q}");
        }
    }

    #[test]
    fn hash_grid_huge_spread() {
        // Float precision of cell coordinates is exhausted far from the origin: queries must
        // stay exact (possibly through the scan-everything fallback).
        let mut points = uniform_points(2_000, 3, Vec3::ZERO, Vec3::ONE);
        points.extend(uniform_points(2_000, 4, Vec3::splat(1e7), Vec3::splat(1e7 + 8.0)));
        points.push(Vec3::splat(3e9));
        // Around 4, `x - origin` is rounded to multiples of 8 (= 80 cells), and a query at 4
        // straddles a rounding boundary: its cell range is huge.
        points.push(Vec3::splat(-1e8));
        points.extend(uniform_points(500, 5, Vec3::splat(3.9), Vec3::splat(4.1)));
        let radius = 0.05;
        let mut grid = HashGrid::new();
        grid.build(&points, radius);
        let mut qs = queries(&grid, &points, radius, 9);
        qs.extend([Vec3::splat(4.0), Vec3::new(4.0, 3.95, 4.02)]);
        check_against_brute_force(&grid, &points, radius, &qs);
    }

    #[test]
    fn lean_build_has_the_same_slots_and_answers() {
        // The lean build (no position copies, one key per point) must give the slots of the full
        // build, so the memory-efficient mode reads its records in the same order, and its
        // queries (positions handed back by the caller, with and without index ranges) must
        // visit the same slots in the same order. NaN points are skipped by both.
        let mut spread = uniform_points(1_500, 3, Vec3::ZERO, Vec3::ONE);
        spread.extend(uniform_points(1_500, 4, Vec3::splat(1e7), Vec3::splat(1e7 + 8.0)));
        let mut with_nan = clustered_points(2_000, 23);
        with_nan[17] = Vec3::new(f32::NAN, 0.0, 0.0);
        with_nan[1_999] = Vec3::splat(f32::INFINITY);
        let cases = [
            (clustered_points(5_000, 21), 0.01, usize::MAX),
            (spread, 0.05, usize::MAX),
            (clustered_points(3_000, 22), 0.02, 16),
            (with_nan, 0.02, usize::MAX),
        ];
        for (points, radius, buckets) in cases {
            let mut full = HashGrid::with_bucket_limit(buckets);
            full.build(&points, radius);
            let mut lean = HashGrid::with_bucket_limit(buckets);
            lean.build_lean(points.len(), |i| points[i], radius);
            assert_eq!(lean.sorted_indices(), full.sorted_indices());
            assert_eq!(lean.starts, full.starts);
            assert!(full.keeps_positions() && !lean.keeps_positions());
            let position = |slot: usize| points[lean.sorted_indices()[slot] as usize];
            let n = points.len() as u32;
            let mut found = 0;
            for q in queries(&full, &points, radius, 37) {
                for range in [None, Some(0..n / 3), Some(n / 3..n)] {
                    let (mut expected, mut got) = (Vec::new(), Vec::new());
                    match &range {
                        None => full.for_each_slot_within(q, radius, |s| expected.push(s)),
                        Some(r) => full.for_each_slot_within_indices(q, radius, r.clone(), |s| expected.push(s)),
                    }
                    lean.for_each_slot_near((q, &lean.plan(q)), radius, range.clone(), position, |s| got.push(s));
                    assert_eq!(got, expected, "query {q}, indices {range:?}");
                    found += got.len();
                }
            }
            assert!(found > 100, "too few points found ({found})");
        }
    }

    #[test]
    fn index_range_queries_match_brute_force() {
        // Points of several groups laid out group after group; a query per group sees exactly
        // the points of its group within the radius (also through the scan-everything fallback
        // of a huge spread, and with buckets shared by many cells).
        let mut spread = uniform_points(1_500, 3, Vec3::ZERO, Vec3::ONE);
        spread.extend(uniform_points(1_500, 4, Vec3::splat(1e7), Vec3::splat(1e7 + 8.0)));
        spread.extend(uniform_points(500, 5, Vec3::splat(3.9), Vec3::splat(4.1)));
        let cases = [
            (clustered_points(5_000, 21), 0.01, usize::MAX),
            (spread, 0.05, usize::MAX),
            (clustered_points(3_000, 22), 0.02, 16),
        ];
        for (points, radius, buckets) in cases {
            let mut grid = HashGrid::with_bucket_limit(buckets);
            grid.build(&points, radius);
            let n = points.len() as u32;
            let bounds = [0, n / 7, n / 2, n / 2, n - 3, n];
            let mut found = 0;
            for q in queries(&grid, &points, radius, 31) {
                for range in bounds.windows(2).map(|b| b[0]..b[1]) {
                    let mut got = Vec::new();
                    grid.for_each_slot_within_indices(q, radius, range.clone(), |slot| {
                        got.push(grid.sorted_indices()[slot] as usize);
                    });
                    got.sort_unstable();
                    let expected: Vec<usize> =
                        brute_force(&points, q, radius).into_iter().filter(|&i| range.contains(&(i as u32))).collect();
                    assert_eq!(got, expected, "query {q}, indices {range:?}");
                    found += got.len();
                }
            }
            assert!(found > 100, "too few points found ({found})");
        }
    }

    #[test]
    fn hash_grid_reuse_and_determinism_across_threads() {
        let points = clustered_points(2 * CHUNK + 777, 12);
        let radius = 0.003;
        let build_with = |threads: usize, grid: &mut HashGrid| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("thread pool");
            pool.install(|| grid.build(&points, radius));
        };
        let mut one = HashGrid::new();
        build_with(1, &mut one);
        let mut two = HashGrid::new();
        // A previous, different build must leave no trace.
        build_with(2, &mut two);
        two.build(&uniform_points(1_000, 1, Vec3::ZERO, Vec3::ONE), 0.5);
        build_with(2, &mut two);
        let mut three = HashGrid::new();
        build_with(3, &mut three);
        for other in [&two, &three] {
            assert_eq!(one.starts, other.starts);
            assert_eq!(one.indices, other.indices);
            assert_eq!(one.sorted_positions, other.sorted_positions);
        }
        let q = points[100];
        assert_eq!(visited(&one, q), visited(&two, q));
        assert!(one.memory_bytes() >= points.len() * 20);
    }
}
