//! The bounding volume hierarchy (BVH) that accelerates ray queries over all primitives.
//!
//! This module owns the tree: its construction from primitive bounds (binned SAH, parallel with
//! rayon for large inputs, then collapsed into 8-wide nodes) and its traversal for nearest hits
//! and occlusion (any hit). It is primitive-agnostic: the tree only knows each primitive's
//! bounding box and index, and the caller intersects a primitive in a closure, so triangles and
//! analytic shapes share one tree; only triangles that need nothing but the geometric test may
//! be handed to the tree, which then tests them itself ([`Bvh::build_with_triangles`]). See
//! `docs/bvh.md`.
//!
//! Files: `build.rs` (binary SAH build), `binary.rs` (its node layout), `wide.rs` (8-wide nodes
//! and the collapse), `ray_box.rs` (the slab test, four lanes at a time), `traverse.rs` (the queries and their
//! tie rule), `triangle_block.rs` (leaves of plain triangles stored as 4-lane blocks that the
//! queries test themselves, [`Bvh::build_with_triangles`]), `binary_traverse.rs` (the previous
//! binary traversal, only for A/B benchmarks behind the `binary-bvh` feature, and for tests),
//! `embree.rs` (the optional Embree 3 backend for triangle-only scenes, behind the `embree`
//! feature; see `docs/embree.md`). Tests: `tests.rs` (the tree), `triangle_block_tests.rs` and
//! `scene_block_tests.rs` (blocks, in the tree and in [`crate::Scene`]'s queries).

mod binary;
#[cfg(any(test, feature = "binary-bvh"))]
#[cfg_attr(not(feature = "binary-bvh"), allow(dead_code))]
mod binary_traverse;
mod build;
#[cfg(feature = "embree")]
pub mod embree;
mod ray_box;
mod traverse;
mod triangle_block;
mod wide;

#[cfg(test)]
mod scene_block_tests;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod triangle_block_tests;

use math::{Aabb, Ray};

use crate::shape::Triangle;

#[cfg(feature = "binary-bvh")]
pub use binary_traverse::BinaryBvh;
#[cfg(feature = "embree")]
pub use embree::EmbreeAccel;

/// Largest tree depth (root = depth 0); the build guarantees a smaller depth, which bounds the
/// traversal stacks.
const MAX_DEPTH: usize = 64;

/// Statistics of a built tree.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BvhStats {
    /// Primitives in the tree (those with a non-empty, NaN-free box).
    pub primitives: usize,
    /// Nodes of the binary SAH tree the wide tree is collapsed from, interior and leaves,
    /// including the root.
    pub nodes: usize,
    /// Leaf nodes (of both trees: collapsing keeps the leaves).
    pub leaves: usize,
    /// Depth of the deepest leaf of the binary tree (a root leaf has depth 0).
    pub max_depth: usize,
    /// Largest number of primitives in one leaf.
    pub max_leaf_size: usize,
    /// SAH cost of the binary tree:
    /// `Σ_interior A(n)/A(root)·C_trav + Σ_leaf A(n)/A(root)·N(n)·C_isect` with
    /// `C_trav = C_isect = 1`.
    pub sah_cost: f32,
    /// Nodes of the 8-wide tree that queries traverse (256 bytes each).
    pub wide_nodes: usize,
    /// Depth of the deepest 8-wide node (the root has depth 0).
    pub wide_max_depth: usize,
}

/// Work done by queries, summed over calls (see [`Bvh::closest_hit_counted`]); for benchmarks
/// and tests, which compare trees by counts instead of times.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TraversalCounts {
    /// Nodes visited (for the wide tree one visit tests eight child boxes).
    pub nodes: u64,
    /// Ray–box tests (eight per wide node visited, two per binary interior node).
    pub box_tests: u64,
    /// Primitives handed to the callback.
    pub primitives: u64,
}

/// A bounding volume hierarchy over primitives known by their bounding boxes.
///
/// Primitive ids are indices into the slice given to [`Bvh::build`]. Queries are read-only and
/// allocation-free, so one tree can be shared by all threads.
#[derive(Clone, Debug)]
pub struct Bvh {
    /// 8-wide nodes in depth-first order, node 0 the root; empty for a tree without primitives.
    nodes: Vec<wide::WideNode>,
    /// Primitive ids, grouped by leaf (leaves of several primitives name a range of it).
    prims: Vec<u32>,
    /// The leaves of plain triangles ([`Bvh::build_with_triangles`]), which the traversal tests
    /// itself; empty for [`Bvh::build`].
    blocks: Vec<triangle_block::TriangleBlock>,
    /// Bounds of all primitives.
    bounds: Aabb,
    /// Statistics gathered while building.
    stats: BvhStats,
}

