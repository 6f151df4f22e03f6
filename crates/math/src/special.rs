//! Special functions.

/// `erfc(x) = 1 − erf(x)` with a relative error below 1.2·10⁻⁷ for every `x` (the Chebyshev
/// fit of Press et al., "Numerical Recipes", §6.2), so that both tails keep their precision.
pub fn erfc(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let poly = -1.265_512_23
        + t * (1.000_023_68
            + t * (0.374_091_96
                + t * (0.096_784_18
                    + t * (-0.186_288_06
                        + t * (0.278_868_07
                            + t * (-1.135_203_98 + t * (1.488_515_87 + t * (-0.822_152_23 + t * 0.170_872_77))))))));
    let r = t * (-z * z + poly).exp();
    if x >= 0.0 { r } else { 2.0 - r }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Against reference values of erfc (Abramowitz & Stegun, Table 7.1, and the normal
    /// quantiles): relative error below 1.2e-7; a 1e-6 perturbation would fail.
    #[test]
    fn erfc_matches_reference_values() {
        for (x, expected) in [
            (0.0, 1.0),
            (0.5, 0.479_500_122_186_953_5),
            (1.0, 0.157_299_207_050_285_13),
            (2.0, 0.004_677_734_981_047_266),
            (3.0, 2.209_049_699_858_544e-5),
            (-1.0, 1.842_700_792_949_715),
        ] {
            let relative = (erfc(x) - expected).abs() / expected;
            assert!(relative < 1.2e-7, "erfc({x}) = {} against {expected}", erfc(x));
        }
    }
}
