//! Wavelength samples stratified over the iterations of a render (spectral mode).
//!
//! Every algorithm renders a pixel once per iteration: one camera path (`pt`), one light and
//! camera sub-path pair (`lt`, `bpt`), or one pair in a wavelength group (`ppm`, `bpm`, `vcm`,
//! `super::vcm::wavelengths`). If each iteration drew the pixel's primary wavelength sample
//! independently, the colour noise of the wavelength choice would fall only as 1/N with the
//! iterations. Instead the sample of iteration n is the golden-ratio (Kronecker) sequence
//! `u_n = frac(c + n·φ)`, φ = (√5 − 1)/2, rotated by a start `c` that is uniform and drawn once
//! per render and index (a Cranley–Patterson rotation). Every `u_n` is uniform (because `c`
//! is), so each iteration keeps the single-sample density and stays unbiased; over N iterations
//! the samples are spread with gaps of at most about 1/N instead of independent, so the part of
//! the variance that the wavelength alone explains falls much faster. Iterations are no longer
//! independent in this one dimension: a variance image computed from the iterations' spread
//! over-estimates the variance of the mean (a safe bound). Measured in docs/spectral.md.

use math::Rng;

/// Offset of the random streams that draw wavelengths (spectral mode only, so RGB renders draw
/// exactly the numbers they drew before spectral mode existed).
pub(crate) const WAVELENGTH_STREAM: u64 = 1 << 61;

/// φ = (√5 − 1)/2, the step of the sequence (the irrational whose multiples are spread most
/// evenly over [0, 1)).
const PHI: f64 = 0.618_033_988_749_894_8;

/// The largest `f32` below 1 (a primary sample must stay in [0, 1)).
pub(crate) const ONE_MINUS: f32 = 1.0 - f32::EPSILON / 2.0;

/// `frac(start + step·φ)`, in [0, 1): element `step` of the golden-ratio sequence rotated by
/// `start` ∈ [0, 1).
pub fn kronecker(start: f32, step: u64) -> f32 {
    // f64: step·φ keeps ~10⁻⁷ absolute precision in its fraction up to step ~10⁸.
    ((f64::from(start) + step as f64 * PHI).fract() as f32).min(ONE_MINUS)
}

/// The primary wavelength sample of pixel (or sub-path pair) `index` in iteration `iteration`
/// of the render with seed `seed`: uniform in [0, 1) for every iteration, and stratified over
/// the iterations of one index (module doc).
pub fn per_index_sample(seed: u64, iteration: u64, index: u64) -> f32 {
    let start = Rng::for_stream(seed, u64::MAX, WAVELENGTH_STREAM | index).uniform();
    kronecker(start, iteration)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_are_stratified_over_iterations_and_uniform_over_renders() {
        // Any N consecutive iterations of one index put at most 3 samples in each 1/N of [0, 1)
        // (the three-gap theorem bounds the gaps of N multiples of φ by about 2.6/N).
        for index in [0u64, 7, 1 << 20] {
            for n in [8usize, 16, 64] {
                let mut hits = vec![0u32; n];
                for i in 0..n as u64 {
                    hits[(per_index_sample(3, 100 + i, index) * n as f32) as usize] += 1;
                }
                assert!(hits.iter().all(|&h| h <= 3), "index {index}, {n} iterations: {hits:?}");
            }
        }
        // Over renders (seeds), one iteration's sample is uniform: chi² over 16 bins, 16 000
        // seeds (15 degrees of freedom; 37.7 is the 0.1 % quantile).
        let mut hits = [0f64; 16];
        for seed in 0..16_000 {
            hits[(per_index_sample(seed, 5, 42) * 16.0) as usize] += 1.0;
        }
        let chi2: f64 = hits.iter().map(|h| (h - 1000.0).powi(2) / 1000.0).sum();
        assert!(chi2 < 37.7, "chi² {chi2}: {hits:?}");
    }
}
