//! pbrt-v4's coated materials (`coateddiffuse`, `coatedconductor`; the book's section 14.3):
//! a dielectric interface (smooth or GGX) over a medium of depth `thickness` over a Lambertian
//! or conductor base, reflection only (one-sided; the loader wraps it in a two-sided material,
//! which is what pbrt's two-sided layered BSDF does).
//!
//! # Deterministic pdf, stochastic value
//!
//! VCM's MIS weights need the *same* pdf in every technique, forward and reverse, so the pdfs
//! here are closed-form functions of the two directions, never estimates:
//!
//! - a **delta lobe** in the mirror direction when the interface is smooth, chosen with a
//!   probability that depends on the fixed direction only;
//! - a **non-delta mixture** of a GGX reflection lobe with the interface's α (rough
//!   interfaces), a GGX lobe for the light that went through the coating to a conductor and
//!   back (the spread inside, `√(α_c² + ((η − 1) α_t/η)²)`, magnified by the refraction out,
//!   `η μ′/μ` at the fixed direction's cosines, clamped to [0.01, 1]) and
//!   a cosine lobe (the diffuse base, the medium's scattering, and at least a tenth of the
//!   mixture so that every direction with `f > 0` has a positive pdf). Its weights are
//!   Fresnel- and transmittance-weighted estimates of each part's energy at the fixed
//!   direction; the reverse pdf uses the weights at the generated direction.
//!
//! Sampling draws from exactly that mixture and reports its pdf, so the sample weight is
//! `f · cos / pdf` with the same `f` that evaluation returns.
//!
//! The **value** is exact where pbrt-v4's expectation has a closed form, and otherwise pbrt's
//! random walk (`layered_walk`) with its random numbers seeded by the direction pair (a
//! deterministic, unbiased estimate):
//!
//! - smooth interface, diffuse base, no scattering (`albedo` 0):
//!   `f = (1 − F(μo))(1 − F(μi)) Tr(μo′) Tr(μi′) ρ S / (π η²)`, with
//!   `Tr(μ′) = exp(−thickness/μ′)` at the refracted cosines and `S = Σ_{k<K} (ρ r̄)^k`,
//!   `r̄ = ∫ F_inside(μ) Tr(μ)² 2μ dμ` (tabulated per material), `K = ⌈maxdepth/2⌉`: the number of base bounces pbrt's walk
//!   reaches (its expectation is this truncated series; `maxdepth → ∞` gives `1/(1 − ρ r̄)`);
//! - smooth interface over a smooth conductor: every unscattered path leaves in the mirror
//!   direction, a delta lobe of weight `F + (1 − F)² a Σ_{k<K} (F a)^k` per channel with
//!   `a = F_c(μ′) Tr(μ′)²`, `K = ⌊maxdepth/2⌋` (pbrt's sampling walk), the conductor's IOR
//!   divided by the coating's; total internal reflection cannot occur for light that entered
//!   through a smooth interface. With scattering (`albedo > 0`) this is the delta part and
//!   the walk estimates the scattered rest;
//! - a smooth interface's own reflection is the delta lobe `F(μo)`; a rough interface's own
//!   reflection `D G F / (4 μo μi)` is evaluated exactly and the walk adds the rest.
//!
//! The value is computed for `(wo, wi) = (fixed, generated)` in radiance mode and
//! `(generated, fixed)` in importance mode, so the adjoint relation holds exactly. The walk's
//! estimate is reciprocal in expectation only. Russian roulette uses a closed-form albedo (the
//! smooth, non-scattering formulas) that does not depend on the random walk, taken at normal
//! incidence for every direction: the continuation probability enters the MIS pdfs in both
//! directions and must be a function of the vertex alone. In spectral mode the value is
//! computed in RGB and upsampled like a conductor's.

use math::{INV_PI, Vec3};
use spectrum::Rgb;

use super::coated_parameters::{CoatedBase, CoatedParameters, ConductorIor, Moments, SMOOTH_ALPHA};
use super::dispatch::LeafModel;
use super::fresnel::fresnel_dielectric;
use super::layered_interfaces::{Base, Top};
use super::layered_walk::{Layers, pair_rng, transmittance};
use super::lobe::{ModelEval, Sampled, micro_reflect, mirror_local};
use super::query::LobeKind;
use super::shading::TransportMode;
use crate::microfacet::{Microfacet, fresnel_conductor_rgb};
use crate::texture::TexturePoint;

