//! The engine's optional modes render the same image as its default: the memory-efficient
//! single-stage mode (tech report §6.2, merging with the previous iteration's light vertices)
//! and the per-pixel merging radius (§6.1). Per-block Z-tests with a Šidák correction, as in
//! `vcm_consistency.rs`; merging is compared only on blocks away from edges (see there).

mod common;

use common::{BlockEstimate, block_estimate, block_views, settings};
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
/// from other surfaces; returns the number of blocks compared.
fn compare(what: &str, mask: u32, a: &BlockEstimate, b: &BlockEstimate, clearance: f32, alpha: f64) -> usize {
    let scene = cornell::build(mask, 32, 32).unwrap();
    let views = block_views(&scene, 32 / GRID);
    let mut am = Vec::new();
    let (mut ae, mut bm, mut be) = (Vec::new(), Vec::new(), Vec::new());
    let mut blocks = 0;
    for (i, view) in views.iter().enumerate() {
        if view.clearance > clearance {
            blocks += 1;
            am.extend_from_slice(&a.means[i * 3..i * 3 + 3]);
            ae.extend_from_slice(&a.std_errors[i * 3..i * 3 + 3]);
            bm.extend_from_slice(&b.means[i * 3..i * 3 + 3]);
            be.extend_from_slice(&b.std_errors[i * 3..i * 3 + 3]);
        }
    }
    let outcome = z_test_entries(&am, &ae, &bm, &be, alpha);
    eprintln!("{what}: {blocks} blocks, {outcome}");
    assert!(outcome.passed, "{what}: {outcome}");
    blocks
}

#[test]
fn memory_efficient_mode_matches_the_default() {
    // Same radius schedule, so the same merging bias: the two estimates must agree everywhere
    // (also on edges).
    for (mask, algorithm) in [(273, "vcm"), (456, "bpm")] {
        let base = RenderSettings { radius_factor: 1e-2, ..settings(algorithm, 1) };
        let efficient = RenderSettings { memory_efficient: true, ..settings(algorithm, 2) };
        let efficient = RenderSettings { radius_factor: 1e-2, ..efficient };
        let a = estimate(mask, 64, &efficient, 150);
        let b = estimate(mask, 64, &base, 150);
        let blocks =
            compare(&format!("scene {mask} {algorithm}: memory-efficient vs default"), mask, &a, &b, 0.0, 1e-3);
        assert_eq!(blocks, 64);
    }
}

#[test]
fn per_pixel_radius_matches_bidirectional_path_tracing() {
    // At 128² the footprint radius is at most ~0.02; compare away from edges within that.
    let mask = 273;
    let per_pixel = RenderSettings { radius_mode: RadiusMode::PerPixel, ..settings("vcm", 3) };
    let a = estimate(mask, 128, &per_pixel, 60);
    let b = estimate(mask, 32, &settings("bpt", 4), 3000);
    let blocks = compare("scene 273 vcm per-pixel radius vs bpt", mask, &a, &b, 0.03, 1e-3);
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
