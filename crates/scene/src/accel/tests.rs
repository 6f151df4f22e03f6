//! Tests of the BVH: queries against brute force (exact primitive and distance, with the tie
//! rule), degenerate inputs, determinism of the build, the structure of the collapse, and the
//! A/B agreement with the previous binary traversal.

use super::binary_traverse::BinaryBvh;
use super::build::{MAX_LEAF_SIZE, PARALLEL_BINNING_THRESHOLD, PARALLEL_THRESHOLD};
use super::wide::{INTERIOR, WIDTH};
use super::*;
use crate::shape::{Sphere, Triangle};
use math::{Rng, Vec3};

pub(super) type Tri = [Vec3; 3];

/// Möller–Trumbore, accepting `0 < t < t_max`.
pub(super) fn intersect_triangle(tri: &Tri, ray: &Ray, t_max: f32) -> Option<f32> {
    Triangle::new(tri[0], tri[1], tri[2]).intersect(ray, t_max)
}

pub(super) fn triangle_bounds(tris: &[Tri]) -> Vec<Aabb> {
    tris.iter().map(|t| Aabb::from_points(t.iter().copied())).collect()
}

/// The reference: every primitive in id order, a later one only when strictly nearer, so of
/// equally near hits the smallest id wins (the tie rule the BVH promises).
pub(super) fn brute_closest(
    n: usize,
    ray: &Ray,
    t_max: f32,
    hit: impl Fn(usize, &Ray, f32) -> Option<f32>,
) -> Option<(u32, f32)> {
    let mut best = None;
    let mut t_best = t_max;
    for i in 0..n {
        if let Some(t) = hit(i, ray, t_best) {
            t_best = t;
            best = Some((i as u32, t));
        }
    }
    best
}

/// Rays for which the BVH's nearest hit (primitive and bit pattern of `t`) or its any-hit answer
/// differs from brute force, and the number of rays that hit something.
pub(super) fn mismatches(
    bvh: &Bvh,
    n: usize,
    rays: &[(Ray, f32)],
    hit: impl Fn(usize, &Ray, f32) -> Option<f32> + Copy,
) -> (Vec<String>, usize) {
    let mut wrong = Vec::new();
    let mut hits = 0;
    for (ray, t_max) in rays {
        let expected = brute_closest(n, ray, *t_max, hit);
        let got = bvh.closest_hit(ray, *t_max, |p, r, t| hit(p as usize, r, t));
        let same = match (expected, got) {
            (None, None) => true,
            (Some((pe, te)), Some((pg, tg))) => pe == pg && te.to_bits() == tg.to_bits(),
            _ => false,
        };
        if !same {
            wrong.push(format!("closest hit of {ray:?}, t_max {t_max}: expected {expected:?}, got {got:?}"));
        }
        hits += expected.is_some() as usize;
        let expected_any = (0..n).any(|i| hit(i, ray, *t_max).is_some());
        let got_any = bvh.any_hit(ray, *t_max, |p, r, t| hit(p as usize, r, t).is_some());
        if expected_any != got_any {
            wrong.push(format!("any hit of {ray:?}, t_max {t_max}: expected {expected_any}, got {got_any}"));
        }
    }
    (wrong, hits)
}

/// Asserts that the BVH over `tris` agrees exactly with brute force; returns the hit count.
fn check(tris: &[Tri], bvh: &Bvh, rays: &[(Ray, f32)]) -> usize {
    let (wrong, hits) = mismatches(bvh, tris.len(), rays, |i, r, t| intersect_triangle(&tris[i], r, t));
    assert!(wrong.is_empty(), "{} of {} rays differ, first: {}", wrong.len(), rays.len(), wrong[0]);
    hits
}

pub(super) fn random_vec(rng: &mut Rng, scale: f32) -> Vec3 {
    Vec3::new(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5) * scale
}

pub(super) fn random_direction(rng: &mut Rng) -> Vec3 {
    loop {
        let v = random_vec(rng, 2.0);
        if v.length_squared() > 1e-4 && v.length_squared() <= 1.0 {
            return v.normalize();
        }
    }
}

pub(super) fn random_soup(rng: &mut Rng, n: usize, size: f32) -> Vec<Tri> {
    (0..n)
        .map(|_| {
            let c = random_vec(rng, 10.0);
            [c + random_vec(rng, size), c + random_vec(rng, size), c + random_vec(rng, size)]
        })
        .collect()
}

