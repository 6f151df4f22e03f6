//! Hash grid benchmark: builds `render::hash_grid::HashGrid` over 1,000,000 points clustered on
//! five faces of a box of edge 2.5 (like the light vertices of a Cornell-box-like scene) with the
//! merge radius 0.0066, on one and two threads, then measures the throughput of 262,144 random
//! radius queries on the same faces.
//!
//! Run with `cargo run --release -p render --example hash_grid_bench [-- POINTS]`.

use math::{Rng, Vec3};
use rayon::prelude::*;
use render::hash_grid::HashGrid;
use std::time::{Duration, Instant};

const HALF: f32 = 1.25;
const RADIUS: f32 = 0.0066;
const QUERIES: usize = 262_144;

/// A point on one of five faces of `[-1.25, 1.25]³` (no front face). A fifth of the points
/// gather in blobs (as under a light, or in a corner), the rest are uniform.
fn surface_point(seed: u64, index: usize) -> Vec3 {
    let mut rng = Rng::for_stream(seed, 0, index as u64);
    let [u, v, w] = rng.uniform3();
    let (mut a, mut b) = (2.0 * u - 1.0, 2.0 * v - 1.0);
    let face = (rng.next_u32() % 5) as usize;
    if w < 0.2 {
        // Blob of half-width 0.3 (in face units), denser in its middle.
        let t = rng.uniform().sqrt();
        let (centre_a, centre_b) = if w < 0.1 { (0.1, -0.2) } else { (0.7, 0.7) };
        a = centre_a + (a * t * 0.3);
        b = centre_b + (b * t * 0.3);
    }
    let (a, b) = (a.clamp(-1.0, 1.0) * HALF, b.clamp(-1.0, 1.0) * HALF);
    match face {
        0 => Vec3::new(a, -HALF, b), // floor
        1 => Vec3::new(a, HALF, b),  // ceiling
        2 => Vec3::new(a, b, -HALF), // back wall
        3 => Vec3::new(-HALF, a, b), // left wall
        _ => Vec3::new(HALF, a, b),  // right wall
    }
}

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("thread pool")
}

fn median(mut times: Vec<Duration>) -> Duration {
    times.sort();
    times[times.len() / 2]
}

fn main() {
    let points: usize = std::env::args().nth(1).map_or(1_000_000, |s| s.parse().expect("POINTS: a number"));
    let positions: Vec<Vec3> = (0..points).into_par_iter().map(|i| surface_point(1, i)).collect();
    let queries: Vec<Vec3> = (0..QUERIES).into_par_iter().map(|i| surface_point(2, i)).collect();
    println!("{points} points, radius {RADIUS}, {QUERIES} queries, {} cores", rayon::current_num_threads());

    let mut grid = HashGrid::new();
    for threads in [1, 2] {
        let pool = pool(threads);
        let times: Vec<Duration> = (0..7)
            .map(|_| {
                pool.install(|| {
                    let start = Instant::now();
                    grid.build(&positions, RADIUS);
                    start.elapsed()
                })
            })
            .collect();
        println!(
            "build, {threads} thread(s): median {:.2} ms (min {:.2} ms)",
            median(times.clone()).as_secs_f64() * 1e3,
            times.iter().min().expect("times").as_secs_f64() * 1e3
        );
    }
    println!("{} points indexed, {:.1} MB", grid.len(), grid.memory_bytes() as f64 / 1e6);

    for threads in [1, 2] {
        let pool = pool(threads);
        let mut best = Duration::MAX;
        let mut found = 0usize;
        for _ in 0..3 {
            let (elapsed, count) = pool.install(|| {
                let start = Instant::now();
                let count: usize = queries
                    .par_chunks(4096)
                    .map(|chunk| {
                        let mut count = 0usize;
                        for &q in chunk {
                            grid.for_each_in_radius(q, |i| {
                                count += 1;
                                std::hint::black_box(i);
                            });
                        }
                        count
                    })
                    .sum();
                (start.elapsed(), count)
            });
            best = best.min(elapsed);
            found = count;
        }
        println!(
            "queries, {threads} thread(s): {:.2} M queries/s ({:.1} ns/query), {:.2} points found per query",
            QUERIES as f64 / best.as_secs_f64() / 1e6,
            best.as_secs_f64() * 1e9 / QUERIES as f64,
            found as f64 / QUERIES as f64
        );
    }
}
