//! The directional light ("sun"), emitting from a disc of the scene's bounding sphere.

use math::{Frame, PdfA, PdfW, Vec3};
use spectrum::Rgb;

use super::{BoundingSphere, DirectSample, EmissionSample, disc_origin, disc_pdf};

/// A directional light ("sun").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DirectionalLight {
    /// Unit direction in which the light travels.
    pub direction: Vec3,
    /// Irradiance on a surface perpendicular to `direction` (W·m⁻² per channel).
    pub irradiance: Rgb,
    frame: Frame,
}

impl DirectionalLight {
    /// Light travelling along `direction` (normalised here) with the given irradiance.
    pub fn new(direction: Vec3, irradiance: Rgb) -> Self {
        let direction = direction.normalize();
        Self { direction, irradiance, frame: Frame::from_z(direction) }
    }
}

impl DirectionalLight {
    /// Next-event estimation: the one direction, density 1.
    pub(super) fn sample_direct(&self, sphere: &BoundingSphere) -> Option<DirectSample> {
        Some(DirectSample {
            radiance: self.irradiance,
            direction: -self.direction,
            distance: f32::INFINITY,
            direct_pdf: PdfW(1.0),
            emission_pdf: PdfW(disc_pdf(sphere)),
            cos_at_light: 1.0,
        })
    }

    /// A light sub-path start on the bounding-sphere disc.
    pub(super) fn sample_emission(&self, u_position: [f32; 2], sphere: &BoundingSphere) -> EmissionSample {
        EmissionSample {
            normal: Vec3::ZERO,
            energy: self.irradiance,
            origin: disc_origin(&self.frame, u_position, sphere),
            direction: self.direction,
            emission_pdf: PdfW(disc_pdf(sphere)),
            direct_pdf: PdfA(1.0),
            cos_at_light: 1.0,
        }
    }
}
