//! Spatial and directional bounds of one light or a set of lights, and the importance bound
//! that [`crate::light_tree`] samples by ("Physically Based Rendering", 4th ed., §12.6.3).
//!
//! A [`LightBounds`] holds a box around the emitting points, a strength `phi`, a normal cone
//! (unit `axis`, `cos θ_o`: every emitting normal lies within θ_o of the axis) and an
//! emission spread (`cos θ_e`: light leaves at most θ_e away from its normal), and whether
//! the emitters are two-sided. The importance for a receiving point `p` with normal `n` is
//! an upper-bound-shaped estimate of the irradiance there:
//!
//! `phi · cos θ' / d² · cos θ'_i`
//!
//! with `d²` the squared distance to the box centre clamped below by half the box diagonal,
//! `θ' = max(0, θ_w − θ_o − θ_b)` (θ_w: angle between the axis and the direction to `p`; θ_b:
//! half-angle the box subtends at `p`), zero when `θ' ≥ θ_e`, and `θ'_i = max(0, θ_i − θ_b)`
//! the receiver's angle (`|cos|`: both sides of the surface; no factor when `n` is zero, a
//! point in a medium). It is zero only where no emitter of the set can send light to `p`.

use math::{Aabb, PI, Vec3};

/// Angle (radians) by which unions widen normal cones, so that rounding never makes a
/// parent's cone miss a child's normals.
const CONE_PAD: f32 = 1e-4;

/// Bounds of a set of lights (see the module).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightBounds {
    /// Box around every emitting point (scene units).
    pub bounds: Aabb,
    /// Strength: luminance of the mean radiant intensity times the solid angle factor that
    /// makes `phi / d²` an irradiance (W/sr; for surfaces `L·A`, W·sr⁻¹). Sums over a set.
    pub phi: f32,
    /// Unit axis of the normal cone (ignored when `cos_o` is −1).
    pub axis: Vec3,
    /// Cosine of the normal cone's half-angle θ_o (−1: every direction).
    pub cos_o: f32,
    /// Cosine of the emission spread θ_e beyond the normal cone (0: a hemisphere, π/2).
    pub cos_e: f32,
    /// Whether any emitter of the set emits from both sides.
    pub two_sided: bool,
}

impl LightBounds {
    /// Bounds that emit in every direction from `bounds` (points, goniometric lights, spheres).
    pub fn omnidirectional(bounds: Aabb, phi: f32) -> Self {
        Self { bounds, phi, axis: Vec3::Z, cos_o: -1.0, cos_e: 0.0, two_sided: false }
    }

    /// The union of two sets: box union, summed strength, a cone around both cones, the wider
    /// emission spread.
    pub fn union(&self, other: &LightBounds) -> LightBounds {
        let (axis, cos_o) = cone_union(self.axis, self.cos_o, other.axis, other.cos_o);
        LightBounds {
            bounds: self.bounds.union(other.bounds),
            phi: self.phi + other.phi,
            axis,
            cos_o,
            cos_e: self.cos_e.min(other.cos_e),
            two_sided: self.two_sided || other.two_sided,
        }
    }

    /// The importance of the set for a receiver at `p` with unit normal `n` (zero vector: no
    /// receiver cosine), see the module. Non-negative and finite.
    pub fn importance(&self, p: Vec3, n: Vec3) -> f32 {
        let center = self.bounds.center();
        let offset = p - center;
        let d2 = offset.length_squared().max(0.5 * self.bounds.extent().length()).max(1e-12);
        let wi = offset.normalize_or_zero();
        let mut cos_w = if wi == Vec3::ZERO { 1.0 } else { self.axis.dot(wi) };
        if self.two_sided {
            cos_w = cos_w.abs();
        }
        let sin_w = sin_of(cos_w);
        let cos_b = cos_subtended(&self.bounds, p);
        let sin_b = sin_of(cos_b);
        let sin_o = sin_of(self.cos_o);
        // θ_x = max(0, θ_w − θ_o), then θ' = max(0, θ_x − θ_b).
        let (cos_x, sin_x) = sub_clamped(cos_w, sin_w, self.cos_o, sin_o);
        let (cos_p, _) = sub_clamped(cos_x, sin_x, cos_b, sin_b);
        if cos_p <= self.cos_e {
            return 0.0;
        }
        let mut importance = self.phi * cos_p / d2;
        if n != Vec3::ZERO && wi != Vec3::ZERO {
            let cos_i = wi.dot(n).abs().min(1.0);
            let (cos_pi, _) = sub_clamped(cos_i, sin_of(cos_i), cos_b, sin_b);
            importance *= cos_pi;
        }
        if importance.is_finite() { importance.max(0.0) } else { 0.0 }
    }

