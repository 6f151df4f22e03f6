//! Smooth dielectric interface (Mitsuba's `dielectric`), two-sided: a Fresnel-weighted mirror
//! and a refraction, each a delta lobe chosen with probability `F` and `1 − F` (that probability
//! is its "pdf", tech report eq. 52). Radiance carries `(η_fixed/η_generated)²` through the
//! refraction, importance does not (Veach 1997, §5.2).

use math::{Vec3, sqr};
use spectrum::Rgb;
use spectrum::ior::Ior;

use super::dispatch::LeafModel;
use super::fresnel::{fresnel_dielectric, relative_ior};
use super::lobe::{ModelEval, Sampled, mirror_local};
use super::query::LobeKind;
use super::shading::TransportMode;

/// Smooth dielectric; `eta` = inside over outside (at the hero wavelength when `dispersive`).
#[derive(Clone, Copy, Debug)]
pub(super) struct Dielectric {
    /// Relative IOR, inside over outside.
    pub eta: f32,
    /// Factor on reflection.
    pub reflectance: Rgb,
    /// Factor on transmission.
    pub transmittance: Rgb,
    /// The index was taken at the hero wavelength of a dispersive glass.
    pub dispersive: bool,
}

impl Dielectric {
    /// The interface between `int_ior` (inside) and `ext_ior`; with a `dispersion` curve and a
    /// hero wavelength `hero` (nm), the inside index is the curve's value there.
    pub(super) fn new(
        int_ior: f32,
        ext_ior: f32,
        dispersion: Option<&Ior>,
        hero: Option<f32>,
        reflectance: Rgb,
        transmittance: Rgb,
    ) -> Self {
        let (int_ior, dispersive) = match (dispersion, hero) {
            (Some(ior), Some(lambda)) => (ior.eval(lambda), true),
            _ => (int_ior, false),
        };
        Dielectric { eta: relative_ior(int_ior, ext_ior), reflectance, transmittance, dispersive }
    }
}

impl LeafModel for Dielectric {
    fn one_sided(&self) -> bool {
        false
    }

    /// A smooth dielectric is oriented by its shading normal alone, as Mitsuba 3's is.
    fn follows_shading_normal(&self) -> bool {
        true
    }

    fn lobe_is_delta(&self, _lobe: usize) -> bool {
        true
    }

    fn lobe_probabilities(&self, w: Vec3) -> [f32; 2] {
        let f = fresnel_dielectric(w.z, self.eta);
        [f, 1.0 - f]
    }

    fn selection_weight(&self) -> f32 {
        self.reflectance.luminance().max(self.transmittance.luminance())
    }

    fn albedo(&self, w: Vec3) -> Rgb {
        let f = fresnel_dielectric(w.z, self.eta);
        self.reflectance * f + self.transmittance * (1.0 - f)
    }

    fn evaluate(&self, _: Vec3, _: Vec3, _: TransportMode, _: [f32; 2], _: [f32; 2]) -> ModelEval {
        ModelEval::default()
    }

    fn sample(&self, fixed: Vec3, lobe: usize, _u: [f32; 3], mode: TransportMode) -> Option<Sampled> {
        let f = fresnel_dielectric(fixed.z, self.eta);
        if lobe == 0 {
            return Some(Sampled::Delta {
                direction: mirror_local(fixed),
                rho: self.reflectance * f,
                lobe: LobeKind::SpecularReflection,
            });
        }
        // η on the fixed side over η on the generated side.
        let ratio = if fixed.z > 0.0 { 1.0 / self.eta } else { self.eta };
        let sin_t2 = sqr(ratio) * (1.0 - sqr(fixed.z)).max(0.0);
        if sin_t2 >= 1.0 {
            return None;
        }
        let cos_t = (1.0 - sin_t2).sqrt();
        let direction = Vec3::new(-ratio * fixed.x, -ratio * fixed.y, -cos_t.copysign(fixed.z));
        let scale = match mode {
            TransportMode::Radiance => (1.0 - f) * sqr(ratio),
            TransportMode::Importance => 1.0 - f,
        };
        Some(Sampled::Delta { direction, rho: self.transmittance * scale, lobe: LobeKind::SpecularTransmission })
    }

    fn dispersive(&self) -> bool {
        self.dispersive
    }
}
