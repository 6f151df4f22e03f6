//! Cameras and pixel reconstruction filters through every algorithm.
//!
//! * Filters: sampled offsets against `eval_normalized` (chi-square), the normalisation of
//!   `eval_normalized` (numerical integral), the unbiasedness of the weighted estimate
//!   (`E[weight · g(offset)] = ∫ g · f/∫f`, Z-test) and the exactness of the box.
//! * Projection: a primary ray's points project back to its raster position through the same
//!   lens point, and the density a light-tracing connection reports equals the inverse of a
//!   pixel's footprint area measured by finite differences of primary rays (an independent
//!   computation), for the pinhole, the thin lens and the (mirrored) orthographic camera.
//! * Rendering: on a small Cornell box (area light, glossy floor, no specular surfaces) with
//!   each camera, light tracing and BPT agree with the path tracer on 8 × 8-pixel block means
//!   (Z-tests with a Šidák correction). Light tracing cannot see emitters directly: blocks
//!   that any primary ray (through the whole filter support and lens) sees an emitter from
//!   are left out of its comparison.

use crate::common;

use common::{BlockEstimate, block_estimate, settings};
use math::{Ray, Rng, Vec2, Vec3};
use render::RenderSettings;
use render::driver::{Budget, render};
use render::vcm::RadiusMode;
use scene::camera::{CameraModel, PrimaryDensity};
use scene::desc::{CameraDesc, FilterDesc, Projection};
use scene::{Camera, Filter, Scene, cornell};
use testkit::{MeanVar, assert_chi2, chi2_square, sidak, z_test_entries};

/// Image side in pixels.
const RESOLUTION: u32 = 64;
/// Block side in pixels.
const BLOCK: u32 = 8;
/// Family-wise significance of each test.
const ALPHA: f64 = 1e-3;
/// Cornell box with the light box and the glossy floor, no spheres.
const MASK: u32 = cornell::CEILING_LIGHT | cornell::GLOSSY_FLOOR;

fn gaussian() -> Filter {
    Filter::from_desc(&FilterDesc::Gaussian { stddev: 0.5, radius: 2.0 }).unwrap()
}

fn filters() -> Vec<(&'static str, Filter)> {
    vec![
        ("box", Filter::Box),
        ("tent r=1.5", Filter::from_desc(&FilterDesc::Tent { radius: 1.5 }).unwrap()),
        ("gaussian σ=0.5 r=2", gaussian()),
        ("gaussian σ=0.7 r=1.3", Filter::from_desc(&FilterDesc::Gaussian { stddev: 0.7, radius: 1.3 }).unwrap()),
    ]
}

/// The reference Cornell camera's pose.
fn reference_pose() -> (Vec3, Vec3, Vec3) {
    let forward = Vec3::new(0.00688625, 0.998505, -0.0542161).normalize();
    let up = Vec3::new(3.73896e-4, 0.0542148, 0.998529);
    let up = (up - forward * forward.dot(up)).normalize();
    (Vec3::new(-0.0439815, -4.12529, 0.222539), forward, up)
}

/// The three cameras of the tests, by name.
fn cameras() -> Vec<(&'static str, Camera)> {
    let (position, forward, up) = reference_pose();
    let right = up.cross(-forward);
    let pinhole = CameraDesc {
        position,
        forward,
        up,
        right,
        projection: Projection::Perspective { horizontal_fov_degrees: 45.0 },
    };
    // Focused in front of the box (its open front is 2.9 away): everything inside is blurred
    // by a few pixels.
    let thin_lens = CameraDesc {
        projection: Projection::ThinLens { horizontal_fov_degrees: 45.0, aperture_radius: 0.1, focus_distance: 2.5 },
        ..pinhole
    };
    // Tilted down and to the right so that the floor and a side wall are seen; mirrored.
    let ortho_forward = Vec3::new(0.15, 1.0, -0.25).normalize();
    let ortho_up = (Vec3::Z - ortho_forward * ortho_forward.z).normalize();
    let orthographic = CameraDesc {
        position: Vec3::new(0.0, -3.0, 0.5),
        forward: ortho_forward,
        up: ortho_up,
        right: -ortho_up.cross(-ortho_forward),
        projection: Projection::Orthographic { width: 1.6 },
    };
    let tent = Filter::from_desc(&FilterDesc::Tent { radius: 1.0 }).unwrap();
    vec![
        (
            "pinhole, gaussian filter",
            Camera::from_desc(&pinhole, RESOLUTION, RESOLUTION).unwrap().with_filter(gaussian()),
        ),
        ("thin lens, tent filter", Camera::from_desc(&thin_lens, RESOLUTION, RESOLUTION).unwrap().with_filter(tent)),
        ("mirrored orthographic, box filter", Camera::from_desc(&orthographic, RESOLUTION, RESOLUTION).unwrap()),
    ]
}

