//! The analytic furnace for every algorithm of the VCM engine (and the path tracer for
//! reference): a closed cube whose inner faces all emit `Le` and reflect diffusely with albedo
//! `ρ`. The radiance is then the same at every point and in every direction, `Le·Σ_{k<K} ρ^k`
//! for a maximum path length of `K` segments, whatever the geometry; light tracing, which
//! cannot see emitters directly, gets `Le·Σ_{1≤k<K} ρ^k`.
//!
//! Every iteration's frame is an independent estimate, so the block means and the image mean
//! over iterations, with standard errors from the spread of the iterations, support two-sided
//! Z-tests against the exact value (Šidák-corrected over every entry of every case, family-wise
//! α = 1e-3).
//!
//! **Power.** Every Z-test is also run on the same estimates scaled by `1 ± β`
//! ([`common::detectable_bias`]) to find the smallest relative bias `β` it rejects, which is
//! asserted: at most 2 % for every algorithm. Measured (2026-11-30): pt, bpt and vcm at most
//! 1.01 % (500 iterations; 0.42 % at the 2000 they had before), lt 1.86 % (K = 1; 4000
//! iterations). The merging algorithms (ppm, bpm) run every case only in the slow tier's
//! `merging_algorithms_resolve_a_2_percent_bias` (800 iterations; measured 1.1–1.7 %) and, in
//! the default tier, the mixed-material test (150 iterations; ppm 1.65 %, bpm 1.48 %).

use crate::common;

use render::driver::{Budget, Renderer};
use render::{Algorithm, RenderSettings};
use scene::{Material, ReferenceMaterial};
use spectrum::Rgb;
use testkit::{MeanVar, sidak, z_test_entries};

/// How one algorithm is run on the furnace.
struct Run {
    algorithm: &'static str,
    resolution: u32,
    iterations: u64,
    radius_factor: f32,
}

/// Blocks per image side.
const BLOCKS: u32 = 8;

// Non-merging algorithms are unbiased: a tiny image and many iterations.
//
// The merging algorithms (ppm, bpm) are only consistent. In the furnace the incident radiance
// is uniform and isotropic everywhere, so the density estimate over the merging disc is exact
// wherever the ball of radius r around the camera vertex cuts a single face: the only bias
// comes from vertices closer than r to an edge, where the ball also catches photons of the
// neighbouring face(s). For a vertex at distance d < r from an edge, the disc loses the
// segment beyond the edge (area r²·acos(d/r) − d·√(r²−d²)) and gains half a disc of radius
// √(r²−d²) on the perpendicular face, of which only the half of the photons arriving from
// above the vertex's own face count: the estimate is (πr² − segment + π(r²−d²)/4)/πr² of the
// truth, between 0.75 and 1, on average over d ∈ [0, r] 1 − (2/3 − π/6)/π ≈ 1 − 0.046.
// Vertices fall within r of an edge with probability about 2r (faces of side 2) times the
// ratio of their density to the uniform one (a few for the primary hits; later vertices of a
// closed enclosure are spread at most as unevenly as the first). With r = 1e-3·R = 1.7e-3
// (R = √3) the relative bias is thus of order 0.046·2r·3 ≈ 5e-4 and at most 0.25·2r·3 ≈ 3e-3,
// below the standard errors reached here (≈ 5e-3 of the value for the image mean, ≈ 4e-2 for
// a block). The price of the small radius is variance (few photons per merge), paid for with a
// larger image: the number of photons in a merging disc grows with the number of light paths.
//
// pt, bpt and vcm detected at most 0.42 % at 2000 iterations (2026-11-30), a fifth of the 2 %
// asserted; at a quarter of the iterations (the detectable bias scales as 1/√N), 1.01 %.
const NON_MERGING: [Run; 4] = [
    Run { algorithm: "pt", resolution: 16, iterations: 500, radius_factor: 1e-3 },
    // Light tracing is noisier per path (1.86 % detectable at 4000 iterations for K = 1).
    Run { algorithm: "lt", resolution: 16, iterations: 4000, radius_factor: 1e-3 },
    Run { algorithm: "bpt", resolution: 16, iterations: 500, radius_factor: 1e-3 },
    // VCM at a small radius: the merges get small MIS weights but are all evaluated.
    Run { algorithm: "vcm", resolution: 16, iterations: 500, radius_factor: 1e-3 },
];
/// The merging runs of the mixed-material test (default tier): at 100 iterations ppm detected
/// 1.98 % there (2026-11-30), too close to the 2 % asserted; at 150, 1.65 % (bpm 1.48 %).
const MERGING: [Run; 2] = [
    Run { algorithm: "ppm", resolution: 128, iterations: 150, radius_factor: 1e-3 },
    Run { algorithm: "bpm", resolution: 128, iterations: 150, radius_factor: 1e-3 },
];
/// The merging runs of the slow tier, with the power to see a 2 % bias.
const MERGING_POWERED: [Run; 2] = [
    Run { algorithm: "ppm", resolution: 128, iterations: 800, radius_factor: 1e-3 },
    Run { algorithm: "bpm", resolution: 128, iterations: 800, radius_factor: 1e-3 },
];
/// Smallest relative bias every test here must detect.
const POWER: f64 = 0.02;

