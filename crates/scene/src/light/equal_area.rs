//! Clarberg's equal-area octahedral map between the unit square and the unit sphere (pbrt-v4's
//! `EqualAreaSquareToSphere` and its inverse): the square's centre maps to +z, its corners to
//! −z, its edges' midpoints to the equator's ±x and ±y; equal areas of the square map to equal
//! solid angles, so a density `p` per unit square is `p/(4π)` per steradian.

use math::{PI, Vec2, Vec3};

/// The unit direction of the square point `p ∈ [0, 1]²`.
pub fn square_to_sphere(p: Vec2) -> Vec3 {
    let (u, v) = (2.0 * p.x - 1.0, 2.0 * p.y - 1.0);
    let (up, vp) = (u.abs(), v.abs());
    // Signed distance from the square's diagonal edges |u| + |v| = 1 (positive inside: +z).
    let signed_distance = 1.0 - (up + vp);
    let r = 1.0 - signed_distance.abs();
    // The azimuth in eighths of a turn (π/4 each), within the first quadrant.
    let eighths = if r == 0.0 { 1.0 } else { (vp - up) / r + 1.0 };
    let (sin_phi, cos_phi) = math::sin_cos_turns(0.125 * eighths);
    let z = (1.0 - r * r).copysign(signed_distance);
    let s = r * (2.0 - r * r).max(0.0).sqrt();
    Vec3::new(cos_phi.copysign(u) * s, sin_phi.copysign(v) * s, z)
}

/// The square point in `[0, 1]²` of the unit direction `d` (the inverse of
/// [`square_to_sphere`]).
pub fn sphere_to_square(d: Vec3) -> Vec2 {
    let (x, y, z) = (d.x.abs(), d.y.abs(), d.z.abs());
    let r = (1.0 - z).max(0.0).sqrt();
    let a = x.max(y);
    let b = if a == 0.0 { 0.0 } else { x.min(y) / a };
    let mut phi = b.atan() * (2.0 / PI);
    if x < y {
        phi = 1.0 - phi;
    }
    let (mut u, mut v) = (r - phi * r, phi * r);
    if d.z < 0.0 {
        (u, v) = (1.0 - v, 1.0 - u);
    }
    Vec2::new((u.copysign(d.x) + 1.0) * 0.5, (v.copysign(d.y) + 1.0) * 0.5)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn landmarks_and_round_trips() {
        let close = |a: Vec3, b: Vec3| (a - b).length() < 1e-5;
        assert!(close(square_to_sphere(Vec2::new(0.5, 0.5)), Vec3::Z));
        assert!(close(square_to_sphere(Vec2::new(0.0, 0.0)), -Vec3::Z));
        assert!(close(square_to_sphere(Vec2::new(1.0, 0.5)), Vec3::X));
        assert!(close(square_to_sphere(Vec2::new(0.5, 1.0)), Vec3::Y));
        assert!(close(square_to_sphere(Vec2::new(0.0, 0.5)), -Vec3::X));
        let mut worst = 0.0f32;
        for i in 0..64 {
            for j in 0..64 {
                let p = Vec2::new((i as f32 + 0.37) / 64.0, (j as f32 + 0.61) / 64.0);
                let d = square_to_sphere(p);
                assert!((d.length() - 1.0).abs() < 1e-5, "{p} -> {d}");
                worst = worst.max((sphere_to_square(d) - p).length());
            }
        }
        assert!(worst < 1e-4, "round trip error {worst}");
    }

    #[test]
    fn equal_areas_map_to_equal_solid_angles() {
        // Midpoints of a uniform grid on the square are uniform on the sphere: E[z] = 0 and
        // E[z²] = E[x²] = 1/3 (midpoint-rule error ~1/n²).
        let n = 200;
        let (mut z, mut z2, mut x2) = (0.0f64, 0.0f64, 0.0f64);
        for i in 0..n {
            for j in 0..n {
                let d = square_to_sphere(Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32));
                z += f64::from(d.z);
                z2 += f64::from(d.z * d.z);
                x2 += f64::from(d.x * d.x);
            }
        }
        let m = f64::from(n * n);
        assert!((z / m).abs() < 1e-3);
        assert!((z2 / m - 1.0 / 3.0).abs() < 1e-3, "{}", z2 / m);
        assert!((x2 / m - 1.0 / 3.0).abs() < 1e-3, "{}", x2 / m);
    }
}
