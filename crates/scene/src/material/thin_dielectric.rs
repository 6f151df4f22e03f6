//! Thin dielectric sheet (Mitsuba's `thindielectric`), two-sided: a mirror and a
//! straight-through transmission, delta lobes chosen with the sheet's reflectance `R'` and
//! `1 − R'`, where `R' = R + T²R/(1 − R²)` sums the inter-reflections inside the slab.

use math::{Vec3, sqr};
use spectrum::Rgb;

use super::dispatch::LeafModel;
use super::fresnel::{fresnel_dielectric, relative_ior};
use super::lobe::{ModelEval, Sampled, mirror_local};
use super::query::LobeKind;
use super::shading::TransportMode;

/// Thin sheet; `eta` = sheet over surroundings.
#[derive(Clone, Copy, Debug)]
pub(super) struct ThinDielectric {
    /// Relative IOR, sheet over surroundings.
    pub eta: f32,
    /// Factor on reflection.
    pub reflectance: Rgb,
    /// Factor on transmission.
    pub transmittance: Rgb,
}

impl ThinDielectric {
    /// A sheet of index `int_ior` in a medium of index `ext_ior`.
    pub(super) fn new(int_ior: f32, ext_ior: f32, reflectance: Rgb, transmittance: Rgb) -> Self {
        ThinDielectric { eta: relative_ior(int_ior, ext_ior), reflectance, transmittance }
    }
}

/// The thin sheet's reflectance with the inter-reflections summed: `R + T²R/(1 − R²)`.
fn thin_reflectance(cos: f32, eta: f32) -> f32 {
    let r = fresnel_dielectric(cos.abs(), eta);
    if r < 1.0 {
        let t = 1.0 - r;
        r + sqr(t) * r / (1.0 - sqr(r))
    } else {
        1.0
    }
}

impl LeafModel for ThinDielectric {
    fn one_sided(&self) -> bool {
        false
    }

    /// A thin dielectric sheet is oriented by its shading normal alone, as Mitsuba 3's is.
    fn follows_shading_normal(&self) -> bool {
        true
    }

    fn lobe_is_delta(&self, _lobe: usize) -> bool {
        true
    }

    fn lobe_probabilities(&self, w: Vec3) -> [f32; 2] {
        let r = thin_reflectance(w.z, self.eta);
        [r, 1.0 - r]
    }

    fn selection_weight(&self) -> f32 {
        self.reflectance.luminance().max(self.transmittance.luminance())
    }

    fn albedo(&self, w: Vec3) -> Rgb {
        let r = thin_reflectance(w.z, self.eta);
        self.reflectance * r + self.transmittance * (1.0 - r)
    }

    fn null_transmission(&self, w: Vec3) -> Option<Rgb> {
        Some(self.transmittance * (1.0 - thin_reflectance(w.z, self.eta)))
    }

    fn evaluate(&self, _: Vec3, _: Vec3, _: TransportMode, _: [f32; 2], _: [f32; 2]) -> ModelEval {
        ModelEval::default()
    }

    fn sample(&self, fixed: Vec3, lobe: usize, _u: [f32; 3], _: TransportMode) -> Option<Sampled> {
        let r = thin_reflectance(fixed.z, self.eta);
        Some(if lobe == 0 {
            Sampled::Delta {
                direction: mirror_local(fixed),
                rho: self.reflectance * r,
                lobe: LobeKind::SpecularReflection,
            }
        } else {
            Sampled::Delta {
                direction: -fixed,
                rho: self.transmittance * (1.0 - r),
                lobe: LobeKind::SpecularTransmission,
            }
        })
    }
}
