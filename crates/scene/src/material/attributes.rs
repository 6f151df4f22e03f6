//! Which hit data a material's textures read: texture coordinates and mesh attributes
//! ([`crate::Texture::MeshAttribute`]). The scene resolves a material's one mesh attribute at
//! each hit into [`super::ShadingPoint::attribute`].

use super::description::Material;
use crate::texture::Texture;

impl Material {
    /// Calls `f` with every texture a BSDF built from this material evaluates (not the normal
    /// or bump map textures, which perturb the shading normal before).
    fn for_each_bsdf_texture<'a>(&'a self, f: &mut dyn FnMut(&'a Texture)) {
        match self {
            Material::Reference(_) | Material::Hair(_) => {}
            Material::Diffuse { reflectance } | Material::Fluorescent { reflectance, .. } => f(reflectance),
            Material::Conductor { specular_reflectance, .. }
            | Material::RoughConductor { specular_reflectance, .. } => f(specular_reflectance),
            Material::DiffuseTransmission { reflectance, transmittance } => {
                f(reflectance);
                f(transmittance);
            }
            Material::Dielectric { specular_reflectance, specular_transmittance, .. }
            | Material::ThinDielectric { specular_reflectance, specular_transmittance, .. }
            | Material::RoughDielectric { specular_reflectance, specular_transmittance, .. } => {
                f(specular_reflectance);
                f(specular_transmittance);
            }
            Material::Plastic { diffuse_reflectance, specular_reflectance, .. }
            | Material::RoughPlastic { diffuse_reflectance, specular_reflectance, .. } => {
                f(diffuse_reflectance);
                f(specular_reflectance);
            }
            Material::Principled(p) => p.textures().into_iter().for_each(f),
            Material::PrincipledThin(p) => p.textures().into_iter().for_each(f),
            Material::Coated(p) => p.textures().into_iter().for_each(f),
            Material::Blend { weight, first, second } => {
                f(weight);
                first.for_each_bsdf_texture(f);
                second.for_each_bsdf_texture(f);
            }
            Material::TexturedRoughness { alpha_u, alpha_v, nested, .. } => {
                f(alpha_u);
                f(alpha_v);
                nested.for_each_bsdf_texture(f);
            }
            Material::NormalMap { nested, .. } | Material::BumpMap { nested, .. } => nested.for_each_bsdf_texture(f),
            Material::TwoSided { front, back } => {
                front.for_each_bsdf_texture(f);
                if let Some(b) = back {
                    b.for_each_bsdf_texture(f);
                }
            }
        }
    }

    /// The name of the mesh attribute this material's BSDF reads, if any. Errors when it reads
    /// two different ones (a hit carries one attribute value), when a fluorescent material
    /// reads one (its re-emission is evaluated at uv only), or when a normal or bump map does.
    pub fn mesh_attribute(&self) -> Result<Option<&str>, String> {
        let mut names: Vec<&str> = Vec::new();
        self.for_each_bsdf_texture(&mut |t| {
            t.for_each_mesh_attribute(&mut |n| {
                if !names.contains(&n) {
                    names.push(n);
                }
            })
        });
        let name = match names.as_slice() {
            [] => None,
            [_] => Some(names[0]),
            [a, b, ..] => {
                return Err(format!("a material reads two mesh attributes, `{a}` and `{b}`; at most one is supported"));
            }
        };
        if name.is_some() && self.fluorescence().is_some() {
            return Err("a fluorescent material cannot read a mesh attribute".into());
        }
        if let Material::NormalMap { normals: t, .. } | Material::BumpMap { height: t, .. } = self
            && let Some(n) = t.mesh_attribute()
        {
            return Err(format!("a normalmap or bumpmap cannot read the mesh attribute `{n}`"));
        }
        Ok(name)
    }

    /// Whether any texture of this material's BSDF varies with the texture coordinates.
    pub fn reads_uv(&self) -> bool {
        let mut any = false;
        self.for_each_bsdf_texture(&mut |t| any |= t.reads_uv());
        any
    }
}
