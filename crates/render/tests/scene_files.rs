//! Scene files through the whole renderer: every Mitsuba scene of `shared/scenes/mitsuba/`
//! renders with every algorithm; the caustic of the glass sphere in `caustic-cbox` is found by
//! the merging algorithms and BPT agrees with PT on it; the pbrt-v4 Cornell box renders like its
//! Mitsuba twin; a GGX conductor of F = 1 in a furnace loses energy only through its
//! single-scattering model.

use crate::common;

use scene::microfacet::Distribution;
use std::path::PathBuf;

use math::{Rng, Vec3};
use render::driver::Budget;
use scene::desc::SceneDescription;
use scene::{Bsdf, Material, Scene, ShadingPoint, Texture, TransportMode};
use spectrum::Rgb;
use testkit::z_test_entries;

const ALGORITHMS: [&str; 6] = ["pt", "lt", "ppm", "bpm", "bpt", "vcm"];

fn shared() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/scenes/mitsuba")
}

fn repository() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Loads a scene file at `resolution`. The tests that read `../shared` are named `shared_*`
/// and ignored; `.ci/run` runs them where it is present, and without it they fail here.
fn load(path: PathBuf, resolution: Option<(u32, u32)>) -> (Scene, SceneDescription) {
    assert!(path.exists(), "{} is absent (the scenes of ../shared must lie beside the clone)", path.display());
    let desc = io::load_scene(&path, &[]).unwrap_or_else(|e| panic!("{e}"));
    let (scene, _) = Scene::from_description(&desc, resolution).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    (scene, desc)
}

#[test]
#[ignore = "needs ../shared: the Mitsuba scenes"]
fn shared_every_mitsuba_scene_renders_with_every_algorithm() {
    let scenes = [
        "cornell-box/cornell_box.xml",
        "caustic-cbox/cbox.xml",
        "cbox-classic/cbox.xml",
        "cbox-classic/cbox-rgb.xml",
        "cbox-classic/cbox-spectral.xml",
        "veach-mis/veach_mis_path.xml",
        "veach-mis/integrator_direct_both.xml",
        "matpreview/matpreview.xml",
    ];
    for name in scenes {
        let (scene, desc) = load(shared().join(name), Some((40, 30)));
        for algorithm in ALGORITHMS {
            let mut settings = common::settings(algorithm, 3);
            settings.max_length = desc.max_path_length.unwrap_or(12).min(12);
            settings.budget = Budget::Iterations(2);
            let output = render::render(&scene, &settings).unwrap();
            let film = &output.film;
            assert_eq!(film.rejected_samples(), 0, "{name} {algorithm}: rejected samples");
            let mean: f64 = film.mean().iter().flat_map(|p| p.iter()).map(|v| *v as f64).sum::<f64>();
            assert!(mean.is_finite() && mean > 0.0, "{name} {algorithm}: image mean {mean}");
        }
    }
}

/// Block means (8×8 blocks over a window of blocks) for one algorithm.
fn window_estimate(
    scene: &Scene,
    algorithm: &str,
    max_length: u32,
    iterations: u64,
    seed: u64,
    window: &[usize],
) -> (Vec<f64>, Vec<f64>) {
    let mut settings = common::settings(algorithm, seed);
    settings.max_length = max_length;
    let estimate = common::block_estimate(scene, &settings, iterations, 8);
    let mut means = Vec::new();
    let mut errors = Vec::new();
    for &b in window {
        means.extend_from_slice(&estimate.means[b * 3..b * 3 + 3]);
        errors.extend_from_slice(&estimate.std_errors[b * 3..b * 3 + 3]);
    }
    (means, errors)
}

#[test]
#[ignore = "needs ../shared: the Mitsuba caustic-cbox"]
fn shared_caustic_of_the_glass_sphere_agrees_between_algorithms() {
    let (scene, desc) = load(shared().join("caustic-cbox/cbox.xml"), Some((64, 64)));
    let max_length = desc.max_path_length.unwrap();
    // The floor below the glass sphere (centre (0.5, −0.75, −0.2), radius 0.25, floor y = −1).
    let below = scene.camera.raster_position(Vec3::new(0.5, -0.99, -0.2)).expect("the caustic is in view");
    let (bx, by) = ((below.x / 8.0) as usize, (below.y / 8.0) as usize);
    // The caustic's block and its neighbours on the floor.
    let window: Vec<usize> =
        [(bx, by), (bx - 1, by), (bx + 1, by), (bx, by - 1)].iter().map(|(x, y)| y * 8 + x).collect();
    let (pt, pt_se) = window_estimate(&scene, "pt", max_length, 400, 1, &window);
    for (algorithm, iterations) in [("bpt", 200), ("vcm", 200)] {
        let (other, other_se) = window_estimate(&scene, algorithm, max_length, iterations, 2, &window);
        let outcome = z_test_entries(&other, &other_se, &pt, &pt_se, 1e-3);
        eprintln!("caustic window, {algorithm} vs pt: worst z {:.2} of {} entries", outcome.worst_z, outcome.entries);
        assert!(outcome.passed, "{algorithm} disagrees with pt on the caustic: {outcome:?}\n{other:?}\n{pt:?}");
    }
}

