//! Pixel reconstruction filters (Mitsuba's `box`, `tent` and `gaussian`), separable in x and y.
//!
//! A pixel `j` with centre `c_j` (raster units, pixels) estimates `∫ f(x − c_j) L(x) dx / ∫ f`
//! over the raster plane. Camera sub-paths sample their raster position as `c_j + offset` with
//! [`Filter::sample`] and carry its weight `(f/∫f)/pdf`; light-tracing splats landing at `x` add
//! `value × `[`Filter::eval_normalized`]`(x − c_j)` to every pixel within [`Filter::radius`].
//! Offsets are in pixels; `eval_normalized` is a density per unit raster area (per pixel²).
//!
//! That is the film mode [`FilmMode::Fis`]. In [`FilmMode::Splat`] camera samples are uniform in
//! their pixel and, like light-tracing splats, add `value × f(x − c_j) / N_j` to every pixel `j`
//! within the radius, `N_j = ∫_image f(x − c_j) dx` the expected weight sum of pixel `j` (the
//! product of [`Filter::clipped_integral_1d`] on both axes; `∫f` away from the borders).

use math::Vec2;

use crate::desc::FilterDesc;

/// Number of bins of the tabulated inverse cumulative distribution of the gaussian, over the
/// 1D support `[−radius, radius]`.
const GAUSSIAN_BINS: usize = 128;

/// Simpson intervals per table bin when integrating the gaussian profile (in f64).
const SIMPSON_STEPS: usize = 32;

/// Entries of the gaussian's table of tails `∫_{k+½}^{r} g` (pixel centres lie at half-integer
/// distances from the image borders); longer distances are integrated when asked.
const TAIL_ENTRIES: usize = 32;

/// Simpson intervals for one tail integral of the gaussian profile (in f64).
const TAIL_STEPS: usize = 512;

/// How camera samples reach the pixels (the command line's `--film`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FilmMode {
    /// Filter importance sampling: a pixel's camera sample is placed around its centre by
    /// [`Filter::sample`] and counts for that pixel only, weighted `(f/∫f)/pdf`.
    #[default]
    Fis,
    /// Splatting (Mitsuba's and pbrt's film): camera samples are uniform in their pixel and add
    /// `value × f(x − c_j)/N_j` to every pixel `j` within the radius, `N_j` the expected weight
    /// sum of pixel `j` over the image rectangle. Identical to [`FilmMode::Fis`] for the box.
    Splat,
}

impl FilmMode {
    /// The command-line name (`fis`, `splat`).
    pub fn name(self) -> &'static str {
        match self {
            FilmMode::Fis => "fis",
            FilmMode::Splat => "splat",
        }
    }

    /// Parses [`FilmMode::name`]'s names.
    pub fn from_name(name: &str) -> Option<FilmMode> {
        match name {
            "fis" => Some(FilmMode::Fis),
            "splat" => Some(FilmMode::Splat),
            _ => None,
        }
    }
}

/// A pixel reconstruction filter.
///
/// The gaussian carries its sampling table inline (about 0.5 KiB) so that the filter, and the
/// camera holding it, stay `Copy`; there is one per camera.
#[derive(Clone, Copy, Debug, PartialEq)]
#[allow(clippy::large_enum_variant)]
pub enum Filter {
    /// Box of half-width 0.5 pixel: `f = 1` on `[−0.5, 0.5]²`, each sample counts for its own
    /// pixel only.
    Box,
    /// Tent `f(x, y) = t(x) t(y)`, `t(x) = max(0, 1 − |x|/radius)`.
    Tent {
        /// Half-width in pixels (> 0).
        radius: f32,
    },
    /// Truncated gaussian `f(x, y) = g(x) g(y)` with `g(x) = max(0, e^{−x²/2σ²} − e^{−r²/2σ²})`.
    Gaussian(GaussianFilter),
}

