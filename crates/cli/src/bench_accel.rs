//! `vcm bench --accel`: the acceleration structure on a scene's own geometry — BVH build time
//! and closest-hit / shadow-ray throughput for incoherent rays, on one thread and on all.
//!
//! Rays start at points on the scene's surfaces (found by casting rays from the camera through
//! random raster positions) and go in uniformly random directions; shadow rays go from one such
//! point towards another. The rays are generated before timing starts.

use std::time::{Duration, Instant};

use math::{Aabb, Ray, Rng, Vec2, Vec3, warp};
use rayon::prelude::*;
use scene::Scene;
use scene::accel::Bvh;

/// Rays per measurement.
const RAYS: usize = 1 << 20;

/// Measures and prints one scene's row.
pub fn run(scene: &Scene, threads: usize) {
    let bounds: Vec<Aabb> = scene.primitives.iter().map(|p| p.shape.bounds()).collect();
    let start = Instant::now();
    let bvh = Bvh::build(&bounds);
    let build = start.elapsed();
    drop(bvh);
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
