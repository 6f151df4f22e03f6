//! Walker's alias method: a discrete distribution sampled with one table read, whatever the
//! number of entries (Vose's construction, in `f64`).
//!
//! Each of the `n` slots holds a threshold `q` and an alias: a uniform number picks slot `k`
//! (probability `1/n`) and, below the threshold, `k` itself, otherwise its alias. The
//! construction pairs an under-full slot with an over-full entry until every slot is full, so
//! that entry `i` is returned with probability `(q_i + Σ_{k: alias_k = i} (1 − q_k)) / n =
//! w_i / Σ w`. Unlike inverting a cumulative sum, the map from `u` to the entry is not
//! monotonic (neighbouring `u` can give distant entries), so it suits importance sampling with
//! independent numbers, not stratified or inverted sampling.

/// One slot of the table, 8 bytes: a sample reads one slot.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Slot {
    /// Probability, within the slot, of returning the slot's own entry (in `[0, 1]`).
    threshold: f32,
    /// The entry returned otherwise.
    alias: u32,
}

/// A distribution over `0..n` proportional to non-negative weights, sampled in constant time.
#[derive(Clone, Debug, PartialEq)]
pub struct AliasTable {
    slots: Vec<Slot>,
}

impl AliasTable {
    /// Builds the table. `None` when there are no weights, more than `u32::MAX`, a weight is
    /// negative or not finite, or all are zero.
    pub fn new(weights: &[f32]) -> Option<Self> {
        let n = weights.len();
        if n == 0 || u32::try_from(n).is_err() || weights.iter().any(|w| !w.is_finite() || *w < 0.0) {
            return None;
        }
        let total: f64 = weights.iter().map(|w| *w as f64).sum();
        if total <= 0.0 {
            return None;
        }
        // Each entry's weight in units of one slot (mean 1).
        let mut scaled: Vec<f64> = weights.iter().map(|w| *w as f64 * n as f64 / total).collect();
        let mut slots: Vec<Slot> = (0..n as u32).map(|i| Slot { threshold: 1.0, alias: i }).collect();
        let (mut under, mut over): (Vec<usize>, Vec<usize>) = (0..n).partition(|i| scaled[*i] < 1.0);
        while let (Some(&small), Some(&large)) = (under.last(), over.last()) {
            under.pop();
            // Slot `small` keeps its own share and lends the rest to `large`.
            slots[small] = Slot { threshold: scaled[small] as f32, alias: large as u32 };
            scaled[large] -= 1.0 - scaled[small];
            if scaled[large] < 1.0 {
                over.pop();
                under.push(large);
            }
        }
        // What is left is full up to rounding: those slots keep threshold 1 (their own entry).
        Some(Self { slots })
    }

    /// Number of entries.
    pub fn len(&self) -> usize {
        self.slots.len()
    }

    /// Always false: an empty table cannot be built.
    pub fn is_empty(&self) -> bool {
        self.slots.is_empty()
    }

    /// Picks an entry for the uniform number `u ∈ [0, 1)` and returns it with a fresh uniform
    /// number in `[0, 1)` (the position of `u` within the part of the slot that chose the
    /// entry; it has about `24 − log2 n` bits).
    #[inline]
    pub fn sample_remapped(&self, u: f32) -> (usize, f32) {
        sample_slots(&self.slots, u)
    }
}

/// One alias table per row of a `rows × width` grid of weights, all slots in one array: a
/// sample reads its row's slot directly, without first reading the row's own table header (a
/// dependent load that missed the cache in the environment map's sampling, where the rows are
/// the map's rows of cells).
#[derive(Clone, Debug, PartialEq)]
pub struct AliasRows {
    width: usize,
    slots: Vec<Slot>,
}

