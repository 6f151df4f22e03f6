//! The splatting film (`--film splat`, [`FilmMode::Splat`]) against independent truths.
//!
//! * Normalisation: every pixel's splat weights integrate to one over the image
//!   (`∫_image f(x − c_j)/N_j dx = 1`, midpoint quadrature), borders and corners included.
//! * Borders: on a plane seen through a 90° pinhole with the eye light, `L(x)` is known in
//!   closed form (`d / |(x − centre, d)|`, `d` the image-plane distance in pixels); every border
//!   pixel of a splat render matches `∫_image f(x − c_j) L(x) dx / N_j` by quadrature (Z-test),
//!   and a filter-importance-sampled render, which estimates the untruncated filter there,
//!   fails the same test (power).
//! * Interior: splat and FIS renders of the Cornell box agree on 8 × 8 block means away from
//!   the borders, with the eye light (a 2 % scaled splat image fails) and the path tracer (a
//!   5 % scaled one fails).
//! * Light tracing agrees with the path tracer in splat mode (blocks that see emitters left
//!   out, as in `cameras.rs`), and a 5 % scaled image fails.
//! * Determinism across thread counts for every algorithm, the box filter bit-identical in both
//!   modes, and technique images summing to the frame in splat mode.

use crate::common;

use common::{BlockEstimate, block_estimate, settings};
use math::{Rng, Vec2, Vec3};
use render::RenderSettings;
use render::driver::{Budget, Renderer, render};
use render::vcm::RadiusMode;
use render::vcm::technique_images::TechniqueLayout;
use scene::desc::FilterDesc;
use scene::filter::FilmMode;
use scene::shape::{Shape, Triangle};
use scene::{Camera, Filter, Material, Primitive, ReferenceMaterial, Scene, cornell};
use spectrum::Rgb;
use testkit::{MeanVar, z_test_entries};

/// Family-wise significance of each Z-test.
const ALPHA: f64 = 1e-3;

fn gaussian(stddev: f32, radius: f32) -> Filter {
    Filter::from_desc(&FilterDesc::Gaussian { stddev, radius }).unwrap()
}

fn tent(radius: f32) -> Filter {
    Filter::from_desc(&FilterDesc::Tent { radius }).unwrap()
}

/// `∫ g` over the square of side `2·half` around `centre`, clipped to the `w × h` image, by the
/// midpoint rule with `n` points per pixel and axis.
fn quadrature(centre: Vec2, half: f32, w: u32, h: u32, n: u32, g: impl Fn(Vec2) -> f64) -> f64 {
    let (x0, x1) = ((centre.x - half).floor().max(0.0), (centre.x + half).ceil().min(w as f32));
    let (y0, y1) = ((centre.y - half).floor().max(0.0), (centre.y + half).ceil().min(h as f32));
    let (nx, ny) = (((x1 - x0) as u32) * n, ((y1 - y0) as u32) * n);
    let step = 1.0 / n as f64;
    let mut sum = 0.0;
    for j in 0..ny {
        for i in 0..nx {
            let p =
                Vec2::new((x0 as f64 + (i as f64 + 0.5) * step) as f32, (y0 as f64 + (j as f64 + 0.5) * step) as f32);
            sum += g(p);
        }
    }
    sum * step * step
}

#[test]
fn splat_weights_integrate_to_one_over_the_image() {
    // A 7 × 5 image: every pixel is within the radius of a border for the wider filters, and
    // the 3-pixel gaussian is clipped on both sides of the short axis.
    for (name, filter) in [
        ("tent r=1.5", tent(1.5)),
        ("gaussian σ=0.5 r=2", gaussian(0.5, 2.0)),
        ("gaussian σ=1 r=3", gaussian(1.0, 3.0)),
    ] {
        let camera =
            Camera::new(Vec3::ZERO, Vec3::Z, Vec3::Y, 60.0, 7, 5).with_filter(filter).with_film(FilmMode::Splat);
        for y in 0..5 {
            for x in 0..7 {
                let centre = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                let integral = quadrature(centre, filter.radius(), 7, 5, 200, |p| camera.splat_weight(p, x, y) as f64);
                // Midpoint rule: O(h²) at the tent's kinks, h = 1/200 pixel.
                assert!((integral - 1.0).abs() < 2e-4, "{name}, pixel ({x}, {y}): ∫ w = {integral}");
            }
        }
    }
}

