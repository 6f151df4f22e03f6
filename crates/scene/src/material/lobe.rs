//! Lobe bookkeeping shared by the leaf models: what a model's sampler returns, what its
//! evaluation returns, and the two reflections every specular or microfacet lobe uses.

use math::Vec3;
use spectrum::Rgb;

use super::query::LobeKind;

/// What a model's sampler produced, in the model's local frame.
pub(super) enum Sampled {
    /// A direction from a non-delta lobe; value and pdfs come from evaluation.
    Lobe { direction: Vec3, lobe: LobeKind },
    /// A delta lobe: the direction and the effective reflectance `ρ` (the value times the local
    /// shading cosine of the direction), already in the transport mode's form.
    Delta { direction: Vec3, rho: Rgb, lobe: LobeKind },
}

/// Value and the two solid-angle pdfs (forward: fixed → generated, reverse: generated →
/// fixed; without the component's selection probability) of one model.
#[derive(Clone, Copy, Default)]
pub(super) struct ModelEval {
    /// Shading-frame BSDF value (per steradian).
    pub value: Rgb,
    /// Forward density, solid angle.
    pub forward: f32,
    /// Reverse density, solid angle.
    pub reverse: f32,
}

/// Mirror direction about the local z axis.
#[inline]
pub(super) fn mirror_local(v: Vec3) -> Vec3 {
    Vec3::new(-v.x, -v.y, v.z)
}

/// Reflection of `w` about the microfacet normal `m`.
#[inline]
pub(super) fn micro_reflect(w: Vec3, m: Vec3) -> Vec3 {
    crate::microfacet::reflect(w, m)
}
