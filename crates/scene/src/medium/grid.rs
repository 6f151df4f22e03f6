//! Spatially varying medium data: voxel grids with trilinear or nearest lookup, and the
//! [`Volume`]s built from them (a grid or a constant, times a colour, through a transform).
//!
//! **Voxel-centre convention** (Mitsuba 3's `gridvolume`, pbrt-v4's `SampledGrid`): a grid of
//! `n` points along an axis covers the unit interval `[0, 1]` of its local space with `n`
//! cells, and value `i` sits at the cell centre `(i + ½) / n`. A lookup at local `p` reads
//! `u = p·n − ½`; trilinear interpolation blends the values at `⌊u⌋` and `⌊u⌋ + 1` with
//! weights `1 − f` and `f`, `f = u − ⌊u⌋`; nearest lookup reads `⌊p·n⌋`. Indices outside
//! `[0, n − 1]` are clamped ([`Outside::Clamp`], Mitsuba's default `wrap_mode`) or read as
//! zero ([`Outside::Zero`], pbrt-v4).

use std::sync::Arc;

use glam::{Affine3A, Vec3};
use spectrum::{Rgb, SpectralMode};

use super::Coefficient;

/// How a lookup blends voxel values.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Filter {
    /// Trilinear interpolation between the 8 nearest voxel centres (Mitsuba's default).
    #[default]
    Trilinear,
    /// The value of the voxel containing the point.
    Nearest,
}

/// What a lookup reads for voxel indices outside the grid.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Outside {
    /// The nearest voxel on the border (Mitsuba's `wrap_mode` `clamp`).
    #[default]
    Clamp,
    /// Zero (pbrt-v4's grids).
    Zero,
}

/// A voxel grid of 1 or 3 channels (unitless values; the [`Volume`] scales them).
#[derive(Clone, Debug, PartialEq)]
pub struct Grid {
    dims: [usize; 3],
    channels: usize,
    /// `dims[0]·dims[1]·dims[2]·channels` values, `x` fastest, then `y`, then `z`, the
    /// channels of one voxel together.
    values: Vec<f32>,
    /// Largest value per channel (RGB; a 1-channel grid repeats it).
    max: Rgb,
}

impl Grid {
    /// A grid of `dims` voxels (each ≥ 1) with `channels` (1 or 3) values per voxel, laid out
    /// as in Mitsuba's `.vol` files. Values must be finite and non-negative.
    pub fn new(dims: [usize; 3], channels: usize, values: Vec<f32>) -> Result<Self, String> {
        if channels != 1 && channels != 3 {
            return Err(format!("a medium grid needs 1 or 3 channels, got {channels}"));
        }
        if dims.contains(&0) {
            return Err(format!("grid size {}×{}×{} has an empty axis", dims[0], dims[1], dims[2]));
        }
        let expected =
            dims[0].checked_mul(dims[1]).and_then(|c| c.checked_mul(dims[2])).and_then(|c| c.checked_mul(channels));
        if expected != Some(values.len()) {
            return Err(format!(
                "{} values for a {}×{}×{} grid of {channels} channel(s)",
                values.len(),
                dims[0],
                dims[1],
                dims[2]
            ));
        }
        if let Some(v) = values.iter().find(|v| !(v.is_finite() && **v >= 0.0)) {
            return Err(format!("grid values must be finite and non-negative, found {v}"));
        }
        let mut max = [0.0f32; 3];
        for voxel in values.chunks_exact(channels) {
            for (c, m) in max.iter_mut().enumerate() {
                *m = m.max(voxel[c.min(channels - 1)]);
            }
        }
        Ok(Self { dims, channels, values, max: Rgb::new(max[0], max[1], max[2]) })
    }

    /// Voxels per axis.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// Channels per voxel (1 or 3).
    pub fn channels(&self) -> usize {
        self.channels
    }

    /// Largest value per channel (a 1-channel grid gives it in all three).
    pub fn max(&self) -> Rgb {
        self.max
    }

    /// The largest value per channel over the voxels with indices in the inclusive ranges
    /// `x`, `y`, `z` (each within the grid).
    pub fn max_over(&self, x: (usize, usize), y: (usize, usize), z: (usize, usize)) -> Rgb {
        let mut max = [0.0f32; 3];
        for k in z.0..=z.1.min(self.dims[2] - 1) {
            for j in y.0..=y.1.min(self.dims[1] - 1) {
                let row = (k * self.dims[1] + j) * self.dims[0];
                for i in x.0..=x.1.min(self.dims[0] - 1) {
                    let at = (row + i) * self.channels;
                    for (c, m) in max.iter_mut().enumerate() {
                        *m = m.max(self.values[at + c.min(self.channels - 1)]);
                    }
                }
            }
        }
        Rgb::new(max[0], max[1], max[2])
    }

