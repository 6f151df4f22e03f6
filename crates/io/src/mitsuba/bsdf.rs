//! `<bsdf>` and `<texture>` plugins.

use spectrum::ior::Ior;
use std::sync::Arc;

use math::Vec2;
use scene::desc::{TextureImage, UvTransform};
use scene::material::{MapOptions, Material};
use scene::microfacet::Distribution;
use scene::{FilterMode, Sampling, Texture, WrapMode};
use spectrum::Rgb;

use super::Loader;
use super::Resolved;
use super::colour::SpectrumUse;
use super::mask::{Masked, twosided_parts, unmasked};
use super::props::Plugin;
use super::transform::Mat4;
use super::transform::positive;
use super::xml::Node;
use crate::scene_error::SceneError;

/// Mitsuba's table of named indices of refraction (`ior.h`: Hecht, *Optics*, ~589 nm).
const IOR_TABLE: [(&str, f64); 23] = [
    ("vacuum", 1.0),
    ("helium", 1.000036),
    ("hydrogen", 1.000132),
    ("air", 1.000277),
    ("carbon dioxide", 1.00045),
    ("water", 1.3330),
    ("acetone", 1.36),
    ("ethanol", 1.361),
    ("carbon tetrachloride", 1.461),
    ("glycerol", 1.4729),
    ("benzene", 1.501),
    ("silicone oil", 1.52045),
    ("bromine", 1.661),
    ("water ice", 1.31),
    ("fused quartz", 1.458),
    ("pyrex", 1.470),
    ("acrylic glass", 1.49),
    ("polypropylene", 1.49),
    ("bk7", 1.5046),
    ("sodium chloride", 1.544),
    ("amber", 1.55),
    ("pet", 1.5750),
    ("diamond", 2.419),
];

