//! 4×4 affine/projective matrices in double precision for pbrt's transformation directives.

/// A 3-vector in double precision.
pub type V3 = [f64; 3];

/// A 4×4 matrix, `m[row][column]`, acting on column vectors.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Mat4 {
    /// Rows.
    pub m: [[f64; 4]; 4],
}

impl Mat4 {
    /// The identity.
    pub const IDENTITY: Mat4 =
        Mat4 { m: [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]] };

    /// The matrix with the given rows.
    pub fn from_rows(m: [[f64; 4]; 4]) -> Self {
        Self { m }
    }

    /// pbrt's `Transform`/`ConcatTransform` list: 16 numbers, column by column (the translation
    /// is in elements 12–14).
    pub fn from_pbrt_list(v: &[f64]) -> Self {
        let mut m = [[0.0; 4]; 4];
        for (c, column) in v.chunks(4).take(4).enumerate() {
            for (r, &x) in column.iter().enumerate() {
                m[r][c] = x;
            }
        }
        Self { m }
    }

    /// Translation by `d`.
    pub fn translate(d: V3) -> Self {
        let mut t = Self::IDENTITY;
        for (row, &x) in t.m.iter_mut().zip(&d) {
            row[3] = x;
        }
        t
    }

    /// Scaling by `s` along the axes.
    pub fn scale(s: V3) -> Self {
        let mut t = Self::IDENTITY;
        for (i, &x) in s.iter().enumerate() {
            t.m[i][i] = x;
        }
        t
    }

    /// Rotation by `degrees` about `axis` (normalised here; right-hand rule for the numbers,
    /// the same matrix pbrt builds).
    pub fn rotate(degrees: f64, axis: V3) -> Option<Self> {
        let len = norm(axis);
        if len == 0.0 || !len.is_finite() {
            return None;
        }
        let [x, y, z] = axis.map(|c| c / len);
        let (s, c) = degrees.to_radians().sin_cos();
        let t = 1.0 - c;
        Some(Self::from_rows([
            [x * x * t + c, x * y * t - z * s, x * z * t + y * s, 0.0],
            [x * y * t + z * s, y * y * t + c, y * z * t - x * s, 0.0],
            [x * z * t - y * s, y * z * t + x * s, z * z * t + c, 0.0],
            [0.0, 0.0, 0.0, 1.0],
        ]))
    }

    /// pbrt's `LookAt`: the camera-from-world matrix of an eye at `eye` looking at `look` with
    /// `up` pointing up. Camera x is `normalize(up × dir)` (pbrt's "right", its image's right
    /// side), y the orthogonalised up, z the viewing direction. `None` when `up` is parallel
    /// to the viewing direction or `look == eye`.
    pub fn look_at(eye: V3, look: V3, up: V3) -> Option<Self> {
        let dir = normalize(sub(look, eye))?;
        let right = normalize(cross(normalize(up)?, dir))?;
        let new_up = cross(dir, right);
        let world_from_camera = Self::from_rows([
            [right[0], new_up[0], dir[0], eye[0]],
            [right[1], new_up[1], dir[1], eye[1]],
            [right[2], new_up[2], dir[2], eye[2]],
            [0.0, 0.0, 0.0, 1.0],
        ]);
        world_from_camera.inverse()
    }

    /// The product `self · other` (apply `other` first).
    pub fn mul(&self, other: &Mat4) -> Mat4 {
        let mut m = [[0.0; 4]; 4];
        for (r, row) in m.iter_mut().enumerate() {
            for (c, x) in row.iter_mut().enumerate() {
                *x = (0..4).map(|k| self.m[r][k] * other.m[k][c]).sum();
            }
        }
        Mat4 { m }
    }

    /// The inverse, `None` when (nearly) singular.
    pub fn inverse(&self) -> Option<Mat4> {
        // Gauss–Jordan elimination with partial pivoting.
        let mut a = self.m;
        let mut inv = Self::IDENTITY.m;
        let scale = self.m.iter().flatten().fold(0.0f64, |s, x| s.max(x.abs()));
        if scale == 0.0 || !scale.is_finite() {
            return None;
        }
        for col in 0..4 {
            let pivot = (col..4).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
            if a[pivot][col].abs() <= 1e-12 * scale {
                return None;
            }
            a.swap(col, pivot);
            inv.swap(col, pivot);
            let p = a[col][col];
            for k in 0..4 {
                a[col][k] /= p;
                inv[col][k] /= p;
            }
            for row in 0..4 {
                if row != col {
                    let f = a[row][col];
                    for k in 0..4 {
                        a[row][k] -= f * a[col][k];
                        inv[row][k] -= f * inv[col][k];
                    }
                }
            }
        }
        Some(Mat4 { m: inv })
    }

    /// Applies the matrix to a point (with the homogeneous divide).
    pub fn point(&self, p: V3) -> V3 {
        let h = |r: usize| self.m[r][0] * p[0] + self.m[r][1] * p[1] + self.m[r][2] * p[2] + self.m[r][3];
        let w = h(3);
        let w = if w == 0.0 { 1.0 } else { w };
        [h(0) / w, h(1) / w, h(2) / w]
    }

    /// Applies the linear part to a direction.
    pub fn vector(&self, v: V3) -> V3 {
        let h = |r: usize| self.m[r][0] * v[0] + self.m[r][1] * v[1] + self.m[r][2] * v[2];
        [h(0), h(1), h(2)]
    }

    /// Determinant of the upper-left 3×3 block (negative when the transform swaps handedness).
    pub fn det3(&self) -> f64 {
        let m = &self.m;
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    }

    /// Whether the bottom row is `0 0 0 1`.
    pub fn is_affine(&self) -> bool {
        self.m[3] == [0.0, 0.0, 0.0, 1.0]
    }

    /// Whether every element is finite.
    pub fn is_finite(&self) -> bool {
        self.m.iter().flatten().all(|x| x.is_finite())
    }
}

/// `a − b`.
pub fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// `a × b` (the usual formula).
pub fn cross(a: V3, b: V3) -> V3 {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

/// `a · b`.
pub fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Euclidean length.
pub fn norm(a: V3) -> f64 {
    dot(a, a).sqrt()
}

/// `a / |a|`, `None` for zero or non-finite vectors.
pub fn normalize(a: V3) -> Option<V3> {
    let n = norm(a);
    (n > 0.0 && n.is_finite()).then(|| a.map(|c| c / n))
}
