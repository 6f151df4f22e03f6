//! Shared helpers of the render integration tests: per-block estimates with standard errors
//! from independent iterations, and masks of the pixels an algorithm can render.

#![allow(dead_code)]

pub mod comparison;
pub mod medium_sphere;
pub mod mis_media_path;
pub mod mis_surface;
pub mod sphere_room;

use math::{RAY_EPSILON, Ray, Vec2, Vec3};
use render::driver::{Budget, Renderer};
use render::{Algorithm, RenderSettings};
use scene::light::AreaLight;
use scene::shape::{Shape, Triangle};
use scene::{Bsdf, Camera, Light, Material, Primitive, ReferenceMaterial, Scene, TransportMode};
use spectrum::Rgb;
use testkit::{MeanVar, z_test_entries};

/// Block means over iterations, per block and channel (`(block * 3 + channel)`), with their
/// standard errors estimated from the spread of the iterations.
pub struct BlockEstimate {
    /// Blocks per row.
    pub blocks_x: usize,
    /// Mean per block and channel.
    pub means: Vec<f64>,
    /// Standard error per block and channel.
    pub std_errors: Vec<f64>,
    /// Every iteration's block means, iteration-major (`iteration * entries + block * 3 +
    /// channel`), for statistics over several blocks ([`BlockEstimate::pooled`]).
    pub iterations: Vec<f64>,
}

impl BlockEstimate {
    /// Per channel, the mean over the blocks that `keep` selects (equal weights) with its
    /// standard error from the spread of the iterations: the blocks of one iteration are not
    /// independent (they share light paths and wavelengths), the iterations are.
    pub fn pooled(&self, keep: &[bool]) -> ([f64; 3], [f64; 3]) {
        let entries = self.means.len();
        assert_eq!(keep.len() * 3, entries, "one flag per block");
        let kept = keep.iter().filter(|k| **k).count().max(1) as f64;
        let mut stats = [MeanVar::new(); 3];
        for frame in self.iterations.chunks_exact(entries) {
            let mut sums = [0.0f64; 3];
            for (b, _) in keep.iter().enumerate().filter(|(_, k)| **k) {
                for (c, sum) in sums.iter_mut().enumerate() {
                    *sum += frame[b * 3 + c];
                }
            }
            for (s, sum) in stats.iter_mut().zip(sums) {
                s.push(sum / kept);
            }
        }
        (stats.map(|s| s.mean()), stats.map(|s| s.std_error()))
    }
}

/// The smallest relative bias of either sign that the Z-test `z_test_entries(a, b, alpha)`
/// detects in `a`: the smallest `β` for which both `a·(1 + β)` and `a·(1 − β)` (means and
/// standard errors scaled, as a biased estimator's would be) fail the same test (bisection to
/// 1e-4; `∞` when even `β = 1` passes). Each entry's `z` is monotonic in the scale (for
/// positive means), so the set of failing scales is an interval beyond the threshold.
pub fn detectable_bias(a_mean: &[f64], a_se: &[f64], b_mean: &[f64], b_se: &[f64], alpha: f64) -> f64 {
    let fails = |scale: f64| {
        let m: Vec<f64> = a_mean.iter().map(|v| v * scale).collect();
        let e: Vec<f64> = a_se.iter().map(|v| v * scale).collect();
        !z_test_entries(&m, &e, b_mean, b_se, alpha).passed
    };
    let mut worst = 0.0f64;
    for sign in [1.0, -1.0] {
        if !fails(1.0 + sign) {
            return f64::INFINITY;
        }
        let (mut lo, mut hi) = (0.0f64, 1.0f64);
        while hi - lo > 1e-4 {
            let mid = 0.5 * (lo + hi);
            if fails(1.0 + sign * mid) { hi = mid } else { lo = mid }
        }
        worst = worst.max(hi);
    }
    worst
}

