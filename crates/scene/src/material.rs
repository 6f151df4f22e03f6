//! Materials and the per-hit BSDF built from them.
//!
//! A [`Bsdf`] is built per hit from the [`Material`], the [`ShadingPoint`] (geometric and
//! shading normal, uv), the *fixed* direction (the one the walk arrived from, pointing away from
//! the surface) and the [`TransportMode`]. Every query takes the *generated* direction and
//! returns both pdfs: `forward` (fixed → generated) and `reverse` (generated → fixed), in solid
//! angle, including the lobe-selection probabilities (the reverse one with the probabilities
//! the BSDF would use if the generated direction were the fixed one). Russian roulette is
//! **not** included in these pdfs; the integrator multiplies them by
//! [`Bsdf::continuation_probability`]. Specular (delta) lobes use "pdf = probability of picking
//! the lobe" and value `ρ/|cos θ|` (tech report eq. 52).
//!
//! **SmallVCM's material** ([`Material::Reference`]) is a sum of Lambertian diffuse, normalised
//! Phong, a perfect mirror and, when `ior ≥ 0`, a smooth dielectric. It uses the geometric
//! normal only. Diffuse and Phong are one-sided: zero unless both directions lie at least
//! [`COSINE_EPSILON`] above the surface on the side the normal points to; mirror and glass work
//! from both sides.
//!
//! **The Mitsuba models** (every other variant) are oriented by the shading normal, while the
//! sides of the surface (reflection or transmission) are decided by the geometric normal
//! (Veach 1997, §5.3). A direction on different sides of the two tangent planes, or within
//! [`COSINE_EPSILON`] of either, scatters nothing. All cosines the integrators see are
//! geometric, so the value returned is the effective BSDF of the geometric-normal formulation:
//! with `f_s` the BSDF in the shading frame,
//!
//! - radiance mode: `value = f_s(fixed, generated) · |generated·Ns| / |generated·Ng|`,
//! - importance mode: `value = f_s(generated, fixed) · |fixed·Ns| / |fixed·Ng|` (the adjoint),
//!
//! so that the radiance value for (a, b) equals the importance value for (b, a). Refraction
//! carries `(η_fixed/η_generated)²` in radiance mode and not in importance mode. Diffuse,
//! conductors and plastics are one-sided (black from behind, as in Mitsuba; wrap them in
//! [`Material::TwoSided`]); the dielectrics work from both sides. The anisotropic GGX
//! roughness is aligned with the tangent of `Frame::from_z(shading normal)` (shading points
//! carry no surface tangent).
//!
//! Deviations from Mitsuba: the rough plastic uses the smooth Fresnel transmittance
//! `1 − F(cos θ)` in place of Mitsuba's precomputed rough transmittance tables, and the smooth
//! internal diffuse reflectance `Fdr(1/η)` in place of the rough one; the plastics'
//! specular sampling weight uses the texture values at the hit instead of the textures' means;
//! a blend chooses its parts in proportion to blend weight × the luminance of the part's
//! largest reflectance factor (Mitsuba: the blend weight alone).

use math::{COSINE_EPSILON, Frame, INV_PI, PdfW, Vec2, Vec3, sqr, warp};

use crate::microfacet::{Ggx, fresnel_conductor_rgb, fresnel_diffuse_reflectance, refract};
use crate::texture::Texture;
use spectrum::Rgb;
use spectrum::fluorescence::Fluorescence;
use spectrum::ior::Ior;

/// Below this cosine between the generated direction and the mirrored fixed direction, the
/// Phong lobe is zero.
const PHONG_COSINE_EPSILON: f32 = 1e-3;

/// SmallVCM's material as a sum of components (all reflectances in `[0, 1]` per channel): the
/// material of the built-in reference scenes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReferenceMaterial {
    /// Lambertian reflectance ρd.
    pub diffuse: Rgb,
    /// Phong reflectance ρs.
    pub phong: Rgb,
    /// Phong exponent n.
    pub phong_exponent: f32,
    /// Mirror reflectance ρm (Fresnel-weighted when `ior ≥ 0`).
    pub mirror: Rgb,
    /// Relative index of refraction inside/outside; negative means "no refraction".
    pub ior: f32,
}

impl ReferenceMaterial {
    /// A material that absorbs everything (used for emitters).
    pub const BLACK: ReferenceMaterial = ReferenceMaterial {
        diffuse: Rgb::BLACK,
        phong: Rgb::BLACK,
        phong_exponent: 1.0,
        mirror: Rgb::BLACK,
        ior: -1.0,
    };

    /// Pure Lambertian reflector.
    pub const fn diffuse(rho: Rgb) -> Self {
        ReferenceMaterial { diffuse: rho, ..Self::BLACK }
    }
}

/// A material: the closed set of scattering models the renderer knows. Index-of-refraction
/// fields are absolute (`int_ior` inside, `ext_ior` outside, the side the geometric normal
/// points to); `alpha` is the GGX roughness (`α = roughness²` in the Disney convention, as
/// Mitsuba's `alpha`). Conductors take the complex IOR `eta + i·k` relative to the outside.
#[derive(Clone, Debug, PartialEq)]
pub enum Material {
    /// SmallVCM's component material (built-in scenes).
    Reference(ReferenceMaterial),
    /// Lambertian, one-sided (black from behind, as Mitsuba's `diffuse`).
    Diffuse {
        /// Reflectance.
        reflectance: Texture,
    },
    /// Smooth conductor (Fresnel-weighted mirror); `eta = 0, k = ∞`-like perfect mirrors use
    /// [`Material::perfect_mirror`].
    Conductor {
        /// Real part of the relative IOR per channel.
        eta: Rgb,
        /// Imaginary part (absorption) per channel.
        k: Rgb,
        /// Factor on the reflection.
        specular_reflectance: Texture,
    },
    /// GGX microfacet conductor with visible-normal sampling.
    RoughConductor {
        /// Roughness along the tangent.
        alpha_u: f32,
        /// Roughness along the bitangent.
        alpha_v: f32,
        /// Real part of the relative IOR per channel.
        eta: Rgb,
        /// Imaginary part per channel.
        k: Rgb,
        /// Factor on the reflection.
        specular_reflectance: Texture,
    },
    /// Smooth dielectric interface (Fresnel reflection + refraction).
    Dielectric {
        /// IOR inside (in RGB mode, and in spectral mode without `dispersion`).
        int_ior: f32,
        /// IOR outside.
        ext_ior: f32,
        /// Factor on reflection.
        specular_reflectance: Texture,
        /// Factor on transmission.
        specular_transmittance: Texture,
        /// Wavelength-dependent IOR inside, used in spectral mode instead of `int_ior` (at the
        /// hero wavelength; the path then continues at the hero wavelength only).
        dispersion: Option<Ior>,
    },
    /// Thin dielectric sheet: reflection and straight-through transmission with the
    /// inter-reflections of a thin slab summed analytically.
    ThinDielectric {
        /// IOR of the sheet.
        int_ior: f32,
        /// IOR around it.
        ext_ior: f32,
        /// Factor on reflection.
        specular_reflectance: Texture,
        /// Factor on transmission.
        specular_transmittance: Texture,
    },
    /// GGX microfacet dielectric (Walter et al. 2007).
    RoughDielectric {
        /// Roughness along the tangent.
        alpha_u: f32,
        /// Roughness along the bitangent.
        alpha_v: f32,
        /// IOR inside.
        int_ior: f32,
        /// IOR outside.
        ext_ior: f32,
        /// Factor on reflection.
        specular_reflectance: Texture,
        /// Factor on transmission.
        specular_transmittance: Texture,
    },
    /// Diffuse base under a smooth dielectric coating (Mitsuba's `plastic`).
    Plastic {
        /// Reflectance of the base.
        diffuse_reflectance: Texture,
        /// Factor on the coating's specular reflection.
        specular_reflectance: Texture,
        /// IOR of the coating.
        int_ior: f32,
        /// IOR outside.
        ext_ior: f32,
        /// Account for colour shifts from internal scattering (Mitsuba's `nonlinear`).
        nonlinear: bool,
    },
    /// Diffuse base under a rough (GGX) dielectric coating (Mitsuba's `roughplastic`).
    RoughPlastic {
        /// Isotropic GGX roughness of the coating.
        alpha: f32,
        /// Reflectance of the base.
        diffuse_reflectance: Texture,
        /// Factor on the coating's specular reflection.
        specular_reflectance: Texture,
        /// IOR of the coating.
        int_ior: f32,
        /// IOR outside.
        ext_ior: f32,
        /// Account for colour shifts from internal scattering.
        nonlinear: bool,
    },
    /// Linear blend `(1 − weight)·first + weight·second`.
    Blend {
        /// Blend weight in [0, 1] (the first channel of the texture is used).
        weight: Texture,
        /// Material at weight 0.
        first: Box<Material>,
        /// Material at weight 1.
        second: Box<Material>,
    },
    /// Lambertian with fluorescence (one-sided): the diagonal reflectance `reflectance` plus
    /// the re-emission of [`Fluorescence`]. The BSDF is the diffuse part; integrators apply
    /// the wavelength shift (a top-level material only: not inside blends or two-sided).
    Fluorescent {
        /// Ordinary (diagonal) reflectance.
        reflectance: Texture,
        /// Absorption and re-emission.
        fluorescence: Fluorescence,
    },
    /// Makes a one-sided material two-sided: seen from behind it behaves as `back` (or as
    /// `front` when `back` is `None`) with the normal flipped.
    TwoSided {
        /// Material on the front side.
        front: Box<Material>,
        /// Material on the back side; `None` = the same as the front.
        back: Option<Box<Material>>,
    },
}

