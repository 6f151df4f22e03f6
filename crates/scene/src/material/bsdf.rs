//! The per-hit [`Bsdf`]: the public face of the materials, dispatching once to SmallVCM's
//! reference BSDF, to the plain Lambertian of a `diffuse` material (the most common one, built
//! without the mixture's machinery and bit-identical to it), or to the shading-normal mixture
//! of leaf models.

use math::Vec3;

use super::description::Material;
use super::diffuse_bsdf::DiffuseBsdf;
use super::mixture::ModelBsdf;
use super::query::{BsdfEval, BsdfSample};
use super::reference::ReferenceBsdf;
use super::shading::{ShadingPoint, TransportMode};

#[cfg(doc)]
use super::MAX_COMPONENTS;
#[cfg(doc)]
use math::COSINE_EPSILON;

/// A BSDF at one hit, for one fixed direction and transport mode.
///
/// Built by [`Bsdf::new`] at every path vertex; it holds no heap data (a blend keeps at most
/// [`MAX_COMPONENTS`] leaf materials inline), so building and copying it is cheap.
#[derive(Clone, Copy, Debug)]
pub struct Bsdf {
    inner: Inner,
}

// Boxing the larger variant would allocate at every path vertex.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Copy, Debug)]
enum Inner {
    Reference(ReferenceBsdf),
    Diffuse(DiffuseBsdf),
    Model(ModelBsdf),
}

impl Bsdf {
    /// Builds the BSDF at the shading point `point` for the unit `fixed` direction (pointing
    /// away from the surface). Textures are evaluated once, at `point.uv`. Returns `None` when
    /// the material cannot scatter for this fixed direction: all components black, the fixed
    /// direction grazing (geometric or shading cosine below [`COSINE_EPSILON`]), on different
    /// sides of the geometric and the shading normal, or behind a one-sided material.
    ///
    /// Inlined so that the caller's `Bsdf` is written in place: the model variant is several
    /// hundred bytes, and returning it through a call costs a copy of all of them at every
    /// vertex even for the small reference variant (measured: ~5 % of a BPT iteration).
    #[inline]
    pub fn new(material: &Material, point: &ShadingPoint, fixed: Vec3, mode: TransportMode) -> Option<Bsdf> {
        Self::new_at(material, point, fixed, mode, None)
    }

    /// [`Bsdf::new`] for a path traced at the hero wavelength `hero` (nm; `None` in RGB mode):
    /// dispersive dielectrics take their index at that wavelength, and their samples are marked
    /// [`BsdfSample::dispersive`].
    #[inline]
    pub fn new_at(
        material: &Material,
        point: &ShadingPoint,
        fixed: Vec3,
        mode: TransportMode,
        hero: Option<f32>,
    ) -> Option<Bsdf> {
        match material {
            Material::Reference(m) => {
                Some(Bsdf { inner: Inner::Reference(ReferenceBsdf::new(m, point.geometric_normal, fixed, mode)?) })
            }
            Material::Diffuse { reflectance } => {
                Some(Bsdf { inner: Inner::Diffuse(DiffuseBsdf::new(reflectance, point, fixed, mode)?) })
            }
            _ => Self::new_model(material, point, fixed, mode, hero),
        }
    }

    #[inline(never)]
    fn new_model(
        material: &Material,
        point: &ShadingPoint,
        fixed: Vec3,
        mode: TransportMode,
        hero: Option<f32>,
    ) -> Option<Bsdf> {
        ModelBsdf::build(material, point, fixed, mode, hero, |b| Bsdf { inner: Inner::Model(b) })
    }

    /// Probability of continuing a path through this vertex (Russian roulette): the largest
    /// per-channel albedo estimate for the fixed direction, at most 1. It enters the MIS pdfs
    /// as a factor.
    pub fn continuation_probability(&self) -> f32 {
        match &self.inner {
            Inner::Reference(b) => b.continuation_probability(),
            Inner::Diffuse(b) => b.continuation,
            Inner::Model(b) => b.continuation,
        }
    }

    /// True when every lobe with non-zero probability is a delta lobe, so that evaluation is
    /// always zero and the vertex cannot be connected to or merged at.
    pub fn is_delta(&self) -> bool {
        match &self.inner {
            Inner::Reference(b) => b.is_delta(),
            Inner::Diffuse(_) => false,
            Inner::Model(b) => b.non_delta_probability <= 0.0,
        }
    }

