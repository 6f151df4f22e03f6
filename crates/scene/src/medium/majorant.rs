//! A coarse grid of majorants over a heterogeneous medium's region, walked by a 3-D DDA.
//!
//! The region's unit cube is cut into `RES³` cells; each cell stores, per RGB channel, the
//! largest voxel value of the `sigma_t` grid that any lookup inside the cell can read (the
//! voxels whose centres lie within one voxel of the cell's footprint in grid space, plus one
//! more voxel of margin against rounding). Delta and ratio tracking then sample tentative
//! collisions cell by cell with the cell's majorant, restarting the exponential at every cell
//! boundary (the exponential is memoryless, so this samples the piecewise-constant majorant's
//! free-flight distribution exactly); a cell with majorant 0 is skipped.

use glam::{Affine3A, Vec3};
use spectrum::Rgb;

use super::grid::{Filter, Volume};

/// Cells per axis.
pub const RES: usize = 16;

/// Per-cell maxima of a grid volume over a region (see the module documentation).
#[derive(Clone, Debug, PartialEq)]
pub struct MajorantGrid {
    /// `RES³` per-channel maxima of the grid factor, `x` fastest.
    cells: Vec<Rgb>,
}

/// One stretch of a ray inside one cell: parameter interval and the cell's maxima.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stretch {
    /// Entry parameter.
    pub t0: f32,
    /// Exit parameter.
    pub t1: f32,
    /// The cell's per-channel maxima of the grid factor.
    pub max: Rgb,
}

impl MajorantGrid {
    /// The majorant grid of `volume` (which must have a grid) over the region whose unit cube
    /// is `region` of world space; `None` without a grid.
    pub fn new(volume: &Volume, region: Affine3A) -> Option<Self> {
        let grid = volume.grid.as_ref()?;
        let region_to_grid = volume.to_local * region.inverse();
        let dims = grid.dims();
        let mut cells = Vec::with_capacity(RES * RES * RES);
        for k in 0..RES {
            for j in 0..RES {
                for i in 0..RES {
                    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
                    for corner in 0..8 {
                        let c = Vec3::new(
                            (i + (corner & 1)) as f32,
                            (j + ((corner >> 1) & 1)) as f32,
                            (k + ((corner >> 2) & 1)) as f32,
                        ) / RES as f32;
                        let p = region_to_grid.transform_point3(c);
                        lo = lo.min(p);
                        hi = hi.max(p);
                    }
                    let range = |a: usize| {
                        let n = dims[a] as f32;
                        let (first, last) = match volume.filter {
                            Filter::Trilinear => ((lo[a] * n - 0.5).floor(), (hi[a] * n - 0.5).floor() + 1.0),
                            Filter::Nearest => ((lo[a] * n).floor(), (hi[a] * n).floor()),
                        };
                        let clamp = |x: f32| (x.max(0.0) as usize).min(dims[a] - 1);
                        (clamp(first - 1.0), clamp(last + 1.0))
                    };
                    cells.push(grid.max_over(range(0), range(1), range(2)));
                }
            }
        }
        Some(Self { cells })
    }

