//! The slab test of one ray against the four child boxes of a wide node at once.
//!
//! Written lane by lane over `[f32; 4]` arrays without branches, so that the compiler turns each
//! step into one SSE instruction (`subps`, `mulps`, `maxps`, `minps`, `cmpps`); no `unsafe`
//! intrinsics.

use math::Ray;

use super::wide::{WIDTH, WideNode};

/// Factor by which a box's exit distance is enlarged so that rounding in the slab test can
/// never reject a box the ray touches (Ize 2013: `1 + 2γ₃`, rounded up).
pub(super) const ROBUST_EXIT: f32 = 1.0 + 4.0 * f32::EPSILON;

/// Ray data precomputed for the slab test.
pub(super) struct RayBox {
    origin: [f32; 3],
    inverse_direction: [f32; 3],
    /// Per axis, the corner (0 = lower, 1 = upper) that holds the near plane: the lower one when
    /// the direction component's sign bit is clear.
    near: [usize; 3],
}

impl RayBox {
    #[inline(always)]
    pub(super) fn new(ray: &Ray) -> Self {
        let d = ray.direction;
        // Zero components give ±∞ (by the sign of the zero), which the slab test handles.
        let inverse_direction = [1.0 / d.x, 1.0 / d.y, 1.0 / d.z];
        let near = [d.x.is_sign_negative() as usize, d.y.is_sign_negative() as usize, d.z.is_sign_negative() as usize];
        Self { origin: ray.origin.to_array(), inverse_direction, near }
    }

    /// Per lane, the distance at which the ray enters the child box within `(0, t_max]`, or
    /// `+∞` when it misses the box.
    ///
    /// A zero direction component makes the plane distance `±∞`, or NaN (`0·∞`) when the origin
    /// lies on the plane; the comparisons below are written so that a NaN never wins, i.e. the
    /// ray counts as inside that slab, which is the correct answer for an origin on the plane.
    #[inline(always)]
    pub(super) fn entries(&self, node: &WideNode, t_max: f32) -> [f32; WIDTH] {
        let mut t_enter = [0.0f32; WIDTH];
        let mut t_exit = [t_max; WIDTH];
        for axis in 0..3 {
            let near_corner = self.near[axis] & 1;
            let near = &node.corners[near_corner][axis];
            let far = &node.corners[near_corner ^ 1][axis];
            let (origin, inverse) = (self.origin[axis], self.inverse_direction[axis]);
            for lane in 0..WIDTH {
                let t_near = (near[lane] - origin) * inverse;
                let t_far = (far[lane] - origin) * inverse;
                // `x > acc` is false for NaN x, so NaN is ignored (this is `maxps(x, acc)`).
                t_enter[lane] = if t_near > t_enter[lane] { t_near } else { t_enter[lane] };
                t_exit[lane] = if t_far < t_exit[lane] { t_far } else { t_exit[lane] };
            }
        }
        let mut result = [f32::INFINITY; WIDTH];
        for lane in 0..WIDTH {
            result[lane] = if t_enter[lane] <= t_exit[lane] * ROBUST_EXIT { t_enter[lane] } else { f32::INFINITY };
        }
        result
    }
}
