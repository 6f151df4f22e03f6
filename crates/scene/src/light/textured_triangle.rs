//! A one-sided triangle emitting a textured radiance (Mitsuba 3's `area` emitter with a
//! `radiance` texture, pbrt-v4's `diffuse` area light with `filename`), its points sampled in
//! proportion to the texture.
//!
//! Sampling: a point of the unit square is drawn from a piecewise-constant density `p(s)` that
//! follows the luminance of the radiance ([`super::tabulated`]) and mapped to the triangle by
//! [`warp::uniform_triangle`], whose Jacobian is constant (`area`). The point's density is
//! therefore `p(s)/area` per unit area, for direct and emission sampling alike; emission adds a
//! cosine-distributed direction, so the emission pdf is `p(s)/area · cos/π` (area × solid
//! angle). A hit point is mapped back by its barycentrics and [`warp::uniform_triangle_inverse`].
//!
//! Masked emitters (an emitting shape with an alpha mask, [`TexturedTriangleLight::masked`]):
//! a masked-out point neither emits nor blocks. A ray sees a point of opacity α with
//! probability α (the stochastic alpha test of [`crate::alpha`]), so the radiance it sees there
//! is the texture's `L` with probability α: `α·L` in expectation. The sampled density follows
//! the luminance of `α·L`, and sampled points (next-event estimation, light sub-paths) carry
//! `α·L`; a hit carries `L` (the test has already kept it with probability α). Both report the
//! same area density, so MIS weights stay consistent, and a point of opacity 0 is never
//! produced with a non-zero weight. The power is `π·∫α·L dA`.

use std::sync::Arc;

use math::{Distribution2D, Frame, PI, PdfA, PdfW, Vec2, Vec3, warp};
use spectrum::Rgb;

use super::{DirectSample, EmissionSample, HitRadiance, tabulated};
use crate::alpha::AlphaMask;
use crate::light_tree_bounds::LightBounds;
use crate::shape::Triangle;
use crate::texture::Texture;

/// Largest tabulation grid per triangle (cells per axis).
const MAX_CELLS: f32 = 32.0;
/// Cells per axis for textures without an image resolution (checkerboards).
const DEFAULT_CELLS: usize = 16;

/// A triangle whose emitted radiance (W·m⁻²·sr⁻¹ per channel) is a texture over its uv.
#[derive(Clone, Debug, PartialEq)]
pub struct TexturedTriangleLight {
    /// The emitting triangle; its front is the side of [`Triangle::normal`].
    pub triangle: Triangle,
    /// Texture coordinates at the three vertices.
    pub uvs: [Vec2; 3],
    texture: Arc<Texture>,
    /// The opacity mask, for masked emitters.
    mask: Option<Arc<AlphaMask>>,
    inv_area: f32,
    distribution: Arc<Distribution2D>,
    /// Luminance of the emitted flux `π·∫L dA` (W).
    power: f32,
}

impl TexturedTriangleLight {
    /// The emitter on `triangle` (vertex uvs `uvs`) with radiance `texture`. `None` when the
    /// texture is black (or not finite) everywhere it is tabulated: the triangle emits nothing.
    pub fn new(triangle: Triangle, uvs: [Vec2; 3], texture: Arc<Texture>) -> Option<Self> {
        Self::build(triangle, uvs, texture, None)
    }

    /// A masked emitter: the triangle emits `texture` where the opacity `mask` (read at the
    /// same uvs) is on, `α·L` in expectation (module docs), and its points are sampled in
    /// proportion to the luminance of `α·L`. `None` when `α·L` is black (or not finite)
    /// everywhere it is tabulated.
    pub fn masked(triangle: Triangle, uvs: [Vec2; 3], texture: Arc<Texture>, mask: Arc<AlphaMask>) -> Option<Self> {
        Self::build(triangle, uvs, texture, Some(mask))
    }

    fn build(triangle: Triangle, uvs: [Vec2; 3], texture: Arc<Texture>, mask: Option<Arc<AlphaMask>>) -> Option<Self> {
        let area = triangle.area();
        let cells_of = |texture: &Texture| match texture.resolution() {
            Some((w, h)) => {
                // About one cell per texel covered, up to MAX_CELLS per axis.
                let uv_area = 0.5 * (uvs[1] - uvs[0]).perp_dot(uvs[2] - uvs[0]).abs();
                let texels = uv_area * w as f32 * h as f32;
                texels.sqrt().ceil().clamp(1.0, MAX_CELLS) as usize
            }
            None if texture.as_constant().is_some() => 1,
            None => DEFAULT_CELLS,
        };
        let cells = cells_of(&texture).max(mask.as_ref().map_or(1, |m| cells_of(&m.texture)));
        let opacity = |uv: Vec2| mask.as_ref().map_or(1.0, |m| m.opacity(uv));
        let radiance_at_square = |s: Vec2| {
            let uv = uv_at(&uvs, warp::uniform_triangle([s.x, s.y]));
            texture.eval(uv).luminance() * opacity(uv)
        };
        let (distribution, mean) = tabulated::tabulate(cells, cells, radiance_at_square)?;
        Some(Self {
            triangle,
            uvs,
            inv_area: 1.0 / area,
            distribution: Arc::new(distribution),
            power: PI * area * mean,
            texture,
            mask,
        })
    }

