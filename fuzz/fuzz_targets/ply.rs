//! Fuzz target: the PLY mesh reader must return a mesh or an error, never panic, and a
//! returned mesh must be valid.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(mesh) = io::mesh::parse_ply(data, std::path::Path::new("fuzz.ply")) {
        assert!(mesh.validate().is_ok());
    }
});
