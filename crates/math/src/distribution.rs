//! Discrete distributions sampled by inverting their cumulative sum (and, in `alias`, by the
//! alias method), and the piecewise-constant 2D density built from them (textured lights,
//! projectors, goniometric lights).

use glam::Vec2;

mod alias;
mod guide;
pub use alias::{AliasRows, AliasTable};
use guide::Guide;

/// The largest `f32` below 1: continuous samples stay in `[0, 1)`.
const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// A distribution over `0..n` proportional to non-negative weights.
#[derive(Clone, Debug, PartialEq)]
pub struct Distribution1D {
    cdf: Vec<f32>,
    total: f32,
    /// Narrows the inversion of `cdf` to a few entries (one on average).
    guide: Guide,
}

impl Distribution1D {
    /// Builds the distribution. Returns `None` when there are no weights, a weight is negative
    /// or not finite, or all are zero.
    pub fn new(weights: &[f32]) -> Option<Self> {
        if weights.iter().any(|w| !w.is_finite() || *w < 0.0) {
            return None;
        }
        Self::from_valid(weights)
    }

    /// [`Distribution1D::new`] for weights already known to be finite and non-negative.
    fn from_valid(weights: &[f32]) -> Option<Self> {
        // At most 2^32 − 1 entries: bins are found with `u32` conversions (`bin_of`).
        if weights.is_empty() || u32::try_from(weights.len()).is_err() {
            return None;
        }
        let mut cdf = Vec::with_capacity(weights.len());
        let mut sum = 0.0f64;
        for w in weights {
            sum += *w as f64;
            cdf.push(sum as f32);
        }
        if sum <= 0.0 {
            return None;
        }
        let total = sum as f32;
        let guide = Guide::new(&cdf, total);
        Some(Self { cdf, total, guide })
    }

    /// Number of entries.
    pub fn len(&self) -> usize {
        self.cdf.len()
    }

    /// Always false: an empty distribution cannot be built.
    pub fn is_empty(&self) -> bool {
        self.cdf.is_empty()
    }

    /// Picks an index for the uniform number `u ∈ [0,1)`; returns it with its probability.
    /// The index is the first whose cumulative weight exceeds `u · total` (the last one if
    /// none does).
    pub fn sample(&self, u: f32) -> (usize, f32) {
        // One entry (a scene with one light): the search below would find it, with probability
        // `cdf[0] / total` = 1 exactly (`total` is the last cumulative weight).
        if self.cdf.len() == 1 {
            return (0, 1.0);
        }
        let target = u * self.total;
        let index = self.guide.partition_point(&self.cdf, target).min(self.cdf.len() - 1);
        (index, self.probability(index))
    }

    /// Probability of index `i`.
    #[inline]
    pub fn probability(&self, i: usize) -> f32 {
        let lo = if i == 0 { 0.0 } else { self.cdf[i - 1] };
        (self.cdf[i] - lo) / self.total
    }

    /// Sum of the weights.
    pub fn total(&self) -> f32 {
        self.total
    }

    /// Samples the piecewise-constant density on `[0, 1)` whose `n` equal bins carry the
    /// weights: returns the point `x ∈ [0, 1)` and its density per unit length,
    /// `n · probability(bin)`. The point is `u` remapped within its bin, so the map is monotonic,
    /// and `x` always lies in the bin whose probability is reported.
    #[inline]
    pub fn sample_continuous(&self, u: f32) -> (f32, f32) {
        let (x, pdf, _) = self.sample_continuous_bin(u);
        (x, pdf)
    }

    /// [`Distribution1D::sample_continuous`] that also returns the bin.
    #[inline]
    fn sample_continuous_bin(&self, u: f32) -> (f32, f32, usize) {
        let (x, index) = self.continuous_point(u);
        (x, self.probability(index) * self.len() as f32, index)
    }

    /// The bin of [`Distribution1D::sample`] for `u` and where `u` falls within that bin's
    /// share of `[0, 1)`, as a fraction in `[0, 1]` (uniformly distributed when `u` is: a fresh
    /// uniform number for sampling within the bin).
    #[inline]
    pub fn sample_remapped(&self, u: f32) -> (usize, f32) {
        let target = u * self.total;
        let index = self.guide.partition_point(&self.cdf, target).min(self.cdf.len() - 1);
        let lo = if index == 0 { 0.0 } else { self.cdf[index - 1] };
        let width = self.cdf[index] - lo;
        let offset = if width > 0.0 { ((target - lo) / width).clamp(0.0, 1.0) } else { 0.5 };
        (index, offset)
    }

