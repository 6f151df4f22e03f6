//! `vcm compare A B`: error metrics between a test image `A` and a reference image `B`.
//!
//! The metrics and the Z-test are [`image_metrics`]'s (its documentation defines them); this
//! module reads the files, prints the table, applies `--threshold` and writes the difference
//! image.
//!
//! **Exit code**: 0 normally; 1 when `--threshold` is given and the relative MSE exceeds it, or
//! when the Z-test fails. Errors (unreadable files, size mismatches, bad options) are returned
//! to the caller.
//!
//! **Difference image** (`--diff FILE`): for every pixel the signed difference `d` of the
//! channel means of `A` and `B`; red where `d > 0` (A brighter), blue where `d < 0`, with
//! linear intensity `|d| / s` clamped to 1, where `s` is the 99th percentile (nearest rank) of
//! `|d|` over the compared pixels. Excluded (non-finite) pixels are green.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result, bail, ensure};

pub use image_metrics::{Metrics, RELATIVE_FLOOR, RELATIVE_MSE_EPSILON, metrics, metrics_with_floor};

/// Channel names, in storage order.
const CHANNELS: [&str; 3] = ["R", "G", "B"];

/// Arguments of `vcm compare`.
#[derive(clap::Args, Debug, Clone)]
pub struct CompareArgs {
    /// Test image.
    pub a: PathBuf,
    /// Reference image.
    pub b: PathBuf,
    /// Per-pixel variance of the mean of A (an image of the same size, e.g. written by
    /// `render --variance`, future); with --variance-b, enables the per-pixel Z-test.
    #[arg(long, value_name = "FILE", requires = "variance_b")]
    pub variance_a: Option<PathBuf>,
    /// Per-pixel variance of the mean of B.
    #[arg(long, value_name = "FILE", requires = "variance_a")]
    pub variance_b: Option<PathBuf>,
    /// Family-wise significance of the per-pixel Z-test (Šidák-corrected over all pixel channels).
    #[arg(long, default_value_t = 1e-3)]
    pub alpha: f64,
    /// Variance floor of the Z-test, relative to the value: an entry's combined standard error
    /// is at least F × max(|A|, |B|), so that pixels deterministic in both images (a constant
    /// background: zero variance) pass when they differ only by rounding, and fail when they
    /// differ by more than about 5 F of their value. 0 disables it.
    #[arg(long, value_name = "F", default_value_t = RELATIVE_FLOOR)]
    pub relative_floor: f64,
    /// Fail (exit code 1) when the relative MSE exceeds this.
    #[arg(long)]
    pub threshold: Option<f64>,
    /// Write a false-colour difference image (PNG/EXR by extension): blue where A < B, red where
    /// A > B, scaled so that |A−B| = the 99th percentile of |A−B| is full intensity.
    #[arg(long, value_name = "FILE")]
    pub diff: Option<PathBuf>,
}

/// Runs `vcm compare`: prints the metrics table on stdout and returns exit code 1 when the
/// `--threshold` is exceeded or the Z-test fails, 0 otherwise.
pub fn run(args: CompareArgs) -> Result<ExitCode> {
    if let Some(t) = args.threshold {
        ensure!(t.is_finite() && t >= 0.0, "--threshold must be a non-negative number, got {t}");
    }
    ensure!(args.alpha > 0.0 && args.alpha < 1.0, "--alpha must be in (0, 1), got {}", args.alpha);
    ensure!(
        args.relative_floor.is_finite() && args.relative_floor >= 0.0,
        "--relative-floor must be a non-negative number, got {}",
        args.relative_floor
    );
    let a = io::read_image(&args.a)?;
    let b = io::read_image(&args.b)?;
    check_same_size(&args.a, &a, &args.b, &b)?;
    let variances = match (&args.variance_a, &args.variance_b) {
        (Some(path_a), Some(path_b)) => {
            let va = io::read_image(path_a)?;
            check_same_size(path_a, &va, &args.a, &a)?;
            let vb = io::read_image(path_b)?;
            check_same_size(path_b, &vb, &args.b, &b)?;
            Some((va, vb))
        }
        (None, None) => None,
        _ => bail!("the Z-test needs both --variance-a and --variance-b"),
    };
    let m = metrics_with_floor(&a, &b, variances.as_ref().map(|(va, vb)| (va, vb)), args.alpha, args.relative_floor)
        .with_context(|| format!("cannot compare '{}' with '{}'", args.a.display(), args.b.display()))?;

    let mut failed = false;
    let mut text = report(&args.a, &args.b, (a.width, a.height), &m, args.alpha, args.relative_floor);
    if let Some(threshold) = args.threshold {
        let pass = m.relative_mse <= threshold;
        failed |= !pass;
        let verdict = if pass { "PASSED" } else { "FAILED" };
        let relation = if pass { "<=" } else { ">" };
        let _ = writeln!(
            text,
            "threshold: relative MSE {} {relation} {}: {verdict}",
            number(m.relative_mse),
            number(threshold)
        );
    }
    if let Some(z) = &m.z_test {
        failed |= !z.passed;
    }
    if let Some(path) = &args.diff {
        let image = diff_image(&a, &b, variances.as_ref().map(|(va, vb)| (va, vb)));
        io::write_image(path, &image, &io::WriteOptions::default())?;
        let _ = writeln!(text, "difference image written to '{}'", path.display());
    }
    print!("{text}");
    Ok(if failed { ExitCode::from(1) } else { ExitCode::SUCCESS })
}