    /// The voxel at integer indices (clamped, or zero outside the grid for [`Outside::Zero`]).
    #[inline]
    fn voxel(&self, i: [i64; 3], outside: Outside) -> Rgb {
        let mut index = [0usize; 3];
        for a in 0..3 {
            let n = self.dims[a] as i64;
            if outside == Outside::Zero && !(0..n).contains(&i[a]) {
                return Rgb::BLACK;
            }
            index[a] = i[a].clamp(0, n - 1) as usize;
        }
        let k = ((index[2] * self.dims[1] + index[1]) * self.dims[0] + index[0]) * self.channels;
        if self.channels == 1 {
            Rgb::splat(self.values[k])
        } else {
            Rgb::new(self.values[k], self.values[k + 1], self.values[k + 2])
        }
    }

    /// The value at `local` (grid space, the unit cube; module documentation for the
    /// convention). A 1-channel grid gives its value in all three channels.
    #[inline]
    pub fn lookup(&self, local: Vec3, filter: Filter, outside: Outside) -> Rgb {
        let p = local.to_array();
        if !p.iter().all(|x| x.is_finite()) {
            return Rgb::BLACK;
        }
        match filter {
            Filter::Nearest => {
                let i: [i64; 3] = std::array::from_fn(|a| (p[a] * self.dims[a] as f32).floor() as i64);
                self.voxel(i, outside)
            }
            Filter::Trilinear => {
                let u: [f32; 3] = std::array::from_fn(|a| p[a] * self.dims[a] as f32 - 0.5);
                let i: [i64; 3] = std::array::from_fn(|a| u[a].floor() as i64);
                let f: [f32; 3] = std::array::from_fn(|a| u[a] - u[a].floor());
                let mut sum = Rgb::BLACK;
                for corner in 0..8 {
                    let mut weight = 1.0;
                    let mut at = i;
                    for a in 0..3 {
                        if (corner >> a) & 1 == 1 {
                            weight *= f[a];
                            at[a] += 1;
                        } else {
                            weight *= 1.0 - f[a];
                        }
                    }
                    if weight > 0.0 {
                        sum += self.voxel(at, outside) * weight;
                    }
                }
                sum
            }
        }
    }
}

/// A spatially varying, spectrally varying quantity: `value ⊙ grid(to_local · p)` (the grid's
/// RGB upsampled as the renderer's reflectances; it is linear in the RGB value, so
/// upsampling after interpolation equals interpolating upsampled voxels), or `value` alone
/// (Mitsuba's `constvolume`).
#[derive(Clone, Debug, PartialEq)]
pub struct Volume {
    /// The grid, `None` for a constant.
    pub grid: Option<Arc<Grid>>,
    /// The factor on the grid (or the constant value).
    pub value: Coefficient,
    /// World → grid space (the unit cube holds the grid).
    pub to_local: Affine3A,
    /// The lookup filter.
    pub filter: Filter,
    /// What lookups outside the grid read.
    pub outside: Outside,
}

impl Volume {
    /// A constant volume of `value` whose grid space is `to_local` of world space.
    pub fn constant(value: Coefficient, to_local: Affine3A) -> Self {
        Self { grid: None, value, to_local, filter: Filter::Trilinear, outside: Outside::Clamp }
    }

    /// The value at world point `p`, with `value` already evaluated at the wavelengths as
    /// `tint`.
    #[inline]
    pub fn eval<S: SpectralMode>(&self, p: Vec3, w: &S::Wavelengths, tint: S) -> S {
        let Some(grid) = &self.grid else { return tint };
        let rgb = grid.lookup(self.to_local.transform_point3(p), self.filter, self.outside);
        if grid.channels == 1 { tint * rgb.r } else { S::from_reflectance(w, rgb) * tint }
    }

    /// [`Volume::eval`] at world point `p` twice from one grid lookup: at the wavelengths `w`
    /// with `tint`, and in linear sRGB with `rgb_tint` (`value` evaluated in RGB mode).
    #[inline]
    pub fn eval_with_rgb<S: SpectralMode>(&self, p: Vec3, w: &S::Wavelengths, tint: S, rgb_tint: Rgb) -> (S, Rgb) {
        let Some(grid) = &self.grid else { return (tint, rgb_tint) };
        let rgb = grid.lookup(self.to_local.transform_point3(p), self.filter, self.outside);
        if grid.channels == 1 {
            (tint * rgb.r, rgb_tint * rgb.r)
        } else {
            (S::from_reflectance(w, rgb) * tint, rgb * rgb_tint)
        }
    }

    /// An upper bound of the grid factor over space at the wavelengths, the largest over
    /// the channels (1 without a grid): the RGB upsampling is linear, so each channel is at
    /// most `Σ_k max(b_k, 0)·max_k` for the basis `b` and per-channel maxima `max_k`.
    pub fn grid_bound<S: SpectralMode>(&self, w: &S::Wavelengths) -> f32 {
        let Some(grid) = &self.grid else { return 1.0 };
        if grid.channels == 1 {
            return grid.max.r;
        }
        let m = grid.max;
        let basis = |rgb: Rgb| S::from_reflectance(w, rgb).map(|b| b.max(0.0));
        let bound = basis(Rgb::new(1.0, 0.0, 0.0)) * m.r
            + basis(Rgb::new(0.0, 1.0, 0.0)) * m.g
            + basis(Rgb::new(0.0, 0.0, 1.0)) * m.b;
        (0..S::CHANNELS).map(|c| bound.channel(c)).fold(0.0, f32::max)
    }

