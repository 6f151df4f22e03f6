//! Tests of the per-hit BSDF: chi-square tests of the samplers against their pdfs, agreement of
//! sampled and evaluated pdfs, the swap of forward and reverse pdfs, reciprocity, albedo, and
//! the specular lobes (mirror, dielectric with its radiance-only (η/η')² factor).

use math::{Frame, Rng, Vec3, reflect, sqr};
use scene::material::fresnel_dielectric;
use scene::{Bsdf, LobeKind, Material, ReferenceMaterial, ShadingPoint, TransportMode};
use spectrum::Rgb;
use testkit::{assert_chi2, chi2_sphere, sidak};

const MODES: [TransportMode; 2] = [TransportMode::Radiance, TransportMode::Importance];

fn normal() -> Vec3 {
    Vec3::new(0.3, -0.2, 0.9).normalize()
}

/// A direction at polar angle `theta_degrees` from `normal`, at a fixed azimuth.
fn direction_at(normal: Vec3, theta_degrees: f32, azimuth: f32) -> Vec3 {
    let t = theta_degrees.to_radians();
    let local = Vec3::new(t.sin() * azimuth.cos(), t.sin() * azimuth.sin(), t.cos());
    Frame::from_z(normal).to_world(local).normalize()
}

fn glossy_materials() -> Vec<(&'static str, ReferenceMaterial)> {
    vec![
        ("white diffuse", ReferenceMaterial::diffuse(Rgb::splat(0.803922))),
        (
            "glossy floor (diffuse 0.1 + Phong 0.7, n = 90)",
            ReferenceMaterial {
                diffuse: Rgb::splat(0.1),
                phong: Rgb::splat(0.7),
                phong_exponent: 90.0,
                ..ReferenceMaterial::BLACK
            },
        ),
        (
            "Phong n = 10",
            ReferenceMaterial { phong: Rgb::splat(0.9), phong_exponent: 10.0, ..ReferenceMaterial::BLACK },
        ),
        (
            "Phong n = 500",
            ReferenceMaterial { phong: Rgb::new(0.2, 0.5, 0.4), phong_exponent: 500.0, ..ReferenceMaterial::BLACK },
        ),
    ]
}

const ANGLES: [f32; 4] = [0.5, 30.0, 60.0, 80.0];

#[test]
fn non_specular_samplers_match_their_pdfs() {
    let n = normal();
    let tests = glossy_materials().len() * ANGLES.len() * MODES.len();
    let significance = sidak(1e-3, tests);
    for (name, material) in glossy_materials() {
        for theta in ANGLES {
            for mode in MODES {
                let fixed = direction_at(n, theta, 0.7);
                let bsdf = reference_bsdf(&material, n, fixed, mode).unwrap();
                // Bin in a frame around the mirrored fixed direction (the Phong lobe axis),
                // where a peaked lobe spreads over many bins.
                let axis = if material.phong.is_black() { n } else { reflect(fixed, n) };
                let frame = Frame::from_z(axis);
                let outcome = chi2_sphere(
                    |rng: &mut Rng| bsdf.sample(rng.uniform3()).map(|s| frame.to_local(s.direction)),
                    |local| bsdf.evaluate(frame.to_world(local).normalize()).map_or(0.0, |e| e.pdf.forward.0 as f64),
                    200_000,
                    7,
                    24,
                    32,
                );
                assert_chi2(&outcome, significance, &format!("{name} at {theta}° ({mode:?})"));
            }
        }
    }
}

#[test]
fn sampled_and_evaluated_values_and_pdfs_agree() {
    let n = normal();
    let mut rng = Rng::for_stream(3, 0, 0);
    for (name, material) in glossy_materials() {
        for theta in ANGLES {
            for mode in MODES {
                let bsdf = reference_bsdf(&material, n, direction_at(n, theta, 2.0), mode).unwrap();
                let mut checked = 0;
                for _ in 0..2000 {
                    let Some(s) = bsdf.sample(rng.uniform3()) else { continue };
                    let e = bsdf.evaluate(s.direction).expect("a sampled direction evaluates to non-zero");
                    let close = |a: f32, b: f32| (a - b).abs() <= 1e-4 * a.abs().max(b.abs());
                    assert!(close(s.pdf.forward.0, e.pdf.forward.0), "{name}: forward {:?} vs {:?}", s.pdf, e.pdf);
                    assert!(close(s.pdf.reverse.0, e.pdf.reverse.0), "{name}: reverse {:?} vs {:?}", s.pdf, e.pdf);
                    assert!(close(s.value.r, e.value.r) && close(s.value.b, e.value.b), "{name}: value");
                    assert_eq!(s.cos_generated, e.cos_generated);
                    checked += 1;
                }
                assert!(checked > 500, "{name} at {theta}°: only {checked} samples succeeded");
            }
        }
    }
}