impl Material {
    /// A perfect mirror (Mitsuba's `conductor` without a material).
    pub fn perfect_mirror() -> Self {
        Material::Conductor { eta: Rgb::BLACK, k: Rgb::BLACK, specular_reflectance: Texture::Constant(Rgb::WHITE) }
    }
}

impl Material {
    /// Number of leaf materials (blends and two-sided wrappers count what they contain; a
    /// two-sided material with a distinct back counts both sides).
    pub fn leaf_count(&self) -> usize {
        match self {
            Material::Blend { first, second, .. } => first.leaf_count() + second.leaf_count(),
            Material::TwoSided { front, back } => front.leaf_count() + back.as_ref().map_or(0, |b| b.leaf_count()),
            _ => 1,
        }
    }

    /// The fluorescence of a (top-level) fluorescent material.
    #[inline]
    pub fn fluorescence(&self) -> Option<&Fluorescence> {
        match self {
            Material::Fluorescent { fluorescence, .. } => Some(fluorescence),
            _ => None,
        }
    }

    /// Whether this material, or one it blends or wraps, has a wavelength-dependent index of
    /// refraction (a dielectric with `dispersion`).
    pub fn is_dispersive(&self) -> bool {
        match self {
            Material::Dielectric { dispersion, .. } => dispersion.is_some_and(|ior| ior.is_dispersive()),
            Material::Blend { first, second, .. } => first.is_dispersive() || second.is_dispersive(),
            Material::TwoSided { front, back } => {
                front.is_dispersive() || back.as_ref().is_some_and(|b| b.is_dispersive())
            }
            _ => false,
        }
    }

    /// Whether a fluorescent material is nested inside a blend or a two-sided material.
    fn nests_fluorescence(&self) -> bool {
        match self {
            Material::Blend { first, second, .. } => {
                first.fluorescence().is_some()
                    || second.fluorescence().is_some()
                    || first.nests_fluorescence()
                    || second.nests_fluorescence()
            }
            Material::TwoSided { front, back } => {
                front.fluorescence().is_some()
                    || front.nests_fluorescence()
                    || back.as_ref().is_some_and(|b| b.fluorescence().is_some() || b.nests_fluorescence())
            }
            _ => false,
        }
    }

    /// Checks what a BSDF can represent: at most [`MAX_COMPONENTS`] leaves per side, fluorescent
    /// materials only at the top level and conserving energy.
    pub fn validate(&self) -> Result<(), String> {
        if self.nests_fluorescence() {
            return Err("a fluorescent material cannot be blended or made two-sided".into());
        }
        if let Material::Fluorescent { reflectance, fluorescence } = self {
            fluorescence.check_energy(reflectance.max_value().max_component())?;
        }
        let per_side = |m: &Material| m.leaf_count();
        let largest = match self {
            Material::TwoSided { front, back } => per_side(front).max(back.as_ref().map_or(0, |b| per_side(b))),
            m => per_side(m),
        };
        if largest > MAX_COMPONENTS {
            return Err(format!(
                "a blend of {largest} materials; at most {MAX_COMPONENTS} can be blended (nest fewer blendbsdfs)"
            ));
        }
        Ok(())
    }
}

impl From<ReferenceMaterial> for Material {
    fn from(m: ReferenceMaterial) -> Self {
        Material::Reference(m)
    }
}

/// The local geometry at a surface point that a BSDF needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadingPoint {
    /// Unit geometric normal (defines the sides of the surface and all cosines the
    /// integrators use).
    pub geometric_normal: Vec3,
    /// Unit shading normal (interpolated mesh normal; equal to the geometric normal
    /// otherwise). BSDF lobes are oriented by it.
    pub shading_normal: Vec3,
    /// Texture coordinates.
    pub uv: Vec2,
}

impl ShadingPoint {
    /// A point whose shading normal is its geometric normal, at uv (0, 0).
    pub fn flat(normal: Vec3) -> Self {
        Self { geometric_normal: normal, shading_normal: normal, uv: Vec2::ZERO }
    }
}

/// Which quantity a sub-path carries. The adjoint BSDF differs for refraction.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TransportMode {
    /// Camera sub-paths: radiance flows towards the fixed direction.
    Radiance,
    /// Light sub-paths: importance flows towards the fixed direction.
    Importance,
}

/// Which kind of lobe produced a sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LobeKind {
    /// Lambertian.
    Diffuse,
    /// Non-delta glossy reflection (normalised Phong, microfacet reflection).
    Glossy,
    /// Non-delta glossy transmission (microfacet refraction).
    GlossyTransmission,
    /// Perfect reflection (delta).
    SpecularReflection,
    /// Perfect refraction (delta).
    SpecularTransmission,
}

impl LobeKind {
    /// True for the delta lobes.
    pub fn is_specular(self) -> bool {
        matches!(self, LobeKind::SpecularReflection | LobeKind::SpecularTransmission)
    }
}

/// Forward and reverse solid-angle pdfs of one direction pair.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PdfPair {
    /// Density of generating the generated direction given the fixed one.
    pub forward: PdfW,
    /// Density of generating the fixed direction given the generated one.
    pub reverse: PdfW,
}

/// Result of [`Bsdf::evaluate`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfEval {
    /// BSDF value f (per steradian), without the cosine; see the module documentation for the
    /// shading-normal form.
    pub value: Rgb,
    /// `|cos θ|` of the generated direction with the geometric normal.
    pub cos_generated: f32,
    /// Lobe-selection-weighted solid-angle pdfs of the non-specular lobes.
    pub pdf: PdfPair,
}

