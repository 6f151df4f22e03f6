//! The scene-side description of pbrt-v4's coated materials (`coateddiffuse`,
//! `coatedconductor`): [`CoatedParameters`], validated when built, with the per-material
//! quadratures the smooth closed forms need (see `coated`).

use spectrum::Rgb;

use super::fresnel::fresnel_dielectric;
use crate::texture::Texture;

/// The dielectric interface on top of a coated material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CoatingInterface {
    /// Relative index of refraction, coating over outside (pbrt's `interface.eta`, default 1.5).
    pub eta: f32,
    /// GGX α along the tangent (pbrt's roughness after `remaproughness`); the interface is
    /// smooth when both α are below 10⁻³.
    pub alpha_u: f32,
    /// GGX α along the bitangent.
    pub alpha_v: f32,
}

/// The medium between the interface and the base.
#[derive(Clone, Debug, PartialEq)]
pub struct CoatingLayer {
    /// Depth of the medium in mean free paths (pbrt's `thickness`, default 0.01; the medium's
    /// extinction is 1 per unit length): a straight crossing at the cosine μ (inside) transmits
    /// `exp(−thickness/μ)`.
    pub thickness: f32,
    /// Single-scattering albedo of the medium, in [0, 1] (default 0: absorption only).
    pub albedo: Texture,
    /// Henyey–Greenstein asymmetry of the medium's phase function, in (−1, 1) (default 0).
    pub g: f32,
    /// Largest number of events of one random walk (pbrt's `maxdepth`, default 10).
    pub max_depth: u32,
    /// Random walks per evaluation (pbrt's `nsamples`, default 1).
    pub samples: u32,
}

impl Default for CoatingLayer {
    fn default() -> Self {
        Self { thickness: 0.01, albedo: Texture::Constant(Rgb::BLACK), g: 0.0, max_depth: 10, samples: 1 }
    }
}

/// The complex IOR of a coated conductor's base.
#[derive(Clone, Debug, PartialEq)]
pub enum ConductorIor {
    /// `eta + i·k` relative to the *outside* (the BSDF divides both by the coating's η, as
    /// pbrt-v4 does).
    Complex {
        /// Real part per channel.
        eta: Rgb,
        /// Imaginary part per channel.
        k: Rgb,
    },
    /// pbrt's `reflectance` r: η = 1, k = 2√r/√(1 − r) (before the division by the coating's
    /// η), whose normal-incidence reflectance in air is r.
    Reflectance(Texture),
}

/// The opaque base under the coating.
#[derive(Clone, Debug, PartialEq)]
pub enum CoatedBase {
    /// Lambertian (`coateddiffuse`'s `reflectance`, default 0.5).
    Diffuse {
        /// Reflectance in [0, 1].
        reflectance: Texture,
    },
    /// A smooth or GGX conductor (`coatedconductor`).
    Conductor {
        /// Its index of refraction.
        ior: ConductorIor,
        /// GGX α along the tangent (smooth when both are below 10⁻³).
        alpha_u: f32,
        /// GGX α along the bitangent.
        alpha_v: f32,
    },
}

/// pbrt-v4's `coateddiffuse` or `coatedconductor`: a dielectric interface over a medium over
/// an opaque base. Built by [`CoatedParameters::new`], which checks the ranges and tabulates
/// the hemispherical moments of the interface.
#[derive(Clone, Debug, PartialEq)]
pub struct CoatedParameters {
    interface: CoatingInterface,
    layer: CoatingLayer,
    base: CoatedBase,
    moments: Moments,
}

/// Hemispherical moments of a smooth interface over the layer (no scattering).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Moments {
    /// `r̄ = ∫ F_inside(μ) Tr(μ)² 2μ dμ`: the fraction of a cosine-distributed upward flux
    /// inside the layer that comes back down to the base after one reflection at the top.
    pub internal_reflectance: f32,
    /// `T̄ = ∫ (1 − F(μ)) Tr(μ′) 2μ dμ` over the outside cosines μ (μ′ the refracted one).
    pub mean_transmittance: f32,
}

/// Below this α on both axes an interface or conductor is smooth (pbrt's `EffectivelySmooth`).
pub(super) const SMOOTH_ALPHA: f32 = 1e-3;

