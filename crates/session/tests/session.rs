//! The session as a front end other than the CLI uses it: no files written unless asked,
//! messages arrive as values through the observer, errors are returned, and a resumed session
//! continues the film exactly.

use render::Algorithm;
use render::driver::Budget;
use session::{Notice, Observer, Request};
use testkit::TempDir;

#[derive(Default)]
struct Collect {
    notices: Vec<Notice>,
    started: usize,
}

impl Observer for Collect {
    fn notice(&mut self, notice: Notice) {
        self.notices.push(notice);
    }

    fn starting(&mut self) {
        self.started += 1;
    }
}

fn request(algorithm: &str) -> Request {
    Request {
        resolution: Some((16, 12)),
        algorithm: Algorithm::from_name(algorithm).unwrap(),
        budget: Some(Budget::Iterations(2)),
        threads: 1,
        ..Request::new(session::scene_source("1", &[]).unwrap())
    }
}

#[test]
fn a_session_renders_in_memory_and_reports_through_the_observer() {
    let mut observer = Collect::default();
    let outcome = session::render(&request("vcm"), None, &mut observer).unwrap();
    assert_eq!(observer.started, 1);
    assert!(observer.notices.is_empty(), "{:?}", observer.notices);
    assert_eq!(outcome.output.film.iterations(), 2);
    assert_eq!((outcome.summary.resolution, outcome.summary.written.len()), ((16, 12), 0));
    assert!(outcome.summary.to_string().starts_with("cornell-area-mirror with vcm at 16x12: 2 iterations"));

    // The memory guard's switch is a note, not a print.
    let mut observer = Collect::default();
    // BPT at 512x512 needs about 69 MiB more than the process holds in the default mode and
    // about 34 MiB in the memory-efficient mode, which stores no light vertex (neither keeps the
    // film's sums of squares: no variance file, no checkpoint).
    let resident = render::vcm::memory::resident_bytes().unwrap();
    let tight = Request {
        max_memory: Some(resident + (50 << 20)),
        resolution: Some((512, 512)),
        budget: Some(Budget::Iterations(1)),
        threads: 2,
        ..request("bpt")
    };
    session::render(&tight, None, &mut observer).unwrap();
    assert!(
        matches!(&observer.notices[..], [Notice::Note(n)] if n.contains("switching to --memory-efficient")),
        "{:?}",
        observer.notices
    );

    // Iterations side by side that do not fit: one at a time, with a note when they were asked
    // for (VCM at 512² holds about 62 MiB per lane here, without the film's squares).
    for (parallelism, noted) in [(render::Parallelism::Iterations, true), (render::Parallelism::Auto, false)] {
        let mut observer = Collect::default();
        let resident = render::vcm::memory::resident_bytes().unwrap();
        let one_lane = Request {
            max_memory: Some(resident + (90 << 20)),
            resolution: Some((512, 512)),
            threads: 2,
            parallelism,
            ..request("vcm")
        };
        let outcome = session::render(&one_lane, None, &mut observer).unwrap();
        assert_eq!(outcome.output.lanes, 1);
        assert_eq!(outcome.output.film.iterations(), 2);
        let note = |n: &Notice| matches!(n, Notice::Note(n) if n.contains("2 iterations side by side would need more"));
        assert_eq!(observer.notices.iter().any(note), noted, "{:?}", observer.notices);
        assert!(!observer.notices.iter().any(|n| n.to_string().contains("memory-efficient")), "{:?}", observer.notices);
        // With room for both lanes, both are used.
        let roomy = Request { max_memory: Some(resident + (400 << 20)), ..one_lane };
        assert_eq!(session::render(&roomy, None, &mut Collect::default()).unwrap().output.lanes, 2);
    }

    // Bad settings are errors before anything starts.
    let mut observer = Collect::default();
    let error = session::render(&Request { radius_alpha: 1.5, ..request("vcm") }, None, &mut observer).unwrap_err();
    assert!(error.to_string().contains("--radius-alpha must be in (0, 1]"), "{error}");
    assert_eq!(observer.started, 0);
}

#[test]
fn a_resumed_session_continues_the_film_exactly() {
    let dir = TempDir::new("session-test");
    let checkpoint = dir.join("c.ckpt");
    let first = Request { checkpoint: Some(checkpoint.clone()), ..request("bpm") };
    session::render(&first, None, &mut Collect::default()).unwrap();
    // Settings that the checkpoint records are taken from it, whatever the request says.
    let resumed =
        Request { resume: Some(checkpoint.clone()), budget: Some(Budget::Iterations(5)), seed: 77, ..request("pt") };
    let outcome = session::render(&resumed, None, &mut Collect::default()).unwrap();
    assert_eq!((outcome.summary.algorithm, outcome.summary.resumed_after), ("bpm", Some(2)));
    let straight = session::render(
        &Request { budget: Some(Budget::Iterations(5)), keep_variance: true, ..request("bpm") },
        None,
        &mut Collect::default(),
    )
    .unwrap();
    assert_eq!(outcome.output.film.sums(), straight.output.film.sums(), "resumed film differs");
    // Checkpoints carry the sums of squares even though no variance file was asked for, so the
    // resumed film has the variance of the uninterrupted one.
    assert_eq!(outcome.output.film.sum_squares(), straight.output.film.sum_squares());
    assert!(straight.output.film.has_variance());
    // Without a variance file, a checkpoint or `keep_variance` the film keeps no squares.
    let lean = session::render(&request("bpm"), None, &mut Collect::default()).unwrap();
    assert!(!lean.output.film.has_variance() && lean.output.film.variance_of_mean().is_none());
}

#[test]
fn a_scene_files_sample_count_is_the_default_budget() {
    let dir = TempDir::new("session-samples");
    let scene = dir.join("samples.xml");
    std::fs::write(
        &scene,
        r#"<scene version="3.0.0">
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0, 0, 3" target="0, 0, 0" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="3"/></sampler>
        <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="6"/></film>
    </sensor>
    <shape type="sphere"><bsdf type="diffuse"/></shape>
    <emitter type="constant"><rgb name="radiance" value="1"/></emitter>
</scene>
"#,
    )
    .unwrap();
    let source = session::scene_source(scene.to_str().unwrap(), &[]).unwrap();
    let render = |budget| {
        let request =
            Request { budget, algorithm: Algorithm::from_name("pt").unwrap(), ..Request::new(source.clone()) };
        session::render(&request, None, &mut Collect::default()).unwrap().output.film.iterations()
    };
    // No budget given: the file's three samples per pixel; a given budget wins.
    assert_eq!(render(None), 3);
    assert_eq!(render(Some(Budget::Iterations(2))), 2);
}
