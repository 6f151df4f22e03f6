//! Lambertian reflection, one-sided (Mitsuba's `diffuse`; also the BSDF part of a fluorescent
//! material): `f = ρ/π`, sampled by the cosine-weighted hemisphere, pdf `cos θ/π` per steradian.

use math::{INV_PI, Vec3, warp};
use spectrum::Rgb;

use super::dispatch::LeafModel;
use super::lobe::{ModelEval, Sampled};
use super::query::LobeKind;
use super::shading::TransportMode;

/// Lambertian: `ρ/π`.
#[derive(Clone, Copy, Debug)]
pub(super) struct Diffuse {
    /// Reflectance ρ at the hit.
    pub reflectance: Rgb,
}

/// The cosine-weighted hemisphere sample shared by the diffuse lobes.
#[inline]
pub(super) fn sample_cosine(u: [f32; 3]) -> Sampled {
    Sampled::Lobe { direction: warp::cosine_hemisphere([u[0], u[1]]), lobe: LobeKind::Diffuse }
}

impl LeafModel for Diffuse {
    fn lobe_is_delta(&self, _lobe: usize) -> bool {
        false
    }

    fn selection_weight(&self) -> f32 {
        self.reflectance.luminance()
    }

    fn albedo(&self, _w: Vec3) -> Rgb {
        self.reflectance
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
        ModelEval {
            value: self.reflectance * INV_PI,
            forward: p_fixed[0] * generated.z * INV_PI,
            reverse: p_generated[0] * fixed.z * INV_PI,
        }
    }

    fn sample(&self, _fixed: Vec3, _lobe: usize, u: [f32; 3], _: TransportMode) -> Option<Sampled> {
        Some(sample_cosine(u))
    }
}
