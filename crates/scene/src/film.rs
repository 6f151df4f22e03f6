//! The film: per-pixel accumulation of linear radiance over iterations (box filter, unit
//! pixel area), with light-tracing splats and the count of rejected (NaN or infinite) samples.

use std::borrow::Cow;

use rayon::prelude::*;

use spectrum::Rgb;

/// One iteration's image: the estimate of every pixel from this iteration only.
#[derive(Clone, Debug)]
pub struct FrameBuffer {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Row-major pixels, top row first.
    pub pixels: Vec<Rgb>,
}

impl FrameBuffer {
    /// A black frame.
    pub fn new(width: u32, height: u32) -> Self {
        Self { width, height, pixels: vec![Rgb::BLACK; width as usize * height as usize] }
    }
}

/// How a film adds up its iterations.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Summation {
    /// f64 sums (24 bytes per pixel, 48 with the sums of squares). Floating-point addition is
    /// not associative, so the sums depend on the order of the iterations in their last bits:
    /// one film must add every iteration, in index order.
    #[default]
    Float,
    /// Fixed-point sums in i128 (48 bytes per pixel, 96 with the sums of squares): each value
    /// is rounded once to a multiple of 2⁻⁶⁴ (squares: 2⁻⁴⁰) and added exactly, so the sums
    /// do not depend on the order of addition and films of disjoint iteration ranges can be
    /// merged ([`Film::merge`]) into the film one process would have accumulated, bit for bit.
    /// Values of magnitude 2⁴⁰ (≈ 1.1·10¹²) or more are rejected like non-finite samples; the
    /// sums are exact up to [`Film::FIXED_MAX_ITERATIONS`] iterations; the sums of squares
    /// while (largest value)²·iterations < 2⁸⁷ ([`Film::variance_of_mean`] is `None` beyond).
    Fixed,
}

impl Summation {
    /// The command line's name: `float` or `fixed`.
    pub fn name(self) -> &'static str {
        match self {
            Summation::Float => "float",
            Summation::Fixed => "fixed",
        }
    }

    /// Parses [`Summation::name`]'s names.
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "float" => Some(Summation::Float),
            "fixed" => Some(Summation::Fixed),
            _ => None,
        }
    }
}

/// Scale of the fixed-point sums: a value v is stored as round(v·2⁶⁴).
const SUM_SCALE: f64 = 18_446_744_073_709_551_616.0;
/// Scale of the fixed-point sums of squares: v² is stored as round(v²·2⁴⁰).
const SQUARE_SCALE: f64 = 1_099_511_627_776.0;
/// Magnitude from which a fixed-point film rejects a value (2⁴⁰).
const FIXED_LIMIT: f64 = 1_099_511_627_776.0;

/// [`Film::merge`]'s error for films with f64 sums.
const ONLY_FIXED: &str = "only films with fixed-point sums (--sums fixed) can be merged exactly";

/// The per-pixel sums of a film in one of the two [`Summation`] modes; the sums of squares are
/// empty when the film keeps no variance.
#[derive(Clone, Debug, PartialEq)]
pub enum FilmSums {
    /// f64 sums and sums of squares.
    Float {
        /// Σv per pixel and channel.
        sums: Vec<[f64; 3]>,
        /// Σv² per pixel and channel (empty without variance).
        squares: Vec<[f64; 3]>,
    },
    /// Fixed-point sums (units of 2⁻⁶⁴) and sums of squares (units of 2⁻⁴⁰).
    Fixed {
        /// Σ round(v·2⁶⁴) per pixel and channel (wrapping i128 addition).
        sums: Vec<[i128; 3]>,
        /// Σ round(v²·2⁴⁰) per pixel and channel (empty without variance).
        squares: Vec<[i128; 3]>,
        /// The largest |v| added (bounds the sums of squares).
        largest: f32,
    },
}

