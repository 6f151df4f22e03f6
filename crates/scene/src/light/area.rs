//! Area lights: one-sided triangles, parallelograms (a rectangle's two triangles as one light),
//! spheres and discs emitting constant radiance, their points sampled uniformly by area (direct
//! and emission sampling share one area density).

use math::{Frame, PI, PdfA, PdfW, Vec3, warp};
use spectrum::Rgb;

use super::{DirectSample, EmissionSample, HitRadiance, check_point, check_rgb};
use crate::light_tree_bounds::LightBounds;
use crate::shape::Triangle;
use math::Aabb;

/// The surface of an area light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AreaShape {
    /// A triangle; its front is the side of [`Triangle::normal`].
    Triangle(Triangle),
    /// A sphere; its front is outside (inside when `flip_normals`).
    Sphere {
        /// Centre (scene units).
        center: Vec3,
        /// Radius (scene units, > 0).
        radius: f32,
        /// The normals (and the emission) point inward.
        flip_normals: bool,
    },
    /// The parallelogram `origin + a·edge_u + b·edge_v`, `a, b ∈ [0, 1]`: a mesh of two
    /// triangles that tile it (Mitsuba's `rectangle`), emitting as one light.
    Parallelogram {
        /// A corner (scene units).
        origin: Vec3,
        /// First edge from `origin` (scene units).
        edge_u: Vec3,
        /// Second edge from `origin` (scene units).
        edge_v: Vec3,
        /// Unit front normal (that of the two triangles).
        normal: Vec3,
    },
    /// The (possibly elliptic) disc `center + x·axis_u + y·axis_v`, `x² + y² ≤ 1`.
    Disc {
        /// Centre (scene units).
        center: Vec3,
        /// Image of the unit disc's x axis (scene units).
        axis_u: Vec3,
        /// Image of the unit disc's y axis (scene units).
        axis_v: Vec3,
        /// Unit front normal: `normalize(axis_u × axis_v)`, negated for flipped discs.
        normal: Vec3,
    },
}

/// A one-sided surface emitting constant radiance into the hemisphere of its normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AreaLight {
    /// The emitting surface.
    pub shape: AreaShape,
    /// Emitted radiance (W·m⁻²·sr⁻¹ per channel).
    pub radiance: Rgb,
    inv_area: f32,
}

impl AreaLight {
    /// An area light on `triangle` with constant `radiance`, emitting on the side of the
    /// triangle's normal.
    pub fn new(triangle: Triangle, radiance: Rgb) -> Self {
        Self { shape: AreaShape::Triangle(triangle), radiance, inv_area: 1.0 / triangle.area() }
    }

    /// An emitting sphere: outward normals (emission leaves the sphere), or inward ones when
    /// `flip_normals`. Fails for a radius that is not positive and finite, a non-finite centre
    /// or a radiance that is negative or not finite.
    pub fn sphere(center: Vec3, radius: f32, flip_normals: bool, radiance: Rgb) -> Result<Self, String> {
        check_point("sphere centre", center)?;
        if !(radius.is_finite() && radius > 0.0) {
            return Err(format!("sphere emitter: expected a positive finite radius, got {radius}"));
        }
        check_rgb("sphere emitter radiance", radiance)?;
        let area = 4.0 * PI * radius * radius;
        Ok(Self { shape: AreaShape::Sphere { center, radius, flip_normals }, radiance, inv_area: 1.0 / area })
    }

    /// An emitting disc `center + x·axis_u + y·axis_v` over the unit disc (an ellipse for
    /// unequal or non-orthogonal axes), with front normal `normalize(axis_u × axis_v)`, negated
    /// when `flip_normals`. Fails for degenerate axes (zero area) or non-finite input.
    pub fn disc(center: Vec3, axis_u: Vec3, axis_v: Vec3, flip_normals: bool, radiance: Rgb) -> Result<Self, String> {
        check_point("disc centre", center)?;
        check_point("disc axis_u", axis_u)?;
        check_point("disc axis_v", axis_v)?;
        check_rgb("disc emitter radiance", radiance)?;
        let cross = axis_u.cross(axis_v);
        let area = PI * cross.length();
        if !(area.is_finite() && area > 0.0) {
            return Err(format!("disc emitter: the axes {axis_u} and {axis_v} span no area"));
        }
        let normal = if flip_normals { -cross.normalize() } else { cross.normalize() };
        Ok(Self { shape: AreaShape::Disc { center, axis_u, axis_v, normal }, radiance, inv_area: 1.0 / area })
    }

