//! Rough plastic (Mitsuba's `roughplastic`), one-sided: a GGX reflection of the coating
//! (lobe 0, pdf `G1(ω_f) D(m)/(4 cos θ_f)` per steradian) over the coated diffuse base (lobe 1,
//! `cos θ/π` per steradian), each pdf scaled by the lobe's selection probability.
//! Deviation from Mitsuba: the smooth Fresnel transmittance and internal reflectance stand in
//! for Mitsuba's precomputed rough tables.

use math::Vec3;
use spectrum::Rgb;

use super::coating::Coating;
use super::diffuse::sample_cosine;
use super::dispatch::LeafModel;
use super::fresnel::fresnel_dielectric;
use super::lobe::{ModelEval, Sampled};
use super::rough_conductor::sample_glossy;
use super::shading::TransportMode;
use crate::microfacet::Ggx;

/// GGX coating over a diffuse base.
#[derive(Clone, Copy, Debug)]
pub(super) struct RoughPlastic {
    /// The coating's (isotropic) microfacet distribution.
    pub ggx: Ggx,
    /// The coating and the base.
    pub coating: Coating,
}

impl RoughPlastic {
    /// See [`Coating::new`]; `alpha` is the coating's GGX roughness.
    pub(super) fn new(alpha: f32, diffuse: Rgb, specular: Rgb, int_ior: f32, ext_ior: f32, nonlinear: bool) -> Self {
        RoughPlastic {
            ggx: Ggx::new(alpha, alpha),
            coating: Coating::new(diffuse, specular, int_ior, ext_ior, nonlinear),
        }
    }
}

impl LeafModel for RoughPlastic {
    fn lobe_is_delta(&self, _lobe: usize) -> bool {
        false
    }

    fn lobe_probabilities(&self, w: Vec3) -> [f32; 2] {
        self.coating.lobe_probabilities(w.z)
    }

    fn selection_weight(&self) -> f32 {
        self.coating.selection_weight()
    }

    fn albedo(&self, w: Vec3) -> Rgb {
        self.coating.albedo(w.z)
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
        let (ggx, c) = (&self.ggx, &self.coating);
        let mut e = c.diffuse_eval(fixed, generated, p_fixed, p_generated);
        let m = (fixed + generated).normalize();
        let d = ggx.d(m);
        if d > 0.0 && m.is_finite() {
            let f = fresnel_dielectric(fixed.dot(m), c.eta);
            let g = ggx.g(fixed, generated, m);
            e.value += c.specular * (f * d * g / (4.0 * fixed.z * generated.z));
            e.forward += p_fixed[0] * ggx.g1(fixed, m) * d / (4.0 * fixed.z);
            e.reverse += p_generated[0] * ggx.g1(generated, m) * d / (4.0 * generated.z);
        }
        e
    }

    fn sample(&self, fixed: Vec3, lobe: usize, u: [f32; 3], _: TransportMode) -> Option<Sampled> {
        Some(if lobe == 0 { sample_glossy(&self.ggx, fixed, u) } else { sample_cosine(u) })
    }
}
