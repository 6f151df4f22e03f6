//! Leaves of plain triangles stored as one block of four lanes, tested against a ray at once.
//!
//! A leaf whose primitives are all triangles that the caller marked as plain (no alpha mask, no
//! other test after the geometric one; see [`super::Bvh::build_with_triangles`]) gets a
//! [`TriangleBlock`]: per lane the first vertex and both edges, as structure of arrays. The
//! traversal tests all four lanes with one Möller–Trumbore test on glam's `Vec4` (one SSE
//! instruction per step on x86-64, scalar code elsewhere; no `unsafe` here), without calling the
//! caller's closure. (Plain loops over `[f32; 4]`, as in `ray_box.rs`, do not work for a formula
//! this long: the vectoriser packs the x, y, z components of one lane instead of the four lanes,
//! and the test cost more instructions than four scalar ones.)
//!
//! Exactness: each lane performs exactly the operations of [`Triangle::intersect`] in the same
//! order on the same values (the edges `p1 − p0` and `p2 − p0` are rounded once when the block
//! is built, as `Triangle::intersect` rounds them at every call), so a lane reports a hit if and
//! only if `Triangle::intersect` does, at the bit-identical distance.

use glam::Vec4;
use math::Ray;

use super::ray_box::RayBox;
use super::wide::{WIDTH, WideNode};
use crate::shape::Triangle;

/// [`WideNode::meta`] flag of a leaf stored as a [`TriangleBlock`]: `meta = TRIANGLES | k` for a
/// leaf of `k` triangles whose block index is in [`WideNode::child`]. Interior children
/// (`meta = u32::MAX`) have the flag set too, so they are told apart first.
pub(super) const TRIANGLES: u32 = 1 << 31;

// A leaf fits in one block.
/// Lanes of a triangle block.
pub(super) const LANES: usize = 4;

const _: () = assert!(super::build::MAX_LEAF_SIZE <= LANES);

/// Up to [`LANES`] triangles of one leaf: `p0[axis]` (the lanes), `edge1 = p1 − p0`,
/// `edge2 = p2 − p0`, and the primitive id of each lane. An unused lane has zero edges (its
/// determinant is 0, so it is never hit) and id `u32::MAX`.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub(super) struct TriangleBlock {
    p0: [Vec4; 3],
    edge1: [Vec4; 3],
    edge2: [Vec4; 3],
    pub(super) ids: [u32; LANES],
}

/// The ray's origin and direction, each component broadcast to the four lanes.
pub(super) struct RayLanes {
    origin: [Vec4; 3],
    direction: [Vec4; 3],
}

impl RayLanes {
    #[cfg(test)]
    pub(super) fn new(ray: &Ray) -> Self {
        let (o, d) = (ray.origin, ray.direction);
        Self {
            origin: [Vec4::splat(o.x), Vec4::splat(o.y), Vec4::splat(o.z)],
            direction: [Vec4::splat(d.x), Vec4::splat(d.y), Vec4::splat(d.z)],
        }
    }

    /// [`RayLanes::new`] with the origin lanes taken from the slab test's, which holds the same
    /// values (the compiler does not see that and would splat and keep them twice).
    #[inline(always)]
    pub(super) fn sharing_origin(test: &RayBox, ray: &Ray) -> Self {
        let d = ray.direction;
        Self { origin: test.origin, direction: [Vec4::splat(d.x), Vec4::splat(d.y), Vec4::splat(d.z)] }
    }
}

impl TriangleBlock {
    /// The block of `triangles` (at most [`LANES`], each with its primitive id), lane by lane.
    pub(super) fn new(triangles: &[(u32, Triangle)]) -> Self {
        let zero = [Vec4::splat(0.0); 3];
        let mut block = TriangleBlock { p0: zero, edge1: zero, edge2: zero, ids: [u32::MAX; LANES] };
        for (lane, (id, triangle)) in triangles.iter().enumerate() {
            let (p0, edge1, edge2) = (triangle.p0, triangle.edge1(), triangle.edge2());
            for axis in 0..3 {
                block.p0[axis][lane] = p0[axis];
                block.edge1[axis][lane] = edge1[axis];
                block.edge2[axis][lane] = edge2[axis];
            }
            block.ids[lane] = *id;
        }
        block
    }

    /// Per lane, the distance `t > 0` at which the ray hits the lane's triangle (both sides), or
    /// `+∞` for a miss; the caller compares with its own `t_max` (a hit needs `t < t_max`, which
    /// `+∞` never is). The operations are those of [`Triangle::intersect`] (module doc).
    #[inline(always)]
    pub(super) fn distances(&self, ray: &RayLanes) -> Vec4 {
        let ([ox, oy, oz], [dx, dy, dz]) = (ray.origin, ray.direction);
        let ([p0x, p0y, p0z], [e1x, e1y, e1z], [e2x, e2y, e2z]) = (self.p0, self.edge1, self.edge2);
        // pvec = d × edge2, det = edge1 · pvec.
        let px = dy * e2z - e2y * dz;
        let py = dz * e2x - e2z * dx;
        let pz = dx * e2y - e2x * dy;
        let det = e1x * px + e1y * py + e1z * pz;
        let inv_det = det.recip();
        // tvec = o − p0, u = (tvec · pvec) / det.
        let (tx, ty, tz) = (ox - p0x, oy - p0y, oz - p0z);
        let u = (tx * px + ty * py + tz * pz) * inv_det;
        // qvec = tvec × edge1, v = (d · qvec) / det, t = (edge2 · qvec) / det.
        let qx = ty * e1z - e1y * tz;
        let qy = tz * e1x - e1z * tx;
        let qz = tx * e1y - e1x * ty;
        let v = (dx * qx + dy * qy + dz * qz) * inv_det;
        let t = (e2x * qx + e2y * qy + e2z * qz) * inv_det;
        let (zero, one) = (Vec4::ZERO, Vec4::ONE);
        let hit = det.cmpne(zero)
            & det.is_finite_mask()
            & u.cmpge(zero)
            & u.cmple(one)
            & !(v.cmplt(zero) | (u + v).cmpgt(one))
            & t.cmpgt(zero);
        Vec4::select(hit, t, Vec4::INFINITY)
    }
}

/// Replaces every leaf child of `nodes` whose primitives all have a triangle (`triangle(id)`
/// is `Some`) by a [`TriangleBlock`] (`meta = TRIANGLES | k`, `child` = block index); returns
/// the blocks, in the order of the nodes.
pub(super) fn gather(
    nodes: &mut [WideNode],
    prims: &[u32],
    triangle: impl Fn(u32) -> Option<Triangle>,
) -> Vec<TriangleBlock> {
    let mut blocks = Vec::new();
    for node in nodes {
        for lane in 0..WIDTH {
            let (meta, child) = (node.meta[lane], node.child[lane]);
            if meta == 0 || meta as usize > LANES {
                continue;
            }
            let ids = if meta == 1 { std::slice::from_ref(&child) } else { &prims[child as usize..][..meta as usize] };
            let triangles: Option<Vec<(u32, Triangle)>> = ids.iter().map(|&id| Some((id, triangle(id)?))).collect();
            if let Some(triangles) = triangles {
                node.meta[lane] = TRIANGLES | meta;
                node.child[lane] = blocks.len() as u32;
                blocks.push(TriangleBlock::new(&triangles));
            }
        }
    }
    blocks
}
