//! CIE colorimetry: the 1931 2° observer, illuminants D65 and A, Planck's law, and the
//! XYZ ↔ linear sRGB matrices.
//!
//! **Tables.** The colour matching functions x̄, ȳ, z̄ and D65 are the CIE's 5 nm tables over
//! 360–830 nm ([`CIE_X`], [`CIE_Y`], [`CIE_Z`], [`D65_TABLE`], `f64`, the values Mitsuba 3
//! embeds). The spectral functions [`cmf`] and [`d65`] interpolate them linearly in single
//! precision (the tables rounded to `f32`) and are zero outside 360–830 nm.
//!
//! **Integrals.** [`CIE_Y_INTEGRAL`], [`D65_Y_INTEGRAL`] and [`D65_XYZ`] are the *exact*
//! integrals of the interpolants that [`cmf`] and [`d65`] return (trapezoid rule for ȳ, the
//! exact per-interval integral of a product of two linear functions for D65·x̄ etc.), computed
//! at compile time from the `f32`-rounded tables. A Monte Carlo estimate
//! `mean(f(λ)/p(λ))` of them therefore has no bias from the table discretisation: a white
//! furnace comes out exactly 1 in expectation.
//!
//! **sRGB.** [`SRGB_TO_XYZ`] is derived from the Rec. 709 primaries' chromaticities
//! (0.64, 0.33), (0.30, 0.60), (0.15, 0.06) and the white point of the *integrated tabulated*
//! D65, (x, y) = (0.312744, 0.329041), so that the XYZ of D65 normalised to Y = 1 maps to
//! exactly (1, 1, 1). The textbook matrix (IEC 61966-2-1 / Lindbloom, white (0.3127, 0.3290),
//! e.g. `XYZ→sRGB` row 0 = 3.240454, −1.537139, −0.498531) differs from ours by at most
//! ~3·10⁻⁴ per entry (the test `matrix_close_to_the_textbook_one` measures it).

use crate::Rgb;

/// Number of entries of every 5 nm table (360, 365, …, 830 nm).
pub const TABLE_LEN: usize = 95;
/// Wavelength of the first table entry (nm).
pub const TABLE_MIN_NM: f32 = 360.0;
/// Wavelength of the last table entry (nm).
pub const TABLE_MAX_NM: f32 = 830.0;
/// Spacing of the tables (nm).
pub const TABLE_STEP_NM: f32 = 5.0;

/// Rounds a table to single precision (at compile time).
const fn to_f32(t: &[f64; TABLE_LEN]) -> [f32; TABLE_LEN] {
    let mut out = [0.0f32; TABLE_LEN];
    let mut i = 0;
    while i < TABLE_LEN {
        out[i] = t[i] as f32;
        i += 1;
    }
    out
}

/// The three colour matching functions interleaved, in single precision.
const CMF_F32: [[f32; 3]; TABLE_LEN] = {
    let (x, y, z) = (to_f32(&CIE_X), to_f32(&CIE_Y), to_f32(&CIE_Z));
    let mut out = [[0.0f32; 3]; TABLE_LEN];
    let mut i = 0;
    while i < TABLE_LEN {
        out[i] = [x[i], y[i], z[i]];
        i += 1;
    }
    out
};

/// D65 in single precision.
const D65_F32: [f32; TABLE_LEN] = to_f32(&D65_TABLE);

/// The interval `i` (0..=93) of the 5 nm grid holding `lambda_nm` and the position `t ∈ [0, 1]`
/// inside it, or `None` outside 360–830 nm (and for NaN).
#[inline]
pub(crate) fn locate(lambda_nm: f32) -> Option<(usize, f32)> {
    let x = (lambda_nm - TABLE_MIN_NM) * (1.0 / TABLE_STEP_NM);
    if !(0.0..=(TABLE_LEN - 1) as f32).contains(&x) {
        return None;
    }
    let i = (x as usize).min(TABLE_LEN - 2);
    Some((i, x - i as f32))
}

