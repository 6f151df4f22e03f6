//! End-to-end test of `vcm conformance` on a tiny suite-like directory (tests/data/conformance):
//! an analytic scene against its exact reference passes with pt and vcm, the same scene against a
//! reference 2 % too bright fails, a scene that does not load is reported with its first error,
//! a scene without references is listed, and the Markdown file carries the provenance.

use std::path::{Path, PathBuf};
use std::process::Command;

/// The lit plane's exact radiance (see tests/data/conformance/lit_plane/*.xml).
const PLANE_RADIANCE: f32 = 0.5;
/// The plane scene's film.
const SIZE: (usize, usize) = (24, 16);

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let path = entry.unwrap().path();
        let target = to.join(path.file_name().unwrap());
        if path.is_dir() {
            copy_dir(&path, &target);
        } else {
            std::fs::copy(&path, &target).unwrap();
        }
    }
}

/// Writes a constant reference image and a zero variance image for scene `name` of `group`.
fn write_references(suite: &Path, group: &str, name: &str, value: f32) {
    let refs = suite.join(group).join("refs");
    std::fs::create_dir_all(&refs).unwrap();
    let image = io::Image::from_fn(SIZE.0, SIZE.1, |_, _| [value; 3]);
    let options = io::WriteOptions::default();
    io::write_image(&refs.join(format!("{name}_ref_rgb.exr")), &image, &options).unwrap();
    io::write_image(&refs.join(format!("{name}_ref_rgb_var.exr")), &io::Image::new(SIZE.0, SIZE.1), &options).unwrap();
}

/// The suite: the data directory plus references, and a biased copy of the plane scene.
fn suite() -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("conformance-suite");
    let _ = std::fs::remove_dir_all(&dir);
    copy_dir(&Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/conformance"), &dir);
    write_references(&dir, "lit_plane", "test_lit_plane", PLANE_RADIANCE);
    std::fs::create_dir_all(dir.join("lit_plane_biased")).unwrap();
    std::fs::copy(dir.join("lit_plane/test_lit_plane_path.xml"), dir.join("lit_plane_biased/test_lit_plane_path.xml"))
        .unwrap();
    write_references(&dir, "lit_plane_biased", "test_lit_plane", 1.02 * PLANE_RADIANCE);
    dir
}

/// The table row of `scene`, split into cells (separated by two or more spaces).
fn row<'a>(table: &'a str, scene: &str) -> Vec<&'a str> {
    let line = table.lines().find(|l| l.starts_with(&format!("{scene} "))).unwrap_or_else(|| panic!("{table}"));
    line.split("  ").map(str::trim).filter(|c| !c.is_empty()).collect()
}

#[test]
fn runner_judges_a_tiny_suite() {
    let suite = suite();
    let markdown = suite.join("conformance.md");
    // 256 iterations: the variance of each pixel mean is estimated from 255 degrees of freedom,
    // close enough to known for the normal Z-test.
    let output = Command::new(env!("CARGO_BIN_EXE_vcm"))
        .args(["conformance", suite.to_str().unwrap(), "--spp", "256", "--algorithms", "pt,vcm"])
        .arg("--markdown")
        .arg(&markdown)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&output.stdout);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stdout}\n{stderr}");

    let exact = row(&stdout, "lit_plane/test_lit_plane");
    assert_eq!(exact[1], "yes", "{stdout}");
    for cell in &exact[2..4] {
        assert!(cell.starts_with("PASS") && cell.ends_with("(256 spp)"), "{stdout}");
    }
    // 2 % too bright a reference: the mean ratio is about 1/1.02 = 0.980 and the cell fails,
    // and its escalated render (16 × 256 iterations, another seed) fails too: a longer render
    // does not excuse a bias.
    let biased = row(&stdout, "lit_plane_biased/test_lit_plane");
    for cell in &biased[2..4] {
        let ratio: f64 = cell.split('×').nth(1).and_then(|r| r.split(' ').next()).unwrap().parse().unwrap();
        assert!(cell.starts_with("FAIL") && (ratio - 1.0 / 1.02).abs() < 0.005, "{stdout}");
        assert!(cell.contains("(4096 spp; at 256 spp: FAIL"), "{stdout}");
    }
    assert_eq!(row(&stdout, "participating_media/test_fog")[1], "no reference", "{stdout}");
    assert_eq!(row(&stdout, "unsupported/test_unknown_shape")[1], "no", "{stdout}");
    assert!(
        stdout.lines().any(|l| l.contains("unsupported/test_unknown_shape: unsupported/test_unknown_shape_path.xml:")
            && l.contains("no_such_shape")),
        "{stdout}"
    );
    assert!(stdout.contains("4 scenes, 2 load and render; passed: pt 1, vcm 1"), "{stdout}");
    assert!(stderr.contains("[1/4]") && stderr.contains("[4/4]"), "{stderr}");

    let md = std::fs::read_to_string(&markdown).unwrap();
    for expected in ["- date: ", "- commit: ", "- machine: ", "- command: `", "| lit_plane/test_lit_plane | yes | PASS"]
    {
        assert!(md.contains(expected), "{expected}: {md}");
    }
}

#[test]
fn bad_arguments_fail_clearly() {
    let run = |args: &[&str]| Command::new(env!("CARGO_BIN_EXE_vcm")).arg("conformance").args(args).output().unwrap();
    let output = run(&["/nonexistent-suite"]);
    assert!(!output.status.success());
    assert!(String::from_utf8_lossy(&output.stderr).contains("/nonexistent-suite"));
    let data = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/conformance");
    let output = run(&[data, "--algorithms", "pt,nope"]);
    assert!(String::from_utf8_lossy(&output.stderr).contains("unknown algorithm 'nope'"));
}