#[test]
fn swapping_fixed_and_generated_swaps_the_pdfs_and_the_value_is_reciprocal() {
    let n = normal();
    let mut rng = Rng::for_stream(5, 0, 0);
    for (name, material) in glossy_materials() {
        let mut nonzero = 0;
        for _ in 0..5000 {
            let a = direction_at(n, 85.0 * rng.uniform(), 6.3 * rng.uniform());
            // For the Phong lobes pick the second direction near the mirror direction.
            let b = if material.phong.is_black() {
                direction_at(n, 85.0 * rng.uniform(), 6.3 * rng.uniform())
            } else {
                (reflect(a, n) + 0.2 * Vec3::new(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5))
                    .normalize()
            };
            for mode in MODES {
                let (Some(from_a), Some(from_b)) =
                    (reference_bsdf(&material, n, a, mode), reference_bsdf(&material, n, b, mode))
                else {
                    continue;
                };
                match (from_a.evaluate(b), from_b.evaluate(a)) {
                    (None, None) => {}
                    (Some(ab), Some(ba)) => {
                        nonzero += 1;
                        let close = |x: f32, y: f32| (x - y).abs() <= 2e-4 * x.abs().max(y.abs());
                        assert!(close(ab.pdf.forward.0, ba.pdf.reverse.0), "{name}: {:?} vs {:?}", ab.pdf, ba.pdf);
                        assert!(close(ab.pdf.reverse.0, ba.pdf.forward.0), "{name}: {:?} vs {:?}", ab.pdf, ba.pdf);
                        assert!(close(ab.value.r, ba.value.r) && close(ab.value.g, ba.value.g), "{name}: reciprocity");
                    }
                    (x, y) => panic!("{name}: one direction of the pair is zero and the other not: {x:?} {y:?}"),
                }
            }
        }
        assert!(nonzero > 1000, "{name}: only {nonzero} non-zero pairs tested");
    }
}

#[test]
fn albedo_never_exceeds_the_reflectance() {
    let n = normal();
    for (name, material) in glossy_materials() {
        let bound = (material.diffuse + material.phong).max_component();
        for theta in ANGLES {
            let bsdf = reference_bsdf(&material, n, direction_at(n, theta, 1.0), TransportMode::Radiance).unwrap();
            let mut rng = Rng::for_stream(11, theta as u64, 0);
            let mut stats = testkit::MeanVar::new();
            for _ in 0..100_000 {
                let w = bsdf
                    .sample(rng.uniform3())
                    .map_or(0.0, |s| (s.value * (s.cos_generated / s.pdf.forward.0)).max_component());
                stats.push(w as f64);
            }
            assert!(
                stats.mean() <= bound as f64 + 4.0 * stats.std_error(),
                "{name} at {theta}°: albedo {} ± {} exceeds {bound}",
                stats.mean(),
                stats.std_error()
            );
            assert!(bsdf.continuation_probability() <= 1.0);
        }
    }
}

#[test]
fn one_sided_lobes_are_zero_from_and_towards_the_back() {
    let n = Vec3::Z;
    let material = ReferenceMaterial {
        diffuse: Rgb::splat(0.5),
        phong: Rgb::splat(0.3),
        phong_exponent: 5.0,
        ..ReferenceMaterial::BLACK
    };
    let front = Vec3::new(0.3, 0.1, 0.9).normalize();
    let back = Vec3::new(0.2, -0.3, -0.8).normalize();
    let bsdf = reference_bsdf(&material, n, front, TransportMode::Radiance).unwrap();
    assert!(bsdf.evaluate(back).is_none());
    let from_back = reference_bsdf(&material, n, back, TransportMode::Radiance).unwrap();
    assert!(from_back.evaluate(Vec3::new(-0.2, 0.3, -0.8).normalize()).is_none());
    assert!(from_back.evaluate(front).is_none());
    let mut rng = Rng::for_stream(1, 1, 1);
    assert!((0..1000).all(|_| from_back.sample(rng.uniform3()).is_none()));
}

