//! Wavelength-dependent indices of refraction (dispersion).
//!
//! Named dispersive materials (Sellmeier fits, λ in µm):
//!
//! | name | source | n_d (587.56 nm) | Abbe V_d | Mitsuba's constant |
//! |---|---|---|---|---|
//! | `bk7` | Schott N-BK7 data sheet | 1.51680 | 64.17 | 1.5046 |
//! | `fused quartz`, `fused silica` | Malitson, JOSA 55 (1965) | 1.45846 | 67.82 | 1.458 |
//! | `diamond` | Peter, Z. Phys. 15 (1923), valid 365–707 nm | 2.41749 | 55.3 | 2.419 |
//!
//! Mitsuba's `bk7` constant, 1.5046, is not BK7's n_d (1.5168) — a scene that names `bk7`
//! renders with a different index in the spectral mode than in Mitsuba. Water is left out:
//! we know no dispersion fit well enough to vouch for its coefficients.

use crate::wavelengths::{LAMBDA_MAX, LAMBDA_MIN};

/// Helium d line (nm): where the glass catalogues quote n_d.
pub const HELIUM_D_NM: f32 = 587.5618;
/// Sodium D line (nm), the mean of D₁ and D₂: where tables like Mitsuba's quote n_D.
pub const SODIUM_D_NM: f32 = 589.29;
/// Hydrogen F line (nm).
pub const HYDROGEN_F_NM: f32 = 486.1327;
/// Hydrogen C line (nm).
pub const HYDROGEN_C_NM: f32 = 656.2725;

/// An index of refraction (unitless) as a function of the vacuum wavelength.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Ior {
    /// The same index at every wavelength.
    Constant(f32),
    /// Cauchy's formula `n(λ) = a + b / λ²` with λ in µm (`b_um2` in µm²).
    Cauchy {
        /// Constant term (unitless).
        a: f32,
        /// Coefficient of `1/λ²` (µm²).
        b_um2: f32,
    },
    /// Sellmeier's formula `n²(λ) = 1 + Σᵢ bᵢ λ² / (λ² − cᵢ)` with λ in µm (`c_um2` in µm²).
    Sellmeier {
        /// Oscillator strengths (unitless).
        b: [f32; 3],
        /// Squared resonance wavelengths (µm²).
        c_um2: [f32; 3],
    },
}

impl Ior {
    /// The index at the vacuum wavelength `lambda_nm` (nm), computed in double precision.
    ///
    /// Wavelengths are clamped to [[`LAMBDA_MIN`], [`LAMBDA_MAX`]] (NaN counts as
    /// `LAMBDA_MIN`), the range the renderer samples and the fits are meant for. If the
    /// parameters give no finite index of at least 1 there (non-finite parameters, a resonance
    /// inside the visible range), the result is 1 (no refraction); [`Ior::validate`] reports
    /// such parameters.
    pub fn eval(&self, lambda_nm: f32) -> f32 {
        let l = if lambda_nm.is_nan() { LAMBDA_MIN } else { lambda_nm.clamp(LAMBDA_MIN, LAMBDA_MAX) };
        let n = self.eval_unchecked(f64::from(l));
        if n.is_finite() && n >= 1.0 { n as f32 } else { 1.0 }
    }

    /// The formula itself, without clamping (λ in nm).
    fn eval_unchecked(&self, lambda_nm: f64) -> f64 {
        let l2 = (lambda_nm * 1e-3).powi(2);
        match *self {
            Ior::Constant(n) => f64::from(n),
            Ior::Cauchy { a, b_um2 } => f64::from(a) + f64::from(b_um2) / l2,
            Ior::Sellmeier { b, c_um2 } => {
                let s: f64 = b.iter().zip(c_um2).map(|(&b, c)| f64::from(b) * l2 / (l2 - f64::from(c))).sum();
                (1.0 + s).sqrt()
            }
        }
    }

    /// Whether the index varies with the wavelength (a Cauchy or Sellmeier formula with a
    /// non-zero wavelength-dependent term).
    pub fn is_dispersive(&self) -> bool {
        match *self {
            Ior::Constant(_) => false,
            Ior::Cauchy { b_um2, .. } => b_um2 != 0.0,
            Ior::Sellmeier { b, .. } => b.iter().any(|&b| b != 0.0),
        }
    }

    /// n_d: the index at the helium d line, 587.5618 nm ([`HELIUM_D_NM`]), as glass
    /// catalogues quote it.
    pub fn n_d(&self) -> f32 {
        self.eval(HELIUM_D_NM)
    }

    /// n_D: the index at the sodium D line, 589.29 nm ([`SODIUM_D_NM`]), as tables like
    /// Mitsuba's quote it (for BK7 it is 7·10⁻⁵ below n_d).
    pub fn n_sodium_d(&self) -> f32 {
        self.eval(SODIUM_D_NM)
    }

    /// Abbe number `V_d = (n_d − 1) / (n_F − n_C)` (unitless; infinite for a constant index).
    pub fn abbe_number(&self) -> f32 {
        (self.n_d() - 1.0) / (self.eval(HYDROGEN_F_NM) - self.eval(HYDROGEN_C_NM))
    }

    /// Checks that the formula gives a finite index of at least 1 over the whole sampled range
    /// (checked every nm), so that [`Ior::eval`] never falls back to 1.
    pub fn validate(&self) -> Result<(), String> {
        let (lo, hi) = (LAMBDA_MIN as u32, LAMBDA_MAX as u32);
        for l in lo..=hi {
            let n = self.eval_unchecked(f64::from(l));
            if !(n.is_finite() && n >= 1.0) {
                return Err(format!("index of refraction {self:?} is {n} at {l} nm (must be finite and at least 1)"));
            }
        }
        Ok(())
    }

