//! Probability densities typed by their measure, so that a solid-angle density can never be
//! used where an area density is expected.
//!
//! Conversions follow the geometry term: for two points at distance `d` where the direction
//! makes angle `θ` with the surface normal at the target point, `p_A = p_ω · |cos θ| / d²`.

/// A density with respect to solid angle (per steradian).
#[derive(Clone, Copy, Debug, Default, PartialEq, PartialOrd)]
pub struct PdfW(pub f32);

/// A density with respect to surface area (per square scene unit). For infinite lights,
/// whose "positions" are directions, the tech report (§5.1) stores a solid-angle density in the
/// same slot; the light's documentation says so where that happens.
#[derive(Clone, Copy, Debug, Default, PartialEq, PartialOrd)]
pub struct PdfA(pub f32);

impl PdfW {
    /// The density per unit area at a point at distance² `distance_squared` whose normal
    /// makes cosine `cos_at_target` with the connecting direction.
    #[inline]
    pub fn to_area(self, distance_squared: f32, cos_at_target: f32) -> PdfA {
        PdfA(self.0 * cos_at_target.abs() / distance_squared)
    }
    /// The raw value.
    #[inline]
    pub fn value(self) -> f32 {
        self.0
    }
}

impl PdfA {
    /// The density per unit solid angle seen from a point at distance² `distance_squared`,
    /// where the target's normal makes cosine `cos_at_target` with the connecting direction.
    /// Returns 0 for a grazing target (cosine 0) instead of infinity.
    #[inline]
    pub fn to_solid_angle(self, distance_squared: f32, cos_at_target: f32) -> PdfW {
        let c = cos_at_target.abs();
        if c == 0.0 { PdfW(0.0) } else { PdfW(self.0 * distance_squared / c) }
    }
    /// The raw value.
    #[inline]
    pub fn value(self) -> f32 {
        self.0
    }
}

impl std::ops::Mul<f32> for PdfW {
    type Output = PdfW;
    #[inline]
    fn mul(self, rhs: f32) -> PdfW {
        PdfW(self.0 * rhs)
    }
}

impl std::ops::Mul<f32> for PdfA {
    type Output = PdfA;
    #[inline]
    fn mul(self, rhs: f32) -> PdfA {
        PdfA(self.0 * rhs)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn conversions_invert() {
        let w = PdfW(0.37);
        let a = w.to_area(4.0, 0.5);
        assert!((a.0 - 0.37 * 0.5 / 4.0).abs() < 1e-7);
        let back = a.to_solid_angle(4.0, -0.5);
        assert!((back.0 - 0.37).abs() < 1e-6);
        assert_eq!(PdfA(1.0).to_solid_angle(1.0, 0.0), PdfW(0.0));
    }
}
