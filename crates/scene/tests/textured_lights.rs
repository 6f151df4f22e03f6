//! Tests of the textured lights: chi-square tests of the textured triangle's point sampler (in
//! the triangle's unit-square parametrisation) and direction samplers, and of the projector's
//! emission sampler, against the pdfs the lights report; a deliberately wrong pdf (uniform)
//! fails the same tests. The three queries report the same pdfs and radiance for the same ray,
//! the textures are looked up in Mitsuba 3's orientation, and the projector's flux and
//! irradiance follow Mitsuba 3's normalisation.

use std::sync::Arc;

use math::{Frame, PI, Rng, Vec2, Vec3, warp};
use scene::Light;
use scene::desc::{ProjectorModel, TextureImage, UvTransform};
use scene::light::{BoundingSphere, ProjectorLight, SpotLight, TexturedTriangleLight};
use scene::shape::Triangle;
use scene::texture::Texture;
use spectrum::Rgb;
use testkit::{MeanVar, assert_chi2, chi2_sphere, chi2_sphere_with, chi2_square, sidak, z_test_p};

const SAMPLES: usize = 100_000;

fn sphere() -> BoundingSphere {
    BoundingSphere { center: Vec3::ZERO, radius: 3.0 }
}

/// A 4 × 3 image with a black texel, a bright one and coloured ones.
fn image() -> Arc<Texture> {
    let values = [0.0, 1.0, 4.0, 0.5, 2.0, 0.1, 8.0, 1.0, 0.3, 3.0, 0.0, 6.0];
    let pixels =
        values.iter().enumerate().map(|(i, &v)| Rgb::new(v, v * (1.0 + (i % 3) as f32) * 0.5, 0.2 * v)).collect();
    let image = Arc::new(TextureImage { width: 4, height: 3, pixels });
    Arc::new(Texture::Bitmap { image, to_uv: UvTransform::IDENTITY })
}

fn triangle() -> Triangle {
    let t = Triangle::new(Vec3::new(-0.5, -0.4, 1.0), Vec3::new(0.6, -0.3, 1.1), Vec3::new(0.0, 0.7, 0.9));
    // Emit downwards, towards receivers below.
    if t.normal.z > 0.0 { Triangle::new(t.p0, t.p2, t.p1) } else { t }
}

fn textured_triangle() -> TexturedTriangleLight {
    let uvs = [Vec2::new(0.05, 0.1), Vec2::new(0.95, 0.2), Vec2::new(0.4, 0.9)];
    TexturedTriangleLight::new(triangle(), uvs, image()).unwrap()
}

/// The unit-square point of `position` in the parametrisation `warp::uniform_triangle`.
fn square_of(t: &Triangle, position: Vec3) -> [f64; 2] {
    let (b1, b2) = t.barycentrics(position);
    warp::uniform_triangle_inverse(Vec2::new(b1, b2)).map(f64::from)
}

#[test]
fn textured_triangle_emits_points_with_its_area_pdf_and_cosine_directions() {
    let light = textured_triangle();
    let t = triangle();
    let l = Light::TexturedTriangle(light.clone());
    // Density in the square = area density × area (the warp's Jacobian is the area).
    let square_pdf = |p: [f64; 2]| {
        let b = warp::uniform_triangle([p[0] as f32, p[1] as f32]);
        (light.area_pdf(t.point(b.x, b.y)) * t.area()) as f64
    };
    let sample =
        |rng: &mut Rng| Some(square_of(&t, l.sample_emission(rng.uniform2(), rng.uniform2(), &sphere()).origin));
    let positions = chi2_square(sample, square_pdf, SAMPLES, 1, 16);
    assert_chi2(&positions, sidak(1e-3, 2), "textured triangle emission positions");
    // The sampler is far from uniform: the uniform density fails the same test.
    let uniform = chi2_square(sample, |_| 1.0, SAMPLES, 1, 16);
    assert!(!uniform.passed(1e-3), "a uniform pdf must fail: p = {}", uniform.p_value);
    // So does the right pdf made 10 % too low over half of the square.
    let low = chi2_square(sample, |p| square_pdf(p) * if p[0] < 0.5 { 0.9 } else { 1.0 }, SAMPLES, 1, 16);
    assert!(!low.passed(1e-3), "a pdf 10 % low on half the square must fail: p = {}", low.p_value);

    let frame = Frame::from_z(t.normal);
    let directions = chi2_sphere(
        |rng: &mut Rng| Some(frame.to_local(l.sample_emission(rng.uniform2(), rng.uniform2(), &sphere()).direction)),
        |local| warp::cosine_hemisphere_pdf(local.z) as f64,
        SAMPLES,
        2,
        16,
        32,
    );
    assert_chi2(&directions, sidak(1e-3, 2), "textured triangle emission directions");
}

