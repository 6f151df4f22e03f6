//! The closed set of leaf scattering models and the one place that dispatches to them.
//!
//! Every model implements [`LeafModel`] in its own file; [`Model`] is the enum over them and
//! [`Model::from_leaf`] maps a [`Material`] to its model with the textures evaluated. Adding a
//! model is one new file, one arm in [`Model`], one line in `each_model!` and the `from_leaf`
//! arm (plus the `Material` variant and the loader lines).

use math::Vec3;
use spectrum::Rgb;

use super::coated::Coated;
use super::conductor::Conductor;
use super::description::Material;
use super::dielectric::Dielectric;
use super::diffuse::Diffuse;
use super::diffuse_transmission::DiffuseTransmission;
use super::hair::Hair;
use super::lobe::{ModelEval, Sampled};
use super::plastic::Plastic;
use super::principled::Principled;
use super::principled_thin::PrincipledThin;
use super::rough_conductor::RoughConductor;
use super::rough_dielectric::RoughDielectric;
use super::rough_plastic::RoughPlastic;
use super::shading::TransportMode;
use super::thin_dielectric::ThinDielectric;
use crate::microfacet::Microfacet;
use crate::texture::TexturePoint;

/// One leaf scattering model with its textures evaluated, in a local frame whose z axis is the
/// (possibly flipped) shading normal. Every pdf is a solid-angle density (1/sr) of the local
/// directions; lobe-selection probabilities are dimensionless.
pub(super) trait LeafModel {
    /// True for the models that scatter only from the front (`fixed.z > 0`). The dispatcher
    /// never asks a one-sided model for the albedo or a sample from behind.
    fn one_sided(&self) -> bool {
        true
    }

    /// True for the models that, as a whole material (not inside a blend, a two-sided or a
    /// normal- or bump-mapped material), follow their shading normal alone: directions need
    /// not lie on the same side of the geometric and the shading tangent planes
    /// ([`super::shading::sides_allowed`] with `relaxed`).
    fn follows_shading_normal(&self) -> bool {
        false
    }

    /// Whether lobe `lobe` (0 or 1) is a delta lobe.
    fn lobe_is_delta(&self, lobe: usize) -> bool;

    /// Selection probabilities of the (up to two) lobes when `w` is the fixed direction.
    fn lobe_probabilities(&self, _w: Vec3) -> [f32; 2] {
        [1.0, 0.0]
    }

    /// Weight of the model when a blend chooses among its components (direction independent):
    /// the luminance of its largest reflectance factor.
    fn selection_weight(&self) -> f32;

    /// Per-channel albedo estimate for the fixed direction `w` (for Russian roulette).
    fn albedo(&self, w: Vec3) -> Rgb;

    /// [`LeafModel::lobe_probabilities`] and [`LeafModel::albedo`] of the fixed direction `w`
    /// (bit for bit); models override it to share work between the two, and may remember what
    /// later queries with the same fixed direction need. Asked of one-sided models only for
    /// `w.z > 0`.
    fn lobes_and_albedo(&mut self, w: Vec3) -> ([f32; 2], Rgb) {
        (self.lobe_probabilities(w), self.albedo(w))
    }

    /// The non-delta part for the local directions `fixed` and `generated`: the BSDF in the
    /// shading frame (`f_s(fixed, generated)` in radiance mode, `f_s(generated, fixed)` in
    /// importance mode), the solid-angle density of generating `generated` from `fixed` with
    /// the lobe probabilities `p_fixed`, and that of generating `fixed` from `generated` with
    /// `p_generated`.
    fn evaluate(
        &self,
        fixed: Vec3,
        generated: Vec3,
        mode: TransportMode,
        p_fixed: [f32; 2],
        p_generated: [f32; 2],
    ) -> ModelEval;

    /// [`LeafModel::evaluate`] with `p_generated` the [`LeafModel::lobe_probabilities`] of
    /// `generated` (bit for bit); models override it to share work with the evaluation.
    fn evaluate_generated(&self, fixed: Vec3, generated: Vec3, mode: TransportMode, p_fixed: [f32; 2]) -> ModelEval {
        self.evaluate(fixed, generated, mode, p_fixed, self.lobe_probabilities(generated))
    }

    /// Samples lobe `lobe` for the local `fixed` direction with `u[0..2]` (direction) and
    /// `u[2]` (any further discrete choice).
    fn sample(&self, fixed: Vec3, lobe: usize, u: [f32; 3], mode: TransportMode) -> Option<Sampled>;