/// Result of [`Bsdf::sample`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample {
    /// The generated unit direction (world space, pointing away from the surface).
    pub direction: Vec3,
    /// BSDF value f (see the module documentation); for specular lobes `ρ/|cos θ|`.
    pub value: Rgb,
    /// `|cos θ|` of the generated direction with the geometric normal.
    pub cos_generated: f32,
    /// Solid-angle pdfs (of the whole non-delta mixture, as [`Bsdf::evaluate`] returns); for
    /// specular lobes the lobe-selection probability.
    pub pdf: PdfPair,
    /// The lobe that was sampled.
    pub lobe: LobeKind,
    /// A delta lobe of a dispersive dielectric at the hero wavelength: the other wavelengths
    /// cannot take this direction, so the path continues at the hero wavelength only.
    pub dispersive: bool,
}

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
        Some(Bsdf { inner: Inner::Model(ModelBsdf::new(material, point, fixed, mode, hero)?) })
    }

    /// Probability of continuing a path through this vertex (Russian roulette): the largest
    /// per-channel albedo estimate for the fixed direction, at most 1. It enters the MIS pdfs
    /// as a factor.
    pub fn continuation_probability(&self) -> f32 {
        match &self.inner {
            Inner::Reference(b) => b.continuation_probability(),
            Inner::Model(b) => b.continuation,
        }
    }

    /// True when every lobe with non-zero probability is a delta lobe, so that evaluation is
    /// always zero and the vertex cannot be connected to or merged at.
    pub fn is_delta(&self) -> bool {
        match &self.inner {
            Inner::Reference(b) => b.is_delta(),
            Inner::Model(b) => b.non_delta_probability <= 0.0,
        }
    }

    /// True when the BSDF has a specular (delta) lobe with non-zero selection probability.
    pub fn has_specular(&self) -> bool {
        match &self.inner {
            Inner::Reference(b) => b.has_specular(),
            Inner::Model(b) => b.delta_probability > 0.0,
        }
    }

    /// The transport mode the BSDF was built for.
    pub fn mode(&self) -> TransportMode {
        match &self.inner {
            Inner::Reference(b) => b.mode,
            Inner::Model(b) => b.mode,
        }
    }

    /// `|cos θ|` of the fixed direction with the geometric normal.
    pub fn cos_fixed(&self) -> f32 {
        match &self.inner {
            Inner::Reference(b) => b.cos_fixed(),
            Inner::Model(b) => b.cos_fixed_geometric.abs(),
        }
    }

    /// The fixed direction in world space (unit length).
    pub fn fixed_direction(&self) -> Vec3 {
        match &self.inner {
            Inner::Reference(b) => b.fixed_direction(),
            Inner::Model(b) => b.fixed,
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
            Inner::Model(b) => b.sample(u, true),
        }
    }
}

/// Largest number of leaf materials a (nested) [`Material::Blend`] may combine (two levels of
/// blends fit). [`Material::validate`] rejects more, and scenes are validated when they are
/// built, so a BSDF never drops a leaf.
pub const MAX_COMPONENTS: usize = 4;

/// The BSDF of every material but [`Material::Reference`]: a weighted sum of leaf models
/// (more than one only for blends), oriented by the shading normal.
#[derive(Clone, Copy, Debug)]
struct ModelBsdf {
    /// Shading frame (z = shading normal, flipped to the side of the geometric normal).
    frame: Frame,
    /// Unit geometric normal (world).
    geometric: Vec3,
    /// Unit fixed direction (world).
    fixed: Vec3,
    /// Fixed direction in the shading frame.
    local_fixed: Vec3,
    /// Signed cosine of the fixed direction with the geometric normal.
    cos_fixed_geometric: f32,
    mode: TransportMode,
    /// Shading normal equal to the geometric normal: no shading-normal correction.
    flat: bool,
    continuation: f32,
    /// Total selection probability of the non-delta lobes.
    non_delta_probability: f32,
    /// Total selection probability of the delta lobes.
    delta_probability: f32,
    count: usize,
    components: [Component; MAX_COMPONENTS],
}

/// One leaf material of a [`ModelBsdf`].
#[derive(Clone, Copy, Debug)]
struct Component {
    model: Model,
    /// Product of the blend weights on the way to this leaf.
    scale: f32,
    /// Probability of choosing this component when sampling (independent of the directions).
    probability: f32,
    /// 1, or −1 for the back side of a two-sided material (the local z axis is mirrored).
    side: f32,
    /// Selection probabilities of the model's lobes for the fixed direction (not including
    /// `probability`).
    lobes: [f32; 2],
}

impl Component {
    /// Unnormalised probability of choosing this component when `w` (in the model's frame) is
    /// the fixed direction: blend weight times the model's selection weight, 0 from behind a
    /// one-sided model.
    #[inline]
    fn selection_weight(&self, w: Vec3) -> f32 {
        if self.model.one_sided() && w.z <= 0.0 { 0.0 } else { self.scale * self.model.selection_weight() }
    }

    /// Shading-frame coordinates → the model's coordinates (and back: the map is its own
    /// inverse).
    #[inline]
    fn orient(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.x, v.y, v.z * self.side)
    }
}

/// A leaf scattering model with its textures evaluated, in a local frame whose z axis is the
/// (possibly flipped) shading normal. One-sided models scatter only for `fixed.z > 0`.
#[derive(Clone, Copy, Debug)]
enum Model {
    /// Lambertian: `ρ/π`.
    Diffuse { reflectance: Rgb },
    /// Fresnel-weighted mirror.
    Conductor { eta: Rgb, k: Rgb, specular: Rgb },
    /// GGX microfacet conductor.
    RoughConductor { ggx: Ggx, eta: Rgb, k: Rgb, specular: Rgb },
    /// Smooth dielectric; `eta` = inside over outside (at the hero wavelength when
    /// `dispersive`).
    Dielectric { eta: f32, reflectance: Rgb, transmittance: Rgb, dispersive: bool },
    /// Thin sheet; `eta` = sheet over surroundings.
    ThinDielectric { eta: f32, reflectance: Rgb, transmittance: Rgb },
    /// GGX microfacet dielectric; `eta` = inside over outside.
    RoughDielectric { ggx: Ggx, eta: f32, reflectance: Rgb, transmittance: Rgb },
    /// Smooth coating over a diffuse base.
    Plastic(Coating),
    /// GGX coating over a diffuse base.
    RoughPlastic { ggx: Ggx, coating: Coating },
}

/// The parameters shared by the smooth and the rough plastic.
#[derive(Clone, Copy, Debug)]
struct Coating {
    /// Coating over outside.
    eta: f32,
    /// Base reflectance (for the albedo estimate).
    diffuse: Rgb,
    /// `ρd / (1 − Fdr_int) / (η² π)` (linear) or `ρd / (1 − ρd Fdr_int) / (η² π)` (nonlinear):
    /// the diffuse BSDF before the two Fresnel transmittances.
    diffuse_bsdf: Rgb,
    /// Factor on the coating reflection.
    specular: Rgb,
    /// Mitsuba's `specular_sampling_weight` = mean(specular) / (mean(diffuse) + mean(specular)).
    specular_weight: f32,
}

impl Coating {
    fn new(diffuse: Rgb, specular: Rgb, int_ior: f32, ext_ior: f32, nonlinear: bool) -> Self {
        let eta = relative_ior(int_ior, ext_ior);
        let fdr_int = fresnel_diffuse_reflectance(1.0 / eta);
        let denominator = if nonlinear { Rgb::WHITE - diffuse * fdr_int } else { Rgb::splat(1.0 - fdr_int) };
        let scale = INV_PI / sqr(eta);
        let diffuse_bsdf = Rgb::new(
            safe_divide(diffuse.r, denominator.r),
            safe_divide(diffuse.g, denominator.g),
            safe_divide(diffuse.b, denominator.b),
        ) * scale;
        let (d, s) = (diffuse.average(), specular.average());
        let specular_weight = if d + s > 0.0 { s / (d + s) } else { 0.5 };
        Coating { eta, diffuse, diffuse_bsdf, specular, specular_weight }
    }

    /// Probabilities of [specular, diffuse] for a direction with local cosine `cos` (Mitsuba:
    /// in proportion to `F·w` and `(1 − F)(1 − w)` with `w` the specular sampling weight).
    fn lobe_probabilities(&self, cos: f32) -> [f32; 2] {
        let f = fresnel_dielectric(cos.abs(), self.eta);
        let specular = f * self.specular_weight;
        let diffuse = (1.0 - f) * (1.0 - self.specular_weight);
        let total = specular + diffuse;
        if total > 0.0 { [specular / total, diffuse / total] } else { [0.5, 0.5] }
    }