/// (Le, ρ, K) cases.
const CASES: [(f32, f32, u32); 5] = [(1.0, 0.5, 1), (1.0, 0.5, 2), (0.5, 0.8, 3), (1.0, 0.5, 10), (0.25, 0.9, 10)];

/// Per-iteration means of the blocks and of the whole image (last entry), channel-averaged
/// (the furnace is grey).
fn furnace_statistics(emission: f32, albedo: f32, max_length: u32, run: &Run, seed: u64) -> Vec<MeanVar> {
    statistics(&common::furnace(emission, albedo, run.resolution), max_length, run, seed)
}

/// Per-iteration block and image means of `run` on `scene`.
fn statistics(scene: &scene::Scene, max_length: u32, run: &Run, seed: u64) -> Vec<MeanVar> {
    let settings = RenderSettings {
        algorithm: Algorithm::from_name(run.algorithm).unwrap(),
        budget: Budget::Iterations(run.iterations),
        max_length,
        seed,
        radius_factor: run.radius_factor,
        ..RenderSettings::default()
    };
    let mut renderer = Renderer::new(scene, &settings).unwrap();
    let (size, block) = (run.resolution as usize, (run.resolution / BLOCKS) as usize);
    let blocks = (BLOCKS * BLOCKS) as usize;
    let mut stats = vec![MeanVar::new(); blocks + 1];
    renderer.in_pool(|renderer| {
        for _ in 0..run.iterations {
            assert_eq!(renderer.step(), 0, "{}: rejected samples", run.algorithm);
            let mut sums = vec![0.0f64; blocks];
            for (i, p) in renderer.frame().pixels.iter().enumerate() {
                let (x, y) = (i % size, i / size);
                sums[(y / block) * BLOCKS as usize + x / block] += p.to_array().iter().map(|&v| v as f64).sum::<f64>();
            }
            let per_block = (block * block * 3) as f64;
            for (s, sum) in stats.iter_mut().zip(&sums) {
                s.push(sum / per_block);
            }
            stats[blocks].push(sums.iter().sum::<f64>() / (size * size * 3) as f64);
        }
    });
    stats
}

/// Z-tests the block and image means in `stats` against `expected` at family-wise level
/// `alpha`; checks the power: the same test rejects the estimates scaled by `1 ± power`
/// (when `expected > 0`). Returns the failure, or the lack of power.
fn judge(what: &str, stats: &[MeanVar], expected: f64, alpha: f64, power: f64) -> Option<String> {
    let means: Vec<f64> = stats.iter().map(MeanVar::mean).collect();
    let errors: Vec<f64> = stats.iter().map(MeanVar::std_error).collect();
    let (truth, exact) = (vec![expected; means.len()], vec![0.0; means.len()]);
    let outcome = z_test_entries(&means, &errors, &truth, &exact, alpha);
    let detectable = if expected > 0.0 { common::detectable_bias(&means, &errors, &truth, &exact, alpha) } else { 0.0 };
    let image = stats.last().unwrap();
    let line = format!(
        "{what}: image {:.5} ± {:.5} vs {expected:.5} (z = {:.2}); detects a bias of {:.2} %; {outcome}",
        image.mean(),
        image.std_error(),
        (image.mean() - expected) / image.std_error().max(1e-300),
        100.0 * detectable,
    );
    eprintln!("{line}");
    if detectable > power {
        return Some(format!("{line}: no power to see a bias of {} %", 100.0 * power));
    }
    (!outcome.passed).then_some(line)
}

