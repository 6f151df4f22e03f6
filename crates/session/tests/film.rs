//! The film mode through a session: checkpoints record it, resuming keeps it, and resuming
//! with another mode is an error.

use render::Algorithm;
use render::driver::Budget;
use scene::filter::FilmMode;
use session::{Notice, Observer, Request};
use testkit::TempDir;

struct Quiet;

impl Observer for Quiet {
    fn notice(&mut self, _: Notice) {}
}

fn request() -> Request {
    Request {
        resolution: Some((16, 12)),
        algorithm: Algorithm::from_name("pt").unwrap(),
        budget: Some(Budget::Iterations(2)),
        threads: 1,
        ..Request::new(session::scene_source("1", &[]).unwrap())
    }
}

#[test]
fn checkpoints_record_the_film_mode_and_resuming_with_another_is_an_error() {
    let dir = TempDir::new("session-film");
    let checkpoint = dir.join("c.ckpt");
    let first = Request { checkpoint: Some(checkpoint.clone()), film: Some(FilmMode::Splat), ..request() };
    session::render(&first, None, &mut Quiet).unwrap();
    let bytes = std::fs::read(&checkpoint).unwrap();
    let header = String::from_utf8_lossy(&bytes[..bytes.len().min(2000)]).to_string();
    assert!(header.lines().any(|l| l == "film=splat"), "no film=splat line in:\n{header}");

    let other = Request { resume: Some(checkpoint.clone()), film: Some(FilmMode::Fis), ..request() };
    let error = session::render(&other, None, &mut Quiet).unwrap_err().to_string();
    assert!(error.contains("--film fis") && error.contains("--film splat"), "{error}");

    // Without a mode, or with the same one, the checkpoint's mode is used.
    for film in [None, Some(FilmMode::Splat)] {
        let resumed =
            Request { resume: Some(checkpoint.clone()), checkpoint: Some(dir.join("d.ckpt")), film, ..request() };
        let outcome =
            session::render(&Request { budget: Some(Budget::Iterations(3)), ..resumed }, None, &mut Quiet).unwrap();
        assert_eq!(outcome.summary.resumed_after, Some(2));
    }
}
