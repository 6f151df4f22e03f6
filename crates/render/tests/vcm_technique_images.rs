//! Per-(s, t) technique images of the VCM engine: they sum to the frame, recording does not
//! change the frame, each contribution lands in the image its path length and sub-path vertex
//! counts say (checked against the scene's geometry and the render's maximum path length), and
//! algorithms without a technique leave its images empty.

use math::Vec2;
use render::driver::{Budget, Renderer};
use render::vcm::Family;
use render::vcm::technique_images::{TechniqueFrame, TechniqueImage, TechniqueLayout};
use render::{Algorithm, RenderSettings};
use scene::{Scene, cornell};
use spectrum::Rgb;

fn settings(algorithm: &str, max_length: u32, memory_efficient: bool, threads: usize) -> RenderSettings {
    RenderSettings {
        algorithm: Algorithm::from_name(algorithm).unwrap(),
        budget: Budget::Iterations(3),
        max_length,
        seed: 11,
        threads,
        // A large radius, so that merges happen often at this resolution.
        radius_factor: 0.02,
        memory_efficient,
        ..RenderSettings::default()
    }
}

/// Per iteration: the frame, the family values and the technique values of a recorded render,
/// and the frame of the same render without recording.
struct Recorded {
    frames: Vec<Vec<Rgb>>,
    families: Vec<Vec<[Rgb; 5]>>,
    techniques: Vec<TechniqueFrame>,
    plain_frames: Vec<Vec<Rgb>>,
}

fn record(scene: &Scene, settings: &RenderSettings, layout: TechniqueLayout, iterations: usize) -> Recorded {
    let mut recorded = Renderer::new(scene, settings).unwrap();
    let engine = recorded.vcm_engine_mut().unwrap();
    engine.record_families(true);
    engine.record_techniques(Some(layout));
    let mut plain = Renderer::new(scene, settings).unwrap();
    let mut out = Recorded { frames: vec![], families: vec![], techniques: vec![], plain_frames: vec![] };
    for _ in 0..iterations {
        recorded.step();
        plain.step();
        out.frames.push(recorded.frame().pixels.clone());
        out.plain_frames.push(plain.frame().pixels.clone());
        let engine = recorded.vcm_engine().unwrap();
        out.families.push(engine.family_frames().unwrap().iter().map(|v| v.0).collect());
        out.techniques.push(engine.technique_frame().unwrap().clone());
    }
    out
}

/// Asserts `parts` sum to `total` per channel within f32 rounding of the sum of their
/// magnitudes (a few ulps per addition).
fn assert_sums_to(parts: impl Iterator<Item = Rgb>, total: Rgb, what: &str) {
    let (mut sum, mut magnitude) = ([0.0f64; 3], [0.0f64; 3]);
    let mut count = 0;
    for part in parts {
        for c in 0..3 {
            let v = f64::from(part.to_array()[c]);
            sum[c] += v;
            magnitude[c] += v.abs();
        }
        count += 1;
    }
    for c in 0..3 {
        let t = f64::from(total.to_array()[c]);
        let tolerance = 4.0 * f64::from(f32::EPSILON) * (count as f64 + 2.0) * (magnitude[c] + t.abs()) + 1e-30;
        assert!((sum[c] - t).abs() <= tolerance, "{what}: channel {c} sums to {} vs {t} (±{tolerance:e})", sum[c]);
    }
}

fn is_black(v: Rgb) -> bool {
    v == Rgb::BLACK
}

