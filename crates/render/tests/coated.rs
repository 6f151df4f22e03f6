//! pbrt-v4's coated materials through the whole renderer.
//!
//! 1. **Furnace.** A closed cube whose faces emit `Le` and are made of a *lossless* coated
//!    material (white base, clear or white-scattering medium, smooth coating: directional
//!    albedo exactly 1 in every direction, see `crates/scene/tests/coated.rs`) has radiance
//!    `K·Le` for paths of at most `K` segments. pt, bpt and vcm must give it: each exercises the
//!    delta lobe, the closed forms or the random walk, Russian roulette by the closed-form albedo
//!    and, for bpt and vcm, the deterministic pdfs in the MIS weights (a weight sum other than 1
//!    would show as a bias).
//! 2. **Consistency.** A pbrt scene with a rough coated diffuse and a rough coated conductor over
//!    a scattering medium, lit by an area light and a constant environment: bpt and vcm agree with
//!    pt (image means per channel).
//!
//! Z-tests at family-wise α = 1e-3 (Šidák); each test also asserts the smallest relative bias
//! it would reject (`common::detectable_bias`).

use crate::common;

use std::path::PathBuf;

use render::driver::{Budget, Renderer};
use render::{Algorithm, RenderSettings};
use scene::material::{CoatedBase, CoatedParameters, CoatingInterface, CoatingLayer, ConductorIor};
use scene::{Material, Scene, Texture};
use spectrum::Rgb;
use testkit::{MeanVar, sidak, z_test_entries};

/// Per-iteration image means (channel-averaged for the grey furnace, per channel otherwise).
fn image_statistics(scene: &Scene, algorithm: &str, iterations: u64, max_length: u32, seed: u64) -> [MeanVar; 3] {
    let settings = RenderSettings {
        algorithm: Algorithm::from_name(algorithm).unwrap(),
        budget: Budget::Iterations(iterations),
        max_length,
        seed,
        radius_factor: 1e-3,
        ..RenderSettings::default()
    };
    let mut renderer = Renderer::new(scene, &settings).unwrap();
    let mut stats = [MeanVar::new(); 3];
    for _ in 0..iterations {
        assert_eq!(renderer.step(), 0, "{algorithm}: rejected samples");
        let pixels = &renderer.frame().pixels;
        let mut sums = [0.0f64; 3];
        for p in pixels {
            for (s, v) in sums.iter_mut().zip(p.to_array()) {
                *s += v as f64;
            }
        }
        for (s, sum) in stats.iter_mut().zip(sums) {
            s.push(sum / pixels.len() as f64);
        }
    }
    stats
}

fn lossless(layer: CoatingLayer, base: CoatedBase) -> Material {
    let interface = CoatingInterface { eta: 1.5, alpha_u: 0.0, alpha_v: 0.0 };
    Material::Coated(Box::new(CoatedParameters::new(interface, layer, base).unwrap()))
}

