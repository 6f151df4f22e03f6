//! Fluorescence: a bispectral reflectance that absorbs light at one wavelength and re-emits part
//! of its energy at a longer one.
//!
//! The model (per unit Lambertian BRDF `1/π`): the reradiation kernel is
//!
//! ```text
//! f(λ_in → λ_out) = ρ(λ_in) δ(λ_in − λ_out) + Q · a(λ_in) · e(λ_out)
//! ```
//!
//! with ρ the ordinary (diagonal) reflectance, `a(λ) = peak · band_a(λ)` the absorbed fraction,
//! `e` the emission spectrum normalised to ∫ e dλ = 1 (per nm) and `Q` the quantum yield (the
//! fraction of absorbed energy that is re-emitted). A column of the kernel sums to
//! `ρ(λ_in) + Q·a(λ_in) ≤ max ρ + Q·peak`, which [`Fluorescence::check_energy`] keeps ≤ 1.
//!
//! Bands are raised cosines with compact support, so that a scene can guarantee that no light
//! is shifted twice: when no emission band overlaps any absorption band (checked when the scene
//! is built), re-emitted light is never absorbed again, a path has at most one wavelength shift,
//! and every estimator of the renderer is unbiased (see `docs/spectral.md`).

use crate::Rgb;

/// A raised-cosine band `cos²(π (λ − centre) / (2 w))` for `|λ − centre| < w`, 0 outside
/// (peak 1 at the centre, integral `w` nm).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Band {
    /// Centre wavelength in nm.
    pub center_nm: f32,
    /// Half width of the support in nm (the band is zero beyond it).
    pub half_width_nm: f32,
}

impl Band {
    /// The band's value at `lambda_nm` (unitless, ≤ 1).
    #[inline]
    pub fn eval(&self, lambda_nm: f32) -> f32 {
        let x = (lambda_nm - self.center_nm) / self.half_width_nm;
        if x.abs() < 1.0 {
            let c = (std::f32::consts::FRAC_PI_2 * x).cos();
            c * c
        } else {
            0.0
        }
    }

    /// ∫ band dλ in nm.
    pub fn integral(&self) -> f32 {
        self.half_width_nm
    }

    /// The open interval where the band is positive, in nm.
    pub fn support(&self) -> (f32, f32) {
        (self.center_nm - self.half_width_nm, self.center_nm + self.half_width_nm)
    }

    /// Checks that the band is finite, at least 1 nm wide and inside 300–900 nm.
    pub fn validate(&self, what: &str) -> Result<(), String> {
        let (lo, hi) = self.support();
        if !(self.center_nm.is_finite() && self.half_width_nm.is_finite() && self.half_width_nm >= 1.0) {
            return Err(format!("{what} band: centre and half width (≥ 1 nm) must be finite numbers"));
        }
        if lo < 300.0 || hi > 900.0 {
            return Err(format!("{what} band {lo}–{hi} nm must lie within 300–900 nm"));
        }
        Ok(())
    }

    /// Whether the supports of two bands overlap.
    pub fn overlaps(&self, other: &Band) -> bool {
        let (a0, a1) = self.support();
        let (b0, b1) = other.support();
        a0 < b1 && b0 < a1
    }
}

/// The fluorescent part of a material (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fluorescence {
    /// Fraction of incident light absorbed at the absorption band's peak, in [0, 1].
    pub absorption_peak: f32,
    /// Where light is absorbed.
    pub absorption: Band,
    /// Where absorbed energy is re-emitted (normalised to unit integral).
    pub emission: Band,
    /// Fraction of the absorbed energy that is re-emitted, in [0, 1].
    pub quantum_yield: f32,
    /// RGB mode: the 3×3 reradiation matrix `[out][in]` (see [`Fluorescence::rgb_matrix`]).
    rgb: [[f32; 3]; 3],
}

impl Fluorescence {
    /// A fluorescence; fails unless the numbers are in range and the emission band lies entirely
    /// at longer wavelengths than the absorption band (Stokes shift, and no re-absorption of
    /// the material's own emission).
    pub fn new(absorption_peak: f32, absorption: Band, emission: Band, quantum_yield: f32) -> Result<Self, String> {
        absorption.validate("absorption")?;
        emission.validate("emission")?;
        if !(0.0..=1.0).contains(&absorption_peak) {
            return Err(format!("absorption peak must be in [0, 1], got {absorption_peak}"));
        }
        if !(0.0..=1.0).contains(&quantum_yield) {
            return Err(format!("quantum yield must be in [0, 1], got {quantum_yield}"));
        }
        if absorption.support().1 > emission.support().0 {
            return Err(format!(
                "the emission band ({:.0}–{:.0} nm) must lie entirely above the absorption band ({:.0}–{:.0} nm)",
                emission.support().0,
                emission.support().1,
                absorption.support().0,
                absorption.support().1
            ));
        }
        let mut f = Fluorescence { absorption_peak, absorption, emission, quantum_yield, rgb: [[0.0; 3]; 3] };
        f.rgb = f.compute_rgb_matrix();
        Ok(f)
    }

