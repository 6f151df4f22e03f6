//! Tests of the lights: chi-square tests of every light's direct (next-event) and emission
//! samplers against their pdfs, agreement of the pdfs and radiance that the three queries report
//! for the same ray, the environment map's lat-long convention, and each light's power against
//! the Monte Carlo flux of its emission sampler.

use std::sync::Arc;

use math::{Frame, PdfA, Ray, Rng, Vec2, Vec3, warp};
use scene::desc::{LightDesc, TextureImage};
use scene::light::{AreaLight, BackgroundLight, BoundingSphere, DirectionalLight, PointLight, SpotLight};
use scene::shape::{Sphere, Triangle};
use scene::{Light, cornell};
use spectrum::Rgb;
use testkit::{Integration, MeanVar, assert_chi2, chi2_sphere, chi2_sphere_with, chi2_square, sidak, z_test_p};

const SAMPLES: usize = 100_000;

fn sphere() -> BoundingSphere {
    BoundingSphere { center: Vec3::new(0.1, -0.2, 0.3), radius: 2.5 }
}

fn area_triangle() -> Triangle {
    let t = Triangle::new(Vec3::new(-0.3, 0.2, 1.0), Vec3::new(0.5, -0.1, 1.1), Vec3::new(0.1, 0.6, 0.8));
    // Emit downwards (towards the receivers below).
    if t.normal.z > 0.0 { Triangle::new(t.p0, t.p2, t.p1) } else { t }
}

fn area_light() -> AreaLight {
    AreaLight::new(area_triangle(), Rgb::splat(3.0))
}

#[test]
fn area_light_direct_sampling_matches_its_solid_angle_pdf() {
    let light = area_light();
    let triangle = area_triangle();
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
                match triangle.intersect(&ray, f32::INFINITY) {
                    Some(t) => {
                        let cos = triangle.normal.dot(-direction);
                        if cos < math::COSINE_EPSILON {
                            0.0
                        } else {
                            PdfA(1.0 / triangle.area()).to_solid_angle(t * t, cos).0 as f64
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
    let frame = Frame::from_z(area_triangle().normal);
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
    let t = area_triangle();
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
        let hit = l.radiance_on_hit(d.direction, Vec3::ZERO, area_triangle().normal, &s).unwrap();
        let close = |a: f32, b: f32| (a - b).abs() <= 1e-4 * a.abs().max(b.abs());
        assert!(close(hit.emission_pdf.0, d.emission_pdf.0));
        assert!(close(hit.direct_pdf.to_solid_angle(d.distance * d.distance, d.cos_at_light).0, d.direct_pdf.0));
        assert!(close(hit.cos_at_light, d.cos_at_light));
        assert!(l.radiance_on_hit(-d.direction, Vec3::ZERO, area_triangle().normal, &s).is_none(), "one-sided");
    }
    // Emission: the emission pdf is area pdf × cosine pdf.
    let e = l.sample_emission([0.2, 0.3], [0.6, 0.5], &s);
    let expected = e.direct_pdf.0 * warp::cosine_hemisphere_pdf(e.cos_at_light);
    assert!((e.emission_pdf.0 - expected).abs() < 1e-5 * expected);
    assert!((e.energy.r - 3.0 * e.cos_at_light).abs() < 1e-5);
    // Background: direct, emission and hit agree.
    let b = Light::Background(BackgroundLight { radiance: Rgb::splat(0.5) });
    let d = b.sample_direct(receiver, [0.3, 0.8], &s).unwrap();
    let hit = b.radiance_on_hit(d.direction, Vec3::ZERO, Vec3::ZERO, &s).unwrap();
    let e = b.sample_emission([0.3, 0.8], [0.3, 0.8], &s);
    assert_eq!(hit.emission_pdf, d.emission_pdf);
    assert_eq!(e.emission_pdf, d.emission_pdf);
    assert_eq!(hit.direct_pdf.0, d.direct_pdf.0);
    // Delta lights cannot be hit; flags.
    let p = Light::Point(PointLight { position: Vec3::ZERO, intensity: Rgb::WHITE });
    assert!(p.radiance_on_hit(Vec3::Z, Vec3::ZERO, Vec3::ZERO, &s).is_none() && p.is_delta() && p.is_finite());
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
                assert_eq!(a.triangle().unwrap().normal, -Vec3::Z);
                a.area()
            }
            _ => panic!("scene 1 has only area lights"),
        })
        .sum();
    // Power L·π·A = 19.661 per channel.
    let power = cornell::LIGHT_BOX_RADIANCE * math::PI * total_area;
    assert!((power - 19.661).abs() < 1e-3, "{power}");
}

// ---------------------------------------------------------------------------------------------
// Spheres and discs.

const SPHERE_CENTER: Vec3 = Vec3::new(0.2, -0.1, 1.5);
const SPHERE_RADIUS: f32 = 0.4;

fn sphere_light(flip_normals: bool) -> AreaLight {
    AreaLight::sphere(SPHERE_CENTER, SPHERE_RADIUS, flip_normals, Rgb::new(2.0, 1.0, 0.5)).unwrap()
}

/// Front normal of the emitting sphere at a point on it.
fn sphere_front(p: Vec3, flip_normals: bool) -> Vec3 {
    let n = (p - SPHERE_CENTER).normalize();
    if flip_normals { -n } else { n }
}

/// Solid-angle pdf of uniform area sampling of a one-sided surface, seen from `receiver` in unit
/// direction `direction`: `t²/(A·cos)` at the first intersection whose front faces the
/// receiver (the surfaces here are convex, so only the first intersection can).
fn area_sampling_pdf(t: f32, cos: f32, area: f32) -> f64 {
    if cos < math::COSINE_EPSILON { 0.0 } else { PdfA(1.0 / area).to_solid_angle(t * t, cos).0 as f64 }
}

