//! Colour quantities carried along light paths.
//!
//! The renderer works in linear sRGB ([`Rgb`]) or spectrally with hero wavelength sampling
//! ([`Hero4`]); [`SpectralMode`] is what the integrators are generic over. The colour science
//! lives beside it: the CIE tables and colour spaces ([`cie`]), the visible-wavelength sampler
//! ([`wavelengths`]), RGB → spectrum upsampling ([`upsample`]), tabulated spectra
//! ([`tabulated`]), dispersive indices of refraction ([`ior`]) and fluorescence
//! ([`fluorescence`]).

pub mod cie;
pub mod fluorescence;
pub mod ior;
pub mod mode;
pub mod tabulated;
pub mod upsample;
pub mod wavelengths;

pub use mode::{HERO_COUNT, Hero4, Slots, SpectralMode, Wavelengths4};

use std::ops::{Add, AddAssign, Div, Mul, MulAssign, Sub};

/// Linear RGB triple (no colour space conversion is implied; the reference scenes are specified
/// directly in these values). Units depend on use: radiance (W·sr⁻¹·m⁻² per channel, unitless in
/// the built-in scenes), throughput, or reflectance.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Rgb {
    /// Red.
    pub r: f32,
    /// Green.
    pub g: f32,
    /// Blue.
    pub b: f32,
}

impl Rgb {
    /// All zero.
    pub const BLACK: Rgb = Rgb::splat(0.0);
    /// All one.
    pub const WHITE: Rgb = Rgb::splat(1.0);

    /// From three channels.
    #[inline]
    pub const fn new(r: f32, g: f32, b: f32) -> Self {
        Self { r, g, b }
    }

    /// The same value in every channel.
    #[inline]
    pub const fn splat(v: f32) -> Self {
        Self { r: v, g: v, b: v }
    }

    /// Largest channel.
    #[inline]
    pub fn max_component(self) -> f32 {
        self.r.max(self.g).max(self.b)
    }

    /// Mean of the channels.
    #[inline]
    pub fn average(self) -> f32 {
        (self.r + self.g + self.b) * (1.0 / 3.0)
    }

    /// Relative luminance with the Rec. 709 / sRGB weights
    /// (0.212671, 0.715160, 0.072169), as used for lobe selection.
    #[inline]
    pub fn luminance(self) -> f32 {
        0.212671 * self.r + 0.715160 * self.g + 0.072169 * self.b
    }

    /// True when every channel is exactly zero.
    #[inline]
    pub fn is_black(self) -> bool {
        self.r == 0.0 && self.g == 0.0 && self.b == 0.0
    }

    /// True when no channel is NaN or infinite.
    #[inline]
    pub fn is_finite(self) -> bool {
        self.r.is_finite() && self.g.is_finite() && self.b.is_finite()
    }

    /// Per-channel maximum.
    pub fn max(self, o: Rgb) -> Rgb {
        Rgb::new(self.r.max(o.r), self.g.max(o.g), self.b.max(o.b))
    }

    /// Per-channel minimum.
    pub fn min(self, o: Rgb) -> Rgb {
        Rgb::new(self.r.min(o.r), self.g.min(o.g), self.b.min(o.b))
    }

    /// Applies `f` to every channel.
    pub fn map(self, f: impl Fn(f32) -> f32) -> Rgb {
        Rgb::new(f(self.r), f(self.g), f(self.b))
    }

    /// The channels as an array.
    pub fn to_array(self) -> [f32; 3] {
        [self.r, self.g, self.b]
    }

    /// From an array `[r, g, b]`.
    #[inline]
    pub fn from_array(a: [f32; 3]) -> Self {
        Self::new(a[0], a[1], a[2])
    }
}

impl Add for Rgb {
    type Output = Rgb;
    #[inline]
    fn add(self, o: Rgb) -> Rgb {
        Rgb::new(self.r + o.r, self.g + o.g, self.b + o.b)
    }
}

impl Sub for Rgb {
    type Output = Rgb;
    #[inline]
    fn sub(self, o: Rgb) -> Rgb {
        Rgb::new(self.r - o.r, self.g - o.g, self.b - o.b)
    }
}

impl AddAssign for Rgb {
    #[inline]
    fn add_assign(&mut self, o: Rgb) {
        *self = *self + o;
    }
}

impl Mul for Rgb {
    type Output = Rgb;
    #[inline]
    fn mul(self, o: Rgb) -> Rgb {
        Rgb::new(self.r * o.r, self.g * o.g, self.b * o.b)
    }
}

impl MulAssign for Rgb {
    #[inline]
    fn mul_assign(&mut self, o: Rgb) {
        *self = *self * o;
    }
}

impl Mul<f32> for Rgb {
    type Output = Rgb;
    #[inline]
    fn mul(self, s: f32) -> Rgb {
        Rgb::new(self.r * s, self.g * s, self.b * s)
    }
}

impl Mul<Rgb> for f32 {
    type Output = Rgb;
    #[inline]
    fn mul(self, c: Rgb) -> Rgb {
        c * self
    }
}

impl MulAssign<f32> for Rgb {
    #[inline]
    fn mul_assign(&mut self, s: f32) {
        *self = *self * s;
    }
}

impl Div<f32> for Rgb {
    type Output = Rgb;
    #[inline]
    fn div(self, s: f32) -> Rgb {
        Rgb::new(self.r / s, self.g / s, self.b / s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arithmetic_and_luminance() {
        let a = Rgb::new(1.0, 2.0, 3.0);
        assert_eq!(a + a, a * 2.0);
        assert_eq!(a * Rgb::WHITE, a);
        assert_eq!(a.max_component(), 3.0);
        assert!((Rgb::WHITE.luminance() - 1.0).abs() < 1e-6);
        assert!(!Rgb::new(f32::NAN, 0.0, 0.0).is_finite());
    }
}
