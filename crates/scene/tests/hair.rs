//! The hair BSDF through the public [`Bsdf`]: chi-square tests of its sampler against its pdf
//! (and a deliberately wrong pdf failing), sampled against evaluated values and pdfs, the
//! weights `f·|cos|/pdf`, mode-independent pdfs that swap, the exact adjoint, and the white
//! furnace through the integrators' convention (`value × cos_generated`).

use math::{Frame, Rng, Vec3};
use scene::material::HairParameters;
use scene::{Bsdf, Material, ShadingPoint, TransportMode};
use spectrum::Rgb;
use testkit::{Integration, MeanVar, assert_chi2, chi2_sphere_with, sidak};

const MODES: [TransportMode; 2] = [TransportMode::Radiance, TransportMode::Importance];

/// A point on a fibre along world `y`: normal `n`, `∂p/∂u` around the tube (so that the fibre
/// is `n × ∂p/∂u`), the shading normal tilted slightly when `tilted`.
fn fibre_point(tilted: bool) -> ShadingPoint {
    let n = Vec3::new(0.6, 0.0, 0.8);
    let around = Vec3::new(0.8, 0.0, -0.6);
    let shading = if tilted { (n + 0.1 * around).normalize() } else { n };
    ShadingPoint {
        geometric_normal: n,
        shading_normal: shading,
        uv: math::Vec2::ZERO,
        tangent: around,
        attribute: Rgb::BLACK,
    }
}

fn hair(sigma_a: Rgb, beta_m: f32, beta_n: f32) -> Material {
    Material::Hair(HairParameters { sigma_a, eta: 1.55, beta_m, beta_n, alpha: 2.0 })
}

fn cases() -> Vec<(&'static str, Material)> {
    vec![
        ("brown β 0.3", Material::Hair(HairParameters::default())),
        ("blonde β_m 0.15 β_n 0.4", hair(HairParameters::sigma_a_from_melanin(0.3, 0.1), 0.15, 0.4)),
        ("white β_m 0.6 β_n 0.8", hair(Rgb::BLACK, 0.6, 0.8)),
    ]
}

/// A unit direction on the normal's side of `point` at polar angle `theta` (degrees).
fn direction(point: &ShadingPoint, theta: f32, azimuth: f32) -> Vec3 {
    let t = theta.to_radians();
    Frame::from_z(point.geometric_normal)
        .to_world(Vec3::new(t.sin() * azimuth.cos(), t.sin() * azimuth.sin(), t.cos()))
        .normalize()
}

/// Bins finer than the sharpest lobe would need millions of samples; the pdf is smooth.
const INTEGRATION: Integration =
    Integration { initial_split: 2, max_depth: 5, abs_tolerance: 1e-5, rel_tolerance: 1e-3 };

/// The chi-square outcome of `material`'s sampler at `fixed` against `pdf` (a function of the
/// world direction), with 200 000 samples over 20 × 40 bins.
fn chi2(bsdf: &Bsdf, pdf: impl Fn(Vec3) -> f64, seed: u64) -> testkit::Chi2Outcome {
    chi2_sphere_with(
        |rng: &mut Rng| bsdf.sample(rng.uniform3()).map(|s| s.direction),
        pdf,
        200_000,
        seed,
        20,
        40,
        &INTEGRATION,
    )
}

#[test]
fn the_sampler_matches_its_pdf() {
    let point = fibre_point(false);
    let all = cases();
    let significance = sidak(1e-3, all.len() * 2);
    for (k, (name, material)) in all.iter().enumerate() {
        for (m, &theta) in [20.0f32, 70.0].iter().enumerate() {
            let mode = MODES[(k + m) % 2];
            let fixed = direction(&point, theta, 0.4);
            let bsdf = Bsdf::new(material, &point, fixed, mode).unwrap();
            let outcome = chi2(&bsdf, |w| bsdf.evaluate(w).map_or(0.0, |e| f64::from(e.pdf.forward.0)), 30 + k as u64);
            assert_chi2(&outcome, significance, &format!("{name} at {theta}° ({mode:?})"));
        }
    }
}

/// The chi-square test has power: the pdf of a slightly different hair (β_n 0.36 instead of
/// 0.3) is rejected for the default hair's sampler.
#[test]
fn a_wrong_pdf_fails_the_chi_square_test() {
    let point = fibre_point(false);
    let fixed = direction(&point, 40.0, 0.4);
    let bsdf = Bsdf::new(&Material::Hair(HairParameters::default()), &point, fixed, TransportMode::Radiance).unwrap();
    let other = Material::Hair(HairParameters { beta_n: 0.36, ..HairParameters::default() });
    let wrong = Bsdf::new(&other, &point, fixed, TransportMode::Radiance).unwrap();
    let outcome = chi2(&bsdf, |w| wrong.evaluate(w).map_or(0.0, |e| f64::from(e.pdf.forward.0)), 40);
    assert!(!outcome.passed(1e-3), "the wrong pdf passed: p = {}", outcome.p_value);
}

