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
//! The raster points are not carried out of the camera passes: every camera pass starts pixel
//! `i`'s camera sub-path from [`camera_stream`], whose first two numbers
//! [`Camera::sample_primary`] turns into the raster point, so [`sample_positions`] draws them
//! again from the same streams.

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

/// The raster positions (pixels) of the camera samples of iteration `iteration`, per pixel
/// (row-major), as [`Camera::sample_primary`] draws them from [`camera_stream`].
pub fn sample_positions(camera: &Camera, seed: u64, iteration: u64) -> Vec<Vec2> {
    let width = camera.width as usize;
    (0..camera.pixel_count())
        .into_par_iter()
        .map(|index| {
            let (x, y) = ((index % width) as u32, (index / width) as u32);
            camera.sample_pixel(x, y, camera_stream(seed, iteration, index).uniform2()).0
        })
        .collect()
}

/// Replaces `values` (`stride` values per pixel, row-major, the camera samples' own values) by
/// their splatted image: value `c` of pixel `j` becomes `Σ_i w_j(x_i) values[i·stride + c]`
/// with `w_j` = [`Camera::splat_weight`] and `x_i` = `positions[i]`. Non-finite values count as
/// black. Parallel over rows; each pixel sums its neighbours in row-major order.
pub fn spread(camera: &Camera, positions: &[Vec2], values: &mut Vec<Rgb>, stride: usize) {
    let (width, height) = (camera.width as usize, camera.height as usize);
    assert_eq!(positions.len(), width * height, "one raster position per pixel");
    assert_eq!(values.len(), width * height * stride, "stride values per pixel");
    if stride == 0 {
        return;
    }
    // Samples lie in their own pixel: only pixels within radius + 1 can reach a pixel centre.
    let reach = camera.filter.radius().ceil() as usize + 1;
    let source = std::mem::take(values);
    let mut out = vec![Rgb::BLACK; source.len()];
    out.par_chunks_mut(width * stride).enumerate().for_each(|(y, row)| {
        let cy = y as f32 + 0.5;
        let rows = y.saturating_sub(reach)..(y + reach + 1).min(height);
        let mut sum = vec![Rgb::BLACK; stride];
        for (x, pixel) in row.chunks_mut(stride).enumerate() {
            let cx = x as f32 + 0.5;
            sum.fill(Rgb::BLACK);
            for sy in rows.clone() {
                for sx in x.saturating_sub(reach)..(x + reach + 1).min(width) {
                    let i = sy * width + sx;
                    let p = positions[i];
                    let f = camera.filter.profile_1d(p.x - cx) * camera.filter.profile_1d(p.y - cy);
                    if f == 0.0 {
                        continue;
                    }
                    for (s, v) in sum.iter_mut().zip(&source[i * stride..(i + 1) * stride]) {
                        if v.is_finite() {
                            *s += *v * f;
                        }
                    }
                }
            }
            let scale = 1.0 / camera.splat_normalization(x as u32, y as u32);
            for (out, s) in pixel.iter_mut().zip(&sum) {
                *out = *s * scale;
            }
        }
    });
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