/// Runs every case of [`CASES`] with every run of `runs`, each of which must detect the
/// relative bias paired with it.
fn geometric_series(runs: &[(&Run, f64)]) {
    // One family of entries per (case, algorithm); Šidák over the families here, over the
    // entries of a family inside `z_test_entries`: family-wise α = 1e-3 over everything.
    let alpha = sidak(1e-3, CASES.len() * runs.len());
    let mut failures = Vec::new();
    for (case, &(emission, albedo, max_length)) in CASES.iter().enumerate() {
        for &(run, power) in runs {
            let expected: f64 = (0..max_length).map(|k| emission as f64 * (albedo as f64).powi(k as i32)).sum();
            let stats = furnace_statistics(emission, albedo, max_length, run, 1000 + case as u64);
            let what = format!("Le={emission} ρ={albedo} K={max_length} {}", run.algorithm);
            failures.extend(judge(&what, &stats, expected, alpha, power));
        }
    }
    assert!(failures.is_empty(), "furnace failures:\n{}", failures.join("\n"));
}

/// pt, lt, bpt and vcm on every case. The merging algorithms run every case in the slow tier
/// ([`merging_algorithms_resolve_a_2_percent_bias`], 8 × the iterations this test gave them
/// until 2026-11-30, when it asserted only a 5 % bias) and in the default tier the
/// mixed-material furnace ([`mixed_diffuse_and_mirror_material_gives_the_geometric_series`],
/// 2 %).
#[test]
fn every_algorithm_gives_the_geometric_series() {
    geometric_series(&NON_MERGING.iter().map(|r| (r, POWER)).collect::<Vec<_>>());
}

#[test]
#[ignore = "slow: run with --ignored"]
fn merging_algorithms_resolve_a_2_percent_bias() {
    geometric_series(&MERGING_POWERED.iter().map(|r| (r, POWER)).collect::<Vec<_>>());
}

#[test]
fn one_segment_is_exactly_the_emission() {
    // K = 1: only emitters seen directly, which every algorithm with camera sub-paths sees
    // with weight 1, exactly.
    for algorithm in ["pt", "ppm", "bpm", "bpt", "vcm"] {
        let run = Run { algorithm, resolution: 8, iterations: 20, radius_factor: 1e-2 };
        let stats = furnace_statistics(0.75, 0.5, 1, &run, 7);
        assert!(stats.iter().all(|s| s.mean() == 0.75 && s.variance() == 0.0), "{algorithm}");
    }
    // Light tracing estimates them by connecting the emitter's point to the camera (s = 1,
    // t = 1): unbiased, not exact, and it must see a 2 % bias.
    let run = Run { algorithm: "lt", resolution: 8, iterations: 12_000, radius_factor: 1e-2 };
    let stats = furnace_statistics(0.75, 0.5, 1, &run, 7);
    assert!(stats.iter().all(|s| s.mean() > 0.0), "lt sees the emitter directly");
    let failure = judge("Le=0.75 K=1 lt", &stats, 0.75, 1e-3, POWER);
    assert!(failure.is_none(), "{}", failure.unwrap_or_default());
}

#[test]
fn mixed_diffuse_and_mirror_material_gives_the_geometric_series() {
    // Every face reflects diffusely with 0.3 and as a mirror with 0.4: total albedo 0.7 in
    // every direction, so the radiance is Le·Σ_{k<K} 0.7^k. Photon mapping must merge at the
    // mixed vertices for their diffuse part and continue through their mirror lobe (there is
    // no non-mixed vertex to fall back to); BPT and VCM must handle specular lobes sampled at
    // vertices that are stored and connected. (Light tracing cannot see the mirror lobe of the
    // first surface and is left out.)
    let material: Material =
        ReferenceMaterial { diffuse: Rgb::splat(0.3), mirror: Rgb::splat(0.4), ..ReferenceMaterial::BLACK }.into();
    let (emission, max_length) = (1.0f32, 4u32);
    let expected: f64 = (0..max_length).map(|k| 0.7f64.powi(k as i32)).sum::<f64>() * emission as f64;
    let runs: Vec<&Run> = NON_MERGING.iter().filter(|r| r.algorithm != "lt").chain(&MERGING).collect();
    let alpha = sidak(1e-3, runs.len());
    let mut failures = Vec::new();
    for run in runs {
        let scene = common::furnace_with(emission, material.clone(), run.resolution);
        let stats = statistics(&scene, max_length, run, 77);
        failures.extend(judge(&format!("mixed material {}", run.algorithm), &stats, expected, alpha, POWER));
    }
    assert!(failures.is_empty(), "furnace failures:\n{}", failures.join("\n"));
}
