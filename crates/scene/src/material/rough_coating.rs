//! The rough dielectric coating's transmittance and internal reflectance that Mitsuba's
//! `roughplastic` weighs its diffuse base with, computed once per (distribution, α, η) by
//! quadrature and cached for the process.
//!
//! - External transmittance `T(μ) = ∫ D_w(m) (1 − F(w·m)) G1(t, m) dm` for `w` at `cos θ = μ`:
//!   the light a visible microfacet refracts into the coating (direction `t`) that is not
//!   masked on the way, tabulated at Mitsuba's 64 cosines `μ_i = max(10⁻⁶, i/63)` and
//!   interpolated linearly in between.
//! - Internal reflectance `R_int = 2 mean_i(μ_i R(μ_i))`, with `R(μ) = ∫ D_w(m) F'(w·m) G1(r, m)
//!   dm` the directional albedo of the microfacet reflection seen from inside (relative index
//!   `1/η`, total internal reflection included; `r` the reflected direction): Mitsuba's
//!   estimate of the hemispherical average `2∫ R(μ) μ dμ` on the same 64 cosines.
//!
//! Both inner integrals run over the two uniform numbers of the visible-normal sampler, by a
//! tensor Gauss–Legendre rule (32 nodes per axis outside, 128 inside, where total internal
//! reflection makes the integrand discontinuous; as Mitsuba). The integrals use the
//! distribution's [`Microfacet::g1`] (Mitsuba's masking). α is rounded to 1/64 octave for the
//! cache key (relative error ≤ 0.55 % in α, far below the tables' sensitivity), so that a
//! textured roughness builds a bounded number of tables.

use std::cell::RefCell;
use std::sync::Mutex;

use math::Vec3;

use super::fresnel::fresnel_dielectric;
use crate::microfacet::{Distribution, Microfacet, reflect, refract};

/// Number of tabulated cosines (Mitsuba's `MI_ROUGH_TRANSMITTANCE_RES`).
pub(super) const RESOLUTION: usize = 64;

/// The tabulated transmittance and the internal reflectance of one rough coating.
#[derive(Debug, PartialEq)]
pub(super) struct CoatingTable {
    /// `T(μ_i)` at `μ_i = max(10⁻⁶, i/63)`.
    transmittance: [f32; RESOLUTION],
    /// `R_int`, the hemispherically averaged internal reflectance.
    pub internal_reflectance: f32,
}

impl CoatingTable {
    /// `T(μ)` interpolated linearly between the tabulated cosines (`μ` clamped to [0, 1]).
    #[inline]
    pub(super) fn transmittance(&self, mu: f32) -> f32 {
        let x = mu.clamp(0.0, 1.0) * (RESOLUTION - 1) as f32;
        let i = (x as usize).min(RESOLUTION - 2);
        let t = x - i as f32;
        self.transmittance[i] * (1.0 - t) + self.transmittance[i + 1] * t
    }

    /// Computes the table of the coating with relative index `eta` (inside over outside, > 0)
    /// and the isotropic distribution `dist`.
    pub(super) fn compute(dist: &Microfacet, eta: f32) -> CoatingTable {
        let outside = gauss_legendre(32);
        let inside = gauss_legendre(128);
        let mut transmittance = [0.0; RESOLUTION];
        let mut internal = 0.0f64;
        for (i, t) in transmittance.iter_mut().enumerate() {
            let mu = (i as f32 / (RESOLUTION - 1) as f32).max(1e-6);
            let w = Vec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
            *t = integrate(&outside, |u| {
                let m = dist.sample_visible(w, u);
                let cos = w.dot(m);
                match refract(w, m, eta) {
                    Some(out) if out.z < 0.0 => (1.0 - fresnel_dielectric(cos, eta)) * dist.g1(out, m),
                    _ => 0.0,
                }
            }) as f32;
            let reflectance = integrate(&inside, |u| {
                let m = dist.sample_visible(w, u);
                let out = reflect(w, m);
                if out.z <= 0.0 {
                    return 0.0;
                }
                // Seen from inside, the far side has the relative index 1/η.
                fresnel_dielectric(w.dot(m), 1.0 / eta) * dist.g1(out, m)
            });
            internal += reflectance * mu as f64;
        }
        CoatingTable { transmittance, internal_reflectance: (2.0 * internal / RESOLUTION as f64) as f32 }
    }
}