/// The human-readable table printed by [`run`] (without the threshold line).
fn report(
    path_a: &Path,
    path_b: &Path,
    (width, height): (usize, usize),
    m: &Metrics,
    alpha: f64,
    relative_floor: f64,
) -> String {
    let mut t = String::new();
    let _ = writeln!(t, "test (A):       {}", path_a.display());
    let _ = writeln!(t, "reference (B):  {}", path_b.display());
    let _ = writeln!(t, "size:           {width}x{height}");
    let _ = writeln!(t, "pixels:         {} compared, {} non-finite excluded", m.pixels, m.non_finite);
    let _ = writeln!(t, "RMSE:           {}", number(m.rmse));
    let _ = writeln!(t, "relative MSE:   {}  (epsilon {RELATIVE_MSE_EPSILON})", number(m.relative_mse));
    let _ = writeln!(t, "MAE:            {}", number(m.mean_absolute_error));
    let _ = writeln!(t);
    let _ = writeln!(t, "{:<8} {:>15} {:>15} {:>15} {:>12}", "channel", "mean A", "mean B", "A-B", "(A-B)/B");
    for ((name, &ma), &mb) in CHANNELS.iter().zip(&m.means_a).zip(&m.means_b) {
        let percent = if mb != 0.0 { format!("{:+.4}%", 100.0 * (ma - mb) / mb.abs()) } else { "-".to_string() };
        let _ =
            writeln!(t, "{:<8} {:>15} {:>15} {:>15} {:>12}", name, number(ma), number(mb), number(ma - mb), percent);
    }
    if let Some(z) = &m.z_test {
        let _ = writeln!(t);
        let _ = writeln!(
            t,
            "per-pixel Z-test: {} entries, worst z {:.3} at ({}, {}) channel {}, p threshold {:.3e} \
             (alpha {alpha}, Šidák; variance floor {relative_floor} of the value), {} failing: {}",
            z.entries,
            z.worst_z,
            z.worst_pixel.0,
            z.worst_pixel.1,
            CHANNELS[z.worst_channel],
            z.threshold_p,
            z.failing,
            if z.passed { "PASSED" } else { "FAILED" }
        );
    }
    t
}

/// The false-colour difference image described in the module documentation.
fn diff_image(a: &io::Image, b: &io::Image, variance: Option<(&io::Image, &io::Image)>) -> io::Image {
    let finite = |p: &[f32; 3]| p.iter().all(|v| v.is_finite());
    let differences: Vec<Option<f64>> = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .enumerate()
        .map(|(i, (pa, pb))| {
            let ok = finite(pa)
                && finite(pb)
                && variance.is_none_or(|(va, vb)| finite(&va.pixels[i]) && finite(&vb.pixels[i]));
            ok.then(|| (0..3).map(|c| f64::from(pa[c]) - f64::from(pb[c])).sum::<f64>() / 3.0)
        })
        .collect();
    let mut magnitudes: Vec<f64> = differences.iter().flatten().map(|d| d.abs()).collect();
    let scale = percentile(&mut magnitudes, 0.99);
    let scale = if scale > 0.0 { scale } else { 1.0 };
    let pixels = differences
        .iter()
        .map(|d| match d {
            None => [0.0, 1.0, 0.0],
            Some(d) => {
                let t = (d.abs() / scale).min(1.0) as f32;
                if *d > 0.0 { [t, 0.0, 0.0] } else { [0.0, 0.0, t] }
            }
        })
        .collect();
    io::Image { width: a.width, height: a.height, pixels }
}

