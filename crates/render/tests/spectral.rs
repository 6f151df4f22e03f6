//! Spectral mode (`RenderSettings::spectral`, four hero-rotated wavelengths per path) against
//! independent truths:
//!
//! 1. the white furnace: every algorithm gives `Le·Σ_{k<K} ρ^k` in every channel, as in RGB
//!    (the upsampled grey reflectance is the constant ρ and the white emitter is D65 scaled so
//!    that its colour is white);
//! 2. the reference Cornell boxes: with white lights and direct light only (two segments) the
//!    spectral image equals the RGB image in expectation (a linearly upsampled reflectance under
//!    D65 has exactly its RGB colour); under the coloured sun the single-bounce colour of every
//!    wall is predicted by quadrature of the CIE tables (products of spectra are not products of
//!    RGB colours);
//! 3. dispersion: a lossless dispersive glass sphere leaves the furnace unchanged, and a BK7
//!    prism splits a collimated white beam on a diffuse floor by the amount Snell's law and the
//!    Sellmeier fit predict (and does not with dispersion off).
//!
//! Every iteration's frame is an independent estimate (its wavelengths included), so means over
//! iterations with standard errors from the spread of the iterations support Z-tests
//! (Šidák-corrected, family-wise α = 1e-3 per test function).

use crate::common;

use math::{Vec2, Vec3};
use render::driver::{Budget, Renderer};
use render::{Algorithm, RenderSettings};
use scene::light::DirectionalLight;
use scene::shape::{Shape, Sphere, Triangle};
use scene::texture::Texture;
use scene::{Camera, Light, Material, Primitive, ReferenceMaterial, Scene};
use spectrum::Rgb;
use spectrum::cie::{CIE_Y_INTEGRAL, cmf, xyz_to_linear_srgb};
use spectrum::ior::Ior;
use testkit::{MeanVar, sidak, z_test_entries};

/// Settings of one run.
fn settings(algorithm: &str, spectral: bool, max_length: u32, radius_factor: f32, seed: u64) -> RenderSettings {
    RenderSettings {
        algorithm: Algorithm::from_name(algorithm).unwrap(),
        budget: Budget::Iterations(1),
        max_length,
        seed,
        radius_factor,
        spectral,
        ..RenderSettings::default()
    }
}

/// Per-iteration means, per channel, of `blocks × blocks` blocks (index `(block * 3 + c)`)
/// followed by the whole image (the last 3 entries), over `iterations` iterations.
fn block_statistics(scene: &Scene, settings: &RenderSettings, iterations: u64, blocks: u32) -> Vec<MeanVar> {
    let mut renderer = Renderer::new(scene, settings).unwrap();
    let (w, h) = (scene.camera.width, scene.camera.height);
    let (bw, bh) = (w / blocks, h / blocks);
    let count = (blocks * blocks) as usize;
    let mut stats = vec![MeanVar::new(); (count + 1) * 3];
    for _ in 0..iterations {
        assert_eq!(renderer.step(), 0, "rejected samples");
        let mut sums = vec![0.0f64; (count + 1) * 3];
        for (i, p) in renderer.frame().pixels.iter().enumerate() {
            let (x, y) = (i as u32 % w, i as u32 / w);
            let b = ((y / bh).min(blocks - 1) * blocks + (x / bw).min(blocks - 1)) as usize;
            for (c, v) in p.to_array().into_iter().enumerate() {
                sums[b * 3 + c] += f64::from(v);
                sums[count * 3 + c] += f64::from(v);
            }
        }
        let per_block = f64::from(bw * bh);
        for (i, (s, sum)) in stats.iter_mut().zip(sums).enumerate() {
            s.push(if i >= count * 3 { sum / f64::from(w * h) } else { sum / per_block });
        }
    }
    stats
}

fn means(stats: &[MeanVar]) -> Vec<f64> {
    stats.iter().map(MeanVar::mean).collect()
}

fn errors(stats: &[MeanVar]) -> Vec<f64> {
    stats.iter().map(MeanVar::std_error).collect()
}

/// The last three entries (the image means per channel) as text.
fn image_line(stats: &[MeanVar]) -> String {
    let n = stats.len();
    let m: Vec<String> = stats[n - 3..].iter().map(|s| format!("{:.4}±{:.4}", s.mean(), s.std_error())).collect();
    m.join(" ")
}

// ---------------------------------------------------------------------------------------------
// 1. The white furnace.
// ---------------------------------------------------------------------------------------------

/// How one algorithm is run on a furnace.
struct Run {
    algorithm: &'static str,
    resolution: u32,
    iterations: u64,
    radius_factor: f32,
}

/// Non-merging algorithms: every pixel draws its own wavelengths, so the image mean averages
/// the wavelength noise of many paths.
const UNBIASED: [Run; 3] = [
    Run { algorithm: "pt", resolution: 16, iterations: 600, radius_factor: 1e-3 },
    Run { algorithm: "lt", resolution: 16, iterations: 600, radius_factor: 1e-3 },
    Run { algorithm: "bpt", resolution: 16, iterations: 600, radius_factor: 1e-3 },
];