/// The tabulated truncated gaussian of [`Filter::Gaussian`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GaussianFilter {
    /// Standard deviation σ in pixels.
    pub stddev: f32,
    /// Truncation radius r in pixels.
    pub radius: f32,
    /// `−1/(2σ²)` (per pixel²).
    alpha: f32,
    /// `e^{−r²/2σ²}`, subtracted so that the profile reaches zero at the radius.
    bias: f32,
    /// `1 / ∫ g(x) dx` over `[−r, r]` (per pixel).
    inv_integral: f32,
    /// Cumulative distribution of the profile over [`GAUSSIAN_BINS`] equal bins of
    /// `[−r, r]`; `cdf[0] = 0`, `cdf[GAUSSIAN_BINS] = 1`.
    cdf: [f32; GAUSSIAN_BINS + 1],
    /// `∫_{k+½}^{r} g(x) dx` (pixels) for `k < TAIL_ENTRIES`.
    tails: [f32; TAIL_ENTRIES],
}

impl GaussianFilter {
    /// The filter with standard deviation `stddev` and radius `radius` (pixels, both > 0).
    fn new(stddev: f32, radius: f32) -> Self {
        let alpha = -1.0 / (2.0 * stddev * stddev);
        let bias = (alpha * radius * radius).exp();
        let (alpha64, bias64, r64) = (alpha as f64, bias as f64, radius as f64);
        let profile = |x: f64| ((alpha64 * x * x).exp() - bias64).max(0.0);
        let width = 2.0 * r64 / GAUSSIAN_BINS as f64;
        // Simpson's rule per bin.
        let bin_integral = |i: usize| {
            let x0 = -r64 + i as f64 * width;
            let h = width / SIMPSON_STEPS as f64;
            let mut sum = profile(x0) + profile(x0 + width);
            for k in 1..SIMPSON_STEPS {
                sum += profile(x0 + k as f64 * h) * if k % 2 == 1 { 4.0 } else { 2.0 };
            }
            sum * h / 3.0
        };
        let bins: Vec<f64> = (0..GAUSSIAN_BINS).map(bin_integral).collect();
        let total: f64 = bins.iter().sum();
        let mut cdf = [0.0f32; GAUSSIAN_BINS + 1];
        let mut running = 0.0f64;
        for (i, b) in bins.iter().enumerate() {
            running += b;
            cdf[i + 1] = (running / total) as f32;
        }
        cdf[GAUSSIAN_BINS] = 1.0;
        let tails = std::array::from_fn(|k| simpson(profile, k as f64 + 0.5, r64, TAIL_STEPS) as f32);
        Self { stddev, radius, alpha, bias, inv_integral: (1.0 / total) as f32, cdf, tails }
    }

    /// `∫_d^r g(x) dx` (pixels) for `d ≥ 0`: from the table at half-integer `d`, integrated
    /// otherwise.
    fn tail(&self, d: f32) -> f64 {
        if d >= self.radius {
            return 0.0;
        }
        let k = (d - 0.5).round();
        if k >= 0.0 && (k as usize) < TAIL_ENTRIES && (d - 0.5 - k).abs() < 1e-4 {
            return self.tails[k as usize] as f64;
        }
        let (alpha, bias) = (self.alpha as f64, self.bias as f64);
        simpson(|x| ((alpha * x * x).exp() - bias).max(0.0), d as f64, self.radius as f64, TAIL_STEPS)
    }

    /// The 1D profile `g(x)` (not normalised).
    #[inline]
    fn profile(&self, x: f32) -> f32 {
        if x.abs() >= self.radius { 0.0 } else { ((self.alpha * x * x).exp() - self.bias).max(0.0) }
    }

    /// Samples a 1D offset from the table: `(offset, (g/∫g)/pdf_table)`.
    fn sample_1d(&self, u: f32) -> (f32, f32) {
        let width = 2.0 * self.radius / GAUSSIAN_BINS as f32;
        // The bin i with cdf[i] ≤ u < cdf[i + 1] (empty bins are skipped by the search).
        let bin = (self.cdf.partition_point(|&c| c <= u).max(1) - 1).min(GAUSSIAN_BINS - 1);
        let (c0, c1) = (self.cdf[bin], self.cdf[bin + 1]);
        let probability = c1 - c0;
        if probability <= 0.0 {
            return (0.0, 0.0);
        }
        let t = ((u - c0) / probability).clamp(0.0, 1.0);
        let x = (-self.radius + (bin as f32 + t) * width).clamp(-self.radius, self.radius);
        let pdf = probability / width;
        (x, self.profile(x) * self.inv_integral / pdf)
    }
}