    /// pbrt-v4's cost of a set for the tree's splits: `phi · M_Ω · surface area`, `M_Ω` the
    /// cosine-weighted solid angle of the cone θ_o widened by θ_e.
    pub fn cost(&self) -> f32 {
        let theta_o = self.cos_o.clamp(-1.0, 1.0).acos();
        let theta_e = self.cos_e.clamp(-1.0, 1.0).acos();
        let theta_w = (theta_o + theta_e).min(PI);
        let sin_o = theta_o.sin();
        let m_omega = 2.0 * PI * (1.0 - self.cos_o)
            + 0.5 * PI * (2.0 * theta_w * sin_o - (theta_o - 2.0 * theta_w).cos() - 2.0 * theta_o * sin_o + self.cos_o);
        let e = self.bounds.extent();
        // A flat or point box still costs by its strength.
        let area = 2.0 * (e.x * e.y + e.y * e.z + e.z * e.x) + 1e-12;
        self.phi * m_omega.max(0.0) * area
    }
}

/// `sin θ` from `cos θ`, for θ ∈ [0, π].
fn sin_of(cos: f32) -> f32 {
    (1.0 - cos * cos).max(0.0).sqrt()
}

/// `(cos, sin)` of `max(0, a − b)` from those of `a` and `b` (angles in [0, π]).
fn sub_clamped(cos_a: f32, sin_a: f32, cos_b: f32, sin_b: f32) -> (f32, f32) {
    if cos_a >= cos_b { (1.0, 0.0) } else { (cos_a * cos_b + sin_a * sin_b, sin_a * cos_b - cos_a * sin_b) }
}

/// Cosine of the half-angle of a cone from `p` that contains `bounds` (−1 when `p` is inside
/// the box or its bounding sphere).
fn cos_subtended(bounds: &Aabb, p: Vec3) -> f32 {
    if p.cmpge(bounds.min).all() && p.cmple(bounds.max).all() {
        return -1.0;
    }
    let (center, radius) = bounds.bounding_sphere();
    let d2 = (p - center).length_squared();
    let r2 = radius * radius;
    if d2 <= r2 {
        return -1.0;
    }
    (1.0 - r2 / d2).max(0.0).sqrt()
}

/// Angle between two unit vectors, accurate near 0 and π.
fn angle_between(a: Vec3, b: Vec3) -> f32 {
    if a.dot(b) < 0.0 {
        PI - 2.0 * ((a + b).length() * 0.5).min(1.0).asin()
    } else {
        2.0 * ((a - b).length() * 0.5).min(1.0).asin()
    }
}

/// The smallest cone (axis, cosine) around the cones `(a, cos_a)` and `(b, cos_b)`, widened by
/// [`CONE_PAD`].
fn cone_union(a: Vec3, cos_a: f32, b: Vec3, cos_b: f32) -> (Vec3, f32) {
    let (theta_a, theta_b) = (cos_a.clamp(-1.0, 1.0).acos(), cos_b.clamp(-1.0, 1.0).acos());
    let theta_d = angle_between(a, b);
    if (theta_d + theta_b).min(PI) <= theta_a {
        return (a, cos_a);
    }
    if (theta_d + theta_a).min(PI) <= theta_b {
        return (b, cos_b);
    }
    let theta_o = 0.5 * (theta_a + theta_d + theta_b) + CONE_PAD;
    let k = a.cross(b);
    if theta_o >= PI || k.length_squared() < 1e-12 {
        return (a, -1.0);
    }
    // Rotate `a` towards `b` about `k` by θ_o − θ_a (k ⟂ a, so Rodrigues' formula shortens).
    let k = k.normalize();
    let theta_r = theta_o - theta_a;
    let axis = (a * theta_r.cos() + k.cross(a) * theta_r.sin()).normalize();
    (axis, theta_o.cos())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cone_union_contains_both_cones() {
        let mut rng = math::Rng::new(3, 0);
        for _ in 0..2000 {
            let a = math::warp::uniform_sphere(rng.uniform2());
            let b = math::warp::uniform_sphere(rng.uniform2());
            let (ca, cb) = (rng.uniform() * 2.0 - 1.0, rng.uniform() * 2.0 - 1.0);
            let (w, c) = cone_union(a, ca, b, cb);
            // Each cone's boundary direction farthest from w lies within the union's cone.
            for (axis, cos) in [(a, ca), (b, cb)] {
                let theta = angle_between(w, axis) + cos.acos();
                assert!(theta.min(PI) <= c.acos() + 1e-3, "{theta} > {}", c.acos());
            }
        }
    }

    #[test]
    fn importance_is_zero_behind_a_one_sided_emitter_only() {
        let flat = LightBounds {
            bounds: Aabb::new(Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, 1.0, 0.0)),
            phi: 1.0,
            axis: Vec3::Z,
            cos_o: 1.0,
            cos_e: 0.0,
            two_sided: false,
        };
        assert!(flat.importance(Vec3::new(0.3, 0.2, 2.0), Vec3::ZERO) > 0.0);
        assert_eq!(flat.importance(Vec3::new(0.3, 0.2, -2.0), Vec3::ZERO), 0.0);
        // Beside the plane but above it: light can arrive at a grazing angle.
        assert!(flat.importance(Vec3::new(5.0, 0.0, 0.01), Vec3::ZERO) > 0.0);
        let two = LightBounds { two_sided: true, ..flat };
        assert!(two.importance(Vec3::new(0.3, 0.2, -2.0), Vec3::ZERO) > 0.0);
    }
}