#[test]
fn sphere_light_direct_sampling_matches_its_solid_angle_pdf() {
    let shape = Sphere { center: SPHERE_CENTER, radius: SPHERE_RADIUS };
    let area = 4.0 * math::PI * SPHERE_RADIUS * SPHERE_RADIUS;
    // Outside receivers see the near cap of an outward sphere, whose solid-angle pdf is singular
    // (1/cos) at the silhouette; an inside receiver sees all of a flipped one. The bins are
    // laid out around the axis from the receiver to the centre (the pdf depends on θ only), and
    // the receivers are placed so that the silhouette (cos θ = √(1 − R²/D²)) falls inside a bin
    // (0.8125 and 0.6875 for 16 bins), not on an edge where the quadrature would evaluate the
    // singularity itself.
    let at_silhouette_cosine = |cos: f32, towards: Vec3| {
        let distance = SPHERE_RADIUS / (1.0 - cos * cos).sqrt();
        SPHERE_CENTER - distance * towards.normalize()
    };
    let cases = [
        (at_silhouette_cosine(0.8125, Vec3::new(0.1, 0.2, 1.0)), false),
        (at_silhouette_cosine(0.6875, Vec3::new(-1.0, 0.3, 0.2)), false),
        (Vec3::new(0.3, -0.2, 1.6), true),
    ];
    let integration = Integration { max_depth: 9, ..Integration::default() };
    for (receiver, flip) in cases {
        let l = Light::Area(sphere_light(flip));
        let frame = Frame::from_z((SPHERE_CENTER - receiver).normalize());
        let outcome = chi2_sphere_with(
            |rng: &mut Rng| l.sample_direct(receiver, rng.uniform2(), &sphere()).map(|d| frame.to_local(d.direction)),
            |local| {
                let direction = frame.to_world(local);
                match shape.intersect(&Ray::new(receiver, direction), f32::INFINITY) {
                    Some(t) => {
                        let p = receiver + t * direction;
                        area_sampling_pdf(t, sphere_front(p, flip).dot(-direction), area)
                    }
                    None => 0.0,
                }
            },
            SAMPLES,
            20,
            16,
            32,
            &integration,
        );
        assert_chi2(&outcome, sidak(1e-3, cases.len()), &format!("sphere light seen from {receiver}"));
        if !flip {
            // The visible cap is the fraction (1 − R/D)/2 of the area.
            let visible = 0.5 * (1.0 - SPHERE_RADIUS / (SPHERE_CENTER - receiver).length()) as f64;
            assert!((outcome.pdf_integral - visible).abs() < 2e-3, "{} vs {visible}", outcome.pdf_integral);
        }
    }
}

const DISC_CENTER: Vec3 = Vec3::new(-0.1, 0.2, 1.2);
const DISC_U: Vec3 = Vec3::new(0.5, 0.1, 0.0);
const DISC_V: Vec3 = Vec3::new(0.2, 0.3, 0.1);

/// An elliptic disc (unequal, non-orthogonal axes) whose front faces down (−z) unless flipped.
fn disc_light(flip_normals: bool) -> AreaLight {
    // axis_u × axis_v points up (+z component 0.13), so flip to face the receivers below.
    AreaLight::disc(DISC_CENTER, DISC_U, DISC_V, !flip_normals, Rgb::new(0.5, 4.0, 1.0)).unwrap()
}

/// Intersection of a ray with the disc by solving `o + t·d = c + x·u + y·v`: `(t, x, y)`.
fn disc_intersection(origin: Vec3, direction: Vec3) -> Option<(f32, f32, f32)> {
    let m = glam::Mat3::from_cols(DISC_U, DISC_V, -direction);
    let solution = m.inverse() * (origin - DISC_CENTER);
    let (x, y, t) = (solution.x, solution.y, solution.z);
    (t > 0.0 && x * x + y * y <= 1.0).then_some((t, x, y))
}

#[test]
fn disc_light_direct_sampling_matches_its_solid_angle_pdf() {
    let geometric_normal = DISC_U.cross(DISC_V).normalize();
    let area = math::PI * DISC_U.cross(DISC_V).length();
    let cases = [(Vec3::ZERO, false), (Vec3::new(0.9, -0.4, 0.5), false), (Vec3::new(0.1, 0.3, 2.0), true)];
    let integration = Integration { initial_split: 4, ..Integration::default() };
    for (receiver, flip) in cases {
        let l = Light::Area(disc_light(flip));
        let front = if flip { geometric_normal } else { -geometric_normal };
        let outcome = chi2_sphere_with(
            |rng: &mut Rng| l.sample_direct(receiver, rng.uniform2(), &sphere()).map(|d| d.direction),
            |direction| match disc_intersection(receiver, direction) {
                Some((t, _, _)) => area_sampling_pdf(t, front.dot(-direction), area),
                None => 0.0,
            },
            SAMPLES,
            21,
            16,
            32,
            &integration,
        );
        assert_chi2(&outcome, sidak(1e-3, cases.len() + 1), &format!("disc light seen from {receiver}"));
    }
    // Emission positions: uniform on the unit disc they map back to.
    let l = Light::Area(disc_light(false));
    let positions = chi2_square(
        |rng: &mut Rng| {
            let e = l.sample_emission(rng.uniform2(), rng.uniform2(), &sphere());
            let (_, x, y) = disc_intersection(e.origin + geometric_normal, -geometric_normal)?;
            let u = warp::concentric_disc_inverse(Vec2::new(x, y));
            Some([u[0] as f64, u[1] as f64])
        },
        |_| 1.0,
        SAMPLES,
        22,
        16,
    );
    assert_chi2(&positions, sidak(1e-3, cases.len() + 1), "disc light emission positions");
}