/// A coated material with its textures evaluated at a hit.
#[derive(Clone, Copy, Debug)]
pub(super) struct Coated {
    layers: Layers,
    moments: Moments,
    /// The angular spread (as GGX α) inside the layer of the light that reached a conductor
    /// base (`None`: diffuse base, or everything unscattered is in the delta lobe).
    base_lobe: Option<Microfacet>,
}

/// The sub-lobe weights of the non-delta mixture for one fixed direction.
struct Weights {
    top: f32,
    base: f32,
    cosine: f32,
}

impl Weights {
    fn total(&self) -> f32 {
        self.top + self.base + self.cosine
    }
}

fn ggx(alpha_u: f32, alpha_v: f32) -> Option<Microfacet> {
    (alpha_u.max(alpha_v) >= SMOOTH_ALPHA).then(|| Microfacet::ggx(alpha_u, alpha_v))
}

impl Coated {
    /// The model of `p` with its textures at `uv`.
    pub(super) fn new(p: &CoatedParameters, uv: TexturePoint) -> Self {
        let interface = p.interface();
        let eta = interface.eta;
        let top = Top { eta, dist: ggx(interface.alpha_u, interface.alpha_v) };
        let (base, base_lobe) = match p.base() {
            CoatedBase::Diffuse { reflectance } => {
                (Base::Diffuse(reflectance.eval_at(uv).map(|x| x.clamp(0.0, 1.0))), None)
            }
            CoatedBase::Conductor { ior, alpha_u, alpha_v } => {
                let (ce, ck) = match ior {
                    ConductorIor::Complex { eta, k } => (*eta, *k),
                    ConductorIor::Reflectance(r) => {
                        let r = r.eval_at(uv).map(|x| x.clamp(0.0, 0.9999));
                        (Rgb::WHITE, r.map(|r| 2.0 * r.sqrt() / (1.0 - r).sqrt()))
                    }
                };
                let dist = ggx(*alpha_u, *alpha_v);
                // The spread inside the layer: the conductor's α, and a rough top's α bent by
                // refraction (see `Coated::base_lobe_at` for the way out).
                let inside = |a_c: f32, a_t: f32| {
                    let a_c = if dist.is_some() { a_c } else { 0.0 };
                    let a_t = if top.dist.is_some() { a_t * (eta - 1.0) / eta } else { 0.0 };
                    (a_c * a_c + a_t * a_t).sqrt()
                };
                let lobe = (dist.is_some() || top.dist.is_some())
                    .then(|| Microfacet::ggx(inside(*alpha_u, interface.alpha_u), inside(*alpha_v, interface.alpha_v)));
                (Base::Conductor { eta: ce / eta, k: ck / eta, dist }, lobe)
            }
        };
        let layer = p.layer();
        let layers = Layers {
            top,
            base,
            thickness: layer.thickness,
            albedo: layer.albedo.eval_at(uv).map(|x| x.clamp(0.0, 1.0)),
            g: layer.g,
            max_depth: layer.max_depth,
            samples: layer.samples,
        };
        Coated { layers, moments: p.moments(), base_lobe }
    }

    /// Fresnel reflectance of the interface, the refracted cosine and the one-way
    /// transmittance along it, for the outside cosine `mu`.
    fn crossing(&self, mu: f32) -> (f32, f32, f32) {
        let eta = self.layers.top.eta;
        let fresnel = fresnel_dielectric(mu, eta);
        let refracted = (1.0 - (1.0 - mu * mu) / (eta * eta)).max(0.0).sqrt().max(1e-7);
        let tr = transmittance(self.layers.thickness, Vec3::new(0.0, 0.0, refracted));
        (fresnel, refracted, tr)
    }

    /// Whether everything unscattered leaves in the mirror direction (smooth interface over a
    /// smooth conductor).
    fn all_specular(&self) -> bool {
        self.layers.top.is_specular() && self.layers.base.is_specular()
    }

    fn scattering(&self) -> bool {
        !self.layers.albedo.is_black()
    }

    /// The delta lobe's weight (value × cosine) for the fixed direction `w`; black for a rough
    /// interface.
    fn delta_weight(&self, w: Vec3) -> Rgb {
        if !self.layers.top.is_specular() {
            return Rgb::BLACK;
        }
        let (fresnel, refracted, tr) = self.crossing(w.z);
        let Base::Conductor { eta, k, dist: None } = self.layers.base else { return Rgb::splat(fresnel) };
        let a = fresnel_conductor_rgb(refracted, eta, k) * (tr * tr);
        let bounces = (self.layers.max_depth / 2) as i32;
        Rgb::splat(fresnel) + a.map(|a| geometric_series(fresnel * a, bounces)) * a * (1.0 - fresnel).powi(2)
    }

