//! Smooth plastic (Mitsuba's `plastic`), one-sided: a delta mirror lobe of the smooth coating
//! (weight `F·specular`) over the coated diffuse base (see [`super::coating`]). Lobe 0 is the
//! mirror, whose "pdf" is its selection probability; lobe 1 the diffuse base, pdf `cos θ/π` per
//! steradian times its selection probability.

use math::Vec3;
use spectrum::Rgb;

use super::coating::Coating;
use super::diffuse::sample_cosine;
use super::dispatch::LeafModel;
use super::lobe::{ModelEval, Sampled, mirror_local};
use super::query::LobeKind;
use super::shading::TransportMode;

/// Smooth coating over a diffuse base.
#[derive(Clone, Copy, Debug)]
pub(super) struct Plastic {
    /// The coating and the base.
    pub coating: Coating,
}

impl Plastic {
    /// See [`Coating::new`].
    pub(super) fn new(diffuse: Rgb, specular: Rgb, int_ior: f32, ext_ior: f32, nonlinear: bool) -> Self {
        Plastic { coating: Coating::new(diffuse, specular, int_ior, ext_ior, nonlinear) }
    }
}

impl LeafModel for Plastic {
    fn lobe_is_delta(&self, lobe: usize) -> bool {
        lobe == 0
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
        self.coating.diffuse_eval_generated(fixed, generated, p_fixed).0
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
        self.coating.diffuse_eval(fixed, generated, p_fixed, p_generated)
    }

    fn sample(&self, fixed: Vec3, lobe: usize, u: [f32; 3], _: TransportMode) -> Option<Sampled> {
        let c = &self.coating;
        Some(if lobe == 0 {
            Sampled::Delta {
                direction: mirror_local(fixed),
                // `fresnel_dielectric(fixed.z, η)`, remembered from the lobe selection.
                rho: c.specular * c.fixed_interface(fixed.z).0,
                lobe: LobeKind::SpecularReflection,
            }
        } else {
            sample_cosine(u)
        })
    }
}
