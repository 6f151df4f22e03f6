//! A render spread over N in-process ranks ([`render::distributed::LocalRanks`]) gives the
//! single-process image bit for bit: film sums, sums of squares (--variance), rejected counts,
//! family films and technique images, for pt, bpt, vcm, spectral vcm, per-pixel radius and the
//! memory-efficient mode, with N = 1, 2, 3; also under a time budget, a stop flag and a resume
//! with another rank count. The truth is `render::render` in one process.

use std::sync::atomic::AtomicBool;
use std::time::Duration;

use render::distributed::{Collective, LocalRanks, agree, run_distributed};
use render::driver::{Budget, Control, RenderOutput, render_with};
use render::progressive::Progressive;
use render::vcm::RadiusMode;
use render::vcm::technique_images::TechniqueLayout;
use render::{Algorithm, RenderSettings};
use scene::{Film, Scene, cornell};

fn settings(algorithm: &str, iterations: u64) -> RenderSettings {
    RenderSettings {
        algorithm: Algorithm::from_name(algorithm).unwrap(),
        budget: Budget::Iterations(iterations),
        seed: 11,
        threads: 1,
        radius_factor: 0.02,
        ..RenderSettings::default()
    }
}

/// What one rank needs besides the scene and settings.
#[derive(Clone, Default)]
struct Extras {
    resume: Option<Film>,
    families: bool,
    techniques: Option<TechniqueLayout>,
    /// Ranks whose stop flag is set from the start.
    stopped: Vec<usize>,
}