/// Complex indices of refraction `(eta, k)` of Mitsuba's named conductors as linear sRGB.
///
/// Source: Mitsuba's RGB variants turn the measured spectra in `data/ior/<name>.{eta,k}.spd`
/// into RGB with `spectrum_list_to_srgb` after scaling by `MI_CIE_Y_NORMALIZATION` (equal-energy
/// CIE 1931 integration, see `colour.rs`). These are the results of that integration as
/// tabulated in Tungsten's `ComplexIorData.hpp` (computed from the same Mitsuba/PBRT data); the
/// silver entry agrees with an independent re-computation of Mitsuba's conversion to 1e-4.
const CONDUCTORS: [(&str, [f64; 3], [f64; 3]); 40] = [
    ("a-C", [2.9440999183, 2.2271502925, 1.9681668794], [0.8874329109, 0.7993216383, 0.8152862927]),
    ("Ag", [0.1552646489, 0.1167232965, 0.1383806959], [4.8283433224, 3.1222459278, 2.1469504455]),
    ("Al", [1.6574599595, 0.8803689579, 0.5212287346], [9.2238691996, 6.2695232477, 4.8370012281]),
    ("AlAs", [3.6051023902, 3.2329365777, 2.2175611545], [0.0006670247, -0.0004999400, 0.0074261204]),
    ("AlSb", [-0.0485225705, 4.1427547893, 4.6697691348], [-0.0363741915, 0.0937665154, 1.3007390124]),
    ("Au", [0.1431189557, 0.3749570432, 1.4424785571], [3.9831604247, 2.3857207478, 1.6032152899]),
    ("Be", [4.1850592788, 3.1850604423, 2.7840913457], [3.8354398268, 3.0101260162, 2.8690088743]),
    ("Cr", [4.3696828663, 2.9167024892, 1.6547005413], [5.2064337956, 4.2313645277, 3.7549467933]),
    ("CsI", [2.1449030413, 1.7023164587, 1.6624194173], [0.0, 0.0, 0.0]),
    ("Cu", [0.2004376970, 0.9240334304, 1.1022119527], [3.9129485033, 2.4528477015, 2.1421879552]),
    ("Cu2O", [3.5492833755, 2.9520622449, 2.7369202137], [0.1132179294, 0.1946659670, 0.6001681264]),
    ("CuO", [3.2453822204, 2.4496293965, 2.1974114493], [0.5202739621, 0.5707372756, 0.7172250613]),
    ("d-C", [2.7112524747, 2.3185812849, 2.2288565009], [0.0, 0.0, 0.0]),
    ("Hg", [2.3989314904, 1.4400254917, 0.9095512090], [6.3276269444, 4.3719414152, 3.4217899270]),
    ("HgTe", [4.7795267752, 3.2309984581, 2.6600252401], [1.6319827058, 1.5808189339, 1.7295753852]),
    ("Ir", [3.0864098394, 2.0821938440, 1.6178866805], [5.5921510077, 4.0671757150, 3.2672611269]),
    ("K", [0.0640493070, 0.0464100621, 0.0381842017], [2.1042155920, 1.3489364357, 0.9132113889]),
    ("Li", [0.2657871942, 0.1956102432, 0.2209198538], [3.5401743407, 2.3111306542, 1.6685930000]),
    ("MgO", [2.0895885542, 1.6507224525, 1.5948759692], [0.0, 0.0, 0.0]),
    ("Mo", [4.4837010280, 3.5254578255, 2.7760769438], [4.1111307988, 3.4208716252, 3.1506031404]),
    ("Na", [0.0602665320, 0.0561412435, 0.0619909494], [3.1792906496, 2.1124800781, 1.5790940266]),
    ("Nb", [3.4201353595, 2.7901921379, 2.3955856658], [3.4413817900, 2.7376437930, 2.5799132708]),
    ("Ni", [2.3672753521, 1.6633583302, 1.4670554172], [4.4988329911, 3.0501643957, 2.3454274399]),
    ("Rh", [2.5857954933, 1.8601866068, 1.5544279524], [6.7822927110, 4.7029501026, 3.9760892461]),
    ("Se-e", [5.7242724833, 4.1653992967, 4.0816099264], [0.8713747439, 1.1052845009, 1.5647788766]),
    ("Se", [4.0592611085, 2.8426947380, 2.8207582835], [0.7543791750, 0.6385150558, 0.5215872029]),
    ("SiC", [3.1723450205, 2.5259677964, 2.4793623897], [0.0000007284, -0.0000006859, 0.0000100150]),
    ("SnTe", [4.5251865890, 1.9811525984, 1.2816819226], [0.0, 0.0, 0.0]),
    ("Ta", [2.0625846607, 2.3930915569, 2.6280684948], [2.4080467973, 1.7413705864, 1.9470377016]),
    ("Te-e", [7.5090397678, 4.2964603080, 2.3698732430], [5.5842076830, 4.9476231084, 3.9975145063]),
    ("Te", [7.3908396088, 4.4821028985, 2.6370708478], [3.2561412892, 3.5273908133, 3.2921683116]),
    ("ThF4", [1.8307187117, 1.4422274283, 1.3876488528], [0.0, 0.0, 0.0]),
    ("TiC", [3.7004673762, 2.8374356509, 2.5823030278], [3.2656905818, 2.3515586388, 2.1727857800]),
    ("TiN", [1.6484691607, 1.1504482522, 1.3797795097], [3.3684596226, 1.9434888540, 1.1020123347]),
    ("TiO2-e", [3.1065574823, 2.5131551146, 2.5823844157], [0.0000289537, -0.0000251484, 0.0001775555]),
    ("TiO2", [3.4566203131, 2.8017076558, 2.9051485020], [0.0001026662, -0.0000897534, 0.0006356902]),
    ("VC", [3.6575665991, 2.7527298065, 2.5326814570], [3.0683516659, 2.1986687713, 1.9631816252]),
    ("VN", [2.8656011588, 2.1191817791, 1.9400767149], [3.0323264950, 2.0561075580, 1.6162930914]),
    ("V", [4.2775126218, 3.5131538236, 2.7611257461], [3.4911844504, 2.8893580874, 3.1116965117]),
    ("W", [4.3707029924, 3.3002972445, 2.9982666528], [3.5006778591, 2.6048652781, 2.2731930614]),
];

/// The named conductor `name` (Mitsuba's names, case-sensitive), as `(eta, k)` clamped to ≥ 0.
pub(crate) fn conductor_ior(name: &str) -> Option<(Rgb, Rgb)> {
    let clamp = |v: [f64; 3]| Rgb::from_array(v.map(|x| x.max(0.0) as f32));
    CONDUCTORS.iter().find(|(n, _, _)| *n == name).map(|(_, eta, k)| (clamp(*eta), clamp(*k)))
}

