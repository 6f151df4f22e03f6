//! The dielectric coating over a diffuse base shared by the smooth and the rough plastic:
//! the diffuse part `ρd/(1 − Fdr)/(η² π) · (1 − F(ω_f))(1 − F(ω_g))`, the lobe choice and the
//! albedo estimate.

use math::{INV_PI, Vec3, sqr};
use spectrum::Rgb;

use super::fresnel::{fresnel_dielectric, relative_ior};
use super::lobe::ModelEval;
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
}

impl Coating {
    /// The coating of index `int_ior` (outside `ext_ior`) over the base reflectance `diffuse`.
    pub(super) fn new(diffuse: Rgb, specular: Rgb, int_ior: f32, ext_ior: f32, nonlinear: bool) -> Self {
        let eta = relative_ior(int_ior, ext_ior);
        let fdr_int = fresnel_diffuse_reflectance(1.0 / eta);
        let denominator = if nonlinear { Rgb::WHITE - diffuse * fdr_int } else { Rgb::splat(1.0 - fdr_int) };
        let scale = INV_PI / sqr(eta);
        let diffuse_bsdf = Rgb::new(
            safe_divide(diffuse.r, denominator.r),
            safe_divide(diffuse.g, denominator.g),
            safe_divide(diffuse.b, denominator.b),
        ) * scale;
        let (d, s) = (diffuse.average(), specular.average());
        let specular_weight = if d + s > 0.0 { s / (d + s) } else { 0.5 };
        Coating { eta, diffuse, diffuse_bsdf, specular, specular_weight }
    }

    /// Probabilities of [specular, diffuse] for a direction with local cosine `cos` (Mitsuba:
    /// in proportion to `F·w` and `(1 − F)(1 − w)` with `w` the specular sampling weight).
    pub(super) fn lobe_probabilities(&self, cos: f32) -> [f32; 2] {
        let f = fresnel_dielectric(cos.abs(), self.eta);
        let specular = f * self.specular_weight;
        let diffuse = (1.0 - f) * (1.0 - self.specular_weight);
        let total = specular + diffuse;
        if total > 0.0 { [specular / total, diffuse / total] } else { [0.5, 0.5] }
    }

    /// The diffuse part of the BSDF, `diffuse_bsdf (1 − F(fixed)) (1 − F(generated))`.
    pub(super) fn diffuse_value(&self, fixed: Vec3, generated: Vec3) -> Rgb {
        let t_fixed = 1.0 - fresnel_dielectric(fixed.z, self.eta);
        let t_generated = 1.0 - fresnel_dielectric(generated.z, self.eta);
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

    /// Albedo estimate `F·specular + (1 − F)·diffuse` for a direction with local cosine `cos`.
    pub(super) fn albedo(&self, cos: f32) -> Rgb {
        let f = fresnel_dielectric(cos, self.eta);
        self.specular * f + self.diffuse * (1.0 - f)
    }
}

/// `a / b`, or 0 when `b` is not positive.
#[inline]
fn safe_divide(a: f32, b: f32) -> f32 {
    if b > 0.0 { a / b } else { 0.0 }
}