    /// The per-channel factor (unitless) by which light passes straight through this surface
    /// with its direction unchanged, when the material is such a *null* interface besides a
    /// delta reflection (Mitsuba 3's `Null` component: the thin dielectric, and blends of thin
    /// dielectrics): `transmittance · (1 − R')` of the fixed direction. `None` for every other
    /// material. The volumetric path tracer asks it only of plain `Material::ThinDielectric`
    /// surfaces (a cheap material test comes first, since every blocked shadow ray would
    /// otherwise build a BSDF): their shadow rays cross with this factor, and a sampled
    /// straight-through transmission of them is no vertex. Blends are not treated as null
    /// there, on either side, so the MIS weights stay consistent.
    pub fn null_transmission(&self) -> Option<spectrum::Rgb> {
        match &self.inner {
            Inner::Reference(_) | Inner::Diffuse(_) => None,
            Inner::Model(b) => b.null_transmission(),
        }
    }

    /// True when the BSDF has a specular (delta) lobe with non-zero selection probability.
    pub fn has_specular(&self) -> bool {
        match &self.inner {
            Inner::Reference(b) => b.has_specular(),
            Inner::Diffuse(_) => false,
            Inner::Model(b) => b.delta_probability > 0.0,
        }
    }

    /// The transport mode the BSDF was built for.
    pub fn mode(&self) -> TransportMode {
        match &self.inner {
            Inner::Reference(b) => b.mode,
            Inner::Diffuse(b) => b.at.mode,
            Inner::Model(b) => b.at.mode,
        }
    }

    /// `|cos θ|` of the fixed direction with the geometric normal.
    pub fn cos_fixed(&self) -> f32 {
        match &self.inner {
            Inner::Reference(b) => b.cos_fixed(),
            Inner::Diffuse(b) => b.at.cos_fixed_geometric.abs(),
            Inner::Model(b) => b.at.cos_fixed_geometric.abs(),
        }
    }

    /// The fixed direction in world space (unit length).
    pub fn fixed_direction(&self) -> Vec3 {
        match &self.inner {
            Inner::Reference(b) => b.fixed_direction(),
            Inner::Diffuse(b) => b.at.fixed,
            Inner::Model(b) => b.at.fixed,
        }
    }

    /// Evaluates the non-delta lobes for the unit world direction `generated`: the value in the
    /// geometric-normal formulation (see the module documentation), `|cos|` of `generated` with
    /// the geometric normal, and both solid-angle pdfs. Returns `None` when the value is zero
    /// (e.g. the other side of a one-sided material, a direction on different sides of the
    /// geometric and the shading normal, or a purely specular material).
    pub fn evaluate(&self, generated: Vec3) -> Option<BsdfEval> {
        match &self.inner {
            Inner::Reference(b) => b.evaluate(generated),
            Inner::Diffuse(b) => b.evaluate(generated),
            Inner::Model(b) => b.evaluate(generated),
        }
    }

    /// Samples a direction with three uniform numbers: `u[2]` picks the lobe, `u[0..2]` the
    /// direction within it (a rescaled `u[2]` makes further discrete choices). For a non-delta
    /// lobe, value and pdfs are those [`Bsdf::evaluate`] returns for the sampled direction
    /// (the pdf of the whole mixture); for a delta lobe, the pdfs are the probability of
    /// choosing it and the value is `ρ/cos_generated`. Returns `None` when the sample carries
    /// no energy (e.g. a microfacet reflection below the surface, which is rejected).
    pub fn sample(&self, u: [f32; 3]) -> Option<BsdfSample> {
        match &self.inner {
            Inner::Reference(b) => b.sample(u),
            Inner::Diffuse(b) => b.sample(u),
            Inner::Model(b) => b.sample(u, false),
        }
    }

    /// Samples only the specular (delta) lobes, chosen in proportion to their selection
    /// probabilities (`u[2]` picks the lobe). The pdfs are the probabilities of that restricted
    /// choice. Used where the non-specular part is estimated otherwise, e.g. photon mapping
    /// merges at a mixed vertex and continues through its specular part only. `None` when the
    /// material has no specular lobe.
    pub fn sample_specular(&self, u: [f32; 3]) -> Option<BsdfSample> {
        match &self.inner {
            Inner::Reference(b) => b.sample_specular(u),
            Inner::Diffuse(_) => None,
            Inner::Model(b) => b.sample(u, true),
        }
    }
}