impl Bvh {
    /// Builds the tree over primitive bounds; primitive ids are indices into `bounds`.
    ///
    /// Uses binned SAH with leaves of at most four primitives, rayon for large inputs, and then
    /// collapses the binary tree into 8-wide nodes. An empty input gives a tree every query
    /// misses. Primitives whose box is empty or contains a NaN can never be hit and are left
    /// out; coordinates beyond ±1e18 are clamped. The tree is the same for any thread count.
    pub fn build(bounds: &[Aabb]) -> Bvh {
        let tree = build::build_binary(bounds);
        if tree.prims.is_empty() {
            return Bvh {
                nodes: Vec::new(),
                prims: Vec::new(),
                blocks: Vec::new(),
                bounds: Aabb::EMPTY,
                stats: tree.stats,
            };
        }
        let wide = wide::collapse(&tree);
        let stats = BvhStats { wide_nodes: wide.nodes.len(), wide_max_depth: wide.max_depth, ..tree.stats };
        let bounds = Aabb::new(tree.root.min(), tree.root.max());
        Bvh { nodes: wide.nodes, prims: tree.prims, blocks: Vec::new(), bounds, stats }
    }

    /// [`Bvh::build`] for primitives of which some are plain triangles: `triangle(id)` returns
    /// the triangle of primitive `id` when the ray queries need nothing but its geometric test
    /// ([`Triangle::intersect`]), `None` otherwise.
    ///
    /// The tree is the same as [`Bvh::build`]'s; every leaf whose primitives are all plain
    /// triangles is stored as a block of four lanes that the queries test at once themselves,
    /// without calling their closure (which is then only called for the other primitives).
    /// The answers are those of [`Bvh::build`] with a closure that calls
    /// [`Triangle::intersect`] for the plain triangles: the same primitive and bit-identical
    /// distance, with the same tie rule.
    pub fn build_with_triangles(bounds: &[Aabb], triangle: impl Fn(u32) -> Option<Triangle>) -> Bvh {
        let mut bvh = Bvh::build(bounds);
        bvh.blocks = triangle_block::gather(&mut bvh.nodes, &bvh.prims, triangle);
        bvh
    }

    /// Bounds of all primitives in the tree ([`Aabb::EMPTY`] for an empty tree).
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// Statistics of the tree: node counts, depth, leaf sizes, SAH cost.
    pub fn stats(&self) -> BvhStats {
        self.stats
    }

    /// Nearest hit along `ray` closer than `t_max` (in units of the ray parameter).
    ///
    /// Calls `intersect(prim, ray, t)`, which must return `Some(t_hit)` for a hit with
    /// `0 < t_hit < t` (and may have side effects: every hit it reports is taken, so the last
    /// one reported is the result whenever the result is a primitive of the closure; the plain
    /// triangles of [`Bvh::build_with_triangles`] are tested without it). Returns the primitive
    /// and distance of the nearest hit. Of primitives hit at exactly the same distance the one with the smallest id
    /// is returned, so the result does not depend on the tree's shape or the traversal order;
    /// for that, `t` is sometimes one ulp above the nearest distance found so far.
    #[inline]
    pub fn closest_hit(
        &self,
        ray: &Ray,
        t_max: f32,
        intersect: impl FnMut(u32, &Ray, f32) -> Option<f32>,
    ) -> Option<(u32, f32)> {
        self.closest_hit_with(ray, t_max, intersect, &mut ())
    }

    /// [`Bvh::closest_hit`] inlined into its caller and compiled for the caller's instruction
    /// set, for callers that run through [`math::isa::dispatch`] themselves (`Scene::intersect`,
    /// so that the hit's surface data is compiled for the same set as the query).
    #[inline(always)]
    pub fn closest_hit_inline(
        &self,
        ray: &Ray,
        t_max: f32,
        intersect: impl FnMut(u32, &Ray, f32) -> Option<f32>,
    ) -> Option<(u32, f32)> {
        self.closest_hit_octants(ray, t_max, intersect, &mut ())
    }

    /// [`Bvh::closest_hit`] that also adds the work it did to `counts`.
    pub fn closest_hit_counted(
        &self,
        ray: &Ray,
        t_max: f32,
        intersect: impl FnMut(u32, &Ray, f32) -> Option<f32>,
        counts: &mut TraversalCounts,
    ) -> Option<(u32, f32)> {
        self.closest_hit_with(ray, t_max, intersect, counts)
    }

    /// Whether anything blocks `ray` before `t_max` (shadow rays); stops at the first blocker.
    ///
    /// Calls `occluded(prim, ray, t_max)`, which must return true if the primitive intersects
    /// the ray at some `t` in `(0, t_max)` (not for the plain triangles of
    /// [`Bvh::build_with_triangles`], which are tested without it).
    #[inline]
    pub fn any_hit(&self, ray: &Ray, t_max: f32, occluded: impl FnMut(u32, &Ray, f32) -> bool) -> bool {
        self.any_hit_with(ray, t_max, occluded, &mut ())
    }

    /// [`Bvh::any_hit`] that also adds the work it did to `counts`.
    pub fn any_hit_counted(
        &self,
        ray: &Ray,
        t_max: f32,
        occluded: impl FnMut(u32, &Ray, f32) -> bool,
        counts: &mut TraversalCounts,
    ) -> bool {
        self.any_hit_with(ray, t_max, occluded, counts)
    }
}
