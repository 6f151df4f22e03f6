//! MIS compensation in the VCM engine (`VcmSettings::mis_compensation`, on by default): next-event
//! estimation samples an image environment's compensated density, and every MIS weight of the
//! engine uses it as the next-event technique's pdf (escaped camera sub-paths, light sub-paths
//! starting at the map). Both settings are estimators of the same image; these tests compare
//! them block by block (Z-tests over independent iterations, as in `vcm_consistency.rs`), show
//! that the comparison would see a small bias, and that the compensation is at work.
//!
//! Power: with 6,400 iterations each comparison would reject a relative bias of 0.4 % of the
//! image, and both mistakes the compensation invites fail it (measured with `bpt`): weighting
//! the escaped camera sub-paths by the full density while next-event estimation samples the
//! compensated one (worst z = −10.4), and starting light sub-paths with the full density's pdf
//! as the next-event technique's (z = 25.7 on the pooled mean).
//!
//! `bpt` is unbiased, so its two estimates agree in expectation exactly. `vcm` merges, which is
//! biased near edges; the compensation changes how much weight merges get only where the
//! next-event technique's pdf changes (directions towards the map's dim part), by far less than
//! the merging bias itself, which `vcm_consistency.rs` bounds against `bpt`.

use crate::common;

use common::comparison::Comparison;
use common::{block_estimate, block_views, image_environment_box, settings};
use render::RenderSettings;

/// Blocks per image side (the scene is 32 × 32 pixels).
const GRID: u32 = 8;
/// Family-wise significance of each comparison.
const ALPHA: f64 = 1e-3;

/// `algorithm` with the compensation (seed 1) against `algorithm` with the full density (seed 2)
/// over `iterations` iterations each: they agree, the comparison would see a relative bias of
/// `power`, and the two estimates differ.
fn check(algorithm: &str, iterations: u64, power: f64) {
    let scene = image_environment_box();
    let compensated = settings(algorithm, 1);
    assert!(compensated.mis_compensation, "the default");
    let full = RenderSettings { mis_compensation: false, ..settings(algorithm, 2) };
    let block = scene.camera.width / GRID;
    let a = block_estimate(&scene, &compensated, iterations, block);
    let b = block_estimate(&scene, &full, iterations, block);
    let views = block_views(&scene, block);
    let what = format!("{algorithm}: compensated vs full density");
    let result = Comparison::new(what, &a, &b, &views, |_| true, ALPHA, 0.02);
    assert!(result.outcome.passed, "{}: {}", result.what, result.outcome);
    assert!(result.detectable < power, "{}: cannot see a bias of {} %", result.what, 100.0 * power);
    // The same seed with the full density gives other estimates: the compensation is at work.
    let same_seed = RenderSettings { mis_compensation: false, ..settings(algorithm, 1) };
    let c = block_estimate(&scene, &same_seed, 2, block);
    let first = block_estimate(&scene, &compensated, 2, block);
    assert!(c.means.iter().zip(&first.means).any(|(x, y)| x != y), "{algorithm}: the compensation changed nothing");
}

#[test]
fn bpt_with_mis_compensation_agrees_with_the_full_density() {
    check("bpt", 6400, 0.01);
}

#[test]
fn vcm_with_mis_compensation_agrees_with_the_full_density() {
    check("vcm", 6400, 0.01);
}
