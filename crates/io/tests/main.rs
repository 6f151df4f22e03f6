//! The `vcm-io` package's integration tests, compiled and linked as one binary instead of one per
//! file (docs/testing.md, "The test build: one test binary per crate"). Each file of this
//! directory is a module here; `every_test_file_is_compiled` fails when one is not.

mod alpha_masks;
mod bsdf_maps;
mod cylinders;
mod embree_scenes;
mod emitter_spectra;
mod fuzz_corpus;
mod hair;
mod heterogeneous;
mod image_files;
mod instancing;
mod light_selection;
mod load_options;
mod media;
mod meshes;
mod mitsuba;
mod nanovdb;
mod pbrt;
mod pbrt_textures;
mod ply_attributes;
mod principled;
mod rr_depth;
mod sdfgrid;
mod search_paths;
mod shape_uvs;
mod texture_formats;

#[test]
fn every_test_file_is_compiled() {
    testkit::assert_every_test_file_compiled(env!("CARGO_MANIFEST_DIR"));
}
