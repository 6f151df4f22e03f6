//! Mitsuba's own Cornell box (`shared/scenes/mitsuba/cornell-box/cornell_box.xml`), loaded from
//! the XML and rendered with `pt` and `vcm`, against Mitsuba 3's converged reference image
//! (`cbox_dict.exr`, 832 spp, path tracer, max_depth 8, gaussian filter).
//!
//! Two checks: the per-channel image means within 1 % of the reference's, and 32×32-pixel block
//! means passing a t-test with Šidák correction. The block's standard error combines ours (from
//! the spread of 64 independent iterations, hence Student's t) and the reference's — see
//! `reference_block_error`. The test prints the smallest block bias it rejects.
//!
//! `vcm` is consistent, not unbiased: where a merging disc of the first iteration's radius
//! reaches across an edge onto another surface (the floor under the boxes, the corners), the
//! photons counted there bias the block by an amount proportional to the radius. Measured on
//! block (192, 192) at 16 iterations, seed 11: +4.3 %, +2.0 %, +0.8 %, +0.6 % against the
//! reference for radius factors 0.006, 0.003, 0.0015, 0.00075. Such blocks are left out of the
//! block test for merging algorithms, as in `vcm_consistency.rs` (the image means keep every
//! pixel); the test prints how many blocks remain and fails when fewer than half do.

use crate::common;

use std::path::PathBuf;

use render::driver::Budget;
use scene::Scene;
use testkit::{sidak, t_test_p, welch_dof};

fn shared() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/scenes/mitsuba/cornell-box")
}

/// The scene at the reference's resolution. The tests are named `shared_*` and ignored;
/// `.ci/run` runs them where `../shared` is present, and without it they fail here.
fn load() -> (Scene, u32, io::Image, f64) {
    let dir = shared();
    assert!(dir.exists(), "{} is absent: this test needs ../shared beside the clone", dir.display());
    let desc = io::load_scene(&dir.join("cornell_box.xml"), &[]).unwrap();
    let max_length = desc.max_path_length.unwrap();
    let (scene, _) = Scene::from_description(&desc, None).unwrap();
    let reference = io::read_image(&dir.join("cbox_dict.exr")).unwrap();
    let json = std::fs::read_to_string(dir.join("cbox_dict.json")).unwrap();
    let relative_error = json
        .split("\"mean_stderr_over_mean\":")
        .nth(1)
        .and_then(|rest| rest.trim_start().split([',', '\n', '}']).next())
        .and_then(|v| v.trim().parse::<f64>().ok())
        .expect("mean_stderr_over_mean in the json");
    (scene, max_length, reference, relative_error)
}

/// Standard error of a reference block mean. The json's `mean_stderr_over_mean` (0.0088) is the
/// pixels' standard error relative to their value, averaged over the image: it cannot be the
/// error of the image mean, which our renders match 30 times more closely (0.03 %). A block of
/// `n` pixels with independent noise then has `1/√n` of it.
fn reference_block_error(block_mean: f64, relative_error: f64, block_pixels: usize) -> f64 {
    block_mean.abs() * relative_error / (block_pixels as f64).sqrt()
}

/// The `|t|` at which [`t_test_p`] equals `alpha` with `dof` degrees of freedom (bisection).
fn t_threshold(alpha: f64, dof: f64) -> f64 {
    let (mut lo, mut hi) = (0.0f64, 1e3f64);
    while hi - lo > 1e-6 {
        let mid = 0.5 * (lo + hi);
        if t_test_p(mid, 1.0, dof) < alpha { hi = mid } else { lo = mid }
    }
    hi
}