pub(super) fn random_rays(rng: &mut Rng, n: usize) -> Vec<(Ray, f32)> {
    (0..n)
        .map(|i| {
            let t_max = if i % 3 == 0 { f32::INFINITY } else { rng.uniform() * 15.0 };
            (Ray::new(random_vec(rng, 14.0), random_direction(rng)), t_max)
        })
        .collect()
}

#[test]
fn accel_matches_brute_force_on_random_soups() {
    let mut rng = Rng::for_stream(1, 0, 0);
    for (n, size) in [(2, 3.0), (7, 2.0), (100, 1.5), (1000, 1.0), (5000, 0.5)] {
        let tris = random_soup(&mut rng, n, size);
        let bvh = Bvh::build(&triangle_bounds(&tris));
        let stats = bvh.stats();
        assert_eq!(stats.primitives, n);
        assert!(stats.max_leaf_size <= MAX_LEAF_SIZE);
        assert_eq!(stats.nodes, 2 * stats.leaves - 1);
        let rays = random_rays(&mut rng, 2000);
        let hits = check(&tris, &bvh, &rays);
        assert!(hits >= if n < 100 { 1 } else { 50 }, "too few hits ({hits}) to be a meaningful test");
    }
}

/// Analytic spheres (whose boxes are loose, and which rays starting inside hit from within).
#[test]
fn accel_matches_brute_force_on_random_spheres() {
    let mut rng = Rng::for_stream(5, 0, 0);
    for n in [1, 5, 300, 3000] {
        let spheres: Vec<Sphere> =
            (0..n).map(|_| Sphere { center: random_vec(&mut rng, 10.0), radius: 0.05 + rng.uniform() * 0.6 }).collect();
        let bvh = Bvh::build(&spheres.iter().map(Sphere::bounds).collect::<Vec<_>>());
        let rays = random_rays(&mut rng, 2000);
        let (wrong, hits) = mismatches(&bvh, n, &rays, |i, r, t| spheres[i].intersect(r, t));
        assert!(wrong.is_empty(), "{} rays differ, first: {}", wrong.len(), wrong[0]);
        assert!(hits >= if n < 300 { 1 } else { 200 }, "too few hits ({hits})");
    }
}

/// The check above has power: small errors in the tree are reported. One primitive of 1000 left
/// out (its box empty), and boxes 5 % too small (triangles stick out of them only in slivers at
/// their corners).
#[test]
fn accel_brute_force_check_detects_a_slightly_wrong_tree() {
    let mut rng = Rng::for_stream(1, 0, 0);
    let tris = random_soup(&mut rng, 1000, 1.0);
    let rays = random_rays(&mut rng, 20_000);
    let count = |bounds: &[Aabb]| {
        let bvh = Bvh::build(bounds);
        mismatches(&bvh, tris.len(), &rays, |i, r, t| intersect_triangle(&tris[i], r, t)).0.len()
    };
    let mut one_missing = triangle_bounds(&tris);
    assert_eq!(count(&one_missing), 0);
    one_missing[500] = Aabb::EMPTY;
    let missing = count(&one_missing);
    assert!(missing >= 5, "one primitive left out changed only {missing} answers");
    let shrunk: Vec<Aabb> = triangle_bounds(&tris)
        .iter()
        .map(|b| {
            let (center, half) = ((b.min + b.max) * 0.5, (b.max - b.min) * 0.5 * 0.95);
            Aabb::new(center - half, center + half)
        })
        .collect();
    let shrunk = count(&shrunk);
    assert!(shrunk >= 5, "boxes 5 % too small changed only {shrunk} answers");
}

/// A grid of `n` × `n` unit squares in z = 0, each split into two triangles, with four copies of
/// each triangle at ids shuffled by `rng`: the tie-rule tests' scene.
pub(super) fn shuffled_tie_grid(n: usize, rng: &mut Rng) -> Vec<Tri> {
    let mut base = Vec::new();
    for i in 0..n {
        for j in 0..n {
            let p = |di: usize, dj: usize| Vec3::new((i + di) as f32, (j + dj) as f32, 0.0);
            base.push([p(0, 0), p(1, 0), p(1, 1)]);
            base.push([p(0, 0), p(1, 1), p(0, 1)]);
        }
    }
    let mut tris: Vec<Tri> = base.iter().flat_map(|t| [*t; 4]).collect();
    for i in (1..tris.len()).rev() {
        let j = (rng.uniform() * (i + 1) as f32) as usize % (i + 1);
        tris.swap(i, j);
    }
    tris
}

