//! Alpha masks (Mitsuba 3's `mask` BSDF, pbrt-v4's shape `alpha`): a texture of opacities α
//! over a surface. A ray passes through a point of opacity α with probability 1 − α and does not
//! see it at all: the hit is skipped by both ray queries ([`crate::Scene::intersect`] and
//! [`crate::Scene::occluded`]), so a masked-out point is never a vertex of any sub-path, never
//! blocks a shadow ray or a connection, and is not seen by light tracing.
//!
//! Fractional opacities use a stochastic alpha test (as pbrt-v4 does): a deterministic hash of
//! the ray's origin, direction and hit distance, uniform in [0, 1), is compared with α. Each ray
//! thus sees the surface either fully present or fully absent, and every technique (and every
//! MIS weight) works with that binary realisation: the estimators stay unbiased, with the
//! surface's expected coverage α, but the MIS weights do not account for α (they are the weights
//! of a scene in which the surface is there, or not). The hit distance enters the hash so that two
//! masked surfaces along one ray decide independently.
//!
//! This module owns the opacity lookup and the test, not where a primitive's mask index is kept
//! ([`crate::Primitive::alpha`]) nor the surface's texture coordinates.

use math::{Ray, Vec2, Vec3};

use crate::scene::{Primitive, Scene, SurfaceAttributes};
use crate::shape::Shape;
use crate::texture::Texture;

/// An opacity texture. The opacity at `uv` is the texture's value where its three channels are
/// equal (a float texture), its luminance otherwise (Mitsuba's single-channel lookup of an RGB
/// texture), clamped to [0, 1].
#[derive(Clone, Debug, PartialEq)]
pub struct AlphaMask {
    /// The opacity texture (unitless).
    pub texture: Texture,
}

impl AlphaMask {
    /// The mask of `texture`.
    pub fn new(texture: Texture) -> Self {
        Self { texture }
    }

    /// The opacity α ∈ [0, 1] at `uv` (NaN counts as 0).
    #[inline]
    pub fn opacity(&self, uv: Vec2) -> f32 {
        let c = self.texture.eval(uv);
        let a = if c.r == c.g && c.g == c.b { c.r } else { c.luminance() };
        if a >= 1.0 {
            1.0
        } else if a > 0.0 {
            a
        } else {
            0.0
        }
    }

    /// The constant opacity, if the texture does not vary.
    pub fn constant_opacity(&self) -> Option<f32> {
        self.texture.as_constant().map(|_| self.opacity(Vec2::ZERO))
    }

    /// Whether the hit at parameter `t` along `ray` is kept: always where α = 1, never where
    /// α = 0, and when `alpha_hash(ray, t) < α` in between.
    #[inline]
    pub fn keeps(&self, uv: Vec2, ray: &Ray, t: f32) -> bool {
        let a = self.opacity(uv);
        a >= 1.0 || (a > 0.0 && alpha_hash(ray.origin, ray.direction, t) < a)
    }
}