/// Calls `add(sum, square, pixel)` for every pixel in parallel (`square` is `None` when the
/// film keeps no sums of squares: `squares` is empty) and combines the results with `combine`
/// from `identity` (a sum or a maximum: the result does not depend on the split).
fn add_per_pixel<T: Send, R: Send + Sync + Copy>(
    sums: &mut [[T; 3]],
    squares: &mut [[T; 3]],
    pixels: &[Rgb],
    identity: R,
    combine: impl Fn(R, R) -> R + Sync + Send,
    add: impl Fn(&mut [T; 3], Option<&mut [T; 3]>, &Rgb) -> R + Sync + Send,
) -> R {
    if squares.is_empty() {
        sums.par_iter_mut().zip(pixels).map(|(sum, pixel)| add(sum, None, pixel)).reduce(|| identity, &combine)
    } else {
        sums.par_iter_mut()
            .zip(squares.par_iter_mut())
            .zip(pixels)
            .map(|((sum, square), pixel)| add(sum, Some(square), pixel))
            .reduce(|| identity, &combine)
    }
}

impl FilmSums {
    fn zeros(pixels: usize, variance: bool, summation: Summation) -> Self {
        let squares = if variance { pixels } else { 0 };
        match summation {
            Summation::Float => FilmSums::Float { sums: vec![[0.0; 3]; pixels], squares: vec![[0.0; 3]; squares] },
            Summation::Fixed => {
                FilmSums::Fixed { sums: vec![[0; 3]; pixels], squares: vec![[0; 3]; squares], largest: 0.0 }
            }
        }
    }

    fn lengths(&self) -> (usize, usize) {
        match self {
            FilmSums::Float { sums, squares } => (sums.len(), squares.len()),
            FilmSums::Fixed { sums, squares, .. } => (sums.len(), squares.len()),
        }
    }

    /// The summation mode of these sums.
    pub fn summation(&self) -> Summation {
        match self {
            FilmSums::Float { .. } => Summation::Float,
            FilmSums::Fixed { .. } => Summation::Fixed,
        }
    }

    /// Adds `other`'s fixed-point sums to these (exact, in any order): both must be fixed-point
    /// sums of the same length, with or without sums of squares alike.
    pub fn add(&mut self, other: &FilmSums) -> Result<(), String> {
        if self.lengths() != other.lengths() {
            return Err("the films differ in size or in keeping sums of squares".into());
        }
        let (
            FilmSums::Fixed { sums, squares, largest },
            FilmSums::Fixed { sums: other_sums, squares: other_squares, largest: other_largest },
        ) = (self, other)
        else {
            return Err(ONLY_FIXED.into());
        };
        for (a, b) in sums.iter_mut().zip(other_sums).chain(squares.iter_mut().zip(other_squares)) {
            for c in 0..3 {
                a[c] = a[c].wrapping_add(b[c]);
            }
        }
        *largest = largest.max(*other_largest);
        Ok(())
    }
}

/// Accumulated image: the sum of the iterations' frames in double precision or in exact fixed
/// point ([`Summation`]), so that long renders do not lose the contribution of late iterations
/// to rounding. A film holds the consecutive iterations `first_iteration..first_iteration + n`.
#[derive(Clone, Debug)]
pub struct Film {
    width: u32,
    height: u32,
    sums: FilmSums,
    first_iteration: u64,
    iterations: u64,
    rejected_samples: u64,
}

impl Film {
    /// The most iterations a [`Summation::Fixed`] film holds (2²³): with values below 2⁴⁰ its
    /// sums stay below 2¹²⁷ in units of 2⁻⁶⁴.
    pub const FIXED_MAX_ITERATIONS: u64 = 1 << 23;

    /// An empty film that keeps the sums of squares for [`Film::variance_of_mean`] (48 bytes
    /// per pixel).
    pub fn new(width: u32, height: u32) -> Self {
        Self::with_variance(width, height, true)
    }

