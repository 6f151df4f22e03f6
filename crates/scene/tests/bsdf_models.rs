//! Tests of the BSDF models other than the reference material: chi-square tests of every
//! sampler against its pdf (delta lobes counted against their selection probabilities),
//! agreement of sampled and evaluated values and pdfs, the swap of forward and reverse pdfs,
//! reciprocity (generalised for refraction) and the shading-normal adjoint relation, energy
//! bounds, the GGX conductor's directional albedo, Fresnel values, and blends / two-sided.

use math::{Frame, Rng, Vec3, sqr};
use scene::material::fresnel_dielectric;
use scene::microfacet::{
    Distribution, Microfacet, fresnel_conductor, fresnel_conductor_rgb, fresnel_diffuse_reflectance,
};
use scene::{Bsdf, LobeKind, Material, ShadingPoint, Texture, TransportMode};
use spectrum::Rgb;
use testkit::{Integration, MeanVar, assert_chi2, chi2_sphere, chi2_sphere_with, sidak};

const MODES: [TransportMode; 2] = [TransportMode::Radiance, TransportMode::Importance];

fn geometric_normal() -> Vec3 {
    Vec3::new(0.3, -0.2, 0.9).normalize()
}

/// A point whose shading normal is tilted by about 10° from the geometric one.
fn tilted_point() -> ShadingPoint {
    let n = geometric_normal();
    let frame = Frame::from_z(n);
    let shading = (n + 0.18 * frame.x - 0.05 * frame.y).normalize();
    ShadingPoint {
        geometric_normal: n,
        shading_normal: shading,
        uv: math::Vec2::ZERO,
        tangent: Vec3::ZERO,
        attribute: Rgb::BLACK,
    }
}

fn flat_point() -> ShadingPoint {
    ShadingPoint::flat(geometric_normal())
}

/// A direction at polar angle `theta_degrees` from `normal`, at azimuth `azimuth` (radians).
fn direction_at(normal: Vec3, theta_degrees: f32, azimuth: f32) -> Vec3 {
    let t = theta_degrees.to_radians();
    let local = Vec3::new(t.sin() * azimuth.cos(), t.sin() * azimuth.sin(), t.cos());
    Frame::from_z(normal).to_world(local).normalize()
}

fn constant(r: f32, g: f32, b: f32) -> Texture {
    Texture::Constant(Rgb::new(r, g, b))
}

fn white() -> Texture {
    constant(1.0, 1.0, 1.0)
}

/// Copper's complex IOR at three wavelengths (approximately).
const CU_ETA: Rgb = Rgb::new(0.27, 0.68, 1.32);
const CU_K: Rgb = Rgb::new(3.61, 2.62, 2.29);

fn diffuse() -> Material {
    Material::Diffuse { reflectance: constant(0.8, 0.5, 0.3) }
}

fn rough_conductor(alpha_u: f32, alpha_v: f32) -> Material {
    Material::RoughConductor {
        distribution: Distribution::Ggx,
        alpha_u,
        alpha_v,
        eta: CU_ETA,
        k: CU_K,
        specular_reflectance: white(),
    }
}

fn dielectric(int_ior: f32, ext_ior: f32) -> Material {
    Material::Dielectric {
        int_ior,
        ext_ior,
        specular_reflectance: white(),
        specular_transmittance: white(),
        dispersion: None,
    }
}

fn rough_dielectric(alpha_u: f32, alpha_v: f32, int_ior: f32, ext_ior: f32) -> Material {
    Material::RoughDielectric {
        distribution: Distribution::Ggx,
        alpha_u,
        alpha_v,
        int_ior,
        ext_ior,
        specular_reflectance: white(),
        specular_transmittance: white(),
    }
}

fn plastic(int_ior: f32, nonlinear: bool) -> Material {
    Material::Plastic {
        diffuse_reflectance: constant(0.5, 0.3, 0.2),
        specular_reflectance: white(),
        int_ior,
        ext_ior: 1.0,
        nonlinear,
    }
}

fn rough_plastic(alpha: f32, nonlinear: bool) -> Material {
    Material::RoughPlastic {
        distribution: Distribution::Ggx,
        alpha,
        diffuse_reflectance: constant(0.5, 0.3, 0.2),
        specular_reflectance: white(),
        int_ior: 1.5,
        ext_ior: 1.0,
        nonlinear,
    }
}

/// The rough model `m` with a Beckmann distribution in place of GGX.
fn beckmann(mut m: Material) -> Material {
    match &mut m {
        Material::RoughConductor { distribution, .. }
        | Material::RoughDielectric { distribution, .. }
        | Material::RoughPlastic { distribution, .. } => *distribution = Distribution::Beckmann,
        _ => panic!("not a rough model"),
    }
    m
}

fn blend(weight: f32, first: Material, second: Material) -> Material {
    Material::Blend { weight: constant(weight, 0.0, 0.0), first: Box::new(first), second: Box::new(second) }
}

/// A material under test, and whether it scatters from behind and transmits.
struct Case {
    name: &'static str,
    material: Material,
    two_sided: bool,
}

fn case(name: &'static str, material: Material, two_sided: bool) -> Case {
    Case { name, material, two_sided }
}

