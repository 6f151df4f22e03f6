//! Elementary statistics for tests: running mean and variance, two-sided z-tests, the Šidák
//! correction for families of tests, and an entry-by-entry comparison of two estimates (for
//! example two renderings of the same scene, pixel by pixel or block by block).

use statrs::distribution::{ContinuousCDF, StudentsT};
use statrs::function::erf::erfc;
use std::fmt;

/// Running mean and variance of `f64` values by Welford's algorithm (numerically stable in one
/// pass).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MeanVar {
    count: u64,
    mean: f64,
    /// Sum of squared deviations from the running mean.
    m2: f64,
}

impl MeanVar {
    /// An empty accumulator.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds one value.
    pub fn push(&mut self, x: f64) {
        self.count += 1;
        let delta = x - self.mean;
        self.mean += delta / self.count as f64;
        self.m2 += delta * (x - self.mean);
    }

    /// Combines two accumulators as if all values had been pushed into one (Chan et al.).
    pub fn merge(&mut self, other: &MeanVar) {
        if other.count == 0 {
            return;
        }
        if self.count == 0 {
            *self = *other;
            return;
        }
        let n = self.count + other.count;
        let delta = other.mean - self.mean;
        let (na, nb, nf) = (self.count as f64, other.count as f64, n as f64);
        self.mean += delta * nb / nf;
        self.m2 += other.m2 + delta * delta * na * nb / nf;
        self.count = n;
    }

    /// Number of values pushed.
    pub fn count(&self) -> u64 {
        self.count
    }

    /// Mean of the values (0 when there are none).
    pub fn mean(&self) -> f64 {
        self.mean
    }

    /// Unbiased sample variance (divides by `n − 1`; 0 for fewer than two values).
    pub fn variance(&self) -> f64 {
        if self.count < 2 { 0.0 } else { (self.m2 / (self.count - 1) as f64).max(0.0) }
    }

    /// Standard error of the mean, `sqrt(variance / n)` (0 for fewer than two values).
    pub fn std_error(&self) -> f64 {
        if self.count < 2 { 0.0 } else { (self.variance() / self.count as f64).sqrt() }
    }
}

impl Extend<f64> for MeanVar {
    fn extend<I: IntoIterator<Item = f64>>(&mut self, iter: I) {
        for x in iter {
            self.push(x);
        }
    }
}

impl FromIterator<f64> for MeanVar {
    fn from_iter<I: IntoIterator<Item = f64>>(iter: I) -> Self {
        let mut mv = MeanVar::new();
        mv.extend(iter);
        mv
    }
}

/// Two-sided p-value of a z-test: the probability that a normal variable with mean 0 and
/// standard deviation `se` is at least `|d|` away from 0.
///
/// A zero (or negative) `se` gives 1 when `d == 0` and 0 otherwise; a non-finite `d` or `se`
/// gives 0 (a NaN is never accepted).
pub fn z_test_p(d: f64, se: f64) -> f64 {
    if !d.is_finite() || !se.is_finite() {
        return 0.0;
    }
    if se <= 0.0 {
        return if d == 0.0 { 1.0 } else { 0.0 };
    }
    let z = (d / se).abs();
    erfc(z / std::f64::consts::SQRT_2).clamp(0.0, 1.0)
}

/// Two-sided p-value of a t-test: the probability that `|T| ≥ |d| / se` for a Student-t
/// variable `T` with `dof` degrees of freedom. This is the null distribution of a difference
/// whose standard error `se` was itself estimated from `dof + 1` independent, normally
/// distributed samples (for example the iterations of a render): with few samples the
/// estimated error is often too small, and a z-test would reject far too often.
///
/// Edge cases as [`z_test_p`]; `dof` must be positive (an infinite `dof` is the z-test).
pub fn t_test_p(d: f64, se: f64, dof: f64) -> f64 {
    assert!(dof > 0.0, "a t-test needs positive degrees of freedom, got {dof}");
    if !d.is_finite() || !se.is_finite() || se <= 0.0 || dof.is_infinite() {
        return z_test_p(d, se);
    }
    let t = (d / se).abs();
    let student = StudentsT::new(0.0, 1.0, dof).expect("valid Student-t parameters");
    (2.0 * student.sf(t)).clamp(0.0, 1.0)
}