    /// An empty film without the sums of squares (24 bytes per pixel): it has no variance.
    pub fn without_variance(width: u32, height: u32) -> Self {
        Self::with_variance(width, height, false)
    }

    /// An empty f64 film, with the sums of squares when `variance` is set.
    pub fn with_variance(width: u32, height: u32, variance: bool) -> Self {
        Self::with_summation(width, height, variance, Summation::Float)
    }

    /// An empty film in the given summation mode, with the sums of squares when `variance` is
    /// set, starting at iteration 0.
    pub fn with_summation(width: u32, height: u32, variance: bool, summation: Summation) -> Self {
        let pixels = width as usize * height as usize;
        Self {
            width,
            height,
            sums: FilmSums::zeros(pixels, variance, summation),
            first_iteration: 0,
            iterations: 0,
            rejected_samples: 0,
        }
    }

    /// This (empty) film, to hold iterations from `first` on (a slice of a render).
    pub fn starting_at(mut self, first: u64) -> Self {
        if self.iterations == 0 {
            self.first_iteration = first;
        }
        self
    }

    /// Whether the film keeps the sums of squares, i.e. has [`Film::variance_of_mean`].
    pub fn has_variance(&self) -> bool {
        let (sums, squares) = self.sums.lengths();
        sums == squares
    }