/// The named dielectric `name` (case-insensitive).
pub(crate) fn named_ior(name: &str) -> Option<f64> {
    let lower = name.trim().to_ascii_lowercase();
    IOR_TABLE.iter().find(|(n, _)| *n == lower).map(|(_, v)| *v)
}

fn rgb(v: [f64; 3]) -> Rgb {
    Rgb::new(v[0] as f32, v[1] as f32, v[2] as f32)
}

impl<'a> Loader<'a> {
    /// An index of refraction given as a number or a material name.
    pub(super) fn ior(&self, p: &Plugin, name: &str, default: f64) -> Result<f64, SceneError> {
        if let Some(prop) = p.prop(name) {
            use super::props::Value;
            let v = match &prop.value {
                Value::Float(v) => *v,
                Value::Integer(v) => *v as f64,
                Value::Str(s) => named_ior(s).ok_or_else(|| {
                    let names: Vec<&str> = IOR_TABLE.iter().map(|(n, _)| *n).collect();
                    prop.pos.error(format!(
                        "{}: unknown index of refraction '{s}' for '{name}' (known: {})",
                        p.what(),
                        names.join(", ")
                    ))
                })?,
                _ => return Err(prop.pos.error(format!("{}: '{name}' must be a float or a material name", p.what()))),
            };
            if !positive(v) {
                return Err(prop.pos.error(format!("{}: '{name}' must be positive, got {v}", p.what())));
            }
            return Ok(v);
        }
        Ok(default)
    }

    /// `int_ior` / `ext_ior` with defaults, checked to differ.
    fn ior_pair(&self, p: &Plugin, int_default: f64) -> Result<(f32, f32), SceneError> {
        let int_ior = self.ior(p, "int_ior", int_default)?;
        let ext_ior = self.ior(p, "ext_ior", 1.000277)?;
        if int_ior == ext_ior {
            return Err(p.error("the interior and exterior indices of refraction must differ"));
        }
        Ok((int_ior as f32, ext_ior as f32))
    }

    /// The renderer's extension for dispersion in spectral mode: `<string name="dispersion"
    /// value="bk7"/>` (a named glass, see [`spectrum::ior::Ior::named`]) or the Cauchy
    /// coefficients `<float name="cauchy_a" …/>` and `<float name="cauchy_b" …/>` (µm²).
    /// Mitsuba has no dispersion and would reject these properties.
    fn dispersion(&self, p: &Plugin) -> Result<Option<Ior>, SceneError> {
        if let Some(name) = p.string("dispersion")? {
            return match Ior::named(name) {
                Some(ior) => Ok(Some(ior)),
                None => Err(p.error(format!(
                    "unknown dispersive material '{name}' ({})",
                    "bk7, fused quartz, fused silica, diamond"
                ))),
            };
        }
        match (p.float("cauchy_a")?, p.float("cauchy_b")?) {
            (None, None) => Ok(None),
            (Some(a), Some(b)) if a.is_finite() && b.is_finite() && a >= 1.0 && b >= 0.0 => {
                Ok(Some(Ior::Cauchy { a: a as f32, b_um2: b as f32 }))
            }
            (Some(_), Some(_)) => Err(p.error("'cauchy_a' must be ≥ 1 and 'cauchy_b' ≥ 0 (µm²)")),
            _ => Err(p.error("dispersion needs both 'cauchy_a' and 'cauchy_b' (µm²)")),
        }
    }