#[test]
fn lossless_coatings_give_the_furnace_series() {
    let white = || CoatedBase::Diffuse { reflectance: Texture::Constant(Rgb::WHITE) };
    let mirror = CoatedBase::Conductor {
        ior: ConductorIor::Complex { eta: Rgb::BLACK, k: Rgb::BLACK },
        alpha_u: 0.0,
        alpha_v: 0.0,
    };
    let layer = |thickness: f32, albedo: f32, g: f32| CoatingLayer {
        thickness,
        albedo: Texture::Constant(Rgb::splat(albedo)),
        g,
        max_depth: 100,
        samples: 1,
    };
    let materials = [
        ("clear coating over white", lossless(layer(0.0, 0.0, 0.0), white())),
        ("white medium over white", lossless(layer(0.3, 1.0, 0.3), white())),
        ("white medium over a mirror", lossless(layer(0.5, 1.0, -0.2), mirror)),
    ];
    let (emission, max_length) = (0.5f32, 4u32);
    let expected = (emission * max_length as f32) as f64;
    let runs = [("pt", 400u64), ("bpt", 400), ("vcm", 400)];
    let alpha = sidak(1e-3, materials.len() * runs.len());
    let mut failures = Vec::new();
    for (m, (name, material)) in materials.iter().enumerate() {
        let scene = common::furnace_with(emission, material.clone(), 16);
        for (algorithm, iterations) in runs {
            let stats = image_statistics(&scene, algorithm, iterations, max_length, 40 + m as u64);
            let mean = [stats.iter().map(MeanVar::mean).sum::<f64>() / 3.0];
            let error = [stats.iter().map(MeanVar::std_error).sum::<f64>() / 3.0];
            let outcome = z_test_entries(&mean, &error, &[expected], &[0.0], alpha);
            let detectable = common::detectable_bias(&mean, &error, &[expected], &[0.0], alpha);
            let line = format!(
                "{name}, {algorithm}: {} ± {} vs {expected}; detects {:.2} %",
                mean[0],
                error[0],
                100.0 * detectable
            );
            eprintln!("{line}");
            if !outcome.passed || detectable > 0.02 {
                failures.push(line);
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

fn consistency_scene() -> Scene {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("coated_consistency");
    std::fs::create_dir_all(&dir).unwrap();
    let text = r#"LookAt 0 -4 2  0 0 0.5  0 0 1
Camera "perspective" "float fov" 40
Film "rgb" "integer xresolution" 16 "integer yresolution" 16
PixelFilter "box"
WorldBegin
LightSource "infinite" "rgb L" [0.3 0.3 0.3]
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [6 6 6]
  Shape "trianglemesh" "point3 P" [-1 -1 3  1 -1 3  1 1 3  -1 1 3] "integer indices" [0 2 1 0 3 2]
AttributeEnd
Material "coateddiffuse" "rgb reflectance" [0.7 0.4 0.2] "float roughness" 0.1 "float thickness" 0.1
Shape "trianglemesh" "point3 P" [-3 -3 0  3 -3 0  3 3 0  -3 3 0] "integer indices" [0 1 2 0 2 3]
Material "coatedconductor" "float interface.roughness" 0.05 "float conductor.roughness" 0.1
    "spectrum conductor.eta" "metal-Au-eta" "spectrum conductor.k" "metal-Au-k"
    "rgb albedo" [0.6 0.6 0.6] "float g" 0.4 "float thickness" 0.2
Shape "sphere" "float radius" 0.8
"#;
    let path = dir.join("coated.pbrt");
    std::fs::write(&path, text).unwrap();
    let desc = io::load_scene(&path, &[]).unwrap_or_else(|e| panic!("{e}"));
    Scene::from_description(&desc, None).unwrap_or_else(|e| panic!("{e}")).0
}

#[test]
fn bpt_and_vcm_agree_with_the_path_tracer() {
    let scene = consistency_scene();
    let max_length = 6;
    let reference = image_statistics(&scene, "pt", 400, max_length, 1);
    let (ref_mean, ref_error): (Vec<f64>, Vec<f64>) = reference.iter().map(|s| (s.mean(), s.std_error())).unzip();
    let alpha = sidak(1e-3, 2);
    let mut failures = Vec::new();
    for (k, algorithm) in ["bpt", "vcm"].into_iter().enumerate() {
        let stats = image_statistics(&scene, algorithm, 400, max_length, 2 + k as u64);
        let (mean, error): (Vec<f64>, Vec<f64>) = stats.iter().map(|s| (s.mean(), s.std_error())).unzip();
        let outcome = z_test_entries(&mean, &error, &ref_mean, &ref_error, alpha);
        let detectable = common::detectable_bias(&mean, &error, &ref_mean, &ref_error, alpha);
        let line = format!(
            "{algorithm}: {mean:?} ± {error:?} vs pt {ref_mean:?} ± {ref_error:?}; detects {:.2} %",
            100.0 * detectable
        );
        eprintln!("{line}");
        if !outcome.passed || detectable > 0.03 {
            failures.push(line);
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
