//! End-to-end tests of the `vcm` binary: a small render writes its files, and bad input fails
//! with a clear message and a non-zero exit code before any rendering.

use std::path::PathBuf;
use std::process::{Command, Output};

fn vcm(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_vcm")).args(args).output().expect("the vcm binary runs")
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("cli-tests").join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

#[test]
fn small_render_writes_linear_image_and_preview() {
    let dir = temp_dir("render");
    let out = dir.join("a.pfm");
    let output =
        vcm(&["render", "--scene", "1", "-a", "pt", "-i", "2", "-r", "32x24", "-o", out.to_str().unwrap(), "--quiet"]);
    assert!(output.status.success(), "{}", stderr(&output));
    let image = io::read_image(&out).unwrap();
    assert_eq!((image.width, image.height), (32, 24));
    assert!(image.channel_means().iter().all(|m| *m > 0.0));
    assert!(dir.join("a.png").exists(), "a PNG preview is written beside a linear output");
    let summary = stderr(&output);
    assert!(summary.contains("2 iterations") && summary.contains("ms/iteration"), "{summary}");
}

#[test]
fn scenes_lists_the_builtins() {
    let output = vcm(&["scenes"]);
    assert!(output.status.success());
    let text = String::from_utf8_lossy(&output.stdout);
    for name in ["cornell-sun", "cornell-area-mirror", "cornell-point", "cornell-env"] {
        assert!(text.contains(name), "{text}");
    }
}

fn assert_fails(args: &[&str], expected: &[&str]) {
    let output = vcm(args);
    assert!(!output.status.success(), "{args:?} should fail");
    let message = stderr(&output);
    for e in expected {
        assert!(message.contains(e), "{args:?}: message {message:?} lacks {e:?}");
    }
}

#[test]
fn bad_input_fails_clearly() {
    let dir = temp_dir("errors");
    let out = dir.join("x.exr");
    let out = out.to_str().unwrap();
    assert_fails(&["render", "--scene", "cornell-moon", "-o", out], &["unknown scene 'cornell-moon'", "cornell-sun"]);
    assert_fails(&["render", "--scene", "7", "-o", out], &["unknown scene '7'"]);
    assert_fails(&["render", "--resolution", "512", "-o", out], &["invalid resolution '512'", "WIDTHxHEIGHT"]);
    assert_fails(&["render", "--resolution", "0x10", "-o", out], &["invalid resolution"]);
    assert_fails(&["render", "--algorithm", "foo", "-o", out], &["invalid value 'foo'", "pt", "vcm"]);
    assert_fails(&["render", "--scene-mask", "600", "-i", "1", "-o", out], &["invalid scene mask 600"]);
    assert_fails(
        &["render", "-i", "1", "-o", "/nonexistent-dir/x.exr"],
        &["cannot write output '/nonexistent-dir/x.exr'"],
    );
    assert_fails(
        &["render", "-i", "1", "-o", dir.join("x.bmp").to_str().unwrap()],
        &["unsupported image extension '.bmp'"],
    );
    assert_fails(&["render", "--scene", "missing.xml", "-o", out], &["scene file 'missing.xml' does not exist"]);
    assert_fails(&["render", "--time", "0", "-o", out], &["--time must be a positive number"]);
    assert!(!std::path::Path::new(out).exists(), "nothing was written");
}
