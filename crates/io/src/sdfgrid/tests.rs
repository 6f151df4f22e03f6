//! Tests of the SDF grid and its tessellation.