fn cases() -> Vec<Case> {
    vec![
        case("diffuse", diffuse(), false),
        case(
            "conductor Cu",
            Material::Conductor { eta: CU_ETA, k: CU_K, specular_reflectance: constant(0.9, 0.8, 1.0) },
            false,
        ),
        case("perfect mirror", Material::perfect_mirror(), false),
        case("rough conductor α 0.05", rough_conductor(0.05, 0.05), false),
        case("rough conductor α 0.3", rough_conductor(0.3, 0.3), false),
        case("rough conductor α 1", rough_conductor(1.0, 1.0), false),
        case("rough conductor α 0.05 × 0.4", rough_conductor(0.05, 0.4), false),
        case("dielectric 1.5", dielectric(1.5, 1.0), true),
        case("dielectric 1/1.5", dielectric(1.0, 1.5), true),
        case(
            "thin dielectric 1.5",
            Material::ThinDielectric {
                int_ior: 1.5,
                ext_ior: 1.0,
                specular_reflectance: white(),
                specular_transmittance: constant(0.9, 0.9, 0.7),
            },
            true,
        ),
        case("rough dielectric α 0.05, 1.5", rough_dielectric(0.05, 0.05, 1.5, 1.0), true),
        case("rough dielectric α 0.3, 1.5", rough_dielectric(0.3, 0.3, 1.5, 1.0), true),
        case("rough dielectric α 1, 1.5", rough_dielectric(1.0, 1.0, 1.5, 1.0), true),
        case("rough dielectric α 0.3, 1/1.5", rough_dielectric(0.3, 0.3, 1.0, 1.5), true),
        case("rough dielectric α 0.1 × 0.4, 1.5", rough_dielectric(0.1, 0.4, 1.5, 1.0), true),
        case("beckmann conductor α 0.3 × 0.08", beckmann(rough_conductor(0.3, 0.08)), false),
        case("beckmann dielectric α 0.3, 1.5", beckmann(rough_dielectric(0.3, 0.3, 1.5, 1.0)), true),
        case("beckmann dielectric α 0.05 × 0.2, 1/1.5", beckmann(rough_dielectric(0.05, 0.2, 1.0, 1.5)), true),
        case("beckmann plastic α 0.2", beckmann(rough_plastic(0.2, false)), false),
        case("plastic 1.5", plastic(1.5, false), false),
        case("plastic 1.9 nonlinear", plastic(1.9, true), false),
        case("rough plastic α 0.05", rough_plastic(0.05, false), false),
        case("rough plastic α 0.3 nonlinear", rough_plastic(0.3, true), false),
        case("rough plastic α 1", rough_plastic(1.0, false), false),
        case("blend diffuse / rough conductor", blend(0.3, diffuse(), rough_conductor(0.3, 0.3)), false),
        case(
            "blend plastic / rough dielectric",
            blend(0.6, plastic(1.5, false), rough_dielectric(0.3, 0.3, 1.5, 1.0)),
            true,
        ),
        case("two-sided diffuse", Material::TwoSided { front: Box::new(diffuse()), back: None }, true),
        case(
            "two-sided rough conductor / diffuse",
            Material::TwoSided { front: Box::new(rough_conductor(0.3, 0.3)), back: Some(Box::new(diffuse())) },
            true,
        ),
    ]
}

/// Polar angles of the fixed direction: near-normal to near-grazing, and from behind for the
/// materials that scatter there.
fn angles(two_sided: bool) -> Vec<f32> {
    let mut a = vec![2.0, 40.0, 70.0, 87.0];
    if two_sided {
        a.extend([125.0, 170.0]);
    }
    a
}

/// Pdf integration for the chi-square tests: coarser than the default, since the BSDF pdfs
/// jump at the horizon, where the default refines to its maximum depth; the bin integrals stay
/// within about 1e-5 of the default's, far below the counting noise of 100 000 samples.
const INTEGRATION: Integration =
    Integration { initial_split: 2, max_depth: 4, abs_tolerance: 1e-5, rel_tolerance: 1e-3 };

#[test]
fn one_sided_samplers_match_their_pdfs_and_delta_lobes_their_probabilities() {
    chi2_cases(false);
}

#[test]
fn two_sided_samplers_match_their_pdfs_and_delta_lobes_their_probabilities() {
    chi2_cases(true);
}

