//! Tests of the lights: chi-square tests of every light's direct (next-event) and emission
//! samplers against their pdfs, and agreement of the pdfs that the three queries report for
//! the same ray.

use math::{Frame, PdfA, Ray, Rng, Vec2, Vec3, warp};
use scene::light::{AreaLight, BackgroundLight, BoundingSphere, DirectionalLight, PointLight};
use scene::shape::Triangle;
use scene::{Light, cornell};
use spectrum::Rgb;
use testkit::{Integration, assert_chi2, chi2_sphere, chi2_sphere_with, chi2_square, sidak};

const SAMPLES: usize = 100_000;

fn sphere() -> BoundingSphere {
    BoundingSphere { center: Vec3::new(0.1, -0.2, 0.3), radius: 2.5 }
}

fn area_light() -> AreaLight {
    let t = Triangle::new(Vec3::new(-0.3, 0.2, 1.0), Vec3::new(0.5, -0.1, 1.1), Vec3::new(0.1, 0.6, 0.8));
    // Emit downwards (towards the receivers below).
    let t = if t.normal.z > 0.0 { Triangle::new(t.p0, t.p2, t.p1) } else { t };
    AreaLight::new(t, Rgb::splat(3.0))
}

#[test]
fn area_light_direct_sampling_matches_its_solid_angle_pdf() {
    let light = area_light();
    let receivers = [Vec3::ZERO, Vec3::new(0.4, 0.3, 0.2), Vec3::new(-1.0, 0.2, 0.9)];
    for receiver in receivers {
        let l = Light::Area(light);
        // The pdf is discontinuous at the triangle's edges: start the quadrature on a finer
        // grid so that thin slivers of the triangle inside a bin are not missed.
        let integration = Integration { initial_split: 12, ..Integration::default() };
        let outcome = chi2_sphere_with(
            |rng: &mut Rng| l.sample_direct(receiver, rng.uniform2(), &sphere()).map(|d| d.direction),
            |direction| {
                // The pdf of the direction: where does it hit the light, and at what cosine?
                let ray = Ray::new(receiver, direction);
                match light.triangle.intersect(&ray, f32::INFINITY) {
                    Some(t) => {
                        let cos = light.triangle.normal.dot(-direction);
                        if cos < math::COSINE_EPSILON {
                            0.0
                        } else {
                            PdfA(1.0 / light.triangle.area()).to_solid_angle(t * t, cos).0 as f64
                        }
                    }
                    None => 0.0,
                }
            },
            SAMPLES,
            1,
            32,
            64,
            &integration,
        );
        assert_chi2(&outcome, sidak(1e-3, receivers.len()), &format!("area light seen from {receiver}"));
    }
}

#[test]
fn area_light_emission_is_uniform_in_area_and_cosine_in_direction() {
    let light = area_light();
    let l = Light::Area(light);
    let frame = Frame::from_z(light.triangle.normal);
    let directions = chi2_sphere(
        |rng: &mut Rng| Some(frame.to_local(l.sample_emission(rng.uniform2(), rng.uniform2(), &sphere()).direction)),
        |local| warp::cosine_hemisphere_pdf(local.z) as f64,
        SAMPLES,
        2,
        16,
        32,
    );
    assert_chi2(&directions, sidak(1e-3, 2), "area light emission directions");
    // Positions: barycentric coordinates mapped back to the unit square by the inverse warp.
    let t = light.triangle;
    let positions = chi2_square(
        |rng: &mut Rng| {
            let p = l.sample_emission(rng.uniform2(), rng.uniform2(), &sphere()).origin;
            let (b1, b2) = barycentric(&t, p);
            let u = warp::uniform_triangle_inverse(Vec2::new(b1, b2));
            Some([u[0] as f64, u[1] as f64])
        },
        |_| 1.0,
        SAMPLES,
        3,
        16,
    );
    assert_chi2(&positions, sidak(1e-3, 2), "area light emission positions");
}

fn barycentric(t: &Triangle, p: Vec3) -> (f32, f32) {
    let (e1, e2, d) = (t.edge1(), t.edge2(), p - t.p0);
    let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (d1, d2) = (d.dot(e1), d.dot(e2));
    let det = d11 * d22 - d12 * d12;
    ((d22 * d1 - d12 * d2) / det, (d11 * d2 - d12 * d1) / det)
}

#[test]
fn point_light_emits_uniformly() {
    let l = Light::Point(PointLight { position: Vec3::new(0.0, 1.0, 2.0), intensity: Rgb::splat(1.0) });
    let outcome = chi2_sphere(
        |rng: &mut Rng| Some(l.sample_emission(rng.uniform2(), rng.uniform2(), &sphere()).direction),
        |_| warp::UNIFORM_SPHERE_PDF as f64,
        SAMPLES,
        4,
        16,
        32,
    );
    assert_chi2(&outcome, 1e-3, "point light emission");
    let s = l.sample_emission([0.3, 0.3], [0.2, 0.9], &sphere());
    assert_eq!(s.origin, Vec3::new(0.0, 1.0, 2.0));
    let d = l.sample_direct(Vec3::ZERO, [0.5, 0.5], &sphere()).unwrap();
    assert!((d.direct_pdf.0 - 5.0).abs() < 1e-5, "solid-angle pdf of a delta position is distance²");
    assert!((d.distance - 5.0f32.sqrt()).abs() < 1e-6);
}