    /// The diffuse part of the BSDF, `diffuse_bsdf (1 − F(fixed)) (1 − F(generated))`.
    fn diffuse_value(&self, fixed: Vec3, generated: Vec3) -> Rgb {
        let t_fixed = 1.0 - fresnel_dielectric(fixed.z, self.eta);
        let t_generated = 1.0 - fresnel_dielectric(generated.z, self.eta);
        self.diffuse_bsdf * (t_fixed * t_generated)
    }

    /// Albedo estimate `F·specular + (1 − F)·diffuse` for a direction with local cosine `cos`.
    fn albedo(&self, cos: f32) -> Rgb {
        let f = fresnel_dielectric(cos, self.eta);
        self.specular * f + self.diffuse * (1.0 - f)
    }
}

/// `a / b`, or 0 when `b` is not positive.
#[inline]
fn safe_divide(a: f32, b: f32) -> f32 {
    if b > 0.0 { a / b } else { 0.0 }
}

/// `int_ior / ext_ior`, or 1 when that is not a positive finite number.
fn relative_ior(int_ior: f32, ext_ior: f32) -> f32 {
    let eta = int_ior / ext_ior;
    if eta.is_finite() && eta > 0.0 { eta } else { 1.0 }
}

/// What a model's sampler produced, in the model's local frame.
enum Sampled {
    /// A direction from a non-delta lobe; value and pdfs come from evaluation.
    Lobe { direction: Vec3, lobe: LobeKind },
    /// A delta lobe: the direction and the effective reflectance `ρ` (the value times the local
    /// shading cosine of the direction), already in the transport mode's form.
    Delta { direction: Vec3, rho: Rgb, lobe: LobeKind },
}

/// Value and the two pdfs (without the component's selection probability) of one model.
#[derive(Clone, Copy, Default)]
struct ModelEval {
    value: Rgb,
    forward: f32,
    reverse: f32,
}

/// Mirror direction about the local z axis.
#[inline]
fn mirror_local(v: Vec3) -> Vec3 {
    Vec3::new(-v.x, -v.y, v.z)
}

/// The thin sheet's reflectance with the inter-reflections summed: `R + T²R/(1 − R²)`.
fn thin_reflectance(cos: f32, eta: f32) -> f32 {
    let r = fresnel_dielectric(cos.abs(), eta);
    if r < 1.0 {
        let t = 1.0 - r;
        r + sqr(t) * r / (1.0 - sqr(r))
    } else {
        1.0
    }
}

impl Model {
    /// The leaf model of a non-blend, non-two-sided material with its textures at `uv`.
    fn from_leaf(material: &Material, uv: Vec2, hero: Option<f32>) -> Option<Model> {
        let model = match material {
            Material::Reference(_) | Material::Blend { .. } | Material::TwoSided { .. } => return None,
            Material::Diffuse { reflectance } => Model::Diffuse { reflectance: reflectance.eval(uv) },
            // Unit reflectance: the integrators apply the diagonal reflectance and the
            // re-emission themselves.
            Material::Fluorescent { .. } => Model::Diffuse { reflectance: Rgb::WHITE },
            Material::Conductor { eta, k, specular_reflectance } => {
                Model::Conductor { eta: *eta, k: *k, specular: specular_reflectance.eval(uv) }
            }
            Material::RoughConductor { alpha_u, alpha_v, eta, k, specular_reflectance } => Model::RoughConductor {
                ggx: Ggx::new(*alpha_u, *alpha_v),
                eta: *eta,
                k: *k,
                specular: specular_reflectance.eval(uv),
            },
            Material::Dielectric { int_ior, ext_ior, specular_reflectance, specular_transmittance, dispersion } => {
                let (int_ior, dispersive) = match (dispersion, hero) {
                    (Some(ior), Some(lambda)) => (ior.eval(lambda), true),
                    _ => (*int_ior, false),
                };
                Model::Dielectric {
                    eta: relative_ior(int_ior, *ext_ior),
                    reflectance: specular_reflectance.eval(uv),
                    transmittance: specular_transmittance.eval(uv),
                    dispersive,
                }
            }
            Material::ThinDielectric { int_ior, ext_ior, specular_reflectance, specular_transmittance } => {
                Model::ThinDielectric {
                    eta: relative_ior(*int_ior, *ext_ior),
                    reflectance: specular_reflectance.eval(uv),
                    transmittance: specular_transmittance.eval(uv),
                }
            }
            Material::RoughDielectric {
                alpha_u,
                alpha_v,
                int_ior,
                ext_ior,
                specular_reflectance,
                specular_transmittance,
            } => Model::RoughDielectric {
                ggx: Ggx::new(*alpha_u, *alpha_v),
                eta: relative_ior(*int_ior, *ext_ior),
                reflectance: specular_reflectance.eval(uv),
                transmittance: specular_transmittance.eval(uv),
            },
            Material::Plastic { diffuse_reflectance, specular_reflectance, int_ior, ext_ior, nonlinear } => {
                Model::Plastic(Coating::new(
                    diffuse_reflectance.eval(uv),
                    specular_reflectance.eval(uv),
                    *int_ior,
                    *ext_ior,
                    *nonlinear,
                ))
            }
            Material::RoughPlastic {
                alpha,
                diffuse_reflectance,
                specular_reflectance,
                int_ior,
                ext_ior,
                nonlinear,
            } => Model::RoughPlastic {
                ggx: Ggx::new(*alpha, *alpha),
                coating: Coating::new(
                    diffuse_reflectance.eval(uv),
                    specular_reflectance.eval(uv),
                    *int_ior,
                    *ext_ior,
                    *nonlinear,
                ),
            },
        };
        Some(model)
    }

    /// True for the models that scatter only from the front (`fixed.z > 0`).
    fn one_sided(&self) -> bool {
        !matches!(self, Model::Dielectric { .. } | Model::ThinDielectric { .. } | Model::RoughDielectric { .. })
    }

    /// Whether lobe `i` is a delta lobe.
    fn lobe_is_delta(&self, i: usize) -> bool {
        match self {
            Model::Conductor { .. } | Model::Dielectric { .. } | Model::ThinDielectric { .. } => true,
            Model::Plastic(_) => i == 0,
            _ => false,
        }
    }

    /// Selection probabilities of the (up to two) lobes when `w` is the fixed direction.
    fn lobe_probabilities(&self, w: Vec3) -> [f32; 2] {
        match self {
            Model::Dielectric { eta, .. } => {
                let f = fresnel_dielectric(w.z, *eta);
                [f, 1.0 - f]
            }
            Model::ThinDielectric { eta, .. } => {
                let r = thin_reflectance(w.z, *eta);
                [r, 1.0 - r]
            }
            Model::Plastic(c) | Model::RoughPlastic { coating: c, .. } => c.lobe_probabilities(w.z),
            _ => [1.0, 0.0],
        }
    }

    /// Weight of the model when a blend chooses among its components (direction independent):
    /// the luminance of its largest reflectance factor.
    fn selection_weight(&self) -> f32 {
        match self {
            Model::Diffuse { reflectance } => reflectance.luminance(),
            Model::Conductor { specular, .. } | Model::RoughConductor { specular, .. } => specular.luminance(),
            Model::Dielectric { reflectance, transmittance, .. }
            | Model::ThinDielectric { reflectance, transmittance, .. }
            | Model::RoughDielectric { reflectance, transmittance, .. } => {
                reflectance.luminance().max(transmittance.luminance())
            }
            Model::Plastic(c) | Model::RoughPlastic { coating: c, .. } => {
                c.specular.luminance().max(c.diffuse.luminance())
            }
        }
        .max(0.0)
    }

