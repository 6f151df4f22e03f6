//! The anisotropic Beckmann distribution: `D`, Smith masking (Mitsuba's rational fit for BSDF
//! values, the exact erf form for the sampler's density) and the exact sampling of visible
//! normals (Heitz & d'Eon 2014, "Importance Sampling Microfacet-Based BSDFs using the
//! Distribution of Visible Normals"). Directions are in the local frame of the macro surface
//! (`z` normal); `ax`, `ay` are the roughnesses along `x` and `y`.

use math::{INV_PI, Vec3, sqr};

use super::erf::{erfc, solve_increasing};

/// `1/√π`.
const INV_SQRT_PI: f64 = 0.564_189_583_547_756_3;

/// `D(m) = exp(−(mx²/αx² + my²/αy²)/mz²) / (π αx αy mz⁴)` per unit solid angle, 0 below the
/// surface and, as in Mitsuba, where `D(m) cos θm ≤ 10⁻²⁰` (the far tail, which holds less
/// than 10⁻¹⁹ of the normalisation: it only keeps denormal garbage out of the images).
#[inline]
pub(super) fn d(ax: f32, ay: f32, m: Vec3) -> f32 {
    if m.z <= 0.0 {
        return 0.0;
    }
    let z2 = sqr(m.z);
    let exponent = -(sqr(m.x / ax) + sqr(m.y / ay)) / z2;
    let value = INV_PI * exponent.exp() / (ax * ay * sqr(z2));
    if value.is_finite() && value * m.z > 1e-20 { value } else { 0.0 }
}

/// `a = 1/(α tan θ)` of the direction `w`, with `α` the roughness projected on its azimuth:
/// `|w.z| / √((αx wx)² + (αy wy)²)` (infinite at normal incidence).
#[inline]
fn inverse_slope(ax: f32, ay: f32, w: Vec3) -> f32 {
    w.z.abs() / (sqr(ax * w.x) + sqr(ay * w.y)).sqrt()
}

/// Smith's `G1` by the rational fit Mitsuba uses (relative error below 0.35 % against
/// [`g1_exact`]): 1 for `a ≥ 1.6`, else `(3.535a + 2.181a²)/(1 + 2.276a + 2.577a²)`. The caller
/// has checked the sides.
#[inline]
pub(super) fn g1(ax: f32, ay: f32, w: Vec3) -> f32 {
    let a = inverse_slope(ax, ay, w);
    if a >= 1.6 || a.is_nan() {
        return 1.0;
    }
    (3.535 * a + 2.181 * sqr(a)) / (1.0 + 2.276 * a + 2.577 * sqr(a))
}

/// The exact Smith `G1 = 1/(1 + Λ(a))`, `Λ(a) = (erf(a) − 1)/2 + exp(−a²)/(2a√π)`: the masking
/// for which [`sample_visible`] has the density `G1 (w·m) D(m) / cos θw`.
#[inline]
pub(super) fn g1_exact(ax: f32, ay: f32, w: Vec3) -> f32 {
    let a = inverse_slope(ax, ay, w) as f64;
    if a.is_nan() || a > 30.0 {
        return 1.0;
    }
    if a <= 0.0 {
        return 0.0;
    }
    let lambda = (0.5 * ((-a * a).exp() * INV_SQRT_PI / a - erfc(a))).max(0.0);
    (1.0 / (1.0 + lambda)) as f32
}

/// Slopes beyond this (in the α = 1 configuration) have a density below `e⁻⁶⁴`.
const SLOPE_BOUND: f64 = 8.0;

/// A normal from the distribution of normals visible from `w` (`w.z > 0`) with two uniform
/// numbers: stretch `w` to the α = 1 configuration, sample the slopes of the visible normals
/// there for the incident angle θ (the `x` slope by inverting its cumulative distribution,
/// the `y` slope, which is independent, from a normal law), rotate by the azimuth of `w`,
/// unstretch.
pub(super) fn sample_visible(ax: f32, ay: f32, w: Vec3, u: [f32; 2]) -> Vec3 {
    let stretched = Vec3::new(ax * w.x, ay * w.y, w.z).normalize();
    let sin_theta = (sqr(stretched.x) + sqr(stretched.y)).sqrt();
    let (cos_phi, sin_phi) =
        if sin_theta > 1e-7 { (stretched.x / sin_theta, stretched.y / sin_theta) } else { (1.0, 0.0) };
    let (sx, sy) = visible_slopes(stretched.z as f64, sin_theta as f64, u);
    let (sx, sy) = (sx as f32, sy as f32);
    let slope_x = ax * (cos_phi * sx - sin_phi * sy);
    let slope_y = ay * (sin_phi * sx + cos_phi * sy);
    Vec3::new(-slope_x, -slope_y, 1.0).normalize()
}

/// Slopes `(x̃, ỹ)` of a visible normal of the α = 1 Beckmann surface seen at the angle θ
/// (`cos`, `sin`) in the `xz` plane. Their density is `(cos θ − x̃ sin θ)⁺ e^{−x̃²−ỹ²}/π` up to
/// normalisation: `ỹ` has density `e^{−ỹ²}/√π`, cumulative `erfc(−ỹ)/2`; `x̃ ≤ cot θ` has
/// density ∝ `(1 − x̃ tan θ) e^{−x̃²}/√π`, cumulative `C(x̃) = erfc(−x̃)/2 + tan θ e^{−x̃²}/(2√π)`.
fn visible_slopes(cos: f64, sin: f64, u: [f32; 2]) -> (f64, f64) {
    let tan = sin / cos;
    let top = if sin > 0.0 { (cos / sin).min(SLOPE_BOUND) } else { SLOPE_BOUND };
    let cdf = |x: f64| 0.5 * erfc(-x) + 0.5 * tan * INV_SQRT_PI * (-x * x).exp();
    let density = |x: f64| ((1.0 - x * tan) * (-x * x).exp() * INV_SQRT_PI).max(0.0);
    let target = u[0] as f64 * cdf(top);
    let x = solve_increasing(cdf, density, target, -SLOPE_BOUND, top, 0.0f64.min(top));
    let normal_cdf = |y: f64| 0.5 * erfc(-y);
    let normal_density = |y: f64| (-y * y).exp() * INV_SQRT_PI;
    let y = solve_increasing(normal_cdf, normal_density, u[1] as f64, -SLOPE_BOUND, SLOPE_BOUND, 0.0);
    (x, y)
}
