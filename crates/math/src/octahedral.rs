//! Unit vectors in 32 bits: the octahedral map (the sphere folded onto the square [−1, 1]²
//! through the octahedron |x| + |y| + |z| = 1), each square coordinate quantised to 16 bits.
//!
//! The encoder tries the four grid points around the exact square position and keeps the one
//! whose decoded direction is closest, so the error is the grid's, not the rounding's: the
//! largest angle between a unit vector and its decoded code is below
//! [`MAX_ANGULAR_ERROR`] radians (measured over 10⁶ random directions and the axes, diagonals
//! and near-seam directions by this module's tests).

use glam::{Vec2, Vec3, Vec4};

/// Upper bound of the angle (radians) between a unit vector and its decoded 32-bit code
/// (tested; the measured maximum is 4.3·10⁻⁵, 0.0025°).
pub const MAX_ANGULAR_ERROR: f32 = 5.0e-5;

/// Largest 16-bit code, the square coordinate +1.
const SCALE: f32 = 65535.0;

/// The octahedral square position of unit vector `v`, in [−1, 1]².
#[inline]
fn to_square(v: Vec3) -> Vec2 {
    let inv_l1 = 1.0 / (v.x.abs() + v.y.abs() + v.z.abs());
    let p = Vec2::new(v.x, v.y) * inv_l1;
    if v.z >= 0.0 {
        p
    } else {
        // Fold the lower hemisphere over the diagonals.
        Vec2::new((1.0 - p.y.abs()) * sign(p.x), (1.0 - p.x.abs()) * sign(p.y))
    }
}

/// The unit vector of square position `p` in [−1, 1]².
#[inline]
fn from_square(p: Vec2) -> Vec3 {
    unfold(p).normalize()
}

/// The point of the octahedron |x| + |y| + |z| = 1 at square position `p` (not normalised).
#[inline]
fn unfold(p: Vec2) -> Vec3 {
    let z = 1.0 - p.x.abs() - p.y.abs();
    let (x, y) = if z >= 0.0 { (p.x, p.y) } else { ((1.0 - p.y.abs()) * sign(p.x), (1.0 - p.x.abs()) * sign(p.y)) };
    Vec3::new(x, y, z)
}

/// +1 for non-negative values, −1 otherwise (0 folds like +0).
#[inline]
fn sign(x: f32) -> f32 {
    if x >= 0.0 { 1.0 } else { -1.0 }
}

/// The square coordinate of 16-bit code `c`.
#[inline]
fn coordinate(c: u32) -> f32 {
    c as f32 * (2.0 / SCALE) - 1.0
}

/// Decodes a 32-bit code made by [`encode`] into a unit vector.
#[inline]
pub fn decode(code: u32) -> Vec3 {
    from_square(Vec2::new(coordinate(code & 0xffff), coordinate(code >> 16)))
}

/// Encodes unit vector `v` (non-zero; it need not be normalised) in 32 bits: the best of the
/// four codes around its square position. A non-finite `v` encodes +z.
///
/// "Best" is the smallest angle to `v`, compared through `sin²θ = |d × v|² / (|d|² |v|²)` of
/// each candidate's unnormalised direction `d`: no square root, no normalisation, and no
/// cancellation (cosines this close to 1 would be equal in f32; the cross product of two nearly
/// parallel vectors is small but accurate to about 10⁻⁷ absolute, against sines of ≥ 10⁻⁵).
/// The candidates are compared by cross-multiplication, so there is no division either.
///
/// The four candidates are evaluated side by side, one per lane of a [`Vec4`], with the
/// operations (and their order) of `unfold`, [`Vec3::cross`] and [`Vec3::length_squared`]
/// lane by lane, so the code is the one a candidate-by-candidate loop picks, bit for bit.
#[inline]
pub fn encode(v: Vec3) -> u32 {
    if !v.is_finite() || v == Vec3::ZERO {
        return encode(Vec3::Z);
    }
    let p = (to_square(v) + 1.0) * (0.5 * SCALE);
    // `as` truncates towards zero and saturates (NaN to 0): on [0, 65535] that is the floor, and
    // below 0 and above 65535 it gives the clamped floor's 0 and 65535.
    let (x0, y0) = ((p.x as u32).min(65535), (p.y as u32).min(65535));
    let (x1, y1) = ((x0 + 1).min(65535), (y0 + 1).min(65535));
    // Candidates in lanes: (x0, y0), (x1, y0), (x0, y1), (x1, y1).
    let xs = [x0, x1, x0, x1];
    let ys = [y0, y0, y1, y1];
    let d = unfold4(coordinates(xs), coordinates(ys));
    let sine = cross_length_squared(d, v).to_array();
    let length = ((d[0] * d[0] + d[1] * d[1]) + d[2] * d[2]).to_array();
    // best = (|d × v|², |d|², code): candidate a beats b when a.0 · b.1 < b.0 · a.1.
    let mut best = (f32::INFINITY, 1.0, 0);
    for lane in 0..4 {
        if sine[lane] * best.1 < best.0 * length[lane] {
            best = (sine[lane], length[lane], xs[lane] | ys[lane] << 16);
        }
    }
    best.2
}

