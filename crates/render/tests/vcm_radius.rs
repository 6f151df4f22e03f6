//! The default merging radius on a scene whose bounding sphere is far larger than what the
//! camera sees (issue #12, the shape of Mitsuba's projector scenes): a point light 0.25 above a
//! 2000 × 2000 diffuse floor, seen from height 1 over `[-1, 1]²`. Every path has two segments
//! (camera → floor → light: nothing else exists), so the pixel values are known analytically:
//! L(x) = (ρ/π) · I · h / d³ at the floor point x, d its distance from the light and h the
//! light's height, averaged over each pixel (the box filter). With the merging scale of
//! `render::vcm::radius` (the visible part's radius here) vcm agrees with that per block; with
//! the scene's bounding-sphere radius (the rule before, 1000 times larger) merging blurs the
//! light's peak and the same test fails.

use crate::common;

use common::{block_estimate, detectable_bias, settings};
use math::Vec3;
use render::RenderSettings;
use render::vcm::radius::MergingScale;
use scene::light::PointLight;
use scene::shape::{Shape, Triangle};
use scene::{Camera, Light, Material, Primitive, ReferenceMaterial, Scene};
use spectrum::Rgb;
use testkit::z_test_entries;

const RESOLUTION: u32 = 32;
const BLOCK: u32 = 4;
const ALBEDO: f32 = 0.5;
const INTENSITY: [f32; 3] = [1.0, 0.7, 0.4];
const LIGHT: Vec3 = Vec3::new(0.3, 0.2, 0.25);

/// The floor (normal +z), the point light above it and the camera looking straight down.
fn scene() -> Scene {
    let c = |x: f32, y: f32| Vec3::new(1000.0 * x, 1000.0 * y, 0.0);
    let primitives = [[c(-1., -1.), c(1., -1.), c(1., 1.)], [c(-1., -1.), c(1., 1.), c(-1., 1.)]]
        .map(|[a, b, d]| Primitive::new(Shape::Triangle(Triangle::new(a, b, d)), 0, None))
        .to_vec();
    let material: Material = ReferenceMaterial::diffuse(Rgb::splat(ALBEDO)).into();
    let light = Light::Point(PointLight { position: LIGHT, intensity: Rgb::from_array(INTENSITY) });
    let camera = Camera::new(Vec3::Z, -Vec3::Z, Vec3::Y, 90.0, RESOLUTION, RESOLUTION);
    Scene::new("floor-point", primitives, vec![material], vec![light], camera)
}

/// The exact block means: L(x) averaged over a 16 × 16 grid of raster points per pixel
/// (midpoint rule; its error is below 1e-4 of the values, far under the estimates' noise).
fn analytic_blocks(scene: &Scene) -> Vec<f64> {
    let blocks = (RESOLUTION / BLOCK) as usize;
    let mut sums = vec![0.0f64; blocks * blocks * 3];
    let sub = 16;
    for y in 0..RESOLUTION {
        for x in 0..RESOLUTION {
            for (j, i) in (0..sub).flat_map(|j| (0..sub).map(move |i| (j, i))) {
                let raster =
                    math::Vec2::new(x as f32 + (i as f32 + 0.5) / sub as f32, y as f32 + (j as f32 + 0.5) / sub as f32);
                let ray = scene.camera.generate_ray(raster);
                let point = ray.origin + ray.direction * (-ray.origin.z / ray.direction.z);
                let d = f64::from((point - LIGHT).length());
                let radiance = f64::from(ALBEDO) / std::f64::consts::PI * f64::from(LIGHT.z) / (d * d * d);
                let b = (y / BLOCK) as usize * blocks + (x / BLOCK) as usize;
                for (channel, intensity) in INTENSITY.iter().enumerate() {
                    sums[b * 3 + channel] += radiance * f64::from(*intensity);
                }
            }
        }
    }
    let samples = f64::from(BLOCK * BLOCK) * f64::from(sub * sub);
    sums.iter().map(|s| s / samples).collect()
}

/// Renders `iterations` of vcm with `radius_factor` and Z-tests the block means against the
/// analytic ones (Šidák over the 192 entries, α = 0.001); returns whether it passed and the
/// smallest relative bias the test detects.
fn test_vcm(scene: &Scene, radius_factor: f32, iterations: u64) -> (bool, f64) {
    let settings = RenderSettings { radius_factor, ..settings("vcm", 21) };
    let estimate = block_estimate(scene, &settings, iterations, BLOCK);
    let truth = analytic_blocks(scene);
    let zero = vec![0.0; truth.len()];
    let outcome = z_test_entries(&estimate.means, &estimate.std_errors, &truth, &zero, 1e-3);
    let detectable = detectable_bias(&estimate.means, &estimate.std_errors, &truth, &zero, 1e-3);
    eprintln!("radius factor {radius_factor}: detects a bias of {:.2} %, {outcome}", 100.0 * detectable);
    (outcome.passed, detectable)
}

/// Power: detects a 1 % bias of the whole image (measured 0.69 %).
#[test]
fn default_radius_renders_a_small_view_of_a_huge_floor_without_merging_blur() {
    let scene = scene();
    let scale = MergingScale::of(&scene);
    assert_eq!(Some(scale.scale), scale.visible_radius, "{scale:?}");
    let (passed, detectable) = test_vcm(&scene, RenderSettings::default().radius_factor, 400);
    assert!(passed, "vcm with the default radius disagrees with the analytic image");
    assert!(detectable <= 0.01, "detects only a bias of {:.1} %", 100.0 * detectable);
}

#[test]
fn the_scene_relative_radius_blurs_the_light_and_fails() {
    // The radius factor that gives the rule before the merging scale: 0.003 × R_scene.
    let scene = scene();
    let scale = MergingScale::of(&scene);
    let factor = RenderSettings::default().radius_factor * scale.scene_radius / scale.scale;
    let (passed, _) = test_vcm(&scene, factor, 100);
    assert!(!passed, "the scene-relative radius (factor {factor}) should blur the light's peak");
}

#[test]
fn the_visible_radius_is_the_same_for_every_thread_count_and_the_memory_efficient_mode() {
    // The probes run on the calling thread: one radius, so the same film bit for bit.
    let scene = scene();
    let image = |threads, memory_efficient| {
        let s = RenderSettings {
            threads,
            memory_efficient,
            budget: render::driver::Budget::Iterations(2),
            ..settings("vcm", 5)
        };
        render::render(&scene, &s).unwrap().film.mean()
    };
    let reference = image(1, false);
    assert_eq!(image(2, false), reference);
    assert_eq!(image(1, true), reference);
    assert_eq!(image(2, true), reference);
}
