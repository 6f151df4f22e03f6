//! Error metrics between a test image `A` and a reference image `B` (`vcm compare`, the Python
//! module's `vcm.compare`, `vcm report`), and the per-entry Z-test ([`ztest`]).
//!
//! Both images must have the same size. With `N` the number of compared pixels and the sums
//! running over those pixels and their three channels (`3N` entries), values taken in `f64`:
//!
//! - **RMSE** = `sqrt(Σ (a − b)² / 3N)`.
//! - **relative MSE** = `Σ (a − b)² / (b² + ε) / 3N` with `ε = 1e-2` ([`RELATIVE_MSE_EPSILON`]):
//!   the usual rMSE of rendering papers, where `ε` keeps near-black reference pixels from
//!   dominating.
//! - **MAE** (mean absolute error) = `Σ |a − b| / 3N`.
//! - **means**: the per-channel means of `A` and `B` over the compared pixels, their difference
//!   `A − B` and the relative difference `(A − B) / B` in percent.
//!
//! A pixel with a non-finite value (NaN or ±∞) in any channel of either image — or of either
//! variance image, when given — is excluded from every metric; such pixels are counted and
//! reported. It is an error when no pixel is left.
//!
//! **Per-pixel Z-test** (only when both `--variance-a` and `--variance-b` are given: images of
//! the same size holding the variance of the per-pixel mean estimate of each channel). For every
//! compared entry, `z = (a − b) / sqrt(v)` with the combined variance
//! `v = max(var_a + var_b, (f · max(|a|, |b|))²)` (negative variances are treated as 0) and the
//! two-sided p-value `p = erfc(|z| / √2)`.
//!
//! The **variance floor** `f` ([`RELATIVE_FLOOR`] = 1e-3 by default, `--relative-floor`) is for
//! entries that are deterministic in both images, e.g. a constant background seen by every
//! sample: their variances are 0, so without the floor any rounding difference between two
//! renderers (f32 arithmetic, half-float EXR storage with its relative step 2⁻¹¹ ≈ 4.9e-4) gives
//! `z = ±∞` and fails the test. With it, such an entry fails only when it differs by more than
//! about `z* · f` of its value, where `z*` is the Šidák-corrected critical value (5.3 for 10⁵
//! entries at `α = 1e-3`: 0.5 %, so a 1 % difference still fails). The floor never matters where
//! the images' own noise is larger than `f` of the value. When `a == b` (also both 0) `z = 0`;
//! a difference between two zero-variance zeros and something else of the same tiny size is
//! still `±∞` (the floor of 0 is 0). An entry fails when `p` is below the Šidák-corrected level
//! `1 − (1 − α)^(1/3N)`, which keeps the family-wise false-alarm rate at `α` over all `3N`
//! entries; the test passes when no entry fails.
//!

pub mod ztest;

use anyhow::{Result, bail, ensure};

/// The `ε` in the relative MSE's denominator `b² + ε`.
pub const RELATIVE_MSE_EPSILON: f64 = 1e-2;

pub use crate::ztest::RELATIVE_FLOOR;
use crate::ztest::{sidak, two_sided_p, z_score};

/// The metrics of a comparison (see the module documentation for the definitions).
#[derive(Debug, Clone, PartialEq)]
pub struct Metrics {
    /// Number of compared pixels (non-finite ones excluded).
    pub pixels: usize,
    /// Root-mean-square error over all compared pixel channels.
    pub rmse: f64,
    /// Mean of `(a − b)² / (b² + 1e-2)` over all compared pixel channels.
    pub relative_mse: f64,
    /// Mean of `|a − b|` over all compared pixel channels.
    pub mean_absolute_error: f64,
    /// Per-channel means of A over the compared pixels.
    pub means_a: [f64; 3],
    /// Per-channel means of B over the compared pixels.
    pub means_b: [f64; 3],
    /// Number of pixels excluded because a channel of an input is NaN or infinite.
    pub non_finite: usize,
    /// The per-pixel Z-test, when variances were given.
    pub z_test: Option<ZTest>,
}

/// The outcome of the per-pixel Z-test.
#[derive(Debug, Clone, PartialEq)]
pub struct ZTest {
    /// Number of tested entries (compared pixels × 3 channels).
    pub entries: usize,
    /// Signed z score `(a − b) / sqrt(var_a + var_b)` of the entry with the largest `|z|`.
    pub worst_z: f64,
    /// Pixel `(x, y)` of the worst entry (row 0 at the top).
    pub worst_pixel: (usize, usize),
    /// Channel (0 = R, 1 = G, 2 = B) of the worst entry.
    pub worst_channel: usize,
    /// Šidák-corrected per-entry significance level: an entry fails when its p-value is below.
    pub threshold_p: f64,
    /// Number of failing entries.
    pub failing: usize,
    /// Whether no entry failed.
    pub passed: bool,
}

