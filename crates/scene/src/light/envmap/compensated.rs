//! The compensated sampling density of an image environment: next-event estimation of the
//! path tracer samples it (MIS compensation, see [`EnvMapLight`](super::EnvMapLight)).

use math::{AliasRows, Distribution1D};
use spectrum::Rgb;

use super::Texel;

/// The compensated sampling density (see [`EnvMapLight`](super::EnvMapLight)): per unit area of the sampling
/// square, the bilinear interpolation of the lattice values
/// `max(0, luminance(pixel) − L̄) · scale[row]`, `scale[row] = sin θ_row / Z_c` (θ a quarter row
/// from the poles, as for the full density; `Z_c` normalises). It is computed from a texel's
/// radiance when needed, by [`Compensated::of`], with the very operations that built the
/// tables, so the tables and the density agree to the last bit: 8 bytes per cell (the alias
/// slot) and 4 per row more than the full density alone.
#[derive(Debug, PartialEq)]
pub(super) struct Compensated {
    /// `L̄`: the mean luminance of the map over the sphere (`∫ luminance dω / 4π`).
    mean: f32,
    /// Per lattice row: `sin θ / Z_c`.
    scale: Vec<f32>,
    /// Picks a row of cells in proportion to the density's integral over it.
    pub(super) rows: Distribution1D,
    /// Picks a cell within a row in proportion to the density's integral over it.
    pub(super) columns: AliasRows,
}

impl Compensated {
    /// Builds the density of a `width × height` map of `pixels` whose luminance integrates to
    /// `integral` over the sphere; `row_sin(j)` is the full density's `sin θ` of row `j`.
    pub(super) fn new(pixels: &[Rgb], width: usize, integral: f64, row_sin: impl Fn(usize) -> f64) -> Option<Self> {
        let height = pixels.len() / width;
        let mean = (integral / (4.0 * std::f64::consts::PI)) as f32;
        let excess = |k: usize| (pixels[k].luminance() - mean).max(0.0);
        // Cell weights (the mean of the corners) of the lattice `excess · sin θ`, in f64.
        let cells = |lattice: &dyn Fn(usize, usize) -> f64| -> Vec<f64> {
            (0..height - 1)
                .flat_map(|j| (0..width).map(move |i| (i, j)))
                .map(|(i, j)| {
                    let i1 = (i + 1) % width;
                    0.25 * (lattice(i, j) + lattice(i1, j) + lattice(i, j + 1) + lattice(i1, j + 1))
                })
                .collect()
        };
        let unnormalised = cells(&|i, j| excess(j * width + i) as f64 * row_sin(j));
        let z = unnormalised.iter().sum::<f64>() / unnormalised.len() as f64;
        if !(z > 0.0 && z.is_finite()) {
            return None;
        }
        let scale: Vec<f32> = (0..height).map(|j| (row_sin(j) / z) as f32).collect();
        // The tables from the densities exactly as `of` computes them.
        let weights: Vec<f32> = cells(&|i, j| excess_density(pixels[j * width + i], mean, scale[j]) as f64)
            .iter()
            .map(|w| *w as f32)
            .collect();
        let row_sums: Vec<f32> =
            weights.chunks_exact(width).map(|row| row.iter().map(|w| *w as f64).sum::<f64>() as f32).collect();
        let rows = Distribution1D::new(&row_sums)?;
        let columns = AliasRows::new(&weights, width)?;
        Some(Self { mean, scale, rows, columns })
    }

    /// The density at the lattice point of a pixel of radiance `radiance` in row `row`.
    #[inline]
    pub(super) fn of(&self, radiance: Rgb, row: usize) -> f32 {
        excess_density(radiance, self.mean, self.scale[row])
    }

    /// The densities at the corners of cell row `j0` ([`EnvMapData::corners`]' order).
    #[inline]
    pub(super) fn corners(&self, [a, b, c, e]: &[Texel; 4], j0: usize) -> [f32; 4] {
        [self.of(a.radiance, j0), self.of(b.radiance, j0), self.of(c.radiance, j0 + 1), self.of(e.radiance, j0 + 1)]
    }
}

/// `max(0, luminance − mean) · scale`: one lattice value of the compensated density.
#[inline]
fn excess_density(radiance: Rgb, mean: f32, scale: f32) -> f32 {
    (radiance.luminance() - mean).max(0.0) * scale
}
