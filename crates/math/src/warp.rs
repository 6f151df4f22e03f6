//! Warps from the unit square to domains used in rendering, each with its density and its
//! inverse (`warp(inverse(x)) == x`). Densities on the sphere are per unit solid angle; densities
//! on discs and triangles are per unit area.

use crate::{INV_PI, PI, sin_cos_turns};
use glam::{Vec2, Vec3};

/// Cosine-weighted direction on the +z hemisphere. Density `cos θ / π` per steradian.
#[inline]
pub fn cosine_hemisphere(u: [f32; 2]) -> Vec3 {
    let (sin_phi, cos_phi) = sin_cos_turns(u[0]);
    let r = (1.0 - u[1]).max(0.0).sqrt();
    Vec3::new(cos_phi * r, sin_phi * r, u[1].sqrt())
}

/// Density of [`cosine_hemisphere`] per steradian for a direction with local `cos θ`
/// (0 below the hemisphere).
#[inline]
pub fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    cos_theta.max(0.0) * INV_PI
}

/// Inverse of [`cosine_hemisphere`].
#[inline]
pub fn cosine_hemisphere_inverse(d: Vec3) -> [f32; 2] {
    [azimuth_fraction(d), d.z * d.z]
}

/// Direction around +z distributed as `cosⁿ α` (α the angle to +z) over the whole sphere:
/// density `(n+1)/(2π)·cosⁿ α` per steradian on the +z hemisphere, 0 elsewhere.
#[inline]
pub fn power_cosine(u: [f32; 2], exponent: f32) -> Vec3 {
    let (sin_phi, cos_phi) = sin_cos_turns(u[0]);
    let cos_theta = u[1].powf(1.0 / (exponent + 1.0));
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    Vec3::new(cos_phi * sin_theta, sin_phi * sin_theta, cos_theta)
}

/// Density of [`power_cosine`] per steradian at local `cos α`.
#[inline]
pub fn power_cosine_pdf(cos_alpha: f32, exponent: f32) -> f32 {
    if cos_alpha <= 0.0 { 0.0 } else { (exponent + 1.0) * (0.5 * INV_PI) * cos_alpha.powf(exponent) }
}

/// Inverse of [`power_cosine`].
#[inline]
pub fn power_cosine_inverse(d: Vec3, exponent: f32) -> [f32; 2] {
    [azimuth_fraction(d), d.z.max(0.0).powf(exponent + 1.0)]
}

/// Uniform direction on the unit sphere. Density `1/(4π)` per steradian.
#[inline]
pub fn uniform_sphere(u: [f32; 2]) -> Vec3 {
    let (sin_phi, cos_phi) = sin_cos_turns(u[0]);
    let z = 1.0 - 2.0 * u[1];
    let r = (1.0 - z * z).max(0.0).sqrt();
    Vec3::new(cos_phi * r, sin_phi * r, z)
}

/// Density of [`uniform_sphere`]: `1/(4π)` per steradian.
pub const UNIFORM_SPHERE_PDF: f32 = 0.25 * INV_PI;

/// Inverse of [`uniform_sphere`].
#[inline]
pub fn uniform_sphere_inverse(d: Vec3) -> [f32; 2] {
    [azimuth_fraction(d), 0.5 * (1.0 - d.z)]
}

/// Point on the unit disc by the concentric map (Shirley & Chiu 1997). Density `1/π` per unit
/// area.
#[inline]
pub fn concentric_disc(u: [f32; 2]) -> Vec2 {
    let a = 2.0 * u[0] - 1.0;
    let b = 2.0 * u[1] - 1.0;
    if a == 0.0 && b == 0.0 {
        return Vec2::ZERO;
    }
    // The angle in turns: π/4 is an eighth of a turn. Written as selects around one division
    // (the operations of the two branches, so the same bits): which coordinate is larger is a
    // coin flip, a branch mispredicted half the time.
    let (a2, b2) = (a * a, b * b);
    let (r, minor) = (select_greater(a2, b2, a, b), select_greater(a2, b2, b, a));
    let t = minor / r;
    let turns = select_greater(a2, b2, 0.125 * t, 0.25 - 0.125 * t);
    let (sin_phi, cos_phi) = sin_cos_turns(turns);
    Vec2::new(r * cos_phi, r * sin_phi)
}

