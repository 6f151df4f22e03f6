//! A guide table (cut points) for inverting a cumulative sum: the same answer as
//! `cdf.partition_point(|c| *c <= target)`, found in a range narrowed by a table lookup.
//!
//! The targets are split into `m` cells by the monotonic map `cell(t) = min(⌊t·m/total⌋, m − 1)`
//! (computed in `f32`; negative and NaN products go to cell 0). Because `cell` never decreases
//! as `t` grows and the cumulative sums never decrease along the table, the entries whose cell
//! is below `cell(t)` are all `< t` and those whose cell is above it are all `> t`. So the answer
//! for `t` lies between `start[cell(t)]` (how many entries lie in earlier cells) and
//! `start[cell(t) + 1]`, and a binary search over that range (one bin on average with `m = n`)
//! returns exactly what a search over the whole table would. Nothing here depends on how the
//! product `t·m/total` rounds, only on the product being monotonic in `t`, which correctly
//! rounded multiplication by a fixed positive factor is.

/// Tables shorter than this are searched whole: a binary search over at most 15 entries (four
/// steps within one or two cache lines) costs less than the guide's lookup.
const MIN_GUIDED_LEN: usize = 16;

/// The cut points of a non-decreasing table of cumulative sums (the table is kept by the owner).
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Guide {
    /// `start[k]` = the number of table entries whose cell is below `k`; `m + 1` entries, the
    /// last one the table length. Empty when the table is shorter than [`MIN_GUIDED_LEN`] or too
    /// long for `u32` indices (then the whole table is searched).
    start: Vec<u32>,
    /// `m / total`: cells per unit of the cumulative sum (positive, possibly infinite).
    scale: f32,
}

impl Guide {
    /// Builds the guide of `cdf` (non-decreasing, non-negative, not NaN) whose last entry is
    /// `total > 0`: one cell per entry, none for short tables.
    pub(super) fn new(cdf: &[f32], total: f32) -> Self {
        if cdf.len() < MIN_GUIDED_LEN {
            return Self { start: Vec::new(), scale: 0.0 };
        }
        Self::with_cells(cdf, total)
    }

    /// [`Guide::new`] with cells whatever the length (unless it exceeds `u32`).
    fn with_cells(cdf: &[f32], total: f32) -> Self {
        let cells = cdf.len();
        if cells == 0 || u32::try_from(cells).is_err() {
            return Self { start: Vec::new(), scale: 0.0 };
        }
        let scale = cells as f32 / total;
        let mut start = vec![0u32; cells + 1];
        // Count the entries of each cell, then accumulate: start[k + 1] = start[k] + count[k].
        for c in cdf {
            start[cell_of(*c, scale, cells) + 1] += 1;
        }
        for k in 1..start.len() {
            start[k] += start[k - 1];
        }
        Self { start, scale }
    }

    /// `cdf.partition_point(|c| *c <= target)` for the table this guide was built from, for
    /// every `target` (including negative, infinite and NaN ones).
    #[inline]
    pub(super) fn partition_point(&self, cdf: &[f32], target: f32) -> usize {
        if self.start.is_empty() {
            return cdf.partition_point(|c| *c <= target);
        }
        let k = cell_of(target, self.scale, self.start.len() - 1);
        let (lo, hi) = (self.start[k] as usize, self.start[k + 1] as usize);
        lo + cdf[lo..hi].partition_point(|c| *c <= target)
    }
}

