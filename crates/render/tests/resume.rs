//! A render stopped and resumed gives the same image, bit for bit, as an uninterrupted render
//! with the same seed and iteration count — for the path tracer and for the VCM engine in its
//! two-stage and memory-efficient modes.

use std::sync::atomic::AtomicBool;

use render::driver::{Budget, Control, render_with};
use render::vcm::RadiusMode;
use render::{Algorithm, RenderSettings};
use scene::cornell;

fn settings(algorithm: &str, iterations: u64) -> RenderSettings {
    RenderSettings {
        algorithm: Algorithm::from_name(algorithm).unwrap(),
        budget: Budget::Iterations(iterations),
        seed: 5,
        radius_factor: 0.01,
        ..RenderSettings::default()
    }
}

#[test]
fn resumed_renders_equal_uninterrupted_ones() {
    let scene = cornell::build(450, 40, 32).unwrap();
    let variants = [
        settings("pt", 0),
        settings("vcm", 0),
        settings("bpm", 0),
        RenderSettings { memory_efficient: true, ..settings("vcm", 0) },
        RenderSettings { memory_efficient: true, radius_mode: RadiusMode::PerPixel, ..settings("vcm", 0) },
    ];
    for base in variants {
        let full =
            render_with(&scene, &RenderSettings { budget: Budget::Iterations(5), ..base.clone() }, Control::default())
                .unwrap()
                .film;
        let first =
            render_with(&scene, &RenderSettings { budget: Budget::Iterations(2), ..base.clone() }, Control::default())
                .unwrap()
                .film;
        assert_eq!(first.iterations(), 2);
        let control = Control { resume: Some(first), ..Control::default() };
        let resumed = render_with(&scene, &RenderSettings { budget: Budget::Iterations(5), ..base.clone() }, control)
            .unwrap()
            .film;
        assert_eq!(resumed.iterations(), 5);
        assert_eq!(full.sums(), resumed.sums(), "{:?} memory-efficient {}", base.algorithm, base.memory_efficient);
    }
}

#[test]
fn a_stop_request_ends_the_render_after_the_current_iteration() {
    let scene = cornell::build(273, 16, 16).unwrap();
    let stop = AtomicBool::new(true);
    let mut saved = Vec::new();
    let control = Control {
        stop: Some(&stop),
        checkpoint: Some((
            std::time::Duration::ZERO,
            Box::new(|film: &scene::Film| {
                saved.push(film.iterations());
                Ok(())
            }),
        )),
        ..Control::default()
    };
    let output = render_with(&scene, &settings("vcm", 100), control).unwrap();
    assert!(output.interrupted);
    assert_eq!(output.film.iterations(), 0, "stopped before the first iteration");
    assert_eq!(saved, vec![0], "the final checkpoint is still written");
}
