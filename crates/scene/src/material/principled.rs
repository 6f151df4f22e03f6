//! Mitsuba 3's `principled` BSDF (the Disney BSDF of Burley 2012/2015 as Mitsuba 3 implements
//! it): a Disney diffuse with retro-reflection, fake subsurface and sheen (weighted by
//! `(1 − metallic)(1 − spec_trans)`, front side only), one anisotropic GGX interface with
//! relative IOR `eta` for the main specular reflection (a blend of the dielectric Fresnel
//! term, Schlick's metallic term tinted by the base colour and a Schlick spec-tint term) and
//! the rough transmission (weighted by `(1 − metallic)·spec_trans`, tinted by
//! `√base_color`), and a GTR1 clearcoat (see `clearcoat`). Seen from behind only the
//! dielectric reflection and transmission remain, weighted by `(1 − metallic)·spec_trans`.
//!
//! Sampling (Mitsuba's scheme, with an exact density): from the front, diffuse (cosine),
//! clearcoat and the main specular lobe are chosen with probabilities proportional to
//! `(1 − metallic)(1 − spec_trans)`, `clearcoat/4` and 1; the specular lobe samples a visible
//! GGX normal `m` and reflects with probability `1 − bsdf·(1 − F(m))` (`bsdf` the transmission
//! weight), else refracts. From behind: reflection with probability `F(m)`, else refraction.
//! The returned pdfs are per steradian and sum every lobe that can generate the direction.

use math::{Vec3, sqr, warp};
use spectrum::Rgb;

use super::clearcoat::Clearcoat;
use super::disney::{alpha_pair, dielectric, diffuse, flip, reflect, schlick_fresnel, schlick_r0, sheen, tint_colour};
use super::dispatch::LeafModel;
use super::lobe::{ModelEval, Sampled};
use super::query::LobeKind;
use super::shading::TransportMode;
use crate::microfacet::{Microfacet, refract};
use crate::texture::{Texture, TexturePoint};

/// The parameters of Mitsuba 3's `principled` BSDF, each a texture (scalar parameters read the
/// luminance of the texture). All are dimensionless weights in [0, 1] except `eta`.
#[derive(Clone, Debug, PartialEq)]
pub struct PrincipledParameters {
    /// Base colour (default 0.5).
    pub base_color: Texture,
    /// Disney roughness; GGX `α = roughness²` (default 0.5).
    pub roughness: Texture,
    /// Anisotropy (default 0): `α_u = α/√(1 − 0.9·anisotropic)` along the tangent,
    /// `α_v = α·√(1 − 0.9·anisotropic)` along the bitangent.
    pub anisotropic: Texture,
    /// Metallic weight (default 0).
    pub metallic: Texture,
    /// Weight of the rough transmission (default 0).
    pub spec_trans: Texture,
    /// Tint of the dielectric specular reflection towards the base colour (default 0).
    pub spec_tint: Texture,
    /// Sheen weight (default 0).
    pub sheen: Texture,
    /// Tint of the sheen towards the base colour (default 0).
    pub sheen_tint: Texture,
    /// Blend of the diffuse towards the fake subsurface (default 0).
    pub flatness: Texture,
    /// Clearcoat weight (default 0).
    pub clearcoat: Texture,
    /// Clearcoat glossiness: GTR1 `α = lerp(0.1, 0.001, clearcoat_gloss)` (default 0).
    pub clearcoat_gloss: Texture,
    /// Relative IOR of the interface, inside over outside (Mitsuba: `eta`, or
    /// `2/(1 − √(0.08·specular)) − 1` from `specular`, default 0.5 → 1.5).
    pub eta: f32,
}

impl Default for PrincipledParameters {
    /// Mitsuba's defaults.
    fn default() -> Self {
        let c = |v: f32| Texture::Constant(Rgb::splat(v));
        PrincipledParameters {
            base_color: c(0.5),
            roughness: c(0.5),
            anisotropic: c(0.0),
            metallic: c(0.0),
            spec_trans: c(0.0),
            spec_tint: c(0.0),
            sheen: c(0.0),
            sheen_tint: c(0.0),
            flatness: c(0.0),
            clearcoat: c(0.0),
            clearcoat_gloss: c(0.0),
            eta: 1.5,
        }
    }
}

impl PrincipledParameters {
    /// Every texture of the model.
    pub fn textures(&self) -> [&Texture; 11] {
        [
            &self.base_color,
            &self.roughness,
            &self.anisotropic,
            &self.metallic,
            &self.spec_trans,
            &self.spec_tint,
            &self.sheen,
            &self.sheen_tint,
            &self.flatness,
            &self.clearcoat,
            &self.clearcoat_gloss,
        ]
    }
}

/// The luminance of a scalar parameter's texture at a point.
#[inline]
pub(super) fn scalar(texture: &Texture, point: TexturePoint) -> f32 {
    texture.eval_at(point).luminance()
}

