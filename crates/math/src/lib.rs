//! Mathematical foundation of the renderer: vectors (re-exported from `glam`), rays, bounding
//! boxes, orthonormal frames, pdfs typed by their measure, sample warps with their pdfs and
//! inverses, discrete distributions and the deterministic random number generator.
//!
//! This crate knows nothing about scenes, colours or light transport.

pub mod bounds;
pub mod distribution;
pub mod frame;
pub mod isa;
pub mod octahedral;
pub mod pdf;
pub mod prefetch;
pub mod ray;
pub mod rng;
pub mod sobol;
pub mod special;
pub mod turns;
pub mod warp;

pub use bounds::Aabb;
pub use distribution::{AliasRows, AliasTable, Distribution1D, Distribution2D};
pub use frame::Frame;
pub use glam::{Vec2, Vec3, Vec3A};
pub use isa::Isa;
pub use pdf::{PdfA, PdfW};
pub use prefetch::prefetch;
pub use ray::Ray;
pub use rng::Rng;
pub use turns::sin_cos_turns;

/// π in single precision.
pub const PI: f32 = std::f32::consts::PI;
/// 1/π in single precision.
pub const INV_PI: f32 = std::f32::consts::FRAC_1_PI;

/// Offset (in scene units) by which a new ray starts past the vertex it leaves, along the ray
/// direction, and by which shadow rays stop short of both end points.
pub const RAY_EPSILON: f32 = 1e-3;

/// Cosines smaller than this are treated as grazing (zero) by the BSDFs and lights.
pub const COSINE_EPSILON: f32 = 1e-6;

/// Square of `x`.
#[inline]
pub fn sqr(x: f32) -> f32 {
    x * x
}

/// Mirror reflection of `direction` (pointing away from the surface) about `normal`.
/// Both are unit vectors; the result points away from the surface on the same side as `normal`
/// when `direction` does.
#[inline]
pub fn reflect(direction: Vec3, normal: Vec3) -> Vec3 {
    2.0 * direction.dot(normal) * normal - direction
}