/// Sampled values and pdfs equal evaluated ones; the sample weight `f cos/pdf` is the
/// evaluation-based one; pdfs do not depend on the mode and swap with the pair; the value in
/// importance mode for (b, a) is the radiance value for (a, b) (also with a tilted shading
/// normal); evaluation is deterministic; the continuation probability does not depend on the
/// fixed direction.
#[test]
fn sampled_and_evaluated_agree_and_the_adjoint_is_exact() {
    let mut rng = Rng::for_stream(9, 0, 0);
    let close = |a: f32, b: f32, tol: f32| (a - b).abs() <= tol * a.abs().max(b.abs()) + 1e-7;
    for point in [fibre_point(false), fibre_point(true)] {
        for (name, material) in cases() {
            let mut pairs = 0;
            let mut continuation = None;
            for theta in [10.0f32, 45.0, 80.0] {
                for mode in MODES {
                    let fixed = direction(&point, theta, 2.0);
                    let bsdf = Bsdf::new(&material, &point, fixed, mode).unwrap();
                    let c = bsdf.continuation_probability();
                    assert!(c > 0.0 && c <= 1.0, "{name}: continuation {c}");
                    // The same for every fixed direction (VCM's recursive weights need it).
                    assert_eq!(*continuation.get_or_insert(c), c, "{name}: continuation depends on the direction");
                    for _ in 0..200 {
                        let Some(s) = bsdf.sample(rng.uniform3()) else { continue };
                        let what = format!("{name} at {theta}° ({mode:?})");
                        let e = bsdf.evaluate(s.direction).expect("a sampled direction evaluates");
                        assert!(close(s.pdf.forward.0, e.pdf.forward.0, 1e-5), "{what}");
                        assert!(close(s.pdf.reverse.0, e.pdf.reverse.0, 1e-5), "{what}");
                        assert!(close(s.value.g, e.value.g, 1e-5), "{what}: value");
                        let weight = s.value.g * s.cos_generated / s.pdf.forward.0;
                        assert!(close(weight, e.value.g * e.cos_generated / e.pdf.forward.0, 1e-5), "{what}");
                        let other = if mode == TransportMode::Radiance {
                            TransportMode::Importance
                        } else {
                            TransportMode::Radiance
                        };
                        if let Some(same) =
                            Bsdf::new(&material, &point, fixed, other).and_then(|b| b.evaluate(s.direction))
                        {
                            assert!(close(same.pdf.forward.0, e.pdf.forward.0, 1e-6), "{what}: pdf depends on mode");
                            assert!(close(same.pdf.reverse.0, e.pdf.reverse.0, 1e-6), "{what}: pdf depends on mode");
                        }
                        let Some(r) = Bsdf::new(&material, &point, s.direction, mode).and_then(|b| b.evaluate(fixed))
                        else {
                            continue;
                        };
                        assert!(close(e.pdf.forward.0, r.pdf.reverse.0, 1e-4), "{what}: {:?} vs {:?}", e.pdf, r.pdf);
                        assert!(close(e.pdf.reverse.0, r.pdf.forward.0, 1e-4), "{what}: {:?} vs {:?}", e.pdf, r.pdf);
                        let adjoint =
                            Bsdf::new(&material, &point, s.direction, other).unwrap().evaluate(fixed).unwrap();
                        assert!(
                            close(e.value.r, adjoint.value.r, 1e-4),
                            "{what}: {:?} vs {:?}",
                            e.value,
                            adjoint.value
                        );
                        assert_eq!(bsdf.evaluate(s.direction), Some(e), "{what}: not deterministic");
                        pairs += 1;
                    }
                }
            }
            assert!(pairs > 500, "{name}: only {pairs} pairs");
        }
    }
}

/// The integrators' estimate `value × cos_generated / pdf` of the directional albedo is 1
/// without absorption (flat tube, radiance mode), within 4 standard errors.
#[test]
fn white_furnace_through_the_bsdf() {
    let point = fibre_point(false);
    let material = hair(Rgb::BLACK, 0.3, 0.3);
    let mut rng = Rng::for_stream(10, 0, 0);
    for theta in [15.0f32, 60.0, 85.0] {
        let fixed = direction(&point, theta, 1.0);
        let bsdf = Bsdf::new(&material, &point, fixed, TransportMode::Radiance).unwrap();
        let mut estimate = MeanVar::new();
        for _ in 0..50_000 {
            let w =
                bsdf.sample(rng.uniform3()).map_or(0.0, |s| f64::from(s.value.g * s.cos_generated / s.pdf.forward.0));
            estimate.push(w);
        }
        // Directions within COSINE_EPSILON of the tangent planes are dropped: a loss far
        // below the tolerance.
        let (mean, se) = (estimate.mean(), estimate.std_error());
        assert!((mean - 1.0).abs() < 4.0 * se + 1e-4, "{theta}°: {mean} ± {se}");
    }
}