    /// Per-channel albedo estimate for the fixed direction `w` (for Russian roulette).
    fn albedo(&self, w: Vec3) -> Rgb {
        if self.one_sided() && w.z <= 0.0 {
            return Rgb::BLACK;
        }
        match self {
            Model::Diffuse { reflectance } => *reflectance,
            Model::Conductor { eta, k, specular } | Model::RoughConductor { eta, k, specular, .. } => {
                fresnel_conductor_rgb(w.z, *eta, *k) * *specular
            }
            Model::Dielectric { eta, reflectance, transmittance, .. }
            | Model::RoughDielectric { eta, reflectance, transmittance, .. } => {
                let f = fresnel_dielectric(w.z, *eta);
                *reflectance * f + *transmittance * (1.0 - f)
            }
            Model::ThinDielectric { eta, reflectance, transmittance } => {
                let r = thin_reflectance(w.z, *eta);
                *reflectance * r + *transmittance * (1.0 - r)
            }
            Model::Plastic(c) | Model::RoughPlastic { coating: c, .. } => c.albedo(w.z),
        }
    }

    /// The non-delta part for the local directions `fixed` and `generated`: the BSDF in the
    /// shading frame (`f_s(fixed, generated)` in radiance mode, `f_s(generated, fixed)` in
    /// importance mode), the density of generating `generated` from `fixed` with the lobe
    /// probabilities `p_fixed`, and that of generating `fixed` from `generated` with
    /// `p_generated`.
    fn evaluate(
        &self,
        fixed: Vec3,
        generated: Vec3,
        mode: TransportMode,
        p_fixed: [f32; 2],
        p_generated: [f32; 2],
    ) -> ModelEval {
        match self {
            Model::Conductor { .. } | Model::Dielectric { .. } | Model::ThinDielectric { .. } => ModelEval::default(),
            Model::Diffuse { reflectance } => {
                if fixed.z <= 0.0 || generated.z <= 0.0 {
                    return ModelEval::default();
                }
                ModelEval {
                    value: *reflectance * INV_PI,
                    forward: p_fixed[0] * generated.z * INV_PI,
                    reverse: p_generated[0] * fixed.z * INV_PI,
                }
            }
            Model::RoughConductor { ggx, eta, k, specular } => {
                if fixed.z <= 0.0 || generated.z <= 0.0 {
                    return ModelEval::default();
                }
                let m = (fixed + generated).normalize();
                let d = ggx.d(m);
                if d <= 0.0 || !m.is_finite() {
                    return ModelEval::default();
                }
                let f = fresnel_conductor_rgb(fixed.dot(m), *eta, *k);
                let g = ggx.g(fixed, generated, m);
                ModelEval {
                    value: *specular * f * (d * g / (4.0 * fixed.z * generated.z)),
                    forward: p_fixed[0] * ggx.g1(fixed, m) * d / (4.0 * fixed.z),
                    reverse: p_generated[0] * ggx.g1(generated, m) * d / (4.0 * generated.z),
                }
            }
            Model::RoughDielectric { ggx, eta, reflectance, transmittance } => {
                rough_dielectric_evaluate(ggx, *eta, *reflectance, *transmittance, fixed, generated, mode)
            }
            Model::Plastic(c) => {
                if fixed.z <= 0.0 || generated.z <= 0.0 {
                    return ModelEval::default();
                }
                ModelEval {
                    value: c.diffuse_value(fixed, generated),
                    forward: p_fixed[1] * generated.z * INV_PI,
                    reverse: p_generated[1] * fixed.z * INV_PI,
                }
            }
            Model::RoughPlastic { ggx, coating: c } => {
                if fixed.z <= 0.0 || generated.z <= 0.0 {
                    return ModelEval::default();
                }
                let mut e = ModelEval {
                    value: c.diffuse_value(fixed, generated),
                    forward: p_fixed[1] * generated.z * INV_PI,
                    reverse: p_generated[1] * fixed.z * INV_PI,
                };
                let m = (fixed + generated).normalize();
                let d = ggx.d(m);
                if d > 0.0 && m.is_finite() {
                    let f = fresnel_dielectric(fixed.dot(m), c.eta);
                    let g = ggx.g(fixed, generated, m);
                    e.value += c.specular * (f * d * g / (4.0 * fixed.z * generated.z));
                    e.forward += p_fixed[0] * ggx.g1(fixed, m) * d / (4.0 * fixed.z);
                    e.reverse += p_generated[0] * ggx.g1(generated, m) * d / (4.0 * generated.z);
                }
                e
            }
        }
    }

    /// Samples lobe `lobe` for the local `fixed` direction with `u[0..2]` (direction) and
    /// `u[2]` (any further discrete choice).
    fn sample(&self, fixed: Vec3, lobe: usize, u: [f32; 3], mode: TransportMode) -> Option<Sampled> {
        if self.one_sided() && fixed.z <= 0.0 {
            return None;
        }
        let cosine = || Sampled::Lobe { direction: warp::cosine_hemisphere([u[0], u[1]]), lobe: LobeKind::Diffuse };
        let glossy = |ggx: &Ggx| {
            let m = ggx.sample_visible(fixed, [u[0], u[1]]);
            Sampled::Lobe { direction: micro_reflect(fixed, m), lobe: LobeKind::Glossy }
        };
        let mirror =
            |rho: Rgb| Sampled::Delta { direction: mirror_local(fixed), rho, lobe: LobeKind::SpecularReflection };
        Some(match self {
            Model::Diffuse { .. } => cosine(),
            Model::Conductor { eta, k, specular } => mirror(fresnel_conductor_rgb(fixed.z, *eta, *k) * *specular),
            Model::RoughConductor { ggx, .. } => glossy(ggx),
            Model::Dielectric { eta, reflectance, transmittance, .. } => {
                let f = fresnel_dielectric(fixed.z, *eta);
                if lobe == 0 {
                    mirror(*reflectance * f)
                } else {
                    // η on the fixed side over η on the generated side.
                    let ratio = if fixed.z > 0.0 { 1.0 / *eta } else { *eta };
                    let sin_t2 = sqr(ratio) * (1.0 - sqr(fixed.z)).max(0.0);
                    if sin_t2 >= 1.0 {
                        return None;
                    }
                    let cos_t = (1.0 - sin_t2).sqrt();
                    let direction = Vec3::new(-ratio * fixed.x, -ratio * fixed.y, -cos_t.copysign(fixed.z));
                    let scale = match mode {
                        TransportMode::Radiance => (1.0 - f) * sqr(ratio),
                        TransportMode::Importance => 1.0 - f,
                    };
                    Sampled::Delta { direction, rho: *transmittance * scale, lobe: LobeKind::SpecularTransmission }
                }
            }
            Model::ThinDielectric { eta, reflectance, transmittance } => {
                let r = thin_reflectance(fixed.z, *eta);
                if lobe == 0 {
                    mirror(*reflectance * r)
                } else {
                    Sampled::Delta {
                        direction: -fixed,
                        rho: *transmittance * (1.0 - r),
                        lobe: LobeKind::SpecularTransmission,
                    }
                }
            }
            Model::RoughDielectric { ggx, eta, .. } => {
                // Work with the fixed direction on the +z side; `e` = η far side / η near side.
                let (side, e) = if fixed.z > 0.0 { (1.0, *eta) } else { (-1.0, 1.0 / *eta) };
                let up = Vec3::new(fixed.x, fixed.y, fixed.z * side);
                let m = ggx.sample_visible(up, [u[0], u[1]]);
                let cos_m = up.dot(m);
                if cos_m <= 0.0 {
                    return None;
                }
                let f = fresnel_dielectric(cos_m, e);
                let (direction, lobe) = if u[2] < f {
                    (micro_reflect(up, m), LobeKind::Glossy)
                } else {
                    (refract(up, m, e)?, LobeKind::GlossyTransmission)
                };
                // A reflection below or a refraction above the macro surface is rejected
                // (evaluation would read it as the other kind of event).
                if (lobe == LobeKind::Glossy) != (direction.z > 0.0) || direction.z == 0.0 {
                    return None;
                }
                Sampled::Lobe { direction: Vec3::new(direction.x, direction.y, direction.z * side), lobe }
            }
            Model::Plastic(c) => {
                if lobe == 0 {
                    mirror(c.specular * fresnel_dielectric(fixed.z, c.eta))
                } else {
                    cosine()
                }
            }
            Model::RoughPlastic { ggx, .. } => {
                if lobe == 0 {
                    glossy(ggx)
                } else {
                    cosine()
                }
            }
        })
    }
}