/// Renders `iterations` iterations of `algorithm` and returns block statistics.
///
/// The standard errors come from the spread of the iterations, which is the error of their mean
/// only when they are independent: the path tracer therefore draws independent numbers here
/// (`PrimarySamples::Independent`). Its default sequence, whose iterations are negatively
/// correlated, would make the errors too large and the tests blunt; it is tested against the
/// independent numbers with errors over independent renders (`tests/primary_samples.rs`).
pub fn block_estimate(scene: &Scene, settings: &RenderSettings, iterations: u64, block: u32) -> BlockEstimate {
    let settings =
        &RenderSettings { primary_samples: render::primary_samples::PrimarySamples::Independent, ..settings.clone() };
    let mut renderer = Renderer::new(scene, settings).unwrap();
    let (w, h) = (scene.camera.width, scene.camera.height);
    let (bx, by) = ((w / block) as usize, (h / block) as usize);
    let mut stats = vec![MeanVar::new(); bx * by * 3];
    let mut all = Vec::with_capacity(iterations as usize * bx * by * 3);
    // In the pool: each step outside it would wait for a worker to wake (`Renderer::in_pool`).
    renderer.in_pool(|renderer| {
        for _ in 0..iterations {
            assert_eq!(renderer.step(), 0, "no rejected samples");
            let frame = renderer.frame();
            let mut sums = vec![0.0f64; bx * by * 3];
            for y in 0..(by as u32 * block) {
                for x in 0..(bx as u32 * block) {
                    let p = frame.pixels[(y * w + x) as usize];
                    let b = (y / block) as usize * bx + (x / block) as usize;
                    for (c, v) in p.to_array().into_iter().enumerate() {
                        sums[b * 3 + c] += v as f64;
                    }
                }
            }
            let n = (block * block) as f64;
            for (s, sum) in stats.iter_mut().zip(sums) {
                s.push(sum / n);
                all.push(sum / n);
            }
        }
    });
    BlockEstimate {
        blocks_x: bx,
        means: stats.iter().map(MeanVar::mean).collect(),
        std_errors: stats.iter().map(MeanVar::std_error).collect(),
        iterations: all,
    }
}

/// Settings for `algorithm` with `seed`, all cores.
pub fn settings(algorithm: &str, seed: u64) -> RenderSettings {
    RenderSettings {
        algorithm: Algorithm::from_name(algorithm).unwrap(),
        budget: Budget::Iterations(1),
        seed,
        ..RenderSettings::default()
    }
}

/// The built-in box with the environment (mask 456) lit by an image environment instead of the
/// constant one: a 16 × 8 map with a bright patch, a gradient and dark rows.
pub fn image_environment_box() -> Scene {
    let base = scene::cornell::build(456, 32, 32).unwrap();
    assert!(base.lights.len() == 1 && base.lights[0].is_environment());
    let (w, h) = (16u32, 8u32);
    let pixels = (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            match (x, y) {
                (5..=7, 2..=3) => spectrum::Rgb::new(30.0, 24.0, 12.0),
                (_, 6..) => spectrum::Rgb::splat(0.05),
                _ => spectrum::Rgb::new(0.3 + 0.1 * x as f32, 0.6, 1.0 - 0.05 * x as f32),
            }
        })
        .collect();
    let image = std::sync::Arc::new(scene::desc::TextureImage { width: w, height: h, pixels });
    let rotation = [math::Vec3::X, math::Vec3::Z, -math::Vec3::Y];
    let env = Light::from_desc(&scene::desc::LightDesc::EnvMap { image, scale: 1.0, to_world: rotation }).unwrap();
    let scene = Scene::new("env-map box", base.primitives.clone(), base.materials.clone(), vec![env], base.camera);
    assert!(matches!(&scene.lights[0], Light::EnvMap(map) if map.has_compensated_density()));
    scene
}

/// What the primary rays of a block see.
#[derive(Clone, Copy, Debug)]
pub struct BlockView {
    /// Some ray hits a purely specular surface.
    pub specular: bool,
    /// Some ray hits an emitter or escapes the scene.
    pub emitter_or_background: bool,
    /// The smallest distance from a point some ray hits to another surface that is not in
    /// the same plane: within it, a merging kernel of that radius reaches across an edge.
    pub clearance: f32,
}

impl Default for BlockView {
    fn default() -> Self {
        Self { specular: false, emitter_or_background: false, clearance: f32::INFINITY }
    }
}

/// Distance from `p` to the closest point of triangle `t` (Ericson, Real-Time Collision
/// Detection §5.1.5, by Voronoi regions).
fn distance_to_triangle(p: Vec3, t: &Triangle) -> f32 {
    let (a, b, c) = (t.p0, t.p1, t.p2);
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return (p - a).length();
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return (p - b).length();
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return (p - (a + ab * (d1 / (d1 - d3)))).length();
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return (p - c).length();
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return (p - (a + ac * (d2 / (d2 - d6)))).length();
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return (p - (b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6))))).length();
    }
    let denominator = 1.0 / (va + vb + vc);
    (p - (a + ab * (vb * denominator) + ac * (vc * denominator))).length()
}

/// Distance from `p` (on primitive `own`) to the nearest other primitive not in its plane,
/// leaving out index-matched (null) boundaries of media: no photon is stored on them.
fn clearance(scene: &Scene, p: Vec3, own: usize) -> f32 {
    let own_shape = scene.primitives[own].shape;
    scene
        .primitives
        .iter()
        .enumerate()
        .filter(|(i, other)| *i != own && !scene.media.is_null(other.material))
        .map(|(_, other)| match (other.shape, own_shape) {
            (Shape::Triangle(t), Shape::Triangle(o))
                if t.normal.dot(o.normal) > 0.9999 && (t.p0 - o.p0).dot(o.normal).abs() < 1e-5 =>
            {
                f32::INFINITY
            }
            (Shape::Triangle(t), _) => distance_to_triangle(p, &t),
            (Shape::Sphere(s), _) => ((p - s.center).length() - s.radius).abs(),
            // The distance to the disc's plane: a lower bound, so the clearance stays conservative.
            (Shape::Disk(d), _) => (p - d.center).dot(d.normal).abs(),
        })
        .fold(f32::INFINITY, f32::min)
}

