//! The complementary error function in double precision and a safeguarded Newton solver for
//! the monotone cumulative distributions the Beckmann sampler inverts.

/// `erfc(x) = 1 − erf(x)` with a relative error below 1.2·10⁻⁷ for every `x` (the Chebyshev
/// fit of Press et al., "Numerical Recipes", §6.2), so that both tails keep their precision.
pub(super) fn erfc(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let poly = -1.265_512_23
        + t * (1.000_023_68
            + t * (0.374_091_96
                + t * (0.096_784_18
                    + t * (-0.186_288_06
                        + t * (0.278_868_07
                            + t * (-1.135_203_98 + t * (1.488_515_87 + t * (-0.822_152_23 + t * 0.170_872_77))))))));
    let r = t * (-z * z + poly).exp();
    if x >= 0.0 { r } else { 2.0 - r }
}

/// The `x` in `[lo, hi]` where the increasing function `f` (with derivative `df ≥ 0`) reaches
/// `target`, by Newton steps that fall back to bisection whenever they leave the bracket.
/// Stops when the bracket or the residual is below `1e-12` relative (at most 64 steps).
pub(super) fn solve_increasing(
    f: impl Fn(f64) -> f64,
    df: impl Fn(f64) -> f64,
    target: f64,
    mut lo: f64,
    mut hi: f64,
    start: f64,
) -> f64 {
    let mut x = start.clamp(lo, hi);
    for _ in 0..64 {
        let value = f(x) - target;
        if value.abs() <= 1e-12 * target.abs().max(1e-300) {
            return x;
        }
        if value > 0.0 {
            hi = x;
        } else {
            lo = x;
        }
        let step = x - value / df(x);
        x = if step > lo && step < hi && step.is_finite() { step } else { 0.5 * (lo + hi) };
        if hi - lo <= 1e-12 * (1.0 + x.abs()) {
            return x;
        }
    }
    x
}