/// Ties: copies of the same triangles under shuffled ids, and coplanar triangles sharing edges
/// hit exactly at their shared vertices. The nearest hit must be the smallest id among equally
/// near ones, whatever the traversal meets first; the previous binary traversal (first found)
/// does not obey this rule, which shows that the test exercises it.
#[test]
fn accel_tie_rule_smallest_id_wins() {
    let mut rng = Rng::for_stream(6, 0, 0);
    let tris = shuffled_tie_grid(12, &mut rng);
    let bvh = Bvh::build(&triangle_bounds(&tris));
    let binary = BinaryBvh::build(&triangle_bounds(&tris));
    // Rays down at grid vertices (shared by up to 6 triangles × 4 copies) and at random points.
    let mut rays = Vec::new();
    for i in 0..=12 {
        for j in 0..=12 {
            let origin = Vec3::new(i as f32, j as f32, 3.0);
            rays.push((Ray::new(origin, -Vec3::Z), f32::INFINITY));
            rays.push((
                Ray::new(origin + random_vec(&mut rng, 0.5), (-Vec3::Z + random_vec(&mut rng, 0.3)).normalize()),
                f32::INFINITY,
            ));
        }
    }
    let hits = check(&tris, &bvh, &rays);
    assert!(hits > 200, "{hits}");
    let first_found_differs = rays.iter().any(|(ray, t_max)| {
        let hit = |p: u32, r: &Ray, t: f32| intersect_triangle(&tris[p as usize], r, t);
        binary.closest_hit(ray, *t_max, hit) != bvh.closest_hit(ray, *t_max, hit)
    });
    assert!(first_found_differs, "no ray had a tie that the traversal order decides");
}

#[test]
fn accel_large_soup_parallel_build() {
    let mut rng = Rng::for_stream(2, 0, 0);
    let tris = random_soup(&mut rng, 200_000, 0.2);
    let bvh = Bvh::build(&triangle_bounds(&tris));
    let stats = bvh.stats();
    assert!(stats.max_depth < MAX_DEPTH);
    assert!(stats.wide_max_depth <= stats.max_depth);
    // Same tree, whatever the thread count: the build is deterministic.
    let again = Bvh::build(&triangle_bounds(&tris));
    assert_eq!(tree_words(&again), tree_words(&bvh));
    let rays = random_rays(&mut rng, 300);
    assert!(check(&tris, &bvh, &rays) > 50);
}

/// Every word of a tree: the wide nodes and the primitive ids.
fn tree_words(bvh: &Bvh) -> Vec<u32> {
    let node_words = bvh.nodes.iter().flat_map(|n| {
        let corners = n.slabs.iter().flatten().flatten().map(|x| x.to_bits());
        corners.chain(n.meta).chain(n.child).collect::<Vec<_>>()
    });
    node_words.chain(bvh.prims.iter().copied()).collect()
}

/// A closed UV sphere of radius 1 with `rings × segments × 2` triangles (its pole rings are
/// degenerate slivers, as in real meshes).
pub(super) fn uv_sphere(rings: usize, segments: usize) -> Vec<Tri> {
    let point = |i: usize, j: usize| {
        let (theta, phi) =
            (std::f32::consts::PI * i as f32 / rings as f32, std::f32::consts::TAU * j as f32 / segments as f32);
        Vec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos())
    };
    let mut tris = Vec::with_capacity(2 * rings * segments);
    for i in 0..rings {
        for j in 0..segments {
            let (a, b, c, d) = (point(i, j), point(i, j + 1), point(i + 1, j), point(i + 1, j + 1));
            tris.push([a, c, d]);
            tris.push([a, d, b]);
        }
    }
    tris
}

