//! The anisotropic GGX (Trowbridge–Reitz) distribution: `D`, its exact Smith masking and the
//! sampling of visible normals (Heitz 2018, "Sampling the GGX Distribution of Visible
//! Normals", JCGT 7(4)). Directions are in the local frame of the macro surface (`z` normal);
//! `ax`, `ay` are the roughnesses along `x` and `y`.

use math::{INV_PI, Vec3, sqr};

/// `D(m) = 1 / (π αx αy (mx²/αx² + my²/αy² + mz²)²)` per unit solid angle, 0 below the surface.
#[inline]
pub(super) fn d(ax: f32, ay: f32, m: Vec3) -> f32 {
    if m.z <= 0.0 {
        return 0.0;
    }
    let t = sqr(m.x / ax) + sqr(m.y / ay) + sqr(m.z);
    let value = INV_PI / (ax * ay * sqr(t));
    if value.is_finite() { value } else { 0.0 }
}

/// Smith's `G1 = 1/(1 + Λ(w))`, `Λ = (√(1 + a²/cos²) − 1)/2` with `a² = (αx wx)² + (αy wy)²`,
/// written as `2|cos|/(|cos| + √(cos² + a²))`, which stays finite at the horizon. The caller
/// has checked the sides.
#[inline]
pub(super) fn g1(ax: f32, ay: f32, w: Vec3) -> f32 {
    let a2 = sqr(ax * w.x) + sqr(ay * w.y);
    let c = w.z.abs();
    2.0 * c / (c + (sqr(c) + a2).sqrt())
}

/// A normal from the distribution of normals visible from `w` (`w.z > 0`) with two uniform
/// numbers: stretch to the α = 1 configuration, sample the projected hemisphere, unstretch.
pub(super) fn sample_visible(ax: f32, ay: f32, w: Vec3, u: [f32; 2]) -> Vec3 {
    // Stretch the view direction to the configuration of the hemisphere (α = 1).
    let vh = Vec3::new(ax * w.x, ay * w.y, w.z).normalize();
    // Orthonormal basis around vh (T1 horizontal).
    let len2 = sqr(vh.x) + sqr(vh.y);
    let t1 = if len2 > 0.0 { Vec3::new(-vh.y, vh.x, 0.0) / len2.sqrt() } else { Vec3::X };
    let t2 = vh.cross(t1);
    // A point on the projected disc: a uniform disc whose lower half is squashed by the
    // projection of the hemisphere.
    let r = u[0].sqrt();
    let (sin_phi, cos_phi) = math::sin_cos_turns(u[1]);
    let p1 = r * cos_phi;
    let s = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - s) * (1.0 - sqr(p1)).max(0.0).sqrt() + s * r * sin_phi;
    let p3 = (1.0 - sqr(p1) - sqr(p2)).max(0.0).sqrt();
    let nh = p1 * t1 + p2 * t2 + p3 * vh;
    // Unstretch.
    Vec3::new(ax * nh.x, ay * nh.y, nh.z.max(0.0)).normalize()
}
