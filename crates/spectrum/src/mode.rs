//! The spectral mode: what a path carries, chosen once at the top of the program.
//!
//! Integrators are generic over [`SpectralMode`], which has exactly two implementations:
//!
//! - [`Rgb`]: three linear-sRGB channels; the wavelength set is `()` and every conversion is the
//!   identity, so RGB renders are bit-identical to a renderer without spectral support.
//! - [`Hero4`]: four wavelengths per path (hero wavelength spectral sampling, Wilkie et al.
//!   2014). The hero is drawn in primary sample space `u`; the others are rotated to
//!   `(u + j/4) mod 1`, and all four are mapped through the visible-importance density
//!   ([`crate::wavelengths::sample_visible`]), so each wavelength is marginally distributed by
//!   that density and the four are stratified.
//!
//! **Reflectances stay RGB inside the BSDF.** Materials are specified in linear sRGB and
//! upsampled by a *linear* basis ([`crate::upsample`]): ρ(λ) = r·b_r(λ) + g·b_g(λ) + b·b_b(λ).
//! A BSDF value that is linear in its colour parameters (Lambert, Fresnel-weighted specular
//! lobes, plastic, blends — every model but two) therefore has the spectral value
//! `B(λ)·value_rgb`, which [`SpectralMode::from_reflectance`] applies with the four basis rows
//! stored in the wavelength set (12 multiply-adds). The two non-linear models (a conductor's
//! per-channel complex Fresnel, the non-linear plastic) are upsampled from their RGB result,
//! exactly as an RGB reflectance texture would be. All sampling decisions (lobe selection,
//! Russian roulette) then use the RGB values and so do not depend on the wavelengths: every
//! wavelength has the same pdf, the HWSS balance heuristic over the four wavelengths reduces
//! to equal weights, and the path-space MIS (the VCM weights) is computed once per path.
//!
//! **Dispersion** is the exception: a refraction direction depends on the wavelength, so the
//! other wavelengths cannot have produced the hero's direction (their pdf is zero). The hero then
//! carries the whole estimate ([`SpectralMode::terminate_secondary`]: its value times four, the
//! others zero — only the hero's technique has a non-zero HWSS weight for such paths). A full path
//! whose light *and* camera sub-paths were both terminated would count the factor four twice;
//! the integrators multiply such contributions by [`SpectralMode::DOUBLE_TERMINATION`].

use crate::Rgb;
use crate::fluorescence::Fluorescence;
use std::fmt::Debug;
use std::ops::{Add, AddAssign, Div, Mul, MulAssign};