#[test]
fn sphere_and_disc_emission_is_cosine_weighted_about_the_front_normal() {
    for (name, light, front) in [
        ("sphere", sphere_light(false), (|p| sphere_front(p, false)) as FrontNormal),
        ("flipped sphere", sphere_light(true), |p| sphere_front(p, true)),
        ("disc", disc_light(false), |_| -DISC_U.cross(DISC_V).normalize()),
    ] {
        let l = Light::Area(light);
        let outcome = chi2_sphere(
            |rng: &mut Rng| {
                let e = l.sample_emission(rng.uniform2(), rng.uniform2(), &sphere());
                Some(Frame::from_z(front(e.origin)).to_local(e.direction))
            },
            |local| warp::cosine_hemisphere_pdf(local.z) as f64,
            SAMPLES / 2,
            23,
            16,
            32,
        );
        assert_chi2(&outcome, sidak(1e-3, 3), &format!("{name} emission directions"));
    }
    // Sphere positions: uniform by area, i.e. uniform directions from the centre.
    let l = Light::Area(sphere_light(false));
    let positions = chi2_sphere(
        |rng: &mut Rng| {
            Some((l.sample_emission(rng.uniform2(), rng.uniform2(), &sphere()).origin - SPHERE_CENTER).normalize())
        },
        |_| warp::UNIFORM_SPHERE_PDF as f64,
        SAMPLES / 2,
        24,
        16,
        32,
    );
    assert_chi2(&positions, 1e-3, "sphere emission positions");
}

// ---------------------------------------------------------------------------------------------
// Spot light.

const SPOT_CUTOFF: f32 = 35.0;
const SPOT_BEAM: f32 = 20.0;

fn spot() -> SpotLight {
    SpotLight::new(
        Vec3::new(0.3, 1.0, -0.2),
        Vec3::new(0.2, -1.0, 0.4),
        Rgb::new(5.0, 3.0, 1.0),
        SPOT_CUTOFF,
        SPOT_BEAM,
    )
    .unwrap()
}

#[test]
fn spot_light_emits_uniformly_in_its_cutoff_cone() {
    let light = spot();
    let l = Light::Spot(light.clone());
    let frame = Frame::from_z(light.axis());
    let cos_cutoff = SPOT_CUTOFF.to_radians().cos();
    let outcome = chi2_sphere(
        |rng: &mut Rng| Some(frame.to_local(l.sample_emission(rng.uniform2(), rng.uniform2(), &sphere()).direction)),
        |local| if local.z > cos_cutoff { 1.0 / (2.0 * std::f64::consts::PI * (1.0 - cos_cutoff as f64)) } else { 0.0 },
        SAMPLES,
        30,
        32,
        16,
    );
    assert_chi2(&outcome, 1e-3, "spot light emission directions");
    let e = l.sample_emission([0.1, 0.2], [0.3, 0.4], &sphere());
    assert_eq!(e.origin, light.position);
}

#[test]
fn spot_light_falls_off_linearly_in_angle_like_mitsuba() {
    let light = spot();
    let l = Light::Spot(light.clone());
    let frame = Frame::from_z(light.axis());
    // Mitsuba 3: 1 inside the beam, (cutoff − θ)/(cutoff − beam) in the transition, 0 beyond.
    let expected = |theta: f32| {
        if theta <= SPOT_BEAM {
            1.0
        } else if theta < SPOT_CUTOFF {
            (SPOT_CUTOFF - theta) / (SPOT_CUTOFF - SPOT_BEAM)
        } else {
            0.0
        }
    };
    for theta in [0.0f32, 10.0, 19.5, 20.5, 25.0, 30.0, 34.0, 34.9, 36.0, 90.0, 170.0] {
        let (s, c) = theta.to_radians().sin_cos();
        let emitted = frame.to_world(Vec3::new(0.6 * s, 0.8 * s, c));
        let receiver = light.position + 2.5 * emitted;
        let want = expected(theta);
        match l.sample_direct(receiver, [0.5, 0.5], &sphere()) {
            Some(d) => {
                assert!((d.radiance.r - 5.0 * want).abs() < 1e-4, "θ = {theta}°: {} vs {}", d.radiance.r, 5.0 * want);
                assert!((d.direct_pdf.0 - 6.25).abs() < 1e-4, "distance² = 6.25");
                assert!((d.distance - 2.5).abs() < 1e-5 && (d.direction + emitted).length() < 1e-5);
            }
            None => assert_eq!(want, 0.0, "θ = {theta}°: nothing emitted, but Mitsuba's falloff is {want}"),
        }
    }
    // Bad descriptions are errors, not panics.
    assert!(SpotLight::new(Vec3::ZERO, Vec3::Z, Rgb::WHITE, 20.0, 25.0).is_err(), "beam wider than cutoff");
    assert!(SpotLight::new(Vec3::ZERO, Vec3::ZERO, Rgb::WHITE, 20.0, 15.0).is_err(), "zero axis");
    assert!(SpotLight::new(Vec3::ZERO, Vec3::Z, Rgb::WHITE, 0.0, 0.0).is_err(), "zero cutoff");
    assert!(SpotLight::new(Vec3::ZERO, Vec3::Z, Rgb::new(f32::NAN, 0.0, 0.0), 20.0, 15.0).is_err());
    assert!(SpotLight::new(Vec3::ZERO, Vec3::Z, Rgb::WHITE, 20.0, 20.0).is_ok(), "no transition");
}

// ---------------------------------------------------------------------------------------------
// Environment map.

const ENV_W: u32 = 8;
const ENV_H: u32 = 5;

/// A gradient with a black patch, a bright spot at pixel (3, 2), scale 1.5.
fn env_image() -> TextureImage {
    let mut pixels = Vec::new();
    for y in 0..ENV_H {
        for x in 0..ENV_W {
            let black = (5..7).contains(&x) && (2..4).contains(&y);
            pixels.push(if (x, y) == (2, 1) {
                Rgb::new(40.0, 30.0, 20.0)
            } else if black {
                Rgb::BLACK
            } else {
                Rgb::new(0.1 + 0.05 * x as f32, 0.2 + 0.1 * y as f32, 0.05)
            });
        }
    }
    TextureImage { width: ENV_W, height: ENV_H, pixels }
}

/// A rotation about an oblique axis, as the columns of `to_world`.
fn env_rotation() -> [Vec3; 3] {
    let m = glam::Mat3::from_axis_angle(Vec3::new(0.3, 1.0, -0.5).normalize(), 1.1);
    [m.x_axis, m.y_axis, m.z_axis]
}

