//! What a hit needs to know of its material before building a BSDF, answered from one small
//! record per material made with the scene ([`crate::Scene::material_flags`]) instead of
//! walking the material's tree at every hit. A new per-hit question is one field here.

use super::description::Material;

/// Facts about one material that the scene and the renderers read at every hit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MaterialFlags {
    /// The BSDF reads a mesh attribute ([`Material::mesh_attribute`]): hits carry its value in
    /// [`crate::SurfaceHit::attribute`].
    pub reads_mesh_attribute: bool,
    /// [`Material::is_anisotropic`]: hits carry ∂p/∂u in [`crate::SurfaceHit::tangent`].
    pub anisotropic: bool,
    /// The hit needs texture coordinates: a texture of the BSDF varies with them
    /// ([`Material::reads_uv`]) or the material is a normal or bump map. Spheres and discs
    /// compute their parameterisation (an `atan2`, on spheres also an `acos`) only then.
    pub reads_uv: bool,
    /// [`Material::is_specular_only`]: every BSDF built on it is delta or absent.
    pub specular_only: bool,
    /// [`Material::is_fibre`]: the scene's queries skip hits on the back side of the surface
    /// (as they skip hits an alpha mask removes).
    pub fibre: bool,
}

impl MaterialFlags {
    /// The flags of a material index that names no material: nothing is assumed (texture
    /// coordinates are computed, no shortcut is taken).
    pub const UNKNOWN: MaterialFlags = MaterialFlags {
        reads_mesh_attribute: false,
        anisotropic: false,
        reads_uv: true,
        specular_only: false,
        fibre: false,
    };

    /// The flags of `material`.
    pub fn of(material: &Material) -> Self {
        Self {
            reads_mesh_attribute: matches!(material.mesh_attribute(), Ok(Some(_))),
            anisotropic: material.is_anisotropic(),
            reads_uv: material.reads_uv() || material.perturbs_shading_normal(),
            specular_only: material.is_specular_only(),
            fibre: material.is_fibre(),
        }
    }
}
