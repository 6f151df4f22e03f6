//! `vcm bench --accel`: the acceleration structure on a scene's own geometry — BVH build time
//! and closest-hit / shadow-ray throughput for incoherent rays, on one thread and on all.
//!
//! Rays start at points on the scene's surfaces (found by casting rays from the camera through
//! random raster positions) and go in uniformly random directions; shadow rays go from one such
//! point towards another. The rays are generated before timing starts.
//!
//! Below each row: the work per ray (wide nodes visited, ray–box tests, primitive tests), counted
//! on a tree over the scene's world primitives (instances are not entered). Built with the
//! `binary-bvh` feature (`cargo build --release --features binary-bvh`), the same counts for the
//! previous binary tree and an interleaved A/B timing of both trees on the same rays in this
//! process, one thread (a rough indication on a loaded machine; the counts are exact).
//!
//! On a processor with AVX2 or AVX-512, a last line times the scene's nearest-hit query compiled
//! for that instruction set against the baseline x86-64 copy (`math::isa`), interleaved on one
//! thread.

use std::time::{Duration, Instant};

use math::{Aabb, Isa, RAY_EPSILON, Ray, Rng, Vec2, Vec3, warp};
use rayon::prelude::*;
use scene::Scene;
use scene::accel::{Bvh, TraversalCounts};

/// Rays per measurement.
const RAYS: usize = 1 << 20;

/// Measures and prints one scene's row.
pub fn run(scene: &Scene, threads: usize) {
    let bounds: Vec<Aabb> = scene.primitives.iter().map(|p| p.shape.bounds()).collect();
    let start = Instant::now();
    let bvh = Bvh::build(&bounds);
    let build = start.elapsed();
    let points = surface_points(scene, RAYS);
    if points.len() < 2 {
        println!("{:<28} {:>10} primitives: the camera sees no surface; no rays to time", scene.name, bounds.len());
        return;
    }
    let mut rng = Rng::for_stream(7, 0, 0);
    let closest: Vec<Ray> =
        (0..RAYS).map(|i| Ray::new(points[i % points.len()], warp::uniform_sphere(rng.uniform2()))).collect();
    let shadow: Vec<(Vec3, Vec3, f32)> = (0..RAYS)
        .filter_map(|i| {
            let a = points[i % points.len()];
            let b = points[(i * 7919 + 13) % points.len()];
            let d = b - a;
            let length = d.length();
            (length > 1e-4).then(|| (a, d / length, length))
        })
        .collect();
    let time = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("a thread pool");
        pool.install(|| {
            let start = Instant::now();
            let hits = closest.par_iter().filter(|r| scene.intersect(r).is_some()).count();
            let closest_time = start.elapsed();
            let start = Instant::now();
            let blocked = shadow.par_iter().filter(|(o, d, l)| scene.occluded(*o, *d, *l)).count();
            (closest_time, start.elapsed(), hits, blocked)
        })
    };
    let all = if threads == 0 { rayon::current_num_threads() } else { threads };
    let (c1, s1, hits, blocked) = time(1);
    let (cn, sn, _, _) = time(all);
    let mrays = |n: usize, t: Duration| n as f64 / t.as_secs_f64() / 1e6;
    println!(
        "{:<28} {:>10} {:>9.3} {:>10.2} {:>10.2} {:>10.2} {:>10.2}   {:.0} % hit, {:.0} % blocked, {all} threads",
        scene.name,
        bounds.len(),
        build.as_secs_f64(),
        mrays(closest.len(), c1),
        mrays(closest.len(), cn),
        mrays(shadow.len(), s1),
        mrays(shadow.len(), sn),
        100.0 * hits as f64 / closest.len() as f64,
        100.0 * blocked as f64 / shadow.len().max(1) as f64,
    );
    let rays = Rays { closest: &closest, shadow: &shadow };
    let wide = rays.counts(
        |r, c| bvh.closest_hit_counted(r, f32::INFINITY, |i, r, t| intersect(scene, i, r, t), c).is_some(),
        |r, t, c| bvh.any_hit_counted(r, t, |i, r, t| intersect(scene, i, r, t).is_some(), c),
    );
    let stats = bvh.stats();
    println!(
        "  8-wide BVH: {} nodes ({:.2} children each), depth {}; per ray: {wide}; queries compiled for {}",
        stats.wide_nodes,
        (stats.wide_nodes - 1 + stats.leaves) as f64 / stats.wide_nodes as f64,
        stats.wide_max_depth,
        Isa::active().name()
    );
    isa_comparison(scene, &rays);
    #[cfg(feature = "binary-bvh")]
    binary_comparison(scene, &bounds, &bvh, &rays);
}

