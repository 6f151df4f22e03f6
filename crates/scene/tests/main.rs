//! The `scene` package's integration tests, compiled and linked as one binary instead of one per
//! file (docs/testing.md, "The test build: one test binary per crate"). Each file of this
//! directory is a module here; `every_test_file_is_compiled` fails when one is not.

mod alpha;
mod bsdf;
mod bsdf_maps;
mod bsdf_models;
mod coated;
mod diffuse_fast_path;
mod emission_spectra;
mod goniometric;
mod hair;
mod instancing;
mod light_tree;
mod lights;
mod map_adapter;
mod masked_emitter;
mod microfacet;
mod microfacet_tangent;
mod phase;
mod principled_formulas;
mod principled_sampling;
mod textured_lights;

#[test]
fn every_test_file_is_compiled() {
    testkit::assert_every_test_file_compiled(env!("CARGO_MANIFEST_DIR"));
}
