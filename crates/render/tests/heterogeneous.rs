//! Heterogeneous (grid) media against closed forms:
//!
//! - ratio tracking and delta tracking (with the majorant grid and with the global majorant
//!   only) through a linear density ramp (trilinear interpolation
//!   of a grid whose values grow linearly along x is exactly linear between the first and last
//!   voxel centres): the mean transmittance estimate, and the probability-weighted pass-through
//!   of delta tracking with the spectral MIS on a chromatic grid, equal
//!   `exp(−∫σ_t) = exp(−(n(b² − a²)/2 − (b − a)/2)·k)` per channel;
//! - the furnace: an albedo-1 heterogeneous, chromatic medium in an index-matched sphere under a
//!   uniform environment of radiance 1 gives radiance 1 on every ray, RGB and spectral.
//!
//! Every check compares a mean with its standard error (fixed seeds, |z| < 4.5) and shows that
//! the same data reject a truth scaled by 1.02 (tracking) or 1.03 (furnace).

use crate::common;

use std::sync::Arc;

use common::medium_sphere::{View, medium_sphere};
use math::{Ray, Rng, Vec3};
use render::path_tracer::PathTracer;
use scene::Scene;
use scene::instance::Affine3A;
use scene::medium::{Coefficient, Coefficients, Filter, Grid, Heterogeneous, Medium, Outside, PhaseFunction, Volume};
use spectrum::Rgb;

const Z_LIMIT: f64 = 4.5;

/// Running sums of a per-channel estimator against a truth and a scaled truth.
struct Stats {
    n: f64,
    sums: [[f64; 4]; 3],
}

impl Stats {
    fn new() -> Self {
        Self { n: 0.0, sums: [[0.0; 4]; 3] }
    }

    fn add(&mut self, estimate: [f32; 3], truth: [f32; 3], bias: f32) {
        self.n += 1.0;
        for c in 0..3 {
            let d = f64::from(estimate[c] - truth[c]);
            let b = f64::from(estimate[c] - bias * truth[c]);
            let s = &mut self.sums[c];
            s[0] += d;
            s[1] += d * d;
            s[2] += b;
            s[3] += b * b;
        }
    }

    fn check(&self, what: &str) {
        let z = |sum: f64, squares: f64| {
            let mean = sum / self.n;
            mean / ((squares / self.n - mean * mean).max(1e-30) / (self.n - 1.0)).sqrt()
        };
        for (c, s) in self.sums.iter().enumerate() {
            let (z, z_biased) = (z(s[0], s[1]), z(s[2], s[3]));
            assert!(z.abs() < Z_LIMIT, "{what}, channel {c}: z = {z:.2} against the truth");
            assert!(z_biased.abs() > Z_LIMIT, "{what}, channel {c}: the biased truth passes (z = {z_biased:.2})");
        }
    }
}

/// A grid of `n` voxels along x (1 along y and z) with value `i` (times `tint` per channel
/// when `tint` is given, as a 3-channel grid) at voxel `i`, on the world box [0, 1]³.
fn ramp_medium(n: usize, tint: Option<Rgb>, scale: f32, majorant_grid: bool) -> Medium {
    let values: Vec<f32> = match tint {
        None => (0..n).map(|i| i as f32).collect(),
        Some(t) => (0..n).flat_map(|i| [i as f32 * t.r, i as f32 * t.g, i as f32 * t.b]).collect(),
    };
    let channels = if tint.is_some() { 3 } else { 1 };
    let grid = Grid::new([n, 1, 1], channels, values).unwrap();
    let sigma_t = Volume {
        grid: Some(Arc::new(grid)),
        value: Coefficient::rgb(Rgb::splat(1.0)),
        to_local: Affine3A::IDENTITY,
        filter: Filter::Trilinear,
        outside: Outside::Clamp,
    };
    let albedo = Volume::constant(Coefficient::rgb(Rgb::splat(0.5)), Affine3A::IDENTITY);
    let h = Heterogeneous::new(sigma_t, albedo, None, Affine3A::IDENTITY);
    let h = if majorant_grid { h } else { h.without_majorant_grid() };
    Medium { coefficients: Coefficients::Heterogeneous(Arc::new(h)), scale, phase: PhaseFunction::Isotropic }
}

/// `exp(−scale·k·∫_a^b (n x − ½) dx)` for the ramp's linear part.
fn ramp_transmittance(n: usize, a: f32, b: f32, k: f32, scale: f32) -> f32 {
    let n = n as f32;
    (-(n * (b * b - a * a) / 2.0 - (b - a) / 2.0) * k * scale).exp()
}

#[test]
fn ratio_tracking_matches_the_analytic_transmittance() {
    let (n, scale) = (8, 0.4);
    for majorant_grid in [true, false] {
        let medium = ramp_medium(n, None, scale, majorant_grid);
        let h = medium.heterogeneous().unwrap();
        let tracker = h.tracker::<Rgb>(medium.scale, &());
        assert_eq!(tracker.majorant(), 7.0 * scale);
        // Along x at y = z = 0.5 from x = 0.1 to x = 0.9, inside the linear part [1/16, 15/16].
        let (a, b) = (0.1, 0.9);
        let truth = ramp_transmittance(n, a, b, 1.0, scale);
        let origin = Vec3::new(0.0, 0.5, 0.5);
        let mut stats = Stats::new();
        for i in 0..100_000 {
            let mut rng = Rng::for_stream(11, 0, i);
            let t = tracker.transmittance(origin, Vec3::X, a, b, &mut rng, &());
            stats.add(t.to_array(), [truth; 3], 1.02);
        }
        stats.check(&format!("ratio tracking, majorant grid {majorant_grid}"));
        // A segment outside the region transmits exactly 1.
        let mut rng = Rng::new(1, 1);
        let outside = tracker.transmittance(Vec3::new(0.0, 2.0, 0.5), Vec3::X, 0.0, 1.0, &mut rng, &());
        assert_eq!(outside, Rgb::splat(1.0));
    }
}