/// Rays per round of [`isa_comparison`].
const ISA_RAYS: usize = 1 << 19;

/// An interleaved A/B timing on this thread of the scene's nearest-hit query
/// ([`Scene::intersect_at`]) compiled for the active instruction set ([`Isa::active`]) and for
/// baseline x86-64 (`math::isa`), on the same rays; nothing when the active set is the
/// baseline. Wall time: the thread's CPU time from `schedstat` advanced in 4 ms steps on the
/// machine this was written on, too coarse for rounds of 10–150 ms.
fn isa_comparison(scene: &Scene, rays: &Rays) {
    let wide = Isa::active();
    if wide == Isa::Baseline {
        return;
    }
    const ROUNDS: usize = 6;
    let closest = &rays.closest[..ISA_RAYS.min(rays.closest.len())];
    let mut times = [Duration::ZERO; 2];
    let mut checks = [0usize; 2];
    for _ in 0..ROUNDS {
        for (set, isa) in [wide, Isa::Baseline].into_iter().enumerate() {
            let start = Instant::now();
            checks[set] = closest.iter().filter(|r| scene.intersect_at(r, isa).is_some()).count();
            times[set] += start.elapsed();
        }
    }
    assert_eq!(checks[0], checks[1], "the instruction sets' queries disagree on the number of hits");
    let rate = |t: Duration| (closest.len() * ROUNDS) as f64 / t.as_secs_f64() / 1e6;
    println!(
        "  closest hits compiled for {} against baseline x86-64, A/B on 1 thread (wall time), {ROUNDS} interleaved \
         rounds: {:.2} vs {:.2} Mrays/s = {:.3}x",
        wide.name(),
        rate(times[0]),
        rate(times[1]),
        times[1].as_secs_f64() / times[0].as_secs_f64(),
    );
}

/// Nearest hit on world primitive `i` (what the scene's query does without alpha masks).
#[inline(always)]
fn intersect(scene: &Scene, i: u32, ray: &Ray, t_max: f32) -> Option<f32> {
    scene.primitives[i as usize].shape.intersect(ray, t_max)
}

/// The rays of one scene: closest-hit rays, and shadow rays as (origin, unit direction, length).
struct Rays<'a> {
    closest: &'a [Ray],
    shadow: &'a [(Vec3, Vec3, f32)],
}

impl Rays<'_> {
    /// The shadow ray and its `t_max` as [`Scene::occluded`] forms them.
    fn shadow_ray(&self, i: usize) -> (Ray, f32) {
        let (o, d, l) = self.shadow[i];
        (Ray::new(o + RAY_EPSILON * d, d), l - 2.0 * RAY_EPSILON)
    }

    /// Work per ray of `closest` over the closest-hit rays and of `any` over the shadow rays.
    fn counts(
        &self,
        closest: impl Fn(&Ray, &mut TraversalCounts) -> bool,
        any: impl Fn(&Ray, f32, &mut TraversalCounts) -> bool,
    ) -> String {
        let (mut c, mut s) = (TraversalCounts::default(), TraversalCounts::default());
        let hits = self.closest.iter().filter(|r| closest(r, &mut c)).count();
        let blocked = (0..self.shadow.len())
            .filter(|&i| {
                let (ray, t_max) = self.shadow_ray(i);
                t_max > 0.0 && any(&ray, t_max, &mut s)
            })
            .count();
        let per = |x: u64, n: usize| x as f64 / n.max(1) as f64;
        let (nc, ns) = (self.closest.len(), self.shadow.len());
        format!(
            "closest {:.2} nodes, {:.2} box tests, {:.2} primitive tests ({hits} hits); \
             shadow {:.2} nodes, {:.2} box tests, {:.2} primitive tests ({blocked} blocked)",
            per(c.nodes, nc),
            per(c.box_tests, nc),
            per(c.primitives, nc),
            per(s.nodes, ns),
            per(s.box_tests, ns),
            per(s.primitives, ns)
        )
    }
}

/// On-CPU time of the calling thread (first field of `/proc/thread-self/schedstat`; zero where
/// that file does not exist), so that time the thread waits for a core is not counted.
#[cfg(feature = "binary-bvh")]
fn thread_cpu_time() -> Duration {
    let text = std::fs::read_to_string("/proc/thread-self/schedstat").unwrap_or_default();
    Duration::from_nanos(text.split_whitespace().next().and_then(|t| t.parse().ok()).unwrap_or(0))
}