fn env_light() -> Light {
    Light::from_desc(&LightDesc::EnvMap { image: Arc::new(env_image()), scale: 1.5, to_world: env_rotation() }).unwrap()
}

/// World direction of the map point `(u, v)` by the convention of `LightDesc::EnvMap`
/// (`u = atan2(x, −z)/2π`, `v = acos(y)/π` in the map's frame).
fn env_direction(u: f32, v: f32) -> Vec3 {
    let (theta, phi) = (v * math::PI, u * 2.0 * math::PI);
    let local = Vec3::new(theta.sin() * phi.sin(), theta.cos(), -theta.sin() * phi.cos());
    let [c0, c1, c2] = env_rotation();
    c0 * local.x + c1 * local.y + c2 * local.z
}

#[test]
fn envmap_follows_the_mitsuba_lat_long_convention() {
    // The convention's own inverse: the direction maps back to (u, v).
    let d = glam::Mat3::from_cols(env_rotation()[0], env_rotation()[1], env_rotation()[2]).transpose()
        * env_direction(0.3, 0.6);
    let u = d.x.atan2(-d.z) / (2.0 * math::PI);
    assert!((u - 0.3).abs() < 1e-5 && (d.y.acos() / math::PI - 0.6).abs() < 1e-5);

    // One bright pixel (x0, y0) of a W × H map sits at u = (x0 + ½)/W, v = y0/(H − 1)
    // (Mitsuba 3: pixel centres in u, rows from pole to pole in v).
    let (w, h, x0, y0) = (8u32, 5u32, 5u32, 1u32);
    let value = Rgb::new(7.0, 5.0, 3.0);
    let mut pixels = vec![Rgb::BLACK; (w * h) as usize];
    pixels[(y0 * w + x0) as usize] = value;
    let image = Arc::new(TextureImage { width: w, height: h, pixels });
    let l = Light::from_desc(&LightDesc::EnvMap { image, scale: 2.0, to_world: env_rotation() }).unwrap();
    let s = sphere();
    let at = |x: f32, y: f32| {
        l.radiance_on_hit(env_direction((x + 0.5) / w as f32, y / (h - 1) as f32), Vec3::ZERO, Vec3::ZERO, &s)
            .unwrap()
            .radiance
    };
    let close = |a: Rgb, b: Rgb| (a - b).map(f32::abs).max_component() < 1e-4;
    assert!(close(at(x0 as f32, y0 as f32), value * 2.0), "{:?}", at(x0 as f32, y0 as f32));
    assert!(close(at(x0 as f32 + 1.0, y0 as f32), Rgb::BLACK));
    assert!(close(at(x0 as f32, y0 as f32 + 1.0), Rgb::BLACK));
    // Bilinear in between.
    assert!(close(at(x0 as f32 + 0.5, y0 as f32), value), "{:?}", at(x0 as f32 + 0.5, y0 as f32));
    assert!(close(at(x0 as f32 - 0.25, y0 as f32 + 0.5), value * (2.0 * 0.75 * 0.5)));
    // Row 0 is the map's +y pole.
    let mut pixels = vec![Rgb::BLACK; (w * h) as usize];
    pixels[..w as usize].fill(value);
    let image = Arc::new(TextureImage { width: w, height: h, pixels: pixels.clone() });
    let l = Light::from_desc(&LightDesc::EnvMap { image, scale: 1.0, to_world: env_rotation() }).unwrap();
    assert!(close(l.radiance_on_hit(env_rotation()[1], Vec3::ZERO, Vec3::ZERO, &s).unwrap().radiance, value));
    assert!(close(l.radiance_on_hit(-env_rotation()[1], Vec3::ZERO, Vec3::ZERO, &s).unwrap().radiance, Rgb::BLACK));
    // u wraps around: u = 0 lies halfway between the last and the first pixel centres.
    pixels[(w - 1) as usize] = Rgb::WHITE;
    let image = Arc::new(TextureImage { width: w, height: h, pixels });
    let l = Light::from_desc(&LightDesc::EnvMap { image, scale: 1.0, to_world: env_rotation() }).unwrap();
    let wrap = l.radiance_on_hit(env_direction(0.0, 1e-4), Vec3::ZERO, Vec3::ZERO, &s).unwrap().radiance;
    assert!((wrap.r - 0.5 * (value.r + 1.0)).abs() < 1e-2, "{wrap:?}");
}

#[test]
fn envmap_direct_sampling_matches_its_pdf() {
    let l = env_light();
    let s = sphere();
    let receiver = Vec3::new(0.3, 0.1, -0.2);
    // Bins around the map's pole axis, with φ measured like the map's u, so that the pdf's
    // discontinuities (the cell edges at u = (i + ½)/12 and θ = jπ/6) run along bin edges or
    // lines of constant θ: binned coordinates (x, y, z) = (−v.z, v.x, v.y) of the map-local
    // direction v = R⁻¹·d. The test's rotation is its own (`env_rotation`), not the light's.
    let rotation = glam::Mat3::from_cols(env_rotation()[0], env_rotation()[1], env_rotation()[2]);
    let to_bins = move |d: Vec3| {
        let v = rotation.transpose() * d;
        Vec3::new(-v.z, v.x, v.y)
    };
    let from_bins = move |b: Vec3| rotation * Vec3::new(b.y, b.z, -b.x);
    let pdf = |b: Vec3| l.radiance_on_hit(from_bins(b), Vec3::ZERO, Vec3::ZERO, &s).unwrap().direct_pdf.0 as f64;
    // Expected counts need ~1 % accuracy; a looser quadrature tolerance keeps the cell edges,
    // where the pdf jumps, cheap.
    let integration = Integration { rel_tolerance: 1e-3, abs_tolerance: 1e-5, max_depth: 5, ..Integration::default() };
    let direct = chi2_sphere_with(
        |rng: &mut Rng| l.sample_direct(receiver, rng.uniform2(), &s).map(|d| to_bins(d.direction)),
        pdf,
        SAMPLES,
        40,
        16,
        16,
        &integration,
    );
    assert_chi2(&direct, sidak(1e-3, 4), "envmap direct sampling");
    // The compensated density (next-event estimation of the path tracer) against its own pdf.
    let compensated_pdf =
        |b: Vec3| l.radiance_on_hit_compensated(from_bins(b), Vec3::ZERO, Vec3::ZERO, &s).unwrap().direct_pdf.0 as f64;
    let compensated = chi2_sphere_with(
        |rng: &mut Rng| l.sample_direct_compensated(receiver, rng.uniform2(), &s).map(|d| to_bins(d.direction)),
        compensated_pdf,
        SAMPLES,
        43,
        16,
        16,
        &integration,
    );
    assert_chi2(&compensated, sidak(1e-3, 4), "envmap compensated direct sampling");
    let emission = chi2_sphere_with(
        |rng: &mut Rng| Some(to_bins(-l.sample_emission(rng.uniform2(), rng.uniform2(), &s).direction)),
        pdf,
        SAMPLES,
        41,
        16,
        16,
        &integration,
    );
    assert_chi2(&emission, sidak(1e-3, 4), "envmap emission directions");
    let origins = disc_chi2(&l, 42);
    assert_chi2(&origins, sidak(1e-3, 4), "envmap emission origins on the disc");
}