    /// An emitting parallelogram `origin + a·edge_u + b·edge_v` (`a, b ∈ [0, 1]`) with unit
    /// front normal `normal` (± `normalize(edge_u × edge_v)`): see [`AreaLight::parallelogram_of`].
    /// Fails for degenerate edges (zero area), a normal that is not unit and perpendicular to the
    /// edges, or non-finite input.
    pub fn parallelogram(
        origin: Vec3,
        edge_u: Vec3,
        edge_v: Vec3,
        normal: Vec3,
        radiance: Rgb,
    ) -> Result<Self, String> {
        check_point("parallelogram origin", origin)?;
        check_point("parallelogram edge_u", edge_u)?;
        check_point("parallelogram edge_v", edge_v)?;
        check_rgb("parallelogram emitter radiance", radiance)?;
        let cross = edge_u.cross(edge_v);
        let area = cross.length();
        if !(area.is_finite() && area > 0.0) {
            return Err(format!("parallelogram emitter: the edges {edge_u} and {edge_v} span no area"));
        }
        if !((normal.length() - 1.0).abs() < 1e-4 && (cross / area).dot(normal).abs() > 1.0 - 1e-4) {
            return Err(format!("parallelogram emitter: {normal} is not the unit normal of its edges"));
        }
        Ok(Self { shape: AreaShape::Parallelogram { origin, edge_u, edge_v, normal }, radiance, inv_area: 1.0 / area })
    }

    /// The parallelogram that the two triangles `a` and `b` tile exactly (they share a
    /// diagonal and face the same way, and the other two corners complete it), as
    /// `(origin, edge_u, edge_v, normal)` with `a`'s normal; `None` otherwise. Corners may differ
    /// by a relative 10⁻⁵ of the edge lengths (a transformed rectangle's rounding).
    pub fn parallelogram_of(a: &Triangle, b: &Triangle) -> Option<(Vec3, Vec3, Vec3, Vec3)> {
        if a.normal.dot(b.normal) < 1.0 - 1e-5 {
            return None;
        }
        let (pa, pb) = (a.vertices(), b.vertices());
        let scale = pa.iter().chain(&pb).map(|p| (*p - pa[0]).length()).fold(0.0f32, f32::max);
        let tolerance = 1e-5 * scale;
        let same = |p: Vec3, q: Vec3| (p - q).length() <= tolerance;
        // The vertex of `a` that `b` lacks, and the one of `b` that `a` lacks.
        let lone_a: Vec<Vec3> = pa.iter().copied().filter(|p| !pb.iter().any(|q| same(*p, *q))).collect();
        let lone_b: Vec<Vec3> = pb.iter().copied().filter(|q| !pa.iter().any(|p| same(*p, *q))).collect();
        let ([corner], [opposite]) = (lone_a.as_slice(), lone_b.as_slice()) else { return None };
        let shared: Vec<Vec3> = pa.iter().copied().filter(|p| !same(*p, *corner)).collect();
        let [s0, s1] = shared.as_slice() else { return None };
        // A parallelogram: the diagonals bisect each other.
        if !same(*corner + *opposite, *s0 + *s1) {
            return None;
        }
        Some((*corner, *s0 - *corner, *s1 - *corner, a.normal))
    }

    /// Surface area (square scene units).
    pub fn area(&self) -> f32 {
        1.0 / self.inv_area
    }

    /// The triangle, for triangle emitters.
    pub fn triangle(&self) -> Option<&Triangle> {
        match &self.shape {
            AreaShape::Triangle(t) => Some(t),
            _ => None,
        }
    }

    /// A point uniformly distributed by area (density `1/area`) and the unit front normal there.
    fn sample_point(&self, u: [f32; 2]) -> (Vec3, Vec3) {
        match self.shape {
            AreaShape::Triangle(t) => {
                let b = warp::uniform_triangle(u);
                (t.point(b.x, b.y), t.normal)
            }
            AreaShape::Sphere { center, radius, flip_normals } => {
                let d = warp::uniform_sphere(u);
                (center + radius * d, if flip_normals { -d } else { d })
            }
            AreaShape::Parallelogram { origin, edge_u, edge_v, normal } => {
                (origin + u[0] * edge_u + u[1] * edge_v, normal)
            }
            AreaShape::Disc { center, axis_u, axis_v, normal } => {
                let q = warp::concentric_disc(u);
                (center + q.x * axis_u + q.y * axis_v, normal)
            }
        }
    }
}

