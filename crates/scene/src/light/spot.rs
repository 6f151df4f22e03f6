//! The spot light: a point emitting into a cone with Mitsuba 3's linear-in-angle falloff,
//! optionally times an image projected over the cone (Mitsuba 3's spot `texture`).

use std::sync::Arc;

use math::{Frame, PI, PdfA, PdfW, Vec2, Vec3};
use spectrum::Rgb;

use crate::texture::Texture;

use super::{DirectSample, EmissionSample, check_direction, check_point, check_rgb};
use crate::light_tree_bounds::LightBounds;

/// A spot light (Mitsuba's `spot`): a point emitting `intensity` within `beam_width` of its
/// axis, falling off *linearly in angle* to zero at `cutoff` (Mitsuba 3's falloff curve):
/// `f(θ) = 1` for `θ ≤ beam_width`, `(cutoff − θ)/(cutoff − beam_width)` up to `cutoff`, 0 beyond.
///
/// With a texture ([`SpotLight::with_texture`]) the intensity in the local direction
/// `(x, y, z)` is further multiplied by the texture at
/// `uv = (½ + ½·x/(z·tan c), ½ + ½·y/(z·tan c))`, `c` the cutoff: the image spans the square
/// circumscribing the cone's cross-section. Directions are still sampled uniformly in the cone.
#[derive(Clone, Debug, PartialEq)]
pub struct SpotLight {
    /// Position.
    pub position: Vec3,
    /// Radiant intensity on the axis (W·sr⁻¹ per channel).
    pub intensity: Rgb,
    /// Frame whose `z` is the unit axis.
    frame: Frame,
    /// Half-angle where the falloff ends (radians).
    cutoff: f32,
    /// Half-angle where the falloff begins (radians, ≤ `cutoff`).
    beam_width: f32,
    cos_cutoff: f32,
    cos_beam_width: f32,
    /// The projected texture and `1/tan(cutoff)`.
    texture: Option<(Arc<Texture>, f32)>,
}

impl SpotLight {
    /// A spot light at `position` shining along `axis` (normalised here). Both angles are
    /// half-angles from the axis in degrees, `0 < cutoff ≤ 180` and `0 ≤ beam_width ≤ cutoff`.
    pub fn new(
        position: Vec3,
        axis: Vec3,
        intensity: Rgb,
        cutoff_degrees: f32,
        beam_width_degrees: f32,
    ) -> Result<Self, String> {
        check_point("spot light position", position)?;
        let axis = check_direction("spot light direction", axis)?;
        check_rgb("spot light intensity", intensity)?;
        if !(cutoff_degrees > 0.0 && cutoff_degrees <= 180.0) {
            return Err(format!("spot light: expected a cutoff angle in (0°, 180°], got {cutoff_degrees}°"));
        }
        if !(0.0..=cutoff_degrees).contains(&beam_width_degrees) {
            return Err(format!(
                "spot light: expected a beam width in [0°, cutoff = {cutoff_degrees}°], got {beam_width_degrees}°"
            ));
        }
        let (cutoff, beam_width) = (cutoff_degrees.to_radians(), beam_width_degrees.to_radians());
        Ok(Self {
            position,
            intensity,
            frame: Frame::from_z(axis),
            cutoff,
            beam_width,
            cos_cutoff: cutoff.cos(),
            cos_beam_width: beam_width.cos(),
            texture: None,
        })
    }

    /// The spot with `texture` projected over its cone; `x_axis` and `y_axis` are the unit
    /// world directions of the texture's local `x` and `y` (orthogonal to the axis and to
    /// each other within 1e-3). Fails for a cutoff of 90° or more (the projection needs the
    /// whole cone in front of the light) or axes that do not form a frame with the spot's axis.
    pub fn with_texture(mut self, texture: Arc<Texture>, x_axis: Vec3, y_axis: Vec3) -> Result<Self, String> {
        if self.cutoff >= 0.5 * PI - 1e-4 {
            return Err(format!(
                "spot light: a texture needs a cutoff angle below 90°, got {}°",
                self.cutoff.to_degrees()
            ));
        }
        let z = self.frame.z;
        let orthonormal =
            [(x_axis, x_axis, 1.0), (y_axis, y_axis, 1.0), (x_axis, y_axis, 0.0), (x_axis, z, 0.0), (y_axis, z, 0.0)]
                .iter()
                .all(|(a, b, expected)| (a.dot(*b) - expected).abs() <= 1e-3);
        if !orthonormal {
            return Err(format!(
                "spot light: texture axes {x_axis} and {y_axis} do not form a frame with the axis {z}"
            ));
        }
        self.frame = Frame { x: x_axis, y: y_axis, z };
        self.texture = Some((texture, 1.0 / self.cutoff.tan()));
        Ok(self)
    }

    /// The texture's value for the local direction `local` (white without a texture).
    fn texture_at(&self, local: Vec3) -> Rgb {
        match &self.texture {
            None => Rgb::WHITE,
            Some((texture, inv_tan)) => {
                let k = 0.5 * inv_tan / local.z;
                texture.eval(Vec2::new(0.5 + k * local.x, 0.5 + k * local.y))
            }
        }
    }

