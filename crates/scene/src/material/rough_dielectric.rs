//! Microfacet dielectric (GGX or Beckmann; Walter et al. 2007; Mitsuba's `roughdielectric`), two-sided,
//! with visible-normal sampling: the sampled microfacet's Fresnel term picks reflection or
//! refraction. Both pdfs are solid-angle densities: the visible-normal density times the Fresnel
//! choice times the Jacobian of the reflection (`1/(4 ω·m)`) or refraction map.

use math::{Vec3, sqr};
use spectrum::Rgb;

use super::dispatch::LeafModel;
use super::fresnel::{fresnel_dielectric, relative_ior};
use super::lobe::{ModelEval, Sampled, micro_reflect};
use super::query::LobeKind;
use super::shading::TransportMode;
use crate::microfacet::{Microfacet, refract};

/// Microfacet dielectric; `eta` = inside over outside.
#[derive(Clone, Copy, Debug)]
pub(super) struct RoughDielectric {
    /// The microfacet distribution.
    pub dist: Microfacet,
    /// Relative IOR, inside over outside.
    pub eta: f32,
    /// Factor on reflection.
    pub reflectance: Rgb,
    /// Factor on transmission.
    pub transmittance: Rgb,
}

impl RoughDielectric {
    /// The rough interface between `int_ior` (inside) and `ext_ior` with the distribution
    /// `dist`.
    pub(super) fn new(dist: Microfacet, int_ior: f32, ext_ior: f32, reflectance: Rgb, transmittance: Rgb) -> Self {
        RoughDielectric { dist, eta: relative_ior(int_ior, ext_ior), reflectance, transmittance }
    }
}

impl LeafModel for RoughDielectric {
    fn one_sided(&self) -> bool {
        false
    }

    fn lobe_is_delta(&self, _lobe: usize) -> bool {
        false
    }

    fn selection_weight(&self) -> f32 {
        self.reflectance.luminance().max(self.transmittance.luminance())
    }

    fn albedo(&self, w: Vec3) -> Rgb {
        let f = fresnel_dielectric(w.z, self.eta);
        self.reflectance * f + self.transmittance * (1.0 - f)
    }

    fn evaluate(&self, fixed: Vec3, generated: Vec3, mode: TransportMode, _: [f32; 2], _: [f32; 2]) -> ModelEval {
        rough_dielectric_evaluate(&self.dist, self.eta, self.reflectance, self.transmittance, fixed, generated, mode)
    }

    fn sample(&self, fixed: Vec3, _lobe: usize, u: [f32; 3], _: TransportMode) -> Option<Sampled> {
        // Work with the fixed direction on the +z side; `e` = η far side / η near side.
        let (side, e) = if fixed.z > 0.0 { (1.0, self.eta) } else { (-1.0, 1.0 / self.eta) };
        let up = Vec3::new(fixed.x, fixed.y, fixed.z * side);
        let m = self.dist.sample_visible(up, [u[0], u[1]]);
        let cos_m = up.dot(m);
        if cos_m <= 0.0 {
            return None;
        }
        let f = fresnel_dielectric(cos_m, e);
        let (direction, lobe) = if u[2] < f {
            (micro_reflect(up, m), LobeKind::Glossy)
        } else {
            (refract(up, m, e)?, LobeKind::GlossyTransmission)
        };
        // A reflection below or a refraction above the macro surface is rejected
        // (evaluation would read it as the other kind of event).
        if (lobe == LobeKind::Glossy) != (direction.z > 0.0) || direction.z == 0.0 {
            return None;
        }
        Some(Sampled::Lobe { direction: Vec3::new(direction.x, direction.y, direction.z * side), lobe })
    }
}

/// The rough dielectric (Walter et al. 2007, with visible-normal sampling) for local
/// directions on either side.
fn rough_dielectric_evaluate(
    dist: &Microfacet,
    eta: f32,
    reflectance: Rgb,
    transmittance: Rgb,
    fixed: Vec3,
    generated: Vec3,
    mode: TransportMode,
) -> ModelEval {
    if fixed.z == 0.0 || generated.z == 0.0 {
        return ModelEval::default();
    }
    // Mirror so that the fixed direction is on +z; `e` = η on the far side / η on the fixed side.
    let (side, e) = if fixed.z > 0.0 { (1.0, eta) } else { (-1.0, 1.0 / eta) };
    let flip = |v: Vec3| Vec3::new(v.x, v.y, v.z * side);
    let (a, b) = (flip(fixed), flip(generated));
    let Some(h) = RoughPair::new(dist, a, b, e) else { return ModelEval::default() };
    let value = if h.reflection {
        reflectance * (h.fresnel * h.d * dist.g(a, b, h.m) / (4.0 * a.z * b.z.abs()))
    } else {
        let core = (h.cos_a * h.cos_b).abs() * (1.0 - h.fresnel) * h.d * dist.g(a, b, h.m)
            / ((a.z * b.z).abs() * sqr(h.cos_a + e * h.cos_b));
        // Radiance: f_s(fixed → generated) ∝ η_fixed²; importance: the adjoint, ∝ η_generated².
        match mode {
            TransportMode::Radiance => transmittance * core,
            TransportMode::Importance => transmittance * (core * sqr(e)),
        }
    };
    let forward = h.density(dist, a, e);
    // The reverse density: the same pair seen from the generated side.
    let (side_b, e_b) = if generated.z > 0.0 { (1.0, eta) } else { (-1.0, 1.0 / eta) };
    let flip_b = |v: Vec3| Vec3::new(v.x, v.y, v.z * side_b);
    let reverse = RoughPair::new(dist, flip_b(generated), flip_b(fixed), e_b)
        .map_or(0.0, |r| r.density(dist, flip_b(generated), e_b));
    ModelEval { value, forward, reverse }
}

/// The half vector of a pair of directions `a` (on +z) and `b` at a rough dielectric interface
/// with relative index `e` (far side over `a`'s side), and what depends on it.
struct RoughPair {
    reflection: bool,
    /// Microfacet normal, on +z.
    m: Vec3,
    d: f32,
    fresnel: f32,
    cos_a: f32,
    cos_b: f32,
}

impl RoughPair {
    fn new(dist: &Microfacet, a: Vec3, b: Vec3, e: f32) -> Option<RoughPair> {
        let reflection = b.z > 0.0;
        let sum = if reflection { a + b } else { a + e * b };
        let m = sum.normalize();
        if !m.is_finite() {
            return None;
        }
        let m = if m.z < 0.0 { -m } else { m };
        let (cos_a, cos_b) = (a.dot(m), b.dot(m));
        // Both directions must lie on the same side of the microfacet as of the macro surface.
        if cos_a <= 0.0 || cos_b * b.z <= 0.0 {
            return None;
        }
        let d = dist.d(m);
        if d <= 0.0 {
            return None;
        }
        Some(RoughPair { reflection, m, d, fresnel: fresnel_dielectric(cos_a, e), cos_a, cos_b })
    }

    /// Density of sampling `b` from `a`: the visible-normal density times the Fresnel choice
    /// times the Jacobian of the reflection or refraction map.
    fn density(&self, dist: &Microfacet, a: Vec3, e: f32) -> f32 {
        let visible = dist.g1_visible(a, self.m) * self.cos_a * self.d / a.z;
        if self.reflection {
            self.fresnel * visible / (4.0 * self.cos_a)
        } else {
            (1.0 - self.fresnel) * visible * sqr(e) * self.cos_b.abs() / sqr(self.cos_a + e * self.cos_b)
        }
    }
}