/// The CIE 1931 2° colour matching functions `[x̄, ȳ, z̄](λ)` (unitless) at `lambda_nm`
/// (nm): linear interpolation of the 5 nm tables, zero outside 360–830 nm.
#[inline]
pub fn cmf(lambda_nm: f32) -> [f32; 3] {
    match locate(lambda_nm) {
        None => [0.0; 3],
        Some((i, t)) => {
            let (a, b) = (CMF_F32[i], CMF_F32[i + 1]);
            [a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t, a[2] + (b[2] - a[2]) * t]
        }
    }
}

/// CIE standard illuminant D65 at `lambda_nm` (nm), relative spectral power (100 at 560 nm):
/// linear interpolation of the 5 nm table, zero outside 360–830 nm.
#[inline]
pub fn d65(lambda_nm: f32) -> f32 {
    match locate(lambda_nm) {
        None => 0.0,
        Some((i, t)) => D65_F32[i] + (D65_F32[i + 1] - D65_F32[i]) * t,
    }
}

/// Second radiation constant as the CIE defines illuminant A with it (m·K).
const CIE_A_C2: f64 = 1.435e-2;
/// Temperature in the CIE's formula for illuminant A (K): 2848 K with `c₂ = 1.435·10⁻²` m·K is
/// the 2856 K Planckian of today's `c₂ = 1.4388·10⁻²` m·K.
const CIE_A_T: f64 = 2848.0;

/// CIE standard illuminant A at `lambda_nm` (nm), relative spectral power (100 at 560 nm), by
/// the CIE's defining formula (CIE 15:2004, eq. 1.1):
/// `S_A(λ) = 100 (560/λ)⁵ (exp(c₂/(T·560 nm)) − 1) / (exp(c₂/(T·λ)) − 1)` with
/// `c₂ = 1.435·10⁻²` m·K and `T = 2848` K — a Planckian radiator of 2856 K on the ITS-90 scale.
/// Defined for every positive wavelength (not limited to 360–830 nm); zero for `λ ≤ 0` or NaN.
pub fn illuminant_a(lambda_nm: f32) -> f32 {
    let l = f64::from(lambda_nm);
    if !(l > 0.0 && l.is_finite()) {
        return 0.0;
    }
    let e = |l_nm: f64| (CIE_A_C2 / (CIE_A_T * l_nm * 1e-9)).exp_m1();
    (100.0 * (560.0 / l).powi(5) * e(560.0) / e(l)) as f32
}

/// Planck constant (J·s).
const PLANCK_H: f64 = 6.626_070_15e-34;
/// Speed of light in vacuum (m/s).
const LIGHT_C: f64 = 299_792_458.0;
/// Boltzmann constant (J/K).
const BOLTZMANN_K: f64 = 1.380_649e-23;
/// Wien's displacement constant (m·K).
pub const WIEN_B: f64 = 2.897_771_955e-3;

/// Planck's law in double precision: spectral radiance in W·sr⁻¹·m⁻²·nm⁻¹.
fn planck(lambda_nm: f64, kelvin: f64) -> f64 {
    if !(lambda_nm > 0.0 && lambda_nm.is_finite() && kelvin > 0.0 && kelvin.is_finite()) {
        return 0.0;
    }
    let l = lambda_nm * 1e-9;
    let denom = (PLANCK_H * LIGHT_C / (l * BOLTZMANN_K * kelvin)).exp_m1();
    // Per metre of wavelength, then per nanometre. An infinite denominator gives 0.
    2.0 * PLANCK_H * LIGHT_C * LIGHT_C / (l.powi(5) * denom) * 1e-9
}

/// Spectral radiance of a blackbody at temperature `kelvin` (K) and wavelength `lambda_nm`
/// (nm), by Planck's law, in **W·sr⁻¹·m⁻²·nm⁻¹** (per nanometre of wavelength). Zero for a
/// non-positive or non-finite wavelength or temperature.
pub fn blackbody(lambda_nm: f32, kelvin: f32) -> f32 {
    planck(f64::from(lambda_nm), f64::from(kelvin)) as f32
}

