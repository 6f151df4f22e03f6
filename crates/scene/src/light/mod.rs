//! Lights and the three queries every integrator asks of them (tech report §3 and §5.1).
//!
//! * [`Light::sample_direct`]: next-event estimation from a receiving point.
//! * [`Light::sample_emission`]: the start of a light sub-path.
//! * [`Light::radiance_on_hit`]: a camera ray that hits (or escapes to) the light.
//!
//! Conventions shared by all three:
//! * `direct_pdf` is the density of choosing the *point* on the light by direct sampling. For
//!   finite lights it is per unit area ([`PdfA`]); `sample_direct` reports it converted to solid
//!   angle at the receiver. Delta-position lights (point, spot, projector) have area density 1, so their
//!   solid angle density is `distance²`; the directional light has density 1 for its one
//!   direction. Infinite lights (directional, constant and image environments) store solid-angle
//!   densities in the area slot (tech report §5.1).
//! * `emission_pdf` is the density of emitting along the connecting ray from the light: area
//!   density of the origin × solid-angle density of the direction. Infinite lights emit from a
//!   disc of the scene's bounding sphere perpendicular to the direction, with area density
//!   `1/(πR²)`.
//! * `cos_at_light` is the cosine between the light's normal and the emitted direction (1 for
//!   lights without a surface).
//! * Light selection is not included: the caller multiplies by its pick probability; for
//!   power-proportional selection [`Light::power`] gives each light's emitted flux.
//!
//! Area lights are one-sided (the front is the side their geometric normal points to). Those
//! with constant radiance ([`AreaLight`]) are sampled uniformly by area on every shape (sphere
//! included); textured triangles ([`TexturedTriangleLight`]) in proportion to their texture.
//! Either way direct and emission sampling share one area density.

mod area;
mod background;
mod directional;
mod envmap;
pub mod equal_area;
mod goniometric;
mod point;
mod projector;
mod spot;
mod tabulated;
mod textured_triangle;

use math::{Frame, PI, PdfA, PdfW, Vec3, warp};
use spectrum::Rgb;

use crate::desc::LightDesc;
use crate::light_tree_bounds::LightBounds;

pub use area::{AreaLight, AreaShape};
pub use background::BackgroundLight;
pub use directional::DirectionalLight;
pub use envmap::EnvMapLight;
pub use goniometric::GoniometricLight;
pub use point::PointLight;
pub use projector::ProjectorLight;
pub use spot::SpotLight;
pub use textured_triangle::TexturedTriangleLight;

/// The scene's bounding sphere, needed by infinite lights.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoundingSphere {
    /// Centre (scene units).
    pub center: Vec3,
    /// Radius (scene units).
    pub radius: f32,
}

/// The kinds of light. Closed set: matched exhaustively.
#[derive(Clone, Debug, PartialEq)]
pub enum Light {
    /// One-sided surface emitter (triangle, sphere, disc).
    Area(AreaLight),
    /// One-sided triangle emitting a radiance texture.
    TexturedTriangle(TexturedTriangleLight),
    /// Point light.
    Point(PointLight),
    /// Spot light.
    Spot(SpotLight),
    /// Projector: a point projecting an image.
    Projector(ProjectorLight),
    /// Goniometric light: a point with an intensity image over the sphere.
    Goniometric(GoniometricLight),
    /// Directional light.
    Directional(DirectionalLight),
    /// Constant environment.
    Background(BackgroundLight),
    /// Image-based environment.
    EnvMap(EnvMapLight),
}

/// Result of [`Light::sample_direct`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DirectSample {
    /// Radiance arriving at the receiver (irradiance for the directional light, intensity for
    /// the point and spot lights); the estimate is `radiance · f · cos / direct_pdf`.
    pub radiance: Rgb,
    /// Unit direction from the receiver towards the light.
    pub direction: Vec3,
    /// Distance to the light point; `f32::INFINITY` for infinite lights.
    pub distance: f32,
    /// Density of this sample per unit solid angle at the receiver.
    pub direct_pdf: PdfW,
    /// Density with which the light would emit this ray (area × solid angle), see the module.
    pub emission_pdf: PdfW,
    /// Cosine at the light (1 without a surface).
    pub cos_at_light: f32,
}

