//! The scene-side description of a material: the closed [`Material`] enum that loaders build,
//! and its validation. A BSDF is made from it per hit ([`super::Bsdf::new`]).

use spectrum::Rgb;
use spectrum::fluorescence::Fluorescence;
use spectrum::ior::Ior;

use super::MAX_COMPONENTS;
use super::coated_parameters::CoatedParameters;
use super::hair::HairParameters;
use super::map_adapter::MapOptions;
use super::principled::PrincipledParameters;
use super::principled_thin::PrincipledThinParameters;
use super::reference::ReferenceMaterial;
use crate::microfacet::Distribution;
use crate::texture::Texture;

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
    /// Lambertian reflection plus Lambertian transmission, two-sided (pbrt-v4's
    /// `diffusetransmission`): `R/π` on the side of the incident direction, `T/π` across.
    DiffuseTransmission {
        /// Reflectance R.
        reflectance: Texture,
        /// Transmittance T.
        transmittance: Texture,
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
    /// Microfacet conductor with visible-normal sampling.
    RoughConductor {
        /// GGX or Beckmann.
        distribution: Distribution,
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
    /// Microfacet dielectric (Walter et al. 2007).
    RoughDielectric {
        /// GGX or Beckmann.
        distribution: Distribution,
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
    /// Diffuse base under a rough dielectric coating (Mitsuba's `roughplastic`).
    RoughPlastic {
        /// GGX or Beckmann.
        distribution: Distribution,
        /// Isotropic roughness of the coating.
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
    /// Mitsuba 3's `principled` (the Disney BSDF): diffuse, sheen, clearcoat, metallic and
    /// dielectric GGX reflection and rough transmission, scattering from both sides (from
    /// behind only through its transmission weight). Anisotropy is aligned with the tangent
    /// of the shading frame, as for the rough conductor.
    Principled(Box<PrincipledParameters>),
    /// Mitsuba 3's `principledthin` (the thin-surface Disney BSDF), the same from both sides.
    PrincipledThin(Box<PrincipledThinParameters>),
    /// pbrt-v4's `coateddiffuse` and `coatedconductor`: a dielectric interface over a
    /// scattering medium over a diffuse or conductor base, one-sided (see `material/coated.rs`).
    Coated(Box<CoatedParameters>),
    /// pbrt-v4's `hair` (Chiang et al. 2016) on curve tubes, two-sided; the fibre runs along
    /// the local y axis `n × ∂p/∂u` (see `material/hair.rs`).
    Hair(HairParameters),
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
    /// A rough model (`RoughConductor`, `RoughDielectric`, `RoughPlastic`) whose GGX roughness
    /// varies over the surface: at a hit, α along the tangent is the luminance of `alpha_u` and
    /// α along the bitangent that of `alpha_v` (square-rooted when `remap`, pbrt's
    /// `RoughnessToAlpha`); the nested model's own α is not used. The plastic is isotropic and
    /// takes `alpha_u`.
    TexturedRoughness {
        /// Roughness along the tangent.
        alpha_u: Texture,
        /// Roughness along the bitangent.
        alpha_v: Texture,
        /// The textures hold pbrt's `roughness`: α = √value.
        remap: bool,
        /// The rough model.
        nested: Box<Material>,
    },
    /// Mitsuba's `normalmap`: `nested` with its shading normal read from a tangent-space
    /// normal map (see `material/normal_map.rs`). Only as the outermost material.
    NormalMap {
        /// Tangent-space normals encoded as `(n + 1)/2` (raw, linear texels).
        normals: Texture,
        /// The material whose shading normal is replaced.
        nested: Box<Material>,
        /// Mitsuba's per-query adapter ([`MapOptions::MITSUBA`] for Mitsuba files).
        options: MapOptions,
    },
    /// Mitsuba's `bumpmap`: `nested` with its shading normal tilted by the gradient of a height
    /// texture (see `material/bump_map.rs`). Only as the outermost material.
    BumpMap {
        /// Height (its luminance), in scene units per unit of `scale`.
        height: Texture,
        /// Factor on the height.
        scale: f32,
        /// The material whose shading normal is perturbed.
        nested: Box<Material>,
        /// Mitsuba's per-query adapter ([`MapOptions::MITSUBA`] for Mitsuba files).
        options: MapOptions,
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

    /// True when every BSDF built from this material, at every point and for every direction,
    /// is purely specular ([`crate::Bsdf::is_delta`]) or absent, so that no vertex on it is
    /// connected to or merged at: SmallVCM's material without diffuse or Phong reflectance
    /// ([`super::ReferenceMaterial::is_specular_only`]), the smooth conductor, dielectric and
    /// thin dielectric, and blends, two-sided wrappers and normal or bump maps of those only
    /// (a perturbed shading normal turns a delta lobe, it does not widen it). Conservative:
    /// every other model answers false, also where a parameter would make it specular (a
    /// rough model at zero roughness, a blend weight of 0 or 1).
    pub fn is_specular_only(&self) -> bool {
        match self {
            Material::Reference(m) => m.is_specular_only(),
            Material::Conductor { .. } | Material::Dielectric { .. } | Material::ThinDielectric { .. } => true,
            Material::Blend { first, second, .. } => first.is_specular_only() && second.is_specular_only(),
            Material::TwoSided { front, back } => {
                front.is_specular_only() && back.as_ref().is_none_or(|b| b.is_specular_only())
            }
            Material::NormalMap { nested, .. } | Material::BumpMap { nested, .. } => nested.is_specular_only(),
            _ => false,
        }
    }
}

impl Material {
    /// Number of leaf materials (blends and two-sided wrappers count what they contain; a
    /// two-sided material with a distinct back counts both sides).
    pub fn leaf_count(&self) -> usize {
        match self {
            Material::Blend { first, second, .. } => first.leaf_count() + second.leaf_count(),
            Material::TwoSided { front, back } => front.leaf_count() + back.as_ref().map_or(0, |b| b.leaf_count()),
            Material::NormalMap { nested, .. } | Material::BumpMap { nested, .. } => nested.leaf_count(),
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
    /// refraction (a dielectric with a dispersive `dispersion`).
    pub fn is_dispersive(&self) -> bool {
        match self {
            Material::Dielectric { dispersion, .. } => dispersion.is_some_and(|ior| ior.is_dispersive()),
            Material::Blend { first, second, .. } => first.is_dispersive() || second.is_dispersive(),
            Material::TwoSided { front, back } => {
                front.is_dispersive() || back.as_ref().is_some_and(|b| b.is_dispersive())
            }
            Material::NormalMap { nested, .. }
            | Material::BumpMap { nested, .. }
            | Material::TexturedRoughness { nested, .. } => nested.is_dispersive(),
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
            Material::NormalMap { nested, .. } | Material::BumpMap { nested, .. } => {
                nested.fluorescence().is_some() || nested.nests_fluorescence()
            }
            _ => false,
        }
    }

    /// Whether a normal or bump map is nested inside another material (or wraps one).
    fn nests_perturbation(&self) -> bool {
        match self {
            Material::Blend { first, second, .. } => {
                first.perturbs_shading_normal()
                    || second.perturbs_shading_normal()
                    || first.nests_perturbation()
                    || second.nests_perturbation()
            }
            Material::TwoSided { front, back } => {
                front.perturbs_shading_normal()
                    || front.nests_perturbation()
                    || back.as_ref().is_some_and(|b| b.perturbs_shading_normal() || b.nests_perturbation())
            }
            Material::NormalMap { nested, .. } | Material::BumpMap { nested, .. } => {
                nested.perturbs_shading_normal() || nested.nests_perturbation()
            }
            _ => false,
        }
    }

    /// Every [`Material::TexturedRoughness`] (at any depth) wraps a rough model.
    fn check_textured_roughness(&self) -> Result<(), String> {
        match self {
            Material::TexturedRoughness { nested, .. } => match **nested {
                Material::RoughConductor { .. } | Material::RoughDielectric { .. } | Material::RoughPlastic { .. } => {
                    Ok(())
                }
                _ => Err("a textured roughness needs a rough conductor, dielectric or plastic".into()),
            },
            Material::Blend { first, second, .. } => {
                first.check_textured_roughness()?;
                second.check_textured_roughness()
            }
            Material::TwoSided { front, back } => {
                front.check_textured_roughness()?;
                back.as_ref().map_or(Ok(()), |b| b.check_textured_roughness())
            }
            Material::NormalMap { nested, .. } | Material::BumpMap { nested, .. } => nested.check_textured_roughness(),
            _ => Ok(()),
        }
    }

    /// Checks what a BSDF can represent: at most [`MAX_COMPONENTS`] leaves per side, fluorescent
    /// materials only at the top level and conserving energy, normal and bump maps only as the
    /// outermost material.
    pub fn validate(&self) -> Result<(), String> {
        if self.nests_fluorescence() {
            return Err("a fluorescent material cannot be blended or made two-sided".into());
        }
        if self.nests_perturbation() {
            return Err("a normalmap or bumpmap must be the outermost bsdf (not inside a blend, a twosided \
                        or another normalmap/bumpmap)"
                .into());
        }
        if let Material::NormalMap { nested, .. } | Material::BumpMap { nested, .. } = self
            && matches!(**nested, Material::Reference(_))
        {
            return Err("a normalmap or bumpmap cannot wrap the reference material (it has no shading normal)".into());
        }
        self.check_textured_roughness()?;
        if let Material::Hair(p) = self {
            p.validate()?;
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
