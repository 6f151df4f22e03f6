//! Where the sub-paths of one iteration get their wavelengths (spectral mode; RGB mode draws
//! nothing that reaches the image).
//!
//! Sub-paths that meet must carry the same wavelengths:
//!
//! - **without merging** (`lt`, `bpt`) light sub-path `i` and camera path `i`, the only pair
//!   that is connected, share the set of index `i`;
//! - **with merging** (`ppm`, `bpm`, `vcm`) the sub-paths are split into `K` *wavelength
//!   groups* ([`GroupLayout`]): pixel `i` and light sub-path `i` belong to group `g(i)`, every
//!   group has its own set, and a camera vertex merges only with the light vertices of its
//!   group (or with all of them, each at its own group's wavelengths, see below). The `4K` wavelengths of an iteration are equally spaced in primary sample space
//!   (one random offset), so the colour of the image mean is stratified over `4K` wavelengths
//!   instead of seeing 4 per iteration. `K = 1` is one set for the whole iteration.
//!
//! **The sets.** Without fluorescence the set of group `k` in iteration `n` has the primary
//! samples `(k + ξ_n)/(4K) + (h_k + j)/4`, `j = 0…3`, the hero's quarter `h_k ∈ {0…3}` drawn
//! per group and iteration (so the hero, which alone survives a dispersive event, is not always
//! the shortest wavelength of its set), and the offset `ξ_n` of `group_offset`: uniform in
//! every iteration, a golden-ratio sequence over blocks of K iterations. With fluorescence
//! (paired sets, see [`spectrum::Wavelengths4`]) the two pairs start at
//! `u_k = (k + ξ_n)/(2K) + h_k/2` and `v_k = (π(k) + ξ')/(2K) + h'_k/2`, `π` a random
//! permutation and `ξ'` uniform per iteration: both pairs are stratified and, for a pixel whose
//! group is uniformly random, `u` and `v` are independent and uniform.
//!
//! **The assignment.** Index `i = y·W + x` (a pixel, or the light sub-path of the same index)
//! has the class `(x + a·y + o) mod K`, a sheared lattice (`a ≈ √K`, so each class is spread
//! evenly over the image, about `√K` pixels apart), and in iteration `n` the group
//! `(σ(class) + n) mod K`; `o` and the permutation `σ` are drawn once per render. Every pixel's
//! group is then uniformly distributed in every iteration, so its wavelengths have the density
//! of the single-set sampler: each technique stays unbiased. K consecutive iterations give a
//! pixel each group once, and with the offsets' sequence a pixel's wavelengths are stratified
//! over the iterations (docs/spectral.md: relMSE 1.18× → 1.14× RGB's on scene 1). The MIS
//! counts (`super::mis::MisConstants`): light tracing still has N_L samples per pixel (every
//! light sub-path splats with its own wavelengths), merging N_L/K.
//!
//! **Merging across groups.** Where no material is dispersive or fluorescent, a camera
//! sub-path's throughput is a product of BSDF values upsampled linearly from RGB
//! (`S::from_reflectance`) and of wavelength-independent factors (cosines, pdfs, the filter
//! weight), so it can be known at every group's set (K spectra from the recorded scattering
//! steps, [`super::subpath::Scattered`], computed for a group when a merge finds its light
//! vertices: [`super::merge::GroupThroughputs`]). A camera vertex then merges with the light
//! vertices of *every* group, each evaluated at its own group's wavelengths, and merging has
//! N_L samples again, as in RGB mode (`super::merge::MergeScope::AcrossGroups`). Each merged
//! pair is a path sampled with the photon's wavelength set, whose density is the single-set
//! density, so the estimate stays unbiased; connections and light tracing are unchanged. A
//! dispersive vertex keeps only the hero wavelength of its own set and a fluorescent one moves
//! wavelengths between slots: neither can be re-evaluated, so such scenes merge within groups.

use math::Rng;
use scene::Scene;
use spectrum::SpectralMode;
use std::borrow::Cow;

use crate::wavelength_sequence::{ONE_MINUS, WAVELENGTH_STREAM, kronecker, per_index_sample};

