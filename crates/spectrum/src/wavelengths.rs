//! Sampling wavelengths over the visible range.
//!
//! The density is pbrt-v4's choice `p(λ) ∝ sech²(a (λ − 538 nm))`, `a = 0.0072 nm⁻¹`, which
//! roughly follows the sum of the colour matching functions, truncated to exactly
//! [[`LAMBDA_MIN`], [`LAMBDA_MAX`]] (the range of the CIE tables in [`crate::cie`]).
//!
//! Derivation. `∫ sech²(a x) dx = tanh(a x) / a`, so with `T₀ = tanh(a (360 − 538))` and
//! `T₁ = tanh(a (830 − 538))`:
//!
//! - normalisation: `p(λ) = a / (T₁ − T₀) · sech²(a (λ − 538))`, `a / (T₁ − T₀) = 0.0039398042`
//!   per nm;
//! - CDF: `P(λ) = (tanh(a (λ − 538)) − T₀) / (T₁ − T₀)`;
//! - inverse: `λ = 538 + atanh(T₀ + u (T₁ − T₀)) / a`.

/// Shortest wavelength sampled (nm).
pub const LAMBDA_MIN: f32 = 360.0;
/// Longest wavelength sampled (nm).
pub const LAMBDA_MAX: f32 = 830.0;

/// Steepness `a` of the density (per nm).
const A: f32 = 0.0072;
/// Centre of the density (nm).
const CENTRE: f32 = 538.0;
/// `T₀ = tanh(a (LAMBDA_MIN − 538))`.
const T0: f32 = -0.856_910_625_469_828_f64 as f32;
/// `T₁ = tanh(a (LAMBDA_MAX − 538))`.
const T1: f32 = 0.970_591_346_940_269_8_f64 as f32;
/// Normalisation `a / (T₁ − T₀)` (per nm).
const NORM: f32 = 0.003_939_804_229_324_407_f64 as f32;

/// Samples a wavelength (nm) in [[`LAMBDA_MIN`], [`LAMBDA_MAX`]] with density
/// [`visible_pdf`] (per nm) from a uniform number `u ∈ [0, 1)`, by the analytic inverse CDF
/// (see the module documentation). Monotonic in `u`; `u` outside `[0, 1]` (or NaN) is clamped
/// into it.
#[inline]
pub fn sample_visible(u: f32) -> f32 {
    let u = if u.is_nan() { 0.0 } else { u.clamp(0.0, 1.0) };
    let lambda = CENTRE + (T0 + u * (T1 - T0)).atanh() * (1.0 / A);
    lambda.clamp(LAMBDA_MIN, LAMBDA_MAX)
}

/// [`sample_visible`] with its density (per nm), in one step and without hyperbolic functions:
/// with `t = T₀ + u (T₁ − T₀)`, `λ = 538 + atanh(t)/a` and `p(λ) = a/(T₁ − T₀) · sech²(atanh t)
/// = a/(T₁ − T₀) · (1 − t²)`, and `atanh t = ½ ln((1 + t)/(1 − t))`. About a third of the
/// instructions of the two separate calls (measured: they dominated the per-path cost of
/// spectral light tracing).
#[inline]
pub fn sample_visible_with_pdf(u: f32) -> (f32, f32) {
    let u = if u.is_nan() { 0.0 } else { u.clamp(0.0, 1.0) };
    let t = T0 + u * (T1 - T0);
    let lambda = CENTRE + 0.5 * ((1.0 + t) / (1.0 - t)).ln() * (1.0 / A);
    (lambda.clamp(LAMBDA_MIN, LAMBDA_MAX), NORM * (1.0 - t * t))
}

