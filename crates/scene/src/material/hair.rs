//! The hair scattering model of Chiang, Bitterli, Tappan and Burley 2016 ("A practical and
//! controllable hair and fur model for production path tracing"), with pbrt-v4's parameters and
//! importance sampling: lobes `p = 0..3` (R, TT, TRT and the residual of longer paths), each the
//! product of a longitudinal function `M_p` (variance `v_p` from `β_m`, the scales tilting lobe
//! `p` by `−2α, α, 4α`), an attenuation `A_p` (Fresnel at the cuticle, Beer–Lambert absorption
//! `σ_a` along the chord) and an azimuthal trimmed logistic `N_p` (scale `s` from `β_n`); the
//! residual lobe is azimuthally uniform.
//!
//! **Frame.** The local z axis is the shading normal and the local y axis the fibre direction:
//! the mixture builds the frame `x = ∂p/∂u` (orthogonalised), `y = n × x`, and the curve meshes
//! (`io::curves`) run `u` around the tube and `v` along it, as Mitsuba's curves, so `y` is
//! along the fibre. The longitudinal angle of a direction is `sin θ = w_y`; its azimuth in the
//! normal plane is `φ = atan2(w_x, w_z)`, measured from the normal.
//!
//! **The offset h.** A tessellated tube has no ray-width parameter, so `h ∈ [−1, 1]` is derived
//! from the shading normal and the *camera-side* direction `wo` (radiance flows towards it):
//! `h = sin γ_o = w_x / √(w_x² + w_z²)`, the signed lateral offset of the hit point across the
//! fibre as seen along `wo` (for a `wo` behind the normal, the offset of the front point with the
//! same lateral position). In radiance mode `wo` is the fixed direction, as pbrt (which takes
//! `h` from the hit's `v`) and Mitsuba (which takes it from the incident direction) do. In
//! importance mode `wo` is the *generated* direction, so both transport modes evaluate the same
//! function of the pair: `value_radiance(a, b) = value_importance(b, a)`, and a bidirectional
//! path gets one value whichever sub-path built it.
//!
//! **Value.** The far-field scattering function `S = Σ_p M_p A_p N_p` satisfies
//! `∫ S(wo, wi) dω_i = Σ_p A_p ≤ 1`. As in pbrt, the BSDF is `f(wo, wi) = S(wo, wi)/|cos θ_wi|`
//! with the shading-frame cosine of the light-side direction, so that the integrators'
//! `f · |cos|` is `S` for a flat tube (shading = geometric normal) and `S · |wi·Ns|/|wi·Ng|`
//! otherwise — the mixture's usual shading-normal correction. `S` is not symmetric (the tilt
//! acts on `θ_o`; `A_p` and `γ_o` depend on `wo` only), so the BSDF is not reciprocal; the
//! adjoint in importance mode is exact by construction (see above).
//!
//! **Sampling and pdfs.** The sampler treats the fixed direction as `wo` whatever the mode:
//! it picks lobe `p` with probability `Ā_p / Σ Ā` (channel averages of `A_p` for the fixed
//! direction's `h` and `θ`), samples `sin θ_i` from `M_p` exactly (the von Mises–Fisher
//! construction) and `φ_i − φ_o` from `N_p` (uniform for the residual). The forward pdf is that
//! sampler's solid-angle density `Σ_p (Ā_p/ΣĀ) M_p N_p` with `h` from the fixed direction, the
//! reverse pdf the same with the roles swapped; both are the same functions in either mode.

use math::{PI, Vec3, sqr};
use spectrum::Rgb;

use super::description::Material;
use super::dispatch::LeafModel;
use super::fresnel::fresnel_dielectric;
use super::hair_functions::{
    P_MAX, azimuthal, azimuthal_scale, longitudinal, longitudinal_variances, perfect_azimuth, sample_trimmed_logistic,
};
use super::lobe::{ModelEval, Sampled};
use super::query::LobeKind;
use super::shading::TransportMode;

/// pbrt's absorption coefficient of eumelanin per unit concentration (RGB, per fibre radius).
pub const EUMELANIN_SIGMA_A: Rgb = Rgb::new(0.419, 0.697, 1.37);
/// pbrt's absorption coefficient of pheomelanin per unit concentration (RGB, per fibre radius).
pub const PHEOMELANIN_SIGMA_A: Rgb = Rgb::new(0.187, 0.4, 1.05);

