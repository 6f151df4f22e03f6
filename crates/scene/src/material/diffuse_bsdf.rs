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

use math::{INV_PI, PdfW, Vec3, warp};
use spectrum::Rgb;

#[cfg(doc)]
use super::description::Material;
use super::mixture::positive;
use super::query::{BsdfEval, BsdfSample, LobeKind, PdfPair};
use super::shading::{FixedFrame, ShadingPoint, TransportMode, consistent, oriented_shading_normal, sides_allowed};
use crate::texture::{Texture, TexturePoint};

/// A one-sided Lambertian BSDF `ρ/π` at one hit, for one fixed direction and transport mode.
/// Pdfs are solid-angle densities (1/sr) of the cosine-weighted hemisphere about the shading
/// normal.
#[derive(Clone, Copy, Debug)]
pub(super) struct DiffuseBsdf {
    /// Shading frame, geometric normal and fixed direction.
    pub(super) at: FixedFrame,
    /// Reflectance ρ at the hit.
    reflectance: Rgb,
    /// Russian-roulette continuation probability: the largest channel of ρ, at most 1.
    pub(super) continuation: f32,
}

impl DiffuseBsdf {
    /// The BSDF of a [`Material::Diffuse`] with `reflectance` at `point`; `None` where the
    /// mixture would return `None`: a grazing fixed direction, one on different sides of the
    /// geometric and the shading normal, behind the surface, or a black reflectance.
    #[inline]
    pub(super) fn new(reflectance: &Texture, point: &ShadingPoint, fixed: Vec3, mode: TransportMode) -> Option<Self> {
        // Read first, so that no part of the frame is live across a texture call (the value is
        // the same whether or not the checks below refuse the point).
        let reflectance = reflectance.eval_at(TexturePoint { uv: point.uv, attribute: point.attribute });
        let at = FixedFrame::new(point, oriented_shading_normal(point), fixed, mode);
        // Lambertian is not relaxed (`LeafModel::follows_shading_normal` is false).
        if !sides_allowed(false, at.cos_fixed_geometric, at.local_fixed.z) {
            return None;
        }
        // The mixture's component weight: 0 from behind (one-sided), else the luminance.
        let weight = if at.local_fixed.z <= 0.0 { 0.0 } else { reflectance.luminance() };
        if !positive(weight) {
            return None;
        }
        let continuation = reflectance.max_component().min(1.0);
        if !positive(continuation) {
            return None;
        }
        Some(Self { at, reflectance, continuation })
    }

    /// `ρ/π` for the unit world direction `generated`, in the geometric-normal formulation,
    /// with both solid-angle pdfs; `None` below the surface or for an inconsistent direction.
    #[inline]
    pub(super) fn evaluate(&self, generated: Vec3) -> Option<BsdfEval> {
        let cos_geometric = generated.dot(self.at.geometric);
        let local = self.at.frame.to_local(generated);
        // (`local_fixed.z > 0` holds: `new` refuses a fixed direction from behind.)
        if !consistent(cos_geometric, local.z) || local.z <= 0.0 {
            return None;
        }
        let value = self.reflectance * INV_PI;
        if value.is_black() || !value.is_finite() {
            return None;
        }
        Some(BsdfEval {
            value: value * self.at.shading_factor(local.z, cos_geometric),
            cos_generated: cos_geometric.abs(),
            pdf: PdfPair { forward: PdfW(local.z * INV_PI), reverse: PdfW(self.at.local_fixed.z * INV_PI) },
        })
    }

    /// A cosine-weighted direction from `u[0..2]` (`u[2]` is unused: one lobe).
    #[inline]
    pub(super) fn sample(&self, u: [f32; 3]) -> Option<BsdfSample> {
        let local = warp::cosine_hemisphere([u[0], u[1]]);
        let direction = self.at.frame.to_world(local).normalize();
        BsdfSample::of_lobe(direction, self.evaluate(direction)?, LobeKind::Diffuse)
    }
}
