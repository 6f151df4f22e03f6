//! A guard for crates whose integration tests are compiled into one binary.
//!
//! Cargo builds and links every `tests/*.rs` file as a binary of its own; with 92 such files a
//! clean test build took longer than running the tests (docs/testing.md, "The test build: one
//! test binary per crate"). The crates therefore set `autotests = false` and declare one `[[test]]`
//! whose root, `tests/main.rs`, lists the files as modules. A file left out of that list would
//! silently never compile nor run; [`assert_every_test_file_compiled`] makes that a failure.

use std::path::Path;

/// Panics, naming the files, unless every `*.rs` file directly in `<manifest_dir>/tests` is
/// either declared as a module (`mod <stem>;`) in `<manifest_dir>/tests/main.rs` or is the
/// `path` of a `[[test]]` target of its own in `<manifest_dir>/Cargo.toml`.
///
/// Call it from a test in `tests/main.rs` with `env!("CARGO_MANIFEST_DIR")`.
pub fn assert_every_test_file_compiled(manifest_dir: &str) {
    let dir = Path::new(manifest_dir).join("tests");
    let main_source = std::fs::read_to_string(dir.join("main.rs"))
        .unwrap_or_else(|e| panic!("cannot read {}/main.rs: {e}", dir.display()));
    let manifest = std::fs::read_to_string(Path::new(manifest_dir).join("Cargo.toml"))
        .unwrap_or_else(|e| panic!("cannot read {manifest_dir}/Cargo.toml: {e}"));
    let entries = std::fs::read_dir(&dir).unwrap_or_else(|e| panic!("cannot list {}: {e}", dir.display()));
    let mut missing = Vec::new();
    let mut files = 0;
    for entry in entries {
        let path = entry.expect("a directory entry of tests/").path();
        let Some(name) = path.file_name().and_then(|n| n.to_str()) else { continue };
        let Some(stem) = name.strip_suffix(".rs") else { continue };
        if stem == "main" || !path.is_file() {
            continue;
        }
        files += 1;
        let declared = main_source.lines().any(|line| line.trim() == format!("mod {stem};"));
        let own_target = manifest.contains(&format!("path = \"tests/{name}\""));
        if !declared && !own_target {
            missing.push(name.to_string());
        }
    }
    assert!(files > 0, "{} holds no test files", dir.display());
    assert!(
        missing.is_empty(),
        "{}: {} neither a module of tests/main.rs (`mod NAME;`) nor a [[test]] target in Cargo.toml, \
         so never compiled nor run",
        dir.display(),
        missing.join(", ")
    );
}
