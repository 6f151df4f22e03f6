//! Chi-square goodness-of-fit tests of samplers against their pdfs.
//!
//! The domain (the unit sphere, or the unit square) is cut into bins. The sampler is run
//! `samples` times and the samples are counted per bin; the expected count of a bin is
//! `samples × ∫_bin pdf`, with the integral computed by adaptive composite Simpson quadrature so
//! that very peaked pdfs (Phong exponents of a thousand or more) are integrated accurately.
//! Samples the sampler refuses to produce (`None`) are counted in an extra *failure* cell whose
//! expected count is `samples × (1 − ∫ pdf)`: a sampler that fails 30 % of the time must report
//! a pdf that integrates to 0.7. When `|1 − ∫ pdf|` is below [`FAILURE_RESOLUTION`] (rare
//! failures, e.g. a glossy lobe grazing the horizon) the quadrature cannot resolve it: the
//! successful samples are then tested against the normalised pdf and the failure rate is only
//! bounded by that resolution.
//!
//! Cells whose expected count is below [`MIN_EXPECTED`] are pooled into one cell before the
//! statistic `Σ (observed − expected)² / expected` is formed; its p-value comes from the
//! chi-square distribution with `cells − 1` degrees of freedom. Samples in cells where the pdf
//! integrates to (numerically) zero fail the test outright, however few.
//!
//! The sampler and the pdf are usually single-precision code, so their agreement is only as good
//! as that: with tens of millions of samples, rounding (say a `cos¹⁰⁰⁰` lobe around an axis that
//! is normalised in `f32`) can become visible.
//!
//! Use [`assert_chi2`] in tests, with a significance such as `1e-3`, corrected with
//! [`crate::sidak`] when a test runs several chi-square tests.

use math::{Rng, Vec3};
use statrs::distribution::{ChiSquared, ContinuousCDF};
use std::f64::consts::PI;
use std::fmt::Write as _;

/// Cells whose expected count is below this are pooled together before computing the statistic.
pub const MIN_EXPECTED: f64 = 5.0;

/// How far above 1 the integral of a pdf may be (numerical integration error, single precision
/// pdfs) before [`assert_chi2`] calls it a bug.
pub const PDF_INTEGRAL_TOLERANCE: f64 = 1e-3;

/// Largest deviation of a sampled direction's length from 1 that [`chi2_sphere`] accepts.
pub const DIRECTION_LENGTH_TOLERANCE: f64 = 1e-3;

/// How far outside the unit square a sample point may lie (by rounding) and still be accepted by
/// [`chi2_square`] (it is counted in the nearest bin).
pub const SQUARE_SLACK: f64 = 1e-6;

/// Result of a chi-square test.
#[derive(Clone, Debug, PartialEq)]
pub struct Chi2Outcome {
    /// The chi-square statistic after pooling (infinite when a sample fell where the pdf
    /// integrates to zero, or when the pdf is negative or NaN somewhere).
    pub statistic: f64,
    /// Degrees of freedom: the number of cells after pooling, minus one.
    pub degrees_of_freedom: usize,
    /// Probability of a statistic at least this large if the sampler matches the pdf.
    pub p_value: f64,
    /// Number of times the sampler was called.
    pub samples: usize,
    /// Number of calls that returned `None`.
    pub failed_samples: usize,
    /// Number of samples that were not valid points of the domain (non-finite, a direction that
    /// is not of unit length, a point outside the unit square). Any makes [`assert_chi2`] fail.
    pub invalid_samples: usize,
    /// Numerical integral of the pdf over the whole domain.
    pub pdf_integral: f64,
    /// Human-readable table of observed against expected counts (the worst cells, the marginal
    /// counts per row of bins, and the failure cell), for failure messages.
    pub table: String,
}

impl Chi2Outcome {
    /// Whether the test passes at `significance`: the p-value is at least `significance`, the pdf
    /// integrates to at most `1 + PDF_INTEGRAL_TOLERANCE`, and every sample was valid.
    pub fn passed(&self, significance: f64) -> bool {
        self.problems(significance).is_empty()
    }

    fn problems(&self, significance: f64) -> Vec<String> {
        let mut problems = Vec::new();
        if !self.pdf_integral.is_finite() {
            problems.push(format!("the pdf integral is not finite ({})", self.pdf_integral));
        } else if self.pdf_integral > 1.0 + PDF_INTEGRAL_TOLERANCE {
            problems.push(format!(
                "the pdf integrates to {:.6} over the domain, more than 1 (tolerance {PDF_INTEGRAL_TOLERANCE:e})",
                self.pdf_integral
            ));
        }
        if self.invalid_samples > 0 {
            problems.push(format!(
                "{} of {} samples were not valid points of the domain",
                self.invalid_samples, self.samples
            ));
        }
        // A NaN p-value fails too.
        if self.p_value.is_nan() || self.p_value < significance {
            problems.push(format!("p-value {:.3e} is below the significance {significance:.3e}", self.p_value));
        }
        problems
    }
}