    /// Luminance of the emitted flux `π·∫L dA` (W), from the tabulated mean radiance.
    pub(super) fn power_luminance(&self) -> f32 {
        self.power
    }

    /// Surface area (square scene units).
    pub fn area(&self) -> f32 {
        1.0 / self.inv_area
    }

    /// Radiance (the texture's, without the mask) and area density at the point with
    /// barycentrics `b` (`b.x = b1`, `b.y = b2`).
    fn at(&self, b: Vec2) -> (Rgb, f32) {
        let s = warp::uniform_triangle_inverse(b).map(|v| v.clamp(0.0, 1.0));
        let radiance = self.texture.eval(uv_at(&self.uvs, b));
        (radiance, self.distribution.pdf(Vec2::new(s[0], s[1])) * self.inv_area)
    }

    /// A point, its expected radiance (`α·L`, module docs) and its area density.
    fn sample_point(&self, u: [f32; 2]) -> (Vec3, Rgb, f32) {
        let (s, _) = self.distribution.sample(u);
        let b = warp::uniform_triangle([s.x, s.y]);
        let (radiance, pdf) = self.at(b);
        let opacity = self.mask.as_ref().map_or(1.0, |m| m.opacity(uv_at(&self.uvs, b)));
        (self.triangle.point(b.x, b.y), radiance * opacity, pdf)
    }

    /// Area density (per square scene unit) with which the point `position` of the triangle
    /// is sampled, by direct and emission sampling alike.
    pub fn area_pdf(&self, position: Vec3) -> f32 {
        let (b1, b2) = self.triangle.barycentrics(position);
        self.at(Vec2::new(b1, b2)).1
    }

    /// Next-event estimation from `receiver`.
    pub(super) fn sample_direct(&self, receiver: Vec3, u: [f32; 2]) -> Option<DirectSample> {
        let (point, radiance, pdf) = self.sample_point(u);
        let to_light = point - receiver;
        let distance_squared = to_light.length_squared();
        let distance = distance_squared.sqrt();
        let direction = to_light / distance;
        let cos_at_light = self.triangle.normal.dot(-direction);
        if cos_at_light < math::COSINE_EPSILON || !distance_squared.is_normal() || radiance.is_black() {
            return None;
        }
        Some(DirectSample {
            radiance,
            direction,
            distance,
            direct_pdf: PdfA(pdf).to_solid_angle(distance_squared, cos_at_light),
            emission_pdf: PdfW(pdf * warp::cosine_hemisphere_pdf(cos_at_light)),
            cos_at_light,
        })
    }

    /// A light sub-path start: a point from the texture's density, a cosine-distributed
    /// direction.
    pub(super) fn sample_emission(&self, u_position: [f32; 2], u_direction: [f32; 2]) -> EmissionSample {
        let (origin, radiance, pdf) = self.sample_point(u_position);
        let local = warp::cosine_hemisphere(u_direction);
        let cos_at_light = local.z;
        EmissionSample {
            normal: self.triangle.normal,
            energy: radiance * cos_at_light,
            origin,
            direction: Frame::from_z(self.triangle.normal).to_world(local),
            emission_pdf: PdfW(pdf * warp::cosine_hemisphere_pdf(cos_at_light)),
            direct_pdf: PdfA(pdf),
            cos_at_light,
        }
    }

    /// The radiance seen along `ray_direction` at `position` on the triangle, `None` from
    /// behind. On a masked emitter this is `L`: the caller's ray has already passed the alpha
    /// test at `position`.
    pub(super) fn radiance_on_hit(&self, ray_direction: Vec3, position: Vec3) -> Option<HitRadiance> {
        let cos_at_light = self.triangle.normal.dot(-ray_direction);
        if cos_at_light <= 0.0 {
            return None;
        }
        let (b1, b2) = self.triangle.barycentrics(position);
        let (radiance, pdf) = self.at(Vec2::new(b1, b2));
        Some(HitRadiance {
            radiance,
            direct_pdf: PdfA(pdf),
            emission_pdf: PdfW(pdf * warp::cosine_hemisphere_pdf(cos_at_light)),
            cos_at_light,
        })
    }
}

/// Texture coordinates at barycentrics `b` (`b.x = b1`, `b.y = b2`).
fn uv_at(uvs: &[Vec2; 3], b: Vec2) -> Vec2 {
    uvs[0] * (1.0 - b.x - b.y) + uvs[1] * b.x + uvs[2] * b.y
}

impl TexturedTriangleLight {
    /// Bounds for the light tree ([`LightBounds`]) from the light's power (W): strength
    /// `power/π` (the mean `L·A`), the triangle's normal as the cone axis, emission into its
    /// hemisphere.
    pub(super) fn bounds(&self, power: f32) -> LightBounds {
        LightBounds {
            bounds: self.triangle.bounds(),
            phi: power / math::PI,
            axis: self.triangle.normal,
            cos_o: 1.0,
            cos_e: 0.0,
            two_sided: false,
        }
    }
}
