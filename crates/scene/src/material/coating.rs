//! The dielectric coating over a diffuse base shared by the smooth and the rough plastic:
//! the diffuse part `ρd/(1 − R_int)/(η² π) · T(ω_f) T(ω_g)`, the lobe choice and the albedo
//! estimate. The smooth coating has the transmittance `T = 1 − F` and the internal reflectance
//! `R_int = Fdr(1/η)` (Mitsuba's `plastic`); the rough one takes both from its
//! [`CoatingTable`] (Mitsuba's `roughplastic`).

use math::{INV_PI, Vec3, sqr};
use spectrum::Rgb;

use super::fresnel::{fresnel_dielectric, relative_ior};
use super::lobe::ModelEval;
use super::rough_coating::CoatingTable;
use crate::microfacet::fresnel_diffuse_reflectance;

/// The parameters shared by the smooth and the rough plastic.
#[derive(Clone, Copy, Debug)]
pub(super) struct Coating {
    /// Coating over outside.
    pub eta: f32,
    /// Base reflectance (for the albedo estimate).
    pub diffuse: Rgb,
    /// `ρd / (1 − Fdr_int) / (η² π)` (linear) or `ρd / (1 − ρd Fdr_int) / (η² π)` (nonlinear):
    /// the diffuse BSDF before the two Fresnel transmittances.
    pub diffuse_bsdf: Rgb,
    /// Factor on the coating reflection.
    pub specular: Rgb,
    /// Mitsuba's `specular_sampling_weight` = mean(specular) / (mean(diffuse) + mean(specular)).
    pub specular_weight: f32,
    /// The rough coating's transmittance table; `None` for the smooth coating.
    pub rough: Option<&'static CoatingTable>,
}

impl Coating {
    /// The smooth coating of index `int_ior` (outside `ext_ior`) over the base reflectance
    /// `diffuse`.
    pub(super) fn new(diffuse: Rgb, specular: Rgb, int_ior: f32, ext_ior: f32, nonlinear: bool) -> Self {
        let eta = relative_ior(int_ior, ext_ior);
        Self::with_interface(diffuse, specular, eta, nonlinear, None)
    }

    /// The rough coating of relative index `eta` (inside over outside) whose transmittance and
    /// internal reflectance are `table`.
    pub(super) fn rough(diffuse: Rgb, specular: Rgb, eta: f32, nonlinear: bool, table: &'static CoatingTable) -> Self {
        Self::with_interface(diffuse, specular, eta, nonlinear, Some(table))
    }

    fn with_interface(
        diffuse: Rgb,
        specular: Rgb,
        eta: f32,
        nonlinear: bool,
        rough: Option<&'static CoatingTable>,
    ) -> Self {
        let fdr_int = rough.map_or_else(|| fresnel_diffuse_reflectance(1.0 / eta), |t| t.internal_reflectance);
        let denominator = if nonlinear { Rgb::WHITE - diffuse * fdr_int } else { Rgb::splat(1.0 - fdr_int) };
        let scale = INV_PI / sqr(eta);
        let diffuse_bsdf = Rgb::new(
            safe_divide(diffuse.r, denominator.r),
            safe_divide(diffuse.g, denominator.g),
            safe_divide(diffuse.b, denominator.b),
        ) * scale;
        let (d, s) = (diffuse.average(), specular.average());
        let specular_weight = if d + s > 0.0 { s / (d + s) } else { 0.5 };
        Coating { eta, diffuse, diffuse_bsdf, specular, specular_weight, rough }
    }

    /// Transmittance `T` of the coating for a direction with local cosine `cos > 0`: `1 − F`
    /// (smooth) or the rough table's.
    #[inline]
    pub(super) fn transmittance(&self, cos: f32) -> f32 {
        match self.rough {
            None => 1.0 - fresnel_dielectric(cos, self.eta),
            Some(table) => table.transmittance(cos),
        }
    }

    /// Probabilities of [specular, diffuse] for a direction with local cosine `cos` (Mitsuba:
    /// in proportion to `(1 − T)·w` and `T (1 − w)` with `w` the specular sampling weight).
    pub(super) fn lobe_probabilities(&self, cos: f32) -> [f32; 2] {
        let f = self.reflectance(cos.abs());
        let specular = f * self.specular_weight;
        let diffuse = (1.0 - f) * (1.0 - self.specular_weight);
        let total = specular + diffuse;
        if total > 0.0 { [specular / total, diffuse / total] } else { [0.5, 0.5] }
    }

    /// The diffuse part of the BSDF, `diffuse_bsdf T(fixed) T(generated)`.
    pub(super) fn diffuse_value(&self, fixed: Vec3, generated: Vec3) -> Rgb {
        let t_fixed = self.transmittance(fixed.z);
        let t_generated = self.transmittance(generated.z);
        self.diffuse_bsdf * (t_fixed * t_generated)
    }

    /// The diffuse lobe for local directions on the front: its value and solid-angle pdfs
    /// (cosine-weighted, scaled by the diffuse lobe's probability `p_*[1]`).
    pub(super) fn diffuse_eval(
        &self,
        fixed: Vec3,
        generated: Vec3,
        p_fixed: [f32; 2],
        p_generated: [f32; 2],
    ) -> ModelEval {
        ModelEval {
            value: self.diffuse_value(fixed, generated),
            forward: p_fixed[1] * generated.z * INV_PI,
            reverse: p_generated[1] * fixed.z * INV_PI,
        }
    }

    /// Weight in a blend: the luminance of the larger of the two reflectances.
    pub(super) fn selection_weight(&self) -> f32 {
        self.specular.luminance().max(self.diffuse.luminance())
    }

    /// Reflectance of the coating `1 − T` (smooth: `F`) for a direction with local cosine
    /// `cos > 0`.
    #[inline]
    fn reflectance(&self, cos: f32) -> f32 {
        match self.rough {
            None => fresnel_dielectric(cos, self.eta),
            Some(table) => 1.0 - table.transmittance(cos),
        }
    }

    /// Albedo estimate `(1 − T)·specular + T·diffuse` for a direction with local cosine `cos`.
    pub(super) fn albedo(&self, cos: f32) -> Rgb {
        let f = self.reflectance(cos);
        self.specular * f + self.diffuse * (1.0 - f)
    }
}

/// `a / b`, or 0 when `b` is not positive.
#[inline]
fn safe_divide(a: f32, b: f32) -> f32 {
    if b > 0.0 { a / b } else { 0.0 }
}
