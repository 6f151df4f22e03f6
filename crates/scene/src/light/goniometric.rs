//! pbrt-v4's goniometric light: a point whose radiant intensity over directions is an image in
//! the equal-area octahedral parametrisation ([`super::equal_area`]).
//!
//! The intensity along the unit world direction `d` is `I · m(square(v))`, with `v` the
//! direction in the light's map frame (`v = (d·x, d·y, d·z)`), `square` the equal-area map and
//! `m` the image's single channel (the mean of its R, G and B) at the nearest texel (pbrt-v4
//! looks the image up without filtering, clamped at the edges). Emission samples a texel in
//! proportion to `m` and a point uniformly within it: the density is `p(s)` per unit square,
//! `p(s)/(4π)` per steradian (the map preserves area), and exactly proportional to the
//! intensity. The flux is `4π · I · mean(m)`.

use std::sync::Arc;

use math::{Distribution2D, Frame, PI, PdfA, PdfW, Vec2, Vec3};
use spectrum::Rgb;

use super::{DirectSample, EmissionSample, check_point, check_rgb, equal_area};
use crate::desc::TextureImage;
use crate::light_tree_bounds::LightBounds;

/// A point light with an intensity image over the sphere of directions.
#[derive(Clone, Debug, PartialEq)]
pub struct GoniometricLight {
    /// Position (scene units).
    pub position: Vec3,
    /// World images of the map's local axes (`z` is the image's centre).
    pub frame: Frame,
    /// Intensity factor (W·sr⁻¹ per channel) applied to the image's values.
    pub intensity: Rgb,
    /// Image side (texels); the image is square.
    resolution: usize,
    /// The single channel, row-major, row 0 at `v = 0` (unitless, ≥ 0).
    values: Arc<Vec<f32>>,
    /// Density over the square in proportion to `values`; `None` when the image is black.
    distribution: Option<Arc<Distribution2D>>,
    /// Mean of `values`.
    mean: f32,
}

impl GoniometricLight {
    /// The light at `position` whose map frame has the orthonormal world axes `frame`, emitting
    /// `intensity × m` with `m` the mean of the channels of the square `image`. Fails for a
    /// non-square or empty image, negative or non-finite texels, a non-orthonormal frame or
    /// a negative or non-finite intensity.
    pub fn new(position: Vec3, frame: [Vec3; 3], image: &TextureImage, intensity: Rgb) -> Result<Self, String> {
        check_point("goniometric light position", position)?;
        check_rgb("goniometric light intensity", intensity)?;
        let orthonormal =
            (0..3).all(|i| (0..3).all(|j| (frame[i].dot(frame[j]) - if i == j { 1.0 } else { 0.0 }).abs() < 1e-4));
        if !orthonormal {
            return Err(format!("goniometric light: the frame {frame:?} is not orthonormal"));
        }
        let n = image.width as usize;
        if n == 0 || image.height != image.width || image.pixels.len() != n * n {
            return Err(format!(
                "goniometric light: the image is {}×{}; an equal-area map is a non-empty square",
                image.width, image.height
            ));
        }
        let values: Vec<f32> = image.pixels.iter().map(|p| (p.r + p.g + p.b) / 3.0).collect();
        if let Some(bad) = values.iter().position(|v| !(v.is_finite() && *v >= 0.0)) {
            return Err(format!(
                "goniometric light: texel ({}, {}) is {:?}; intensities must be finite and non-negative",
                bad % n,
                bad / n,
                image.pixels[bad].to_array()
            ));
        }
        let mean = (values.iter().map(|&v| f64::from(v)).sum::<f64>() / (n * n) as f64) as f32;
        let distribution = Distribution2D::new(&values, n, n).map(Arc::new);
        Ok(Self {
            position,
            frame: Frame { x: frame[0], y: frame[1], z: frame[2] },
            intensity,
            resolution: n,
            values: Arc::new(values),
            distribution,
            mean,
        })
    }

    /// Luminance of the radiant flux `4π · I · mean(m)` (W).
    pub(super) fn power_luminance(&self) -> f32 {
        4.0 * PI * self.mean * self.intensity.luminance()
    }

    /// Intensity (W/sr per channel) along the unit world direction `direction`, and the
    /// solid-angle density with which `GoniometricLight::sample_emission` emits along it.
    pub fn emitted(&self, direction: Vec3) -> (Rgb, f32) {
        let Some(distribution) = &self.distribution else { return (Rgb::BLACK, 0.0) };
        let s = equal_area::sphere_to_square(self.frame.to_local(direction)).clamp(Vec2::ZERO, Vec2::ONE);
        let texel = |c: f32| ((c * self.resolution as f32) as usize).min(self.resolution - 1);
        let value = self.values[texel(s.y) * self.resolution + texel(s.x)];
        (self.intensity * value, distribution.pdf(s) / (4.0 * PI))
    }

    /// Next-event estimation from `receiver` (direct density 1 per unit area, as for point
    /// lights); `None` where the intensity is black.
    pub(super) fn sample_direct(&self, receiver: Vec3) -> Option<DirectSample> {
        let to_light = self.position - receiver;
        let distance_squared = to_light.length_squared();
        let distance = distance_squared.sqrt();
        let direction = to_light / distance;
        let (intensity, pdf) = self.emitted(-direction);
        if intensity.is_black() || !distance_squared.is_normal() {
            return None;
        }
        Some(DirectSample {
            radiance: intensity,
            direction,
            distance,
            direct_pdf: PdfA(1.0).to_solid_angle(distance_squared, 1.0),
            emission_pdf: PdfW(pdf),
            cos_at_light: 1.0,
        })
    }

    /// A light sub-path start: a direction in proportion to the intensity.
    pub(super) fn sample_emission(&self, u_direction: [f32; 2]) -> EmissionSample {
        let direction = match &self.distribution {
            Some(distribution) => {
                let (s, _) = distribution.sample(u_direction);
                self.frame.to_world(equal_area::square_to_sphere(s))
            }
            None => Vec3::Z,
        };
        // Intensity and density evaluated from the direction, as sample_direct does.
        let (energy, pdf) = self.emitted(direction);
        EmissionSample {
            normal: Vec3::ZERO,
            energy,
            origin: self.position,
            direction,
            emission_pdf: PdfW(pdf),
            direct_pdf: PdfA(1.0),
            cos_at_light: 1.0,
        }
    }
}

impl GoniometricLight {
    /// Bounds for the light tree ([`LightBounds`]) from the light's power (W): strength
    /// `power/4π` (the mean intensity), emission in every direction.
    pub(super) fn bounds(&self, power: f32) -> LightBounds {
        LightBounds::omnidirectional(math::Aabb::new(self.position, self.position), power / (4.0 * math::PI))
    }
}
