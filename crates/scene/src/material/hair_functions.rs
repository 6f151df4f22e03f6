//! The one-dimensional pieces of the hair model of Chiang et al. 2016 (as in pbrt-v4, §9.9 of
//! the 4th edition): the longitudinal scattering function `M_p`, the trimmed logistic azimuthal
//! distribution `N_p` with its sampler, and the roughness mappings from `β_m` and `β_n`.
//! Angles are in radians; `M_p` is a density in `sin θ_i` (that is, per `cos θ_i dθ_i`),
//! `N_p` a density in the azimuth `φ` (per radian).

use std::f64::consts::PI as PI64;

use math::PI;

/// Number of explicit lobes (R, TT, TRT); lobe `P_MAX` is the residual of all longer paths.
pub(super) const P_MAX: usize = 3;

/// The longitudinal variances `v_0..v_3` for the longitudinal roughness `β_m ∈ [0, 1]`:
/// `v_0 = (0.726 β_m + 0.812 β_m² + 3.7 β_m²⁰)²`, `v_1 = v_0/4`, `v_2 = v_3 = 4 v_0`.
pub(super) fn longitudinal_variances(beta_m: f32) -> [f32; P_MAX + 1] {
    let b = f64::from(beta_m);
    let v0 = (0.726 * b + 0.812 * b * b + 3.7 * b.powi(20)).powi(2);
    [v0, 0.25 * v0, 4.0 * v0, 4.0 * v0].map(|v| v.max(1e-7) as f32)
}

/// The logistic scale `s = √(π/8) (0.265 β_n + 1.194 β_n² + 5.372 β_n²²)` for the azimuthal
/// roughness `β_n ∈ [0, 1]`.
pub(super) fn azimuthal_scale(beta_n: f32) -> f32 {
    let b = f64::from(beta_n);
    ((PI64 / 8.0).sqrt() * (0.265 * b + 1.194 * b * b + 5.372 * b.powi(22))).max(1e-7) as f32
}

/// `ln I₀(x)` for `x ≥ 0`: the power series `Σ (x/2)^{2k}/(k!)²` up to `x = 30`, above it the
/// asymptotic expansion `eˣ/√(2πx) · (1 + 1/(8x) + 9/(128x²) + 225/(3072x³))` (relative error
/// below 2·10⁻⁷ there).
pub(super) fn log_bessel_i0(x: f64) -> f64 {
    if x > 30.0 {
        let r = 1.0 / x;
        let series = 1.0 + r / 8.0 + 9.0 * r * r / 128.0 + 225.0 * r * r * r / 3072.0;
        return x - 0.5 * (2.0 * PI64 * x).ln() + series.ln();
    }
    let q = 0.25 * x * x;
    let (mut term, mut sum) = (1.0f64, 1.0f64);
    for k in 1..200 {
        term *= q / (k * k) as f64;
        sum += term;
        if term < 1e-17 * sum {
            break;
        }
    }
    sum.ln()
}

/// The longitudinal scattering function of variance `v`:
/// `M(θ_i, θ_o) = e^{−sin θ_i sin θ_o / v} I₀(cos θ_i cos θ_o / v) / (2 v sinh(1/v))`,
/// a density in `sin θ_i` that integrates to 1 over `[−1, 1]` (computed in logarithms, in f64).
pub(super) fn longitudinal(cos_i: f32, cos_o: f32, sin_i: f32, sin_o: f32, v: f32) -> f32 {
    let v = f64::from(v);
    let a = f64::from(cos_i) * f64::from(cos_o) / v;
    let b = f64::from(sin_i) * f64::from(sin_o) / v;
    // ln(2 v sinh(1/v)) = ln v + 1/v + ln(1 − e^{−2/v}).
    let log_norm = v.ln() + 1.0 / v + (-(-2.0 / v).exp_m1()).ln();
    (log_bessel_i0(a.max(0.0)) - b - log_norm).exp() as f32
}

/// `Φ(p, γ_o, γ_t) = 2pγ_t − 2γ_o + pπ`: the azimuth change of lobe `p` without roughness.
pub(super) fn perfect_azimuth(p: usize, gamma_o: f32, gamma_t: f32) -> f32 {
    let p = p as f32;
    2.0 * p * gamma_t - 2.0 * gamma_o + p * PI
}

/// The logistic density `e^{−|x|/s} / (s (1 + e^{−|x|/s})²)`.
fn logistic(x: f32, s: f32) -> f32 {
    let e = (-x.abs() / s).exp();
    e / (s * (1.0 + e) * (1.0 + e))
}

