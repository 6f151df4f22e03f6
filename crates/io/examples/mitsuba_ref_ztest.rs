//! Per-pixel Z-test of a rendered image against a reference of Mitsuba 3's render-test suite.
//!
//! Mitsuba's `refs/<name>_ref_rgb_var.exr` holds the *per-sample* variance `m2 − m1²` of the
//! `moment` integrator, and the references are rendered with 32 000 samples per pixel
//! (`src/render/tests/test_renders.py`, `--spp` default), so the variance of the reference mean
//! is that image divided by the sample count. `vcm compare --variance-b` expects the variance of
//! the mean, hence this tool.
//!
//! ```text
//! cargo run --release -p vcm-io --example mitsuba_ref_ztest -- \
//!     img.exr img-var.exr ref.exr ref_var.exr [ref_spp = 32000] [alpha = 0.001]
//! ```
//! `img-var.exr` is the variance of the mean written by `vcm render --variance`. Prints the
//! channel means, the worst entry and the verdict of the strict test (every entry passes at the
//! Šidák-corrected level), then the number of failing entries and the verdict of Mitsuba's own
//! acceptance rule (at most 0.25 % of the entries fail); exits with 1 when the latter fails.

use std::path::Path;
use std::process::ExitCode;

use testkit::{z_test_entries, z_test_p};

fn read(path: &str) -> Result<io::Image, String> {
    io::read_image(Path::new(path)).map_err(|e| format!("{path}: {e}"))
}

fn run(args: &[String]) -> Result<bool, String> {
    let [image, image_var, reference, reference_var, rest @ ..] = args else {
        return Err("usage: mitsuba_ref_ztest img.exr img-var.exr ref.exr ref_var.exr [ref_spp] [alpha]".into());
    };
    let number = |i: usize, default: f64| -> Result<f64, String> {
        rest.get(i).map_or(Ok(default), |s| s.parse().map_err(|_| format!("not a number: '{s}'")))
    };
    let (spp, alpha) = (number(0, 32_000.0)?, number(1, 1e-3)?);
    let (a, a_var, b, b_var) = (read(image)?, read(image_var)?, read(reference)?, read(reference_var)?);
    if [&a_var, &b, &b_var].iter().any(|i| (i.width, i.height) != (a.width, a.height)) {
        return Err("the four images must have the same size".into());
    }
    let flat = |i: &io::Image| i.pixels.iter().flatten().map(|&v| f64::from(v)).collect::<Vec<_>>();
    let (a_mean, b_mean) = (flat(&a), flat(&b));
    let a_se: Vec<f64> = flat(&a_var).iter().map(|v| v.max(0.0).sqrt()).collect();
    let b_se: Vec<f64> = flat(&b_var).iter().map(|v| (v.max(0.0) / spp).sqrt()).collect();
    for c in 0..3 {
        let mean = |v: &[f64]| v.iter().skip(c).step_by(3).sum::<f64>() / (v.len() / 3) as f64;
        let (ma, mb) = (mean(&a_mean), mean(&b_mean));
        println!("channel {c}: mean {ma:.6} vs reference {mb:.6} ({:+.3} %)", 100.0 * (ma - mb) / mb);
    }
    let outcome = z_test_entries(&a_mean, &a_se, &b_mean, &b_se, alpha);
    let pixel = outcome.worst_index / 3;
    println!(
        "per-pixel Z-test over {} entries: worst z {:.3} at ({}, {}) channel {}, p {:.3e}, threshold {:.3e}: {}",
        outcome.entries,
        outcome.worst_z,
        pixel % a.width,
        pixel / a.width,
        outcome.worst_index % 3,
        outcome.worst_p,
        outcome.threshold,
        if outcome.passed { "PASSED" } else { "FAILED" }
    );
    // Mitsuba's own acceptance: at least 99.75 % of the entries pass at the Šidák level.
    let failures: Vec<usize> = (0..a_mean.len())
        .filter(|&i| z_test_p(a_mean[i] - b_mean[i], a_se[i].hypot(b_se[i])) < outcome.threshold)
        .collect();
    let failing = failures.len();
    let listed: Vec<String> =
        failures.iter().take(24).map(|i| format!("({}, {})", (i / 3) % a.width, i / 3 / a.width)).collect();
    if !listed.is_empty() {
        println!("failing pixels (x, y), first {}: {}", listed.len(), listed.join(" "));
    }
    let accepted = failing as f64 <= 0.0025 * a_mean.len() as f64;
    println!(
        "{failing} failing entries ({:.2} %); Mitsuba's acceptance (at most 0.25 %): {}",
        100.0 * failing as f64 / a_mean.len() as f64,
        if accepted { "PASSED" } else { "FAILED" }
    );
    Ok(accepted)
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match run(&args) {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::FAILURE,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(2)
        }
    }
}
