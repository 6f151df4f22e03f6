//! The per-entry Z-test shared by `vcm compare` and `vcm conformance`: the z score of one
//! pixel channel with the variance floor for deterministic entries, the two-sided normal tail
//! and the Šidák correction. It owns no image handling and no verdict (each command decides
//! what fraction of entries must pass).

/// Default variance floor of the per-pixel Z-test, relative to the value: the combined
/// standard error of an entry is at least this times `max(|a|, |b|)`, so that entries that are
/// deterministic in both images (zero variance, e.g. a constant background) pass when they
/// differ only by rounding (half-float storage: 2⁻¹¹ ≈ 4.9e-4 relative) and fail when they
/// differ by more than about `z* · f` of their value.
pub const RELATIVE_FLOOR: f64 = 1e-3;

/// The z score `(a − b) / se` of one entry with values `a`, `b` and variances of their means
/// `var_a`, `var_b` (negative variances count as 0), where the combined standard error is
/// `se = sqrt(max(var_a + var_b, (floor · max(|a|, |b|))²))`. `a == b` gives 0 (also for
/// two zero-variance zeros); any other difference with `se = 0` gives ±∞.
pub fn z_score(a: f64, b: f64, var_a: f64, var_b: f64, relative_floor: f64) -> f64 {
    let difference = a - b;
    if difference == 0.0 {
        return 0.0;
    }
    let floor = relative_floor * a.abs().max(b.abs());
    let variance = var_a.max(0.0) + var_b.max(0.0);
    difference / variance.max(floor * floor).sqrt()
}

/// Šidák-corrected per-test level `1 − (1 − alpha)^(1/tests)`, which keeps the family-wise
/// false-alarm rate of `tests` independent tests at `alpha`; computed accurately for tiny
/// `alpha`.
pub fn sidak(alpha: f64, tests: usize) -> f64 {
    -((-alpha).ln_1p() / tests.max(1) as f64).exp_m1()
}

/// Two-sided normal tail probability `P(|Z| ≥ z)` for `z ≥ 0`, i.e. `erfc(z / √2)`.
pub fn two_sided_p(z: f64) -> f64 {
    erfc(z / std::f64::consts::SQRT_2).clamp(0.0, 1.0)
}

pub use math::special::erfc;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_tail_matches_known_quantiles() {
        assert!((erfc(0.0) - 1.0).abs() < 1e-7);
        assert!((two_sided_p(1.959_963_984_540_054) - 0.05).abs() < 1e-8);
        assert!((two_sided_p(3.290_526_731_491_926) - 1e-3).abs() < 1e-9);
        assert!((two_sided_p(1.0) - 0.317_310_507_862_914_1).abs() < 1e-7);
        assert!((erfc(-1.0) - 1.842_700_792_949_715).abs() < 1e-7);
        // Deep tail, relative accuracy: P(|Z| >= 6) = 1.973175e-9.
        assert!((two_sided_p(6.0) / 1.973_175_290_075_7e-9 - 1.0).abs() < 1e-6);
        assert_eq!(two_sided_p(100.0), 0.0);
    }

    #[test]
    fn sidak_level() {
        assert!((sidak(0.05, 1) - 0.05).abs() < 1e-15);
        let level = sidak(1e-3, 1000);
        assert!(((1.0 - level).powi(1000) - (1.0 - 1e-3)).abs() < 1e-12);
    }

    #[test]
    fn z_score_floor_and_zero_cases() {
        // Noise above the floor: the plain z.
        assert!((z_score(1.1, 1.0, 0.005, 0.005, 1e-3) - 1.0).abs() < 1e-12);
        // Zero variance: the floor 1e-3 · 2 gives z = 0.01 / 0.002 = 5.
        assert!((z_score(2.0, 1.99, 0.0, 0.0, 1e-3) - 5.0).abs() < 1e-9);
        assert_eq!(z_score(0.0, 0.0, 0.0, 0.0, 1e-3), 0.0);
        assert!(z_score(1e-9, 0.0, 0.0, 0.0, 0.0).is_infinite());
        // Negative variances count as zero.
        assert!((z_score(1.1, 1.0, -5.0, 0.01, 0.0) - 1.0).abs() < 1e-12);
    }
}
