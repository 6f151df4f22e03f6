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
//! the lattice's offset, [`film_offset`], is all [`spread_lattice`] needs, and on a lattice the
//! filter sum is a separable convolution with one list of weights per axis and iteration.

use math::Rng;
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

/// Largest offset (pixels, per axis) between the pixel holding a sample and a pixel whose centre
/// its filter reaches: a sample lies in its own pixel `[s, s + 1)`, so `|p − c| < radius` needs
/// `|s − x| < radius + ½`.
fn reach_of(radius: f32) -> usize {
    ((radius + 0.5).ceil() as usize).saturating_sub(1)
}

/// Buffers of [`spread_lattice`] and [`spread_camera_pass`], which the path tracer keeps from
/// iteration to iteration: allocated anew each time, the two image-sized buffers (12 bytes per
/// value each) came fresh from the kernel every iteration, whose page faults and unmapping cost
/// a two-thread `pt` render of Mitsuba's Cornell box about 3 % of its time (docs/performance.md,
/// "Buffers kept across iterations"). Reusing them changes no value. (The VCM engine passes
/// fresh ones, freed before its next light pass, so that they do not add to its peak memory.)
#[derive(Clone, Debug, Default)]
pub struct SpreadScratch {
    /// The values as flat float triples (the row pass's input, then the column pass's output).
    triples: Vec<[f32; 3]>,
    /// The row pass's sums, three floats per value.
    along_rows: Vec<f32>,
    /// The per-family values of the camera pass, five per pixel.
    families: Vec<Rgb>,
}