/// Controls the adaptive quadrature that integrates the pdf over each bin.
///
/// Each bin is first cut into `initial_split × initial_split` rectangles; each rectangle is
/// integrated by composite Simpson on 8 × 8 and 4 × 4 intervals, and cut into four while the two
/// disagree by more than the rectangle's tolerance, down to `max_depth` levels. The tolerance of
/// a bin is the larger of `rel_tolerance × |bin integral|` and the bin's share (by area) of
/// `abs_tolerance`; a rectangle gets its share (by area) of that, or `rel_tolerance` times its
/// own integral if larger.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Integration {
    /// Initial subdivisions of each bin along each axis (at least 1).
    pub initial_split: usize,
    /// Maximum number of refinement levels below the initial subdivision.
    pub max_depth: u32,
    /// Absolute error budget (probability) for the whole domain, shared by area.
    pub abs_tolerance: f64,
    /// Relative error accepted for each bin's integral (shared by area among its rectangles).
    pub rel_tolerance: f64,
}

impl Default for Integration {
    /// 2 × 2 initial rectangles per bin (16 × 16 Simpson intervals), 7 refinement levels,
    /// absolute tolerance 1e-6 and relative tolerance 1e-4 (tighter relative tolerances chase
    /// the rounding noise of single-precision pdfs, which for `cos¹⁰⁰⁰` is about 1e-4).
    fn default() -> Self {
        Self { initial_split: 2, max_depth: 7, abs_tolerance: 1e-6, rel_tolerance: 1e-4 }
    }
}

/// Chi-square test of a sampler of directions on the unit sphere against its pdf per unit solid
/// angle.
///
/// Bins: `theta_bins` in `cos θ` (equal width in `cos θ`, hence equal solid angle; bin 0 is
/// around +z) × `phi_bins` in `φ = atan2(y, x) ∈ [0, 2π)`. The sampler is called `samples`
/// times with one generator seeded from `seed`; `None` counts as a failed sample (see the module
/// documentation). Directions must be of unit length (within [`DIRECTION_LENGTH_TOLERANCE`]).
/// The pdf is integrated with [`Integration::default`]; see [`chi2_sphere_with`] to change it.
pub fn chi2_sphere(
    sample: impl FnMut(&mut Rng) -> Option<Vec3>,
    pdf: impl Fn(Vec3) -> f64,
    samples: usize,
    seed: u64,
    theta_bins: usize,
    phi_bins: usize,
) -> Chi2Outcome {
    chi2_sphere_with(sample, pdf, samples, seed, theta_bins, phi_bins, &Integration::default())
}

/// [`chi2_sphere`] with explicit control of the pdf integration.
///
/// # Panics
/// If `theta_bins` or `phi_bins` is zero.
pub fn chi2_sphere_with(
    mut sample: impl FnMut(&mut Rng) -> Option<Vec3>,
    pdf: impl Fn(Vec3) -> f64,
    samples: usize,
    seed: u64,
    theta_bins: usize,
    phi_bins: usize,
    integration: &Integration,
) -> Chi2Outcome {
    assert!(theta_bins > 0 && phi_bins > 0, "chi2_sphere: need at least one bin in θ and in φ");
    let z_edge = |i: usize| 1.0 - 2.0 * i as f64 / theta_bins as f64;
    let phi_edge = |j: usize| 2.0 * PI * j as f64 / phi_bins as f64;

    // Expected probabilities, integrated over (θ, φ) with the Jacobian sin θ: θ resolves a lobe
    // at the pole far better than cos θ does.
    let integrand = |theta: f64, phi: f64| {
        let (s, c) = theta.sin_cos();
        let d = Vec3::new((s * phi.cos()) as f32, (s * phi.sin()) as f32, c as f32);
        pdf(d) * s
    };
    let domain_area = PI * 2.0 * PI;
    let mut probabilities = Vec::with_capacity(theta_bins * phi_bins);
    for i in 0..theta_bins {
        let (t0, t1) = (z_edge(i).clamp(-1.0, 1.0).acos(), z_edge(i + 1).clamp(-1.0, 1.0).acos());
        for j in 0..phi_bins {
            let rect = Rect { x0: t0, x1: t1, y0: phi_edge(j), y1: phi_edge(j + 1) };
            probabilities.push(integrate_bin(&integrand, rect, domain_area, integration));
        }
    }

    let classify = |d: Vec3| {
        let (x, y, z) = (d.x as f64, d.y as f64, d.z as f64);
        let len = (x * x + y * y + z * z).sqrt();
        if !len.is_finite() || (len - 1.0).abs() > DIRECTION_LENGTH_TOLERANCE {
            return None;
        }
        let z = (z / len).clamp(-1.0, 1.0);
        let i = (((1.0 - z) * 0.5 * theta_bins as f64) as usize).min(theta_bins - 1);
        let mut phi = y.atan2(x);
        if phi < 0.0 {
            phi += 2.0 * PI;
        }
        let j = ((phi / (2.0 * PI) * phi_bins as f64) as usize).min(phi_bins - 1);
        Some(i * phi_bins + j)
    };
    let counts = count_samples(&mut sample, classify, samples, seed, probabilities.len());

    let label = |cell: usize| {
        let (i, j) = (cell / phi_bins, cell % phi_bins);
        format!(
            "θ-bin {i:>3} (cos θ {:+.3}..{:+.3}) φ-bin {j:>3} (φ {:>5.1}°..{:>5.1}°)",
            z_edge(i + 1),
            z_edge(i),
            phi_edge(j).to_degrees(),
            phi_edge(j + 1).to_degrees()
        )
    };
    let row_label = |i: usize| format!("θ-bin {i:>3} (cos θ {:+.3}..{:+.3})", z_edge(i + 1), z_edge(i));
    finish(samples, counts, &probabilities, phi_bins, &label, &row_label)
}