/// Degrees of freedom of the difference of two estimates with standard errors `se_a` and
/// `se_b`, estimated with `dof_a` and `dof_b` degrees of freedom (Welch–Satterthwaite):
/// `(se_a² + se_b²)² / (se_a⁴/dof_a + se_b⁴/dof_b)`. An infinite `dof` marks an error that is
/// known, not estimated. Lies between `min(dof_a, dof_b)` and `dof_a + dof_b`.
pub fn welch_dof(se_a: f64, dof_a: f64, se_b: f64, dof_b: f64) -> f64 {
    let (va, vb) = (se_a * se_a, se_b * se_b);
    let denominator = va * va / dof_a + vb * vb / dof_b;
    if denominator > 0.0 { (va + vb) * (va + vb) / denominator } else { f64::INFINITY }
}

/// Šidák-corrected per-test significance level: running `tests` independent tests each at this
/// level rejects at least one true hypothesis with probability `alpha`, i.e.
/// `1 − (1 − alpha)^(1/tests)`. Zero tests are treated as one.
pub fn sidak(alpha: f64, tests: usize) -> f64 {
    let tests = tests.max(1) as f64;
    // Written with ln_1p/expm1 to stay accurate for tiny alpha.
    -((-alpha).ln_1p() / tests).exp_m1()
}

/// Result of [`z_test_entries`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ZTestOutcome {
    /// Number of entries compared.
    pub entries: usize,
    /// Index of the entry with the smallest p-value (0 when there are no entries).
    pub worst_index: usize,
    /// Z score `(a − b) / sqrt(se_a² + se_b²)` of the worst entry (signed).
    pub worst_z: f64,
    /// Two-sided p-value of the worst entry.
    pub worst_p: f64,
    /// Per-entry significance level after the Šidák correction.
    pub threshold: f64,
    /// Whether every entry passes at the Šidák-corrected level (`worst_p >= threshold`).
    pub passed: bool,
}

impl fmt::Display for ZTestOutcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} entries, worst entry {} with z = {:.3} and p = {:.3e} (per-entry threshold {:.3e}): {}",
            self.entries,
            self.worst_index,
            self.worst_z,
            self.worst_p,
            self.threshold,
            if self.passed { "passed" } else { "FAILED" }
        )
    }
}

