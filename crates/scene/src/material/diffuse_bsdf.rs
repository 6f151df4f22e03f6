//! The per-hit BSDF of a plain [`Material::Diffuse`] (Mitsuba's `diffuse`, pbrt's `diffuse`):
//! the mixture of [`super::mixture`] specialised to its one Lambertian leaf, without the
//! component arrays, the model dispatch and the lobe search.
//!
//! It computes the same floats as the mixture does for that material, operation for operation
//! (the blend scale, the component and lobe probabilities are all exactly 1 there, and
//! multiplying by 1 or adding to 0 is exact), so images are bit-identical to the general path:
//! `crates/scene/tests/diffuse_fast_path.rs` compares both on random geometry. The mixture
//! builds ~670 bytes per vertex and dispatches over every leaf model at each query; this
//! struct is ~100 bytes. Measured on Mitsuba's Cornell box (all `diffuse`), `pt`: see
//! docs/performance.md, "Per-sample cost on Mitsuba's scenes".

use math::{Frame, INV_PI, PdfW, Vec3, warp};
use spectrum::Rgb;

use super::description::Material;
use super::mixture::positive;
use super::query::{BsdfEval, BsdfSample, LobeKind, PdfPair};
use super::shading::{ShadingPoint, TransportMode, consistent, oriented_shading_normal, sides_allowed};
use crate::texture::TexturePoint;

/// A one-sided Lambertian BSDF `ρ/π` at one hit, for one fixed direction and transport mode.
/// Pdfs are solid-angle densities (1/sr) of the cosine-weighted hemisphere about the shading
/// normal.
#[derive(Clone, Copy, Debug)]
pub(super) struct DiffuseBsdf {
    /// Shading frame (z = shading normal, on the side of the geometric normal).
    frame: Frame,
    /// Unit geometric normal (world).
    geometric: Vec3,
    /// Unit fixed direction (world).
    pub(super) fixed: Vec3,
    /// Fixed direction in the shading frame.
    local_fixed: Vec3,
    /// Signed cosine of the fixed direction with the geometric normal.
    pub(super) cos_fixed_geometric: f32,
    pub(super) mode: TransportMode,
    /// Shading normal equal to the geometric normal: no shading-normal correction.
    flat: bool,
    /// Reflectance ρ at the hit.
    reflectance: Rgb,
    /// Russian-roulette continuation probability: the largest channel of ρ, at most 1.
    pub(super) continuation: f32,
}

impl DiffuseBsdf {
    /// The BSDF of `material` (which must be [`Material::Diffuse`]) at `point`; `None` where
    /// the mixture would return `None`: a grazing fixed direction, one on different sides of
    /// the geometric and the shading normal, behind the surface, or a black reflectance.
    #[inline]
    pub(super) fn new(material: &Material, point: &ShadingPoint, fixed: Vec3, mode: TransportMode) -> Option<Self> {
        let Material::Diffuse { reflectance } = material else { return None };
        let geometric = point.geometric_normal;
        let shading = oriented_shading_normal(point);
        let cos_fixed_geometric = fixed.dot(geometric);
        let flat = shading == geometric;
        let frame = ShadingPoint::frame(shading, point.tangent);
        let local_fixed = frame.to_local(fixed);
        // Lambertian is not relaxed (`LeafModel::follows_shading_normal` is false).
        if !sides_allowed(false, cos_fixed_geometric, local_fixed.z) {
            return None;
        }
        let reflectance = reflectance.eval_at(TexturePoint { uv: point.uv, attribute: point.attribute });
        // The mixture's component weight: 0 from behind (one-sided), else the luminance.
        let weight = if local_fixed.z <= 0.0 { 0.0 } else { reflectance.luminance() };
        if !positive(weight) {
            return None;
        }
        let continuation = reflectance.max_component().min(1.0);
        if !positive(continuation) {
            return None;
        }
        Some(Self { frame, geometric, fixed, local_fixed, cos_fixed_geometric, mode, flat, reflectance, continuation })
    }

    /// The shading-normal correction (as [`super::mixture`]'s `shading_factor`).
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

    /// `ρ/π` for the unit world direction `generated`, in the geometric-normal formulation,
    /// with both solid-angle pdfs; `None` below the surface or for an inconsistent direction.
    #[inline]
    pub(super) fn evaluate(&self, generated: Vec3) -> Option<BsdfEval> {
        let cos_geometric = generated.dot(self.geometric);
        let local = self.frame.to_local(generated);
        if !consistent(cos_geometric, local.z) || self.local_fixed.z <= 0.0 || local.z <= 0.0 {
            return None;
        }
        let value = self.reflectance * INV_PI;
        if value.is_black() || !value.is_finite() {
            return None;
        }
        Some(BsdfEval {
            value: value * self.shading_factor(local.z, cos_geometric),
            cos_generated: cos_geometric.abs(),
            pdf: PdfPair { forward: PdfW(local.z * INV_PI), reverse: PdfW(self.local_fixed.z * INV_PI) },
        })
    }

    /// A cosine-weighted direction from `u[0..2]` (`u[2]` is unused: one lobe).
    #[inline]
    pub(super) fn sample(&self, u: [f32; 3]) -> Option<BsdfSample> {
        let local = warp::cosine_hemisphere([u[0], u[1]]);
        let direction = self.frame.to_world(local).normalize();
        let eval = self.evaluate(direction)?;
        if !positive(eval.pdf.forward.0) {
            return None;
        }
        Some(BsdfSample {
            direction,
            value: eval.value,
            cos_generated: eval.cos_generated,
            pdf: eval.pdf,
            lobe: LobeKind::Diffuse,
            dispersive: false,
        })
    }
}
