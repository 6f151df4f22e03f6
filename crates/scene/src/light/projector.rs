//! The projector (Mitsuba 3's `projector`, pbrt-v4's `projection` light): a pinhole that
//! projects an image into the scene the way a perspective camera with the same frame and
//! field of view sees it.
//!
//! Geometry: the image plane lies at distance 1 along the local `z` axis. The local direction
//! `(x, y, z)`, `z > 0`, meets it at `(x/z, y/z)` and looks up the image at
//! `u = ½ − ½·(x/z)/t`, `v = ½ − ½·a·(y/z)/t` (`t = tan(fov_x/2)`, `a` = width/height), so the
//! plane spans `A = 4t²/a` square units and `dω = cos³θ · A · du dv`.
//!
//! Emission ([`ProjectorModel`]): Mitsuba 3's intensity `I(ω) = π·scale·E(u, v)/cos³θ` (W/sr),
//! which puts the irradiance `π·scale·E` on the image plane, flux `π·scale·A·∫E du dv`; or
//! pbrt-v4's `I(ω) = scale·E(u, v)`, flux `scale·A·∫E·cos³θ du dv`.
//!
//! Sampling: emission picks `(u, v)` from a piecewise-constant density `p(u, v)` over the
//! image that follows the flux per unit image area (the luminance of `E`, times cos³θ for
//! pbrt's model) ([`super::tabulated`]); the direction then has the solid-angle density
//! `p/(A·cos³θ)`. The position is a delta (area density 1, as for point lights).

use std::sync::Arc;

use math::{Distribution2D, Frame, PI, PdfA, PdfW, Vec2, Vec3};
use spectrum::Rgb;

use super::{DirectSample, EmissionSample, check_point, tabulated};
use crate::desc::ProjectorModel;
use crate::light_tree_bounds::LightBounds;
use crate::texture::Texture;

/// Largest tabulation grid of the sampling density (cells per axis).
const MAX_CELLS: u32 = 1024;
/// Grid for textures without an image resolution (checkerboards).
const DEFAULT_CELLS: u32 = 64;

/// A projector; see the module documentation.
#[derive(Clone, Debug, PartialEq)]
pub struct ProjectorLight {
    /// Position of the pinhole.
    pub position: Vec3,
    /// Local frame: `x` towards the image's left, `y` up, `z` the optical axis.
    frame: Frame,
    irradiance: Arc<Texture>,
    /// How the image becomes intensity.
    model: ProjectorModel,
    /// `π·scale` (Mitsuba's model) or `scale` (pbrt's).
    factor: f32,
    /// `tan(fov_x/2)`.
    tan_half_fov: f32,
    /// Width / height of the image.
    aspect: f32,
    /// Area of the image plane at distance 1 (square scene units).
    plane_area: f32,
    distribution: Arc<Distribution2D>,
    /// Luminance of the radiant flux (W).
    power: f32,
}

impl ProjectorLight {
    /// A projector at `position` with local axes `frame` (`[x, y, z]`, orthonormal within
    /// 1e-3), projecting `irradiance` times `scale` over a full horizontal field of view of
    /// `fov_x_degrees` ∈ (0°, 180°) and an image aspect (width/height) `aspect` > 0, in the
    /// given model (Mitsuba's [`ProjectorModel::Irradiance`] or pbrt's
    /// [`ProjectorModel::Intensity`]).
    pub fn new(
        model: ProjectorModel,
        position: Vec3,
        frame: [Vec3; 3],
        irradiance: Arc<Texture>,
        scale: f32,
        fov_x_degrees: f32,
        aspect: f32,
    ) -> Result<Self, String> {
        check_point("projector position", position)?;
        for (i, a) in frame.iter().enumerate() {
            for (j, b) in frame.iter().enumerate() {
                let error = (a.dot(*b) - if i == j { 1.0 } else { 0.0 }).abs();
                if error.is_nan() || error > 1e-3 {
                    return Err(format!("projector: the frame {frame:?} is not orthonormal"));
                }
            }
        }
        if !(fov_x_degrees > 0.0 && fov_x_degrees < 180.0) {
            return Err(format!("projector: expected a field of view in (0°, 180°), got {fov_x_degrees}°"));
        }
        if !(aspect.is_finite() && aspect > 0.0) {
            return Err(format!("projector: expected a positive aspect ratio, got {aspect}"));
        }
        if !(scale.is_finite() && scale >= 0.0) {
            return Err(format!("projector: expected a finite non-negative scale, got {scale}"));
        }
        let tan_half_fov = (0.5 * fov_x_degrees.to_radians()).tan();
        let plane_area = 4.0 * tan_half_fov * tan_half_fov / aspect;
        let (w, h) = irradiance
            .resolution()
            .map(|(w, h)| (w.min(MAX_CELLS), h.min(MAX_CELLS)))
            .unwrap_or(if irradiance.as_constant().is_some() { (1, 1) } else { (DEFAULT_CELLS, DEFAULT_CELLS) });
        // cos³θ of the direction through the image point (u, v).
        let cos3 = |uv: Vec2| {
            let x = (1.0 - 2.0 * uv.x) * tan_half_fov;
            let y = (1.0 - 2.0 * uv.y) * tan_half_fov / aspect;
            (1.0 + x * x + y * y).powf(-1.5)
        };
        let luminance = |uv: Vec2| match model {
            ProjectorModel::Irradiance => irradiance.eval(uv).luminance(),
            ProjectorModel::Intensity => irradiance.eval(uv).luminance() * cos3(uv),
        };
        let (distribution, mean) = match tabulated::tabulate(w as usize, h as usize, luminance) {
            Some(found) => found,
            // A black image: uniform sampling keeps the densities valid; nothing is emitted.
            None => (Distribution2D::new(&[1.0], 1, 1).ok_or("projector: no sampling distribution")?, 0.0),
        };
        let factor = match model {
            ProjectorModel::Irradiance => PI * scale,
            ProjectorModel::Intensity => scale,
        };
        Ok(Self {
            position,
            frame: Frame { x: frame[0], y: frame[1], z: frame[2] },
            irradiance,
            model,
            factor,
            tan_half_fov,
            aspect,
            plane_area,
            distribution: Arc::new(distribution),
            power: factor * plane_area * mean,
        })
    }