/// A deterministic hash of a ray and a hit distance, uniform in [0, 1) (24 bits): the random
/// number of the stochastic alpha test. Any change of a single bit of the inputs gives an
/// unrelated value.
#[inline]
pub fn alpha_hash(origin: Vec3, direction: Vec3, t: f32) -> f32 {
    let mut h: u64 = 0x9e37_79b9_7f4a_7c15;
    for x in [origin.x, origin.y, origin.z, direction.x, direction.y, direction.z, t] {
        h = mix(h ^ u64::from(x.to_bits()));
    }
    (h >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
}

/// The 64-bit finaliser of SplitMix64 (a bijection with full avalanche), applied after a
/// golden-ratio increment.
#[inline]
fn mix(x: u64) -> u64 {
    let mut z = x.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

impl Scene {
    /// Whether the hit of `primitive` at parameter `t` along `ray` (both in the primitive's own
    /// space, world or object) survives the primitive's alpha mask; true without a mask. A hit
    /// on the back side of a hair fibre's surface ([`crate::Material::is_fibre`]) never does.
    #[inline]
    pub(crate) fn alpha_keeps(&self, primitive: &Primitive, ray: &Ray, t: f32) -> bool {
        if self.material_flags(primitive.material).fibre
            && ray.direction.dot(primitive.shape.normal_at(ray.at(t))) > 0.0
        {
            return false;
        }
        let Some(index) = primitive.alpha else { return true };
        let Some(mask) = self.alpha_masks.get(index as usize) else { return true };
        mask.keeps(self.alpha_uv(primitive, ray.at(t)), ray, t)
    }

    /// The texture coordinates of `primitive` at `position` (in its own space), as a hit there
    /// reports them: interpolated vertex uvs on triangles that have them, (0, 0) on triangles
    /// that do not, the analytic parameterisation on spheres and discs.
    fn alpha_uv(&self, primitive: &Primitive, position: Vec3) -> Vec2 {
        match (&primitive.shape, self.attributes.get(primitive.attributes as usize)) {
            (Shape::Triangle(t), Some(SurfaceAttributes::Triangle { uvs: Some(uv), .. })) => {
                let (b1, b2) = t.barycentrics(position);
                uv[0] * (1.0 - b1 - b2) + uv[1] * b1 + uv[2] * b2
            }
            (Shape::Triangle(_), _) => Vec2::ZERO,
            (Shape::Sphere(s), _) => s.uv_at(position),
            (Shape::Disk(d), _) => d.uv_at(position),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use spectrum::Rgb;

    #[test]
    fn the_hash_is_uniform_and_the_test_keeps_a_fraction_alpha() {
        // 10⁶ rays from a grid of origins in a fan of directions: the fraction of hashes below
        // α is α within 5σ, σ = √(α(1−α)/n) = 0.00046 for α = 0.3, so a fraction 2 % too high
        // (0.306, 13σ away) fails the same test.
        let n = 1_000_000;
        let mask = AlphaMask::new(Texture::Constant(Rgb::splat(0.3)));
        let mut kept = 0usize;
        let mut below_half = 0usize;
        for i in 0..n {
            let origin = Vec3::new((i % 100) as f32 * 0.01, (i / 100 % 100) as f32 * 0.01, 1.0);
            let direction = Vec3::new(0.001 * (i / 10_000) as f32, 0.0, -1.0).normalize();
            let ray = Ray::new(origin, direction);
            kept += mask.keeps(Vec2::ZERO, &ray, 2.0) as usize;
            below_half += (alpha_hash(origin, direction, 2.0) < 0.5) as usize;
        }
        let sigma = |p: f64| (p * (1.0 - p) / n as f64).sqrt();
        let fraction = kept as f64 / n as f64;
        assert!((fraction - 0.3).abs() < 5.0 * sigma(0.3), "{fraction}");
        assert!((fraction - 0.3 * 1.02).abs() > 5.0 * sigma(0.3), "a 2 % bias is detectable");
        let half = below_half as f64 / n as f64;
        assert!((half - 0.5).abs() < 5.0 * sigma(0.5), "{half}");
    }

    #[test]
    fn binary_opacities_are_deterministic_and_distances_decorrelate() {
        let ray = Ray::new(Vec3::ZERO, Vec3::Z);
        let opaque = AlphaMask::new(Texture::Constant(Rgb::WHITE));
        let clear = AlphaMask::new(Texture::Constant(Rgb::BLACK));
        assert!(opaque.keeps(Vec2::ZERO, &ray, 1.0) && !clear.keeps(Vec2::ZERO, &ray, 1.0));
        assert_eq!(opaque.constant_opacity(), Some(1.0));
        // NaN and out-of-range values clamp; coloured values use the luminance.
        assert_eq!(AlphaMask::new(Texture::Constant(Rgb::splat(f32::NAN))).opacity(Vec2::ZERO), 0.0);
        assert_eq!(AlphaMask::new(Texture::Constant(Rgb::splat(3.0))).opacity(Vec2::ZERO), 1.0);
        let green = AlphaMask::new(Texture::Constant(Rgb::new(0.0, 1.0, 0.0)));
        assert!((green.opacity(Vec2::ZERO) - 0.71516).abs() < 1e-5);
        // The same ray and distance always decide alike; two surfaces along one ray decide
        // independently: over 10 000 rays, both hashes below ½ about a quarter of the time.
        assert_eq!(alpha_hash(Vec3::ONE, Vec3::Z, 1.5), alpha_hash(Vec3::ONE, Vec3::Z, 1.5));
        let n = 10_000;
        let both = (0..n)
            .filter(|&i| {
                let origin = Vec3::new(i as f32 * 1e-3, 0.0, 0.0);
                alpha_hash(origin, Vec3::Z, 1.0) < 0.5 && alpha_hash(origin, Vec3::Z, 2.0) < 0.5
            })
            .count();
        let fraction = both as f64 / n as f64;
        assert!((fraction - 0.25).abs() < 5.0 * (0.25f64 * 0.75 / n as f64).sqrt(), "{fraction}");
    }
}