/// The `q`-quantile of `values` by the nearest-rank method (0 for no values). Reorders `values`.
fn percentile(values: &mut [f64], q: f64) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    let rank = ((q * values.len() as f64).ceil() as usize).clamp(1, values.len());
    *values.select_nth_unstable_by(rank - 1, f64::total_cmp).1
}

/// Errors with a message naming both files and both sizes unless the images have the same size.
fn check_same_size(path_a: &Path, a: &io::Image, path_b: &Path, b: &io::Image) -> Result<()> {
    ensure!(
        (a.width, a.height) == (b.width, b.height),
        "image sizes differ: '{}' is {}x{} but '{}' is {}x{}",
        path_a.display(),
        a.width,
        a.height,
        path_b.display(),
        b.width,
        b.height
    );
    Ok(())
}

/// Formats a metric with 7 significant digits: fixed-point for moderate magnitudes, scientific
/// otherwise.
fn number(x: f64) -> String {
    let magnitude = x.abs();
    if x == 0.0 {
        "0".to_string()
    } else if (1e-3..1e6).contains(&magnitude) {
        let decimals = (6 - magnitude.log10().floor() as i32).max(0) as usize;
        format!("{x:.decimals$}")
    } else {
        format!("{x:.6e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(width: usize, height: usize, f: impl FnMut(usize, usize) -> [f32; 3]) -> io::Image {
        io::Image::from_fn(width, height, f)
    }

    fn constant(like: &io::Image, value: f32) -> io::Image {
        image(like.width, like.height, |_, _| [value; 3])
    }

    #[test]
    fn diff_image_colours_and_scale() {
        let a = image(10, 10, |x, y| [(x + 10 * y) as f32 / 100.0; 3]);
        let b = constant(&a, 0.5);
        let mut a_nan = a.clone();
        a_nan.set(0, 0, [f32::NAN; 3]);
        let diff = diff_image(&a_nan, &b, None);
        assert_eq!((diff.width, diff.height), (10, 10));
        assert_eq!(diff.get(0, 0), [0.0, 1.0, 0.0]);
        assert_eq!(diff.get(0, 5), [0.0, 0.0, 0.0]);
        // Differences -0.49..0.49; the 99th percentile of |d| over 99 pixels is 0.49.
        let red = diff.get(9, 9);
        assert!((red[0] - 1.0).abs() < 1e-6 && red[1] == 0.0 && red[2] == 0.0, "{red:?}");
        let blue = diff.get(1, 0);
        assert!(blue[0] == 0.0 && blue[1] == 0.0 && (blue[2] - 1.0).abs() < 1e-6, "{blue:?}");
        let half = diff.get(4, 7);
        assert!((half[0] - 0.24 / 0.49).abs() < 1e-5 && half[2] == 0.0, "{half:?}");
        // Identical images: black, no division by zero.
        assert!(diff_image(&b, &b, None).pixels.iter().all(|p| *p == [0.0; 3]));
    }

    #[test]
    fn percentile_nearest_rank() {
        let mut v: Vec<f64> = (1..=100).rev().map(f64::from).collect();
        assert_eq!(percentile(&mut v, 0.99), 99.0);
        assert_eq!(percentile(&mut [3.0], 0.99), 3.0);
        assert_eq!(percentile(&mut [], 0.99), 0.0);
    }

    #[test]
    fn numbers_are_formatted_readably() {
        assert_eq!(number(0.0), "0");
        assert_eq!(number(0.1), "0.1000000");
        assert_eq!(number(12.5), "12.50000");
        assert_eq!(number(1e-5), "1.000000e-5");
    }
}