/// Counts of the previous binary tree, and an interleaved A/B timing of both trees.
#[cfg(feature = "binary-bvh")]
fn binary_comparison(scene: &Scene, bounds: &[Aabb], bvh: &Bvh, rays: &Rays) {
    use scene::accel::BinaryBvh;
    let binary = BinaryBvh::build(bounds);
    let counts = rays.counts(
        |r, c| binary.closest_hit_counted(r, f32::INFINITY, |i, r, t| intersect(scene, i, r, t), c).is_some(),
        |r, t, c| binary.any_hit_counted(r, t, |i, r, t| intersect(scene, i, r, t).is_some(), c),
    );
    println!("  binary BVH, per ray: {counts}");
    // Alternating rounds over the same rays on this thread; the sums of each tree's rounds.
    const ROUNDS: usize = 6;
    let shadow: Vec<(Ray, f32)> = (0..rays.shadow.len()).map(|i| rays.shadow_ray(i)).filter(|r| r.1 > 0.0).collect();
    let mut times = [[Duration::ZERO; 2]; 2];
    let mut checks = [[0usize; 2]; 2];
    for _ in 0..ROUNDS {
        for (tree, (time, check)) in times.iter_mut().zip(checks.iter_mut()).enumerate() {
            let start = thread_cpu_time();
            check[0] = rays
                .closest
                .iter()
                .filter(|r| {
                    let hit = |i, r: &Ray, t| intersect(scene, i, r, t);
                    match tree {
                        0 => bvh.closest_hit(r, f32::INFINITY, hit).is_some(),
                        _ => binary.closest_hit(r, f32::INFINITY, hit).is_some(),
                    }
                })
                .count();
            time[0] += thread_cpu_time() - start;
            let start = thread_cpu_time();
            check[1] = shadow
                .iter()
                .filter(|(r, t_max)| {
                    let hit = |i, r: &Ray, t| intersect(scene, i, r, t).is_some();
                    match tree {
                        0 => bvh.any_hit(r, *t_max, hit),
                        _ => binary.any_hit(r, *t_max, hit),
                    }
                })
                .count();
            time[1] += thread_cpu_time() - start;
        }
    }
    assert_eq!(checks[0], checks[1], "the two trees disagree on the number of hits");
    let rate = |n: usize, t: Duration| (n * ROUNDS) as f64 / t.as_secs_f64() / 1e6;
    println!(
        "  A/B, 1 thread (its CPU time), {ROUNDS} interleaved rounds: closest {:.2} (8-wide) vs {:.2} (binary) Mrays/s = {:.2}x; \
         shadow {:.2} vs {:.2} Mrays/s = {:.2}x",
        rate(rays.closest.len(), times[0][0]),
        rate(rays.closest.len(), times[1][0]),
        times[1][0].as_secs_f64() / times[0][0].as_secs_f64(),
        rate(shadow.len(), times[0][1]),
        rate(shadow.len(), times[1][1]),
        times[1][1].as_secs_f64() / times[0][1].as_secs_f64(),
    );
}

/// The header of [`run`]'s rows.
pub fn header() {
    println!(
        "{:<28} {:>10} {:>9} {:>10} {:>10} {:>10} {:>10}",
        "scene", "primitives", "build s", "closest 1T", "closest nT", "shadow 1T", "shadow nT"
    );
    println!("{:<28} {:>10} {:>9} {:>10} {:>10} {:>10} {:>10}", "", "", "", "Mrays/s", "Mrays/s", "Mrays/s", "Mrays/s");
}

/// Up to `count` points where camera rays through random raster positions hit the scene,
/// offset slightly off the surface along the ray.
fn surface_points(scene: &Scene, count: usize) -> Vec<Vec3> {
    let mut rng = Rng::for_stream(3, 0, 0);
    let (w, h) = (scene.camera.width as f32, scene.camera.height as f32);
    let mut points = Vec::with_capacity(count);
    for _ in 0..count {
        let raster = Vec2::new(rng.uniform() * w, rng.uniform() * h);
        let ray = scene.camera.generate_ray(raster);
        if let Some(hit) = scene.intersect(&ray) {
            points.push(hit.position - ray.direction * 1e-3);
        }
    }
    points
}