/// Midpoint quadrature of `f` over the sphere in the map's (θ, φ).
/// With `n_theta` a multiple of the map's rows − 1 and `2·n_theta` of twice its columns, the
/// cell edges of the sampling density lie on grid lines.
fn integrate_over_sphere(f: impl Fn(Vec3) -> f64, n_theta: usize) -> f64 {
    let n_phi = 2 * n_theta;
    let (d_theta, d_phi) = (std::f64::consts::PI / n_theta as f64, 2.0 * std::f64::consts::PI / n_phi as f64);
    let mut sum = 0.0;
    for i in 0..n_theta {
        let theta = (i as f64 + 0.5) * d_theta;
        for j in 0..n_phi {
            let phi = (j as f64 + 0.5) * d_phi;
            let d = env_direction((phi / (2.0 * std::f64::consts::PI)) as f32, (theta / std::f64::consts::PI) as f32);
            sum += f(d.normalize()) * theta.sin() * d_theta * d_phi;
        }
    }
    sum
}

#[test]
fn envmap_pdf_is_positive_wherever_radiance_is_and_integrates_to_one() {
    let s = sphere();
    let (w, h) = (10u32, 6u32);
    let map = |pixels: Vec<Rgb>| {
        let image = Arc::new(TextureImage { width: w, height: h, pixels });
        Light::from_desc(&LightDesc::EnvMap { image, scale: 1.0, to_world: env_rotation() }).unwrap()
    };
    // A sparse map (one bright pixel) is where a pixel-based pdf would miss the bilinear tails.
    let mut pixels = vec![Rgb::BLACK; (w * h) as usize];
    pixels[(2 * w + 9) as usize] = Rgb::new(0.0, 0.0, 3.0);
    let sparse = map(pixels);
    // Lit on the top (pole) row and one pixel of row 3: a density from luminance × sin θ at the
    // pixel rows would be 0 on the whole first row of cells, where the radiance is not.
    let mut pixels = vec![Rgb::BLACK; (w * h) as usize];
    pixels[..w as usize].iter_mut().for_each(|p| *p = Rgb::new(1.0, 2.0, 0.5));
    pixels[(3 * w + 4) as usize] = Rgb::new(2.0, 1.0, 1.0);
    let pole = map(pixels);
    for (name, l) in [("gradient", env_light()), ("sparse", sparse), ("pole", pole)] {
        let Light::EnvMap(env) = &l else { unreachable!() };
        let mut lit = 0;
        let mut rng = Rng::for_stream(4, 5, 6);
        for _ in 0..200_000 {
            let d = warp::uniform_sphere(rng.uniform2());
            let hit = l.radiance_on_hit(d, Vec3::ZERO, Vec3::ZERO, &s).unwrap();
            if !hit.radiance.is_black() {
                lit += 1;
                assert!(hit.direct_pdf.0 > 0.0, "{name}: radiance {:?} but pdf 0 at {d}", hit.radiance);
            }
        }
        assert!(lit > 1000, "{name}: {lit} lit directions");
        let pdf_integral = integrate_over_sphere(|d| env.pdf(d) as f64, 320);
        assert!((pdf_integral - 1.0).abs() < 1e-4, "{name}: pdf integrates to {pdf_integral}");
        // The compensated density too; it is 0 where the map is dimmer than its mean.
        assert!(env.has_compensated_density(), "{name}");
        let compensated = |d: Vec3| l.radiance_on_hit_compensated(d, Vec3::ZERO, Vec3::ZERO, &s).unwrap().direct_pdf.0;
        let compensated_integral = integrate_over_sphere(|d| compensated(d) as f64, 320);
        assert!(
            (compensated_integral - 1.0).abs() < 1e-4,
            "{name}: compensated pdf integrates to {compensated_integral}"
        );
        let unsampled = integrate_over_sphere(|d| f64::from(u8::from(compensated(d) == 0.0)), 320);
        assert!(unsampled > 0.5, "{name}: the compensated density leaves only {unsampled} sr to BSDF sampling");
        // The flux integral used by power() against brute-force quadrature of the radiance.
        let integral = integrate_over_sphere(|d| env.radiance(d).luminance() as f64, 320);
        let rel = (integral - env.luminance_integral() as f64).abs() / integral;
        assert!(rel < 2e-3, "{name}: ∫L dω = {integral} by quadrature, {} stored", env.luminance_integral());
    }
}

