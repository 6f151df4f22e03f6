//! Per-(s, t) technique images: every contribution of the engine filed under the technique
//! that produced it, so that the images sum to the iteration's frame.
//!
//! **Conventions.** A full path `y_0 … y_{s−1} z_{t−1} … z_0` joins a light sub-path of `s`
//! vertices (`y_0` on the light) and a camera sub-path of `t` vertices (`z_0` on the camera), as
//! in Veach's thesis and the VCM tech report; the path has `s + t − 1` segments.
//!
//! - `s = 0`: the camera sub-path hits an emitter or escapes to the environment (the emitter or
//!   environment vertex is `z_{t−1}`), so a light seen directly is `s0-t2` (light tracing
//!   alone finds these paths as `s = 1, t = 1` and files them under the same image, the only
//!   one of length 1);
//! - `s = 1`: next-event estimation at camera vertex `z_{t−2}`;
//! - `t = 1`: light tracing, light vertex `y_{s−1}` connected to the camera;
//! - `s, t ≥ 2`: vertex connection of `y_{s−1}` and `z_{t−1}`.
//!
//! **Vertex merging** keeps the counts of its two sub-paths: `s` light vertices *including* the
//! merged vertex `y_{s−1}` and `t` camera vertices including `z_{t−1}`, the vertex `y_{s−1}` is
//! merged with. The two coincide in the full path, which therefore has `s + t − 1` vertices and
//! `s + t − 2` segments (one fewer than a connection with the same `s, t`). A merged path is a
//! different technique from every connection of the same length, so merges have their own
//! images: `merge-s2-t2` is direct illumination (light → surface ≈ surface → camera).
//!
//! **Length.** Images exist for every technique the engine has of up to
//! [`TechniqueLayout::max_length`] *segments*: `s0-t2` of length 1, then for each length
//! `k ≥ 2` the `k + 1` techniques `s0-t(k+1)`, `s1-tk`, …, `sk-t1` and the `k − 1` merges
//! `merge-s2-tk`, …, `merge-sk-t2`. Everything longer goes to one bucket per family
//! (`longer-emitter-hit`, `longer-next-event`, `longer-light-tracing`, `longer-connection`,
//! `longer-merging`), so the images always sum to the frame. The engine has no `s1-t1`
//! (light tracing starts at the first vertex after the light) and no `s = 0` light tracing.
//!
//! Every image holds MIS-weighted contributions in the units of the frame (radiance times the
//! pixel filter's normalisation), and the sum over all images equals the frame up to float
//! rounding: the merges at one camera vertex are summed once for the frame and once per image.

use spectrum::Rgb;

use super::{Family, FamilyValues};

/// One per-(s, t) image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TechniqueImage {
    /// A connection-type technique: `s` light and `t` camera sub-path vertices (s = 0 emitter
    /// hit, s = 1 next-event estimation, t = 1 light tracing, otherwise vertex connection).
    Path {
        /// Light sub-path vertices.
        s: u32,
        /// Camera sub-path vertices.
        t: u32,
    },
    /// Vertex merging with `s` light sub-path vertices (the merged one included) and `t` camera
    /// sub-path vertices.
    Merge {
        /// Light sub-path vertices, the merged vertex included.
        s: u32,
        /// Camera sub-path vertices, the vertex merged at included.
        t: u32,
    },
    /// All contributions of a family longer than the layout's maximum length.
    Longer(Family),
}

impl TechniqueImage {
    /// The file-name stem: `s0-t2`, `merge-s2-t2`, `longer-connection`.
    pub fn name(self) -> String {
        match self {
            TechniqueImage::Path { s, t } => format!("s{s}-t{t}"),
            TechniqueImage::Merge { s, t } => format!("merge-s{s}-t{t}"),
            TechniqueImage::Longer(family) => format!("longer-{}", family.name()),
        }
    }

