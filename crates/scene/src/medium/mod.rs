//! Participating media: homogeneous and heterogeneous (grid) media with an isotropic or
//! Henyey–Greenstein phase function, attached to the two sides of shapes and to the camera.
//!
//! **What a scene holds** ([`Media`]): the media, the medium on each side of the world
//! primitives that bound one ([`MediumInterface`]: interior = the side opposite the geometric
//! normal, exterior = the side it points to; `None` is vacuum), the medium the camera sits in,
//! and which materials are index-matched boundaries (Mitsuba's `null` BSDF, pbrt's `interface`
//! material) that rays pass through unchanged. A ray crossing or leaving a primitive with an
//! interface enters the medium on the side its new direction points to; a primitive without
//! one keeps the ray's medium (Mitsuba 3's and pbrt-v4's rule).
//!
//! **Units.** Coefficients σ_t, σ_s, σ_a are per scene unit of length (the file's `scale`
//! applied); albedo is unitless. RGB values are used as they are in RGB mode; in spectral mode
//! the albedo is upsampled as a reflectance and the coefficients as unbounded spectra
//! (the reflectance upsampling of `rgb / max` times `max`); tabulated spectra are evaluated at
//! the wavelengths.
//!
//! Heterogeneous media ([`heterogeneous`], [`grid`]) hold their coefficients in [`Volume`]s and
//! are sampled by delta tracking and ratio tracking.
//!
//! What this module does not do: media on instanced geometry, emissive media, and light
//! transport (the volumetric path tracer lives in the `render` crate). Issue #15.

pub(crate) mod build;
pub mod grid;
pub mod heterogeneous;
pub mod homogeneous;
pub mod majorant;
pub mod phase;

use std::sync::Arc;

use spectrum::tabulated::Tabulated;
use spectrum::{Rgb, SpectralMode};

pub use grid::{Filter, Grid, Outside, Volume};
pub use heterogeneous::{Heterogeneous, MajorantProfile, Tracker};
pub use homogeneous::{DistanceSample, sample_distance, transmittance};
pub use phase::{PhaseFunction, PhaseSample};

/// A spectrally varying medium coefficient: an RGB value, or a tabulated spectrum (with its
/// RGB value for RGB mode).
#[derive(Clone, Debug, PartialEq)]
pub struct Coefficient {
    /// Linear-sRGB value (RGB mode; spectral mode upsamples it when there is no spectrum).
    pub rgb: Rgb,
    /// The spectrum (per nm of wavelength), used in spectral mode when present.
    pub spectrum: Option<Arc<Tabulated>>,
}

impl Coefficient {
    /// An RGB value.
    pub fn rgb(rgb: Rgb) -> Self {
        Self { rgb, spectrum: None }
    }

    /// The value at the wavelengths: a reflectance-like quantity in [0, 1] when `bounded`
    /// (albedo), otherwise any non-negative value (extinction, scattering, absorption).
    #[inline]
    fn eval<S: SpectralMode>(&self, w: &S::Wavelengths, bounded: bool) -> S {
        if let Some(t) = &self.spectrum {
            return S::from_function(w, |lambda| t.eval(lambda), self.rgb);
        }
        let peak = self.rgb.max_component();
        if bounded || peak <= 1.0 {
            S::from_reflectance(w, self.rgb)
        } else {
            S::from_reflectance(w, self.rgb * (1.0 / peak)) * peak
        }
    }

    fn validate(&self, what: &str) -> Result<(), String> {
        let bad = |v: f32| !(v.is_finite() && v >= 0.0);
        if bad(self.rgb.r) || bad(self.rgb.g) || bad(self.rgb.b) {
            return Err(format!("{what} must be finite and non-negative, got {:?}", self.rgb.to_array()));
        }
        if let Some((l, v)) = self.spectrum.as_ref().and_then(|t| t.points().find(|(_, v)| bad(*v))) {
            return Err(format!("{what} is {v} at {l} nm; it must be finite and non-negative"));
        }
        Ok(())
    }
}

