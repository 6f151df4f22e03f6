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
//! [`Material::TwoSided`]); the dielectrics work from both sides. An anisotropic roughness's
//! `alpha_u` lies along ∂p/∂u made orthogonal to the shading normal
//! ([`ShadingPoint::tangent`], Mitsuba's shading frame); isotropic models use the frame of
//! `Frame::from_z(shading normal)`. The rough models take a GGX or Beckmann distribution
//! ([`crate::microfacet::Microfacet`]); the rough plastic weighs its base by the rough
//! coating's transmittance and internal reflectance, tabulated by quadrature as Mitsuba does
//! (`rough_coating`).
//!
//! Deviations from Mitsuba: the plastics' specular sampling weight uses the texture values at the hit instead of the textures' means;
//! a blend chooses its parts in proportion to blend weight × the luminance of the part's
//! largest reflectance factor (Mitsuba: the blend weight alone).
//!
//! # Layout: one file per model
//!
//! Each leaf model lives in its own file with its evaluated parameters, evaluation, sampling,
//! forward and reverse solid-angle pdfs, lobe probabilities, albedo (the continuation
//! probability is the largest channel of the blended albedo, taken in `mixture`):
//! `diffuse`, `diffuse_transmission`, `conductor`, `rough_conductor`, `dielectric`,
//! `thin_dielectric`, `rough_dielectric`, `plastic`, `rough_plastic` (these two share
//! `coating`; the rough one's tables are in `rough_coating`), `principled` and
//! `principled_thin` (sharing `disney`; the clearcoat lobe in `clearcoat`), pbrt-v4's coated
//! materials in `coated` (parameters in `coated_parameters`, pbrt's random walk in
//! `layered_walk` over the pieces in `layered_interfaces`), the hair fibre model of Chiang et al.
//! 2016 in `hair` (its 1-D functions in `hair_functions`), and
//! SmallVCM's `reference` material, which keeps its own BSDF. Shared helpers have their own
//! files: `fresnel`, `lobe` (sample/evaluation records), `shading` (shading point,
//! transport mode, side tests, shading frame), GGX and Beckmann in [`crate::microfacet`].
//! `dispatch` holds the one closed
//! enum over the leaf models; `mixture` builds a BSDF from blends and two-sided wrappers;
//! `bsdf` is the public per-hit [`Bsdf`]; `description` the [`Material`] enum loaders build.
//!
//! Normal and bump maps (`normal_map`, `bump_map`, dispatched in `perturb`) are not BSDFs but
//! perturbations of the shading normal, which the scene applies when it builds a hit; their
//! BSDF is the nested material's, with Mitsuba's per-query adapter (`map_adapter`: the normal
//! mirrored for a camera-side direction below it, and a shadowing factor on the light side).
//!
//! **Adding a model** is one new file (a struct implementing `dispatch::LeafModel`), one arm in
//! `dispatch::Model` and in its `each_model!` macro, the `from_leaf` arm, the [`Material`]
//! variant, and the loader lines.

#[cfg(doc)]
use math::COSINE_EPSILON;

mod attributes;
mod bsdf;
mod bump_map;
mod clearcoat;
mod coated;
mod coated_parameters;
mod coating;
mod conductor;
mod description;
mod dielectric;
mod diffuse;
mod diffuse_bsdf;
mod diffuse_transmission;
mod disney;
mod dispatch;
mod flags;
mod fresnel;
mod hair;
mod hair_functions;
mod layered_interfaces;
mod layered_walk;
mod lobe;
mod map_adapter;
mod mixture;
mod normal_map;
mod perturb;
mod plastic;
mod principled;
mod principled_thin;
mod query;
mod reference;
mod rough_coating;
mod rough_conductor;
mod rough_dielectric;
mod rough_plastic;
mod shading;
mod thin_dielectric;

pub use bsdf::Bsdf;
pub use bump_map::luminance_gradient;
pub use coated_parameters::{CoatedBase, CoatedParameters, CoatingInterface, CoatingLayer, ConductorIor};
pub use description::Material;
pub use flags::MaterialFlags;
pub use fresnel::fresnel_dielectric;
pub use hair::{EUMELANIN_SIGMA_A, HairParameters, PHEOMELANIN_SIGMA_A};
pub use map_adapter::MapOptions;
pub use perturb::SurfaceTangents;
pub use principled::PrincipledParameters;
pub use principled_thin::PrincipledThinParameters;
pub use query::{BsdfEval, BsdfSample, LobeKind, PdfPair};
pub use reference::ReferenceMaterial;
pub use shading::{ShadingPoint, TransportMode};

/// Largest number of leaf materials a (nested) [`Material::Blend`] may combine (two levels of
/// blends fit). [`Material::validate`] rejects more, and scenes are validated when they are
/// built, so a BSDF never drops a leaf.
pub const MAX_COMPONENTS: usize = 4;
