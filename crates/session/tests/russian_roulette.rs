//! The path tracer's Russian roulette is resolved in one place: an explicit rule wins (the
//! library's default is the albedo rule); a request for the scene file's rule (`None`) gives a
//! Mitsuba file's integrator `rr_depth` (Mitsuba's default 5 when it does not say) with Mitsuba
//! 3's throughput rule, and the albedo rule for built-in scenes. The summary line and the
//! checkpoint state the policy used, and a resumed render keeps it.

use std::fs;
use std::path::{Path, PathBuf};

use render::Algorithm;
use render::driver::Budget;
use render::path_tracer::RussianRoulette;
use session::{Notice, Observer, Prepared, Request};

struct Quiet;

impl Observer for Quiet {
    fn notice(&mut self, _: Notice) {}
}

fn scratch(test: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("vcm-session-rr-tests").join(test);
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    dir
}

/// A small Mitsuba scene (a diffuse sphere under a constant sky) whose integrator carries
/// `integrator` (e.g. an `rr_depth`), written into `dir`.
fn scene_file(dir: &Path, integrator: &str) -> PathBuf {
    let path = dir.join("scene.xml");
    let text = format!(
        r#"<scene version="3.0.0">
    <integrator type="path">{integrator}</integrator>
    <sensor type="perspective"><transform name="to_world"><lookat origin="0, 0, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="6"/></film></sensor>
    <emitter type="constant"/>
    <shape type="sphere"><bsdf type="diffuse"/></shape>
</scene>
"#
    );
    fs::write(&path, text).unwrap();
    path
}

fn request(scene: &Path, asked: Option<RussianRoulette>) -> Request {
    Request {
        algorithm: Algorithm::PathTracing,
        budget: Some(Budget::Iterations(2)),
        threads: 1,
        russian_roulette: asked,
        ..Request::new(session::scene_source(scene.to_str().unwrap(), &[]).unwrap())
    }
}

/// The policy the session settles on for `request`, as the driver and the checkpoint get it.
fn resolved(request: &Request) -> RussianRoulette {
    let prepared = Prepared::new(request, &mut Quiet).unwrap();
    assert_eq!(prepared.settings.russian_roulette, prepared.recorded.russian_roulette);
    assert_eq!(prepared.request.russian_roulette, Some(prepared.settings.russian_roulette));
    prepared.settings.russian_roulette
}

#[test]
fn the_files_rr_depth_is_used_when_asked_and_an_explicit_option_overrides_it() {
    let three = scene_file(&scratch("file-three"), r#"<integer name="rr_depth" value="3"/>"#);
    let silent = scene_file(&scratch("file-silent"), "");
    assert_eq!(resolved(&request(&three, None)), RussianRoulette::Throughput { start: 3 });
    assert_eq!(resolved(&request(&silent, None)), RussianRoulette::Throughput { start: 5 });
    assert_eq!(resolved(&request(&three, Some(RussianRoulette::Albedo))), RussianRoulette::Albedo);
    assert_eq!(
        resolved(&request(&three, Some(RussianRoulette::Throughput { start: 9 }))),
        RussianRoulette::Throughput { start: 9 }
    );
    // Built-in scenes keep the albedo rule unless asked.
    let builtin = Request { resolution: Some((8, 6)), ..request(&three, None) };
    let builtin = Request { scene: session::scene_source("1", &[]).unwrap(), ..builtin };
    assert_eq!(resolved(&builtin), RussianRoulette::Albedo);
    assert_eq!(
        resolved(&Request { russian_roulette: Some(RussianRoulette::Throughput { start: 2 }), ..builtin }),
        RussianRoulette::Throughput { start: 2 }
    );
    // A request that leaves the choice to the library gets the albedo rule (measured more
    // efficient, docs/performance.md), also for a file that names an rr_depth; `None` (the CLI's
    // `--rr-depth file`) asks for the file's.
    let default = Request::new(session::scene_source(three.to_str().unwrap(), &[]).unwrap());
    assert_eq!(default.russian_roulette, Some(RussianRoulette::Albedo));
    assert_eq!(resolved(&request(&three, default.russian_roulette)), RussianRoulette::Albedo);
    // The same rule as the library function.
    assert_eq!(session::resolve_russian_roulette(None, None), RussianRoulette::Albedo);
    assert_eq!(session::resolve_russian_roulette(None, Some(4)), RussianRoulette::Throughput { start: 4 });
}

#[test]
fn a_bad_rr_depth_in_the_file_is_an_error_naming_it() {
    let bad = scene_file(&scratch("bad"), r#"<integer name="rr_depth" value="0"/>"#);
    let error = Prepared::new(&request(&bad, None), &mut Quiet).err().expect("rr_depth 0 must be refused");
    let message = format!("{error:#}");
    assert!(message.contains("rr_depth") && message.contains("scene.xml:2"), "{message}");
}

#[test]
fn the_summary_and_the_checkpoint_state_the_policy_and_a_resume_keeps_it() {
    let dir = scratch("resume");
    let scene = scene_file(&dir, r#"<integer name="rr_depth" value="3"/>"#);
    let checkpoint = dir.join("film.ckpt");
    let first = Request { checkpoint: Some(checkpoint.clone()), ..request(&scene, None) };
    let outcome = session::render(&first, None, &mut Quiet).unwrap();
    assert!(outcome.summary.to_string().contains("with pt (rr-depth 3) at 8x6"), "{}", outcome.summary);
    let (recorded, _) = session::checkpoint::load(&checkpoint).unwrap();
    assert_eq!(recorded.russian_roulette, RussianRoulette::Throughput { start: 3 });

    // A resume without an option, or with another one, continues with the recorded policy
    // (as for every other recorded setting).
    for asked in [None, Some(RussianRoulette::Albedo)] {
        let resumed = Request {
            resume: Some(checkpoint.clone()),
            checkpoint: Some(dir.join("resumed.ckpt")),
            budget: Some(Budget::Iterations(3)),
            ..request(&scene, asked)
        };
        assert_eq!(resolved(&resumed), RussianRoulette::Throughput { start: 3 });
    }
    // The other algorithms always use the albedo rule; their line does not name a policy.
    let vcm = Request { algorithm: Algorithm::from_name("vcm").unwrap(), ..request(&scene, None) };
    let line = session::render(&vcm, None, &mut Quiet).unwrap().summary.to_string();
    assert!(line.contains("with vcm at 8x6") && !line.contains("rr-depth"), "{line}");
}