fn check(algorithm: &str, iterations: u64) {
    let (scene, max_length, reference, relative_error) = load();
    let (w, h) = (scene.camera.width as usize, scene.camera.height as usize);
    assert_eq!((reference.width, reference.height), (w, h));
    let mut settings = common::settings(algorithm, 11);
    settings.max_length = max_length;
    settings.budget = Budget::Iterations(iterations);
    let block = 32u32;
    let estimate = common::block_estimate(&scene, &settings, iterations, block);
    let merging = matches!(algorithm, "ppm" | "bpm" | "vcm");
    let radius = settings.vcm_settings().map(|v| render::vcm::base_radius(&scene, &v));
    let views = common::block_views(&scene, block);
    let comparable = |b: usize| !merging || radius.is_none_or(|r| views[b].clearance > r);

    // Image means per channel.
    let reference_means: [f64; 3] =
        std::array::from_fn(|c| reference.pixels.iter().map(|p| p[c] as f64).sum::<f64>() / (w * h) as f64);
    let blocks = estimate.means.len() / 3;
    let mut failures = Vec::new();
    for (c, reference_mean) in reference_means.into_iter().enumerate() {
        let ours: f64 = (0..blocks).map(|b| estimate.means[b * 3 + c]).sum::<f64>() / blocks as f64;
        let relative = (ours - reference_mean) / reference_mean;
        eprintln!("{algorithm} channel {c}: ours {ours:.5}, Mitsuba {reference_mean:.5} ({:+.3} %)", 100.0 * relative);
        if relative.abs() > 0.01 {
            failures.push(format!("channel {c}: mean differs by {:+.3} %", 100.0 * relative));
        }
    }

    // Block means.
    let bx = estimate.blocks_x;
    let mut worst = 0.0f64;
    let mut detectable = Vec::new();
    let compared: Vec<usize> = (0..blocks).filter(|b| comparable(*b)).collect();
    eprintln!(
        "{algorithm}: {} of {blocks} blocks compared (merging radius {radius:?}: blocks within it of an edge left out)",
        compared.len()
    );
    assert!(2 * compared.len() >= blocks, "too few blocks away from edges: {}", compared.len());
    let alpha = sidak(1e-3, compared.len() * 3);
    for b in compared.iter().copied() {
        let (x0, y0) = ((b % bx) * block as usize, (b / bx) * block as usize);
        for c in 0..3 {
            let mut sum = 0.0f64;
            for y in y0..y0 + block as usize {
                for x in x0..x0 + block as usize {
                    sum += reference.pixels[y * w + x][c] as f64;
                }
            }
            let reference_mean = sum / (block * block) as f64;
            let ours = estimate.std_errors[b * 3 + c];
            let theirs = reference_block_error(reference_mean, relative_error, (block * block) as usize);
            let error = ours.hypot(theirs).max(1e-12);
            // Our error is estimated from `iterations` samples, the reference's is taken as
            // known: Student's t with the Welch–Satterthwaite degrees of freedom (≥ iterations − 1).
            let dof = welch_dof(ours, (iterations - 1) as f64, theirs, f64::INFINITY);
            let d = estimate.means[b * 3 + c] - reference_mean;
            let z = d / error;
            worst = worst.max(z.abs());
            detectable.push(t_threshold(alpha, dof) * error / reference_mean.abs().max(1e-12));
            if t_test_p(d, error, dof) < alpha {
                failures.push(format!(
                    "block ({x0},{y0}) channel {c}: ours {:.5} ± {ours:.5}, Mitsuba {reference_mean:.5}, t = {z:.2} \
                     ({dof:.0} degrees of freedom)",
                    estimate.means[b * 3 + c],
                ));
            }
        }
    }
    detectable.sort_by(f64::total_cmp);
    eprintln!(
        "{algorithm}: a block mean off by {:.2} % fails (median block; a t-test at the Šidák level)",
        100.0 * detectable[detectable.len() / 2]
    );
    eprintln!("{algorithm}: worst block |t| = {worst:.2} over {} entries (Šidák α = {alpha:.2e})", compared.len() * 3);
    assert!(failures.is_empty(), "{algorithm} differs from Mitsuba:\n{}", failures.join("\n"));
}

#[test]
#[ignore = "needs ../shared: Mitsuba's Cornell box and its reference image"]
fn shared_cornell_box_pt_matches_mitsuba() {
    check("pt", 64);
}

#[test]
#[ignore = "needs ../shared: Mitsuba's Cornell box and its reference image"]
fn shared_cornell_box_vcm_matches_mitsuba() {
    check("vcm", 64);
}