// Merging algorithms split an iteration into K wavelength groups (4K wavelengths per
// iteration, a camera vertex merges with the N_L/K photons of its group); with one set per
// iteration (K = 1, before the groups) the measured standard deviation per iteration in the
// blue channel was 0.6 of the value for vcm at 16², 0.8 for ppm and bpm at 64², 1.9 at 32². Merging bias at radius
// 1e-3·√3: see `vcm_furnace.rs` (relative 5e-4, at most 3e-3, below the standard errors here).
const MERGING_FAST: [Run; 1] = [Run { algorithm: "vcm", resolution: 16, iterations: 1500, radius_factor: 1e-3 }];
const MERGING_SLOW: [Run; 2] = [
    Run { algorithm: "ppm", resolution: 64, iterations: 3000, radius_factor: 1e-3 },
    Run { algorithm: "bpm", resolution: 64, iterations: 3000, radius_factor: 1e-3 },
];

/// (Le, ρ, K): white walls (ρ = 1, the radiance grows by Le per segment) and grey walls.
const FURNACE_CASES: [(f32, f32, u32); 3] = [(1.0, 1.0, 3), (1.0, 0.5, 10), (0.5, 0.8, 4)];

/// Blocks per image side in the furnace tests.
const FURNACE_BLOCKS: u32 = 4;

/// Z-tests every block and the image mean of every channel against `expected`; checks the power
/// (image mean resolved to 2 % of the value). Returns the failure, if any.
fn judge(what: &str, stats: &[MeanVar], expected: f64, alpha: f64) -> Option<String> {
    let n = stats.len();
    let outcome = z_test_entries(&means(stats), &errors(stats), &vec![expected; n], &vec![0.0; n], alpha);
    let line = format!("{what}: image {} vs {expected:.5}; {outcome}", image_line(stats));
    eprintln!("{line}");
    for s in &stats[n - 3..] {
        assert!(s.std_error() < 0.02 * expected, "{line}: not enough power");
    }
    (!outcome.passed).then_some(line)
}

fn furnace_check(runs: &[Run]) {
    let alpha = sidak(1e-3, FURNACE_CASES.len() * runs.len());
    let mut failures = Vec::new();
    for (case, &(emission, albedo, max_length)) in FURNACE_CASES.iter().enumerate() {
        for run in runs {
            let expected: f64 = (0..max_length).map(|k| f64::from(emission) * f64::from(albedo).powi(k as i32)).sum();
            let scene = common::furnace(emission, albedo, run.resolution);
            let s = settings(run.algorithm, true, max_length, run.radius_factor, 3000 + case as u64);
            let stats = block_statistics(&scene, &s, run.iterations, FURNACE_BLOCKS);
            let what = format!("spectral furnace Le={emission} ρ={albedo} K={max_length} {}", run.algorithm);
            failures.extend(judge(&what, &stats, expected, alpha));
        }
    }
    assert!(failures.is_empty(), "spectral furnace failures:\n{}", failures.join("\n"));
}

#[test]
fn spectral_furnace_without_merging() {
    furnace_check(&UNBIASED);
}

#[test]
fn spectral_furnace_vcm() {
    furnace_check(&MERGING_FAST);
}

#[test]
#[ignore = "slow: run with --ignored"]
fn spectral_furnace_photon_mapping() {
    furnace_check(&MERGING_SLOW);
}

// ---------------------------------------------------------------------------------------------
// 2. The reference Cornell boxes, spectral vs RGB.
// ---------------------------------------------------------------------------------------------

/// Masks of the four reference scenes (ids 0–3).
const CORNELL_MASKS: [u32; 4] = [450, 273, 452, 456];

/// The material every primary sub-ray of a pixel hits, when it is one non-specular material for
/// all 4×4 sub-rays of the pixel and of its eight neighbours (pixels on or next to edges, on
/// spheres or seeing emitters or the background get `None`).
fn pixel_materials(scene: &Scene) -> Vec<Option<u32>> {
    let (w, h) = (scene.camera.width, scene.camera.height);
    let mut out = Vec::with_capacity((w * h) as usize);
    for y in 0..h {
        for x in 0..w {
            let mut material = None;
            let mut uniform = true;
            for s in 0..16 {
                let raster =
                    Vec2::new(x as f32 + (s % 4) as f32 / 4.0 + 0.125, y as f32 + (s / 4) as f32 / 4.0 + 0.125);
                let ray = scene.camera.generate_ray(raster);
                let m = scene.intersect(&ray).filter(|hit| hit.light.is_none()).map(|hit| hit.material);
                match (m, material) {
                    (None, _) => uniform = false,
                    (Some(m), None) => material = Some(m),
                    (Some(m), Some(previous)) => uniform &= m == previous,
                }
            }
            let diffuse_like = material.is_some_and(|m| match &scene.materials[m as usize] {
                Material::Reference(r) => r.mirror.is_black(),
                _ => false,
            });
            out.push(if uniform && diffuse_like { material } else { None });
        }
    }
    // Erode by one pixel: a pixel on an edge may hold a sliver of the neighbouring surface that
    // no sub-ray caught, and a bright neighbour (the sunlit green wall next to the dim back wall)
    // would show through it.
    let at = |x: i64, y: i64| {
        if (0..w as i64).contains(&x) && (0..h as i64).contains(&y) { out[(y * w as i64 + x) as usize] } else { None }
    };
    (0..(w * h) as i64)
        .map(|i| {
            let (x, y) = (i % w as i64, i / w as i64);
            let own = at(x, y);
            let interior = (-1..=1).all(|dy| (-1..=1).all(|dx| at(x + dx, y + dy) == own));
            if interior { own } else { None }
        })
        .collect()
}

