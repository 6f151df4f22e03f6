//! Materials: `Material`, `MakeNamedMaterial` and their parameters (roughness, index of
//! refraction, normal and bump maps, hair).

use std::path::Path;
use std::sync::Arc;

use math::Vec2;
use scene::desc::{TextureImage, UvTransform};
use scene::material::{HairParameters, Material};
use scene::microfacet::Distribution;
use scene::texture::{FilterMode, Sampling, Texture, WrapMode};
use spectrum::Rgb;

use crate::pbrt::parser::{Directive, ParamSet, Value};
use crate::pbrt::tokenizer::Pos;
use crate::scene_error::SceneError;

use super::color;
use super::{Builder, SMOOTH_ALPHA, err, resolve};

impl Builder {
    /// Textured roughness: `Some((α_u, α_v textures, remap))` when `roughness`, `uroughness`
    /// or `vroughness` names a non-constant texture (the others are taken as constants).
    pub(super) fn roughness_textures(&self, p: &ParamSet) -> Result<Option<(Texture, Texture, bool)>, SceneError> {
        let textured = |name: &str| {
            p.find(name).is_some_and(|x| {
                x.ty == "texture"
                    && matches!(&x.values[..], [Value::Str(t)]
                        if self.textures.get(t).is_some_and(|n| n.texture.as_constant().is_none()))
            })
        };
        if !["roughness", "uroughness", "vroughness"].iter().any(|n| textured(n)) {
            return Ok(None);
        }
        let r = self.spectrum_texture(p, "roughness", Rgb::BLACK, false)?;
        let u = if p.find("uroughness").is_some() {
            self.spectrum_texture(p, "uroughness", Rgb::BLACK, false)?
        } else {
            r.clone()
        };
        let v =
            if p.find("vroughness").is_some() { self.spectrum_texture(p, "vroughness", Rgb::BLACK, false)? } else { r };
        Ok(Some((u, v, p.bool("remaproughness", true)?)))
    }

    /// `material(α_u, α_v)` with constant roughness, or wrapped in
    /// [`Material::TexturedRoughness`] with textured roughness; `smooth` is the material for
    /// constant α below [`SMOOTH_ALPHA`].
    pub(super) fn rough(
        &self,
        p: &ParamSet,
        smooth: impl FnOnce() -> Material,
        make: impl FnOnce(f32, f32) -> Material,
    ) -> Result<Material, SceneError> {
        if let Some((alpha_u, alpha_v, remap)) = self.roughness_textures(p)? {
            return Ok(Material::TexturedRoughness { alpha_u, alpha_v, remap, nested: Box::new(make(0.1, 0.1)) });
        }
        let (alpha_u, alpha_v) = self.roughness(p)?;
        Ok(if alpha_u.max(alpha_v) < SMOOTH_ALPHA { smooth() } else { make(alpha_u, alpha_v) })
    }

    pub(super) fn roughness(&self, p: &ParamSet) -> Result<(f32, f32), SceneError> {
        let r = self.constant_float(p, "roughness", 0.0)?;
        let u = if p.find("uroughness").is_some() { self.constant_float(p, "uroughness", r)? } else { r };
        let v = if p.find("vroughness").is_some() { self.constant_float(p, "vroughness", r)? } else { r };
        if !(u >= 0.0 && v >= 0.0 && u.is_finite() && v.is_finite()) {
            return Err(
                p.error(p.params.first().map_or(Pos { line: 0, column: 0 }, |x| x.pos), "roughness must be ≥ 0")
            );
        }
        let remap = p.bool("remaproughness", true)?;
        Ok(if remap { (u.sqrt(), v.sqrt()) } else { (u, v) })
    }

    pub(super) fn material(&self, file: &Path, d: &Directive, ty: &str) -> Result<Material, SceneError> {
        let material = self.base_material(file, d, ty)?;
        if ty == "mix" { Ok(material) } else { self.perturbation(file, d, material) }
    }

