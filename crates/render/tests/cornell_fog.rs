//! lt, ppm, bpm and vcm against a long `bpt` render per block on the fog-filled Cornell
//! box of issue #15 (`scenes/cornell-fog.xml`, loaded as a user's file is: a spot light shining
//! down through a glass sphere into homogeneous fog, a volumetric caustic and a surface caustic,
//! the file's length limit of 12). Slow tier.
//!
//! The image (32 × 32; the merging algorithms at 4 × that, as in `vcm_consistency.rs`) is cut
//! into 8 × 8 blocks; every iteration is an independent estimate, so each block's mean over the
//! iterations, with its standard error from their spread, supports a Z-test against the
//! reference's (Šidák over the entries of all comparisons, family-wise α = 1e-3), and so do the
//! channel means pooled over the compared blocks, which give the power check: every comparison
//! must reject its estimate scaled by 1 ± [`POWER`].
//!
//! Which blocks are compared, and why:
//! * none whose primary rays meet the glass sphere: the reference `bpt` cannot join the
//!   sub-paths of light that reaches the camera through the sphere after the sphere focused
//!   the delta spot (camera – glass – fog or wall – glass – spot has no connectable pair of
//!   vertices), so it is not a reference there (docs/performance.md measured it 4.6 % low in the
//!   sphere's box against a long `vcm`); `lt` cannot see through the sphere either;
//! * for `ppm`, `bpm` and `vcm`, none where a merging disc of the initial radius reaches
//!   across an edge onto another surface (their kernel bias, `vcm_consistency.rs`);
//! * `pt` is not compared: it cannot sample any path whose light vertex is the delta spot
//!   followed by the glass, and the focused beam lights the fog and the floor in most blocks.
//!
//! Merging radii: `ppm` at r = 0.01 R (R the scene's bounding radius), as in
//! `vcm_consistency.rs`; `bpm` and `vcm` at the renderer's default r = 0.003 R. At 0.01 R and 0.03 R vcm's
//! block (6, 3) came out 2.6 % and 11 % low (z = −4.4 and −11) while at 0.003 R and 0.001 R it
//! agrees within 0.1 %: a deficit that shrinks with the radius is the merging kernel's blur
//! of a sharp feature, not an engine bias, and at the default radius it is below the noise.
//! All three merge at medium vertices within the default volume radius
//! (`render::vcm::DEFAULT_VOLUME_RADIUS_FACTOR` × the fog box's radius, docs/media.md).
//!
//! **`bpm` needs 3000 iterations.** Before the volume radius existed (the ball had the surface
//! radius) its rare, large volumetric merges left block ratios to bpt from 0.72 to 1.29 after
//! 10 000 iterations at 32² (r = 0.01 R). With the volume radius its estimates are still
//! heavy-tailed: measured 2026-11-28 at 128² (seed 2, default volume radius), the per-iteration
//! block values have a skewness of 8–18 and the largest 1 % of the iterations carry 11–17 % of
//! a block's total, so a mean over too few iterations is usually low and its standard error
//! too small. After 1000 iterations the red wall near the floor came out low in green and blue
//! by 9–18 % (z down to −5.3) at surface radii 0.01, 0.003 and 0.001 R alike, while vcm agreed
//! on the same blocks within 0.5 % (z > −1.5, against `bpt` of another seed); after 3000
//! iterations that block agreed (blue −1.1 %, z −0.3). At 3000 iterations (r = 0.003 R) the
//! comparison passed for seeds 2, 3 and 4 with worst entries at z = −2.95, −3.34 and −3.07
//! (the per-entry threshold is |z| ≈ 4.8) and detectable biases of 4.4, 3.5 and 4.3 %
//! (measured 2026-11-28 with this module's functions): the tail still pulls the worst entries
//! low, so fewer iterations are not a fair test of bpm, and this budget is.

use crate::common;

use std::path::Path;

use common::comparison::Comparison;
use common::{BlockEstimate, BlockView, block_estimate, block_views, settings};
use render::RenderSettings;
use render::vcm::DEFAULT_VOLUME_RADIUS_FACTOR;
use scene::Scene;

/// Reference resolution (square).
const RESOLUTION: u32 = 32;
/// Blocks per image side.
const GRID: u32 = 8;
/// Family-wise significance over every entry of every comparison.
const ALPHA: f64 = 1e-3;
/// The fog box is dark: its compared block means average about 0.011 (the Cornell scenes'
/// tests ask for 0.02); the power check [`POWER`] is what guards against a test too noisy to
/// see anything.
const MIN_MEAN: f64 = 0.005;
/// The relative bias every comparison must be able to detect.
const POWER: f64 = 0.05;

