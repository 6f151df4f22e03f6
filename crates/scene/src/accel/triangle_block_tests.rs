//! Tests of the triangle blocks (`triangle_block.rs`): trees built with
//! [`Bvh::build_with_triangles`] answer exactly as brute force over [`Triangle::intersect`]
//! (primitive, bit pattern of the distance, tie rule, any hit), without calling the closure for
//! the plain triangles, on random soups, ties, axis-aligned rays with zero direction components,
//! degenerate triangles, and leaves mixing plain triangles with primitives of the closure.

use super::tests::{
    Tri, intersect_triangle, mismatches, random_direction, random_rays, random_soup, random_vec, shuffled_tie_grid,
    triangle_bounds, uv_sphere,
};
use super::triangle_block::{LANES, RayLanes, TRIANGLES, TriangleBlock};
use super::wide::INTERIOR;
use super::*;
use crate::alpha::alpha_hash;
use crate::shape::{Sphere, Triangle};
use math::{Rng, Vec3};

/// Every primitive of `tris` is a plain triangle.
fn plain(tris: &[Tri]) -> impl Fn(u32) -> Option<Triangle> + '_ {
    move |id| tris.get(id as usize).map(|t| Triangle::new(t[0], t[1], t[2]))
}

/// The number of block leaves of `bvh` and of the primitives in them.
fn blocks(bvh: &Bvh) -> (usize, usize) {
    let lanes = bvh.nodes.iter().flat_map(|n| n.meta);
    let block_lanes: Vec<u32> = lanes.filter(|&m| m != INTERIOR && m & TRIANGLES != 0).collect();
    (block_lanes.len(), block_lanes.iter().map(|m| (m & !TRIANGLES) as usize).sum())
}

/// Asserts that the tree over `tris`, all of them plain triangles, agrees exactly with brute
/// force on `rays` and never calls its closure; returns the number of rays that hit.
fn check_blocks(tris: &[Tri], rays: &[(Ray, f32)]) -> usize {
    let bvh = Bvh::build_with_triangles(&triangle_bounds(tris), plain(tris));
    let (block_count, in_blocks) = blocks(&bvh);
    assert_eq!(in_blocks, bvh.stats().primitives, "every primitive in a block");
    assert_eq!(block_count, bvh.stats().leaves);
    let (wrong, hits) = mismatches(&bvh, tris.len(), rays, |i, r, t| intersect_triangle(&tris[i], r, t));
    assert!(wrong.is_empty(), "{} of {} rays differ, first: {}", wrong.len(), rays.len(), wrong[0]);
    for (ray, t_max) in rays {
        bvh.closest_hit(ray, *t_max, |_, _, _| panic!("a plain triangle went to the closure"));
        bvh.any_hit(ray, *t_max, |_, _, _| panic!("a plain triangle went to the closure"));
    }
    hits
}

/// Each lane of a block reports exactly what `Triangle::intersect` reports (bit pattern of `t`),
/// unused lanes nothing.
#[test]
fn block_lanes_equal_triangle_intersect() {
    let mut rng = Rng::for_stream(21, 0, 0);
    for count in 1..=LANES {
        for _ in 0..200 {
            let tris: Vec<(u32, Triangle)> = random_soup(&mut rng, count, 3.0)
                .iter()
                .enumerate()
                .map(|(i, t)| (i as u32, Triangle::new(t[0], t[1], t[2])))
                .collect();
            let block = TriangleBlock::new(&tris);
            for _ in 0..20 {
                let ray = Ray::new(random_vec(&mut rng, 14.0), random_direction(&mut rng));
                let t = block.distances(&RayLanes::new(&ray)).to_array();
                for (lane, t) in t.iter().enumerate() {
                    let expected = tris.get(lane).and_then(|(_, tri)| tri.intersect(&ray, f32::INFINITY));
                    assert_eq!(t.to_bits(), expected.unwrap_or(f32::INFINITY).to_bits(), "{ray:?} lane {lane}");
                }
            }
        }
    }
}