/// Chi-square test of a sampler of points of the unit square `[0, 1)²` against its pdf per unit
/// area (used for positions on triangles and discs after mapping them to the square).
///
/// Bins: `bins × bins` equal squares. Points outside the square (beyond a slack of
/// [`SQUARE_SLACK`] for rounding) are invalid samples. The pdf is integrated with
/// [`Integration::default`]; see [`chi2_square_with`] to change it.
pub fn chi2_square(
    sample: impl FnMut(&mut Rng) -> Option<[f64; 2]>,
    pdf: impl Fn([f64; 2]) -> f64,
    samples: usize,
    seed: u64,
    bins: usize,
) -> Chi2Outcome {
    chi2_square_with(sample, pdf, samples, seed, bins, &Integration::default())
}

/// [`chi2_square`] with explicit control of the pdf integration.
///
/// # Panics
/// If `bins` is zero.
pub fn chi2_square_with(
    mut sample: impl FnMut(&mut Rng) -> Option<[f64; 2]>,
    pdf: impl Fn([f64; 2]) -> f64,
    samples: usize,
    seed: u64,
    bins: usize,
    integration: &Integration,
) -> Chi2Outcome {
    assert!(bins > 0, "chi2_square: need at least one bin");
    let edge = |i: usize| i as f64 / bins as f64;
    let integrand = |x: f64, y: f64| pdf([x, y]);
    let mut probabilities = Vec::with_capacity(bins * bins);
    for i in 0..bins {
        for j in 0..bins {
            let rect = Rect { x0: edge(i), x1: edge(i + 1), y0: edge(j), y1: edge(j + 1) };
            probabilities.push(integrate_bin(&integrand, rect, 1.0, integration));
        }
    }

    let classify = |p: [f64; 2]| {
        let inside = |v: f64| v.is_finite() && (-SQUARE_SLACK..=1.0 + SQUARE_SLACK).contains(&v);
        if !inside(p[0]) || !inside(p[1]) {
            return None;
        }
        let index = |v: f64| ((v.max(0.0) * bins as f64) as usize).min(bins - 1);
        Some(index(p[0]) * bins + index(p[1]))
    };
    let counts = count_samples(&mut sample, classify, samples, seed, probabilities.len());

    let label = |cell: usize| {
        let (i, j) = (cell / bins, cell % bins);
        format!("x-bin {i:>3} ({:.3}..{:.3}) y-bin {j:>3} ({:.3}..{:.3})", edge(i), edge(i + 1), edge(j), edge(j + 1))
    };
    let row_label = |i: usize| format!("x-bin {i:>3} ({:.3}..{:.3})", edge(i), edge(i + 1));
    finish(samples, counts, &probabilities, bins, &label, &row_label)
}

/// Panics with a readable message (statistic, degrees of freedom, p-value, pdf integral and the
/// table of counts) when the test failed at `significance`: the p-value is below it, the pdf
/// integrates to more than `1 + PDF_INTEGRAL_TOLERANCE`, or some samples were invalid.
///
/// `what` names the sampler in the message. For several tests in one test function, pass
/// [`crate::sidak`]`(alpha, tests)` as the significance.
#[track_caller]
pub fn assert_chi2(outcome: &Chi2Outcome, significance: f64, what: &str) {
    let problems = outcome.problems(significance);
    if problems.is_empty() {
        return;
    }
    panic!(
        "chi-square test of {what} FAILED: {}\n  statistic {:.3} with {} degrees of freedom, p-value {:.3e} \
         (significance {significance:.3e})\n  pdf integral {:.6}, {} samples, {} failed (None), {} invalid\n{}",
        problems.join("; "),
        outcome.statistic,
        outcome.degrees_of_freedom,
        outcome.p_value,
        outcome.pdf_integral,
        outcome.samples,
        outcome.failed_samples,
        outcome.invalid_samples,
        outcome.table
    );
}

/// Sample counts: per bin, failed, invalid.
struct Counts {
    bins: Vec<u64>,
    failed: usize,
    invalid: usize,
}

fn count_samples<T>(
    sample: &mut impl FnMut(&mut Rng) -> Option<T>,
    classify: impl Fn(T) -> Option<usize>,
    samples: usize,
    seed: u64,
    bins: usize,
) -> Counts {
    let mut counts = Counts { bins: vec![0; bins], failed: 0, invalid: 0 };
    let mut rng = Rng::for_stream(seed, 0, 0);
    for _ in 0..samples {
        match sample(&mut rng) {
            None => counts.failed += 1,
            Some(x) => match classify(x) {
                Some(cell) => counts.bins[cell] += 1,
                None => counts.invalid += 1,
            },
        }
    }
    counts
}