    /// pbrt-v4's `string normalmap` (an image of tangent-space normals, read linear, looked up
    /// at (u, 1 − v) with repeat and bilinear filtering) or `float texture displacement` (a
    /// bump map: the gradient of the displacement tilts the shading normal; pbrt's finite
    /// difference is replaced by the exact gradient and its `displace · ∂n/∂u` term is
    /// omitted) around `material`.
    pub(super) fn perturbation(&self, file: &Path, d: &Directive, material: Material) -> Result<Material, SceneError> {
        let p = &d.params;
        let normal_map = p.string("normalmap")?;
        let displacement = p.find("displacement").map(|x| x.pos);
        let nested = Box::new(material.clone());
        let wrapped = match (normal_map, displacement) {
            (None, None) => return Ok(material),
            (Some((_, pos)), Some(_)) => {
                return Err(p.error(pos, "give either \"normalmap\" or \"displacement\", not both"));
            }
            (Some((filename, pos)), None) => {
                let path = resolve(file, &filename);
                let stored = crate::read_texture_file(&path)
                    .map_err(|e| p.error(pos, format!("cannot read normal map: {e}")))?;
                let image = stored.linear(crate::TextureEncoding::Linear);
                let pixels = image.pixels.iter().map(|&c| Rgb::from_array(c)).collect();
                let image = Arc::new(TextureImage { width: image.width as u32, height: image.height as u32, pixels });
                // (u, 1 − v): v = 0 is the bottom row; our v' runs from the top.
                let to_uv = UvTransform {
                    columns: [Vec2::new(1.0, 0.0), Vec2::new(0.0, -1.0)],
                    translation: Vec2::new(0.0, 1.0),
                };
                let normals =
                    Texture::bitmap(image, to_uv, Sampling { wrap: WrapMode::Repeat, filter: FilterMode::Bilinear });
                Material::NormalMap { normals, nested, options: scene::material::MapOptions::NONE }
            }
            (None, Some(_)) => {
                let height = self.spectrum_texture(p, "displacement", Rgb::BLACK, false)?;
                Material::BumpMap { height, scale: 1.0, nested, options: scene::material::MapOptions::NONE }
            }
        };
        let pos = p.params.first().map_or(d.pos, |x| x.pos);
        wrapped.validate().map_err(|e| p.error(pos, e))?;
        Ok(wrapped)
    }