/// The parameters of pbrt-v4's `hair` material (Mitsuba 3's `hair` maps onto them).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HairParameters {
    /// Absorption coefficient inside the fibre, per unit of fibre *radius* (the chord at offset
    /// `h` is `2√(1 − h'²)` radii in the normal plane), per channel, ≥ 0.
    pub sigma_a: Rgb,
    /// Index of refraction of the fibre relative to the outside (pbrt default 1.55).
    pub eta: f32,
    /// Longitudinal roughness `β_m ∈ [0, 1]` (default 0.3).
    pub beta_m: f32,
    /// Azimuthal roughness `β_n ∈ [0, 1]` (default 0.3).
    pub beta_n: f32,
    /// Tilt of the cuticle scales, degrees (default 2).
    pub alpha: f32,
}

impl Default for HairParameters {
    /// pbrt-v4's defaults: eumelanin 1.3, η 1.55, β_m = β_n = 0.3, α = 2°.
    fn default() -> Self {
        Self { sigma_a: Self::sigma_a_from_melanin(1.3, 0.0), eta: 1.55, beta_m: 0.3, beta_n: 0.3, alpha: 2.0 }
    }
}

impl HairParameters {
    /// `σ_a` of the pigment concentrations (pbrt: `eumelanin · σ_eu + pheomelanin · σ_pheo`).
    pub fn sigma_a_from_melanin(eumelanin: f32, pheomelanin: f32) -> Rgb {
        EUMELANIN_SIGMA_A * eumelanin.max(0.0) + PHEOMELANIN_SIGMA_A * pheomelanin.max(0.0)
    }

    /// `σ_a` giving roughly the multiple-scattering reflectance `color` (Chiang et al. 2016,
    /// eq. 9): `σ_a = (ln c / (5.969 − 0.215β_n + 2.532β_n² − 10.73β_n³ + 5.574β_n⁴ + 0.245β_n⁵))²`
    /// per channel (`c` clamped to [10⁻⁴, 1]).
    pub fn sigma_a_from_color(color: Rgb, beta_n: f32) -> Rgb {
        let b = beta_n;
        let d = 5.969 - 0.215 * b + 2.532 * b * b - 10.73 * b.powi(3) + 5.574 * b.powi(4) + 0.245 * b.powi(5);
        color.map(|c| sqr(c.clamp(1e-4, 1.0).ln() / d))
    }

    /// Checks the ranges: `β_m, β_n ∈ [0, 1]`, `η > 0` and finite, `σ_a ≥ 0` and finite, `α`
    /// finite.
    pub fn validate(&self) -> Result<(), String> {
        if !(0.0..=1.0).contains(&self.beta_m) || !(0.0..=1.0).contains(&self.beta_n) {
            return Err(format!("hair beta_m and beta_n must lie in [0, 1] (got {}, {})", self.beta_m, self.beta_n));
        }
        if !(self.eta > 0.0 && self.eta.is_finite()) {
            return Err(format!("hair eta must be positive (got {})", self.eta));
        }
        if !self.sigma_a.is_finite() || self.sigma_a.to_array().iter().any(|&s| s < 0.0) {
            return Err(format!("hair sigma_a must be non-negative (got {:?})", self.sigma_a));
        }
        if !self.alpha.is_finite() {
            return Err("hair alpha must be a finite angle in degrees".into());
        }
        Ok(())
    }
}

impl Material {
    /// True for a hair fibre: the curve's tube is seen from outside only. Like Mitsuba's hair
    /// (a null component on the back side), hits on the inside of the tube are skipped by both
    /// ray queries, so the path that the TT and TRT lobes send into the fibre continues through
    /// it: a lobe stands for the whole walk inside, entering and leaving at the hit point.
    pub fn is_fibre(&self) -> bool {
        matches!(self, Material::Hair(_))
    }
}

/// The hair model at a hit (see the module documentation).
#[derive(Clone, Copy, Debug)]
pub(super) struct Hair {
    sigma_a: Rgb,
    eta: f32,
    /// Longitudinal variances of the lobes.
    v: [f32; P_MAX + 1],
    /// Logistic scale.
    s: f32,
    /// `sin(2^k α)` and `cos(2^k α)` for k = 0, 1, 2.
    sin_2k_alpha: [f32; 3],
    cos_2k_alpha: [f32; 3],
}

/// What depends on the camera-side direction only.
struct Outgoing {
    sin_theta: f32,
    cos_theta: f32,
    phi: f32,
    gamma_o: f32,
    gamma_t: f32,
    /// `A_0..A_3`.
    attenuation: [Rgb; P_MAX + 1],
}

/// `sin θ`, `cos θ` and `φ` of a local direction (y along the fibre, z the normal).
fn angles(w: Vec3) -> (f32, f32, f32) {
    let sin_theta = w.y.clamp(-1.0, 1.0);
    (sin_theta, (1.0 - sin_theta * sin_theta).max(0.0).sqrt(), w.x.atan2(w.z))
}