/// Stream index of the per-iteration numbers of the merging algorithms (the shared set, or the
/// groups' offsets and permutations).
const SHARED_WAVELENGTHS: u64 = (1 << 61) - 1;

/// Wavelength groups per iteration of the merging algorithms in spectral mode (chosen by
/// measurement, `docs/spectral.md`).
pub const DEFAULT_WAVELENGTH_GROUPS: u32 = 4;

/// The most wavelength groups a camera sub-path carries its throughput for when it merges across
/// groups ([`super::merge::MergeScope::AcrossGroups`]); with more groups it merges within its own.
pub const MAX_CROSS_GROUPS: usize = 16;

/// Which group each light sub-path and pixel of an iteration belongs to, and how many there
/// are in each group.
#[derive(Clone, Debug)]
pub struct GroupLayout {
    width: usize,
    shear: usize,
    offset: usize,
    /// Group of each lattice class (`σ`).
    class_group: Vec<u32>,
    /// Number of indices `0..count` in each group.
    sizes: Vec<u32>,
    /// `x mod K` for every column x (so that [`GroupLayout::group_of`] divides once).
    column_class: Vec<u32>,
    /// `(a·y + o) mod K` for every row y of the indices `0..count`.
    row_class: Vec<u32>,
}

impl GroupLayout {
    /// The layout of `groups` groups over indices `0..count` of an image `width` pixels wide for
    /// iteration `iteration`: the lattice offset and the permutation are drawn once per render
    /// from `render_rng`, and each iteration moves every class on to the next group
    /// (`(σ(class) + iteration) mod K`), so that K consecutive iterations give each pixel each
    /// group once.
    fn new(groups: usize, width: usize, count: usize, iteration: u64, render_rng: &mut Rng) -> Self {
        let groups = groups.max(1);
        let shear = ((groups as f64).sqrt().round() as usize).max(1);
        let offset = (render_rng.next_u32() as usize) % groups;
        let shift = (iteration % groups as u64) as u32;
        let class_group = permutation(groups, render_rng).into_iter().map(|g| (g + shift) % groups as u32).collect();
        let width = width.max(1);
        let column_class = (0..width).map(|x| (x % groups) as u32).collect();
        let row_class = (0..count.div_ceil(width)).map(|y| (((shear * y) % groups + offset) % groups) as u32).collect();
        let sizes = vec![0; groups];
        let mut layout = Self { width, shear, offset, class_group, sizes, column_class, row_class };
        let mut sizes = std::mem::take(&mut layout.sizes);
        layout.for_each_group(count, |_, g| sizes[g] += 1);
        layout.sizes = sizes;
        layout
    }

    /// Calls `visit(index, group)` for the indices `0..count` in increasing order: the groups of
    /// [`GroupLayout::group_of`], found row by row without a division per index.
    fn for_each_group(&self, count: usize, mut visit: impl FnMut(usize, usize)) {
        let k = self.count();
        let (mut start, mut y) = (0, 0);
        while start < count {
            let end = (start + self.width).min(count);
            // The class of the row's first pixel (x = 0); each step right adds one, modulo K.
            let mut class = ((self.shear * y) % k + self.offset) % k;
            for index in start..end {
                visit(index, self.class_group[class] as usize);
                class += 1;
                if class == k {
                    class = 0;
                }
            }
            (start, y) = (end, y + 1);
        }
    }

    /// Number of groups.
    pub fn count(&self) -> usize {
        self.class_group.len()
    }

    /// The group of pixel (and light sub-path) `index`.
    #[inline]
    pub fn group_of(&self, index: usize) -> usize {
        let (x, y) = (index % self.width, index / self.width);
        let class = match self.row_class.get(y) {
            // The sum of two classes is below 2K: one subtraction reduces it.
            Some(&row) => {
                let class = (self.column_class[x] + row) as usize;
                if class >= self.count() { class - self.count() } else { class }
            }
            None => (x + (self.shear * y) % self.count() + self.offset) % self.count(),
        };
        self.class_group[class] as usize
    }

    /// Number of light sub-paths (and pixels) in each group.
    pub fn sizes(&self) -> &[u32] {
        &self.sizes
    }

