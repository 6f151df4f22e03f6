//! Piecewise-linear spectra given by samples (measured reflectances, emission spectra, …).

use crate::cie::{D65_Y_INTEGRAL, TABLE_LEN, TABLE_MAX_NM, TABLE_MIN_NM, TABLE_STEP_NM, cmf, d65};

/// A spectrum given by samples `(λ nm, value)`, linearly interpolated between them and zero
/// outside `[first λ, last λ]`. The unit of the values is the caller's (a reflectance is
/// unitless, a radiance per nm, …).
#[derive(Clone, Debug, PartialEq)]
pub struct Tabulated {
    /// Wavelengths (nm), strictly increasing, finite, at least two.
    lambda: Vec<f32>,
    /// Values at those wavelengths, finite.
    value: Vec<f32>,
}

impl Tabulated {
    /// From `(wavelength nm, value)` pairs. Errors unless there are at least two pairs, every
    /// number is finite, and the wavelengths are strictly increasing.
    pub fn new(points: &[(f32, f32)]) -> Result<Self, String> {
        if points.len() < 2 {
            return Err(format!("a tabulated spectrum needs at least two samples, got {}", points.len()));
        }
        for (i, &(l, v)) in points.iter().enumerate() {
            if !l.is_finite() || !v.is_finite() {
                return Err(format!("sample {i} of the tabulated spectrum is not finite: ({l}, {v})"));
            }
            if i > 0 && l <= points[i - 1].0 {
                return Err(format!(
                    "the wavelengths of a tabulated spectrum must be strictly increasing: sample {i} ({l} nm) \
                     follows {} nm",
                    points[i - 1].0
                ));
            }
        }
        Ok(Self { lambda: points.iter().map(|p| p.0).collect(), value: points.iter().map(|p| p.1).collect() })
    }

