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
    iterations: u64,
    rejected_samples: u64,
}

impl Film {
    /// An empty film.
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            sum: vec![[0.0; 3]; width as usize * height as usize],
            iterations: 0,
            rejected_samples: 0,
        }
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
        for (sum, pixel) in self.sum.iter_mut().zip(&frame.pixels) {
            sum[0] += pixel.r as f64;
            sum[1] += pixel.g as f64;
            sum[2] += pixel.b as f64;
        }
        self.iterations += 1;
        self.rejected_samples += rejected_samples;
    }

    /// The per-pixel sums of the iterations' frames (row-major), for checkpoints.
    pub fn sums(&self) -> &[[f64; 3]] {
        &self.sum
    }

    /// A film with the given sums and counts (a checkpoint being resumed); `None` when the
    /// number of sums does not match the size.
    pub fn from_sums(
        width: u32,
        height: u32,
        sums: Vec<[f64; 3]>,
        iterations: u64,
        rejected_samples: u64,
    ) -> Option<Self> {
        (sums.len() == width as usize * height as usize).then_some(Self {
            width,
            height,
            sum: sums,
            iterations,
            rejected_samples,
        })
    }

    /// The mean over iterations: the rendered image (row-major, top row first).
    pub fn mean(&self) -> Vec<[f32; 3]> {
        let scale = if self.iterations == 0 { 0.0 } else { 1.0 / self.iterations as f64 };
        self.sum.iter().map(|s| [(s[0] * scale) as f32, (s[1] * scale) as f32, (s[2] * scale) as f32]).collect()
    }
}