#[test]
fn mirror_reflects_exactly_from_both_sides() {
    let mirror = ReferenceMaterial { mirror: Rgb::splat(1.0), ..ReferenceMaterial::BLACK };
    let n = normal();
    for theta in [0.5f32, 45.0, 89.0, 120.0, 170.0] {
        let fixed = direction_at(n, theta, 0.3);
        for mode in MODES {
            let bsdf = reference_bsdf(&mirror, n, fixed, mode).unwrap();
            assert!(bsdf.is_delta());
            assert!(bsdf.evaluate(reflect(fixed, n)).is_none(), "delta lobes do not evaluate");
            let s = bsdf.sample([0.3, 0.6, 0.5]).unwrap();
            assert_eq!(s.lobe, LobeKind::SpecularReflection);
            assert!((s.direction - reflect(fixed, n)).length() < 1e-5);
            let weight = s.value * (s.cos_generated / s.pdf.forward.0);
            assert!((weight.r - 1.0).abs() < 1e-5, "throughput weight {weight:?}");
            assert_eq!(bsdf.continuation_probability(), 1.0);
        }
    }
}

#[test]
fn glass_chooses_reflection_with_the_fresnel_probability_and_refracts_by_snell() {
    let glass = ReferenceMaterial { mirror: Rgb::splat(1.0), ior: 1.6, ..ReferenceMaterial::BLACK };
    let n = normal();
    // Outside at several angles, inside below and above the critical angle (38.7°).
    for theta in [0.5f32, 30.0, 60.0, 85.0, 150.0, 170.0, 130.0] {
        let fixed = direction_at(n, theta, 1.1);
        let cos_fixed = fixed.dot(n);
        let fresnel = fresnel_dielectric(cos_fixed, 1.6);
        for mode in MODES {
            let bsdf = reference_bsdf(&glass, n, fixed, mode).unwrap();
            assert!(bsdf.is_delta());
            assert_eq!(bsdf.continuation_probability(), 1.0);
            let mut rng = Rng::for_stream(9, theta as u64, mode as u64);
            let trials = 20_000;
            let mut reflections = 0;
            for _ in 0..trials {
                let s = bsdf.sample(rng.uniform3()).unwrap();
                let weight = (s.value * (s.cos_generated / s.pdf.forward.0)).r;
                match s.lobe {
                    LobeKind::SpecularReflection => {
                        reflections += 1;
                        assert!((s.direction - reflect(fixed, n)).length() < 1e-5);
                        assert!((weight - 1.0).abs() < 1e-4, "reflection weight F·ρ/P(reflect) = 1, got {weight}");
                    }
                    LobeKind::SpecularTransmission => {
                        let cos_generated = s.direction.dot(n);
                        assert!(cos_generated * cos_fixed < 0.0, "refraction crosses the surface");
                        let (eta_fixed, eta_generated) = if cos_fixed > 0.0 { (1.0, 1.6) } else { (1.6, 1.0) };
                        let sin = |c: f32| (1.0 - c * c).max(0.0).sqrt();
                        assert!(
                            (eta_fixed * sin(cos_fixed) - eta_generated * sin(cos_generated)).abs() < 1e-4,
                            "Snell"
                        );
                        // In the plane of incidence: generated, fixed and normal are coplanar.
                        assert!(n.cross(fixed).dot(s.direction).abs() < 1e-4);
                        let expected = match mode {
                            TransportMode::Radiance => sqr(eta_fixed / eta_generated),
                            TransportMode::Importance => 1.0,
                        };
                        assert!(
                            (weight - expected).abs() < 1e-4 * expected,
                            "refraction weight {weight} vs {expected}"
                        );
                    }
                    other => panic!("glass sampled {other:?}"),
                }
            }
            // Binomial test of the reflection frequency against F at 5 sigma.
            let p = fresnel as f64;
            let sigma = (p * (1.0 - p) / trials as f64).sqrt().max(1e-9);
            let freq = reflections as f64 / trials as f64;
            assert!((freq - p).abs() <= 5.0 * sigma + 1e-12, "θ={theta}: reflected {freq}, F = {p}");
        }
    }
    // Total internal reflection beyond the critical angle.
    assert_eq!(fresnel_dielectric(-0.5, 1.6), 1.0);
    // Normal incidence: ((1.6 − 1)/(1.6 + 1))².
    assert!((fresnel_dielectric(1.0, 1.6) - sqr(0.6 / 2.6)).abs() < 1e-6);
    assert!((fresnel_dielectric(-1.0, 1.6) - sqr(0.6 / 2.6)).abs() < 1e-6);
}