#[test]
fn accel_parallel_build_is_identical_with_one_and_two_threads() {
    // 81,920 triangles: above both the parallel subtree threshold and the parallel binning
    // threshold, so the two-thread build splits work at both levels.
    let tris = uv_sphere(160, 256);
    assert!(tris.len() >= PARALLEL_BINNING_THRESHOLD && tris.len() >= PARALLEL_THRESHOLD);
    let bounds = triangle_bounds(&tris);
    let build = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| Bvh::build(&bounds))
    };
    let (one, two) = (build(1), build(2));
    assert_eq!(one.stats(), two.stats());
    assert_eq!(one.stats().primitives, tris.len());
    let (a, b) = (tree_words(&one), tree_words(&two));
    assert_eq!(a.len(), b.len());
    let first_difference = a.iter().zip(&b).position(|(x, y)| x != y);
    assert_eq!(first_difference, None, "the trees differ at word {first_difference:?}");
    // And the tree is right: rays from outside at the sphere find the brute-force hits.
    let mut rng = Rng::for_stream(4, 0, 0);
    let rays: Vec<(Ray, f32)> = (0..300)
        .map(|_| {
            let origin = random_direction(&mut rng) * 3.0;
            let target = random_vec(&mut rng, 1.0);
            (Ray::new(origin, (target - origin).normalize()), f32::INFINITY)
        })
        .collect();
    assert!(check(&tris, &two, &rays) > 150);
}

/// The collapse keeps every leaf of the binary tree exactly once, each child box is the box of
/// its binary node (so it contains its primitives), every wide node has at least two children,
/// and the wide tree needs fewer, shallower nodes.
#[test]
fn accel_collapse_structure() {
    let mut rng = Rng::for_stream(8, 0, 0);
    let tris = random_soup(&mut rng, 20_000, 0.3);
    let bounds = triangle_bounds(&tris);
    let bvh = Bvh::build(&bounds);
    let stats = bvh.stats();
    let mut seen = vec![0u32; tris.len()];
    let mut leaves = 0;
    let mut lanes_used = 0;
    for node in &bvh.nodes {
        let mut used_here = 0;
        for lane in 0..WIDTH {
            let (meta, child) = (node.meta[lane], node.child[lane]);
            let lane_box = Aabb::new(
                Vec3::new(node.slabs[0][0][lane], node.slabs[1][0][lane], node.slabs[2][0][lane]),
                Vec3::new(node.slabs[0][1][lane], node.slabs[1][1][lane], node.slabs[2][1][lane]),
            );
            if meta == 0 {
                assert!(lane_box.min.x == f32::INFINITY && lane_box.max.x == f32::NEG_INFINITY, "unused lane box");
                continue;
            }
            used_here += 1;
            if meta == INTERIOR {
                assert!((child as usize) < bvh.nodes.len());
                continue;
            }
            leaves += 1;
            let prims: Vec<u32> =
                if meta == 1 { vec![child] } else { bvh.prims[child as usize..(child + meta) as usize].to_vec() };
            for p in prims {
                seen[p as usize] += 1;
                let b = bounds[p as usize];
                assert!(
                    lane_box.min.cmple(b.min).all() && lane_box.max.cmpge(b.max).all(),
                    "leaf box misses a primitive"
                );
            }
        }
        assert!(used_here >= 2 || bvh.nodes.len() == 1, "a wide node with one child");
        lanes_used += used_here;
    }
    assert!(seen.iter().all(|&s| s == 1), "every primitive in exactly one leaf");
    assert_eq!(leaves, stats.leaves);
    // Every wide node but the root hangs from one lane.
    assert_eq!(lanes_used, bvh.nodes.len() - 1 + leaves);
    assert_eq!(stats.wide_nodes, bvh.nodes.len());
    assert!(stats.wide_max_depth < stats.max_depth, "{stats:?}");
}