#[test]
fn technique_images_sum_to_the_frame_and_to_the_families() {
    // Ceiling area light, mirror and glossy floor; point light, small mirror and glass.
    for (mask, memory_efficient) in [(273, false), (452, false), (273, true)] {
        let scene = cornell::build(mask, 36, 32).unwrap();
        // Length 3 of 10: the longer buckets are in use too.
        let layout = TechniqueLayout::new(3).unwrap();
        let images = layout.images();
        let r = record(&scene, &settings("vcm", 10, memory_efficient, 2), layout, 2);
        let mut used = vec![false; layout.len()];
        for i in 0..r.frames.len() {
            assert!(
                r.frames[i]
                    .iter()
                    .zip(&r.plain_frames[i])
                    .all(|(a, b)| a.to_array().map(f32::to_bits) == b.to_array().map(f32::to_bits)),
                "scene {mask}: recording changed the frame"
            );
            for (pixel, total) in r.frames[i].iter().enumerate() {
                let values = &r.techniques[i].values[pixel * layout.len()..(pixel + 1) * layout.len()];
                let what = format!("scene {mask} (memory-efficient {memory_efficient}) pixel {pixel}");
                assert_sums_to(values.iter().copied(), *total, &what);
                for family in Family::ALL {
                    let parts = images.iter().zip(values).filter(|(image, _)| image.family() == family);
                    let family_value = r.families[i][pixel][family as usize];
                    assert_sums_to(parts.map(|(_, v)| *v), family_value, &format!("{what} {}", family.name()));
                }
                for (u, v) in used.iter_mut().zip(values) {
                    *u |= !is_black(*v);
                }
            }
        }
        // Not vacuous: every family has a short technique and its longer bucket in use.
        for (image, used) in images.iter().zip(&used) {
            let expected = match image {
                TechniqueImage::Path { s: 0, t: 2 } => true,
                TechniqueImage::Path { s, t } => s + t - 1 == 2,
                TechniqueImage::Merge { s, t } => s + t - 2 == 2,
                TechniqueImage::Longer(_) => true,
            };
            // Only the scene with an area light has emitter hits (the point light has none).
            let area_light = mask & 1 != 0;
            if expected && (area_light || image.family() != Family::EmitterHit) {
                assert!(used, "scene {mask}: {} is all zero", image.name());
            }
        }
    }
}

#[test]
fn images_have_exactly_the_techniques_of_the_maximum_path_length() {
    // Ceiling area light, diffuse box: every technique of every length exists, none longer
    // than the render's maximum path length (in segments) may appear.
    let scene = cornell::build(1, 32, 32).unwrap();
    let layout = TechniqueLayout::new(4).unwrap();
    for max_length in [2, 3] {
        let r = record(&scene, &settings("vcm", max_length, false, 2), layout, 3);
        for (index, image) in layout.images().iter().enumerate() {
            let length = match *image {
                TechniqueImage::Path { s, t } => s + t - 1,
                TechniqueImage::Merge { s, t } => s + t - 2,
                TechniqueImage::Longer(_) => 5,
            };
            let used =
                r.techniques.iter().any(|f| f.values.iter().skip(index).step_by(layout.len()).any(|v| !is_black(*v)));
            assert_eq!(used, length <= max_length, "max length {max_length}: {} (length {length})", image.name());
        }
    }
}

/// Whether every point of a `grid × grid` lattice over pixel `(x, y)` (corners included) sees an
/// emitter (`Some(true)`), none does (`Some(false)`), or some do (`None`).
fn pixel_sees_emitter(scene: &Scene, x: u32, y: u32, grid: u32) -> Option<bool> {
    let (mut hits, mut total) = (0, 0);
    for i in 0..=grid {
        for j in 0..=grid {
            let raster = Vec2::new(x as f32 + i as f32 / grid as f32, y as f32 + j as f32 / grid as f32);
            let ray = scene.camera.generate_ray(raster);
            hits += scene.intersect(&ray).is_some_and(|h| h.light.is_some()) as u32;
            total += 1;
        }
    }
    match hits {
        0 => Some(false),
        h if h == total => Some(true),
        _ => None,
    }
}