#[test]
fn camera_ray_entering_glass_is_scaled_by_the_inverse_squared_ior() {
    let glass = ReferenceMaterial { mirror: Rgb::splat(1.0), ior: 1.6, ..ReferenceMaterial::BLACK };
    let bsdf = reference_bsdf(&glass, Vec3::Z, Vec3::Z, TransportMode::Radiance).unwrap();
    let s = bsdf.sample([0.0, 0.0, 0.999]).unwrap();
    assert_eq!(s.lobe, LobeKind::SpecularTransmission);
    let weight = (s.value * (s.cos_generated / s.pdf.forward.0)).r;
    assert!((weight - 1.0 / (1.6 * 1.6)).abs() < 1e-5, "{weight}");
}

#[test]
fn black_materials_do_not_scatter() {
    assert!(reference_bsdf(&ReferenceMaterial::BLACK, Vec3::Z, Vec3::Z, TransportMode::Radiance).is_none());
    let white = ReferenceMaterial::diffuse(Rgb::splat(0.5));
    assert!(reference_bsdf(&white, Vec3::Z, Vec3::X, TransportMode::Radiance).is_none(), "grazing fixed direction");
}

/// `ReferenceMaterial::is_specular_only` (the VCM camera pass plans no merge query on such
/// hits) holds exactly when every BSDF built from the material, at any angle and in either
/// mode, is delta or absent: mirror, glass, black and a mirror-glass mix are; any diffuse or
/// Phong reflectance, however small, is not.
#[test]
fn specular_only_materials_build_only_delta_bsdfs() {
    let glass = ReferenceMaterial { mirror: Rgb::splat(1.0), ior: 1.6, ..ReferenceMaterial::BLACK };
    let specular = [
        ("black", ReferenceMaterial::BLACK),
        ("mirror", ReferenceMaterial { mirror: Rgb::new(0.9, 0.5, 0.2), ..ReferenceMaterial::BLACK }),
        ("glass", glass),
        ("glass without mirror", ReferenceMaterial { mirror: Rgb::BLACK, ..glass }),
    ];
    let tiny = Rgb::new(0.0, 0.0, 1e-6);
    let not_specular = [
        ("faint diffuse", ReferenceMaterial { diffuse: tiny, ..glass }),
        ("faint Phong", ReferenceMaterial { phong: tiny, phong_exponent: 20.0, ..glass }),
        ("white diffuse", ReferenceMaterial::diffuse(Rgb::splat(0.8))),
    ];
    let n = normal();
    for (name, material, expected) in
        specular.iter().map(|&(n, m)| (n, m, true)).chain(not_specular.iter().map(|&(n, m)| (n, m, false)))
    {
        assert_eq!(material.is_specular_only(), expected, "{name}");
        assert_eq!(Material::from(material).is_specular_only(), expected, "{name} as a Material");
        let mut any_non_delta = false;
        for theta in [0.5, 30.0, 60.0, 85.0, 95.0, 150.0] {
            for mode in MODES {
                let fixed = direction_at(n, theta, 0.7);
                if let Some(bsdf) = reference_bsdf(&material, n, fixed, mode) {
                    any_non_delta |= !bsdf.is_delta();
                }
            }
        }
        assert_eq!(any_non_delta, !expected, "{name}: some BSDF is not delta");
    }
}

/// The BSDF of a reference material with the shading normal equal to the geometric one.
fn reference_bsdf(material: &ReferenceMaterial, normal: Vec3, fixed: Vec3, mode: TransportMode) -> Option<Bsdf> {
    Bsdf::new(&Material::from(*material), &ShadingPoint::flat(normal), fixed, mode)
}