    /// The samples as `(wavelength nm, value)` pairs.
    pub fn points(&self) -> impl Iterator<Item = (f32, f32)> + '_ {
        self.lambda.iter().copied().zip(self.value.iter().copied())
    }

    /// The spectrum at `lambda_nm` (nm): linear interpolation, zero outside the sampled range
    /// (and for NaN). No allocation; `O(log n)`.
    pub fn eval(&self, lambda_nm: f32) -> f32 {
        let (first, last) = (self.lambda[0], self.lambda[self.lambda.len() - 1]);
        if !(first..=last).contains(&lambda_nm) {
            return 0.0;
        }
        // The first sample above `lambda_nm`, kept in 1..len so that [i − 1, i] is an interval.
        let i = self.lambda.partition_point(|&l| l <= lambda_nm).clamp(1, self.lambda.len() - 1);
        let (l0, l1, v0, v1) = (self.lambda[i - 1], self.lambda[i], self.value[i - 1], self.value[i]);
        v0 + (v1 - v0) * ((lambda_nm - l0) / (l1 - l0))
    }

    /// `∫ s(λ) (x̄, ȳ, z̄)(λ) dλ` (units of the values × nm) with the colour matching functions
    /// of [`crate::cie::cmf`], computed exactly: on every interval between consecutive
    /// breakpoints of both piecewise-linear functions the integrand is quadratic, and
    /// Simpson's rule integrates it exactly. Divide by [`crate::cie::CIE_Y_INTEGRAL`] for an
    /// emitted spectrum's normalised XYZ.
    pub fn to_xyz(&self) -> [f64; 3] {
        self.integrate(|l| cmf(l).map(f64::from))
    }

    /// The XYZ of the spectrum as a reflectance under D65:
    /// `∫ s D65 (x̄, ȳ, z̄) dλ / ∫ D65 ȳ dλ` (units of the values; a constant reflectance `c`
    /// gives `Y = c`), exact (cubic integrand, Simpson's rule).
    pub fn to_xyz_under_d65(&self) -> [f64; 3] {
        self.integrate(|l| {
            let w = f64::from(d65(l)) / D65_Y_INTEGRAL;
            cmf(l).map(|c| f64::from(c) * w)
        })
    }

    /// `∫ s(λ) w(λ) dλ` over the overlap with 360–830 nm, for `w` linear (or quadratic) on every
    /// 5 nm interval: Simpson's rule on every interval between the breakpoints of `s` and the
    /// 5 nm grid.
    fn integrate(&self, w: impl Fn(f32) -> [f64; 3]) -> [f64; 3] {
        let lo = self.lambda[0].max(TABLE_MIN_NM);
        let hi = self.lambda[self.lambda.len() - 1].min(TABLE_MAX_NM);
        let mut sum = [0.0; 3];
        if lo >= hi {
            return sum;
        }
        // Merge the spectrum's wavelengths with the grid's, both sorted, inside [lo, hi].
        let grid = (0..TABLE_LEN).map(|i| TABLE_MIN_NM + TABLE_STEP_NM * i as f32);
        let mut points: Vec<f32> = self.lambda.iter().copied().chain(grid).filter(|l| (lo..=hi).contains(l)).collect();
        points.push(lo);
        points.push(hi);
        points.sort_by(f32::total_cmp);
        points.dedup();
        for pair in points.windows(2) {
            let (a, b) = (pair[0], pair[1]);
            let m = 0.5 * (a + b);
            let f = |l: f32| w(l).map(|v| v * f64::from(self.eval(l)));
            let (fa, fm, fb) = (f(a), f(m), f(b));
            let h = f64::from(b - a) / 6.0;
            for c in 0..3 {
                sum[c] += h * (fa[c] + 4.0 * fm[c] + fb[c]);
            }
        }
        sum
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cie::{CMF_INTEGRALS, D65_TABLE, D65_XYZ};

    #[test]
    fn rejects_bad_input() {
        assert!(Tabulated::new(&[]).is_err());
        assert!(Tabulated::new(&[(500.0, 1.0)]).is_err());
        assert!(Tabulated::new(&[(500.0, 1.0), (500.0, 2.0)]).is_err());
        assert!(Tabulated::new(&[(500.0, 1.0), (400.0, 2.0)]).is_err());
        assert!(Tabulated::new(&[(500.0, f32::NAN), (600.0, 2.0)]).is_err());
        assert!(Tabulated::new(&[(500.0, 1.0), (f32::INFINITY, 2.0)]).is_err());
        assert!(Tabulated::new(&[(500.0, 1.0), (600.0, -2.0)]).is_ok());
    }

    #[test]
    fn evaluates_piecewise_linearly_and_zero_outside() {
        let s = Tabulated::new(&[(400.0, 1.0), (500.0, 3.0), (700.0, 0.0)]).unwrap();
        assert_eq!(s.eval(400.0), 1.0);
        assert_eq!(s.eval(450.0), 2.0);
        assert_eq!(s.eval(500.0), 3.0);
        assert_eq!(s.eval(650.0), 0.75);
        assert_eq!(s.eval(700.0), 0.0);
        for l in [399.9, 700.1, f32::NAN] {
            assert_eq!(s.eval(l), 0.0);
        }
        assert_eq!(s.points().count(), 3);
    }

    #[test]
    fn xyz_of_constant_and_of_d65_match_the_cie_integrals() {
        let one = Tabulated::new(&[(300.0, 1.0), (900.0, 1.0)]).unwrap();
        let xyz = one.to_xyz();
        for c in 0..3 {
            assert!((xyz[c] / CMF_INTEGRALS[c] - 1.0).abs() < 1e-6, "{xyz:?}");
        }
        let d = one.to_xyz_under_d65();
        assert!((d[1] - 1.0).abs() < 1e-6, "{d:?}");
        let table: Vec<(f32, f32)> =
            D65_TABLE.iter().enumerate().map(|(i, &v)| (360.0 + 5.0 * i as f32, v as f32)).collect();
        let xyz = Tabulated::new(&table).unwrap().to_xyz();
        for c in 0..3 {
            assert!((xyz[c] / D65_XYZ[c] - 1.0).abs() < 1e-6, "{xyz:?} vs {D65_XYZ:?}");
        }
    }

    #[test]
    fn xyz_matches_brute_force_on_an_irregular_spectrum() {
        // Breakpoints off the 5 nm grid, partly outside 360–830 nm.
        let s = Tabulated::new(&[(340.0, 0.2), (411.3, 0.9), (412.0, 0.1), (587.7, 0.6), (640.2, 0.05), (850.0, 0.4)])
            .unwrap();
        let n = 470_000;
        let h = 470.0 / n as f64;
        let mut brute = [0.0f64; 3];
        let mut brute_d65 = [0.0f64; 3];
        for i in 0..n {
            let l = (360.0 + (i as f64 + 0.5) * h) as f32;
            let c = cmf(l);
            for k in 0..3 {
                brute[k] += f64::from(s.eval(l)) * f64::from(c[k]) * h;
                brute_d65[k] += f64::from(s.eval(l) * d65(l)) * f64::from(c[k]) * h / D65_Y_INTEGRAL;
            }
        }
        let (exact, exact_d65) = (s.to_xyz(), s.to_xyz_under_d65());
        for k in 0..3 {
            assert!((exact[k] / brute[k] - 1.0).abs() < 1e-5, "{exact:?} vs {brute:?}");
            assert!((exact_d65[k] / brute_d65[k] - 1.0).abs() < 1e-5, "{exact_d65:?} vs {brute_d65:?}");
        }
        // A spectrum entirely outside the tables has no colour.
        assert_eq!(Tabulated::new(&[(900.0, 1.0), (1000.0, 1.0)]).unwrap().to_xyz(), [0.0; 3]);
    }
}
