//! A session spread over in-process ranks ([`render::distributed::LocalRanks`]) writes the
//! files of a one-process session byte for byte (image, variance image, checkpoint), resumes
//! with another rank count, and ends every rank with the error of a rank that cannot load its
//! scene.

use std::path::Path;

use render::Algorithm;
use render::distributed::LocalRanks;
use render::driver::Budget;
use session::{Notice, Observer, Outcome, Request};
use testkit::TempDir;

struct Quiet;

impl Observer for Quiet {
    fn notice(&mut self, _: Notice) {}
}

fn dir(name: &str) -> TempDir {
    TempDir::new(&format!("session-distributed-{name}"))
}

fn request(algorithm: &str, iterations: u64, dir: &Path) -> Request {
    Request {
        resolution: Some((16, 12)),
        algorithm: Algorithm::from_name(algorithm).unwrap(),
        budget: Some(Budget::Iterations(iterations)),
        threads: 1,
        output: Some(dir.join("image.exr")),
        variance: Some(dir.join("variance.exr")),
        checkpoint: Some(dir.join("film.ckpt")),
        ..Request::new(session::scene_source("1", &[]).unwrap())
    }
}

/// Runs `requests[r]` on rank r.
fn on_ranks(requests: &[Request]) -> Vec<anyhow::Result<Outcome>> {
    let comms = LocalRanks::connect(requests.len());
    std::thread::scope(|s| {
        let handles: Vec<_> = comms
            .into_iter()
            .zip(requests)
            .map(|(comm, request)| s.spawn(move || session::render_on(request, None, &mut Quiet, Some(&comm))))
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    })
}

fn files(dir: &Path) -> Vec<Vec<u8>> {
    ["image.exr", "variance.exr", "film.ckpt"].iter().map(|f| std::fs::read(dir.join(f)).unwrap()).collect()
}

#[test]
fn distributed_sessions_write_the_files_of_one_process() {
    for algorithm in ["pt", "vcm"] {
        let single = dir(&format!("single-{algorithm}"));
        session::render(&request(algorithm, 5, &single), None, &mut Quiet).unwrap();
        for ranks in [2, 3] {
            let many = dir(&format!("{algorithm}-{ranks}"));
            let outcomes = on_ranks(&vec![request(algorithm, 5, &many); ranks]);
            let summary = &outcomes[0].as_ref().unwrap().summary;
            assert_eq!((summary.iterations, summary.ranks), (5, Some(ranks)));
            assert!(summary.to_string().contains(&format!("x {ranks} ranks")), "{summary}");
            assert!(files(&single) == files(&many), "{algorithm} on {ranks} ranks: files differ");
        }
    }
}

#[test]
fn a_distributed_resume_with_another_rank_count_equals_one_uninterrupted_process() {
    let single = dir("resume-single");
    session::render(&request("vcm", 6, &single), None, &mut Quiet).unwrap();
    let many = dir("resume-many");
    on_ranks(&vec![request("vcm", 2, &many); 2]).into_iter().for_each(|o| drop(o.unwrap()));
    let resumed = Request { resume: Some(many.join("film.ckpt")), ..request("vcm", 6, &many) };
    let outcomes = on_ranks(&vec![resumed; 3]);
    assert_eq!(outcomes[0].as_ref().unwrap().summary.resumed_after, Some(2));
    assert!(files(&single)[..2] == files(&many)[..2], "resumed image differs");
}

#[test]
fn a_scene_that_fails_on_one_rank_ends_every_rank_with_its_error() {
    let d = dir("bad-scene");
    let bad = d.join("bad.xml");
    std::fs::write(&bad, "<scene version=\"3.0.0\">\n<shape type=\"nonsense\"/>\n").unwrap();
    let broken = Request { scene: session::scene_source(bad.to_str().unwrap(), &[]).unwrap(), ..request("pt", 2, &d) };
    let outcomes = on_ranks(&[request("pt", 2, &d), broken]);
    let errors: Vec<String> = outcomes.into_iter().map(|o| format!("{:#}", o.unwrap_err())).collect();
    assert!(errors[0].starts_with("rank 1: "), "{}", errors[0]);
    assert_eq!(errors[0], errors[1]);
    assert!(errors[0].contains("bad.xml"), "the error names the file: {}", errors[0]);
}