/// `∫∫ f(u) du` over the unit square by the tensor product of the Gauss–Legendre rule `rule`
/// (nodes and weights on [−1, 1]).
fn integrate(rule: &[(f64, f64)], f: impl Fn([f32; 2]) -> f32) -> f64 {
    let mut sum = 0.0;
    for &(x, wx) in rule {
        for &(y, wy) in rule {
            let u = [(0.5 * x + 0.5) as f32, (0.5 * y + 0.5) as f32];
            sum += wx * wy * f(u) as f64;
        }
    }
    0.25 * sum
}

/// The `n`-point Gauss–Legendre rule on [−1, 1]: the roots of the Legendre polynomial `Pn` by
/// Newton's method from the asymptotic guesses `cos(π(i + 3/4)/(n + 1/2))`, with the weights
/// `2/((1 − x²) Pn'(x)²)`.
fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    (0..n)
        .map(|i| {
            let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
            let mut derivative = 1.0;
            for _ in 0..100 {
                // P_k by the three-term recurrence; P_n' from P_n and P_{n−1}.
                let (mut p0, mut p1) = (1.0, x);
                for k in 2..=n {
                    let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                    p0 = p1;
                    p1 = p2;
                }
                derivative = n as f64 * (x * p1 - p0) / (x * x - 1.0);
                let step = p1 / derivative;
                x -= step;
                if step.abs() < 1e-15 {
                    break;
                }
            }
            (x, 2.0 / ((1.0 - x * x) * derivative * derivative))
        })
        .collect()
}

/// Cache key: distribution, α rounded to 1/64 octave, η bits.
type Key = (Distribution, i32, u32);

