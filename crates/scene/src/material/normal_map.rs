//! Mitsuba's `normalmap`: a nested material whose shading normal is read from a texture of
//! tangent-space normals. A texel `v` ∈ [0, 1]³ (raw, linear data) encodes the normal `2v − 1`
//! in the shading frame `(s, t, n)` of [`SurfaceTangents::shading_frame`] (`s` along ∂p/∂u).
//! The BSDF is the nested material's with the perturbed normal (see [`super::perturb`]).

use math::Vec3;

use super::perturb::SurfaceTangents;
use crate::texture::Texture;

/// The normalised perturbed normal `frame · (2·normals(uv) − 1)` (world space; it may point
/// away from the geometric normal's side, which the BSDF then flips).
pub(super) fn perturb(normals: &Texture, tangents: &SurfaceTangents) -> Vec3 {
    let v = normals.eval(tangents.uv);
    let local = Vec3::new(2.0 * v.r - 1.0, 2.0 * v.g - 1.0, 2.0 * v.b - 1.0);
    tangents.shading_frame().to_world(local).normalize()
}