    /// The microfacet `distribution` (Beckmann by default, as Mitsuba) and the roughness
    /// `(alpha_u, alpha_v)`: `alpha`, or both `alpha_u` and `alpha_v`; default 0.1, each a
    /// number or a texture (then [`Roughness::Textured`]).
    fn roughness(&mut self, p: &Plugin<'a>, anisotropic: bool) -> Result<(Distribution, Roughness), SceneError> {
        let distribution = match p.string("distribution")?.map(str::to_ascii_lowercase).as_deref() {
            Some("ggx") => Distribution::Ggx,
            Some("beckmann") | None => Distribution::Beckmann,
            Some(other) => return Err(p.error(format!("unknown microfacet distribution '{other}' (beckmann or ggx)"))),
        };
        let check = |v: f64, name: &str| -> Result<f32, SceneError> {
            if v.is_finite() && v >= 0.0 {
                Ok(v as f32)
            } else {
                Err(p.error(format!("'{name}' must be a non-negative number, got {v}")))
            }
        };
        let textured = |name: &str| p.objects.iter().any(|o| o.name.as_deref() == Some(name));
        let given = |name: &str| p.has(name) || textured(name);
        let (has_u, has_v, has_alpha) = (given("alpha_u"), given("alpha_v"), given("alpha"));
        let names: &[&str] = if has_u || has_v {
            if !anisotropic {
                return Err(p.error("anisotropic roughness (alpha_u, alpha_v) is not supported by this plugin"));
            }
            if !(has_u && has_v && !has_alpha) {
                return Err(p.error("give either 'alpha' or both 'alpha_u' and 'alpha_v'"));
            }
            &["alpha_u", "alpha_v"]
        } else {
            &["alpha", "alpha"]
        };
        if names.iter().any(|n| textured(n)) {
            let mut texture =
                |name: &str| self.texture_prop(p, name, 0.1, SpectrumUse::Unbounded).map(float_evaluation);
            let alpha_u = texture(names[0])?;
            let alpha_v = if names[1] == names[0] { alpha_u.clone() } else { texture(names[1])? };
            return Ok((distribution, Roughness::Textured(alpha_u, alpha_v)));
        }
        let value = |name: &str| -> Result<f32, SceneError> { check(p.float(name)?.unwrap_or(0.1), name) };
        Ok((distribution, Roughness::Constant(value(names[0])?, value(names[1])?)))
    }

    /// A texture-valued property: a nested `<texture>`, a `<ref name=… id=…>` to one, a
    /// colour, or the constant `default`.
    pub(crate) fn texture_prop(
        &mut self,
        p: &Plugin<'a>,
        name: &str,
        default: f64,
        usage: SpectrumUse,
    ) -> Result<Texture, SceneError> {
        if let Some(object) = p.named_object(name) {
            let node = object.node;
            return match node.tag.as_str() {
                "texture" => self.texture(node),
                "ref" => match self.resolve(node.required_attr("id")?, node)? {
                    Resolved::Texture(t) => Ok(t),
                    other => Err(node.pos.error(format!(
                        "{}: '{name}' refers to a {}, expected a texture",
                        p.what(),
                        other.kind()
                    ))),
                },
                other => Err(node.pos.error(format!("{}: '{name}' must be a texture, not a <{other}>", p.what()))),
            };
        }
        let value = p.color(name, usage, &mut self.warnings)?.unwrap_or([default; 3]);
        if usage == SpectrumUse::Reflectance && value.iter().any(|&v| !(-1e-6..=1.0 + 1e-6).contains(&v)) {
            let pos = p.prop(name).map(|q| q.pos.clone()).unwrap_or_else(|| p.node.pos.clone());
            return Err(pos.error(format!("{}: reflectance '{name}' = {value:?} must lie in [0, 1]", p.what())));
        }
        Ok(Texture::Constant(rgb(value.map(|v| v.clamp(0.0, f64::MAX)))))
    }

