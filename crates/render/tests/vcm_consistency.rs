//! Consistency of the VCM engine's algorithms with each other and with the path tracer on
//! the four reference scenes: per-block Z-tests with a Šidák correction, restricted to the
//! blocks each algorithm can render (cornell.md §3.9).
//!
//! Every iteration's frame is an independent unbiased (merging: consistent) estimate, so the
//! mean of a block over iterations with its standard error from the spread of the iterations
//! supports a Z-test. The image is cut into a fixed 8 × 8 grid of blocks; an algorithm may be
//! rendered at a multiple of the reference resolution (the block then has more pixels but
//! covers the same part of the image, so its mean estimates the same quantity).
//!
//! Exclusions (cornell.md §3.9):
//! * `lt` cannot see the environment nor anything through the mirror or glass (area emitters
//!   seen directly it renders, compared with pt in `cameras.rs`): only blocks whose primary
//!   rays all hit non-specular, non-emitting surfaces are compared;
//! * `pt` misses every caustic from a delta light (the sun of scene 0, the point light of
//!   scene 2), which falls on diffuse surfaces all over those scenes: `pt` is not compared
//!   there at all;
//! * `bpt`, the reference, cannot render L S D S E paths from delta lights (a caustic seen via
//!   the mirror or glass): on scenes 0 and 2 only blocks whose primary rays see no specular
//!   surface are compared;
//! * `ppm` and `bpm` see emitters only through purely specular camera paths, but that is
//!   complete (every other path is merged), so they need no restriction.
//!
//! Merging (`ppm`, `bpm`, `vcm`) is consistent, not unbiased: the density estimate blurs the
//! incident light over the merging disc (radius r), which biases it near geometric edges and
//! corners (the disc leaves the surface or catches another one: up to −25 % within r of a
//! right-angled edge), at shadow and caustic boundaries and on the glossy floor. The bias is
//! confined to a band of width about r around such features, so on a block mean it is at most
//! of the order of 0.25 × (length of the features inside the block) × r / (block area). A block
//! is about 0.3 scene units wide on the back wall; with r = 0.01 × 2.217 = 0.022 the worst
//! block (one crossed by a full box edge) is biased by about 0.25 · 0.3 · 0.022 / 0.09 ≈ 2 %,
//! typical blocks by far less, against standard errors of several % for the merging estimates.
//! A smaller radius is not better here: with r = 1e-3 × R or 3e-3 × R a merging disc holds a
//! photon only rarely (≪ 1 on average at these photon counts), the per-iteration block values
//! are then so skewed that their mean over a few hundred iterations is far from normal and
//! its standard error is underestimated (measured on scene 1 at r = 1e-3 × R: ppm 40–60 %
//! low on the dark front floor blocks with a spurious z = −13; at 1e-2 × R, |z| < 2.2 there).
//! The merging algorithms are also rendered at 4 × the resolution (16 × the light sub-paths,
//! hence 16 × the photons in each disc and 16 × the camera paths per block).
//!
//! **Power.** Besides every block, each comparison tests the channel means pooled over the
//! compared blocks, which sees a bias common to the image far more sharply than a block (whose
//! standard error is several %). Every comparison then finds, with
//! [`common::detectable_bias`], the smallest relative bias of the tested estimate that the same
//! test rejects, and each test asserts a bound on it (stated at the test).

use crate::common;

use common::comparison::Comparison;
use common::{BlockEstimate, BlockView, block_estimate, block_views, settings};
use render::RenderSettings;
use scene::{Scene, cornell};

/// Reference resolution (square).
const RESOLUTION: u32 = 32;
/// Blocks per image side.
const GRID: u32 = 8;
/// Family-wise significance of every comparison of a test.
const ALPHA: f64 = 1e-3;
/// Merging radius factor (see the module documentation for the bias).
const RADIUS_FACTOR: f32 = 1e-2;

/// Scenes 0 and 2 are lit by delta lights (sun, point).
fn delta_lights(mask: u32) -> bool {
    mask & (cornell::SUN | cornell::POINT_LIGHT) != 0
}