/// The `principled` model with its textures evaluated.
#[derive(Clone, Copy, Debug)]
pub(super) struct Principled {
    base_color: Rgb,
    roughness: f32,
    metallic: f32,
    spec_tint: f32,
    sheen: f32,
    sheen_tint: f32,
    flatness: f32,
    /// Weight of the diffuse part, `(1 − metallic)(1 − spec_trans)`.
    brdf: f32,
    /// Weight of the transmission, `(1 − metallic)·spec_trans`.
    bsdf: f32,
    clearcoat: Clearcoat,
    eta: f32,
    ggx: Microfacet,
}

impl Principled {
    /// The model at `point`.
    pub(super) fn new(p: &PrincipledParameters, point: TexturePoint) -> Self {
        let s = |t: &Texture| scalar(t, point);
        let (metallic, spec_trans) = (s(&p.metallic), s(&p.spec_trans));
        let roughness = s(&p.roughness);
        let (alpha_u, alpha_v) = alpha_pair(roughness, s(&p.anisotropic));
        Principled {
            base_color: p.base_color.eval_at(point),
            roughness,
            metallic,
            spec_tint: s(&p.spec_tint),
            sheen: s(&p.sheen),
            sheen_tint: s(&p.sheen_tint),
            flatness: s(&p.flatness),
            brdf: (1.0 - metallic) * (1.0 - spec_trans),
            bsdf: (1.0 - metallic) * spec_trans,
            clearcoat: Clearcoat::new(s(&p.clearcoat), s(&p.clearcoat_gloss)),
            eta: p.eta,
            ggx: Microfacet::ggx(alpha_u, alpha_v),
        }
    }

    /// Normalised selection probabilities of (diffuse, clearcoat, main specular) for a fixed
    /// direction on the front (`front`) or the back.
    fn lobe_weights(&self, front: bool) -> [f32; 3] {
        if !front {
            return [0.0, 0.0, 1.0];
        }
        let (d, c) = (self.brdf.max(0.0), (0.25 * self.clearcoat.weight).max(0.0));
        let total = d + c + 1.0;
        [d / total, c / total, 1.0 / total]
    }

    /// Probability that the main specular lobe reflects at a microfacet with dielectric
    /// Fresnel reflectance `f` (else it refracts).
    fn reflect_probability(&self, front: bool, f: f32) -> f32 {
        if front { 1.0 - self.bsdf * (1.0 - f) } else { f }
    }

    /// Mitsuba's front-side Fresnel term of the main specular reflection for the dielectric
    /// reflectance `f` at a microfacet seen at cosine `cos` from outside.
    fn fresnel(&self, f: f32, cos: f32) -> Rgb {
        let tinted = tint_colour(self.base_color) * schlick_r0(self.eta);
        Rgb::splat((1.0 - self.metallic) * (1.0 - self.spec_tint) * f)
            + schlick_fresnel(self.base_color, cos, self.eta) * self.metallic
            + schlick_fresnel(tinted, cos, self.eta) * ((1.0 - self.metallic) * self.spec_tint)
    }

    /// The BSDF `f(wi → wo)` in radiance form (Mitsuba's `eval` divided by `|cos θ_o|`).
    fn value(&self, wi: Vec3, wo: Vec3) -> Rgb {
        if wi.z == 0.0 || wo.z == 0.0 {
            return Rgb::BLACK;
        }
        let front = wi.z > 0.0;
        if !front && self.bsdf <= 0.0 {
            return Rgb::BLACK;
        }
        let (side, e) = if front { (1.0, self.eta) } else { (-1.0, 1.0 / self.eta) };
        let (a, b) = (flip(wi, side), flip(wo, side));
        let reflection = b.z > 0.0;
        let mut value = Rgb::BLACK;
        if let Some(m) = half_vector(a, b, e) {
            let f = dielectric(a.dot(m), e);
            let dg = self.ggx.d(m) * self.ggx.g(a, b, m);
            if reflection && f > 0.0 {
                let fresnel = if front { self.fresnel(f, a.dot(m)) } else { Rgb::splat(self.bsdf * f) };
                value += fresnel * (dg / (4.0 * a.z * b.z));
            } else if !reflection && self.bsdf > 0.0 && f < 1.0 {
                let (cos_a, cos_b) = (a.dot(m), b.dot(m));
                let core = (1.0 - f) * dg * (cos_a * cos_b).abs() / (a.z * b.z.abs() * sqr(cos_a + e * cos_b));
                value += self.base_color.map(f32::sqrt) * (self.bsdf * core);
            }
        }
        if front && reflection {
            let h = (a + b).normalize();
            if self.clearcoat.weight > 0.0 && h.is_finite() {
                value += Rgb::splat(self.clearcoat.value(a, b, h, self.eta));
            }
            if self.brdf > 0.0 {
                value += diffuse(self.base_color, self.roughness, self.flatness, a, b, h) * self.brdf;
            }
            if self.sheen > 0.0 && self.metallic < 1.0 {
                value += sheen(self.base_color, self.sheen, self.sheen_tint, b, h) * (1.0 - self.metallic);
            }
        }
        value
    }