/// Classifies every block by shooting a grid of primary rays through each of its pixels.
pub fn block_views(scene: &Scene, block: u32) -> Vec<BlockView> {
    let (w, h) = (scene.camera.width, scene.camera.height);
    let (bx, by) = (w / block, h / block);
    let mut views = vec![BlockView::default(); (bx * by) as usize];
    for y in 0..by * block {
        for x in 0..bx * block {
            let view = &mut views[((y / block) * bx + x / block) as usize];
            for sy in 0..4 {
                for sx in 0..4 {
                    let raster = Vec2::new(x as f32 + (sx as f32 + 0.5) / 4.0, y as f32 + (sy as f32 + 0.5) / 4.0);
                    let mut ray = scene.camera.generate_ray(raster);
                    // Index-matched (null) boundaries of media are no surfaces to look at: the
                    // block sees what lies behind them.
                    let mut found = scene.intersect(&ray);
                    while let Some(hit) = found.as_ref().filter(|h| scene.media.is_null(h.material)) {
                        ray = Ray::new(hit.position + RAY_EPSILON * ray.direction, ray.direction);
                        found = scene.intersect(&ray);
                    }
                    match found {
                        None => view.emitter_or_background = true,
                        Some(hit) => {
                            if hit.light.is_some() {
                                view.emitter_or_background = true;
                            }
                            view.clearance = view.clearance.min(clearance(scene, hit.position, hit.primitive as usize));
                            let bsdf = Bsdf::new(
                                scene.material(&hit),
                                &hit.shading_point(),
                                -ray.direction,
                                TransportMode::Radiance,
                            );
                            if bsdf.is_some_and(|b| b.is_delta()) {
                                view.specular = true;
                            }
                        }
                    }
                }
            }
        }
    }
    views
}

/// Keeps the entries (3 per block) of the blocks for which `keep` holds.
pub fn select(
    estimate: &BlockEstimate,
    views: &[BlockView],
    keep: impl Fn(&BlockView) -> bool,
) -> (Vec<f64>, Vec<f64>) {
    let mut means = Vec::new();
    let mut errors = Vec::new();
    for (b, view) in views.iter().enumerate() {
        if keep(view) {
            means.extend_from_slice(&estimate.means[b * 3..b * 3 + 3]);
            errors.extend_from_slice(&estimate.std_errors[b * 3..b * 3 + 3]);
        }
    }
    (means, errors)
}

/// A closed cube `[-1, 1]³` whose inner faces all emit `emission` and reflect diffusely with
/// `albedo`, seen from inside by a `resolution²` camera.
pub fn furnace(emission: f32, albedo: f32, resolution: u32) -> Scene {
    furnace_with(emission, ReferenceMaterial::diffuse(Rgb::splat(albedo)).into(), resolution)
}

/// The furnace cube with every face made of `material`.
pub fn furnace_with(emission: f32, material: Material, resolution: u32) -> Scene {
    let c = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    let corners = [
        c(-1., -1., -1.),
        c(1., -1., -1.),
        c(1., 1., -1.),
        c(-1., 1., -1.),
        c(-1., -1., 1.),
        c(1., -1., 1.),
        c(1., 1., 1.),
        c(-1., 1., 1.),
    ];
    // Faces as corner quadruples, wound so that normals point into the cube.
    let faces = [[0, 1, 2, 3], [4, 7, 6, 5], [0, 4, 5, 1], [3, 2, 6, 7], [0, 3, 7, 4], [1, 5, 6, 2]];
    let mut primitives = Vec::new();
    let mut lights = Vec::new();
    for f in faces {
        for tri in [[f[0], f[1], f[2]], [f[0], f[2], f[3]]] {
            let t = Triangle::new(corners[tri[0]], corners[tri[1]], corners[tri[2]]);
            assert!(t.normal.dot(-t.p0) > 0.0, "normals point inwards");
            primitives.push(Primitive::new(Shape::Triangle(t), 0, Some(lights.len() as u32)));
            lights.push(Light::Area(AreaLight::new(t, Rgb::splat(emission))));
        }
    }
    let camera = Camera::new(c(0.2, -0.3, 0.1), c(0.3, 1.0, 0.2), Vec3::Z, 90.0, resolution, resolution);
    Scene::new("furnace", primitives, vec![material], lights, camera)
}