impl Hair {
    pub(super) fn new(p: &HairParameters) -> Self {
        let mut sin_2k_alpha = [p.alpha.to_radians().sin(); 3];
        let mut cos_2k_alpha = [(1.0 - sqr(sin_2k_alpha[0])).max(0.0).sqrt(); 3];
        for k in 1..3 {
            sin_2k_alpha[k] = 2.0 * cos_2k_alpha[k - 1] * sin_2k_alpha[k - 1];
            cos_2k_alpha[k] = sqr(cos_2k_alpha[k - 1]) - sqr(sin_2k_alpha[k - 1]);
        }
        Self {
            sigma_a: p.sigma_a,
            eta: p.eta,
            v: longitudinal_variances(p.beta_m),
            s: azimuthal_scale(p.beta_n),
            sin_2k_alpha,
            cos_2k_alpha,
        }
    }

    /// The camera-side quantities of `wo`; `None` along the fibre (no normal plane).
    fn outgoing(&self, wo: Vec3) -> Option<Outgoing> {
        let (sin_theta, cos_theta, phi) = angles(wo);
        let across = wo.x.hypot(wo.z);
        if cos_theta < 1e-6 || across <= 0.0 {
            return None;
        }
        let h = (wo.x / across).clamp(-1.0, 1.0);
        let sin_theta_t = sin_theta / self.eta;
        let cos_theta_t = (1.0 - sqr(sin_theta_t)).max(1e-12).sqrt();
        // The modified index of refraction in the normal plane (Bravais).
        let eta_p = (sqr(self.eta) - sqr(sin_theta)).max(0.0).sqrt() / cos_theta;
        let sin_gamma_t = (h / eta_p).clamp(-1.0, 1.0);
        let cos_gamma_t = (1.0 - sqr(sin_gamma_t)).max(0.0).sqrt();
        let transmittance = (self.sigma_a * (-2.0 * cos_gamma_t / cos_theta_t)).map(f32::exp);
        // Fresnel for the angle between wo and the normal at offset h.
        let fresnel = fresnel_dielectric(cos_theta * (1.0 - h * h).max(0.0).sqrt(), self.eta);
        let a0 = Rgb::splat(fresnel);
        let a1 = transmittance * sqr(1.0 - fresnel);
        let a2 = a1 * transmittance * fresnel;
        let rest = (Rgb::WHITE - transmittance * fresnel).map(|d| if d > 0.0 { 1.0 / d } else { 0.0 });
        let a3 = a2 * transmittance * rest * fresnel;
        Some(Outgoing {
            sin_theta,
            cos_theta,
            phi,
            gamma_o: h.asin(),
            gamma_t: sin_gamma_t.asin(),
            attenuation: [a0, a1, a2, a3],
        })
    }

    /// `(sin θ_o, |cos θ_o|)` rotated by lobe `p`'s scale tilt (−2α for R, α for TT, 4α for
    /// TRT; none for the residual).
    fn tilted(&self, p: usize, o: &Outgoing) -> (f32, f32) {
        let (s, c) = (o.sin_theta, o.cos_theta);
        let (sa, ca) = (self.sin_2k_alpha, self.cos_2k_alpha);
        let (sin, cos) = match p {
            0 => (s * ca[1] - c * sa[1], c * ca[1] + s * sa[1]),
            1 => (s * ca[0] + c * sa[0], c * ca[0] - s * sa[0]),
            2 => (s * ca[2] + c * sa[2], c * ca[2] - s * sa[2]),
            _ => (s, c),
        };
        (sin, cos.abs())
    }

    /// The density of lobe `p` (without its weight) at `wi` for the outgoing `o`, per sr.
    fn lobe(&self, p: usize, o: &Outgoing, wi: Vec3) -> f32 {
        let (sin_i, cos_i, phi_i) = angles(wi);
        let (sin_o, cos_o) = self.tilted(p, o);
        let m = longitudinal(cos_i, cos_o, sin_i, sin_o, self.v[p]);
        if p < P_MAX { m * azimuthal(phi_i - o.phi, p, self.s, o.gamma_o, o.gamma_t) } else { m / (2.0 * PI) }
    }

    /// The far-field scattering function `S(wo, wi) = Σ_p A_p M_p N_p` (per sr, no cosine).
    pub(super) fn scattering(&self, wo: Vec3, wi: Vec3) -> Rgb {
        let Some(o) = self.outgoing(wo) else { return Rgb::BLACK };
        (0..=P_MAX).fold(Rgb::BLACK, |sum, p| sum + o.attenuation[p] * self.lobe(p, &o, wi))
    }

    /// Lobe selection probabilities `Ā_p / Σ Ā` for `o`; `None` when everything is absorbed.
    fn lobe_weights(o: &Outgoing) -> Option<[f32; P_MAX + 1]> {
        let a = o.attenuation.map(Rgb::average);
        let total: f32 = a.iter().sum();
        (total > 0.0 && total.is_finite()).then(|| a.map(|x| x / total))
    }