/// How a file gives a homogeneous medium's coefficients.
#[derive(Clone, Debug, PartialEq)]
pub enum Coefficients {
    /// Extinction σ_t (per unit length before `scale`) and single-scattering albedo
    /// σ_s/σ_t (Mitsuba).
    ExtinctionAlbedo {
        /// σ_t.
        sigma_t: Coefficient,
        /// Albedo in [0, 1].
        albedo: Coefficient,
    },
    /// Absorption σ_a and scattering σ_s (per unit length before `scale`; pbrt).
    AbsorptionScattering {
        /// σ_a.
        sigma_a: Coefficient,
        /// σ_s.
        sigma_s: Coefficient,
    },
    /// Spatially varying extinction and albedo (Mitsuba's `heterogeneous`, pbrt-v4's
    /// `uniformgrid`); `scale` multiplies the extinction.
    Heterogeneous(Arc<Heterogeneous>),
}

/// A participating medium: homogeneous, or heterogeneous when its coefficients are
/// [`Coefficients::Heterogeneous`].
#[derive(Clone, Debug, PartialEq)]
pub struct Medium {
    /// The coefficients as the file gives them.
    pub coefficients: Coefficients,
    /// Factor on σ_t (or σ_a and σ_s), e.g. a change of length unit (≥ 0).
    pub scale: f32,
    /// The phase function.
    pub phase: PhaseFunction,
}

/// Extinction and scattering coefficients at a path's wavelengths, per scene unit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MediumCoefficients<S> {
    /// σ_t = σ_a + σ_s.
    pub sigma_t: S,
    /// σ_s.
    pub sigma_s: S,
}

impl Medium {
    /// σ_t and σ_s at the wavelengths (scale applied), per scene unit. For a heterogeneous
    /// medium: the majorant σ̄ (a bound of σ_t over space) in every channel and σ_s = 0 —
    /// use [`Medium::heterogeneous`] for its coefficients at a point.
    #[inline]
    pub fn coefficients<S: SpectralMode>(&self, w: &S::Wavelengths) -> MediumCoefficients<S> {
        match &self.coefficients {
            Coefficients::ExtinctionAlbedo { sigma_t, albedo } => {
                let sigma_t = sigma_t.eval::<S>(w, false) * self.scale;
                let albedo = albedo.eval::<S>(w, true).map(|a| a.clamp(0.0, 1.0));
                MediumCoefficients { sigma_t, sigma_s: sigma_t * albedo }
            }
            Coefficients::AbsorptionScattering { sigma_a, sigma_s } => {
                let sigma_a = sigma_a.eval::<S>(w, false).map(|v| v.max(0.0)) * self.scale;
                let sigma_s = sigma_s.eval::<S>(w, false).map(|v| v.max(0.0)) * self.scale;
                MediumCoefficients { sigma_t: sigma_a + sigma_s, sigma_s }
            }
            Coefficients::Heterogeneous(h) => MediumCoefficients {
                sigma_t: S::splat(h.tracker::<S>(self.scale, w).majorant()),
                sigma_s: S::default(),
            },
        }
    }

    /// The spatially varying coefficients, `None` for a homogeneous medium.
    #[inline]
    pub fn heterogeneous(&self) -> Option<&Heterogeneous> {
        match &self.coefficients {
            Coefficients::Heterogeneous(h) => Some(h),
            _ => None,
        }
    }

    /// The largest single-scattering albedo over the RGB channels (unitless; Russian roulette's
    /// continuation probability at a scattering event).
    pub fn max_albedo(&self) -> f32 {
        if let Some(h) = self.heterogeneous() {
            return h.max_albedo();
        }
        let c = self.coefficients::<Rgb>(&());
        let a = |t: f32, s: f32| if t > 0.0 { s / t } else { 0.0 };
        a(c.sigma_t.r, c.sigma_s.r).max(a(c.sigma_t.g, c.sigma_s.g)).max(a(c.sigma_t.b, c.sigma_s.b)).min(1.0)
    }