/// The cell of `t`: `min(⌊t·scale⌋, cells − 1)`, 0 for negative or NaN products. Monotonic
/// (never decreasing) in `t` for a fixed `scale ≥ 0`. `cells` is at most `u32::MAX`.
#[inline]
fn cell_of(t: f32, scale: f32, cells: usize) -> usize {
    // `as` saturates: negatives and NaN give 0, large values u32::MAX (a cheaper conversion
    // than to usize).
    ((t * scale) as u32).min((cells - 1) as u32) as usize
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Rng;

    /// The cumulative sums (in `f64`, rounded to `f32`, as `Distribution1D` builds them).
    fn cdf_of(weights: &[f32]) -> (Vec<f32>, f32) {
        let mut sum = 0.0f64;
        let cdf: Vec<f32> = weights
            .iter()
            .map(|w| {
                sum += *w as f64;
                sum as f32
            })
            .collect();
        (cdf, sum as f32)
    }

    /// Targets that probe every boundary: each entry, its neighbouring floats, the cell
    /// boundaries `k·total/m` and their neighbours, the ends and out-of-range values, and `u ·
    /// total` for a uniform grid and the largest `u` below 1.
    fn probe_targets(cdf: &[f32], total: f32) -> Vec<f32> {
        let below = |x: f32| if x > 0.0 { f32::from_bits(x.to_bits() - 1) } else { -f32::MIN_POSITIVE };
        let above = |x: f32| if x >= 0.0 { f32::from_bits(x.to_bits() + 1) } else { 0.0 };
        let mut targets = vec![0.0, -0.0, -1.0, f32::NAN, f32::INFINITY, f32::NEG_INFINITY, total, 2.0 * total];
        let m = cdf.len();
        for k in 0..=m {
            let t = (k as f64 * total as f64 / m as f64) as f32;
            targets.extend([below(t), t, above(t)]);
        }
        for c in cdf {
            targets.extend([below(*c), *c, above(*c)]);
        }
        for i in 0..=1000 {
            targets.push(i as f32 / 1000.0 * total);
        }
        targets.push(super::super::ONE_MINUS_EPSILON * total);
        targets
    }

    /// How many of `targets` the guide answers differently from a search of the whole table.
    fn mismatches(guide: &Guide, cdf: &[f32], targets: &[f32]) -> usize {
        targets.iter().filter(|t| guide.partition_point(cdf, **t) != cdf.partition_point(|c| *c <= **t)).count()
    }

    fn check(weights: &[f32]) {
        let (cdf, total) = cdf_of(weights);
        let targets = probe_targets(&cdf, total);
        for guide in [Guide::new(&cdf, total), Guide::with_cells(&cdf, total)] {
            assert_eq!(mismatches(&guide, &cdf, &targets), 0, "weights {weights:?}");
        }
    }

    #[test]
    fn agrees_with_a_full_search_on_edge_cases() {
        check(&[1.0]);
        check(&[0.0, 0.0, 5.0]);
        check(&[5.0, 0.0, 0.0]);
        check(&[1.0, 0.0, 0.0, 0.0, 1.0]);
        check(&[0.0, 1.0, 0.0, 1.0, 0.0]);
        check(&[1.0; 7]);
        // Huge and tiny dynamic range: one entry takes (almost) all the mass.
        check(&[1e-30, 1e30, 1e-30, 1e-30]);
        check(&[1e30, 1e-30, 1e-30]);
        // A total that overflows f32 (scale 0) and one so small that m/total overflows.
        check(&[f32::MAX, f32::MAX, 1.0]);
        check(&[f32::from_bits(1), 0.0, f32::from_bits(1)]);
        // Plateaus of the rounded f32 table: increments below the table's resolution.
        let mut plateau = vec![1e8f32];
        plateau.extend([1.0; 50]);
        plateau.push(1e8);
        check(&plateau);
    }

    #[test]
    fn agrees_with_a_full_search_on_random_tables() {
        let mut rng = Rng::new(7, 11);
        for n in [2, 3, 10, 64, 100, 1000, 4097] {
            for _ in 0..4 {
                // Mixtures of zero runs, small and large weights.
                let weights: Vec<f32> = (0..n)
                    .map(|_| match rng.next_u32() % 4 {
                        0 => 0.0,
                        1 => rng.uniform() * 1e-3,
                        2 => rng.uniform(),
                        _ => rng.uniform() * 1e3,
                    })
                    .collect();
                if weights.iter().any(|w| *w > 0.0) {
                    check(&weights);
                }
            }
        }
    }

    #[test]
    fn a_wrong_guide_is_detected() {
        // Power check of the comparison: a guide built for another table must disagree somewhere.
        let (cdf, total) = cdf_of(&[1.0, 2.0, 3.0, 4.0, 0.0, 5.0]);
        let (other, other_total) = cdf_of(&[5.0, 0.0, 4.0, 3.0, 2.0, 1.0]);
        let wrong = Guide::with_cells(&other, other_total);
        assert!(mismatches(&wrong, &cdf, &probe_targets(&cdf, total)) > 0);
    }

    #[test]
    fn falls_back_to_a_full_search_without_cells() {
        let (cdf, total) = cdf_of(&[1.0, 0.0, 2.0]);
        let empty = Guide { start: Vec::new(), scale: 0.0 };
        assert_eq!(mismatches(&empty, &cdf, &probe_targets(&cdf, total)), 0);
    }
}
