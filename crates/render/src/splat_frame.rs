//! Splatting camera samples over the pixels their filter reaches ([`FilmMode::Splat`]).
//!
//! Under [`FilmMode::Splat`] the camera sample of pixel `i` lies at a raster point `x_i`
//! uniform in that pixel and carries the value `L_i` (filter weight 1). After the camera pass
//! every pixel `j` gathers `Σ_i f(x_i − c_j) L_i / N_j` over its neighbours `i`, with `N_j` the
//! expected weight sum `∫_image f(x − c_j) dx` ([`Camera::splat_weight`]): an unbiased estimate
//! of `∫_image f(x − c_j) L(x) dx / N_j` per iteration, the same measurement light-tracing splats
//! make. Each pixel sums its neighbours in a fixed order, so the frame does not depend on the
//! number of threads.
//!
//! All camera samples of an iteration share one offset in their pixels ([`film_offset`]): the
//! samples form a randomly shifted lattice, so the weight sum a pixel receives is almost exactly
//! `N_j` and the division by the expected instead of the actual weight sum costs no variance in
//! smooth regions (docs/film.md). The raster points are not carried out of the camera passes:
//! [`sample_positions`] recomputes them from [`film_offset`], as [`Camera::sample_primary`]
//! placed them.

use math::{Rng, Vec2};
use rayon::prelude::*;
use scene::Camera;
use scene::filter::FilmMode;
use spectrum::Rgb;

use crate::vcm::FamilyValues;
use crate::vcm::technique_images::TechniqueFrame;

/// The random stream of pixel `pixel`'s camera sample in iteration `iteration`: every camera
/// pass starts the pixel's camera sub-path with it (and draws its raster position first).
#[inline]
pub fn camera_stream(seed: u64, iteration: u64, pixel: usize) -> Rng {
    Rng::for_stream(seed, iteration, pixel as u64)
}

/// The stream index of [`film_offset`] (apart from the pixels' indices, the light streams'
/// `1 << 62` and the wavelength streams' `1 << 61`).
const FILM_OFFSET_STREAM: u64 = 1 << 60;

/// The raster offset, uniform in `[0,1)²`, that every splatted camera sample of iteration
/// `iteration` adds to its pixel's corner ([`Camera::sample_primary`]).
///
/// One offset for the whole iteration makes the camera samples a shifted lattice: pixel `j`'s
/// weight sum `Σ_i f(c_i + u − c_j)` then hardly depends on `u` (for Mitsuba's gaussian, σ = ½
/// truncated at 2, it stays within ±1.43 % of `N_j` per axis, 0.972–1.029 × `N_j` in 2D; the
/// box and the tent of radius 1 sum to exactly `N_j`), where
/// independent offsets per pixel make it fluctuate by tens of percent. Dividing by the expected
/// weight sum `N_j` (unbiased, see the module) then costs almost no variance in smooth regions,
/// which is what Mitsuba's and pbrt's ratio estimators (dividing by the actual weight sum) buy at
/// the price of a bias. Each sample is still uniform in its pixel, and iterations stay independent.
pub fn film_offset(seed: u64, iteration: u64) -> [f32; 2] {
    Rng::for_stream(seed, iteration, FILM_OFFSET_STREAM).uniform2()
}

/// The raster positions (pixels) of the camera samples of iteration `iteration`, per pixel
/// (row-major), as [`Camera::sample_primary`] places them when splatting: the pixel's corner
/// plus [`film_offset`].
pub fn sample_positions(camera: &Camera, seed: u64, iteration: u64) -> Vec<Vec2> {
    let width = camera.width as usize;
    let offset = film_offset(seed, iteration);
    (0..camera.pixel_count())
        .into_par_iter()
        .map(|index| {
            let (x, y) = ((index % width) as u32, (index / width) as u32);
            camera.sample_pixel(x, y, offset).0
        })
        .collect()
}

/// Filter taps per axis that [`spread`] precomputes for each camera sample: offsets up to this
/// many pixels between the sample's pixel and a pixel it reaches (filter radii below 3.5
/// pixels; wider filters evaluate the filter per pair instead).
const MAX_REACH: usize = 3;

/// Taps per axis: offsets `−MAX_REACH..=MAX_REACH`.
const TAPS: usize = 2 * MAX_REACH + 1;

/// Output rows per band of [`spread`]: the taps of a band's source rows are held at once, so
/// the extra memory is `(BAND_ROWS + 2·reach) × width × 56` bytes whatever the image height.
const BAND_ROWS: usize = 64;