/// What a light path carries (throughput, radiance, importance) and the per-path wavelengths.
pub trait SpectralMode:
    Copy
    + Clone
    + Debug
    + Default
    + PartialEq
    + Send
    + Sync
    + 'static
    + Add<Output = Self>
    + AddAssign
    + Mul<Output = Self>
    + MulAssign
    + Mul<f32, Output = Self>
    + MulAssign<f32>
    + Div<f32, Output = Self>
{
    /// The wavelengths a path is traced at (and what is precomputed for them).
    type Wavelengths: Copy + Debug + Send + Sync;

    /// Which wavelength slot (RGB: channel) each channel of a camera sub-path is currently at:
    /// the identity until a fluorescent vertex shifts it ([`SpectralMode::shift_camera`]).
    type Slots: Copy + Debug + Default + PartialEq + Send + Sync;

    /// Number of input slots a fluorescent shift chooses among (RGB: the 3 channels; spectral:
    /// the 2 wavelengths of the other independent pair).
    const SHIFT_CHOICES: u32;

    /// `"rgb"` or `"spectral"`.
    const NAME: &'static str;

    /// Factor for a contribution whose light and camera sub-paths both terminated their secondary
    /// wavelengths (1 in RGB mode, 1/4 for [`Hero4`]).
    const DOUBLE_TERMINATION: f32;

    /// The same value for every channel / wavelength.
    fn splat(v: f32) -> Self;

    /// Draws the wavelengths from uniform numbers in [0, 1). `paired` (scenes with
    /// fluorescence) draws two independent stratified pairs instead of four rotated
    /// wavelengths, so that a fluorescent shift can take its input wavelength from the other
    /// pair, independent of its output wavelength.
    fn sample_wavelengths(u: f32, v: f32, paired: bool) -> Self::Wavelengths;

    /// The hero wavelength in nm (`None` in RGB mode and with paired wavelengths), for
    /// dispersive materials.
    fn hero_wavelength(w: &Self::Wavelengths) -> Option<f32>;

    /// The channels of `self` read from the slots `slots` (channel j takes slot `slots[j]`).
    fn gather(self, slots: &Self::Slots) -> Self;

    /// A light-side fluorescent shift with input choice `choice` (< [`SpectralMode::SHIFT_CHOICES`]):
    /// output slot `a` takes `K(b → a) · v[b]` from its candidate input slot `b`, where the
    /// kernel `K` is such that summing over the choices estimates the re-emitted quantity
    /// (RGB: the reradiation matrix; spectral: `Q a(λ_b) e(λ_a) / (2 p(λ_b))`, the two input
    /// wavelengths of the other pair estimating ∫ dλ_in). The Lambertian factor and the
    /// probability of the choice are the caller's.
    fn shift_light(w: &Self::Wavelengths, f: &Fluorescence, choice: u32, v: Self) -> Self;

    /// The camera-side counterpart (the adjoint): channel `j` at slot `a = slots[j]` is
    /// multiplied by `K(b → a)` and moves to its candidate input slot `b`.
    fn shift_camera(w: &Self::Wavelengths, f: &Fluorescence, choice: u32, slots: &mut Self::Slots, t: Self) -> Self;

    /// A reflectance-like quantity given in linear sRGB (a BSDF value or albedo, a bounded
    /// reflectance): upsampled with the linear basis.
    fn from_reflectance(w: &Self::Wavelengths, rgb: Rgb) -> Self;

    /// Emitted radiance (or intensity, irradiance) given in linear sRGB: the upsampled
    /// reflectance times the colour space's illuminant (D65), scaled so that its colour is `rgb`.
    fn from_emission(w: &Self::Wavelengths, rgb: Rgb) -> Self;

    /// A spectral function of the wavelength in nm, evaluated at the wavelengths (RGB mode has
    /// no wavelengths and returns `fallback`).
    fn from_function(w: &Self::Wavelengths, f: impl Fn(f32) -> f32, fallback: Rgb) -> Self;

    /// The linear-sRGB colour of an estimate (for the film): in spectral mode the Monte Carlo
    /// estimate of ∫ v(λ) x̄ȳz̄(λ) dλ / ∫ ȳ over the wavelengths, converted to sRGB.
    fn to_rgb(self, w: &Self::Wavelengths) -> Rgb;

    /// Keeps only the hero wavelength, which then carries the whole estimate (dispersion).
    fn terminate_secondary(self) -> Self;

    /// Largest channel.
    fn max_component(self) -> f32;

    /// True when every channel is zero.
    fn is_black(self) -> bool;

    /// True when no channel is NaN or infinite.
    fn is_finite(self) -> bool;

    /// Number of channels (RGB: 3, [`Hero4`]: 4); participating media pick one to sample
    /// distances with.
    const CHANNELS: usize;

    /// Channel `i` (< [`SpectralMode::CHANNELS`]).
    fn channel(self, i: usize) -> f32;

    /// `f` applied to every channel.
    fn map(self, f: impl Fn(f32) -> f32) -> Self;
}

/// A per-channel slot map (identity by default).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Slots<const N: usize>(pub [u8; N]);

impl<const N: usize> Default for Slots<N> {
    fn default() -> Self {
        Slots(std::array::from_fn(|i| i as u8))
    }
}

impl SpectralMode for Rgb {
    type Wavelengths = ();
    type Slots = Slots<3>;
    const SHIFT_CHOICES: u32 = 3;
    const NAME: &'static str = "rgb";
    const DOUBLE_TERMINATION: f32 = 1.0;
    const CHANNELS: usize = 3;

