//! Closed forms and quadratures of Mitsuba's normal- and bump-mapped Lambertian surfaces, as
//! truths for tests of the renderer's `normalmap` and `bumpmap` (Mitsuba 3.7's definitions,
//! written independently of the renderer's code).

use std::f64::consts::{FRAC_PI_2, PI, TAU};

/// Mitsuba's bump-terminator shadowing factor (Estevez et al. 2019, as Mitsuba 3 uses it) for a
/// perturbed normal `tilt` radians and a light direction `theta` radians from the unperturbed
/// normal: `2 / (1 + √(1 + α² tan²θ))`, `α² = min(tan²(tilt) / 8, 1)`.
pub fn shadowing(tilt: f64, theta: f64) -> f64 {
    let alpha2 = (tilt.tan().powi(2) / 8.0).min(1.0);
    2.0 / (1.0 + (1.0 + alpha2 * theta.tan().powi(2)).sqrt())
}

/// The directional albedo of a Lambertian surface of reflectance `rho` whose shading normal
/// is tilted by `tilt` radians, lit from the geometric upper hemisphere:
/// `ρ/π ∫ max(0, l·n) G(l) dω` with Mitsuba's shadowing `G` when `shadowed`, else with `G = 1`
/// (then the sky-view factor `ρ (1 + cos tilt)/2`). Midpoint rule on a 1500 × 1500 grid in
/// (θ, φ) (relative error below 10⁻⁵).
pub fn tilted_diffuse_albedo(rho: f64, tilt: f64, shadowed: bool) -> f64 {
    let n = 1500;
    let normal = [tilt.sin(), 0.0, tilt.cos()];
    let mut sum = 0.0;
    for i in 0..n {
        let theta = (i as f64 + 0.5) / n as f64 * FRAC_PI_2;
        let g = if shadowed { shadowing(tilt, theta) } else { 1.0 };
        for j in 0..n {
            let phi = (j as f64 + 0.5) / n as f64 * TAU;
            let l = [theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos()];
            let cos = l[0] * normal[0] + l[1] * normal[1] + l[2] * normal[2];
            sum += cos.max(0.0) * g * theta.sin();
        }
    }
    let cell = FRAC_PI_2 / n as f64 * TAU / n as f64;
    rho / PI * sum * cell
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unshadowed_albedo_is_the_sky_view_factor() {
        for tilt in [0.0, 0.4, 1.0, 1.4] {
            let q = tilted_diffuse_albedo(0.7, tilt, false);
            let exact = 0.7 * (1.0 + f64::cos(tilt)) / 2.0;
            assert!((q - exact).abs() < 1e-5 * exact, "tilt {tilt}: {q} vs {exact}");
        }
        // Shadowing darkens a tilted surface and leaves an untilted one.
        assert!(tilted_diffuse_albedo(0.7, 0.9, true) < 0.98 * tilted_diffuse_albedo(0.7, 0.9, false));
        assert!((tilted_diffuse_albedo(0.7, 0.0, true) - 0.7).abs() < 1e-5);
    }
}