    /// Density per steradian of sampling `wo` from `wi`.
    fn density(&self, wi: Vec3, wo: Vec3) -> f32 {
        if wi.z == 0.0 || wo.z == 0.0 {
            return 0.0;
        }
        let front = wi.z > 0.0;
        if !front && self.bsdf <= 0.0 {
            return 0.0;
        }
        let (side, e) = if front { (1.0, self.eta) } else { (-1.0, 1.0 / self.eta) };
        let (a, b) = (flip(wi, side), flip(wo, side));
        let [p_diffuse, p_clearcoat, p_specular] = self.lobe_weights(front);
        let reflection = b.z > 0.0;
        let mut pdf = if reflection { p_diffuse * warp::cosine_hemisphere_pdf(b.z) } else { 0.0 };
        if let Some(m) = half_vector(a, b, e) {
            let (cos_a, cos_b) = (a.dot(m), b.dot(m));
            let visible = self.ggx.visible_pdf(a, m);
            let p_reflect = self.reflect_probability(front, dielectric(cos_a, e));
            if reflection {
                let normals = p_specular * p_reflect * visible + p_clearcoat * self.clearcoat.normal_pdf(m);
                pdf += normals / (4.0 * cos_b);
            } else {
                pdf += p_specular * (1.0 - p_reflect) * visible * sqr(e) * cos_b.abs() / sqr(cos_a + e * cos_b);
            }
        }
        pdf
    }
}

/// The microfacet normal (on +z) of the pair `a` (above) and `b` at an interface with relative
/// IOR `e` (far side over `a`'s side): `a + b` for a reflection, `a + e·b` for a refraction.
/// `None` when degenerate or when a direction lies on the wrong side of the microfacet.
fn half_vector(a: Vec3, b: Vec3, e: f32) -> Option<Vec3> {
    let reflection = b.z > 0.0;
    let m = if reflection { a + b } else { a + e * b }.normalize();
    if !m.is_finite() {
        return None;
    }
    let m = if m.z < 0.0 { -m } else { m };
    let compatible = a.dot(m) > 0.0 && if reflection { b.dot(m) > 0.0 } else { b.dot(m) < 0.0 };
    compatible.then_some(m)
}

impl LeafModel for Principled {
    fn one_sided(&self) -> bool {
        false
    }

    fn lobe_is_delta(&self, _lobe: usize) -> bool {
        false
    }

    fn selection_weight(&self) -> f32 {
        self.albedo(Vec3::Z).luminance().max(1e-3)
    }

    /// An estimate: Fresnel-weighted specular reflection and transmission at the macro normal
    /// plus the diffuse weight times the base colour, the sheen and the clearcoat, clamped to 1.
    fn albedo(&self, w: Vec3) -> Rgb {
        if w.z == 0.0 {
            return Rgb::BLACK;
        }
        let f = dielectric(w.z, self.eta);
        let transmission = self.base_color.map(f32::sqrt) * (self.bsdf * (1.0 - f));
        let albedo = if w.z > 0.0 {
            self.fresnel(f, w.z)
                + transmission
                + self.base_color * self.brdf
                + Rgb::splat(0.1 * self.sheen * (1.0 - self.metallic) + 0.04 * self.clearcoat.weight)
        } else {
            Rgb::splat(self.bsdf * f) + transmission
        };
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
        let front = fixed.z > 0.0;
        if !front && self.bsdf <= 0.0 {
            return None;
        }
        let (side, e) = if front { (1.0, self.eta) } else { (-1.0, 1.0 / self.eta) };
        let a = flip(fixed, side);
        let [p_diffuse, p_clearcoat, p_specular] = self.lobe_weights(front);
        let (b, lobe) = if u[2] < p_diffuse {
            (warp::cosine_hemisphere([u[0], u[1]]), LobeKind::Diffuse)
        } else if u[2] < p_diffuse + p_clearcoat {
            let m = self.clearcoat.sample_normal([u[0], u[1]]);
            let b = reflect(a, m);
            if a.dot(m) <= 0.0 || b.z <= 0.0 {
                return None;
            }
            (b, LobeKind::Glossy)
        } else {
            // The rest of u[2] chooses between reflection and refraction.
            let choice = ((u[2] - p_diffuse - p_clearcoat) / p_specular).clamp(0.0, 1.0);
            let m = self.ggx.sample_visible(a, [u[0], u[1]]);
            let cos = a.dot(m);
            if cos <= 0.0 {
                return None;
            }
            if choice < self.reflect_probability(front, dielectric(cos, e)) {
                let b = reflect(a, m);
                if b.z <= 0.0 {
                    return None;
                }
                (b, LobeKind::Glossy)
            } else {
                let b = refract(a, m, e)?;
                if b.z >= 0.0 {
                    return None;
                }
                (b, LobeKind::GlossyTransmission)
            }
        };
        Some(Sampled::Lobe { direction: flip(b, side), lobe })
    }
}