    /// The light vertices of sub-paths whose vertices end at `path_ends` (cumulative) reordered
    /// group after group (stable within a group): their indices, and the `K + 1` offsets of
    /// the groups in that order.
    pub fn order_by_group(&self, path_ends: &[u32]) -> (Vec<u32>, Vec<u32>) {
        let mut starts = vec![0u32; self.count() + 1];
        let mut begin = 0;
        self.for_each_group(path_ends.len(), |path, g| {
            let end = path_ends[path];
            starts[g + 1] += end - begin;
            begin = end;
        });
        for g in 0..self.count() {
            starts[g + 1] += starts[g];
        }
        let mut cursor = starts.clone();
        let mut order = vec![0u32; begin as usize];
        let mut begin = 0;
        self.for_each_group(path_ends.len(), |path, g| {
            let end = path_ends[path];
            for vertex in begin..end {
                order[cursor[g] as usize] = vertex;
                cursor[g] += 1;
            }
            begin = end;
        });
        (order, starts)
    }
}

/// The offset ξ of the group sets of `iteration` (in units of one group's stratum): a
/// Kronecker sequence over blocks of `groups` iterations, `ξ = frac(ξ₀ + ⌊iteration / K⌋ · φ)`
/// with φ = (√5 − 1)/2 and ξ₀ uniform per render ([`kronecker`]). Within a block each pixel visits every group
/// once ([`GroupLayout::new`]), so its K offsets `(g + ξ)/K` form a shifted lattice, and the
/// blocks' shifts are spread by the golden-ratio sequence: a pixel's wavelengths over the
/// iterations are stratified instead of independent. For every single iteration ξ is uniform
/// (ξ₀ is), so each iteration's sets keep the single-set density.
fn group_offset(xi0: f32, iteration: u64, groups: usize) -> f32 {
    kronecker(xi0, iteration / groups.max(1) as u64)
}

/// A uniformly random permutation of `0..n` (Fisher–Yates).
fn permutation(n: usize, rng: &mut Rng) -> Vec<u32> {
    let mut p: Vec<u32> = (0..n as u32).collect();
    for i in (1..n).rev() {
        let j = (rng.next_u32() as usize) % (i + 1);
        p.swap(i, j);
    }
    p
}

/// How the sets of one iteration are chosen.
enum Sets<W> {
    /// One per light/camera sub-path pair (no merging).
    PerPair,
    /// One for the whole iteration (`K = 1`).
    Shared(W),
    /// One per wavelength group.
    Grouped(GroupLayout, Vec<W>),
}

/// Where the sub-paths of one iteration get their wavelengths. `paired` (the scene has
/// fluorescence, see [`spectrum::Wavelengths4::paired`]) is decided once per iteration.
pub(super) struct WavelengthSource<S: SpectralMode> {
    sets: Sets<S::Wavelengths>,
    paired: bool,
}

impl<S: SpectralMode> WavelengthSource<S> {
    /// The source of iteration `iteration` of `scene`: per pair without merging, else `groups`
    /// groups over `count` indices of an image `width` pixels wide (one shared set for 1).
    pub(super) fn new(
        scene: &Scene,
        seed: u64,
        iteration: u64,
        merge: bool,
        groups: u32,
        width: usize,
        count: usize,
    ) -> Self {
        let paired = scene.has_fluorescence();
        let mut source = Self { sets: Sets::PerPair, paired };
        if merge && groups <= 1 {
            source.sets = Sets::Shared(source.draw(seed, iteration, SHARED_WAVELENGTHS));
        } else if merge {
            let k = groups as usize;
            // The per-render numbers (lattice offset, class permutation, first offset ξ₀), then
            // the iteration's own (hero quarters, the fluorescent pairs' partners and offset).
            let mut render_rng = Rng::for_stream(seed, u64::MAX, WAVELENGTH_STREAM | SHARED_WAVELENGTHS);
            let layout = GroupLayout::new(k, width, count, iteration, &mut render_rng);
            let xi = group_offset(render_rng.uniform(), iteration, k);
            let mut rng = Rng::for_stream(seed, iteration, WAVELENGTH_STREAM | SHARED_WAVELENGTHS);
            let xi_v = rng.uniform();
            let partner = permutation(k, &mut rng);
            let sets = (0..k)
                .map(|g| {
                    let (h, h_v) = (rng.next_u32() % 4, rng.next_u32() % 4);
                    let (u, v) = if paired {
                        let start = |stratum: usize, xi: f32, half: u32| {
                            (stratum as f32 + xi) / (2 * k) as f32 + 0.5 * (half % 2) as f32
                        };
                        (start(g, xi, h), start(partner[g] as usize, xi_v, h_v))
                    } else {
                        ((g as f32 + xi) / (4 * k) as f32 + 0.25 * h as f32, 0.0)
                    };
                    S::sample_wavelengths(u.min(ONE_MINUS), v.min(ONE_MINUS), paired)
                })
                .collect();
            source.sets = Sets::Grouped(layout, sets);
        }
        source
    }