/// A large plane at distance 1 in front of a 90° pinhole (`w × h` pixels), with `filter` and
/// `film`: with the eye light every raster point `x` sees `d / |(x − centre, d)|`.
fn plane(w: u32, h: u32, filter: Filter, film: FilmMode) -> Scene {
    let corners = [Vec3::new(-10.0, -10.0, 1.0), Vec3::new(10.0, -10.0, 1.0), Vec3::new(10.0, 10.0, 1.0)];
    let fourth = Vec3::new(-10.0, 10.0, 1.0);
    let primitives = vec![
        Primitive::new(Shape::Triangle(Triangle::new(corners[0], corners[2], corners[1])), 0, None),
        Primitive::new(Shape::Triangle(Triangle::new(corners[0], fourth, corners[2])), 0, None),
    ];
    let material: Material = ReferenceMaterial::diffuse(Rgb::splat(0.5)).into();
    let camera = Camera::new(Vec3::ZERO, Vec3::Z, Vec3::Y, 90.0, w, h).with_filter(filter).with_film(film);
    Scene::new("eye-light plane", primitives, vec![material], Vec::new(), camera)
}

/// Per pixel, the mean over `iterations` eye-light iterations (grey channel) and its standard
/// error.
fn eye_light_pixels(scene: &Scene, iterations: u64) -> (Vec<f64>, Vec<f64>) {
    let mut renderer = Renderer::new(scene, &settings("el", 21)).unwrap();
    let mut stats = vec![MeanVar::new(); scene.camera.pixel_count()];
    for _ in 0..iterations {
        assert_eq!(renderer.step(), 0);
        for (s, p) in stats.iter_mut().zip(&renderer.frame().pixels) {
            s.push(p.g as f64);
        }
    }
    (stats.iter().map(MeanVar::mean).collect(), stats.iter().map(MeanVar::std_error).collect())
}

#[test]
fn border_pixels_average_the_filter_truncated_to_the_image() {
    let (w, h) = (24u32, 16u32);
    // Mitsuba's default gaussian and a wider one (larger border effect).
    for (name, filter, iterations) in
        [("gaussian σ=0.5 r=2", gaussian(0.5, 2.0), 1024), ("gaussian σ=1 r=3", gaussian(1.0, 3.0), 1024)]
    {
        let truth_scene = plane(w, h, filter, FilmMode::Splat);
        let camera = truth_scene.camera;
        let d = w as f64 / 2.0;
        let radiance = |p: Vec2| {
            let (dx, dy) = (p.x as f64 - w as f64 / 2.0, p.y as f64 - h as f64 / 2.0);
            d / (dx * dx + dy * dy + d * d).sqrt()
        };
        // The border pixels: within the radius of an edge.
        let r = filter.radius();
        let border: Vec<(u32, u32)> = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .filter(|&(x, y)| {
                let (cx, cy) = (x as f32 + 0.5, y as f32 + 0.5);
                cx < r || cy < r || w as f32 - cx < r || h as f32 - cy < r
            })
            .collect();
        let truth: Vec<f64> = border
            .iter()
            .map(|&(x, y)| {
                let centre = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                quadrature(centre, r, w, h, 64, |p| camera.splat_weight(p, x, y) as f64 * radiance(p))
            })
            .collect();
        let zero = vec![0.0; truth.len()];
        let check = |film: FilmMode| {
            let (means, errors) = eye_light_pixels(&plane(w, h, filter, film), iterations);
            let pick = |v: &[f64]| border.iter().map(|&(x, y)| v[(y * w + x) as usize]).collect::<Vec<f64>>();
            z_test_entries(&pick(&means), &pick(&errors), &truth, &zero, ALPHA)
        };
        let splat = check(FilmMode::Splat);
        let fis = check(FilmMode::Fis);
        eprintln!("{name}: {} border pixels; splat: {splat}; fis: {fis}", border.len());
        assert!(splat.passed, "{name}: splat border pixels differ from the truncated filter: {splat}");
        assert!(!fis.passed, "{name}: no power: FIS (the untruncated filter) passes too: {fis}");
    }
}

