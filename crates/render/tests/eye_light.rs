//! The eye-light preview (`-a el`) through the renderer: a plane seen head-on is grey with
//! `|cos θ| = 1`, a plane tilted by 60° grey with 0.5, the same plane seen from behind red with
//! 0.5, and rays that miss are black — the values the README promises (`|cos| preview; back
//! faces red`).
//!
//! Truth: the cosine between the plane's normal and the ray through the pixel, from the pinhole
//! geometry alone. The camera's field of view is 2° over 32 pixels, so a pixel spans
//! `2°/32 = 1.09e-3` rad and the cosine changes across one by at most `sin θ · 1.09e-3`; every
//! tolerance below is that bound.

use math::Vec3;
use render::driver::Budget;
use render::{Algorithm, RenderSettings};
use scene::shape::{Shape, Triangle};
use scene::{Camera, Material, Primitive, ReferenceMaterial, Scene};
use spectrum::Rgb;

const RESOLUTION: u32 = 32;
const FOV_DEGREES: f32 = 2.0;

/// A square of half side 1 around `(0, 0, 5)` (the camera at the origin looks along +z), turned
/// by `tilt_degrees` about the y axis, facing the camera (`front`) or away from it.
fn plane(tilt_degrees: f32, front: bool) -> Scene {
    let (s, c) = tilt_degrees.to_radians().sin_cos();
    let centre = Vec3::new(0.0, 0.0, 5.0);
    // In-plane axes: x turned about y, and y.
    let (u, v) = (Vec3::new(c, 0.0, -s), Vec3::Y);
    let corners = [centre - u - v, centre + u - v, centre + u + v, centre - u + v];
    let mut primitives = Vec::new();
    for [a, b, d] in [[0, 1, 2], [0, 2, 3]] {
        // Winding (a, b, d) has the normal u × v = (sin, 0, cos), away from the camera.
        let t = if front {
            Triangle::new(corners[a], corners[d], corners[b])
        } else {
            Triangle::new(corners[a], corners[b], corners[d])
        };
        let towards_camera = t.normal.dot(-centre) > 0.0;
        assert_eq!(towards_camera, front, "winding of the test plane");
        primitives.push(Primitive::new(Shape::Triangle(t), 0, None));
    }
    let material: Material = ReferenceMaterial::diffuse(Rgb::splat(0.5)).into();
    let camera = Camera::new(Vec3::ZERO, Vec3::Z, Vec3::Y, FOV_DEGREES, RESOLUTION, RESOLUTION);
    Scene::new("eye-light plane", primitives, vec![material], Vec::new(), camera)
}

/// One eye-light iteration of `scene`.
fn render(scene: &Scene) -> Vec<[f32; 3]> {
    let settings = RenderSettings {
        algorithm: Algorithm::from_name("el").unwrap(),
        budget: Budget::Iterations(1),
        seed: 5,
        ..RenderSettings::default()
    };
    let output = render::render(scene, &settings).unwrap();
    assert_eq!(output.film.rejected_samples(), 0);
    output.film.mean()
}

/// Angle of the ray through the image corner (the largest) and the span of one pixel, in rad.
fn angles() -> (f32, f32) {
    let tan_half = (FOV_DEGREES.to_radians() / 2.0).tan();
    (tan_half.hypot(tan_half).atan(), FOV_DEGREES.to_radians() / RESOLUTION as f32)
}

/// The four pixels around the image centre, where the ray is within one pixel diagonal of the
/// optical axis.
fn centre(image: &[[f32; 3]]) -> Vec<[f32; 3]> {
    let (a, b) = (RESOLUTION as usize / 2 - 1, RESOLUTION as usize / 2);
    [(a, a), (a, b), (b, a), (b, b)].iter().map(|&(x, y)| image[y * RESOLUTION as usize + x]).collect()
}

#[test]
fn plane_seen_head_on_is_grey_one() {
    let image = render(&plane(0.0, true));
    let (corner, pixel) = angles();
    // Tilt 0: the plane covers the whole view (half side 1 at distance 5 ≫ tan 1°·5).
    for (i, p) in image.iter().enumerate() {
        assert!(p[0] == p[1] && p[1] == p[2], "pixel {i} is not grey: {p:?}");
        assert!(p[0] <= 1.0 && p[0] >= corner.cos() - 1e-6, "pixel {i}: {p:?} (corner cosine {})", corner.cos());
    }
    // Near the axis θ ≤ √2 pixels: cos ≥ 1 − θ²/2.
    let bound = 1.0 - (2.0 * pixel * pixel);
    for p in centre(&image) {
        assert!(p[0] >= bound - 1e-6, "{p:?} below {bound}");
    }
}

#[test]
fn tilted_plane_gives_the_cosine_and_back_faces_are_red() {
    let (_, pixel) = angles();
    // Within √2 pixels of the axis the cosine is 0.5 ± sin 60° · √2 · pixel.
    let tolerance = 60f32.to_radians().sin() * 2f32.sqrt() * pixel + 1e-6;
    let front = render(&plane(60.0, true));
    for p in centre(&front) {
        assert!((p[0] - 0.5).abs() < tolerance && p[0] == p[1] && p[1] == p[2], "front {p:?} (±{tolerance})");
    }
    let back = render(&plane(60.0, false));
    for p in centre(&back) {
        assert!((p[0] - 0.5).abs() < tolerance && p[1] == 0.0 && p[2] == 0.0, "back {p:?} (±{tolerance})");
    }
    // Front and back see the same |cos| in every pixel the plane covers.
    for (f, b) in front.iter().zip(&back) {
        assert!((f[0] - b[0]).abs() < 1e-6, "{f:?} vs {b:?}");
    }
}

#[test]
fn rays_that_miss_are_black() {
    // Tilted by 89.9°, the square is seen nearly edge-on: |x| ≤ cos 89.9° = 1.7e-3 at depths
    // z ≥ 4, i.e. within 1.7e-3 / 4 / tan 1° · 16 = 0.4 pixel of the vertical centre line; the
    // other 30 columns are black.
    let image = render(&plane(89.9, true));
    let black = image.iter().filter(|p| **p == [0.0; 3]).count();
    assert!(black >= (RESOLUTION * (RESOLUTION - 2)) as usize, "{black} black pixels");
    assert!(image.iter().all(|p| p.iter().all(|v| (0.0..=1.0).contains(v))));
}
