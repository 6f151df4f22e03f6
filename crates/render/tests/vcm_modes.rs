//! The engine's optional modes render the same image as its default: the memory-efficient
//! single-stage mode (tech report §6.2, merging with the previous iteration's light vertices)
//! and the per-pixel merging radius (§6.1). Per-block Z-tests with a Šidák correction, as in
//! `vcm_consistency.rs`; merging is compared only on blocks away from edges (see there).

mod common;

use common::{BlockEstimate, block_estimate, block_views, detectable_bias, settings};
use render::RenderSettings;
use render::vcm::RadiusMode;
use scene::cornell;
use testkit::z_test_entries;

const GRID: u32 = 8;

fn estimate(mask: u32, resolution: u32, settings: &RenderSettings, iterations: u64) -> BlockEstimate {
    let scene = cornell::build(mask, resolution, resolution).unwrap();
    block_estimate(&scene, settings, iterations, resolution / GRID)
}

/// Z-test of `a` against `b` on the blocks whose primary hits are farther than `clearance`
/// from other surfaces, and on the channel means pooled over those blocks; asserts that it
/// passes and that it detects a relative bias of `power` in `a` (the same test rejects `a`
/// scaled by `1 ± power`). Returns the number of blocks compared.
fn compare(what: &str, mask: u32, a: &BlockEstimate, b: &BlockEstimate, clearance: f32, power: f64) -> usize {
    let alpha = 1e-3;
    let scene = cornell::build(mask, 32, 32).unwrap();
    let views = block_views(&scene, 32 / GRID);
    let keep: Vec<bool> = views.iter().map(|v| v.clearance > clearance).collect();
    let (mut am, mut ae, mut bm, mut be) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for (i, _) in keep.iter().enumerate().filter(|(_, k)| **k) {
        am.extend_from_slice(&a.means[i * 3..i * 3 + 3]);
        ae.extend_from_slice(&a.std_errors[i * 3..i * 3 + 3]);
        bm.extend_from_slice(&b.means[i * 3..i * 3 + 3]);
        be.extend_from_slice(&b.std_errors[i * 3..i * 3 + 3]);
    }
    let blocks = am.len() / 3;
    for (estimate, means, errors) in [(a, &mut am, &mut ae), (b, &mut bm, &mut be)] {
        let (pooled, pooled_errors) = estimate.pooled(&keep);
        means.extend(pooled);
        errors.extend(pooled_errors);
    }
    let outcome = z_test_entries(&am, &ae, &bm, &be, alpha);
    let detectable = detectable_bias(&am, &ae, &bm, &be, alpha);
    eprintln!("{what}: {blocks} blocks, detects a bias of {:.1} %, {outcome}", 100.0 * detectable);
    assert!(outcome.passed, "{what}: {outcome}");
    assert!(detectable <= power, "{what}: detects only a bias of {:.1} %, not {} %", 100.0 * detectable, 100.0 * power);
    blocks
}

/// Renders `algorithm` on `mask` at 64² for `iterations` iterations in the memory-efficient and
/// the default mode and compares them, asserting the power to see a relative bias of `power`.
fn memory_efficient_against_default(mask: u32, algorithm: &str, iterations: u64, power: f64) {
    // Same radius schedule, so the same merging bias: the two estimates must agree everywhere
    // (also on edges).
    let base = RenderSettings { radius_factor: 1e-2, ..settings(algorithm, 1) };
    let efficient = RenderSettings { memory_efficient: true, ..settings(algorithm, 2) };
    let efficient = RenderSettings { radius_factor: 1e-2, ..efficient };
    let a = estimate(mask, 64, &efficient, iterations);
    let b = estimate(mask, 64, &base, iterations);
    let what = format!("scene {mask} {algorithm}: memory-efficient vs default");
    let blocks = compare(&what, mask, &a, &b, 0.0, power);
    assert_eq!(blocks, 64);
}

/// Power: vcm on the area-light scene detects a 2 % bias (measured 1.4 %); bpm on the scene lit
/// by the environment through glass and mirror spheres (456) is far noisier and detects only
/// about 11 % at this sample count (asserted: 15 %). The slow tier's
/// `memory_efficient_bpm_resolves_a_bias_of_3_percent` runs it with 60 × the iterations.
#[test]
fn memory_efficient_mode_matches_the_default() {
    memory_efficient_against_default(273, "vcm", 250, 0.02);
    memory_efficient_against_default(456, "bpm", 150, 0.15);
}

/// The bpm comparison of [`memory_efficient_mode_matches_the_default`] with 60 × the
/// iterations. It detects a bias of 2.2 % (asserted: 3 %), not the 11.4 % / √60 = 1.5 % that
/// Gaussian noise would give: bpm's block values on this scene are heavy-tailed (rare bright
/// caustic paths through the glass sphere), so the spread of the iterations keeps growing
/// with their number.
#[test]
#[ignore = "slow: run with --ignored"]
fn memory_efficient_bpm_resolves_a_bias_of_3_percent() {
    memory_efficient_against_default(456, "bpm", 9000, 0.03);
}

/// Power: detects a 2 % bias (measured 1.6 %).
#[test]
fn per_pixel_radius_matches_bidirectional_path_tracing() {
    // At 128² the footprint radius is at most ~0.02; compare away from edges within that.
    let mask = 273;
    let per_pixel = RenderSettings { radius_mode: RadiusMode::PerPixel, ..settings("vcm", 3) };
    let a = estimate(mask, 128, &per_pixel, 60);
    let b = estimate(mask, 32, &settings("bpt", 4), 3000);
    let blocks = compare("scene 273 vcm per-pixel radius vs bpt", mask, &a, &b, 0.03, 0.02);
    assert!(blocks >= 16, "only {blocks} blocks compared");
}

#[test]
fn memory_efficient_mode_is_deterministic_across_threads() {
    let scene = cornell::build(273, 40, 36).unwrap();
    let image = |threads| {
        let s = RenderSettings {
            memory_efficient: true,
            threads,
            budget: render::driver::Budget::Iterations(3),
            ..settings("vcm", 9)
        };
        render::render(&scene, &s).unwrap().film.mean()
    };
    assert_eq!(image(1), image(2));
}