/// A 64² Cornell box (ceiling light, glossy floor) with `filter` and `film`.
fn cornell_with(filter: Filter, film: FilmMode, resolution: u32) -> Scene {
    let mut scene = cornell::build(cornell::CEILING_LIGHT | cornell::GLOSSY_FLOOR, resolution, resolution).unwrap();
    scene.camera = scene.camera.with_filter(filter).with_film(film);
    scene
}

/// The entries (3 per block) of the blocks `keep` selects, scaled.
fn entries(estimate: &BlockEstimate, keep: &[bool], scale: f64) -> (Vec<f64>, Vec<f64>) {
    let (mut means, mut errors) = (Vec::new(), Vec::new());
    for (b, _) in keep.iter().enumerate().filter(|(_, k)| **k) {
        means.extend(estimate.means[b * 3..b * 3 + 3].iter().map(|m| m * scale));
        errors.extend(estimate.std_errors[b * 3..b * 3 + 3].iter().map(|e| e * scale));
    }
    (means, errors)
}

#[test]
fn splat_and_fis_agree_away_from_the_borders() {
    const BLOCK: u32 = 8;
    let resolution = 64;
    // The eye light (noise from the raster positions only) must see a 2 % error; the path
    // tracer (the full estimator, much noisier per block) a 5 % one.
    let plans = [("el", 256u64, 1.02), ("pt", 600, 1.05)];
    for (name, filter) in [("tent r=1.5", tent(1.5)), ("gaussian σ=0.5 r=2", gaussian(0.5, 2.0))] {
        for (algorithm, iterations, power_scale) in plans {
            let splat = cornell_with(filter, FilmMode::Splat, resolution);
            let fis = cornell_with(filter, FilmMode::Fis, resolution);
            let splat = block_estimate(&splat, &settings(algorithm, 1), iterations, BLOCK);
            let fis = block_estimate(&fis, &settings(algorithm, 2), iterations, BLOCK);
            // Blocks not touching the image border (6 × 6 of 8 × 8).
            let blocks = resolution / BLOCK;
            let inner = |b: u32| (1..blocks - 1).contains(&b);
            let keep: Vec<bool> = (0..blocks * blocks).map(|b| inner(b % blocks) && inner(b / blocks)).collect();
            let (am, ae) = entries(&splat, &keep, 1.0);
            let (bm, be) = entries(&fis, &keep, 1.0);
            let outcome = z_test_entries(&am, &ae, &bm, &be, ALPHA);
            let (sm, se) = entries(&splat, &keep, power_scale);
            let scaled = z_test_entries(&sm, &se, &bm, &be, ALPHA);
            eprintln!("{name}, {algorithm}: splat vs fis: {outcome}; splat × {power_scale}: {scaled}");
            assert!(outcome.passed, "{name}, {algorithm}: splat and fis disagree: {outcome}");
            assert!(!scaled.passed, "{name}, {algorithm}: no power to see a scale of {power_scale}: {scaled}");
        }
    }
}