#[test]
fn textured_triangle_direct_sampling_picks_points_with_its_area_pdf() {
    // Direct sampling draws the point like emission does and converts its density to solid
    // angle (the conversion is shared with the untextured lights and checked against
    // `radiance_on_hit` below); here the points it reaches are tested in the square.
    let light = textured_triangle();
    let t = triangle();
    let l = Light::TexturedTriangle(light.clone());
    let receivers = [Vec3::ZERO, Vec3::new(0.4, 0.3, 0.2)];
    for (k, receiver) in receivers.into_iter().enumerate() {
        let square_pdf = |p: [f64; 2]| {
            let b = warp::uniform_triangle([p[0] as f32, p[1] as f32]);
            let point = t.point(b.x, b.y);
            let direction = (point - receiver).normalize();
            // Points that emit nothing towards the receiver are not returned by the sampler.
            match l.radiance_on_hit(direction, point, t.normal, &sphere()) {
                Some(h) if !h.radiance.is_black() => (light.area_pdf(point) * t.area()) as f64,
                _ => 0.0,
            }
        };
        let sample = |rng: &mut Rng| {
            let d = l.sample_direct(receiver, rng.uniform2(), &sphere())?;
            Some(square_of(&t, receiver + d.distance * d.direction))
        };
        let outcome = chi2_square(sample, square_pdf, SAMPLES, 3 + k as u64, 16);
        assert_chi2(&outcome, sidak(1e-3, receivers.len()), &format!("textured triangle seen from {receiver}"));
    }
}

#[test]
fn textured_triangle_queries_agree_and_look_up_the_hit_uv() {
    let light = textured_triangle();
    let t = triangle();
    let l = Light::TexturedTriangle(light.clone());
    let s = sphere();
    let mut rng = Rng::for_stream(5, 0, 0);
    let mut checked = 0;
    for _ in 0..200 {
        let receiver = Vec3::new(rng.uniform() - 0.5, rng.uniform() - 0.5, 0.0);
        let Some(d) = l.sample_direct(receiver, rng.uniform2(), &s) else { continue };
        let point = receiver + d.distance * d.direction;
        let hit = l.radiance_on_hit(d.direction, point, t.normal, &s).unwrap();
        let close = |a: f32, b: f32| (a - b).abs() <= 2e-3 * a.abs().max(b.abs()) + 1e-6;
        assert!(close(hit.radiance.r, d.radiance.r) && close(hit.radiance.b, d.radiance.b), "{hit:?} {d:?}");
        let solid_angle = hit.direct_pdf.to_solid_angle(d.distance * d.distance, d.cos_at_light).0;
        assert!(close(solid_angle, d.direct_pdf.0) && close(hit.emission_pdf.0, d.emission_pdf.0), "{hit:?} {d:?}");
        checked += 1;
    }
    assert!(checked > 150, "only {checked} samples emitted");
    // At a vertex the texture is looked up at that vertex's uv: vertex 2 has uv (0.4, 0.9),
    // texel (1, 2) of the 4 × 3 image at the bilinear centre… away from centres, compare with
    // the texture itself.
    let at_vertex = l.radiance_on_hit(-t.normal, t.p2, t.normal, &s).unwrap().radiance;
    assert_eq!(at_vertex, image().eval(Vec2::new(0.4, 0.9)));
}

fn projector() -> ProjectorLight {
    // Looking down −y, image left = +x… any orthonormal frame works.
    let frame = [Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 0.0, 1.0), Vec3::new(0.0, -1.0, 0.0)];
    ProjectorLight::new(ProjectorModel::Irradiance, Vec3::new(0.0, 2.0, 0.0), frame, image(), 1.5, 70.0, 4.0 / 3.0)
        .unwrap()
}

