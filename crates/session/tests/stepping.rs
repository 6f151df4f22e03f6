//! The session's stepping API runs the driver's iterations: `session::render` (now Prepared +
//! Progressive + run_budget) gives the film of `render::driver::render_with` bit for bit, technique
//! images included, and a `Live` session stepped in pieces gives the film of one render.

use std::sync::atomic::AtomicBool;

use render::Algorithm;
use render::driver::{Budget, Control};
use render::vcm::technique_images::TechniqueLayout;
use session::{Live, Notice, Observer, Prepared, Request};
use testkit::TempDir;

struct Quiet;

impl Observer for Quiet {
    fn notice(&mut self, _: Notice) {}
}

fn request(algorithm: &str, scene: &str) -> Request {
    Request {
        resolution: Some((24, 16)),
        algorithm: Algorithm::from_name(algorithm).unwrap(),
        budget: Some(Budget::Iterations(3)),
        seed: 9,
        threads: 2,
        ..Request::new(session::scene_source(scene, &[]).unwrap())
    }
}

#[test]
fn session_render_equals_the_drivers_render_with() {
    // The session creates the technique images' folder itself.
    let scratch = TempDir::new("stepping");
    let dir = scratch.join("techniques");
    for (algorithm, spectral, memory_efficient) in [
        ("pt", false, false),
        ("lt", false, false),
        ("ppm", false, true),
        ("bpm", false, false),
        ("bpt", false, false),
        ("vcm", false, false),
        ("vcm", true, false),
        ("vcm", false, true),
    ] {
        let mut r = request(algorithm, "cornell-area-mirror");
        r.spectral = spectral;
        r.memory_efficient = memory_efficient;
        let recording = matches!(r.algorithm, Algorithm::Vcm(_));
        if recording {
            r.techniques = Some(dir.clone());
            r.technique_length = 3;
        }
        let ours = session::render(&r, None, &mut Quiet).unwrap().output;
        // The same settings through the driver's own loop.
        let prepared = Prepared::new(&r, &mut Quiet).unwrap();
        let control = Control {
            record_families: recording,
            record_techniques: recording.then(|| TechniqueLayout::new(3).unwrap()),
            ..Control::default()
        };
        let theirs = render::driver::render_with(&prepared.scene, &prepared.settings, control).unwrap();
        let what = format!("{algorithm} spectral={spectral} memory_efficient={memory_efficient}");
        assert_eq!(ours.film.iterations(), 3, "{what}");
        assert_eq!(ours.film.sums(), theirs.film.sums(), "{what}");
        assert_eq!(ours.film.sum_squares(), theirs.film.sum_squares(), "{what}");
        assert_eq!(ours.rejected_by_family, theirs.rejected_by_family, "{what}");
        if recording {
            let (a, b) = (ours.family_films.unwrap(), theirs.family_films.unwrap());
            for (fa, fb) in a.iter().zip(&b) {
                assert_eq!(fa.sums(), fb.sums(), "{what}: family films");
            }
            let (a, b) = (ours.technique_images.unwrap(), theirs.technique_images.unwrap());
            for index in 0..a.layout().len() {
                assert_eq!(a.mean(index), b.mean(index), "{what}: technique image {index}");
            }
        }
        // Power: another seed gives another film.
        let other = session::render(&Request { seed: 10, techniques: None, ..r.clone() }, None, &mut Quiet).unwrap();
        assert_ne!(other.output.film.sums(), theirs.film.sums(), "{what}");
    }
}

#[test]
fn a_live_session_stepped_in_pieces_equals_one_render() {
    for algorithm in ["pt", "vcm"] {
        let r = request(algorithm, "cornell-sun");
        let one = session::render(&r, None, &mut Quiet).unwrap().output.film;
        let mut live = Live::start(Prepared::new(&r, &mut Quiet).unwrap()).unwrap();
        assert_eq!(live.step(1, None).unwrap(), 1);
        assert_eq!(live.step(2, None).unwrap(), 2);
        assert_eq!(live.film().sums(), one.sums(), "{algorithm}");
        // A set stop flag renders nothing more.
        let stop = AtomicBool::new(true);
        assert_eq!(live.step(5, Some(&stop)).unwrap(), 0);
        assert_eq!(live.film().iterations(), 3);
    }
}