    #[inline]
    fn channel(self, i: usize) -> f32 {
        self.to_array()[i]
    }
    #[inline]
    fn map(self, f: impl Fn(f32) -> f32) -> Self {
        Rgb::map(self, f)
    }

    #[inline]
    fn splat(v: f32) -> Self {
        Rgb::splat(v)
    }
    #[inline]
    fn sample_wavelengths(_u: f32, _v: f32, _paired: bool) {}
    #[inline]
    fn hero_wavelength(_w: &()) -> Option<f32> {
        None
    }
    #[inline]
    fn gather(self, slots: &Slots<3>) -> Self {
        let v = self.to_array();
        Rgb::new(v[slots.0[0] as usize], v[slots.0[1] as usize], v[slots.0[2] as usize])
    }
    fn shift_light(_w: &(), f: &Fluorescence, choice: u32, v: Self) -> Self {
        let (m, b) = (f.rgb_matrix(), (choice as usize).min(2));
        let input = v.to_array()[b];
        Rgb::new(m[0][b] * input, m[1][b] * input, m[2][b] * input)
    }
    fn shift_camera(_w: &(), f: &Fluorescence, choice: u32, slots: &mut Slots<3>, t: Self) -> Self {
        let (m, b) = (f.rgb_matrix(), (choice as usize).min(2));
        let mut out = t.to_array();
        for (value, slot) in out.iter_mut().zip(slots.0.iter_mut()) {
            *value *= m[*slot as usize][b];
            *slot = b as u8;
        }
        Rgb::from_array(out)
    }
    #[inline]
    fn from_reflectance(_w: &(), rgb: Rgb) -> Self {
        rgb
    }
    #[inline]
    fn from_emission(_w: &(), rgb: Rgb) -> Self {
        rgb
    }
    #[inline]
    fn from_function(_w: &(), _f: impl Fn(f32) -> f32, fallback: Rgb) -> Self {
        fallback
    }
    #[inline]
    fn to_rgb(self, _w: &()) -> Rgb {
        self
    }
    #[inline]
    fn terminate_secondary(self) -> Self {
        self
    }
    #[inline]
    fn max_component(self) -> f32 {
        Rgb::max_component(self)
    }
    #[inline]
    fn is_black(self) -> bool {
        Rgb::is_black(self)
    }
    #[inline]
    fn is_finite(self) -> bool {
        Rgb::is_finite(self)
    }
}

/// Number of wavelengths a [`Hero4`] path carries.
pub const HERO_COUNT: usize = 4;

/// Values at the four wavelengths of a [`Wavelengths4`] set (index 0 is the hero). Units as for
/// [`Rgb`], per nm where the quantity is spectral radiance.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Hero4(pub [f32; HERO_COUNT]);

/// Four hero-rotated wavelengths and what the conversions need at them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Wavelengths4 {
    /// Wavelengths in nm; index 0 is the hero.
    pub lambda: [f32; HERO_COUNT],
    /// Their densities per nm ([`crate::wavelengths::visible_pdf`]).
    pub pdf: [f32; HERO_COUNT],
    /// The upsampling basis at the wavelengths: `basis[c][j]` is b_c (c = r, g, b) at
    /// wavelength j (stored by colour so that upsampling is three 4-wide multiply-adds).
    pub basis: [[f32; HERO_COUNT]; 3],
    /// The emitter factor at each wavelength: D65(λ)·∫ȳ/∫(D65·ȳ).
    pub illuminant: [f32; HERO_COUNT],
    /// Linear-sRGB weight of each wavelength: M_XYZ→sRGB · x̄ȳz̄(λ) / (4 · pdf(λ) · ∫ȳ).
    pub to_rgb: [[f32; 3]; HERO_COUNT],
    /// Two independent pairs (slots 0, 1 at `u, u + ½` and 2, 3 at `v, v + ½` in primary
    /// sample space) instead of four rotated wavelengths.
    pub paired: bool,
}

