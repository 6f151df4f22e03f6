//! The random number generator: PCG32 (O'Neill 2014, XSH-RR output), seeded per stream.
//!
//! Every sub-path draws from its own stream created by [`Rng::for_stream`] from
//! `(seed, iteration, index)`, so an image does not depend on how work is spread over threads.

/// PCG32 generator state. 8 bytes of state plus an odd increment that selects the stream.
#[derive(Clone, Debug)]
pub struct Rng {
    state: u64,
    increment: u64,
}

const MULTIPLIER: u64 = 6_364_136_223_846_793_005;

/// SplitMix64 finaliser: a bijective mix of 64 bits.
#[inline]
fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

impl Rng {
    /// A generator with the given initial state and stream selector.
    pub fn new(state: u64, stream: u64) -> Self {
        let mut rng = Rng { state: 0, increment: (stream << 1) | 1 };
        rng.next_u32();
        rng.state = rng.state.wrapping_add(state);
        rng.next_u32();
        rng
    }

    /// The generator for sub-path `index` of `iteration` of a render seeded with `seed`.
    /// Different triples give statistically independent streams.
    pub fn for_stream(seed: u64, iteration: u64, index: u64) -> Self {
        let a = mix64(seed ^ mix64(iteration.wrapping_add(0x9e37_79b9_7f4a_7c15)));
        let b = mix64(a ^ mix64(index.wrapping_add(0x632b_e59b_d9b4_e019)));
        Rng::new(b, mix64(b ^ 0xd1b5_4a32_d192_ed03))
    }

    /// The next 32 uniformly distributed bits.
    #[inline]
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(MULTIPLIER).wrapping_add(self.increment);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// A uniform float in `[0, 1)` with 24 bits of resolution.
    #[inline]
    pub fn uniform(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0)
    }

    /// Two uniform floats in `[0, 1)`.
    #[inline]
    pub fn uniform2(&mut self) -> [f32; 2] {
        [self.uniform(), self.uniform()]
    }

    /// Three uniform floats in `[0, 1)`.
    #[inline]
    pub fn uniform3(&mut self) -> [f32; 3] {
        [self.uniform(), self.uniform(), self.uniform()]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streams_are_reproducible_and_distinct() {
        let a: Vec<u32> = (0..4).map(|_| 0).scan(Rng::for_stream(1, 2, 3), |r, _| Some(r.next_u32())).collect();
        let b: Vec<u32> = (0..4).map(|_| 0).scan(Rng::for_stream(1, 2, 3), |r, _| Some(r.next_u32())).collect();
        let c: Vec<u32> = (0..4).map(|_| 0).scan(Rng::for_stream(1, 2, 4), |r, _| Some(r.next_u32())).collect();
        assert_eq!(a, b);
        assert_ne!(a, c);
    }

    #[test]
    fn uniform_mean_and_range() {
        let mut r = Rng::for_stream(7, 0, 0);
        let n = 200_000;
        let mut sum = 0.0f64;
        for _ in 0..n {
            let u = r.uniform();
            assert!((0.0..1.0).contains(&u));
            sum += u as f64;
        }
        let mean = sum / n as f64;
        // Standard error of the mean of U[0,1) is sqrt(1/12/n); allow 5 sigma.
        assert!((mean - 0.5).abs() < 5.0 * (1.0 / 12.0 / n as f64).sqrt(), "{mean}");
    }
}