/// The 1D filter profiles of one camera sample at `p` (in pixel `(sx, sy)`) towards the pixel
/// centres around it: `x[k] = f₁(p.x − c)` for the column `sx + k − reach` (centre `c`), `y[k]`
/// likewise for the rows. The same products as evaluating `f₁(p.x − cx) f₁(p.y − cy)` per pair.
#[derive(Clone, Copy)]
struct Taps {
    x: [f32; TAPS],
    y: [f32; TAPS],
}

/// Largest offset (pixels, per axis) between the pixel holding a sample and a pixel whose centre
/// its filter reaches: a sample lies in its own pixel `[s, s + 1)`, so `|p − c| < radius` needs
/// `|s − x| < radius + ½`.
fn reach_of(radius: f32) -> usize {
    ((radius + 0.5).ceil() as usize).saturating_sub(1)
}

/// Replaces `values` (`stride` values per pixel, row-major, the camera samples' own values) by
/// their splatted image: value `c` of pixel `j` becomes `Σ_i w_j(x_i) values[i·stride + c]`
/// with `w_j` = [`Camera::splat_weight`] and `x_i` = `positions[i]`. Non-finite values count as
/// black. Parallel over rows; each pixel sums its neighbours in row-major order, so the result
/// does not depend on the thread count. Filters of radius below 3.5 pixels take their 1D
/// profiles from per-sample [`Taps`] computed once per band of rows (2·(2·reach + 1) profile
/// evaluations per sample instead of two per (sample, pixel) pair; bit-identical).
pub fn spread(camera: &Camera, positions: &[Vec2], values: &mut Vec<Rgb>, stride: usize) {
    spread_with(camera, positions, values, stride, MAX_REACH);
}

/// [`spread`] with taps for reaches up to `max_reach` (at most [`MAX_REACH`]; the tests compare
/// both paths with 0).
fn spread_with(camera: &Camera, positions: &[Vec2], values: &mut Vec<Rgb>, stride: usize, max_reach: usize) {
    let (width, height) = (camera.width as usize, camera.height as usize);
    assert_eq!(positions.len(), width * height, "one raster position per pixel");
    assert_eq!(values.len(), width * height * stride, "stride values per pixel");
    if stride == 0 {
        return;
    }
    let filter = &camera.filter;
    let reach = reach_of(filter.radius());
    let source = std::mem::take(values);
    let mut out = vec![Rgb::BLACK; source.len()];
    // N_j per axis (the product is Camera::splat_normalization).
    let nx: Vec<f64> = (0..width).map(|x| filter.clipped_integral_1d(x as f32 + 0.5, width as f32)).collect();
    let ny: Vec<f64> = (0..height).map(|y| filter.clipped_integral_1d(y as f32 + 0.5, height as f32)).collect();
    let columns = |x: usize| x.saturating_sub(reach)..(x + reach + 1).min(width);
    let rows = |y: usize| y.saturating_sub(reach)..(y + reach + 1).min(height);
    let accumulate = |sum: &mut [Rgb], i: usize, f: f32| {
        for (s, v) in sum.iter_mut().zip(&source[i * stride..(i + 1) * stride]) {
            if v.is_finite() {
                *s += *v * f;
            }
        }
    };
    let finish = |pixel: &mut [Rgb], sum: &[Rgb], x: usize, y: usize| {
        let scale = 1.0 / ((nx[x] * ny[y]) as f32);
        for (out, s) in pixel.iter_mut().zip(sum) {
            *out = *s * scale;
        }
    };
    if reach > max_reach.min(MAX_REACH) {
        out.par_chunks_mut(width * stride).enumerate().for_each(|(y, row)| {
            let cy = y as f32 + 0.5;
            let mut sum = vec![Rgb::BLACK; stride];
            for (x, pixel) in row.chunks_mut(stride).enumerate() {
                let cx = x as f32 + 0.5;
                sum.fill(Rgb::BLACK);
                for sy in rows(y) {
                    for sx in columns(x) {
                        let i = sy * width + sx;
                        let p = positions[i];
                        let f = filter.profile_1d(p.x - cx) * filter.profile_1d(p.y - cy);
                        if f != 0.0 {
                            accumulate(&mut sum, i, f);
                        }
                    }
                }
                finish(pixel, &sum, x, y);
            }
        });
        *values = out;
        return;
    }
    let taps_of = |i: usize| {
        let (p, sx, sy) = (positions[i], i % width, i / width);
        let mut taps = Taps { x: [0.0; TAPS], y: [0.0; TAPS] };
        for k in 0..=2 * reach {
            // Pixel centres sx + k − reach and sy + k − reach (outside the image: never read).
            let cx = (sx + k) as f32 - reach as f32 + 0.5;
            let cy = (sy + k) as f32 - reach as f32 + 0.5;
            taps.x[k] = filter.profile_1d(p.x - cx);
            taps.y[k] = filter.profile_1d(p.y - cy);
        }
        taps
    };
    let mut taps = Vec::new();
    for (band, band_out) in out.chunks_mut(BAND_ROWS * width * stride).enumerate() {
        let first = band * BAND_ROWS;
        let last = (first + BAND_ROWS).min(height);
        let (lo, hi) = (first.saturating_sub(reach), (last + reach).min(height));
        (lo * width..hi * width).into_par_iter().map(taps_of).collect_into_vec(&mut taps);
        band_out.par_chunks_mut(width * stride).enumerate().for_each(|(row_in_band, row)| {
            let y = first + row_in_band;
            if stride == 1 {
                // The frame alone (the common case): each source of the rows in reach scatters
                // into a padded row of sums (index x + MAX_REACH). Every pixel still receives
                // its neighbours in row-major order, and adding the zero products of filter
                // zeros and non-finite (blackened) sources leaves a sum that starts at +0
                // unchanged, so the bits are those of the gather.
                let mut sums = vec![Rgb::BLACK; width + 2 * MAX_REACH];
                for sy in rows(y) {
                    let ty = y + reach - sy;
                    let row_taps = &taps[(sy - lo) * width..(sy - lo + 1) * width];
                    let row_values = &source[sy * width..(sy + 1) * width];
                    for (sx, (t, v)) in row_taps.iter().zip(row_values).enumerate() {
                        let v = if v.is_finite() { *v } else { Rgb::BLACK };
                        let fy = t.y[ty];
                        let targets = &mut sums[sx + MAX_REACH - reach..][..2 * reach + 1];
                        for (sum, fx) in targets.iter_mut().zip(&t.x) {
                            *sum += v * (fx * fy);
                        }
                    }
                }
                for (x, (pixel, sum)) in row.iter_mut().zip(&sums[MAX_REACH..]).enumerate() {
                    finish(std::slice::from_mut(pixel), std::slice::from_ref(sum), x, y);
                }
                return;
            }
            let mut sum = vec![Rgb::BLACK; stride];
            for (x, pixel) in row.chunks_mut(stride).enumerate() {
                sum.fill(Rgb::BLACK);
                for sy in rows(y) {
                    let ty = y + reach - sy;
                    for sx in columns(x) {
                        let i = sy * width + sx;
                        let t = &taps[i - lo * width];
                        let f = t.x[x + reach - sx] * t.y[ty];
                        if f != 0.0 {
                            accumulate(&mut sum, i, f);
                        }
                    }
                }
                finish(pixel, &sum, x, y);
            }
        });
    }
    *values = out;
}

