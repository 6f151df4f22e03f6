//! The `render` package's integration tests, compiled and linked as one binary instead of one per
//! file (docs/testing.md, "The test build: one test binary per crate"). Each file of this
//! directory is a module here; `every_test_file_is_compiled` fails when one is not.
//! `vcm_memory.rs` stays a binary of its own (a `[[test]]` in Cargo.toml): it reads
//! its own process's peak memory, which the other tests would inflate.

mod alpha_masks;
mod cameras;
mod coated;
mod coated_mis;
mod common;
mod cornell_fog;
mod diffuse_transmission;
mod distributed;
mod eye_light;
mod film;
mod fluorescence;
mod goniometric;
mod heterogeneous;
mod light_tree;
mod masked_emitter;
mod media;
mod mesh_attributes;
mod mesh_attributes_vcm;
mod mis_compensation;
mod mis_oracle;
mod mis_oracle_media;
mod mitsuba_reference;
mod parallelism;
mod path_tracer;
mod primary_samples;
mod resume;
mod scene_files;
mod spectral;
mod textured_lights;
mod vcm_consistency;
mod vcm_determinism;
mod vcm_furnace;
mod vcm_grid_media;
mod vcm_media;
mod vcm_modes;
mod vcm_radius;
mod vcm_technique_images;
mod volume_radius;

#[test]
fn every_test_file_is_compiled() {
    testkit::assert_every_test_file_compiled(env!("CARGO_MANIFEST_DIR"));
}