/// Builds the outcome from the counts and the bin probabilities. Cells are laid out row-major
/// with `row_len` cells per row.
fn finish(
    samples: usize,
    counts: Counts,
    probabilities: &[f64],
    row_len: usize,
    label: &dyn Fn(usize) -> String,
    row_label: &dyn Fn(usize) -> String,
) -> Chi2Outcome {
    let n = samples as f64;
    let pdf_integral: f64 = probabilities.iter().sum();

    // Observed and expected counts; the failure cell last.
    let mut observed: Vec<u64> = counts.bins.clone();
    observed.push(counts.failed as u64);
    let failure_probability = 1.0 - pdf_integral;
    let mut expected: Vec<f64>;
    let mut unresolved_failures = None;
    if failure_probability.abs() < FAILURE_RESOLUTION {
        // The failure probability is below what the quadrature of a single-precision pdf can
        // resolve: test the shape of the successful samples (expected counts scaled to them)
        // and bound the failure rate separately.
        let successes = (samples - counts.failed - counts.invalid) as f64;
        expected = probabilities.iter().map(|p| p * successes / pdf_integral).collect();
        expected.push(0.0);
        let rate = counts.failed as f64 / n;
        let bound = FAILURE_RESOLUTION + 5.0 * (FAILURE_RESOLUTION / n).sqrt();
        if rate > bound {
            unresolved_failures = Some(format!(
                "{} samples failed ({rate:.2e} of all) although the pdf integrates to {pdf_integral:.6} (bound {bound:.2e})",
                counts.failed
            ));
        }
    } else {
        expected = probabilities.iter().map(|p| p * n).collect();
        expected.push((n * failure_probability).max(0.0));
    }
    // Invalid samples are counted against the test separately; they are in no cell, so the
    // observed counts may sum to less than `samples`.

    let mut counted = observed.clone();
    if failure_probability.abs() < FAILURE_RESOLUTION {
        // The failure cell is not part of the statistic (see above).
        counted[probabilities.len()] = 0;
    }
    let mut chi2 = pooled_chi2(&counted, &expected);
    if let Some(note) = unresolved_failures {
        chi2.notes.push(note);
        chi2.statistic = f64::INFINITY;
        chi2.p_value = 0.0;
    }
    let table = make_table(&observed, &expected, row_len, label, row_label, &chi2);
    Chi2Outcome {
        statistic: chi2.statistic,
        degrees_of_freedom: chi2.dof,
        p_value: chi2.p_value,
        samples,
        failed_samples: counts.failed,
        invalid_samples: counts.invalid,
        pdf_integral,
        table,
    }
}

struct PooledChi2 {
    statistic: f64,
    dof: usize,
    p_value: f64,
    pooled_cells: usize,
    pooled_expected: f64,
    pooled_observed: u64,
    notes: Vec<String>,
}

/// Pearson's statistic after pooling the cells with small expected counts.
fn pooled_chi2(observed: &[u64], expected: &[f64]) -> PooledChi2 {
    let mut notes = Vec::new();
    let mut hard_fail = false;

    let bad_expected = expected.iter().filter(|e| !e.is_finite() || **e < 0.0).count();
    if bad_expected > 0 {
        notes.push(format!("{bad_expected} cells have a negative or non-finite expected count (pdf < 0 or NaN?)"));
        hard_fail = true;
    }
    // Samples where (almost) nothing is expected: with at most ZERO_EXPECTED_TOTAL samples
    // expected there in all, even one is a rejection at that level, however they are pooled.
    let (stray, stray_expected) = observed
        .iter()
        .zip(expected)
        .filter(|(_, e)| **e <= ZERO_EXPECTED)
        .fold((0u64, 0.0f64), |(o_sum, e_sum), (o, e)| (o_sum + o, e_sum + e));
    if stray > 0 && stray_expected <= ZERO_EXPECTED_TOTAL {
        notes.push(format!(
            "{stray} samples fell in cells where the pdf integrates to zero (expected {stray_expected:.1e} there)"
        ));
        hard_fail = true;
    }

    let mut cells: Vec<(f64, f64)> = Vec::new();
    let (mut pooled_o, mut pooled_e, mut pooled_cells) = (0u64, 0.0f64, 0usize);
    for (&o, &e) in observed.iter().zip(expected) {
        if !e.is_finite() || e < 0.0 {
            continue;
        }
        if e >= MIN_EXPECTED {
            cells.push((o as f64, e));
        } else {
            pooled_o += o;
            pooled_e += e;
            pooled_cells += 1;
        }
    }
    if pooled_e >= MIN_EXPECTED || cells.is_empty() {
        if pooled_e > 0.0 {
            cells.push((pooled_o as f64, pooled_e));
        }
    } else if pooled_e > 0.0 || pooled_o > 0 {
        // Too little to form a cell of its own: merge into the smallest regular cell.
        let smallest = (0..cells.len()).min_by(|&a, &b| cells[a].1.total_cmp(&cells[b].1)).unwrap_or(0);
        cells[smallest].0 += pooled_o as f64;
        cells[smallest].1 += pooled_e;
    }

    let dof = cells.len().saturating_sub(1);
    let (statistic, p_value) = if hard_fail {
        (f64::INFINITY, 0.0)
    } else if dof == 0 {
        (0.0, 1.0)
    } else {
        let statistic: f64 = cells.iter().map(|&(o, e)| (o - e) * (o - e) / e).sum();
        let p = match ChiSquared::new(dof as f64) {
            Ok(dist) => dist.sf(statistic),
            Err(_) => f64::NAN,
        };
        (statistic, p)
    };
    PooledChi2 { statistic, dof, p_value, pooled_cells, pooled_expected: pooled_e, pooled_observed: pooled_o, notes }
}