/// Delta tracking with the spectral MIS on a chromatic ramp: over many paths, each with its
/// own channel, the weight of passing through (zero when the path scattered) has mean T per
/// channel.
#[test]
fn delta_tracking_is_unbiased_per_channel() {
    let (n, scale) = (8, 0.3);
    let tint = Rgb::new(0.3, 1.0, 1.8);
    for majorant_grid in [true, false] {
        let medium = ramp_medium(n, Some(tint), scale, majorant_grid);
        let h = medium.heterogeneous().unwrap();
        let tracker = h.tracker::<Rgb>(medium.scale, &());
        let (a, b) = (0.1, 0.9);
        let truth = tint.map(|k| ramp_transmittance(n, a, b, k, scale)).to_array();
        let origin = Vec3::new(a, 0.5, 0.5);
        let mut stats = Stats::new();
        for i in 0..1_000_000 {
            let mut rng = Rng::for_stream(12, 0, i);
            let channel = (rng.uniform() * 3.0) as usize;
            let mut ratios = Rgb::splat(1.0);
            let flight = tracker.sample_distance(origin, Vec3::X, b - a, channel.min(2), &mut rng, &mut ratios, &());
            let passed = if flight.scattered { Rgb::BLACK } else { flight.weight };
            stats.add(passed.to_array(), truth, 1.02);
        }
        stats.check(&format!("delta tracking, chromatic, majorant grid {majorant_grid}"));
    }
}

/// The unit sphere of `medium` seen from (0, 0, −5) under a uniform environment of radiance 1.
fn sphere_scene(medium: Medium) -> Scene {
    let view = View { position: Vec3::new(0.0, 0.0, -5.0), inside: false, fov_degrees: 30.0, resolution: 4 };
    medium_sphere(medium, view, false)
}

/// A chromatic 4×4×4 grid (values 0.2 … 4.1, varying per channel) over [−1, 1]³, albedo 1
/// (or, with `direct_sigma_s`, σ_s given as the same grid, as pbrt's `rgbgrid` does).
fn furnace_medium(direct_sigma_s: bool) -> Medium {
    let values: Vec<f32> = (0..64)
        .flat_map(|i| {
            let v = 0.2 + ((i * 37) % 64) as f32 / 16.0;
            [v, 0.5 * v + 0.3, 2.0 - v.min(1.8)]
        })
        .collect();
    let to_world = Affine3A::from_translation(Vec3::splat(-1.0)) * Affine3A::from_scale(Vec3::splat(2.0));
    let sigma_t = Volume {
        grid: Some(Arc::new(Grid::new([4, 4, 4], 3, values).unwrap())),
        value: Coefficient::rgb(Rgb::splat(1.0)),
        to_local: to_world.inverse(),
        filter: Filter::Trilinear,
        outside: Outside::Clamp,
    };
    let albedo = Volume::constant(Coefficient::rgb(Rgb::splat(1.0)), Affine3A::IDENTITY);
    let sigma_s = direct_sigma_s.then(|| sigma_t.clone());
    let h = Heterogeneous::new(sigma_t, albedo, sigma_s, to_world.inverse());
    Medium {
        coefficients: Coefficients::Heterogeneous(Arc::new(h)),
        scale: 1.5,
        phase: PhaseFunction::henyey_greenstein(0.5).unwrap(),
    }
}

#[test]
fn heterogeneous_furnace_conserves_energy() {
    for (direct, spectral) in [(false, false), (false, true), (true, false)] {
        let scene = sphere_scene(furnace_medium(direct));
        assert!(scene.media.has_heterogeneous());
        let tracer = PathTracer { spectral, ..PathTracer::new(u32::MAX) };
        let mut stats = Stats::new();
        for i in 0..200_000 {
            let mut rng = Rng::for_stream(13, 0, i);
            let (u, v) = (rng.uniform(), rng.uniform());
            let b = 0.95 * u.sqrt();
            let phi = std::f32::consts::TAU * v;
            let ray = Ray::new(Vec3::new(b * phi.cos(), b * phi.sin(), -5.0), Vec3::Z);
            let estimate = tracer.radiance(&scene, ray, &mut rng);
            stats.add(estimate.to_array(), [1.0; 3], 1.03);
        }
        stats.check(&format!("heterogeneous furnace, spectral {spectral}, direct σ_s {direct}"));
    }
}

#[test]
fn every_algorithm_but_the_eye_light_renders_grid_media() {
    use render::driver::{Algorithm, RenderSettings, Renderer};
    use render::vcm::VcmAlgorithm;
    let scene = sphere_scene(furnace_medium(false));
    for algorithm in [
        Algorithm::PathTracing,
        Algorithm::Vcm(VcmAlgorithm::LightTracing),
        Algorithm::Vcm(VcmAlgorithm::BidirectionalPathTracing),
        Algorithm::Vcm(VcmAlgorithm::VertexConnectionMerging),
    ] {
        let settings = RenderSettings { algorithm, threads: 1, ..RenderSettings::default() };
        assert!(Renderer::new(&scene, &settings).is_ok(), "{algorithm:?}");
    }
    let settings = RenderSettings { algorithm: Algorithm::EyeLight, threads: 1, ..RenderSettings::default() };
    let error = Renderer::new(&scene, &settings).err().expect("the eye light refuses media");
    assert!(error.contains("media are rendered by pt"), "{error}");
}