impl CoatedParameters {
    /// Checks and stores the parameters: `eta` positive and finite, α ≥ 0, `thickness` ≥ 0
    /// and finite, `g` in (−1, 1), `max_depth` and `samples` at least 1, constant albedos
    /// and diffuse reflectances in [0, 1].
    pub fn new(interface: CoatingInterface, layer: CoatingLayer, base: CoatedBase) -> Result<Self, String> {
        if !(interface.eta > 0.0 && interface.eta.is_finite()) {
            return Err(format!("interface.eta = {} must be positive and finite", interface.eta));
        }
        let alpha_ok = |a: f32| a >= 0.0 && a.is_finite();
        let base_alpha = match &base {
            CoatedBase::Conductor { alpha_u, alpha_v, .. } => [*alpha_u, *alpha_v],
            CoatedBase::Diffuse { .. } => [0.0; 2],
        };
        if ![interface.alpha_u, interface.alpha_v].into_iter().chain(base_alpha).all(alpha_ok) {
            return Err("roughness must be a finite number ≥ 0".into());
        }
        if !(layer.thickness >= 0.0 && layer.thickness.is_finite()) {
            return Err(format!("thickness = {} must be a finite number ≥ 0", layer.thickness));
        }
        if !(layer.g > -1.0 && layer.g < 1.0) {
            return Err(format!("g = {} must lie in (−1, 1)", layer.g));
        }
        if layer.max_depth == 0 || layer.samples == 0 {
            return Err("maxdepth and nsamples must be at least 1".into());
        }
        let unit = |t: &Texture, name: &str| match t.as_constant() {
            Some(c) if !(c.r.min(c.g).min(c.b) >= 0.0 && c.max_component() <= 1.0) => {
                Err(format!("{name} = ({}, {}, {}) is outside [0, 1]", c.r, c.g, c.b))
            }
            _ => Ok(()),
        };
        unit(&layer.albedo, "albedo")?;
        if let CoatedBase::Diffuse { reflectance } = &base {
            unit(reflectance, "reflectance")?;
        }
        let moments = Moments::new(interface.eta, layer.thickness);
        Ok(Self { interface, layer, base, moments })
    }

    /// The top interface.
    pub fn interface(&self) -> &CoatingInterface {
        &self.interface
    }

    /// The medium between the interface and the base.
    pub fn layer(&self) -> &CoatingLayer {
        &self.layer
    }

    /// The base.
    pub fn base(&self) -> &CoatedBase {
        &self.base
    }

    pub(super) fn moments(&self) -> Moments {
        self.moments
    }

    /// Every texture the BSDF evaluates.
    pub fn textures(&self) -> Vec<&Texture> {
        let mut t = vec![&self.layer.albedo];
        match &self.base {
            CoatedBase::Diffuse { reflectance } => t.push(reflectance),
            CoatedBase::Conductor { ior: ConductorIor::Reflectance(r), .. } => t.push(r),
            CoatedBase::Conductor { .. } => {}
        }
        t
    }

    /// True when either rough surface is anisotropic.
    pub fn is_anisotropic(&self) -> bool {
        let base = match &self.base {
            CoatedBase::Conductor { alpha_u, alpha_v, .. } => alpha_u != alpha_v,
            CoatedBase::Diffuse { .. } => false,
        };
        base || self.interface.alpha_u != self.interface.alpha_v
    }
}

impl Moments {
    /// Midpoint quadrature in μ (4096 steps, double precision sums).
    fn new(eta: f32, thickness: f32) -> Self {
        let steps = 4096;
        let (mut internal, mut transmitted) = (0.0f64, 0.0f64);
        for i in 0..steps {
            let mu = ((i as f64 + 0.5) / steps as f64) as f32;
            let tr = |cos: f32| if thickness <= 0.0 { 1.0 } else { (-thickness / cos).exp() };
            internal += (fresnel_dielectric(-mu, eta) * tr(mu) * tr(mu) * mu) as f64;
            let refracted = (1.0 - (1.0 - mu * mu) / (eta * eta)).max(0.0).sqrt();
            if refracted > 0.0 {
                transmitted += ((1.0 - fresnel_dielectric(mu, eta)) * tr(refracted) * mu) as f64;
            }
        }
        Self {
            internal_reflectance: (2.0 * internal / steps as f64) as f32,
            mean_transmittance: (2.0 * transmitted / steps as f64) as f32,
        }
    }
}
