//! pbrt-v4's coated materials through the public BSDF: chi-square tests of the sampler against
//! its (deterministic) pdf, agreement of sampled and evaluated values and pdfs, the swap of
//! forward and reverse pdfs, the exact adjoint relation, energy bounds, a lossless furnace
//! (albedo exactly 1), and the smooth conductor's closed-form delta weight against the random
//! walk over a nearly smooth conductor.

use math::{Frame, Rng, Vec3};
use scene::material::{CoatedBase, CoatedParameters, CoatingInterface, CoatingLayer, ConductorIor};
use scene::{Bsdf, LobeKind, Material, ShadingPoint, Texture, TransportMode};
use spectrum::Rgb;
use testkit::{Integration, MeanVar, assert_chi2, chi2_sphere_with, sidak};

const MODES: [TransportMode; 2] = [TransportMode::Radiance, TransportMode::Importance];

fn constant(c: Rgb) -> Texture {
    Texture::Constant(c)
}

fn coated(alpha: f32, layer: CoatingLayer, base: CoatedBase) -> Material {
    let interface = CoatingInterface { eta: 1.5, alpha_u: alpha, alpha_v: alpha };
    Material::Coated(Box::new(CoatedParameters::new(interface, layer, base).unwrap()))
}

fn diffuse_base(rho: Rgb) -> CoatedBase {
    CoatedBase::Diffuse { reflectance: constant(rho) }
}

/// Gold-like complex IOR (relative to air).
fn gold(alpha_u: f32, alpha_v: f32) -> CoatedBase {
    CoatedBase::Conductor {
        ior: ConductorIor::Complex { eta: Rgb::new(0.18, 0.42, 1.37), k: Rgb::new(3.42, 2.35, 1.77) },
        alpha_u,
        alpha_v,
    }
}

fn medium(albedo: Rgb, g: f32, thickness: f32) -> CoatingLayer {
    CoatingLayer { thickness, albedo: constant(albedo), g, ..CoatingLayer::default() }
}

fn cases() -> Vec<(&'static str, Material)> {
    let plain = CoatingLayer::default;
    vec![
        ("smooth coated diffuse", coated(0.0, plain(), diffuse_base(Rgb::new(0.6, 0.4, 0.2)))),
        ("rough coated diffuse α 0.3", coated(0.3, plain(), diffuse_base(Rgb::new(0.6, 0.4, 0.2)))),
        (
            "smooth coated diffuse, scattering",
            coated(0.0, medium(Rgb::new(0.9, 0.6, 0.3), 0.5, 0.4), diffuse_base(Rgb::splat(0.5))),
        ),
        ("smooth over rough gold α 0.2", coated(0.0, plain(), gold(0.2, 0.2))),
        ("rough α 0.2 over smooth gold", coated(0.2, plain(), gold(0.0, 0.0))),
        ("rough α 0.1 over rough gold 0.05 × 0.4", coated(0.1, medium(Rgb::splat(0.5), -0.3, 0.2), gold(0.05, 0.4))),
        ("smooth over smooth gold, scattering", coated(0.0, medium(Rgb::splat(0.8), 0.7, 0.3), gold(0.0, 0.0))),
    ]
}

fn tilted_point() -> ShadingPoint {
    let n = Vec3::new(0.3, -0.2, 0.9).normalize();
    let frame = Frame::from_z(n);
    ShadingPoint {
        geometric_normal: n,
        shading_normal: (n + 0.15 * frame.x - 0.05 * frame.y).normalize(),
        uv: math::Vec2::ZERO,
        tangent: frame.x,
        attribute: Rgb::BLACK,
    }
}

fn direction_at(normal: Vec3, theta_degrees: f32, azimuth: f32) -> Vec3 {
    let t = theta_degrees.to_radians();
    Frame::from_z(normal).to_world(Vec3::new(t.sin() * azimuth.cos(), t.sin() * azimuth.sin(), t.cos())).normalize()
}

const ANGLES: [f32; 3] = [5.0, 50.0, 80.0];

