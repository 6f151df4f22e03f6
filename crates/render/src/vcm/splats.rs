//! The light-tracing splats (t = 1) of one iteration, summed per pixel as they are traced.
//!
//! A splat lands on any pixel, so it cannot be added to the frame while camera paths are still
//! writing it. Instead of keeping every splat of the iteration until the camera pass is over
//! (28 bytes each, about one per light sub-path), both modes add them, in light sub-path order,
//! into one sum per pixel (12 bytes) and add the sums to the frame at the end: the order of the
//! additions, hence the image, is the same in both modes and for any thread count. Only when
//! technique families or (s, t) images are recorded are the splats also kept, to be filed there
//! once the camera pass has filled those frames.

use scene::Camera;
use spectrum::Rgb;

use super::connect::{Splat, SplatTarget};
use super::technique_images::TechniqueFrame;
use super::{Family, FamilyValues, RejectedCounts};

/// How many splats ahead [`SplatSums::add`] prefetches a pixel's sum.
const SPLAT_AHEAD: usize = 8;

/// Per-pixel sums of one iteration's splats, and the splats themselves when recorded.
#[derive(Debug, Default)]
pub(super) struct SplatSums {
    /// Sum of the splats per pixel (linear sRGB, the frame's units); allocated at the first
    /// splat (photon mapping never splats).
    sums: Vec<Rgb>,
    /// Pixels of the iteration.
    pixels: usize,
    /// The splats in light sub-path order, when families or (s, t) images are recorded.
    kept: Vec<Vec<Splat>>,
    /// Whether to keep them.
    keep: bool,
    /// Splats added.
    count: usize,
    /// Non-finite splats (added as black).
    rejected: u64,
}

impl SplatSums {
    /// Starts an iteration of `pixels` pixels; `keep` keeps the splats for family or (s, t)
    /// images.
    pub(super) fn start(&mut self, pixels: usize, keep: bool) {
        self.sums.clear();
        self.pixels = pixels;
        self.kept.clear();
        self.keep = keep;
        self.count = 0;
        self.rejected = 0;
    }

    /// Adds `splats`, the next ones in light sub-path order: a pixel splat to its pixel, a
    /// filtered splat to every pixel within the camera filter's radius, weighted by the filter.
    /// The splats are moved out of `splats` when kept; otherwise `splats` is left as it was (the
    /// caller may reuse its allocation).
    pub(super) fn add(&mut self, camera: &Camera, splats: &mut Vec<Splat>) {
        self.count += splats.len();
        if !splats.is_empty() && self.sums.is_empty() {
            self.sums.resize(self.pixels, Rgb::BLACK);
        }
        for (index, splat) in splats.iter().enumerate() {
            // The pixels of the splats lie anywhere in the frame: start the miss of a later one.
            if let Some(SplatTarget::Pixel(pixel)) = splats.get(index + SPLAT_AHEAD).map(|s| s.target)
                && let Some(sum) = self.sums.get(pixel as usize)
            {
                crate::prefetch::prefetch(sum);
            }
            if !splat.value.is_finite() {
                self.rejected += 1;
            }
            let sums = &mut self.sums;
            spread(camera, splat, |pixel, value| sums[pixel as usize] += value);
        }
        if self.keep {
            self.kept.push(std::mem::take(splats));
        }
    }

    /// Adds the sums to `frame` (the camera pass's values) and the kept splats to the family and
    /// technique frames; counts the non-finite splats in `rejected`. Returns the number of
    /// splats.
    pub(super) fn finish(
        &mut self,
        frame: &mut [Rgb],
        camera: &Camera,
        mut family_frames: Option<&mut Vec<FamilyValues>>,
        mut technique_frame: Option<&mut TechniqueFrame>,
        rejected: &mut RejectedCounts,
    ) -> usize {
        for (pixel, sum) in frame.iter_mut().zip(&self.sums) {
            *pixel += *sum;
        }
        rejected[Family::LightTracing as usize] += self.rejected;
        let mut file = |pixel: u32, s: u32, value: Rgb| {
            if let Some(families) = family_frames.as_deref_mut() {
                families[pixel as usize].add(Family::LightTracing, value);
            }
            if let Some(techniques) = technique_frame.as_deref_mut() {
                techniques.add_splat(pixel as usize, s, value);
            }
        };
        for splat in self.kept.iter().flatten() {
            spread(camera, splat, |pixel, value| file(pixel, splat.s, value));
        }
        self.kept.clear();
        self.count
    }
}

/// Calls `add(pixel, value)` for every pixel `splat` reaches: a pixel splat its pixel, a
/// filtered splat every pixel within the camera filter's radius, weighted by the filter. A
/// non-finite splat adds black.
fn spread(camera: &Camera, splat: &Splat, mut add: impl FnMut(u32, Rgb)) {
    let value = if splat.value.is_finite() { splat.value } else { Rgb::BLACK };
    match splat.target {
        SplatTarget::Pixel(pixel) => add(pixel, value),
        SplatTarget::Filtered(raster) => {
            for (pixel, filter) in camera.filter_pixels(raster) {
                add(pixel, value * filter);
            }
        }
    }
}