/// Density (per nm) with which [`sample_visible`] picks `lambda_nm` (nm):
/// `0.0039398042 / cosh²(0.0072 (λ − 538))` on [[`LAMBDA_MIN`], [`LAMBDA_MAX`]] (integrates to
/// exactly 1 there), zero outside and for NaN.
#[inline]
pub fn visible_pdf(lambda_nm: f32) -> f32 {
    if !(LAMBDA_MIN..=LAMBDA_MAX).contains(&lambda_nm) {
        return 0.0;
    }
    let c = (A * (lambda_nm - CENTRE)).cosh();
    NORM / (c * c)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fused_sampler_agrees_with_the_separate_functions() {
        for i in 0..=1000 {
            let u = i as f32 / 1000.0;
            let (lambda, pdf) = sample_visible_with_pdf(u);
            assert!((lambda - sample_visible(u)).abs() < 2e-3, "u = {u}: {lambda} vs {}", sample_visible(u));
            let reference = visible_pdf(lambda);
            assert!((pdf - reference).abs() < 2e-5 * reference.max(1e-3), "u = {u}: {pdf} vs {reference}");
        }
    }
    use testkit::{assert_chi2, chi2_square};

    #[test]
    fn constants_follow_from_their_definition() {
        let (a, c) = (f64::from(A), f64::from(CENTRE));
        let t0 = (a * (f64::from(LAMBDA_MIN) - c)).tanh();
        let t1 = (a * (f64::from(LAMBDA_MAX) - c)).tanh();
        assert!((f64::from(T0) - t0).abs() < 1e-7);
        assert!((f64::from(T1) - t1).abs() < 1e-7);
        assert!((f64::from(NORM) / (a / (t1 - t0)) - 1.0).abs() < 1e-7);
    }

    #[test]
    fn pdf_integrates_to_one_and_vanishes_outside() {
        // Midpoint rule, 470 000 intervals of 0.001 nm: error ~h²/24·|p''|·470 ≪ 1e-9.
        let n = 470_000;
        let h = 470.0 / n as f64;
        let total: f64 = (0..n).map(|i| f64::from(visible_pdf((360.0 + (i as f64 + 0.5) * h) as f32)) * h).sum();
        assert!((total - 1.0).abs() < 1e-5, "{total}");
        for l in [359.9, 830.1, f32::NAN, -5.0] {
            assert_eq!(visible_pdf(l), 0.0);
        }
    }

    #[test]
    fn inverse_cdf_is_monotonic_and_inverts_the_cdf() {
        assert!((sample_visible(0.0) - LAMBDA_MIN).abs() < 1e-3);
        assert!((sample_visible(1.0) - LAMBDA_MAX).abs() < 1e-2);
        assert_eq!(sample_visible(f32::NAN), sample_visible(0.0));
        let mut previous = 0.0;
        for i in 0..=10_000 {
            let u = i as f32 / 10_000.0;
            let l = sample_visible(u);
            assert!(l >= previous, "not monotonic at u = {u}");
            previous = l;
            // The CDF in double precision, evaluated independently.
            let cdf = ((f64::from(A) * (f64::from(l) - 538.0)).tanh() - f64::from(T0)) / f64::from(T1 - T0);
            assert!((cdf - f64::from(u)).abs() < 2e-6, "u {u}: CDF(λ) = {cdf}");
        }
    }

    #[test]
    fn sampler_matches_pdf_chi2() {
        // x = (λ − 360) / 470 on the unit square, y uniform and unused; 30 × 30 cells, a
        // million samples (≈ 1100 per cell).
        let outcome = chi2_square(
            |rng| {
                let [u, v] = rng.uniform2();
                Some([f64::from((sample_visible(u) - LAMBDA_MIN) / 470.0), f64::from(v)])
            },
            |p| f64::from(visible_pdf(LAMBDA_MIN + 470.0 * p[0] as f32)) * 470.0,
            1_000_000,
            0x5eed_1a3b,
            30,
        );
        assert_chi2(&outcome, 1e-3, "sample_visible");
        assert!((outcome.pdf_integral - 1.0).abs() < 1e-4, "{}", outcome.pdf_integral);
    }
}
