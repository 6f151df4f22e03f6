//! Fuzz target: the Mitsuba `.serialized` reader (first byte picks the shape index) must return a
//! mesh or an error, never panic, and a returned mesh must be valid.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((index, bytes)) = data.split_first() else { return };
    if let Ok(mesh) = io::mesh::parse_serialized(bytes, u32::from(*index % 4), std::path::Path::new("fuzz.serialized"))
    {
        assert!(mesh.validate().is_ok());
    }
});