/// Computes the metrics of test image `a` against reference `b`, with the per-pixel Z-test at
/// family-wise level `alpha` when `variance` (of A, of B) is given, with the default variance
/// floor [`RELATIVE_FLOOR`].
///
/// Errors if the sizes differ, an image's pixel buffer does not match its size, `alpha` is not
/// in (0, 1) while variances are given, or no pixel is finite in every input.
pub fn metrics(
    a: &io::Image,
    b: &io::Image,
    variance: Option<(&io::Image, &io::Image)>,
    alpha: f64,
) -> Result<Metrics> {
    metrics_with_floor(a, b, variance, alpha, RELATIVE_FLOOR)
}

/// [`metrics`] with the Z-test's variance floor `relative_floor` (a fraction of the value, ≥ 0;
/// see the module documentation). Errors also when `relative_floor` is negative or not finite.
pub fn metrics_with_floor(
    a: &io::Image,
    b: &io::Image,
    variance: Option<(&io::Image, &io::Image)>,
    alpha: f64,
    relative_floor: f64,
) -> Result<Metrics> {
    ensure!(
        relative_floor.is_finite() && relative_floor >= 0.0,
        "the Z-test's relative variance floor must be a non-negative number, got {relative_floor}"
    );
    check_shape("A", a)?;
    check_shape("B", b)?;
    ensure!(
        (a.width, a.height) == (b.width, b.height),
        "image sizes differ: A is {}x{}, B is {}x{}",
        a.width,
        a.height,
        b.width,
        b.height
    );
    if let Some((va, vb)) = variance {
        for (name, v) in [("variance of A", va), ("variance of B", vb)] {
            check_shape(name, v)?;
            ensure!(
                (v.width, v.height) == (a.width, a.height),
                "image sizes differ: the {name} is {}x{}, the images are {}x{}",
                v.width,
                v.height,
                a.width,
                a.height
            );
        }
        ensure!(alpha > 0.0 && alpha < 1.0, "the Z-test significance alpha must be in (0, 1), got {alpha}");
    }

    let mut pixels = 0usize;
    let mut non_finite = 0usize;
    let mut squared = 0.0f64;
    let mut relative = 0.0f64;
    let mut absolute = 0.0f64;
    let mut sum_a = [0.0f64; 3];
    let mut sum_b = [0.0f64; 3];
    // (|z|, signed z, pixel index, channel) of the worst entry, and the |z| of every entry.
    let mut worst: Option<(f64, f64, usize, usize)> = None;
    let mut abs_z = Vec::new();
    for (index, (pa, pb)) in a.pixels.iter().zip(&b.pixels).enumerate() {
        let vars = variance.map(|(va, vb)| (va.pixels[index], vb.pixels[index]));
        let finite = |p: &[f32; 3]| p.iter().all(|v| v.is_finite());
        if !(finite(pa) && finite(pb) && vars.is_none_or(|(va, vb)| finite(&va) && finite(&vb))) {
            non_finite += 1;
            continue;
        }
        pixels += 1;
        for c in 0..3 {
            let (x, y) = (f64::from(pa[c]), f64::from(pb[c]));
            let d = x - y;
            squared += d * d;
            relative += d * d / (y * y + RELATIVE_MSE_EPSILON);
            absolute += d.abs();
            sum_a[c] += x;
            sum_b[c] += y;
            if let Some((va, vb)) = vars {
                let z = z_score(x, y, f64::from(va[c]), f64::from(vb[c]), relative_floor);
                abs_z.push(z.abs());
                if worst.is_none_or(|(w, ..)| z.abs() > w) {
                    worst = Some((z.abs(), z, index, c));
                }
            }
        }
    }
    if pixels == 0 {
        bail!("no pixel to compare: all {non_finite} pixels have a non-finite value");
    }
    let entries = 3 * pixels;
    let n = entries as f64;
    let z_test = worst.map(|(_, worst_z, index, channel)| {
        let threshold_p = sidak(alpha, entries);
        let failing = abs_z.iter().filter(|&&z| two_sided_p(z) < threshold_p).count();
        ZTest {
            entries,
            worst_z,
            worst_pixel: (index % a.width, index / a.width),
            worst_channel: channel,
            threshold_p,
            failing,
            passed: failing == 0,
        }
    });
    Ok(Metrics {
        pixels,
        rmse: (squared / n).sqrt(),
        relative_mse: relative / n,
        mean_absolute_error: absolute / n,
        means_a: sum_a.map(|s| s / pixels as f64),
        means_b: sum_b.map(|s| s / pixels as f64),
        non_finite,
        z_test,
    })
}