/// The pdfs jump at the horizon; coarser than the default integration (see bsdf_models.rs).
const INTEGRATION: Integration =
    Integration { initial_split: 2, max_depth: 4, abs_tolerance: 1e-5, rel_tolerance: 1e-3 };

/// Three cases (closed form with a delta lobe, rough walk over a medium, delta plus scattered
/// walk) at one angle: each pdf evaluation also runs the walk for the value, so every case at
/// every angle is in the slow tier.
#[test]
fn samplers_match_their_pdfs_and_delta_lobes_their_probabilities() {
    chi2_cases(&[0, 5, 6], &[50.0], 500);
}

#[test]
#[ignore = "slow: chi-square tests of every case at three angles (about 3 minutes)"]
fn samplers_match_their_pdfs_at_every_angle() {
    chi2_cases(&[0, 1, 2, 3, 4, 5, 6], &ANGLES, 700);
}

/// Chi-square tests of the cases numbered `which` at the polar angles `angles`, each case on a
/// thread of its own (the pdf integration runs a walk per evaluation, so a case takes seconds;
/// the outcome does not depend on the threads: each (case, angle) has its own seed index).
fn chi2_cases(which: &[usize], angles: &[f32], seed: u64) {
    let all: Vec<_> = cases().into_iter().enumerate().filter(|(i, _)| which.contains(i)).map(|(_, c)| c).collect();
    let significance = sidak(1e-3, all.len() * angles.len());
    std::thread::scope(|scope| {
        let handles: Vec<_> = all
            .iter()
            .enumerate()
            .map(|(k, (name, material))| {
                let first = seed + (k * angles.len()) as u64;
                scope.spawn(move || chi2_case(name, material, angles, first, significance))
            })
            .collect();
        for handle in handles {
            if let Err(panic) = handle.join() {
                std::panic::resume_unwind(panic);
            }
        }
    });
}

/// The chi-square tests of one case at the polar angles `angles`, with seed indices from
/// `first` on.
fn chi2_case(name: &str, material: &Material, angles: &[f32], first: u64, significance: f64) {
    let point = tilted_point();
    let n = point.shading_normal;
    let mut index = first;
    for &theta in angles {
        let mode = MODES[(index % 2) as usize];
        index += 1;
        let fixed = direction_at(point.geometric_normal, theta, 0.7);
        let bsdf = Bsdf::new(material, &point, fixed, mode).unwrap();
        let frame = Frame::from_z((2.0 * fixed.dot(n) * n - fixed).normalize());
        let mut delta: Option<(f32, u64)> = None;
        let samples = 100_000;
        let outcome = chi2_sphere_with(
            |rng: &mut Rng| {
                let s = bsdf.sample(rng.uniform3())?;
                if s.lobe.is_specular() {
                    assert_eq!(s.lobe, LobeKind::SpecularReflection);
                    let d = delta.get_or_insert((s.pdf.forward.0, 0));
                    assert!((d.0 - s.pdf.forward.0).abs() < 1e-6);
                    d.1 += 1;
                    return None;
                }
                Some(frame.to_local(s.direction))
            },
            |local| bsdf.evaluate(frame.to_world(local).normalize()).map_or(0.0, |e| e.pdf.forward.0 as f64),
            samples,
            index,
            24,
            32,
            &INTEGRATION,
        );
        let what = format!("{name} at {theta}° ({mode:?})");
        assert_chi2(&outcome, significance, &what);
        if let Some((p, count)) = delta {
            let p = p as f64;
            let sigma = (p * (1.0 - p) / samples as f64).sqrt();
            let freq = count as f64 / samples as f64;
            assert!((freq - p).abs() <= 5.0 * sigma + 1e-4, "{what}: delta chosen {freq}, probability {p}");
        }
    }
}

