//! The slab test of one ray against the child boxes of a wide node, four lanes at a time.
//!
//! Written with glam's `Vec4`, so that each step is one SSE instruction (`subps`, `mulps`,
//! `maxps`, `minps`, `cmpps`); no `unsafe` intrinsics in our code.

use glam::Vec4;
use math::Ray;

use super::wide::{WIDTH, WideNode};

/// Factor by which a box's exit distance is enlarged so that rounding in the slab test can
/// never reject a box the ray touches (Ize 2013: `1 + 2γ₃`, rounded up).
pub(super) const ROBUST_EXIT: f32 = 1.0 + 4.0 * f32::EPSILON;

/// Ray data precomputed for the slab test, each component splatted over four lanes.
pub(super) struct RayBox {
    /// The ray's origin, each component splatted.
    pub(super) origin: [Vec4; 3],
    inverse_direction: [Vec4; 3],
}

/// The octant of `ray`'s direction: bit `axis` is set when that component's sign bit is set,
/// i.e. when the near plane of that axis is a box's upper corner (the lower one otherwise).
///
/// The queries are compiled once per octant ([`RayBox::entries`] takes it as a constant), so
/// that the slab test reads its planes at fixed offsets: with the octant a per-ray variable, the
/// six plane offsets did not fit in registers and were reloaded and scaled at every node.
#[inline(always)]
pub(super) fn octant(ray: &Ray) -> usize {
    let d = ray.direction;
    d.x.is_sign_negative() as usize | (d.y.is_sign_negative() as usize) << 1 | (d.z.is_sign_negative() as usize) << 2
}

impl RayBox {
    #[inline(always)]
    pub(super) fn new(ray: &Ray) -> Self {
        let d = ray.direction;
        // Zero components give ±∞ (by the sign of the zero), which the slab test handles.
        let inverse = [1.0 / d.x, 1.0 / d.y, 1.0 / d.z];
        let o = ray.origin;
        Self {
            origin: [Vec4::splat(o.x), Vec4::splat(o.y), Vec4::splat(o.z)],
            inverse_direction: inverse.map(Vec4::splat),
        }
    }

    /// Per lane, the distance at which the ray enters the child box within `(0, t_max]`, or
    /// `+∞` when it misses the box. `OCTANT` must be the ray's [`octant`].
    ///
    /// A zero direction component makes the plane distance `±∞`, or NaN (`0·∞`) when the origin
    /// lies on the plane; the comparisons below are written so that a NaN never wins, i.e. the
    /// ray counts as inside that slab, which is the correct answer for an origin on the plane.
    #[inline(always)]
    pub(super) fn entries<const OCTANT: usize>(&self, node: &WideNode, t_max: f32) -> [f32; WIDTH] {
        let mut out = [0.0; WIDTH];
        for (half, out) in out.chunks_exact_mut(4).enumerate() {
            let mut t_enter = Vec4::ZERO;
            let mut t_exit = Vec4::splat(t_max);
            for axis in 0..3 {
                let near_corner = (OCTANT >> axis) & 1;
                let near = Vec4::from_slice(&node.slabs[axis][near_corner][4 * half..]);
                let far = Vec4::from_slice(&node.slabs[axis][near_corner ^ 1][4 * half..]);
                let (origin, inverse) = (self.origin[axis], self.inverse_direction[axis]);
                let t_near = (near - origin) * inverse;
                let t_far = (far - origin) * inverse;
                // Per lane `if t_near > t_enter { t_near } else { t_enter }` (one `maxps`, whose
                // second operand wins on NaN and on equality), and the same for the exit with
                // `<` (`minps`): a NaN plane distance is ignored. `t_enter` and `t_exit` are
                // never NaN.
                t_enter = t_near.max(t_enter);
                t_exit = t_far.min(t_exit);
            }
            let hit = t_enter.cmple(t_exit * ROBUST_EXIT);
            out.copy_from_slice(&Vec4::select(hit, t_enter, Vec4::INFINITY).to_array());
        }
        out
    }
}