/// Counts: the wide tree visits fewer nodes than the binary one on the same rays and finds the
/// same hits (distances bit-identical; primitives equal up to ties).
#[test]
fn accel_wide_tree_agrees_with_binary_and_visits_fewer_nodes() {
    let tris = uv_sphere(100, 200);
    let bounds = triangle_bounds(&tris);
    let (bvh, binary) = (Bvh::build(&bounds), BinaryBvh::build(&bounds));
    assert_eq!(binary.stats().nodes, bvh.stats().nodes);
    let mut rng = Rng::for_stream(9, 0, 0);
    let rays: Vec<(Ray, f32)> =
        (0..5000).map(|_| (Ray::new(random_vec(&mut rng, 3.0), random_direction(&mut rng)), f32::INFINITY)).collect();
    let (mut wide_counts, mut binary_counts) = (TraversalCounts::default(), TraversalCounts::default());
    let hit = |p: u32, r: &Ray, t: f32| intersect_triangle(&tris[p as usize], r, t);
    for (ray, t_max) in &rays {
        let a = bvh.closest_hit_counted(ray, *t_max, hit, &mut wide_counts);
        let b = binary.closest_hit_counted(ray, *t_max, hit, &mut binary_counts);
        assert_eq!(a.map(|h| h.1.to_bits()), b.map(|h| h.1.to_bits()), "{ray:?}");
        let any_a = bvh.any_hit_counted(ray, 1.0, |p, r, t| hit(p, r, t).is_some(), &mut TraversalCounts::default());
        let any_b = binary.any_hit_counted(ray, 1.0, |p, r, t| hit(p, r, t).is_some(), &mut TraversalCounts::default());
        assert_eq!(any_a, any_b);
    }
    // Measured: 23,189 wide against 40,179 binary interior nodes (0.58×), the same primitive
    // tests up to ties (5,424 against 5,427).
    assert!(wide_counts.nodes * 3 < binary_counts.nodes * 2, "{wide_counts:?} vs {binary_counts:?}");
    assert!(wide_counts.primitives.abs_diff(binary_counts.primitives) * 100 < binary_counts.primitives);
}

#[test]
fn accel_empty_tree_misses() {
    let bvh = Bvh::build(&[]);
    let ray = Ray::new(Vec3::ZERO, Vec3::X);
    assert_eq!(bvh.closest_hit(&ray, f32::INFINITY, |_, _, _| panic!("no primitives")), None);
    assert!(!bvh.any_hit(&ray, f32::INFINITY, |_, _, _| panic!("no primitives")));
    assert_eq!(bvh.bounds(), Aabb::EMPTY);
    assert_eq!(bvh.stats().nodes, 0);
    // Primitives with empty or NaN boxes are left out.
    let bvh = Bvh::build(&[Aabb::EMPTY, Aabb::new(Vec3::NAN, Vec3::ONE)]);
    assert!(!bvh.any_hit(&ray, f32::INFINITY, |_, _, _| panic!("no primitives")));
}

/// Rays with NaN or infinite components enter every box (NaN plane distances are ignored), so
/// they reach the unused lanes too; these must not lead anywhere.
#[test]
fn accel_rays_with_nans_terminate() {
    let mut rng = Rng::for_stream(10, 0, 0);
    let tris = random_soup(&mut rng, 300, 1.0);
    let bvh = Bvh::build(&triangle_bounds(&tris));
    for ray in [
        Ray::new(Vec3::NAN, Vec3::X),
        Ray::new(Vec3::ZERO, Vec3::NAN),
        Ray::new(Vec3::ZERO, Vec3::new(f32::INFINITY, 0.0, 0.0)),
    ] {
        let mut calls = 0;
        bvh.closest_hit(&ray, f32::INFINITY, |p, r, t| {
            calls += 1;
            intersect_triangle(&tris[p as usize], r, t)
        });
        assert!(calls <= tris.len());
        bvh.any_hit(&ray, f32::INFINITY, |p, r, t| intersect_triangle(&tris[p as usize], r, t).is_some());
    }
    let ray = Ray::new(Vec3::ZERO, Vec3::X);
    assert_eq!(bvh.closest_hit(&ray, f32::NAN, |_, _, _| panic!("t_max is NaN")), None);
    assert!(!bvh.any_hit(&ray, -1.0, |_, _, _| panic!("t_max is negative")));
}

#[test]
fn accel_single_primitive() {
    let tris = vec![[Vec3::new(1.0, -1.0, -1.0), Vec3::new(1.0, 1.0, -1.0), Vec3::new(1.0, 0.0, 1.0)]];
    let bvh = Bvh::build(&triangle_bounds(&tris));
    assert_eq!(bvh.bounds(), triangle_bounds(&tris)[0]);
    assert_eq!(bvh.stats().nodes, 1);
    assert_eq!(bvh.stats().wide_nodes, 1);
    let hit = bvh.closest_hit(&Ray::new(Vec3::ZERO, Vec3::X), f32::INFINITY, |p, r, t| {
        intersect_triangle(&tris[p as usize], r, t)
    });
    assert_eq!(hit, Some((0, 1.0)));
    let shadow = |t_max| {
        bvh.any_hit(&Ray::new(Vec3::ZERO, Vec3::X), t_max, |p, r, t| {
            intersect_triangle(&tris[p as usize], r, t).is_some()
        })
    };
    assert!(shadow(2.0));
    assert!(!shadow(1.0));
    assert!(bvh.closest_hit(&Ray::new(Vec3::ZERO, -Vec3::X), f32::INFINITY, |_, _, _| None).is_none());
}