/// [`blackbody`] divided by its maximum over all wavelengths (at `λ_max = b/T`, Wien's
/// displacement law, `b` = [`WIEN_B`]), so the peak is 1 (unitless). Zero for a non-positive or
/// non-finite wavelength or temperature.
pub fn blackbody_normalized(lambda_nm: f32, kelvin: f32) -> f32 {
    let t = f64::from(kelvin);
    let peak = planck(WIEN_B / t * 1e9, t);
    if !(peak > 0.0 && peak.is_finite()) {
        return 0.0;
    }
    (planck(f64::from(lambda_nm), t) / peak) as f32
}

/// `∫ a(λ) b(λ) dλ` of two piecewise-linear functions on the 5 nm grid (exact: each interval
/// integrates `h (2a₀b₀ + a₀b₁ + a₁b₀ + 2a₁b₁) / 6`), in nm × units of `a` and `b`.
const fn product_integral(a: &[f32; TABLE_LEN], b: &[f32; TABLE_LEN]) -> f64 {
    let h = TABLE_STEP_NM as f64;
    let mut sum = 0.0;
    let mut i = 0;
    while i + 1 < TABLE_LEN {
        let (a0, a1, b0, b1) = (a[i] as f64, a[i + 1] as f64, b[i] as f64, b[i + 1] as f64);
        sum += h * (2.0 * a0 * b0 + a0 * b1 + a1 * b0 + 2.0 * a1 * b1) / 6.0;
        i += 1;
    }
    sum
}

/// A constant 1 on the grid.
const ONES: [f32; TABLE_LEN] = [1.0; TABLE_LEN];

/// `∫ ȳ(λ) dλ` over 360–830 nm (nm) of the interpolant [`cmf`] returns, exactly: ≈ 106.857029
/// (the CIE's 1 nm table gives 106.856895).
pub const CIE_Y_INTEGRAL: f64 = product_integral(&to_f32(&CIE_Y), &ONES);

/// `∫ (x̄, ȳ, z̄)(λ) dλ` over 360–830 nm (nm), exactly, of the interpolants [`cmf`] returns:
/// the XYZ of the equal-energy spectrum 1.
pub const CMF_INTEGRALS: [f64; 3] =
    [product_integral(&to_f32(&CIE_X), &ONES), CIE_Y_INTEGRAL, product_integral(&to_f32(&CIE_Z), &ONES)];

/// `∫ D65(λ) (x̄, ȳ, z̄)(λ) dλ` over 360–830 nm (nm × relative power), exactly, of the
/// interpolants [`d65`] and [`cmf`] return.
pub const D65_XYZ: [f64; 3] = [
    product_integral(&D65_F32, &to_f32(&CIE_X)),
    product_integral(&D65_F32, &to_f32(&CIE_Y)),
    product_integral(&D65_F32, &to_f32(&CIE_Z)),
];

/// `∫ D65(λ) ȳ(λ) dλ` over 360–830 nm (nm × relative power), exactly, of the interpolants
/// [`d65`] and [`cmf`] return: ≈ 10 567 (D65 is 100 at 560 nm).
pub const D65_Y_INTEGRAL: f64 = D65_XYZ[1];

/// The white point: XYZ of the tabulated D65 normalised to `Y = 1`.
pub const WHITE_XYZ: [f64; 3] = [D65_XYZ[0] / D65_XYZ[1], 1.0, D65_XYZ[2] / D65_XYZ[1]];

/// Chromaticities (x, y) of the Rec. 709 / sRGB primaries red, green, blue.
pub const SRGB_PRIMARIES_XY: [[f64; 2]; 3] = [[0.64, 0.33], [0.30, 0.60], [0.15, 0.06]];

