//! Slices (`--slice K/N`) merged by `vcm merge` ([`session::merge`]) equal one process's
//! render with fixed-point sums bit for bit — image, variance image and checkpoint files — for
//! pt, bpt, vcm (RGB and spectral), a scene file and slices rendered on in-process ranks; an
//! interrupted slice resumes in place; bad sets of slices are clear errors.

use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

use render::Algorithm;
use render::distributed::LocalRanks;
use render::driver::Budget;
use scene::Summation;
use session::slice::SliceSpec;
use session::{Notice, Observer, Request};
use testkit::TempDir;

struct Quiet;

impl Observer for Quiet {
    fn notice(&mut self, _: Notice) {}
}

fn dir(name: &str) -> TempDir {
    TempDir::new(&format!("session-slices-{name}"))
}

fn request(scene: &str, algorithm: &str, iterations: u64, out: &Path, name: &str) -> Request {
    Request {
        resolution: Some((16, 12)),
        algorithm: Algorithm::from_name(algorithm).unwrap(),
        budget: Some(Budget::Iterations(iterations)),
        threads: 1,
        output: Some(out.join(format!("{name}.exr"))),
        checkpoint: Some(out.join(format!("{name}.ckpt"))),
        ..Request::new(session::scene_source(scene, &[]).unwrap())
    }
}

/// Renders `base` as `count` slices and merges them; returns the merged film's image,
/// variance image and checkpoint bytes.
fn sliced(base: &Request, count: u32, out: &Path) -> Vec<Vec<u8>> {
    let parts: Vec<PathBuf> = (0..count)
        .map(|index| {
            let part = out.join(format!("part-{index}.ckpt"));
            let request = Request {
                slice: Some(SliceSpec { index, count }),
                checkpoint: Some(part.clone()),
                output: Some(out.join(format!("part-{index}.exr"))),
                ..base.clone()
            };
            let outcome = session::render(&request, None, &mut Quiet).unwrap();
            assert!(outcome.summary.to_string().contains(&format!("of slice {index}/{count}")), "{}", outcome.summary);
            part
        })
        .collect();
    let merged = session::merge::merge(&parts).unwrap();
    let files = [out.join("merged.exr"), out.join("merged-variance.exr"), out.join("merged.ckpt")];
    session::merge::write(&merged, &files[0], Some(&files[1]), Some(&files[2])).unwrap();
    files.iter().map(|f| std::fs::read(f).unwrap()).collect()
}

fn single(base: &Request, out: &Path) -> Vec<Vec<u8>> {
    let request = Request {
        summation: Some(Summation::Fixed),
        output: Some(out.join("single.exr")),
        variance: Some(out.join("single-variance.exr")),
        checkpoint: Some(out.join("single.ckpt")),
        ..base.clone()
    };
    session::render(&request, None, &mut Quiet).unwrap();
    ["single.exr", "single-variance.exr", "single.ckpt"].iter().map(|f| std::fs::read(out.join(f)).unwrap()).collect()
}

#[test]
fn merged_slices_write_the_files_of_one_process() {
    let shared_free = [("1", "pt", false), ("1", "bpt", false), ("1", "vcm", false), ("4", "vcm", true)];
    for (scene, algorithm, spectral) in shared_free {
        let out = dir(&format!("{scene}-{algorithm}-{spectral}"));
        let base = Request { spectral, ..request(scene, algorithm, 7, &out, "base") };
        let truth = single(&base, &out);
        for count in [1, 3, 7] {
            assert!(
                sliced(&base, count, &out) == truth,
                "{algorithm} (scene {scene}, spectral {spectral}) in {count} slices"
            );
        }
    }
}

#[test]
fn merged_slices_of_a_scene_file_equal_one_process() {
    let out = dir("file");
    let xml = out.join("box.xml");
    std::fs::write(
        &xml,
        r#"<scene version="3.0.0">
  <sensor type="perspective"><float name="fov" value="40"/>
    <transform name="to_world"><lookat origin="0,0,4" target="0,0,0" up="0,1,0"/></transform>
    <film type="hdrfilm"><integer name="width" value="16"/><integer name="height" value="12"/></film></sensor>
  <shape type="sphere"><bsdf type="diffuse"/></shape>
  <shape type="rectangle"><transform name="to_world"><translate z="-1.5"/><scale value="4"/></transform>
    <bsdf type="dielectric"/></shape>
  <emitter type="point"><point name="position" x="1" y="2" z="2"/><rgb name="intensity" value="20"/></emitter>
  <emitter type="constant"><rgb name="radiance" value="0.1"/></emitter>
</scene>"#,
    )
    .unwrap();
    let base = request(&xml.display().to_string(), "vcm", 5, &out, "base");
    assert!(sliced(&base, 2, &out) == single(&base, &out), "scene file in 2 slices");
}

