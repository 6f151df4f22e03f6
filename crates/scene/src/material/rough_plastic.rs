//! Rough plastic (Mitsuba's `roughplastic`), one-sided: a microfacet reflection of the coating
//! (lobe 0, pdf `G1(ω_f) D(m)/(4 cos θ_f)` per steradian) over the coated diffuse base (lobe 1,
//! `cos θ/π` per steradian), each pdf scaled by the lobe's selection probability. The base is
//! weighed by the rough coating's transmittance and internal reflectance
//! ([`super::rough_coating`]), as in Mitsuba.

use math::Vec3;
use spectrum::Rgb;

use super::coating::Coating;
use super::diffuse::sample_cosine;
use super::dispatch::LeafModel;
use super::fresnel::{fresnel_dielectric, relative_ior};
use super::lobe::{ModelEval, Sampled};
use super::rough_coating::coating_table;
use super::rough_conductor::sample_glossy;
use super::shading::TransportMode;
use crate::microfacet::{Distribution, Microfacet};

/// GGX coating over a diffuse base.
#[derive(Clone, Copy, Debug)]
pub(super) struct RoughPlastic {
    /// The coating's (isotropic) microfacet distribution.
    pub dist: Microfacet,
    /// The coating and the base.
    pub coating: Coating,
}

impl RoughPlastic {
    /// The coating of index `int_ior` (outside `ext_ior`) with the isotropic roughness `alpha`
    /// over the base reflectance `diffuse` (see [`Coating`]).
    pub(super) fn new(
        distribution: Distribution,
        alpha: f32,
        diffuse: Rgb,
        specular: Rgb,
        int_ior: f32,
        ext_ior: f32,
        nonlinear: bool,
    ) -> Self {
        let eta = relative_ior(int_ior, ext_ior);
        RoughPlastic {
            dist: Microfacet::new(distribution, alpha, alpha),
            coating: Coating::rough(diffuse, specular, eta, nonlinear, coating_table(distribution, alpha, eta)),
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

    fn lobes_and_albedo(&mut self, w: Vec3) -> ([f32; 2], Rgb) {
        self.coating.lobes_and_albedo(w.z)
    }

    fn evaluate_generated(&self, fixed: Vec3, generated: Vec3, _: TransportMode, p_fixed: [f32; 2]) -> ModelEval {
        if fixed.z <= 0.0 || generated.z <= 0.0 {
            return ModelEval::default();
        }
        let (e, p_generated) = self.coating.diffuse_eval_generated(fixed, generated, p_fixed);
        self.add_glossy(e, fixed, generated, p_fixed, p_generated)
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
        let e = self.coating.diffuse_eval(fixed, generated, p_fixed, p_generated);
        self.add_glossy(e, fixed, generated, p_fixed, p_generated)
    }

    fn sample(&self, fixed: Vec3, lobe: usize, u: [f32; 3], _: TransportMode) -> Option<Sampled> {
        Some(if lobe == 0 { sample_glossy(&self.dist, fixed, u) } else { sample_cosine(u) })
    }
}

impl RoughPlastic {
    /// Adds the coating's microfacet reflection to the diffuse part `e` of
    /// [`LeafModel::evaluate`] (both directions on the front).
    #[inline]
    fn add_glossy(
        &self,
        mut e: ModelEval,
        fixed: Vec3,
        generated: Vec3,
        p_fixed: [f32; 2],
        p_generated: [f32; 2],
    ) -> ModelEval {
        let (dist, c) = (&self.dist, &self.coating);
        let m = (fixed + generated).normalize();
        let d = dist.d(m);
        if d > 0.0 && m.is_finite() {
            let f = fresnel_dielectric(fixed.dot(m), c.eta);
            let g = dist.g(fixed, generated, m);
            e.value += c.specular * (f * d * g / (4.0 * fixed.z * generated.z));
            e.forward += p_fixed[0] * dist.g1_visible(fixed, m) * d / (4.0 * fixed.z);
            e.reverse += p_generated[0] * dist.g1_visible(generated, m) * d / (4.0 * generated.z);
        }
        e
    }
}