    /// Luminance of the radiant flux (W).
    pub(super) fn power_luminance(&self) -> f32 {
        self.power
    }

    /// Image coordinates of the unit local direction `local`, `None` behind the pinhole or
    /// outside the image.
    fn uv_of(&self, local: Vec3) -> Option<Vec2> {
        if local.z <= 0.0 {
            return None;
        }
        let k = 0.5 / (self.tan_half_fov * local.z);
        let uv = Vec2::new(0.5 - k * local.x, 0.5 - k * self.aspect * local.y);
        ((0.0..=1.0).contains(&uv.x) && (0.0..=1.0).contains(&uv.y)).then_some(uv)
    }

    /// Intensity (W/sr per channel) and emission density (per steradian) of the unit local
    /// direction `local`, `None` outside the image.
    fn emitted(&self, local: Vec3) -> Option<(Rgb, f32)> {
        let uv = self.uv_of(local)?;
        let cos3 = local.z * local.z * local.z;
        let intensity = match self.model {
            ProjectorModel::Irradiance => self.irradiance.eval(uv) * (self.factor / cos3),
            ProjectorModel::Intensity => self.irradiance.eval(uv) * self.factor,
        };
        let pdf = self.distribution.pdf(uv) / (self.plane_area * cos3);
        Some((intensity, pdf))
    }

    /// Next-event estimation from `receiver` (direct density 1 per unit area, as for point
    /// lights); `None` outside the projected image.
    pub(super) fn sample_direct(&self, receiver: Vec3) -> Option<DirectSample> {
        let to_light = self.position - receiver;
        let distance_squared = to_light.length_squared();
        let distance = distance_squared.sqrt();
        let direction = to_light / distance;
        let (intensity, pdf) = self.emitted(self.frame.to_local(-direction))?;
        if intensity.is_black() {
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

    /// A light sub-path start: `(u, v)` from the image's density, the direction through it.
    pub(super) fn sample_emission(&self, u_direction: [f32; 2]) -> EmissionSample {
        let (uv, _) = self.distribution.sample(u_direction);
        let on_plane = Vec3::new(
            (1.0 - 2.0 * uv.x) * self.tan_half_fov,
            (1.0 - 2.0 * uv.y) * self.tan_half_fov / self.aspect,
            1.0,
        );
        let local = on_plane.normalize();
        // Density and intensity evaluated from the direction, as sample_direct does.
        let (energy, pdf) = self.emitted(local).unwrap_or((Rgb::BLACK, 0.0));
        EmissionSample {
            normal: Vec3::ZERO,
            energy,
            origin: self.position,
            direction: self.frame.to_world(local),
            emission_pdf: PdfW(pdf),
            direct_pdf: PdfA(1.0),
            cos_at_light: 1.0,
        }
    }

    /// Solid-angle density with which `ProjectorLight::sample_emission` emits along the
    /// unit world direction `direction` (0 outside the image).
    pub fn emission_pdf(&self, direction: Vec3) -> f32 {
        self.emitted(self.frame.to_local(direction)).map_or(0.0, |(_, pdf)| pdf)
    }
}

impl ProjectorLight {
    /// Bounds for the light tree ([`LightBounds`]) from the light's power (W): strength
    /// `power / Ω` (the mean intensity over the image's solid angle
    /// `Ω = 4·atan(t_x·t_y/√(1 + t_x² + t_y²))`), the optical axis with θ_o the half-angle of
    /// the image's diagonal and θ_e = 1e-3 rad: zero importance only outside the image.
    pub(super) fn bounds(&self, power: f32) -> LightBounds {
        let (tx, ty) = (self.tan_half_fov, self.tan_half_fov / self.aspect);
        let diagonal = (1.0 + tx * tx + ty * ty).sqrt();
        let solid_angle = 4.0 * (tx * ty / diagonal).atan();
        let phi = if solid_angle > 0.0 { power / solid_angle } else { 0.0 };
        LightBounds {
            bounds: math::Aabb::new(self.position, self.position),
            phi,
            axis: self.frame.z,
            cos_o: 1.0 / diagonal,
            cos_e: 1e-3f32.cos(),
            two_sided: false,
        }
    }
}
