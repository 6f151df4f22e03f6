//! Everything a scene is made of: shapes and their intersection, the BVH, materials and the
//! per-hit BSDF, lights, the camera, the film and the built-in reference scenes.
//!
//! This crate does not know about integrators or file formats.

pub mod accel;