/// Replaces `values` (`stride` values per pixel, row-major, the camera samples' own values) by
/// their splatted image, for samples at their pixel's corner plus `offset` (as
/// [`Camera::sample_primary`] places them when splatting): value `c` of pixel `j` becomes
/// `Σ_i w_j(x_i) values[i·stride + c]` with `w_j` = [`Camera::splat_weight`]. Non-finite values
/// count as black.
///
/// On a shifted lattice the offset from a sample to a pixel centre `d` pixels away is the same
/// for every sample, `u − ½ − d` per axis, so the separable filter's weights are one short list
/// per axis for the whole iteration, and the sum is a separable convolution: a pass along the
/// rows with the x weights, then along the columns with the y weights (2·(2·reach + 1)
/// multiply-adds per value instead of (2·reach + 1)²). Parallel over rows; each pixel sums in
/// a fixed order, so the result does not depend on the thread count.
pub fn spread_lattice(
    camera: &Camera,
    offset: [f32; 2],
    values: &mut [Rgb],
    stride: usize,
    scratch: &mut SpreadScratch,
) {
    let (width, height) = (camera.width as usize, camera.height as usize);
    assert_eq!(values.len(), width * height * stride, "stride values per pixel");
    if stride == 0 || values.is_empty() {
        return;
    }
    let filter = &camera.filter;
    let reach = reach_of(filter.radius());
    // weights[k]: the filter towards the pixel d = k − reach pixels after the sample's own.
    let weights = |u: f32| -> Vec<f32> {
        (0..=2 * reach).map(|k| filter.profile_1d(u - 0.5 - (k as f32 - reach as f32))).collect()
    };
    let (wx, wy) = (weights(offset[0]), weights(offset[1]));
    // The sums run over flat lists of floats (three per value) rather than over `Rgb`s, so that
    // each multiply-add pass is a plain loop over contiguous floats that the compiler
    // vectorises. Every float still takes the same operations in the same order (one
    // multiplication and one addition per tap), so the result is the same to the bit.
    let per_pixel = 3 * stride;
    let row_len = width * per_pixel;
    // Non-finite values count as black: they enter the flat copy as zeros, which adds exactly
    // zero where the pairwise sum skipped them.
    let SpreadScratch { triples, along_rows, .. } = scratch;
    triples.clear();
    triples.par_extend(values.par_iter().map(|v| if v.is_finite() { [v.r, v.g, v.b] } else { [0.0; 3] }));
    // Along the rows: each pixel x gathers the samples sx = x + reach − k of its row for
    // k = 0..=2·reach, in increasing k (tap k outer, so each pass is a multiply-add over a
    // contiguous run without per-tap range checks, and every pixel still sums its taps in the
    // pairwise order); taps outside the row are skipped.
    along_rows.resize(triples.len() * 3, 0.0);
    along_rows.par_chunks_mut(row_len).zip(triples.as_flattened().par_chunks(row_len)).for_each(|(out, source)| {
        // The buffer holds the previous iteration's sums.
        out.fill(0.0);
        for (k, &w) in wx.iter().enumerate() {
            // sx ∈ [0, width) ⇔ x ∈ [k − reach, width + k − reach).
            let x_first = k.saturating_sub(reach);
            let x_end = (width + k).saturating_sub(reach).min(width);
            if x_first >= x_end {
                continue;
            }
            let n = (x_end - x_first) * per_pixel;
            let sources = &source[(x_first + reach - k) * per_pixel..][..n];
            for (o, v) in out[x_first * per_pixel..][..n].iter_mut().zip(sources) {
                *o += *v * w;
            }
        }
    });
    // N_j per axis (the product is Camera::splat_normalization).
    let nx: Vec<f64> = (0..width).map(|x| filter.clipped_integral_1d(x as f32 + 0.5, width as f32)).collect();
    let ny: Vec<f64> = (0..height).map(|y| filter.clipped_integral_1d(y as f32 + 0.5, height as f32)).collect();
    let along_rows = &along_rows[..];
    // Along the columns (into the flat copy, no longer needed), then the division by N_j on
    // the way back into `values`. The first tap of a row (there is one: k = reach, sy = y)
    // writes `0 + v·w`, what adding it to a zeroed row gives, so the rows need no clearing.
    triples.par_chunks_mut(width * stride).zip(values.par_chunks_mut(width * stride)).enumerate().for_each(
        |(y, (row, result))| {
            let out = row.as_flattened_mut();
            let mut first = true;
            for (k, &w) in wy.iter().enumerate() {
                let Some(sy) = (y + reach).checked_sub(k).filter(|&sy| sy < height) else { continue };
                let source = &along_rows[sy * row_len..(sy + 1) * row_len];
                if first {
                    for (o, v) in out.iter_mut().zip(source) {
                        *o = 0.0 + *v * w;
                    }
                    first = false;
                } else {
                    for (o, v) in out.iter_mut().zip(source) {
                        *o += *v * w;
                    }
                }
            }
            let ny = ny[y];
            let scale = |n: f64| 1.0 / ((n * ny) as f32);
            if stride == 1 {
                // The frame: one value per pixel, without the inner loop.
                for ((v, c), &n) in result.iter_mut().zip(row.iter()).zip(&nx) {
                    *v = Rgb::new(c[0], c[1], c[2]) * scale(n);
                }
            } else {
                for ((pixel, sums), &n) in result.chunks_exact_mut(stride).zip(row.chunks_exact(stride)).zip(&nx) {
                    let scale = scale(n);
                    for (v, c) in pixel.iter_mut().zip(sums) {
                        *v = Rgb::new(c[0], c[1], c[2]) * scale;
                    }
                }
            }
        },
    );
}