    /// The summation mode.
    pub fn summation(&self) -> Summation {
        self.sums.summation()
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Number of iterations accumulated.
    pub fn iterations(&self) -> u64 {
        self.iterations
    }

    /// Global index of the film's first iteration (0 unless the film holds a slice).
    pub fn first_iteration(&self) -> u64 {
        self.first_iteration
    }

    /// Global index of the next iteration: [`Film::first_iteration`] + [`Film::iterations`].
    pub fn next_iteration(&self) -> u64 {
        self.first_iteration + self.iterations
    }

    /// Whether another iteration can be added ([`Film::FIXED_MAX_ITERATIONS`] for fixed-point
    /// films; always for f64 films).
    pub fn has_room(&self) -> bool {
        self.summation() == Summation::Float || self.iterations < Self::FIXED_MAX_ITERATIONS
    }

    /// Number of samples that were NaN or infinite (or, in a fixed-point film, of magnitude
    /// 2⁴⁰ or more) and therefore not accumulated.
    pub fn rejected_samples(&self) -> u64 {
        self.rejected_samples
    }

    /// Adds one iteration's frame and the number of samples the iteration rejected. A
    /// fixed-point film beyond [`Film::FIXED_MAX_ITERATIONS`] would lose exactness: callers
    /// check [`Film::has_room`] first.
    pub fn add_iteration(&mut self, frame: &FrameBuffer, rejected_samples: u64) {
        assert_eq!((frame.width, frame.height), (self.width, self.height), "frame size must match the film");
        // In parallel over the pixels (on the caller's rayon pool): every pixel's sums take the
        // same operations whatever the split, and the fixed-point film's count and largest
        // value are a sum and a maximum, so the film is the same bit for bit. (Added by one
        // thread, a 512² iteration kept the other idle for about a millisecond:
        // docs/performance.md, "Buffers kept across iterations".)
        let mut rejected = rejected_samples;
        match &mut self.sums {
            FilmSums::Float { sums, squares } => {
                add_per_pixel(
                    sums,
                    squares,
                    &frame.pixels,
                    (),
                    |_, _| (),
                    |sum, square, pixel| {
                        let value = pixel.to_array().map(f64::from);
                        for c in 0..3 {
                            sum[c] += value[c];
                        }
                        if let Some(square) = square {
                            for c in 0..3 {
                                square[c] += value[c] * value[c];
                            }
                        }
                    },
                );
            }
            FilmSums::Fixed { sums, squares, largest } => {
                // Per pixel: (rejected, largest |v| added).
                let combine = |a: (u64, f32), b: (u64, f32)| (a.0 + b.0, a.1.max(b.1));
                let (count, most) =
                    add_per_pixel(sums, squares, &frame.pixels, (0, 0.0), combine, |sum, square, pixel| {
                        let value = pixel.to_array().map(f64::from);
                        if !value.iter().all(|v| v.abs() < FIXED_LIMIT) {
                            return (1, 0.0);
                        }
                        let mut most = 0.0f32;
                        for c in 0..3 {
                            // v·2⁶⁴ and v²·2⁴⁰ are exact in f64 for an f32 v; rounding them to
                            // integers is the only rounding, and the additions are exact.
                            sum[c] = sum[c].wrapping_add((value[c] * SUM_SCALE).round() as i128);
                            most = most.max(value[c].abs() as f32);
                        }
                        if let Some(square) = square {
                            for c in 0..3 {
                                let s = (value[c] * value[c] * SQUARE_SCALE).round() as i128;
                                square[c] = square[c].wrapping_add(s);
                            }
                        }
                        (0, most)
                    });
                rejected += count;
                *largest = largest.max(most);
            }
        }
        self.iterations += 1;
        self.rejected_samples += rejected;
    }

    /// Adds `other`, a film of the same size, mode and variance whose iterations directly
    /// follow or precede this film's, so that the result holds both ranges. Only fixed-point
    /// films merge: their sums do not depend on the order of addition, so the result equals
    /// the film that added every iteration itself, bit for bit.
    pub fn merge(&mut self, other: &Film) -> Result<(), String> {
        if (other.width, other.height) != (self.width, self.height) {
            return Err(format!(
                "a {}x{} film cannot merge a {}x{} film",
                self.width, self.height, other.width, other.height
            ));
        }
        if (self.summation(), other.summation()) != (Summation::Fixed, Summation::Fixed) {
            return Err(ONLY_FIXED.into());
        }
        let first = if other.first_iteration == self.next_iteration() {
            self.first_iteration
        } else if other.next_iteration() == self.first_iteration {
            other.first_iteration
        } else {
            return Err(format!(
                "iterations {}..{} do not adjoin iterations {}..{}",
                other.first_iteration,
                other.next_iteration(),
                self.first_iteration,
                self.next_iteration()
            ));
        };
        self.sums.add(&other.sums)?;
        self.first_iteration = first;
        self.iterations += other.iterations;
        self.rejected_samples += other.rejected_samples;
        Ok(())
    }

    /// The per-pixel sums of the iterations' values (row-major) as f64: the sums themselves for
    /// an f64 film, the fixed-point sums converted (rounded to nearest) otherwise.
    pub fn sums(&self) -> Cow<'_, [[f64; 3]]> {
        match &self.sums {
            FilmSums::Float { sums, .. } => Cow::Borrowed(sums),
            FilmSums::Fixed { sums, .. } => Cow::Owned(sums.iter().map(|s| s.map(|v| v as f64 / SUM_SCALE)).collect()),
        }
    }