#[test]
fn sampled_and_evaluated_agree_pdfs_swap_and_the_adjoint_is_exact() {
    let point = tilted_point();
    let n = point.geometric_normal;
    let mut rng = Rng::for_stream(8, 0, 0);
    let close = |a: f32, b: f32, tol: f32| (a - b).abs() <= tol * a.abs().max(b.abs()) + 1e-7;
    for (name, material) in cases() {
        let mut pairs = 0;
        for theta in ANGLES {
            for mode in MODES {
                let fixed = direction_at(n, theta, 2.0);
                let bsdf = Bsdf::new(&material, &point, fixed, mode).unwrap();
                assert!(bsdf.continuation_probability() > 0.0 && bsdf.continuation_probability() <= 1.0);
                for _ in 0..300 {
                    let Some(s) = bsdf.sample(rng.uniform3()) else { continue };
                    if s.lobe.is_specular() {
                        continue;
                    }
                    let what = format!("{name} at {theta}° ({mode:?})");
                    let e = bsdf.evaluate(s.direction).expect("a sampled direction evaluates");
                    assert!(close(s.pdf.forward.0, e.pdf.forward.0, 1e-5), "{what}");
                    assert!(close(s.pdf.reverse.0, e.pdf.reverse.0, 1e-5), "{what}");
                    assert!(close(s.value.g, e.value.g, 1e-5), "{what}: value");
                    // The walk's estimate for the swapped pair may be zero (it is another
                    // random number); its pdfs are still checked whenever it is not.
                    let Some(r) = Bsdf::new(&material, &point, s.direction, mode).and_then(|b| b.evaluate(fixed))
                    else {
                        continue;
                    };
                    assert!(close(e.pdf.forward.0, r.pdf.reverse.0, 2e-3), "{what}: {:?} vs {:?}", e.pdf, r.pdf);
                    assert!(close(e.pdf.reverse.0, r.pdf.forward.0, 2e-3), "{what}: {:?} vs {:?}", e.pdf, r.pdf);
                    // The adjoint: radiance value(a → b) = importance value(b → a), the same
                    // walk (its random numbers depend on the pair in radiance order).
                    let other = if mode == TransportMode::Radiance {
                        TransportMode::Importance
                    } else {
                        TransportMode::Radiance
                    };
                    let adjoint = Bsdf::new(&material, &point, s.direction, other).unwrap().evaluate(fixed).unwrap();
                    assert!(close(e.value.r, adjoint.value.r, 1e-3), "{what}: {:?} vs {:?}", e.value, adjoint.value);
                    // What VCM's weights need: the same pdfs in both transport modes and on
                    // every evaluation (deterministic), whatever the walk's estimate.
                    // (The other mode's value is the walk of the swapped pair, possibly zero.)
                    if let Some(same) = Bsdf::new(&material, &point, fixed, other).unwrap().evaluate(s.direction) {
                        assert_eq!(same.pdf, e.pdf, "{what}: pdfs depend on the mode");
                    }
                    assert_eq!(bsdf.evaluate(s.direction), Some(e), "{what}: not deterministic");
                    pairs += 1;
                }
            }
        }
        // The smooth-over-smooth case samples its delta lobe most of the time.
        assert!(pairs > 200, "{name}: only {pairs} pairs");
    }
}

/// Directional albedo by sampling in importance mode: mean of `f cos / pdf` over `n` samples.
fn albedo(material: &Material, point: &ShadingPoint, fixed: Vec3, n: usize, seed: u64) -> (MeanVar, MeanVar) {
    let bsdf = Bsdf::new(material, point, fixed, TransportMode::Importance).unwrap();
    let mut rng = Rng::for_stream(seed, 0, 0);
    let (mut red, mut blue) = (MeanVar::new(), MeanVar::new());
    for _ in 0..n {
        let w = bsdf.sample(rng.uniform3()).map_or(Rgb::BLACK, |s| s.value * (s.cos_generated / s.pdf.forward.0));
        red.push(w.r as f64);
        blue.push(w.b as f64);
    }
    (red, blue)
}

#[test]
fn directional_albedo_never_exceeds_one() {
    let point = ShadingPoint::flat(Vec3::Z);
    for (k, (name, material)) in cases().into_iter().enumerate() {
        for theta in ANGLES {
            let (r, b) = albedo(&material, &point, direction_at(Vec3::Z, theta, 1.0), 20_000, k as u64);
            for s in [r, b] {
                let (mean, error) = (s.mean(), s.std_error());
                assert!(mean <= 1.0 + 4.0 * error, "{name} at {theta}°: {mean} ± {error}");
            }
        }
    }
}

