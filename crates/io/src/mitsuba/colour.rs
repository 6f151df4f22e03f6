//! Tabulated spectra to linear sRGB, following Mitsuba 3's RGB variants.
//!
//! The spectrum (piecewise linear between its samples, zero outside them) is integrated against
//! the CIE 1931 2° colour matching functions (the CIE's 5 nm table, 360–830 nm, linearly
//! interpolated, the same data Mitsuba embeds) and the resulting XYZ is converted with the
//! XYZ → linear Rec. 709/sRGB matrix Mitsuba uses. Two normalisations, as in Mitsuba:
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

/// First wavelength of the tables (nm).
const CIE_MIN: f64 = 360.0;
/// Last wavelength of the tables (nm).
const CIE_MAX: f64 = 830.0;
/// Table spacing (nm).
const CIE_STEP: f64 = 5.0;

/// CIE 1931 2° x̄, 360–830 nm in 5 nm steps.
const CIE_X: [f64; 95] = [
    0.0001299,
    0.0002321,
    0.0004149,
    0.0007416,
    0.001368,
    0.002236,
    0.004243,
    0.00765,
    0.01431,
    0.02319,
    0.04351,
    0.07763,
    0.13438,
    0.21477,
    0.2839,
    0.3285,
    0.34828,
    0.34806,
    0.3362,
    0.3187,
    0.2908,
    0.2511,
    0.19536,
    0.1421,
    0.09564,
    0.05795001,
    0.03201,
    0.0147,
    0.0049,
    0.0024,
    0.0093,
    0.0291,
    0.06327,
    0.1096,
    0.1655,
    0.2257499,
    0.2904,
    0.3597,
    0.4334499,
    0.5120501,
    0.5945,
    0.6784,
    0.7621,
    0.8425,
    0.9163,
    0.9786,
    1.0263,
    1.0567,
    1.0622,
    1.0456,
    1.0026,
    0.9384,
    0.8544499,
    0.7514,
    0.6424,
    0.5419,
    0.4479,
    0.3608,
    0.2835,
    0.2187,
    0.1649,
    0.1212,
    0.0874,
    0.0636,
    0.04677,
    0.0329,
    0.0227,
    0.01584,
    0.01135916,
    0.008110916,
    0.005790346,
    0.004109457,
    0.002899327,
    0.00204919,
    0.001439971,
    0.0009999493,
    0.0006900786,
    0.0004760213,
    0.0003323011,
    0.0002348261,
    0.0001661505,
    0.000117413,
    8.307527e-05,
    5.870652e-05,
    4.150994e-05,
    2.935326e-05,
    2.067383e-05,
    1.455977e-05,
    1.025398e-05,
    7.221456e-06,
    5.085868e-06,
    3.581652e-06,
    2.522525e-06,
    1.776509e-06,
    1.251141e-06,
];

/// CIE 1931 2° ȳ, 360–830 nm in 5 nm steps.
const CIE_Y: [f64; 95] = [
    3.917e-06, 6.965e-06, 1.239e-05, 2.202e-05, 3.9e-05, 6.4e-05, 0.00012, 0.000217, 0.000396, 0.00064, 0.00121,
    0.00218, 0.004, 0.0073, 0.0116, 0.01684, 0.023, 0.0298, 0.038, 0.048, 0.06, 0.0739, 0.09098, 0.1126, 0.13902,
    0.1693, 0.20802, 0.2586, 0.323, 0.4073, 0.503, 0.6082, 0.71, 0.7932, 0.862, 0.9148501, 0.954, 0.9803, 0.9949501,
    1.0, 0.995, 0.9786, 0.952, 0.9154, 0.87, 0.8163, 0.757, 0.6949, 0.631, 0.5668, 0.503, 0.4412, 0.381, 0.321, 0.265,
    0.217, 0.175, 0.1382, 0.107, 0.0816, 0.061, 0.04458, 0.032, 0.0232, 0.017, 0.01192, 0.00821, 0.005723, 0.004102,
    0.002929, 0.002091, 0.001484, 0.001047, 0.00074, 0.00052, 0.0003611, 0.0002492, 0.0001719, 0.00012, 8.48e-05,
    6e-05, 4.24e-05, 3e-05, 2.12e-05, 1.499e-05, 1.06e-05, 7.4657e-06, 5.2578e-06, 3.7029e-06, 2.6078e-06, 1.8366e-06,
    1.2934e-06, 9.1093e-07, 6.4153e-07, 4.5181e-07,
];

/// CIE 1931 2° z̄, 360–830 nm in 5 nm steps.
const CIE_Z: [f64; 95] = [
    0.0006061,
    0.001086,
    0.001946,
    0.003486,
    0.006450001,
    0.01054999,
    0.02005001,
    0.03621,
    0.06785001,
    0.1102,
    0.2074,
    0.3713,
    0.6456,
    1.0390501,
    1.3856,
    1.62296,
    1.74706,
    1.7826,
    1.77211,
    1.7441,
    1.6692,
    1.5281,
    1.28764,
    1.0419,
    0.8129501,
    0.6162,
    0.46518,
    0.3533,
    0.272,
    0.2123,
    0.1582,
    0.1117,
    0.07824999,
    0.05725001,
    0.04216,
    0.02984,
    0.0203,
    0.0134,
    0.008749999,
    0.005749999,
    0.0039,
    0.002749999,
    0.0021,
    0.0018,
    0.001650001,
    0.0014,
    0.0011,
    0.001,
    0.0008,
    0.0006,
    0.00034,
    0.00024,
    0.00019,
    0.0001,
    4.999999e-05,
    3e-05,
    2e-05,
    1e-05,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
    0.0,
];

/// CIE standard illuminant D65 (relative, 100 at 560 nm), 360–830 nm in 5 nm steps.
const D65: [f64; 95] = [
    46.6383, 49.3637, 52.0891, 51.0323, 49.9755, 52.3118, 54.6482, 68.7015, 82.7549, 87.1204, 91.486, 92.4589, 93.4318,
    90.057, 86.6823, 95.7736, 104.865, 110.936, 117.008, 117.41, 117.812, 116.336, 114.861, 115.392, 115.923, 112.367,
    108.811, 109.082, 109.354, 108.578, 107.802, 106.296, 104.79, 106.239, 107.689, 106.047, 104.405, 104.225, 104.046,
    102.023, 100.0, 98.1671, 96.3342, 96.0611, 95.788, 92.2368, 88.6856, 89.3459, 90.0062, 89.8026, 89.5991, 88.6489,
    87.6987, 85.4936, 83.2886, 83.4939, 83.6992, 81.863, 80.0268, 80.1207, 80.2146, 81.2462, 82.2778, 80.281, 78.2842,
    74.0027, 69.7213, 70.6652, 71.6091, 72.979, 74.349, 67.9765, 61.604, 65.7448, 69.8856, 72.4863, 75.087, 69.3398,
    63.5927, 55.0054, 46.4182, 56.6118, 66.8054, 65.0941, 63.3828, 63.8434, 64.304, 61.8779, 59.4519, 55.7054, 51.959,
    54.6998, 57.4406, 58.8765, 60.3125,
];

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
    let weighted = usage != SpectrumUse::Emission;
    let weight = |l: f64| if weighted { table(&D65, l) } else { 1.0 };
    let xyz = integrate(|l| {
        let s = sample(spectrum, l) * weight(l);
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