#[test]
fn projector_emission_matches_its_pdf() {
    let light = projector();
    let l = Light::Projector(light.clone());
    let frame = Frame { x: Vec3::X, y: Vec3::Z, z: -Vec3::Y };
    let sample = |rng: &mut Rng| {
        let e = l.sample_emission(rng.uniform2(), rng.uniform2(), &sphere());
        Some(frame.to_local(e.direction))
    };
    let integration = testkit::Integration { initial_split: 4, ..testkit::Integration::default() };
    let pdf = |local: Vec3| light.emission_pdf(frame.to_world(local)) as f64;
    let outcome = chi2_sphere_with(sample, pdf, SAMPLES, 4, 16, 32, &integration);
    assert_chi2(&outcome, sidak(1e-3, 2), "projector emission");
    assert!((outcome.pdf_integral - 1.0).abs() < 1e-3, "pdf integral {}", outcome.pdf_integral);
    // A pdf uniform over the image plane (area A, dω = cos³θ·A·du dv) is wrong and fails.
    let tan = (35f32).to_radians().tan();
    let area = 4.0 * tan * tan * 3.0 / 4.0;
    let uniform = |local: Vec3| {
        let inside = local.z > 0.0 && (local.x / local.z).abs() <= tan && (local.y / local.z).abs() <= tan * 0.75;
        if inside { 1.0 / (area * local.z.powi(3)) as f64 } else { 0.0 }
    };
    let wrong = chi2_sphere_with(sample, uniform, SAMPLES, 4, 16, 32, &integration);
    assert!(!wrong.passed(sidak(1e-3, 2)), "a uniform image density must fail: p = {}", wrong.p_value);
    let low =
        chi2_sphere_with(sample, |d| pdf(d) * if d.x < 0.0 { 0.9 } else { 1.0 }, SAMPLES, 4, 16, 32, &integration);
    assert!(!low.passed(sidak(1e-3, 2)), "a pdf 10 % low on half the image must fail: p = {}", low.p_value);
}

#[test]
fn projector_queries_agree_and_follow_mitsubas_normalisation() {
    let light = projector();
    let l = Light::Projector(light.clone());
    let s = sphere();
    // On the axis (uv = (½, ½)) a point at distance 2 receives π·scale·E/d².
    let receiver = Vec3::ZERO;
    let d = l.sample_direct(receiver, [0.5, 0.5], &s).unwrap();
    let expected = image().eval(Vec2::new(0.5, 0.5)) * (PI * 1.5);
    assert!((d.radiance.r - expected.r).abs() < 1e-4 * expected.r && (d.distance - 2.0).abs() < 1e-6);
    assert!((d.emission_pdf.0 - light.emission_pdf(-d.direction)).abs() <= 1e-6 * d.emission_pdf.0);
    // Image orientation: local +x (world +x here) is the image's left (u < ½), local +y (world
    // +z) its top (v < ½).
    let left = l.sample_direct(Vec3::new(0.6, 0.0, 0.0), [0.5, 0.5], &s).unwrap();
    let top = l.sample_direct(Vec3::new(0.0, 0.0, 0.5), [0.5, 0.5], &s).unwrap();
    let cos3 = |p: Vec3| (2.0 / (p - Vec3::new(0.0, 2.0, 0.0)).length()).powi(3);
    let tan = (35f32).to_radians().tan();
    let u_left = 0.5 - 0.5 * (0.6 / 2.0) / tan;
    let v_top = 0.5 - 0.5 * (4.0 / 3.0) * (0.5 / 2.0) / tan;
    let e_left = image().eval(Vec2::new(u_left, 0.5)) * (PI * 1.5 / cos3(Vec3::new(0.6, 0.0, 0.0)));
    let e_top = image().eval(Vec2::new(0.5, v_top)) * (PI * 1.5 / cos3(Vec3::new(0.0, 0.0, 0.5)));
    assert!((left.radiance.g - e_left.g).abs() < 1e-4 * e_left.g.max(1e-3), "{left:?} vs {e_left:?}");
    assert!((top.radiance.g - e_top.g).abs() < 1e-4 * e_top.g.max(1e-3), "{top:?} vs {e_top:?}");
    // Outside the field of view and behind: nothing.
    assert!(l.sample_direct(Vec3::new(5.0, 0.0, 0.0), [0.5, 0.5], &s).is_none());
    assert!(l.sample_direct(Vec3::new(0.0, 3.0, 0.0), [0.5, 0.5], &s).is_none());
}

