//! Bounding volume hierarchy (being written).