    /// The family the technique belongs to.
    pub fn family(self) -> Family {
        match self {
            TechniqueImage::Path { s: 0, .. } => Family::EmitterHit,
            TechniqueImage::Path { s: 1, .. } => Family::NextEvent,
            TechniqueImage::Path { t: 1, .. } => Family::LightTracing,
            TechniqueImage::Path { .. } => Family::Connection,
            TechniqueImage::Merge { .. } => Family::Merging,
            TechniqueImage::Longer(family) => family,
        }
    }
}

/// The largest [`TechniqueLayout::max_length`] accepted: 76 images, whose buffers take
/// 36 bytes per image and pixel.
pub const MAX_TECHNIQUE_LENGTH: u32 = 8;

/// Which images exist and where each contribution goes: the connection-type techniques by
/// length, then the merges by length, then the five "longer" buckets ([`Family::ALL`] order).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TechniqueLayout {
    max_length: u32,
}

impl TechniqueLayout {
    /// Images for techniques of up to `max_length` segments (1 to [`MAX_TECHNIQUE_LENGTH`]).
    pub fn new(max_length: u32) -> Result<Self, String> {
        if !(1..=MAX_TECHNIQUE_LENGTH).contains(&max_length) {
            return Err(format!("the technique length must be 1 to {MAX_TECHNIQUE_LENGTH} segments, not {max_length}"));
        }
        Ok(Self { max_length })
    }

    /// The longest technique (in segments) with its own image.
    pub fn max_length(&self) -> u32 {
        self.max_length
    }

    /// Connection-type images: 1 of length 1, k + 1 of each length k ≥ 2.
    fn path_count(&self) -> usize {
        let n = self.max_length as usize;
        (n + 1) * (n + 2) / 2 - 2
    }

    /// Merge images: k − 1 of each length k ≥ 2.
    fn merge_count(&self) -> usize {
        let n = self.max_length as usize;
        n * (n - 1) / 2
    }

    /// The number of images.
    pub fn len(&self) -> usize {
        self.path_count() + self.merge_count() + Family::ALL.len()
    }

    /// Never empty (kept for the `len`/`is_empty` convention).
    pub fn is_empty(&self) -> bool {
        false
    }

    /// The index of the image that a contribution of `family` with `s` light and `t` camera
    /// sub-path vertices belongs to (for merges `s` includes the merged vertex).
    #[inline]
    pub fn index(&self, family: Family, s: u32, t: u32) -> usize {
        let longer = self.path_count() + self.merge_count() + family as usize;
        let n = self.max_length;
        if family == Family::Merging {
            let k = (s + t).saturating_sub(2);
            if s < 2 || t < 2 || k > n {
                return longer;
            }
            let k = k as usize;
            self.path_count() + (k - 2) * (k - 1) / 2 + (s as usize - 2)
        } else {
            debug_assert!(
                matches!((family, s, t), (Family::EmitterHit, 0, 2..) | (Family::NextEvent, 1, 2..))
                    || matches!((family, s, t), (Family::LightTracing, 1.., 1) | (Family::Connection, 2.., 2..)),
                "no {family:?} technique with s = {s}, t = {t}"
            );
            let k = (s + t).saturating_sub(1);
            // Length 1 has one image: the camera sees an emitter (s = 0, t = 2, or light tracing
            // alone connecting the emitter's point, s = 1, t = 1).
            if k > n || (k == 1 && s > 1) || t == 0 {
                return longer;
            }
            let k = k as usize;
            if k == 1 { 0 } else { k * (k + 1) / 2 - 2 + s as usize }
        }
    }