/// A failure probability `1 − ∫pdf` smaller than this in magnitude is below the resolution of
/// the quadrature of single-precision pdfs: the failure cell is then left out of the statistic
/// (the successful samples are tested against the normalised pdf) and the failure rate is only
/// bounded by it.
pub const FAILURE_RESOLUTION: f64 = 1e-3;

/// Cells expecting at most this many samples count as cells where the pdf is zero.
const ZERO_EXPECTED: f64 = 1e-6;
/// A sample in such cells fails the test when they expect at most this many samples in all.
const ZERO_EXPECTED_TOTAL: f64 = 1e-3;

/// Number of individual cells listed in the table.
const WORST_CELLS: usize = 24;

fn make_table(
    observed: &[u64],
    expected: &[f64],
    row_len: usize,
    label: &dyn Fn(usize) -> String,
    row_label: &dyn Fn(usize) -> String,
    chi2: &PooledChi2,
) -> String {
    let mut t = String::new();
    let bins = observed.len() - 1;
    for note in &chi2.notes {
        let _ = writeln!(t, "  NOTE: {note}");
    }
    let contribution = |k: usize| {
        let (o, e) = (observed[k] as f64, expected[k]);
        if e > 0.0 {
            (o - e) * (o - e) / e
        } else if o > 0.0 {
            f64::INFINITY
        } else {
            0.0
        }
    };
    let _ = writeln!(
        t,
        "  {} of {} cells pooled (expected < {MIN_EXPECTED}): observed {}, expected {:.2}",
        chi2.pooled_cells,
        observed.len(),
        chi2.pooled_observed,
        chi2.pooled_expected
    );
    let _ = writeln!(t, "  failure cell (None): observed {}, expected {:.2}", observed[bins], expected[bins]);

    let mut order: Vec<usize> = (0..bins).collect();
    order.sort_by(|&a, &b| contribution(b).total_cmp(&contribution(a)));
    let _ = writeln!(t, "  worst cells by (observed − expected)²/expected:");
    let _ = writeln!(t, "    {:<62} {:>10} {:>12} {:>10}", "cell", "observed", "expected", "(o−e)²/e");
    for &k in order.iter().take(WORST_CELLS) {
        let _ = writeln!(t, "    {:<62} {:>10} {:>12.2} {:>10.2}", label(k), observed[k], expected[k], contribution(k));
    }

    let rows = bins / row_len;
    let _ = writeln!(t, "  per row (summed over the row's {row_len} cells):");
    let _ = writeln!(t, "    {:<32} {:>10} {:>12} {:>8}", "row", "observed", "expected", "z");
    for r in 0..rows {
        let o: u64 = observed[r * row_len..(r + 1) * row_len].iter().sum();
        let e: f64 = expected[r * row_len..(r + 1) * row_len].iter().sum();
        let z = if e > 0.0 { (o as f64 - e) / e.sqrt() } else { 0.0 };
        let _ = writeln!(t, "    {:<32} {:>10} {:>12.2} {:>8.2}", row_label(r), o, e, z);
    }
    t
}

/// An axis-aligned rectangle of the integration domain.
#[derive(Clone, Copy, Debug)]
struct Rect {
    x0: f64,
    x1: f64,
    y0: f64,
    y1: f64,
}

impl Rect {
    fn area(&self) -> f64 {
        ((self.x1 - self.x0) * (self.y1 - self.y0)).abs()
    }
}