/// Result of [`Light::sample_emission`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmissionSample {
    /// Emitted radiance times `cos_at_light` (before division by `emission_pdf`).
    pub energy: Rgb,
    /// Start of the light sub-path.
    pub origin: Vec3,
    /// Unit direction of travel.
    pub direction: Vec3,
    /// Density of `(origin, direction)`: area density × solid-angle density.
    pub emission_pdf: PdfW,
    /// Density of choosing `origin` by direct sampling (area; solid angle for infinite lights).
    pub direct_pdf: PdfA,
    /// Cosine at the light (1 without a surface).
    pub cos_at_light: f32,
    /// Unit front normal at `origin` for lights on a surface (area and textured-triangle
    /// lights; for spheres oriented like the emitting side), zero for the others.
    pub normal: Vec3,
}

/// Result of [`Light::radiance_on_hit`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HitRadiance {
    /// Radiance arriving along the ray.
    pub radiance: Rgb,
    /// Density of choosing the hit point by direct sampling (area; solid angle for infinite
    /// lights).
    pub direct_pdf: PdfA,
    /// Density with which the light would emit the reversed ray.
    pub emission_pdf: PdfW,
    /// Cosine at the light (1 without a surface).
    pub cos_at_light: f32,
}

impl Light {
    /// Builds a light that is not attached to a shape from its description (`Constant` becomes
    /// [`Light::Background`]). Returns a message naming the first invalid parameter.
    pub fn from_desc(desc: &LightDesc) -> Result<Light, String> {
        match desc {
            LightDesc::Point { position, intensity } => {
                check_point("point light position", *position)?;
                check_rgb("point light intensity", *intensity)?;
                Ok(Light::Point(PointLight { position: *position, intensity: *intensity }))
            }
            LightDesc::Spot { position, direction, intensity, cutoff_degrees, beam_width_degrees, texture } => {
                let spot = SpotLight::new(*position, *direction, *intensity, *cutoff_degrees, *beam_width_degrees)?;
                Ok(Light::Spot(match texture {
                    None => spot,
                    Some(t) => spot.with_texture(t.texture.clone(), t.x_axis, t.y_axis)?,
                }))
            }
            LightDesc::Projector { model, position, frame, irradiance, scale, fov_x_degrees, aspect } => {
                Ok(Light::Projector(ProjectorLight::new(
                    *model,
                    *position,
                    *frame,
                    irradiance.clone(),
                    *scale,
                    *fov_x_degrees,
                    *aspect,
                )?))
            }
            LightDesc::Goniometric { position, frame, image, intensity } => {
                Ok(Light::Goniometric(GoniometricLight::new(*position, *frame, image, *intensity)?))
            }
            LightDesc::Directional { direction, irradiance } => {
                let direction = check_direction("directional light direction", *direction)?;
                check_rgb("directional light irradiance", *irradiance)?;
                Ok(Light::Directional(DirectionalLight::new(direction, *irradiance)))
            }
            LightDesc::Constant { radiance } => {
                check_rgb("constant environment radiance", *radiance)?;
                Ok(Light::Background(BackgroundLight { radiance: *radiance }))
            }
            LightDesc::EnvMap { image, scale, to_world } => {
                Ok(Light::EnvMap(EnvMapLight::new(image, *scale, *to_world)?))
            }
        }
    }

    /// True for lights whose position (point, spot) or direction (directional) is a delta
    /// distribution: they cannot be hit by rays.
    pub fn is_delta(&self) -> bool {
        matches!(
            self,
            Light::Point(_) | Light::Spot(_) | Light::Projector(_) | Light::Goniometric(_) | Light::Directional(_)
        )
    }

    /// True for lights at finite distance (area, point, spot, projector).
    pub fn is_finite(&self) -> bool {
        matches!(
            self,
            Light::Area(_)
                | Light::TexturedTriangle(_)
                | Light::Point(_)
                | Light::Spot(_)
                | Light::Projector(_)
                | Light::Goniometric(_)
        )
    }

