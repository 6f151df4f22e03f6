//! The VCM engine's algorithms in homogeneous media (`render::vcm::medium`) against closed
//! forms, on an index-matched (null boundary) sphere of radius R = 1 filled with a medium of
//! albedo 1 (chromatic σ_t = (0.5, 1, 2), Henyey–Greenstein g = 0.6) under a uniform
//! environment of radiance 1, seen by a pinhole camera at distance 3 whose image covers the
//! sphere and some sky. The medium conserves energy, so every camera ray sees radiance 1 per
//! channel (up to paths longer than the length limit of 200 segments, whose share is below
//! 10⁻⁹ at these optical depths).
//!
//! Every iteration's frame is an independent estimate: the per-channel image means over
//! iterations, with standard errors from their spread, are Z-tested against the truth
//! (Šidák, family-wise α = 1e-3), and the same data must reject the truth scaled by 1 ± 3 %
//! ([`common::detectable_bias`]): the power to see a 3 % bias.
//!
//! Known open problem (the reason lt and bpt refuse a camera inside a medium): with the camera
//! at the sphere's centre, bpt at a length limit of 2 gives 0.712 ± 0.002 where pt and each of
//! bpt's three techniques alone (unweighted) give 0.700 ± 0.001 (grey σ_t = 1); the weights of
//! a sampled path recomputed from the same densities sum to 1. Not resolved.

mod common;

use math::Vec3;
use render::driver::{Budget, Renderer};
use render::{Algorithm, RenderSettings};
use scene::Scene;
use scene::desc::{CameraDesc, FilmDesc, FilterDesc, Geometry, LightDesc, Projection, SceneDescription, ShapeDesc};
use scene::material::Material;
use scene::medium::{Coefficient, Coefficients, MediaDesc, Medium, MediumInterface, PhaseFunction};
use scene::texture::Texture;
use spectrum::Rgb;
use testkit::{MeanVar, sidak, z_test_entries};

const SIGMA_T: [f32; 3] = [0.5, 1.0, 2.0];
const MAX_LENGTH: u32 = 200;
const POWER: f64 = 0.03;
/// The camera position of the outside view.
const CAMERA: Vec3 = Vec3::new(0.0, 0.0, -3.0);

/// The medium sphere of radius 1 (around the camera when `inside`, else seen from
/// [`CAMERA`]), under an environment of radiance 1.
fn furnace(resolution: u32, inside: bool) -> Scene {
    let medium = Medium {
        coefficients: Coefficients::ExtinctionAlbedo {
            sigma_t: Coefficient::rgb(Rgb::new(SIGMA_T[0], SIGMA_T[1], SIGMA_T[2])),
            albedo: Coefficient::rgb(Rgb::splat(1.0)),
        },
        scale: 1.0,
        phase: PhaseFunction::henyey_greenstein(0.6).unwrap(),
    };
    let camera = inside.then_some(0);
    let mut media = MediaDesc { media: vec![medium], null_materials: vec![0], camera, ..Default::default() };
    media.shapes.insert(0, MediumInterface { interior: Some(0), exterior: None });
    let desc = SceneDescription {
        name: "medium furnace".into(),
        camera: CameraDesc {
            position: if inside { Vec3::ZERO } else { CAMERA },
            forward: Vec3::Z,
            up: Vec3::Y,
            right: Vec3::X,
            projection: Projection::Perspective { horizontal_fov_degrees: 60.0 },
        },
        film: FilmDesc { width: resolution, height: resolution, filter: FilterDesc::Box },
        materials: vec![Material::Diffuse { reflectance: Texture::Constant(Rgb::BLACK) }],
        shapes: vec![ShapeDesc {
            name: "sphere".into(),
            geometry: Geometry::Sphere { center: Vec3::ZERO, radius: 1.0, flip_normals: false },
            material: 0,
            emission: None,
            alpha: None,
        }],
        lights: vec![LightDesc::Constant { radiance: Rgb::splat(1.0) }],
        max_path_length: None,
        warnings: Vec::new(),
        emission_spectra: Default::default(),
        objects: Vec::new(),
        instances: Vec::new(),
        media,
    };
    Scene::from_description(&desc, None).unwrap().0
}