impl Wavelengths4 {
    /// The set whose hero has primary sample `u` ∈ [0, 1): four wavelengths rotated by a
    /// quarter in primary sample space, or, when `paired`, two pairs rotated by a half, the
    /// second pair starting at the independent `v`.
    pub fn sample(u: f32, v: f32, paired: bool) -> Self {
        let mut w = Wavelengths4 {
            lambda: [0.0; HERO_COUNT],
            pdf: [0.0; HERO_COUNT],
            basis: [[0.0; HERO_COUNT]; 3],
            illuminant: [0.0; HERO_COUNT],
            to_rgb: [[0.0; 3]; HERO_COUNT],
            paired,
        };
        let clean = |x: f32| if x.is_finite() { x.clamp(0.0, 1.0) } else { 0.0 };
        let (u, v) = (clean(u), clean(v));
        let illuminant_scale = (crate::cie::CIE_Y_INTEGRAL / crate::cie::D65_Y_INTEGRAL) as f32;
        let norm = 1.0 / (HERO_COUNT as f32 * crate::cie::CIE_Y_INTEGRAL as f32);
        // Rotation in primary sample space without `fract` (the offsets are below 1).
        let wrap = |x: f32| if x >= 1.0 { x - 1.0 } else { x };
        for j in 0..HERO_COUNT {
            let uj = if paired {
                let start = if j < 2 { u } else { v };
                wrap(start + 0.5 * (j % 2) as f32)
            } else {
                wrap(u + j as f32 / HERO_COUNT as f32)
            };
            let (lambda, pdf) = crate::wavelengths::sample_visible_with_pdf(uj);
            w.lambda[j] = lambda;
            w.pdf[j] = pdf;
            // One table lookup for the basis, D65 and the sRGB colour matching functions (all
            // on the same 5 nm grid).
            if let Some((i, t)) = crate::cie::locate(lambda) {
                for (row, b) in w.basis.iter_mut().zip(crate::upsample::basis_at(i, t)) {
                    row[j] = b;
                }
                let (srgb_cmf, d65) = crate::cie::srgb_cmf_at(i, t);
                w.illuminant[j] = d65 * illuminant_scale;
                let scale = if pdf > 0.0 { norm / pdf } else { 0.0 };
                w.to_rgb[j] = srgb_cmf.map(|c| c * scale);
            }
        }
        w
    }
}

/// The input slot of a fluorescent shift into slot `a` with choice `choice` (paired layout:
/// the other pair).
#[inline]
fn other_pair(a: usize, choice: u32) -> usize {
    let c = (choice as usize).min(1);
    if a < 2 { 2 + c } else { c }
}

/// The spectral shift kernel K(b → a) = Q a(λ_b) e(λ_a) / (2 p(λ_b)).
#[inline]
fn hero_kernel(w: &Wavelengths4, f: &Fluorescence, b: usize, a: usize) -> f32 {
    if w.pdf[b] > 0.0 { f.kernel(w.lambda[b], w.lambda[a]) / (2.0 * w.pdf[b]) } else { 0.0 }
}

impl SpectralMode for Hero4 {
    type Wavelengths = Wavelengths4;
    type Slots = Slots<HERO_COUNT>;
    const SHIFT_CHOICES: u32 = 2;
    const NAME: &'static str = "spectral";
    const DOUBLE_TERMINATION: f32 = 1.0 / HERO_COUNT as f32;
    const CHANNELS: usize = HERO_COUNT;

    #[inline]
    fn channel(self, i: usize) -> f32 {
        self.0[i]
    }
    #[inline]
    fn map(self, f: impl Fn(f32) -> f32) -> Self {
        Hero4(self.0.map(f))
    }