/// How an algorithm is rendered: resolution multiple, iterations and merging radius factor.
#[derive(Clone, Copy, Debug)]
struct Plan {
    algorithm: &'static str,
    scale: u32,
    iterations: u64,
    radius_factor: f32,
    volume_radius_factor: f32,
}

/// ppm's radius factor (as `vcm_consistency.rs`, whose module documentation bounds the bias).
const PPM_RADIUS_FACTOR: f32 = 1e-2;
/// bpm's and vcm's: the renderer's default (see the module documentation).
const VCM_RADIUS_FACTOR: f32 = 3e-3;

/// `scenes/cornell-fog.xml` at `resolution²` and its length limit.
fn cornell_fog(resolution: u32) -> (Scene, u32) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/cornell-fog.xml");
    let desc = io::load_scene(&path, &[]).unwrap_or_else(|e| panic!("{e}"));
    assert!(desc.warnings.is_empty(), "{:?}", desc.warnings);
    let max_length = desc.max_path_length.expect("the file names max_depth");
    let (scene, _) = Scene::from_description(&desc, Some((resolution, resolution))).unwrap();
    (scene, max_length)
}

/// Renders `plan` and returns its 8 × 8 block estimate.
fn estimate(plan: Plan, seed: u64) -> BlockEstimate {
    let resolution = RESOLUTION * plan.scale;
    let (scene, max_length) = cornell_fog(resolution);
    let settings = RenderSettings {
        radius_factor: plan.radius_factor,
        volume_radius_factor: plan.volume_radius_factor,
        max_length,
        ..settings(plan.algorithm, seed)
    };
    let estimate = block_estimate(&scene, &settings, plan.iterations, resolution / GRID);
    assert_eq!(estimate.blocks_x, GRID as usize);
    estimate
}

/// Whether `algorithm` is compared with the `bpt` reference on a block that looks like `view`.
fn comparable(algorithm: &str, view: &BlockView, radius: f32) -> bool {
    let lt_ok = algorithm != "lt" || !view.emitter_or_background;
    let merging = matches!(algorithm, "ppm" | "bpm" | "vcm");
    !view.specular && lt_ok && (!merging || view.clearance > radius)
}

/// lt, ppm, bpm and vcm agree with a long bpt per block and in the pooled means, on the blocks the
/// module documentation lists, and each comparison detects a 5 % bias.
#[test]
#[ignore = "slow: run with --ignored"]
fn lt_ppm_bpm_and_vcm_agree_with_bpt_in_the_fog_box() {
    let volume = DEFAULT_VOLUME_RADIUS_FACTOR;
    let plans = [
        Plan { algorithm: "lt", scale: 1, iterations: 4000, radius_factor: 0.0, volume_radius_factor: volume },
        Plan {
            algorithm: "ppm",
            scale: 4,
            iterations: 200,
            radius_factor: PPM_RADIUS_FACTOR,
            volume_radius_factor: volume,
        },
        Plan {
            algorithm: "bpm",
            scale: 4,
            iterations: 3000,
            radius_factor: VCM_RADIUS_FACTOR,
            volume_radius_factor: volume,
        },
        Plan {
            algorithm: "vcm",
            scale: 4,
            iterations: 300,
            radius_factor: VCM_RADIUS_FACTOR,
            volume_radius_factor: volume,
        },
    ];
    let reference =
        Plan { algorithm: "bpt", scale: 1, iterations: 8000, radius_factor: 0.0, volume_radius_factor: volume };
    let (scene, _) = cornell_fog(RESOLUTION);
    let views = block_views(&scene, RESOLUTION / GRID);
    let radius = |plan: Plan| plan.radius_factor * scene.bounding_sphere.radius;
    let alpha = testkit::sidak(ALPHA, plans.len());
    let bpt = estimate(reference, 1);
    let mut failures = Vec::new();
    for plan in plans {
        let tested = estimate(plan, 2);
        let what = format!("cornell-fog: {} vs bpt", plan.algorithm);
        let keep = |v: &BlockView| comparable(plan.algorithm, v, radius(plan));
        let result = Comparison::new(what, &tested, &bpt, &views, keep, alpha, MIN_MEAN);
        if !result.outcome.passed {
            failures.push(format!("{}: {}", result.what, result.outcome));
        }
        if result.detectable > POWER {
            failures.push(format!("{}: no power to see a bias of {} %", result.what, 100.0 * POWER));
        }
    }
    assert!(failures.is_empty(), "inconsistent estimates:\n{}", failures.join("\n"));
}
