//! The pass/fail rule of `vcm conformance`, after Mitsuba 3's render tests: a per-entry
//! (pixel channel) Z-test with a Šidák correction, a minimum fraction of passing entries, and
//! the image means. Pure functions on images; rendering and files live in the runner.
//!
//! For every entry, `z = (a − b) / sqrt(var_a + var_b)` with both variances those of the pixel
//! mean, with the variance floor of `vcm compare` ([`crate::ztest::z_score`]) for entries whose
//! variances are both 0; its two-sided p-value passes when it is at least the Šidák level
//! `1 − (1 − α)^(1/n)` over the `n` tested entries. The verdict is PASS iff at least
//! [`Criteria::pass_fraction`] of the entries pass **and** every channel's image mean agrees
//! with the reference's: within [`Criteria::mean_tolerance`] (relative), or, where the image
//! means themselves are noisier than that, within the noise — the difference's two-sided
//! p-value against its standard error `σ = sqrt(Σ var_a + Σ var_b) / n_pixels` (from the same
//! variance images) at least the Šidák level of [`Criteria::mean_alpha`] over the 3 channels
//! (|Δ| ≤ 2.94 σ at 1 %). A fixed 1 % band narrower than the noise of the image means fails
//! correct renders: on Mitsuba's `bsdf_spheres/test_pointlight` at its budget (868 spp) the
//! image mean's relative standard error is 1.5–2 %, and Mitsuba's own path tracer misses the
//! 1 % band on some seeds (docs/lights-suite.md). Where σ is below the 1 % band, as on most
//! scenes, the band decides.
//!
//! An entry whose reference value or reference variance is not finite is left out (counted); an
//! entry whose test value or variance is not finite fails, and makes that channel's mean
//! non-finite, which fails the mean check.

use anyhow::{Result, ensure};

use crate::ztest::{sidak, two_sided_p, z_score};

/// The thresholds of the verdict.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Criteria {
    /// Family-wise significance of the per-entry Z-test (Šidák-corrected over all entries).
    pub alpha: f64,
    /// Fraction of entries that must pass, in [0, 1].
    pub pass_fraction: f64,
    /// Largest relative difference `|mean_a / mean_b − 1|` of a channel's image mean.
    pub mean_tolerance: f64,
    /// Variance floor relative to the value, for zero-variance entries (see `vcm compare`).
    pub relative_floor: f64,
    /// Family-wise significance (Šidák over the 3 channels) of the image means' agreement
    /// within their noise, when it exceeds `mean_tolerance`.
    pub mean_alpha: f64,
}

impl Criteria {
    /// Mitsuba 3's render-test rule (α = 0.01, 99.75 % of the entries) plus the 1 % mean check,
    /// with `vcm compare`'s default variance floor.
    pub const MITSUBA: Criteria = Criteria {
        alpha: 0.01,
        pass_fraction: 0.9975,
        mean_tolerance: 0.01,
        relative_floor: crate::ztest::RELATIVE_FLOOR,
        mean_alpha: 0.01,
    };
}

/// The outcome of comparing a render with a reference.
#[derive(Clone, Debug, PartialEq)]
pub struct Verdict {
    /// Tested entries (pixel channels with a finite reference).
    pub entries: usize,
    /// Entries whose p-value is at least the Šidák level.
    pub passing: usize,
    /// Entries left out because the reference or its variance is not finite.
    pub excluded: usize,
    /// Šidák-corrected per-entry level.
    pub threshold_p: f64,
    /// Per-channel image means of the render over the tested pixels.
    pub means_test: [f64; 3],
    /// Per-channel image means of the reference over the tested pixels.
    pub means_reference: [f64; 3],
    /// Per channel, the standard error of `means_test − means_reference` from the variance
    /// images.
    pub mean_errors: [f64; 3],
    /// Whether both conditions hold.
    pub passed: bool,
}

impl Verdict {
    /// `passing / entries` (0 when nothing was tested).
    pub fn pass_fraction(&self) -> f64 {
        if self.entries == 0 { 0.0 } else { self.passing as f64 / self.entries as f64 }
    }

