//! The microfacet distributions against independent quadrature: `D` is normalised
//! (`∫ D(m) cos θm dω = 1`), the masking `G1` is Smith's (`G1(w) = cos θw / ∫ ⟨w, m⟩⁺ D(m) dω`),
//! the visible-normal samplers have the densities they report (chi-square), and a GGX stand-in
//! for Beckmann fails each of these checks.

use math::{Rng, Vec3};
use scene::microfacet::{Distribution, Microfacet};
use testkit::{assert_chi2, chi2_sphere, sidak};

/// `∫ f(m) dω(m)` over the upper hemisphere by the midpoint rule in `(t, φ)` with `θ = t²·π/2`,
/// which puts half of the polar steps within a quarter of the range nearest to the normal,
/// where narrow distributions live.
fn hemisphere_integral(f: impl Fn(Vec3) -> f64) -> f64 {
    let (nt, np) = (3000, 256);
    let mut sum = 0.0;
    for i in 0..nt {
        let t = (i as f64 + 0.5) / nt as f64;
        let theta = t * t * std::f64::consts::FRAC_PI_2;
        let dtheta = 2.0 * t * std::f64::consts::FRAC_PI_2 / nt as f64;
        let (s, c) = theta.sin_cos();
        for j in 0..np {
            let phi = (j as f64 + 0.5) / np as f64 * std::f64::consts::TAU;
            let m = Vec3::new((s * phi.cos()) as f32, (s * phi.sin()) as f32, c as f32);
            sum += f(m) * s * dtheta * std::f64::consts::TAU / np as f64;
        }
    }
    sum
}

fn distributions() -> Vec<Microfacet> {
    let mut v = Vec::new();
    for kind in [Distribution::Beckmann, Distribution::Ggx] {
        for (ax, ay) in [(0.1f32, 0.1f32), (0.5, 0.5), (0.3, 0.08), (1.0, 0.4)] {
            v.push(Microfacet::new(kind, ax, ay));
        }
    }
    v
}

/// A direction at polar angle `theta` (radians) and azimuth `phi`.
fn direction(theta: f32, phi: f32) -> Vec3 {
    Vec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos())
}

#[test]
fn distributions_are_normalised() {
    for dist in distributions() {
        let integral = hemisphere_integral(|m| dist.d(m) as f64 * m.z as f64);
        // The quadrature error of the narrowest case (α 0.08) is below 1e-4.
        assert!((integral - 1.0).abs() < 1e-3, "{dist:?}: ∫ D cos = {integral}");
    }
}

/// `cos θw / ∫ ⟨w, m⟩⁺ D(m) dω(m)` by quadrature: Smith's masking function.
fn smith_by_quadrature(dist: &Microfacet, w: Vec3) -> f64 {
    w.z as f64 / hemisphere_integral(|m| dist.d(m) as f64 * w.dot(m).max(0.0) as f64)
}

#[test]
fn masking_is_smiths() {
    for dist in distributions() {
        for theta_deg in [20.0f32, 60.0, 80.0, 88.0] {
            let w = direction(theta_deg.to_radians(), 0.7);
            let m = Vec3::Z;
            let exact = smith_by_quadrature(&dist, w);
            let visible = dist.g1_visible(w, m) as f64;
            assert!((visible - exact).abs() < 1e-3 * exact.max(0.1), "{dist:?} θ {theta_deg}: {visible} vs {exact}");
            // The masking in BSDF values: Mitsuba's rational fit for Beckmann (0.35 % bound).
            let value = dist.g1(w, m) as f64;
            assert!((value - exact).abs() < 4e-3 * exact + 1e-4, "{dist:?} θ {theta_deg}: fit {value} vs {exact}");
        }
    }
}

/// The checks above tell Beckmann from GGX of the same α: a GGX stand-in (the renderer's former
/// approximation) misses Smith's masking of a Beckmann surface and the Beckmann density.
#[test]
fn ggx_stand_in_fails_the_beckmann_checks() {
    let beckmann = Microfacet::beckmann(0.5, 0.5);
    let ggx = Microfacet::ggx(0.5, 0.5);
    let w = direction(80f32.to_radians(), 0.0);
    let exact = smith_by_quadrature(&beckmann, w);
    let wrong = ggx.g1_visible(w, Vec3::Z) as f64;
    assert!((wrong - exact).abs() > 1e-2 * exact, "GGX G1 {wrong} vs Beckmann {exact}");
    // Density of GGX visible normals against the Beckmann pdf: rejected.
    let outcome = chi2_sphere(
        |rng: &mut Rng| Some(ggx.sample_visible(w, rng.uniform2())),
        |m| beckmann.visible_pdf(w, m) as f64,
        100_000,
        77,
        32,
        32,
    );
    assert!(outcome.p_value < 1e-6, "GGX samples pass as Beckmann: p = {}", outcome.p_value);
}

#[test]
fn beckmann_visible_normal_sampler_matches_its_pdf() {
    let significance = sidak(1e-3, 12);
    let mut seed = 60;
    for (ax, ay) in [(0.05f32, 0.05f32), (0.3, 0.3), (1.0, 0.2), (0.1, 0.6)] {
        let dist = Microfacet::beckmann(ax, ay);
        for theta_deg in [3.0f32, 50.0, 85.0] {
            let w = direction(theta_deg.to_radians(), 0.9);
            seed += 1;
            let outcome = chi2_sphere(
                |rng: &mut Rng| Some(dist.sample_visible(w, rng.uniform2())),
                |m| dist.visible_pdf(w, m) as f64,
                100_000,
                seed,
                32,
                32,
            );
            assert_chi2(&outcome, significance, &format!("Beckmann visible normals α {ax}×{ay}, θ {theta_deg}"));
            assert!((outcome.pdf_integral - 1.0).abs() < 2e-3, "∫ D_w = {}", outcome.pdf_integral);
        }
    }
}