/// Integral of `f` over one bin, starting from an `initial_split²` subdivision.
///
/// The first pass estimates the bin's integral; each rectangle is then refined until its error
/// estimate is within its share (by area) of `rel_tolerance × |bin integral|` or of
/// `abs_tolerance` (shared by area over the whole domain), whichever is larger. Tolerances
/// relative to the bin rather than only to each rectangle keep the far tails of a peaked pdf,
/// which matter to no count, from being refined to the maximum depth.
fn integrate_bin(f: &impl Fn(f64, f64) -> f64, bin: Rect, domain_area: f64, cfg: &Integration) -> f64 {
    let k = cfg.initial_split.max(1);
    let (dx, dy) = ((bin.x1 - bin.x0) / k as f64, (bin.y1 - bin.y0) / k as f64);
    let mut rects = Vec::with_capacity(k * k);
    for a in 0..k {
        for b in 0..k {
            let x0 = bin.x0 + a as f64 * dx;
            let y0 = bin.y0 + b as f64 * dy;
            // Exact outer edges, so that neighbouring bins share their boundaries.
            let x1 = if a + 1 == k { bin.x1 } else { x0 + dx };
            let y1 = if b + 1 == k { bin.y1 } else { y0 + dy };
            let r = Rect { x0, x1, y0, y1 };
            let (fine, coarse) = simpson(f, r);
            rects.push((r, fine, coarse));
        }
    }
    let estimate: f64 = rects.iter().map(|(_, fine, _)| fine).sum();
    let bin_area = bin.area();
    let tolerance_per_area = if bin_area > 0.0 {
        (cfg.abs_tolerance / domain_area).max(cfg.rel_tolerance * estimate.abs() / bin_area)
    } else {
        0.0
    };
    let tol = Tolerance { per_area: tolerance_per_area, relative: cfg.rel_tolerance };
    rects.into_iter().map(|(r, fine, coarse)| refine(f, r, fine, coarse, tol, cfg.max_depth)).sum()
}

/// Intervals per axis of the fine Simpson rule (the coarse rule uses every other point).
const SIMPSON_N: usize = 8;

/// Composite Simpson estimates of the integral of `f` over `r` with `SIMPSON_N` and
/// `SIMPSON_N / 2` intervals per axis, sharing the evaluations.
fn simpson(f: &impl Fn(f64, f64) -> f64, r: Rect) -> (f64, f64) {
    const N: usize = SIMPSON_N;
    let hx = (r.x1 - r.x0) / N as f64;
    let hy = (r.y1 - r.y0) / N as f64;
    let weight = |i: usize, n: usize| {
        if i == 0 || i == n {
            1.0
        } else if i % 2 == 1 {
            4.0
        } else {
            2.0
        }
    };
    let mut fine = 0.0;
    let mut coarse = 0.0;
    for i in 0..=N {
        let x = if i == N { r.x1 } else { r.x0 + i as f64 * hx };
        for j in 0..=N {
            let y = if j == N { r.y1 } else { r.y0 + j as f64 * hy };
            let v = f(x, y);
            fine += weight(i, N) * weight(j, N) * v;
            if i % 2 == 0 && j % 2 == 0 {
                coarse += weight(i / 2, N / 2) * weight(j / 2, N / 2) * v;
            }
        }
    }
    (fine * hx * hy / 9.0, coarse * (2.0 * hx) * (2.0 * hy) / 9.0)
}

/// Error accepted for a rectangle: the larger of `per_area × area` (its share of the bin's
/// tolerance) and `relative × |its integral|`. The second keeps the rounding noise of a
/// single-precision pdf on top of a peak from driving the refinement to the maximum depth; the
/// sum of either over a bin's rectangles stays within the bin's tolerance.
#[derive(Clone, Copy, Debug)]
struct Tolerance {
    per_area: f64,
    relative: f64,
}