#[test]
fn envmap_descriptions_are_validated() {
    let desc = |w: u32, h: u32, pixels: Vec<Rgb>, scale: f32, to_world: [Vec3; 3]| LightDesc::EnvMap {
        image: Arc::new(TextureImage { width: w, height: h, pixels }),
        scale,
        to_world,
    };
    let id = [Vec3::X, Vec3::Y, Vec3::Z];
    assert!(Light::from_desc(&desc(2, 1, vec![Rgb::WHITE; 2], 1.0, id)).is_err(), "one row");
    assert!(Light::from_desc(&desc(2, 2, vec![Rgb::WHITE; 3], 1.0, id)).is_err(), "pixel count");
    assert!(Light::from_desc(&desc(1, 2, vec![Rgb::WHITE, Rgb::splat(f32::NAN)], 1.0, id)).is_err(), "NaN");
    assert!(Light::from_desc(&desc(1, 2, vec![Rgb::WHITE; 2], -1.0, id)).is_err(), "negative scale");
    assert!(Light::from_desc(&desc(1, 2, vec![Rgb::WHITE; 2], 1.0, [Vec3::X, Vec3::X, Vec3::Z])).is_err());
    // A black map is valid and emits nothing.
    let black = Light::from_desc(&desc(4, 3, vec![Rgb::BLACK; 12], 1.0, id)).unwrap();
    assert_eq!(black.power(&sphere()), 0.0);
    assert!(black.sample_direct(Vec3::ZERO, [0.3, 0.3], &sphere()).is_none());
    assert!(black.sample_emission([0.3, 0.3], [0.4, 0.6], &sphere()).energy.is_black());
    // A constant map is the constant environment.
    let grey = Light::from_desc(&desc(4, 3, vec![Rgb::splat(0.5); 12], 1.0, id)).unwrap();
    let constant = Light::from_desc(&LightDesc::Constant { radiance: Rgb::splat(0.5) }).unwrap();
    assert!(matches!(constant, Light::Background(_)) && constant.is_environment() && grey.is_environment());
    let (a, b) = (grey.power(&sphere()), constant.power(&sphere()));
    assert!((a - b).abs() < 1e-4 * b, "{a} vs {b}");
}

// ---------------------------------------------------------------------------------------------
// Agreement of the three queries, and power.

fn rel_close(a: f32, b: f32, tolerance: f32) -> bool {
    (a - b).abs() <= tolerance * a.abs().max(b.abs())
}

fn rgb_close(a: Rgb, b: Rgb, tolerance: f32) -> bool {
    rel_close(a.r, b.r, tolerance) && rel_close(a.g, b.g, tolerance) && rel_close(a.b, b.b, tolerance)
}

/// The front normal of a test emitter at a point on it.
type FrontNormal = fn(Vec3) -> Vec3;

#[test]
fn new_lights_report_the_same_pdfs_and_radiance_for_the_same_ray() {
    let s = sphere();
    let mut rng = Rng::for_stream(7, 8, 9);
    // Sphere and disc: direct samples, then the same rays as hits with the normal at the hit.
    let surfaces: [(&str, Light, Vec3, FrontNormal); 3] = [
        ("sphere", Light::Area(sphere_light(false)), Vec3::ZERO, |p| sphere_front(p, false)),
        ("flipped sphere", Light::Area(sphere_light(true)), Vec3::new(0.3, -0.2, 1.6), |p| sphere_front(p, true)),
        ("disc", Light::Area(disc_light(false)), Vec3::new(0.1, 0.0, 0.0), |_| -DISC_U.cross(DISC_V).normalize()),
    ];
    for (name, l, receiver, front) in &surfaces {
        let mut checked = 0;
        for _ in 0..500 {
            let Some(d) = l.sample_direct(*receiver, rng.uniform2(), &s) else { continue };
            let p = *receiver + d.distance * d.direction;
            let hit = l.radiance_on_hit(d.direction, Vec3::ZERO, front(p), &s).unwrap();
            assert_eq!(hit.radiance, d.radiance, "{name}");
            assert!(rel_close(hit.emission_pdf.0, d.emission_pdf.0, 1e-4), "{name}");
            assert!(rel_close(hit.cos_at_light, d.cos_at_light, 1e-4), "{name}");
            let direct_w = hit.direct_pdf.to_solid_angle(d.distance * d.distance, hit.cos_at_light);
            assert!(rel_close(direct_w.0, d.direct_pdf.0, 1e-3), "{name}: {} vs {}", direct_w.0, d.direct_pdf.0);
            assert!(l.radiance_on_hit(-d.direction, Vec3::ZERO, front(p), &s).is_none(), "{name}: one-sided");
            checked += 1;
        }
        assert!(checked > 100, "{name}: only {checked} direct samples");
        // Emission: energy L·cos, pdf (1/A)·cos/π, and the hit of the reversed ray agrees.
        for _ in 0..200 {
            let e = l.sample_emission(rng.uniform2(), rng.uniform2(), &s);
            let n = front(e.origin);
            assert!(rel_close(e.cos_at_light, n.dot(e.direction), 1e-4), "{name}");
            let Light::Area(a) = l else { unreachable!() };
            assert!(rel_close(e.direct_pdf.0, 1.0 / a.area(), 1e-5), "{name}");
            assert!(rel_close(e.emission_pdf.0, e.direct_pdf.0 * e.cos_at_light / math::PI, 1e-4), "{name}");
            assert!(rgb_close(e.energy, a.radiance * e.cos_at_light, 1e-5), "{name}");
            let hit = l.radiance_on_hit(-e.direction, Vec3::ZERO, n, &s).unwrap();
            assert!(rel_close(hit.emission_pdf.0, e.emission_pdf.0, 1e-4), "{name}");
        }
    }

    // Spot: emission energy in a direction equals the direct radiance seen from along it.
    let light = spot();
    let l = Light::Spot(light.clone());
    for _ in 0..200 {
        let e = l.sample_emission(rng.uniform2(), rng.uniform2(), &s);
        let Some(d) = l.sample_direct(light.position + 3.0 * e.direction, rng.uniform2(), &s) else {
            assert!(e.energy.is_black(), "nothing seen where energy is emitted");
            continue;
        };
        assert!(rgb_close(d.radiance, e.energy, 1e-3), "{:?} vs {:?}", d.radiance, e.energy);
        assert_eq!(d.emission_pdf, e.emission_pdf);
        assert_eq!(e.direct_pdf.0, 1.0);
    }
    assert!(l.radiance_on_hit(Vec3::Z, Vec3::ZERO, Vec3::Z, &s).is_none() && l.is_delta() && l.is_finite());

    // Environment map: direct and emission samples against the hit of the same direction.
    let l = env_light();
    assert!(!l.is_delta() && !l.is_finite());
    for _ in 0..1000 {
        let d = l.sample_direct(Vec3::new(0.2, 0.1, 0.0), rng.uniform2(), &s).unwrap();
        assert!(d.distance.is_infinite() && d.cos_at_light == 1.0);
        let hit = l.radiance_on_hit(d.direction, Vec3::ZERO, Vec3::ZERO, &s).unwrap();
        assert!(rgb_close(hit.radiance, d.radiance, 1e-3), "{:?} vs {:?}", hit.radiance, d.radiance);
        assert!(rel_close(hit.direct_pdf.0, d.direct_pdf.0, 1e-3), "{} vs {}", hit.direct_pdf.0, d.direct_pdf.0);
        assert!(rel_close(hit.emission_pdf.0, d.emission_pdf.0, 1e-3));
        let e = l.sample_emission(rng.uniform2(), rng.uniform2(), &s);
        let hit = l.radiance_on_hit(-e.direction, Vec3::ZERO, Vec3::ZERO, &s).unwrap();
        assert!(rgb_close(hit.radiance, e.energy, 1e-3), "{:?} vs {:?}", hit.radiance, e.energy);
        assert!(rel_close(hit.direct_pdf.0, e.direct_pdf.0, 1e-3));
        assert!(rel_close(hit.emission_pdf.0, e.emission_pdf.0, 1e-3));
        let expected = e.direct_pdf.0 / (math::PI * s.radius * s.radius);
        assert!(rel_close(e.emission_pdf.0, expected, 1e-5), "emission pdf = direction pdf × disc pdf");
    }
}