impl AreaLight {
    /// Next-event estimation from `receiver`: a point uniform by area (see [`super::Light::sample_direct`]).
    pub(super) fn sample_direct(&self, receiver: Vec3, u: [f32; 2]) -> Option<DirectSample> {
        let (point, normal) = self.sample_point(u);
        let to_light = point - receiver;
        let distance_squared = to_light.length_squared();
        let distance = distance_squared.sqrt();
        let direction = to_light / distance;
        let cos_at_light = normal.dot(-direction);
        if cos_at_light < math::COSINE_EPSILON || !distance_squared.is_normal() {
            return None;
        }
        Some(DirectSample {
            radiance: self.radiance,
            direction,
            distance,
            direct_pdf: PdfA(self.inv_area).to_solid_angle(distance_squared, cos_at_light),
            emission_pdf: PdfW(self.inv_area * warp::cosine_hemisphere_pdf(cos_at_light)),
            cos_at_light,
        })
    }

    /// A light sub-path start: a point uniform by area, a cosine-distributed direction.
    pub(super) fn sample_emission(&self, u_position: [f32; 2], u_direction: [f32; 2]) -> EmissionSample {
        let (origin, normal) = self.sample_point(u_position);
        let local = warp::cosine_hemisphere(u_direction);
        let cos_at_light = local.z;
        EmissionSample {
            normal,
            energy: self.radiance * cos_at_light,
            origin,
            direction: Frame::from_z(normal).to_world(local),
            emission_pdf: PdfW(self.inv_area * warp::cosine_hemisphere_pdf(cos_at_light)),
            direct_pdf: PdfA(self.inv_area),
            cos_at_light,
        }
    }

    /// The radiance seen along `ray_direction` at a point with front normal `normal` (used by
    /// spheres only), `None` from behind.
    pub(super) fn radiance_on_hit(&self, ray_direction: Vec3, normal: Vec3) -> Option<HitRadiance> {
        let front = match self.shape {
            AreaShape::Triangle(t) => t.normal,
            AreaShape::Disc { normal, .. } | AreaShape::Parallelogram { normal, .. } => normal,
            AreaShape::Sphere { .. } => normal,
        };
        let cos_at_light = front.dot(-ray_direction);
        if cos_at_light <= 0.0 {
            return None;
        }
        Some(HitRadiance {
            radiance: self.radiance,
            direct_pdf: PdfA(self.inv_area),
            emission_pdf: PdfW(self.inv_area * warp::cosine_hemisphere_pdf(cos_at_light)),
            cos_at_light,
        })
    }
}

impl AreaLight {
    /// Bounds for the light tree ([`LightBounds`]) from the light's [`super::Light::power`]
    /// `power` (W): strength `power/π = L·A` (one-sided Lambertian emission), the normal as
    /// the cone axis for triangles, parallelograms and discs, every direction for spheres, and emission into
    /// the hemisphere (θ_e = π/2).
    pub(super) fn bounds(&self, power: f32) -> LightBounds {
        let phi = power / PI;
        match self.shape {
            AreaShape::Triangle(t) => {
                LightBounds { bounds: t.bounds(), phi, axis: t.normal, cos_o: 1.0, cos_e: 0.0, two_sided: false }
            }
            AreaShape::Sphere { center, radius, .. } => {
                LightBounds::omnidirectional(Aabb::new(center - Vec3::splat(radius), center + Vec3::splat(radius)), phi)
            }
            AreaShape::Parallelogram { origin, edge_u, edge_v, normal } => {
                let corners = [origin, origin + edge_u, origin + edge_v, origin + edge_u + edge_v];
                LightBounds {
                    bounds: corners.iter().fold(Aabb::EMPTY, |b, p| b.grow(*p)),
                    phi,
                    axis: normal,
                    cos_o: 1.0,
                    cos_e: 0.0,
                    two_sided: false,
                }
            }
            AreaShape::Disc { center, axis_u, axis_v, normal } => {
                let extent = Vec3::new(axis_u.x.hypot(axis_v.x), axis_u.y.hypot(axis_v.y), axis_u.z.hypot(axis_v.z));
                LightBounds {
                    bounds: Aabb::new(center - extent, center + extent),
                    phi,
                    axis: normal,
                    cos_o: 1.0,
                    cos_e: 0.0,
                    two_sided: false,
                }
            }
        }
    }
}
