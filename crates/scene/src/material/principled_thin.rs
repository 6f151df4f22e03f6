//! Mitsuba 3's `principledthin` BSDF: the thin-surface Disney BSDF (Burley 2015) as Mitsuba 3
//! implements it, the same from both sides. With `st = spec_trans` and `dt = diff_trans/2`:
//! a GGX specular reflection `st · F · D G / (4 cos θ_i cos θ_o)` (F the dielectric Fresnel
//! term for the relative IOR `eta`, blended towards a tinted Schlick term by `spec_tint`), a
//! straight-through rough transmission `st · base_color · (1 − F) · D' G' / (4 cos θ_i
//! |cos θ_o|)` with the half vector of the mirrored direction and roughness scaled by
//! `0.65·eta − 0.35`, the Disney diffuse and sheen weighted by `(1 − st)(1 − dt)`, and a
//! Lambertian transmission `(1 − st)·dt·base_color/π`.
//!
//! Sampling chooses specular reflection, specular transmission (a visible-normal reflection
//! mirrored to the other side), cosine reflection and cosine transmission with probabilities
//! `st/2`, `st/2`, `(1 − st)(1 − dt)`, `(1 − st)·dt`; pdfs are per steradian and sum every lobe.

use math::{INV_PI, Vec3, warp};
use spectrum::Rgb;

use super::disney::{alpha_pair, dielectric, diffuse, flip, reflect, schlick_fresnel, schlick_r0, sheen, tint_colour};
use super::dispatch::LeafModel;
use super::lobe::{ModelEval, Sampled};
use super::principled::scalar;
use super::query::LobeKind;
use super::shading::TransportMode;
use crate::microfacet::Microfacet;
use crate::texture::{Texture, TexturePoint};

/// The parameters of Mitsuba 3's `principledthin` BSDF, each a texture (scalar parameters read
/// the luminance of the texture).
#[derive(Clone, Debug, PartialEq)]
pub struct PrincipledThinParameters {
    /// Base colour (default 0.5).
    pub base_color: Texture,
    /// Disney roughness; GGX `α = roughness²` (default 0.5).
    pub roughness: Texture,
    /// Anisotropy (default 0), as in [`super::PrincipledParameters::anisotropic`].
    pub anisotropic: Texture,
    /// Weight of the specular reflection and transmission (default 0).
    pub spec_trans: Texture,
    /// Tint of the specular reflection towards the base colour (default 0).
    pub spec_tint: Texture,
    /// Sheen weight (default 0).
    pub sheen: Texture,
    /// Tint of the sheen towards the base colour (default 0).
    pub sheen_tint: Texture,
    /// Blend of the diffuse towards the fake subsurface (default 0).
    pub flatness: Texture,
    /// Diffuse transmission in [0, 2] (default 0): the fraction `diff_trans/2` of the diffuse
    /// part is transmitted.
    pub diff_trans: Texture,
    /// Relative IOR of the sheet (default 1.5).
    pub eta: Texture,
}

impl Default for PrincipledThinParameters {
    /// Mitsuba's defaults.
    fn default() -> Self {
        let c = |v: f32| Texture::Constant(Rgb::splat(v));
        PrincipledThinParameters {
            base_color: c(0.5),
            roughness: c(0.5),
            anisotropic: c(0.0),
            spec_trans: c(0.0),
            spec_tint: c(0.0),
            sheen: c(0.0),
            sheen_tint: c(0.0),
            flatness: c(0.0),
            diff_trans: c(0.0),
            eta: c(1.5),
        }
    }
}

impl PrincipledThinParameters {
    /// Every texture of the model.
    pub fn textures(&self) -> [&Texture; 10] {
        [
            &self.base_color,
            &self.roughness,
            &self.anisotropic,
            &self.spec_trans,
            &self.spec_tint,
            &self.sheen,
            &self.sheen_tint,
            &self.flatness,
            &self.diff_trans,
            &self.eta,
        ]
    }
}