    /// Checks that the coefficients are finite and non-negative, the albedo at most 1 and the
    /// scale finite and non-negative.
    pub fn validate(&self) -> Result<(), String> {
        if !(self.scale.is_finite() && self.scale >= 0.0) {
            return Err(format!("the scale must be finite and non-negative, got {}", self.scale));
        }
        match &self.coefficients {
            Coefficients::ExtinctionAlbedo { sigma_t, albedo } => {
                sigma_t.validate("sigma_t")?;
                albedo.validate("albedo")?;
                if albedo.rgb.max_component() > 1.0 {
                    return Err(format!("the albedo must be at most 1, got {:?}", albedo.rgb.to_array()));
                }
            }
            Coefficients::AbsorptionScattering { sigma_a, sigma_s } => {
                sigma_a.validate("sigma_a")?;
                sigma_s.validate("sigma_s")?;
            }
            Coefficients::Heterogeneous(h) => {
                h.sigma_t.value.validate("sigma_t")?;
                h.albedo.value.validate("albedo")?;
                if h.albedo.value.rgb.max_component() * h.albedo.grid.as_ref().map_or(1.0, |g| g.max().max_component())
                    > 1.0
                {
                    return Err("the albedo must be at most 1".to_string());
                }
            }
        }
        Ok(())
    }
}

/// The media on the two sides of a surface (indices into [`Media::media`], `None` = vacuum).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MediumInterface {
    /// The medium on the side opposite the geometric normal (inside a closed, outward-facing
    /// shape).
    pub interior: Option<u32>,
    /// The medium on the side the geometric normal points to.
    pub exterior: Option<u32>,
}

impl MediumInterface {
    /// The medium a ray leaving the surface along `direction` travels in, for the geometric
    /// normal `normal`.
    #[inline]
    pub fn medium_towards(&self, direction: math::Vec3, normal: math::Vec3) -> Option<u32> {
        if direction.dot(normal) > 0.0 { self.exterior } else { self.interior }
    }
}

/// The participating media of a scene (empty for surface-only scenes).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Media {
    /// The media.
    pub media: Vec<Medium>,
    /// By world primitive index: the interface of primitives that bound media (empty or shorter
    /// than the primitives when some have none).
    pub interfaces: Vec<Option<MediumInterface>>,
    /// The medium the camera sits in.
    pub camera: Option<u32>,
    /// By material index: whether the material is an index-matched boundary (a ray passes
    /// through it unchanged and it does not count as a scattering vertex).
    pub null_materials: Vec<bool>,
}

impl Media {
    /// Whether the scene needs the volumetric path tracer: it has media or pass-through
    /// boundaries.
    pub fn is_active(&self) -> bool {
        !self.media.is_empty() || self.null_materials.iter().any(|n| *n)
    }

    /// Whether any medium is heterogeneous.
    pub fn has_heterogeneous(&self) -> bool {
        self.media.iter().any(|m| m.heterogeneous().is_some())
    }

    /// The interface of world primitive `primitive`, if it has one.
    #[inline]
    pub fn interface(&self, primitive: u32) -> Option<MediumInterface> {
        self.interfaces.get(primitive as usize).copied().flatten()
    }

    /// Whether material `material` is an index-matched boundary.
    #[inline]
    pub fn is_null(&self, material: u32) -> bool {
        self.null_materials.get(material as usize).copied().unwrap_or(false)
    }

    /// The medium with index `index`.
    #[inline]
    pub fn medium(&self, index: u32) -> &Medium {
        &self.media[index as usize]
    }
}

/// The media of a scene description (what loaders produce; [`crate::Scene::from_description`]
/// turns it into [`Media`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MediaDesc {
    /// The media.
    pub media: Vec<Medium>,
    /// Interfaces by index into [`crate::desc::SceneDescription::shapes`] (world shapes only;
    /// media on instanced shapes are not supported).
    pub shapes: std::collections::BTreeMap<u32, MediumInterface>,
    /// The medium the camera sits in.
    pub camera: Option<u32>,
    /// Indices of the materials that are index-matched boundaries.
    pub null_materials: Vec<u32>,
}
