//! Unit tests of the hair model in its local frame (y along the fibre, z the normal).

use super::*;
use math::Rng;

fn params(sigma_a: Rgb, beta_m: f32, beta_n: f32, alpha: f32) -> HairParameters {
    HairParameters { sigma_a, eta: 1.55, beta_m, beta_n, alpha }
}

/// A uniformly distributed unit vector.
fn uniform_sphere(rng: &mut Rng) -> Vec3 {
    let z = 1.0 - 2.0 * rng.uniform();
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * rng.uniform();
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// A camera-side direction on the normal's side (the fixed direction of a radiance query).
fn front(rng: &mut Rng) -> Vec3 {
    let w = uniform_sphere(rng);
    Vec3::new(w.x, w.y, w.z.abs().max(0.05)).normalize()
}

/// Monte Carlo estimate of `∫ f |cos θ_i| dω_i = ∫ S dω_i` (`dω = d(sin θ) dφ`): the mean of
/// [`REPLICATES`] independent jittered-grid estimates (`GRID × 3 GRID` strata of `sin θ_i × φ_i`), and
/// its standard error from their spread, per channel.
fn furnace(hair: &Hair, wo: Vec3, rng: &mut Rng) -> ([f64; 3], [f64; 3]) {
    let p = [1.0, 0.0];
    let cell = (2.0 / GRID as f64) * (2.0 * std::f64::consts::PI / (3 * GRID) as f64);
    let estimates: Vec<[f64; 3]> = (0..REPLICATES)
        .map(|_| {
            let mut sum = [0.0f64; 3];
            for i in 0..GRID {
                for j in 0..3 * GRID {
                    let sin_theta = -1.0 + 2.0 * (i as f32 + rng.uniform()) / GRID as f32;
                    let phi = 2.0 * PI * (j as f32 + rng.uniform()) / (3 * GRID) as f32;
                    let cos_theta = (1.0 - sin_theta * sin_theta).max(0.0).sqrt();
                    let wi = Vec3::new(cos_theta * phi.sin(), sin_theta, cos_theta * phi.cos());
                    let e = hair.evaluate(wo, wi, TransportMode::Radiance, p, p);
                    let x = (e.value * wi.z.abs()).to_array();
                    for c in 0..3 {
                        sum[c] += f64::from(x[c]) * cell;
                    }
                }
            }
            sum
        })
        .collect();
    let k = REPLICATES as f64;
    let mean = [0, 1, 2].map(|c| estimates.iter().map(|e| e[c]).sum::<f64>() / k);
    let se =
        [0, 1, 2].map(|c| (estimates.iter().map(|e| (e[c] - mean[c]).powi(2)).sum::<f64>() / (k - 1.0) / k).sqrt());
    (mean, se)
}

/// Strata in `sin θ` of one furnace estimate (three times as many in φ).
const GRID: usize = 120;
/// Independent estimates whose spread gives the standard error.
const REPLICATES: usize = 12;

/// White furnace (pbrt-v4's test idea): without absorption, `∫ S dω_i = 1` for random `wo` on
/// a grid of roughnesses, within 4 standard errors (each below 0.3 %, so that a 1 % error in
/// the normalisation would fail); with absorption it equals the analytic `Σ A_p < 1`.
#[test]
fn white_furnace_conserves_energy() {
    let mut rng = Rng::for_stream(14, 0, 0);
    for beta_m in [0.2f32, 0.5, 1.0] {
        for beta_n in [0.2f32, 0.5, 1.0] {
            let hair = Hair::new(&params(Rgb::BLACK, beta_m, beta_n, 2.0));
            let wo = front(&mut rng);
            let (mean, se) = furnace(&hair, wo, &mut rng);
            let what = format!("β_m {beta_m} β_n {beta_n}: {} ± {}", mean[1], se[1]);
            assert!((mean[1] - 1.0).abs() < 4.0 * se[1] + 1e-5, "{what}");
            assert!(se[1] < 0.003 && (1.01 * mean[1] - 1.0).abs() > 4.0 * se[1], "{what}: no power");
            assert!((hair.total_attenuation(wo) - Rgb::WHITE).max_component().abs() < 1e-5);
        }
    }
    let hair = Hair::new(&params(Rgb::new(0.1, 0.5, 2.0), 0.4, 0.4, 2.0));
    let wo = front(&mut rng);
    let (mean, se) = furnace(&hair, wo, &mut rng);
    let albedo = hair.total_attenuation(wo).to_array();
    for c in 0..3 {
        assert!(albedo[c] < 0.999 && (mean[c] - f64::from(albedo[c])).abs() < 4.0 * se[c] + 1e-5, "{c}: {mean:?}");
    }
    assert!(albedo[0] > albedo[1] && albedo[1] > albedo[2], "more absorption, less albedo: {albedo:?}");
}

/// Without absorption the sampler's weight `S/pdf` is exactly 1 (the lobe weights are the
/// `A_p`), and the sampled directions carry the pdf that evaluation reports.
#[test]
fn sampled_weights_are_one_without_absorption() {
    let mut rng = Rng::for_stream(15, 0, 0);
    for (beta_m, beta_n) in [(0.1f32, 0.1f32), (0.3, 0.3), (0.8, 0.6)] {
        let hair = Hair::new(&params(Rgb::BLACK, beta_m, beta_n, 3.0));
        for _ in 0..2000 {
            let wo = front(&mut rng);
            let Some(wi) = hair.sample_direction(wo, rng.uniform3()) else { panic!("no sample") };
            assert!((wi.length() - 1.0).abs() < 1e-4);
            let s = hair.scattering(wo, wi).g;
            let pdf = hair.pdf(wo, wi);
            assert!(pdf > 0.0, "{wo} → {wi}");
            assert!((s / pdf - 1.0).abs() < 1e-3, "β {beta_m}/{beta_n}: S {s} pdf {pdf}");
        }
    }
}

/// The frame convention: with no tilt, little roughness and a hair that absorbs everything
/// that enters, all light is the R lobe, mirrored about the normal (`θ_i = −θ_o`,
/// `φ_i = −φ_o`): the sign of `h` matches the azimuth.
#[test]
fn the_r_lobe_is_the_mirror_direction() {
    let hair = Hair::new(&params(Rgb::splat(1e4), 0.05, 0.05, 0.0));
    let mut rng = Rng::for_stream(16, 0, 0);
    for _ in 0..200 {
        let wo = front(&mut rng);
        let mirror = Vec3::new(-wo.x, -wo.y, wo.z);
        let wi = hair.sample_direction(wo, rng.uniform3()).unwrap();
        assert!(wi.dot(mirror) > 0.99, "{wo}: sampled {wi}, mirror {mirror}");
    }
}

/// Reciprocity: `M_p` is symmetric without tilt, but `S` is not (A_p and h depend on `wo`
/// only, and the tilt rotates `θ_o`): the model is not reciprocal, which the mixture's exact
/// adjoint handles (see the module documentation).
#[test]
fn what_is_and_is_not_reciprocal() {
    use super::super::hair_functions::longitudinal;
    let (a, b) = (0.3f32, -0.7f32);
    let m = |x: f32, y: f32| longitudinal(x.cos(), y.cos(), x.sin(), y.sin(), 0.05);
    assert!((m(a, b) - m(b, a)).abs() <= 1e-6 * m(a, b));
    let hair = Hair::new(&params(Rgb::new(0.3, 0.3, 0.3), 0.3, 0.3, 2.0));
    let wo = Vec3::new(0.5, 0.2, 0.8).normalize();
    let wi = Vec3::new(-0.1, -0.3, 0.9).normalize();
    let (s1, s2) = (hair.scattering(wo, wi).g, hair.scattering(wi, wo).g);
    assert!((s1 - s2).abs() > 1e-3 * s1, "S happens to be symmetric here: {s1} {s2}");
}

/// The colour and melanin parametrisations: σ_a from a colour decreases with the colour and is
/// zero for white; pbrt's default is eumelanin 1.3; validation rejects out-of-range values.
#[test]
fn parameters_map_and_validate() {
    let dark = HairParameters::sigma_a_from_color(Rgb::splat(0.1), 0.3);
    let light = HairParameters::sigma_a_from_color(Rgb::splat(0.8), 0.3);
    assert!(dark.g > light.g && light.g > 0.0);
    assert_eq!(HairParameters::sigma_a_from_color(Rgb::WHITE, 0.3), Rgb::BLACK);
    assert_eq!(HairParameters::default().sigma_a, EUMELANIN_SIGMA_A * 1.3);
    assert!(HairParameters::default().validate().is_ok());
    assert!(params(Rgb::BLACK, 1.5, 0.3, 2.0).validate().unwrap_err().contains("beta_m"));
    assert!(params(Rgb::splat(-1.0), 0.3, 0.3, 2.0).validate().unwrap_err().contains("sigma_a"));
}
