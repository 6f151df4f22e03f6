//! A randomised (0,2)-sequence: points in `[0,1)²` whose every power-of-two prefix is
//! stratified.
//!
//! The sequence is the first two dimensions of Sobol's sequence (base 2): `x` is the van der
//! Corput radical inverse of the index, `y` its companion whose generator matrix is Pascal's
//! triangle mod 2 (the direction numbers `v₁ = 2⁻¹`, `v_{k+1} = v_k ⊕ (v_k ≫ 1)`; Kollig and
//! Keller 2002, "Efficient Multidimensional Sampling"). Every block of `2^m` consecutive indices
//! that starts at a multiple of `2^m` is a (0, m, 2)-net: each of the `2^m` elementary
//! rectangles `2^−a × 2^−b` (`a + b = m`) of any shape holds exactly one point.
//!
//! Randomisation, keyed by a 64-bit `key` (the index shuffle of Burley 2020, "Practical
//! Hash-based Owen Scrambling", with a stronger hash):
//! * the index is shuffled by a nested uniform scramble of its bits (bit `j` flipped by a hash of
//!   the bits above it), which maps every aligned block of `2^m` indices onto an aligned block,
//!   so every prefix of `2^m` indices still gives a (0, m, 2)-net, while two keys visit the
//!   points in unrelated orders (two dimension pairs keyed apart are not correlated point by
//!   point);
//! * each coordinate is Owen-scrambled (bit `j` of the fraction flipped by a hash of the bits
//!   before it), which keeps the nets and makes every single point uniform over the keys (on
//!   the grid of `2⁻²⁴` that `f32` numbers in `[0, 1)` get here). A random digital shift (an
//!   XOR with one random number) would also keep both, and costs less, but it leaves the bits
//!   below the stratum the same for every point of a prefix: the renderer's samplers reuse
//!   those bits (an alias table's slot fraction, a lobe choice's remapped number), so their
//!   decisions came out the same for all of a pixel's samples, and matpreview `pt` at 64 spp
//!   had 1.65× Mitsuba's variance against 0.74× with the Owen scramble
//!   (docs/performance.md, "Stratified first vertices").
//!
//! So any one point, over random keys, is an exact uniform sample (an estimator that uses it
//! stays unbiased), and `N` consecutive points from index 0 are spread like a stratified
//! sample.

/// A bijection of 32-bit numbers in which output bit `k` is input bit `k` flipped by a function
/// of the bits below it and of `key` ("scrambles upwards"): products with even constants, the
/// key added and a product with an odd number made from the key. The key enters by a product as
/// well as a sum, so that two keys give unrelated permutations (with the key only added, as in
/// Laine and Karras's original, two keys' permutations are one index offset apart, and dimension
/// pairs keyed apart came out correlated: matpreview `pt` at 64 spp had 1.65× Mitsuba's
/// variance instead of less). The constants are those of Vegdahl's improved hash (2021).
#[inline]
fn permute_upwards(mut x: u32, key: u32) -> u32 {
    x ^= x.wrapping_mul(0x3d20_adea);
    x = x.wrapping_add(key);
    x = x.wrapping_mul((key >> 16) | 1);
    x ^= x.wrapping_mul(0x0552_6c56);
    x ^= x.wrapping_mul(0x53a2_2864);
    x
}

/// The second Sobol dimension of `index`, as a 32-bit fraction.
const fn sobol_y(mut index: u32) -> u32 {
    let (mut v, mut y) = (1u32 << 31, 0u32);
    while index != 0 {
        if index & 1 != 0 {
            y ^= v;
        }
        index >>= 1;
        v ^= v >> 1;
    }
    y
}

/// `Y_REVERSED[k][b]`: the bit-reversed second Sobol dimension of the index whose bit-reversed
/// form is the byte `b` in byte `k`. The map is linear over GF(2), so for any index it is the XOR
/// of its four bytes' entries ([`y_reversed`]).
static Y_REVERSED: [[u32; 256]; 4] = {
    let mut table = [[0u32; 256]; 4];
    let mut k = 0;
    while k < 4 {
        let mut b = 0;
        while b < 256 {
            table[k][b] = sobol_y(((b as u32) << (8 * k)).reverse_bits()).reverse_bits();
            b += 1;
        }
        k += 1;
    }
    table
};

