//! The integrator's `rr_depth` (the first bounce of Mitsuba 3's Russian roulette) reaches
//! [`io::RenderSettings::rr_depth`]: from the path integrators, through the `aov` and `moment`
//! wrappers, Mitsuba's default 5 when the file does not say, `None` for pbrt files; bad values
//! are errors at their line.

use std::fs;
use std::path::{Path, PathBuf};

use io::{LoadOptions, LoadedScene, SceneError};

const STRICT: LoadOptions = LoadOptions { permissive: false };

/// Writes `text` as `<test>/<name>` in a fresh directory and loads it strictly.
fn load(test: &str, name: &str, text: &str) -> (Result<LoadedScene, SceneError>, PathBuf) {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("vcm-io-rr-depth-tests").join(test);
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    fs::write(&path, text).unwrap();
    (io::load_scene_with(&path, &[], &STRICT), path)
}

/// A Mitsuba scene of `body` (starting on line 2).
fn mitsuba(test: &str, body: &str) -> (Result<LoadedScene, SceneError>, PathBuf) {
    load(test, "scene.xml", &format!("<scene version=\"3.0.0\">\n{body}\n</scene>\n"))
}

fn rr_depth(test: &str, body: &str) -> Option<u32> {
    mitsuba(test, body).0.unwrap_or_else(|e| panic!("{test}: {e}")).settings.rr_depth
}

#[test]
fn the_path_integrators_give_their_rr_depth() {
    for ty in ["path", "volpath", "volpathmis"] {
        let body = format!(r#"<integrator type="{ty}"><integer name="rr_depth" value="3"/></integrator>"#);
        assert_eq!(rr_depth(ty, &body), Some(3), "{ty}");
    }
    // The default parameter route the reference scenes use.
    let body = r#"<default name="rr" value="12"/>
        <integrator type="path"><integer name="rr_depth" value="$rr"/><integer name="max_depth" value="20"/></integrator>"#;
    assert_eq!(rr_depth("default_parameter", body), Some(12));
}

#[test]
fn wrapped_integrators_give_the_rr_depth_of_the_one_they_wrap() {
    for wrapper in ["aov", "moment"] {
        let body = format!(
            r#"<integrator type="{wrapper}"><string name="aovs" value="dd.y:depth"/>
                <integrator type="volpath" name="image"><integer name="rr_depth" value="7"/></integrator>
            </integrator>"#
        );
        assert_eq!(rr_depth(wrapper, &body), Some(7), "{wrapper}");
    }
    let body = r#"<integrator type="moment"><integer name="max_depth" value="4"/><integrator type="aov">
        <integer name="max_depth" value="4"/><integrator type="path"><integer name="rr_depth" value="2"/></integrator>
        </integrator></integrator>"#;
    assert_eq!(rr_depth("nested_twice", body), Some(2));
}

#[test]
fn mitsuba_files_that_do_not_say_get_mitsubas_default_and_pbrt_files_none() {
    assert_eq!(rr_depth("path_without", r#"<integrator type="path"/>"#), Some(5));
    assert_eq!(rr_depth("no_integrator", ""), Some(5));
    let pbrt = "Film \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\nWorldBegin\n";
    let (r, _) = load("pbrt", "scene.pbrt", pbrt);
    assert_eq!(r.unwrap().settings.rr_depth, None);
}

#[test]
fn bad_rr_depths_are_errors_at_their_line() {
    for (test, value, kind, needle) in [
        ("zero", "0", "integer", "≥ 1"),
        ("negative", "-1", "integer", "≥ 1"),
        ("float", "2.5", "float", "wrong type"),
        ("too_large", "4294967296", "integer", "≥ 1"),
    ] {
        let body = format!("<integrator type=\"path\">\n<{kind} name=\"rr_depth\" value=\"{value}\"/>\n</integrator>");
        let (r, path) = mitsuba(test, &body);
        let e = r.expect_err(test);
        assert_eq!((e.file.as_path(), e.line), (path.as_path(), Some(3)), "{test}: {e}");
        assert!(e.message.contains("rr_depth") && e.message.contains(needle), "{test}: {e}");
    }
    // Not an integer at all.
    let (r, path) =
        mitsuba("text", "<integrator type=\"path\">\n<integer name=\"rr_depth\" value=\"five\"/>\n</integrator>");
    let e = r.expect_err("text");
    assert_eq!((e.file.as_path(), e.line), (path.as_path(), Some(3)), "{e}");
}