/// Inverse of a 3×3 matrix (rows), by cofactors. The callers pass invertible matrices.
const fn inverse3(m: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let c00 = m[1][1] * m[2][2] - m[1][2] * m[2][1];
    let c01 = m[1][2] * m[2][0] - m[1][0] * m[2][2];
    let c02 = m[1][0] * m[2][1] - m[1][1] * m[2][0];
    let det = m[0][0] * c00 + m[0][1] * c01 + m[0][2] * c02;
    let d = 1.0 / det;
    [
        [c00 * d, (m[0][2] * m[2][1] - m[0][1] * m[2][2]) * d, (m[0][1] * m[1][2] - m[0][2] * m[1][1]) * d],
        [c01 * d, (m[0][0] * m[2][2] - m[0][2] * m[2][0]) * d, (m[0][2] * m[1][0] - m[0][0] * m[1][2]) * d],
        [c02 * d, (m[0][1] * m[2][0] - m[0][0] * m[2][1]) * d, (m[0][0] * m[1][1] - m[0][1] * m[1][0]) * d],
    ]
}

/// Linear sRGB → XYZ (rows; `xyz = M · rgb`), derived from [`SRGB_PRIMARIES_XY`] and
/// [`WHITE_XYZ`]: the columns are the primaries' XYZ `(x/y, 1, (1−x−y)/y)` scaled by
/// `S = P⁻¹ · white`, so `M · (1, 1, 1) = WHITE_XYZ` exactly (up to rounding).
pub const SRGB_TO_XYZ: [[f64; 3]; 3] = {
    let p = &SRGB_PRIMARIES_XY;
    let mut cols = [[0.0; 3]; 3];
    let mut c = 0;
    while c < 3 {
        let (x, y) = (p[c][0], p[c][1]);
        cols[c] = [x / y, 1.0, (1.0 - x - y) / y];
        c += 1;
    }
    let pm = [
        [cols[0][0], cols[1][0], cols[2][0]],
        [cols[0][1], cols[1][1], cols[2][1]],
        [cols[0][2], cols[1][2], cols[2][2]],
    ];
    let inv = inverse3(&pm);
    let w = &WHITE_XYZ;
    let mut s = [0.0; 3];
    let mut r = 0;
    while r < 3 {
        s[r] = inv[r][0] * w[0] + inv[r][1] * w[1] + inv[r][2] * w[2];
        r += 1;
    }
    [
        [pm[0][0] * s[0], pm[0][1] * s[1], pm[0][2] * s[2]],
        [pm[1][0] * s[0], pm[1][1] * s[1], pm[1][2] * s[2]],
        [pm[2][0] * s[0], pm[2][1] * s[1], pm[2][2] * s[2]],
    ]
};

/// XYZ → linear sRGB (rows; `rgb = M · xyz`), the inverse of [`SRGB_TO_XYZ`].
pub const XYZ_TO_SRGB: [[f64; 3]; 3] = inverse3(&SRGB_TO_XYZ);

/// A matrix in single precision.
const fn mat_f32(m: &[[f64; 3]; 3]) -> [[f32; 3]; 3] {
    [
        [m[0][0] as f32, m[0][1] as f32, m[0][2] as f32],
        [m[1][0] as f32, m[1][1] as f32, m[1][2] as f32],
        [m[2][0] as f32, m[2][1] as f32, m[2][2] as f32],
    ]
}

const SRGB_TO_XYZ_F32: [[f32; 3]; 3] = mat_f32(&SRGB_TO_XYZ);
const XYZ_TO_SRGB_F32: [[f32; 3]; 3] = mat_f32(&XYZ_TO_SRGB);

/// The linear-sRGB colour matching functions on the 5 nm grid: `M_XYZ→sRGB · x̄ȳz̄(λ_i)`.
/// Interpolating them linearly is the same as converting the interpolated x̄ȳz̄ (the map is
/// linear), so [`srgb_cmf_at`] is exact with respect to [`cmf`] followed by
/// [`xyz_to_linear_srgb`].
const SRGB_CMF: [[f32; 3]; TABLE_LEN] = {
    let mut out = [[0.0f32; 3]; TABLE_LEN];
    let mut i = 0;
    while i < TABLE_LEN {
        let mut r = 0;
        while r < 3 {
            let m = XYZ_TO_SRGB_F32[r];
            out[i][r] = m[0] * CMF_F32[i][0] + m[1] * CMF_F32[i][1] + m[2] * CMF_F32[i][2];
            r += 1;
        }
        i += 1;
    }
    out
};