/// The `principledthin` model with its textures evaluated.
#[derive(Clone, Copy, Debug)]
pub(super) struct PrincipledThin {
    base_color: Rgb,
    roughness: f32,
    spec_trans: f32,
    spec_tint: f32,
    sheen: f32,
    sheen_tint: f32,
    flatness: f32,
    /// `diff_trans/2`.
    diff_trans: f32,
    eta: f32,
    /// Distribution of the reflection.
    ggx: Microfacet,
    /// Distribution of the transmission (roughness scaled by `0.65·eta − 0.35`).
    ggx_transmission: Microfacet,
}

impl PrincipledThin {
    /// The model at `point`.
    pub(super) fn new(p: &PrincipledThinParameters, point: TexturePoint) -> Self {
        let s = |t: &Texture| scalar(t, point);
        let (roughness, anisotropic, eta) = (s(&p.roughness), s(&p.anisotropic), s(&p.eta));
        let (alpha_u, alpha_v) = alpha_pair(roughness, anisotropic);
        let (scaled_u, scaled_v) = alpha_pair((0.65 * eta - 0.35) * roughness, anisotropic);
        PrincipledThin {
            base_color: p.base_color.eval_at(point),
            roughness,
            spec_trans: s(&p.spec_trans),
            spec_tint: s(&p.spec_tint),
            sheen: s(&p.sheen),
            sheen_tint: s(&p.sheen_tint),
            flatness: s(&p.flatness),
            diff_trans: 0.5 * s(&p.diff_trans),
            eta,
            ggx: Microfacet::ggx(alpha_u, alpha_v),
            ggx_transmission: Microfacet::ggx(scaled_u, scaled_v),
        }
    }

    /// Normalised probabilities of (specular reflection, specular transmission, diffuse
    /// reflection, diffuse transmission).
    fn lobe_weights(&self) -> [f32; 4] {
        let (st, dt) = (self.spec_trans, self.diff_trans);
        let w = [0.5 * st, 0.5 * st, (1.0 - st) * (1.0 - dt), (1.0 - st) * dt].map(|x| x.max(0.0));
        let total: f32 = w.iter().sum();
        if total > 0.0 { w.map(|x| x / total) } else { [0.0; 4] }
    }

    /// The BSDF `f(wi → wo)` (Mitsuba's `eval` divided by `|cos θ_o|`); symmetric.
    fn value(&self, wi: Vec3, wo: Vec3) -> Rgb {
        if wi.z == 0.0 || wo.z == 0.0 {
            return Rgb::BLACK;
        }
        let side = wi.z.signum();
        let (a, b) = (flip(wi, side), flip(wo, side));
        let reflection = b.z > 0.0;
        let h = (a + Vec3::new(b.x, b.y, b.z.abs())).normalize();
        if !h.is_finite() {
            return Rgb::BLACK;
        }
        let (st, dt) = (self.spec_trans, self.diff_trans);
        let mut value = Rgb::BLACK;
        let compatible = a.dot(h) > 0.0 && (b.dot(h) > 0.0) == reflection && b.dot(h) != 0.0;
        if st > 0.0 && compatible {
            let f = dielectric(a.dot(h), self.eta);
            if reflection {
                let tinted = tint_colour(self.base_color) * schlick_r0(self.eta);
                let fresnel = Rgb::splat((1.0 - self.spec_tint) * f)
                    + schlick_fresnel(tinted, a.dot(h), self.eta) * self.spec_tint;
                let dg = self.ggx.d(h) * self.ggx.g(a, b, h);
                value += fresnel * (st * dg / (4.0 * a.z * b.z));
            } else {
                let g = &self.ggx_transmission;
                let dg = g.d(h) * g.g(a, b, h);
                value += self.base_color * (st * (1.0 - f) * dg / (4.0 * a.z * b.z.abs()));
            }
        }
        if reflection && st < 1.0 && dt < 1.0 {
            let weight = (1.0 - st) * (1.0 - dt);
            value += diffuse(self.base_color, self.roughness, self.flatness, a, b, h) * weight;
            if self.sheen > 0.0 {
                value += sheen(self.base_color, self.sheen, self.sheen_tint, b, h) * weight;
            }
        }
        if !reflection && st < 1.0 && dt > 0.0 {
            value += self.base_color * ((1.0 - st) * dt * INV_PI);
        }
        value
    }