/// [`coordinate`] of four codes, one per lane.
#[inline]
fn coordinates(codes: [u32; 4]) -> Vec4 {
    Vec4::from_array(codes.map(|c| c as f32)) * (2.0 / SCALE) - 1.0
}

/// [`unfold`] of four square positions (x and y coordinates by lane): the octahedron points'
/// x, y and z components.
#[inline]
fn unfold4(x: Vec4, y: Vec4) -> [Vec4; 3] {
    let (ax, ay) = (x.abs(), y.abs());
    let z = Vec4::ONE - ax - ay;
    let sign = |c: Vec4| Vec4::select(c.cmpge(Vec4::ZERO), Vec4::ONE, Vec4::NEG_ONE);
    let upper = z.cmpge(Vec4::ZERO);
    let folded_x = (Vec4::ONE - ay) * sign(x);
    let folded_y = (Vec4::ONE - ax) * sign(y);
    [Vec4::select(upper, x, folded_x), Vec4::select(upper, y, folded_y), z]
}

/// `|d × v|²` of four vectors `d` (components by lane), as [`Vec3::cross`] and
/// [`Vec3::length_squared`] compute it.
#[inline]
fn cross_length_squared([dx, dy, dz]: [Vec4; 3], v: Vec3) -> Vec4 {
    let (vx, vy, vz) = (Vec4::splat(v.x), Vec4::splat(v.y), Vec4::splat(v.z));
    let cx = dy * vz - vy * dz;
    let cy = dz * vx - vz * dx;
    let cz = dx * vy - vx * dy;
    (cx * cx + cy * cy) + cz * cz
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Rng;

    fn angle(a: Vec3, b: Vec3) -> f32 {
        // atan2 of |a×b| and a·b is accurate for small angles (acos is not).
        a.cross(b).length().atan2(a.dot(b))
    }

    #[test]
    fn decoded_codes_are_within_the_stated_angle() {
        let mut rng = Rng::for_stream(3, 0, 0);
        let mut worst = 0.0f32;
        let mut check = |v: Vec3| {
            let v = v.normalize();
            let d = decode(encode(v));
            assert!((d.length() - 1.0).abs() < 1e-6);
            worst = worst.max(angle(v, d));
        };
        for _ in 0..1_000_000 {
            let (u, w) = (rng.uniform(), rng.uniform());
            let z = 1.0 - 2.0 * u;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = 2.0 * std::f32::consts::PI * w;
            check(Vec3::new(r * phi.cos(), r * phi.sin(), z));
        }
        // Axes, diagonals, and directions next to the fold (z ≈ 0) and the seams (x or y ≈ 0).
        for v in [Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X, -Vec3::Y, -Vec3::Z, Vec3::ONE, -Vec3::ONE] {
            check(v);
        }
        for e in [1e-7f32, 1e-5, 1e-3] {
            for (x, y) in [(1.0, 1.0), (-1.0, 1.0), (1.0, -1.0), (-1.0, -1.0), (e, 1.0), (1.0, e), (-e, -1.0)] {
                check(Vec3::new(x, y, e));
                check(Vec3::new(x, y, -e));
            }
        }
        assert!(worst < MAX_ANGULAR_ERROR, "largest angular error {worst} rad");
        // The bound is tight enough to mean something: the grid spacing is ~3e-5.
        assert!(worst > 0.25 * MAX_ANGULAR_ERROR, "largest angular error {worst} rad");
    }

    /// The encoder's definition, written plainly: the candidate whose normalised decoded
    /// direction is nearest to normalised `v` (distances, in f64).
    fn reference_encode(v: Vec3) -> u32 {
        let n = v.as_dvec3().normalize();
        let p = (to_square(v) + 1.0) * (0.5 * SCALE);
        let (x0, y0) = (p.x.floor().clamp(0.0, SCALE) as u32, p.y.floor().clamp(0.0, SCALE) as u32);
        let candidates = [(0, 0), (1, 0), (0, 1), (1, 1)].map(|(dx, dy)| ((x0 + dx).min(65535), (y0 + dy).min(65535)));
        let distance = |&(x, y): &(u32, u32)| {
            (unfold(Vec2::new(coordinate(x), coordinate(y))).as_dvec3().normalize() - n).length_squared()
        };
        let (x, y) = candidates.into_iter().min_by(|a, b| distance(a).total_cmp(&distance(b))).unwrap();
        x | y << 16
    }

    #[test]
    fn encoder_picks_the_nearest_candidate() {
        // The sin² comparison in f32 agrees with nearest-by-distance in f64, except where two
        // candidates are equally near to within f32 rounding (then either is within the bound).
        let mut rng = Rng::for_stream(5, 0, 0);
        let (mut differ, n) = (0, 200_000);
        for _ in 0..n {
            let (u, w) = (rng.uniform(), rng.uniform());
            let z = 1.0 - 2.0 * u;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = 2.0 * std::f32::consts::PI * w;
            let v = Vec3::new(r * phi.cos(), r * phi.sin(), z) * (0.5 + w);
            let (fast, slow) = (encode(v), reference_encode(v));
            if fast != slow {
                differ += 1;
                let n = v.normalize();
                let gap = (decode(fast) - n).length() - (decode(slow) - n).length();
                assert!(gap.abs() < 2e-6, "{v}: codes {fast:#x} / {slow:#x} differ by {gap}");
            }
        }
        assert!(differ < n / 1000, "{differ} of {n} codes differ from the nearest candidate");
    }

    /// The encoder as a loop over the candidates, one at a time (the lane-parallel [`encode`]
    /// must pick the same code, bit for bit).
    fn one_at_a_time_encode(v: Vec3) -> u32 {
        if !v.is_finite() || v == Vec3::ZERO {
            return one_at_a_time_encode(Vec3::Z);
        }
        let p = (to_square(v) + 1.0) * (0.5 * SCALE);
        let (x0, y0) = (p.x.floor().clamp(0.0, SCALE) as u32, p.y.floor().clamp(0.0, SCALE) as u32);
        let mut best = (f32::INFINITY, 1.0, 0);
        for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
            let (x, y) = ((x0 + dx).min(65535), (y0 + dy).min(65535));
            let d = unfold(Vec2::new(coordinate(x), coordinate(y)));
            let (sine, length) = (d.cross(v).length_squared(), d.length_squared());
            if sine * best.1 < best.0 * length {
                best = (sine, length, x | y << 16);
            }
        }
        best.2
    }

    #[test]
    fn lanes_pick_the_code_of_the_one_at_a_time_loop() {
        let mut rng = Rng::for_stream(7, 0, 0);
        let check = |v: Vec3| assert_eq!(encode(v), one_at_a_time_encode(v), "{v}");
        for _ in 0..1_000_000 {
            let (u, w) = (rng.uniform(), rng.uniform());
            let z = 1.0 - 2.0 * u;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = 2.0 * std::f32::consts::PI * w;
            check(Vec3::new(r * phi.cos(), r * phi.sin(), z) * (0.25 + 4.0 * rng.uniform()));
        }
        let tiny = f32::MIN_POSITIVE * 1e-3;
        for v in [Vec3::X, Vec3::Y, Vec3::Z, -Vec3::X, -Vec3::Y, -Vec3::Z, Vec3::ONE, -Vec3::ONE, Vec3::ZERO] {
            check(v);
        }
        for e in [0.0, tiny, 1e-7f32, 1e-5, 1e-3] {
            for (x, y) in [(1.0, 1.0), (-1.0, 1.0), (1.0, -1.0), (-1.0, -1.0), (e, 1.0), (1.0, e), (-e, -1.0)] {
                check(Vec3::new(x, y, e));
                check(Vec3::new(x, y, -e));
                check(Vec3::new(x * tiny, y * tiny, e));
            }
        }
        for v in [Vec3::new(f32::NAN, 0.0, 1.0), Vec3::splat(f32::INFINITY), Vec3::new(f32::MAX, f32::MAX, 1.0)] {
            check(v);
        }
    }

    #[test]
    fn degenerate_input_encodes_plus_z() {
        assert_eq!(decode(encode(Vec3::ZERO)), decode(encode(Vec3::Z)));
        assert_eq!(decode(encode(Vec3::new(f32::NAN, 0.0, 1.0))), decode(encode(Vec3::Z)));
    }
}