/// Linear interpolation of a row table at a located point.
#[inline]
fn lerp3(table: &[[f32; 3]; TABLE_LEN], i: usize, t: f32) -> [f32; 3] {
    let (a, b) = (table[i], table[i + 1]);
    [a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t, a[2] + (b[2] - a[2]) * t]
}

/// The sRGB colour matching functions and D65 at the table point `(i, t)` of
/// [`locate`] (one lookup for both, for the wavelength sampler).
#[inline]
pub(crate) fn srgb_cmf_at(i: usize, t: f32) -> ([f32; 3], f32) {
    (lerp3(&SRGB_CMF, i, t), D65_F32[i] + (D65_F32[i + 1] - D65_F32[i]) * t)
}

#[inline]
fn mul3(m: &[[f32; 3]; 3], v: [f32; 3]) -> [f32; 3] {
    m.map(|row| row[0] * v[0] + row[1] * v[1] + row[2] * v[2])
}

/// CIE XYZ → linear sRGB with [`XYZ_TO_SRGB`] (no clamping: out-of-gamut colours get negative
/// channels). The scale is kept: `Y = 1` white is `(1, 1, 1)`.
#[inline]
pub fn xyz_to_linear_srgb(xyz: [f32; 3]) -> Rgb {
    Rgb::from_array(mul3(&XYZ_TO_SRGB_F32, xyz))
}

/// Linear sRGB → CIE XYZ with [`SRGB_TO_XYZ`].
#[inline]
pub fn linear_srgb_to_xyz(rgb: Rgb) -> [f32; 3] {
    mul3(&SRGB_TO_XYZ_F32, rgb.to_array())
}

// ---- Tables

/// CIE 1931 2° colour matching function x̄ (unitless), 360–830 nm in 5 nm steps (the CIE
/// 5 nm table, as Mitsuba 3 embeds it).
#[rustfmt::skip]
pub const CIE_X: [f64; TABLE_LEN] = [
    0.0001299, 0.0002321, 0.0004149, 0.0007416, 0.001368, 0.002236, 0.004243, 0.00765,
    0.01431, 0.02319, 0.04351, 0.07763, 0.13438, 0.21477, 0.2839, 0.3285,
    0.34828, 0.34806, 0.3362, 0.3187, 0.2908, 0.2511, 0.19536, 0.1421,
    0.09564, 0.05795001, 0.03201, 0.0147, 0.0049, 0.0024, 0.0093, 0.0291,
    0.06327, 0.1096, 0.1655, 0.2257499, 0.2904, 0.3597, 0.4334499, 0.5120501,
    0.5945, 0.6784, 0.7621, 0.8425, 0.9163, 0.9786, 1.0263, 1.0567,
    1.0622, 1.0456, 1.0026, 0.9384, 0.8544499, 0.7514, 0.6424, 0.5419,
    0.4479, 0.3608, 0.2835, 0.2187, 0.1649, 0.1212, 0.0874, 0.0636,
    0.04677, 0.0329, 0.0227, 0.01584, 0.01135916, 0.008110916, 0.005790346, 0.004109457,
    0.002899327, 0.00204919, 0.001439971, 0.0009999493, 0.0006900786, 0.0004760213, 0.0003323011, 0.0002348261,
    0.0001661505, 0.000117413, 8.307527e-05, 5.870652e-05, 4.150994e-05, 2.935326e-05, 2.067383e-05, 1.455977e-05,
    1.025398e-05, 7.221456e-06, 5.085868e-06, 3.581652e-06, 2.522525e-06, 1.776509e-06, 1.251141e-06,
];