impl AliasRows {
    /// Builds row `r`'s table from `weights[r·width..(r+1)·width]` exactly as
    /// [`AliasTable::new`] does; a row whose weights are all zero gets a uniform table (it is
    /// never picked when its row is sampled in proportion to its sum). `None` when `width` is
    /// 0 or does not divide the number of weights, there are no weights, or a weight is
    /// negative or not finite.
    pub fn new(weights: &[f32], width: usize) -> Option<Self> {
        if width == 0 || weights.is_empty() || !weights.len().is_multiple_of(width) {
            return None;
        }
        let mut slots = Vec::with_capacity(weights.len());
        for row in weights.chunks_exact(width) {
            let table = match AliasTable::new(row) {
                Some(table) => table,
                None if row.iter().all(|w| *w == 0.0) => AliasTable::new(&vec![1.0; width])?,
                None => return None,
            };
            slots.extend(table.slots);
        }
        Some(Self { width, slots })
    }

    /// Entries per row.
    pub fn width(&self) -> usize {
        self.width
    }

    /// [`AliasTable::sample_remapped`] in row `row`: the entry (a column) and the remapped number.
    #[inline]
    pub fn sample_remapped(&self, row: usize, u: f32) -> (usize, f32) {
        sample_slots(&self.slots[row * self.width..(row + 1) * self.width], u)
    }

    /// The slot that [`AliasRows::sample_remapped`] reads for `u` in row `row`, and its own
    /// entry (the answer unless the slot passes `u` on to its alias): for a caller that issues a
    /// prefetch hint ([`crate::prefetch()`]) for the slot and the entry's data before it samples.
    #[inline]
    pub fn slot_of(&self, row: usize, u: f32) -> (&impl Sized, usize) {
        let k = slot_index(self.width, u);
        (&self.slots[row * self.width + k], k)
    }
}

/// The slot of `n` that `u` falls in. `as u32` saturates (negatives and NaN give 0).
#[inline]
fn slot_index(n: usize, u: f32) -> usize {
    ((u * n as f32) as u32).min(n as u32 - 1) as usize
}

/// [`AliasTable::sample_remapped`] on a table's slots (not empty).
#[inline]
fn sample_slots(slots: &[Slot], u: f32) -> (usize, f32) {
    let n = slots.len();
    let x = u * n as f32;
    // `as u32` saturates (negatives and NaN give 0).
    let k = (x as u32).min(n as u32 - 1) as usize;
    let within = (x - k as f32).clamp(0.0, ONE_BELOW_ONE);
    let slot = slots[k];
    if within < slot.threshold {
        (k, (within / slot.threshold).min(ONE_BELOW_ONE))
    } else {
        let rest = 1.0 - slot.threshold;
        let v = if rest > 0.0 { (within - slot.threshold) / rest } else { 0.0 };
        (slot.alias as usize, v.clamp(0.0, ONE_BELOW_ONE))
    }
}

