//! The engine's optional modes render the same image as its default: the per-pixel merging
//! radius (§6.1) by per-block Z-tests with a Šidák correction, as in `vcm_consistency.rs`
//! (merging is compared only on blocks away from edges, see there), and the memory-efficient
//! mode's determinism across thread counts (its equality with the default mode is tested bit
//! for bit in `vcm_memory.rs`).

use crate::common;

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

// The memory-efficient mode is not compared statistically: it renders the default mode's
// image bit for bit (`vcm_memory.rs`), a stronger check than any Z-test.

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