/// Chi-square tests of the cases that are (or are not) two-sided, at every angle, with a
/// shading normal tilted from the geometric one.
fn chi2_cases(two_sided: bool) {
    let point = tilted_point();
    let n = point.shading_normal;
    let cases: Vec<Case> = cases().into_iter().filter(|c| c.two_sided == two_sided).collect();
    let total: usize = cases.iter().map(|c| angles(c.two_sided).len()).sum();
    let significance = sidak(1e-3, total);
    let mut index = if two_sided { 1000u64 } else { 0 };
    for case in cases {
        for theta in angles(case.two_sided) {
            // Both modes over the angles (the pdfs do not depend on the mode).
            let mode = MODES[(index % 2) as usize];
            index += 1;
            let fixed = direction_at(point.geometric_normal, theta, 0.7);
            let Some(bsdf) = Bsdf::new(&case.material, &point, fixed, mode) else {
                panic!("{} at {theta}°: no BSDF", case.name)
            };
            // Bin around the mirror direction (about the shading normal), where glossy lobes
            // spread over many bins.
            let frame = Frame::from_z((2.0 * fixed.dot(n) * n - fixed).normalize());
            let mut delta: Vec<(LobeKind, f32, u64)> = Vec::new();
            let samples = 100_000;
            let outcome = chi2_sphere_with(
                |rng: &mut Rng| {
                    let s = bsdf.sample(rng.uniform3())?;
                    if s.lobe.is_specular() {
                        match delta.iter_mut().find(|d| d.0 == s.lobe) {
                            Some(d) => {
                                assert!((d.1 - s.pdf.forward.0).abs() < 1e-6, "one probability per delta lobe");
                                d.2 += 1;
                            }
                            None => delta.push((s.lobe, s.pdf.forward.0, 1)),
                        }
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
            let what = format!("{} at {theta}° ({mode:?})", case.name);
            assert_chi2(&outcome, significance, &what);
            for (lobe, p, count) in delta {
                let p = p as f64;
                let sigma = (p * (1.0 - p) / samples as f64).sqrt();
                let freq = count as f64 / samples as f64;
                assert!((freq - p).abs() <= 5.0 * sigma + 1e-4, "{what}: {lobe:?} chosen {freq}, probability {p}");
            }
        }
    }
}

/// The relative IOR of the side of `d` (outside = 1) for the dielectric cases.
fn side_ior(case: &Case, d: Vec3, n: Vec3) -> f32 {
    let inside = match &case.material {
        Material::Dielectric { int_ior, ext_ior, .. } | Material::RoughDielectric { int_ior, ext_ior, .. } => {
            int_ior / ext_ior
        }
        Material::Blend { second, .. } => match second.as_ref() {
            Material::RoughDielectric { int_ior, ext_ior, .. } => int_ior / ext_ior,
            _ => 1.0,
        },
        _ => 1.0,
    };
    if d.dot(n) > 0.0 { 1.0 } else { inside }
}

#[test]
fn sampled_and_evaluated_agree_pdfs_swap_and_values_are_reciprocal() {
    let mut rng = Rng::for_stream(3, 0, 0);
    let close = |a: f32, b: f32, tol: f32| (a - b).abs() <= tol * a.abs().max(b.abs()) + 1e-7;
    for case in cases() {
        let mut pairs = 0;
        for point in [flat_point(), tilted_point()] {
            let n = point.geometric_normal;
            for theta in angles(case.two_sided) {
                for mode in MODES {
                    let fixed = direction_at(n, theta, 2.0);
                    let Some(bsdf) = Bsdf::new(&case.material, &point, fixed, mode) else {
                        // Only where the fixed direction lies between the two tangent planes.
                        let split = fixed.dot(n) * fixed.dot(point.shading_normal) <= 0.0;
                        assert!(split, "{} at {theta}°: no BSDF", case.name);
                        continue;
                    };
                    assert!(bsdf.continuation_probability() <= 1.0 && bsdf.continuation_probability() > 0.0);
                    assert!((bsdf.cos_fixed() - fixed.dot(n).abs()).abs() < 1e-6);
                    for _ in 0..400 {
                        let Some(s) = bsdf.sample(rng.uniform3()) else { continue };
                        assert!((s.cos_generated - s.direction.dot(n).abs()).abs() < 1e-5, "geometric cosine");
                        if s.lobe.is_specular() {
                            assert!(bsdf.evaluate(s.direction).is_none_or(|e| e.pdf.forward.0.is_finite()));
                            continue;
                        }
                        let e = bsdf.evaluate(s.direction).expect("a sampled direction evaluates to non-zero");
                        let what = format!("{} at {theta}° ({mode:?})", case.name);
                        assert!(close(s.pdf.forward.0, e.pdf.forward.0, 1e-5), "{what}: {:?} vs {:?}", s.pdf, e.pdf);
                        assert!(close(s.pdf.reverse.0, e.pdf.reverse.0, 1e-5), "{what}: {:?} vs {:?}", s.pdf, e.pdf);
                        assert!(close(s.value.g, e.value.g, 1e-5), "{what}: value");
                        // Swap: the BSDF built at the generated direction.
                        let Some(back) = Bsdf::new(&case.material, &point, s.direction, mode) else {
                            panic!(
                                "{what}: no BSDF at the generated direction {:?} cos g {} cos s {} {:?}",
                                s,
                                s.direction.dot(n),
                                s.direction.dot(point.shading_normal),
                                e
                            )
                        };
                        let Some(r) = back.evaluate(fixed) else {
                            panic!("{what}: the swapped pair evaluates to zero")
                        };
                        pairs += 1;
                        assert!(close(e.pdf.forward.0, r.pdf.reverse.0, 2e-3), "{what}: {:?} vs {:?}", e.pdf, r.pdf);
                        assert!(close(e.pdf.reverse.0, r.pdf.forward.0, 2e-3), "{what}: {:?} vs {:?}", e.pdf, r.pdf);
                        // The adjoint relation: radiance value(a → b) = importance value(b → a).
                        let other = match mode {
                            TransportMode::Radiance => TransportMode::Importance,
                            TransportMode::Importance => TransportMode::Radiance,
                        };
                        let adjoint = Bsdf::new(&case.material, &point, s.direction, other)
                            .and_then(|b| b.evaluate(fixed))
                            .expect("adjoint pair");
                        assert!(
                            close(e.value.r, adjoint.value.r, 2e-3),
                            "{what}: adjoint {:?} vs {:?}",
                            e.value,
                            adjoint.value
                        );
                        // Reciprocity (generalised for refraction) with flat normals:
                        // value(fixed = a, generated = b) / η_a² = value(fixed = b, generated = a) / η_b²
                        // in radiance mode, with η_a and η_b swapped in importance mode.
                        if point.shading_normal == point.geometric_normal {
                            let (eta_fixed, eta_generated) =
                                (side_ior(&case, fixed, n), side_ior(&case, s.direction, n));
                            let (x, y) = match mode {
                                TransportMode::Radiance => (e.value.b / sqr(eta_fixed), r.value.b / sqr(eta_generated)),
                                TransportMode::Importance => {
                                    (e.value.b / sqr(eta_generated), r.value.b / sqr(eta_fixed))
                                }
                            };
                            assert!(close(x, y, 2e-3), "{what}: reciprocity {x} vs {y}");
                        }
                    }
                }
            }
        }
        let delta_only = matches!(
            case.material,
            Material::Conductor { .. } | Material::Dielectric { .. } | Material::ThinDielectric { .. }
        );
        assert!(delta_only || pairs > 1000, "{}: only {pairs} pairs tested", case.name);
    }
}

#[test]
fn directional_albedo_never_exceeds_one() {
    // Importance mode: the integral over the generated directions is the fraction of the
    // energy arriving along the fixed direction that is scattered.
    let point = flat_point();
    let n = point.geometric_normal;
    for case in cases() {
        for theta in angles(case.two_sided) {
            let fixed = direction_at(n, theta, 1.0);
            let bsdf = Bsdf::new(&case.material, &point, fixed, TransportMode::Importance).unwrap();
            let mut rng = Rng::for_stream(11, theta as u64, 0);
            let mut stats = MeanVar::new();
            for _ in 0..20_000 {
                let w = bsdf
                    .sample(rng.uniform3())
                    .map_or(0.0, |s| (s.value * (s.cos_generated / s.pdf.forward.0)).max_component());
                stats.push(w as f64);
            }
            assert!(
                stats.mean() <= 1.0 + 4.0 * stats.std_error() + 1e-3,
                "{} at {theta}°: albedo {} ± {}",
                case.name,
                stats.mean(),
                stats.std_error()
            );
        }
    }
}

/// Directional albedo of the GGX conductor with F = 1 (eta = k = 0), measured by sampling
/// (200 000 samples, standard errors ≤ 0.001) and checked against uniform sampling of
/// `evaluate` as an independent estimate. Single scattering loses the light that microfacets
/// reflect below the horizon or into masking microfacets; GGX's long tails make that large at
/// high roughness (at α = 1 the visible normals at normal incidence are cosine distributed, so
/// half of the reflections point below the horizon):
///
/// | α \ cos θ | 1     | 0.5   | 0.1   |
/// |-----------|-------|-------|-------|
/// | 0.1       | 0.989 | 0.969 | 0.874 |
/// | 0.5       | 0.688 | 0.687 | 0.772 |
/// | 1.0       | 0.308 | 0.409 | 0.558 |
///
/// At normal incidence the fraction of samples reflected below the horizon is exactly
/// `α²/(1 + α²)` (the visible-normal distribution has `P(tan² θm ≤ t) = t/(α² + t)`).
#[test]
fn ggx_conductor_albedo_loses_energy_only_to_single_scattering() {
    let point = ShadingPoint::flat(Vec3::Z);
    let mut table = String::new();
    for cos in [1.0f32, 0.5, 0.1] {
        let fixed = Vec3::new((1.0 - cos * cos).sqrt(), 0.0, cos);
        let mut previous = f64::INFINITY;
        for alpha in [0.1f32, 0.5, 1.0] {
            let material = Material::RoughConductor {
                distribution: Distribution::Ggx,
                alpha_u: alpha,
                alpha_v: alpha,
                eta: Rgb::BLACK,
                k: Rgb::BLACK,
                specular_reflectance: white(),
            };
            let bsdf = Bsdf::new(&material, &point, fixed, TransportMode::Radiance).unwrap();
            let mut rng = Rng::for_stream(17, (alpha * 10.0) as u64, (cos * 10.0) as u64);
            let mut sampled = MeanVar::new();
            let mut uniform = MeanVar::new();
            let mut below = 0u32;
            let samples = 200_000;
            for _ in 0..samples {
                let s = bsdf.sample(rng.uniform3());
                below += s.is_none() as u32;
                let w = s.map_or(0.0, |s| s.value.r * s.cos_generated / s.pdf.forward.0);
                sampled.push(w as f64);
                let d = math::warp::uniform_sphere(rng.uniform2());
                let v = bsdf.evaluate(d).map_or(0.0, |e| e.value.r * e.cos_generated / math::warp::UNIFORM_SPHERE_PDF);
                uniform.push(v as f64);
            }
            let (a, sa) = (sampled.mean(), sampled.std_error());
            let (b, sb) = (uniform.mean(), uniform.std_error());
            table.push_str(&format!("α {alpha} cos {cos}: sampled {a:.4} ± {sa:.4}, uniform {b:.4} ± {sb:.4}\n"));
            assert!((a - b).abs() <= 5.0 * (sa * sa + sb * sb).sqrt(), "α {alpha} cos {cos}: {a} vs {b}");
            assert!(a <= 1.0 + 4.0 * sa, "α {alpha} cos {cos}: albedo {a} > 1");
            if cos == 1.0 {
                let p = (alpha * alpha / (1.0 + alpha * alpha)) as f64;
                let freq = below as f64 / samples as f64;
                let sigma = (p * (1.0 - p) / samples as f64).sqrt();
                assert!((freq - p).abs() < 5.0 * sigma, "α {alpha}: {freq} of the samples below, expected {p}");
            }
            if alpha == 0.1 && cos >= 0.5 {
                assert!(a > 0.95, "α {alpha} cos {cos}: albedo {a}, expected close to 1");
            }
            assert!(a < previous, "albedo must decrease with α: {table}");
            previous = a;
        }
    }
    println!("{table}");
}

/// Fresnel reflectance of a conductor from complex arithmetic in double precision:
/// rs = (cos − w)/(cos + w), rp = (n² cos − w)/(n² cos + w), w = √(n² − sin²).
fn fresnel_complex(cos: f64, eta: f64, k: f64) -> f64 {
    type C = (f64, f64);
    let mul = |a: C, b: C| (a.0 * b.0 - a.1 * b.1, a.0 * b.1 + a.1 * b.0);
    let div = |a: C, b: C| {
        let d = b.0 * b.0 + b.1 * b.1;
        ((a.0 * b.0 + a.1 * b.1) / d, (a.1 * b.0 - a.0 * b.1) / d)
    };
    let sqrt = |a: C| {
        let r = (a.0 * a.0 + a.1 * a.1).sqrt();
        let re = (0.5 * (r + a.0)).sqrt();
        let im = (0.5 * (r - a.0)).max(0.0).sqrt().copysign(a.1);
        (re, im)
    };
    let n2 = mul((eta, k), (eta, k));
    let sin2 = 1.0 - cos * cos;
    let w = sqrt((n2.0 - sin2, n2.1));
    let rs = div((cos - w.0, -w.1), (cos + w.0, w.1));
    let n2c = (n2.0 * cos, n2.1 * cos);
    let rp = div((n2c.0 - w.0, n2c.1 - w.1), (n2c.0 + w.0, n2c.1 + w.1));
    0.5 * (rs.0 * rs.0 + rs.1 * rs.1 + rp.0 * rp.0 + rp.1 * rp.1)
}

#[test]
fn conductor_fresnel_matches_known_values() {
    for (eta, k) in [(0.27f32, 3.61f32), (1.32, 2.29), (0.18, 3.42), (2.9, 3.0), (1.5, 0.0)] {
        let normal = (sqr(eta - 1.0) + sqr(k)) / (sqr(eta + 1.0) + sqr(k));
        assert!((fresnel_conductor(1.0, eta, k) - normal).abs() < 1e-6, "η {eta} k {k}");
        for cos in [1.0f32, 0.8, 0.5, 0.2, 0.05, 0.001] {
            let expected = fresnel_complex(cos as f64, eta as f64, k as f64);
            let got = fresnel_conductor(cos, eta, k) as f64;
            assert!((got - expected).abs() < 1e-5, "η {eta} k {k} cos {cos}: {got} vs {expected}");
        }
    }
    // A real index is a dielectric.
    for cos in [0.9f32, 0.4, 0.1] {
        assert!((fresnel_conductor(cos, 1.5, 0.0) - fresnel_dielectric(cos, 1.5)).abs() < 1e-6);
    }
    // eta = k = 0: a perfect mirror; grazing: total reflection.
    assert_eq!(fresnel_conductor(0.3, 0.0, 0.0), 1.0);
    assert!((fresnel_conductor(0.0, 0.27, 3.61) - 1.0).abs() < 1e-6);
}

/// The conductor Fresnel reflectance the textbook way, as `fresnel_conductor` computed it before
/// it was reduced to one division: `Rs` and `Rp` each with its own division, their mean, in f64,
/// with the same special cases (η = k = 0 a mirror, non-finite → 1, clamped to [0, 1]).
fn fresnel_conductor_two_divisions(cos_incident: f32, eta: f32, k: f32) -> f64 {
    if eta == 0.0 && k == 0.0 {
        return 1.0;
    }
    let c = (cos_incident.abs() as f64).min(1.0);
    let (eta, k) = (eta as f64, k as f64);
    let c2 = c * c;
    let s2 = 1.0 - c2;
    let t0 = eta * eta - k * k - s2;
    let a2b2 = (t0 * t0 + 4.0 * eta * eta * k * k).sqrt();
    let a = (0.5 * (a2b2 + t0)).max(0.0).sqrt();
    let rs = (a2b2 + c2 - 2.0 * a * c) / (a2b2 + c2 + 2.0 * a * c);
    let t1 = a2b2 * c2 + s2 * s2;
    let t2 = 2.0 * a * c * s2;
    let rp = rs * (t1 - t2) / (t1 + t2);
    let r = 0.5 * (rs + rp);
    if r.is_finite() { r.clamp(0.0, 1.0) } else { 1.0 }
}

/// `fresnel_conductor` against [`fresnel_conductor_two_divisions`]: within a relative 1e-6 or
/// an absolute 1e-7 (f32 rounding of the result is 6e-8 relative).
fn assert_conductor_fresnel_matches_two_divisions(cos: f32, eta: f32, k: f32) {
    let expected = fresnel_conductor_two_divisions(cos, eta, k);
    let got = fresnel_conductor(cos, eta, k) as f64;
    let error = (got - expected).abs();
    assert!(
        error <= 1e-7 || error <= 1e-6 * expected,
        "cos {cos:e} η {eta} k {k}: {got:e} vs two divisions {expected:e} (error {error:e})"
    );
}

/// The one-division form of the conductor reflectance agrees with the two-division textbook
/// form on a dense grid: cos from 0 to 1 (both exactly, and grazing and near-normal values),
/// η ∈ {0, 0.05, …, 5} and k ∈ {0, 0.05, …, 10}, so η = 0 with k > 0, k = 0 with η > 0 and η = 1,
/// k = 0 at cos = 0 (a denominator of 0) are all on it.
#[test]
fn conductor_fresnel_one_division_matches_two_divisions_on_a_dense_grid() {
    let mut cosines: Vec<f32> = (0..=500).map(|i| i as f32 / 500.0).collect();
    cosines.extend([1e-7f32, 1e-6, 1e-5, 1e-4, 1e-3, 0.999, 0.9999, 0.99999, 1.0 - f32::EPSILON / 2.0]);
    let mut points = 0;
    for eta in (0..=100).map(|i| i as f32 / 20.0) {
        for k in (0..=200).map(|j| j as f32 / 20.0) {
            for &cos in &cosines {
                assert_conductor_fresnel_matches_two_divisions(cos, eta, k);
                points += 1;
            }
        }
    }
    assert_eq!(points, 101 * 201 * 510);
}

/// The special cases of the conductor reflectance are those of the two-division form: a
/// denominator of 0 (η = 1, k = 0 at grazing incidence) and every non-finite value give 1, η = k
/// = 0 is a mirror at every angle (also cos = 1, where t₁ = 0), the sign of the cosine does not
/// matter, a cosine above 1 (or NaN) is normal incidence, and tiny or huge indices stay finite.
#[test]
fn conductor_fresnel_special_cases_match_two_divisions() {
    assert_eq!(fresnel_conductor(0.0, 1.0, 0.0), 1.0);
    assert_eq!(fresnel_conductor_two_divisions(0.0, 1.0, 0.0), 1.0);
    for cos in [0.0f32, 0.3, 1.0, -0.5] {
        for (eta, k) in [(0.0f32, 0.0f32), (-0.0, 0.0), (0.0, -0.0)] {
            assert_eq!(fresnel_conductor(cos, eta, k), 1.0, "cos {cos} η {eta} k {k}");
        }
    }
    let special = [
        0.0f32,
        -0.0,
        1.0,
        -1.0,
        1e-45,
        1e-30,
        1e-10,
        0.5,
        3.0,
        1e10,
        1e30,
        f32::MAX,
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::NAN,
    ];
    let cosines = [0.0f32, -0.0, 1e-45, 1e-20, 0.2, -0.2, 0.7, 1.0, -1.0, 1.5, f32::INFINITY, f32::NAN];
    for &cos in &cosines {
        for &eta in &special {
            for &k in &special {
                assert_conductor_fresnel_matches_two_divisions(cos, eta, k);
                let got = fresnel_conductor(cos, eta, k);
                assert!((0.0..=1.0).contains(&got), "cos {cos} η {eta} k {k}: {got}");
                if !(eta.is_finite() && k.is_finite()) {
                    assert_eq!(got, 1.0, "cos {cos} η {eta} k {k}");
                }
            }
        }
    }
}

/// `fresnel_conductor_rgb` computes the three channels together; each equals the scalar
/// function bit for bit, also when the channels mix ordinary, mirror and non-finite indices.
#[test]
fn conductor_fresnel_rgb_is_the_scalar_function_per_channel() {
    let special = [0.0f32, 1.0, 1e-45, f32::MAX, f32::INFINITY, f32::NAN];
    let mut rng = Rng::new(91, 7);
    let pick = |rng: &mut Rng| {
        if rng.uniform() < 0.1 {
            special[(rng.next_u32() % special.len() as u32) as usize]
        } else {
            10.0 * rng.uniform()
        }
    };
    for i in 0..200_000 {
        let cos = match i % 50 {
            0 => 0.0,
            1 => 1.0,
            _ => 2.0 * rng.uniform() - 1.0,
        };
        let eta = Rgb::new(pick(&mut rng), pick(&mut rng), pick(&mut rng));
        let k = Rgb::new(pick(&mut rng), pick(&mut rng), pick(&mut rng));
        let rgb = fresnel_conductor_rgb(cos, eta, k);
        let scalar = [(eta.r, k.r), (eta.g, k.g), (eta.b, k.b)].map(|(e, k)| fresnel_conductor(cos, e, k));
        assert_eq!(
            [rgb.r, rgb.g, rgb.b].map(f32::to_bits),
            scalar.map(f32::to_bits),
            "cos {cos} η {eta:?} k {k:?}: {rgb:?} vs {scalar:?}"
        );
    }
}

/// The total reflectors that `fresnel_conductor_rgb` answers without the formula (`η = 0`,
/// `k` = 0 or 1 per channel): the formula itself, through the scalar function, gives exactly
/// 1 for them at every angle, so the shortcut changes no value. A shortcut taken for another
/// index (here `k = 0.5`, `η = 0.01`) would fail the per-channel comparison.
#[test]
fn conductor_fresnel_of_total_reflectors_is_one() {
    let mut rng = Rng::new(17, 3);
    let mut cosines = vec![0.0f32, -0.0, 1e-45, 1e-30, 1e-7, 0.5, 1.0, -1.0, 1.5, f32::INFINITY, f32::NAN];
    cosines.extend((0..100_000).map(|_| 2.0 * rng.uniform() - 1.0));
    let ks = [Rgb::BLACK, Rgb::WHITE, Rgb::new(0.0, 1.0, 0.0), Rgb::new(1.0, 1.0, 0.0), Rgb::new(-0.0, 1.0, 1.0)];
    for &cos in &cosines {
        for k in ks {
            for eta in [Rgb::BLACK, Rgb::splat(-0.0)] {
                let scalar = [k.r, k.g, k.b].map(|k| fresnel_conductor(cos, 0.0, k));
                assert_eq!(scalar, [1.0; 3], "cos {cos} k {k:?}");
                assert_eq!(fresnel_conductor_rgb(cos, eta, k), Rgb::WHITE, "cos {cos} k {k:?}");
            }
        }
        // Not total reflectors: the general formula, per channel.
        for (eta, k) in [(Rgb::BLACK, Rgb::splat(0.5)), (Rgb::new(0.0, 0.0, 0.01), Rgb::WHITE)] {
            let rgb = fresnel_conductor_rgb(cos, eta, k);
            let scalar = [(eta.r, k.r), (eta.g, k.g), (eta.b, k.b)].map(|(e, k)| fresnel_conductor(cos, e, k));
            assert_eq!([rgb.r, rgb.g, rgb.b].map(f32::to_bits), scalar.map(f32::to_bits), "cos {cos}");
        }
    }
}

#[test]
fn diffuse_fresnel_reflectance_fit_matches_quadrature() {
    for eta in [1.0f32 / 1.5, 1.2, 1.5, 1.9] {
        // 2 ∫₀¹ F(μ) μ dμ by the midpoint rule.
        let steps = 20_000;
        let mut sum = 0.0f64;
        for i in 0..steps {
            let mu = (i as f64 + 0.5) / steps as f64;
            sum += fresnel_dielectric(mu as f32, eta) as f64 * mu;
        }
        let exact = 2.0 * sum / steps as f64;
        let fit = fresnel_diffuse_reflectance(eta) as f64;
        assert!((fit - exact).abs() < 0.01 * exact, "η {eta}: fit {fit} vs {exact}");
    }
}

#[test]
fn visible_normal_sampler_matches_its_pdf() {
    let significance = sidak(1e-3, 6);
    let mut seed = 40;
    for (ax, ay) in [(0.05f32, 0.05f32), (0.3, 0.3), (1.0, 0.2)] {
        let ggx = Microfacet::ggx(ax, ay);
        for cos in [0.9f32, 0.15] {
            let w = Vec3::new((1.0 - cos * cos).sqrt() * 0.6, (1.0 - cos * cos).sqrt() * 0.8, cos);
            seed += 1;
            let outcome = chi2_sphere(
                |rng: &mut Rng| Some(ggx.sample_visible(w, rng.uniform2())),
                |m| ggx.visible_pdf(w, m) as f64,
                100_000,
                seed,
                32,
                32,
            );
            assert_chi2(&outcome, significance, &format!("visible normals α {ax}×{ay}, cos {cos}"));
            assert!((outcome.pdf_integral - 1.0).abs() < 2e-3, "∫ D_w = {}", outcome.pdf_integral);
        }
    }
}

#[test]
fn smooth_models_have_the_right_delta_weights() {
    let n = geometric_normal();
    let point = flat_point();
    let weight = |s: &scene::BsdfSample| s.value * (s.cos_generated / s.pdf.forward.0);
    let mirror_of = |d: Vec3| 2.0 * d.dot(n) * n - d;
    for theta in [3.0f32, 45.0, 80.0] {
        let fixed = direction_at(n, theta, 0.4);
        let cos = fixed.dot(n);
        for mode in MODES {
            // Perfect mirror: weight 1 into the mirror direction.
            let b = Bsdf::new(&Material::perfect_mirror(), &point, fixed, mode).unwrap();
            assert!(b.is_delta() && b.has_specular() && b.continuation_probability() == 1.0);
            let s = b.sample([0.2, 0.7, 0.4]).unwrap();
            assert!((s.direction - mirror_of(fixed)).length() < 1e-5);
            assert!((weight(&s).r - 1.0).abs() < 1e-5);
            // Conductor: weight F per channel.
            let m = Material::Conductor { eta: CU_ETA, k: CU_K, specular_reflectance: white() };
            let s = Bsdf::new(&m, &point, fixed, mode).unwrap().sample([0.2, 0.7, 0.4]).unwrap();
            let f = fresnel_complex(cos as f64, CU_ETA.b as f64, CU_K.b as f64) as f32;
            assert!((weight(&s).b - f).abs() < 1e-4, "{} vs {f}", weight(&s).b);
            // Thin dielectric: R' = R + T²R/(1 − R²) reflected, the rest straight through.
            let thin = Material::ThinDielectric {
                int_ior: 1.5,
                ext_ior: 1.0,
                specular_reflectance: white(),
                specular_transmittance: white(),
            };
            let b = Bsdf::new(&thin, &point, fixed, mode).unwrap();
            let r = fresnel_dielectric(cos, 1.5);
            let expected = r + sqr(1.0 - r) * r / (1.0 - r * r);
            let s = b.sample_specular([0.5, 0.5, 0.0]).unwrap();
            assert_eq!(s.lobe, LobeKind::SpecularReflection);
            assert!((s.pdf.forward.0 - expected).abs() < 1e-5, "R' {} vs {expected}", s.pdf.forward.0);
            assert!((weight(&s).r - 1.0).abs() < 1e-4);
            let s = b.sample([0.5, 0.5, 0.9999]).unwrap();
            assert_eq!(s.lobe, LobeKind::SpecularTransmission);
            assert!((s.direction + fixed).length() < 1e-5, "straight through");
            assert!((weight(&s).r - 1.0).abs() < 1e-4);
            // Its null transmission (what volumetric shadow rays multiply by) is 1 − R'; other
            // materials have none.
            let null = b.null_transmission().expect("a thin dielectric is a null interface");
            assert!((null.g - (1.0 - expected)).abs() < 1e-5, "1 − R' {} vs {}", null.g, 1.0 - expected);
            assert!(Bsdf::new(&m, &point, fixed, mode).unwrap().null_transmission().is_none());
            // Dielectric from inside at 3° (no total reflection): radiance weight (η_in/η_out)².
            let inside = direction_at(n, 180.0 - theta.min(30.0), 0.4);
            let b = Bsdf::new(&dielectric(1.5, 1.0), &point, inside, mode).unwrap();
            let s = b.sample([0.5, 0.5, 0.9999]).unwrap();
            assert_eq!(s.lobe, LobeKind::SpecularTransmission);
            let expected = match mode {
                TransportMode::Radiance => 1.5 * 1.5,
                TransportMode::Importance => 1.0,
            };
            assert!((weight(&s).r - expected).abs() < 1e-4 * expected, "{} vs {expected}", weight(&s).r);
        }
    }
}

#[test]
fn plastic_follows_mitsubas_formulas() {
    let n = Vec3::Z;
    let point = ShadingPoint::flat(n);
    let (eta, rho) = (1.5f32, Rgb::new(0.5, 0.3, 0.2));
    for nonlinear in [false, true] {
        let m = plastic(eta, nonlinear);
        let fixed = direction_at(n, 50.0, 0.0);
        let generated = direction_at(n, 20.0, 2.0);
        let b = Bsdf::new(&m, &point, fixed, TransportMode::Radiance).unwrap();
        assert!(b.has_specular() && !b.is_delta());
        let e = b.evaluate(generated).unwrap();
        let (fi, fo) = (fresnel_dielectric(fixed.z, eta), fresnel_dielectric(generated.z, eta));
        // Internal diffuse reflectance by quadrature, independent of the fit.
        let steps = 20_000;
        let fdr: f32 = (0..steps)
            .map(|i| {
                let mu = (i as f32 + 0.5) / steps as f32;
                fresnel_dielectric(mu, 1.0 / eta) * mu
            })
            .sum::<f32>()
            * 2.0
            / steps as f32;
        let base = if nonlinear { rho.r / (1.0 - rho.r * fdr) } else { rho.r / (1.0 - fdr) };
        let expected = base * (1.0 - fi) * (1.0 - fo) / (eta * eta * math::PI);
        assert!((e.value.r - expected).abs() < 0.01 * expected, "{} vs {expected}", e.value.r);
        // Specular sampling weight s/(d + s) with the channel means, Fresnel-weighted.
        let sw = 1.0 / (rho.average() + 1.0);
        let ps = fi * sw / (fi * sw + (1.0 - fi) * (1.0 - sw));
        assert!((e.pdf.forward.0 - (1.0 - ps) * generated.z / math::PI).abs() < 1e-5);
        let s = b.sample([0.3, 0.3, 0.0]).unwrap();
        assert_eq!(s.lobe, LobeKind::SpecularReflection);
        assert!((s.pdf.forward.0 - ps).abs() < 1e-6);
        assert!((s.value.r * s.cos_generated - fi).abs() < 1e-5, "ρ = F");
    }
}

#[test]
fn two_sided_and_blend_combine_their_parts() {
    let point = tilted_point();
    let flipped = ShadingPoint {
        geometric_normal: -point.geometric_normal,
        shading_normal: -point.shading_normal,
        uv: point.uv,
        ..point
    };
    let n = point.geometric_normal;
    let front = rough_conductor(0.3, 0.3);
    let two = Material::TwoSided { front: Box::new(front.clone()), back: Some(Box::new(diffuse())) };
    let same = Material::TwoSided { front: Box::new(front.clone()), back: None };
    let mixed = blend(0.3, diffuse(), front.clone());
    let mut rng = Rng::for_stream(23, 0, 0);
    for _ in 0..500 {
        let a = direction_at(n, 80.0 * rng.uniform(), 6.3 * rng.uniform());
        let b = direction_at(n, 80.0 * rng.uniform(), 6.3 * rng.uniform());
        for mode in MODES {
            let eval = |m: &Material, p: &ShadingPoint, fixed: Vec3, generated: Vec3| {
                Bsdf::new(m, p, fixed, mode).and_then(|x| x.evaluate(generated))
            };
            // Front: the front material; back: the back material with the normals flipped.
            assert_eq!(eval(&two, &point, a, b).map(|e| e.value), eval(&front, &point, a, b).map(|e| e.value));
            let back = eval(&two, &point, -a, -b).map(|e| (e.value, e.pdf));
            assert_eq!(back, eval(&diffuse(), &flipped, -a, -b).map(|e| (e.value, e.pdf)));
            assert!(eval(&diffuse(), &point, -a, -b).is_none(), "one-sided from behind");
            let back_same = eval(&same, &point, -a, -b).map(|e| e.value);
            assert_eq!(back_same, eval(&front, &flipped, -a, -b).map(|e| e.value));
            // Blend: (1 − w)·first + w·second.
            let (Some(x), Some(y), Some(z)) =
                (eval(&mixed, &point, a, b), eval(&diffuse(), &point, a, b), eval(&front, &point, a, b))
            else {
                continue;
            };
            let expected = y.value * 0.7 + z.value * 0.3;
            assert!((x.value.g - expected.g).abs() <= 1e-5 * expected.g.max(1.0), "{:?} vs {expected:?}", x.value);
        }
    }
}

#[test]
fn inconsistent_or_one_sided_configurations_do_not_scatter() {
    let point = tilted_point();
    let (ng, ns) = (point.geometric_normal, point.shading_normal);
    // A fixed direction above the geometric but below the shading plane.
    let t = ng.cross(ns).normalize();
    let tangent = ns.cross(t).normalize();
    let split = (tangent + 0.5 * (ng - ns) - 0.02 * ns).normalize();
    assert!(split.dot(ng) > 0.0 && split.dot(ns) < 0.0, "{} {}", split.dot(ng), split.dot(ns));
    for case in cases() {
        // A smooth dielectric and a thin sheet follow the shading normal alone, as Mitsuba's
        // do (`shading::sides_allowed`): they scatter the split direction, about `ns`.
        let relaxed = matches!(case.material, Material::Dielectric { .. } | Material::ThinDielectric { .. });
        let bsdf = Bsdf::new(&case.material, &point, split, TransportMode::Radiance);
        assert_eq!(bsdf.is_some(), relaxed, "{}", case.name);
        if let Some(bsdf) = bsdf {
            for u in [[0.5, 0.5, 0.0], [0.5, 0.5, 0.999]] {
                if let Some(sample) = bsdf.sample(u) {
                    let mirror = 2.0 * split.dot(ns) * ns - split;
                    let through = sample.direction.dot(split) < -0.999;
                    let reflected = sample.direction.dot(mirror) > 0.999;
                    let refracted = sample.direction.dot(ns) * split.dot(ns) < 0.0;
                    assert!(through || reflected || refracted, "{}: {:?}", case.name, sample.direction);
                }
            }
        }
        let behind = direction_at(ng, 150.0, 1.0);
        let from_behind = Bsdf::new(&case.material, &point, behind, TransportMode::Radiance);
        assert_eq!(from_behind.is_some(), case.two_sided, "{}", case.name);
    }
    // Black materials do not scatter.
    let black = Material::Diffuse { reflectance: constant(0.0, 0.0, 0.0) };
    assert!(Bsdf::new(&black, &point, ng, TransportMode::Radiance).is_none());
}

/// `Material::is_specular_only` (the VCM camera pass plans no merge query on such hits) answers
/// true for the smooth models and what wraps only them, and then every BSDF built from the
/// material, at a flat and a tilted point, from both sides, in both modes, is delta or absent;
/// the rough and diffuse models, and any wrapper holding one, answer false and build a
/// non-delta BSDF somewhere.
#[test]
fn smooth_models_and_their_wrappers_are_specular_only() {
    let conductor = Material::Conductor { eta: CU_ETA, k: CU_K, specular_reflectance: constant(0.9, 0.8, 1.0) };
    let thin = Material::ThinDielectric {
        int_ior: 1.5,
        ext_ior: 1.0,
        specular_reflectance: white(),
        specular_transmittance: constant(0.9, 0.9, 0.7),
    };
    let mapped = |nested: Material| Material::NormalMap {
        normals: constant(0.6, 0.45, 0.9),
        nested: Box::new(nested),
        options: scene::material::MapOptions::MITSUBA,
    };
    let two_sided = |front: Material, back: Option<Material>| Material::TwoSided {
        front: Box::new(front),
        back: back.map(Box::new),
    };
    let specular = [
        ("conductor", conductor.clone()),
        ("perfect mirror", Material::perfect_mirror()),
        ("dielectric", dielectric(1.5, 1.0)),
        ("thin dielectric", thin.clone()),
        ("blend of conductor and dielectric", blend(0.4, conductor.clone(), dielectric(1.3, 1.0))),
        ("two-sided conductor", two_sided(conductor.clone(), None)),
        ("two-sided conductor / mirror", two_sided(conductor.clone(), Some(Material::perfect_mirror()))),
        ("normal-mapped dielectric", mapped(dielectric(1.5, 1.0))),
        ("normal-mapped thin dielectric", mapped(thin)),
    ];
    let not_specular = [
        ("diffuse", diffuse()),
        ("rough conductor", rough_conductor(0.05, 0.05)),
        ("rough dielectric", rough_dielectric(0.05, 0.05, 1.5, 1.0)),
        ("plastic", plastic(1.5, false)),
        ("blend of conductor and diffuse", blend(0.999, conductor.clone(), diffuse())),
        ("two-sided conductor / diffuse", two_sided(conductor.clone(), Some(diffuse()))),
        ("normal-mapped rough conductor", mapped(rough_conductor(0.3, 0.3))),
    ];
    let flat = flat_point();
    let points = [flat, tilted_point()];
    for (name, material, expected) in
        specular.iter().map(|(n, m)| (n, m, true)).chain(not_specular.iter().map(|(n, m)| (n, m, false)))
    {
        assert_eq!(material.is_specular_only(), expected, "{name}");
        let mut any_non_delta = false;
        for point in &points {
            for theta in [0.5, 20.0, 45.0, 70.0, 88.0, 92.0, 120.0, 160.0] {
                for azimuth in [0.3, 2.5, 4.4] {
                    let fixed = direction_at(point.geometric_normal, theta, azimuth);
                    for mode in MODES {
                        if let Some(bsdf) = Bsdf::new(material, point, fixed, mode) {
                            any_non_delta |= !bsdf.is_delta();
                        }
                    }
                }
            }
        }
        assert_eq!(any_non_delta, !expected, "{name}: some BSDF is not delta");
    }
}
