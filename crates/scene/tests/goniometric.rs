//! The goniometric light (pbrt-v4's): intensity from a square image in the equal-area
//! octahedral map. Checked against facts of the map that do not use our implementation of it
//! (its centre is +z, its corners −z, the middles of its right and top edges +x and +y), the
//! equal-area property (a constant image emits uniformly over the sphere: chi-square against
//! `1/(4π)`), emission sampling against the pdf the light reports (chi-square; a uniform pdf
//! fails), the flux `4π · I · mean` by a Monte Carlo estimate of `E[energy / pdf]` (5σ, detects a
//! 1 % bias), and the agreement of direct and emission queries for the same direction.

use std::sync::Arc;

use math::{PI, Rng, Vec3};
use scene::Light;
use scene::desc::{LightDesc, TextureImage};
use scene::light::BoundingSphere;
use spectrum::Rgb;
use testkit::{MeanVar, assert_chi2, chi2_sphere, sidak};

const SAMPLES: usize = 100_000;

fn sphere() -> BoundingSphere {
    BoundingSphere { center: Vec3::ZERO, radius: 10.0 }
}

/// An 8 × 8 image whose texel (x, y) has channel mean `1 + x + 8·y` (R, G, B differ), with
/// one black texel.
fn image(constant: bool) -> Arc<TextureImage> {
    let pixels = (0..64)
        .map(|i| {
            let m = if constant {
                1.0
            } else if i == 9 {
                0.0
            } else {
                1.0 + i as f32
            };
            Rgb::new(0.5 * m, m, 1.5 * m)
        })
        .collect();
    Arc::new(TextureImage { width: 8, height: 8, pixels })
}

/// The map's local axes in the world: x → world y, y → world z, z → world x.
const FRAME: [Vec3; 3] = [Vec3::Y, Vec3::Z, Vec3::X];

fn light(constant: bool) -> Light {
    let desc = LightDesc::Goniometric {
        position: Vec3::new(0.0, 1.0, 0.0),
        frame: FRAME,
        image: image(constant),
        intensity: Rgb::new(2.0, 1.0, 0.5),
    };
    Light::from_desc(&desc).unwrap_or_else(|e| panic!("{e}"))
}

fn to_world(local: Vec3) -> Vec3 {
    (FRAME[0] * local.x + FRAME[1] * local.y + FRAME[2] * local.z).normalize()
}

#[test]
fn the_image_is_looked_up_in_the_equal_area_map() {
    let l = light(false);
    let s = sphere();
    // (local direction, texel it must fall in): just off the map's landmarks.
    let cases = [
        (Vec3::new(0.01, 0.01, 1.0), (4, 4)), // +z: the square's centre
        (Vec3::new(-0.01, -0.01, 1.0), (3, 3)),
        (Vec3::new(1.0, 0.01, 0.0), (7, 4)),   // +x: the middle of the right edge
        (Vec3::new(0.01, 1.0, 0.0), (4, 7)),   // +y: the middle of the far edge (v = 1)
        (Vec3::new(-1.0, -0.01, 0.0), (0, 3)), // −x: the left edge
        (Vec3::new(0.01, 0.01, -1.0), (7, 7)), // −z: the corners
        (Vec3::new(-0.01, -0.01, -1.0), (0, 0)),
    ];
    for (local, (x, y)) in cases {
        let receiver = Vec3::new(0.0, 1.0, 0.0) + 3.0 * to_world(local);
        let d = l.sample_direct(receiver, [0.5, 0.5], &s).unwrap();
        let expected = 1.0 + (x + 8 * y) as f32;
        assert!((d.radiance.r - 2.0 * expected).abs() < 1e-4 * expected, "{local}: texel ({x}, {y}): {d:?}");
        assert!((d.radiance.b - 0.5 * expected).abs() < 1e-4 * expected, "{local}: {d:?}");
        assert!((d.direct_pdf.0 - 9.0).abs() < 1e-3, "a delta position: solid-angle density d² {d:?}");
    }
    // The black texel emits nothing: no sample towards it.
    let black = to_world(equal_area_centre(1, 1));
    assert!(l.sample_direct(Vec3::new(0.0, 1.0, 0.0) + 3.0 * black, [0.5, 0.5], &s).is_none());
}