    /// The closed form of a smooth interface over a diffuse base without scattering.
    fn smooth_diffuse(&self, wo: Vec3, wi: Vec3, rho: Rgb) -> Rgb {
        let (fo, _, to) = self.crossing(wo.z);
        let (fi, _, ti) = self.crossing(wi.z);
        let bounces = self.layers.max_depth.div_ceil(2) as i32;
        let r = self.moments.internal_reflectance;
        let eta = self.layers.top.eta;
        let factor = (1.0 - fo) * (1.0 - fi) * to * ti * INV_PI / (eta * eta);
        rho.map(|p| p * geometric_series(p * r, bounces)) * factor
    }

    /// The non-delta value for `wo` (towards the viewer) and `wi` (towards the light).
    fn value(&self, wo: Vec3, wi: Vec3) -> Rgb {
        let layers = &self.layers;
        if layers.top.is_specular() && !self.scattering() {
            match layers.base {
                Base::Diffuse(rho) => return self.smooth_diffuse(wo, wi, rho),
                Base::Conductor { dist: None, .. } => return Rgb::BLACK,
                Base::Conductor { .. } => {}
            }
        }
        let own = Rgb::splat(layers.top.f(wo, wi, true));
        own + layers.estimate(wo, wi, &mut pair_rng(wo, wi))
    }

    /// The sampling lobe outside of the light that reached a conductor base, for the fixed
    /// direction `w`: the spread inside magnified by refraction, `dθ_out/dθ_in = η μ′/μ`
    /// (μ, μ′ the outside and refracted cosines of `w`), clamped to [0.01, 1].
    fn base_lobe_at(&self, w: Vec3) -> Option<Microfacet> {
        let inside = self.base_lobe?;
        let (_, refracted, _) = self.crossing(w.z);
        let scale = self.layers.top.eta * refracted / w.z.max(1e-3);
        let alpha = |a: f32| (a * scale).clamp(0.01, 1.0);
        Some(Microfacet::ggx(alpha(inside.alpha_x), alpha(inside.alpha_y)))
    }

    /// The largest channel of the base's reflectance seen at the refracted cosine.
    fn base_reflectance(&self, refracted: f32) -> Rgb {
        match self.layers.base {
            Base::Diffuse(rho) => rho,
            Base::Conductor { eta, k, .. } => fresnel_conductor_rgb(refracted, eta, k),
        }
    }

    /// The non-delta mixture's weights at the fixed direction `w`.
    fn weights(&self, w: Vec3) -> Weights {
        let (fresnel, refracted, tr) = self.crossing(w.z);
        let below = 1.0 - fresnel;
        let reflectance = self.base_reflectance(refracted).max_component() * tr * tr;
        let scatter = below * (1.0 - tr * tr) * self.layers.albedo.max_component();
        let top = if self.layers.top.is_specular() { 0.0 } else { fresnel };
        let (base, diffuse) = match (self.layers.base, self.base_lobe) {
            (Base::Diffuse(_), _) => (0.0, below * reflectance),
            (_, Some(_)) => (below * reflectance, 0.0),
            (_, None) => (0.0, 0.0),
        };
        let cosine = diffuse + scatter + 0.1 * (top + base);
        Weights { top, base, cosine: if top + base + cosine > 0.0 { cosine } else { 1.0 } }
    }

    /// Density of the non-delta mixture generating `b` from `a` (both on +z), per steradian.
    fn mixture_pdf(&self, a: Vec3, b: Vec3) -> f32 {
        let w = self.weights(a);
        let m = (a + b).normalize_or_zero();
        let lobe = |dist: Option<&Microfacet>| match dist {
            Some(d) if m.z > 0.0 => d.reflection_pdf(a, m),
            _ => 0.0,
        };
        let sum = w.top * lobe(self.layers.top.dist.as_ref())
            + w.base * lobe(self.base_lobe_at(a).as_ref())
            + w.cosine * b.z * INV_PI;
        sum / w.total()
    }