    /// The per-pixel sums of the squares of the iterations' values as f64 (empty when the film
    /// keeps no variance), converted like [`Film::sums`].
    pub fn sum_squares(&self) -> Cow<'_, [[f64; 3]]> {
        match &self.sums {
            FilmSums::Float { squares, .. } => Cow::Borrowed(squares),
            FilmSums::Fixed { squares, .. } => {
                Cow::Owned(squares.iter().map(|s| s.map(|v| v as f64 / SQUARE_SCALE)).collect())
            }
        }
    }

    /// The sums in their own representation, for checkpoints.
    pub fn raw_sums(&self) -> &FilmSums {
        &self.sums
    }

    /// The sums in their own representation, taken out of the film.
    pub fn into_raw_sums(self) -> FilmSums {
        self.sums
    }

    /// A film with the given sums and counts (a checkpoint being resumed, or a slice): it holds
    /// iterations `first_iteration..first_iteration + iterations`; `None` when the lengths of
    /// the sums do not match the size (the sums of squares may be empty: no variance).
    pub fn from_raw(
        width: u32,
        height: u32,
        sums: FilmSums,
        first_iteration: u64,
        iterations: u64,
        rejected_samples: u64,
    ) -> Option<Self> {
        let pixels = width as usize * height as usize;
        let (n, squares) = sums.lengths();
        (n == pixels && (squares == pixels || squares == 0)).then_some(Self {
            width,
            height,
            sums,
            first_iteration,
            iterations,
            rejected_samples,
        })
    }

    /// Per pixel and channel, the estimated variance of the mean over iterations (the squared
    /// standard error), `(Σx² − (Σx)²/n) / (n(n−1))`, from the spread of the iterations; zero
    /// with fewer than two iterations; `None` when the film keeps no variance, or when a
    /// fixed-point film's sums of squares may have left their range ((largest value)² ·
    /// iterations ≥ 2⁸⁷).
    pub fn variance_of_mean(&self) -> Option<Vec<[f32; 3]>> {
        let n = self.iterations as f64;
        if !self.has_variance() {
            return None;
        }
        if let FilmSums::Fixed { largest, .. } = &self.sums
            && f64::from(*largest).powi(2) * n >= 2f64.powi(87)
        {
            return None;
        }
        if self.iterations < 2 {
            return Some(vec![[0.0; 3]; self.sums.lengths().0]);
        }
        let variance = self
            .sums()
            .iter()
            .zip(self.sum_squares().iter())
            .map(|(s, q)| std::array::from_fn(|c| ((q[c] - s[c] * s[c] / n).max(0.0) / (n * (n - 1.0))) as f32))
            .collect();
        Some(variance)
    }

    /// The mean over iterations: the rendered image (row-major, top row first).
    pub fn mean(&self) -> Vec<[f32; 3]> {
        let scale = if self.iterations == 0 { 0.0 } else { 1.0 / self.iterations as f64 };
        self.sums().iter().map(|s| [(s[0] * scale) as f32, (s[1] * scale) as f32, (s[2] * scale) as f32]).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn variance_of_the_mean_matches_the_formula() {
        let mut film = Film::new(1, 1);
        let values = [1.0f32, 3.0, 2.0, 6.0];
        for v in values {
            let frame = FrameBuffer { width: 1, height: 1, pixels: vec![Rgb::new(v, 2.0 * v, 5.0)] };
            film.add_iteration(&frame, 0);
        }
        // Sample variance of {1, 3, 2, 6} is 14/3; of the mean, 14/12.
        let variance = film.variance_of_mean().unwrap()[0];
        assert!((variance[0] - 14.0 / 12.0).abs() < 1e-6, "{variance:?}");
        assert!((variance[1] - 4.0 * 14.0 / 12.0).abs() < 1e-5);
        assert_eq!(variance[2], 0.0, "a constant has no variance");
        assert_eq!(film.mean()[0][0], 3.0);
        // Without the sums of squares the mean is the same and there is no variance.
        let mut lean = Film::without_variance(1, 1);
        for v in values {
            lean.add_iteration(&FrameBuffer { width: 1, height: 1, pixels: vec![Rgb::new(v, 2.0 * v, 5.0)] }, 0);
        }
        assert_eq!((lean.mean(), lean.variance_of_mean(), lean.sum_squares().len()), (film.mean(), None, 0));
    }

    fn frame(values: &[f32]) -> FrameBuffer {
        FrameBuffer {
            width: values.len() as u32,
            height: 1,
            pixels: values.iter().map(|&v| Rgb::new(v, -v, 0.5 * v)).collect(),
        }
    }

    /// Per-iteration frames over a wide dynamic range (1e-12 to 1e9, and negative values as
    /// signed splats give), from a fixed xorshift stream.
    fn wide_frames(count: usize, pixels: usize) -> Vec<FrameBuffer> {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        (0..count)
            .map(|_| {
                let values: Vec<f32> = (0..pixels)
                    .map(|_| {
                        let exponent = (next() % 22) as i32 - 12;
                        let mantissa = (next() % 1_000_000) as f32 / 1e5 + 1.0;
                        mantissa * 10f32.powi(exponent)
                    })
                    .collect();
                frame(&values)
            })
            .collect()
    }

    #[test]
    fn fixed_sums_do_not_depend_on_the_order_and_slices_merge_exactly() {
        let frames = wide_frames(12, 16);
        let film_of = |order: &[usize], summation| {
            let mut film = Film::with_summation(16, 1, true, summation);
            for &i in order {
                film.add_iteration(&frames[i], 0);
            }
            film
        };
        let forward: Vec<usize> = (0..12).collect();
        let shuffled = [7, 2, 11, 0, 5, 9, 1, 3, 10, 4, 8, 6];
        let (a, b) = (film_of(&forward, Summation::Fixed), film_of(&shuffled, Summation::Fixed));
        assert_eq!(a.raw_sums(), b.raw_sums());
        // The control: f64 sums of the same values depend on the order (this is why merging
        // needs fixed point), so the assertion above can fail.
        let (c, d) = (film_of(&forward, Summation::Float), film_of(&shuffled, Summation::Float));
        assert_ne!(c.raw_sums(), d.raw_sums(), "the f64 control should be order-dependent");
        // Three slices of 0..12 merged in any order equal the single film, bit for bit.
        let slice = |range: std::ops::Range<usize>| {
            let mut film = Film::with_summation(16, 1, true, Summation::Fixed).starting_at(range.start as u64);
            for i in range {
                film.add_iteration(&frames[i], 1);
            }
            film
        };
        let (s0, s1, s2) = (slice(0..4), slice(4..9), slice(9..12));
        let mut merged = s2.clone();
        merged.merge(&s0).unwrap_err(); // 0..4 does not adjoin 9..12
        merged.merge(&s1).unwrap();
        merged.merge(&s0).unwrap();
        assert_eq!(merged.raw_sums(), a.raw_sums());
        assert_eq!((merged.first_iteration(), merged.iterations(), merged.rejected_samples()), (0, 12, 12));
        assert_eq!(merged.mean(), a.mean());
        assert_eq!(merged.variance_of_mean(), a.variance_of_mean());
        // The fixed-point image equals the f64 one to f32 precision.
        for (x, y) in a.mean().iter().flatten().zip(c.mean().iter().flatten()) {
            assert!((x - y).abs() <= 1e-6 * y.abs(), "{x} vs {y}");
        }
        // f64 films do not merge.
        assert!(c.clone().merge(&d).unwrap_err().contains("fixed-point"));
    }

    #[test]
    fn fixed_sums_reject_values_beyond_their_range() {
        let mut film = Film::with_summation(3, 1, true, Summation::Fixed);
        film.add_iteration(&frame(&[1.0, 2e12, -3.0]), 0);
        film.add_iteration(&frame(&[3.0, 1.0, -1.0]), 0);
        assert_eq!(film.rejected_samples(), 1, "the pixel with 2e12 is rejected");
        assert_eq!(film.mean()[0], [2.0, -2.0, 1.0]);
        assert_eq!(film.mean()[1], [0.5, -0.5, 0.25]);
        assert_eq!(film.mean()[2], [-2.0, 2.0, -1.0]);
        // Large accepted values: the sums of squares leave their range and the variance is refused.
        let mut large = Film::with_summation(1, 1, true, Summation::Fixed);
        // (10¹²)²·155 ≥ 2⁸⁷: from 155 iterations on.
        for _ in 0..154 {
            large.add_iteration(&frame(&[1e12]), 0);
        }
        assert_eq!(large.variance_of_mean(), Some(vec![[0.0; 3]]));
        large.add_iteration(&frame(&[1e12]), 0);
        assert_eq!((large.rejected_samples(), large.mean()[0][0]), (0, 1e12));
        assert_eq!(large.variance_of_mean(), None);
    }
}
