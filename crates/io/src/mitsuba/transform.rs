//! 4×4 affine transforms in double precision, as Mitsuba's `<transform>` builds them.

use math::Vec3;

/// A 4×4 matrix, row-major: `m[row][column]`. Points are column vectors (`p' = M·p`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Mat4 {
    /// Rows.
    pub m: [[f64; 4]; 4],
}

impl Mat4 {
    /// The identity.
    pub const IDENTITY: Mat4 =
        Mat4 { m: [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]] };

    /// A translation by `t`.
    pub fn translate(t: [f64; 3]) -> Mat4 {
        let mut r = Mat4::IDENTITY;
        for (i, v) in t.iter().enumerate() {
            r.m[i][3] = *v;
        }
        r
    }

    /// The affine map taking the unit axes to `x`, `y`, `z` and the origin to `origin`.
    pub fn from_columns(x: [f64; 3], y: [f64; 3], z: [f64; 3], origin: [f64; 3]) -> Mat4 {
        let mut r = Mat4::IDENTITY;
        for row in 0..3 {
            r.m[row] = [x[row], y[row], z[row], origin[row]];
        }
        r
    }

    /// A scale by `s` along the axes.
    pub fn scale(s: [f64; 3]) -> Mat4 {
        let mut r = Mat4::IDENTITY;
        for (i, v) in s.iter().enumerate() {
            r.m[i][i] = *v;
        }
        r
    }

    /// A right-handed rotation by `degrees` about `axis` (normalised here; must be non-zero).
    pub fn rotate(axis: [f64; 3], degrees: f64) -> Option<Mat4> {
        let len = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
        if !positive(len) {
            return None;
        }
        let [x, y, z] = axis.map(|a| a / len);
        let (s, c) = degrees.to_radians().sin_cos();
        let t = 1.0 - c;
        Some(Mat4 {
            m: [
                [t * x * x + c, t * x * y - s * z, t * x * z + s * y, 0.0],
                [t * x * y + s * z, t * y * y + c, t * y * z - s * x, 0.0],
                [t * x * z - s * y, t * y * z + s * x, t * z * z + c, 0.0],
                [0.0, 0.0, 0.0, 1.0],
            ],
        })
    }

    /// Mitsuba's `lookat`: the camera at `origin` looks along `+z` towards `target`, with `+y`
    /// towards `up` and `+x = up × direction` (to the left in the image). `None` when the
    /// direction is zero or parallel to `up`.
    pub fn look_at(origin: [f64; 3], target: [f64; 3], up: [f64; 3]) -> Option<Mat4> {
        let dir = normalize(sub(target, origin))?;
        let left = normalize(cross(up, dir))?;
        let new_up = cross(dir, left);
        Some(Mat4 {
            m: [
                [left[0], new_up[0], dir[0], origin[0]],
                [left[1], new_up[1], dir[1], origin[1]],
                [left[2], new_up[2], dir[2], origin[2]],
                [0.0, 0.0, 0.0, 1.0],
            ],
        })
    }

    /// The product `self · rhs` (apply `rhs` first).
    pub fn mul(&self, rhs: &Mat4) -> Mat4 {
        let mut r = [[0.0; 4]; 4];
        for (i, row) in r.iter_mut().enumerate() {
            for (j, v) in row.iter_mut().enumerate() {
                *v = (0..4).map(|k| self.m[i][k] * rhs.m[k][j]).sum();
            }
        }
        Mat4 { m: r }
    }

    /// Transforms a point (w = 1; the projective row is ignored, transforms are affine).
    pub fn point(&self, p: [f64; 3]) -> [f64; 3] {
        let m = &self.m;
        [0, 1, 2].map(|i| m[i][0] * p[0] + m[i][1] * p[1] + m[i][2] * p[2] + m[i][3])
    }

    /// Transforms a direction (w = 0).
    pub fn vector(&self, v: [f64; 3]) -> [f64; 3] {
        let m = &self.m;
        [0, 1, 2].map(|i| m[i][0] * v[0] + m[i][1] * v[1] + m[i][2] * v[2])
    }

    /// Determinant of the upper-left 3×3 (linear) part.
    pub fn det3(&self) -> f64 {
        let m = &self.m;
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    }

    /// The inverse transpose of the linear part (the matrix that maps normals), or `None` if
    /// the linear part is singular.
    pub fn normal_matrix(&self) -> Option<[[f64; 3]; 3]> {
        let m = &self.m;
        let det = self.det3();
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        // Cofactor matrix / det = inverse transpose.
        let c = |r0: usize, r1: usize, c0: usize, c1: usize| m[r0][c0] * m[r1][c1] - m[r0][c1] * m[r1][c0];
        let cof = [
            [c(1, 2, 1, 2), -c(1, 2, 0, 2), c(1, 2, 0, 1)],
            [-c(0, 2, 1, 2), c(0, 2, 0, 2), -c(0, 2, 0, 1)],
            [c(0, 1, 1, 2), -c(0, 1, 0, 2), c(0, 1, 0, 1)],
        ];
        Some(cof.map(|row| row.map(|v| v / det)))
    }

    /// Whether all entries are finite and the last row is `0 0 0 1`.
    pub fn is_affine(&self) -> bool {
        self.m.iter().flatten().all(|v| v.is_finite()) && self.m[3] == [0.0, 0.0, 0.0, 1.0]
    }
}

/// Applies a 3×3 matrix.
pub(crate) fn apply3(n: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|i| n[i][0] * v[0] + n[i][1] * v[1] + n[i][2] * v[2])
}

pub(crate) fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

pub(crate) fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

pub(crate) fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

pub(crate) fn length(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

/// `a / |a|`, or `None` for a zero or non-finite vector.
pub(crate) fn normalize(a: [f64; 3]) -> Option<[f64; 3]> {
    let l = length(a);
    if l > 0.0 && l.is_finite() { Some(a.map(|v| v / l)) } else { None }
}

pub(crate) fn to_vec3(a: [f64; 3]) -> Vec3 {
    Vec3::new(a[0] as f32, a[1] as f32, a[2] as f32)
}

pub(crate) fn from_vec3(v: Vec3) -> [f64; 3] {
    [f64::from(v.x), f64::from(v.y), f64::from(v.z)]
}

/// Whether `v` is positive and finite.
pub(crate) fn positive(v: f64) -> bool {
    v > 0.0 && v.is_finite()
}