/// CIE 1931 2° colour matching function ȳ (unitless, 1 at 555 nm), 360–830 nm in 5 nm steps.
#[rustfmt::skip]
pub const CIE_Y: [f64; TABLE_LEN] = [
    3.917e-06, 6.965e-06, 1.239e-05, 2.202e-05, 3.9e-05, 6.4e-05, 0.00012, 0.000217,
    0.000396, 0.00064, 0.00121, 0.00218, 0.004, 0.0073, 0.0116, 0.01684,
    0.023, 0.0298, 0.038, 0.048, 0.06, 0.0739, 0.09098, 0.1126,
    0.13902, 0.1693, 0.20802, 0.2586, 0.323, 0.4073, 0.503, 0.6082,
    0.71, 0.7932, 0.862, 0.9148501, 0.954, 0.9803, 0.9949501, 1.0,
    0.995, 0.9786, 0.952, 0.9154, 0.87, 0.8163, 0.757, 0.6949,
    0.631, 0.5668, 0.503, 0.4412, 0.381, 0.321, 0.265, 0.217,
    0.175, 0.1382, 0.107, 0.0816, 0.061, 0.04458, 0.032, 0.0232,
    0.017, 0.01192, 0.00821, 0.005723, 0.004102, 0.002929, 0.002091, 0.001484,
    0.001047, 0.00074, 0.00052, 0.0003611, 0.0002492, 0.0001719, 0.00012, 8.48e-05,
    6e-05, 4.24e-05, 3e-05, 2.12e-05, 1.499e-05, 1.06e-05, 7.4657e-06, 5.2578e-06,
    3.7029e-06, 2.6078e-06, 1.8366e-06, 1.2934e-06, 9.1093e-07, 6.4153e-07, 4.5181e-07,
];

/// CIE 1931 2° colour matching function z̄ (unitless), 360–830 nm in 5 nm steps.
#[rustfmt::skip]
pub const CIE_Z: [f64; TABLE_LEN] = [
    0.0006061, 0.001086, 0.001946, 0.003486, 0.006450001, 0.01054999, 0.02005001, 0.03621,
    0.06785001, 0.1102, 0.2074, 0.3713, 0.6456, 1.0390501, 1.3856, 1.62296,
    1.74706, 1.7826, 1.77211, 1.7441, 1.6692, 1.5281, 1.28764, 1.0419,
    0.8129501, 0.6162, 0.46518, 0.3533, 0.272, 0.2123, 0.1582, 0.1117,
    0.07824999, 0.05725001, 0.04216, 0.02984, 0.0203, 0.0134, 0.008749999, 0.005749999,
    0.0039, 0.002749999, 0.0021, 0.0018, 0.001650001, 0.0014, 0.0011, 0.001,
    0.0008, 0.0006, 0.00034, 0.00024, 0.00019, 0.0001, 4.999999e-05, 3e-05,
    2e-05, 1e-05, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
    0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
];

/// CIE standard illuminant D65, relative spectral power (100 at 560 nm), 360–830 nm in 5 nm
/// steps.
#[rustfmt::skip]
pub const D65_TABLE: [f64; TABLE_LEN] = [
    46.6383, 49.3637, 52.0891, 51.0323, 49.9755, 52.3118, 54.6482, 68.7015,
    82.7549, 87.1204, 91.486, 92.4589, 93.4318, 90.057, 86.6823, 95.7736,
    104.865, 110.936, 117.008, 117.41, 117.812, 116.336, 114.861, 115.392,
    115.923, 112.367, 108.811, 109.082, 109.354, 108.578, 107.802, 106.296,
    104.79, 106.239, 107.689, 106.047, 104.405, 104.225, 104.046, 102.023,
    100.0, 98.1671, 96.3342, 96.0611, 95.788, 92.2368, 88.6856, 89.3459,
    90.0062, 89.8026, 89.5991, 88.6489, 87.6987, 85.4936, 83.2886, 83.4939,
    83.6992, 81.863, 80.0268, 80.1207, 80.2146, 81.2462, 82.2778, 80.281,
    78.2842, 74.0027, 69.7213, 70.6652, 71.6091, 72.979, 74.349, 67.9765,
    61.604, 65.7448, 69.8856, 72.4863, 75.087, 69.3398, 63.5927, 55.0054,
    46.4182, 56.6118, 66.8054, 65.0941, 63.3828, 63.8434, 64.304, 61.8779,
    59.4519, 55.7054, 51.959, 54.6998, 57.4406, 58.8765, 60.3125,
];