// ---------------------------------------------------------------------------------------------
// Filters

#[test]
fn filter_samples_follow_the_normalised_filter() {
    let filters = filters();
    let significance = sidak(ALPHA, filters.len());
    for (name, filter) in filters {
        let r = filter.radius() as f64;
        // The gaussian is sampled from a piecewise-constant table of 128 bins over [−r, r]
        // whose bin probabilities are the exact integrals of the filter, so on bins aligned
        // with the table (16 divides 128) the counts must match the filter itself; inside a
        // bin the weight corrects the difference (tested below).
        let outcome = chi2_square(
            |rng: &mut Rng| {
                let (offset, _) = filter.sample(rng.uniform2());
                Some([(offset.x as f64 + r) / (2.0 * r), (offset.y as f64 + r) / (2.0 * r)])
            },
            |p| {
                let offset = Vec2::new(((2.0 * p[0] - 1.0) * r) as f32, ((2.0 * p[1] - 1.0) * r) as f32);
                filter.eval_normalized(offset) as f64 * 4.0 * r * r
            },
            200_000,
            7,
            16,
        );
        assert_chi2(&outcome, significance, name);
    }
}

#[test]
fn normalised_filters_integrate_to_one() {
    for (name, filter) in filters() {
        // Midpoint rule on 1000² cells of the support: the filters are continuous with a few
        // kinks, so the error is far below 1e-4.
        let r = filter.radius() as f64;
        let n = 1000;
        let h = 2.0 * r / n as f64;
        let mut sum = 0.0f64;
        for i in 0..n {
            for j in 0..n {
                let x = -r + (i as f64 + 0.5) * h;
                let y = -r + (j as f64 + 0.5) * h;
                sum += filter.eval_normalized(Vec2::new(x as f32, y as f32)) as f64;
            }
        }
        let integral = sum * h * h;
        assert!((integral - 1.0).abs() < 1e-4, "{name}: ∫ f/∫f = {integral}");
        // Nothing outside the radius.
        assert_eq!(filter.eval_normalized(Vec2::new(filter.radius() * 1.001, 0.0)), 0.0, "{name}");
    }
}

/// A function of a filter offset.
type TestFunction = fn(Vec2) -> f64;

#[test]
fn weighted_filter_samples_are_unbiased() {
    // E[weight · g(offset)] must equal ∫ g · f/∫f for test functions g that do not follow the
    // gaussian's table bins: an indicator of an unaligned rectangle, and x² + x·y.
    let tests: [(&str, TestFunction); 2] = [
        ("rectangle", |o| if (0.13..0.61).contains(&o.x) && (-0.37..0.29).contains(&o.y) { 1.0 } else { 0.0 }),
        ("x² + xy", |o| (o.x * o.x + o.x * o.y) as f64),
    ];
    let filters = filters();
    let threshold = sidak(ALPHA, filters.len() * tests.len());
    for (name, filter) in filters {
        let r = filter.radius() as f64;
        for (what, g) in tests {
            let n = 2000;
            let h = 2.0 * r / n as f64;
            let mut exact = 0.0f64;
            for i in 0..n {
                for j in 0..n {
                    let o = Vec2::new((-r + (i as f64 + 0.5) * h) as f32, (-r + (j as f64 + 0.5) * h) as f32);
                    exact += g(o) * filter.eval_normalized(o) as f64;
                }
            }
            exact *= h * h;
            let mut rng = Rng::new(11, 3);
            let mut estimate = MeanVar::new();
            for _ in 0..1_000_000 {
                let (offset, weight) = filter.sample(rng.uniform2());
                estimate.push(weight as f64 * g(offset));
            }
            let p = testkit::z_test_p(estimate.mean() - exact, estimate.std_error());
            assert!(
                p >= threshold,
                "{name}, {what}: estimate {} ± {} against {exact} (p = {p:.2e})",
                estimate.mean(),
                estimate.std_error()
            );
        }
    }
}