    /// The image at `index` (`index < len()`).
    pub fn image(&self, index: usize) -> TechniqueImage {
        let n = self.max_length;
        let mut i = index;
        if i < self.path_count() {
            if i == 0 {
                return TechniqueImage::Path { s: 0, t: 2 };
            }
            i -= 1;
            for k in 2..=n {
                if i <= k as usize {
                    let s = i as u32;
                    return TechniqueImage::Path { s, t: k + 1 - s };
                }
                i -= k as usize + 1;
            }
        }
        i = index - self.path_count();
        if i < self.merge_count() {
            for k in 2..=n {
                if i < (k - 1) as usize {
                    let s = i as u32 + 2;
                    return TechniqueImage::Merge { s, t: k + 2 - s };
                }
                i -= (k - 1) as usize;
            }
        }
        TechniqueImage::Longer(Family::ALL[(index - self.path_count() - self.merge_count()).min(4)])
    }

    /// All images in index order.
    pub fn images(&self) -> Vec<TechniqueImage> {
        (0..self.len()).map(|i| self.image(i)).collect()
    }
}

/// Where the camera pass puts its contributions: by family ([`FamilyValues`], the plain
/// render) or by family and (s, t) ([`TechniqueValues`], technique images requested).
pub trait Record {
    /// Whether contributions are wanted per (s, t); when false, merges are summed without
    /// looking at the individual light vertices ([`Record::stage_merge`] is never called).
    const PER_TECHNIQUE: bool;

    /// Adds a contribution of `family` with `s` light and `t` camera sub-path vertices (for
    /// merges: all merges at one camera vertex, `s` ignored, after their parts were staged). A
    /// NaN or infinite value is counted against the family and never added.
    fn record(&mut self, family: Family, s: u32, t: u32, value: Rgb);

    /// One merged light vertex's part (`s` light vertices, the merged one included, `t` camera
    /// vertices) of the merges at the current camera vertex; it counts once their sum is
    /// recorded and is finite.
    fn stage_merge(&mut self, s: u32, t: u32, value: Rgb);
}

impl Record for FamilyValues {
    const PER_TECHNIQUE: bool = false;

    #[inline]
    fn record(&mut self, family: Family, _s: u32, _t: u32, value: Rgb) {
        self.add(family, value);
    }

    #[inline]
    fn stage_merge(&mut self, _s: u32, _t: u32, _value: Rgb) {}
}

/// Contributions of one camera sub-path by family and by (s, t) image.
#[derive(Debug)]
pub struct TechniqueValues<'a> {
    layout: TechniqueLayout,
    families: FamilyValues,
    /// This pixel's images ([`TechniqueLayout`] order).
    images: &'a mut [Rgb],
    /// Merge parts of the current camera vertex, per image (only merge images are touched).
    stage: &'a mut [Rgb],
}

impl<'a> TechniqueValues<'a> {
    /// Records into `images` (this pixel's `layout.len()` values, added to); `stage` is
    /// scratch space of the same length, all zero.
    pub fn new(layout: TechniqueLayout, images: &'a mut [Rgb], stage: &'a mut [Rgb]) -> Self {
        debug_assert_eq!(images.len(), layout.len());
        debug_assert_eq!(stage.len(), layout.len());
        Self { layout, families: FamilyValues::default(), images, stage }
    }

    /// The family values, after discarding an estimate whose sum overflows (in the images
    /// too), as [`FamilyValues`] does.
    pub fn finish(mut self) -> FamilyValues {
        if self.families.discard_overflow() {
            self.images.fill(Rgb::BLACK);
        }
        self.families
    }
}

impl Record for TechniqueValues<'_> {
    const PER_TECHNIQUE: bool = true;

    fn record(&mut self, family: Family, s: u32, t: u32, value: Rgb) {
        if family == Family::Merging {
            let finite = value.is_finite();
            for (image, staged) in self.images.iter_mut().zip(self.stage.iter_mut()) {
                if finite {
                    *image += *staged;
                }
                *staged = Rgb::BLACK;
            }
        } else if value.is_finite() {
            self.images[self.layout.index(family, s, t)] += value;
        }
        self.families.add(family, value);
    }

    fn stage_merge(&mut self, s: u32, t: u32, value: Rgb) {
        self.stage[self.layout.index(Family::Merging, s, t)] += value;
    }
}

