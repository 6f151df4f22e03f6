//! Fluorescent vertices in the integrators.
//!
//! A fluorescent material ([`scene::Material::Fluorescent`]) scatters like a Lambertian surface
//! whose BSDF (built with unit reflectance) gives the geometric factor; what it does to the
//! wavelengths is decided here. At every fluorescent vertex of every technique — a vertex a
//! light or camera walk passes through, a connection end, a merge — a discrete **label** is
//! drawn: *stay* (the diagonal reflectance, probability `q`) or *shift* with one of
//! [`SpectralMode::SHIFT_CHOICES`] input choices (probability `(1 − q)/n` each). Every technique
//! draws the label with the same probabilities, so they cancel from all MIS weights and the
//! path-space MIS of the VCM engine stays as it is; each estimate divides by the label's
//! probability, so summing over labels gives the full bispectral reflectance.
//!
//! Light-side quantities are indexed by wavelength *slot* (RGB: channel): a shift writes into
//! each output slot `a` the kernel times the input slot `b` ([`SpectralMode::shift_light`]).
//! A camera sub-path keeps, per channel (which the film weighs with its own wavelength), the
//! slot it is currently at; a shift moves it ([`SpectralMode::shift_camera`]), and everything the
//! camera path meets is read through its slots ([`SpectralMode::gather`]). In spectral mode
//! the input slots are the other independent pair of wavelengths
//! ([`spectrum::Wavelengths4::paired`]), so that the input and output wavelengths of a shift
//! are independent and the two-sample estimate of ∫ dλ_in is unbiased.

use math::{Rng, Vec2};
use scene::Material;
use spectrum::fluorescence::Fluorescence;
use spectrum::{Rgb, SpectralMode};

/// What happens to the wavelengths at a fluorescent vertex.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Label {
    /// The diagonal (ordinary) reflectance.
    Stay,
    /// A wavelength shift with this input choice (< [`SpectralMode::SHIFT_CHOICES`]).
    Shift(u32),
}

/// A fluorescent material at a hit.
#[derive(Clone, Copy, Debug)]
pub struct FluorescentVertex<'a> {
    fluorescence: &'a Fluorescence,
    /// The diagonal reflectance at the hit (linear sRGB).
    reflectance: Rgb,
    /// Probability of [`Label::Stay`].
    stay: f32,
}

impl<'a> FluorescentVertex<'a> {
    /// The fluorescent vertex of `material` at texture coordinates `uv`, or `None` for other
    /// materials.
    #[inline]
    pub fn at(material: &'a Material, uv: Vec2) -> Option<Self> {
        let Material::Fluorescent { reflectance, fluorescence } = material else { return None };
        let reflectance = reflectance.eval(uv);
        // In proportion to the diagonal albedo and the re-emitted fraction of white light,
        // kept away from 0 and 1 so that neither label is starved.
        let (d, f) = (reflectance.average().max(0.0), fluorescence.white_yield().max(0.0));
        let stay = if d + f > 0.0 { (d / (d + f)).clamp(0.1, 0.9) } else { 0.5 };
        Some(Self { fluorescence, reflectance, stay })
    }

    /// Draws a label with one uniform number.
    #[inline]
    pub fn sample_label<S: SpectralMode>(&self, u: f32) -> Label {
        if u < self.stay {
            Label::Stay
        } else {
            let choices = S::SHIFT_CHOICES;
            let x = (u - self.stay) / (1.0 - self.stay) * choices as f32;
            Label::Shift((x as u32).min(choices - 1))
        }
    }

    /// The factor that divides by the label's probability (shift: `n / (1 − q)`).
    #[inline]
    fn label_factor<S: SpectralMode>(&self, label: Label) -> f32 {
        match label {
            Label::Stay => 1.0 / self.stay,
            Label::Shift(_) => S::SHIFT_CHOICES as f32 / (1.0 - self.stay),
        }
    }

    /// Applies the vertex to a slot-indexed quantity `v` (a light sub-path's throughput, or
    /// what arrives at the vertex from the light side). `unit` is the value of the unit
    /// reflectance BSDF for the directions at hand (grey: its red channel is used).
    #[inline]
    pub fn apply_slots<S: SpectralMode>(&self, w: &S::Wavelengths, label: Label, unit: Rgb, v: S) -> S {
        let scale = unit.r * self.label_factor::<S>(label);
        match label {
            Label::Stay => v * S::from_reflectance(w, self.reflectance) * scale,
            Label::Shift(choice) => S::shift_light(w, self.fluorescence, choice, v) * scale,
        }
    }

    /// Applies the vertex to a camera sub-path's throughput `t`, whose channels are at `slots`
    /// (a shift moves them).
    #[inline]
    pub fn apply_camera<S: SpectralMode>(
        &self,
        w: &S::Wavelengths,
        label: Label,
        unit: Rgb,
        slots: &mut S::Slots,
        t: S,
    ) -> S {
        let scale = unit.r * self.label_factor::<S>(label);
        match label {
            Label::Stay => t * S::from_reflectance(w, self.reflectance).gather(slots) * scale,
            Label::Shift(choice) => S::shift_camera(w, self.fluorescence, choice, slots, t) * scale,
        }
    }
}

/// Scatters the slot-indexed quantity `v` at a vertex whose BSDF has value `value` for the
/// directions at hand: the ordinary product, or, at a fluorescent vertex, a label drawn from
/// `rng` and applied ([`FluorescentVertex::apply_slots`]). The one rule for every connection
/// end and next-event estimate.
#[inline]
pub fn scatter_slots<S: SpectralMode>(
    vertex: Option<&FluorescentVertex>,
    w: &S::Wavelengths,
    value: Rgb,
    v: S,
    rng: &mut Rng,
) -> S {
    match vertex {
        None => v * S::from_reflectance(w, value),
        Some(f) => f.apply_slots(w, f.sample_label::<S>(rng.uniform()), value, v),
    }
}

/// Reads `v` (slot-indexed) through a camera path's slots, skipping the identity.
#[inline]
pub fn view<S: SpectralMode>(slots: &S::Slots, v: S) -> S {
    if *slots == S::Slots::default() { v } else { v.gather(slots) }
}