/// How an algorithm is rendered: resolution multiple and iterations.
#[derive(Clone, Copy, Debug)]
struct Plan {
    algorithm: &'static str,
    scale: u32,
    iterations: u64,
}

/// Renders `plan` on scene `mask` (spectral mode when `spectral`) and returns its 8 × 8 block
/// estimate.
fn estimate(mask: u32, plan: Plan, seed: u64, spectral: bool) -> BlockEstimate {
    let resolution = RESOLUTION * plan.scale;
    let scene = cornell::build(mask, resolution, resolution).unwrap();
    let settings = RenderSettings { radius_factor: RADIUS_FACTOR, spectral, ..settings(plan.algorithm, seed) };
    let estimate = block_estimate(&scene, &settings, plan.iterations, resolution / GRID);
    assert_eq!(estimate.blocks_x, GRID as usize);
    estimate
}

/// Which blocks `algorithm` can be compared on with a `bpt` (or `pt`) reference on `mask`.
/// Merging algorithms are compared only where no merging disc of the initial radius reaches
/// across an edge onto another surface (e.g. from the ceiling onto the bottom of the thin
/// light box, 0.02 below it, whose photons would otherwise be counted on the ceiling).
fn comparable(algorithm: &str, mask: u32, view: &BlockView, radius: f32) -> bool {
    let lt_ok = algorithm != "lt" || (!view.specular && !view.emitter_or_background);
    let delta_ok = !delta_lights(mask) || !view.specular;
    let merging = matches!(algorithm, "ppm" | "bpm" | "vcm");
    let edge_ok = !merging || view.clearance > radius;
    lt_ok && delta_ok && edge_ok
}

/// Runs the comparisons of `algorithms` against a long `bpt` run on each scene of `masks`,
/// and of that `bpt` run against a long `pt` run on the scenes without delta lights. Panics
/// listing every failed comparison, and every comparison that cannot detect a relative bias
/// of `power(algorithm)` of the tested estimate (`bpt` for bpt against pt).
fn check(
    masks: &[u32],
    algorithms: &[Plan],
    reference: Plan,
    pt_reference: Plan,
    spectral: bool,
    power: impl Fn(&str) -> f64,
) {
    let mut comparisons: Vec<(u32, Plan, Option<Plan>)> = Vec::new();
    for &mask in masks {
        for &plan in algorithms {
            if !(plan.algorithm == "pt" && delta_lights(mask)) {
                comparisons.push((mask, plan, None));
            }
        }
        if !delta_lights(mask) {
            comparisons.push((mask, reference, Some(pt_reference)));
        }
    }
    // Šidák over the comparisons here, over the entries inside `z_test_entries`.
    let alpha = testkit::sidak(ALPHA, comparisons.len());
    let mut failures = Vec::new();
    for &mask in masks {
        let scene: Scene = cornell::build(mask, RESOLUTION, RESOLUTION).unwrap();
        let views = block_views(&scene, RESOLUTION / GRID);
        let radius = RADIUS_FACTOR * scene.bounding_sphere.radius;
        let bpt = estimate(mask, reference, 1, spectral);
        for &(_, plan, against) in comparisons.iter().filter(|c| c.0 == mask) {
            let tested = if against.is_some() { "bpt" } else { plan.algorithm };
            let result = match against {
                None => {
                    let a = estimate(mask, plan, 2, spectral);
                    let what = format!("scene {mask}: {} vs bpt", plan.algorithm);
                    Comparison::new(
                        what,
                        &a,
                        &bpt,
                        &views,
                        |v| comparable(plan.algorithm, mask, v, radius),
                        alpha,
                        0.02,
                    )
                }
                Some(pt) => {
                    let p = estimate(mask, pt, 3, spectral);
                    let what = format!("scene {mask}: bpt vs pt");
                    Comparison::new(what, &bpt, &p, &views, |_| true, alpha, 0.02)
                }
            };
            if !result.outcome.passed {
                failures.push(format!("{}: {}", result.what, result.outcome));
            }
            if result.detectable > power(tested) {
                failures.push(format!("{}: no power to see a bias of {} %", result.what, 100.0 * power(tested)));
            }
        }
    }
    assert!(failures.is_empty(), "inconsistent estimates:\n{}", failures.join("\n"));
}

