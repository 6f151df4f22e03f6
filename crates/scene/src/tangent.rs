//! Surface differentials ∂p/∂u and ∂p/∂v at a hit, for materials that perturb the shading
//! normal (normal and bump maps) or orient an anisotropic roughness along ∂p/∂u (as Mitsuba's
//! shading frame `s = normalize(∂p/∂u − n (n·∂p/∂u))`). Computed only for those materials.

use math::{Frame, Vec2, Vec3};

use crate::material::Material;
use crate::shape::{Disk, Sphere, Triangle};

/// ∂p/∂u, ∂p/∂v of a triangle with texture coordinates `uvs` (constant over the triangle):
/// the solution of `p1 − p0 = Δu₁ ∂p/∂u + Δv₁ ∂p/∂v`, `p2 − p0 = Δu₂ ∂p/∂u + Δv₂ ∂p/∂v`.
/// Without uvs, or when they are degenerate, two unit tangents of the geometric normal.
pub fn triangle(t: &Triangle, uvs: Option<[Vec2; 3]>) -> (Vec3, Vec3) {
    let fallback = || {
        let f = Frame::from_z(t.normal);
        (f.x, f.y)
    };
    let Some([uv0, uv1, uv2]) = uvs else { return fallback() };
    let [p0, p1, p2] = t.vertices();
    let (duv1, duv2) = (uv1 - uv0, uv2 - uv0);
    let (dp1, dp2) = (p1 - p0, p2 - p0);
    let det = duv1.x * duv2.y - duv1.y * duv2.x;
    if det == 0.0 || !det.is_finite() {
        return fallback();
    }
    let inv = 1.0 / det;
    let dp_du = (dp1 * duv2.y - dp2 * duv1.y) * inv;
    let dp_dv = (dp2 * duv1.x - dp1 * duv2.x) * inv;
    if dp_du.is_finite() && dp_dv.is_finite() { (dp_du, dp_dv) } else { fallback() }
}

/// ∂p/∂u, ∂p/∂v of a sphere in the parameterisation of [`Sphere::uv_at`] (`u = φ/2π`,
/// `v = θ/π`): `2π r (−sin φ sin θ, cos φ sin θ, 0)` and `π r (cos θ cos φ, cos θ sin φ, −sin θ)`.
/// At the poles ∂p/∂u vanishes (the shading frame then falls back to an arbitrary tangent).
pub fn sphere(s: &Sphere, position: Vec3) -> (Vec3, Vec3) {
    use std::f32::consts::PI;
    let d = (position - s.center) / s.radius;
    let phi = d.y.atan2(d.x);
    let cos_theta = d.z.clamp(-1.0, 1.0);
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    let dp_du = Vec3::new(-d.y, d.x, 0.0) * (2.0 * PI * s.radius);
    let dp_dv = Vec3::new(cos_theta * phi.cos(), cos_theta * phi.sin(), -sin_theta) * (PI * s.radius);
    (dp_du, dp_dv)
}

/// Two unit tangents of `normal` (shapes without a uv parameterisation).
pub fn fallback(normal: Vec3) -> (Vec3, Vec3) {
    let f = Frame::from_z(normal);
    (f.x, f.y)
}

/// ∂p/∂u, ∂p/∂v of a disc in the parameterisation of [`Disk::uv_at`] (`u` = radius, `v` =
/// angle/2π): the radial direction `(x a_u + y a_v)/r` and `2π (−y a_u + x a_v)` at the local
/// point `(x, y)`, `a_u`, `a_v` the disc's axes. At the centre, two tangents of `normal`.
pub fn disk(d: &Disk, position: Vec3, normal: Vec3) -> (Vec3, Vec3) {
    let (axis_u, axis_v) = d.axes();
    let local = d.uv_at(position);
    let (r, phi) = (local.x, local.y * 2.0 * std::f32::consts::PI);
    let (x, y) = (r * phi.cos(), r * phi.sin());
    if r <= 1e-6 {
        return fallback(normal);
    }
    let dp_du = (axis_u * x + axis_v * y) / r;
    let dp_dv = (axis_v * x - axis_u * y) * (2.0 * std::f32::consts::PI);
    (dp_du, dp_dv)
}

impl Material {
    /// True when the material (or a part of it) has an anisotropic roughness, whose BSDF then
    /// needs the surface tangent ([`crate::ShadingPoint::tangent`]): a rough conductor or
    /// dielectric with `alpha_u ≠ alpha_v`, a textured roughness over one of them with two
    /// different textures, a principled material whose `anisotropic` is not a constant 0, or
    /// hair (its fibre direction comes from the tangent).
    pub fn is_anisotropic(&self) -> bool {
        match self {
            Material::RoughConductor { alpha_u, alpha_v, .. } | Material::RoughDielectric { alpha_u, alpha_v, .. } => {
                alpha_u != alpha_v
            }
            Material::TexturedRoughness { alpha_u, alpha_v, nested, .. } => {
                alpha_u != alpha_v && !matches!(**nested, Material::RoughPlastic { .. })
            }
            Material::Blend { first, second, .. } => first.is_anisotropic() || second.is_anisotropic(),
            Material::TwoSided { front, back } => {
                front.is_anisotropic() || back.as_ref().is_some_and(|b| b.is_anisotropic())
            }
            Material::NormalMap { nested, .. } | Material::BumpMap { nested, .. } => nested.is_anisotropic(),
            Material::Principled(p) => varies(&p.anisotropic),
            Material::PrincipledThin(p) => varies(&p.anisotropic),
            Material::Coated(p) => p.is_anisotropic(),
            // The fibre direction is `n × ∂p/∂u`.
            Material::Hair(_) => true,
            _ => false,
        }
    }
}

/// Whether an `anisotropic` parameter can be non-zero (a texture, or a non-zero constant).
fn varies(anisotropic: &crate::Texture) -> bool {
    anisotropic.as_constant().is_none_or(|c| c != spectrum::Rgb::BLACK)
}