#[test]
fn power_matches_the_monte_carlo_flux_of_emission_sampling() {
    let s = sphere();
    let lights: Vec<(&str, Light)> = vec![
        ("triangle", Light::Area(area_light())),
        ("sphere", Light::Area(sphere_light(false))),
        ("flipped sphere", Light::Area(sphere_light(true))),
        ("disc", Light::Area(disc_light(true))),
        ("point", Light::Point(PointLight { position: Vec3::ONE, intensity: Rgb::new(1.0, 2.0, 3.0) })),
        ("spot", Light::Spot(spot())),
        ("narrow spot", Light::Spot(SpotLight::new(Vec3::ZERO, Vec3::Y, Rgb::WHITE, 5.0, 5.0).unwrap())),
        ("wide spot", Light::Spot(SpotLight::new(Vec3::ZERO, Vec3::Y, Rgb::WHITE, 150.0, 0.0).unwrap())),
        ("directional", Light::Directional(DirectionalLight::new(Vec3::new(1.0, -2.0, 0.5), Rgb::new(3.0, 2.0, 1.0)))),
        ("constant", Light::Background(BackgroundLight { radiance: Rgb::new(0.2, 0.4, 0.6) })),
        ("envmap", env_light()),
    ];
    let n = 200_000;
    for (name, l) in &lights {
        let mut rng = Rng::for_stream(11, 12, 13);
        let flux: MeanVar = (0..n)
            .map(|_| {
                let e = l.sample_emission(rng.uniform2(), rng.uniform2(), &s);
                if e.emission_pdf.0 > 0.0 { e.energy.luminance() as f64 / e.emission_pdf.0 as f64 } else { 0.0 }
            })
            .collect();
        let power = l.power(&s) as f64;
        let (mean, se) = (flux.mean(), flux.std_error());
        // Deterministic estimators (constant energy/pdf) are compared to float precision.
        let p = z_test_p(mean - power, se.max(1e-5 * power));
        eprintln!("{name}: power {power:.5}, Monte Carlo {mean:.5} ± {se:.5}");
        assert!(p > sidak(1e-3, lights.len()), "{name}: power {power} but emission sampling gives {mean} ± {se}");
    }
    // The analytic spot integral against its closed forms at the extremes: 2π(1 − cos c) without
    // a transition, and for b = 0 the linear ramp 2π(1 − sin c / c).
    let no_transition = SpotLight::new(Vec3::ZERO, Vec3::Y, Rgb::WHITE, 40.0, 40.0).unwrap();
    let expected = 2.0 * math::PI * (1.0 - 40f32.to_radians().cos());
    assert!((no_transition.falloff_solid_angle() - expected).abs() < 1e-5);
    let ramp = SpotLight::new(Vec3::ZERO, Vec3::Y, Rgb::WHITE, 60.0, 0.0).unwrap();
    let c = 60f32.to_radians();
    assert!((ramp.falloff_solid_angle() - 2.0 * math::PI * (1.0 - c.sin() / c)).abs() < 1e-5);
}

// ---------------------------------------------------------------------------------------------
// Parallelograms: a rectangle's two triangles as one light.

/// Mitsuba's `rectangle` ([−1, 1]² at z = 0, normal +z) transformed by a rotation, a shear-free
/// scale and a translation, as its two triangles `(0, 1, 2)` and `(2, 3, 0)`.
fn rectangle_triangles() -> (Triangle, Triangle) {
    let frame = Frame::from_z(Vec3::new(0.2, -0.3, -1.0).normalize());
    let corner = |x: f32, y: f32| Vec3::new(0.3, 0.1, 1.2) + 0.4 * x * frame.x + 0.25 * y * frame.y;
    let p = [corner(-1.0, -1.0), corner(1.0, -1.0), corner(1.0, 1.0), corner(-1.0, 1.0)];
    (Triangle::new(p[0], p[1], p[2]), Triangle::new(p[2], p[3], p[0]))
}

