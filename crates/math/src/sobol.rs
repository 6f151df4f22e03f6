//! The first [`DIMENSIONS`] dimensions of Sobol's sequence, Owen-scrambled per dimension.
//!
//! Dimension 0 is the van der Corput radical inverse; dimension `j ≥ 1` uses the primitive
//! polynomial and initial direction numbers `m₁ … m_s` of Joe and Kuo's table (2008, "new"
//! numbers, dimensions 2–8 in their counting), extended by Bratley and Fox's recurrence.
//! All dimensions share one index, unshuffled: the points are one digital (t, s)-sequence, so a
//! pixel's dimensions fill their joint space together as the index grows. (The first version of
//! `--sampler sobol` drew each dimension pair from its own hash-shuffle of a two-dimensional
//! sequence; its renders of Mitsuba's Cornell box at 512² stopped converging, for a reason not
//! identified: docs/performance.md, "Stratified first vertices".)
//!
//! Each coordinate is Owen-scrambled by a hash keyed per dimension (bit `j` of the fraction
//! flipped by a hash of the bits before it): every point is then uniform over the keys (an
//! estimator using it stays unbiased), every prefix keeps the sequence's stratification, and
//! the bits below a point's stratum differ between points (a digital shift would leave them
//! equal, which samplers that reuse those bits, e.g. an alias table's slot fraction, turn into
//! equal decisions for all of a pixel's samples).

use crate::isa::Kernel;

/// Dimensions available.
pub const DIMENSIONS: usize = 8;

/// Per dimension `j ≥ 1`: degree `s`, the polynomial's inner coefficients `a` (bit `s − 1 − i`
/// is `a_i`), and the initial direction numbers `m₁ … m_s` (odd, `m_k < 2^k`).
const POLYNOMIALS: [(u32, u32, [u32; 5]); DIMENSIONS - 1] = [
    (1, 0, [1, 0, 0, 0, 0]),
    (2, 1, [1, 3, 0, 0, 0]),
    (3, 1, [1, 3, 1, 0, 0]),
    (3, 2, [1, 1, 1, 0, 0]),
    (4, 1, [1, 1, 3, 3, 0]),
    (4, 4, [1, 3, 5, 13, 0]),
    (5, 2, [1, 1, 5, 5, 17]),
];

/// `MATRICES[j][k]`: the column of dimension `j`'s generator matrix for index bit `k`, as a
/// 32-bit fraction.
static MATRICES: [[u32; 32]; DIMENSIONS] = {
    let mut v = [[0u32; 32]; DIMENSIONS];
    let mut k = 0;
    while k < 32 {
        v[0][k] = 1 << (31 - k);
        k += 1;
    }
    let mut j = 1;
    while j < DIMENSIONS {
        let (s, a, m) = POLYNOMIALS[j - 1];
        let s = s as usize;
        let mut k = 0;
        while k < 32 {
            v[j][k] = if k < s {
                m[k] << (31 - k)
            } else {
                let mut x = v[j][k - s] ^ (v[j][k - s] >> s);
                let mut i = 1;
                while i < s {
                    if (a >> (s - 1 - i)) & 1 == 1 {
                        x ^= v[j][k - i];
                    }
                    i += 1;
                }
                x
            };
            k += 1;
        }
        j += 1;
    }
    v
};

/// `REVERSED[j][k]`: `MATRICES[j][k]` with its bits reversed (bit `i` the fraction's `2^-(i+1)`
/// digit), so that the scramble, which works from the low bits up, needs one reversal per sample.
static REVERSED: [[u32; 32]; DIMENSIONS] = {
    let mut r = [[0u32; 32]; DIMENSIONS];
    let mut j = 0;
    while j < DIMENSIONS {
        let mut k = 0;
        while k < 32 {
            r[j][k] = MATRICES[j][k].reverse_bits();
            k += 1;
        }
        j += 1;
    }
    r
};

/// Dimension `dimension` of point `index`, unscrambled, as a 32-bit fraction.
#[cfg(test)]
fn raw(index: u32, dimension: usize) -> u32 {
    raw_reversed(index, dimension).reverse_bits()
}

/// [`raw`] with its bits reversed: the XOR of the columns of the index's set bits (one step per
/// set bit).
#[inline]
fn raw_reversed(index: u32, dimension: usize) -> u32 {
    let columns = &REVERSED[dimension];
    let (mut i, mut x) = (index, 0u32);
    while i != 0 {
        x ^= columns[i.trailing_zeros() as usize];
        i &= i - 1;
    }
    x
}