/// `if x > y { if_greater } else { otherwise }` for non-negative, non-NaN `x` and `y`, computed
/// on the bits (such floats order like their bit patterns) so that the compiler keeps it free of
/// branches: for a comparison that is a coin flip, where a branch would be mispredicted half
/// the time. (A `bool` condition turned into a mask was compiled back into a branch.)
#[inline]
fn select_greater(x: f32, y: f32, if_greater: f32, otherwise: f32) -> f32 {
    // All ones when y's bits are below x's: the difference of two patterns in [0, 2³¹) cannot
    // overflow.
    let mask = ((y.to_bits() as i32).wrapping_sub(x.to_bits() as i32) >> 31) as u32;
    let (g, o) = (if_greater.to_bits(), otherwise.to_bits());
    f32::from_bits(o ^ ((g ^ o) & mask))
}

/// Density of [`concentric_disc`]: `1/π` per unit area.
pub const CONCENTRIC_DISC_PDF: f32 = INV_PI;

/// Inverse of [`concentric_disc`].
#[inline]
pub fn concentric_disc_inverse(p: Vec2) -> [f32; 2] {
    let r = p.length();
    if r == 0.0 {
        return [0.5, 0.5];
    }
    let mut phi = p.y.atan2(p.x);
    if phi < -PI / 4.0 {
        phi += 2.0 * PI;
    }
    let (a, b) = if phi < PI / 4.0 {
        (r, r * phi / (PI / 4.0))
    } else if phi < 3.0 * PI / 4.0 {
        (r * (PI / 2.0 - phi) / (PI / 4.0), r)
    } else if phi < 5.0 * PI / 4.0 {
        (-r, -r * (phi - PI) / (PI / 4.0))
    } else {
        (-r * (3.0 * PI / 2.0 - phi) / (PI / 4.0), -r)
    };
    [0.5 * (a + 1.0), 0.5 * (b + 1.0)]
}

/// Uniform barycentric coordinates `(b1, b2)` on a triangle (the point is
/// `p0 + b1·(p1−p0) + b2·(p2−p0)`). Density `1/area` per unit area.
#[inline]
pub fn uniform_triangle(u: [f32; 2]) -> Vec2 {
    let s = u[0].sqrt();
    Vec2::new(1.0 - s, u[1] * s)
}

/// Inverse of [`uniform_triangle`].
#[inline]
pub fn uniform_triangle_inverse(b: Vec2) -> [f32; 2] {
    let s = 1.0 - b.x;
    [s * s, if s > 0.0 { b.y / s } else { 0.0 }]
}

/// A point of `[0, 1]` with density proportional to `(1 − x)·v0 + x·v1` (`v0, v1 ≥ 0`, not both
/// zero; `u` itself when both are zero). The density per unit length is
/// [`linear_pdf`]`(x, v0, v1)`; the map inverts the cumulative distribution
/// `F(x) = (v0·x + (v1 − v0)·x²/2) / ((v0 + v1)/2)` in a form without cancellation.
#[inline]
pub fn linear(u: f32, v0: f32, v1: f32) -> f32 {
    let sum = v0 + v1;
    if sum.is_nan() || sum <= 0.0 || v0 == v1 {
        return u;
    }
    // Roots of F(x) = u: x = u·(v0 + v1) / (v0 + √((1 − u)·v0² + u·v1²)).
    // The denominator is zero only for v0 = 0 and u = 0, whose root is x = 0.
    let denominator = v0 + ((1.0 - u) * v0 * v0 + u * v1 * v1).sqrt();
    if denominator > 0.0 { (u * sum / denominator).clamp(0.0, 1.0) } else { 0.0 }
}