    /// A `<texture>` element.
    pub(crate) fn texture(&mut self, node: &'a Node) -> Result<Texture, SceneError> {
        let p = Plugin::new(node)?;
        let to_uv = match p.transform("to_uv")? {
            Some(m) => uv_transform(&m),
            None => UvTransform::IDENTITY,
        };
        let texture = match p.ty.as_str() {
            "bitmap" => {
                let filename = p.string_required("filename")?.to_string();
                let raw = p.boolean_or("raw", false)?;
                let wrap = match p.string("wrap_mode")?.unwrap_or("repeat") {
                    "repeat" => WrapMode::Repeat,
                    "mirror" => WrapMode::Mirror,
                    "clamp" => WrapMode::Clamp,
                    other => {
                        return Err(p.error(format!("wrap_mode '{other}' is not one of repeat, mirror, clamp")));
                    }
                };
                let filter = match p.string("filter_type")?.unwrap_or("bilinear") {
                    "bilinear" => FilterMode::Bilinear,
                    "nearest" => FilterMode::Nearest,
                    other => return Err(p.error(format!("filter_type '{other}' is not one of bilinear, nearest"))),
                };
                p.ignore(&["format"]);
                let image = self.image(&filename, node, raw)?;
                Texture::bitmap(image, to_uv, Sampling { wrap, filter })
            }
            "checkerboard" => {
                // Unbounded: a checkerboard may drive a parameter beyond [0, 1] (principledthin's
                // diff_trans ranges to 2), as bitmap texels may.
                let color = |loader: &mut Self, name: &str, default: f64| -> Result<Rgb, SceneError> {
                    let t = loader.texture_prop(&p, name, default, SpectrumUse::Unbounded)?;
                    t.as_constant().ok_or_else(|| p.error(format!("'{name}' must be a constant colour")))
                };
                let color0 = color(self, "color0", 0.4)?;
                let color1 = color(self, "color1", 0.2)?;
                Texture::Checkerboard { color0, color1, to_uv }
            }
            // Mitsuba's constant texture of raw (unconverted) values.
            "rawconstant" => {
                let value = match p.vector("value") {
                    Ok(Some(v)) => v,
                    _ => [p.float_required("value")?; 3],
                };
                Texture::Constant(rgb(value))
            }
            // The value of a PLY attribute at the hit; the scene checks that the shape has it.
            "mesh_attribute" => {
                let name = p.string_required("name")?;
                if !(name.starts_with("vertex_") || name.starts_with("face_")) {
                    return Err(p.error(format!("mesh attribute name '{name}' must start with 'vertex_' or 'face_'")));
                }
                let scale = p.float_or("scale", 1.0)?;
                if !scale.is_finite() {
                    return Err(p.error(format!("scale {scale} is not finite")));
                }
                Texture::MeshAttribute { name: name.to_owned(), scale: scale as f32 }
            }
            other => return Err(p.error(format!("unsupported texture type '{other}'"))),
        };
        p.finish(&mut self.warnings);
        Ok(texture)
    }

    /// Reads an image file for a texture. Integer formats (8- and 16-bit) are sRGB-decoded
    /// unless `raw`; float formats (EXR, HDR, PFM, float TIFF) are linear, as in Mitsuba.
    fn image(&mut self, filename: &str, node: &Node, raw: bool) -> Result<Arc<TextureImage>, SceneError> {
        let path = self.resolve_file(filename, node)?;
        let key = (path.clone(), raw);
        if let Some(image) = self.images.get(&key) {
            return Ok(image.clone());
        }
        let file = crate::read_texture_file(&path).map_err(|e| node.pos.error(format!("cannot read texture: {e}")))?;
        let encoding = if raw { crate::TextureEncoding::Linear } else { crate::TextureEncoding::Srgb };
        let image = file.linear(encoding);
        let (Ok(width), Ok(height)) = (u32::try_from(image.width), u32::try_from(image.height)) else {
            return Err(node.pos.error(format!("texture '{}' is too large", path.display())));
        };
        let pixels = image.pixels.iter().map(|&p| Rgb::from_array(p)).collect();
        let texture = Arc::new(TextureImage { width, height, pixels });
        self.images.insert(key, texture.clone());
        Ok(texture)
    }