/// Simpson's rule for `∫_a^b f` with `steps` (even) intervals.
fn simpson(f: impl Fn(f64) -> f64, a: f64, b: f64, steps: usize) -> f64 {
    if b <= a {
        return 0.0;
    }
    let h = (b - a) / steps as f64;
    let mut sum = f(a) + f(b);
    for k in 1..steps {
        sum += f(a + k as f64 * h) * if k % 2 == 1 { 4.0 } else { 2.0 };
    }
    sum * h / 3.0
}

impl Filter {
    /// The filter a scene description asks for. Radii and standard deviations must be finite
    /// and positive; the message names the offending parameter otherwise.
    pub fn from_desc(desc: &FilterDesc) -> Result<Filter, String> {
        let positive = |name: &str, v: f32| {
            if v.is_finite() && v > 0.0 {
                Ok(v)
            } else {
                Err(format!("filter {name} must be a finite positive number of pixels, got {v}"))
            }
        };
        Ok(match *desc {
            FilterDesc::Box => Filter::Box,
            FilterDesc::Tent { radius } => Filter::Tent { radius: positive("radius", radius)? },
            FilterDesc::Gaussian { stddev, radius } => {
                Filter::Gaussian(GaussianFilter::new(positive("stddev", stddev)?, positive("radius", radius)?))
            }
        })
    }

    /// Half-width of the support in pixels (0.5 for the box): `f` vanishes when either offset
    /// coordinate is at least this far from 0.
    pub fn radius(&self) -> f32 {
        match self {
            Filter::Box => 0.5,
            Filter::Tent { radius } => *radius,
            Filter::Gaussian(g) => g.radius,
        }
    }

    /// Whether this is the box filter (one pixel per sample).
    pub fn is_box(&self) -> bool {
        matches!(self, Filter::Box)
    }

    /// `f(offset) / ∫ f`: the normalised filter, per unit raster area (pixel⁻²), at `offset`
    /// (pixels) from a pixel centre.
    pub fn eval_normalized(&self, offset: Vec2) -> f32 {
        match self {
            Filter::Box => {
                if offset.x.abs() <= 0.5 && offset.y.abs() <= 0.5 {
                    1.0
                } else {
                    0.0
                }
            }
            Filter::Tent { radius } => {
                let t = |x: f32| (1.0 - x.abs() / radius).max(0.0) / radius;
                t(offset.x) * t(offset.y)
            }
            Filter::Gaussian(g) => g.profile(offset.x) * g.profile(offset.y) * g.inv_integral * g.inv_integral,
        }
    }

    /// The 1D profile `f₁` (not normalised, dimensionless) at `x` pixels from a pixel centre;
    /// `f(x, y) = f₁(x) f₁(y)`: box 1 on `|x| ≤ ½`, tent `1 − |x|/r`, the truncated gaussian.
    pub fn profile_1d(&self, x: f32) -> f32 {
        match self {
            Filter::Box => {
                if x.abs() <= 0.5 {
                    1.0
                } else {
                    0.0
                }
            }
            Filter::Tent { radius } => (1.0 - x.abs() / radius).max(0.0),
            Filter::Gaussian(g) => g.profile(x),
        }
    }

    /// `∫_d^∞ f₁(x) dx` (pixels) for `d ≥ 0`: the part of the profile beyond `d`.
    pub fn tail_1d(&self, d: f32) -> f64 {
        let d = d.max(0.0);
        match self {
            Filter::Box => (0.5 - d as f64).max(0.0),
            Filter::Tent { radius } => {
                let rest = (*radius as f64 - d as f64).max(0.0);
                rest * rest / (2.0 * *radius as f64)
            }
            Filter::Gaussian(g) => g.tail(d),
        }
    }

    /// `∫ f₁` over the whole line (pixels).
    pub fn integral_1d(&self) -> f64 {
        match self {
            Filter::Gaussian(g) => 1.0 / g.inv_integral as f64,
            _ => 2.0 * self.tail_1d(0.0),
        }
    }