    /// The point of [`Distribution1D::sample_continuous`] and its bin, without the density.
    #[inline]
    fn continuous_point(&self, u: f32) -> (f32, usize) {
        let (index, offset) = self.sample_remapped(u);
        let n = self.len();
        // Through `i64`: the same exact values as from `usize` (both below 2^53), one
        // instruction each instead of an unsigned conversion's several.
        let mut x = (((index as i64 as f64 + offset as f64) / n as i64 as f64) as f32).min(ONE_MINUS_EPSILON);
        // Rounding must not move the point into the next bin (the pdf looks the bin up the same
        // way).
        while x > 0.0 && bin_of(x, n) > index {
            x = f32::from_bits(x.to_bits() - 1);
        }
        while bin_of(x, n) < index {
            x = f32::from_bits(x.to_bits() + 1);
        }
        (x, index)
    }

    /// Density per unit length of [`Distribution1D::sample_continuous`] on bin `i`:
    /// `n · probability(i)`.
    #[inline]
    fn bin_density(&self, i: usize) -> f32 {
        self.probability(i) * self.len() as f32
    }

    /// Density per unit length of [`Distribution1D::sample_continuous`] at `x ∈ [0, 1]`
    /// (0 outside).
    pub fn pdf_continuous(&self, x: f32) -> f32 {
        if !(0.0..=1.0).contains(&x) {
            return 0.0;
        }
        self.bin_density(bin_of(x, self.len()))
    }
}

/// The bin of `x ∈ [0, 1]` among `n` equal bins (`n ≤ 2^32`; negative and NaN products give
/// bin 0).
#[inline]
fn bin_of(x: f32, n: usize) -> usize {
    // `as u32` saturates like `as usize` and is cheaper; with `n ≤ 2^32` the minimum with
    // `n − 1` is the same either way.
    ((x * n as i64 as f32) as u32).min((n - 1) as u32) as usize
}

/// A piecewise-constant density on the unit square `[0, 1)²` over a grid of `width × height`
/// equal cells, proportional to non-negative cell weights: a marginal distribution over the rows
/// (`y`) and a conditional distribution over the columns (`x`) of each row.
#[derive(Clone, Debug, PartialEq)]
pub struct Distribution2D {
    marginal: Distribution1D,
    conditional: Vec<Distribution1D>,
}

impl Distribution2D {
    /// Builds the distribution from `width × height` weights in row-major order (row `y`, column
    /// `x` at `y·width + x`). Returns `None` when the size does not match, a weight is negative or
    /// not finite, or all are zero.
    pub fn new(weights: &[f32], width: usize, height: usize) -> Option<Self> {
        if width == 0 || height == 0 || weights.len() != width.checked_mul(height)? {
            return None;
        }
        let mut conditional = Vec::with_capacity(height);
        let mut row_sums = Vec::with_capacity(height);
        for row in weights.chunks_exact(width) {
            if row.iter().any(|w| !w.is_finite() || *w < 0.0) {
                return None;
            }
            let sum: f64 = row.iter().map(|w| *w as f64).sum();
            row_sums.push(sum as f32);
            // A row without weight is never chosen; give it a uniform conditional so that every
            // row has one.
            conditional.push(match Distribution1D::from_valid(row) {
                Some(d) => d,
                None => Distribution1D::new(&vec![1.0; width])?,
            });
        }
        let marginal = Distribution1D::new(&row_sums)?;
        Some(Self { marginal, conditional })
    }

    /// Number of columns.
    pub fn width(&self) -> usize {
        self.conditional[0].len()
    }

    /// Number of rows.
    pub fn height(&self) -> usize {
        self.marginal.len()
    }

    /// Sum of all weights.
    pub fn total(&self) -> f32 {
        self.marginal.total()
    }

    /// Samples a point of `[0, 1)²` with two uniform numbers (`u[1]` picks the row, `u[0]` the
    /// position within it); returns the point and its density per unit area of the square.
    #[inline]
    pub fn sample(&self, u: [f32; 2]) -> (Vec2, f32) {
        let (y, pdf_y, row) = self.marginal.sample_continuous_bin(u[1]);
        let (x, pdf_x) = self.conditional[row].sample_continuous(u[0]);
        (Vec2::new(x, y), pdf_x * pdf_y)
    }

