//! Microfacet conductor (Mitsuba's `roughconductor`, GGX or Beckmann) with visible-normal sampling:
//! `f = F(ω_f·m) D(m) G(ω_f, ω_g) / (4 cos θ_f cos θ_g)`, forward pdf
//! `G1(ω_f) D(m) / (4 cos θ_f)` per steradian (the visible-normal density times the reflection
//! Jacobian `1/(4 ω·m)`).

use math::Vec3;
use spectrum::Rgb;

use super::dispatch::LeafModel;
use super::lobe::{ModelEval, Sampled, micro_reflect};
use super::query::LobeKind;
use super::shading::TransportMode;
use crate::microfacet::{Microfacet, fresnel_conductor_rgb};

/// Microfacet conductor.
#[derive(Clone, Copy, Debug)]
pub(super) struct RoughConductor {
    /// The microfacet distribution (anisotropic α along the frame's tangent and bitangent).
    pub dist: Microfacet,
    /// Real part of the relative IOR per channel.
    pub eta: Rgb,
    /// Imaginary part per channel.
    pub k: Rgb,
    /// Factor on the reflection.
    pub specular: Rgb,
}

impl RoughConductor {
    /// The model with the distribution `dist`.
    pub(super) fn new(dist: Microfacet, eta: Rgb, k: Rgb, specular: Rgb) -> Self {
        RoughConductor { dist, eta, k, specular }
    }
}

/// A visible-normal sample of `dist` reflected about the sampled microfacet (a glossy lobe).
#[inline]
pub(super) fn sample_glossy(dist: &Microfacet, fixed: Vec3, u: [f32; 3]) -> Sampled {
    let m = dist.sample_visible(fixed, [u[0], u[1]]);
    Sampled::Lobe { direction: micro_reflect(fixed, m), lobe: LobeKind::Glossy }
}

impl LeafModel for RoughConductor {
    fn lobe_is_delta(&self, _lobe: usize) -> bool {
        false
    }

    fn selection_weight(&self) -> f32 {
        self.specular.luminance()
    }

    fn albedo(&self, w: Vec3) -> Rgb {
        fresnel_conductor_rgb(w.z, self.eta, self.k) * self.specular
    }

    fn evaluate(
        &self,
        fixed: Vec3,
        generated: Vec3,
        _: TransportMode,
        p_fixed: [f32; 2],
        p_generated: [f32; 2],
    ) -> ModelEval {
        if fixed.z <= 0.0 || generated.z <= 0.0 {
            return ModelEval::default();
        }
        let dist = &self.dist;
        let m = (fixed + generated).normalize();
        let d = dist.d(m);
        if d <= 0.0 || !m.is_finite() {
            return ModelEval::default();
        }
        let f = fresnel_conductor_rgb(fixed.dot(m), self.eta, self.k);
        let g = dist.g(fixed, generated, m);
        ModelEval {
            value: self.specular * f * (d * g / (4.0 * fixed.z * generated.z)),
            forward: p_fixed[0] * dist.g1_visible(fixed, m) * d / (4.0 * fixed.z),
            reverse: p_generated[0] * dist.g1_visible(generated, m) * d / (4.0 * generated.z),
        }
    }

    fn sample(&self, fixed: Vec3, _lobe: usize, u: [f32; 3], _: TransportMode) -> Option<Sampled> {
        Some(sample_glossy(&self.dist, fixed, u))
    }
}
