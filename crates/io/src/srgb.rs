//! The sRGB transfer functions used for 8-bit PNG output and input.

/// The sRGB opto-electronic transfer function (linear → encoded), exact
/// piecewise form: `12.92·x` for `x ≤ 0.0031308`, else
/// `1.055·x^(1/2.4) − 0.055`. The input is not clamped.
pub fn srgb_oetf(linear: f64) -> f64 {
    if linear <= 0.003_130_8 { 12.92 * linear } else { 1.055 * linear.powf(1.0 / 2.4) - 0.055 }
}

/// The inverse of [`srgb_oetf`] (encoded → linear): `v / 12.92` for
/// `v ≤ 0.04045`, else `((v + 0.055) / 1.055)^2.4`. The input is not clamped.
pub fn srgb_eotf(encoded: f64) -> f64 {
    if encoded <= 0.040_45 { encoded / 12.92 } else { ((encoded + 0.055) / 1.055).powf(2.4) }
}

/// Encodes one linear value as an 8-bit sRGB code: clamps to `[0, 1]`
/// (NaN becomes 0), applies [`srgb_oetf`] and rounds to the nearest code.
pub fn linear_to_srgb8(linear: f64) -> u8 {
    let clamped = if linear.is_nan() { 0.0 } else { linear.clamp(0.0, 1.0) };
    // In [0, 255] after the clamp, so the cast is exact after rounding.
    (srgb_oetf(clamped) * 255.0).round() as u8
}

/// Decodes an 8-bit sRGB code to a linear value in `[0, 1]`.
pub fn srgb8_to_linear(code: u8) -> f32 {
    srgb_eotf(f64::from(code) / 255.0) as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eotf_inverts_oetf() {
        for i in 0..=1000 {
            let x = f64::from(i) / 1000.0;
            assert!((srgb_eotf(srgb_oetf(x)) - x).abs() < 1e-9, "x = {x}");
        }
    }

    #[test]
    fn every_code_survives_a_round_trip() {
        for code in 0..=255u8 {
            assert_eq!(linear_to_srgb8(f64::from(srgb8_to_linear(code))), code);
        }
    }
}
