//! Phase functions: isotropic and Henyey–Greenstein, with their samplers.
//!
//! Directions follow the BSDF convention: `fixed` points *away* from the scattering point,
//! back along the path (the negated propagation direction of the arriving ray), `generated`
//! points away from it along the new segment. The scattering angle θ is the angle between
//! the propagation directions, `cos θ = −fixed · generated`; θ = 0 is no deflection. Values
//! are per steradian and integrate to 1 over the sphere, so the sampling pdf (solid angle)
//! equals the value and a sample's weight `value / pdf` is exactly 1.

use math::{Frame, Vec3};
use std::f32::consts::PI;

/// A phase function.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PhaseFunction {
    /// `1 / (4π)`.
    Isotropic,
    /// Henyey–Greenstein with mean cosine `g ∈ (−1, 1)` (g > 0 scatters forward):
    /// `p(θ) = (1 − g²) / (4π (1 + g² − 2g cos θ)^{3/2})` (Henyey and Greenstein 1941).
    HenyeyGreenstein {
        /// Mean cosine of the scattering angle.
        g: f32,
    },
}

/// A sampled direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhaseSample {
    /// Unit generated direction.
    pub direction: Vec3,
    /// Phase function value = pdf (per steradian, solid angle).
    pub pdf: f32,
}

impl PhaseFunction {
    /// Henyey–Greenstein with `g`, isotropic when `g = 0`. `g` must lie in (−1, 1).
    pub fn henyey_greenstein(g: f32) -> Result<Self, String> {
        if !(g > -1.0 && g < 1.0) {
            return Err(format!("the Henyey–Greenstein parameter g must lie in (−1, 1), got {g}"));
        }
        Ok(if g == 0.0 { PhaseFunction::Isotropic } else { PhaseFunction::HenyeyGreenstein { g } })
    }

    /// The value (= solid-angle pdf) for the unit directions `fixed` and `generated`
    /// (module convention); symmetric in the two.
    #[inline]
    pub fn evaluate(&self, fixed: Vec3, generated: Vec3) -> f32 {
        match *self {
            PhaseFunction::Isotropic => 1.0 / (4.0 * PI),
            PhaseFunction::HenyeyGreenstein { g } => {
                let cos_theta = -fixed.dot(generated);
                let denominator = (1.0 + g * g - 2.0 * g * cos_theta).max(1e-12);
                (1.0 - g * g) / (4.0 * PI * denominator * denominator.sqrt())
            }
        }
    }

    /// Samples `generated` for `fixed` from `u ∈ [0,1)²` in proportion to the value: the
    /// inverse of the cumulative distribution of cos θ (for Henyey–Greenstein
    /// `cos θ = (1 + g² − ((1 − g²)/(1 − g + 2g·u₀))²) / (2g)`), φ = 2π·u₁ about the
    /// propagation direction `−fixed`.
    #[inline]
    pub fn sample(&self, fixed: Vec3, u: [f32; 2]) -> PhaseSample {
        let cos_theta = match *self {
            PhaseFunction::Isotropic => 1.0 - 2.0 * u[0],
            PhaseFunction::HenyeyGreenstein { g } if g.abs() < 1e-3 => 1.0 - 2.0 * u[0],
            PhaseFunction::HenyeyGreenstein { g } => {
                let s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u[0]);
                (1.0 + g * g - s * s) / (2.0 * g)
            }
        }
        .clamp(-1.0, 1.0);
        let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
        let (sin_phi, cos_phi) = math::sin_cos_turns(u[1]);
        let local = Vec3::new(sin_theta * cos_phi, sin_theta * sin_phi, cos_theta);
        let direction = Frame::from_z(-fixed).to_world(local).normalize();
        PhaseSample { direction, pdf: self.evaluate(fixed, direction) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn isotropic_and_forward_values() {
        let d = Vec3::Z;
        assert!((PhaseFunction::Isotropic.evaluate(d, d) - 1.0 / (4.0 * PI)).abs() < 1e-7);
        // No deflection (generated = −fixed): (1 − g²)/(4π(1 − g)³) = (1 + g)/(4π(1 − g)²).
        let g = 0.5;
        let p = PhaseFunction::HenyeyGreenstein { g }.evaluate(-d, d);
        assert!((p - (1.0 + g) / (4.0 * PI * (1.0 - g) * (1.0 - g))).abs() < 1e-5, "{p}");
        assert!(PhaseFunction::henyey_greenstein(1.0).is_err());
        assert_eq!(PhaseFunction::henyey_greenstein(0.0), Ok(PhaseFunction::Isotropic));
    }
}