#[test]
fn blocks_match_brute_force_on_random_soups() {
    let mut rng = Rng::for_stream(22, 0, 0);
    for (n, size) in [(1, 3.0), (3, 3.0), (7, 2.0), (100, 1.5), (1000, 1.0), (5000, 0.5)] {
        let tris = random_soup(&mut rng, n, size);
        let hits = check_blocks(&tris, &random_rays(&mut rng, 2000));
        assert!(hits >= if n < 100 { 1 } else { 50 }, "too few hits ({hits})");
    }
}

/// Trees large enough for the queries' cache hints on pushed children
/// ([`super::traverse::HINT_MIN_NODES`] nodes or more) answer exactly as brute force, with the
/// triangles in the closure and in blocks. (A hint changes no answer; this runs that code.)
#[test]
fn trees_with_child_hints_match_brute_force() {
    let mut rng = Rng::for_stream(29, 0, 0);
    let tris = random_soup(&mut rng, 100_000, 0.3);
    let rays = random_rays(&mut rng, 300);
    let closure_tree = Bvh::build(&triangle_bounds(&tris));
    let nodes = closure_tree.stats().wide_nodes;
    assert!(nodes >= super::traverse::HINT_MIN_NODES, "{nodes} nodes: too few for the hints");
    let hit = |i: usize, r: &Ray, t: f32| intersect_triangle(&tris[i], r, t);
    let (wrong, hits) = mismatches(&closure_tree, tris.len(), &rays, hit);
    assert!(wrong.is_empty(), "{} of {} rays differ, first: {}", wrong.len(), rays.len(), wrong[0]);
    assert!(hits >= 50, "too few hits ({hits})");
    check_blocks(&tris, &rays);
}

/// The same tree, the same visits and the same counts as [`Bvh::build`] with the triangle test in
/// the closure: blocks change how a leaf is tested, not the traversal. (An any-hit query counts
/// a whole block where the closure stops at the first blocker of a leaf.)
#[test]
fn blocks_traverse_like_the_closure_tree() {
    let tris = uv_sphere(60, 120);
    let bounds = triangle_bounds(&tris);
    let (closure_tree, block_tree) = (Bvh::build(&bounds), Bvh::build_with_triangles(&bounds, plain(&tris)));
    assert_eq!(closure_tree.stats(), block_tree.stats());
    let mut rng = Rng::for_stream(23, 0, 0);
    let [mut a, mut b, mut any_a, mut any_b] = [TraversalCounts::default(); 4];
    let hit = |p: u32, r: &Ray, t: f32| intersect_triangle(&tris[p as usize], r, t);
    for _ in 0..3000 {
        let ray = Ray::new(random_vec(&mut rng, 3.0), random_direction(&mut rng));
        let t_max = if rng.uniform() < 0.5 { f32::INFINITY } else { rng.uniform() * 2.0 };
        let expected = closure_tree.closest_hit_counted(&ray, t_max, hit, &mut a);
        let got = block_tree.closest_hit_counted(&ray, t_max, |_, _, _| None, &mut b);
        assert_eq!(expected.map(|(p, t)| (p, t.to_bits())), got.map(|(p, t)| (p, t.to_bits())));
        let expected = closure_tree.any_hit_counted(&ray, t_max, |p, r, t| hit(p, r, t).is_some(), &mut any_a);
        assert_eq!(expected, block_tree.any_hit_counted(&ray, t_max, |_, _, _| false, &mut any_b));
    }
    assert_eq!(a, b);
    assert!(a.primitives > 1000, "{a:?}");
    assert_eq!((any_a.nodes, any_a.box_tests), (any_b.nodes, any_b.box_tests));
    assert!(any_a.primitives <= any_b.primitives);
}