const PT_REFERENCE: Plan = Plan { algorithm: "pt", scale: 1, iterations: 4000 };

/// Power: every comparison detects a bias of 3.5 % (measured: pt 3.0 %, ppm 2.6 %, bpm and
/// bpt against pt 2.2 %, lt, vcm ≤ 1.4 %); `all_algorithms_agree_with_bpt_on_every_scene` (slow
/// tier, 4 × the samples) detects 2 % on this scene.
#[test]
fn algorithms_agree_with_bpt_on_the_area_light_scene() {
    check(
        &[273],
        &[
            Plan { algorithm: "pt", scale: 1, iterations: 1000 },
            Plan { algorithm: "lt", scale: 1, iterations: 1000 },
            Plan { algorithm: "ppm", scale: 4, iterations: 100 },
            Plan { algorithm: "bpm", scale: 4, iterations: 100 },
            Plan { algorithm: "vcm", scale: 4, iterations: 50 },
        ],
        Plan { algorithm: "bpt", scale: 1, iterations: 3000 },
        PT_REFERENCE,
        false,
        |_| 0.035,
    );
}

/// The area-light scene in spectral mode, where the merging algorithms merge across wavelength
/// groups (every camera vertex with the photons of all K groups, each at its group's
/// wavelengths, `render::vcm::wavelengths`): ppm, bpm and vcm against spectral bpt (and bpt
/// against spectral pt). Power: a bias of 3.5 %, as the RGB test.
#[test]
fn merging_across_wavelength_groups_agrees_with_bpt_spectral() {
    check(
        &[273],
        &[
            Plan { algorithm: "ppm", scale: 4, iterations: 100 },
            Plan { algorithm: "bpm", scale: 4, iterations: 100 },
            Plan { algorithm: "vcm", scale: 4, iterations: 50 },
        ],
        Plan { algorithm: "bpt", scale: 1, iterations: 3000 },
        PT_REFERENCE,
        true,
        |_| 0.035,
    );
}

/// The fluorescent Cornell box (`cornell-fluorescent`, RGB mode: the reradiation matrix).
/// Power: every comparison detects a bias of 2 % (measured 0.8–1.5 %).
#[test]
fn algorithms_agree_with_bpt_on_the_fluorescent_scene() {
    check(
        &[cornell::FLUORESCENT | cornell::CEILING_LIGHT],
        &[
            Plan { algorithm: "pt", scale: 1, iterations: 1000 },
            Plan { algorithm: "lt", scale: 1, iterations: 1000 },
            Plan { algorithm: "ppm", scale: 4, iterations: 100 },
            Plan { algorithm: "bpm", scale: 4, iterations: 100 },
            Plan { algorithm: "vcm", scale: 4, iterations: 50 },
        ],
        Plan { algorithm: "bpt", scale: 1, iterations: 3000 },
        PT_REFERENCE,
        false,
        |_| 0.02,
    );
}

/// The fluorescent Cornell box in spectral mode: pt, lt and vcm against bpt (and bpt against
/// pt). Power: pt, lt and bpt detect a bias of 3 % (measured 1.0–2.4 %), vcm 12 % asserted
/// (measured 1.2 % with K = 4 wavelength groups; the bound dates from one wavelength set per
/// iteration). The merging-only algorithms are in
/// [`known_deviation_photon_mapping_on_the_fluorescent_scene_spectral`].
#[test]
#[ignore = "slow: run with --ignored"]
fn algorithms_agree_with_bpt_on_the_fluorescent_scene_spectral() {
    check(
        &[cornell::FLUORESCENT | cornell::CEILING_LIGHT],
        &[
            Plan { algorithm: "pt", scale: 1, iterations: 2000 },
            Plan { algorithm: "lt", scale: 1, iterations: 2000 },
            Plan { algorithm: "vcm", scale: 2, iterations: 1000 },
        ],
        Plan { algorithm: "bpt", scale: 1, iterations: 6000 },
        Plan { algorithm: "pt", scale: 1, iterations: 8000 },
        true,
        |algorithm| if algorithm == "vcm" { 0.12 } else { 0.03 },
    );
}