    /// The sampler's solid-angle density of `wi` with `wo` in the camera role (per sr).
    pub(super) fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let Some(o) = self.outgoing(wo) else { return 0.0 };
        let Some(w) = Self::lobe_weights(&o) else { return 0.0 };
        (0..=P_MAX).map(|p| w[p] * self.lobe(p, &o, wi)).sum()
    }

    /// Samples `wi` for `wo` with `u[2]` (lobe), `u[0]` (longitudinal) and `u[1]` (the
    /// longitudinal lobe's azimuth around its axis); the lobe's azimuth reuses the rescaled
    /// `u[2]`.
    pub(super) fn sample_direction(&self, wo: Vec3, u: [f32; 3]) -> Option<Vec3> {
        let o = self.outgoing(wo)?;
        let w = Self::lobe_weights(&o)?;
        let mut uc = u[2];
        let mut p = 0;
        while p < P_MAX && (uc >= w[p] || w[p] <= 0.0) {
            uc -= w[p];
            p += 1;
        }
        if w[p] <= 0.0 {
            return None;
        }
        let uc = (uc / w[p]).clamp(0.0, 1.0 - f32::EPSILON);
        let (sin_o, cos_o) = self.tilted(p, &o);
        let v = self.v[p];
        let u0 = u[0].max(1e-5);
        let cos_theta = (1.0 + v * (u0 + (1.0 - u0) * (-2.0 / v).exp()).ln()).clamp(-1.0, 1.0);
        let sin_theta = (1.0 - sqr(cos_theta)).max(0.0).sqrt();
        let cos_phi = (2.0 * PI * u[1]).cos();
        let sin_i = (-cos_theta * sin_o + sin_theta * cos_phi * cos_o).clamp(-1.0, 1.0);
        let cos_i = (1.0 - sqr(sin_i)).max(0.0).sqrt();
        let dphi = if p < P_MAX {
            perfect_azimuth(p, o.gamma_o, o.gamma_t) + sample_trimmed_logistic(uc, self.s)
        } else {
            2.0 * PI * uc
        };
        let (sin_phi, cos_phi) = (o.phi + dphi).sin_cos();
        Some(Vec3::new(cos_i * sin_phi, sin_i, cos_i * cos_phi))
    }

    /// `Σ_p A_p` for `w` as the camera-side direction (the fraction not absorbed).
    pub(super) fn total_attenuation(&self, w: Vec3) -> Rgb {
        self.outgoing(w).map_or(Rgb::BLACK, |o| o.attenuation.iter().fold(Rgb::BLACK, |s, &a| s + a))
    }
}

impl LeafModel for Hair {
    fn one_sided(&self) -> bool {
        false
    }

    fn lobe_is_delta(&self, _lobe: usize) -> bool {
        false
    }

    /// The albedo seen head-on (`h = 0`, `θ = 0`).
    fn selection_weight(&self) -> f32 {
        self.total_attenuation(Vec3::Z).luminance()
    }

    /// `Σ_p A_p` seen head-on (`h = 0`, `θ = 0`), the same for every direction: the engine's
    /// MIS weights need a continuation probability that does not depend on the direction (see
    /// `docs/materials.md`, coated materials). The directional albedo `∫ S dω_i` for `wo` is
    /// `total_attenuation(wo)`.
    fn albedo(&self, _w: Vec3) -> Rgb {
        self.total_attenuation(Vec3::Z)
    }

    fn evaluate(
        &self,
        fixed: Vec3,
        generated: Vec3,
        mode: TransportMode,
        p_fixed: [f32; 2],
        p_generated: [f32; 2],
    ) -> ModelEval {
        let (wo, wi) = match mode {
            TransportMode::Radiance => (fixed, generated),
            TransportMode::Importance => (generated, fixed),
        };
        if wi.z == 0.0 || wi.z.is_nan() {
            return ModelEval::default();
        }
        ModelEval {
            value: self.scattering(wo, wi) * (1.0 / wi.z.abs()),
            forward: p_fixed[0] * self.pdf(fixed, generated),
            reverse: p_generated[0] * self.pdf(generated, fixed),
        }
    }

    fn sample(&self, fixed: Vec3, _lobe: usize, u: [f32; 3], _: TransportMode) -> Option<Sampled> {
        let direction = self.sample_direction(fixed, u)?;
        let lobe = if direction.z * fixed.z >= 0.0 { LobeKind::Glossy } else { LobeKind::GlossyTransmission };
        Some(Sampled::Lobe { direction, lobe })
    }
}

#[cfg(test)]
#[path = "hair_tests.rs"]
mod tests;
