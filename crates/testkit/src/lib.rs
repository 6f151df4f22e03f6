//! Statistical test harnesses for the renderer's tests.
//!
//! - [`chi2`]: chi-square goodness-of-fit tests of samplers against their pdfs, on the unit
//!   sphere ([`chi2_sphere`]) and on the unit square ([`chi2_square`]), with [`assert_chi2`] to
//!   fail a test with a readable table of observed against expected counts.
//! - [`stats`]: running mean and variance ([`MeanVar`]), two-sided z-tests ([`z_test_p`]), the
//!   Šidák correction for families of tests ([`sidak`]) and entry-by-entry comparisons of two
//!   estimates such as two images ([`z_test_entries`]).
//! - [`mitsuba_maps`]: Mitsuba's normal- and bump-mapped Lambertian surfaces in closed form and
//!   by quadrature.
//! - [`temp_dir`]: [`TempDir`], a scratch directory under the system temp dir that is removed
//!   when the guard is dropped (kept if `VCM_KEEP_TEST_DIRS` is set, to inspect a failing test).
//! - [`test_files`]: [`assert_every_test_file_compiled`], the guard of the crates whose
//!   integration tests are modules of one `tests/main.rs`.
//!
//! Every test is deterministic: samplers draw from a [`math::Rng`] seeded by the caller, so a
//! test that passes once passes always. Choose significance levels (say `1e-3`, Šidák-corrected
//! for several tests) so that a correct sampler fails only on an unlucky seed.

pub mod chi2;
pub mod mitsuba_maps;
pub mod stats;
pub mod temp_dir;
pub mod test_files;

pub use chi2::{
    Chi2Outcome, Integration, MIN_EXPECTED, PDF_INTEGRAL_TOLERANCE, assert_chi2, chi2_sphere, chi2_sphere_with,
    chi2_square, chi2_square_with,
};
pub use stats::{MeanVar, ZTestOutcome, sidak, t_test_p, welch_dof, z_test_entries, z_test_p};
pub use temp_dir::TempDir;
pub use test_files::assert_every_test_file_compiled;