#[test]
fn the_visible_light_is_only_in_s0_t2() {
    // The ceiling light of the reference Cornell box is black and ends every path: pixels that
    // see only the light get nothing but the s = 0, t = 2 emitter hit; pixels that do not see
    // it at all get nothing in s0-t2. Which pixels see it comes from the scene geometry.
    // (The light is a thin strip in the image: 96 × 96 for a few dozen pixels that see only it.)
    let size = 96;
    let scene = cornell::build(1, size, size).unwrap();
    let layout = TechniqueLayout::new(4).unwrap();
    let direct = layout.index(Family::EmitterHit, 0, 2);
    for algorithm in ["vcm", "bpt"] {
        let r = record(&scene, &settings(algorithm, 10, false, 2), layout, 2);
        let (mut light_pixels, mut dark_pixels) = (0, 0);
        for y in 0..size {
            for x in 0..size {
                let pixel = (y * size + x) as usize;
                let Some(sees) = pixel_sees_emitter(&scene, x, y, 6) else { continue };
                for (frame, techniques) in r.frames.iter().zip(&r.techniques) {
                    let values = &techniques.values[pixel * layout.len()..(pixel + 1) * layout.len()];
                    if sees {
                        assert!(!is_black(frame[pixel]), "{algorithm}: light pixel ({x}, {y}) is black");
                        assert_eq!(values[direct], frame[pixel], "{algorithm}: pixel ({x}, {y})");
                        for (i, v) in values.iter().enumerate() {
                            assert!(i == direct || is_black(*v), "{algorithm}: ({x}, {y}) in image {i}");
                        }
                    } else {
                        assert!(is_black(values[direct]), "{algorithm}: pixel ({x}, {y}) sees no light");
                    }
                }
                if sees {
                    light_pixels += 1;
                } else {
                    dark_pixels += 1;
                }
            }
        }
        assert!(light_pixels >= 20 && dark_pixels >= 8000, "{light_pixels} light and {dark_pixels} dark pixels");
    }
}

#[test]
fn algorithms_leave_the_images_of_their_missing_techniques_empty() {
    let scene = cornell::build(273, 32, 32).unwrap();
    let layout = TechniqueLayout::new(4).unwrap();
    for algorithm in ["bpt", "lt", "ppm", "bpm"] {
        let r = record(&scene, &settings(algorithm, 10, false, 2), layout, 2);
        let mut used = vec![false; layout.len()];
        for frame in &r.techniques {
            for values in frame.values.chunks_exact(layout.len()) {
                for (u, v) in used.iter_mut().zip(values) {
                    *u |= !is_black(*v);
                }
            }
        }
        for (image, used) in layout.images().iter().zip(used) {
            let allowed = match algorithm {
                "bpt" => image.family() != Family::Merging,
                // Light tracing, and emitters seen directly, which lt connects as s = 1, t = 1
                // and files under the one image of length 1 (named after s = 0, t = 2).
                "lt" => image.family() == Family::LightTracing || matches!(image, TechniqueImage::Path { s: 0, t: 2 }),
                // Merging, and emitters seen directly or through purely specular paths.
                _ => matches!(image.family(), Family::Merging | Family::EmitterHit),
            };
            assert!(allowed || !used, "{algorithm}: {} is not empty", image.name());
            // The family the algorithm is built on does contribute.
            if matches!((algorithm, *image), ("bpt", TechniqueImage::Path { s: 1, t: 2 }))
                || matches!((algorithm, *image), ("lt", TechniqueImage::Path { s: 2, t: 1 }))
                || matches!((algorithm, *image), ("lt", TechniqueImage::Path { s: 0, t: 2 }))
                || matches!((algorithm, *image), ("ppm" | "bpm", TechniqueImage::Merge { s: 2, t: 2 }))
            {
                assert!(used, "{algorithm}: {} is all zero", image.name());
            }
        }
    }
}

#[test]
fn technique_images_do_not_depend_on_the_thread_count() {
    let scene = cornell::build(452, 40, 36).unwrap();
    let layout = TechniqueLayout::new(3).unwrap();
    for memory_efficient in [false, true] {
        let one = record(&scene, &settings("vcm", 10, memory_efficient, 1), layout, 1);
        let two = record(&scene, &settings("vcm", 10, memory_efficient, 2), layout, 1);
        let bits = |f: &TechniqueFrame| f.values.iter().map(|v| v.to_array().map(f32::to_bits)).collect::<Vec<_>>();
        assert!(bits(&one.techniques[0]) == bits(&two.techniques[0]), "memory-efficient {memory_efficient}");
    }
}