/// `sobol_y(reversed.reverse_bits()).reverse_bits()`, from four table reads.
#[inline]
fn y_reversed(reversed: u32) -> u32 {
    let [b0, b1, b2, b3] = reversed.to_le_bytes();
    Y_REVERSED[0][b0 as usize] ^ Y_REVERSED[1][b1 as usize] ^ Y_REVERSED[2][b2 as usize] ^ Y_REVERSED[3][b3 as usize]
}

/// A 64-bit finaliser (splitmix64's), to derive independent 32-bit scramble keys from `key`.
#[inline]
fn hash64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// `x / 2³²` rounded down to a multiple of `2⁻²⁴`: in `[0, 1)`, exactly representable.
#[inline]
fn to_unit(x: u32) -> f32 {
    (x >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// One index of the sequence, with what every key's point at that index shares.
#[derive(Clone, Copy, Debug)]
pub struct SequenceIndex {
    reversed: u32,
}

impl SequenceIndex {
    /// Index `index` (sample number, from 0).
    #[inline]
    pub fn new(index: u32) -> Self {
        Self { reversed: index.reverse_bits() }
    }

    /// This index's point of the sequence randomised by `key` (module doc), in `[0, 1)²`.
    ///
    /// Bit reversals are what this costs (the baseline x86-64 target has no instruction for
    /// them), so the point is computed with three. The shuffled index is
    /// `s = reverse(P(reverse(i)))` (`P`: the module's `permute_upwards`); its van der Corput point is
    /// `reverse(s) = t = P(reverse(i))`, and the Owen scramble of a fraction `x` is
    /// `reverse(P(reverse(x)))`, so `x = reverse(P(reverse(t))) = reverse(P(s))`, and
    /// `y = reverse(P(reverse(sobol_y(s))))`, whose inner reversal comes from the table.
    #[inline]
    pub fn point(self, key: u64) -> [f32; 2] {
        let h = hash64(key);
        let t = permute_upwards(self.reversed, h as u32);
        let (key_x, key_y) = ((h >> 32) as u32, (h.wrapping_mul(0x9e37_79b9_7f4a_7c15) >> 32) as u32);
        let x = permute_upwards(t.reverse_bits(), key_x).reverse_bits();
        let y = permute_upwards(y_reversed(t), key_y).reverse_bits();
        [to_unit(x), to_unit(y)]
    }
}

/// Point `index` of the (0,2)-sequence randomised by `key` (module doc), in `[0, 1)²`.
#[inline]
pub fn point(index: u32, key: u64) -> [f32; 2] {
    SequenceIndex::new(index).point(key)
}

/// A key for one `(seed, stream, dimension pair)`: hashes the three together so that nearby
/// values give unrelated keys.
#[inline]
pub fn key(seed: u64, stream: u64, pair: u32) -> u64 {
    hash64(hash64(hash64(seed) ^ stream) ^ u64::from(pair))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every elementary rectangle `2^−a × 2^−b` with `a + b = m` holds exactly one of `points`
    /// (`2^m` of them).
    fn is_02_net(points: &[[f32; 2]], m: u32) -> bool {
        (0..=m).all(|a| {
            let (nx, ny) = (1usize << a, 1usize << (m - a));
            let mut cells = vec![0u32; nx * ny];
            for p in points {
                let (i, j) = ((p[0] * nx as f32) as usize, (p[1] * ny as f32) as usize);
                cells[j * nx + i] += 1;
            }
            cells.iter().all(|&c| c == 1)
        })
    }

    #[test]
    fn every_power_of_two_prefix_is_a_net() {
        for k in [0u64, 1, 77, key(3, 12345, 5)] {
            for m in 0..=10 {
                let points: Vec<_> = (0..1u32 << m).map(|i| point(i, k)).collect();
                assert!(is_02_net(&points, m), "key {k}, 2^{m} points");
            }
            // An aligned block further on is a net as well.
            let block: Vec<_> = (768..1024).map(|i| point(i, k)).collect();
            assert!(is_02_net(&block, 8), "key {k}, block 768..1024");
        }
    }

    #[test]
    fn the_table_is_the_second_dimension() {
        let mut rng = crate::Rng::new(4, 0);
        for _ in 0..10_000 {
            let t = rng.next_u32();
            assert_eq!(y_reversed(t), sobol_y(t.reverse_bits()).reverse_bits(), "t = {t:#x}");
        }
    }

    #[test]
    fn the_bits_below_the_stratum_differ_between_points() {
        // Within a prefix of 64 points, where each point sits inside its 1/64 stratum is random
        // (Owen scrambling): spread like a uniform number (standard deviation 0.289), not one
        // offset shared by all, which is what a digital shift gives (deviation 0) and what broke
        // the samplers that reuse those bits (module doc).
        for k in [3u64, key(1, 2, 3)] {
            for axis in 0..2 {
                let within: Vec<f64> = (0..64).map(|i| (point(i, k)[axis] as f64 * 64.0).fract()).collect();
                let mean = within.iter().sum::<f64>() / 64.0;
                let deviation = (within.iter().map(|w| (w - mean).powi(2)).sum::<f64>() / 63.0).sqrt();
                assert!(deviation > 0.2, "key {k}, axis {axis}: deviation {deviation}");
            }
        }
    }

    #[test]
    fn the_unscrambled_net_check_rejects_a_random_set() {
        // Power of the check above: 16 independent uniform points are almost never a (0,4,2)-net.
        let mut rng = crate::Rng::new(9, 0);
        let points: Vec<_> = (0..16).map(|_| rng.uniform2()).collect();
        assert!(!is_02_net(&points, 4));
    }

    /// Chi-square statistic of `points` over an `n × n` grid against the uniform density.
    fn chi_square(points: &[[f32; 2]], n: usize) -> f64 {
        let mut cells = vec![0u32; n * n];
        for p in points {
            cells[(p[1] * n as f32) as usize * n + (p[0] * n as f32) as usize] += 1;
        }
        let expected = points.len() as f64 / (n * n) as f64;
        cells.iter().map(|&c| (c as f64 - expected).powi(2) / expected).sum()
    }

    #[test]
    fn one_point_over_random_keys_is_uniform() {
        // 40,000 keys, 8 × 8 cells: 63 degrees of freedom, whose chi-square exceeds 110 with
        // probability below 1e-4. The same test rejects points squeezed by 3 % towards the centre.
        for index in [0u32, 1, 5, 1000] {
            let points: Vec<_> = (0..40_000u64).map(|s| point(index, key(s, 7, 2))).collect();
            let chi = chi_square(&points, 8);
            assert!(chi < 110.0, "index {index}: chi-square {chi}");
            let squeezed: Vec<_> = points.iter().map(|p| p.map(|v| 0.5 + 0.97 * (v - 0.5))).collect();
            assert!(chi_square(&squeezed, 8) > 110.0, "the test must see a 3 % squeeze");
        }
    }

    #[test]
    fn two_keys_order_the_points_differently() {
        // Dimension pairs keyed apart must not see the same point at the same index: over 256
        // indices their first coordinates are uncorrelated (|r| < 0.25, about 4 standard errors).
        let (a, b) = (key(1, 2, 0), key(1, 2, 1));
        let xs: Vec<(f64, f64)> =
            (0..256).map(|i| (point(i, a)[0] as f64 - 0.5, point(i, b)[0] as f64 - 0.5)).collect();
        let r = xs.iter().map(|(x, y)| x * y).sum::<f64>()
            / (xs.iter().map(|(x, _)| x * x).sum::<f64>() * xs.iter().map(|(_, y)| y * y).sum::<f64>()).sqrt();
        assert!(r.abs() < 0.25, "correlation {r}");
    }
}