    /// `∫_0^size f₁(x − centre) dx` (pixels): the expected weight sum along one axis of a pixel
    /// whose centre is at `centre` (pixels, inside `[0, size]`) in an image `size` pixels wide,
    /// under [`FilmMode::Splat`]. Equals [`Filter::integral_1d`] at least a radius from both ends.
    pub fn clipped_integral_1d(&self, centre: f32, size: f32) -> f64 {
        self.integral_1d() - self.tail_1d(centre) - self.tail_1d(size - centre)
    }

    /// Samples an offset (pixels) from a pixel centre with `u ∈ [0,1)²`. Returns the offset and
    /// the weight `(f/∫f)(offset) / pdf(offset)` (pdf per unit raster area) that makes the
    /// sample an unbiased estimate of the filtered pixel. The box and the tent are inverted
    /// exactly (weight 1); the gaussian is sampled from a piecewise-constant table and the
    /// weight corrects for the difference (≈ 1, 0 at the radius).
    pub fn sample(&self, u: [f32; 2]) -> (Vec2, f32) {
        match self {
            Filter::Box => (Vec2::new(u[0] - 0.5, u[1] - 0.5), 1.0),
            Filter::Tent { radius } => {
                // Inverse CDF of the symmetric triangle on [−r, r].
                let invert = |u: f32| {
                    if u < 0.5 {
                        radius * ((2.0 * u).sqrt() - 1.0)
                    } else {
                        radius * (1.0 - (2.0 - 2.0 * u).max(0.0).sqrt())
                    }
                };
                (Vec2::new(invert(u[0]), invert(u[1])), 1.0)
            }
            Filter::Gaussian(g) => {
                let (x, wx) = g.sample_1d(u[0]);
                let (y, wy) = g.sample_1d(u[1]);
                (Vec2::new(x, y), wx * wy)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn invalid_parameters_are_errors() {
        assert!(Filter::from_desc(&FilterDesc::Tent { radius: 0.0 }).unwrap_err().contains("radius"));
        assert!(Filter::from_desc(&FilterDesc::Gaussian { stddev: f32::NAN, radius: 2.0 }).is_err());
        assert!(Filter::from_desc(&FilterDesc::Gaussian { stddev: 0.5, radius: -1.0 }).is_err());
        assert_eq!(Filter::from_desc(&FilterDesc::Box).unwrap(), Filter::Box);
    }

    #[test]
    fn gaussian_normalisation_matches_erf_closed_form() {
        // ∫_{−r}^{r} (e^{−x²/2σ²} − e^{−r²/2σ²}) dx = σ√(2π) erf(r/(σ√2)) − 2r e^{−r²/2σ²};
        // with r = 4σ (Mitsuba's default) erf(2√2) = 0.999936657516334.
        let Filter::Gaussian(g) = Filter::from_desc(&FilterDesc::Gaussian { stddev: 0.5, radius: 2.0 }).unwrap() else {
            unreachable!()
        };
        let sigma = 0.5f64;
        let expected = sigma * (2.0 * std::f64::consts::PI).sqrt() * 0.999_936_657_516_334 - 4.0 * (-8.0f64).exp();
        assert!((1.0 / g.inv_integral as f64 - expected).abs() < 1e-6 * expected, "{}", 1.0 / g.inv_integral);
    }

    #[test]
    fn tent_sampling_inverts_its_cdf() {
        let f = Filter::Tent { radius: 1.5 };
        // The CDF of the triangle at the sampled point must give back u.
        for i in 0..=100 {
            let u = i as f32 / 100.0 * 0.9999;
            let (o, w) = f.sample([u, 0.5]);
            assert_eq!(w, 1.0);
            let x = o.x / 1.5;
            let cdf = if x < 0.0 { 0.5 * (1.0 + x) * (1.0 + x) } else { 1.0 - 0.5 * (1.0 - x) * (1.0 - x) };
            assert!((cdf - u).abs() < 1e-5, "u {u}: cdf {cdf}");
        }
    }
}