    /// The channel ratio `mean_test / mean_reference` farthest from 1 (NaN if a mean is NaN;
    /// ±∞ when a reference mean is 0 and the render's is not; 1 when both are 0).
    pub fn worst_mean_ratio(&self) -> f64 {
        let ratios = (0..3).map(|c| {
            let (a, b) = (self.means_test[c], self.means_reference[c]);
            if a == b { 1.0 } else { a / b }
        });
        ratios.fold(1.0, |worst, r| if r.is_nan() || (r - 1.0).abs() > (worst - 1.0).abs() { r } else { worst })
    }

    /// The largest relative standard error of a channel's mean difference, `σ_c / mean_ref_c`
    /// (∞ when a reference mean is 0 and its σ is not).
    pub fn largest_mean_error(&self) -> f64 {
        (0..3)
            .map(|c| {
                let (sigma, b) = (self.mean_errors[c], self.means_reference[c].abs());
                if sigma == 0.0 { 0.0 } else { sigma / b }
            })
            .fold(0.0, f64::max)
    }
}

/// Judges `test` (with the variance of its pixel means `test_variance`) against `reference`
/// (with `reference_variance`, also of the pixel means) by `criteria`. Errors when the four
/// images do not have the same size, or no entry is tested.
pub fn judge(
    test: &io::Image,
    test_variance: &io::Image,
    reference: &io::Image,
    reference_variance: &io::Image,
    criteria: &Criteria,
) -> Result<Verdict> {
    let size = (reference.width, reference.height);
    for (name, image) in
        [("render", test), ("render's variance", test_variance), ("reference variance", reference_variance)]
    {
        ensure!(
            (image.width, image.height) == size && image.pixels.len() == size.0 * size.1,
            "the {name} is {}x{}, the reference {}x{}",
            image.width,
            image.height,
            size.0,
            size.1
        );
    }
    ensure!(reference.pixels.len() == size.0 * size.1, "the reference's pixel buffer does not match its size");

    let mut excluded = 0usize;
    let mut scores = Vec::with_capacity(3 * reference.pixels.len());
    let mut sums = [[0.0f64; 3]; 2];
    let mut variances = [0.0f64; 3];
    let mut counted = [0usize; 3];
    for index in 0..reference.pixels.len() {
        for c in 0..3 {
            let b = f64::from(reference.pixels[index][c]);
            let var_b = f64::from(reference_variance.pixels[index][c]);
            if !(b.is_finite() && var_b.is_finite()) {
                excluded += 1;
                continue;
            }
            let a = f64::from(test.pixels[index][c]);
            let var_a = f64::from(test_variance.pixels[index][c]);
            sums[0][c] += a;
            sums[1][c] += b;
            variances[c] += var_a + var_b;
            counted[c] += 1;
            // A non-finite render value or variance fails its entry.
            let z = if a.is_finite() && var_a.is_finite() {
                z_score(a, b, var_a, var_b, criteria.relative_floor)
            } else {
                f64::INFINITY
            };
            scores.push(z.abs());
        }
    }
    let entries = scores.len();
    ensure!(entries > 0, "no pixel channel to compare: the reference has no finite value");
    let threshold_p = sidak(criteria.alpha, entries);
    let passing = scores.iter().filter(|&&z| two_sided_p(z) >= threshold_p).count();
    let mean = |sum: f64, count: usize| if count == 0 { 0.0 } else { sum / count as f64 };
    let means_test = std::array::from_fn(|c| mean(sums[0][c], counted[c]));
    let means_reference = std::array::from_fn(|c| mean(sums[1][c], counted[c]));
    let mean_errors: [f64; 3] =
        std::array::from_fn(|c| if counted[c] == 0 { 0.0 } else { variances[c].sqrt() / counted[c] as f64 });
    let mean_level = sidak(criteria.mean_alpha, 3);
    let means_agree = (0..3).all(|c| {
        let (a, b): (f64, f64) = (means_test[c], means_reference[c]);
        let within_band = (a - b).abs() <= criteria.mean_tolerance * b.abs();
        let within_noise = mean_errors[c] > 0.0 && two_sided_p((a - b).abs() / mean_errors[c]) >= mean_level;
        within_band || within_noise
    });
    let fraction_ok = passing as f64 >= criteria.pass_fraction * entries as f64;
    Ok(Verdict {
        entries,
        passing,
        excluded,
        threshold_p,
        means_test,
        means_reference,
        mean_errors,
        passed: fraction_ok && means_agree,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use math::Rng;

    /// A smooth test pattern in (0.2, 1.2).
    fn truth(x: usize, y: usize, c: usize) -> f64 {
        0.7 + 0.5 * ((0.11 * x as f64 + 0.07 * y as f64 + c as f64).sin())
    }

    /// The mean of `samples` Gaussian samples with standard deviation `sigma · truth` around
    /// `scale · truth` per entry (the sample mean is drawn directly: normal with variance
    /// σ²/n), and the estimated variance of that mean (its true value, as from many
    /// iterations).
    fn render(rng: &mut Rng, size: usize, scale: f64, sigma: f64, samples: f64) -> (io::Image, io::Image) {
        let mut image = io::Image::new(size, size);
        let mut variance = io::Image::new(size, size);
        for y in 0..size {
            for x in 0..size {
                let mut value = [0.0f32; 3];
                let mut var = [0.0f32; 3];
                for c in 0..3 {
                    let t = truth(x, y, c);
                    let sd = sigma * t / samples.sqrt();
                    value[c] = (scale * t + sd * normal(rng)) as f32;
                    var[c] = (sd * sd) as f32;
                }
                image.set(x, y, value);
                variance.set(x, y, var);
            }
        }
        (image, variance)
    }

    /// A standard normal sample (Box–Muller).
    fn normal(rng: &mut Rng) -> f64 {
        let u1 = 1.0 - f64::from(rng.uniform());
        let u2 = f64::from(rng.uniform());
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }

    #[test]
    fn equal_distributions_pass() {
        // 10 seeds of 64x64 images (12288 entries each): the expected number of failing
        // entries per image is α = 0.01 in total, far below the 0.25 % (31) allowed.
        for seed in 0..10 {
            let mut rng = Rng::for_stream(seed, 0, 0);
            let (a, va) = render(&mut rng, 64, 1.0, 0.5, 256.0);
            let (b, vb) = render(&mut rng, 64, 1.0, 0.5, 32000.0);
            let v = judge(&a, &va, &b, &vb, &Criteria::MITSUBA).unwrap();
            assert!(v.passed, "seed {seed}: {v:?}");
            assert!(v.passing + 2 >= v.entries, "seed {seed}: {v:?}");
            assert!((v.worst_mean_ratio() - 1.0).abs() < 0.002, "{v:?}");
        }
    }

    #[test]
    fn a_two_percent_bias_fails() {
        // With the combined standard error sqrt(0.5² / 4096 + 0.5² / 32000) t ≈ 0.0083 t, a
        // 2 % bias shifts every z by about 2.4: the Šidák critical value for 12288 entries at
        // α = 0.01 is about 4.9, so few entries fail one by one; the mean check (1 %) catches
        // it.
        let mut rng = Rng::for_stream(7, 0, 0);
        let (a, va) = render(&mut rng, 64, 1.02, 0.5, 4096.0);
        let (b, vb) = render(&mut rng, 64, 1.0, 0.5, 32000.0);
        let v = judge(&a, &va, &b, &vb, &Criteria::MITSUBA).unwrap();
        assert!(!v.passed, "{v:?}");
        assert!((v.worst_mean_ratio() - 1.02).abs() < 0.002, "{v:?}");
        // With the same bias at 64 times the samples (standard error ≈ 0.0030 t, limited by
        // the reference's), z ≈ 6.8 and P(|z| < 4.9) ≈ 3 %: the verdict fails by the Z-test
        // alone, with the mean check switched off.
        let (a, va) = render(&mut rng, 64, 1.02, 0.5, 262_144.0);
        let lenient = Criteria { mean_tolerance: f64::INFINITY, ..Criteria::MITSUBA };
        let v = judge(&a, &va, &b, &vb, &lenient).unwrap();
        assert!(!v.passed && v.pass_fraction() < 0.1, "{v:?}");
        // The same render without bias passes.
        let (a, va) = render(&mut rng, 64, 1.0, 0.5, 262_144.0);
        assert!(judge(&a, &va, &b, &vb, &Criteria::MITSUBA).unwrap().passed);
    }

    #[test]
    fn noisy_image_means_are_judged_within_their_noise_and_quiet_ones_by_the_band() {
        // Per-pixel σ = 1.28 t: over 4096 pixels the image mean's relative standard error is
        // 2 %, as on Mitsuba's point-light sphere scene. A 3 % offset is 1.5 σ: not a bias this
        // budget can see, so it passes (the 1 % band alone would fail it).
        let mut rng = Rng::for_stream(11, 0, 0);
        let (b, vb) = render(&mut rng, 64, 1.0, 0.5, 32000.0);
        let (mut a, va) = render(&mut rng, 64, 1.0, 1.28, 1.0);
        // Shift the noisy render's mean to exactly 1.03 × the reference's, per channel.
        let shift: [f32; 3] = std::array::from_fn(|c| {
            let mean = |image: &io::Image| image.pixels.iter().map(|p| f64::from(p[c])).sum::<f64>() / 4096.0;
            (1.03 * mean(&b) - mean(&a)) as f32
        });
        for p in &mut a.pixels {
            for c in 0..3 {
                p[c] += shift[c];
            }
        }
        let v = judge(&a, &va, &b, &vb, &Criteria::MITSUBA).unwrap();
        assert!((v.worst_mean_ratio() - 1.03).abs() < 1e-3 && (v.largest_mean_error() - 0.02).abs() < 0.003, "{v:?}");
        assert!(v.passed, "{v:?}");
        let band_only = Criteria { mean_alpha: 1.0, ..Criteria::MITSUBA };
        assert!(!judge(&a, &va, &b, &vb, &band_only).unwrap().passed);
        // The same 3 % offset judged with variances 7 times smaller (σ ≈ 0.85 %, as 7 times
        // the samples would give): 3.5 σ, a bias the budget can see, fails.
        let quieter = io::Image { pixels: va.pixels.iter().map(|p| p.map(|v| v / 7.0)).collect(), ..va.clone() };
        let v = judge(&a, &quieter, &b, &vb, &lenient_fraction()).unwrap();
        assert!(v.largest_mean_error() < 0.009 && !v.passed, "{v:?}");
    }

    /// The rule with the entry fraction switched off (for tests of the mean check alone).
    fn lenient_fraction() -> Criteria {
        Criteria { pass_fraction: 0.0, ..Criteria::MITSUBA }
    }

    #[test]
    fn a_zero_variance_equal_background_passes_and_a_brighter_one_fails() {
        // A constant background rendered deterministically by both (zero variance), equal up
        // to half-float rounding (2⁻¹¹ relative): every entry passes by the variance floor.
        let b = io::Image::from_fn(32, 32, |_, _| [0.25, 0.5, 1.0]);
        let zero = io::Image::new(32, 32);
        let a =
            io::Image { pixels: b.pixels.iter().map(|p| p.map(|v| v * (1.0 + 2f32.powi(-11)))).collect(), ..b.clone() };
        let v = judge(&a, &zero, &b, &zero, &Criteria::MITSUBA).unwrap();
        assert!(v.passed && v.passing == v.entries, "{v:?}");
        // 1 % brighter: z = 0.01 / 1.01e-3 ≈ 9.9 for every entry.
        let brighter = io::Image { pixels: b.pixels.iter().map(|p| p.map(|v| v * 1.01)).collect(), ..b.clone() };
        let lenient = Criteria { mean_tolerance: f64::INFINITY, ..Criteria::MITSUBA };
        let v = judge(&brighter, &zero, &b, &zero, &lenient).unwrap();
        assert!(!v.passed && v.passing == 0, "{v:?}");
    }

    #[test]
    fn non_finite_values_fail_or_are_excluded() {
        let b = io::Image::from_fn(8, 8, |_, _| [0.5; 3]);
        let zero = io::Image::new(8, 8);
        let mut a = b.clone();
        a.set(1, 1, [f32::NAN, 0.5, 0.5]);
        let v = judge(&a, &zero, &b, &zero, &Criteria::MITSUBA).unwrap();
        assert_eq!((v.entries, v.passing), (192, 191));
        assert!(!v.passed && v.worst_mean_ratio().is_nan(), "{v:?}");
        let mut reference = b.clone();
        reference.set(2, 2, [f32::INFINITY; 3]);
        let v = judge(&b, &zero, &reference, &zero, &Criteria::MITSUBA).unwrap();
        assert_eq!((v.entries, v.excluded), (189, 3));
        assert!(v.passed);
        assert!(judge(&io::Image::new(4, 4), &zero, &b, &zero, &Criteria::MITSUBA).is_err());
    }
}
