//! What the BSDF queries return: lobe kinds, the pair of solid-angle pdfs, evaluations and
//! samples.

use math::{PdfW, Vec3};
use spectrum::Rgb;

#[cfg(doc)]
use super::Bsdf;

/// Which kind of lobe produced a sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LobeKind {
    /// Lambertian.
    Diffuse,
    /// Non-delta glossy reflection (normalised Phong, microfacet reflection).
    Glossy,
    /// Non-delta glossy transmission (microfacet refraction).
    GlossyTransmission,
    /// Perfect reflection (delta).
    SpecularReflection,
    /// Perfect refraction (delta).
    SpecularTransmission,
}

impl LobeKind {
    /// True for the delta lobes.
    pub fn is_specular(self) -> bool {
        matches!(self, LobeKind::SpecularReflection | LobeKind::SpecularTransmission)
    }
}

/// Forward and reverse solid-angle pdfs of one direction pair.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PdfPair {
    /// Density of generating the generated direction given the fixed one.
    pub forward: PdfW,
    /// Density of generating the fixed direction given the generated one.
    pub reverse: PdfW,
}

/// Result of [`Bsdf::evaluate`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfEval {
    /// BSDF value f (per steradian), without the cosine; see the module documentation for the
    /// shading-normal form.
    pub value: Rgb,
    /// `|cos θ|` of the generated direction with the geometric normal.
    pub cos_generated: f32,
    /// Lobe-selection-weighted solid-angle pdfs of the non-specular lobes.
    pub pdf: PdfPair,
}

/// Result of [`Bsdf::sample`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample {
    /// The generated unit direction (world space, pointing away from the surface).
    pub direction: Vec3,
    /// BSDF value f (see the module documentation); for specular lobes `ρ/|cos θ|`.
    pub value: Rgb,
    /// `|cos θ|` of the generated direction with the geometric normal.
    pub cos_generated: f32,
    /// Solid-angle pdfs (of the whole non-delta mixture, as [`Bsdf::evaluate`] returns); for
    /// specular lobes the lobe-selection probability.
    pub pdf: PdfPair,
    /// The lobe that was sampled.
    pub lobe: LobeKind,
    /// A delta lobe of a dispersive dielectric at the hero wavelength: the other wavelengths
    /// cannot take this direction, so the path continues at the hero wavelength only.
    pub dispersive: bool,
}

/// `cos` between a sampled direction and the incoming ray's direction above which a specular
/// sample counts as passing straight through (see [`BsdfSample::is_straight_through`]).
pub const STRAIGHT_THROUGH_COS: f32 = 1.0 - 1e-6;

impl BsdfSample {
    /// The sample of a non-delta lobe `lobe` in the unit world `direction`, carrying the BSDF's
    /// evaluation there (value, cosine and the mixture's pdfs); `None` when its forward pdf is
    /// not positive.
    #[inline]
    pub(super) fn of_lobe(direction: Vec3, eval: BsdfEval, lobe: LobeKind) -> Option<Self> {
        (eval.pdf.forward.0 > 0.0).then_some(BsdfSample {
            direction,
            value: eval.value,
            cos_generated: eval.cos_generated,
            pdf: eval.pdf,
            lobe,
            dispersive: false,
        })
    }

    /// True for a specular sample that continues in the direction the ray arrived in, i.e.
    /// along `-fixed` (`fixed`: the unit direction back along the arriving ray), within
    /// `STRAIGHT_THROUGH_COS`: a thin dielectric's transmission, or a refraction between
    /// equal indices. Mitsuba 3 gives its thin dielectric's transmission a *null* component,
    /// which its volumetric path tracers do not count as a bounce; ours (pt and the VCM
    /// engine, in scenes with media) follow it with this test.
    pub fn is_straight_through(&self, fixed: Vec3) -> bool {
        self.lobe.is_specular() && self.direction.dot(-fixed) > STRAIGHT_THROUGH_COS
    }
}