    /// A `<bsdf>` element.
    /// A `<bsdf>`: its material and, for a `mask` (or a `twosided` around one), its opacity.
    pub(crate) fn bsdf(&mut self, node: &'a Node) -> Result<Masked, SceneError> {
        let p = Plugin::new(node)?;
        let reflectance = SpectrumUse::Reflectance;
        let mut opacity = None;
        let material = match p.ty.as_str() {
            "diffuse" => Material::Diffuse { reflectance: self.texture_prop(&p, "reflectance", 0.5, reflectance)? },
            "conductor" | "roughconductor" => {
                let rough = p.ty == "roughconductor";
                let material_name = p.string("material")?.map(str::to_string);
                let given = p.has("eta") || p.has("k");
                if given && material_name.as_deref().is_some_and(|m| m != "none") {
                    return Err(p.error("give either 'material' or 'eta'/'k', not both"));
                }
                let ior = match material_name.as_deref() {
                    Some("none") | None if given => {
                        let eta = p.color("eta", SpectrumUse::Unbounded, &mut self.warnings)?.unwrap_or([0.0; 3]);
                        let k = p.color("k", SpectrumUse::Unbounded, &mut self.warnings)?.unwrap_or([1.0; 3]);
                        Some((rgb(eta), rgb(k)))
                    }
                    Some("none") | None => None,
                    Some(name) => Some(conductor_ior(name).ok_or_else(|| {
                        p.error(format!(
                            "unknown conductor material '{name}' (known: {})",
                            CONDUCTORS.iter().map(|c| c.0).collect::<Vec<_>>().join(", ")
                        ))
                    })?),
                };
                let specular_reflectance = self.texture_prop(&p, "specular_reflectance", 1.0, reflectance)?;
                if rough {
                    let (distribution, roughness) = self.roughness(&p, true)?;
                    // Without a material Mitsuba uses eta = 0, k = 1: a Fresnel factor of 1.
                    let (eta, k) = ior.unwrap_or((Rgb::BLACK, Rgb::WHITE));
                    roughness.apply(|alpha_u, alpha_v| Material::RoughConductor {
                        distribution,
                        alpha_u,
                        alpha_v,
                        eta,
                        k,
                        specular_reflectance,
                    })
                } else {
                    match ior {
                        Some((eta, k)) => Material::Conductor { eta, k, specular_reflectance },
                        None => match specular_reflectance.as_constant() {
                            Some(c) if c == Rgb::WHITE => Material::perfect_mirror(),
                            _ => Material::Conductor { eta: Rgb::BLACK, k: Rgb::BLACK, specular_reflectance },
                        },
                    }
                }
            }
            "dielectric" | "thindielectric" | "roughdielectric" => {
                let (int_ior, ext_ior) = self.ior_pair(&p, 1.5046)?;
                let specular_reflectance = self.texture_prop(&p, "specular_reflectance", 1.0, reflectance)?;
                let specular_transmittance = self.texture_prop(&p, "specular_transmittance", 1.0, reflectance)?;
                match p.ty.as_str() {
                    "dielectric" => {
                        let dispersion = self.dispersion(&p)?;
                        Material::Dielectric {
                            int_ior,
                            ext_ior,
                            specular_reflectance,
                            specular_transmittance,
                            dispersion,
                        }
                    }
                    "thindielectric" => {
                        Material::ThinDielectric { int_ior, ext_ior, specular_reflectance, specular_transmittance }
                    }
                    _ => {
                        let (distribution, roughness) = self.roughness(&p, true)?;
                        roughness.apply(|alpha_u, alpha_v| Material::RoughDielectric {
                            distribution,
                            alpha_u,
                            alpha_v,
                            int_ior,
                            ext_ior,
                            specular_reflectance,
                            specular_transmittance,
                        })
                    }
                }
            }
            "plastic" | "roughplastic" => {
                let (int_ior, ext_ior) = self.ior_pair(&p, 1.49)?;
                let diffuse_reflectance = self.texture_prop(&p, "diffuse_reflectance", 0.5, reflectance)?;
                let specular_reflectance = self.texture_prop(&p, "specular_reflectance", 1.0, reflectance)?;
                let nonlinear = p.boolean_or("nonlinear", false)?;
                if p.ty == "plastic" {
                    Material::Plastic { diffuse_reflectance, specular_reflectance, int_ior, ext_ior, nonlinear }
                } else {
                    let (distribution, roughness) = self.roughness(&p, false)?;
                    roughness.apply(|alpha, _| Material::RoughPlastic {
                        distribution,
                        alpha,
                        diffuse_reflectance,
                        specular_reflectance,
                        int_ior,
                        ext_ior,
                        nonlinear,
                    })
                }
            }
            "blendbsdf" => {
                if !p.has("weight") {
                    return Err(p.error("missing required property 'weight'"));
                }
                let weight = self.texture_prop(&p, "weight", 0.5, reflectance)?;
                let nested = unmasked(&p, self.nested_bsdfs(&p)?)?;
                outermost_maps(&p, &nested)?;
                let [first, second]: [Material; 2] = nested.try_into().map_err(|v: Vec<Material>| {
                    p.error(format!("needs exactly two nested BSDFs, found {}", v.len()))
                })?;
                Material::Blend { weight, first: Box::new(first), second: Box::new(second) }
            }
            "twosided" => {
                let (nested, nested_opacity) = twosided_parts(&p, self.nested_bsdfs(&p)?)?;
                opacity = nested_opacity;
                outermost_maps(&p, &nested)?;
                let mut nested = nested.into_iter();
                match (nested.next(), nested.next(), nested.next()) {
                    (Some(front), back, None) => {
                        Material::TwoSided { front: Box::new(front), back: back.map(Box::new) }
                    }
                    _ => return Err(p.error("needs one or two nested BSDFs")),
                }
            }
            "principled" => self.principled(&p)?,
            "principledthin" => self.principled_thin(&p)?,
            "hair" => self.hair(&p)?,
            "fluorescent" => self.fluorescent(&p)?,
            "normalmap" | "bumpmap" => self.perturbing(&p)?,
            "mask" => {
                let (material, mask) = self.mask(&p)?;
                opacity = Some(mask);
                material
            }
            "null" => return Err(p.error("a null bsdf is supported only as a shape's own bsdf")),
            other => return Err(p.error(format!("unsupported bsdf type '{other}'"))),
        };
        p.ignore(&["sample_visible"]);
        p.finish(&mut self.warnings);
        Ok(Masked { material, opacity })
    }