    /// Draws the set of stream `index` (two numbers of its own stream).
    #[inline]
    fn draw(&self, seed: u64, iteration: u64, index: u64) -> S::Wavelengths {
        let mut rng = Rng::for_stream(seed, iteration, WAVELENGTH_STREAM | index);
        let (u, v) = (rng.uniform(), rng.uniform());
        S::sample_wavelengths(u, v, self.paired)
    }

    /// The set of sub-path pair `index`: the first sample stratified over the iterations of
    /// the pair's index ([`per_index_sample`]), the second (a fluorescent scene's partner pair)
    /// drawn per iteration.
    #[inline]
    fn draw_pair(&self, seed: u64, iteration: u64, index: u64) -> S::Wavelengths {
        if std::mem::size_of::<S::Wavelengths>() == 0 {
            // RGB mode: no wavelengths, nothing to draw.
            return S::sample_wavelengths(0.0, 0.0, false);
        }
        let v = if self.paired { Rng::for_stream(seed, iteration, WAVELENGTH_STREAM | index).uniform() } else { 0.0 };
        S::sample_wavelengths(per_index_sample(seed, iteration, index), v, self.paired)
    }

    /// The wavelengths of sub-path pair `index` of `iteration`: its own set (drawn), its
    /// group's, or the iteration's shared set (borrowed: no copy of the set per sub-path).
    #[inline]
    pub(super) fn get(&self, seed: u64, iteration: u64, index: u64) -> Cow<'_, S::Wavelengths> {
        match &self.sets {
            Sets::PerPair => Cow::Owned(self.draw_pair(seed, iteration, index)),
            Sets::Shared(w) => Cow::Borrowed(w),
            Sets::Grouped(layout, sets) => Cow::Borrowed(&sets[layout.group_of(index as usize)]),
        }
    }

    /// The wavelength set of every group, when the iteration has more than one.
    pub(super) fn group_sets(&self) -> Option<&[S::Wavelengths]> {
        match &self.sets {
            Sets::Grouped(_, sets) => Some(sets),
            _ => None,
        }
    }

    /// The wavelength groups, when the iteration has more than one.
    pub(super) fn groups(&self) -> Option<&GroupLayout> {
        match &self.sets {
            Sets::Grouped(layout, _) => Some(layout),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn groups_partition_the_image_evenly() {
        let mut rng = Rng::for_stream(3, 0, 0);
        for (groups, width, height) in [(16, 64, 64), (16, 37, 23), (4, 8, 8), (64, 512, 512), (1, 5, 5)] {
            let layout = GroupLayout::new(groups, width, width * height, 0, &mut rng);
            let sizes = layout.sizes();
            let (min, max) = (sizes.iter().min().unwrap(), sizes.iter().max().unwrap());
            assert_eq!(sizes.iter().sum::<u32>() as usize, width * height);
            // Each image row holds every class at most ⌈W/K⌉ times: sizes differ by a few rows.
            assert!(max - min <= height as u32, "{groups} groups on {width}×{height}: {sizes:?}");
            if width % groups == 0 {
                assert_eq!(min, max, "{groups} groups on {width}×{height}: {sizes:?}");
            }
            // Every K×K block of pixels (K ≤ 16) holds every group K times.
            if groups <= 16 && width >= groups && height >= groups {
                let mut count = vec![0; groups];
                for y in 0..groups {
                    for x in 0..groups {
                        count[layout.group_of(y * width + x)] += 1;
                    }
                }
                assert!(count.iter().all(|&c| c == groups), "{groups} groups on {width}×{height}: {count:?}");
            }
        }
    }

    #[test]
    fn groups_row_by_row_are_those_of_group_of() {
        let mut rng = Rng::for_stream(5, 0, 0);
        for (groups, width, count) in [(4, 8, 64), (16, 37, 37 * 23 - 5), (3, 1, 10), (64, 100, 1000), (1, 5, 25)] {
            let layout = GroupLayout::new(groups, width, count, 7, &mut rng);
            let mut next = 0;
            layout.for_each_group(count, |index, g| {
                assert_eq!((index, g), (next, layout.group_of(index)), "{groups} groups, width {width}");
                next += 1;
            });
            assert_eq!(next, count);
            // The tables agree with the lattice formula, also past `count` (no table rows there).
            for index in 0..count + 2 * width {
                let (x, y) = (index % width, index / width);
                let class = (x + (layout.shear * y) % groups + layout.offset) % groups;
                assert_eq!(layout.group_of(index), layout.class_group[class] as usize);
            }
        }
    }

    #[test]
    fn vertices_are_ordered_group_after_group() {
        let mut rng = Rng::for_stream(4, 0, 0);
        let layout = GroupLayout::new(4, 5, 20, 2, &mut rng);
        // Path p has p % 3 vertices.
        let mut ends = Vec::new();
        let mut total = 0;
        for p in 0..20u32 {
            total += p % 3;
            ends.push(total);
        }
        let (order, starts) = layout.order_by_group(&ends);
        assert_eq!(order.len(), total as usize);
        let path_of = |v: u32| ends.iter().position(|&e| v < e).unwrap();
        for g in 0..4 {
            let members = &order[starts[g] as usize..starts[g + 1] as usize];
            assert!(members.windows(2).all(|w| w[0] < w[1]));
            assert!(members.iter().all(|&v| layout.group_of(path_of(v)) == g));
        }
        let mut sorted = order.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..total).collect::<Vec<_>>());
    }

    #[test]
    fn consecutive_iterations_give_each_pixel_every_group_once() {
        for (groups, width, height) in [(4, 8, 8), (16, 37, 23), (3, 5, 4)] {
            let count = width * height;
            // Iterations 8 … 8 + 2K − 1: two blocks of K, each a permutation of the groups.
            let layouts: Vec<GroupLayout> = (8..8 + 2 * groups as u64)
                .map(|i| GroupLayout::new(groups, width, count, i, &mut Rng::for_stream(9, u64::MAX, 0)))
                .collect();
            for index in 0..count {
                for block in layouts.chunks(groups) {
                    let mut seen: Vec<usize> = block.iter().map(|l| l.group_of(index)).collect();
                    seen.sort_unstable();
                    assert_eq!(seen, (0..groups).collect::<Vec<_>>(), "pixel {index}, {groups} groups");
                }
            }
        }
    }

    #[test]
    fn a_pixels_offsets_over_iterations_are_stratified() {
        // 16 iterations of K = 4: a pixel's offsets (g + ξ)/K fill each sixteenth of [0, 1) at
        // most twice (independent offsets would leave some empty and pile up elsewhere).
        let (k, width) = (4usize, 8usize);
        for seed in 0..20 {
            let xi0 = Rng::for_stream(seed, 1, 2).uniform();
            for index in [0, 5, 13, 63] {
                let mut hits = [0u32; 16];
                for i in 0..16u64 {
                    let layout = GroupLayout::new(k, width, 64, i, &mut Rng::for_stream(seed, u64::MAX, 0));
                    let t = (layout.group_of(index) as f32 + group_offset(xi0, i, k)) / k as f32;
                    hits[((t * 16.0) as usize).min(15)] += 1;
                }
                assert!(hits.iter().all(|&h| h <= 2), "seed {seed}, pixel {index}: {hits:?}");
            }
        }
    }
}
