//! A safeguarded Newton solver for the monotone cumulative distributions the Beckmann sampler
//! inverts (and the complementary error function they are made of, from [`math::special`]).

pub(super) use math::special::erfc;

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
