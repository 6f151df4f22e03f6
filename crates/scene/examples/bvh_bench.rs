//! BVH benchmark: builds the tree over a ~1M-triangle noisy tessellated sphere and measures
//! closest-hit and any-hit (shadow) throughput for incoherent random rays, on one thread and on
//! all cores, for `scene::accel::Bvh` (8-wide) and, for comparison, the previous binary
//! traversal (`scene::accel::BinaryBvh`) and the `obvhs` crate's CWBVH. Also counts the work per
//! ray (nodes visited, box tests, primitive tests) and times the 8-wide and binary trees in
//! interleaved rounds on the same rays.
//!
//! Run with `cargo run --release -p scene --features binary-bvh --example bvh_bench [-- STACKS]`
//! (default 500 stacks, i.e. 4·500² = 1M triangles). With `--features binary-bvh,embree` also
//! Embree 3 (`scene::accel::EmbreeAccel`, docs/embree.md): build time, the same rows and an
//! interleaved A/B of our 8-wide tree against Embree.

use math::{Aabb, Ray, Rng, Vec3, Vec3A, warp};
use obvhs::BvhBuildParams;
use obvhs::cwbvh::builder::build_cwbvh;
use obvhs::ray::RayHit;
use rayon::prelude::*;
use scene::accel::{BinaryBvh, Bvh, TraversalCounts};
use std::time::{Duration, Instant};

type Tri = [Vec3A; 3];

/// A named ray query for the interleaved A/B timing: the name and the query, which returns a
/// number for the checksum.
type NamedQuery<'a> = (&'a str, &'a (dyn Fn(&Ray, f32) -> f64 + Sync));

/// Möller–Trumbore, accepting `0 < t < t_max`.
#[inline(always)]
fn intersect(tri: &Tri, origin: Vec3A, direction: Vec3A, t_max: f32) -> Option<f32> {
    let e1 = tri[1] - tri[0];
    let e2 = tri[2] - tri[0];
    let p = direction.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 {
        return None;
    }
    let inv_det = 1.0 / det;
    let s = origin - tri[0];
    let u = s.dot(p) * inv_det;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = direction.dot(q) * inv_det;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = e2.dot(q) * inv_det;
    (t > 0.0 && t < t_max).then_some(t)
}

/// A latitude–longitude sphere of radius ≈ 1 with a smooth radial displacement:
/// `stacks × 2·stacks` quads, two triangles each.
fn noisy_sphere(stacks: usize) -> Vec<Tri> {
    let slices = 2 * stacks;
    let point = |i: usize, j: usize| {
        let theta = std::f32::consts::PI * i as f32 / stacks as f32;
        let phi = 2.0 * std::f32::consts::PI * (j % slices) as f32 / slices as f32;
        let r = 1.0
            + 0.05 * (7.0 * theta).sin() * (5.0 * phi).cos()
            + 0.02 * (23.0 * theta + 3.0 * phi).sin()
            + 0.005 * (91.0 * theta).cos() * (67.0 * phi).sin();
        Vec3A::new(r * theta.sin() * phi.cos(), r * theta.sin() * phi.sin(), r * theta.cos())
    };
    let mut tris = Vec::with_capacity(2 * stacks * slices);
    for i in 0..stacks {
        for j in 0..slices {
            let (a, b, c, d) = (point(i, j), point(i + 1, j), point(i + 1, j + 1), point(i, j + 1));
            tris.push([a, b, c]);
            tris.push([a, c, d]);
        }
    }
    tris
}

fn random_point(rng: &mut Rng) -> Vec3 {
    Vec3::new(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5) * 3.0
}

/// Rays from random points in `[-1.5, 1.5]³` (inside and around the sphere) in random
/// directions, with `t_max = ∞`.
fn closest_rays(n: usize) -> Vec<(Ray, f32)> {
    (0..n)
        .map(|i| {
            let mut rng = Rng::for_stream(7, 0, i as u64);
            let origin = random_point(&mut rng);
            (Ray::new(origin, warp::uniform_sphere(rng.uniform2())), f32::INFINITY)
        })
        .collect()
}

/// Shadow rays between two random points in `[-1.5, 1.5]³`.
fn shadow_rays(n: usize) -> Vec<(Ray, f32)> {
    (0..n)
        .map(|i| {
            let mut rng = Rng::for_stream(7, 1, i as u64);
            let (a, b) = (random_point(&mut rng), random_point(&mut rng));
            let d = b - a;
            let len = d.length().max(1e-6);
            (Ray::new(a, d / len), len * (1.0 - 1e-4))
        })
        .collect()
}