/// Density per unit length of [`linear`] at `x ∈ [0, 1]`: `2·((1 − x)·v0 + x·v1) / (v0 + v1)`
/// (1 when both are zero).
#[inline]
pub fn linear_pdf(x: f32, v0: f32, v1: f32) -> f32 {
    let sum = v0 + v1;
    if sum.is_nan() || sum <= 0.0 {
        return 1.0;
    }
    2.0 * ((1.0 - x) * v0 + x * v1) / sum
}

/// A point of the unit square with density proportional to the bilinear interpolation of the
/// non-negative corner values `w = [w(0,0), w(1,0), w(0,1), w(1,1)]` (`w(x, y)`): `y` from its
/// marginal (linear between the mean of the `y = 0` corners and that of the `y = 1` corners),
/// then `x` from the conditional at that `y` (linear). Density per unit area:
/// [`bilinear_pdf`]. Uniform when all corners are zero.
#[inline]
pub fn bilinear(u: [f32; 2], w: [f32; 4]) -> Vec2 {
    let y = linear(u[1], w[0] + w[1], w[2] + w[3]);
    let x = linear(u[0], (1.0 - y) * w[0] + y * w[2], (1.0 - y) * w[1] + y * w[3]);
    Vec2::new(x, y)
}

/// Density per unit area of [`bilinear`] at `p ∈ [0, 1]²`: the bilinear interpolation of `w` at
/// `p` divided by the mean of the corners (1 when all are zero).
#[inline]
pub fn bilinear_pdf(p: Vec2, w: [f32; 4]) -> f32 {
    let sum = w[0] + w[1] + w[2] + w[3];
    if sum.is_nan() || sum <= 0.0 {
        return 1.0;
    }
    let top = (1.0 - p.x) * w[0] + p.x * w[1];
    let bottom = (1.0 - p.x) * w[2] + p.x * w[3];
    4.0 * ((1.0 - p.y) * top + p.y * bottom) / sum
}