    /// True for the environment lights (constant and image), which rays leaving the scene see.
    pub fn is_environment(&self) -> bool {
        matches!(self, Light::Background(_) | Light::EnvMap(_))
    }

    /// Luminance ([`Rgb::luminance`]) of the flux the light emits (watts), for
    /// power-proportional light selection:
    /// * area: `π·A·L`; point: `4π·I`; spot: `I·∫f dω` with the exact integral of the falloff,
    ///   `2π·I·(1 − (sin c − sin b)/(c − b))`;
    /// * goniometric: `4π·I·mean(m)` (exact: the map preserves area);
    /// * textured triangle, textured spot, projector: the same integrals evaluated numerically
    ///   over the texture (see each light); they only steer light selection, which stays
    ///   unbiased for any positive power;
    /// * directional: `π·R²·E`, the flux through the bounding-sphere disc;
    /// * constant and image environments: `π·R²·∫L(ω) dω` — the radiance from each direction ω
    ///   crosses the bounding-sphere disc perpendicular to ω (area πR²); for a constant
    ///   environment this is `4π²R²·L`, what [`Light::sample_emission`] emits on average.
    pub fn power(&self, sphere: &BoundingSphere) -> f32 {
        let disc_area = PI * sphere.radius * sphere.radius;
        match self {
            Light::Area(light) => PI * light.area() * light.radiance.luminance(),
            Light::Point(light) => 4.0 * PI * light.intensity.luminance(),
            Light::TexturedTriangle(light) => light.power_luminance(),
            Light::Spot(light) => light.power_luminance(),
            Light::Projector(light) => light.power_luminance(),
            Light::Goniometric(light) => light.power_luminance(),
            Light::Directional(light) => disc_area * light.irradiance.luminance(),
            Light::Background(light) => disc_area * 4.0 * PI * light.radiance.luminance(),
            Light::EnvMap(light) => disc_area * light.luminance_integral(),
        }
    }

    /// Bounds of a finite light for the light tree ([`crate::light_tree`]), with the strength
    /// derived from [`Light::power`] (see each light's `bounds`); `None` for infinite lights
    /// and for lights whose power is zero or not finite (never picked).
    pub fn bounds(&self, sphere: &BoundingSphere) -> Option<LightBounds> {
        let power = self.power(sphere);
        if !(power.is_finite() && power > 0.0) {
            return None;
        }
        let bounds = match self {
            Light::Area(light) => light.bounds(power),
            Light::TexturedTriangle(light) => light.bounds(power),
            Light::Point(light) => light.bounds(power),
            Light::Spot(light) => light.bounds(power),
            Light::Projector(light) => light.bounds(power),
            Light::Goniometric(light) => light.bounds(power),
            Light::Directional(_) | Light::Background(_) | Light::EnvMap(_) => return None,
        };
        (bounds.phi.is_finite() && bounds.phi > 0.0).then_some(bounds)
    }

    /// A prefetch hint for [`Light::sample_direct`] with the same `u`, for a caller that knows
    /// `u` some work before it samples: the environment map's tables and texels that the sample
    /// will read (they are megabytes and read at random, so they miss the cache); a no-op for
    /// the other lights. No value changes.
    #[inline]
    pub fn prefetch_direct(&self, u: [f32; 2]) {
        if let Light::EnvMap(light) = self {
            light.prefetch_sample(u, envmap::Density::Full);
        }
    }

    /// [`Light::prefetch_direct`] for [`Light::sample_direct_compensated`].
    #[inline]
    pub fn prefetch_direct_compensated(&self, u: [f32; 2]) {
        if let Light::EnvMap(light) = self {
            light.prefetch_sample(u, envmap::Density::Compensated);
        }
    }