/// Splats one iteration's camera values when the camera asks for it
/// ([`Camera::splats_camera_samples`]; nothing otherwise): the frame, and the per-family and
/// per-(s, t) values when recorded, so that they still sum to the frame. Call it after the
/// camera pass and before the light-tracing splats are added.
pub fn spread_camera_pass(
    camera: &Camera,
    seed: u64,
    iteration: u64,
    frame: &mut [Rgb],
    families: Option<&mut Vec<FamilyValues>>,
    techniques: Option<&mut TechniqueFrame>,
    scratch: &mut SpreadScratch,
) {
    if !camera.splats_camera_samples() {
        return;
    }
    debug_assert_eq!(camera.film, FilmMode::Splat);
    let offset = film_offset(seed, iteration);
    spread_lattice(camera, offset, frame, 1, scratch);
    if let Some(families) = families.filter(|f| !f.is_empty()) {
        let mut flat = std::mem::take(&mut scratch.families);
        flat.clear();
        flat.extend(families.iter().flat_map(|f| f.0));
        spread_lattice(camera, offset, &mut flat, 5, scratch);
        for (family, values) in families.iter_mut().zip(flat.chunks_exact(5)) {
            family.0.copy_from_slice(values);
        }
        scratch.families = flat;
    }
    if let Some(techniques) = techniques {
        let stride = techniques.layout.len();
        spread_lattice(camera, offset, &mut techniques.values, stride, scratch);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use math::Vec2;
    use math::Vec3;
    use scene::filter::Filter;

    /// The raster positions of iteration `iteration`'s camera samples, as
    /// [`Camera::sample_primary`] places them when splatting.
    fn sample_positions(camera: &Camera, seed: u64, iteration: u64) -> Vec<Vec2> {
        let width = camera.width as usize;
        let offset = film_offset(seed, iteration);
        (0..camera.pixel_count())
            .map(|index| camera.sample_pixel((index % width) as u32, (index / width) as u32, offset).0)
            .collect()
    }

    /// The splatted image by its definition: every pixel sums `w_j(x_i) v_i` over every sample
    /// `i` (in f64), then divides by `N_j`.
    fn pairwise(camera: &Camera, positions: &[Vec2], values: &[Rgb], stride: usize) -> Vec<[f64; 3]> {
        let (width, height) = (camera.width as usize, camera.height as usize);
        let f = &camera.filter;
        let mut out = vec![[0.0f64; 3]; values.len()];
        for j in 0..width * height {
            let (cx, cy) = ((j % width) as f32 + 0.5, (j / width) as f32 + 0.5);
            let n = f.clipped_integral_1d(cx, width as f32) * f.clipped_integral_1d(cy, height as f32);
            for (i, p) in positions.iter().enumerate() {
                let w = f64::from(f.profile_1d(p.x - cx)) * f64::from(f.profile_1d(p.y - cy));
                for c in 0..stride {
                    let v = values[i * stride + c];
                    if w != 0.0 && v.is_finite() {
                        for (o, x) in out[j * stride + c].iter_mut().zip([v.r, v.g, v.b]) {
                            *o += w * f64::from(x) / n;
                        }
                    }
                }
            }
        }
        out
    }

    /// The separable lattice sum agrees with the pairwise definition to float rounding, for
    /// several filters (gaussian radius 2 and 3.4, tents), at the borders, with non-finite
    /// values (black) and with several values per pixel.
    #[test]
    fn lattice_spread_matches_the_pairwise_sum() {
        let filters = [
            Filter::from_desc(&scene::desc::FilterDesc::Gaussian { stddev: 0.5, radius: 2.0 }).unwrap(),
            Filter::Tent { radius: 1.5 },
            Filter::Tent { radius: 1.0 },
            Filter::from_desc(&scene::desc::FilterDesc::Gaussian { stddev: 1.0, radius: 3.4 }).unwrap(),
        ];
        let (width, height) = (23u32, 17u32);
        // One scratch for every case: what a case leaves in it must not reach the next.
        let mut scratch = SpreadScratch::default();
        for filter in filters {
            let mut camera = Camera::new(Vec3::ZERO, Vec3::Z, Vec3::Y, 40.0, width, height).with_filter(filter);
            camera.film = FilmMode::Splat;
            let mut rng = Rng::for_stream(5, 0, 0);
            for (iteration, stride) in [(0, 1), (1, 3)] {
                let values: Vec<Rgb> = (0..camera.pixel_count() * stride)
                    .map(|i| {
                        if i % 97 == 5 {
                            Rgb::splat(f32::NAN)
                        } else {
                            Rgb::new(rng.uniform() - 0.5, if i % 5 == 0 { -0.0 } else { 1.0 }, i as f32)
                        }
                    })
                    .collect();
                let expected = pairwise(&camera, &sample_positions(&camera, 7, iteration), &values, stride);
                let mut spread = values.clone();
                spread_lattice(&camera, film_offset(7, iteration), &mut spread, stride, &mut scratch);
                assert!(spread.iter().all(|v| v.is_finite()), "non-finite values count as black");
                for (i, (got, want)) in spread.iter().zip(&expected).enumerate() {
                    for (g, w) in [got.r, got.g, got.b].into_iter().zip(want) {
                        let scale = 1.0 + w.abs();
                        assert!(
                            (f64::from(g) - w).abs() < 1e-5 * scale,
                            "{filter:?}, stride {stride}, value {i}: {g} vs {w}"
                        );
                    }
                }
            }
        }
    }

    /// The separable sum over `Rgb` values as it was before [`spread_lattice`] ran over flat
    /// floats: the reference for the bit-identity test below.
    fn spread_lattice_rgb(camera: &Camera, offset: [f32; 2], values: &mut [Rgb], stride: usize) {
        let (width, height) = (camera.width as usize, camera.height as usize);
        let filter = &camera.filter;
        let reach = reach_of(filter.radius());
        let weights = |u: f32| -> Vec<f32> {
            (0..=2 * reach).map(|k| filter.profile_1d(u - 0.5 - (k as f32 - reach as f32))).collect()
        };
        let (wx, wy) = (weights(offset[0]), weights(offset[1]));
        let row_len = width * stride;
        values.iter_mut().filter(|v| !v.is_finite()).for_each(|v| *v = Rgb::BLACK);
        let mut along_rows = vec![Rgb::BLACK; values.len()];
        for (out, source) in along_rows.chunks_mut(row_len).zip(values.chunks(row_len)) {
            for (k, &w) in wx.iter().enumerate() {
                let x_first = k.saturating_sub(reach);
                let x_end = (width + k).saturating_sub(reach).min(width);
                if x_first >= x_end {
                    continue;
                }
                let n = (x_end - x_first) * stride;
                let sources = &source[(x_first + reach - k) * stride..][..n];
                for (o, v) in out[x_first * stride..][..n].iter_mut().zip(sources) {
                    *o += *v * w;
                }
            }
        }
        let nx: Vec<f64> = (0..width).map(|x| filter.clipped_integral_1d(x as f32 + 0.5, width as f32)).collect();
        let ny: Vec<f64> = (0..height).map(|y| filter.clipped_integral_1d(y as f32 + 0.5, height as f32)).collect();
        for (y, out) in values.chunks_mut(row_len).enumerate() {
            out.fill(Rgb::BLACK);
            for (k, w) in wy.iter().enumerate() {
                let Some(sy) = (y + reach).checked_sub(k).filter(|&sy| sy < height) else { continue };
                for (o, v) in out.iter_mut().zip(&along_rows[sy * row_len..(sy + 1) * row_len]) {
                    *o += *v * *w;
                }
            }
            for (x, pixel) in out.chunks_mut(stride).enumerate() {
                let scale = 1.0 / ((nx[x] * ny[y]) as f32);
                for v in pixel {
                    *v *= scale;
                }
            }
        }
    }

    /// The flat-float sum gives the same bits as the sum over `Rgb`s (gaussian and tent
    /// filters, one and three values per pixel, non-finite values, negative zeros).
    #[test]
    fn flat_spread_is_bit_identical_to_the_rgb_spread() {
        let filters = [
            Filter::from_desc(&scene::desc::FilterDesc::Gaussian { stddev: 0.5, radius: 2.0 }).unwrap(),
            Filter::Tent { radius: 1.5 },
            Filter::Box,
        ];
        // One scratch for every case (strides 1, 3, 5, then 1 again): reused buffers must give
        // the bits of the reference.
        let mut scratch = SpreadScratch::default();
        for filter in filters {
            let mut camera = Camera::new(Vec3::ZERO, Vec3::Z, Vec3::Y, 40.0, 19, 11).with_filter(filter);
            camera.film = FilmMode::Splat;
            let mut rng = Rng::for_stream(11, 0, 0);
            for (iteration, stride) in [(0, 1), (1, 3), (2, 5)] {
                let values: Vec<Rgb> = (0..camera.pixel_count() * stride)
                    .map(|i| match i % 41 {
                        3 => Rgb::new(f32::INFINITY, 1.0, 2.0),
                        7 => Rgb::splat(f32::NAN),
                        11 => Rgb::new(-0.0, 0.0, -0.0),
                        _ => Rgb::new(rng.uniform() - 0.5, rng.uniform() * 1e3, -rng.uniform()),
                    })
                    .collect();
                let offset = film_offset(13, iteration);
                let (mut flat, mut rgb) = (values.clone(), values);
                spread_lattice(&camera, offset, &mut flat, stride, &mut scratch);
                spread_lattice_rgb(&camera, offset, &mut rgb, stride);
                for (i, (a, b)) in flat.iter().zip(&rgb).enumerate() {
                    let bits = |v: &Rgb| [v.r.to_bits(), v.g.to_bits(), v.b.to_bits()];
                    assert_eq!(bits(a), bits(b), "{filter:?}, stride {stride}, value {i}");
                }
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
                let mut values = vec![Rgb::splat(1.0); camera.pixel_count()];
                spread_lattice(&camera, film_offset(9, iteration), &mut values, 1, &mut SpreadScratch::default());
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