#[test]
#[ignore = "needs ../shared: Mitsuba's Cornell box"]
fn shared_pbrt_cornell_box_renders_like_its_mitsuba_twin() {
    let (mitsuba, desc) = load(shared().join("cornell-box/cornell_box.xml"), Some((64, 64)));
    let (pbrt, pbrt_desc) = load(repository().join("scenes/cornell-box.pbrt"), Some((64, 64)));
    assert_eq!(desc.max_path_length, pbrt_desc.max_path_length);
    let max_length = desc.max_path_length.unwrap();
    let all: Vec<usize> = (0..64).collect();
    let (a, a_se) = window_estimate(&mitsuba, "pt", max_length, 256, 1, &all);
    let (b, b_se) = window_estimate(&pbrt, "pt", max_length, 256, 2, &all);
    let outcome = z_test_entries(&a, &a_se, &b, &b_se, 1e-3);
    eprintln!("pbrt vs Mitsuba twin: worst z {:.2} of {} entries", outcome.worst_z, outcome.entries);
    assert!(outcome.passed, "the twins differ: {outcome:?}");
}

/// Monte Carlo directional albedo of `material` at incidence cosine `cos` (BSDF sampling).
fn albedo(material: &Material, cos: f32, samples: usize) -> f64 {
    let fixed = Vec3::new((1.0 - cos * cos).sqrt(), 0.0, cos);
    let bsdf = Bsdf::new(material, &ShadingPoint::flat(Vec3::Z), fixed, TransportMode::Radiance).unwrap();
    let mut rng = Rng::for_stream(9, 0, 0);
    let mut sum = 0.0f64;
    for _ in 0..samples {
        if let Some(s) = bsdf.sample(rng.uniform3()) {
            sum += (s.value.r * s.cos_generated / s.pdf.forward.0) as f64;
        }
    }
    sum / samples as f64
}

#[test]
fn ggx_conductor_furnace_loses_energy_only_to_single_scattering() {
    // F = 1 everywhere (eta = k = 0): every loss comes from the single-scattering microfacet
    // model (paths that would scatter again between microfacets are dropped).
    let alpha = 0.3;
    let material = Material::RoughConductor {
        distribution: Distribution::Ggx,
        alpha_u: alpha,
        alpha_v: alpha,
        eta: Rgb::BLACK,
        k: Rgb::BLACK,
        specular_reflectance: Texture::Constant(Rgb::WHITE),
    };
    // The directional albedo over incidence angles bounds the furnace's effective albedo.
    let albedos: Vec<f64> = (1..=20).map(|i| albedo(&material, i as f32 / 20.0, 40_000)).collect();
    let (low, high) = albedos.iter().fold((f64::MAX, 0.0f64), |(l, h), a| (l.min(*a), h.max(*a)));
    eprintln!("GGX α = {alpha}, F = 1: directional albedo from {low:.4} to {high:.4}");
    assert!(high < 1.0 + 0.01 && low > 0.5, "albedo range {low}..{high}");

    let emission = 0.5f32;
    let scene = common::furnace_with(emission, material, 16);
    let all: Vec<usize> = (0..4).collect();
    let max_length = 40;
    let (pt, pt_se) = window_estimate(&scene, "pt", max_length, 64, 1, &all);
    // Furnace radiance L = Le / (1 − a) for an effective albedo a between the extremes.
    for (m, se) in pt.iter().zip(&pt_se) {
        let effective = 1.0 - emission as f64 / m;
        eprintln!("pt furnace radiance {m:.4} ± {se:.4}: effective albedo {effective:.4}");
        assert!(
            effective > low - 0.01 && effective < high + 0.01,
            "effective albedo {effective} outside {low}..{high}"
        );
    }
    for algorithm in ["bpt", "vcm"] {
        let (other, other_se) = window_estimate(&scene, algorithm, max_length, 64, 2, &all);
        let outcome = z_test_entries(&other, &other_se, &pt, &pt_se, 1e-3);
        assert!(outcome.passed, "{algorithm} disagrees with pt in the GGX furnace: {outcome:?}");
    }
}