/// Tables built so far (never freed: one per distinct key, a few hundred bytes each).
static TABLES: Mutex<Vec<(Key, &'static CoatingTable)>> = Mutex::new(Vec::new());

thread_local! {
    /// This thread's copy of the keys it has looked up, so that a hit needs no lock.
    static LOCAL: RefCell<Vec<(Key, &'static CoatingTable)>> = const { RefCell::new(Vec::new()) };
}

/// The table of the coating with relative index `eta` over the distribution `kind` with
/// roughness `alpha` (rounded to 1/64 octave), computed on first use.
pub(super) fn coating_table(kind: Distribution, alpha: f32, eta: f32) -> &'static CoatingTable {
    let step = (alpha.max(crate::microfacet::MIN_ALPHA).log2() * 64.0).round() as i32;
    let key = (kind, step, eta.to_bits());
    if let Some(table) = LOCAL.with(|l| l.borrow().iter().find(|e| e.0 == key).map(|e| e.1)) {
        return table;
    }
    let table = {
        let mut tables = TABLES.lock().unwrap_or_else(|e| e.into_inner());
        match tables.iter().find(|e| e.0 == key) {
            Some(e) => e.1,
            None => {
                let alpha = (step as f32 / 64.0).exp2();
                let table: &'static CoatingTable =
                    Box::leak(Box::new(CoatingTable::compute(&Microfacet::new(kind, alpha, alpha), eta)));
                tables.push((key, table));
                table
            }
        }
    };
    LOCAL.with(|l| l.borrow_mut().push((key, table)));
    table
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `T(μ)` by quadrature over microfacet normals in solid angle (midpoint rule in θ, φ),
    /// independent of the sampler: `∫ G1(w, m) ⟨w, m⟩ D(m)/μ · (1 − F(w·m)) G1(t, m) dω(m)`.
    fn transmittance_by_quadrature(dist: &Microfacet, eta: f32, mu: f32) -> f64 {
        let w = Vec3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
        let (nt, np) = (1500, 600);
        let mut sum = 0.0;
        for i in 0..nt {
            let theta = (i as f64 + 0.5) / nt as f64 * std::f64::consts::FRAC_PI_2;
            for j in 0..np {
                let phi = (j as f64 + 0.5) / np as f64 * std::f64::consts::TAU;
                let m =
                    Vec3::new((theta.sin() * phi.cos()) as f32, (theta.sin() * phi.sin()) as f32, theta.cos() as f32);
                let cos = w.dot(m);
                if cos <= 0.0 {
                    continue;
                }
                let Some(t) = refract(w, m, eta) else { continue };
                let visible = dist.g1_visible(w, m) * cos * dist.d(m) / mu;
                let value = visible * (1.0 - fresnel_dielectric(cos, eta)) * dist.g1(t, m);
                sum += value as f64 * theta.sin();
            }
        }
        sum * (std::f64::consts::FRAC_PI_2 / nt as f64) * (std::f64::consts::TAU / np as f64)
    }

    #[test]
    fn transmittance_matches_solid_angle_quadrature() {
        for dist in [Microfacet::ggx(0.4, 0.4), Microfacet::beckmann(0.4, 0.4), Microfacet::ggx(1.0, 1.0)] {
            let table = CoatingTable::compute(&dist, 1.5);
            for i in [10, 32, 63] {
                let mu = i as f32 / 63.0;
                let expected = transmittance_by_quadrature(&dist, 1.5, mu);
                let got = table.transmittance(mu) as f64;
                assert!((got - expected).abs() < 2e-3, "{dist:?} μ {mu}: table {got}, quadrature {expected}");
            }
        }
    }

    /// At α → 0 the rough coating becomes the smooth one: `T = 1 − F` and the internal
    /// reflectance is the same 64-cosine estimate of `2∫ F(μ) μ dμ` seen from inside.
    #[test]
    fn smooth_limit_is_the_fresnel_coating() {
        for kind in [Distribution::Ggx, Distribution::Beckmann] {
            let table = CoatingTable::compute(&Microfacet::new(kind, 1e-3, 1e-3), 1.5);
            for i in [0, 20, 50, 63] {
                let mu = (i as f32 / 63.0).max(1e-6);
                let smooth = 1.0 - fresnel_dielectric(mu, 1.5);
                // Near grazing the microfacets' masking still takes a visible part.
                let tolerance = if i == 0 { 1.0 } else { 1e-3 };
                assert!((table.transmittance(mu) - smooth).abs() <= tolerance, "{kind:?} μ {mu}");
            }
            let smooth: f64 = (0..RESOLUTION)
                .map(|i| {
                    let mu = (i as f32 / (RESOLUTION - 1) as f32).max(1e-6);
                    fresnel_dielectric(mu, 1.0 / 1.5) as f64 * mu as f64
                })
                .sum::<f64>()
                * 2.0
                / RESOLUTION as f64;
            let r = table.internal_reflectance as f64;
            assert!((r - smooth).abs() < 2e-3, "{kind:?}: R_int {r} vs smooth {smooth}");
        }
    }

    #[test]
    fn gauss_legendre_integrates_polynomials_exactly() {
        let rule = gauss_legendre(8);
        let weights: f64 = rule.iter().map(|r| r.1).sum();
        assert!((weights - 2.0).abs() < 1e-12);
        // ∫ x¹⁴ over [−1, 1] = 2/15: exact for 8 nodes (degree ≤ 15).
        let x14: f64 = rule.iter().map(|&(x, w)| w * x.powi(14)).sum();
        assert!((x14 - 2.0 / 15.0).abs() < 1e-12, "{x14}");
    }
}