/// On-CPU time of the calling thread (first field of `/proc/thread-self/schedstat`, in ns), so
/// that single-thread numbers are not skewed by other processes sharing the machine.
fn thread_cpu_time() -> Option<Duration> {
    let text = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    Some(Duration::from_nanos(text.split_whitespace().next()?.parse().ok()?))
}

/// Runs `query` over all rays (sequentially or on the rayon pool), best of `REPEATS`; returns
/// Mrays/s by wall-clock time, Mrays/s by the calling thread's CPU time (sequential runs only)
/// and the checksum of the last run.
fn measure(rays: &[(Ray, f32)], parallel: bool, query: impl Fn(&Ray, f32) -> f64 + Sync) -> (f64, f64, f64) {
    const REPEATS: usize = 5;
    let mut best_wall = Duration::MAX;
    let mut best_cpu = Duration::MAX;
    let mut checksum = 0.0;
    for _ in 0..REPEATS {
        let cpu_start = thread_cpu_time();
        let start = Instant::now();
        checksum = if parallel {
            rays.par_chunks(1024).map(|chunk| chunk.iter().map(|(r, t)| query(r, *t)).sum::<f64>()).sum()
        } else {
            rays.iter().map(|(r, t)| query(r, *t)).sum()
        };
        best_wall = best_wall.min(start.elapsed());
        if let (Some(a), Some(b)) = (cpu_start, thread_cpu_time()) {
            best_cpu = best_cpu.min(b.saturating_sub(a));
        }
    }
    let rate = |d: Duration| rays.len() as f64 / d.as_secs_f64() / 1e6;
    (rate(best_wall), if parallel || best_cpu == Duration::MAX { f64::NAN } else { rate(best_cpu) }, checksum)
}

fn time<T>(f: impl FnOnce() -> T) -> (T, f64) {
    let start = Instant::now();
    let value = f();
    (value, start.elapsed().as_secs_f64())
}