/// A bijection of 32-bit numbers in which output bit `k` is input bit `k` flipped by a function
/// of the bits below it and of `key`: products with even constants, the key added and a product
/// with an odd number made from the key (the constants of Vegdahl's hash, 2021).
#[inline(always)]
fn permute_upwards(mut x: u32, key: u32) -> u32 {
    x ^= x.wrapping_mul(0x3d20_adea);
    x = x.wrapping_add(key);
    x = x.wrapping_mul((key >> 16) | 1);
    x ^= x.wrapping_mul(0x0552_6c56);
    x ^= x.wrapping_mul(0x53a2_2864);
    x
}

/// A 64-bit finaliser (splitmix64's).
#[inline(always)]
fn hash64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// Dimension `dimension` (< [`DIMENSIONS`]) of point `index`, Owen-scrambled by `key`, in
/// `[0, 1)` (a multiple of `2⁻²⁴`).
#[inline]
pub fn sample(index: u32, dimension: usize, key: u64) -> f32 {
    scrambled(raw_reversed(index, dimension), dimension_key(key, dimension))
}

/// The scramble key of dimension `dimension` for the point key `key`.
#[inline(always)]
fn dimension_key(key: u64, dimension: usize) -> u32 {
    hash64(key ^ (dimension as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15)) as u32
}

