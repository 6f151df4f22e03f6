//! The closed forms against pbrt's random walk (`layered_walk`), which estimates the same
//! expectation independently, and the walk's reciprocity in expectation.

use math::{Rng, Vec3};
use spectrum::Rgb;

use super::Coated;
use crate::material::coated_parameters::{CoatedBase, CoatedParameters, CoatingInterface, CoatingLayer, ConductorIor};
use crate::texture::{Texture, TexturePoint};

fn model(alpha: f32, layer: CoatingLayer, base: CoatedBase) -> Coated {
    let interface = CoatingInterface { eta: 1.5, alpha_u: alpha, alpha_v: alpha };
    let p = CoatedParameters::new(interface, layer, base).unwrap();
    Coated::new(&p, TexturePoint { uv: math::Vec2::ZERO, attribute: Rgb::BLACK })
}

fn at(theta_degrees: f32, azimuth: f32) -> Vec3 {
    let t = theta_degrees.to_radians();
    Vec3::new(t.sin() * azimuth.cos(), t.sin() * azimuth.sin(), t.cos())
}

/// Mean and standard error per channel of `n` walks for the pair, each with its own stream.
fn walk_mean(m: &Coated, wo: Vec3, wi: Vec3, n: u64, seed: u64) -> ([f64; 3], [f64; 3]) {
    let (mut sum, mut sq) = ([0.0f64; 3], [0.0f64; 3]);
    for i in 0..n {
        let v = m.layers.estimate(wo, wi, &mut Rng::for_stream(seed, i, 0)).to_array();
        for c in 0..3 {
            sum[c] += v[c] as f64;
            sq[c] += (v[c] as f64).powi(2);
        }
    }
    let mean = sum.map(|s| s / n as f64);
    let error = std::array::from_fn(|c| ((sq[c] / n as f64 - mean[c] * mean[c]).max(0.0) / n as f64).sqrt());
    (mean, error)
}

/// 4.5 standard errors: with the 3 channels × 12 comparisons below, a two-sided normal tail of
/// 7e-6 each, below 3e-4 in all.
const Z: f64 = 4.5;

#[test]
fn smooth_diffuse_closed_form_is_the_walks_expectation() {
    let rho = Rgb::new(0.9, 0.5, 0.15);
    let pairs = [(at(10.0, 0.0), at(30.0, 2.0)), (at(60.0, 1.0), at(5.0, 0.3)), (at(80.0, 0.0), at(75.0, 3.0))];
    for max_depth in [1, 3, 10, 100] {
        let layer = CoatingLayer { thickness: 0.3, max_depth, ..CoatingLayer::default() };
        let m = model(0.0, layer, CoatedBase::Diffuse { reflectance: Texture::Constant(rho) });
        for (k, (wo, wi)) in pairs.into_iter().enumerate() {
            let exact = m.smooth_diffuse(wo, wi, rho).to_array();
            let (mean, error) = walk_mean(&m, wo, wi, 40_000, 7 + k as u64);
            for c in 0..3 {
                let e = exact[c] as f64;
                assert!(
                    (mean[c] - e).abs() <= Z * error[c] + 1e-7,
                    "maxdepth {max_depth} pair {k} channel {c}: walk {} ± {} vs closed form {e}",
                    mean[c],
                    error[c]
                );
                // Power: a 3 % error of the closed form would be detected.
                assert!(0.03 * e > 2.0 * Z * error[c], "maxdepth {max_depth}: the test cannot see 3 % ({})", error[c]);
            }
        }
    }
}

#[test]
fn walk_is_reciprocal_in_expectation() {
    let layer = CoatingLayer {
        thickness: 0.5,
        albedo: Texture::Constant(Rgb::new(0.8, 0.5, 0.3)),
        g: 0.4,
        max_depth: 10,
        samples: 1,
    };
    let base = CoatedBase::Conductor {
        ior: ConductorIor::Complex { eta: Rgb::new(0.2, 0.9, 1.1), k: Rgb::new(3.9, 2.4, 2.2) },
        alpha_u: 0.2,
        alpha_v: 0.2,
    };
    let m = model(0.3, layer, base);
    for (k, (a, b)) in [(at(20.0, 0.0), at(50.0, 2.5)), (at(70.0, 1.0), at(10.0, 0.1))].into_iter().enumerate() {
        let (x, ex) = walk_mean(&m, a, b, 40_000, 100 + k as u64);
        let (y, ey) = walk_mean(&m, b, a, 40_000, 200 + k as u64);
        for c in 0..3 {
            let sigma = (ex[c] * ex[c] + ey[c] * ey[c]).sqrt();
            assert!((x[c] - y[c]).abs() <= Z * sigma, "pair {k} channel {c}: {} vs {} (σ {sigma})", x[c], y[c]);
        }
    }
}