    pub(super) fn base_material(&self, file: &Path, d: &Directive, ty: &str) -> Result<Material, SceneError> {
        let p = &d.params;
        let two_sided = |m: Material| Material::TwoSided { front: Box::new(m), back: None };
        Ok(match ty {
            "diffuse" => two_sided(Material::Diffuse {
                reflectance: self.spectrum_texture(p, "reflectance", Rgb::splat(0.5), true)?,
            }),
            "conductor" => {
                let (eta, k, specular_reflectance) = if p.find("reflectance").is_some() {
                    for name in ["eta", "k"] {
                        if let Some(x) = p.find(name) {
                            return Err(p.error(x.pos, format!("'{name}' and 'reflectance' exclude each other")));
                        }
                    }
                    match self.spectrum_texture(p, "reflectance", Rgb::WHITE, true)? {
                        // pbrt: η = 1, k = 2√r / √(1 − r), whose normal-incidence Fresnel is r.
                        Texture::Constant(r) => {
                            let k = r.map(|r| {
                                let r = r.min(0.9999);
                                2.0 * r.sqrt() / (1.0 - r).sqrt()
                            });
                            (Rgb::WHITE, k, Texture::Constant(Rgb::WHITE))
                        }
                        textured => (Rgb::BLACK, Rgb::BLACK, textured),
                    }
                } else {
                    let eta = self.unbounded(p, "eta", "metal-Cu-eta")?;
                    let k = self.unbounded(p, "k", "metal-Cu-k")?;
                    (eta, k, Texture::Constant(Rgb::WHITE))
                };
                let smooth_reflectance = specular_reflectance.clone();
                let m = self.rough(
                    p,
                    || Material::Conductor { eta, k, specular_reflectance: smooth_reflectance },
                    |alpha_u, alpha_v| Material::RoughConductor {
                        distribution: Distribution::Ggx,
                        alpha_u,
                        alpha_v,
                        eta,
                        k,
                        specular_reflectance,
                    },
                )?;
                two_sided(m)
            }
            "diffusetransmission" => {
                // pbrt-v4: reflectance and transmittance (default 0.25 each), both times `scale`.
                let scale = p.float("scale", 1.0)?;
                let scaled = |texture: Texture| match texture.as_constant() {
                    Some(c) => Texture::Constant(c * scale),
                    None if scale == 1.0 => texture,
                    None => Texture::Scale {
                        texture: Arc::new(texture),
                        scale: Arc::new(Texture::Constant(Rgb::splat(scale))),
                    },
                };
                Material::DiffuseTransmission {
                    reflectance: scaled(self.spectrum_texture(p, "reflectance", Rgb::splat(0.25), true)?),
                    transmittance: scaled(self.spectrum_texture(p, "transmittance", Rgb::splat(0.25), true)?),
                }
            }
            "dielectric" | "thindielectric" => {
                let eta = self.ior(p)?;
                let white = || Texture::Constant(Rgb::WHITE);
                if ty == "thindielectric" {
                    Material::ThinDielectric {
                        int_ior: eta,
                        ext_ior: 1.0,
                        specular_reflectance: white(),
                        specular_transmittance: white(),
                    }
                } else {
                    self.rough(
                        p,
                        || Material::Dielectric {
                            int_ior: eta,
                            ext_ior: 1.0,
                            specular_reflectance: white(),
                            specular_transmittance: white(),
                            dispersion: None,
                        },
                        |alpha_u, alpha_v| Material::RoughDielectric {
                            distribution: Distribution::Ggx,
                            alpha_u,
                            alpha_v,
                            int_ior: eta,
                            ext_ior: 1.0,
                            specular_reflectance: white(),
                            specular_transmittance: white(),
                        },
                    )?
                }
            }
            "mix" => {
                let Some(param) = p.typed("materials", &["string"])? else {
                    return Err(err(file, d.pos, "mix material needs \"string materials\" [two names]"));
                };
                let names = param.strings();
                if names.len() != 2 {
                    return Err(p.error(param.pos, format!("mix needs 2 materials, got {}", names.len())));
                }
                let lookup = |n: &str| {
                    self.named_materials
                        .get(n)
                        .map(|(m, _)| Box::new(m.clone()))
                        .ok_or_else(|| p.error(param.pos, format!("unknown named material \"{n}\"")))
                };
                let weight = match p.find("amount") {
                    Some(a) if a.ty == "texture" => self.spectrum_texture(p, "amount", Rgb::splat(0.5), false)?,
                    _ => Texture::Constant(Rgb::splat(p.float("amount", 0.5)?)),
                };
                Material::Blend { weight, first: lookup(&names[0])?, second: lookup(&names[1])? }
            }
            // An index-matched boundary: a placeholder the scene marks as such (`medium.rs`).
            "interface" => Material::Diffuse { reflectance: Texture::Constant(Rgb::BLACK) },
            "coateddiffuse" | "coatedconductor" => self.coated_material(d, ty)?,
            "hair" => Material::Hair(self.hair(p, d.pos)?),
            other @ ("measured" | "subsurface") => {
                return Err(err(file, d.pos, format!("material \"{other}\" is not supported")));
            }
            other => return Err(err(file, d.pos, format!("unknown material type \"{other}\""))),
        })
    }