/// The azimuth of `d` as a fraction of a full turn, in `[0, 1)`.
#[inline]
fn azimuth_fraction(d: Vec3) -> f32 {
    let mut phi = d.y.atan2(d.x);
    if phi < 0.0 {
        phi += 2.0 * PI;
    }
    let f = phi / (2.0 * PI);
    if f >= 1.0 { 0.0 } else { f }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn select_greater_is_the_comparison() {
        let values = [0.0f32, 1e-45, 1e-30, 0.25, 0.5, 1.0, 1.0 + f32::EPSILON, 3.0, 1e30, f32::MAX, f32::INFINITY];
        for &x in &values {
            for &y in &values {
                let want = if x > y { -7.5f32 } else { 2.0 };
                let got = select_greater(x, y, -7.5, 2.0);
                assert_eq!(got.to_bits(), want.to_bits(), "{x} > {y}");
                // The selected value's bits, signed zeros included.
                assert_eq!(select_greater(x, y, -0.0, 0.0).to_bits(), if x > y { 0x8000_0000 } else { 0 });
            }
        }
    }

    fn grid() -> impl Iterator<Item = [f32; 2]> {
        (1..20).flat_map(|i| (1..20).map(move |j| [i as f32 / 20.0, j as f32 / 20.0]))
    }

    fn close(a: [f32; 2], b: [f32; 2]) -> bool {
        (a[0] - b[0]).abs() < 2e-4 && (a[1] - b[1]).abs() < 2e-4
    }

    #[test]
    fn linear_inverts_its_cumulative_distribution() {
        // F(x(u)) = u for the closed-form F of the documentation, including one zero end.
        for (v0, v1) in [(1.0f32, 3.0f32), (3.0, 1.0), (0.0, 2.0), (2.0, 0.0), (1e-6, 5.0), (2.0, 2.0)] {
            for i in 0..=100 {
                let u = i as f32 / 100.0;
                let x = linear(u, v0, v1);
                assert!((0.0..=1.0).contains(&x), "{x}");
                let f = (v0 * x + (v1 - v0) * x * x / 2.0) / ((v0 + v1) / 2.0);
                assert!((f - u).abs() < 2e-6, "v = ({v0}, {v1}), u = {u}: F(x) = {f}");
            }
        }
        assert_eq!(linear(0.3, 0.0, 0.0), 0.3);
        assert_eq!(linear_pdf(0.3, 0.0, 0.0), 1.0);
        assert!((linear_pdf(0.25, 1.0, 3.0) - 2.0 * 1.5 / 4.0).abs() < 1e-6);
    }

    /// Chi-square of 200k [`bilinear`] points for the corners `sampled` in a 10 × 10 histogram
    /// against the integral of [`bilinear_pdf`] for the corners `expected` over each bin
    /// (midpoint rule on a 20 × 20 sub-grid: exact for a bilinear function).
    fn bilinear_chi2(sampled: [f32; 4], expected: [f32; 4]) -> f64 {
        let mut rng = crate::Rng::new(7, 11);
        let n = 200_000;
        let mut counts = [0u32; 100];
        for _ in 0..n {
            let p = bilinear(rng.uniform2(), sampled);
            assert!((0.0..=1.0).contains(&p.x) && (0.0..=1.0).contains(&p.y), "{p}");
            let (i, j) = (((p.x * 10.0) as usize).min(9), ((p.y * 10.0) as usize).min(9));
            counts[j * 10 + i] += 1;
        }
        let mut chi2 = 0.0f64;
        for (k, observed) in counts.iter().enumerate() {
            let (i, j) = (k % 10, k / 10);
            let mut integral = 0.0f64;
            for a in 0..20 {
                for b in 0..20 {
                    let x = (i as f32 + (a as f32 + 0.5) / 20.0) / 10.0;
                    let y = (j as f32 + (b as f32 + 0.5) / 20.0) / 10.0;
                    integral += bilinear_pdf(Vec2::new(x, y), expected) as f64 / 40_000.0;
                }
            }
            let expected = integral * n as f64;
            chi2 += (*observed as f64 - expected).powi(2) / expected.max(1e-9);
        }
        chi2
    }

    #[test]
    fn bilinear_matches_its_density_by_chi_square() {
        // Chi-square with 99 degrees of freedom: about 157 at p = 1e-4.
        for w in [[1.0f32, 4.0, 0.5, 2.0], [0.0, 0.0, 1.0, 3.0], [5.0, 0.0, 0.0, 1.0], [0.0; 4]] {
            let chi2 = bilinear_chi2(w, w);
            assert!(chi2 < 157.0, "w = {w:?}: chi-square {chi2}");
        }
        // Power: corners off by 10 % at one corner are detected.
        let chi2 = bilinear_chi2([1.0, 4.0, 0.5, 2.0], [1.0, 4.0, 0.5, 2.2]);
        assert!(chi2 > 157.0, "a 10 % error at one corner passed: chi-square {chi2}");
    }

    #[test]
    fn warps_invert() {
        for u in grid() {
            assert!(close(cosine_hemisphere_inverse(cosine_hemisphere(u)), u), "cosine {u:?}");
            assert!(close(power_cosine_inverse(power_cosine(u, 7.0), 7.0), u), "power {u:?}");
            assert!(close(uniform_sphere_inverse(uniform_sphere(u)), u), "sphere {u:?}");
            assert!(close(concentric_disc_inverse(concentric_disc(u)), u), "disc {u:?}");
            assert!(close(uniform_triangle_inverse(uniform_triangle(u)), u), "triangle {u:?}");
        }
    }

    #[test]
    fn warps_land_in_their_domain() {
        for u in grid() {
            assert!((cosine_hemisphere(u).length() - 1.0).abs() < 1e-5 && cosine_hemisphere(u).z >= 0.0);
            assert!((uniform_sphere(u).length() - 1.0).abs() < 1e-5);
            assert!(concentric_disc(u).length() <= 1.0 + 1e-6);
            let b = uniform_triangle(u);
            assert!(b.x >= 0.0 && b.y >= 0.0 && b.x + b.y <= 1.0 + 1e-6);
        }
    }
}