/// Reflection of `w` about the microfacet normal `m`.
#[inline]
fn micro_reflect(w: Vec3, m: Vec3) -> Vec3 {
    crate::microfacet::reflect(w, m)
}

/// The rough dielectric (Walter et al. 2007, with visible-normal sampling) for local
/// directions on either side.
fn rough_dielectric_evaluate(
    ggx: &Ggx,
    eta: f32,
    reflectance: Rgb,
    transmittance: Rgb,
    fixed: Vec3,
    generated: Vec3,
    mode: TransportMode,
) -> ModelEval {
    if fixed.z == 0.0 || generated.z == 0.0 {
        return ModelEval::default();
    }
    // Mirror so that the fixed direction is on +z; `e` = η on the far side / η on the fixed side.
    let (side, e) = if fixed.z > 0.0 { (1.0, eta) } else { (-1.0, 1.0 / eta) };
    let flip = |v: Vec3| Vec3::new(v.x, v.y, v.z * side);
    let (a, b) = (flip(fixed), flip(generated));
    let Some(h) = RoughPair::new(ggx, a, b, e) else { return ModelEval::default() };
    let value = if h.reflection {
        reflectance * (h.fresnel * h.d * ggx.g(a, b, h.m) / (4.0 * a.z * b.z.abs()))
    } else {
        let core = (h.cos_a * h.cos_b).abs() * (1.0 - h.fresnel) * h.d * ggx.g(a, b, h.m)
            / ((a.z * b.z).abs() * sqr(h.cos_a + e * h.cos_b));
        // Radiance: f_s(fixed → generated) ∝ η_fixed²; importance: the adjoint, ∝ η_generated².
        match mode {
            TransportMode::Radiance => transmittance * core,
            TransportMode::Importance => transmittance * (core * sqr(e)),
        }
    };
    let forward = h.density(ggx, a, e);
    // The reverse density: the same pair seen from the generated side.
    let (side_b, e_b) = if generated.z > 0.0 { (1.0, eta) } else { (-1.0, 1.0 / eta) };
    let flip_b = |v: Vec3| Vec3::new(v.x, v.y, v.z * side_b);
    let reverse = RoughPair::new(ggx, flip_b(generated), flip_b(fixed), e_b)
        .map_or(0.0, |r| r.density(ggx, flip_b(generated), e_b));
    ModelEval { value, forward, reverse }
}

/// The half vector of a pair of directions `a` (on +z) and `b` at a rough dielectric interface
/// with relative index `e` (far side over `a`'s side), and what depends on it.
struct RoughPair {
    reflection: bool,
    /// Microfacet normal, on +z.
    m: Vec3,
    d: f32,
    fresnel: f32,
    cos_a: f32,
    cos_b: f32,
}

impl RoughPair {
    fn new(ggx: &Ggx, a: Vec3, b: Vec3, e: f32) -> Option<RoughPair> {
        let reflection = b.z > 0.0;
        let sum = if reflection { a + b } else { a + e * b };
        let m = sum.normalize();
        if !m.is_finite() {
            return None;
        }
        let m = if m.z < 0.0 { -m } else { m };
        let (cos_a, cos_b) = (a.dot(m), b.dot(m));
        // Both directions must lie on the same side of the microfacet as of the macro surface.
        if cos_a <= 0.0 || cos_b * b.z <= 0.0 {
            return None;
        }
        let d = ggx.d(m);
        if d <= 0.0 {
            return None;
        }
        Some(RoughPair { reflection, m, d, fresnel: fresnel_dielectric(cos_a, e), cos_a, cos_b })
    }

    /// Density of sampling `b` from `a`: the visible-normal density times the Fresnel choice
    /// times the Jacobian of the reflection or refraction map.
    fn density(&self, ggx: &Ggx, a: Vec3, e: f32) -> f32 {
        let visible = ggx.g1(a, self.m) * self.cos_a * self.d / a.z;
        if self.reflection {
            self.fresnel * visible / (4.0 * self.cos_a)
        } else {
            (1.0 - self.fresnel) * visible * sqr(e) * self.cos_b.abs() / sqr(self.cos_a + e * self.cos_b)
        }
    }
}

impl ModelBsdf {
    fn new(
        material: &Material,
        point: &ShadingPoint,
        fixed: Vec3,
        mode: TransportMode,
        hero: Option<f32>,
    ) -> Option<ModelBsdf> {
        let geometric = point.geometric_normal;
        // The shading normal on the side of the geometric normal (a degenerate one is replaced
        // by the geometric normal).
        let mut shading = point.shading_normal;
        let cos_normals = shading.dot(geometric);
        if cos_normals.abs() < 1e-4 || cos_normals.is_nan() || !shading.is_finite() {
            shading = geometric;
        } else if cos_normals < 0.0 {
            shading = -shading;
        }
        let flat = shading == geometric;
        let frame = Frame::from_z(shading);
        let cos_fixed_geometric = fixed.dot(geometric);
        let local_fixed = frame.to_local(fixed);
        if !consistent(cos_fixed_geometric, local_fixed.z) {
            return None;
        }
        let empty = Component {
            model: Model::Diffuse { reflectance: Rgb::BLACK },
            scale: 0.0,
            probability: 0.0,
            side: 1.0,
            lobes: [0.0; 2],
        };
        let mut bsdf = ModelBsdf {
            frame,
            geometric,
            fixed,
            local_fixed,
            cos_fixed_geometric,
            mode,
            flat,
            continuation: 0.0,
            non_delta_probability: 0.0,
            delta_probability: 0.0,
            count: 0,
            components: [empty; MAX_COMPONENTS],
        };
        bsdf.add(material, point.uv, 1.0, 1.0, hero);

        let mut total_weight = 0.0;
        let mut albedo = Rgb::BLACK;
        for c in &mut bsdf.components[..bsdf.count] {
            let w = c.orient(local_fixed);
            c.lobes = c.model.lobe_probabilities(w);
            albedo += c.model.albedo(w) * c.scale;
            c.probability = c.selection_weight(w);
            total_weight += c.probability;
        }
        if !positive(total_weight) {
            return None;
        }
        for c in &mut bsdf.components[..bsdf.count] {
            c.probability /= total_weight;
            for (i, p) in c.lobes.iter().enumerate() {
                if c.model.lobe_is_delta(i) {
                    bsdf.delta_probability += c.probability * p;
                } else {
                    bsdf.non_delta_probability += c.probability * p;
                }
            }
        }
        bsdf.continuation = albedo.max_component().min(1.0);
        if !positive(bsdf.continuation) {
            return None;
        }
        Some(bsdf)
    }

    /// Adds the leaves of `material` with blend weight `scale`, on side `side`.
    fn add(&mut self, material: &Material, uv: Vec2, scale: f32, side: f32, hero: Option<f32>) {
        if !positive(scale) {
            return;
        }
        match material {
            Material::Blend { weight, first, second } => {
                let w = weight.eval(uv).r;
                let w = if w.is_nan() { 0.0 } else { w.clamp(0.0, 1.0) };
                self.add(first, uv, scale * (1.0 - w), side, hero);
                self.add(second, uv, scale * w, side, hero);
            }
            Material::TwoSided { front, back } => {
                if self.local_fixed.z * side < 0.0 {
                    self.add(back.as_deref().unwrap_or(front), uv, scale, -side, hero);
                } else {
                    self.add(front, uv, scale, side, hero);
                }
            }
            leaf => {
                if self.count < MAX_COMPONENTS
                    && let Some(model) = Model::from_leaf(leaf, uv, hero)
                {
                    self.components[self.count] = Component { model, scale, probability: 0.0, side, lobes: [0.0; 2] };
                    self.count += 1;
                }
            }
        }
    }