/// Errors unless `image`'s pixel buffer matches its non-zero size.
fn check_shape(name: &str, image: &io::Image) -> Result<()> {
    ensure!(
        image.width > 0 && image.height > 0 && image.width.checked_mul(image.height) == Some(image.pixels.len()),
        "{name} is {}x{} but has {} pixels",
        image.width,
        image.height,
        image.pixels.len()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(width: usize, height: usize, f: impl FnMut(usize, usize) -> [f32; 3]) -> io::Image {
        io::Image::from_fn(width, height, f)
    }

    fn gradient() -> io::Image {
        image(5, 4, |x, y| [0.1 * x as f32, 0.25 * y as f32, 0.5 + 0.05 * (x + y) as f32])
    }

    fn offset(a: &io::Image, by: f32) -> io::Image {
        io::Image { pixels: a.pixels.iter().map(|p| p.map(|v| v + by)).collect(), ..a.clone() }
    }

    fn constant(like: &io::Image, value: f32) -> io::Image {
        image(like.width, like.height, |_, _| [value; 3])
    }

    #[test]
    fn identical_images_give_zero() {
        let a = gradient();
        let m = metrics(&a, &a, None, 1e-3).unwrap();
        assert_eq!(m.pixels, 20);
        assert_eq!(m.non_finite, 0);
        assert_eq!((m.rmse, m.relative_mse, m.mean_absolute_error), (0.0, 0.0, 0.0));
        assert_eq!(m.means_a, m.means_b);
        assert_eq!(m.means_a, a.channel_means());
        assert!(m.z_test.is_none());
    }

    #[test]
    fn constant_offset_gives_the_known_numbers() {
        let a = gradient();
        let b = offset(&a, 0.1);
        let m = metrics(&a, &b, None, 1e-3).unwrap();
        assert!((m.rmse - 0.1).abs() < 1e-6, "{}", m.rmse);
        assert!((m.mean_absolute_error - 0.1).abs() < 1e-6, "{}", m.mean_absolute_error);
        for c in 0..3 {
            assert!((m.means_b[c] - m.means_a[c] - 0.1).abs() < 1e-6);
        }
        // Closed form: mean over entries of 0.1² / (b² + 0.01).
        let values: Vec<f64> = b.pixels.iter().flatten().map(|&v| f64::from(v)).collect();
        let expected = values.iter().map(|v| 0.01 / (v * v + 0.01)).sum::<f64>() / values.len() as f64;
        assert!((m.relative_mse - expected).abs() < 1e-6 * expected, "{} vs {expected}", m.relative_mse);
        // A single known value: a = 0, b = 0.1 everywhere gives 0.01 / 0.02 = 0.5.
        let zero = constant(&a, 0.0);
        let m = metrics(&zero, &constant(&a, 0.1), None, 1e-3).unwrap();
        assert!((m.relative_mse - 0.5).abs() < 1e-6, "{}", m.relative_mse);
        assert!((m.rmse - 0.1).abs() < 1e-6);
    }

    #[test]
    fn size_mismatch_is_an_error_naming_both_sizes() {
        let error = metrics(&gradient(), &image(4, 5, |_, _| [0.0; 3]), None, 1e-3).unwrap_err().to_string();
        assert!(error.contains("5x4") && error.contains("4x5"), "{error}");
    }

    #[test]
    fn non_finite_pixels_are_counted_and_excluded() {
        let a = gradient();
        let mut b = a.clone();
        b.set(2, 1, [f32::NAN, 0.0, 0.0]);
        b.set(3, 3, [0.0, f32::INFINITY, 0.0]);
        let m = metrics(&a, &b, None, 1e-3).unwrap();
        assert_eq!((m.pixels, m.non_finite), (18, 2));
        assert_eq!((m.rmse, m.relative_mse, m.mean_absolute_error), (0.0, 0.0, 0.0));
        assert!(m.means_a.iter().all(|v| v.is_finite()));
        assert_eq!(m.means_a, m.means_b);

        let all_nan = constant(&a, f32::NAN);
        let error = metrics(&a, &all_nan, None, 1e-3).unwrap_err().to_string();
        assert!(error.contains("no pixel"), "{error}");
    }

    #[test]
    fn z_test_fails_an_offset_and_passes_identical_images() {
        let a = gradient();
        let variance = constant(&a, 1e-6);
        let m = metrics(&a, &a, Some((&variance, &variance)), 1e-3).unwrap();
        let z = m.z_test.unwrap();
        assert_eq!((z.entries, z.failing, z.worst_z), (60, 0, 0.0));
        assert!(z.passed);
        assert!((z.threshold_p - sidak(1e-3, 60)).abs() < 1e-15);

        let mut b = a.clone();
        b.set(3, 2, [a.get(3, 2)[0], a.get(3, 2)[1] - 0.01, a.get(3, 2)[2]]);
        let m = metrics(&b, &a, Some((&variance, &variance)), 1e-3).unwrap();
        let z = m.z_test.unwrap();
        assert!(!z.passed);
        assert_eq!(z.failing, 1);
        assert_eq!((z.worst_pixel, z.worst_channel), ((3, 2), 1));
        // z = -0.01 / sqrt(2e-6) ≈ -7.07 (up to f32 rounding of the pixel values).
        assert!((z.worst_z + 0.01 / 2e-6f64.sqrt()).abs() < 1e-3, "{}", z.worst_z);

        // An offset comparable to the noise passes: z = 0.001 / sqrt(2e-6) ≈ 0.71.
        let m = metrics(&offset(&a, 0.001), &a, Some((&variance, &variance)), 1e-3).unwrap();
        assert!(m.z_test.unwrap().passed);

        // A size mismatch of a variance image is an error.
        let small = image(2, 2, |_, _| [0.0; 3]);
        assert!(metrics(&a, &a, Some((&small, &variance)), 1e-3).is_err());
    }

    #[test]
    fn zero_variance_without_a_floor_fails_any_difference() {
        let a = gradient();
        let zero = constant(&a, 0.0);
        let z = metrics_with_floor(&a, &a, Some((&zero, &zero)), 1e-3, 0.0).unwrap().z_test.unwrap();
        assert!(z.passed);
        let z = metrics_with_floor(&offset(&a, 1e-3), &a, Some((&zero, &zero)), 1e-3, 0.0).unwrap().z_test.unwrap();
        assert!(!z.passed && z.worst_z.is_infinite());
        assert!(metrics_with_floor(&a, &a, Some((&zero, &zero)), 1e-3, -1.0).is_err());
    }

    /// Scales every value of `image` by `factor`.
    fn scaled(image: &io::Image, factor: f32) -> io::Image {
        io::Image { pixels: image.pixels.iter().map(|p| p.map(|v| v * factor)).collect(), ..image.clone() }
    }

    #[test]
    fn zero_variance_entries_get_a_floor_relative_to_their_value() {
        // A deterministic image (zero variance everywhere) against itself changed by rounding
        // (one half-float step, 2⁻¹¹ relative) passes; the same image 1 % brighter fails every
        // non-zero entry, at z = 0.01 / (1.01 · 1e-3) ≈ 9.9.
        let a = image(30, 20, |x, y| [0.2 + 0.01 * x as f32, 0.5 + 0.02 * y as f32, 3.0]);
        let zero = constant(&a, 0.0);
        let rounded = scaled(&a, 1.0 + 2f32.powi(-11));
        let z = metrics(&rounded, &a, Some((&zero, &zero)), 1e-3).unwrap().z_test.unwrap();
        assert!(z.passed && z.failing == 0, "{z:?}");
        assert!(z.worst_z > 0.45 && z.worst_z < 0.5, "{z:?}");
        let brighter = scaled(&a, 1.01);
        let z = metrics(&brighter, &a, Some((&zero, &zero)), 1e-3).unwrap().z_test.unwrap();
        assert!(!z.passed && z.failing == 1800, "{z:?}");
        assert!((z.worst_z - 0.01 / 1.01e-3).abs() < 1e-3, "{z:?}");
        // Where the images' own variance exceeds the floor, the floor changes nothing: z of a
        // 1e-3 offset on variances 1e-6 is 1e-3 / √2e-6 ≈ 0.707 for every entry whose value is
        // below √2e-6 / 1e-3 ≈ 1.41 (the blue channel, 3.0, is limited by the floor: 0.33).
        let v = constant(&a, 1e-6);
        let z = metrics(&offset(&a, 1e-3), &a, Some((&v, &v)), 1e-3).unwrap().z_test.unwrap();
        assert!((z.worst_z - 1e-3 / 2e-6f64.sqrt()).abs() < 1e-3, "{z:?}");
    }
}
