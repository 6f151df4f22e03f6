//! Microfacet building blocks of the rough BSDFs: the anisotropic GGX (Trowbridge–Reitz) and
//! Beckmann distributions of normals ([`Microfacet`], one value every rough model holds; the
//! models never match on the kind), their Smith masking, sampling of the distribution of
//! *visible* normals with its density, refraction through a microfacet, and Fresnel
//! reflectances of conductors (complex index of refraction) and of the diffuse (hemispherically
//! averaged) dielectric case.
//!
//! Every direction here is in the local frame of the macro surface: `z` is the (shading) normal,
//! `x` the tangent along which the roughness is `alpha_x`. Densities are per unit solid angle.

mod beckmann;
mod erf;
mod ggx;

use math::{Vec3, sqr};
use spectrum::Rgb;

/// Smallest roughness accepted: below it the distribution is too peaked for single precision
/// (Mitsuba uses the same bound).
pub const MIN_ALPHA: f32 = 1e-4;

/// The shape of a microfacet normal distribution (Mitsuba's `distribution` parameter).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Distribution {
    /// Trowbridge–Reitz: long tails; pbrt-v4's only distribution.
    #[default]
    Ggx,
    /// Beckmann (Gaussian slopes): Mitsuba's default for the rough plugins.
    Beckmann,
}

/// An anisotropic microfacet distribution of normals.
///
/// `D(m)` is normalised so that `∫ D(m) cos θm dω(m) = 1` (the projected area of the
/// microsurface equals that of the macro surface):
/// - GGX: `D(m) = 1 / (π αx αy (mx²/αx² + my²/αy² + mz²)²)`,
/// - Beckmann: `D(m) = exp(−(mx²/αx² + my²/αy²)/mz²) / (π αx αy mz⁴)`,
///
/// both 0 for `m` below the macro surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Microfacet {
    /// GGX or Beckmann.
    pub kind: Distribution,
    /// Roughness along the local `x` axis (tangent), at least [`MIN_ALPHA`].
    pub alpha_x: f32,
    /// Roughness along the local `y` axis (bitangent), at least [`MIN_ALPHA`].
    pub alpha_y: f32,
}

impl Microfacet {
    /// A distribution of kind `kind` with roughness `alpha_x` along the tangent and `alpha_y`
    /// along the bitangent (`α`, i.e. Disney `roughness²`, the RMS slope √2·σ for Beckmann).
    /// Non-finite or tiny values are raised to [`MIN_ALPHA`].
    pub fn new(kind: Distribution, alpha_x: f32, alpha_y: f32) -> Self {
        let clamp = |a: f32| if a.is_finite() { a.max(MIN_ALPHA) } else { MIN_ALPHA };
        Self { kind, alpha_x: clamp(alpha_x), alpha_y: clamp(alpha_y) }
    }

    /// A GGX distribution (see [`Microfacet::new`]).
    pub fn ggx(alpha_x: f32, alpha_y: f32) -> Self {
        Self::new(Distribution::Ggx, alpha_x, alpha_y)
    }

    /// A Beckmann distribution (see [`Microfacet::new`]).
    pub fn beckmann(alpha_x: f32, alpha_y: f32) -> Self {
        Self::new(Distribution::Beckmann, alpha_x, alpha_y)
    }

    /// Density of microfacet normals `D(m)` per unit solid angle of `m` (not a probability
    /// density: `D(m) cos θm` is). Zero for `m` below the macro surface.
    #[inline]
    pub fn d(&self, m: Vec3) -> f32 {
        match self.kind {
            Distribution::Ggx => ggx::d(self.alpha_x, self.alpha_y, m),
            Distribution::Beckmann => beckmann::d(self.alpha_x, self.alpha_y, m),
        }
    }

    /// Smith's masking function `G1(w, m) = 1 / (1 + Λ(w))` used in BSDF values, for the
    /// direction `w` (either hemisphere); 0 when `w` sees the back of the microfacet `m`
    /// (`(w·m)(w·n) ≤ 0`). GGX: exact; Beckmann: Mitsuba's rational fit (below 0.35 % from
    /// [`Microfacet::g1_visible`]).
    #[inline]
    pub fn g1(&self, w: Vec3, m: Vec3) -> f32 {
        if w.dot(m) * w.z <= 0.0 {
            return 0.0;
        }
        match self.kind {
            Distribution::Ggx => ggx::g1(self.alpha_x, self.alpha_y, w),
            Distribution::Beckmann => beckmann::g1(self.alpha_x, self.alpha_y, w),
        }
    }

    /// The exact Smith masking `G1(w, m)` that normalises the visible-normal density of
    /// [`Microfacet::sample_visible`]: `visible_pdf = g1_visible · max(0, w·m) · D(m) / cos θw`.
    /// Equal to [`Microfacet::g1`] for GGX.
    #[inline]
    pub fn g1_visible(&self, w: Vec3, m: Vec3) -> f32 {
        if w.dot(m) * w.z <= 0.0 {
            return 0.0;
        }
        match self.kind {
            Distribution::Ggx => ggx::g1(self.alpha_x, self.alpha_y, w),
            Distribution::Beckmann => beckmann::g1_exact(self.alpha_x, self.alpha_y, w),
        }
    }

    /// Separable Smith shadowing-masking `G(a, b, m) = G1(a, m) · G1(b, m)` (Mitsuba's choice).
    #[inline]
    pub fn g(&self, a: Vec3, b: Vec3, m: Vec3) -> f32 {
        self.g1(a, m) * self.g1(b, m)
    }

