//! STUB (replaced by the spectral-data branch).
/// Index of refraction as a function of wavelength.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Ior {
    /// Constant.
    Constant(f32),
    /// Cauchy.
    Cauchy {
        /// A.
        a: f32,
        /// B in µm².
        b_um2: f32,
    },
    /// Sellmeier.
    Sellmeier {
        /// B.
        b: [f32; 3],
        /// C in µm².
        c_um2: [f32; 3],
    },
}
impl Ior {
    /// Value at a wavelength in nm.
    pub fn eval(&self, lambda_nm: f32) -> f32 {
        let l2 = (lambda_nm * 1e-3).powi(2);
        match *self {
            Ior::Constant(n) => n,
            Ior::Cauchy { a, b_um2 } => a + b_um2 / l2,
            Ior::Sellmeier { b, c_um2 } => (1.0 + (0..3).map(|i| b[i] * l2 / (l2 - c_um2[i])).sum::<f32>()).sqrt(),
        }
    }
}
impl Ior {
    /// Names.
    pub const NAMES: &'static [&'static str] = &["bk7"];
    /// Named.
    pub fn named(name: &str) -> Option<Ior> {
        (name == "bk7").then_some(Ior::Sellmeier {
            b: [1.039_612_1, 0.231_792_34, 1.010_469_5],
            c_um2: [0.006_000_699, 0.020_017_914, 103.560_65],
        })
    }
}