/// Ties inside one block and across blocks: copies of the same triangles under shuffled ids and
/// coplanar triangles meeting at shared vertices. The smallest id of the equally near wins.
#[test]
fn blocks_keep_the_tie_rule() {
    let mut rng = Rng::for_stream(24, 0, 0);
    let tris = shuffled_tie_grid(8, &mut rng);
    let mut rays = Vec::new();
    for i in 0..=8 {
        for j in 0..=8 {
            let origin = Vec3::new(i as f32, j as f32, 3.0);
            rays.push((Ray::new(origin, -Vec3::Z), f32::INFINITY));
            rays.push((Ray::new(origin + random_vec(&mut rng, 0.5), -Vec3::Z), f32::INFINITY));
        }
    }
    assert!(check_blocks(&tris, &rays) > 100);
    // Four copies of one triangle: one block, a four-way tie, from above and below.
    let copies = vec![[Vec3::new(-1.0, -1.0, 2.0), Vec3::new(1.0, -1.0, 2.0), Vec3::new(0.0, 1.0, 2.0)]; 4];
    let bvh = Bvh::build_with_triangles(&triangle_bounds(&copies), plain(&copies));
    assert_eq!(blocks(&bvh), (1, 4));
    for direction in [Vec3::Z, -Vec3::Z] {
        let ray = Ray::new(-direction * 2.0 + Vec3::Z * 2.0, direction);
        assert_eq!(bvh.closest_hit(&ray, f32::INFINITY, |_, _, _| None), Some((0, 2.0)));
    }
}

/// Axis-aligned triangles on an integer grid and rays with zero direction components (both signs
/// of zero) whose origins lie on box and triangle planes.
#[test]
fn blocks_with_zero_direction_components() {
    let mut rng = Rng::for_stream(25, 0, 0);
    let grid = |rng: &mut Rng| (rng.uniform() * 7.0).floor() - 3.0;
    let mut tris = Vec::new();
    for _ in 0..300 {
        let p = Vec3::new(grid(&mut rng), grid(&mut rng), grid(&mut rng));
        let (a, b) = match (rng.uniform() * 3.0) as usize {
            0 => (Vec3::Y, Vec3::Z),
            1 => (Vec3::Z, Vec3::X),
            _ => (Vec3::X, Vec3::Y),
        };
        tris.push([p, p + a, p + b]);
        tris.push([p, p + a + Vec3::ONE * 0.5, p + b * 2.0]);
    }
    let axes = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
    let mut rays = Vec::new();
    for i in 0..3000 {
        let mut o = Vec3::new(grid(&mut rng), grid(&mut rng), grid(&mut rng));
        if i % 2 == 0 {
            o += Vec3::new(rng.uniform(), rng.uniform(), 0.0) * 0.999;
        }
        let d = if i % 3 == 0 {
            let zero = if i % 2 == 0 { 0.0 } else { -0.0 };
            let d = Vec3::new(rng.uniform() - 0.5, rng.uniform() - 0.5, zero);
            if d.length_squared() == 0.0 { Vec3::X } else { d.normalize() }
        } else {
            axes[i % 6]
        };
        rays.push((Ray::new(o, d), if i % 4 == 0 { 2.5 } else { f32::INFINITY }));
    }
    assert!(check_blocks(&tris, &rays) > 200);
}

/// Degenerate but NaN-free triangles: collinear vertices, repeated vertices, a point, slivers,
/// and triangles so large that the determinant overflows; rays in their planes and through
/// their edges. Exactly as brute force says, and never a hit on a triangle with a zero edge
/// (its determinant is exactly 0).
#[test]
fn blocks_with_degenerate_triangles() {
    let mut rng = Rng::for_stream(26, 0, 0);
    let mut tris: Vec<Tri> = Vec::new();
    for _ in 0..200 {
        let (p, q) = (random_vec(&mut rng, 8.0), random_vec(&mut rng, 2.0));
        tris.push([p, p + q, p + q * 2.5]);
        tris.push([p, p, p + q]);
        tris.push([p; 3]);
        tris.push([p, p + q, p + q + Vec3::splat(1e-7)]);
        tris.push([p, p + q, p + random_vec(&mut rng, 2.0)]);
    }
    tris.push([Vec3::new(-1e30, -1e30, 0.0), Vec3::new(1e30, -1e30, 0.0), Vec3::new(0.0, 1e30, 0.0)]);
    let degenerate = |t: &Tri| t[1] == t[0] || t[2] == t[0];
    let mut rays = random_rays(&mut rng, 2000);
    for t in tris.iter().take(300) {
        // Along an edge and within the plane.
        let (a, b) = (t[0] - (t[1] - t[0]), t[1] - t[0]);
        if b.length_squared() > 0.0 {
            rays.push((Ray::new(a, b.normalize()), f32::INFINITY));
        }
    }
    rays.push((Ray::new(Vec3::new(0.5, 0.5, 5.0), -Vec3::Z), f32::INFINITY));
    assert!(check_blocks(&tris, &rays) > 100);
    let bvh = Bvh::build_with_triangles(&triangle_bounds(&tris), plain(&tris));
    for (ray, t_max) in &rays {
        if let Some((p, _)) = bvh.closest_hit(ray, *t_max, |_, _, _| None) {
            assert!(!degenerate(&tris[p as usize]), "a triangle with a zero edge was hit: {ray:?}");
        }
    }
}

