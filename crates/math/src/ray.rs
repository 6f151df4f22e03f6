//! Rays: an origin and a unit direction.

use glam::Vec3;

/// A ray `origin + t·direction`, `t > 0`. `direction` is expected to be unit length, so `t` is a
/// distance in scene units.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Start point (scene units).
    pub origin: Vec3,
    /// Unit direction.
    pub direction: Vec3,
}

impl Ray {
    /// A ray from `origin` along the unit vector `direction`.
    #[inline]
    pub fn new(origin: Vec3, direction: Vec3) -> Self {
        Self { origin, direction }
    }

    /// The point at distance `t` along the ray.
    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + t * self.direction
    }
}
