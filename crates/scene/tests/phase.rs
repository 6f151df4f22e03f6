//! Phase functions: the Henyey–Greenstein and isotropic samplers against their pdfs by a
//! chi-square test (several `g`, fixed directions off the poles), the pdf against the sample's
//! reported pdf, normalisation, and a deliberately wrong sampler that the test rejects.

use math::{Rng, Vec3};
use scene::medium::PhaseFunction;
use testkit::{assert_chi2, chi2_sphere, sidak};

const SAMPLES: usize = 400_000;

fn phases() -> Vec<PhaseFunction> {
    let mut p = vec![PhaseFunction::Isotropic];
    for g in [-0.7, -0.2, 0.3, 0.8, 0.95] {
        p.push(PhaseFunction::henyey_greenstein(g).unwrap());
    }
    p
}

fn fixed() -> Vec3 {
    Vec3::new(0.3, -0.5, 0.81).normalize()
}

#[test]
fn samplers_match_their_pdfs() {
    let phases = phases();
    for (index, phase) in phases.iter().enumerate() {
        let fixed = fixed();
        let outcome = chi2_sphere(
            |rng: &mut Rng| {
                let s = phase.sample(fixed, rng.uniform2());
                let expected = phase.evaluate(fixed, s.direction);
                assert!((s.pdf - expected).abs() <= 1e-4 * expected, "sample pdf {} vs {expected}", s.pdf);
                Some(s.direction)
            },
            |d| f64::from(phase.evaluate(fixed, d)),
            SAMPLES,
            index as u64,
            32,
            64,
        );
        assert_chi2(&outcome, sidak(1e-3, phases.len()), &format!("{phase:?}"));
    }
}

#[test]
fn a_sampler_with_the_wrong_g_fails() {
    // Sampling with g = 0.33 but reporting the pdf of g = 0.3: a 10 % error in g.
    let (truth, wrong) =
        (PhaseFunction::henyey_greenstein(0.3).unwrap(), PhaseFunction::henyey_greenstein(0.33).unwrap());
    let fixed = fixed();
    let outcome = chi2_sphere(
        |rng: &mut Rng| Some(wrong.sample(fixed, rng.uniform2()).direction),
        |d| f64::from(truth.evaluate(fixed, d)),
        SAMPLES,
        7,
        32,
        64,
    );
    assert!(!outcome.passed(1e-3), "the chi-square test did not notice a wrong g: p = {}", outcome.p_value);
}

#[test]
fn values_are_symmetric_and_normalised() {
    let phase = PhaseFunction::henyey_greenstein(0.6).unwrap();
    let (a, b) = (fixed(), Vec3::new(-0.2, 0.9, 0.1).normalize());
    assert!((phase.evaluate(a, b) - phase.evaluate(b, a)).abs() < 1e-6);
    // ∫ p dω = 2π ∫ p(cos θ) d cos θ by the midpoint rule on 20000 intervals.
    let n = 20_000;
    let integral: f64 = (0..n)
        .map(|i| {
            let cos_theta = -1.0 + (2.0 * i as f64 + 1.0) / n as f64;
            let generated = Vec3::new((1.0 - cos_theta * cos_theta).sqrt() as f32, 0.0, cos_theta as f32);
            f64::from(phase.evaluate(-Vec3::Z, generated)) * 2.0 / n as f64
        })
        .sum::<f64>()
        * std::f64::consts::TAU;
    assert!((integral - 1.0).abs() < 1e-3, "{integral}");
}