/// The logistic cumulative distribution `1/(1 + e^{−x/s})`.
fn logistic_cdf(x: f32, s: f32) -> f32 {
    1.0 / (1.0 + (-x / s).exp())
}

/// The logistic of scale `s` restricted (and renormalised) to `[−π, π]`.
fn trimmed_logistic(x: f32, s: f32) -> f32 {
    logistic(x, s) / (logistic_cdf(PI, s) - logistic_cdf(-PI, s))
}

/// Samples the logistic of scale `s` restricted to `[−π, π]` with `u ∈ [0, 1)` (inverse cdf).
pub(super) fn sample_trimmed_logistic(u: f32, s: f32) -> f32 {
    let low = logistic_cdf(-PI, s);
    let k = logistic_cdf(PI, s) - low;
    let c = (u * k + low).clamp(f32::MIN_POSITIVE, 1.0 - f32::EPSILON);
    (-s * (1.0 / c - 1.0).ln()).clamp(-PI, PI)
}

/// `x` wrapped to `[−π, π)`.
pub(super) fn wrap_angle(x: f32) -> f32 {
    (x + PI).rem_euclid(2.0 * PI) - PI
}

/// The azimuthal distribution `N_p(φ) = trimmed logistic(φ − Φ(p, γ_o, γ_t))`, the difference
/// wrapped to `[−π, π)`; a density in `φ = φ_i − φ_o` that integrates to 1 over a period.
pub(super) fn azimuthal(phi: f32, p: usize, s: f32, gamma_o: f32, gamma_t: f32) -> f32 {
    trimmed_logistic(wrap_angle(phi - perfect_azimuth(p, gamma_o, gamma_t)), s)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The series and the asymptotic expansion of ln I₀ meet at 30; known values of I₀.
    #[test]
    fn bessel_i0_matches_known_values() {
        // I₀(1) = 1.2660658777520082, I₀(10) = 2815.716628466254.
        assert!((log_bessel_i0(1.0).exp() - 1.266_065_877_752_008).abs() < 1e-12);
        assert!((log_bessel_i0(10.0).exp() / 2_815.716_628_466_254 - 1.0).abs() < 1e-12);
        assert!((log_bessel_i0(30.0 + 1e-9) - log_bessel_i0(30.0)).abs() < 1e-6);
        assert_eq!(log_bessel_i0(0.0), 0.0);
    }

    /// `M_p` integrates to 1 in `sin θ_i`, for small and large variances and tilted `θ_o`.
    #[test]
    fn longitudinal_is_normalised() {
        for v in [0.002f32, 0.02, 0.1, 0.5, 3.0, 30.0] {
            for theta_o in [-1.2f32, 0.0, 0.4, 1.5] {
                let (sin_o, cos_o) = theta_o.sin_cos();
                let n = 20_000;
                let mut sum = 0.0f64;
                for k in 0..n {
                    let sin_i = -1.0 + 2.0 * (k as f32 + 0.5) / n as f32;
                    let cos_i = (1.0 - sin_i * sin_i).max(0.0).sqrt();
                    sum += f64::from(longitudinal(cos_i, cos_o, sin_i, sin_o, v)) * 2.0 / n as f64;
                }
                assert!((sum - 1.0).abs() < 2e-3, "v {v} θ_o {theta_o}: {sum}");
            }
        }
    }

    /// `N_p` integrates to 1 over a period and its sampler inverts its cdf.
    #[test]
    fn azimuthal_is_normalised_and_sampled() {
        for s in [0.01f32, 0.3, 2.0] {
            let n = 100_000;
            let sum: f64 = (0..n)
                .map(|k| f64::from(azimuthal(-PI + 2.0 * PI * (k as f32 + 0.5) / n as f32, 1, s, 0.3, 0.1)))
                .sum::<f64>()
                * 2.0
                * std::f64::consts::PI
                / n as f64;
            assert!((sum - 1.0).abs() < 1e-3, "s {s}: {sum}");
            // The sampled quantiles: the median is 0, and P(x < sample(u)) = u.
            assert!(sample_trimmed_logistic(0.5, s).abs() < 1e-4);
            let x = sample_trimmed_logistic(0.8, s);
            let cdf = (logistic_cdf(x, s) - logistic_cdf(-PI, s)) / (logistic_cdf(PI, s) - logistic_cdf(-PI, s));
            assert!((cdf - 0.8).abs() < 1e-4, "s {s}: {cdf}");
        }
        assert!((wrap_angle(3.0 * PI + 0.1) - (-PI + 0.1)).abs() < 1e-5);
    }
}
