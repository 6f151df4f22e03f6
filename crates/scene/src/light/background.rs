//! The constant environment.

use math::{Frame, PdfA, PdfW, Vec3, warp};
use spectrum::Rgb;

use super::{BoundingSphere, DirectSample, EmissionSample, HitRadiance, disc_origin, disc_pdf};

/// A constant environment: the same radiance from every direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BackgroundLight {
    /// Radiance arriving from every direction (W·m⁻²·sr⁻¹ per channel).
    pub radiance: Rgb,
}

impl BackgroundLight {
    /// Next-event estimation: a uniform direction on the sphere.
    pub(super) fn sample_direct(&self, u: [f32; 2], sphere: &BoundingSphere) -> Option<DirectSample> {
        let direction = warp::uniform_sphere(u);
        Some(DirectSample {
            radiance: self.radiance,
            direction,
            distance: f32::INFINITY,
            direct_pdf: PdfW(warp::UNIFORM_SPHERE_PDF),
            emission_pdf: PdfW(warp::UNIFORM_SPHERE_PDF * disc_pdf(sphere)),
            cos_at_light: 1.0,
        })
    }

    /// A light sub-path start: a uniform direction, an origin on the bounding-sphere disc.
    pub(super) fn sample_emission(
        &self,
        u_position: [f32; 2],
        u_direction: [f32; 2],
        sphere: &BoundingSphere,
    ) -> EmissionSample {
        let direction = warp::uniform_sphere(u_direction);
        EmissionSample {
            normal: Vec3::ZERO,
            energy: self.radiance,
            origin: disc_origin(&Frame::from_z(direction), u_position, sphere),
            direction,
            emission_pdf: PdfW(warp::UNIFORM_SPHERE_PDF * disc_pdf(sphere)),
            direct_pdf: PdfA(warp::UNIFORM_SPHERE_PDF),
            cos_at_light: 1.0,
        }
    }

    /// The radiance of a ray escaping the scene.
    pub(super) fn radiance_on_hit(&self, sphere: &BoundingSphere) -> Option<HitRadiance> {
        Some(HitRadiance {
            radiance: self.radiance,
            direct_pdf: PdfA(warp::UNIFORM_SPHERE_PDF),
            emission_pdf: PdfW(warp::UNIFORM_SPHERE_PDF * disc_pdf(sphere)),
            cos_at_light: 1.0,
        })
    }
}