/// Splats one iteration's camera values when the camera asks for it
/// ([`Camera::splats_camera_samples`]; nothing otherwise): the frame, and the per-family and
/// per-(s, t) values when recorded, so that they still sum to the frame. Call it after the
/// camera pass and before the light-tracing splats are added.
pub fn spread_camera_pass(
    camera: &Camera,
    seed: u64,
    iteration: u64,
    frame: &mut Vec<Rgb>,
    families: Option<&mut Vec<FamilyValues>>,
    techniques: Option<&mut TechniqueFrame>,
) {
    if !camera.splats_camera_samples() {
        return;
    }
    debug_assert_eq!(camera.film, FilmMode::Splat);
    let positions = sample_positions(camera, seed, iteration);
    spread(camera, &positions, frame, 1);
    if let Some(families) = families.filter(|f| !f.is_empty()) {
        let mut flat: Vec<Rgb> = families.iter().flat_map(|f| f.0).collect();
        spread(camera, &positions, &mut flat, 5);
        for (family, values) in families.iter_mut().zip(flat.chunks_exact(5)) {
            family.0.copy_from_slice(values);
        }
    }
    if let Some(techniques) = techniques {
        let stride = techniques.layout.len();
        spread(camera, &positions, &mut techniques.values, stride);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use math::Vec3;
    use scene::filter::Filter;

    /// The tap path gives the same bits as evaluating the filter per (sample, pixel) pair, over
    /// several bands, at the borders, with non-finite, negative and negative-zero values and with
    /// several values per pixel.
    #[test]
    fn taps_match_the_direct_evaluation_bit_for_bit() {
        let filters = [
            Filter::from_desc(&scene::desc::FilterDesc::Gaussian { stddev: 0.5, radius: 2.0 }).unwrap(),
            Filter::Tent { radius: 1.5 },
            Filter::Tent { radius: 1.0 },
            Filter::from_desc(&scene::desc::FilterDesc::Gaussian { stddev: 1.0, radius: 3.4 }).unwrap(),
        ];
        let (width, height) = (37u32, 2 * BAND_ROWS as u32 + 11);
        for filter in filters {
            let mut camera = Camera::new(Vec3::ZERO, Vec3::Z, Vec3::Y, 40.0, width, height).with_filter(filter);
            camera.film = FilmMode::Splat;
            let mut rng = Rng::for_stream(5, 0, 0);
            let positions: Vec<Vec2> = (0..camera.pixel_count())
                .map(|i| {
                    let u = rng.uniform2();
                    Vec2::new((i % width as usize) as f32 + u[0], (i / width as usize) as f32 + u[1])
                })
                .collect();
            for stride in [1, 3] {
                let mut values: Vec<Rgb> = (0..camera.pixel_count() * stride)
                    .map(|i| {
                        if i % 97 == 5 {
                            Rgb::splat(f32::NAN)
                        } else {
                            Rgb::new(rng.uniform() - 0.5, if i % 5 == 0 { -0.0 } else { 1.0 }, i as f32)
                        }
                    })
                    .collect();
                let mut direct = values.clone();
                spread_with(&camera, &positions, &mut values, stride, MAX_REACH);
                spread_with(&camera, &positions, &mut direct, stride, 0);
                let bits = |v: &[Rgb]| v.iter().flat_map(|c| [c.r, c.g, c.b]).map(f32::to_bits).collect::<Vec<_>>();
                assert_eq!(bits(&values), bits(&direct), "{filter:?}, stride {stride}");
                assert!(values.iter().all(|v| v.is_finite()));
            }
        }
    }

    /// Every splatted sample of an iteration sits at the same offset in its pixel, the offsets
    /// of successive iterations are uniform in [0,1)² (χ² over 8 × 8 cells, 4096 iterations;
    /// an offset confined to 7/8 of the pixel fails), and a constant image then splats to within
    /// 3 % of itself at interior pixels for Mitsuba's gaussian (lattice sum 1 ± 1.43 % per axis) and exactly for the tent of
    /// radius 1 (lattice sums), where independent offsets per pixel miss by tens of percent.
    #[test]
    fn splatted_samples_share_one_uniform_offset_per_iteration() {
        let gaussian = Filter::from_desc(&scene::desc::FilterDesc::Gaussian { stddev: 0.5, radius: 2.0 }).unwrap();
        let (width, height) = (24u32, 20u32);
        let mut camera = Camera::new(Vec3::ZERO, Vec3::Z, Vec3::Y, 40.0, width, height).with_filter(gaussian);
        camera.film = FilmMode::Splat;
        let cells = 8usize;
        let (mut counts, mut confined) = (vec![0u32; cells * cells], vec![0u32; cells * cells]);
        let iterations = 4096u64;
        for iteration in 0..iterations {
            let positions = sample_positions(&camera, 3, iteration);
            let u = film_offset(3, iteration);
            for (i, p) in positions.iter().enumerate() {
                let corner = Vec2::new((i % width as usize) as f32, (i / width as usize) as f32);
                assert_eq!((p.x, p.y), (corner.x + u[0], corner.y + u[1]), "pixel {i}, iteration {iteration}");
            }
            let cell = |v: f32| ((v * cells as f32) as usize).min(cells - 1);
            counts[cell(u[1]) * cells + cell(u[0])] += 1;
            confined[cell(u[1] * 0.875) * cells + cell(u[0] * 0.875)] += 1;
        }
        let expected = iterations as f64 / (cells * cells) as f64;
        let chi2 = |c: &[u32]| c.iter().map(|&n| (f64::from(n) - expected).powi(2) / expected).sum::<f64>();
        // χ² with 63 degrees of freedom: 1 − 10⁻⁴ quantile ≈ 112.
        assert!(chi2(&counts) < 112.0, "offsets not uniform: χ² = {}", chi2(&counts));
        assert!(chi2(&confined) > 112.0, "the test cannot see a confined offset: χ² = {}", chi2(&confined));
        for (filter, tolerance) in [(gaussian, 0.03), (Filter::Tent { radius: 1.0 }, 1e-5)] {
            let camera = camera.with_filter(filter);
            for iteration in 0..64 {
                let positions = sample_positions(&camera, 9, iteration);
                let mut values = vec![Rgb::splat(1.0); camera.pixel_count()];
                spread(&camera, &positions, &mut values, 1);
                for y in 3..height - 3 {
                    for x in 3..width - 3 {
                        let v = values[(y * width + x) as usize].r;
                        assert!((v - 1.0).abs() < tolerance, "{filter:?}: pixel ({x}, {y}) = {v}");
                    }
                }
            }
        }
    }
}