/// One iteration's per-pixel technique values: `layout.len()` values per pixel, pixel-major.
#[derive(Clone, Debug)]
pub struct TechniqueFrame {
    /// Which images.
    pub layout: TechniqueLayout,
    /// `values[pixel * layout.len() + image]`.
    pub values: Vec<Rgb>,
}

impl TechniqueFrame {
    /// All zero.
    pub fn new(layout: TechniqueLayout, pixel_count: usize) -> Self {
        Self { layout, values: vec![Rgb::BLACK; pixel_count * layout.len()] }
    }

    /// Zeroes the values (resized for `pixel_count` pixels).
    pub fn clear(&mut self, pixel_count: usize) {
        self.values.clear();
        self.values.resize(pixel_count * self.layout.len(), Rgb::BLACK);
    }

    /// Adds a light-tracing splat value of a light sub-path with `s` vertices to `pixel`.
    #[inline]
    pub fn add_splat(&mut self, pixel: usize, s: u32, value: Rgb) {
        let index = pixel * self.layout.len() + self.layout.index(Family::LightTracing, s, 1);
        self.values[index] += value;
    }
}

/// The technique images of a render: per image and pixel, the mean over iterations (f64 sums).
#[derive(Clone, Debug)]
pub struct TechniqueImages {
    layout: TechniqueLayout,
    pixel_count: usize,
    iterations: u64,
    /// `sums[image * pixel_count + pixel]`.
    sums: Vec<[f64; 3]>,
}

impl TechniqueImages {
    /// Empty images of `pixel_count` pixels.
    pub fn new(layout: TechniqueLayout, pixel_count: usize) -> Self {
        Self { layout, pixel_count, iterations: 0, sums: vec![[0.0; 3]; pixel_count * layout.len()] }
    }

    /// Which images.
    pub fn layout(&self) -> TechniqueLayout {
        self.layout
    }

    /// Iterations added.
    pub fn iterations(&self) -> u64 {
        self.iterations
    }

    /// Adds one iteration's values (same layout and pixel count, else an error).
    pub fn add_iteration(&mut self, frame: &TechniqueFrame) -> Result<(), String> {
        let n = self.layout.len();
        if frame.layout != self.layout || frame.values.len() != self.pixel_count * n {
            return Err("technique frame of another layout or size".to_string());
        }
        for (pixel, values) in frame.values.chunks_exact(n).enumerate() {
            for (image, value) in values.iter().enumerate() {
                let sum = &mut self.sums[image * self.pixel_count + pixel];
                for (s, v) in sum.iter_mut().zip(value.to_array()) {
                    *s += f64::from(v);
                }
            }
        }
        self.iterations += 1;
        Ok(())
    }

