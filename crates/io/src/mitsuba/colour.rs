//! Tabulated spectra to linear sRGB, following Mitsuba 3's RGB variants.
//!
//! The spectrum (piecewise linear between its samples, zero outside them) is integrated against
//! the CIE 1931 2° colour matching functions (the CIE's 5 nm table, 360–830 nm, linearly
//! interpolated, the same data Mitsuba embeds; the tables live in `spectrum::cie`) and the
//! resulting XYZ is converted with the XYZ → linear Rec. 709/sRGB matrix Mitsuba uses (kept
//! here, not `spectrum::cie`'s derived one, to match Mitsuba). Two normalisations, as in Mitsuba:
//!
//! - **reflectance-like** quantities (reflectances, `eta`/`k`, texture colours) are seen under
//!   the sRGB white point: the spectrum is weighted by the CIE D65 illuminant and divided by
//!   `∫ ȳ·D65`, so a constant spectrum `c` gives (almost exactly) the grey `(c, c, c)`;
//! - **emitted** quantities (radiance, intensity, irradiance) are integrated as they are and
//!   divided by `∫ ȳ` (Mitsuba's `MI_CIE_Y_NORMALIZATION`), which is what Mitsuba's spectral
//!   variants report for such an emitter; a constant spectrum `c` then gives the slightly
//!   purple `c · M_{XYZ→sRGB} · (1, 1, 1)` that Mitsuba's RGB variants use for it.
//!
//! Reflectances are clamped to `[0, 1]`, other quantities to `≥ 0`, with a warning, as Mitsuba.

use spectrum::cie::{CIE_X, CIE_Y, CIE_Z, D65_TABLE as D65};

/// First wavelength of the tables (nm).
const CIE_MIN: f64 = 360.0;
/// Last wavelength of the tables (nm).
const CIE_MAX: f64 = 830.0;
/// Table spacing (nm).
const CIE_STEP: f64 = 5.0;

/// XYZ → linear sRGB (Rec. 709 primaries, D65 white), the matrix of Mitsuba's `xyz_to_srgb`.
const XYZ_TO_SRGB: [[f64; 3]; 3] =
    [[3.240479, -1.537150, -0.498535], [-0.969256, 1.875991, 0.041556], [0.055648, -0.204043, 1.057311]];

/// Integration step (nm) of the spectra.
const STEP: f64 = 0.5;

/// How a tabulated spectrum is turned into RGB.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum SpectrumUse {
    /// A reflectance in `[0, 1]`: D65-weighted, clamped to `[0, 1]`.
    Reflectance,
    /// A reflectance-like but unbounded quantity (`eta`, `k`): D65-weighted, clamped to `≥ 0`.
    Unbounded,
    /// An emitted quantity: unweighted, divided by `∫ ȳ`, clamped to `≥ 0`.
    Emission,
}

/// Linear interpolation in one of the 5 nm tables (zero outside 360–830 nm).
fn table(t: &[f64; 95], lambda: f64) -> f64 {
    if !(CIE_MIN..=CIE_MAX).contains(&lambda) {
        return 0.0;
    }
    let x = (lambda - CIE_MIN) / CIE_STEP;
    let i = (x.floor() as usize).min(93);
    let f = x - i as f64;
    t[i] * (1.0 - f) + t[i + 1] * f
}

/// The piecewise-linear spectrum at `lambda` (zero outside the sampled range). The
/// wavelengths are strictly increasing and there are at least two samples.
fn sample(spectrum: &[(f64, f64)], lambda: f64) -> f64 {
    let (Some(first), Some(last)) = (spectrum.first(), spectrum.last()) else { return 0.0 };
    if spectrum.len() < 2 || lambda < first.0 || lambda > last.0 {
        return 0.0;
    }
    // The first sample at a wavelength above `lambda` (the last one at the upper end).
    let i = spectrum.partition_point(|&(w, _)| w <= lambda).clamp(1, spectrum.len() - 1);
    let (w0, v0) = spectrum[i - 1];
    let (w1, v1) = spectrum[i];
    v0 + (v1 - v0) * (lambda - w0) / (w1 - w0)
}

