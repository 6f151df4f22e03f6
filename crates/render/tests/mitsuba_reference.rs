//! Mitsuba's own Cornell box (`shared/scenes/mitsuba/cornell-box/cornell_box.xml`), loaded from
//! the XML and rendered with `pt` and `vcm`, against Mitsuba 3's converged reference image
//! (`cbox_dict.exr`, 832 spp, path tracer, max_depth 8, gaussian filter).
//!
//! Two checks: the per-channel image means within 1 % of the reference's, and 32×32-pixel block
//! means passing a Z-test with Šidák correction. The block's standard error combines ours (from
//! the spread of independent iterations) and the reference's — see `reference_block_error`.

mod common;

use std::path::PathBuf;

use render::driver::Budget;
use scene::Scene;
use testkit::{sidak, z_test_p};

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

fn check(algorithm: &str, iterations: u64) {
    let (scene, max_length, reference, relative_error) = load();
    let (w, h) = (scene.camera.width as usize, scene.camera.height as usize);
    assert_eq!((reference.width, reference.height), (w, h));
    let mut settings = common::settings(algorithm, 11);
    settings.max_length = max_length;
    settings.budget = Budget::Iterations(iterations);
    let block = 32u32;
    let estimate = common::block_estimate(&scene, &settings, iterations, block);

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
    let alpha = sidak(1e-3, blocks * 3);
    let bx = estimate.blocks_x;
    let mut worst = 0.0f64;
    for b in 0..blocks {
        let (x0, y0) = ((b % bx) * block as usize, (b / bx) * block as usize);
        for c in 0..3 {
            let mut sum = 0.0f64;
            for y in y0..y0 + block as usize {
                for x in x0..x0 + block as usize {
                    sum += reference.pixels[y * w + x][c] as f64;
                }
            }
            let reference_mean = sum / (block * block) as f64;
            let error = estimate.std_errors[b * 3 + c].hypot(reference_block_error(
                reference_mean,
                relative_error,
                (block * block) as usize,
            ));
            let z = (estimate.means[b * 3 + c] - reference_mean) / error.max(1e-12);
            worst = worst.max(z.abs());
            if z_test_p(estimate.means[b * 3 + c] - reference_mean, error.max(1e-12)) < alpha {
                failures.push(format!(
                    "block ({x0},{y0}) channel {c}: ours {:.5} ± {:.5}, Mitsuba {reference_mean:.5}, z = {z:.2}",
                    estimate.means[b * 3 + c],
                    estimate.std_errors[b * 3 + c]
                ));
            }
        }
    }
    eprintln!("{algorithm}: worst block |z| = {worst:.2} over {} entries (Šidák α = {alpha:.2e})", blocks * 3);
    assert!(failures.is_empty(), "{algorithm} differs from Mitsuba:\n{}", failures.join("\n"));
}

#[test]
#[ignore = "needs ../shared: Mitsuba's Cornell box and its reference image"]
fn shared_cornell_box_pt_matches_mitsuba() {
    check("pt", 16);
}

#[test]
#[ignore = "needs ../shared: Mitsuba's Cornell box and its reference image"]
fn shared_cornell_box_vcm_matches_mitsuba() {
    check("vcm", 16);
}