/// Blocks in which some raster point within the filter radius of one of the block's pixels
/// sees an emitter (64 random points per pixel).
fn blocks_seeing_emitters(scene: &Scene, block: u32) -> Vec<bool> {
    let camera = &scene.camera;
    let (w, h) = (camera.width, camera.height);
    let blocks_x = w / block;
    let mut seen = vec![false; (blocks_x * (h / block)) as usize];
    let mut rng = Rng::new(77, 0);
    let r = camera.filter.radius() + 0.5;
    for y in 0..h {
        for x in 0..w {
            for _ in 0..64 {
                let raster = Vec2::new(x as f32 + 0.5, y as f32 + 0.5)
                    + Vec2::new((2.0 * rng.uniform() - 1.0) * r, (2.0 * rng.uniform() - 1.0) * r);
                let ray = camera.generate_ray(raster);
                if scene.intersect(&ray).is_some_and(|hit| hit.light.is_some()) {
                    seen[((y / block) * blocks_x + x / block) as usize] = true;
                }
            }
        }
    }
    seen
}

#[test]
fn light_tracing_agrees_with_the_path_tracer_when_splatting() {
    const BLOCK: u32 = 8;
    let scene = cornell_with(gaussian(0.5, 2.0), FilmMode::Splat, 64);
    let keep: Vec<bool> = blocks_seeing_emitters(&scene, BLOCK).iter().map(|e| !e).collect();
    assert!(keep.iter().filter(|k| **k).count() >= 32, "too few blocks without emitters");
    let pt = block_estimate(&scene, &settings("pt", 1), 320, BLOCK);
    let lt = block_estimate(&scene, &settings("lt", 2), 320, BLOCK);
    let (am, ae) = entries(&lt, &keep, 1.0);
    let (bm, be) = entries(&pt, &keep, 1.0);
    let outcome = z_test_entries(&am, &ae, &bm, &be, ALPHA);
    let (sm, se) = entries(&lt, &keep, 1.05);
    let scaled = z_test_entries(&sm, &se, &bm, &be, ALPHA);
    eprintln!("lt vs pt, splat: {outcome}; lt × 1.05: {scaled}");
    assert!(outcome.passed, "light tracing and the path tracer disagree when splatting: {outcome}");
    assert!(!scaled.passed, "no power to see a 5 % error: {scaled}");
}