#[test]
fn accel_many_identical_primitives() {
    let tri = [Vec3::new(-1.0, -1.0, 2.0), Vec3::new(1.0, -1.0, 2.0), Vec3::new(0.0, 1.0, 2.0)];
    let tris = vec![tri; 1000];
    let bvh = Bvh::build(&triangle_bounds(&tris));
    let stats = bvh.stats();
    assert!(stats.max_leaf_size <= MAX_LEAF_SIZE);
    assert!(stats.max_depth < MAX_DEPTH);
    let ray = Ray::new(Vec3::ZERO, Vec3::Z);
    let mut calls = 0;
    let hit = bvh.closest_hit(&ray, f32::INFINITY, |p, r, t| {
        calls += 1;
        intersect_triangle(&tris[p as usize], r, t)
    });
    assert_eq!(hit, Some((0, 2.0)), "of equally near hits the smallest id");
    assert_eq!(calls, 1000, "every copy is visited: any may have a smaller id");
    // Identical points (all centroids and boxes equal, zero area).
    let points = vec![Aabb::new(Vec3::ONE, Vec3::ONE); 777];
    let bvh = Bvh::build(&points);
    assert!(bvh.stats().max_leaf_size <= MAX_LEAF_SIZE);
    let ray = Ray::new(Vec3::ZERO, Vec3::ONE.normalize());
    let mut seen = vec![false; points.len()];
    assert!(!bvh.any_hit(&ray, f32::INFINITY, |p, _, _| {
        seen[p as usize] = true;
        false
    }));
    assert!(seen.iter().all(|s| *s), "every primitive is reachable");
}

/// Axis-aligned geometry on an integer grid and rays with zero direction components whose
/// origins lie exactly on box planes: the slab test's `0·∞` cases.
#[test]
fn accel_axis_aligned_rays() {
    let mut rng = Rng::for_stream(3, 0, 0);
    let grid = |rng: &mut Rng| (rng.uniform() * 9.0).floor() - 4.0;
    let mut tris = Vec::new();
    for _ in 0..400 {
        let p = Vec3::new(grid(&mut rng), grid(&mut rng), grid(&mut rng));
        let axis = (rng.uniform() * 3.0) as usize;
        let (a, b) = match axis {
            0 => (Vec3::Y, Vec3::Z),
            1 => (Vec3::Z, Vec3::X),
            _ => (Vec3::X, Vec3::Y),
        };
        // Axis-aligned (flat box) triangles and skewed ones touching grid planes.
        tris.push([p, p + a, p + b]);
        tris.push([p, p + a + Vec3::ONE * 0.5, p + b * 2.0]);
    }
    let bvh = Bvh::build(&triangle_bounds(&tris));
    let mut rays = Vec::new();
    let dirs = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
    for i in 0..3000 {
        let mut o = Vec3::new(grid(&mut rng), grid(&mut rng), grid(&mut rng));
        // Some origins off the grid on some axes.
        if i % 2 == 0 {
            o += Vec3::new(rng.uniform(), rng.uniform(), 0.0) * 0.999;
        }
        let d = if i % 3 == 0 {
            // Zero in one component, including negative zero.
            let mut d = Vec3::new(rng.uniform() - 0.5, rng.uniform() - 0.5, if i % 2 == 0 { 0.0 } else { -0.0 });
            if d.length_squared() == 0.0 {
                d = Vec3::X;
            }
            d.normalize()
        } else {
            dirs[i % 6]
        };
        rays.push((Ray::new(o, d), if i % 4 == 0 { 3.0 } else { f32::INFINITY }));
    }
    let hits = check(&tris, &bvh, &rays);
    assert!(hits > 200, "{hits}");
}
