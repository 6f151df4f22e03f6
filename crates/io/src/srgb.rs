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
///
/// The result is bit for bit `round(255 · srgb_oetf(clamped))`, found without a power function:
/// the code is the number of `thresholds` at or below the clamped value (a binary search of
/// 255 entries). A 512² PNG preview took 120 M instructions with one `powf` per channel.
pub fn linear_to_srgb8(linear: f64) -> u8 {
    let clamped = if linear.is_nan() { 0.0 } else { linear.clamp(0.0, 1.0) };
    // At most 255 thresholds, so the count fits in a u8.
    thresholds().partition_point(|&t| t <= clamped) as u8
}

/// `round(255 · srgb_oetf(x))` for `x` in `[0, 1]`: the definition [`linear_to_srgb8`] follows.
fn code_of(x: f64) -> u8 {
    // In [0, 255] for x in [0, 1], so the cast is exact after rounding.
    (srgb_oetf(x) * 255.0).round() as u8
}

/// Entry `k − 1` is the smallest `f64` in `[0, 1]` whose code ([`code_of`]) is at least `k`,
/// for `k` = 1..=255; found once by bisection over the bit patterns of non-negative `f64`s,
/// which are ordered as the values are. The code is non-decreasing in `x` (the tests compare
/// both forms on 10⁶ values and on both sides of every threshold).
fn thresholds() -> &'static [f64; 255] {
    static THRESHOLDS: std::sync::OnceLock<[f64; 255]> = std::sync::OnceLock::new();
    THRESHOLDS.get_or_init(|| {
        std::array::from_fn(|i| {
            let k = i as u8 + 1;
            let (mut below, mut at) = (0.0f64.to_bits(), 1.0f64.to_bits());
            while at - below > 1 {
                let middle = below + (at - below) / 2;
                if code_of(f64::from_bits(middle)) >= k {
                    at = middle;
                } else {
                    below = middle;
                }
            }
            f64::from_bits(at)
        })
    })
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
    fn the_threshold_search_gives_the_formula_s_code() {
        let exact = |x: f64| code_of(if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) });
        for &t in thresholds() {
            let below = f64::from_bits(t.to_bits() - 1);
            assert_eq!(linear_to_srgb8(t), exact(t), "threshold {t}");
            assert_eq!(linear_to_srgb8(below), exact(below), "below threshold {t}");
            assert_eq!(exact(below) + 1, exact(t), "threshold {t} is not a step of one code");
        }
        // A fixed-seed stream over [−0.1, 1.1], denser where codes are dense (x², near 0).
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        for _ in 0..1_000_000 {
            state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
            let u = (state >> 11) as f64 / (1u64 << 53) as f64;
            for x in [1.2 * u - 0.1, u * u] {
                assert_eq!(linear_to_srgb8(x), exact(x), "x = {x}");
            }
        }
        for x in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, -0.0, 0.0, 1.0, f64::MIN_POSITIVE] {
            assert_eq!(linear_to_srgb8(x), exact(x), "x = {x}");
        }
    }

    #[test]
    fn every_code_survives_a_round_trip() {
        for code in 0..=255u8 {
            assert_eq!(linear_to_srgb8(f64::from(srgb8_to_linear(code))), code);
        }
    }
}