    /// `<bsdf type="fluorescent">` (our extension): a Lambertian `reflectance` (colour or
    /// texture, default 0.5) plus fluorescence with raised-cosine bands
    /// ([`spectrum::fluorescence`]): `absorption_center`, `absorption_width`,
    /// `emission_center`, `emission_width` (nm, the widths are half widths of the support;
    /// required), `absorption_peak` (fraction absorbed at the centre, in [0, 1], default 0.5)
    /// and `quantum_yield` (fraction of the absorbed energy re-emitted, in [0, 1], default 1).
    /// Bad numbers, an emission band not entirely above the absorption band, and a material
    /// that would reflect more than it receives are errors at the element.
    fn fluorescent(&mut self, p: &Plugin<'a>) -> Result<Material, SceneError> {
        use spectrum::fluorescence::{Band, Fluorescence};
        let reflectance = self.texture_prop(p, "reflectance", 0.5, SpectrumUse::Reflectance)?;
        let band = |centre: &str, width: &str| -> Result<Band, SceneError> {
            Ok(Band { center_nm: p.float_required(centre)? as f32, half_width_nm: p.float_required(width)? as f32 })
        };
        let absorption = band("absorption_center", "absorption_width")?;
        let emission = band("emission_center", "emission_width")?;
        let peak = p.float_or("absorption_peak", 0.5)? as f32;
        let quantum_yield = p.float_or("quantum_yield", 1.0)? as f32;
        let fluorescence = Fluorescence::new(peak, absorption, emission, quantum_yield).map_err(|e| p.error(e))?;
        let material = Material::Fluorescent { reflectance, fluorescence };
        material.validate().map_err(|e| p.error(e))?;
        Ok(material)
    }

    /// `<bsdf type="normalmap">` (a texture `normalmap` of tangent-space normals, raw data) or
    /// `<bsdf type="bumpmap">` (one nested texture of any name, its luminance the height, and
    /// `scale`, default 1), each around exactly one nested BSDF. They must be the outermost
    /// BSDF of a shape. `flip_invalid_normals` and `use_shadowing_function` (default true)
    /// switch Mitsuba's per-query adapter ([`MapOptions`]).
    fn perturbing(&mut self, p: &Plugin<'a>) -> Result<Material, SceneError> {
        let texture = if p.ty == "normalmap" {
            if p.named_object("normalmap").is_none() && !p.has("normalmap") {
                return Err(p.error("missing the texture 'normalmap'"));
            }
            self.texture_prop(p, "normalmap", 0.5, SpectrumUse::Unbounded)?
        } else {
            let object = p
                .objects
                .iter()
                .find(|o| !o.is_taken() && (o.node.tag == "texture" || o.node.tag == "ref") && o.name.is_some())
                .ok_or_else(|| p.error("missing the height texture (a nested <texture>)"))?;
            let name = object.name.clone().unwrap_or_default();
            self.texture_prop(p, &name, 0.0, SpectrumUse::Unbounded)?
        };
        let mut nested = unmasked(p, self.nested_bsdfs(p)?)?.into_iter();
        let (Some(nested), None) = (nested.next(), nested.next()) else {
            return Err(p.error("needs exactly one nested BSDF"));
        };
        let nested = Box::new(nested);
        let options = MapOptions {
            flip_invalid_normals: p.boolean_or("flip_invalid_normals", true)?,
            shadowing: p.boolean_or("use_shadowing_function", true)?,
        };
        let material = if p.ty == "normalmap" {
            Material::NormalMap { normals: texture, nested, options }
        } else {
            let scale = p.float_or("scale", 1.0)?;
            if !scale.is_finite() {
                return Err(p.error(format!("'scale' must be a finite number, got {scale}")));
            }
            Material::BumpMap { height: texture, scale: scale as f32, nested, options }
        };
        material.validate().map_err(|e| p.error(e))?;
        Ok(material)
    }