/// Runs the distributed loop on `ranks` threads; returns each rank's output (rank 0 first).
fn distributed(scene: &Scene, settings: &RenderSettings, ranks: usize, extras: &Extras) -> Vec<RenderOutput> {
    let comms = LocalRanks::connect(ranks);
    std::thread::scope(|s| {
        let handles: Vec<_> = comms
            .into_iter()
            .map(|comm| {
                s.spawn(move || {
                    let rank = comm.rank();
                    let resume = if rank == 0 { extras.resume.clone() } else { None };
                    let mut progressive =
                        Progressive::new(scene, settings, resume, extras.families, extras.techniques).unwrap();
                    let stop = AtomicBool::new(extras.stopped.contains(&rank));
                    let interrupted = run_distributed(&mut progressive, settings, Some(&stop), None, &comm).unwrap();
                    progressive.into_output(interrupted)
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    })
}

fn single(scene: &Scene, settings: &RenderSettings, extras: &Extras) -> RenderOutput {
    let control = Control {
        resume: extras.resume.clone(),
        record_families: extras.families,
        record_techniques: extras.techniques,
        ..Control::default()
    };
    render_with(scene, settings, control).unwrap()
}

fn assert_same_film(a: &Film, b: &Film, what: &str) {
    assert_eq!(a.iterations(), b.iterations(), "{what}: iterations");
    assert_eq!(a.rejected_samples(), b.rejected_samples(), "{what}: rejected");
    // Bit equality of the f64 sums (== on f64 would also accept -0 for +0).
    let bits = |v: &[[f64; 3]]| v.iter().flatten().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert!(bits(&a.sums()) == bits(&b.sums()), "{what}: sums differ");
    assert!(bits(&a.sum_squares()) == bits(&b.sum_squares()), "{what}: sums of squares differ");
}

#[test]
fn every_rank_count_reproduces_one_process_bit_for_bit() {
    let scene = cornell::build(450, 20, 16).unwrap();
    let variants = [
        ("pt", settings("pt", 5)),
        ("bpt", settings("bpt", 5)),
        ("vcm", settings("vcm", 5)),
        ("spectral vcm", RenderSettings { spectral: true, ..settings("vcm", 5) }),
        ("per-pixel vcm", RenderSettings { radius_mode: RadiusMode::PerPixel, ..settings("vcm", 5) }),
        ("memory-efficient vcm", RenderSettings { memory_efficient: true, ..settings("vcm", 5) }),
        ("vcm without variance", RenderSettings { variance: false, ..settings("vcm", 5) }),
    ];
    for (name, s) in &variants {
        let truth = single(&scene, s, &Extras::default());
        for ranks in 1..=3 {
            let outputs = distributed(&scene, s, ranks, &Extras::default());
            assert_same_film(&outputs[0].film, &truth.film, &format!("{name}, {ranks} ranks"));
            assert_eq!(outputs[0].rejected_by_family, truth.rejected_by_family, "{name}, {ranks} ranks");
            assert!(outputs.iter().all(|o| !o.interrupted));
            assert!(outputs[1..].iter().all(|o| o.film.iterations() == 0), "only rank 0 keeps a film");
        }
    }
}

#[test]
fn family_films_and_technique_images_are_bit_identical() {
    let scene = cornell::build(450, 16, 12).unwrap();
    let s = settings("vcm", 4);
    let extras = Extras { families: true, techniques: Some(TechniqueLayout::new(4).unwrap()), ..Extras::default() };
    let truth = single(&scene, &s, &extras);
    let (truth_families, truth_images) = (truth.family_films.unwrap(), truth.technique_images.unwrap());
    for ranks in [2, 3] {
        let output = distributed(&scene, &s, ranks, &extras).swap_remove(0);
        let (families, images) = (output.family_films.unwrap(), output.technique_images.unwrap());
        for (a, b) in families.iter().zip(&truth_families) {
            assert_same_film(a, b, &format!("family film, {ranks} ranks"));
        }
        for image in 0..truth_images.layout().len() {
            assert_eq!(images.mean(image), truth_images.mean(image), "technique image {image}, {ranks} ranks");
        }
    }
}

#[test]
fn a_time_budget_renders_whole_rounds_equal_to_that_many_iterations() {
    let scene = cornell::build(450, 12, 12).unwrap();
    let s = RenderSettings { budget: Budget::Time(Duration::from_millis(1)), ..settings("vcm", 0) };
    let outputs = distributed(&scene, &s, 3, &Extras::default());
    let n = outputs[0].film.iterations();
    assert!(n >= 3 && n.is_multiple_of(3), "whole rounds of 3 iterations, got {n}");
    let truth = single(&scene, &RenderSettings { budget: Budget::Iterations(n), ..s.clone() }, &Extras::default());
    assert_same_film(&outputs[0].film, &truth.film, "time budget");
}

#[test]
fn a_resume_with_another_rank_count_equals_the_uninterrupted_render() {
    let scene = cornell::build(450, 12, 12).unwrap();
    for name in ["pt", "vcm"] {
        let first = distributed(&scene, &settings(name, 2), 2, &Extras::default()).swap_remove(0).film;
        assert_eq!(first.iterations(), 2);
        let extras = Extras { resume: Some(first), ..Extras::default() };
        let resumed = distributed(&scene, &settings(name, 7), 3, &extras).swap_remove(0).film;
        let truth = single(&scene, &settings(name, 7), &Extras::default());
        assert_same_film(&resumed, &truth.film, &format!("{name} resumed from 2 ranks on 3"));
    }
}

#[test]
fn a_stop_flag_on_any_rank_stops_every_rank_with_consecutive_iterations() {
    let scene = cornell::build(450, 12, 12).unwrap();
    let s = settings("vcm", 9);
    // Rank 1 is stopped before its first iteration: rank 0's iteration 0 is kept, rank 2's
    // iteration 2 is not (it would leave a gap).
    let extras = Extras { stopped: vec![1], ..Extras::default() };
    let outputs = distributed(&scene, &s, 3, &extras);
    assert!(outputs.iter().all(|o| o.interrupted), "every rank reports the interrupt");
    let truth = single(&scene, &settings("vcm", 1), &Extras::default());
    assert_same_film(&outputs[0].film, &truth.film, "stopped on rank 1");
}

#[test]
fn a_wrong_iteration_is_caught_by_the_comparison() {
    // The check above is sensitive: a film in which one iteration is replaced by another
    // (e.g. a rank rendering the wrong index) differs from the truth.
    let scene = cornell::build(450, 12, 12).unwrap();
    let s = settings("vcm", 3);
    let truth = single(&scene, &s, &Extras::default());
    let mut progressive = Progressive::new(&scene, &s, None, false, None).unwrap();
    for (slot, index) in [(0, 0), (1, 2), (2, 2)] {
        let mut result = progressive.render_iteration(index);
        result.iteration = slot;
        progressive.add_result(&result).unwrap();
    }
    let wrong = progressive.into_output(false).film;
    assert_eq!(wrong.iterations(), truth.film.iterations());
    assert_ne!(wrong.sums(), truth.film.sums());
    // And the film refuses an iteration out of order.
    let mut progressive = Progressive::new(&scene, &s, None, false, None).unwrap();
    let result = progressive.render_iteration(1);
    assert!(progressive.add_result(&result).is_err());
}

#[test]
fn an_error_on_one_rank_ends_every_rank_with_it() {
    let comms = LocalRanks::connect(3);
    let results: Vec<Result<usize, String>> = std::thread::scope(|s| {
        let handles: Vec<_> = comms
            .into_iter()
            .map(|comm| {
                s.spawn(move || {
                    let rank = comm.rank();
                    let own = if rank == 2 { Err("scene.xml:3: expected a float".to_string()) } else { Ok(rank) };
                    agree(&comm, own)
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    for result in &results {
        assert_eq!(result.as_ref().unwrap_err(), "rank 2: scene.xml:3: expected a float");
    }
    let comms = LocalRanks::connect(2);
    let ok: Vec<Result<usize, String>> = std::thread::scope(|s| {
        let handles: Vec<_> = comms.into_iter().map(|comm| s.spawn(move || agree(&comm, Ok(comm.rank())))).collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    assert_eq!(ok, vec![Ok(0), Ok(1)]);
}