#[cfg(test)]
#[allow(clippy::needless_range_loop)] // Matrix entries read best as m[r][c].
mod tests {
    use super::*;

    /// Midpoint rule with `n` intervals over `[a, b]` in double precision.
    fn midpoint(f: impl Fn(f64) -> f64, a: f64, b: f64, n: usize) -> f64 {
        let h = (b - a) / n as f64;
        (0..n).map(|i| f(a + (i as f64 + 0.5) * h)).sum::<f64>() * h
    }

    #[test]
    fn tables_interpolate_and_vanish_outside() {
        assert_eq!(cmf(555.0)[1], 1.0);
        assert_eq!(d65(560.0), 100.0);
        assert_eq!(cmf(360.0)[0], 0.0001299);
        assert_eq!(cmf(830.0)[1], 4.5181e-7);
        // Halfway between 500 and 505 nm.
        assert!((d65(502.5) - 0.5 * (109.354 + 108.578)).abs() < 1e-4);
        for l in [359.99, 830.01, -1.0, f32::NAN, f32::INFINITY] {
            assert_eq!(cmf(l), [0.0; 3]);
            assert_eq!(d65(l), 0.0);
        }
    }

    #[test]
    fn integrals_are_those_of_the_interpolants() {
        // 360–830 nm cut into 47 000 midpoint intervals: 10 per 0.1 nm; each 5 nm interval is
        // linear (quadratic for the products), so the midpoint error is ~h²/24·|f''| ≈ 1e-9.
        let n = 47_000;
        let y = midpoint(|l| f64::from(cmf(l as f32)[1]), 360.0, 830.0, n);
        assert!((y / CIE_Y_INTEGRAL - 1.0).abs() < 1e-6, "{y} vs {CIE_Y_INTEGRAL}");
        // The CIE's 1 nm table integrates to 106.856895 (pbrt-v4's `CIE_Y_integral`); the 5 nm
        // table agrees to ~1e-6.
        assert!((CIE_Y_INTEGRAL / 106.856895 - 1.0).abs() < 1e-5, "{CIE_Y_INTEGRAL}");
        for c in 0..3 {
            let v = midpoint(|l| f64::from(d65(l as f32) * cmf(l as f32)[c]), 360.0, 830.0, n);
            assert!((v / D65_XYZ[c] - 1.0).abs() < 1e-6, "channel {c}: {v} vs {}", D65_XYZ[c]);
            let e = midpoint(|l| f64::from(cmf(l as f32)[c]), 360.0, 830.0, n);
            assert!((e / CMF_INTEGRALS[c] - 1.0).abs() < 1e-6, "channel {c}: {e} vs {}", CMF_INTEGRALS[c]);
        }
        // The 5 nm table's D65 chromaticity, (0.312744, 0.329041), is the standard's
        // (0.31272, 0.32903) to ~2.5e-5.
        let s: f64 = D65_XYZ.iter().sum();
        let (x, y) = (D65_XYZ[0] / s, D65_XYZ[1] / s);
        assert!((x - 0.31272).abs() < 5e-5 && (y - 0.32903).abs() < 5e-5, "({x}, {y})");
    }

    #[test]
    fn matrix_maps_white_to_one_and_primaries_to_their_chromaticities() {
        let one = xyz_to_linear_srgb(WHITE_XYZ.map(|v| v as f32));
        for v in one.to_array() {
            assert!((v - 1.0).abs() < 1e-6, "{one:?}");
        }
        for c in 0..3 {
            let col = [SRGB_TO_XYZ[0][c], SRGB_TO_XYZ[1][c], SRGB_TO_XYZ[2][c]];
            let s: f64 = col.iter().sum();
            assert!((col[0] / s - SRGB_PRIMARIES_XY[c][0]).abs() < 1e-12);
            assert!((col[1] / s - SRGB_PRIMARIES_XY[c][1]).abs() < 1e-12);
        }
        // Inverse pair.
        for r in 0..3 {
            for c in 0..3 {
                let p: f64 = (0..3).map(|k| XYZ_TO_SRGB[r][k] * SRGB_TO_XYZ[k][c]).sum();
                assert!((p - f64::from(u8::from(r == c))).abs() < 1e-12);
            }
        }
        let rgb = Rgb::new(0.2, 0.5, 0.9);
        let back = xyz_to_linear_srgb(linear_srgb_to_xyz(rgb));
        assert!((back - rgb).to_array().iter().all(|d| d.abs() < 1e-6));
    }