    /// The dispersion fit of a material named as in Mitsuba's index-of-refraction table
    /// (case-insensitive): `bk7`, `fused quartz` (also `fused silica`), `diamond` (see the
    /// module documentation for the sources). `None` for other names, including Mitsuba names
    /// we have no fit for.
    pub fn named(name: &str) -> Option<Ior> {
        match name.trim().to_ascii_lowercase().as_str() {
            // Schott N-BK7: B = 1.03961212, 0.231792344, 1.01046945; C = 0.00600069867,
            // 0.0200179144, 103.560653 µm² (as f32).
            "bk7" | "n-bk7" => Some(Ior::Sellmeier {
                b: [1.039_612, 0.231_792_34, 1.010_469_4],
                c_um2: [0.006_000_698_7, 0.020_017_914, 103.560_65],
            }),
            // Malitson 1965: the resonances 0.0684043, 0.1162414 and 9.896161 µm, squared.
            "fused quartz" | "fused silica" => Some(Ior::Sellmeier {
                b: [0.696_166_3, 0.407_942_6, 0.897_479_4],
                c_um2: [0.004_679_148, 0.013_512_063, 97.934_003],
            }),
            // Peter 1923: resonances 0.175 and 0.106 µm.
            "diamond" => Some(Ior::Sellmeier { b: [0.3306, 4.3356, 0.0], c_um2: [0.030_625, 0.011_236, 0.0] }),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bk7_matches_the_schott_catalogue() {
        let g = Ior::named("BK7").unwrap();
        assert!((g.n_d() - 1.5168).abs() < 1e-4, "{}", g.n_d());
        assert!((g.eval(HYDROGEN_F_NM) - 1.52238).abs() < 1e-4);
        assert!((g.eval(HYDROGEN_C_NM) - 1.51432).abs() < 1e-4);
        assert!((g.abbe_number() - 64.17).abs() < 0.1, "{}", g.abbe_number());
        assert!((g.n_sodium_d() - g.n_d() + 7e-5).abs() < 3e-5);
        assert!(g.is_dispersive());
        g.validate().unwrap();
    }

    #[test]
    fn fused_silica_and_diamond_match_their_known_values() {
        let s = Ior::named("fused quartz").unwrap();
        assert_eq!(Ior::named("Fused Silica"), Some(s));
        assert!((s.n_d() - 1.4585).abs() < 1e-4, "{}", s.n_d());
        assert!((s.abbe_number() - 67.8).abs() < 0.1, "{}", s.abbe_number());
        // Mitsuba's constant table: 1.458.
        assert!((s.n_sodium_d() - 1.458).abs() < 1e-3);
        s.validate().unwrap();

        let d = Ior::named("diamond").unwrap();
        // n_D = 2.417 and the gemmologists' dispersion n(430.8) − n(686.7) = 0.044.
        assert!((d.n_sodium_d() - 2.417).abs() < 1e-3, "{}", d.n_sodium_d());
        assert!((d.eval(430.8) - d.eval(686.7) - 0.044).abs() < 1e-3);
        // Mitsuba's constant table: 2.419.
        assert!((d.n_sodium_d() - 2.419).abs() < 3e-3);
        d.validate().unwrap();

        assert_eq!(Ior::named("water"), None);
        assert_eq!(Ior::named("unobtainium"), None);
    }

    #[test]
    fn normal_dispersion_decreases_with_wavelength() {
        for name in ["bk7", "fused silica", "diamond"] {
            let g = Ior::named(name).unwrap();
            for l in (360..830).step_by(10) {
                assert!(g.eval(l as f32) > g.eval(l as f32 + 10.0), "{name} at {l} nm");
            }
        }
    }

    #[test]
    fn constant_cauchy_and_bad_input() {
        assert_eq!(Ior::Constant(1.5).eval(400.0), 1.5);
        assert!(!Ior::Constant(1.5).is_dispersive());
        assert!(Ior::Constant(1.5).abbe_number().is_infinite());
        // Cauchy: 1.5 + 0.004 / 0.5² = 1.516 at 500 nm.
        let c = Ior::Cauchy { a: 1.5, b_um2: 0.004 };
        assert!((c.eval(500.0) - 1.516).abs() < 1e-6);
        assert!(c.is_dispersive() && !Ior::Cauchy { a: 1.5, b_um2: 0.0 }.is_dispersive());
        // Out-of-range wavelengths are clamped, NaN is the shortest.
        assert_eq!(c.eval(100.0), c.eval(LAMBDA_MIN));
        assert_eq!(c.eval(f32::NAN), c.eval(LAMBDA_MIN));
        assert_eq!(c.eval(f32::INFINITY), c.eval(LAMBDA_MAX));
        // A resonance at 500 nm inside the range: eval falls back to 1, validate says why.
        let bad = Ior::Sellmeier { b: [1.0, 0.0, 0.0], c_um2: [0.25, 0.0, 0.0] };
        assert!(bad.validate().is_err());
        assert!((360..=830).all(|l| bad.eval(l as f32).is_finite() && bad.eval(l as f32) >= 1.0));
        assert!(Ior::Constant(f32::NAN).validate().is_err());
        assert_eq!(Ior::Constant(f32::NAN).eval(500.0), 1.0);
        assert!(Ior::Constant(0.5).validate().is_err());
    }
}