/// Trapezoid integral over 360–830 nm of `f(λ)`.
fn integrate(f: impl Fn(f64) -> [f64; 3]) -> [f64; 3] {
    let n = ((CIE_MAX - CIE_MIN) / STEP).round() as usize;
    let mut sum = [0.0; 3];
    for i in 0..=n {
        let w = if i == 0 || i == n { 0.5 } else { 1.0 };
        let v = f(CIE_MIN + i as f64 * STEP);
        for c in 0..3 {
            sum[c] += w * v[c] * STEP;
        }
    }
    sum
}

/// XYZ → linear sRGB.
pub(crate) fn xyz_to_srgb(xyz: [f64; 3]) -> [f64; 3] {
    XYZ_TO_SRGB.map(|row| row[0] * xyz[0] + row[1] * xyz[1] + row[2] * xyz[2])
}

/// The XYZ tristimulus values of `spectrum` (wavelength in nm, value) with the normalisation of
/// `usage` (see the module documentation).
pub(crate) fn spectrum_to_xyz(spectrum: &[(f64, f64)], usage: SpectrumUse) -> [f64; 3] {
    function_to_xyz(|l| sample(spectrum, l), usage)
}

/// The XYZ tristimulus values of the spectrum `f(λ nm)` with the normalisation of `usage`.
fn function_to_xyz(f: impl Fn(f64) -> f64, usage: SpectrumUse) -> [f64; 3] {
    let weighted = usage != SpectrumUse::Emission;
    let weight = |l: f64| if weighted { table(&D65, l) } else { 1.0 };
    let xyz = integrate(|l| {
        let s = f(l) * weight(l);
        [table(&CIE_X, l) * s, table(&CIE_Y, l) * s, table(&CIE_Z, l) * s]
    });
    let norm = integrate(|l| [table(&CIE_Y, l) * weight(l), 0.0, 0.0])[0];
    xyz.map(|v| v / norm)
}

/// Linear sRGB of a tabulated spectrum, and whether it had to be clamped.
pub(crate) fn spectrum_to_rgb(spectrum: &[(f64, f64)], usage: SpectrumUse) -> ([f64; 3], bool) {
    let rgb = xyz_to_srgb(spectrum_to_xyz(spectrum, usage));
    let clamped = rgb.map(|v| match usage {
        SpectrumUse::Reflectance => v.clamp(0.0, 1.0),
        _ => v.max(0.0),
    });
    (clamped, clamped != rgb)
}

/// Linear sRGB of the constant spectrum `value` (Mitsuba's uniform spectrum): the grey
/// `value` for reflectance-like quantities, `value · M·(1, 1, 1)` for emitted ones.
pub(crate) fn constant_spectrum_to_rgb(value: f64, usage: SpectrumUse) -> [f64; 3] {
    match usage {
        SpectrumUse::Emission => xyz_to_srgb([1.0; 3]).map(|v| v * value),
        _ => [value; 3],
    }
}

/// Linear sRGB of an emitted blackbody, `scale` times Planck's law at `kelvin`
/// (W·m⁻²·sr⁻¹·nm⁻¹, [`spectrum::cie::blackbody`]), with the emission normalisation (what
/// Mitsuba's spectral variants report for it; its RGB variants have no blackbody), clamped to
/// ≥ 0 like any emitter (blackbodies below about 1500 K lie slightly outside the gamut).
pub(crate) fn blackbody_to_rgb(kelvin: f64, scale: f64) -> [f64; 3] {
    let xyz = function_to_xyz(
        |l| scale * f64::from(spectrum::cie::blackbody(l as f32, kelvin as f32)),
        SpectrumUse::Emission,
    );
    xyz_to_srgb(xyz).map(|v| v.max(0.0))
}