/// Per-iteration means per channel over the pixels of each material (index `m * 3 + c`).
fn material_statistics(scene: &Scene, settings: &RenderSettings, iterations: u64, map: &[Option<u32>]) -> Vec<MeanVar> {
    let materials = scene.materials.len();
    let mut counts = vec![0u32; materials];
    for m in map.iter().flatten() {
        counts[*m as usize] += 1;
    }
    let mut renderer = Renderer::new(scene, settings).unwrap();
    let mut stats = vec![MeanVar::new(); materials * 3];
    for _ in 0..iterations {
        assert_eq!(renderer.step(), 0, "rejected samples");
        let mut sums = vec![0.0f64; materials * 3];
        for (p, m) in renderer.frame().pixels.iter().zip(map) {
            if let Some(m) = m {
                for (c, v) in p.to_array().into_iter().enumerate() {
                    sums[*m as usize * 3 + c] += f64::from(v);
                }
            }
        }
        for (i, (s, sum)) in stats.iter_mut().zip(sums).enumerate() {
            if counts[i / 3] > 0 {
                s.push(sum / f64::from(counts[i / 3]));
            }
        }
    }
    stats
}

/// The linear-sRGB colour of the spectrum `f(λ)` (per nm, as the renderer's film sees it:
/// `∫ f (x̄, ȳ, z̄) dλ / ∫ ȳ`), by the midpoint rule on 0.25 nm steps over 360–830 nm.
fn colour_of(f: impl Fn(f32) -> f64) -> [f64; 3] {
    let step = 0.25f64;
    let mut xyz = [0.0f64; 3];
    let mut lambda = 360.0 + 0.5 * step;
    while lambda < 830.0 {
        let value = f(lambda as f32);
        let c = cmf(lambda as f32);
        for i in 0..3 {
            xyz[i] += value * f64::from(c[i]) * step / CIE_Y_INTEGRAL;
        }
        lambda += step;
    }
    // XYZ → linear sRGB is linear: convert in f64 via the f32 matrix on a normalised vector.
    let scale = xyz.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(1e-300);
    let rgb = xyz_to_linear_srgb([(xyz[0] / scale) as f32, (xyz[1] / scale) as f32, (xyz[2] / scale) as f32]);
    rgb.to_array().map(|v| f64::from(v) * scale)
}

/// The colour of a Lambertian reflectance `albedo` lit by the RGB emitter `light`, both
/// upsampled (reflectance: the linear basis; emitter: basis × D65).
fn spectral_product(albedo: Rgb, light: Rgb) -> [f64; 3] {
    colour_of(|l| {
        f64::from(spectrum::upsample::reflectance(albedo, l)) * f64::from(spectrum::upsample::emission(light, l))
    })
}