    /// Calls `visit` for the stretches of the ray `origin + t·direction`, `t ∈ [t0, t1]`, in the
    /// cells it crosses, in order (`origin`, `direction` in world space; `region` maps world to
    /// the region's unit cube). `visit` returns false to stop.
    pub fn walk(
        &self,
        region: &Affine3A,
        origin: Vec3,
        direction: Vec3,
        t0: f32,
        t1: f32,
        mut visit: impl FnMut(Stretch) -> bool,
    ) {
        let o = region.transform_point3(origin);
        let d = region.transform_vector3(direction);
        let res = RES as f32;
        let start = o + t0 * d;
        let mut cell = [0i64; 3];
        let mut next = [f32::INFINITY; 3];
        let mut delta = [f32::INFINITY; 3];
        let mut step = [0i64; 3];
        for a in 0..3 {
            cell[a] = ((start[a] * res).floor() as i64).clamp(0, RES as i64 - 1);
            if d[a] > 0.0 {
                step[a] = 1;
                next[a] = ((cell[a] + 1) as f32 / res - o[a]) / d[a];
                delta[a] = 1.0 / (res * d[a]);
            } else if d[a] < 0.0 {
                step[a] = -1;
                next[a] = (cell[a] as f32 / res - o[a]) / d[a];
                delta[a] = -1.0 / (res * d[a]);
            }
        }
        let mut t = t0;
        loop {
            let axis = if next[0] <= next[1] && next[0] <= next[2] {
                0
            } else if next[1] <= next[2] {
                1
            } else {
                2
            };
            let exit = next[axis].min(t1);
            let index = ((cell[2] as usize * RES) + cell[1] as usize) * RES + cell[0] as usize;
            if exit > t && !visit(Stretch { t0: t, t1: exit, max: self.cells[index] }) {
                return;
            }
            if exit >= t1 {
                return;
            }
            cell[axis] += step[axis];
            if !(0..RES as i64).contains(&cell[axis]) {
                return;
            }
            t = exit.max(t);
            next[axis] += delta[axis];
        }
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use super::*;
    use crate::medium::Coefficient;
    use crate::medium::grid::{Grid, Outside};

    /// A 20×7×5 grid of pseudo-random values under a rotated, scaled `to_local`, on a region
    /// that is the grid's world box.
    fn volume(filter: Filter) -> (Volume, Affine3A) {
        let values: Vec<f32> = (0..20 * 7 * 5).map(|i| ((i * 7919) % 101) as f32 / 10.0).collect();
        let to_world = Affine3A::from_rotation_z(0.4) * Affine3A::from_scale(Vec3::new(2.0, 1.0, 0.5));
        let volume = Volume {
            grid: Some(Arc::new(Grid::new([20, 7, 5], 1, values).unwrap())),
            value: Coefficient::rgb(Rgb::splat(1.0)),
            to_local: to_world.inverse(),
            filter,
            outside: Outside::Clamp,
        };
        let (lo, hi) = volume.world_bounds();
        let region = Affine3A::from_scale((hi - lo).recip()) * Affine3A::from_translation(-lo);
        (volume, region)
    }

    #[test]
    fn cells_bound_every_lookup_along_rays() {
        for filter in [Filter::Trilinear, Filter::Nearest] {
            let (volume, region) = volume(filter);
            let grid = MajorantGrid::new(&volume, region).unwrap();
            let to_world = region.inverse();
            let mut rng = math::Rng::new(3, 4);
            let (mut checked, mut stretches) = (0, 0);
            for _ in 0..200 {
                let a = to_world.transform_point3(Vec3::from(rng.uniform3()));
                let b = to_world.transform_point3(Vec3::from(rng.uniform3()));
                let direction = (b - a).normalize();
                let length = (b - a).length();
                let mut last = 0.0;
                grid.walk(&region, a, direction, 0.0, length, |s| {
                    assert!(s.t0 >= last - 1e-4 && s.t1 > s.t0, "stretches in order: {s:?} after {last}");
                    last = s.t1;
                    stretches += 1;
                    for k in 0..8 {
                        let t = s.t0 + (s.t1 - s.t0) * (k as f32 + 0.5) / 8.0;
                        let v = volume.eval::<Rgb>(a + t * direction, &(), Rgb::splat(1.0)).r;
                        assert!(v <= s.max.r, "{v} > cell bound {}", s.max.r);
                        checked += 1;
                    }
                    true
                });
                assert!(
                    (last - length).abs() < 1e-3 * length.max(1.0),
                    "the walk covers the segment: {last} of {length}"
                );
            }
            assert!(checked > 1000 && stretches > 200, "{checked} {stretches}");
        }
    }
}
