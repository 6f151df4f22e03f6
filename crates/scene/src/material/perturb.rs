//! Shading-normal perturbation: the surface differentials a normal or bump map needs, and the
//! dispatch to [`super::normal_map`] and [`super::bump_map`].
//!
//! A perturbing material (Mitsuba's `normalmap`, `bumpmap`) changes only the shading normal of
//! the nested material. The scene applies it when it builds a hit ([`crate::Scene::intersect`]),
//! so the perturbed normal is the hit's shading normal everywhere downstream: BSDFs on camera
//! and light sub-paths, stored light vertices, and the shading-normal correction of the adjoint
//! (Veach 1997, §5.3) in importance mode. The material's BSDF is then the nested one's.

use math::{Frame, Vec2, Vec3};

use super::bump_map;
use super::description::Material;
use super::normal_map;

/// The local differential geometry at a hit (world space).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceTangents {
    /// Unit geometric normal.
    pub geometric_normal: Vec3,
    /// Unit shading normal before the perturbation.
    pub shading_normal: Vec3,
    /// Texture coordinates.
    pub uv: Vec2,
    /// ∂p/∂u (scene units per unit of u).
    pub dp_du: Vec3,
    /// ∂p/∂v (scene units per unit of v).
    pub dp_dv: Vec3,
}

impl SurfaceTangents {
    /// Mitsuba's shading frame: `s = normalize(dp_du − n (n·dp_du))`, `t = n × s`, `n` the
    /// shading normal; the frame of [`Frame::from_z`] when `dp_du` is degenerate.
    pub fn shading_frame(&self) -> Frame {
        let n = self.shading_normal;
        let s = (self.dp_du - n * n.dot(self.dp_du)).normalize();
        if !s.is_finite() {
            return Frame::from_z(n);
        }
        Frame { x: s, y: n.cross(s), z: n }
    }
}

impl Material {
    /// True for a material that perturbs the shading normal (normal or bump map).
    #[inline]
    pub fn perturbs_shading_normal(&self) -> bool {
        matches!(self, Material::NormalMap { .. } | Material::BumpMap { .. })
    }

    /// The unit shading normal after the material's perturbation (unchanged for other
    /// materials, and where the perturbed normal would be degenerate).
    pub fn perturbed_shading_normal(&self, tangents: &SurfaceTangents) -> Vec3 {
        let perturbed = match self {
            Material::NormalMap { normals, .. } => normal_map::perturb(normals, tangents),
            Material::BumpMap { height, scale, .. } => bump_map::perturb(height, *scale, tangents),
            _ => return tangents.shading_normal,
        };
        if perturbed.is_finite() && perturbed.length_squared() > 0.5 { perturbed } else { tangents.shading_normal }
    }
}