    /// Density per steradian of sampling `wo` from `wi`.
    fn density(&self, wi: Vec3, wo: Vec3) -> f32 {
        if wi.z == 0.0 || wo.z == 0.0 {
            return 0.0;
        }
        let side = wi.z.signum();
        let (a, b) = (flip(wi, side), flip(wo, side));
        let reflection = b.z > 0.0;
        let mirrored = Vec3::new(b.x, b.y, b.z.abs());
        let [p_reflect, p_transmit, p_diffuse, p_diffuse_transmit] = self.lobe_weights();
        let mut pdf = warp::cosine_hemisphere_pdf(mirrored.z) * if reflection { p_diffuse } else { p_diffuse_transmit };
        let h = (a + mirrored).normalize();
        if h.is_finite() && a.dot(h) > 0.0 && (b.dot(h) > 0.0) == reflection && b.dot(h) != 0.0 {
            let (p, ggx) = if reflection { (p_reflect, &self.ggx) } else { (p_transmit, &self.ggx_transmission) };
            pdf += p * ggx.visible_pdf(a, h) / (4.0 * mirrored.dot(h));
        }
        pdf
    }
}

impl LeafModel for PrincipledThin {
    fn one_sided(&self) -> bool {
        false
    }

    fn lobe_is_delta(&self, _lobe: usize) -> bool {
        false
    }

    fn selection_weight(&self) -> f32 {
        self.albedo(Vec3::Z).luminance().max(1e-3)
    }

    /// An estimate: the specular weight split by the Fresnel term at the macro normal plus the
    /// diffuse weight times the base colour, clamped to 1.
    fn albedo(&self, w: Vec3) -> Rgb {
        let f = dielectric(w.z.abs(), self.eta);
        let st = self.spec_trans;
        let albedo = Rgb::splat(st * f) + self.base_color * (st * (1.0 - f) + (1.0 - st));
        albedo.map(|c| c.clamp(0.0, 1.0))
    }

    fn evaluate(&self, fixed: Vec3, generated: Vec3, mode: TransportMode, p: [f32; 2], q: [f32; 2]) -> ModelEval {
        let value = match mode {
            TransportMode::Radiance => self.value(fixed, generated),
            TransportMode::Importance => self.value(generated, fixed),
        };
        ModelEval {
            value,
            forward: p[0] * self.density(fixed, generated),
            reverse: q[0] * self.density(generated, fixed),
        }
    }

    fn sample(&self, fixed: Vec3, _lobe: usize, u: [f32; 3], _: TransportMode) -> Option<Sampled> {
        if fixed.z == 0.0 {
            return None;
        }
        let side = fixed.z.signum();
        let a = flip(fixed, side);
        let [p_reflect, p_transmit, p_diffuse, _] = self.lobe_weights();
        let uv = [u[0], u[1]];
        let (b, lobe) = if u[2] < p_reflect + p_transmit {
            let transmit = u[2] >= p_reflect;
            let ggx = if transmit { &self.ggx_transmission } else { &self.ggx };
            let m = ggx.sample_visible(a, uv);
            let r = reflect(a, m);
            if a.dot(m) <= 0.0 || r.z <= 0.0 {
                return None;
            }
            if transmit {
                let b = Vec3::new(r.x, r.y, -r.z);
                if b.dot(m) >= 0.0 {
                    return None;
                }
                (b, LobeKind::GlossyTransmission)
            } else {
                (r, LobeKind::Glossy)
            }
        } else {
            let d = warp::cosine_hemisphere(uv);
            if u[2] < p_reflect + p_transmit + p_diffuse { (d, LobeKind::Diffuse) } else { (-d, LobeKind::Diffuse) }
        };
        Some(Sampled::Lobe { direction: flip(b, side), lobe })
    }
}
