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
    /// The local cosine of the fixed direction given to [`Coating::lobes_and_albedo`], with its
    /// reflectance and transmittance ([`Coating::interface`]): later queries with the same
    /// cosine read them instead of evaluating the interface again.
    fixed: Option<(f32, f32, f32)>,
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
        Coating { eta, diffuse, diffuse_bsdf, specular, specular_weight, rough, fixed: None }
    }

    /// Transmittance `T` of the coating for a direction with local cosine `cos > 0`: `1 − F`
    /// (smooth) or the rough table's.
    #[inline]
    pub(super) fn transmittance(&self, cos: f32) -> f32 {
        self.interface(cos).1
    }

    /// Probabilities of [specular, diffuse] for a direction with local cosine `cos` (Mitsuba:
    /// in proportion to `(1 − T)·w` and `T (1 − w)` with `w` the specular sampling weight).
    pub(super) fn lobe_probabilities(&self, cos: f32) -> [f32; 2] {
        self.lobes_of(self.reflectance(cos.abs()))
    }

    /// [`Coating::lobe_probabilities`] and [`Coating::albedo`] for the fixed direction, with
    /// local cosine `cos > 0`, from one evaluation of the interface; remembers it for the
    /// queries that follow ([`Coating::fixed_interface`]).
    pub(super) fn lobes_and_albedo(&mut self, cos: f32) -> ([f32; 2], Rgb) {
        let (f, t) = self.interface(cos);
        self.fixed = Some((cos, f, t));
        (self.lobes_of(f), self.albedo_of(f))
    }

    /// [`Coating::interface`] of the local cosine `cos > 0` (the same bits), read back when
    /// it is the fixed direction's.
    #[inline]
    pub(super) fn fixed_interface(&self, cos: f32) -> (f32, f32) {
        match self.fixed {
            Some((fixed_cos, f, t)) if fixed_cos.to_bits() == cos.to_bits() => (f, t),
            _ => self.interface(cos),
        }
    }

    /// The lobe probabilities for the coating reflectance `f` of a direction.
    #[inline]
    fn lobes_of(&self, f: f32) -> [f32; 2] {
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

    /// The coating's reflectance `1 − T` and transmittance `T` for a direction with local
    /// cosine `cos > 0`, from one evaluation: the values [`Coating::reflectance`] and
    /// [`Coating::transmittance`] give.
    #[inline]
    pub(super) fn interface(&self, cos: f32) -> (f32, f32) {
        match self.rough {
            None => {
                let f = fresnel_dielectric(cos, self.eta);
                (f, 1.0 - f)
            }
            Some(table) => {
                let t = table.transmittance(cos);
                (1.0 - t, t)
            }
        }
    }

    /// [`Coating::diffuse_eval`] with the lobe probabilities of the generated direction
    /// computed here ([`Coating::lobe_probabilities`] of `generated.z`), sharing one
    /// evaluation of its reflectance; both directions on the front.
    pub(super) fn diffuse_eval_generated(
        &self,
        fixed: Vec3,
        generated: Vec3,
        p_fixed: [f32; 2],
    ) -> (ModelEval, [f32; 2]) {
        let (f_generated, t_generated) = self.interface(generated.z);
        let p_generated = self.lobes_of(f_generated);
        let (_, t_fixed) = self.fixed_interface(fixed.z);
        let e = ModelEval {
            value: self.diffuse_bsdf * (t_fixed * t_generated),
            forward: p_fixed[1] * generated.z * INV_PI,
            reverse: p_generated[1] * fixed.z * INV_PI,
        };
        (e, p_generated)
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
        self.interface(cos).0
    }

    /// Albedo estimate `(1 − T)·specular + T·diffuse` for a direction with local cosine `cos`.
    pub(super) fn albedo(&self, cos: f32) -> Rgb {
        self.albedo_of(self.reflectance(cos))
    }

    /// The albedo estimate for the coating reflectance `f` of a direction.
    #[inline]
    fn albedo_of(&self, f: f32) -> Rgb {
        self.specular * f + self.diffuse * (1.0 - f)
    }
}

/// `a / b`, or 0 when `b` is not positive.
#[inline]
fn safe_divide(a: f32, b: f32) -> f32 {
    if b > 0.0 { a / b } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::rough_coating::coating_table;
    use crate::microfacet::Distribution;

    fn bits(v: Rgb) -> [u32; 3] {
        [v.r.to_bits(), v.g.to_bits(), v.b.to_bits()]
    }

    /// The shared-evaluation forms give the bits of the separate calls, for the smooth and the
    /// rough coating.
    #[test]
    fn shared_forms_match_the_separate_calls() {
        let (diffuse, specular) = (Rgb::new(0.9, 0.3, 0.4), Rgb::new(1.0, 0.8, 0.6));
        let coatings = [
            Coating::new(diffuse, specular, 1.9, 1.0, false),
            Coating::new(diffuse, specular, 1.5, 1.0, true),
            Coating::rough(diffuse, specular, 1.5, false, coating_table(Distribution::Ggx, 0.3, 1.5)),
        ];
        let mut rng = math::Rng::new(4, 9);
        for mut c in coatings {
            for _ in 0..5000 {
                let [a, b] = rng.uniform2();
                let fixed = Vec3::new(0.3 * a, -0.2, (1.0 - a).max(1e-6)).normalize();
                let generated = Vec3::new(-0.1, 0.5 * b, b.max(1e-6)).normalize();
                let (lobes, albedo) = c.lobes_and_albedo(fixed.z);
                assert_eq!(lobes.map(f32::to_bits), c.lobe_probabilities(fixed.z).map(f32::to_bits));
                assert_eq!(bits(albedo), bits(c.albedo(fixed.z)));
                let (e, p_generated) = c.diffuse_eval_generated(fixed, generated, lobes);
                assert_eq!(p_generated.map(f32::to_bits), c.lobe_probabilities(generated.z).map(f32::to_bits));
                let reference = c.diffuse_eval(fixed, generated, lobes, p_generated);
                assert_eq!(bits(e.value), bits(reference.value));
                assert_eq!(e.forward.to_bits(), reference.forward.to_bits());
                assert_eq!(e.reverse.to_bits(), reference.reverse.to_bits());
                let (f, t) = c.fixed_interface(fixed.z);
                assert_eq!(
                    (f.to_bits(), t.to_bits()),
                    (c.reflectance(fixed.z).to_bits(), c.transmittance(fixed.z).to_bits())
                );
                let (f, t) = c.fixed_interface(generated.z);
                assert_eq!(
                    (f.to_bits(), t.to_bits()),
                    (c.reflectance(generated.z).to_bits(), c.transmittance(generated.z).to_bits())
                );
            }
        }
    }
}