    /// Luminance of the radiant flux (W): `∫ I·f(θ)·T(ω) dω` over the cone, by the midpoint
    /// rule on a 64 × 256 grid in (cos θ, φ) when textured, exactly otherwise.
    pub(super) fn power_luminance(&self) -> f32 {
        if self.texture.is_none() {
            return self.falloff_solid_angle() * self.intensity.luminance();
        }
        let (n_theta, n_phi) = (64, 256);
        let d_cos = (1.0 - self.cos_cutoff) / n_theta as f32;
        let mut sum = 0.0f64;
        for i in 0..n_theta {
            let cos_theta = 1.0 - (i as f32 + 0.5) * d_cos;
            let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
            for j in 0..n_phi {
                let (sin_phi, cos_phi) = (2.0 * PI * (j as f32 + 0.5) / n_phi as f32).sin_cos();
                let local = Vec3::new(cos_phi * sin_theta, sin_phi * sin_theta, cos_theta);
                let value = (self.intensity * self.falloff(cos_theta) * self.texture_at(local)).luminance();
                sum += f64::from(value.max(0.0));
            }
        }
        (sum * f64::from(d_cos) * 2.0 * std::f64::consts::PI / n_phi as f64) as f32
    }

    /// Unit axis.
    pub fn axis(&self) -> Vec3 {
        self.frame.z
    }

    /// Falloff factor in `[0, 1]` for a direction whose cosine with the axis is `cos_theta`.
    pub fn falloff(&self, cos_theta: f32) -> f32 {
        if cos_theta <= self.cos_cutoff {
            0.0
        } else if cos_theta >= self.cos_beam_width {
            1.0
        } else {
            ((self.cutoff - cos_theta.clamp(-1.0, 1.0).acos()) / (self.cutoff - self.beam_width)).clamp(0.0, 1.0)
        }
    }

    /// Solid-angle density of emitted directions: uniform in the cutoff cone.
    fn cone_pdf(&self) -> f32 {
        1.0 / (2.0 * PI * (1.0 - self.cos_cutoff))
    }

    /// `∫ f(θ) dω` over the sphere (steradians): `2π(1 − (sin c − sin b)/(c − b))`, which is
    /// `2π(1 − cos c)` when `b = c`.
    pub fn falloff_solid_angle(&self) -> f32 {
        let (c, b) = (self.cutoff as f64, self.beam_width as f64);
        // (sin c − sin b)/(c − b) = cos((c+b)/2)·sinc((c−b)/2), stable for c ≈ b.
        let h = 0.5 * (c - b);
        let sinc = if h.abs() < 1e-4 { 1.0 - h * h / 6.0 } else { h.sin() / h };
        (2.0 * std::f64::consts::PI * (1.0 - (0.5 * (c + b)).cos() * sinc)) as f32
    }
}

impl SpotLight {
    /// Next-event estimation from `receiver` (direct density 1 per unit area); `None` outside
    /// the cone.
    pub(super) fn sample_direct(&self, receiver: Vec3) -> Option<DirectSample> {
        let to_light = self.position - receiver;
        let distance_squared = to_light.length_squared();
        let distance = distance_squared.sqrt();
        let direction = to_light / distance;
        let falloff = self.falloff(self.axis().dot(-direction));
        if falloff <= 0.0 {
            return None;
        }
        let radiance = match self.texture {
            None => self.intensity * falloff,
            Some(_) => self.intensity * falloff * self.texture_at(self.frame.to_local(-direction)),
        };
        Some(DirectSample {
            radiance,
            direction,
            distance,
            direct_pdf: PdfA(1.0).to_solid_angle(distance_squared, 1.0),
            emission_pdf: PdfW(self.cone_pdf()),
            cos_at_light: 1.0,
        })
    }

    /// A light sub-path start: a direction uniform in the cutoff cone.
    pub(super) fn sample_emission(&self, u_direction: [f32; 2]) -> EmissionSample {
        // Uniform in the cutoff cone: cos θ uniform in [cos c, 1].
        let cos_theta = 1.0 - u_direction[1] * (1.0 - self.cos_cutoff);
        let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
        let (sin_phi, cos_phi) = math::sin_cos_turns(u_direction[0]);
        let local = Vec3::new(cos_phi * sin_theta, sin_phi * sin_theta, cos_theta);
        let energy = match self.texture {
            None => self.intensity * self.falloff(cos_theta),
            Some(_) => self.intensity * self.falloff(cos_theta) * self.texture_at(local),
        };
        EmissionSample {
            normal: Vec3::ZERO,
            energy,
            origin: self.position,
            direction: self.frame.to_world(local),
            emission_pdf: PdfW(self.cone_pdf()),
            direct_pdf: PdfA(1.0),
            cos_at_light: 1.0,
        }
    }
}

impl SpotLight {
    /// Bounds for the light tree ([`LightBounds`]) from the light's power (W): strength
    /// `power / ∫f dω` (the mean intensity over the falloff, the peak intensity without a
    /// texture), the axis with θ_o = beam width and θ_e = cutoff − beam width (+1e-3 rad), so
    /// that the importance is zero only beyond the cutoff, where the spot emits nothing.
    pub(super) fn bounds(&self, power: f32) -> LightBounds {
        let spread = self.falloff_solid_angle();
        let phi = if spread > 0.0 { power / spread } else { 0.0 };
        LightBounds {
            bounds: math::Aabb::new(self.position, self.position),
            phi,
            axis: self.axis(),
            cos_o: self.cos_beam_width,
            cos_e: (self.cutoff - self.beam_width + 1e-3).min(PI).cos(),
            two_sided: false,
        }
    }
}