/// The direction of texel (x, y)'s centre of the 8 × 8 map (through the light's own map).
fn equal_area_centre(x: usize, y: usize) -> Vec3 {
    scene::light::equal_area::square_to_sphere(math::Vec2::new((x as f32 + 0.5) / 8.0, (y as f32 + 0.5) / 8.0))
}

#[test]
fn a_constant_image_emits_uniformly_over_the_sphere() {
    let l = light(true);
    let sample = |rng: &mut Rng| Some(l.sample_emission(rng.uniform2(), rng.uniform2(), &sphere()).direction);
    let outcome = chi2_sphere(sample, |_| 1.0 / (4.0 * std::f64::consts::PI), SAMPLES, 1, 16, 32);
    assert_chi2(&outcome, 1e-3, "goniometric light, constant image");
}

#[test]
fn emission_follows_the_reported_pdf_and_carries_the_flux() {
    let l = light(false);
    let s = sphere();
    let pdf = |d: Vec3| {
        let receiver = Vec3::new(0.0, 1.0, 0.0) + d;
        l.sample_direct(receiver, [0.5, 0.5], &s).map_or(0.0, |x| f64::from(x.emission_pdf.0))
    };
    let sample = |rng: &mut Rng| Some(l.sample_emission(rng.uniform2(), rng.uniform2(), &s).direction);
    let outcome = chi2_sphere(sample, pdf, SAMPLES, 2, 16, 32);
    assert_chi2(&outcome, sidak(1e-3, 2), "goniometric emission directions");
    let uniform = chi2_sphere(sample, |_| 1.0 / (4.0 * std::f64::consts::PI), SAMPLES, 2, 16, 32);
    assert!(!uniform.passed(1e-3), "a uniform pdf must fail: p = {}", uniform.p_value);

    // Flux: 4π · I · mean(m); the mean of 1..=64 without texel 9's value 10 is (2080 − 10)/64.
    let mean = (2080.0 - 10.0) / 64.0;
    let expected = 4.0 * std::f64::consts::PI * mean; // channel G, I_g = 1
    let mut rng = Rng::for_stream(3, 0, 0);
    let mut stats = MeanVar::new();
    for _ in 0..SAMPLES {
        let e = l.sample_emission(rng.uniform2(), rng.uniform2(), &s);
        stats.push(if e.emission_pdf.0 > 0.0 { f64::from(e.energy.g / e.emission_pdf.0) } else { 0.0 });
        // Direct and emission queries agree along the sampled direction.
        let d = l.sample_direct(e.origin + 2.0 * e.direction, [0.5, 0.5], &s).unwrap();
        assert!((d.emission_pdf.0 - e.emission_pdf.0).abs() <= 1e-3 * e.emission_pdf.0, "{d:?} {e:?}");
        assert!((d.radiance.g - e.energy.g).abs() <= 1e-4 * e.energy.g, "{d:?} {e:?}");
    }
    let error = (stats.variance() / SAMPLES as f64).sqrt();
    assert!(
        (stats.mean() - expected).abs() < 5.0 * error + 1e-5 * expected,
        "{} ± {error} vs {expected}",
        stats.mean()
    );
    assert!(5.0 * error < 0.01 * expected, "detects only a bias of {}", 5.0 * error / expected);
    let power = l.power(&s) as f64;
    let luminance = Rgb::new(2.0, 1.0, 0.5).luminance() as f64;
    assert!((power - 4.0 * f64::from(PI) * mean * luminance).abs() < 1e-4 * power, "power {power}");
}

#[test]
fn bad_images_and_frames_are_errors() {
    let make = |width: u32, height: u32, frame: [Vec3; 3], value: f32| {
        let pixels = vec![Rgb::splat(value); (width * height) as usize];
        let image = Arc::new(TextureImage { width, height, pixels });
        Light::from_desc(&LightDesc::Goniometric { position: Vec3::ZERO, frame, image, intensity: Rgb::WHITE })
    };
    let e = make(4, 2, FRAME, 1.0).unwrap_err();
    assert!(e.contains("4×2") && e.contains("square"), "{e}");
    let e = make(2, 2, FRAME, f32::NAN).unwrap_err();
    assert!(e.contains("texel"), "{e}");
    let e = make(2, 2, [Vec3::X, Vec3::X, Vec3::Z], 1.0).unwrap_err();
    assert!(e.contains("orthonormal"), "{e}");
    // A black image emits nothing, and is not an error.
    let black = make(2, 2, FRAME, 0.0).unwrap();
    assert_eq!(black.power(&sphere()), 0.0);
}