#[test]
fn slices_rendered_on_ranks_merge_into_one_process_s_render() {
    let out = dir("ranks");
    let base = request("1", "vcm", 6, &out, "base");
    let truth = single(&base, &out);
    let parts: Vec<PathBuf> = (0..2)
        .map(|index| {
            let part = out.join(format!("ranked-{index}.ckpt"));
            let request =
                Request { slice: Some(SliceSpec { index, count: 2 }), checkpoint: Some(part.clone()), ..base.clone() };
            let comms = LocalRanks::connect(2);
            std::thread::scope(|s| {
                let handles: Vec<_> = comms
                    .into_iter()
                    .map(|comm| {
                        let request = &request;
                        s.spawn(move || session::render_on(request, None, &mut Quiet, Some(&comm)).map(drop))
                    })
                    .collect();
                handles.into_iter().for_each(|h| h.join().unwrap().unwrap());
            });
            part
        })
        .collect();
    let merged = session::merge::merge(&parts).unwrap();
    let checkpoint = out.join("ranked-merged.ckpt");
    session::merge::write(&merged, &out.join("ranked.exr"), None, Some(&checkpoint)).unwrap();
    assert!(std::fs::read(checkpoint).unwrap() == truth[2], "slices on 2 ranks each");
}

#[test]
fn an_interrupted_slice_is_refused_by_merge_and_resumes_in_place() {
    let out = dir("interrupted");
    let base = request("1", "pt", 6, &out, "base");
    let truth = single(&base, &out);
    let part = |index: u32| out.join(format!("part-{index}.ckpt"));
    let slice = |index: u32| Request {
        slice: Some(SliceSpec { index, count: 2 }),
        checkpoint: Some(part(index)),
        ..base.clone()
    };
    session::render(&slice(0), None, &mut Quiet).unwrap();
    // A stop flag set before the first iteration: slice 1 is saved with none of its 3.
    let stop = AtomicBool::new(true);
    assert!(session::render(&slice(1), Some(&stop), &mut Quiet).unwrap().summary.interrupted);
    let message = format!("{:#}", session::merge::merge(&[part(0), part(1)]).err().unwrap());
    assert!(message.contains("holds iterations 3..3 of slice 1/2's 3..6") && message.contains("--resume"), "{message}");
    let resumed = Request { resume: Some(part(1)), ..Request::new(session::scene_source("1", &[]).unwrap()) };
    let outcome = session::render(&Request { threads: 1, ..resumed }, None, &mut Quiet).unwrap();
    assert_eq!((outcome.summary.iterations, outcome.summary.resumed_after), (3, Some(0)));
    let merged = session::merge::merge(&[part(1), part(0)]).unwrap();
    let checkpoint = out.join("merged.ckpt");
    session::merge::write(&merged, &out.join("merged.exr"), None, Some(&checkpoint)).unwrap();
    assert!(std::fs::read(checkpoint).unwrap() == truth[2], "resumed slice merged");
}

#[test]
fn bad_sets_of_slices_are_clear_errors() {
    let out = dir("bad");
    let base = request("1", "pt", 4, &out, "base");
    let part = |index: u32, count: u32, seed: u64| {
        let path = out.join(format!("part-{index}-of-{count}-seed-{seed}.ckpt"));
        let request =
            Request { slice: Some(SliceSpec { index, count }), checkpoint: Some(path.clone()), seed, ..base.clone() };
        session::render(&request, None, &mut Quiet).unwrap();
        path
    };
    let error = |parts: &[PathBuf]| format!("{:#}", session::merge::merge(parts).err().unwrap());
    let (a, b, c) = (part(0, 3, 0), part(1, 3, 0), part(2, 3, 0));
    assert!(error(&[a.clone(), c.clone()]).contains("slices missing: 1/3 (iterations 1..2)"));
    assert!(error(&[a.clone(), b.clone(), b.clone(), c.clone()]).contains("slice 1/3 is given twice"));
    let other_seed = part(1, 3, 9);
    let message = error(&[a.clone(), other_seed, c.clone()]);
    assert!(message.contains("not slices of one render") && message.contains("seed=0 vs seed=9"), "{message}");
    let message = error(&[a.clone(), part(1, 2, 0)]);
    assert!(message.contains("slice=0/3 vs slice=1/2") || message.contains("not slices of one render"), "{message}");
    let whole = out.join("base.ckpt");
    session::render(&base, None, &mut Quiet).unwrap();
    assert!(error(&[whole]).contains("holds a whole render, not a slice"));
    // Requests a slice cannot have.
    let slice = |r: Request| Request { slice: Some(SliceSpec { index: 0, count: 2 }), ..r };
    let refused = |r: Request| format!("{:#}", session::render(&r, None, &mut Quiet).err().unwrap());
    assert!(refused(slice(Request { checkpoint: None, ..base.clone() })).contains("needs --checkpoint"));
    assert!(refused(slice(Request { summation: Some(Summation::Float), ..base.clone() })).contains("--sums fixed"));
    let timed = Request { budget: Some(Budget::Time(std::time::Duration::from_secs(1))), ..base.clone() };
    assert!(refused(slice(timed)).contains("not --time"));
    let many = Request { slice: Some(SliceSpec { index: 0, count: 9 }), ..base.clone() };
    assert!(refused(many).contains("cannot be split into 9 slices"));
}
