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
    let [r] = fresnel_conductor_lanes(cos_incident, [eta], [k]);
    r
}

/// [`fresnel_conductor`] per colour channel, bit for bit. The three channels are computed
/// together: the compiler packs red and green into SSE2 registers and computes blue beside them.
///
/// Total reflectors skip the formula: `η = 0` with `k = 0` (our perfect mirror) or `k = 1`
/// (Mitsuba's conductors without a material) in every channel, for which it gives exactly 1 at
/// every angle (`conductor_fresnel_of_total_reflectors_is_one`). Mitsuba's default `conductor`
/// is such a mirror; its two square roots and division in f64 per channel were 5 % of a `pt`
/// render of its caustic box (docs/performance.md, "Conductor Fresnel").
pub fn fresnel_conductor_rgb(cos_incident: f32, eta: Rgb, k: Rgb) -> Rgb {
    if eta == Rgb::BLACK && [k.r, k.g, k.b].iter().all(|&v| v == 0.0 || v == 1.0) {
        return Rgb::WHITE;
    }
    let [r, g, b] = fresnel_conductor_lanes(cos_incident, [eta.r, eta.g, eta.b], [k.r, k.g, k.b]);
    Rgb::new(r, g, b)
}

/// The conductor Fresnel reflectance of [`fresnel_conductor`] for `N` complex indices at one
/// angle, in f64, every lane by the same operations (so one lane of a wider call equals the
/// scalar call bit for bit).
///
/// With `(a + i b)² = (η + i k)² − sin²θ`, `A = a² + b² + cos²θ` and `B = 2 a cosθ`, the s- and
/// p-polarised reflectances are `Rs = (A − B)/(A + B)` and `Rp = Rs·(t₁ − t₂)/(t₁ + t₂)` with
/// `t₁ = (a² + b²) cos²θ + sin⁴θ` and `t₂ = B sin²θ`. Their mean is
/// `Rs/2 · (1 + (t₁ − t₂)/(t₁ + t₂)) = Rs·t₁/(t₁ + t₂) = (A − B)·t₁ / ((A + B)·(t₁ + t₂))`:
/// one division instead of two. Both factors of the denominator are sums of non-negative terms;
/// it is 0 only at `cosθ = 0` with `η = ±1, k = 0` (and for `η = k = 0`, returned as 1 anyway),
/// where the numerator is 0 too: NaN, as with two divisions, and NaN becomes 1.
///
/// Written as straight-line steps over the lanes, without branches, so that LLVM's SLP
/// vectoriser packs the lanes into SSE2 registers (`sqrtpd`, `divpd`). Keep the last step as it
/// is: with `if mirror || !r.is_finite() { 1 } else { clamped }` or an `if mirror { 1 } else if
/// …` chain instead, the whole function went back to scalar code (docs/performance.md).
#[inline(always)]
fn fresnel_conductor_lanes<const N: usize>(cos_incident: f32, eta: [f32; N], k: [f32; N]) -> [f32; N] {
    let c = (cos_incident.abs() as f64).min(1.0);
    let c2 = c * c;
    let s2 = 1.0 - c2;
    let s4 = s2 * s2;
    let eta = eta.map(f64::from);
    let k = k.map(f64::from);
    let mut r = [0.0f64; N];
    for i in 0..N {
        let (eta2, k2) = (eta[i] * eta[i], k[i] * k[i]);
        // a² + b² = |η² − k² − sin²θ + 2iηk|.
        let t0 = eta2 - k2 - s2;
        let a2b2 = (t0 * t0 + 4.0 * eta2 * k2).sqrt();
        let a = (0.5 * (a2b2 + t0)).max(0.0).sqrt();
        let big_a = a2b2 + c2;
        let big_b = 2.0 * a * c;
        let t1 = a2b2 * c2 + s4;
        r[i] = ((big_a - big_b) * t1) / ((big_a + big_b) * (t1 + big_b * s2));
    }
    std::array::from_fn(|i| {
        // η = k = 0 (the squares of f32 values cannot underflow in f64) is a perfect mirror.
        // The formula gives it too (a = B = 0, so the numerator equals the denominator: 1 or
        // 0/0), but the special case stays explicit.
        let mirror = eta[i] * eta[i] + k[i] * k[i] == 0.0;
        // NaN and −∞ fail `r ≥ −MAX` and become 1, as the mirror does; +∞ is clamped to 1.
        let r = if !mirror && r[i] >= -f64::MAX { r[i] } else { 1.0 };
        r.clamp(0.0, 1.0) as f32
    })
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