/// ppm and bpm on the fluorescent box in spectral mode, which since wavelength groups (K = 4)
/// are precise enough to show a deviation: both are low in the red channel of the same block
/// ((3, 5): z = −3.9 and −5.2; on the branch that introduced the groups, with other random
/// streams, z = −4.1 and −3.6 at the same place), while vcm there agrees with bpt. The block is
/// dim in red and heavy-tailed: bpm with another seed (`vcm render --scene-mask 513 --spectral
/// -a bpm -r 64x64 -i 1500 --radius-factor 0.01 --seed 6 --variance …` against bpt at 32²,
/// 6000 iterations) is 33 % low there but at z = −1.3 with the per-pixel variances.
///
/// **Explained as heavy tails, not a bias** (measured the same way with seeds 1–3, radius
/// factor 0.01, red mean of block (3, 5) over bpt's): ppm 1.06 (z 0.1), 0.23 (z −3.9), 1.81
/// (z +1.3); bpm 0.89 (z −0.4), 0.37 (z −5.1) at seed 2. The block's estimate swings by a
/// factor of 8 between seeds while each run's standard error (from the spread of its
/// iterations) claims a few %: its red light comes from rare fluorescent photon paths, the mean
/// of 1500 iterations is far from normal, and a run that misses the rare paths is low with a
/// spurious |z| of 4–5. ppm and bpm with the same seed trace the same light sub-paths, so both
/// are low together at seed 2, the seed this test uses (and both were low on the earlier
/// branch for the same reason). The mean ratio over the five runs is 0.87 ± 0.29; the pooled
/// image means of all five are within 0.4 % of bpt's in every channel. A Z-test cannot judge
/// such a block; the test stays out of CI's slow tier by its name (`.ci/run` skips
/// `known_deviation_`) as the record of this measurement.
#[test]
#[ignore = "known deviation, see the doc comment: run with --ignored known_deviation_"]
fn known_deviation_photon_mapping_on_the_fluorescent_scene_spectral() {
    check(
        &[cornell::FLUORESCENT | cornell::CEILING_LIGHT],
        &[Plan { algorithm: "ppm", scale: 2, iterations: 1500 }, Plan { algorithm: "bpm", scale: 2, iterations: 1500 }],
        Plan { algorithm: "bpt", scale: 1, iterations: 6000 },
        Plan { algorithm: "pt", scale: 1, iterations: 8000 },
        true,
        |_| 0.12,
    );
}

/// Power: every comparison detects a bias of 2 % (measured 0.3–1.9 %, the largest lt and ppm
/// on scene 456 and pt on scene 273); asserted with a margin for other random streams: 2.5 %.
#[test]
#[ignore = "slow: run with --ignored"]
fn all_algorithms_agree_with_bpt_on_every_scene() {
    check(
        &[450, 273, 452, 456],
        &[
            Plan { algorithm: "pt", scale: 1, iterations: 4000 },
            Plan { algorithm: "lt", scale: 1, iterations: 4000 },
            Plan { algorithm: "ppm", scale: 4, iterations: 400 },
            Plan { algorithm: "bpm", scale: 4, iterations: 300 },
            Plan { algorithm: "vcm", scale: 4, iterations: 200 },
        ],
        Plan { algorithm: "bpt", scale: 1, iterations: 12000 },
        Plan { algorithm: "pt", scale: 1, iterations: 16000 },
        false,
        |_| 0.025,
    );
}
