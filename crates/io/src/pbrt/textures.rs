//! Textures: the `Texture` directive and the texture-or-value parameters of materials and lights.

use std::path::Path;
use std::sync::Arc;

use math::Vec2;
use scene::desc::{TextureImage, UvTransform};
use scene::texture::{FilterMode, Sampling, Texture, WrapMode};
use spectrum::Rgb;

use crate::pbrt::parser::{Directive, ParamSet, Value};
use crate::scene_error::SceneError;

use super::color;
use super::{Builder, NamedTexture, err, resolve};

impl Builder {
    /// A spectrum-valued parameter of a material or texture (`rgb`, `spectrum`, `float`,
    /// `texture`). `albedo` restricts values to [0, 1] and rejects named spectra.
    pub(super) fn spectrum_texture(
        &self,
        p: &ParamSet,
        name: &str,
        default: Rgb,
        albedo: bool,
    ) -> Result<Texture, SceneError> {
        let Some(param) = p.find(name) else { return Ok(Texture::Constant(default)) };
        let pos = param.pos;
        let value = match param.ty.as_str() {
            "rgb" => {
                let v = param.numbers();
                if v.len() != 3 {
                    return Err(p.error(pos, format!("parameter '{name}' needs 3 values, got {}", v.len())));
                }
                Rgb::new(v[0] as f32, v[1] as f32, v[2] as f32)
            }
            "float" => match param.numbers()[..] {
                [x] => Rgb::splat(x as f32),
                _ => return Err(p.error(pos, format!("parameter '{name}' needs one value"))),
            },
            "spectrum" => match &param.values[..] {
                [Value::Str(s)] => {
                    if albedo {
                        return Err(p.error(pos, format!("named spectrum \"{s}\" cannot be a reflectance")));
                    }
                    color::named_metal(s)
                        .ok_or_else(|| p.error(pos, format!("unknown or unsupported named spectrum \"{s}\"")))?
                }
                [Value::Num(x)] => Rgb::splat(*x as f32),
                _ => {
                    let v = param.numbers();
                    if albedo {
                        return Err(p.error(
                            pos,
                            format!("parameter '{name}': sampled reflectance spectra are not supported (use rgb)"),
                        ));
                    }
                    let s = color::piecewise_linear(&v).filter(|_| v.len() % 2 == 0).ok_or_else(|| {
                        p.error(
                            pos,
                            format!("parameter '{name}': expected wavelength/value pairs with increasing wavelengths"),
                        )
                    })?;
                    let [r, g, b] = color::PRIMARY_WAVELENGTHS.map(|l| s(l) as f32);
                    Rgb::new(r, g, b)
                }
            },
            "texture" => {
                let [Value::Str(t)] = &param.values[..] else {
                    return Err(p.error(pos, format!("parameter '{name}' needs one texture name")));
                };
                return match self.textures.get(t) {
                    Some(tex) => Ok(tex.texture.clone()),
                    None => Err(p.error(pos, format!("unknown texture \"{t}\""))),
                };
            }
            other => {
                return Err(p.error(
                    pos,
                    format!("parameter '{name}' has type '{other}', expected rgb, spectrum, float or texture"),
                ));
            }
        };
        if !value.is_finite() || (albedo && (value.r.min(value.g).min(value.b) < 0.0 || value.max_component() > 1.0)) {
            return Err(p.error(pos, format!("{name} = ({}, {}, {}) is outside [0, 1]", value.r, value.g, value.b)));
        }
        Ok(Texture::Constant(value))
    }

    /// A float parameter that pbrt allows to be a texture; we need a constant.
    pub(super) fn constant_float(&self, p: &ParamSet, name: &str, default: f32) -> Result<f32, SceneError> {
        let Some(param) = p.find(name) else { return Ok(default) };
        match param.ty.as_str() {
            "float" => p.float(name, default),
            "texture" => {
                let [Value::Str(t)] = &param.values[..] else {
                    return Err(p.error(param.pos, format!("parameter '{name}' needs one texture name")));
                };
                match self.textures.get(t).map(|x| &x.texture) {
                    Some(Texture::Constant(c)) => Ok(c.r),
                    Some(_) => {
                        Err(p
                            .error(param.pos, format!("parameter '{name}': only constant textures are supported here")))
                    }
                    None => Err(p.error(param.pos, format!("unknown texture \"{t}\""))),
                }
            }
            other => {
                Err(p.error(param.pos, format!("parameter '{name}' has type '{other}', expected float or texture")))
            }
        }
    }

