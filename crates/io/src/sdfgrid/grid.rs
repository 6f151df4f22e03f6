//! The SDF grid as Mitsuba 3's `sdfgrid` defines it: values at the points of a regular grid
//! spanning the unit cube (object space), the surface the zero set of their trilinear
//! interpolant, and the two shading normals (`analytic`, `smooth`).
//!
//! Positions are either in object space `p ∈ [0, 1]³` or in *index space* `q = p · (n − 1)`
//! per axis, where grid point `(i, j, k)` sits at `q = (i, j, k)` and voxel `(i, j, k)` is the
//! unit cube `[i, i + 1] × [j, j + 1] × [k, k + 1]`. Values are unitless (whatever the file
//! holds); only their sign and zero set matter. Negative is inside, and the gradient (towards
//! positive values) is the outward normal.

use glam::DVec3;

/// A scalar grid of at least 2 points per axis, `x` varying fastest.
#[derive(Clone, Debug)]
pub(crate) struct SdfGrid {
    dims: [usize; 3],
    values: Vec<f32>,
}

impl SdfGrid {
    /// A grid of `dims` points (each ≥ 2) with `values` (`x` fastest, then `y`, then `z`), all
    /// finite.
    pub(crate) fn new(dims: [usize; 3], values: Vec<f32>) -> Result<SdfGrid, String> {
        if dims.iter().any(|&d| d < 2) {
            return Err(format!("grid size {dims:?}: an SDF grid needs at least 2 points per axis"));
        }
        if dims.iter().product::<usize>() != values.len() {
            return Err(format!("{} values for a {dims:?} grid", values.len()));
        }
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            return Err(format!("value {i} is not finite ({})", values[i]));
        }
        Ok(SdfGrid { dims, values })
    }

    /// Points per axis.
    pub(crate) fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// Voxels per axis (`dims − 1`), as floats: the object-to-index scale.
    pub(crate) fn resolution(&self) -> DVec3 {
        DVec3::new(self.dims[0] as f64 - 1.0, self.dims[1] as f64 - 1.0, self.dims[2] as f64 - 1.0)
    }

    /// The value at grid point `(i, j, k)`.
    pub(crate) fn value(&self, i: usize, j: usize, k: usize) -> f64 {
        self.values[i + self.dims[0] * (j + self.dims[1] * k)] as f64
    }

    /// The eight corner values of voxel `v`, corner `c` at offset `(c & 1, c >> 1 & 1, c >> 2 & 1)`.
    pub(crate) fn corners(&self, v: [usize; 3]) -> [f64; 8] {
        std::array::from_fn(|c| self.value(v[0] + (c & 1), v[1] + (c >> 1 & 1), v[2] + (c >> 2 & 1)))
    }

    /// The trilinear interpolant of voxel `v` at local coordinates `t` (`[0, 1]³` inside the
    /// voxel; outside, the voxel's polynomial extended).
    pub(crate) fn eval_in_voxel(&self, v: [usize; 3], t: DVec3) -> f64 {
        let c = self.corners(v);
        let x00 = c[0] + (c[1] - c[0]) * t.x;
        let x10 = c[2] + (c[3] - c[2]) * t.x;
        let x01 = c[4] + (c[5] - c[4]) * t.x;
        let x11 = c[6] + (c[7] - c[6]) * t.x;
        let y0 = x00 + (x10 - x00) * t.y;
        let y1 = x01 + (x11 - x01) * t.y;
        y0 + (y1 - y0) * t.z
    }

    /// The voxel holding index-space point `q` (clamped to the grid) and `q`'s coordinates in it.
    pub(crate) fn locate(&self, q: DVec3) -> ([usize; 3], DVec3) {
        let mut voxel = [0usize; 3];
        let mut local = DVec3::ZERO;
        for axis in 0..3 {
            let last = (self.dims[axis] - 1) as f64;
            let x = q[axis].clamp(0.0, last);
            let cell = (x.floor() as usize).min(self.dims[axis] - 2);
            voxel[axis] = cell;
            local[axis] = x - cell as f64;
        }
        (voxel, local)
    }

    /// The interpolant at index-space point `q`, clamped to the grid (Mitsuba's texture lookup
    /// with clamping: outside the grid the value of the nearest border point).
    pub(crate) fn eval_index(&self, q: DVec3) -> f64 {
        let (voxel, local) = self.locate(q);
        self.eval_in_voxel(voxel, local)
    }

    /// The interpolant at object-space point `p` (clamped to the unit cube).
    pub(crate) fn eval(&self, p: DVec3) -> f64 {
        self.eval_index(p * self.resolution())
    }

    /// Mitsuba's per-voxel gradient (object-space units, value per unit length) at object-space
    /// point `p` for voxel `v` (which may lie beyond the grid's upper end): per axis, the
    /// difference of the clamped interpolant between the voxel's two faces, at `p`'s other two
    /// coordinates, over the voxel size. Inside voxel `v` this is the exact gradient of its
    /// trilinear interpolant.
    pub(crate) fn voxel_gradient(&self, p: DVec3, v: [i64; 3]) -> DVec3 {
        let res = self.resolution();
        let mut gradient = DVec3::ZERO;
        for axis in 0..3 {
            let size = 1.0 / res[axis];
            let low = v[axis] as f64 * size;
            let (mut a, mut b) = (p, p);
            a[axis] = low + size;
            b[axis] = low;
            gradient[axis] = (self.eval(a) - self.eval(b)) / size;
        }
        gradient
    }

    /// Mitsuba's `analytic` normal direction at `p` (object space, not normalised): the
    /// gradient of the voxel that holds `p` (by `floor`).
    #[cfg(test)]
    pub(crate) fn analytic_gradient(&self, p: DVec3) -> DVec3 {
        let q = p * self.resolution();
        self.voxel_gradient(p, [q.x.floor() as i64, q.y.floor() as i64, q.z.floor() as i64])
    }

    /// Mitsuba's `smooth` normal direction at `p` (object space, not normalised; Hansson-
    /// Söderlund, Evans and Akenine-Möller 2022): the unit gradients of the eight voxels whose
    /// centres surround `p`, each evaluated at `p`, blended trilinearly by `p`'s position
    /// between those centres. Voxels with a negative index are left out and the blend weight
    /// moves to the other side of an axis where all four on one side are missing; voxels past
    /// the upper end take the clamped interpolant, as Mitsuba does.
    pub(crate) fn smooth_normal(&self, p: DVec3) -> DVec3 {
        let scaled = p * self.resolution();
        let rounded = scaled.round();
        let base = [rounded.x as i64 - 1, rounded.y as i64 - 1, rounded.z as i64 - 1];
        let voxel = |c: usize| [base[0] + (c & 1) as i64, base[1] + (c >> 1 & 1) as i64, base[2] + (c >> 2 & 1) as i64];
        let valid: [bool; 8] = std::array::from_fn(|c| voxel(c).iter().all(|&i| i >= 0));
        let normals: [DVec3; 8] = std::array::from_fn(|c| {
            if valid[c] { self.voxel_gradient(p, voxel(c)).normalize_or_zero() } else { DVec3::ZERO }
        });
        // Position between the voxel centres: scaled − (base + 1) + 1/2.
        let mut weight = scaled - rounded + DVec3::splat(0.5);
        for axis in 0..3 {
            let bit = 1 << axis;
            let side_missing = |high: bool| (0..8).filter(|c| (c & bit != 0) == high).all(|c| !valid[c]);
            if side_missing(false) {
                weight[axis] = 1.0;
            }
            if side_missing(true) {
                weight[axis] = 0.0;
            }
        }
        let mut n = DVec3::ZERO;
        for (c, normal) in normals.iter().enumerate() {
            let w: f64 =
                (0..3).map(|axis| if c >> axis & 1 == 1 { weight[axis] } else { 1.0 - weight[axis] }).product();
            n += w * *normal;
        }
        n
    }
}