/// The largest `f32` below 1.
const ONE_BELOW_ONE: f32 = 1.0 - f32::EPSILON / 2.0;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Rng;

    /// Chi-square of `n` samples of `table` against the probabilities `expected`, over the
    /// entries with a positive expectation (an entry sampled with none fails at once).
    fn chi2(table: &AliasTable, expected: &[f64], n: usize) -> f64 {
        let mut rng = Rng::new(21, 8);
        let mut counts = vec![0u64; table.len()];
        let mut remapped_low = 0u64;
        for _ in 0..n {
            let (i, v) = table.sample_remapped(rng.uniform());
            assert!((0.0..1.0).contains(&v), "{v}");
            counts[i] += 1;
            remapped_low += (v < 0.5) as u64;
        }
        // The remapped number is uniform: half of it falls below one half (5 sigma).
        let half = n as f64 / 2.0;
        assert!((remapped_low as f64 - half).abs() < 5.0 * half.sqrt(), "{remapped_low} of {n} below 0.5");
        let mut chi2 = 0.0;
        for (count, p) in counts.iter().zip(expected) {
            let e = p * n as f64;
            assert!(e > 0.0 || *count == 0, "an entry of probability 0 was sampled");
            if e > 0.0 {
                chi2 += (*count as f64 - e).powi(2) / e;
            }
        }
        chi2
    }

    fn normalised(weights: &[f32]) -> Vec<f64> {
        let total: f64 = weights.iter().map(|w| *w as f64).sum();
        weights.iter().map(|w| *w as f64 / total).collect()
    }

    #[test]
    fn samples_in_proportion_to_the_weights() {
        let mut rng = Rng::new(3, 3);
        let random: Vec<f32> = (0..50).map(|i| if i % 7 == 0 { 0.0 } else { rng.uniform() * 5.0 }).collect();
        // Chi-square critical values at p = 1e-4: 3 entries (2 dof) 18.4; 50 entries (at most
        // 49 dof) 90.
        for (weights, critical) in [(vec![1.0f32, 0.0, 3.0], 18.4), (random, 90.0), (vec![2.0; 7], 35.0)] {
            let table = AliasTable::new(&weights).unwrap();
            let expected = normalised(&weights);
            let c = chi2(&table, &expected, 200_000);
            assert!(c < critical, "{weights:?}: chi-square {c}");
        }
    }

    #[test]
    fn a_wrong_table_fails_the_test() {
        // Power check: expecting a distribution 5 % off on two entries is detected.
        let weights = [1.0f32, 2.0, 3.0, 4.0];
        let table = AliasTable::new(&weights).unwrap();
        let mut expected = normalised(&weights);
        expected[0] *= 1.05;
        expected[3] -= expected[0] / 1.05 * 0.05;
        assert!(chi2(&table, &expected, 200_000) > 21.1, "chi-square did not see a 5 % error");
    }

    #[test]
    fn rejects_bad_weights() {
        assert!(AliasTable::new(&[]).is_none());
        assert!(AliasTable::new(&[0.0, 0.0]).is_none());
        assert!(AliasTable::new(&[1.0, -1.0]).is_none());
        assert!(AliasTable::new(&[1.0, f32::NAN]).is_none());
        assert!(AliasTable::new(&[f32::INFINITY]).is_none());
        let one = AliasTable::new(&[4.0]).unwrap();
        assert_eq!(one.sample_remapped(0.7).0, 0);
        assert_eq!(one.sample_remapped(f32::NAN).0, 0);
        assert_eq!(one.sample_remapped(1.0).0, 0);
    }

    #[test]
    fn rows_sample_as_their_own_tables() {
        // Each row of `AliasRows` answers bit for bit as an `AliasTable` of that row's weights;
        // an all-zero row as a uniform table.
        let mut rng = Rng::new(5, 2);
        let width = 13;
        let weights: Vec<f32> =
            (0..width * 6).map(|i| if i / width == 2 || i % 5 == 0 { 0.0 } else { rng.uniform() * 3.0 }).collect();
        let rows = AliasRows::new(&weights, width).unwrap();
        assert_eq!(rows.width(), width);
        for (r, row) in weights.chunks_exact(width).enumerate() {
            let table = AliasTable::new(row).unwrap_or_else(|| AliasTable::new(&[1.0; 13]).unwrap());
            for _ in 0..2000 {
                let u = rng.uniform();
                let (a, b) = (rows.sample_remapped(r, u), table.sample_remapped(u));
                assert_eq!((a.0, a.1.to_bits()), (b.0, b.1.to_bits()), "row {r}, u {u}");
                // The hinted slot is the one read: the answer is its own entry or its alias.
                let (k, slot) = (rows.slot_of(r, u).1, rows.slots[r * width + slot_index(width, u)]);
                assert!(k == slot_index(width, u) && (a.0 == k || a.0 == slot.alias as usize), "row {r}, u {u}");
            }
        }
        // Power check of the comparison: another row's table answers differently.
        let other = AliasTable::new(&weights[..width]).unwrap();
        assert!(
            (0..100).any(|i| other.sample_remapped(i as f32 / 100.0).0 != rows.sample_remapped(1, i as f32 / 100.0).0)
        );
        assert!(AliasRows::new(&weights, 0).is_none());
        assert!(AliasRows::new(&weights[..width + 1], width).is_none());
        assert!(AliasRows::new(&[1.0, f32::NAN], 2).is_none());
    }
}