fn main() {
    let stacks: usize = std::env::args().nth(1).map(|s| s.parse().expect("STACKS must be a number")).unwrap_or(500);
    let threads = rayon::current_num_threads();
    let tris = noisy_sphere(stacks);
    let bounds: Vec<Aabb> = tris.iter().map(|t| Aabb::from_points(t.iter().map(|p| Vec3::from(*p)))).collect();
    println!("{} triangles, {threads} rayon threads", tris.len());

    // --- Our BVH.
    let (bvh, build_all) = time(|| Bvh::build(&bounds));
    let single_pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().expect("thread pool");
    let (_, build_one) = time(|| single_pool.install(|| Bvh::build(&bounds)));
    let stats = bvh.stats();
    println!(
        "scene::accel::Bvh  build {build_all:.3} s ({threads} threads), {build_one:.3} s (1 thread); \
         binary tree: {} nodes, {} leaves, depth {}, SAH cost {:.1}; 8-wide: {} nodes, depth {}",
        stats.nodes, stats.leaves, stats.max_depth, stats.sah_cost, stats.wide_nodes, stats.wide_max_depth
    );
    let binary = BinaryBvh::build(&bounds);

    let rays = closest_rays(2_000_000);
    let shadows = shadow_rays(2_000_000);
    let ours_closest = |ray: &Ray, t_max: f32| {
        let (o, d) = (Vec3A::from(ray.origin), Vec3A::from(ray.direction));
        bvh.closest_hit(ray, t_max, |p, _, t| intersect(&tris[p as usize], o, d, t)).map_or(0.0, |h| h.1 as f64)
    };
    let ours_any = |ray: &Ray, t_max: f32| {
        let (o, d) = (Vec3A::from(ray.origin), Vec3A::from(ray.direction));
        bvh.any_hit(ray, t_max, |p, _, t| intersect(&tris[p as usize], o, d, t).is_some()) as u32 as f64
    };
    let binary_closest = |ray: &Ray, t_max: f32| {
        let (o, d) = (Vec3A::from(ray.origin), Vec3A::from(ray.direction));
        binary.closest_hit(ray, t_max, |p, _, t| intersect(&tris[p as usize], o, d, t)).map_or(0.0, |h| h.1 as f64)
    };
    let binary_any = |ray: &Ray, t_max: f32| {
        let (o, d) = (Vec3A::from(ray.origin), Vec3A::from(ray.direction));
        binary.any_hit(ray, t_max, |p, _, t| intersect(&tris[p as usize], o, d, t).is_some()) as u32 as f64
    };

    // --- obvhs CWBVH (8-wide, compressed nodes), built from the same boxes.
    let ob_aabbs: Vec<obvhs::aabb::Aabb> =
        bounds.iter().map(|b| obvhs::aabb::Aabb::new(b.min.into(), b.max.into())).collect();
    let (cwbvh, ob_build_all) =
        time(|| build_cwbvh(&ob_aabbs, BvhBuildParams::medium_build(), &mut Duration::default()));
    let (_, ob_build_one) = time(|| {
        single_pool.install(|| build_cwbvh(&ob_aabbs, BvhBuildParams::medium_build(), &mut Duration::default()))
    });
    let (_, ob_fast_build_all) =
        time(|| build_cwbvh(&ob_aabbs, BvhBuildParams::fast_build(), &mut Duration::default()));
    println!(
        "obvhs CwBvh        build {ob_build_all:.3} s ({threads} threads), {ob_build_one:.3} s (1 thread) \
         [medium_build]; fast_build {ob_fast_build_all:.3} s; {} nodes (8-wide)",
        cwbvh.nodes.len()
    );
    // Same indirection as ours: the closure maps the BVH's slot to the original triangle.
    let ob_closest = |ray: &Ray, t_max: f32| {
        let r = obvhs::ray::Ray::new(ray.origin.into(), ray.direction.into(), 0.0, t_max);
        let mut hit = RayHit::none();
        let found = cwbvh.ray_traverse(r, &mut hit, |r, slot| {
            let tri = &tris[cwbvh.primitive_indices[slot] as usize];
            intersect(tri, r.origin, r.direction, r.tmax).unwrap_or(f32::INFINITY)
        });
        if found { hit.t as f64 } else { 0.0 }
    };
    let ob_any = |ray: &Ray, t_max: f32| {
        let r = obvhs::ray::Ray::new(ray.origin.into(), ray.direction.into(), 0.0, t_max);
        let miss = cwbvh.ray_traverse_miss(r, |r, slot| {
            let tri = &tris[cwbvh.primitive_indices[slot] as usize];
            intersect(tri, r.origin, r.direction, r.tmax).unwrap_or(f32::INFINITY)
        });
        (!miss) as u32 as f64
    };

    // Primitive tests per ray (a measure of tree quality independent of timing noise).
    let sample = 200_000;
    let count_tests = |name: &str, rays: &[(Ray, f32)], any: bool| {
        let test =
            |p: u32, r: &Ray, t: f32| intersect(&tris[p as usize], Vec3A::from(r.origin), Vec3A::from(r.direction), t);
        let (mut wide, mut bin) = (TraversalCounts::default(), TraversalCounts::default());
        for (r, t) in &rays[..sample] {
            if any {
                bvh.any_hit_counted(r, *t, |p, r, t| test(p, r, t).is_some(), &mut wide);
                binary.any_hit_counted(r, *t, |p, r, t| test(p, r, t).is_some(), &mut bin);
            } else {
                bvh.closest_hit_counted(r, *t, test, &mut wide);
                binary.closest_hit_counted(r, *t, test, &mut bin);
            }
        }
        let per = |x: u64| x as f64 / sample as f64;
        println!(
            "{name}: per ray, 8-wide: {:.2} nodes, {:.2} box tests; binary: {:.2} nodes, {:.2} box tests",
            per(wide.nodes),
            per(wide.box_tests),
            per(bin.nodes),
            per(bin.box_tests)
        );
        let ours = wide.primitives;
        let tests = std::cell::Cell::new(0u64);
        let ob_test = |r: &obvhs::ray::Ray, slot: usize| {
            tests.set(tests.get() + 1);
            let tri = &tris[cwbvh.primitive_indices[slot] as usize];
            intersect(tri, r.origin, r.direction, r.tmax).unwrap_or(f32::INFINITY)
        };
        for (r, t) in &rays[..sample] {
            let r = obvhs::ray::Ray::new(r.origin.into(), r.direction.into(), 0.0, *t);
            if any {
                cwbvh.ray_traverse_miss(r, ob_test);
            } else {
                cwbvh.ray_traverse(r, &mut RayHit::none(), ob_test);
            }
        }
        let theirs = tests.get();
        println!(
            "{name}: primitive tests per ray: scene::accel 8-wide {:.2}, binary {:.2}, obvhs {:.2}",
            ours as f64 / sample as f64,
            bin.primitives as f64 / sample as f64,
            theirs as f64 / sample as f64
        );
    };
    count_tests("closest hit", &rays, false);
    count_tests("any hit", &shadows, true);

    println!(
        "\nMrays/s ({} rays each, best of 5)   1 thread (wall)  1 thread (cpu)  {threads} threads (wall)  checksum",
        rays.len()
    );
    let report = |name: &str, rays: &[(Ray, f32)], query: &(dyn Fn(&Ray, f32) -> f64 + Sync)| {
        let (one, one_cpu, checksum) = single_pool.install(|| measure(rays, false, query));
        let (all, _, _) = measure(rays, true, query);
        println!("{name:<36} {one:>15.2} {one_cpu:>15.2} {all:>18.2}   {checksum:.6e}");
    };
    report("scene::accel::Bvh closest_hit", &rays, &ours_closest);
    report("scene::accel::BinaryBvh closest_hit", &rays, &binary_closest);
    report("obvhs CwBvh ray_traverse", &rays, &ob_closest);
    report("scene::accel::Bvh any_hit (shadow)", &shadows, &ours_any);
    report("scene::accel::BinaryBvh any_hit", &shadows, &binary_any);
    report("obvhs CwBvh ray_traverse_miss", &shadows, &ob_any);

    // Interleaved A/B on one thread: rounds alternate between the trees on the same rays, so
    // that load from other processes affects both alike.
    let interleaved = |name: &str, rays: &[(Ray, f32)], (a_name, a): NamedQuery, (b_name, b): NamedQuery| {
        const ROUNDS: usize = 6;
        let rays = &rays[..500_000];
        let mut times = [Duration::ZERO; 2];
        for _ in 0..ROUNDS {
            for (time, query) in times.iter_mut().zip([a, b]) {
                let start = thread_cpu_time();
                let checksum: f64 = rays.iter().map(|(r, t)| query(r, *t)).sum();
                std::hint::black_box(checksum);
                *time += thread_cpu_time().zip(start).map_or(Duration::ZERO, |(b, a)| b.saturating_sub(a));
            }
        }
        let rate = |t: Duration| (rays.len() * ROUNDS) as f64 / t.as_secs_f64() / 1e6;
        println!(
            "A/B {name}, 1 thread (cpu), {ROUNDS} interleaved rounds: {a_name} {:.2}, {b_name} {:.2} Mrays/s, time {b_name} / time {a_name} = {:.2}",
            rate(times[0]),
            rate(times[1]),
            times[1].as_secs_f64() / times[0].as_secs_f64()
        );
    };
    single_pool.install(|| {
        interleaved("closest hit", &rays, ("8-wide", &ours_closest), ("binary", &binary_closest));
        interleaved("any hit", &shadows, ("8-wide", &ours_any), ("binary", &binary_any));
    });

    // --- Embree 3, over the same triangles (ids = indices).
    #[cfg(feature = "embree")]
    {
        let verts: Vec<[Vec3; 3]> = tris.iter().map(|t| t.map(Vec3::from)).collect();
        let (embree, embree_build) = time(|| scene::accel::EmbreeAccel::build(&verts).expect("an Embree scene"));
        println!("\nEmbree 3 build {embree_build:.3} s (Embree's own threads)");
        let embree_closest = |ray: &Ray, t_max: f32| embree.closest_hit(ray, t_max).map_or(0.0, |h| h.1 as f64);
        let embree_any = |ray: &Ray, t_max: f32| embree.any_hit(ray, t_max) as u32 as f64;
        report("scene::accel::Bvh closest_hit", &rays, &ours_closest);
        report("Embree closest_hit", &rays, &embree_closest);
        report("scene::accel::Bvh any_hit (shadow)", &shadows, &ours_any);
        report("Embree any_hit (shadow)", &shadows, &embree_any);
        single_pool.install(|| {
            interleaved("closest hit", &rays, ("8-wide", &ours_closest), ("Embree", &embree_closest));
            interleaved("any hit", &shadows, ("8-wide", &ours_any), ("Embree", &embree_any));
        });
    }
}
