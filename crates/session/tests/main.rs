//! The `session` package's integration tests, compiled and linked as one binary instead of one per
//! file (docs/testing.md, "The test build: one test binary per crate"). Each file of this
//! directory is a module here; `every_test_file_is_compiled` fails when one is not.

mod distributed;
mod film;
mod russian_roulette;
mod session;
mod slices;
mod stepping;

#[test]
fn every_test_file_is_compiled() {
    testkit::assert_every_test_file_compiled(env!("CARGO_MANIFEST_DIR"));
}