#[test]
fn a_per_pixel_radius_splats_like_the_global_one_without_merging() {
    // Splatting with a per-pixel radius, a light-tracing splat takes the constants of the pixel
    // containing its raster point; without merging BPT's weights do not depend on the radius,
    // so the image must be the global radius' up to rounding.
    let scene = cornell_with(gaussian(0.5, 2.0), FilmMode::Splat, 32);
    let run = |radius_mode| {
        let s = RenderSettings { budget: Budget::Iterations(2), radius_mode, ..settings("bpt", 5) };
        render(&scene, &s).unwrap().film.mean()
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

fn film_bits(scene: &Scene, settings: &RenderSettings) -> Vec<u64> {
    let film = render(scene, settings).unwrap().film;
    film.sums().iter().flat_map(|s| s.map(f64::to_bits)).collect()
}

#[test]
fn splat_images_do_not_depend_on_the_thread_count() {
    let scene = cornell_with(gaussian(0.5, 2.0), FilmMode::Splat, 24);
    for (algorithm, memory_efficient) in
        [("pt", false), ("el", false), ("lt", false), ("bpt", false), ("ppm", false), ("vcm", false), ("vcm", true)]
    {
        let run = |threads| {
            let s = RenderSettings {
                budget: Budget::Iterations(2),
                threads,
                memory_efficient,
                radius_factor: 0.02,
                ..settings(algorithm, 3)
            };
            film_bits(&scene, &s)
        };
        assert_eq!(run(1), run(2), "{algorithm} (memory-efficient {memory_efficient}): thread count changed the image");
    }
}

#[test]
fn the_box_filter_is_the_same_in_both_modes() {
    for algorithm in ["pt", "bpt", "vcm"] {
        let s = RenderSettings { budget: Budget::Iterations(2), ..settings(algorithm, 4) };
        let fis = film_bits(&cornell_with(Filter::Box, FilmMode::Fis, 24), &s);
        let splat = film_bits(&cornell_with(Filter::Box, FilmMode::Splat, 24), &s);
        assert_eq!(fis, splat, "{algorithm}: the box filter splats differently");
    }
}

#[test]
fn technique_images_and_families_sum_to_the_splatted_frame() {
    let scene = cornell_with(gaussian(0.5, 2.0), FilmMode::Splat, 20);
    let layout = TechniqueLayout::new(3).unwrap();
    for memory_efficient in [false, true] {
        let s = RenderSettings { memory_efficient, radius_factor: 0.02, ..settings("vcm", 6) };
        let mut renderer = Renderer::new(&scene, &s).unwrap();
        let engine = renderer.vcm_engine_mut().unwrap();
        engine.record_families(true);
        engine.record_techniques(Some(layout));
        let mut plain = Renderer::new(&scene, &s).unwrap();
        renderer.step();
        plain.step();
        let engine = renderer.vcm_engine().unwrap();
        let (families, techniques) = (engine.family_frames().unwrap(), engine.technique_frame().unwrap());
        for (pixel, total) in renderer.frame().pixels.iter().enumerate() {
            assert_eq!(total.to_array(), plain.frame().pixels[pixel].to_array(), "recording changed pixel {pixel}");
            let values = &techniques.values[pixel * layout.len()..(pixel + 1) * layout.len()];
            for (parts, what) in [(values, "techniques"), (&families[pixel].0[..], "families")] {
                let sum = parts.iter().fold([0.0f64; 3], |a, v| std::array::from_fn(|c| a[c] + v.to_array()[c] as f64));
                let magnitude: f64 =
                    parts.iter().map(|v| v.to_array().iter().map(|c| c.abs() as f64).sum::<f64>()).sum();
                for c in 0..3 {
                    let error = (sum[c] - total.to_array()[c] as f64).abs();
                    assert!(
                        error <= 1e-5 * (magnitude + 1e-20),
                        "memory-efficient {memory_efficient}, pixel {pixel}: {what} sum to {sum:?}, frame {total:?}"
                    );
                }
            }
        }
    }
}

/// Mean over pixels and channels of the per-pixel variance of the mean after `iterations`.
fn mean_variance(scene: &Scene, algorithm: &str, iterations: u64) -> f64 {
    let s = RenderSettings { budget: Budget::Iterations(iterations), ..settings(algorithm, 9) };
    let film = render(scene, &s).unwrap().film;
    let variance = film.variance_of_mean().expect("the film keeps its variance by default");
    variance.iter().map(|v| v.iter().map(|c| *c as f64).sum::<f64>()).sum::<f64>() / (3.0 * variance.len() as f64)
}

/// The measurement behind docs/film.md's variance table: per-pixel variance at equal sample
/// counts, FIS over splat, on the four built-in scenes (128², 64 iterations) with the path
/// tracer. The box must
/// give exactly 1 (the same image); the other ratios are printed.
#[test]
#[ignore = "slow: measurement for docs/film.md (cargo test -p render --test integration film:: -- --ignored --nocapture)"]
fn measure_variance_splat_against_fis() {
    let filters = [("box", Filter::Box), ("tent r=1.5", tent(1.5)), ("gaussian σ=0.5 r=2", gaussian(0.5, 2.0))];
    for (mask, scene_name) in cornell::BUILTIN_SCENES.map(|s| (s.mask, s.name)) {
        for (name, filter) in filters {
            let scene = |film| {
                let mut scene = cornell::build(mask, 128, 128).unwrap();
                scene.camera = scene.camera.with_filter(filter).with_film(film);
                scene
            };
            let fis = mean_variance(&scene(FilmMode::Fis), "pt", 64);
            let splat = mean_variance(&scene(FilmMode::Splat), "pt", 64);
            eprintln!(
                "{scene_name}, {name}: mean variance fis {fis:.4e}, splat {splat:.4e}, fis/splat {:.3}",
                fis / splat
            );
            if filter.is_box() {
                assert_eq!(fis, splat, "the box filter must give the same image in both modes");
            }
        }
    }
}
