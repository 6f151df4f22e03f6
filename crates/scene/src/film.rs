//! The film: per-pixel accumulation of linear radiance over iterations (box filter, unit
//! pixel area), with light-tracing splats and the count of rejected (NaN or infinite) samples.

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

/// Accumulated image: the sum of the iterations' frames in double precision, so that long
/// renders do not lose the contribution of late iterations to rounding.
#[derive(Clone, Debug)]
pub struct Film {
    width: u32,
    height: u32,
    sum: Vec<[f64; 3]>,
    /// Sums of the squares of the iterations' pixel values, for the variance of the mean;
    /// empty when the film keeps no variance ([`Film::without_variance`]).
    sum_squares: Vec<[f64; 3]>,
    iterations: u64,
    rejected_samples: u64,
}

impl Film {
    /// An empty film that keeps the sums of squares for [`Film::variance_of_mean`] (48 bytes
    /// per pixel).
    pub fn new(width: u32, height: u32) -> Self {
        Self::with_variance(width, height, true)
    }

    /// An empty film without the sums of squares (24 bytes per pixel): it has no variance.
    pub fn without_variance(width: u32, height: u32) -> Self {
        Self::with_variance(width, height, false)
    }

    /// An empty film, with the sums of squares when `variance` is set.
    pub fn with_variance(width: u32, height: u32, variance: bool) -> Self {
        let pixels = width as usize * height as usize;
        Self {
            width,
            height,
            sum: vec![[0.0; 3]; pixels],
            sum_squares: if variance { vec![[0.0; 3]; pixels] } else { Vec::new() },
            iterations: 0,
            rejected_samples: 0,
        }
    }

    /// Whether the film keeps the sums of squares, i.e. has [`Film::variance_of_mean`].
    pub fn has_variance(&self) -> bool {
        self.sum_squares.len() == self.sum.len()
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

    /// Number of samples that were NaN or infinite and therefore not accumulated.
    pub fn rejected_samples(&self) -> u64 {
        self.rejected_samples
    }

    /// Adds one iteration's frame and the number of samples the iteration rejected.
    pub fn add_iteration(&mut self, frame: &FrameBuffer, rejected_samples: u64) {
        assert_eq!((frame.width, frame.height), (self.width, self.height), "frame size must match the film");
        // Without the sums of squares `squares` is empty and only the sums are added.
        for (i, (sum, pixel)) in self.sum.iter_mut().zip(&frame.pixels).enumerate() {
            let value = pixel.to_array().map(f64::from);
            for c in 0..3 {
                sum[c] += value[c];
            }
            if let Some(squares) = self.sum_squares.get_mut(i) {
                for c in 0..3 {
                    squares[c] += value[c] * value[c];
                }
            }
        }
        self.iterations += 1;
        self.rejected_samples += rejected_samples;
    }

    /// The per-pixel sums of the iterations' frames (row-major), for checkpoints.
    pub fn sums(&self) -> &[[f64; 3]] {
        &self.sum
    }

    /// The per-pixel sums of the squares of the iterations' values, for checkpoints (empty
    /// when the film keeps no variance).
    pub fn sum_squares(&self) -> &[[f64; 3]] {
        &self.sum_squares
    }

    /// A film with the given sums, sums of squares and counts (a checkpoint being resumed);
    /// `None` when their lengths do not match the size.
    pub fn from_sums(
        width: u32,
        height: u32,
        sums: Vec<[f64; 3]>,
        sum_squares: Vec<[f64; 3]>,
        iterations: u64,
        rejected_samples: u64,
    ) -> Option<Self> {
        let pixels = width as usize * height as usize;
        (sums.len() == pixels && sum_squares.len() == pixels).then_some(Self {
            width,
            height,
            sum: sums,
            sum_squares,
            iterations,
            rejected_samples,
        })
    }

    /// Per pixel and channel, the estimated variance of the mean over iterations (the squared
    /// standard error), `(Σx² − (Σx)²/n) / (n(n−1))`, from the spread of the iterations; zero
    /// with fewer than two iterations; `None` when the film keeps no variance.
    pub fn variance_of_mean(&self) -> Option<Vec<[f32; 3]>> {
        let n = self.iterations as f64;
        if !self.has_variance() {
            return None;
        }
        if self.iterations < 2 {
            return Some(vec![[0.0; 3]; self.sum.len()]);
        }
        let variance = self
            .sum
            .iter()
            .zip(&self.sum_squares)
            .map(|(s, q)| std::array::from_fn(|c| ((q[c] - s[c] * s[c] / n).max(0.0) / (n * (n - 1.0))) as f32))
            .collect();
        Some(variance)
    }

    /// The mean over iterations: the rendered image (row-major, top row first).
    pub fn mean(&self) -> Vec<[f32; 3]> {
        let scale = if self.iterations == 0 { 0.0 } else { 1.0 / self.iterations as f64 };
        self.sum.iter().map(|s| [(s[0] * scale) as f32, (s[1] * scale) as f32, (s[2] * scale) as f32]).collect()
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
}