#[test]
fn box_filter_is_exact() {
    let camera = Camera::new(Vec3::ZERO, Vec3::Y, Vec3::Z, 45.0, 40, 30);
    let mut rng = Rng::new(5, 1);
    for _ in 0..10_000 {
        let u = rng.uniform2();
        let (offset, weight) = Filter::Box.sample(u);
        assert_eq!(weight, 1.0);
        assert!(offset.x.abs() <= 0.5 && offset.y.abs() <= 0.5);
        let (raster, weight) = camera.sample_pixel(17, 4, u);
        assert_eq!(weight, 1.0);
        assert_eq!((raster.x.to_bits(), raster.y.to_bits()), ((17.0 + u[0]).to_bits(), (4.0 + u[1]).to_bits()));
    }
    // A primary ray of the pinhole with the box filter draws two numbers, nothing for a lens.
    let mut a = Rng::new(9, 9);
    let mut b = Rng::new(9, 9);
    let primary = camera.sample_primary(3, 5, [0.25, 0.75], &mut a);
    let u = b.uniform2();
    assert_eq!(primary.ray, camera.generate_ray(Vec2::new(3.0 + u[0], 5.0 + u[1])));
    assert_eq!(a.next_u32(), b.next_u32(), "same random stream position");
}

#[test]
fn filter_pixels_lists_every_pixel_the_filter_reaches() {
    // Brute force over all pixels of a small image: every pixel whose centre the filter reaches
    // (non-zero value) is listed once, with the filter's value at its offset.
    for (name, filter) in filters() {
        let camera = Camera::new(Vec3::ZERO, Vec3::Y, Vec3::Z, 45.0, 9, 7).with_filter(filter);
        let mut rng = Rng::new(2, 8);
        for _ in 0..2000 {
            let raster = Vec2::new(rng.uniform() * 13.0 - 2.0, rng.uniform() * 11.0 - 2.0);
            if !camera.accepts_raster(raster) {
                continue;
            }
            let listed: Vec<(u32, f32)> = camera.filter_pixels(raster).collect();
            let mut pixels: Vec<u32> = listed.iter().map(|l| l.0).collect();
            pixels.dedup();
            assert_eq!(pixels.len(), listed.len(), "{name}: a pixel listed twice at {raster}");
            for y in 0..7u32 {
                for x in 0..9u32 {
                    let expected = if filter.is_box() {
                        let inside = raster.x.floor() as u32 == x && raster.y.floor() as u32 == y;
                        if inside { 1.0 } else { 0.0 }
                    } else {
                        filter.eval_normalized(raster - Vec2::new(x as f32 + 0.5, y as f32 + 0.5))
                    };
                    let got = listed.iter().find(|l| l.0 == y * 9 + x).map_or(0.0, |l| l.1);
                    assert_eq!(got, expected, "{name}: pixel ({x}, {y}) at raster {raster}");
                }
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Projection

/// Where `ray` crosses the plane through `point` with normal `normal`.
fn on_plane(ray: &Ray, point: Vec3, normal: Vec3) -> Vec3 {
    ray.at((point - ray.origin).dot(normal) / ray.direction.dot(normal))
}

#[test]
fn primary_rays_project_back_and_report_their_footprint_density() {
    for (name, camera) in cameras() {
        let mut rng = Rng::new(3, 4);
        let r = camera.filter.radius().max(0.5);
        let (w, h) = (camera.width as f32, camera.height as f32);
        let mut checked = 0;
        for _ in 0..500 {
            // Raster positions up to the filter's reach outside the image.
            let raster =
                Vec2::new(0.5 - r + rng.uniform() * (w - 1.0 + 2.0 * r), 0.5 - r + rng.uniform() * (h - 1.0 + 2.0 * r));
            if !camera.accepts_raster(raster) {
                continue;
            }
            let u_lens = rng.uniform2();
            let ray = camera.generate_ray_through_lens(raster, u_lens);
            let t = 1.0 + 3.0 * rng.uniform();
            let point = ray.at(t);
            let connection = camera.connect(point, u_lens).unwrap_or_else(|| panic!("{name}: {raster} not connected"));
            assert!((connection.raster - raster).length() < 2e-3, "{name}: {raster} -> {}", connection.raster);
            assert!((connection.lens_point - ray.origin).length() < 1e-5, "{name}: lens point");
            assert!((connection.direction + ray.direction).length() < 1e-4, "{name}: direction");
            assert!((connection.distance - t).abs() < 1e-4 * t, "{name}: distance {} vs {t}", connection.distance);

            // The density per unit area on a random plane through the point: the inverse of the
            // area one pixel covers there, by central differences of rays through the same lens
            // point.
            let tilt = Vec3::new(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5);
            let normal = (-ray.direction + tilt).normalize();
            let cos = normal.dot(connection.direction);
            let step = 0.25;
            let at = |dx: f32, dy: f32| {
                on_plane(&camera.generate_ray_through_lens(raster + Vec2::new(dx, dy), u_lens), point, normal)
            };
            let ex = (at(step, 0.0) - at(-step, 0.0)) / (2.0 * step);
            let ey = (at(0.0, step) - at(0.0, -step)) / (2.0 * step);
            let pixel_area = ex.cross(ey).length();
            let pdf = connection.area_pdf(cos).0;
            assert!((pdf * pixel_area - 1.0).abs() < 2e-3, "{name}: area pdf {pdf} × pixel area {pixel_area}");
            // The MIS start of a camera sub-path reaches the same density at the point.
            let start = match camera.primary_density(ray.direction) {
                PrimaryDensity::SolidAngle(p) => p.to_area(t * t, cos).0,
                PrimaryDensity::Area(p) => p.0 * cos,
            };
            assert!((start / pdf - 1.0).abs() < 1e-3, "{name}: start density {start} vs {pdf}");
            // The footprint radius of the per-pixel merging radius: a disc of the area of one
            // pixel, perpendicular to the ray through the lens centre.
            let centre = [0.5, 0.5];
            let ray = camera.generate_ray_through_lens(raster, centre);
            let at = |dx: f32, dy: f32| {
                on_plane(&camera.generate_ray_through_lens(raster + Vec2::new(dx, dy), centre), point, ray.direction)
            };
            let ex = (at(step, 0.0) - at(-step, 0.0)) / (2.0 * step);
            let ey = (at(0.0, step) - at(0.0, -step)) / (2.0 * step);
            let footprint = camera.footprint_radius(&ray, (point - ray.origin).dot(ray.direction));
            let area = math::PI * footprint * footprint;
            let measured = ex.cross(ey).length();
            assert!((area / measured - 1.0).abs() < 2e-3, "{name}: footprint {area} vs {measured}");
            checked += 1;
        }
        assert!(checked > 400, "{name}: only {checked} raster positions checked");
        // Behind the camera: nothing.
        assert!(camera.connect(camera.position - camera.forward, [0.3, 0.6]).is_none(), "{name}");
    }
}

#[test]
fn thin_lens_focuses_and_mirroring_flips_the_image() {
    let (_, thin) = cameras().swap_remove(1);
    let CameraModel::ThinLens { focus_distance, .. } = thin.model else { panic!("not a thin lens") };
    let mut rng = Rng::new(1, 2);
    for _ in 0..100 {
        let raster = Vec2::new(rng.uniform() * 64.0, rng.uniform() * 64.0);
        let centre = thin.generate_ray(raster);
        // The point of the plane in focus on the centre ray projects to the same raster point
        // through every lens point; a point behind it does not.
        let focused = centre.at(focus_distance / centre.direction.dot(thin.forward));
        let behind = centre.at(2.0 * focus_distance / centre.direction.dot(thin.forward));
        let u = rng.uniform2();
        let c = thin.connect(focused, u).unwrap();
        assert!((c.raster - raster).length() < 2e-3, "{raster} -> {}", c.raster);
        let edge = [0.999, 0.5];
        if let Some(c) = thin.connect(behind, edge) {
            assert!((c.raster - raster).length() > 1.0, "out of focus: {raster} -> {}", c.raster);
        }
    }
    // A mirrored pinhole sees at raster (x, y) what the original sees at (width − x, y).
    let (position, forward, up) = reference_pose();
    let desc = |right: Vec3| CameraDesc {
        position,
        forward,
        up,
        right,
        projection: Projection::Perspective { horizontal_fov_degrees: 45.0 },
    };
    let normal = Camera::from_desc(&desc(up.cross(-forward)), 64, 48).unwrap();
    let mirrored = Camera::from_desc(&desc(-up.cross(-forward)), 64, 48).unwrap();
    for raster in [Vec2::new(3.0, 7.0), Vec2::new(40.5, 30.25)] {
        let a = normal.generate_ray(raster).direction;
        let b = mirrored.generate_ray(Vec2::new(64.0 - raster.x, raster.y)).direction;
        assert!((a - b).length() < 1e-6, "{a} vs {b}");
    }
    // Camera::from_desc reproduces Camera::new for the same pose.
    let built = Camera::new(position, forward, up, 45.0, 64, 48);
    for raster in [Vec2::new(0.0, 0.0), Vec2::new(33.3, 12.0)] {
        let (a, b) = (built.generate_ray(raster).direction, normal.generate_ray(raster).direction);
        assert!((a - b).length() < 1e-6, "{a} vs {b}");
    }
}

#[test]
fn invalid_camera_descriptions_are_errors() {
    let (position, forward, up) = reference_pose();
    let good = CameraDesc {
        position,
        forward,
        up,
        right: up.cross(-forward),
        projection: Projection::Perspective { horizontal_fov_degrees: 45.0 },
    };
    let error = |desc: CameraDesc| Camera::from_desc(&desc, 16, 16).unwrap_err();
    assert!(
        error(CameraDesc { projection: Projection::Perspective { horizontal_fov_degrees: 180.0 }, ..good })
            .contains("field of view")
    );
    let lens = Projection::ThinLens { horizontal_fov_degrees: 40.0, aperture_radius: 0.0, focus_distance: 1.0 };
    assert!(error(CameraDesc { projection: lens, ..good }).contains("aperture"));
    assert!(error(CameraDesc { projection: Projection::Orthographic { width: -1.0 }, ..good }).contains("width"));
    assert!(error(CameraDesc { right: forward, ..good }).contains("right"));
    assert!(error(CameraDesc { up: forward, ..good }).contains("up"));
    assert!(error(CameraDesc { position: Vec3::NAN, ..good }).contains("position"));
    assert!(Camera::from_desc(&good, 0, 16).is_err());
}

// ---------------------------------------------------------------------------------------------
// Rendering

/// The test scene seen by `camera`.
fn scene_with(camera: Camera) -> Scene {
    let mut scene = cornell::build(MASK, RESOLUTION, RESOLUTION).unwrap();
    scene.camera = camera;
    scene
}

/// Blocks in which some primary ray (any raster point of the filter support of any of the
/// block's pixels, any lens point) sees an emitter: 64 random rays per pixel.
fn blocks_seeing_emitters(scene: &Scene) -> Vec<bool> {
    let camera = &scene.camera;
    let blocks = RESOLUTION / BLOCK;
    let mut seen = vec![false; (blocks * blocks) as usize];
    let mut rng = Rng::new(77, 0);
    for y in 0..RESOLUTION {
        for x in 0..RESOLUTION {
            for _ in 0..64 {
                // Uniform over the support (the filter's own samples avoid its tails).
                let r = camera.filter.radius();
                let raster = Vec2::new(x as f32 + 0.5, y as f32 + 0.5)
                    + Vec2::new((2.0 * rng.uniform() - 1.0) * r, (2.0 * rng.uniform() - 1.0) * r);
                let ray = camera.generate_ray_through_lens(raster, rng.uniform2());
                if scene.intersect(&ray).is_some_and(|hit| hit.light.is_some()) {
                    seen[((y / BLOCK) * blocks + x / BLOCK) as usize] = true;
                }
            }
        }
    }
    seen
}

/// The entries (3 per block) of the blocks `keep` selects, scaled.
fn entries(estimate: &BlockEstimate, keep: &[bool], scale: f64) -> (Vec<f64>, Vec<f64>) {
    let mut means = Vec::new();
    let mut errors = Vec::new();
    for (b, _) in keep.iter().enumerate().filter(|(_, k)| **k) {
        means.extend(estimate.means[b * 3..b * 3 + 3].iter().map(|m| m * scale));
        errors.extend(estimate.std_errors[b * 3..b * 3 + 3].iter().map(|e| e * scale));
    }
    (means, errors)
}

#[test]
fn light_tracing_and_bpt_agree_with_the_path_tracer_for_every_camera() {
    let cameras = cameras();
    // Two comparisons per camera.
    let alpha = sidak(ALPHA, 2 * cameras.len());
    let mut failures = Vec::new();
    let mut emitter_blocks = 0;
    for (name, camera) in cameras {
        let scene = scene_with(camera);
        let emitters = blocks_seeing_emitters(&scene);
        let start = std::time::Instant::now();
        let pt = block_estimate(&scene, &settings("pt", 1), 320, BLOCK);
        let lt = block_estimate(&scene, &settings("lt", 2), 320, BLOCK);
        let bpt = block_estimate(&scene, &settings("bpt", 3), 120, BLOCK);
        eprintln!("{name}: rendered in {:.1} s", start.elapsed().as_secs_f64());
        let all = vec![true; emitters.len()];
        // lt shows emitters seen directly through its s = 1, t = 1 connection: every block is
        // compared, those seeing an emitter included (they were black before it).
        let seeing = emitters.iter().filter(|e| **e).count();
        eprintln!("{name}: {seeing} blocks see an emitter");
        emitter_blocks += seeing;
        for (algorithm, estimate, keep) in [("lt", &lt, &all), ("bpt", &bpt, &all)] {
            let blocks = keep.iter().filter(|k| **k).count();
            assert!(blocks >= 32, "{name}, {algorithm}: only {blocks} blocks compared");
            let (am, ae) = entries(estimate, keep, 1.0);
            let (bm, be) = entries(&pt, keep, 1.0);
            let outcome = z_test_entries(&am, &ae, &bm, &be, alpha);
            // Power: a 5 % error in the compared blocks would be seen.
            let (sm, se) = entries(estimate, keep, 1.05);
            let scaled = z_test_entries(&sm, &se, &bm, &be, alpha);
            eprintln!("{name}: {algorithm} vs pt on {blocks} blocks: {outcome}; scaled by 1.05: {scaled}");
            assert!(!scaled.passed, "{name}, {algorithm}: no power to see a 5 % error ({scaled})");
            if !outcome.passed {
                let block = outcome.worst_index / 3;
                failures.push(format!("{name}: {algorithm} vs pt (worst entry in block {block}): {outcome}"));
            }
        }
    }
    assert!(emitter_blocks >= 8, "only {emitter_blocks} blocks see an emitter: lt's s = 1, t = 1 splats go untested");
    assert!(failures.is_empty(), "inconsistent estimates:\n{}", failures.join("\n"));
}

#[test]
fn per_pixel_splats_match_filtered_splats() {
    // With a per-pixel radius, light tracing splats into each pixel of the filter's reach with
    // that pixel's MIS constants; without merging those weights do not depend on the radius,
    // so BPT must give the image of the global radius (which splats once per connection and
    // spreads it when the splats are applied), up to rounding.
    let (_, camera) = cameras().swap_remove(0);
    let scene = scene_with(camera);
    let run = |radius_mode| {
        let settings = RenderSettings { budget: Budget::Iterations(2), radius_mode, ..settings("bpt", 5) };
        render(&scene, &settings).unwrap().film.mean()
    };
    let (global, per_pixel) = (run(RadiusMode::Global), run(RadiusMode::PerPixel));
    let mut largest = 0.0f32;
    for (a, b) in global.iter().zip(&per_pixel) {
        for c in 0..3 {
            largest = largest.max((a[c] - b[c]).abs() / a[c].abs().max(1e-3));
        }
    }
    assert!(largest < 1e-4, "largest relative difference {largest}");
    assert!(global.iter().any(|p| p[0] > 0.0));
}

/// Image of the edge test: columns × rows.
const EDGE_SIZE: (u32, u32) = (32, 8);
/// Raster column of the plane's edge.
const EDGE_RASTER: f32 = 13.3;
/// Albedo of the plane and irradiance of the light.
const EDGE_ALBEDO: f32 = 0.7;
const EDGE_IRRADIANCE: f32 = 3.0;

/// A diffuse plane at z = 0 seen straight from above (height 2, 2 scene units across the
/// image), lit by a directional light, that covers the image right of raster column
/// [`EDGE_RASTER`] and nothing else: the filtered image of column `i` is
/// `L · P(X > EDGE_RASTER − (i + 0.5))`, X distributed as the filter's marginal, with the
/// radiance `L = ρ E cos/π` exact (one bounce, nothing else to hit).
fn edge_scene(camera: Camera) -> (Scene, f32) {
    use scene::light::DirectionalLight;
    use scene::shape::{Shape, Triangle};
    use scene::{Light, Primitive, ReferenceMaterial};
    use spectrum::Rgb;
    let (w, _) = EDGE_SIZE;
    let pixel = 2.0 / w as f32;
    let x0 = (EDGE_RASTER - 0.5 * w as f32) * pixel;
    let (x1, y0, y1) = (1.25, -0.5, 0.5);
    let p = |x: f32, y: f32| Vec3::new(x, y, 0.0);
    let triangles = [Triangle::new(p(x0, y0), p(x1, y0), p(x1, y1)), Triangle::new(p(x0, y0), p(x1, y1), p(x0, y1))];
    let primitives = triangles.map(|t| Primitive::new(Shape::Triangle(t), 0, None)).to_vec();
    let direction = Vec3::new(0.3, 0.2, -1.0).normalize();
    let light = Light::Directional(DirectionalLight::new(direction, Rgb::splat(EDGE_IRRADIANCE)));
    let material = ReferenceMaterial::diffuse(Rgb::splat(EDGE_ALBEDO)).into();
    let radiance = EDGE_ALBEDO * EDGE_IRRADIANCE * (-direction.z) / math::PI;
    (Scene::new("edge", primitives, vec![material], vec![light], camera), radiance)
}

/// `P(X > a)` for X distributed as the marginal of the normalised filter (midpoint rule).
fn marginal_tail(filter: &Filter, a: f64) -> f64 {
    let r = filter.radius() as f64;
    let integrate = |from: f64, to: f64, f: &dyn Fn(f64) -> f64| {
        if to <= from {
            return 0.0;
        }
        let n = 100_000;
        let h = (to - from) / n as f64;
        (0..n).map(|k| f(from + (k as f64 + 0.5) * h)).sum::<f64>() * h
    };
    // Separable: eval(t, 0) / ∫ eval(0, y) dy is the marginal density.
    let column = integrate(-r, r, &|y| filter.eval_normalized(Vec2::new(0.0, y as f32)) as f64);
    integrate(a.max(-r), r, &|t| filter.eval_normalized(Vec2::new(t as f32, 0.0)) as f64) / column
}

#[test]
fn filtered_edge_matches_its_analytic_image() {
    let (w, h) = EDGE_SIZE;
    let looking_down = |projection| CameraDesc {
        position: Vec3::new(0.0, 0.0, 2.0),
        forward: Vec3::NEG_Z,
        up: Vec3::Y,
        right: Vec3::X,
        projection,
    };
    let fov = 2.0 * 0.5f32.atan().to_degrees();
    let wide_gaussian = Filter::from_desc(&FilterDesc::Gaussian { stddev: 1.0, radius: 3.0 }).unwrap();
    let tent = Filter::from_desc(&FilterDesc::Tent { radius: 2.0 }).unwrap();
    let cameras = [
        ("pinhole, gaussian σ=1 r=3", Projection::Perspective { horizontal_fov_degrees: fov }, wide_gaussian),
        (
            "thin lens focused on the plane, tent r=2",
            Projection::ThinLens { horizontal_fov_degrees: fov, aperture_radius: 0.05, focus_distance: 2.0 },
            tent,
        ),
        ("orthographic, gaussian σ=1 r=3", Projection::Orthographic { width: 2.0 }, wide_gaussian),
    ];
    let plans = [("pt", 1500u64), ("lt", 3000), ("bpt", 1000)];
    let alpha = sidak(ALPHA, cameras.len() * plans.len());
    let mut failures = Vec::new();
    for (name, projection, filter) in cameras {
        let camera = Camera::from_desc(&looking_down(projection), w, h).unwrap().with_filter(filter);
        let (scene, radiance) = edge_scene(camera);
        let expected: Vec<f64> =
            (0..w).map(|i| radiance as f64 * marginal_tail(&filter, (EDGE_RASTER - (i as f32 + 0.5)) as f64)).collect();
        // What an unfiltered (box) image would show: the test must tell it apart.
        let unfiltered: Vec<f64> =
            (0..w).map(|i| radiance as f64 * (i as f64 + 1.0 - EDGE_RASTER as f64).clamp(0.0, 1.0)).collect();
        // Numerical accuracy of the expected values (f32 rendering, quadrature).
        let tolerance: Vec<f64> = expected.iter().map(|e| 2e-4 * e + 1e-7).collect();
        for (algorithm, iterations) in plans {
            let settings = RenderSettings { max_length: 3, ..settings(algorithm, 9) };
            let mut renderer = render::driver::Renderer::new(&scene, &settings).unwrap();
            let mut columns = vec![MeanVar::new(); w as usize];
            for _ in 0..iterations {
                assert_eq!(renderer.step(), 0);
                for (x, column) in columns.iter_mut().enumerate() {
                    let sum: f64 = (0..h).map(|y| renderer.frame().pixels[(y * w) as usize + x].r as f64).sum();
                    column.push(sum / h as f64);
                }
            }
            // Columns the filter reaches only with its last percent of mass are left out: camera
            // paths land there only a few times in the whole run, so the spread of the
            // iterations does not show the error of their mean (a rare-event tail, not a
            // bias). Columns it does not reach at all must be exactly black.
            let kept: Vec<usize> =
                (0..w as usize).filter(|&i| expected[i] == 0.0 || expected[i] >= 0.01 * radiance as f64).collect();
            let pick = |v: &[f64]| kept.iter().map(|&i| v[i]).collect::<Vec<f64>>();
            let means = pick(&columns.iter().map(MeanVar::mean).collect::<Vec<f64>>());
            let errors = pick(&columns.iter().map(MeanVar::std_error).collect::<Vec<f64>>());
            let (expected, unfiltered, tolerance) = (pick(&expected), pick(&unfiltered), pick(&tolerance));
            let outcome = z_test_entries(&means, &errors, &expected, &tolerance, alpha);
            let against_box = z_test_entries(&means, &errors, &unfiltered, &tolerance, alpha);
            eprintln!("{name}, {algorithm}: {outcome}; against the unfiltered edge: {against_box}");
            assert!(!against_box.passed, "{name}, {algorithm}: cannot tell the filtered edge from the unfiltered one");
            if !outcome.passed {
                let i = outcome.worst_index;
                failures.push(format!(
                    "{name}, {algorithm}: column {} {} ± {} against {}: {outcome}",
                    kept[i], means[i], errors[i], expected[i]
                ));
            }
        }
    }
    assert!(failures.is_empty(), "filtered edges differ from the analytic image:\n{}", failures.join("\n"));
}