#[test]
fn background_light_samples_the_sphere_uniformly() {
    let l = Light::Background(BackgroundLight { radiance: Rgb::splat(1.0) });
    let direct = chi2_sphere(
        |rng: &mut Rng| l.sample_direct(Vec3::ZERO, rng.uniform2(), &sphere()).map(|d| d.direction),
        |_| warp::UNIFORM_SPHERE_PDF as f64,
        SAMPLES,
        5,
        16,
        32,
    );
    assert_chi2(&direct, sidak(1e-3, 3), "background direct sampling");
    let emission = chi2_sphere(
        |rng: &mut Rng| Some(l.sample_emission(rng.uniform2(), rng.uniform2(), &sphere()).direction),
        |_| warp::UNIFORM_SPHERE_PDF as f64,
        SAMPLES,
        6,
        16,
        32,
    );
    assert_chi2(&emission, sidak(1e-3, 3), "background emission directions");
    let origins = disc_chi2(&l, 7);
    assert_chi2(&origins, sidak(1e-3, 3), "background emission origins on the disc");
}

/// Chi-square test of emission origins on the bounding-sphere disc (uniform in area).
fn disc_chi2(l: &Light, seed: u64) -> testkit::Chi2Outcome {
    let s = sphere();
    chi2_square(
        |rng: &mut Rng| {
            let e = l.sample_emission(rng.uniform2(), rng.uniform2(), &s);
            let frame = Frame::from_z(e.direction);
            // The disc is centred at centre − R·d, perpendicular to d.
            let offset = (e.origin - (s.center - s.radius * e.direction)) / s.radius;
            assert!(offset.dot(e.direction).abs() < 1e-4, "origin lies in the disc plane");
            let u = warp::concentric_disc_inverse(Vec2::new(offset.dot(frame.x), offset.dot(frame.y)));
            Some([u[0] as f64, u[1] as f64])
        },
        |_| 1.0,
        SAMPLES,
        seed,
        16,
    )
}

#[test]
fn directional_light_emits_along_its_direction_from_the_disc() {
    let light = DirectionalLight::new(Vec3::new(-1.0, 1.5, -1.0), Rgb::new(10.0, 4.0, 0.0));
    let l = Light::Directional(light);
    let origins = disc_chi2(&l, 8);
    assert_chi2(&origins, 1e-3, "directional light origins");
    let s = l.sample_emission([0.1, 0.7], [0.4, 0.4], &sphere());
    assert_eq!(s.direction, light.direction);
    let expected_pdf = 1.0 / (math::PI * 2.5 * 2.5);
    assert!((s.emission_pdf.0 - expected_pdf).abs() < 1e-6 * expected_pdf);
    let d = l.sample_direct(Vec3::ZERO, [0.5, 0.5], &sphere()).unwrap();
    assert_eq!(d.direction, -light.direction);
    assert_eq!(d.direct_pdf.0, 1.0);
    assert!(d.distance.is_infinite());
}

#[test]
fn the_three_queries_report_the_same_pdfs_for_the_same_ray() {
    let s = sphere();
    // Area light: direct sample from a receiver, then the same ray as a hit.
    let light = area_light();
    let l = Light::Area(light);
    let receiver = Vec3::new(0.1, 0.1, 0.0);
    let mut rng = Rng::for_stream(1, 2, 3);
    for _ in 0..100 {
        let Some(d) = l.sample_direct(receiver, rng.uniform2(), &s) else { continue };
        let hit = l.radiance_on_hit(d.direction, &s).unwrap();
        let close = |a: f32, b: f32| (a - b).abs() <= 1e-4 * a.abs().max(b.abs());
        assert!(close(hit.emission_pdf.0, d.emission_pdf.0));
        assert!(close(hit.direct_pdf.to_solid_angle(d.distance * d.distance, d.cos_at_light).0, d.direct_pdf.0));
        assert!(close(hit.cos_at_light, d.cos_at_light));
        assert!(l.radiance_on_hit(-d.direction, &s).is_none(), "one-sided");
    }
    // Emission: the emission pdf is area pdf × cosine pdf.
    let e = l.sample_emission([0.2, 0.3], [0.6, 0.5], &s);
    let expected = e.direct_pdf.0 * warp::cosine_hemisphere_pdf(e.cos_at_light);
    assert!((e.emission_pdf.0 - expected).abs() < 1e-5 * expected);
    assert!((e.energy.r - 3.0 * e.cos_at_light).abs() < 1e-5);
    // Background: direct, emission and hit agree.
    let b = Light::Background(BackgroundLight { radiance: Rgb::splat(0.5) });
    let d = b.sample_direct(receiver, [0.3, 0.8], &s).unwrap();
    let hit = b.radiance_on_hit(d.direction, &s).unwrap();
    let e = b.sample_emission([0.3, 0.8], [0.3, 0.8], &s);
    assert_eq!(hit.emission_pdf, d.emission_pdf);
    assert_eq!(e.emission_pdf, d.emission_pdf);
    assert_eq!(hit.direct_pdf.0, d.direct_pdf.0);
    // Delta lights cannot be hit; flags.
    let p = Light::Point(PointLight { position: Vec3::ZERO, intensity: Rgb::WHITE });
    assert!(p.radiance_on_hit(Vec3::Z, &s).is_none() && p.is_delta() && p.is_finite());
    assert!(!b.is_delta() && !b.is_finite());
    assert!(l.is_finite() && !l.is_delta());
}

#[test]
fn cornell_area_lights_emit_downwards_with_the_specified_power() {
    let scene = cornell::build(273, 16, 16).unwrap();
    let total_area: f32 = scene
        .lights
        .iter()
        .map(|l| match l {
            Light::Area(a) => {
                assert_eq!(a.triangle.normal, -Vec3::Z);
                a.triangle.area()
            }
            _ => panic!("scene 1 has only area lights"),
        })
        .sum();
    // Power L·π·A = 19.661 per channel.
    let power = cornell::LIGHT_BOX_RADIANCE * math::PI * total_area;
    assert!((power - 19.661).abs() < 1e-3, "{power}");
}