    /// The factor that turns the shading-frame BSDF into the value in the geometric-normal
    /// formulation, for a generated direction with shading cosine `cos_shading` and geometric
    /// cosine `cos_geometric`.
    #[inline]
    fn shading_factor(&self, cos_shading: f32, cos_geometric: f32) -> f32 {
        if self.flat {
            return 1.0;
        }
        match self.mode {
            TransportMode::Radiance => (cos_shading / cos_geometric).abs(),
            TransportMode::Importance => (self.local_fixed.z / self.cos_fixed_geometric).abs(),
        }
    }

    fn evaluate(&self, generated: Vec3) -> Option<BsdfEval> {
        if self.non_delta_probability <= 0.0 {
            return None;
        }
        let cos_geometric = generated.dot(self.geometric);
        let local = self.frame.to_local(generated);
        if !consistent(cos_geometric, local.z) {
            return None;
        }
        // Component probabilities when the generated direction is the fixed one (they differ
        // from the stored ones only by the one-sided components, which do not scatter from
        // behind).
        let mut reverse_total = 0.0;
        if self.count > 1 {
            for c in &self.components[..self.count] {
                reverse_total += c.selection_weight(c.orient(local));
            }
        }
        let mut value = Rgb::BLACK;
        let mut pdf = PdfPair::default();
        for c in &self.components[..self.count] {
            let fixed = c.orient(self.local_fixed);
            let generated = c.orient(local);
            let p_generated = c.model.lobe_probabilities(generated);
            let e = c.model.evaluate(fixed, generated, self.mode, c.lobes, p_generated);
            value += e.value * c.scale;
            pdf.forward.0 += c.probability * e.forward;
            let reverse_probability = if self.count == 1 {
                1.0
            } else if reverse_total > 0.0 {
                c.selection_weight(generated) / reverse_total
            } else {
                0.0
            };
            pdf.reverse.0 += reverse_probability * e.reverse;
        }
        if value.is_black() || !value.is_finite() {
            return None;
        }
        Some(BsdfEval {
            value: value * self.shading_factor(local.z, cos_geometric),
            cos_generated: cos_geometric.abs(),
            pdf,
        })
    }

    /// Samples a lobe (all lobes, or only the delta lobes when `specular_only`).
    fn sample(&self, u: [f32; 3], specular_only: bool) -> Option<BsdfSample> {
        let total = if specular_only { self.delta_probability } else { 1.0 };
        if !positive(total) {
            return None;
        }
        // Walk the lobes with u[2]; keep the last candidate for rounding at the end.
        let mut pick = u[2] * total;
        let mut chosen = None;
        'search: for (index, c) in self.components[..self.count].iter().enumerate() {
            for (lobe, p) in c.lobes.iter().enumerate() {
                let probability = c.probability * p;
                if !positive(probability) || (specular_only && !c.model.lobe_is_delta(lobe)) {
                    continue;
                }
                chosen = Some((index, lobe, probability, pick));
                if pick < probability {
                    break 'search;
                }
                pick -= probability;
            }
        }
        let (index, lobe, probability, pick) = chosen?;
        let c = &self.components[index];
        let rescaled = (pick / probability).clamp(0.0, ONE_MINUS_EPSILON);
        let sampled = c.model.sample(c.orient(self.local_fixed), lobe, [u[0], u[1], rescaled], self.mode)?;
        match sampled {
            Sampled::Lobe { direction, lobe } => {
                let direction = self.frame.to_world(c.orient(direction)).normalize();
                let eval = self.evaluate(direction)?;
                if !positive(eval.pdf.forward.0) {
                    return None;
                }
                Some(BsdfSample {
                    direction,
                    value: eval.value,
                    cos_generated: eval.cos_generated,
                    pdf: eval.pdf,
                    lobe,
                    dispersive: false,
                })
            }
            Sampled::Delta { direction, rho, lobe } => {
                let local = c.orient(direction);
                let world = self.frame.to_world(local).normalize();
                let cos_geometric = world.dot(self.geometric);
                if !consistent(cos_geometric, local.z) || rho.is_black() {
                    return None;
                }
                let value = rho * (c.scale * self.shading_factor(local.z, cos_geometric) / local.z.abs());
                let pdf = PdfW(probability / total);
                Some(BsdfSample {
                    direction: world,
                    value,
                    cos_generated: cos_geometric.abs(),
                    pdf: PdfPair { forward: pdf, reverse: pdf },
                    lobe,
                    dispersive: matches!(c.model, Model::Dielectric { dispersive: true, .. }),
                })
            }
        }
    }
}

/// `x > 0` (false for NaN).
#[inline]
fn positive(x: f32) -> bool {
    x > 0.0
}

/// Whether a direction with geometric cosine `cos_geometric` and shading cosine
/// `cos_shading` lies on the same side of both tangent planes, neither grazing (below
/// [`COSINE_EPSILON`]).
#[inline]
fn consistent(cos_geometric: f32, cos_shading: f32) -> bool {
    cos_geometric * cos_shading > 0.0 && cos_geometric.abs() >= COSINE_EPSILON && cos_shading.abs() >= COSINE_EPSILON
}

/// The largest `f32` below 1.
const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// Lobe selection probabilities, proportional to each lobe's albedo (luminance).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct LobeProbabilities {
    diffuse: f32,
    phong: f32,
    reflect: f32,
    refract: f32,
}

/// SmallVCM's BSDF (the [`Material::Reference`] case), built on the geometric normal only.
#[derive(Clone, Copy, Debug)]
struct ReferenceBsdf {
    material: ReferenceMaterial,
    frame: Frame,
    local_fixed: Vec3,
    mode: TransportMode,
    probabilities: LobeProbabilities,
    fresnel: f32,
    continuation: f32,
}

/// Unpolarised Fresnel reflectance of a smooth dielectric with relative IOR `ior` (inside over
/// outside) for a direction with cosine `cos_incident` to the outward normal (negative: the
/// direction is inside). Returns 1 for total internal reflection and for `ior < 0`.
pub fn fresnel_dielectric(cos_incident: f32, ior: f32) -> f32 {
    if ior < 0.0 {
        return 1.0;
    }
    let (cos_i, eta) = if cos_incident < 0.0 { (-cos_incident, ior) } else { (cos_incident, 1.0 / ior) };
    // eta = η_incident / η_transmitted.
    let sin_t2 = sqr(eta) * (1.0 - sqr(cos_i)).max(0.0);
    if sin_t2 >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin_t2).sqrt();
    let r_parallel = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let r_perpendicular = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    0.5 * (sqr(r_parallel) + sqr(r_perpendicular))
}

/// `x^n` for the Phong exponent: repeated squaring for integer exponents (the usual case,
/// several times faster than `powf`), `powf` otherwise.
#[inline]
fn pow_exponent(x: f32, n: f32) -> f32 {
    if n.fract() == 0.0 && (0.0..=4096.0).contains(&n) { x.powi(n as i32) } else { x.powf(n) }
}

impl ReferenceBsdf {
    #[inline]
    fn new(material: &ReferenceMaterial, normal: Vec3, fixed: Vec3, mode: TransportMode) -> Option<ReferenceBsdf> {
        let frame = Frame::from_z(normal);
        let local_fixed = frame.to_local(fixed);
        if local_fixed.z.abs() < COSINE_EPSILON {
            return None;
        }
        let fresnel = fresnel_dielectric(local_fixed.z, material.ior);
        let albedo_diffuse = material.diffuse.luminance();
        let albedo_phong = material.phong.luminance();
        let albedo_reflect = fresnel * material.mirror.luminance();
        let albedo_refract = if material.ior > 0.0 { 1.0 - fresnel } else { 0.0 };
        let total = albedo_diffuse + albedo_phong + albedo_reflect + albedo_refract;
        if total < 1e-9 {
            return None;
        }
        let probabilities = LobeProbabilities {
            diffuse: albedo_diffuse / total,
            phong: albedo_phong / total,
            reflect: albedo_reflect / total,
            refract: albedo_refract / total,
        };
        // Russian roulette keeps the path with the largest per-channel albedo, so a path's
        // weight never grows through the roulette (refraction has weight 1 − F).
        let refract_weight = if material.ior > 0.0 { 1.0 - fresnel } else { 0.0 };
        let continuation =
            ((material.diffuse + material.phong + material.mirror * fresnel).max_component() + refract_weight).min(1.0);
        Some(ReferenceBsdf { material: *material, frame, local_fixed, mode, probabilities, fresnel, continuation })
    }