/// A white base under a clear coating and a non-absorbing medium loses nothing: every
/// smooth-interface configuration reflects all the light (with enough events per walk).
/// A 3 % loss would be seen: the tolerance is 4.5 standard errors, checked below 1.5 %.
#[test]
fn lossless_coatings_reflect_everything() {
    let point = ShadingPoint::flat(Vec3::Z);
    let white = Rgb::WHITE;
    let lossless = |albedo: f32, g: f32, thickness: f32| CoatingLayer {
        thickness,
        albedo: constant(Rgb::splat(albedo)),
        g,
        max_depth: 400,
        samples: 1,
    };
    let materials = [
        ("no medium", coated(0.0, lossless(0.0, 0.0, 0.0), diffuse_base(white))),
        ("white medium g 0", coated(0.0, lossless(1.0, 0.0, 0.5), diffuse_base(white))),
        ("white medium g 0.6", coated(0.0, lossless(1.0, 0.6, 1.0), diffuse_base(white))),
        ("white medium over a mirror", coated(0.0, lossless(1.0, -0.4, 0.7), gold_mirror())),
    ];
    for (k, (name, material)) in materials.iter().enumerate() {
        for theta in [10.0, 60.0] {
            let (r, _) = albedo(material, &point, direction_at(Vec3::Z, theta, 0.3), 200_000, 90 + k as u64);
            let (mean, error) = (r.mean(), r.std_error());
            println!("{name} at {theta}°: {mean} ± {error}");
            assert!((mean - 1.0).abs() <= 4.5 * error + 1e-4, "{name} at {theta}°: {mean} ± {error}");
            assert!(4.5 * error < 0.015, "{name}: the test cannot see a 3 % loss ({error})");
        }
    }
}

/// A lossless conductor (η = k = 0 is a perfect mirror).
fn gold_mirror() -> CoatedBase {
    CoatedBase::Conductor { ior: ConductorIor::Complex { eta: Rgb::BLACK, k: Rgb::BLACK }, alpha_u: 0.0, alpha_v: 0.0 }
}

/// The smooth conductor's closed-form delta weight against the walk over a conductor of
/// α = 0.002 (whose lobe is nearly a mirror): equal to within 4.5 standard errors and 0.2 %
/// for the difference of the two surfaces (GGX's long tail; at α = 0.01 it is 0.9 % at 55°).
#[test]
fn smooth_conductor_closed_form_matches_the_walk_over_a_nearly_smooth_one() {
    let point = ShadingPoint::flat(Vec3::Z);
    let layer = || medium(Rgb::BLACK, 0.0, 0.3);
    let smooth = coated(0.0, layer(), gold(0.0, 0.0));
    let nearly = coated(0.0, layer(), gold(0.002, 0.002));
    // Not near 72°, where the refracted direction meets the critical angle inside and the
    // rough conductor's spread sends part of the light into total internal reflection.
    for theta in [5.0f32, 30.0, 55.0] {
        let fixed = direction_at(Vec3::Z, theta, 0.0);
        let bsdf = Bsdf::new(&smooth, &point, fixed, TransportMode::Importance).unwrap();
        assert!(bsdf.is_delta());
        let s = bsdf.sample([0.5, 0.5, 0.5]).unwrap();
        let exact = s.value * (s.cos_generated / s.pdf.forward.0);
        let (r, b) = albedo(&nearly, &point, fixed, 400_000, theta as u64);
        for (channel, stats, expected) in [("red", r, exact.r), ("blue", b, exact.b)] {
            let (mean, error) = (stats.mean(), stats.std_error());
            println!("{theta}° {channel}: walk {mean} ± {error} vs closed form {expected}");
            let tolerance = 4.5 * error + 2e-3 * expected as f64;
            assert!(
                (mean - expected as f64).abs() <= tolerance,
                "{theta}° {channel}: walk {mean} ± {error} vs closed form {expected}"
            );
            assert!(tolerance < 0.02 * expected as f64, "{theta}°: the test cannot see 2 % ({error})");
        }
    }
}