#[test]
fn projector_flux_is_pi_scale_area_times_the_mean_irradiance() {
    // A constant image: flux π·scale·A·E exactly, A = 4·tan²(fov/2)/aspect.
    let frame = [Vec3::X, Vec3::Y, Vec3::Z];
    let constant = Arc::new(Texture::Constant(Rgb::splat(0.8)));
    let light = ProjectorLight::new(ProjectorModel::Irradiance, Vec3::ZERO, frame, constant, 2.0, 90.0, 2.0).unwrap();
    let l = Light::Projector(light);
    let expected = PI as f64 * 2.0 * (4.0 / 2.0) * 0.8;
    let mut rng = Rng::for_stream(9, 0, 0);
    let flux: MeanVar = (0..50_000)
        .map(|_| {
            let e = l.sample_emission(rng.uniform2(), rng.uniform2(), &sphere());
            e.energy.luminance() as f64 / e.emission_pdf.0 as f64
        })
        .collect();
    // Constant energy/pdf: the estimate is exact up to rounding.
    assert!((flux.mean() - expected).abs() < 1e-4 * expected, "flux {} vs {expected}", flux.mean());
    assert!((l.power(&sphere()) as f64 - expected).abs() < 1e-4 * expected);
    // The textured projector's power against the Monte Carlo flux of its emission sampler.
    let l = Light::Projector(projector());
    let mut rng = Rng::for_stream(9, 1, 0);
    let flux: MeanVar = (0..200_000)
        .map(|_| {
            let e = l.sample_emission(rng.uniform2(), rng.uniform2(), &sphere());
            if e.emission_pdf.0 > 0.0 { e.energy.luminance() as f64 / e.emission_pdf.0 as f64 } else { 0.0 }
        })
        .collect();
    // The power is the bilinear image's integral by the midpoint rule on the texel grid; the
    // bilinear texture's exact mean differs from it by a few percent, so compare loosely.
    let power = l.power(&sphere()) as f64;
    assert!((flux.mean() - power).abs() < 0.1 * power, "power {power} vs flux {} ± {}", flux.mean(), flux.std_error());
}

#[test]
fn pbrt_projector_has_constant_intensity_per_texel_and_samples_its_flux() {
    // pbrt-v4's model: I = scale·E(u, v), no 1/cos³θ; the sampler follows E·cos³θ.
    let frame = [Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 0.0, 1.0), Vec3::new(0.0, -1.0, 0.0)];
    let light =
        ProjectorLight::new(ProjectorModel::Intensity, Vec3::new(0.0, 2.0, 0.0), frame, image(), 1.5, 70.0, 4.0 / 3.0)
            .unwrap();
    let l = Light::Projector(light.clone());
    let s = sphere();
    let tan = (35f32).to_radians().tan();
    for receiver in [Vec3::ZERO, Vec3::new(0.6, 0.0, 0.0), Vec3::new(-0.9, 0.0, 0.7)] {
        let d = l.sample_direct(receiver, [0.5, 0.5], &s).unwrap();
        let local = receiver - Vec3::new(0.0, 2.0, 0.0);
        let (x, y, z) = (local.x, local.z, -local.y);
        let uv = Vec2::new(0.5 - 0.5 * (x / z) / tan, 0.5 - 0.5 * (4.0 / 3.0) * (y / z) / tan);
        let expected = image().eval(uv) * 1.5;
        assert!((d.radiance.g - expected.g).abs() <= 1e-4 * expected.g.max(1e-3), "{d:?} vs {expected:?}");
    }
    let dir_frame = Frame { x: Vec3::X, y: Vec3::Z, z: -Vec3::Y };
    let sample =
        |rng: &mut Rng| Some(dir_frame.to_local(l.sample_emission(rng.uniform2(), rng.uniform2(), &s).direction));
    let integration = testkit::Integration { initial_split: 4, ..testkit::Integration::default() };
    let pdf = |local: Vec3| light.emission_pdf(dir_frame.to_world(local)) as f64;
    let outcome = chi2_sphere_with(sample, pdf, SAMPLES, 4, 16, 32, &integration);
    assert_chi2(&outcome, sidak(1e-3, 2), "pbrt projector emission");
    // Mitsuba's sampling density (E without cos³θ) is not this one and fails.
    let mitsuba =
        ProjectorLight::new(ProjectorModel::Irradiance, Vec3::new(0.0, 2.0, 0.0), frame, image(), 1.5, 70.0, 4.0 / 3.0)
            .unwrap();
    let wrong = chi2_sphere_with(
        sample,
        |local: Vec3| mitsuba.emission_pdf(dir_frame.to_world(local)) as f64,
        SAMPLES,
        4,
        16,
        32,
        &integration,
    );
    assert!(!wrong.passed(sidak(1e-3, 2)), "Mitsuba's density must fail: p = {}", wrong.p_value);
    // Flux: the sampler's Monte Carlo estimate against the stated power (midpoint rule on the
    // texel grid of the bilinear image, so loosely, as for Mitsuba's model above).
    let mut rng = Rng::for_stream(9, 2, 0);
    let flux: MeanVar = (0..200_000)
        .map(|_| {
            let e = l.sample_emission(rng.uniform2(), rng.uniform2(), &s);
            if e.emission_pdf.0 > 0.0 { e.energy.luminance() as f64 / e.emission_pdf.0 as f64 } else { 0.0 }
        })
        .collect();
    let power = l.power(&s) as f64;
    assert!((flux.mean() - power).abs() < 0.1 * power, "power {power} vs flux {} ± {}", flux.mean(), flux.std_error());
    let mitsuba_power = Light::Projector(mitsuba).power(&s) as f64;
    assert!(mitsuba_power > 2.0 * power, "π·(1/cos³) makes Mitsuba's projector brighter: {mitsuba_power} vs {power}");
}

