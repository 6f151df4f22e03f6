//! Smooth conductor: a Fresnel-weighted mirror (Mitsuba's `conductor`), one delta lobe whose
//! "pdf" is its selection probability (tech report eq. 52).

use math::Vec3;
use spectrum::Rgb;

use super::dispatch::LeafModel;
use super::lobe::{ModelEval, Sampled, mirror_local};
use super::query::LobeKind;
use super::shading::TransportMode;
use crate::microfacet::fresnel_conductor_rgb;

/// Fresnel-weighted mirror with the complex IOR `eta + i·k` relative to the outside.
#[derive(Clone, Copy, Debug)]
pub(super) struct Conductor {
    /// Real part of the relative IOR per channel.
    pub eta: Rgb,
    /// Imaginary part per channel.
    pub k: Rgb,
    /// Factor on the reflection.
    pub specular: Rgb,
}

impl LeafModel for Conductor {
    fn lobe_is_delta(&self, _lobe: usize) -> bool {
        true
    }

    fn selection_weight(&self) -> f32 {
        self.specular.luminance()
    }

    fn albedo(&self, w: Vec3) -> Rgb {
        fresnel_conductor_rgb(w.z, self.eta, self.k) * self.specular
    }

    fn evaluate(&self, _: Vec3, _: Vec3, _: TransportMode, _: [f32; 2], _: [f32; 2]) -> ModelEval {
        ModelEval::default()
    }

    fn sample(&self, fixed: Vec3, _lobe: usize, _u: [f32; 3], _: TransportMode) -> Option<Sampled> {
        let rho = fresnel_conductor_rgb(fixed.z, self.eta, self.k) * self.specular;
        Some(Sampled::Delta { direction: mirror_local(fixed), rho, lobe: LobeKind::SpecularReflection })
    }
}
