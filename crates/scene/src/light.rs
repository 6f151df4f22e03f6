//! Lights and the three queries every integrator asks of them (tech report §3 and §5.1).
//!
//! * [`Light::sample_direct`]: next-event estimation from a receiving point.
//! * [`Light::sample_emission`]: the start of a light sub-path.
//! * [`Light::radiance_on_hit`]: a camera ray that hits (or escapes to) the light.
//!
//! Conventions shared by all three:
//! * `direct_pdf` is the density of choosing the *point* on the light by direct sampling. For
//!   finite lights it is per unit area ([`PdfA`]); `sample_direct` reports it converted to solid
//!   angle at the receiver. Delta-position lights (point) have area density 1, so their solid
//!   angle density is `distance²`; the directional light has density 1 for its one direction.
//!   Infinite lights (directional, environment) store solid-angle densities in the area slot
//!   (tech report §5.1).
//! * `emission_pdf` is the density of emitting along the connecting ray from the light: area
//!   density of the origin × solid-angle density of the direction. Infinite lights emit from a
//!   disc of the scene's bounding sphere perpendicular to the direction, with area density
//!   `1/(πR²)`.
//! * `cos_at_light` is the cosine between the light's normal and the emitted direction (1 for
//!   lights without a surface).
//! * Light selection is not included: the caller multiplies by its pick probability.

use math::{Frame, PdfA, PdfW, Vec3, warp};
use spectrum::Rgb;

use crate::shape::Triangle;

/// The scene's bounding sphere, needed by infinite lights.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoundingSphere {
    /// Centre (scene units).
    pub center: Vec3,
    /// Radius (scene units).
    pub radius: f32,
}

/// A one-sided triangle emitting constant radiance into the hemisphere of its normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AreaLight {
    /// The emitting triangle; emission leaves on the side of its normal.
    pub triangle: Triangle,
    /// Emitted radiance.
    pub radiance: Rgb,
    frame: Frame,
    inv_area: f32,
}

impl AreaLight {
    /// An area light on `triangle` with constant `radiance`.
    pub fn new(triangle: Triangle, radiance: Rgb) -> Self {
        let frame = Frame::from_z(triangle.normal);
        Self { triangle, radiance, frame, inv_area: 1.0 / triangle.area() }
    }
}

/// An isotropic point light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointLight {
    /// Position.
    pub position: Vec3,
    /// Radiant intensity (per steradian).
    pub intensity: Rgb,
}

/// A directional light ("sun").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DirectionalLight {
    /// Unit direction in which the light travels.
    pub direction: Vec3,
    /// Irradiance on a surface perpendicular to `direction`.
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

/// A constant environment: the same radiance from every direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BackgroundLight {
    /// Radiance arriving from every direction.
    pub radiance: Rgb,
}

/// The kinds of light. Closed set: matched exhaustively.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Light {
    /// One-sided triangle emitter.
    Area(AreaLight),
    /// Point light.
    Point(PointLight),
    /// Directional light.
    Directional(DirectionalLight),
    /// Constant environment.
    Background(BackgroundLight),
}