/// Leaves that mix plain triangles with primitives of the closure (spheres, and triangles whose
/// hits the closure keeps only where a hash of the hit says so, as alpha masks do): blocks where
/// a leaf is all plain, the closure for the rest, and exactly the brute-force answer.
#[test]
fn blocks_mixed_with_closure_primitives() {
    let mut rng = Rng::for_stream(27, 0, 0);
    #[derive(Clone, Copy)]
    enum Prim {
        Plain(Triangle),
        Masked(Triangle),
        Ball(Sphere),
    }
    let mut prims = Vec::new();
    for (i, t) in random_soup(&mut rng, 3000, 1.2).iter().enumerate() {
        let triangle = Triangle::new(t[0], t[1], t[2]);
        prims.push(match i % 10 {
            0 | 1 => Prim::Masked(triangle),
            2 => Prim::Ball(Sphere { center: t[0], radius: 0.05 + rng.uniform() * 0.3 }),
            _ => Prim::Plain(triangle),
        });
    }
    // Whole regions of plain triangles too, so that many leaves are blocks.
    for t in random_soup(&mut rng, 2000, 0.4) {
        prims.push(Prim::Plain(Triangle::new(t[0] * 0.3, t[1] * 0.3, t[2] * 0.3)));
    }
    let bounds: Vec<Aabb> = prims
        .iter()
        .map(|p| match p {
            Prim::Plain(t) | Prim::Masked(t) => t.bounds(),
            Prim::Ball(s) => s.bounds(),
        })
        .collect();
    let hit = |i: usize, r: &Ray, t_max: f32| match &prims[i] {
        Prim::Plain(t) => t.intersect(r, t_max),
        Prim::Masked(t) => t.intersect(r, t_max).filter(|&t| alpha_hash(r.origin, r.direction, t) < 0.5),
        Prim::Ball(s) => s.intersect(r, t_max),
    };
    let bvh = Bvh::build_with_triangles(&bounds, |id| match prims[id as usize] {
        Prim::Plain(t) => Some(t),
        _ => None,
    });
    let (block_count, _) = blocks(&bvh);
    assert!(block_count > 100 && block_count < bvh.stats().leaves, "{block_count} of {} leaves", bvh.stats().leaves);
    let (wrong, hits) = mismatches(&bvh, prims.len(), &random_rays(&mut rng, 4000), hit);
    assert!(wrong.is_empty(), "{} rays differ, first: {}", wrong.len(), wrong[0]);
    assert!(hits > 500, "{hits}");
    // The closure is asked only about primitives outside blocks.
    let ids = block_ids(&bvh);
    let in_blocks: Vec<bool> = (0..prims.len() as u32).map(|id| ids.binary_search(&id).is_ok()).collect();
    assert_eq!(in_blocks.iter().filter(|&&b| b).count(), ids.len());
    for (ray, t_max) in random_rays(&mut rng, 500) {
        bvh.closest_hit(&ray, t_max, |p, r, t| {
            assert!(!in_blocks[p as usize], "primitive {p} of a block went to the closure");
            hit(p as usize, r, t)
        });
    }
}

/// The primitive ids stored in the blocks of `bvh`.
fn block_ids(bvh: &Bvh) -> Vec<u32> {
    let mut ids: Vec<u32> = bvh.blocks.iter().flat_map(|b| b.ids).filter(|&id| id != u32::MAX).collect();
    ids.sort_unstable();
    ids
}
