//! Iterations side by side ([`render::Parallelism::Iterations`]) give the film of one iteration
//! at a time bit for bit: the image, the variance, the family films and the technique images,
//! for every algorithm, with a batch that fills all lanes and a last one that does not.

use std::time::Duration;

use render::driver::{Budget, Control, RenderOutput, render_with};
use render::vcm::technique_images::TechniqueLayout;
use render::{Algorithm, Parallelism, RenderSettings};
use scene::{Scene, cornell};

fn render(scene: &Scene, algorithm: &str, threads: usize, parallelism: Parallelism, spectral: bool) -> RenderOutput {
    let settings = RenderSettings {
        algorithm: Algorithm::from_name(algorithm).unwrap(),
        // Five: with two or three lanes, full batches and a shorter last one.
        budget: Budget::Iterations(5),
        seed: 7,
        threads,
        // A large radius, so that merges happen often at this resolution.
        radius_factor: 0.02,
        spectral,
        parallelism,
        ..RenderSettings::default()
    };
    let vcm_engine = matches!(settings.algorithm, Algorithm::Vcm(_));
    let control = Control {
        record_families: vcm_engine,
        record_techniques: vcm_engine.then(|| TechniqueLayout::new(3).unwrap()),
        ..Control::default()
    };
    render_with(scene, &settings, control).unwrap()
}

fn bits(pixels: &[[f32; 3]]) -> Vec<[u32; 3]> {
    pixels.iter().map(|p| p.map(f32::to_bits)).collect()
}

#[test]
fn iterations_side_by_side_give_the_film_of_one_at_a_time() {
    let cases =
        [(273, "vcm", false), (456, "bpt", false), (450, "lt", false), (273, "bpm", false), (456, "ppm", false)];
    let more = [(452, "vcm", true), (456, "pt", false), (273, "pt", true)];
    for (mask, algorithm, spectral) in cases.into_iter().chain(more) {
        // 40 × 36: more than one light chunk of 1024 paths.
        let scene = cornell::build(mask, 40, 36).unwrap();
        let one = render(&scene, algorithm, 2, Parallelism::Pixels, spectral);
        assert_eq!(one.lanes, 1);
        let image = bits(&one.film.mean());
        assert!(image.iter().any(|p| p.iter().any(|&v| f32::from_bits(v) > 0.0)), "{mask} {algorithm}: black");
        for threads in [2, 3] {
            let side = render(&scene, algorithm, threads, Parallelism::Iterations, spectral);
            let case = format!("scene {mask} {algorithm} spectral={spectral}, {threads} lanes");
            // Else the test would compare one iteration at a time with itself.
            assert_eq!(side.lanes, threads, "{case}");
            assert_eq!(side.film.iterations(), 5, "{case}");
            assert_eq!(bits(&side.film.mean()), image, "{case}: image");
            assert_eq!(
                bits(&side.film.variance_of_mean().unwrap()),
                bits(&one.film.variance_of_mean().unwrap()),
                "{case}: variance"
            );
            assert_eq!(side.film.rejected_samples(), one.film.rejected_samples(), "{case}");
            if let (Some(a), Some(b)) = (&one.family_films, &side.family_films) {
                for (k, (a, b)) in a.iter().zip(b).enumerate() {
                    assert_eq!(bits(&a.mean()), bits(&b.mean()), "{case}: family {k}");
                }
            }
            assert_eq!(one.family_films.is_some(), side.family_films.is_some(), "{case}");
            match (&one.technique_images, &side.technique_images) {
                (Some(a), Some(b)) => {
                    assert_eq!(a.iterations(), b.iterations(), "{case}");
                    for k in 0..a.layout().len() {
                        assert_eq!(bits(&a.mean(k)), bits(&b.mean(k)), "{case}: technique image {k}");
                    }
                }
                (None, None) => assert!(algorithm == "pt", "{case}: no technique images"),
                _ => panic!("{case}: technique images in one render only"),
            }
        }
    }
}

#[test]
fn a_time_budget_renders_whole_batches_and_stops() {
    let scene = cornell::build(273, 32, 32).unwrap();
    let settings = RenderSettings {
        algorithm: Algorithm::from_name("vcm").unwrap(),
        budget: Budget::Time(Duration::from_millis(200)),
        threads: 2,
        parallelism: Parallelism::Iterations,
        ..RenderSettings::default()
    };
    let output = render_with(&scene, &settings, Control::default()).unwrap();
    assert_eq!(output.lanes, 2);
    assert!(output.film.iterations() >= 2, "{} iterations", output.film.iterations());
    // Well under a second: the loop stops at the budget (a batch here takes milliseconds).
    assert!(output.elapsed < Duration::from_secs(2), "{:?}", output.elapsed);
}

#[test]
fn auto_puts_lanes_only_on_the_vcm_engine_and_large_images() {
    let settings = |algorithm: &str, parallelism, memory_efficient| RenderSettings {
        algorithm: Algorithm::from_name(algorithm).unwrap(),
        parallelism,
        memory_efficient,
        ..RenderSettings::default()
    };
    let large = Parallelism::AUTO_MIN_PIXELS;
    for algorithm in ["lt", "ppm", "bpm", "bpt", "vcm"] {
        assert_eq!(settings(algorithm, Parallelism::Auto, false).lanes(4, large), 4, "{algorithm}");
        assert_eq!(settings(algorithm, Parallelism::Auto, false).lanes(4, large - 1), 1, "{algorithm}");
        assert_eq!(settings(algorithm, Parallelism::Auto, true).lanes(4, large), 1, "{algorithm}");
        assert_eq!(settings(algorithm, Parallelism::Pixels, false).lanes(4, large), 1, "{algorithm}");
    }
    assert_eq!(settings("pt", Parallelism::Auto, false).lanes(4, large), 1);
    assert_eq!(settings("pt", Parallelism::Iterations, false).lanes(4, 16), 4);
    assert_eq!(settings("vcm", Parallelism::Iterations, true).lanes(3, 16), 3);
    assert_eq!(settings("vcm", Parallelism::Iterations, false).lanes(0, 16), 1);
    for (p, name) in Parallelism::ALL {
        assert_eq!(Parallelism::from_name(name), Some(p));
        assert_eq!(p.name(), name);
    }
    assert_eq!(Parallelism::from_name("threads"), None);
}