    /// A prefetch hint for [`Light::sample_emission`] with the same `u_direction`, for a caller
    /// that knows it some work before it samples (the light pass, one light sub-path ahead): for
    /// an environment map the tables and texels its direction sample reads, as
    /// [`Light::prefetch_direct`]; a no-op for the other lights. No value changes.
    #[inline]
    pub fn prefetch_emission(&self, u_direction: [f32; 2]) {
        if let Light::EnvMap(light) = self {
            light.prefetch_sample(u_direction, envmap::Density::Full);
        }
    }

    /// Whether [`Light::prefetch_direct`] and [`Light::prefetch_emission`] do anything for this
    /// light (an environment map), so that callers can skip preparing its numbers for the other
    /// lights.
    pub fn has_prefetch(&self) -> bool {
        matches!(self, Light::EnvMap(_))
    }

    /// Samples a point on the light as seen from `receiver` with two uniform numbers.
    /// Returns `None` when nothing is emitted towards the receiver.
    pub fn sample_direct(&self, receiver: Vec3, u: [f32; 2], sphere: &BoundingSphere) -> Option<DirectSample> {
        match self {
            Light::Area(light) => light.sample_direct(receiver, u),
            Light::Point(light) => light.sample_direct(receiver),
            Light::TexturedTriangle(light) => light.sample_direct(receiver, u),
            Light::Spot(light) => light.sample_direct(receiver),
            Light::Projector(light) => light.sample_direct(receiver),
            Light::Goniometric(light) => light.sample_direct(receiver),
            Light::Directional(light) => light.sample_direct(sphere),
            Light::Background(light) => light.sample_direct(u, sphere),
            Light::EnvMap(light) => light.sample_direct(u, sphere),
        }
    }

    /// [`Light::sample_direct`] for an estimator that combines next-event estimation with BSDF
    /// sampling by MIS (the path tracer): an image environment samples its *compensated*
    /// density (`EnvMapLight`'s documentation), which leaves the directions dimmer than its mean
    /// to BSDF sampling; every other light samples as [`Light::sample_direct`]. `direct_pdf` is
    /// the density sampled, so such an estimator must weigh the light's hits by
    /// [`Light::radiance_on_hit_compensated`], whose `direct_pdf` is the same density: where it
    /// is 0, BSDF sampling gets the whole weight, and nothing is lost as long as BSDF sampling
    /// can reach every direction the BSDF scatters into (all non-delta BSDFs here). The
    /// `emission_pdf` stays that of [`Light::sample_emission`].
    pub fn sample_direct_compensated(
        &self,
        receiver: Vec3,
        u: [f32; 2],
        sphere: &BoundingSphere,
    ) -> Option<DirectSample> {
        match self {
            Light::EnvMap(light) => light.sample_direct_compensated(u, sphere),
            _ => self.sample_direct(receiver, u, sphere),
        }
    }

    /// [`Light::radiance_on_hit`] with the `direct_pdf` of [`Light::sample_direct_compensated`]
    /// (different only for an image environment).
    pub fn radiance_on_hit_compensated(
        &self,
        ray_direction: Vec3,
        position: Vec3,
        normal: Vec3,
        sphere: &BoundingSphere,
    ) -> Option<HitRadiance> {
        match self {
            Light::EnvMap(light) => light.radiance_on_hit_compensated(ray_direction, sphere),
            _ => self.radiance_on_hit(ray_direction, position, normal, sphere),
        }
    }

    /// Samples the start of a light sub-path: `u_position` for the point, `u_direction` for
    /// the direction. A sample with zero `emission_pdf` or black `energy` carries nothing.
    pub fn sample_emission(
        &self,
        u_position: [f32; 2],
        u_direction: [f32; 2],
        sphere: &BoundingSphere,
    ) -> EmissionSample {
        match self {
            Light::Area(light) => light.sample_emission(u_position, u_direction),
            Light::Point(light) => light.sample_emission(u_direction),
            Light::TexturedTriangle(light) => light.sample_emission(u_position, u_direction),
            Light::Spot(light) => light.sample_emission(u_direction),
            Light::Projector(light) => light.sample_emission(u_direction),
            Light::Goniometric(light) => light.sample_emission(u_direction),
            Light::Directional(light) => light.sample_emission(u_position, sphere),
            Light::Background(light) => light.sample_emission(u_position, u_direction, sphere),
            Light::EnvMap(light) => light.sample_emission(u_position, u_direction, sphere, envmap::Density::Full),
        }
    }