/// Per-iteration per-channel image means of `algorithm` on `scene`.
fn channel_means(scene: &Scene, algorithm: &str, iterations: u64, spectral: bool, seed: u64) -> Vec<MeanVar> {
    let settings = RenderSettings {
        algorithm: Algorithm::from_name(algorithm).unwrap(),
        budget: Budget::Iterations(iterations),
        max_length: MAX_LENGTH,
        seed,
        spectral,
        ..RenderSettings::default()
    };
    let mut renderer = Renderer::new(scene, &settings).unwrap();
    let mut stats = vec![MeanVar::new(); 3];
    for _ in 0..iterations {
        assert_eq!(renderer.step(), 0, "{algorithm}: rejected samples");
        let pixels = &renderer.frame().pixels;
        let mut sums = [0.0f64; 3];
        for p in pixels {
            for (s, v) in sums.iter_mut().zip(p.to_array()) {
                *s += f64::from(v);
            }
        }
        for (s, sum) in stats.iter_mut().zip(sums) {
            s.push(sum / pixels.len() as f64);
        }
    }
    stats
}

/// Z-tests `stats` against `truth` per channel and checks the power; returns the failure.
fn judge(what: &str, stats: &[MeanVar], truth: &[f64], alpha: f64) -> Option<String> {
    let means: Vec<f64> = stats.iter().map(MeanVar::mean).collect();
    let errors: Vec<f64> = stats.iter().map(MeanVar::std_error).collect();
    let exact = vec![0.0; truth.len()];
    let outcome = z_test_entries(&means, &errors, truth, &exact, alpha);
    let detectable = common::detectable_bias(&means, &errors, truth, &exact, alpha);
    let line = format!(
        "{what}: means {:?} ± {:?} vs {truth:?}; detects a bias of {:.2} %; {outcome}",
        means.iter().map(|m| format!("{m:.4}")).collect::<Vec<_>>(),
        errors.iter().map(|e| format!("{e:.4}")).collect::<Vec<_>>(),
        100.0 * detectable
    );
    eprintln!("{line}");
    if detectable > POWER {
        return Some(format!("{line}: no power to see a bias of {} %", 100.0 * POWER));
    }
    (!outcome.passed).then_some(line)
}

#[test]
fn bpt_with_media_gives_the_furnace_radiance() {
    let runs: [(u64, bool); 2] = [(400, false), (200, true)];
    let alpha = sidak(1e-3, runs.len());
    let scene = furnace(16, false);
    let mut failures = Vec::new();
    for (i, &(iterations, spectral)) in runs.iter().enumerate() {
        let stats = channel_means(&scene, "bpt", iterations, spectral, 77 + i as u64);
        let what = format!("bpt{}", if spectral { " spectral" } else { "" });
        failures.extend(judge(&what, &stats, &[1.0; 3], alpha));
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

#[test]
fn refusals_name_the_issue() {
    let outside = furnace(4, false);
    let inside = furnace(4, true);
    let cases = [(&outside, "ppm"), (&outside, "bpm"), (&outside, "vcm"), (&inside, "lt"), (&inside, "bpt")];
    for (scene, name) in cases {
        let settings = RenderSettings { algorithm: Algorithm::from_name(name).unwrap(), ..RenderSettings::default() };
        let error = Renderer::new(scene, &settings).err().expect("refused");
        assert!(error.contains("issue #15"), "{name}: {error}");
    }
    for name in ["pt", "lt", "bpt"] {
        let settings = RenderSettings { algorithm: Algorithm::from_name(name).unwrap(), ..RenderSettings::default() };
        assert!(Renderer::new(&outside, &settings).is_ok(), "{name}");
    }
}