    /// True when a delta sample continues at the hero wavelength only (dispersion).
    fn dispersive(&self) -> bool {
        false
    }

    /// The model's *null* transmission for the local direction `w` (Mitsuba 3's `Null` BSDF
    /// component): the per-channel factor by which light passes straight through, unchanged in
    /// direction, when that pass-through is all the model does besides delta reflection; `None`
    /// for every other model. Volumetric shadow rays cross such surfaces with this factor.
    fn null_transmission(&self, _w: Vec3) -> Option<Rgb> {
        None
    }
}

/// A leaf scattering model (see [`LeafModel`]).
#[derive(Clone, Copy, Debug)]
pub(super) enum Model {
    Diffuse(Diffuse),
    DiffuseTransmission(DiffuseTransmission),
    Conductor(Conductor),
    RoughConductor(RoughConductor),
    Dielectric(Dielectric),
    ThinDielectric(ThinDielectric),
    RoughDielectric(RoughDielectric),
    Plastic(Plastic),
    RoughPlastic(RoughPlastic),
    Principled(Principled),
    PrincipledThin(PrincipledThin),
    Coated(Coated),
    Hair(Hair),
}

/// `each_model!(model, m => expression)`: evaluates the expression with `m` bound to the
/// model inside whichever variant `model` is.
macro_rules! each_model {
    ($model:expr, $m:ident => $e:expr) => {
        match $model {
            Model::Diffuse($m) => $e,
            Model::DiffuseTransmission($m) => $e,
            Model::Conductor($m) => $e,
            Model::RoughConductor($m) => $e,
            Model::Dielectric($m) => $e,
            Model::ThinDielectric($m) => $e,
            Model::RoughDielectric($m) => $e,
            Model::Plastic($m) => $e,
            Model::RoughPlastic($m) => $e,
            Model::Principled($m) => $e,
            Model::PrincipledThin($m) => $e,
            Model::Coated($m) => $e,
            Model::Hair($m) => $e,
        }
    };
}

impl Model {
    /// The leaf model of a non-blend, non-two-sided material with its textures at `uv`, at the
    /// hero wavelength `hero` (nm) in spectral mode; `alpha` replaces a rough model's
    /// `(α_u, α_v)` (textured roughness).
    pub(super) fn from_leaf(
        material: &Material,
        uv: TexturePoint,
        hero: Option<f32>,
        alpha: Option<(f32, f32)>,
    ) -> Option<Model> {
        let model = match material {
            Material::Reference(_)
            | Material::Blend { .. }
            | Material::TwoSided { .. }
            | Material::NormalMap { .. }
            | Material::BumpMap { .. }
            | Material::TexturedRoughness { .. } => return None,
            Material::Diffuse { reflectance } => Model::Diffuse(Diffuse { reflectance: reflectance.eval_at(uv) }),
            Material::DiffuseTransmission { reflectance, transmittance } => {
                Model::DiffuseTransmission(DiffuseTransmission {
                    reflectance: reflectance.eval_at(uv),
                    transmittance: transmittance.eval_at(uv),
                })
            }
            // Unit reflectance: the integrators apply the diagonal reflectance and the
            // re-emission themselves.
            Material::Fluorescent { .. } => Model::Diffuse(Diffuse { reflectance: Rgb::WHITE }),
            Material::Conductor { eta, k, specular_reflectance } => {
                Model::Conductor(Conductor { eta: *eta, k: *k, specular: specular_reflectance.eval_at(uv) })
            }
            Material::RoughConductor { distribution, alpha_u, alpha_v, eta, k, specular_reflectance } => {
                let (alpha_u, alpha_v) = alpha.unwrap_or((*alpha_u, *alpha_v));
                let dist = Microfacet::new(*distribution, alpha_u, alpha_v);
                Model::RoughConductor(RoughConductor::new(dist, *eta, *k, specular_reflectance.eval_at(uv)))
            }
            Material::Dielectric { int_ior, ext_ior, specular_reflectance, specular_transmittance, dispersion } => {
                Model::Dielectric(Dielectric::new(
                    *int_ior,
                    *ext_ior,
                    dispersion.as_ref(),
                    hero,
                    specular_reflectance.eval_at(uv),
                    specular_transmittance.eval_at(uv),
                ))
            }
            Material::ThinDielectric { int_ior, ext_ior, specular_reflectance, specular_transmittance } => {
                Model::ThinDielectric(ThinDielectric::new(
                    *int_ior,
                    *ext_ior,
                    specular_reflectance.eval_at(uv),
                    specular_transmittance.eval_at(uv),
                ))
            }
            Material::RoughDielectric {
                distribution,
                alpha_u,
                alpha_v,
                int_ior,
                ext_ior,
                specular_reflectance,
                specular_transmittance,
            } => Model::RoughDielectric(RoughDielectric::new(
                Microfacet::new(*distribution, alpha.map_or(*alpha_u, |a| a.0), alpha.map_or(*alpha_v, |a| a.1)),
                *int_ior,
                *ext_ior,
                specular_reflectance.eval_at(uv),
                specular_transmittance.eval_at(uv),
            )),
            Material::Plastic { diffuse_reflectance, specular_reflectance, int_ior, ext_ior, nonlinear } => {
                Model::Plastic(Plastic::new(
                    diffuse_reflectance.eval_at(uv),
                    specular_reflectance.eval_at(uv),
                    *int_ior,
                    *ext_ior,
                    *nonlinear,
                ))
            }
            Material::RoughPlastic {
                distribution,
                alpha: alpha_plastic,
                diffuse_reflectance,
                specular_reflectance,
                int_ior,
                ext_ior,
                nonlinear,
            } => Model::RoughPlastic(RoughPlastic::new(
                *distribution,
                alpha.map_or(*alpha_plastic, |a| a.0),
                diffuse_reflectance.eval_at(uv),
                specular_reflectance.eval_at(uv),
                *int_ior,
                *ext_ior,
                *nonlinear,
            )),
            Material::Principled(p) => Model::Principled(Principled::new(p, uv)),
            Material::PrincipledThin(p) => Model::PrincipledThin(PrincipledThin::new(p, uv)),
            Material::Coated(p) => Model::Coated(Coated::new(p, uv)),
            Material::Hair(p) => Model::Hair(Hair::new(p)),
        };
        Some(model)
    }

