//! The in-memory linear RGB image and small helpers on it (construction,
//! pixel access, channel means, box downsampling).

use crate::ImageError;

/// Largest number of pixels any reader in this crate will allocate
/// (2^28, e.g. 16384 × 16384). Files claiming more are rejected with an
/// error instead of exhausting memory.
pub const MAX_PIXELS: usize = 1 << 28;

/// A linear RGB radiance image.
///
/// Pixels are stored row-major with the top row first: pixel `(x, y)` is
/// `pixels[y * width + x]`, with `y = 0` at the top. Values are linear
/// (not gamma encoded) and unbounded.
///
/// The fields are public for convenience; the writers check that
/// `pixels.len() == width * height` and return an error otherwise.
#[derive(Debug, Clone, PartialEq)]
pub struct Image {
    /// Number of columns.
    pub width: usize,
    /// Number of rows.
    pub height: usize,
    /// `width * height` RGB triples, row-major, top row first.
    pub pixels: Vec<[f32; 3]>,
}

impl Image {
    /// A black image of the given size.
    ///
    /// # Panics
    ///
    /// Panics if `width * height` overflows `usize`.
    pub fn new(width: usize, height: usize) -> Self {
        let count = width.checked_mul(height).expect("image dimensions overflow usize");
        Self { width, height, pixels: vec![[0.0; 3]; count] }
    }

    /// An image whose pixel `(x, y)` is `f(x, y)`.
    ///
    /// # Panics
    ///
    /// Panics if `width * height` overflows `usize`.
    pub fn from_fn(width: usize, height: usize, mut f: impl FnMut(usize, usize) -> [f32; 3]) -> Self {
        let mut image = Self::new(width, height);
        for y in 0..height {
            for x in 0..width {
                image.pixels[y * width + x] = f(x, y);
            }
        }
        image
    }

    /// The pixel at column `x`, row `y` (row 0 is the top).
    ///
    /// # Panics
    ///
    /// Panics if `(x, y)` is outside the image.
    pub fn get(&self, x: usize, y: usize) -> [f32; 3] {
        assert!(x < self.width && y < self.height, "pixel ({x}, {y}) outside {}x{} image", self.width, self.height);
        self.pixels[y * self.width + x]
    }

    /// Sets the pixel at column `x`, row `y` (row 0 is the top).
    ///
    /// # Panics
    ///
    /// Panics if `(x, y)` is outside the image.
    pub fn set(&mut self, x: usize, y: usize, value: [f32; 3]) {
        assert!(x < self.width && y < self.height, "pixel ({x}, {y}) outside {}x{} image", self.width, self.height);
        self.pixels[y * self.width + x] = value;
    }

    /// The mean of each channel over all pixels, accumulated in `f64`.
    ///
    /// Returns `[0.0; 3]` for an image without pixels. Non-finite values
    /// propagate into the result.
    pub fn channel_means(&self) -> [f64; 3] {
        if self.pixels.is_empty() {
            return [0.0; 3];
        }
        let mut sum = [0.0f64; 3];
        for pixel in &self.pixels {
            for (s, &v) in sum.iter_mut().zip(pixel) {
                *s += f64::from(v);
            }
        }
        let n = self.pixels.len() as f64;
        sum.map(|s| s / n)
    }

    /// Checks the invariant `pixels.len() == width * height` and that the
    /// image is not empty. Returns a description of the problem otherwise.
    pub(crate) fn check_shape(&self) -> Result<(), String> {
        if self.width == 0 || self.height == 0 {
            return Err(format!("image is empty ({}x{})", self.width, self.height));
        }
        match self.width.checked_mul(self.height) {
            Some(n) if n == self.pixels.len() => Ok(()),
            _ => Err(format!("image is {}x{} but has {} pixels", self.width, self.height, self.pixels.len())),
        }
    }
}

/// Box-filters `image` down by `factor` in each direction: every output
/// pixel is the mean (computed in `f64`) of a `factor × factor` block.
///
/// Errors if `factor` is zero, if the width or height is not divisible by
/// `factor`, or if the image's pixel buffer does not match its dimensions.
pub fn downsample_box(image: &Image, factor: usize) -> Result<Image, ImageError> {
    let fail = |message: String| ImageError::InvalidOperation { operation: "downsample_box", message };
    if factor == 0 {
        return Err(fail("factor must be at least 1".to_string()));
    }
    image.check_shape().map_err(fail)?;
    if image.width % factor != 0 || image.height % factor != 0 {
        return Err(fail(format!(
            "{}x{} image is not divisible into {factor}x{factor} blocks",
            image.width, image.height
        )));
    }
    let (w, h) = (image.width / factor, image.height / factor);
    let norm = 1.0 / (factor as f64 * factor as f64);
    let mut out = Image::new(w, h);
    for oy in 0..h {
        for ox in 0..w {
            let mut sum = [0.0f64; 3];
            for y in oy * factor..(oy + 1) * factor {
                let row = &image.pixels[y * image.width..(y + 1) * image.width];
                for pixel in &row[ox * factor..(ox + 1) * factor] {
                    for (s, &v) in sum.iter_mut().zip(pixel) {
                        *s += f64::from(v);
                    }
                }
            }
            out.pixels[oy * w + ox] = sum.map(|s| (s * norm) as f32);
        }
    }
    Ok(out)
}