    /// Absorbed fraction a(λ) at `lambda_nm`.
    #[inline]
    pub fn absorbed(&self, lambda_nm: f32) -> f32 {
        self.absorption_peak * self.absorption.eval(lambda_nm)
    }

    /// Emission spectrum e(λ) in nm⁻¹ (∫ e dλ = 1).
    #[inline]
    pub fn emitted(&self, lambda_nm: f32) -> f32 {
        self.emission.eval(lambda_nm) / self.emission.integral()
    }

    /// The off-diagonal kernel `Q·a(λ_in)·e(λ_out)` in nm⁻¹ (per nm of λ_out), without the
    /// Lambertian `1/π`.
    #[inline]
    pub fn kernel(&self, lambda_in_nm: f32, lambda_out_nm: f32) -> f32 {
        self.quantum_yield * self.absorbed(lambda_in_nm) * self.emitted(lambda_out_nm)
    }

    /// Fails when a column of the kernel could exceed 1 with a diagonal reflectance whose
    /// largest upsampled value is `max_reflectance`.
    pub fn check_energy(&self, max_reflectance: f32) -> Result<(), String> {
        let column = max_reflectance + self.quantum_yield * self.absorption_peak;
        if column > 1.0 + 1e-6 {
            return Err(format!(
                "reflectance {max_reflectance} plus re-emitted fraction {} exceeds 1: the material would create energy",
                self.quantum_yield * self.absorption_peak
            ));
        }
        Ok(())
    }

    /// RGB mode's reradiation matrix `M[out][in]`: light of linear-sRGB radiance `rgb` (as an
    /// emitter's spectrum, [`crate::upsample`]) is re-emitted as `M · rgb`. Exact for light
    /// whose spectrum is an upsampled RGB emitter; an approximation for other spectra, like
    /// every RGB rendering of a spectral effect.
    pub fn rgb_matrix(&self) -> &[[f32; 3]; 3] {
        &self.rgb
    }

    /// An estimate of the re-emitted fraction of white light (for sampling decisions).
    pub fn white_yield(&self) -> f32 {
        let m = &self.rgb;
        (0..3).map(|o| m[o][0] + m[o][1] + m[o][2]).sum::<f32>() / 3.0
    }

    fn compute_rgb_matrix(&self) -> [[f32; 3]; 3] {
        use crate::cie::{CIE_Y_INTEGRAL, D65_Y_INTEGRAL, cmf, d65, xyz_to_linear_srgb};
        // A_c = (∫ȳ / ∫D65·ȳ) ∫ a(λ) b_c(λ) D65(λ) dλ: absorbed power per unit of channel c;
        // rgb(e) = M_XYZ→sRGB ∫ e(λ) x̄ȳz̄(λ) dλ / ∫ȳ: the colour of the unit emission.
        let scale = (CIE_Y_INTEGRAL / D65_Y_INTEGRAL) as f32;
        let mut absorbed = [0.0f64; 3];
        let mut xyz = [0.0f64; 3];
        let step = 0.5f32;
        let mut lambda = 360.0 + 0.5 * step;
        while lambda < 830.0 {
            let b = crate::upsample::basis(lambda);
            let a = self.absorbed(lambda) * d65(lambda) * scale;
            let e = self.emitted(lambda);
            let c = cmf(lambda);
            for i in 0..3 {
                absorbed[i] += f64::from(a * b[i] * step);
                xyz[i] += f64::from(e * c[i] * step) / CIE_Y_INTEGRAL;
            }
            lambda += step;
        }
        let colour: Rgb = xyz_to_linear_srgb([xyz[0] as f32, xyz[1] as f32, xyz[2] as f32]);
        let colour = colour.to_array();
        std::array::from_fn(|o| std::array::from_fn(|i| self.quantum_yield * colour[o].max(0.0) * absorbed[i] as f32))
    }
}
