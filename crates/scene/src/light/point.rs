//! The isotropic point light.

use math::{PdfA, PdfW, Vec3, warp};
use spectrum::Rgb;

use super::{DirectSample, EmissionSample};
use crate::light_tree_bounds::LightBounds;

/// An isotropic point light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointLight {
    /// Position.
    pub position: Vec3,
    /// Radiant intensity (W·sr⁻¹ per channel).
    pub intensity: Rgb,
}

impl PointLight {
    /// Next-event estimation from `receiver` (direct density 1 per unit area).
    pub(super) fn sample_direct(&self, receiver: Vec3) -> Option<DirectSample> {
        let to_light = self.position - receiver;
        let distance_squared = to_light.length_squared();
        let distance = distance_squared.sqrt();
        Some(DirectSample {
            radiance: self.intensity,
            direction: to_light / distance,
            distance,
            direct_pdf: PdfA(1.0).to_solid_angle(distance_squared, 1.0),
            emission_pdf: PdfW(warp::UNIFORM_SPHERE_PDF),
            cos_at_light: 1.0,
        })
    }

    /// A light sub-path start: a uniform direction on the sphere.
    pub(super) fn sample_emission(&self, u_direction: [f32; 2]) -> EmissionSample {
        EmissionSample {
            normal: Vec3::ZERO,
            energy: self.intensity,
            origin: self.position,
            direction: warp::uniform_sphere(u_direction),
            emission_pdf: PdfW(warp::UNIFORM_SPHERE_PDF),
            direct_pdf: PdfA(1.0),
            cos_at_light: 1.0,
        }
    }
}

impl PointLight {
    /// Bounds for the light tree ([`LightBounds`]) from the light's power (W): strength
    /// `power/4π` (the intensity), emission in every direction.
    pub(super) fn bounds(&self, power: f32) -> LightBounds {
        LightBounds::omnidirectional(math::Aabb::new(self.position, self.position), power / (4.0 * math::PI))
    }
}