/// Refines `r` (whose Simpson estimates are `fine` and `coarse`) by quadrisection until the
/// estimates agree within the tolerance or `depth_left` levels are used up.
fn refine(f: &impl Fn(f64, f64) -> f64, r: Rect, fine: f64, coarse: f64, tol: Tolerance, depth_left: u32) -> f64 {
    let err = (fine - coarse).abs();
    if err <= (tol.per_area * r.area()).max(tol.relative * fine.abs()) || depth_left == 0 || !err.is_finite() {
        return fine;
    }
    let xm = 0.5 * (r.x0 + r.x1);
    let ym = 0.5 * (r.y0 + r.y1);
    [
        Rect { x0: r.x0, x1: xm, y0: r.y0, y1: ym },
        Rect { x0: xm, x1: r.x1, y0: r.y0, y1: ym },
        Rect { x0: r.x0, x1: xm, y0: ym, y1: r.y1 },
        Rect { x0: xm, x1: r.x1, y0: ym, y1: r.y1 },
    ]
    .into_iter()
    .map(|q| {
        let (fine, coarse) = simpson(f, q);
        refine(f, q, fine, coarse, tol, depth_left - 1)
    })
    .sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sidak;
    use math::{Frame, warp};

    const ALPHA: f64 = 1e-3;

    /// `(n+1)/(2π)·cosⁿ α` around `axis`, in double precision.
    fn lobe_pdf(d: Vec3, axis: Vec3, n: f64) -> f64 {
        let c = d.as_dvec3().dot(axis.as_dvec3().normalize());
        if c <= 0.0 { 0.0 } else { (n + 1.0) / (2.0 * PI) * c.powf(n) }
    }

    fn lobe_sampler(axis: Vec3, n: f32) -> impl FnMut(&mut Rng) -> Option<Vec3> {
        let frame = Frame::from_z(axis);
        move |rng: &mut Rng| Some(frame.to_world(warp::power_cosine(rng.uniform2(), n)).normalize())
    }

    fn tilted_axis() -> Vec3 {
        Vec3::new(0.6, -0.3, 0.5).normalize()
    }

    #[test]
    fn integration_of_peaked_lobes_is_accurate() {
        for axis in [Vec3::Z, -Vec3::Z, tilted_axis(), Vec3::X] {
            for n in [1.0, 100.0, 1000.0, 5000.0] {
                let o = chi2_sphere(|_| None, |d| lobe_pdf(d, axis, n), 0, 1, 16, 32);
                assert!((o.pdf_integral - 1.0).abs() < 1e-4, "axis {axis} n {n}: {}", o.pdf_integral);
            }
        }
        let o = chi2_sphere(|_| None, |_| 0.25 / PI, 0, 1, 7, 5);
        assert!((o.pdf_integral - 1.0).abs() < 1e-6, "{}", o.pdf_integral);
        let o = chi2_square(|_| None, |p| if p[0] + p[1] <= 1.0 { 2.0 } else { 0.0 }, 0, 1, 13);
        assert!((o.pdf_integral - 1.0).abs() < 1e-4, "{}", o.pdf_integral);
    }

    #[test]
    fn accepts_uniform_sphere() {
        let o = chi2_sphere(
            |rng| Some(warp::uniform_sphere(rng.uniform2())),
            |_| warp::UNIFORM_SPHERE_PDF as f64,
            200_000,
            1,
            16,
            32,
        );
        assert_chi2(&o, ALPHA, "uniform sphere");
        assert_eq!(o.degrees_of_freedom, 16 * 32 - 1);
        assert_eq!(o.failed_samples, 0);
    }

    #[test]
    fn accepts_cosine_hemisphere() {
        let o = chi2_sphere(
            |rng| Some(warp::cosine_hemisphere(rng.uniform2())),
            |d| warp::cosine_hemisphere_pdf(d.z) as f64,
            200_000,
            2,
            16,
            32,
        );
        assert_chi2(&o, ALPHA, "cosine hemisphere");
        assert!((o.pdf_integral - 1.0).abs() < 1e-5, "{}", o.pdf_integral);
    }

    #[test]
    fn accepts_tilted_phong_lobe() {
        let axis = tilted_axis();
        let alpha = sidak(ALPHA, 2);
        let o = chi2_sphere(lobe_sampler(axis, 500.0), |d| lobe_pdf(d, axis, 500.0), 200_000, 3, 64, 128);
        assert_chi2(&o, alpha, "cos^500 lobe, tilted");
        assert!(o.degrees_of_freedom > 20, "{}", o.degrees_of_freedom);
        // Also at the pole, where the bins in cos θ are widest in θ.
        let o = chi2_sphere(lobe_sampler(Vec3::Z, 1000.0), |d| lobe_pdf(d, Vec3::Z, 1000.0), 200_000, 4, 256, 16);
        assert_chi2(&o, alpha, "cos^1000 lobe at the pole");
        assert!(o.degrees_of_freedom > 10, "{}", o.degrees_of_freedom);
    }

    #[test]
    fn rejects_cosine_samples_against_uniform_pdf() {
        let o = chi2_sphere(
            |rng| Some(warp::cosine_hemisphere(rng.uniform2())),
            |_| warp::UNIFORM_SPHERE_PDF as f64,
            10_000,
            5,
            8,
            16,
        );
        assert!(!o.passed(ALPHA));
        assert!(o.p_value < 1e-12, "{}", o.p_value);
        // Cosine samples against a uniform hemisphere pdf: only the shape is wrong.
        let o = chi2_sphere(
            |rng| Some(warp::cosine_hemisphere(rng.uniform2())),
            |d| if d.z > 0.0 { 0.5 / PI } else { 0.0 },
            10_000,
            6,
            8,
            16,
        );
        assert!(o.p_value < 1e-12, "{}", o.p_value);
    }

    #[test]
    fn rejects_lobe_with_wrong_exponent() {
        let axis = tilted_axis();
        let o = chi2_sphere(lobe_sampler(axis, 20.0), |d| lobe_pdf(d, axis, 22.0), 200_000, 7, 32, 64);
        assert!(o.pdf_integral < 1.0 + 1e-6);
        assert!(o.p_value < 1e-6, "p = {} (statistic {}, dof {})", o.p_value, o.statistic, o.degrees_of_freedom);
        // The right exponent passes with the same seed and bins.
        let o = chi2_sphere(lobe_sampler(axis, 20.0), |d| lobe_pdf(d, axis, 20.0), 200_000, 7, 32, 64);
        assert_chi2(&o, ALPHA, "cos^20 lobe");
    }

    fn sometimes_failing(rng: &mut Rng) -> Option<Vec3> {
        if rng.uniform() < 0.3 { None } else { Some(warp::uniform_sphere(rng.uniform2())) }
    }

    #[test]
    fn failure_cell_accepts_scaled_pdf() {
        let o = chi2_sphere(sometimes_failing, |_| 0.7 * warp::UNIFORM_SPHERE_PDF as f64, 100_000, 8, 8, 16);
        assert_chi2(&o, ALPHA, "uniform sphere failing 30% of the time");
        assert!((o.failed_samples as f64 / 100_000.0 - 0.3).abs() < 0.01);
        assert!((o.pdf_integral - 0.7).abs() < 1e-6);
    }

    #[test]
    fn failure_cell_rejects_unscaled_pdf() {
        let o = chi2_sphere(sometimes_failing, |_| warp::UNIFORM_SPHERE_PDF as f64, 100_000, 8, 8, 16);
        assert!(!o.passed(ALPHA));
        assert!(o.p_value < 1e-12);
        assert!(o.table.contains("failure cell (None): observed 29"), "{}", o.table);
        // A slightly too small scale is caught through the failure cell as well.
        let o = chi2_sphere(sometimes_failing, |_| 0.65 * warp::UNIFORM_SPHERE_PDF as f64, 100_000, 8, 8, 16);
        assert!(o.p_value < 1e-12, "{}", o.p_value);
    }

    #[test]
    #[should_panic(expected = "the pdf integrates to 1.1")]
    fn assert_chi2_rejects_pdf_integrating_above_one() {
        // Even with no samples at all to contradict it.
        let o = chi2_sphere(|_| None, |_| 1.1 * warp::UNIFORM_SPHERE_PDF as f64, 0, 9, 8, 16);
        assert_chi2(&o, ALPHA, "overweight pdf");
    }

    #[test]
    #[should_panic(expected = "chi-square test of cosine vs uniform FAILED")]
    fn assert_chi2_panics_with_a_message() {
        let o = chi2_sphere(
            |rng| Some(warp::cosine_hemisphere(rng.uniform2())),
            |_| warp::UNIFORM_SPHERE_PDF as f64,
            10_000,
            5,
            8,
            16,
        );
        assert_chi2(&o, ALPHA, "cosine vs uniform");
    }

    #[test]
    fn invalid_directions_fail() {
        let o = chi2_sphere(
            |rng| Some(2.0 * warp::uniform_sphere(rng.uniform2())),
            |_| warp::UNIFORM_SPHERE_PDF as f64,
            1000,
            10,
            4,
            8,
        );
        assert_eq!(o.invalid_samples, 1000);
        assert!(!o.passed(ALPHA));
    }

    #[test]
    fn accepts_uniform_triangle() {
        let o = chi2_square(
            |rng| {
                let b = warp::uniform_triangle(rng.uniform2());
                Some([b.x as f64, b.y as f64])
            },
            |p| if p[0] + p[1] <= 1.0 { 2.0 } else { 0.0 },
            100_000,
            11,
            16,
        );
        assert_chi2(&o, ALPHA, "uniform triangle");
        assert!((o.pdf_integral - 1.0).abs() < 1e-4, "{}", o.pdf_integral);
    }

    #[test]
    fn square_accepts_and_rejects_simple_densities() {
        // x = sqrt(u), y = sqrt(v) has density 4xy.
        let sampler = |rng: &mut Rng| {
            let [u, v] = rng.uniform2();
            Some([(u as f64).sqrt(), (v as f64).sqrt()])
        };
        let o = chi2_square(sampler, |p| 4.0 * p[0] * p[1], 100_000, 12, 16);
        assert_chi2(&o, ALPHA, "4xy");
        let o = chi2_square(sampler, |_| 1.0, 100_000, 12, 16);
        assert!(o.p_value < 1e-12, "{}", o.p_value);
        // A subtly wrong density: samples of 4xy against 6x²y.
        let o = chi2_square(sampler, |p| 6.0 * p[0] * p[0] * p[1], 100_000, 12, 16);
        assert!(o.p_value < 1e-12, "{}", o.p_value);
        // Points outside the square are invalid.
        let o = chi2_square(|rng| Some([rng.uniform() as f64 + 1.5, 0.5]), |_| 1.0, 100, 12, 4);
        assert_eq!(o.invalid_samples, 100);
        assert!(!o.passed(ALPHA));
    }

    #[test]
    fn pooling_merges_small_cells() {
        // Expected 2 per cell in 10 cells → one pooled cell of 20; 100 cells of 10.
        let mut observed = vec![10u64; 100];
        let mut expected = vec![10.0; 100];
        observed.extend([2u64; 10]);
        expected.extend([2.0; 10]);
        let c = pooled_chi2(&observed, &expected);
        assert_eq!(c.dof, 100);
        assert_eq!(c.pooled_cells, 10);
        assert_eq!(c.statistic, 0.0);
        assert!((c.p_value - 1.0).abs() < 1e-12);

        // A pool too small to stand alone is merged into the smallest cell.
        let c = pooled_chi2(&[10, 20, 1], &[10.0, 20.0, 1.0]);
        assert_eq!(c.dof, 1);
        assert_eq!(c.pooled_cells, 1);

        // Everything empty: nothing to test.
        let c = pooled_chi2(&[0, 0], &[0.0, 0.0]);
        assert_eq!(c.dof, 0);
        assert_eq!(c.p_value, 1.0);

        // A sample where nothing is expected is a hard failure.
        let c = pooled_chi2(&[10, 1], &[11.0, 0.0]);
        assert_eq!(c.p_value, 0.0);
    }
}