    /// The closed-form directional albedo per channel for the fixed direction `w` (the smooth,
    /// non-scattering formulas; a rough estimate otherwise), at most 1.
    fn directional_albedo(&self, w: Vec3) -> Rgb {
        let (fresnel, refracted, tr) = self.crossing(w.z);
        let scatter = self.layers.albedo * ((1.0 - fresnel) * (1.0 - tr * tr));
        let eta = self.layers.top.eta;
        let below = match self.layers.base {
            Base::Diffuse(rho) => {
                let r = self.moments.internal_reflectance;
                let bounces = self.layers.max_depth.div_ceil(2) as i32;
                let t = self.moments.mean_transmittance * tr * (1.0 - fresnel) / (eta * eta);
                rho.map(|p| p * t * geometric_series(p * r, bounces))
            }
            Base::Conductor { .. } if self.all_specular() => return (self.delta_weight(w) + scatter).min(Rgb::WHITE),
            Base::Conductor { eta, k, .. } => {
                let a = fresnel_conductor_rgb(refracted, eta, k) * (tr * tr);
                a.map(|a| a * (1.0 - fresnel).powi(2) / (1.0 - fresnel * a))
            }
        };
        (Rgb::splat(fresnel) + below + scatter).min(Rgb::WHITE)
    }
}

/// `Σ_{k<n} x^k`.
fn geometric_series(x: f32, n: i32) -> f32 {
    if (1.0 - x).abs() < 1e-6 { n as f32 } else { (1.0 - x.powi(n)) / (1.0 - x) }
}

impl LeafModel for Coated {
    fn lobe_is_delta(&self, lobe: usize) -> bool {
        lobe == 0
    }

    fn lobe_probabilities(&self, w: Vec3) -> [f32; 2] {
        if !self.layers.top.is_specular() {
            return [0.0, 1.0];
        }
        let delta = self.delta_weight(w).max_component();
        let rest = if self.all_specular() && !self.scattering() { 0.0 } else { self.weights(w).total() };
        if rest <= 0.0 {
            return [1.0, 0.0];
        }
        let p = (delta / (delta + rest)).min(0.9);
        [p, 1.0 - p]
    }

    fn selection_weight(&self) -> f32 {
        self.albedo(Vec3::Z).luminance()
    }

    /// The closed-form albedo at normal incidence, for every fixed direction: Russian
    /// roulette's continuation probability enters the MIS pdfs in both directions, and the
    /// engine takes it at the fixed direction for both, so it must not depend on the direction
    /// (`crates/render/tests/coated_mis.rs` checks the weights against the oracle).
    fn albedo(&self, _: Vec3) -> Rgb {
        self.directional_albedo(Vec3::Z)
    }

    fn evaluate(
        &self,
        fixed: Vec3,
        generated: Vec3,
        mode: TransportMode,
        p_fixed: [f32; 2],
        p_generated: [f32; 2],
    ) -> ModelEval {
        if fixed.z <= 0.0 || generated.z <= 0.0 || (p_fixed[1] <= 0.0 && p_generated[1] <= 0.0) {
            return ModelEval::default();
        }
        let (wo, wi) = match mode {
            TransportMode::Radiance => (fixed, generated),
            TransportMode::Importance => (generated, fixed),
        };
        ModelEval {
            value: self.value(wo, wi),
            forward: p_fixed[1] * self.mixture_pdf(fixed, generated),
            reverse: p_generated[1] * self.mixture_pdf(generated, fixed),
        }
    }

    fn sample(&self, fixed: Vec3, lobe: usize, u: [f32; 3], _: TransportMode) -> Option<Sampled> {
        if lobe == 0 {
            return Some(Sampled::Delta {
                direction: mirror_local(fixed),
                rho: self.delta_weight(fixed),
                lobe: LobeKind::SpecularReflection,
            });
        }
        let w = self.weights(fixed);
        let pick = u[2] * w.total();
        let glossy =
            |dist: &Microfacet| (micro_reflect(fixed, dist.sample_visible(fixed, [u[0], u[1]])), LobeKind::Glossy);
        let (direction, kind) = match (self.layers.top.dist.as_ref(), self.base_lobe_at(fixed).as_ref()) {
            (Some(top), _) if pick < w.top => glossy(top),
            (_, Some(base)) if pick < w.top + w.base => glossy(base),
            _ => (math::warp::cosine_hemisphere([u[0], u[1]]), LobeKind::Diffuse),
        };
        (direction.z > 0.0).then_some(Sampled::Lobe { direction, lobe: kind })
    }
}

#[cfg(test)]
#[path = "coated_tests.rs"]
mod tests;