    /// pbrt-v4's `hair`: the absorption from `sigma_a`, else from `reflectance` (pbrt-v3:
    /// `color`) through Chiang et al.'s mapping, else from `eumelanin`/`pheomelanin` (eumelanin
    /// 1.3 when none is given); `eta` 1.55, `beta_m`, `beta_n` 0.3, `alpha` 2°. Textured
    /// parameters are not supported.
    pub(super) fn hair(&self, p: &ParamSet, pos: Pos) -> Result<HairParameters, SceneError> {
        let constant = |name: &str, albedo: bool| -> Result<Option<Rgb>, SceneError> {
            let Some(param) = p.find(name) else { return Ok(None) };
            match self.spectrum_texture(p, name, Rgb::BLACK, albedo)? {
                Texture::Constant(c) => Ok(Some(c)),
                _ => Err(p.error(param.pos, format!("hair: a textured '{name}' is not supported"))),
            }
        };
        let mut hair = HairParameters {
            eta: p.float("eta", 1.55)?,
            beta_m: p.float("beta_m", 0.3)?,
            beta_n: p.float("beta_n", 0.3)?,
            alpha: p.float("alpha", 2.0)?,
            ..HairParameters::default()
        };
        let reflectance = match constant("reflectance", true)? {
            Some(c) => Some(c),
            None => constant("color", true)?,
        };
        let (eumelanin, pheomelanin) = (p.float_opt("eumelanin")?, p.float_opt("pheomelanin")?);
        hair.sigma_a = if let Some(s) = constant("sigma_a", false)? {
            s
        } else if let Some(c) = reflectance {
            HairParameters::sigma_a_from_color(c, hair.beta_n)
        } else {
            let eumelanin = if pheomelanin.is_none() { eumelanin.unwrap_or(1.3) } else { eumelanin.unwrap_or(0.0) };
            HairParameters::sigma_a_from_melanin(eumelanin, pheomelanin.unwrap_or(0.0))
        };
        hair.validate().map_err(|e| p.error(pos, e))?;
        Ok(hair)
    }

    /// A conductor's η or k: constant RGB (named spectra via the table in [`color`]).
    pub(super) fn unbounded(&self, p: &ParamSet, name: &str, default: &str) -> Result<Rgb, SceneError> {
        match self.spectrum_texture(p, name, color::named_metal(default).unwrap_or(Rgb::WHITE), false)? {
            Texture::Constant(c) => Ok(c),
            _ => Err(p.error(
                p.find(name).map_or(Pos { line: 0, column: 0 }, |x| x.pos),
                format!("textured '{name}' is not supported"),
            )),
        }
    }

    /// A dielectric's index of refraction (`float`, a constant or a named glass spectrum).
    pub(super) fn ior(&self, p: &ParamSet) -> Result<f32, SceneError> {
        let Some(param) = p.find("eta") else { return Ok(1.5) };
        let pos = param.pos;
        let eta = match (param.ty.as_str(), &param.values[..]) {
            ("float" | "spectrum", [Value::Num(x)]) => *x as f32,
            ("spectrum", [Value::Str(s)]) => {
                color::named_glass(s).ok_or_else(|| p.error(pos, format!("unknown named glass spectrum \"{s}\"")))?
            }
            ("texture", _) => self.constant_float(p, "eta", 1.5)?,
            ("spectrum", _) => {
                let nums = param.numbers();
                let s = color::piecewise_linear(&nums)
                    .filter(|_| nums.len() % 2 == 0)
                    .ok_or_else(|| p.error(pos, "eta: expected wavelength/value pairs with increasing wavelengths"))?;
                s(587.6) as f32
            }
            _ => return Err(p.error(pos, "eta needs one float, a named glass spectrum or a sampled spectrum")),
        };
        if !(eta > 0.0 && eta.is_finite()) {
            return Err(p.error(pos, format!("eta {eta} must be positive")));
        }
        Ok(eta)
    }

    /// The material of the shape being defined: the graphics state's, else the file's default
    /// (pbrt's `diffuse`, created on first use).
    pub(super) fn current_material(&mut self) -> u32 {
        if let Some(m) = self.state.material {
            return m;
        }
        if let Some(m) = self.default_material {
            return m;
        }
        self.materials.push(Material::TwoSided {
            front: Box::new(Material::Diffuse { reflectance: Texture::Constant(Rgb::splat(0.5)) }),
            back: None,
        });
        let m = self.materials.len() as u32 - 1;
        self.default_material = Some(m);
        m
    }
}