#[test]
fn two_triangles_that_tile_a_parallelogram_are_recognised() {
    let (a, b) = rectangle_triangles();
    let (origin, edge_u, edge_v, normal) = AreaLight::parallelogram_of(&a, &b).expect("a rectangle");
    assert!((edge_u.cross(edge_v).length() - (a.area() + b.area())).abs() < 1e-5, "area of both triangles");
    assert_eq!(normal, a.normal);
    let light = AreaLight::parallelogram(origin, edge_u, edge_v, normal, Rgb::splat(3.0)).unwrap();
    assert!((light.area() - (a.area() + b.area())).abs() < 1e-5);
    // Not a parallelogram: the fourth corner moved (a kite), or the second triangle turned over.
    let kite = Triangle::new(b.p0, b.p1 + 0.1 * (b.p1 - b.p0), b.p2);
    assert!(AreaLight::parallelogram_of(&a, &kite).is_none());
    assert!(AreaLight::parallelogram_of(&a, &Triangle::new(b.p0, b.p2, b.p1)).is_none());
    // Two triangles that share no edge.
    let apart = Triangle::new(b.p0 + Vec3::X, b.p1 + Vec3::X, b.p2 + Vec3::X);
    assert!(AreaLight::parallelogram_of(&a, &apart).is_none());
    // Bad parameters are errors.
    assert!(AreaLight::parallelogram(origin, edge_u, 2.0 * edge_u, normal, Rgb::WHITE).is_err());
    assert!(AreaLight::parallelogram(origin, edge_u, edge_v, Vec3::new(normal.y, -normal.x, 0.0), Rgb::WHITE).is_err());
}

/// The parallelogram light's next-event estimate of the irradiance agrees with the closed form
/// at the point under an axis-aligned rectangle's centre: `E = 4 · L · ½ (A/√(1+A²) atan(B/√(1+A²)) + B/√(1+B²) atan(A/√(1+B²)))`
/// over the four quarter rectangles (A, B: half-sides over the height), for an axis-aligned
/// rectangle facing the receiver; and, for a tilted rectangle, with the estimate of its two
/// triangle lights (each picked with probability ½).
#[test]
fn parallelogram_light_estimates_the_irradiance_of_its_two_triangles() {
    let s = sphere();
    let radiance = 3.0f32;
    let estimate = |lights: &[Light], receiver: Vec3, normal: Vec3, seed: u64| {
        let mut rng = Rng::for_stream(seed, 0, 0);
        let mut stats = MeanVar::new();
        for _ in 0..SAMPLES {
            let pick = ((rng.uniform() * lights.len() as f32) as usize).min(lights.len() - 1);
            let value = lights[pick].sample_direct(receiver, rng.uniform2(), &s).map_or(0.0, |d| {
                f64::from(d.radiance.r * d.direction.dot(normal).max(0.0) / d.direct_pdf.0) * lights.len() as f64
            });
            stats.push(value);
        }
        stats
    };
    // Axis-aligned: the closed form.
    let (half_x, half_y, height) = (0.4f32, 0.25f32, 0.6f32);
    let p = [
        Vec3::new(-half_x, -half_y, height),
        Vec3::new(half_x, -half_y, height),
        Vec3::new(half_x, half_y, height),
        Vec3::new(-half_x, half_y, height),
    ];
    // Wound to face down (−z), towards the receiver at the origin.
    let (a, b) = (Triangle::new(p[0], p[2], p[1]), Triangle::new(p[2], p[0], p[3]));
    assert!(a.normal.z < 0.0 && b.normal.z < 0.0);
    let (origin, u, v, n) = AreaLight::parallelogram_of(&a, &b).unwrap();
    let one = [Light::Area(AreaLight::parallelogram(origin, u, v, n, Rgb::splat(radiance)).unwrap())];
    let (big_a, big_b) = (f64::from(half_x / height), f64::from(half_y / height));
    let quarter = |a: f64, b: f64| {
        0.5 * (a / (1.0 + a * a).sqrt() * (b / (1.0 + a * a).sqrt()).atan()
            + b / (1.0 + b * b).sqrt() * (a / (1.0 + b * b).sqrt()).atan())
    };
    let exact = 4.0 * f64::from(radiance) * quarter(big_a, big_b);
    let measured = estimate(&one, Vec3::ZERO, Vec3::Z, 1);
    let z = (measured.mean() - exact) / measured.std_error();
    assert!(z.abs() < 4.5, "parallelogram: {} against the closed form {exact} (z {z:.2})", measured.mean());
    // A wrong area density (the triangles' instead of the parallelogram's) is far outside.
    assert!((exact * 0.98 - measured.mean()).abs() / measured.std_error() > 4.5, "the test resolves 2 %");
    // Tilted and off-centre: the two triangle lights are the reference.
    let (a, b) = rectangle_triangles();
    let (origin, u, v, n) = AreaLight::parallelogram_of(&a, &b).unwrap();
    let one = [Light::Area(AreaLight::parallelogram(origin, u, v, n, Rgb::splat(radiance)).unwrap())];
    let two_tilted =
        [Light::Area(AreaLight::new(a, Rgb::splat(radiance))), Light::Area(AreaLight::new(b, Rgb::splat(radiance)))];
    // Receivers in front of the emitting side, near (grazing, off to the side) and far.
    let center = origin + 0.5 * (u + v);
    let side = u.normalize();
    for (receiver, normal) in [
        (center + 0.1 * n + 0.7 * side, side),
        (center + 0.3 * n - 0.1 * side, -n),
        (center + 3.0 * n + 0.5 * v, Vec3::new(0.3, 0.2, 0.9).normalize()),
    ] {
        let normal = if (center - receiver).dot(normal) < 0.0 { -normal } else { normal };
        let (x, y) = (estimate(&one, receiver, normal, 2), estimate(&two_tilted, receiver, normal, 3));
        let z = (x.mean() - y.mean()) / x.std_error().hypot(y.std_error());
        assert!(z.abs() < 4.5, "at {receiver}: parallelogram {} against triangles {} (z {z:.2})", x.mean(), y.mean());
    }
}
