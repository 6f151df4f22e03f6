//! Lambertian reflection and Lambertian transmission (pbrt-v4's `diffusetransmission`), two-sided:
//! `f = R/π` for two directions on the same side of the surface, `T/π` for directions on
//! opposite sides. The sampler picks reflection with probability `p_R = max(R)/(max(R) + max(T))`
//! (pbrt-v4's choice) and transmission with `p_T = 1 − p_R`, then a cosine-weighted direction on
//! that side: the pdf is `p_R |cos θ|/π` or `p_T |cos θ|/π` per steradian, the same function of
//! the pair in both directions (the model is symmetric, so radiance and importance agree).

use math::{INV_PI, Vec3};
use spectrum::Rgb;

use super::diffuse::sample_cosine;
use super::dispatch::LeafModel;
use super::lobe::{ModelEval, Sampled};
use super::shading::TransportMode;

/// Diffuse reflection `R/π` plus diffuse transmission `T/π`.
#[derive(Clone, Copy, Debug)]
pub(super) struct DiffuseTransmission {
    /// Reflectance R at the hit.
    pub reflectance: Rgb,
    /// Transmittance T at the hit.
    pub transmittance: Rgb,
}

impl DiffuseTransmission {
    /// Probability of sampling the reflection lobe.
    fn reflection_probability(&self) -> f32 {
        let (r, t) = (self.reflectance.max_component().max(0.0), self.transmittance.max_component().max(0.0));
        if r + t > 0.0 { r / (r + t) } else { 0.5 }
    }
}

impl LeafModel for DiffuseTransmission {
    fn one_sided(&self) -> bool {
        false
    }

    fn lobe_is_delta(&self, _lobe: usize) -> bool {
        false
    }

    fn lobe_probabilities(&self, _w: Vec3) -> [f32; 2] {
        let p = self.reflection_probability();
        [p, 1.0 - p]
    }

    fn selection_weight(&self) -> f32 {
        self.reflectance.luminance().max(self.transmittance.luminance())
    }

    fn albedo(&self, _w: Vec3) -> Rgb {
        self.reflectance + self.transmittance
    }

    fn evaluate(
        &self,
        fixed: Vec3,
        generated: Vec3,
        _: TransportMode,
        p_fixed: [f32; 2],
        p_generated: [f32; 2],
    ) -> ModelEval {
        let product = fixed.z * generated.z;
        if product == 0.0 || product.is_nan() {
            return ModelEval::default();
        }
        let (value, lobe) = if product > 0.0 { (self.reflectance, 0) } else { (self.transmittance, 1) };
        ModelEval {
            value: value * INV_PI,
            forward: p_fixed[lobe] * generated.z.abs() * INV_PI,
            reverse: p_generated[lobe] * fixed.z.abs() * INV_PI,
        }
    }

    fn sample(&self, fixed: Vec3, lobe: usize, u: [f32; 3], _: TransportMode) -> Option<Sampled> {
        let Sampled::Lobe { direction, lobe: kind } = sample_cosine(u) else { return None };
        // The cosine sample lies above the surface; reflection stays on the fixed side,
        // transmission goes to the other.
        let above = (fixed.z > 0.0) == (lobe == 0);
        let direction = if above { direction } else { Vec3::new(direction.x, direction.y, -direction.z) };
        Some(Sampled::Lobe { direction, lobe: kind })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn model() -> DiffuseTransmission {
        DiffuseTransmission { reflectance: Rgb::new(0.6, 0.3, 0.1), transmittance: Rgb::new(0.2, 0.4, 0.3) }
    }

    /// The pdf integrates to 1 over the sphere, from either side, and the sampler's histogram
    /// over (side, cos θ) bins matches it (χ² against the integrated pdf).
    #[test]
    fn sampler_matches_its_pdf() {
        let m = model();
        let p = m.lobe_probabilities(Vec3::Z);
        assert!((p[0] - 0.6).abs() < 1e-6, "max components 0.6 and 0.4");
        for fixed in [Vec3::new(0.3, 0.1, 0.9).normalize(), Vec3::new(-0.2, 0.4, -0.7).normalize()] {
            const BINS: usize = 20; // 10 cos bins per side
            let n = 200_000;
            let mut counts = [0.0f64; BINS];
            let mut rng = math::Rng::for_stream(3, 0, 0);
            for _ in 0..n {
                let u = [rng.uniform(), rng.uniform(), rng.uniform()];
                let lobe = usize::from(u[2] >= p[0]);
                let Some(Sampled::Lobe { direction, .. }) = m.sample(fixed, lobe, u, TransportMode::Radiance) else {
                    panic!("no sample")
                };
                let e = m.evaluate(fixed, direction, TransportMode::Radiance, p, p);
                assert!(e.forward > 0.0);
                let side = usize::from(direction.z < 0.0);
                let bin = ((direction.z.abs() * 10.0) as usize).min(9);
                counts[side * 10 + bin] += 1.0;
            }
            // Expected: P(side) · (c1² − c0²) for cos bins [c0, c1) (∫ cos/π dω over a band).
            let same = if fixed.z > 0.0 { 0 } else { 1 };
            let mut chi2 = 0.0;
            for (b, count) in counts.iter().enumerate() {
                let side_p = if b / 10 == same { p[0] } else { p[1] };
                let (c0, c1) = ((b % 10) as f64 / 10.0, (b % 10 + 1) as f64 / 10.0);
                let expected = n as f64 * side_p as f64 * (c1 * c1 - c0 * c0);
                chi2 += (count - expected).powi(2) / expected;
            }
            // 19 degrees of freedom: the 0.999 quantile is 43.8.
            assert!(chi2 < 43.8, "chi2 {chi2}");
        }
    }

    /// Values and pdfs: reflection on the same side, transmission across; reciprocal; the
    /// reverse pdf is the forward pdf of the swapped pair.
    #[test]
    fn values_and_pdfs_are_reciprocal() {
        let m = model();
        let p = m.lobe_probabilities(Vec3::Z);
        let a = Vec3::new(0.3, 0.1, 0.9).normalize();
        let b = Vec3::new(-0.5, 0.2, 0.6).normalize();
        let c = Vec3::new(0.1, -0.4, -0.8).normalize();
        let r = m.evaluate(a, b, TransportMode::Radiance, p, p);
        assert_eq!(r.value, m.reflectance * INV_PI);
        let t = m.evaluate(a, c, TransportMode::Radiance, p, p);
        assert_eq!(t.value, m.transmittance * INV_PI);
        let back = m.evaluate(c, a, TransportMode::Importance, p, p);
        assert_eq!((back.value, back.forward, back.reverse), (t.value, t.reverse, t.forward));
        assert!((t.forward - p[1] * c.z.abs() * INV_PI).abs() < 1e-7);
        // A white furnace: albedo R + T, at most 1 per channel here.
        let albedo = m.albedo(a);
        assert!((albedo - Rgb::new(0.8, 0.7, 0.4)).to_array().iter().all(|d| d.abs() < 1e-6), "{albedo:?}");
    }
}