/// Result of [`Light::sample_direct`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DirectSample {
    /// Radiance arriving at the receiver (irradiance for the directional light, intensity for
    /// the point light); the estimate is `radiance · f · cos / direct_pdf`.
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
    /// True for lights whose position (point) or direction (directional) is a delta
    /// distribution: they cannot be hit by rays.
    pub fn is_delta(&self) -> bool {
        matches!(self, Light::Point(_) | Light::Directional(_))
    }

    /// True for lights at finite distance (area, point).
    pub fn is_finite(&self) -> bool {
        matches!(self, Light::Area(_) | Light::Point(_))
    }

    /// Samples a point on the light as seen from `receiver` with two uniform numbers.
    /// Returns `None` when nothing is emitted towards the receiver.
    pub fn sample_direct(&self, receiver: Vec3, u: [f32; 2], sphere: &BoundingSphere) -> Option<DirectSample> {
        match self {
            Light::Area(light) => {
                let b = warp::uniform_triangle(u);
                let point = light.triangle.point(b.x, b.y);
                let to_light = point - receiver;
                let distance_squared = to_light.length_squared();
                let distance = distance_squared.sqrt();
                let direction = to_light / distance;
                let cos_at_light = light.frame.z.dot(-direction);
                if cos_at_light < math::COSINE_EPSILON {
                    return None;
                }
                Some(DirectSample {
                    radiance: light.radiance,
                    direction,
                    distance,
                    direct_pdf: PdfA(light.inv_area).to_solid_angle(distance_squared, cos_at_light),
                    emission_pdf: PdfW(light.inv_area * warp::cosine_hemisphere_pdf(cos_at_light)),
                    cos_at_light,
                })
            }
            Light::Point(light) => {
                let to_light = light.position - receiver;
                let distance_squared = to_light.length_squared();
                let distance = distance_squared.sqrt();
                Some(DirectSample {
                    radiance: light.intensity,
                    direction: to_light / distance,
                    distance,
                    direct_pdf: PdfA(1.0).to_solid_angle(distance_squared, 1.0),
                    emission_pdf: PdfW(warp::UNIFORM_SPHERE_PDF),
                    cos_at_light: 1.0,
                })
            }
            Light::Directional(light) => Some(DirectSample {
                radiance: light.irradiance,
                direction: -light.direction,
                distance: f32::INFINITY,
                direct_pdf: PdfW(1.0),
                emission_pdf: PdfW(disc_pdf(sphere)),
                cos_at_light: 1.0,
            }),
            Light::Background(light) => {
                let direction = warp::uniform_sphere(u);
                Some(DirectSample {
                    radiance: light.radiance,
                    direction,
                    distance: f32::INFINITY,
                    direct_pdf: PdfW(warp::UNIFORM_SPHERE_PDF),
                    emission_pdf: PdfW(warp::UNIFORM_SPHERE_PDF * disc_pdf(sphere)),
                    cos_at_light: 1.0,
                })
            }
        }
    }

    /// Samples the start of a light sub-path: `u_position` for the point, `u_direction` for
    /// the direction.
    pub fn sample_emission(
        &self,
        u_position: [f32; 2],
        u_direction: [f32; 2],
        sphere: &BoundingSphere,
    ) -> EmissionSample {
        match self {
            Light::Area(light) => {
                let b = warp::uniform_triangle(u_position);
                let origin = light.triangle.point(b.x, b.y);
                let local = warp::cosine_hemisphere(u_direction);
                let cos_at_light = local.z;
                EmissionSample {
                    energy: light.radiance * cos_at_light,
                    origin,
                    direction: light.frame.to_world(local),
                    emission_pdf: PdfW(light.inv_area * warp::cosine_hemisphere_pdf(cos_at_light)),
                    direct_pdf: PdfA(light.inv_area),
                    cos_at_light,
                }
            }
            Light::Point(light) => EmissionSample {
                energy: light.intensity,
                origin: light.position,
                direction: warp::uniform_sphere(u_direction),
                emission_pdf: PdfW(warp::UNIFORM_SPHERE_PDF),
                direct_pdf: PdfA(1.0),
                cos_at_light: 1.0,
            },
            Light::Directional(light) => EmissionSample {
                energy: light.irradiance,
                origin: disc_origin(&light.frame, u_position, sphere),
                direction: light.direction,
                emission_pdf: PdfW(disc_pdf(sphere)),
                direct_pdf: PdfA(1.0),
                cos_at_light: 1.0,
            },
            Light::Background(light) => {
                let direction = warp::uniform_sphere(u_direction);
                EmissionSample {
                    energy: light.radiance,
                    origin: disc_origin(&Frame::from_z(direction), u_position, sphere),
                    direction,
                    emission_pdf: PdfW(warp::UNIFORM_SPHERE_PDF * disc_pdf(sphere)),
                    direct_pdf: PdfA(warp::UNIFORM_SPHERE_PDF),
                    cos_at_light: 1.0,
                }
            }
        }
    }

    /// Radiance along a ray with unit direction `ray_direction` that hits the light (area
    /// lights; the radiance is constant over the surface) or escapes the scene (infinite
    /// lights). `None` for delta lights, which cannot be hit, and for the back of area lights.
    pub fn radiance_on_hit(&self, ray_direction: Vec3, sphere: &BoundingSphere) -> Option<HitRadiance> {
        match self {
            Light::Area(light) => {
                let cos_at_light = light.frame.z.dot(-ray_direction);
                if cos_at_light <= 0.0 {
                    return None;
                }
                Some(HitRadiance {
                    radiance: light.radiance,
                    direct_pdf: PdfA(light.inv_area),
                    emission_pdf: PdfW(light.inv_area * warp::cosine_hemisphere_pdf(cos_at_light)),
                    cos_at_light,
                })
            }
            Light::Point(_) | Light::Directional(_) => None,
            Light::Background(light) => Some(HitRadiance {
                radiance: light.radiance,
                direct_pdf: PdfA(warp::UNIFORM_SPHERE_PDF),
                emission_pdf: PdfW(warp::UNIFORM_SPHERE_PDF * disc_pdf(sphere)),
                cos_at_light: 1.0,
            }),
        }
    }
}

/// Area density `1/(πR²)` of an origin on the bounding-sphere disc.
fn disc_pdf(sphere: &BoundingSphere) -> f32 {
    warp::CONCENTRIC_DISC_PDF / (sphere.radius * sphere.radius)
}

/// A point on the disc of radius R centred at `center − R·z`, perpendicular to `frame.z`.
fn disc_origin(frame: &Frame, u: [f32; 2], sphere: &BoundingSphere) -> Vec3 {
    let d = warp::concentric_disc(u);
    sphere.center + sphere.radius * (-frame.z + frame.x * d.x + frame.y * d.y)
}