    /// Probability of continuing a path through this vertex (Russian roulette). It enters the
    /// MIS pdfs as a factor.
    fn continuation_probability(&self) -> f32 {
        self.continuation
    }

    /// True when every lobe with non-zero probability is a delta lobe, so that evaluation is
    /// always zero and the vertex cannot be connected to or merged at.
    fn is_delta(&self) -> bool {
        self.probabilities.diffuse == 0.0 && self.probabilities.phong == 0.0
    }

    /// `|cos θ|` of the fixed direction with the geometric normal.
    fn cos_fixed(&self) -> f32 {
        self.local_fixed.z.abs()
    }

    /// The fixed direction in world space.
    fn fixed_direction(&self) -> Vec3 {
        self.frame.to_world(self.local_fixed)
    }

    /// Evaluates the non-specular lobes for the unit world direction `generated`. Returns
    /// `None` when the value is zero (other side of the surface, below a one-sided lobe, or a
    /// purely specular material).
    fn evaluate(&self, generated: Vec3) -> Option<BsdfEval> {
        let local_generated = self.frame.to_local(generated);
        if local_generated.z * self.local_fixed.z <= 0.0 {
            return None;
        }
        let mut value = Rgb::BLACK;
        let mut pdf = PdfPair::default();
        self.add_non_delta(local_generated, &mut value, &mut pdf);
        if value.is_black() {
            return None;
        }
        Some(BsdfEval { value, cos_generated: local_generated.z.abs(), pdf })
    }

    /// Samples a direction with three uniform numbers: `u[2]` picks the lobe (in proportion to
    /// the lobe albedos), `u[0..2]` the direction within it. Returns `None` when the sample
    /// carries no energy (e.g. a Phong direction below the surface, which is rejected rather
    /// than continued through the surface).
    fn sample(&self, u: [f32; 3]) -> Option<BsdfSample> {
        let p = self.probabilities;
        let pick = u[2];
        if pick < p.diffuse + p.phong {
            let local = if pick < p.diffuse {
                if self.local_fixed.z < COSINE_EPSILON {
                    return None;
                }
                warp::cosine_hemisphere([u[0], u[1]])
            } else {
                let lobe_axis = self.reflected_fixed();
                Frame::from_z(lobe_axis).to_world(warp::power_cosine([u[0], u[1]], self.material.phong_exponent))
            };
            // Evaluate the world direction exactly as `evaluate` would, so that a sample and
            // the evaluation of its direction always agree (also at the horizon).
            let direction = self.frame.to_world(local);
            let eval = self.evaluate(direction)?;
            if eval.pdf.forward.0 <= 0.0 {
                return None;
            }
            let lobe = if pick < p.diffuse { LobeKind::Diffuse } else { LobeKind::Glossy };
            return Some(BsdfSample {
                direction,
                value: eval.value,
                cos_generated: eval.cos_generated,
                pdf: eval.pdf,
                lobe,
                dispersive: false,
            });
        }
        if pick < p.diffuse + p.phong + p.reflect {
            return Some(self.sample_reflection(p.reflect));
        }
        self.sample_refraction(p.refract)
    }

    /// Samples only the specular (delta) lobes, chosen in proportion to their albedos among
    /// themselves (`u[2]` picks the lobe). The pdfs are the probabilities of that restricted
    /// choice. Used where the non-specular part is estimated otherwise, e.g. photon mapping
    /// merges at a mixed vertex and continues through its specular part only. `None` when the
    /// material has no specular lobe.
    fn sample_specular(&self, u: [f32; 3]) -> Option<BsdfSample> {
        let p = self.probabilities;
        let specular = p.reflect + p.refract;
        if specular <= 0.0 {
            return None;
        }
        if u[2] * specular < p.reflect {
            Some(self.sample_reflection(p.reflect / specular))
        } else {
            self.sample_refraction(p.refract / specular)
        }
    }

    /// True when the material has a specular (delta) lobe.
    fn has_specular(&self) -> bool {
        self.probabilities.reflect + self.probabilities.refract > 0.0
    }

    /// The mirror lobe, chosen with probability `probability`.
    fn sample_reflection(&self, probability: f32) -> BsdfSample {
        let local = self.reflected_fixed();
        let cos = local.z.abs();
        BsdfSample {
            direction: self.frame.to_world(local),
            value: self.material.mirror * (self.fresnel / cos),
            cos_generated: cos,
            pdf: PdfPair { forward: PdfW(probability), reverse: PdfW(probability) },
            lobe: LobeKind::SpecularReflection,
            dispersive: false,
        }
    }

    /// The fixed direction mirrored about the normal, in local coordinates.
    fn reflected_fixed(&self) -> Vec3 {
        Vec3::new(-self.local_fixed.x, -self.local_fixed.y, self.local_fixed.z)
    }

    /// Adds diffuse and Phong values and their selection-weighted pdfs for a local direction.
    fn add_non_delta(&self, local_generated: Vec3, value: &mut Rgb, pdf: &mut PdfPair) {
        let p = self.probabilities;
        let fixed = self.local_fixed;
        if fixed.z < COSINE_EPSILON || local_generated.z < COSINE_EPSILON {
            return;
        }
        if p.diffuse > 0.0 {
            *value += self.material.diffuse * INV_PI;
            pdf.forward.0 += p.diffuse * warp::cosine_hemisphere_pdf(local_generated.z);
            pdf.reverse.0 += p.diffuse * warp::cosine_hemisphere_pdf(fixed.z);
        }
        if p.phong > 0.0 {
            let cos_alpha = self.reflected_fixed().dot(local_generated);
            if cos_alpha > PHONG_COSINE_EPSILON {
                let n = self.material.phong_exponent;
                let lobe = pow_exponent(cos_alpha, n);
                *value += self.material.phong * ((n + 2.0) * 0.5 * INV_PI * lobe);
                // The lobe around reflect(fixed) evaluated at generated has the same cosine
                // as the lobe around reflect(generated) evaluated at fixed.
                let density = p.phong * (n + 1.0) * 0.5 * INV_PI * lobe;
                pdf.forward.0 += density;
                pdf.reverse.0 += density;
            }
        }
    }

    /// The refraction lobe, chosen with probability `probability`; `None` under total internal
    /// reflection or without a dielectric.
    fn sample_refraction(&self, probability: f32) -> Option<BsdfSample> {
        if probability <= 0.0 {
            return None;
        }
        let fixed = self.local_fixed;
        // eta = η on the fixed side / η on the generated side.
        let (eta, sign) = if fixed.z > 0.0 { (1.0 / self.material.ior, -1.0) } else { (self.material.ior, 1.0) };
        let sin_t2 = sqr(eta) * (1.0 - sqr(fixed.z)).max(0.0);
        if sin_t2 >= 1.0 {
            return None;
        }
        let cos_t = (1.0 - sin_t2).sqrt();
        let local = Vec3::new(-eta * fixed.x, -eta * fixed.y, sign * cos_t);
        let transmit = 1.0 - self.fresnel;
        // Radiance is compressed by (η_fixed/η_generated)² when it crosses into the denser
        // medium towards the camera; importance is not (Veach 1997, §5.2).
        let scale = match self.mode {
            TransportMode::Radiance => transmit * sqr(eta),
            TransportMode::Importance => transmit,
        };
        Some(BsdfSample {
            direction: self.frame.to_world(local),
            value: Rgb::splat(scale / cos_t),
            cos_generated: cos_t,
            pdf: PdfPair { forward: PdfW(probability), reverse: PdfW(probability) },
            lobe: LobeKind::SpecularTransmission,
            dispersive: false,
        })
    }
}