    pub(super) fn texture_directive(&mut self, file: &Path, d: &Directive) -> Result<(), SceneError> {
        let name = d.str_arg(0).to_string();
        let kind = d.str_arg(1);
        let class = d.str_arg(2);
        let p = &d.params;
        if kind != "spectrum" && kind != "float" {
            return Err(err(file, d.arg_pos[1], format!("texture type \"{kind}\" (expected spectrum or float)")));
        }
        if self.textures.contains_key(&name) {
            return Err(err(file, d.arg_pos[0], format!("texture \"{name}\" defined twice")));
        }
        let uv = |p: &ParamSet| -> Result<(f32, f32, f32, f32), SceneError> {
            if let Some((m, pos)) = p.string("mapping")?
                && m != "uv"
            {
                return Err(p.error(pos, format!("texture mapping \"{m}\" is not supported (only uv)")));
            }
            Ok((p.float("uscale", 1.0)?, p.float("vscale", 1.0)?, p.float("udelta", 0.0)?, p.float("vdelta", 0.0)?))
        };
        let texture = match class {
            "constant" => {
                if kind == "float" {
                    Texture::Constant(Rgb::splat(p.float("value", 1.0)?))
                } else {
                    self.spectrum_texture(p, "value", Rgb::WHITE, false)?
                }
            }
            "checkerboard" => {
                let dimension = p.int("dimension", 2)?;
                if dimension != 2 {
                    return Err(err(file, d.pos, "3D checkerboard textures are not supported"));
                }
                let (su, sv, du, dv) = uv(p)?;
                let constant = |name: &str, default: f32| -> Result<Rgb, SceneError> {
                    match self.spectrum_texture(p, name, Rgb::splat(default), false)? {
                        Texture::Constant(c) => Ok(c),
                        _ => Err(p.error(d.pos, format!("checkerboard: '{name}' must be a constant, not a texture"))),
                    }
                };
                // pbrt: tex1 where floor(s) + floor(t) is even, with (s, t) = (su·u + du, sv·v + dv).
                // Ours: colour0 where frac(s') and frac(t') lie on the same side of ½; with
                // (s', t') = (s, t) / 2 the two agree.
                Texture::Checkerboard {
                    color0: constant("tex1", 1.0)?,
                    color1: constant("tex2", 0.0)?,
                    to_uv: UvTransform {
                        columns: [Vec2::new(su * 0.5, 0.0), Vec2::new(0.0, sv * 0.5)],
                        translation: Vec2::new(du * 0.5, dv * 0.5),
                    },
                }
            }
            "imagemap" => {
                let Some((filename, fpos)) = p.string("filename")? else {
                    return Err(err(file, d.pos, "imagemap texture needs a \"string filename\""));
                };
                let path = resolve(file, &filename);
                let stored =
                    crate::read_texture_file(&path).map_err(|e| p.error(fpos, format!("cannot read image: {e}")))?;
                // pbrt-v4: `encoding` applies to 8-bit (here: every integer) images, default sRGB;
                // float images are linear.
                let encoding = match p.string("encoding")? {
                    None => crate::TextureEncoding::Srgb,
                    Some((e, _)) if e == "sRGB" => crate::TextureEncoding::Srgb,
                    Some((e, _)) if e == "linear" => crate::TextureEncoding::Linear,
                    Some((e, epos)) => match e.strip_prefix("gamma ").map(|g| g.trim().parse::<f32>()) {
                        Some(Ok(g)) if g.is_finite() && g > 0.0 => crate::TextureEncoding::Gamma(g),
                        _ => {
                            return Err(p.error(
                                epos,
                                format!("encoding \"{e}\" is not one of \"sRGB\", \"linear\", \"gamma <g>\" (g > 0)"),
                            ));
                        }
                    },
                };
                let image = stored.linear(encoding);
                let filter = match p.string("filter")? {
                    None => FilterMode::Bilinear,
                    Some((f, _)) if f == "bilinear" => FilterMode::Bilinear,
                    Some((f, _)) if f == "point" => FilterMode::Nearest,
                    Some((f, fpos)) if f == "trilinear" || f == "ewa" || f == "EWA" => {
                        self.unsupported(
                            p.error(fpos, format!("imagemap filter \"{f}\" (MIP-mapping) is not supported")),
                            "bilinear filtering used",
                        )?;
                        FilterMode::Bilinear
                    }
                    Some((f, fpos)) => {
                        return Err(p.error(fpos, format!("unknown imagemap filter \"{f}\"")));
                    }
                };
                let wrap = match p.string("wrap")? {
                    None => WrapMode::Repeat,
                    Some((w, _)) if w == "repeat" => WrapMode::Repeat,
                    Some((w, _)) if w == "clamp" => WrapMode::Clamp,
                    Some((w, _)) if w == "black" => WrapMode::Black,
                    Some((w, wpos)) => {
                        return Err(p.error(wpos, format!("imagemap wrap \"{w}\" is not one of repeat, clamp, black")));
                    }
                };
                p.float("maxanisotropy", 8.0)?;
                let scale = p.float("scale", 1.0)?;
                let invert = p.bool("invert", false)?;
                let (su, sv, du, dv) = uv(p)?;
                let pixels = image
                    .pixels
                    .iter()
                    .map(|px| {
                        let mut c = *px;
                        if kind == "float" {
                            c = [c[0]; 3];
                        }
                        let c = c.map(|v| {
                            let v = v * scale;
                            if invert { (1.0 - v).max(0.0) } else { v }
                        });
                        Rgb::from_array(c)
                    })
                    .collect();
                let image = Arc::new(TextureImage { width: image.width as u32, height: image.height as u32, pixels });
                // pbrt looks up (s, 1 − t): t = 0 is the bottom row; our v' runs from the top.
                let to_uv = UvTransform {
                    columns: [Vec2::new(su, 0.0), Vec2::new(0.0, -sv)],
                    translation: Vec2::new(du, 1.0 - dv),
                };
                Texture::bitmap(image, to_uv, Sampling { wrap, filter })
            }
            "scale" => {
                let texture = self.spectrum_texture(p, "tex", Rgb::WHITE, false)?;
                let scale = self.spectrum_texture(p, "scale", Rgb::WHITE, false)?;
                match (texture.as_constant(), scale.as_constant()) {
                    (Some(a), Some(b)) => Texture::Constant(a * b),
                    _ => Texture::Scale { texture: Arc::new(texture), scale: Arc::new(scale) },
                }
            }
            "mix" => {
                let tex1 = self.spectrum_texture(p, "tex1", Rgb::BLACK, false)?;
                let tex2 = self.spectrum_texture(p, "tex2", Rgb::WHITE, false)?;
                let amount = self.spectrum_texture(p, "amount", Rgb::splat(0.5), false)?;
                if let Some(a) = amount.as_constant()
                    && !(0.0..=1.0).contains(&a.r)
                {
                    let pos = p.find("amount").map_or(d.pos, |x| x.pos);
                    return Err(p.error(pos, format!("mix amount {} outside [0, 1] is not supported", a.r)));
                }
                match (tex1.as_constant(), tex2.as_constant(), amount.as_constant()) {
                    (Some(a), Some(b), Some(t)) => Texture::Constant(a * (1.0 - t.r) + b * t.r),
                    _ => Texture::Mix { tex1: Arc::new(tex1), tex2: Arc::new(tex2), amount: Arc::new(amount) },
                }
            }
            other @ ("directionmix" | "bilerp" | "dots" | "fbm" | "wrinkled" | "windy" | "marble" | "ptex") => {
                return Err(err(file, d.arg_pos[2], format!("texture class \"{other}\" is not supported")));
            }
            other => return Err(err(file, d.arg_pos[2], format!("unknown texture class \"{other}\""))),
        };
        self.warn_unused(p);
        self.textures.insert(name, NamedTexture { texture });
        Ok(())
    }
}