    /// The mean over iterations of image `image` (row-major pixels; zero before any iteration).
    pub fn mean(&self, image: usize) -> Vec<[f32; 3]> {
        let scale = 1.0 / self.iterations.max(1) as f64;
        self.sums[image * self.pixel_count..(image + 1) * self.pixel_count]
            .iter()
            .map(|s| s.map(|v| (v * scale) as f32))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Lists the images by brute force from the definitions in the module doc.
    fn expected_images(n: u32) -> Vec<TechniqueImage> {
        let mut paths = Vec::new();
        let mut merges = Vec::new();
        for k in 1..=n {
            for s in 0..=k + 1 {
                let t = k + 1 - s;
                let exists = match s {
                    0 => t >= 2,
                    1 => t >= 2,
                    _ => t >= 1,
                };
                if exists {
                    paths.push(TechniqueImage::Path { s, t });
                }
            }
            for s in 2..=k {
                let t = k + 2 - s;
                if t >= 2 {
                    merges.push(TechniqueImage::Merge { s, t });
                }
            }
        }
        paths.extend(merges);
        paths.extend(Family::ALL.map(TechniqueImage::Longer));
        paths
    }

    #[test]
    fn layout_lists_every_technique_once_and_indexes_it() {
        for n in 1..=MAX_TECHNIQUE_LENGTH {
            let layout = TechniqueLayout::new(n).unwrap();
            let images = layout.images();
            assert_eq!(images, expected_images(n), "length {n}");
            assert_eq!(images.len(), layout.len());
            for (i, image) in images.iter().enumerate() {
                let index = match *image {
                    TechniqueImage::Path { s, t } => layout.index(image.family(), s, t),
                    TechniqueImage::Merge { s, t } => layout.index(Family::Merging, s, t),
                    TechniqueImage::Longer(_) => continue,
                };
                assert_eq!(index, i, "length {n}: {}", image.name());
            }
            // One step too long: the family's bucket.
            let longer = |f: Family| layout.len() - 5 + f as usize;
            assert_eq!(layout.index(Family::EmitterHit, 0, n + 2), longer(Family::EmitterHit));
            assert_eq!(layout.index(Family::NextEvent, 1, n + 1), longer(Family::NextEvent));
            assert_eq!(layout.index(Family::LightTracing, n + 1, 1), longer(Family::LightTracing));
            assert_eq!(layout.index(Family::Connection, n.max(2), 2), longer(Family::Connection));
            assert_eq!(layout.index(Family::Merging, n, 3), longer(Family::Merging));
            assert_eq!(layout.image(longer(Family::Merging)), TechniqueImage::Longer(Family::Merging));
        }
        let four = TechniqueLayout::new(4).unwrap();
        assert_eq!(four.len(), 13 + 6 + 5);
        let names: Vec<String> = four.images().iter().map(|i| i.name()).collect();
        assert_eq!(&names[..5], ["s0-t2", "s0-t3", "s1-t2", "s2-t1", "s0-t4"]);
        assert_eq!(names[13], "merge-s2-t2");
        assert_eq!(names[23], "longer-merging");
        assert!(TechniqueLayout::new(0).is_err());
        assert!(TechniqueLayout::new(MAX_TECHNIQUE_LENGTH + 1).is_err());
    }

    #[test]
    fn merges_count_only_when_their_sum_is_finite() {
        let layout = TechniqueLayout::new(3).unwrap();
        let mut images = vec![Rgb::BLACK; layout.len()];
        let mut stage = vec![Rgb::BLACK; layout.len()];
        let mut values = TechniqueValues::new(layout, &mut images, &mut stage);
        values.stage_merge(2, 2, Rgb::splat(1.0));
        values.stage_merge(3, 2, Rgb::splat(2.0));
        values.record(Family::Merging, 0, 2, Rgb::splat(3.0));
        values.stage_merge(2, 3, Rgb::splat(5.0));
        values.record(Family::Merging, 0, 3, Rgb::splat(f32::INFINITY));
        values.record(Family::NextEvent, 1, 2, Rgb::splat(7.0));
        values.record(Family::NextEvent, 1, 2, Rgb::splat(f32::NAN));
        let families = values.finish();
        assert_eq!(families.total(), Rgb::splat(10.0));
        assert_eq!(families.1, [0, 1, 0, 0, 1]);
        assert_eq!(images[layout.index(Family::Merging, 2, 2)], Rgb::splat(1.0));
        assert_eq!(images[layout.index(Family::Merging, 3, 2)], Rgb::splat(2.0));
        assert_eq!(images[layout.index(Family::Merging, 2, 3)], Rgb::BLACK);
        assert_eq!(images[layout.index(Family::NextEvent, 1, 2)], Rgb::splat(7.0));
        assert_eq!(images.iter().fold(Rgb::BLACK, |a, b| a + *b), Rgb::splat(10.0));
        assert!(stage.iter().all(|v| *v == Rgb::BLACK));
    }
}
