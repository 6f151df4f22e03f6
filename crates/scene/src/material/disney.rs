//! Formulas shared by the Disney-style models `principled` and `principled_thin` (Burley 2012,
//! 2015, in the form of Mitsuba 3's `principledhelpers.h`): Schlick's Fresnel weight, the
//! tinted Fresnel terms, the roughness-to-α map, and the Disney diffuse with retro-reflection,
//! the fake subsurface ("flatness") and sheen. Every direction is local with `z` the normal;
//! the values are BSDF values (per steradian, without the cosine).

use math::{INV_PI, Vec3, sqr};
use spectrum::Rgb;

use super::fresnel::fresnel_dielectric;

/// Schlick's weight `(1 − cos)⁵`, the argument clamped to [0, 1].
#[inline]
pub(super) fn schlick_weight(cos: f32) -> f32 {
    let m = (1.0 - cos).clamp(0.0, 1.0);
    sqr(sqr(m)) * m
}

/// Normal-incidence reflectance `((η − 1)/(η + 1))²` of a dielectric with relative IOR `eta`.
#[inline]
pub(super) fn schlick_r0(eta: f32) -> f32 {
    sqr((eta - 1.0) / (eta + 1.0))
}

/// Schlick's approximation `R0 + (1 − R0)(1 − cos)⁵` at an interface of relative IOR `eta`
/// (inside over outside), for a direction with cosine `cos_incident` to the microfacet normal
/// (negative inside). Seen from the denser side the cosine of the refracted direction is used
/// (Mitsuba's `calc_schlick`; 0 beyond the critical angle, giving weight 1).
pub(super) fn schlick_fresnel(r0: Rgb, cos_incident: f32, eta: f32) -> Rgb {
    let outside = cos_incident >= 0.0;
    let (eta_it, eta_ti) = if outside { (eta, 1.0 / eta) } else { (1.0 / eta, eta) };
    let weight = if eta_it > 1.0 {
        schlick_weight(cos_incident.abs())
    } else {
        let cos_t2 = 1.0 - (1.0 - sqr(cos_incident)) * sqr(eta_ti);
        schlick_weight(cos_t2.max(0.0).sqrt())
    };
    r0 + (Rgb::WHITE - r0) * weight
}

/// `base_color` divided by its luminance (white when the luminance is not positive): the hue
/// the specular and sheen tints lean towards.
#[inline]
pub(super) fn tint_colour(base_color: Rgb) -> Rgb {
    let luminance = base_color.luminance();
    if luminance > 0.0 { base_color / luminance } else { Rgb::WHITE }
}

/// `(1 − t)·a + t·b`.
#[inline]
pub(super) fn lerp(a: f32, b: f32, t: f32) -> f32 {
    a + t * (b - a)
}

/// GGX `(α_x, α_y)` for the Disney `roughness` and `anisotropic` (Burley 2012):
/// `α = roughness²`, stretched by `aspect = √(1 − 0.9·anisotropic)` (`α/aspect` along the
/// tangent, `α·aspect` along the bitangent), each at least 0.001.
pub(super) fn alpha_pair(roughness: f32, anisotropic: f32) -> (f32, f32) {
    let a = sqr(roughness);
    // Anisotropy above 1/0.9 (outside Mitsuba's range) would make the aspect imaginary.
    let aspect = (1.0 - 0.9 * anisotropic).max(1e-4).sqrt();
    ((a / aspect).max(0.001), (a * aspect).max(0.001))
}

/// The dielectric Fresnel reflectance for a direction with cosine `cos_incident` to the
/// microfacet normal (negative inside) and relative IOR `eta`.
#[inline]
pub(super) fn dielectric(cos_incident: f32, eta: f32) -> f32 {
    fresnel_dielectric(cos_incident, eta)
}

/// The diffuse-like reflection of the Disney models for two local directions `wi`, `wo` above
/// the surface with half vector `h`: `base_color/π · lerp(f_diffuse + f_retro, f_subsurface,
/// flatness)` (without any lobe weight).
pub(super) fn diffuse(base_color: Rgb, roughness: f32, flatness: f32, wi: Vec3, wo: Vec3, h: Vec3) -> Rgb {
    let (cos_i, cos_o) = (wi.z.abs(), wo.z.abs());
    let (fi, fo) = (schlick_weight(cos_i), schlick_weight(cos_o));
    let f_diffuse = (1.0 - 0.5 * fi) * (1.0 - 0.5 * fo);
    let rr = 2.0 * roughness * sqr(h.dot(wo));
    let f_retro = rr * (fo + fi + fo * fi * (rr - 1.0));
    let mut shape = f_diffuse + f_retro;
    if flatness != 0.0 {
        // Hanrahan–Krueger-like fake subsurface, flattening the retro-reflection.
        let fss90 = 0.5 * rr;
        let fss = lerp(1.0, fss90, fo) * lerp(1.0, fss90, fi);
        let f_subsurface = 1.25 * (fss * (1.0 / (cos_o + cos_i) - 0.5) + 0.5);
        shape = lerp(shape, f_subsurface, flatness);
    }
    base_color * (shape * INV_PI)
}

/// The sheen of the Disney models, `sheen · (1 − cos θ_d)⁵ · lerp(1, tint, sheen_tint)` with
/// `θ_d` the angle between `wo` and the half vector `h` (Mitsuba's form, without a 1/π).
pub(super) fn sheen(base_color: Rgb, sheen: f32, sheen_tint: f32, wo: Vec3, h: Vec3) -> Rgb {
    let colour = Rgb::splat(1.0 - sheen_tint) + tint_colour(base_color) * sheen_tint;
    colour * (sheen * schlick_weight(h.dot(wo).abs()))
}

/// Reflection of `w` about the unit vector `m`.
#[inline]
pub(super) fn reflect(w: Vec3, m: Vec3) -> Vec3 {
    2.0 * w.dot(m) * m - w
}

/// `v` with its z component multiplied by `side` (±1).
#[inline]
pub(super) fn flip(v: Vec3, side: f32) -> Vec3 {
    Vec3::new(v.x, v.y, v.z * side)
}