    /// The nested BSDFs (inline or referenced) of a blend or two-sided BSDF, in order.
    pub(crate) fn nested_bsdfs(&mut self, p: &Plugin<'a>) -> Result<Vec<Masked>, SceneError> {
        let mut out = Vec::new();
        for object in &p.objects {
            let node = object.node;
            match node.tag.as_str() {
                "bsdf" if !object.is_taken() => {
                    object.take();
                    out.push(self.bsdf(node)?);
                }
                "ref" if !object.is_taken() => {
                    object.take();
                    match self.resolve(node.required_attr("id")?, node)? {
                        Resolved::Bsdf(m) => out.push(m),
                        other => {
                            return Err(node.pos.error(format!(
                                "{}: reference to a {}, expected a bsdf",
                                p.what(),
                                other.kind()
                            )));
                        }
                    }
                }
                _ => {}
            }
        }
        Ok(out)
    }
}

/// A texture as Mitsuba evaluates it as a float (`eval_1`, what roughness reads): a checkerboard
/// there takes `color0` where the parities of `u` and `v` differ, the opposite of its colour
/// evaluation (Mitsuba 2 and 3, "legacy scalar checkerboard convention"), so its colours swap.
pub(super) fn float_evaluation(texture: Texture) -> Texture {
    match texture {
        Texture::Checkerboard { color0, color1, to_uv } => {
            Texture::Checkerboard { color0: color1, color1: color0, to_uv }
        }
        other => other,
    }
}

/// A rough material's α: numbers, or textures evaluated at each hit.
enum Roughness {
    /// `(α_u, α_v)`.
    Constant(f32, f32),
    /// `(α_u, α_v)` textures.
    Textured(Texture, Texture),
}

impl Roughness {
    /// The rough material `make(α_u, α_v)`, wrapped in [`Material::TexturedRoughness`] when
    /// the roughness is textured (its own α is then unused).
    fn apply(self, make: impl FnOnce(f32, f32) -> Material) -> Material {
        match self {
            Roughness::Constant(u, v) => make(u, v),
            Roughness::Textured(alpha_u, alpha_v) => {
                Material::TexturedRoughness { alpha_u, alpha_v, remap: false, nested: Box::new(make(0.1, 0.1)) }
            }
        }
    }
}

/// An error when a normal or bump map is nested in `p` (they must be the outermost BSDF).
fn outermost_maps(p: &Plugin, nested: &[Material]) -> Result<(), SceneError> {
    if nested.iter().any(Material::perturbs_shading_normal) {
        return Err(p.error("a normalmap or bumpmap must be the outermost bsdf (wrap the blend or twosided in it)"));
    }
    Ok(())
}

/// The 2D affine part of a 4×4 `to_uv` transform (as Mitsuba reduces it).
fn uv_transform(m: &Mat4) -> UvTransform {
    let f = |v: f64| v as f32;
    UvTransform {
        columns: [Vec2::new(f(m.m[0][0]), f(m.m[1][0])), Vec2::new(f(m.m[0][1]), f(m.m[1][1]))],
        translation: Vec2::new(f(m.m[0][3]), f(m.m[1][3])),
    }
}