    /// Samples a microfacet normal from the distribution of normals visible from `w`
    /// (`w.z > 0`), `D_w(m) = G1(w, m) max(0, w·m) D(m) / cos θw`, with two uniform numbers
    /// (GGX: Heitz 2018; Beckmann: Heitz & d'Eon 2014). Its density per unit solid angle of `m`
    /// is [`Microfacet::visible_pdf`].
    #[inline]
    pub fn sample_visible(&self, w: Vec3, u: [f32; 2]) -> Vec3 {
        match self.kind {
            Distribution::Ggx => ggx::sample_visible(self.alpha_x, self.alpha_y, w, u),
            Distribution::Beckmann => beckmann::sample_visible(self.alpha_x, self.alpha_y, w, u),
        }
    }

    /// Density per unit solid angle of [`Microfacet::sample_visible`] producing `m` for the
    /// direction `w` (`w.z > 0`).
    #[inline]
    pub fn visible_pdf(&self, w: Vec3, m: Vec3) -> f32 {
        if w.z <= 0.0 {
            return 0.0;
        }
        self.g1_visible(w, m) * w.dot(m).max(0.0) * self.d(m) / w.z
    }

    /// Density per unit solid angle of the direction reflected about a visible normal sampled
    /// for `w` (`w.z > 0`) when the reflection is about `m`: the visible-normal density times
    /// the Jacobian `1/(4 w·m)`, i.e. `G1(w, m) D(m) / (4 cos θw)`.
    #[inline]
    pub fn reflection_pdf(&self, w: Vec3, m: Vec3) -> f32 {
        self.g1_visible(w, m) * self.d(m) / (4.0 * w.z)
    }
}
/// Reflection of `w` about the unit vector `m` (both pointing away from the surface).
#[inline]
pub fn reflect(w: Vec3, m: Vec3) -> Vec3 {
    2.0 * w.dot(m) * m - w
}

/// Refraction of `w` (with `w·m > 0`) through the interface with unit normal `m` when the index
/// of refraction on the far side over that on `w`'s side is `eta`. `None` under total internal
/// reflection. The result points away from the surface, on the other side of `m`.
#[inline]
pub fn refract(w: Vec3, m: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = w.dot(m);
    let inv = 1.0 / eta;
    let sin_t2 = sqr(inv) * (1.0 - sqr(cos_i)).max(0.0);
    if sin_t2 >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin_t2).sqrt();
    Some((inv * cos_i - cos_t) * m - inv * w)
}

/// Unpolarised Fresnel reflectance of a conductor with complex index of refraction
/// `eta + i·k` (relative to the outside) for an incident direction with cosine `cos_incident`
/// to the normal (its absolute value is used). Exact for any complex index; `eta = k = 0` is a
/// perfect mirror (reflectance 1). At normal incidence it is `((η−1)² + k²)/((η+1)² + k²)`.
pub fn fresnel_conductor(cos_incident: f32, eta: f32, k: f32) -> f32 {
    if eta == 0.0 && k == 0.0 {
        return 1.0;
    }
    let c = (cos_incident.abs() as f64).min(1.0);
    let (eta, k) = (eta as f64, k as f64);
    let c2 = c * c;
    let s2 = 1.0 - c2;
    // With (a + i b)² = (η + i k)² − sin²θ:  a² + b² = |η² − k² − sin²θ + 2iηk|.
    let t0 = eta * eta - k * k - s2;
    let a2b2 = (t0 * t0 + 4.0 * eta * eta * k * k).sqrt();
    let a = (0.5 * (a2b2 + t0)).max(0.0).sqrt();
    let rs = (a2b2 + c2 - 2.0 * a * c) / (a2b2 + c2 + 2.0 * a * c);
    let t1 = a2b2 * c2 + s2 * s2;
    let t2 = 2.0 * a * c * s2;
    let rp = rs * (t1 - t2) / (t1 + t2);
    let r = 0.5 * (rs + rp);
    if r.is_finite() { r.clamp(0.0, 1.0) as f32 } else { 1.0 }
}

/// [`fresnel_conductor`] per colour channel.
pub fn fresnel_conductor_rgb(cos_incident: f32, eta: Rgb, k: Rgb) -> Rgb {
    Rgb::new(
        fresnel_conductor(cos_incident, eta.r, k.r),
        fresnel_conductor(cos_incident, eta.g, k.g),
        fresnel_conductor(cos_incident, eta.b, k.b),
    )
}

/// Hemispherical average `2∫₀¹ F(μ) μ dμ` of the unpolarised Fresnel reflectance of a smooth
/// dielectric interface seen from a side whose relative index (far side over near side) is
/// `eta`, by the polynomial fits Mitsuba uses: Egan & Hilgeman (1973) for `eta < 1`, d'Eon &
/// Irving (2011) otherwise (relative error below 1 % for `eta` in [1/2, 2]).
pub fn fresnel_diffuse_reflectance(eta: f32) -> f32 {
    if eta < 1.0 {
        -1.4399 * sqr(eta) + 0.7099 * eta + 0.6681 + 0.0636 / eta
    } else {
        let i = 1.0 / eta;
        let (i2, i3) = (i * i, i * i * i);
        0.919317 - 3.4793 * i + 6.75335 * i2 - 7.80989 * i3 + 4.98554 * i2 * i2 - 1.36881 * i2 * i3
    }
}