    /// [`Light::sample_emission`] for an estimator whose next-event estimation samples
    /// [`Light::sample_direct_compensated`] (MIS compensation in the VCM engine): the same
    /// sample, whose `direct_pdf` is the compensated density's for an image environment (the
    /// density with which next-event estimation would have found the direction towards the
    /// light; 0 where the map is dimmer than its mean). Every other light samples as
    /// [`Light::sample_emission`].
    pub fn sample_emission_compensated(
        &self,
        u_position: [f32; 2],
        u_direction: [f32; 2],
        sphere: &BoundingSphere,
    ) -> EmissionSample {
        match self {
            Light::EnvMap(light) => {
                light.sample_emission(u_position, u_direction, sphere, envmap::Density::Compensated)
            }
            _ => self.sample_emission(u_position, u_direction, sphere),
        }
    }

    /// Radiance along a ray with unit direction `ray_direction` that hits the light (area
    /// lights) or escapes the scene (environment lights). `position` is the hit point (used by
    /// textured emitters; infinite lights ignore it) and `normal` the unit geometric normal
    /// there, oriented like the emitter's front (for spheres with flipped normals, inward);
    /// triangles and discs use their own (constant) normal, spheres this one, and infinite
    /// lights ignore it. `None` for delta lights, which cannot be hit, and for the back of
    /// area lights.
    pub fn radiance_on_hit(
        &self,
        ray_direction: Vec3,
        position: Vec3,
        normal: Vec3,
        sphere: &BoundingSphere,
    ) -> Option<HitRadiance> {
        match self {
            Light::Area(light) => light.radiance_on_hit(ray_direction, normal),
            Light::TexturedTriangle(light) => light.radiance_on_hit(ray_direction, position),
            Light::Point(_) | Light::Spot(_) | Light::Projector(_) | Light::Goniometric(_) | Light::Directional(_) => {
                None
            }
            Light::Background(light) => light.radiance_on_hit(sphere),
            Light::EnvMap(light) => light.radiance_on_hit(ray_direction, sphere),
        }
    }
}

/// Area density `1/(πR²)` of an origin on the bounding-sphere disc.
pub(super) fn disc_pdf(sphere: &BoundingSphere) -> f32 {
    warp::CONCENTRIC_DISC_PDF / (sphere.radius * sphere.radius)
}

/// A point on the disc of radius R centred at `center − R·z`, perpendicular to `frame.z`.
pub(super) fn disc_origin(frame: &Frame, u: [f32; 2], sphere: &BoundingSphere) -> Vec3 {
    let d = warp::concentric_disc(u);
    sphere.center + sphere.radius * (-frame.z + frame.x * d.x + frame.y * d.y)
}

/// Error unless every coordinate of `p` is finite.
pub(super) fn check_point(what: &str, p: Vec3) -> Result<(), String> {
    if p.is_finite() { Ok(()) } else { Err(format!("{what}: expected finite coordinates, got {p}")) }
}

/// The normalised direction, or an error for a zero or non-finite vector.
pub(super) fn check_direction(what: &str, d: Vec3) -> Result<Vec3, String> {
    let n = d.normalize_or_zero();
    if d.is_finite() && n != Vec3::ZERO {
        Ok(n)
    } else {
        Err(format!("{what}: expected a non-zero finite vector, got {d}"))
    }
}

/// Error unless every channel is finite and non-negative.
pub(super) fn check_rgb(what: &str, c: Rgb) -> Result<(), String> {
    if c.is_finite() && c.r >= 0.0 && c.g >= 0.0 && c.b >= 0.0 {
        Ok(())
    } else {
        Err(format!("{what}: expected finite non-negative values, got ({}, {}, {})", c.r, c.g, c.b))
    }
}
