//! Determinism of the VCM engine across thread counts and seeds, and the decomposition of an
//! iteration's frame into technique families (which families each algorithm may use).

use render::driver::{Budget, Renderer};
use render::vcm::Family;
use render::{Algorithm, RenderSettings};
use scene::cornell;
use spectrum::Rgb;

fn settings(algorithm: &str, seed: u64, threads: usize) -> RenderSettings {
    RenderSettings {
        algorithm: Algorithm::from_name(algorithm).unwrap(),
        budget: Budget::Iterations(3),
        seed,
        threads,
        // A large radius, so that merges happen often at this resolution.
        radius_factor: 0.02,
        ..RenderSettings::default()
    }
}

fn image(mask: u32, algorithm: &str, seed: u64, threads: usize) -> Vec<[u32; 3]> {
    // 48 × 44: more than one light chunk of 1024 paths, rows of unequal cost.
    let scene = cornell::build(mask, 48, 44).unwrap();
    let output = render::render(&scene, &settings(algorithm, seed, threads)).unwrap();
    assert_eq!(output.threads, threads);
    output.film.mean().into_iter().map(|p| p.map(f32::to_bits)).collect()
}

#[test]
fn images_do_not_depend_on_the_thread_count() {
    for (mask, algorithm) in [(273, "vcm"), (452, "vcm"), (456, "bpt"), (450, "lt"), (273, "bpm"), (456, "ppm")] {
        let one = image(mask, algorithm, 42, 1);
        let two = image(mask, algorithm, 42, 2);
        let differing = one.iter().zip(&two).filter(|(a, b)| a != b).count();
        assert_eq!(differing, 0, "scene {mask} {algorithm}: {differing} pixels differ between 1 and 2 threads");
        assert!(one.iter().any(|p| p.iter().any(|&v| f32::from_bits(v) > 0.0)), "scene {mask} {algorithm}: black");
        let other = image(mask, algorithm, 43, 2);
        let differing = one.iter().zip(&other).filter(|(a, b)| a != b).count();
        assert!(differing > one.len() / 4, "scene {mask} {algorithm}: seed changes only {differing} pixels");
    }
}

/// Which families an algorithm may use (index = `Family as usize`).
fn allowed(algorithm: &str) -> [bool; 5] {
    // [emitter hit, next event, light tracing, connection, merging]
    match algorithm {
        "lt" => [false, false, true, false, false],
        "ppm" | "bpm" => [true, false, false, false, true],
        "bpt" => [true, true, true, true, false],
        "vcm" => [true; 5],
        _ => unreachable!(),
    }
}

#[test]
fn families_sum_to_the_frame_and_match_the_algorithm() {
    for mask in [273, 452, 456] {
        let scene = cornell::build(mask, 40, 40).unwrap();
        for algorithm in ["lt", "ppm", "bpm", "bpt", "vcm"] {
            let mut renderer = Renderer::new(&scene, &settings(algorithm, 5, 2)).unwrap();
            renderer.vcm_engine_mut().expect("a VCM algorithm").record_families(true);
            let mut used = [false; 5];
            for _ in 0..3 {
                assert_eq!(renderer.step(), 0);
                let frame = renderer.frame();
                let families = renderer.vcm_engine().unwrap().family_frames().expect("recorded");
                assert_eq!(families.len(), frame.pixels.len());
                for (pixel, values) in frame.pixels.iter().zip(families) {
                    let total = values.0.iter().fold(Rgb::BLACK, |a, b| a + *b);
                    for (t, p) in total.to_array().into_iter().zip(pixel.to_array()) {
                        assert!(
                            (t - p).abs() <= 1e-5 * p.abs().max(1.0),
                            "scene {mask} {algorithm}: {total:?} vs {pixel:?}"
                        );
                    }
                    for family in Family::ALL {
                        if values.0[family as usize] != Rgb::BLACK {
                            used[family as usize] = true;
                        }
                    }
                }
            }
            let allowed = allowed(algorithm);
            for family in Family::ALL {
                let i = family as usize;
                assert!(!used[i] || allowed[i], "scene {mask} {algorithm}: family {} is not zero", family.name());
            }
            // And the families an algorithm relies on do contribute.
            let expected_used: &[Family] = match algorithm {
                "lt" => &[Family::LightTracing],
                "ppm" | "bpm" => &[Family::Merging],
                "bpt" => &[Family::NextEvent, Family::LightTracing, Family::Connection],
                _ => &[Family::NextEvent, Family::LightTracing, Family::Connection, Family::Merging],
            };
            for &family in expected_used {
                assert!(used[family as usize], "scene {mask} {algorithm}: family {} is all zero", family.name());
            }
        }
    }
}