    /// Density per unit area of [`Distribution2D::sample`] at `p ∈ [0, 1]²` (0 outside).
    pub fn pdf(&self, p: Vec2) -> f32 {
        if !(0.0..=1.0).contains(&p.x) || !(0.0..=1.0).contains(&p.y) {
            return 0.0;
        }
        self.cell_pdf(bin_of(p.x, self.width()), bin_of(p.y, self.height()))
    }

    /// Density per unit area of [`Distribution2D::sample`] on the cell in column `x` and row
    /// `y` (the value [`Distribution2D::pdf`] reports at every point of that cell); 0 outside
    /// the grid.
    #[inline]
    pub fn cell_pdf(&self, x: usize, y: usize) -> f32 {
        match self.conditional.get(y) {
            Some(row) if x < row.len() => self.marginal.bin_density(y) * row.bin_density(x),
            _ => 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_in_proportion() {
        let d = Distribution1D::new(&[1.0, 0.0, 3.0]).unwrap();
        assert_eq!(d.sample(0.0).0, 0);
        assert_eq!(d.sample(0.2).0, 0);
        assert_eq!(d.sample(0.3).0, 2);
        assert_eq!(d.sample(0.999).0, 2);
        assert!((d.probability(2) - 0.75).abs() < 1e-6);
        assert_eq!(d.probability(1), 0.0);
        assert!(Distribution1D::new(&[0.0]).is_none());
        assert!(Distribution1D::new(&[f32::NAN]).is_none());
    }

    #[test]
    fn guided_sampling_picks_the_bin_of_a_full_search() {
        let mut rng = crate::Rng::new(1, 2);
        let random: Vec<f32> = (0..777).map(|i| if i % 5 < 2 { 0.0 } else { rng.uniform() * 10.0 }).collect();
        // One entry with any weight: `sample`'s shortcut must give the searched bin's probability.
        let tables: [&[f32]; 9] = [
            &[1.0],
            &[0.3],
            &[7e-20],
            &[3.0e38],
            &[0.0, 0.0, 5.0],
            &[5.0, 0.0, 0.0],
            &[1.0, 0.0, 0.0, 0.0, 2.0],
            &[1e-30, 1e30, 1e-30],
            &random,
        ];
        for weights in tables {
            let d = Distribution1D::new(weights).unwrap();
            let mut us = vec![0.0, ONE_MINUS_EPSILON, 1.0, -0.0];
            us.extend((0..=10_000).map(|i| i as f32 / 10_000.0));
            us.extend(d.cdf.iter().flat_map(|c| {
                let u = c / d.total;
                [u, f32::from_bits(u.to_bits().saturating_sub(1)), f32::from_bits(u.to_bits() + 1)]
            }));
            for u in us {
                let target = u * d.total;
                let index = d.cdf.partition_point(|c| *c <= target).min(d.len() - 1);
                let (guided, probability) = d.sample(u);
                assert_eq!(guided, index, "u = {u}, weights {weights:?}");
                assert_eq!(probability.to_bits(), d.probability(index).to_bits());
            }
        }
    }

    #[test]
    fn continuous_samples_stay_in_their_bin_and_report_its_density() {
        let d = Distribution1D::new(&[1.0, 0.0, 3.0, 4.0]).unwrap();
        for i in 0..=1000 {
            let u = (i as f32 / 1000.0).min(ONE_MINUS_EPSILON);
            let (x, pdf) = d.sample_continuous(u);
            assert!((0.0..1.0).contains(&x), "{x}");
            assert_eq!(pdf, d.pdf_continuous(x), "u = {u}, x = {x}");
            assert!(pdf > 0.0, "zero-weight bins are never sampled");
        }
        // Piecewise linear: halfway through a bin's share of u lands halfway through the bin.
        assert!((d.sample_continuous(0.0625).0 - 0.125).abs() < 1e-6);
        assert!((d.sample_continuous(0.125 + 0.375 * 0.5).0 - 0.625).abs() < 1e-6);
        assert_eq!(d.pdf_continuous(0.3), 0.0);
        assert_eq!(d.pdf_continuous(-0.1), 0.0);
    }

    /// Weights with zero rows and zero cells, 5 columns × 4 rows.
    const WEIGHTS: [f32; 20] =
        [1.0, 2.0, 0.0, 4.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 3.0, 0.5, 0.5, 7.0, 2.0, 0.0, 0.0, 9.0, 0.0, 0.0];

    #[test]
    fn distribution_2d_sampling_matches_the_cell_weights() {
        let (w, h) = (5, 4);
        let d = Distribution2D::new(&WEIGHTS, w, h).unwrap();
        assert_eq!((d.width(), d.height()), (w, h));
        let total: f32 = WEIGHTS.iter().sum();
        assert!((d.total() - total).abs() < 1e-5);
        // Stratified samples: an n × n grid of u. The inverse-CDF map is monotonic in each
        // coordinate, so the fraction landing in each cell equals its probability to within
        // the grid resolution (2/n per dimension).
        let n = 400;
        let mut counts = [0usize; 20];
        for i in 0..n {
            for j in 0..n {
                let u = [(i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32];
                let (p, pdf) = d.sample(u);
                assert!((0.0..1.0).contains(&p.x) && (0.0..1.0).contains(&p.y), "{p}");
                let (cx, cy) = ((p.x * w as f32) as usize, (p.y * h as f32) as usize);
                counts[cy * w + cx] += 1;
                // The density per unit area is the cell's probability times the cell count.
                let expected = WEIGHTS[cy * w + cx] / total * (w * h) as f32;
                assert!((pdf - expected).abs() < 1e-5 * expected, "{pdf} vs {expected}");
                assert!((d.pdf(p) - pdf).abs() <= 1e-6 * pdf);
            }
        }
        for (cell, count) in counts.iter().enumerate() {
            let fraction = *count as f32 / (n * n) as f32;
            let probability = WEIGHTS[cell] / total;
            assert!((fraction - probability).abs() < 4.0 / n as f32, "cell {cell}: {fraction} vs {probability}");
            if WEIGHTS[cell] == 0.0 {
                assert_eq!(*count, 0, "cell {cell} has no weight");
            }
        }
        // The density integrates to one (it is constant on each cell).
        let integral: f32 = (0..20)
            .map(|c| d.pdf(Vec2::new(((c % w) as f32 + 0.5) / w as f32, ((c / w) as f32 + 0.5) / h as f32)))
            .sum::<f32>()
            / 20.0;
        assert!((integral - 1.0).abs() < 1e-5);
        assert_eq!(d.pdf(Vec2::new(1.5, 0.5)), 0.0);
    }

    #[test]
    fn bins_agree_with_the_usize_conversion() {
        for n in [1usize, 2, 3, 7, 255, 1000, 4097] {
            let mut xs = vec![0.0, -0.0, 1.0, ONE_MINUS_EPSILON, -1.0, 2.0, f32::NAN, f32::INFINITY];
            xs.extend((0..=n).flat_map(|i| {
                let x = i as f32 / n as f32;
                [x, f32::from_bits(x.to_bits().saturating_sub(1)), f32::from_bits(x.to_bits() + 1)]
            }));
            for x in xs {
                assert_eq!(bin_of(x, n), ((x * n as f32) as usize).min(n - 1), "x = {x}, n = {n}");
            }
        }
    }

    #[test]
    fn cell_pdf_is_the_density_at_every_point_of_its_cell() {
        let (w, h) = (5, 4);
        let d = Distribution2D::new(&WEIGHTS, w, h).unwrap();
        for y in 0..h {
            for x in 0..w {
                // The product of the two 1D densities, computed as `pdf` did before `cell_pdf`.
                let expected = (d.marginal.probability(y) * h as f32) * (d.conditional[y].probability(x) * w as f32);
                assert_eq!(d.cell_pdf(x, y).to_bits(), expected.to_bits(), "cell ({x}, {y})");
                for (fx, fy) in [(0.0, 0.0), (0.5, 0.5), (0.999, 0.001)] {
                    let p = Vec2::new((x as f32 + fx) / w as f32, (y as f32 + fy) / h as f32);
                    assert_eq!(d.pdf(p).to_bits(), expected.to_bits(), "{p}");
                }
            }
        }
        assert_eq!(d.cell_pdf(w, 0), 0.0);
        assert_eq!(d.cell_pdf(0, h), 0.0);
    }

    #[test]
    fn distribution_2d_rejects_bad_weights() {
        assert!(Distribution2D::new(&WEIGHTS, 4, 4).is_none(), "size mismatch");
        assert!(Distribution2D::new(&[0.0; 6], 3, 2).is_none(), "all zero");
        assert!(Distribution2D::new(&[1.0, -1.0], 2, 1).is_none(), "negative");
        assert!(Distribution2D::new(&[1.0, f32::INFINITY], 1, 2).is_none(), "infinite");
        assert!(Distribution2D::new(&[], 0, 0).is_none());
    }
}