    #[inline]
    fn splat(v: f32) -> Self {
        Hero4([v; HERO_COUNT])
    }
    #[inline]
    fn sample_wavelengths(u: f32, v: f32, paired: bool) -> Wavelengths4 {
        Wavelengths4::sample(u, v, paired)
    }
    #[inline]
    fn hero_wavelength(w: &Wavelengths4) -> Option<f32> {
        (!w.paired).then_some(w.lambda[0])
    }
    #[inline]
    fn gather(self, slots: &Slots<HERO_COUNT>) -> Self {
        Hero4(std::array::from_fn(|j| self.0[slots.0[j] as usize]))
    }
    fn shift_light(w: &Wavelengths4, f: &Fluorescence, choice: u32, v: Self) -> Self {
        Hero4(std::array::from_fn(|a| {
            let b = other_pair(a, choice);
            hero_kernel(w, f, b, a) * v.0[b]
        }))
    }
    fn shift_camera(w: &Wavelengths4, f: &Fluorescence, choice: u32, slots: &mut Slots<HERO_COUNT>, t: Self) -> Self {
        let mut out = t.0;
        for (value, slot) in out.iter_mut().zip(slots.0.iter_mut()) {
            let a = *slot as usize;
            let b = other_pair(a, choice);
            *value *= hero_kernel(w, f, b, a);
            *slot = b as u8;
        }
        Hero4(out)
    }
    #[inline]
    fn from_reflectance(w: &Wavelengths4, rgb: Rgb) -> Self {
        let [r, g, b] = &w.basis;
        Hero4(std::array::from_fn(|j| r[j] * rgb.r + g[j] * rgb.g + b[j] * rgb.b))
    }
    #[inline]
    fn from_emission(w: &Wavelengths4, rgb: Rgb) -> Self {
        let mut v = Self::from_reflectance(w, rgb);
        for (x, i) in v.0.iter_mut().zip(w.illuminant) {
            *x *= i;
        }
        v
    }
    #[inline]
    fn from_function(w: &Wavelengths4, f: impl Fn(f32) -> f32, _fallback: Rgb) -> Self {
        Hero4(std::array::from_fn(|j| f(w.lambda[j])))
    }
    #[inline]
    fn to_rgb(self, w: &Wavelengths4) -> Rgb {
        // Most estimates of a path are zero (occluded, out of range): the sum below would be +0
        // in every channel (a zero times a negative weight is −0, and +0 + −0 = +0).
        if self.is_black() {
            return Rgb::BLACK;
        }
        let mut out = [0.0f32; 3];
        for (v, weight) in self.0.iter().zip(&w.to_rgb) {
            for c in 0..3 {
                out[c] += v * weight[c];
            }
        }
        Rgb::from_array(out)
    }
    #[inline]
    fn terminate_secondary(self) -> Self {
        let mut v = [0.0; HERO_COUNT];
        v[0] = self.0[0] * HERO_COUNT as f32;
        Hero4(v)
    }
    #[inline]
    fn max_component(self) -> f32 {
        self.0.iter().fold(self.0[0], |m, v| m.max(*v))
    }
    #[inline]
    fn is_black(self) -> bool {
        self.0.iter().all(|v| *v == 0.0)
    }
    #[inline]
    fn is_finite(self) -> bool {
        self.0.iter().all(|v| v.is_finite())
    }
}

impl Add for Hero4 {
    type Output = Hero4;
    #[inline]
    fn add(self, o: Hero4) -> Hero4 {
        Hero4(std::array::from_fn(|j| self.0[j] + o.0[j]))
    }
}

impl AddAssign for Hero4 {
    #[inline]
    fn add_assign(&mut self, o: Hero4) {
        *self = *self + o;
    }
}

impl Mul for Hero4 {
    type Output = Hero4;
    #[inline]
    fn mul(self, o: Hero4) -> Hero4 {
        Hero4(std::array::from_fn(|j| self.0[j] * o.0[j]))
    }
}

impl MulAssign for Hero4 {
    #[inline]
    fn mul_assign(&mut self, o: Hero4) {
        *self = *self * o;
    }
}

impl Mul<f32> for Hero4 {
    type Output = Hero4;
    #[inline]
    fn mul(self, s: f32) -> Hero4 {
        Hero4(self.0.map(|v| v * s))
    }
}

impl MulAssign<f32> for Hero4 {
    #[inline]
    fn mul_assign(&mut self, s: f32) {
        *self = *self * s;
    }
}

impl Div<f32> for Hero4 {
    type Output = Hero4;
    #[inline]
    fn div(self, s: f32) -> Hero4 {
        Hero4(self.0.map(|v| v / s))
    }
}