/// Means of `n` walks with our weights and with pbrt-v4's, each against a walk that only
/// connects through the presampled exit (no weights: an unbiased reference).
#[test]
fn walk_weights_of_pbrt_are_biased_under_a_rough_top() {
    let base = CoatedBase::Diffuse { reflectance: Texture::Constant(Rgb::splat(0.7)) };
    let layer = CoatingLayer { thickness: 0.5, max_depth: 100, ..CoatingLayer::default() };
    let m = model(0.3, layer, base);
    let (wo, wi) = (at(20.0, 0.0), at(50.0, 2.5));
    let n = 40_000u64;
    let mean = |f: &dyn Fn(&mut Rng) -> f32, seed: u64| {
        let values: Vec<f64> = (0..n).map(|i| f(&mut Rng::for_stream(seed, i, 0)) as f64).collect();
        let mean = values.iter().sum::<f64>() / n as f64;
        let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
        (mean, (var / n as f64).sqrt())
    };
    let ours = mean(&|r| m.layers.estimate(wo, wi, r).r, 1);
    let ours_reversed = mean(&|r| m.layers.estimate(wi, wo, r).r, 2);
    let pbrt = mean(&|r| m.layers.estimate_with_pbrt_weights(wo, wi, r).r, 3);
    let pbrt_reversed = mean(&|r| m.layers.estimate_with_pbrt_weights(wi, wo, r).r, 4);
    let apart = |a: (f64, f64), b: (f64, f64)| (a.0 - b.0).abs() / (a.1 * a.1 + b.1 * b.1).sqrt();
    println!("ours {ours:?} reversed {ours_reversed:?}; pbrt {pbrt:?} reversed {pbrt_reversed:?}");
    assert!(apart(ours, ours_reversed) < Z, "ours is reciprocal");
    assert!(apart(pbrt, ours) > Z && pbrt.0 > ours.0, "pbrt's weights are measurably too bright");
    assert!(apart(pbrt, pbrt_reversed) > Z, "pbrt's weights are not reciprocal");
}

/// A lossless medium over a perfect mirror under a smooth coating reflects everything: the
/// delta lobe (exact) plus the walk's scattered part, integrated by cosine sampling (the walk
/// estimate times π). pbrt's walk, which lacks the mirror chains, loses a quarter of it.
#[test]
fn pbrt_walk_loses_the_mirror_chains() {
    let layer =
        CoatingLayer { thickness: 0.7, albedo: Texture::Constant(Rgb::WHITE), g: -0.4, max_depth: 400, samples: 1 };
    let mirror = CoatedBase::Conductor {
        ior: ConductorIor::Complex { eta: Rgb::BLACK, k: Rgb::BLACK },
        alpha_u: 0.0,
        alpha_v: 0.0,
    };
    let m = model(0.0, layer, mirror);
    let wo = at(10.0, 0.3);
    let delta = m.delta_weight(wo).r as f64;
    let n = 100_000u64;
    let albedo = |pbrt: bool| {
        let mut stats = (0.0f64, 0.0f64);
        for i in 0..n {
            let mut rng = Rng::for_stream(31, i, pbrt as u64);
            let wi = math::warp::cosine_hemisphere(rng.uniform2());
            let v = if pbrt {
                m.layers.estimate_with_pbrt_weights(wo, wi, &mut rng)
            } else {
                m.layers.estimate(wo, wi, &mut rng)
            };
            let x = (v.r * math::PI) as f64;
            stats.0 += x;
            stats.1 += x * x;
        }
        let mean = stats.0 / n as f64;
        (delta + mean, ((stats.1 / n as f64 - mean * mean) / n as f64).sqrt())
    };
    let (ours, ours_error) = albedo(false);
    let (pbrt, pbrt_error) = albedo(true);
    println!("albedo: ours {ours} ± {ours_error}, pbrt {pbrt} ± {pbrt_error}");
    assert!((ours - 1.0).abs() <= Z * ours_error + 1e-4, "ours: {ours} ± {ours_error}");
    assert!(pbrt < 0.8 && pbrt > 0.7, "pbrt: {pbrt} ± {pbrt_error}");
}
