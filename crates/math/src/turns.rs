//! Sine and cosine of an angle given in turns (one turn = 2π radians), inline and without a
//! library call.
//!
//! The sample warps draw an azimuth as a fraction `u ∈ [0, 1)` of a turn, and called the C
//! library's `sincosf` on `2πu`: 3.9 % of a `pt` run's samples on Mitsuba's Cornell box and
//! 2.6 % of a VCM run's on SmallVCM's scene 3 (`perf record`, 2026-12-01). A fraction of a turn
//! needs no general range reduction: the nearest quarter turn is an exact subtraction away, and
//! the remainder, at most an eighth of a turn, goes into two short Taylor polynomials, inline.
//! (Measured in docs/performance.md, "Sines and cosines of azimuths without the C library":
//! about 1 % fewer instructions, no time difference this machine resolves.)

use std::f64::consts::TAU;

/// Terms of the two polynomials in the remainder `r` (turns): `sin 2πr = Σ S[k]·r^(2k+1)`,
/// `cos 2πr = Σ C[k]·r^(2k)`, the Taylor coefficients `(−1)^k (2π)^n / n!`. For `|r| ≤ 1/8` the
/// first omitted terms are below 1.8·10⁻⁹ (sine, `(π/4)^11/11!`) and 1.2·10⁻¹⁰ (cosine,
/// `(π/4)^12/12!`), far below half a unit in the last place of the results.
const S: [f32; 5] = [
    TAU as f32,
    (-TAU * TAU * TAU / 6.0) as f32,
    (TAU * TAU * TAU * TAU * TAU / 120.0) as f32,
    (-TAU * TAU * TAU * TAU * TAU * TAU * TAU / 5040.0) as f32,
    (TAU * TAU * TAU * TAU * TAU * TAU * TAU * TAU * TAU / 362_880.0) as f32,
];
const C: [f32; 6] = [
    1.0,
    (-TAU * TAU / 2.0) as f32,
    (TAU * TAU * TAU * TAU / 24.0) as f32,
    (-TAU * TAU * TAU * TAU * TAU * TAU / 720.0) as f32,
    (TAU * TAU * TAU * TAU * TAU * TAU * TAU * TAU / 40_320.0) as f32,
    (-TAU * TAU * TAU * TAU * TAU * TAU * TAU * TAU * TAU * TAU / 3_628_800.0) as f32,
];

/// Adding and subtracting 1.5·2²³ rounds an `f32` of magnitude below 2²² to the nearest
/// integer (ties to even) under the default rounding mode, with two additions and no library
/// call (the baseline x86-64 target has no rounding instruction).
const ROUNDING: f32 = 12_582_912.0;

/// `(sin 2πt, cos 2πt)` for an angle of `t` turns (`t = 1` is 2π radians).
///
/// Accurate to about one unit in the last place for `|t| ≤ 2²⁰` (tested against `f64` over
/// [−2, 2] turns: absolute error below 1.2·10⁻⁷); exact at whole quarter turns (0, ±1). Meant
/// for the sample warps' azimuths `t ∈ [0, 1]`; a non-finite `t` gives NaN.
#[inline]
pub fn sin_cos_turns(t: f32) -> (f32, f32) {
    // Nearest quarter turn q; the remainder t − q/4 ∈ [−1/8, 1/8] is exact (Sterbenz: t and
    // q/4 are within a factor of two of each other whenever q ≠ 0).
    let q = (4.0 * t + ROUNDING) - ROUNDING;
    let r = t - 0.25 * q;
    let r2 = r * r;
    let s = r * (S[0] + r2 * (S[1] + r2 * (S[2] + r2 * (S[3] + r2 * S[4]))));
    let c = C[0] + r2 * (C[1] + r2 * (C[2] + r2 * (C[3] + r2 * (C[4] + r2 * C[5]))));
    // Rotate by q quarter turns: (sin, cos) of x + q·π/2 is (s, c), (c, −s), (−s, −c), (−c, s).
    // On the bits, without branches (the quadrant of a random azimuth is unpredictable): swap
    // when q is odd, flip the sine's sign bit for q = 2, 3 and the cosine's for q = 1, 2 (a
    // sign-bit flip is exactly negation).
    let quadrant = (q as i32 as u32) & 3;
    let (s, c) = (s.to_bits(), c.to_bits());
    let swap = (s ^ c) & (quadrant & 1).wrapping_neg();
    let sin_sign = (quadrant >> 1) << 31;
    let cos_sign = ((quadrant ^ (quadrant >> 1)) & 1) << 31;
    (f32::from_bits(s ^ swap ^ sin_sign), f32::from_bits(c ^ swap ^ cos_sign))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Largest absolute errors of sine and cosine against `f64` over `n + 1` evenly spaced
    /// angles in `[a, b]` turns.
    fn max_errors(a: f64, b: f64, n: usize) -> (f64, f64) {
        let (mut es, mut ec) = (0.0f64, 0.0f64);
        for i in 0..=n {
            let t = (a + (b - a) * i as f64 / n as f64) as f32;
            let (s, c) = sin_cos_turns(t);
            let x = TAU * t as f64;
            es = es.max((s as f64 - x.sin()).abs());
            ec = ec.max((c as f64 - x.cos()).abs());
        }
        (es, ec)
    }

    #[test]
    fn matches_double_precision_over_two_turns_each_way() {
        let (es, ec) = max_errors(-2.0, 2.0, 4_000_000);
        // Half an ulp of 1 is 6·10⁻⁸; the polynomial's own rounding adds about as much.
        assert!(es < 1.2e-7 && ec < 1.2e-7, "errors sin {es:e}, cos {ec:e}");
    }

    #[test]
    fn fine_near_zero_and_the_quadrant_boundaries() {
        // Near zero the sine must be relatively accurate, not just absolutely.
        for k in 1..200 {
            let t = 1e-6f32 * k as f32;
            let (s, _) = sin_cos_turns(t);
            let exact = (TAU * t as f64).sin();
            assert!(((s as f64 - exact) / exact).abs() < 2.4e-7, "t {t}: {s} against {exact}");
        }
        // Both sides of each eighth of a turn, where the quadrant and the polynomial change.
        for k in -16..=16 {
            for d in [-1e-6f64, -1e-7, 0.0, 1e-7, 1e-6] {
                let (es, ec) = max_errors(k as f64 / 8.0 + d, k as f64 / 8.0 + d, 1);
                assert!(es < 1.2e-7 && ec < 1.2e-7, "t {}: {es:e} {ec:e}", k as f64 / 8.0 + d);
            }
        }
    }

    #[test]
    fn exact_at_quarter_turns() {
        for k in -8i32..=8 {
            let (s, c) = sin_cos_turns(0.25 * k as f32);
            let (es, ec) = match k.rem_euclid(4) {
                0 => (0.0, 1.0),
                1 => (1.0, 0.0),
                2 => (0.0, -1.0),
                _ => (-1.0, 0.0),
            };
            assert!(s == es && c == ec, "k {k}: ({s}, {c})");
        }
    }
}