#[test]
fn white_light_single_bounce_matches_rgb() {
    // Scenes 1 (area light) and 2 (point light), paths of two segments: the emitter seen
    // directly and direct lighting. Linear upsampling under the white (D65) emitter reproduces
    // every reflectance's RGB colour exactly, so the spectral image equals the RGB image in
    // expectation, block by block.
    let (size, blocks, iterations) = (64u32, 8u32, 300u64);
    let alpha = sidak(1e-3, 2);
    let mut failures = Vec::new();
    for (case, mask) in [273u32, 452].into_iter().enumerate() {
        let scene = scene::cornell::build(mask, size, size).unwrap();
        let rgb = block_statistics(&scene, &settings("pt", false, 2, 0.003, 40 + case as u64), iterations, blocks);
        let spectral = block_statistics(&scene, &settings("pt", true, 2, 0.003, 50 + case as u64), iterations, blocks);
        let outcome = z_test_entries(&means(&spectral), &errors(&spectral), &means(&rgb), &errors(&rgb), alpha);
        let line =
            format!("mask {mask}, length 2: spectral {} vs rgb {}; {outcome}", image_line(&spectral), image_line(&rgb));
        eprintln!("{line}");
        for image in &spectral[spectral.len() - 3..] {
            assert!(image.std_error() < 0.01 * image.mean(), "{line}: not enough power");
        }
        if !outcome.passed {
            failures.push(line);
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn coloured_sun_single_bounce_matches_quadrature() {
    // Scene 0, paths of two segments: the walls lit directly by the sun (0.5, 0.2, 0)·20. For a
    // Lambertian wall of RGB albedo c the RGB render is g·(c ⊙ sun) and the spectral render
    // g·S(c, sun), with the same geometric factor g (cosine, visibility, 1/π) and S the colour of
    // the product of the two upsampled spectra, computed here by quadrature. So on the pixels of
    // each wall the spectral mean must equal the RGB mean of the wall's strongest channel times
    // S_c / (c ⊙ sun)_strongest. Grey materials (white walls, the grey glossy floor) must give
    // the RGB answer exactly.
    let (size, iterations) = (64u32, 400u64);
    let scene = scene::cornell::build(450, size, size).unwrap();
    let map = pixel_materials(&scene);
    let rgb = material_statistics(&scene, &settings("pt", false, 2, 0.003, 60), iterations, &map);
    let spectral = material_statistics(&scene, &settings("pt", true, 2, 0.003, 61), iterations, &map);
    let sun = Rgb::new(0.5, 0.2, 0.0) * 20.0;
    let (mut predicted, mut predicted_se, mut measured, mut measured_se) = (vec![], vec![], vec![], vec![]);
    let mut lit_walls = 0;
    let mut largest_shift_z = 0.0f64;
    for (m, material) in scene.materials.iter().enumerate() {
        let Material::Reference(r) = material else { continue };
        if spectral[m * 3].count() == 0 || !r.mirror.is_black() {
            continue;
        }
        let grey = r.diffuse.r == r.diffuse.g
            && r.diffuse.g == r.diffuse.b
            && r.phong.r == r.phong.g
            && r.phong.g == r.phong.b;
        let rgb_means: Vec<f64> = (0..3).map(|c| rgb[m * 3 + c].mean()).collect();
        let rgb_errors: Vec<f64> = (0..3).map(|c| rgb[m * 3 + c].std_error()).collect();
        let (p, pse) = if grey {
            (rgb_means.clone(), rgb_errors.clone())
        } else {
            let product = (r.diffuse * sun).to_array();
            let strongest = (0..3).max_by(|a, b| product[*a].total_cmp(&product[*b])).unwrap();
            let s = spectral_product(r.diffuse, sun);
            let k: Vec<f64> = s.iter().map(|s| s / f64::from(product[strongest])).collect();
            if rgb_means[strongest] > 0.0 {
                lit_walls += 1;
            }
            (
                k.iter().map(|k| k * rgb_means[strongest]).collect(),
                k.iter().map(|k| (k * rgb_errors[strongest]).abs()).collect(),
            )
        };
        let spectral_means: Vec<f64> = (0..3).map(|c| spectral[m * 3 + c].mean()).collect();
        let spectral_errors: Vec<f64> = (0..3).map(|c| spectral[m * 3 + c].std_error()).collect();
        for c in 0..3 {
            let combined = spectral_errors[c].hypot(rgb_errors[c]);
            if combined > 0.0 {
                largest_shift_z = largest_shift_z.max((spectral_means[c] - rgb_means[c]).abs() / combined);
            }
        }
        eprintln!(
            "scene 0 length 2, material {m} (diffuse {:?}): {} px; rgb {:.6?}; spectral {:.6?} ± {:.6?}; predicted {:.6?} ± {:.6?}",
            r.diffuse.to_array(),
            map.iter().filter(|x| **x == Some(m as u32)).count(),
            rgb_means,
            spectral_means,
            spectral_errors,
            p,
            pse
        );
        predicted.extend(p);
        predicted_se.extend(pse);
        measured.extend(spectral_means);
        measured_se.extend(spectral_errors);
    }
    assert!(lit_walls >= 2, "the sun must light at least two coloured walls directly");
    let outcome = z_test_entries(&measured, &measured_se, &predicted, &predicted_se, 1e-3);
    eprintln!("{outcome}");
    assert!(outcome.passed, "{outcome}");
    // Power: the test resolves the colour shift it predicts. Somewhere (the green wall's red
    // channel) the spectral render differs from the RGB render by more than 20 standard errors,
    // so "spectral = RGB" would have failed.
    assert!(largest_shift_z > 20.0, "largest spectral − RGB shift only {largest_shift_z} standard errors");
}

#[test]
#[ignore = "slow: run with --ignored (a measurement: prints the spectral − RGB colour differences)"]
fn cornell_spectral_minus_rgb_table() {
    // The four reference scenes with path tracing, direct light only (2 segments) and full
    // length (10): per-channel image means in both modes and their difference. Under white light
    // the single-bounce difference is zero (tested above); multiple bounces multiply upsampled
    // reflectances, whose products are not the products of the RGB colours, and the coloured
    // sun and sky differ already at one bounce. The only assertion is the power: every image
    // mean is resolved to 1 % of its value (plus 1e-4), so the printed differences are measurements.
    let (size, iterations) = (64u32, 400u64);
    eprintln!("| scene | length | RGB (r, g, b) | spectral (r, g, b) | spectral − RGB | (spectral − RGB) / RGB |");
    eprintln!("|---|---|---|---|---|---|");
    for (id, mask) in CORNELL_MASKS.into_iter().enumerate() {
        let scene = scene::cornell::build(mask, size, size).unwrap();
        for max_length in [2u32, 10] {
            let rgb = block_statistics(&scene, &settings("pt", false, max_length, 0.003, 80), iterations, 1);
            let spectral = block_statistics(&scene, &settings("pt", true, max_length, 0.003, 81), iterations, 1);
            let (r, s) = (&rgb[rgb.len() - 3..], &spectral[spectral.len() - 3..]);
            let text = |v: &[MeanVar]| v.iter().map(|m| format!("{:.4}", m.mean())).collect::<Vec<_>>().join(", ");
            let difference: Vec<String> = (0..3)
                .map(|c| format!("{:+.4}±{:.4}", s[c].mean() - r[c].mean(), s[c].std_error().hypot(r[c].std_error())))
                .collect();
            let relative: Vec<String> = (0..3)
                .map(|c| {
                    if r[c].mean() > 0.0 {
                        format!("{:+.1} %", 100.0 * (s[c].mean() / r[c].mean() - 1.0))
                    } else {
                        "–".to_string()
                    }
                })
                .collect();
            eprintln!(
                "| {id} | {max_length} | {} | {} | {} | {} |",
                text(r),
                text(s),
                difference.join(", "),
                relative.join(", ")
            );
            for m in r.iter().chain(s) {
                assert!(m.std_error() < 0.01 * m.mean().abs() + 1e-4, "scene {id}: not enough power");
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// 3. Dispersion.
// ---------------------------------------------------------------------------------------------

/// Smooth BK7 glass (n_d = 1.5168) without absorption, dispersive in spectral mode when
/// `dispersive`.
fn bk7(dispersive: bool) -> Material {
    let ior = Ior::named("bk7").unwrap();
    Material::Dielectric {
        int_ior: ior.n_d(),
        ext_ior: 1.0,
        specular_reflectance: Texture::Constant(Rgb::WHITE),
        specular_transmittance: Texture::Constant(Rgb::WHITE),
        dispersion: dispersive.then_some(ior),
    }
}

/// The furnace cube of `common::furnace` with a dispersive BK7 sphere inside, in view of the
/// camera.
fn furnace_with_sphere(emission: f32, albedo: f32, resolution: u32) -> Scene {
    let cube = common::furnace(emission, albedo, resolution);
    let mut primitives = cube.primitives.clone();
    primitives.push(Primitive::new(Shape::Sphere(Sphere { center: Vec3::new(0.3, 0.5, 0.25), radius: 0.35 }), 1, None));
    let materials = vec![cube.materials[0].clone(), bk7(true)];
    Scene::new("furnace-bk7-sphere", primitives, materials, cube.lights.clone(), cube.camera)
}

#[test]
fn only_dispersive_glass_counts_as_dispersion() {
    // The engine merges across wavelength groups only in scenes without dispersion (a camera
    // sub-path through dispersive glass keeps one wavelength and cannot be re-evaluated at
    // another group's): the scene must tell them apart, blends included.
    assert!(furnace_with_sphere(1.0, 0.5, 8).has_dispersion());
    assert!(!common::furnace(1.0, 0.5, 8).has_dispersion());
    assert!(bk7(true).is_dispersive() && !bk7(false).is_dispersive());
    let constant = Material::Dielectric {
        int_ior: 1.5,
        ext_ior: 1.0,
        specular_reflectance: Texture::Constant(Rgb::WHITE),
        specular_transmittance: Texture::Constant(Rgb::WHITE),
        dispersion: Some(Ior::Constant(1.5)),
    };
    assert!(!constant.is_dispersive(), "a constant index is not dispersive");
    let blend = |m: Material| Material::Blend {
        weight: Texture::Constant(Rgb::splat(0.5)),
        first: Box::new(m),
        second: Box::new(bk7(false)),
    };
    assert!(blend(bk7(true)).is_dispersive() && !blend(bk7(false)).is_dispersive());
}

#[test]
fn dispersive_sphere_leaves_the_furnace_unchanged() {
    // A lossless dielectric does not change a uniform, isotropic radiance field (radiance/η² is
    // conserved along refracted rays and Fresnel reflection plus transmission sum to one), so
    // the furnace radiance Le·Σρ^k is seen everywhere, through the sphere too. Paths through the
    // sphere are longer, so the truncation at K segments is not uniform any more: with ρ = 0.5
    // and K = 40 the missing tail is below 0.5^20 of the answer even for paths with a glass
    // passage (two segments) after every diffuse bounce. Camera paths through the sphere carry
    // only their hero wavelength (times four), and so do light paths: BPT and VCM connections
    // between two such sub-paths exercise the 1/4 of `DOUBLE_TERMINATION`. Light tracing cannot
    // see the sphere (a delta surface in front of the camera): it is checked on the blocks that
    // see only walls, where it must give Le·Σ_{k≥1}ρ^k.
    let (emission, albedo, max_length) = (1.0f32, 0.5f32, 40u32);
    let full = f64::from(emission) / (1.0 - f64::from(albedo));
    let runs = [
        Run { algorithm: "pt", resolution: 16, iterations: 600, radius_factor: 1e-3 },
        Run { algorithm: "bpt", resolution: 16, iterations: 600, radius_factor: 1e-3 },
        Run { algorithm: "lt", resolution: 16, iterations: 600, radius_factor: 1e-3 },
        Run { algorithm: "vcm", resolution: 16, iterations: 4000, radius_factor: 1e-3 },
    ];
    let alpha = sidak(1e-3, runs.len());
    let mut failures = Vec::new();
    for (index, run) in runs.iter().enumerate() {
        let scene = furnace_with_sphere(emission, albedo, run.resolution);
        let s = settings(run.algorithm, true, max_length, run.radius_factor, 700 + index as u64);
        let stats = block_statistics(&scene, &s, run.iterations, FURNACE_BLOCKS);
        let views = common::block_views(&scene, run.resolution / FURNACE_BLOCKS);
        assert!(views.iter().filter(|v| v.specular).count() >= 2, "the camera sees the sphere");
        let what = format!("bk7 sphere in the furnace, {}", run.algorithm);
        if run.algorithm == "lt" {
            // The walls' emission is seen directly (s = 1, t = 1), as by the other algorithms.
            let expected = full;
            let (m, e): (Vec<f64>, Vec<f64>) = views
                .iter()
                .enumerate()
                .filter(|(_, v)| !v.specular)
                .flat_map(|(b, _)| (0..3).map(move |c| b * 3 + c))
                .map(|i| (stats[i].mean(), stats[i].std_error()))
                .unzip();
            let outcome = z_test_entries(&m, &e, &vec![expected; m.len()], &vec![0.0; m.len()], alpha);
            eprintln!("{what} (wall blocks): {outcome}");
            if !outcome.passed {
                failures.push(format!("{what}: {outcome}"));
            }
        } else {
            failures.extend(judge(&what, &stats, full, alpha));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Half width of the prism (x) and of the slit, half length of both (y), height of the prism's
/// top face, apex angle between its top face and its slanted face, height of the screen.
const PRISM_HALF_WIDTH: f32 = 0.2;
const PRISM_HALF_LENGTH: f32 = 0.5;
const PRISM_TOP: f32 = 2.9;
const PRISM_ANGLE_DEG: f32 = 38.0;
const SCREEN_HEIGHT: f32 = 2.95;

/// Two triangles of the quad `a b c d`, wound so that the normal points away from `inside`.
fn quad_facing_away(a: Vec3, b: Vec3, c: Vec3, d: Vec3, inside: Vec3, material: u32) -> [Primitive; 2] {
    let triangle = |p0: Vec3, p1: Vec3, p2: Vec3| {
        let t = Triangle::new(p0, p1, p2);
        let t = if t.normal.dot(p0 - inside) < 0.0 { Triangle::new(p0, p2, p1) } else { t };
        Primitive::new(Shape::Triangle(t), material, None)
    };
    [triangle(a, b, c), triangle(a, c, d)]
}

/// A collimated white beam (sun straight down) through a slit in a black screen, a BK7 prism
/// under the slit (a wedge: horizontal top face, vertical face at +x, the slanted face at
/// [`PRISM_ANGLE_DEG`] to the top falling towards +x), and a white Lambertian floor at z = 0
/// lit only by the refracted beam, seen straight down by a pinhole camera above the spot.
fn prism_scene(dispersive: bool, resolution: u32) -> Scene {
    let (w, l, top) = (PRISM_HALF_WIDTH, PRISM_HALF_LENGTH, PRISM_TOP);
    let bottom = top - 2.0 * w * PRISM_ANGLE_DEG.to_radians().tan();
    let (floor, glass, black) = (0u32, 1u32, 2u32);
    let v = Vec3::new;
    let mut primitives = Vec::new();
    // Floor, normal up.
    let below = v(0.0, 0.0, -1.0);
    primitives.extend(quad_facing_away(
        v(-0.5, -1.5, 0.0),
        v(3.0, -1.5, 0.0),
        v(3.0, 1.5, 0.0),
        v(-0.5, 1.5, 0.0),
        below,
        floor,
    ));
    // Prism: the cross-section (−w, top), (w, top), (w, bottom), extruded over y ∈ [−l, l].
    let inside = v(w / 3.0, 0.0, (2.0 * top + bottom) / 3.0);
    let (p1, p2, p3) = (|y: f32| v(-w, y, top), |y: f32| v(w, y, top), |y: f32| v(w, y, bottom));
    primitives.extend(quad_facing_away(p1(-l), p2(-l), p2(l), p1(l), inside, glass));
    primitives.extend(quad_facing_away(p2(-l), p3(-l), p3(l), p2(l), inside, glass));
    primitives.extend(quad_facing_away(p3(-l), p1(-l), p1(l), p3(l), inside, glass));
    for y in [-l, l] {
        let t = Triangle::new(p1(y), p2(y), p3(y));
        let t = if t.normal.dot(p1(y) - inside) < 0.0 { Triangle::new(p1(y), p3(y), p2(y)) } else { t };
        primitives.push(Primitive::new(Shape::Triangle(t), glass, None));
    }
    // Screen over everything the camera sees, with the slit above the prism.
    let z = SCREEN_HEIGHT;
    let above = v(0.0, 0.0, 10.0);
    let mut rect = |x0: f32, x1: f32, y0: f32, y1: f32| {
        primitives.extend(quad_facing_away(v(x0, y0, z), v(x1, y0, z), v(x1, y1, z), v(x0, y1, z), above, black));
    };
    rect(-0.6, -w, -1.6, 1.6);
    rect(w, 3.1, -1.6, 1.6);
    rect(-w, w, -1.6, -l);
    rect(-w, w, l, 1.6);
    let materials = vec![
        ReferenceMaterial::diffuse(Rgb::splat(0.8)).into(),
        bk7(dispersive),
        ReferenceMaterial::diffuse(Rgb::splat(0.0)).into(),
    ];
    let lights = vec![Light::Directional(DirectionalLight::new(v(0.0, 0.0, -1.0), Rgb::splat(5.0)))];
    let camera = Camera::new(v(1.67, 0.0, 1.5), v(0.0, 0.0, -1.0), Vec3::Y, 53.13, resolution, resolution);
    Scene::new("bk7-prism", primitives, materials, lights, camera)
}

/// Where the central ray of the beam (entering the top face at x = 0) lands on the floor at the
/// wavelength whose index is `n`, and the fraction of the beam's flux that gets there (Fresnel
/// transmission at normal incidence on the top face and at the apex angle on the slanted face).
fn prism_landing(n: f64) -> (f64, f64) {
    let a = f64::from(PRISM_ANGLE_DEG).to_radians();
    let sin_t = n * a.sin();
    assert!(sin_t < 1.0, "no total internal reflection");
    let deviation = sin_t.asin() - a;
    let exit_height = f64::from(PRISM_TOP) - f64::from(PRISM_HALF_WIDTH) * a.tan();
    let fresnel = |cos_i: f64, eta: f64| {
        // eta = n_incident / n_transmitted.
        let cos_t = (1.0 - eta * eta * (1.0 - cos_i * cos_i)).sqrt();
        let rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
        let rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
        0.5 * (rs * rs + rp * rp)
    };
    let transmitted = (1.0 - fresnel(1.0, 1.0 / n)) * (1.0 - fresnel(a.cos(), n));
    (exit_height * deviation.tan(), transmitted)
}

/// Per channel, the floor-x centroid of the beam predicted by quadrature over the wavelengths:
/// each wavelength lands (on average over the slit) where its central ray does, weighted by its
/// flux and by the channel's colour-matching weight.
fn predicted_centroids() -> [f64; 3] {
    let ior = Ior::named("bk7").unwrap();
    let mut weighted = [0.0f64; 3];
    let mut total = [0.0f64; 3];
    let step = 0.25f64;
    let mut lambda = 360.0 + 0.5 * step;
    while lambda < 830.0 {
        let l = lambda as f32;
        let (x, t) = prism_landing(f64::from(ior.eval(l)));
        let power = f64::from(spectrum::upsample::emission(Rgb::WHITE, l)) * t;
        let c = cmf(l);
        let rgb = xyz_to_linear_srgb(c).to_array();
        for ch in 0..3 {
            weighted[ch] += x * power * f64::from(rgb[ch]);
            total[ch] += power * f64::from(rgb[ch]);
        }
        lambda += step;
    }
    std::array::from_fn(|c| weighted[c] / total[c])
}

/// One iteration's per-channel sums of pixel values and of pixel values times floor x.
type Moments = ([f64; 3], [f64; 3]);

/// Light-traces the prism scene and returns, per channel, the floor-x centroid of the image
/// with its standard error, and the difference red − blue with its standard error (from the
/// per-iteration linearisation of the ratio estimators, covariances included).
fn measured_centroids(dispersive: bool, resolution: u32, iterations: u64, seed: u64) -> ([f64; 3], [f64; 3], f64, f64) {
    let scene = prism_scene(dispersive, resolution);
    // World x of every pixel centre on the floor.
    let w = resolution;
    let xs: Vec<f64> = (0..w * w)
        .map(|i| {
            let ray = scene.camera.generate_ray(Vec2::new((i % w) as f32 + 0.5, (i / w) as f32 + 0.5));
            let t = -ray.origin.z / ray.direction.z;
            f64::from(ray.origin.x + t * ray.direction.x)
        })
        .collect();
    let mut renderer = Renderer::new(&scene, &settings("lt", true, 4, 0.003, seed)).unwrap();
    let mut per_iteration = Vec::with_capacity(iterations as usize);
    for _ in 0..iterations {
        assert_eq!(renderer.step(), 0, "rejected samples");
        let (mut s, mut m) = ([0.0f64; 3], [0.0f64; 3]);
        for (p, x) in renderer.frame().pixels.iter().zip(&xs) {
            for (c, v) in p.to_array().into_iter().enumerate() {
                s[c] += f64::from(v);
                m[c] += f64::from(v) * x;
            }
        }
        per_iteration.push((s, m));
    }
    let n = iterations as f64;
    let s_mean: [f64; 3] = std::array::from_fn(|c| per_iteration.iter().map(|(s, _)| s[c]).sum::<f64>() / n);
    let m_mean: [f64; 3] = std::array::from_fn(|c| per_iteration.iter().map(|(_, m)| m[c]).sum::<f64>() / n);
    let centroid: [f64; 3] = std::array::from_fn(|c| m_mean[c] / s_mean[c]);
    // Influence of each iteration on each ratio: (m − r·s) / s̄.
    let influence = |(s, m): &Moments, c: usize| (m[c] - centroid[c] * s[c]) / s_mean[c];
    let se = |f: &dyn Fn(&Moments) -> f64| {
        let mut mv = MeanVar::new();
        for it in &per_iteration {
            mv.push(f(it));
        }
        mv.std_error()
    };
    let centroid_se: [f64; 3] = std::array::from_fn(|c| se(&|it| influence(it, c)));
    let difference_se = se(&|it| influence(it, 0) - influence(it, 2));
    (centroid, centroid_se, centroid[0] - centroid[2], difference_se)
}

#[test]
fn prism_splits_red_from_blue() {
    // Snell's law with the BK7 Sellmeier fit: red is bent less than blue, so the red centroid of
    // the spot lies closer to the prism (smaller x) than the blue one. The image of a floor
    // parallel to the image plane is an affine map of it and the floor is Lambertian, so the
    // pixel-weighted centroid of world x is the flux centroid of the spot (up to the binning into
    // pixels, well below a pixel, 0.023 here, and common to the channels).
    let (resolution, iterations) = (64u32, 1500u64);
    let predicted = predicted_centroids();
    let predicted_difference = predicted[0] - predicted[2];
    let (on, on_se, difference, difference_se) = measured_centroids(true, resolution, iterations, 90);
    let (off, off_se, off_difference, off_difference_se) = measured_centroids(false, resolution, iterations, 91);
    eprintln!(
        "prism: predicted centroids {predicted:.4?} (red − blue {predicted_difference:.4}); dispersive {on:.4?} ± {on_se:.4?}, \
         red − blue {difference:.4} ± {difference_se:.4}; non-dispersive {off:.4?} ± {off_se:.4?}, red − blue {off_difference:.4} ± {off_difference_se:.4}"
    );
    assert!(predicted_difference < -0.02, "the prediction separates the colours: {predicted_difference}");
    // Dispersion on: clearly separated (more than 10 standard errors), by the predicted amount
    // (within 4 standard errors plus 10 % for the pixel binning and the secondary beams).
    assert!(difference < -10.0 * difference_se, "red − blue = {difference} ± {difference_se}");
    assert!(
        (difference - predicted_difference).abs() < 4.0 * difference_se + 0.1 * predicted_difference.abs(),
        "red − blue = {difference} ± {difference_se}, predicted {predicted_difference}"
    );
    // Every channel's centroid where the prediction puts it.
    for c in 0..3 {
        assert!((on[c] - predicted[c]).abs() < 4.0 * on_se[c] + 0.01, "channel {c}: {} vs {}", on[c], predicted[c]);
    }
    // Dispersion off: one spot for every wavelength (up to 4.4 standard errors, α ≈ 1e-5),
    // landing where the ray at n_d does.
    assert!(off_difference.abs() < 4.4 * off_difference_se, "red − blue = {off_difference} ± {off_difference_se}");
    let (x_d, _) = prism_landing(f64::from(Ior::named("bk7").unwrap().n_d()));
    assert!((off[1] - x_d).abs() < 4.0 * off_se[1] + 0.01, "{} vs {x_d}", off[1]);
    // Power: the resolution of the test is far below the effect.
    assert!(difference_se < 0.1 * predicted_difference.abs(), "se {difference_se}");
}

// ---------------------------------------------------------------------------------------------
// 4. Wavelength groups of the merging algorithms.
// ---------------------------------------------------------------------------------------------

/// Resolution and iterations of the wavelength-group test.
const GROUPS_SIZE: u32 = 128;
const GROUPS_ITERATIONS: u64 = 128;

/// Image mean of a frame, per channel.
fn frame_mean(renderer: &Renderer) -> [f64; 3] {
    let pixels = &renderer.frame().pixels;
    let mut sum = [0.0f64; 3];
    for p in pixels {
        for (s, v) in sum.iter_mut().zip(p.to_array()) {
            *s += f64::from(v);
        }
    }
    sum.map(|s| s / pixels.len() as f64)
}

/// Scene 1 (white area light) at 128², two segments: a linearly upsampled reflectance under
/// the white light has exactly its RGB colour, so the spectral and RGB image means agree in
/// expectation. RGB and spectral renders with the same seed trace the same paths (the
/// wavelengths have their own random streams and every sampling decision uses RGB values), so
/// the per-iteration difference Δ of their image means is the colour error of the wavelengths
/// alone. Returns per channel the RGB statistics and those of Δ.
fn colour_error(algorithm: &str, groups: u32) -> Vec<(MeanVar, MeanVar)> {
    let scene = scene::cornell::build(CORNELL_MASKS[1], GROUPS_SIZE, GROUPS_SIZE).unwrap();
    let mut rgb = Renderer::new(&scene, &settings(algorithm, false, 2, 0.003, 90)).unwrap();
    let spectral_settings = RenderSettings { wavelength_groups: groups, ..settings(algorithm, true, 2, 0.003, 90) };
    let mut spectral = Renderer::new(&scene, &spectral_settings).unwrap();
    let mut stats = vec![(MeanVar::new(), MeanVar::new()); 3];
    for _ in 0..GROUPS_ITERATIONS {
        assert_eq!(rgb.step() + spectral.step(), 0, "rejected samples");
        let (r, s) = (frame_mean(&rgb), frame_mean(&spectral));
        for c in 0..3 {
            stats[c].0.push(r[c]);
            stats[c].1.push(s[c] - r[c]);
        }
    }
    for (c, (r, d)) in stats.iter().enumerate() {
        eprintln!(
            "{algorithm}, {groups} groups, channel {c}: RGB {:.5}±{:.5}, spectral − RGB {:+.5}±{:.5} ({:+.2} %)",
            r.mean(),
            r.std_error(),
            d.mean(),
            d.std_error(),
            100.0 * d.mean() / r.mean()
        );
    }
    stats
}

#[test]
fn wavelength_groups_keep_the_image_colour_of_rgb() {
    // Per channel: (1) the colour error is unbiased (Z-test of Δ against 0, with the power to
    // see a 1 % cast in vcm, 2 % in bpm); (2) for vcm, its standard error is at most that of the RGB image mean itself,
    // i.e. the colour noise of the wavelengths is below the noise the RGB render has with the
    // same number of samples.
    let alpha = sidak(1e-3, 6);
    // The cast each must resolve: bpm merges alone, so its colour error is noisier.
    for (algorithm, cast_fraction) in [("vcm", 0.01), ("bpm", 0.02)] {
        for (c, (rgb, delta)) in
            colour_error(algorithm, render::vcm::wavelengths::DEFAULT_WAVELENGTH_GROUPS).iter().enumerate()
        {
            let p = testkit::z_test_p(delta.mean(), delta.std_error());
            assert!(p > alpha, "{algorithm} channel {c}: spectral − RGB = {} ± {}", delta.mean(), delta.std_error());
            let cast = testkit::z_test_p(cast_fraction * rgb.mean(), delta.std_error());
            assert!(cast < alpha, "{algorithm} channel {c}: not enough power (a {cast_fraction} cast has p = {cast})");
            // bpm merges alone: its Δ also holds the noise of merging with other photons than
            // the RGB render (N_L/K of them), measured 1.1× the RGB noise in blue; only its
            // unbiasedness is tested.
            assert!(
                algorithm == "bpm" || delta.std_error() <= rgb.std_error(),
                "{algorithm} channel {c}: colour noise {} above the RGB noise {}",
                delta.std_error(),
                rgb.std_error()
            );
        }
    }
}

#[test]
fn one_wavelength_set_per_iteration_casts_a_colour() {
    // The scheme before wavelength groups (K = 1: the whole iteration at four wavelengths)
    // fails the same test: the colour noise of its image mean is above the RGB noise.
    let stats = colour_error("vcm", 1);
    assert!(
        stats.iter().any(|(rgb, delta)| delta.std_error() > rgb.std_error()),
        "K = 1 passed: its colour noise is below the RGB noise"
    );
}