    /// See [`LeafModel::one_sided`].
    #[inline]
    pub(super) fn one_sided(&self) -> bool {
        each_model!(self, m => m.one_sided())
    }

    /// See [`LeafModel::follows_shading_normal`].
    #[inline]
    pub(super) fn follows_shading_normal(&self) -> bool {
        each_model!(self, m => m.follows_shading_normal())
    }

    /// See [`LeafModel::lobe_is_delta`].
    #[inline]
    pub(super) fn lobe_is_delta(&self, lobe: usize) -> bool {
        each_model!(self, m => m.lobe_is_delta(lobe))
    }

    /// See [`LeafModel::lobe_probabilities`].
    #[inline]
    pub(super) fn lobe_probabilities(&self, w: Vec3) -> [f32; 2] {
        each_model!(self, m => m.lobe_probabilities(w))
    }

    /// See [`LeafModel::selection_weight`] (never negative).
    #[inline]
    pub(super) fn selection_weight(&self) -> f32 {
        each_model!(self, m => m.selection_weight()).max(0.0)
    }

    /// See [`LeafModel::lobes_and_albedo`]; black albedo from behind a one-sided model.
    #[inline]
    pub(super) fn lobes_and_albedo(&mut self, w: Vec3) -> ([f32; 2], Rgb) {
        if self.one_sided() && w.z <= 0.0 {
            return (self.lobe_probabilities(w), Rgb::BLACK);
        }
        each_model!(self, m => m.lobes_and_albedo(w))
    }

    /// See [`LeafModel::evaluate_generated`].
    #[inline]
    pub(super) fn evaluate_generated(
        &self,
        fixed: Vec3,
        generated: Vec3,
        mode: TransportMode,
        p_fixed: [f32; 2],
    ) -> ModelEval {
        each_model!(self, m => m.evaluate_generated(fixed, generated, mode, p_fixed))
    }

    /// See [`LeafModel::sample`]; `None` from behind a one-sided model.
    #[inline]
    pub(super) fn sample(&self, fixed: Vec3, lobe: usize, u: [f32; 3], mode: TransportMode) -> Option<Sampled> {
        if self.one_sided() && fixed.z <= 0.0 {
            return None;
        }
        each_model!(self, m => m.sample(fixed, lobe, u, mode))
    }

    /// See [`LeafModel::dispersive`].
    #[inline]
    pub(super) fn dispersive(&self) -> bool {
        each_model!(self, m => m.dispersive())
    }

    /// See [`LeafModel::null_transmission`].
    #[inline]
    pub(super) fn null_transmission(&self, w: Vec3) -> Option<Rgb> {
        each_model!(self, m => m.null_transmission(w))
    }
}