    /// World-space bounding box of the grid space's unit cube (Mitsuba's volume `bbox`).
    pub fn world_bounds(&self) -> (Vec3, Vec3) {
        let to_world = self.to_local.inverse();
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for corner in 0..8 {
            let c = Vec3::new((corner & 1) as f32, ((corner >> 1) & 1) as f32, ((corner >> 2) & 1) as f32);
            let p = to_world.transform_point3(c);
            lo = lo.min(p);
            hi = hi.max(p);
        }
        (lo, hi)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 2×2×2 grid with value `x + 2y + 4z` at voxel (x, y, z).
    fn ramp() -> Grid {
        Grid::new([2, 2, 2], 1, (0..8).map(|i| i as f32).collect()).unwrap()
    }

    #[test]
    fn trilinear_lookup_matches_hand_computed_values() {
        let g = ramp();
        let at = |x: f32, y: f32, z: f32, o| g.lookup(Vec3::new(x, y, z), Filter::Trilinear, o).r;
        // Voxel centres at 1/4 and 3/4.
        assert_eq!(at(0.25, 0.25, 0.25, Outside::Clamp), 0.0);
        assert_eq!(at(0.75, 0.75, 0.75, Outside::Clamp), 7.0);
        // The cube's centre: the mean of the 8 voxels.
        assert!((at(0.5, 0.5, 0.5, Outside::Clamp) - 3.5).abs() < 1e-6);
        // u = (0.6·2 − 0.5, 0.25·2 − 0.5, 0.75·2 − 0.5) = (0.7, 0, 1): 0.7·1 + 0 + 4 = 4.7.
        assert!((at(0.6, 0.25, 0.75, Outside::Clamp) - 4.7).abs() < 1e-6);
        // Below the first centre: clamped to voxel 0 (Mitsuba), or blended with 0 (pbrt).
        assert_eq!(at(0.0, 0.25, 0.25, Outside::Clamp), 0.0);
        assert!((at(0.0, 0.75, 0.75, Outside::Clamp) - 6.0).abs() < 1e-6);
        // pbrt: u_x = −0.5 blends voxel −1 (zero) and voxel 0 (value 6) half and half.
        assert!((at(0.0, 0.75, 0.75, Outside::Zero) - 3.0).abs() < 1e-6);
        assert_eq!(at(1.5, 0.75, 0.75, Outside::Zero), 0.0);
    }

    #[test]
    fn nearest_lookup_and_channels() {
        let g = ramp();
        assert_eq!(g.lookup(Vec3::new(0.49, 0.51, 0.99), Filter::Nearest, Outside::Clamp).r, 6.0);
        assert_eq!(g.max(), Rgb::splat(7.0));
        let rgb = Grid::new([1, 1, 2], 3, vec![1.0, 2.0, 3.0, 3.0, 2.0, 1.0]).unwrap();
        let v = rgb.lookup(Vec3::new(0.5, 0.5, 0.5), Filter::Trilinear, Outside::Clamp);
        assert_eq!(v.to_array(), [2.0, 2.0, 2.0]);
        assert_eq!(rgb.max().to_array(), [3.0, 2.0, 3.0]);
        assert!(Grid::new([2, 2, 2], 2, vec![0.0; 16]).is_err());
        assert!(Grid::new([2, 2, 2], 1, vec![0.0; 7]).is_err());
        assert!(Grid::new([1, 1, 1], 1, vec![-1.0]).is_err());
    }

    #[test]
    fn volume_maps_world_to_the_unit_cube() {
        // Mitsuba's to_world = translate(−0.5) · scale(1.5): the grid covers [−0.5, 1]³.
        let to_world = Affine3A::from_translation(Vec3::splat(-0.5)) * Affine3A::from_scale(Vec3::splat(1.5));
        let volume = Volume {
            grid: Some(Arc::new(ramp())),
            value: Coefficient::rgb(Rgb::splat(2.0)),
            to_local: to_world.inverse(),
            filter: Filter::Trilinear,
            outside: Outside::Clamp,
        };
        let (lo, hi) = volume.world_bounds();
        assert!((lo - Vec3::splat(-0.5)).abs().max_element() < 1e-6 && (hi - Vec3::ONE).abs().max_element() < 1e-6);
        // World (−0.5 + 1.5·0.75)³ is the centre of voxel (1, 1, 1): 7 × the value 2.
        let p = Vec3::splat(-0.5 + 1.5 * 0.75);
        let v: Rgb = volume.eval::<Rgb>(p, &(), Rgb::splat(2.0));
        assert!((v.r - 14.0).abs() < 1e-5, "{v:?}");
        assert_eq!(volume.grid_bound::<Rgb>(&()), 7.0);
    }
}