#[test]
fn spot_texture_multiplies_the_intensity_at_mitsubas_uv() {
    let axis = -Vec3::Y;
    let spot = SpotLight::new(Vec3::new(0.0, 2.0, 0.0), axis, Rgb::splat(3.0), 30.0, 30.0).unwrap();
    let textured = spot.clone().with_texture(image(), Vec3::X, Vec3::Z).unwrap();
    let (plain, l) = (Light::Spot(spot), Light::Spot(textured));
    let s = sphere();
    // The local direction (x, y, z) looks up (½ + ½·x/(z·tan c), ½ + ½·y/(z·tan c)).
    let tan = 30f32.to_radians().tan();
    for receiver in [Vec3::new(0.3, 0.0, 0.2), Vec3::new(-0.5, 0.0, 0.4), Vec3::new(0.1, 0.0, -0.6)] {
        let d = l.sample_direct(receiver, [0.5, 0.5], &s).unwrap();
        let p = plain.sample_direct(receiver, [0.5, 0.5], &s).unwrap();
        let uv = Vec2::new(0.5 + 0.5 * receiver.x / (2.0 * tan), 0.5 + 0.5 * receiver.z / (2.0 * tan));
        let expected = p.radiance * image().eval(uv);
        assert!((d.radiance.g - expected.g).abs() <= 1e-4 * expected.g.max(1e-3), "{receiver}: {d:?} vs {expected:?}");
        assert_eq!(d.direct_pdf, p.direct_pdf);
        assert_eq!(d.emission_pdf, p.emission_pdf);
    }
    // Emission: the same uniform cone, the energy times the texture in the emitted direction.
    let mut rng = Rng::for_stream(3, 0, 0);
    for _ in 0..100 {
        let (u, v) = (rng.uniform2(), rng.uniform2());
        let (e, p) = (l.sample_emission(u, v, &s), plain.sample_emission(u, v, &s));
        assert!((e.direction - p.direction).length() < 1e-6 || e.direction.dot(axis) > 0.0);
        let local = Vec3::new(e.direction.x, e.direction.z, -e.direction.y);
        let uv = Vec2::new(0.5 + 0.5 * local.x / (local.z * tan), 0.5 + 0.5 * local.y / (local.z * tan));
        let expected = 3.0 * image().eval(uv).g;
        assert!((e.energy.g - expected).abs() <= 1e-3 * expected.max(1e-3), "{e:?} vs {expected}");
    }
    // Power against the Monte Carlo flux of emission sampling (its midpoint rule converges).
    let mut rng = Rng::for_stream(3, 1, 0);
    let flux: MeanVar = (0..200_000)
        .map(|_| {
            let e = l.sample_emission(rng.uniform2(), rng.uniform2(), &s);
            e.energy.luminance() as f64 / e.emission_pdf.0 as f64
        })
        .collect();
    let power = l.power(&s) as f64;
    let p = z_test_p(flux.mean() - power, flux.std_error().hypot(2e-3 * power));
    assert!(p > 1e-3, "power {power} vs flux {} ± {}", flux.mean(), flux.std_error());
    // A cutoff of 90° or more cannot carry a texture.
    let wide = SpotLight::new(Vec3::ZERO, axis, Rgb::WHITE, 95.0, 10.0).unwrap();
    assert!(wide.with_texture(image(), Vec3::X, Vec3::Z).is_err());
}