/// Compares two estimates entry by entry, each entry given as a mean with its standard error.
///
/// Each entry gets a two-sided z-test of `a_mean[i] − b_mean[i]` against the combined standard
/// error `sqrt(a_se[i]² + b_se[i]²)`; the family passes when every p-value is at least the
/// Šidák-corrected level [`sidak`]`(alpha, entries)`. Entries with zero combined error pass only
/// when the means are equal; non-finite means or errors fail.
///
/// # Panics
/// If the four slices do not have the same length.
pub fn z_test_entries(a_mean: &[f64], a_se: &[f64], b_mean: &[f64], b_se: &[f64], alpha: f64) -> ZTestOutcome {
    let n = a_mean.len();
    assert!(
        a_se.len() == n && b_mean.len() == n && b_se.len() == n,
        "z_test_entries: slices of different lengths ({}, {}, {}, {})",
        n,
        a_se.len(),
        b_mean.len(),
        b_se.len()
    );
    let threshold = sidak(alpha, n);
    let mut worst = (0usize, 0.0f64, 1.0f64);
    for i in 0..n {
        let d = a_mean[i] - b_mean[i];
        let se = (a_se[i] * a_se[i] + b_se[i] * b_se[i]).sqrt();
        let p = z_test_p(d, se);
        let z = if !d.is_finite() || !se.is_finite() {
            f64::NAN
        } else if se > 0.0 {
            d / se
        } else if d == 0.0 {
            0.0
        } else {
            d.signum() * f64::INFINITY
        };
        if p < worst.2 || (p == worst.2 && z.abs() > worst.1.abs()) {
            worst = (i, z, p);
        }
    }
    ZTestOutcome {
        entries: n,
        worst_index: worst.0,
        worst_z: worst.1,
        worst_p: worst.2,
        threshold,
        passed: worst.2 >= threshold,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Against the closed forms of one and two degrees of freedom (Cauchy: `1 − 2·atan(t)/π`;
    /// `ν = 2`: `1 − t/√(2 + t²)`), and the z-test as the degrees of freedom grow.
    #[test]
    fn t_test_matches_closed_forms() {
        for t in [0.0, 0.5, 1.0, 2.5, 10.0, 300.0] {
            let cauchy = 1.0 - 2.0 * f64::atan(t) / std::f64::consts::PI;
            let two = 1.0 - t / (2.0 + t * t).sqrt();
            assert!((t_test_p(t, 1.0, 1.0) - cauchy).abs() < 1e-12 * cauchy.max(1e-3), "ν = 1, t = {t}");
            assert!((t_test_p(-t, 1.0, 2.0) - two).abs() < 1e-10 * two.max(1e-3), "ν = 2, t = {t}");
        }
        // The 99.5 % quantile of t with 15 degrees of freedom is 2.947 (tables).
        assert!((t_test_p(2.947, 1.0, 15.0) - 0.01).abs() < 1e-4);
        let (z, t) = (z_test_p(4.0, 1.0), t_test_p(4.0, 1.0, 1e7));
        // The tails differ by a relative O(t⁴/ν) ≈ 1e-5 here.
        assert!((t - z).abs() < 1e-4 * z, "{t} vs {z}");
        assert_eq!(t_test_p(4.0, 1.0, f64::INFINITY), z);
        // Heavier tails than the normal: rejects less at the same |d|/se.
        assert!(t_test_p(5.0, 1.0, 15.0) > 100.0 * z_test_p(5.0, 1.0));
        assert_eq!(t_test_p(f64::NAN, 1.0, 15.0), 0.0);
    }

    #[test]
    fn welch_dof_limits() {
        assert_eq!(welch_dof(1.0, 15.0, 0.0, 100.0), 15.0);
        assert!((welch_dof(1.0, 15.0, 1.0, 15.0) - 30.0).abs() < 1e-12);
        assert!(welch_dof(1.0, 15.0, 0.1, f64::INFINITY) > 15.0);
        assert_eq!(welch_dof(0.0, 15.0, 0.0, 15.0), f64::INFINITY);
    }

    #[test]
    fn mean_var_known_values() {
        let mv: MeanVar = [2.0, 4.0, 4.0, 4.0, 5.0, 5.0, 7.0, 9.0].into_iter().collect();
        assert_eq!(mv.count(), 8);
        assert!((mv.mean() - 5.0).abs() < 1e-12);
        // Population variance 4, sample variance 32/7.
        assert!((mv.variance() - 32.0 / 7.0).abs() < 1e-12);
        assert!((mv.std_error() - (32.0 / 7.0 / 8.0f64).sqrt()).abs() < 1e-12);

        let empty = MeanVar::new();
        assert_eq!(empty.count(), 0);
        assert_eq!(empty.mean(), 0.0);
        assert_eq!(empty.variance(), 0.0);
        assert_eq!(empty.std_error(), 0.0);
    }

    #[test]
    fn mean_var_is_stable_with_large_offset() {
        let mv: MeanVar = (0..1000).map(|i| 1e9 + (i % 2) as f64).collect();
        assert!((mv.mean() - (1e9 + 0.5)).abs() < 1e-6);
        assert!((mv.variance() - 0.25 * 1000.0 / 999.0).abs() < 1e-9);
    }

    #[test]
    fn mean_var_merge_matches_single_pass() {
        let values: Vec<f64> = (0..101).map(|i| ((i * 37) % 11) as f64 * 0.5 - 1.0).collect();
        let all: MeanVar = values.iter().copied().collect();
        let mut a: MeanVar = values[..40].iter().copied().collect();
        let b: MeanVar = values[40..].iter().copied().collect();
        a.merge(&b);
        assert_eq!(a.count(), all.count());
        assert!((a.mean() - all.mean()).abs() < 1e-12);
        assert!((a.variance() - all.variance()).abs() < 1e-12);
        let mut e = MeanVar::new();
        e.merge(&all);
        assert_eq!(e, all);
    }

    #[test]
    fn z_test_known_values() {
        assert!((z_test_p(1.96, 1.0) - 0.05).abs() < 1e-3);
        assert!((z_test_p(-1.96, 1.0) - 0.05).abs() < 1e-3);
        assert!((z_test_p(2.0 * 2.575_829, 2.0) - 0.01).abs() < 1e-5);
        assert_eq!(z_test_p(0.0, 1.0), 1.0);
        assert_eq!(z_test_p(0.0, 0.0), 1.0);
        assert_eq!(z_test_p(1.0, 0.0), 0.0);
        assert_eq!(z_test_p(f64::NAN, 1.0), 0.0);
        assert_eq!(z_test_p(1.0, f64::NAN), 0.0);
        assert!(z_test_p(10.0, 1.0) < 1e-20);
    }

    #[test]
    fn sidak_known_values() {
        assert!((sidak(0.05, 1) - 0.05).abs() < 1e-15);
        assert!((sidak(0.05, 0) - 0.05).abs() < 1e-15);
        assert!((sidak(0.05, 10) - (1.0 - 0.95f64.powf(0.1))).abs() < 1e-15);
        assert!((sidak(0.05, 10) - 0.005_116).abs() < 1e-6);
        // Close to Bonferroni for small alpha, and accurate there.
        let s = sidak(1e-9, 1000);
        assert!((s - 1e-12).abs() < 1e-18, "{s}");
    }

    #[test]
    fn z_test_entries_finds_the_outlier() {
        let n = 1000;
        let a: Vec<f64> = (0..n).map(|i| (i as f64 * 0.618_034).fract()).collect();
        let se = vec![0.01; n];
        // b = a plus small deterministic noise well inside the errors.
        let mut b: Vec<f64> = a.iter().enumerate().map(|(i, x)| x + 0.005 * ((i as f64) * 1.7).sin()).collect();
        let ok = z_test_entries(&a, &se, &b, &se, 0.01);
        assert!(ok.passed, "{ok}");
        assert_eq!(ok.entries, n);

        b[123] += 0.1; // z ≈ 7
        let bad = z_test_entries(&a, &se, &b, &se, 0.01);
        assert!(!bad.passed, "{bad}");
        assert_eq!(bad.worst_index, 123);
        assert!(bad.worst_z < -6.0, "{bad}");
        assert!(bad.worst_p < bad.threshold);
    }

    #[test]
    fn z_test_entries_edge_cases() {
        let empty = z_test_entries(&[], &[], &[], &[], 0.01);
        assert!(empty.passed);
        assert_eq!(empty.entries, 0);

        // Exactly equal entries with no error pass, different ones fail.
        let same = z_test_entries(&[0.0, 1.0], &[0.0, 0.0], &[0.0, 1.0], &[0.0, 0.0], 0.01);
        assert!(same.passed);
        let diff = z_test_entries(&[0.0, 1.0], &[0.0, 0.0], &[0.0, 1.5], &[0.0, 0.0], 0.01);
        assert!(!diff.passed);
        assert_eq!(diff.worst_index, 1);

        let nan = z_test_entries(&[f64::NAN], &[1.0], &[0.0], &[1.0], 0.01);
        assert!(!nan.passed);
    }

    #[test]
    #[should_panic(expected = "different lengths")]
    fn z_test_entries_rejects_mismatched_lengths() {
        z_test_entries(&[0.0, 1.0], &[0.0], &[0.0, 1.0], &[0.0, 0.0], 0.01);
    }
}