    #[test]
    fn matrix_close_to_the_textbook_one() {
        // Lindbloom's XYZ → sRGB for the white (0.95047, 1, 1.08883).
        let textbook = [
            [3.2404542, -1.5371385, -0.4985314],
            [-0.9692660, 1.8760108, 0.0415560],
            [0.0556434, -0.2040259, 1.0572252],
        ];
        let mut worst: f64 = 0.0;
        for r in 0..3 {
            for c in 0..3 {
                worst = worst.max((XYZ_TO_SRGB[r][c] - textbook[r][c]).abs());
            }
        }
        assert!(worst < 1e-3, "largest difference {worst}");
    }

    #[test]
    fn illuminant_a_matches_the_cie_table() {
        // CIE 15:2004 table of illuminant A (relative, 100 at 560 nm).
        for (l, v) in [(300.0, 0.930483), (380.0, 9.7951), (500.0, 59.8611), (560.0, 100.0), (780.0, 241.675)] {
            let a = illuminant_a(l);
            assert!((a / v - 1.0).abs() < 1e-4, "A({l}) = {a}, table {v}");
        }
        assert_eq!(illuminant_a(0.0), 0.0);
        assert_eq!(illuminant_a(f32::NAN), 0.0);
    }

    #[test]
    fn blackbody_obeys_stefan_boltzmann_and_wien() {
        const SIGMA: f64 = 5.670_374_419e-8; // W·m⁻²·K⁻⁴
        for t in [1000.0f32, 2856.0, 6500.0] {
            // π ∫ L dλ over 10 nm … 1 mm; the tails beyond hold < 1e-7 of the power at these T.
            let total = std::f64::consts::PI * midpoint(|l| planck(l, f64::from(t)), 10.0, 1_000_000.0, 2_000_000);
            let expected = SIGMA * f64::from(t).powi(4);
            assert!((total / expected - 1.0).abs() < 1e-4, "T {t}: {total} vs {expected}");
            let peak = (WIEN_B / f64::from(t) * 1e9) as f32;
            assert!((blackbody_normalized(peak, t) - 1.0).abs() < 1e-6);
            for d in [-20.0, -1.0, 1.0, 20.0] {
                assert!(blackbody_normalized(peak + d, t) < 1.0);
            }
        }
        // Hand value: λ = 500 nm, T = 5000 K: 2hc²/λ⁵ = 3.8307e15 W·sr⁻¹·m⁻³ … per nm below.
        let x = PLANCK_H * LIGHT_C / (500e-9 * BOLTZMANN_K * 5000.0);
        let hand = 2.0 * PLANCK_H * LIGHT_C * LIGHT_C / 500e-9f64.powi(5) / (x.exp() - 1.0) * 1e-9;
        assert!((f64::from(blackbody(500.0, 5000.0)) / hand - 1.0).abs() < 1e-6);
        assert!((hand - 1.2107e4).abs() < 5.0, "{hand}");
        for (l, t) in [(0.0, 5000.0), (500.0, 0.0), (500.0, -1.0), (f32::NAN, 5000.0), (500.0, f32::INFINITY)] {
            assert_eq!(blackbody(l, t), 0.0);
            assert_eq!(blackbody_normalized(l, t), 0.0);
        }
        // Far in the ultraviolet the exponential overflows: 0, not NaN.
        assert_eq!(blackbody(1.0, 300.0), 0.0);
    }
}