/// A coordinate in `[0, 1)` from its unscrambled bits (reversed, [`raw_reversed`]) and its
/// dimension's key: Owen-scrambled, reversed back, rounded down to a multiple of `2⁻²⁴`.
#[inline(always)]
fn scrambled(reversed: u32, key: u32) -> f32 {
    (permute_upwards(reversed, key).reverse_bits() >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// The columns of [`REVERSED`] by bit: `BY_BIT[k][j] = REVERSED[j][k]`, so that one step of
/// [`point`] updates all dimensions with one row.
static BY_BIT: [[u32; DIMENSIONS]; 32] = {
    let mut t = [[0u32; DIMENSIONS]; 32];
    let mut k = 0;
    while k < 32 {
        let mut j = 0;
        while j < DIMENSIONS {
            t[k][j] = REVERSED[j][k];
            j += 1;
        }
        k += 1;
    }
    t
};

/// All [`DIMENSIONS`] dimensions of point `index`, each Owen-scrambled by `key`: the same values
/// as [`sample`] for `dimension` 0, 1, … (bit for bit), computed together. The unscrambled point
/// is one row XOR per set bit of the index for all dimensions, and the scrambles are written as
/// lane-wise array operations, which the compiler vectorises (callgrind on Mitsuba's Cornell box
/// `pt`: about 515 instructions per sample through [`sample`], docs/performance.md).
///
/// Runs through [`crate::isa::dispatch`]: with AVX2 the eight dimensions are one vector, with
/// AVX-512 the 64-bit hashes of the dimension keys are vector multiplications as well (about 50
/// instructions for the whole point; docs/bvh.md, "Instruction sets chosen at run time",
/// measures it).
#[inline]
pub fn point(index: u32, key: u64) -> [f32; DIMENSIONS] {
    crate::isa::dispatch(Point { index, key })
}

/// [`point`] as a kernel of [`crate::isa::dispatch`].
struct Point {
    index: u32,
    key: u64,
}

impl Kernel for Point {
    type Output = [f32; DIMENSIONS];
    #[inline(always)]
    fn run(self) -> [f32; DIMENSIONS] {
        point_in_place(self.index, self.key)
    }
}

/// The body of [`point`], inlined into each instruction set's copy.
#[inline(always)]
fn point_in_place(index: u32, key: u64) -> [f32; DIMENSIONS] {
    let mut raw = [0u32; DIMENSIONS];
    let mut i = index;
    while i != 0 {
        let row = &BY_BIT[i.trailing_zeros() as usize];
        for (x, c) in raw.iter_mut().zip(row) {
            *x ^= c;
        }
        i &= i - 1;
    }
    let keys: [u32; DIMENSIONS] = std::array::from_fn(|j| dimension_key(key, j));
    let mut out = [0.0f32; DIMENSIONS];
    for ((o, &x), &k) in out.iter_mut().zip(&raw).zip(&keys) {
        *o = scrambled(x, k);
    }
    out
}

/// A key for one `(seed, stream)`: hashes the two together so that nearby values give
/// unrelated keys.
#[inline]
pub fn key(seed: u64, stream: u64) -> u64 {
    hash64(hash64(seed) ^ stream)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The `t` of the smallest (t, m, 2)-net that the points (dimensions `a`, `b`) form: every
    /// elementary rectangle of area `2^(t − m)` holds exactly `2^t` points.
    fn net_t(points: &[(u32, u32)], m: u32) -> u32 {
        (0..=m)
            .find(|&t| {
                (0..=m - t).all(|p| {
                    let q = m - t - p;
                    let mut cells = vec![0u32; 1 << (m - t)];
                    for &(x, y) in points {
                        let cx = if p == 0 { 0 } else { x >> (32 - p) };
                        let cy = if q == 0 { 0 } else { y >> (32 - q) };
                        cells[((cy << p) | cx) as usize] += 1;
                    }
                    cells.iter().all(|&c| c == 1 << t)
                })
            })
            .unwrap()
    }

    #[test]
    fn every_dimension_is_stratified_alone_and_pairs_are_nets() {
        for m in 1..=10u32 {
            let n = 1u32 << m;
            for j in 0..DIMENSIONS {
                // One dimension: one point in each interval of length 2^-m.
                let mut seen = vec![false; n as usize];
                for i in 0..n {
                    seen[(raw(i, j) >> (32 - m)) as usize] = true;
                }
                assert!(seen.iter().all(|s| *s), "dimension {j}, 2^{m} points");
            }
            // The pairs the path tracer uses: (0,1) is a (0,m,2)-net; the others have small t
            // (a wrong direction number or polynomial gives a large t or breaks the 1D check).
            for (a, b, bound) in [(0, 1, 0), (2, 3, 3), (4, 5, 3), (6, 7, 3)] {
                let points: Vec<(u32, u32)> = (0..n).map(|i| (raw(i, a), raw(i, b))).collect();
                let t = net_t(&points, m);
                assert!(t <= bound, "dimensions ({a}, {b}), 2^{m} points: t = {t}");
            }
        }
    }

    #[test]
    fn scrambling_keeps_the_strata_and_varies_the_bits_below() {
        for key in [3u64, key(1, 2)] {
            for j in 0..DIMENSIONS {
                let values: Vec<f32> = (0..64).map(|i| sample(i, j, key)).collect();
                let mut strata = [false; 64];
                for v in &values {
                    strata[(v * 64.0) as usize] = true;
                }
                assert!(strata.iter().all(|s| *s), "key {key}, dimension {j}");
                let within: Vec<f64> = values.iter().map(|v| (*v as f64 * 64.0).fract()).collect();
                let mean = within.iter().sum::<f64>() / 64.0;
                let deviation = (within.iter().map(|w| (w - mean).powi(2)).sum::<f64>() / 63.0).sqrt();
                assert!(deviation > 0.2, "key {key}, dimension {j}: deviation {deviation}");
            }
        }
    }

    #[test]
    fn a_point_is_its_samples() {
        for key in [0u64, 3, key(1, 2), u64::MAX] {
            for index in (0..70u32).chain([255, 256, 1 << 20, u32::MAX - 1, u32::MAX]) {
                let p = point(index, key);
                for (j, v) in p.iter().enumerate() {
                    assert_eq!(v.to_bits(), sample(index, j, key).to_bits(), "index {index}, dimension {j}");
                }
            }
        }
    }

    /// Each instruction set's copy of [`point`] (`crate::isa`) gives its samples bit for bit
    /// (on a processor without a set, the copy falls back to a narrower one).
    #[test]
    fn point_copies_agree() {
        use crate::isa::{Isa, dispatch_at};
        let mut rng = crate::Rng::for_stream(5, 0, 0);
        for i in 0..20_000u32 {
            let (index, key) = if i < 100 {
                (i, 3)
            } else {
                (rng.next_u32(), u64::from(rng.next_u32()) << 32 | u64::from(rng.next_u32()))
            };
            let expected: [u32; DIMENSIONS] = std::array::from_fn(|j| sample(index, j, key).to_bits());
            for isa in [Isa::Baseline, Isa::Avx2, Isa::Avx512] {
                assert_eq!(dispatch_at(isa, Point { index, key }).map(f32::to_bits), expected, "{isa:?} {index} {key}");
            }
        }
    }

    #[test]
    fn one_sample_over_random_keys_is_uniform() {
        // 40,000 keys, 64 cells: chi-square over 63 degrees of freedom exceeds 110 with
        // probability below 1e-4; the same test rejects values squeezed by 3 % to the centre.
        for (index, j) in [(0u32, 0usize), (1, 3), (5, 7), (1000, 5)] {
            let mut cells = [0u32; 64];
            let mut squeezed = [0u32; 64];
            for s in 0..40_000u64 {
                let v = sample(index, j, key(s, 9));
                cells[(v * 64.0) as usize] += 1;
                squeezed[((0.5 + 0.97 * (v - 0.5)) * 64.0) as usize] += 1;
            }
            let chi = |c: &[u32; 64]| c.iter().map(|&n| (n as f64 - 625.0).powi(2) / 625.0).sum::<f64>();
            assert!(chi(&cells) < 110.0, "index {index}, dimension {j}: {}", chi(&cells));
            assert!(chi(&squeezed) > 110.0, "the test must see a 3 % squeeze");
        }
    }
}
