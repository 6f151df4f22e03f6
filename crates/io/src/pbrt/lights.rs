//! Lights: `LightSource` and `AreaLightSource`, their emission spectra and images.

use std::path::Path;
use std::sync::Arc;

use math::{Vec2, Vec3};
use scene::desc::{EmissionSpectrum, LightDesc, TextureImage, UvTransform};
use scene::texture::{FilterMode, Sampling, Texture, WrapMode};
use spectrum::Rgb;
use spectrum::tabulated::Tabulated;

use crate::pbrt::parser::{Directive, ParamSet, Value};
use crate::pbrt::transform::{V3, normalize};
use crate::scene_error::SceneError;

use super::{Builder, err, f32v, resolve, rotation_columns, similarity_scale};
use super::{color, envmap, goniometric, transform};

impl Builder {
    /// A light's spectrum as RGB radiance/intensity before `scale` (see [`color`]) and, for
    /// blackbody, sampled and constant spectra, the spectrum itself, normalised like the RGB
    /// value to luminance `Y = ∫ s ȳ dλ / ∫ ȳ dλ = 1` (pbrt-v4's photometric normalisation; its
    /// blackbody is normalised to peak 1 first, which this cancels).
    pub(super) fn light_emission(
        &self,
        p: &ParamSet,
        name: &str,
    ) -> Result<(Rgb, Option<EmissionSpectrum>), SceneError> {
        let Some(param) = p.find(name) else { return Ok((Rgb::WHITE, None)) };
        let pos = param.pos;
        let nums = param.numbers();
        let normalised = |s: &dyn Fn(f64) -> f64| {
            color::emission_rgb(s).ok_or_else(|| p.error(pos, format!("parameter '{name}': spectrum has no luminance")))
        };
        // The spectrum scaled to Y = 1 (None when it has no luminance: the RGB path reports it).
        let unit = |s: EmissionSpectrum| -> Result<Option<EmissionSpectrum>, SceneError> {
            let y = s.xyz()[1];
            if !(y > 0.0 && y.is_finite()) {
                return Ok(None);
            }
            let s = s.scaled((1.0 / y) as f32).map_err(|e| p.error(pos, format!("parameter '{name}': {e}")))?;
            s.validate().map_err(|e| p.error(pos, format!("parameter '{name}': {e}")))?;
            Ok(Some(s))
        };
        let flat = || -> Result<Option<EmissionSpectrum>, SceneError> {
            let t = Tabulated::new(&[(360.0, 1.0), (830.0, 1.0)]).map_err(|e| p.error(pos, e))?;
            unit(EmissionSpectrum::Tabulated(Arc::new(t)))
        };
        let mut spectrum = None;
        let rgb = match param.ty.as_str() {
            "rgb" => match nums[..] {
                [r, g, b] => Rgb::new(r as f32, g as f32, b as f32),
                _ => return Err(p.error(pos, format!("parameter '{name}' needs 3 values, got {}", nums.len()))),
            },
            "blackbody" => match nums[..] {
                [t] if t > 0.0 => {
                    spectrum = unit(EmissionSpectrum::Blackbody { kelvin: t as f32, scale: 1.0 })?;
                    normalised(&|l| color::planck(l, t))?
                }
                _ => return Err(p.error(pos, format!("parameter '{name}' needs one positive temperature in kelvin"))),
            },
            "spectrum" => match &param.values[..] {
                [Value::Str(s)] if s == "stdillum-D65" => Rgb::WHITE,
                [Value::Str(s)] => {
                    return Err(p.error(pos, format!("named spectrum \"{s}\" is not supported for lights (stdillum-D65, blackbody, rgb or sampled spectra are)")));
                }
                [Value::Num(_)] => {
                    spectrum = flat()?;
                    normalised(&|_| 1.0)?
                }
                _ => {
                    let s = color::piecewise_linear(&nums).filter(|_| nums.len() % 2 == 0).ok_or_else(|| {
                        p.error(
                            pos,
                            format!("parameter '{name}': expected wavelength/value pairs with increasing wavelengths"),
                        )
                    })?;
                    let points: Vec<(f32, f32)> = nums.chunks_exact(2).map(|c| (c[0] as f32, c[1] as f32)).collect();
                    let table =
                        Tabulated::new(&points).map_err(|e| p.error(pos, format!("parameter '{name}': {e}")))?;
                    spectrum = unit(EmissionSpectrum::Tabulated(Arc::new(table)))?;
                    normalised(&s)?
                }
            },
            "float" => {
                spectrum = flat()?;
                normalised(&|_| 1.0)?
            }
            other => {
                return Err(p.error(
                    pos,
                    format!("parameter '{name}' has type '{other}', expected rgb, spectrum or blackbody"),
                ));
            }
        };
        if !rgb.is_finite() {
            return Err(p.error(pos, format!("parameter '{name}' is not finite")));
        }
        Ok((rgb, spectrum))
    }

    /// pbrt-v4's `projection` light: the image (`filename`, looked up nearest-texel, row 0 at
    /// the top) is the intensity `scale·E` (W/sr) over a pinhole frustum along the light's +z
    /// whose shorter image axis spans `fov` degrees; the image's left is the light's −x and its
    /// top the light's +y (pbrt flips y). `power` rescales so that the flux, Σ over texels of
    /// luminance·cos³θ times the frustum's plane area over the texel count, is `power` watts.
    pub(super) fn projection_light(&self, file: &Path, d: &Directive, scale: f32) -> Result<LightDesc, SceneError> {
        let p = &d.params;
        let (filename, fpos) =
            p.string("filename")?.ok_or_else(|| err(file, d.pos, "projection: \"filename\" is required"))?;
        let fov = p.float("fov", 90.0)?;
        if !(fov > 0.0 && fov < 180.0) {
            return Err(err(file, d.pos, format!("projection: fov {fov} is not in (0, 180) degrees")));
        }
        let power = p.float_opt("power")?;
        let image = light_image(&resolve(file, &filename), 1.0).map_err(|e| p.error(fpos, e))?;
        let (width, height) = (image.width as usize, image.height as usize);
        let aspect = width as f32 / height as f32;
        let tan = (0.5 * fov.to_radians()).tan();
        // The screen window is [-a, a]×[-1, 1] for a wide image and [-1, 1]×[-1/a, 1/a] otherwise.
        let (bx, by) = if aspect > 1.0 { (aspect, 1.0) } else { (1.0, 1.0 / aspect) };
        let mut scale = scale;
        if let Some(power) = power.filter(|&power| power > 0.0) {
            let area = 4.0 * tan * tan * bx * by;
            let mut sum = 0.0f64;
            for (i, texel) in image.pixels.iter().enumerate() {
                let x = (2.0 * ((i % width) as f32 + 0.5) / width as f32 - 1.0) * bx * tan;
                let y = (2.0 * ((i / width) as f32 + 0.5) / height as f32 - 1.0) * by * tan;
                let cos3 = (1.0 + x * x + y * y).powf(-1.5);
                sum += f64::from(texel.luminance() * cos3);
            }
            let flux = f64::from(area) * sum / (width * height) as f64;
            if flux <= 0.0 {
                return Err(p.error(fpos, "projection: a black image cannot have a power"));
            }
            scale *= (f64::from(power) / flux) as f32;
        }
        let ctm = self.state.ctm;
        if similarity_scale(&ctm).is_none() {
            return Err(err(file, d.pos, "projection light under a non-uniform scale or shear"));
        }
        let axis =
            |v: V3| normalize(ctm.vector(v)).map(f32v).ok_or_else(|| err(file, d.pos, "singular transformation"));
        let (x, y, z) = (axis([1.0, 0.0, 0.0])?, axis([0.0, 1.0, 0.0])?, axis([0.0, 0.0, 1.0])?);
        let fov_x_degrees = 2.0 * (bx * tan).atan().to_degrees();
        let sampling = Sampling { wrap: WrapMode::Clamp, filter: FilterMode::Nearest };
        Ok(LightDesc::Projector {
            model: scene::desc::ProjectorModel::Intensity,
            position: f32v(ctm.point([0.0; 3])),
            frame: [-x, y, z],
            irradiance: Arc::new(Texture::bitmap(image, UvTransform::IDENTITY, sampling)),
            scale,
            fov_x_degrees,
            aspect,
        })
    }

    pub(super) fn area_light_directive(&mut self, file: &Path, d: &Directive) -> Result<(), SceneError> {
        if d.str_arg(0) != "diffuse" {
            return Err(err(
                file,
                d.arg_pos[0],
                format!("unknown area light type \"{}\" (expected diffuse)", d.str_arg(0)),
            ));
        }
        let p = &d.params;
        if let Some(x) = p.find("power") {
            return Err(p.error(x.pos, "parameter 'power' is not supported"));
        }
        if p.bool("twosided", false)? {
            let pos = p.find("twosided").map_or(d.pos, |x| x.pos);
            return Err(p.error(pos, "two-sided area lights are not supported (our emitters are one-sided)"));
        }
        let scale = p.float("scale", 1.0)?;
        self.state.area_light_texture = None;
        if let Some((filename, fpos)) = p.string("filename")? {
            if let Some(x) = p.find("L") {
                return Err(p.error(x.pos, "'L' and 'filename' exclude each other"));
            }
            let texture = area_light_image(&resolve(file, &filename), scale).map_err(|e| p.error(fpos, e))?;
            self.state.area_light = Some(texture.max_value().max(Rgb::splat(f32::MIN_POSITIVE)));
            self.state.area_light_spectrum = None;
            self.state.area_light_texture = Some(Arc::new(texture));
            self.warn_unused(p);
            return Ok(());
        }
        let (l, spectrum) = self.light_emission(p, "L")?;
        self.state.area_light = Some(l * scale);
        self.state.area_light_spectrum = match spectrum {
            Some(s) => Some(s.scaled(scale).map_err(|e| err(file, d.pos, e))?),
            None => None,
        };
        self.warn_unused(p);
        Ok(())
    }

    pub(super) fn light_directive(&mut self, file: &Path, d: &Directive) -> Result<(), SceneError> {
        let p = &d.params;
        let ctm = self.state.ctm;
        let scale = p.float("scale", 1.0)?;
        let point3 = |name: &str, default: V3| -> Result<V3, SceneError> {
            match p.numbers(name, &["point3"], 3)? {
                Some((v, pos)) if v.len() != 3 => Err(p.error(pos, format!("'{name}' needs one point"))),
                Some((v, _)) => Ok([v[0], v[1], v[2]]),
                None => Ok(default),
            }
        };
        let direction = |from: V3, to: V3| -> Result<Vec3, SceneError> {
            normalize(ctm.vector(transform::sub(to, from)))
                .map(f32v)
                .ok_or_else(|| err(file, d.pos, "'from' and 'to' coincide"))
        };
        // The unscaled RGB value and spectrum of a light given spectrally.
        let mut spectrum: Option<(Rgb, EmissionSpectrum)> = None;
        let light = match d.str_arg(0) {
            "point" => {
                let mut intensity = self.light_emission(p, "I").map(|(c, s)| {
                    spectrum = s.map(|s| (c, s));
                    c
                })? * scale;
                if let Some(power) = p.float_opt("power")? {
                    intensity *= power / (4.0 * std::f32::consts::PI);
                }
                LightDesc::Point { position: f32v(ctm.point(point3("from", [0.0; 3])?)), intensity }
            }
            "spot" => {
                let from = point3("from", [0.0; 3])?;
                let to = point3("to", [0.0, 0.0, 1.0])?;
                let cone = p.float("coneangle", 30.0)?;
                if let Some(old) = p.find("conedelta") {
                    return Err(
                        p.error(old.pos, "spot: pbrt-v4 calls this parameter \"conedeltaangle\", not \"conedelta\"")
                    );
                }
                let delta = p.float("conedeltaangle", 5.0)?;
                if !(cone > 0.0 && cone <= 180.0 && (0.0..=cone).contains(&delta)) {
                    return Err(err(
                        file,
                        d.pos,
                        format!("spot: coneangle {cone} / conedeltaangle {delta} out of range"),
                    ));
                }
                let mut intensity = self.light_emission(p, "I").map(|(c, s)| {
                    spectrum = s.map(|s| (c, s));
                    c
                })? * scale;
                if let Some(power) = p.float_opt("power")? {
                    let (cos_end, cos_start) = (cone.to_radians().cos(), (cone - delta).to_radians().cos());
                    let k = 2.0 * std::f32::consts::PI * ((1.0 - cos_start) + (cos_start - cos_end) / 2.0);
                    intensity *= power / k;
                }
                LightDesc::Spot {
                    position: f32v(ctm.point(from)),
                    direction: direction(from, to)?,
                    intensity,
                    cutoff_degrees: cone,
                    beam_width_degrees: cone - delta,
                    texture: None,
                }
            }
            "distant" => {
                let from = point3("from", [0.0; 3])?;
                let to = point3("to", [0.0, 0.0, 1.0])?;
                let mut irradiance = self.light_emission(p, "L").map(|(c, s)| {
                    spectrum = s.map(|s| (c, s));
                    c
                })? * scale;
                if let Some(e) = p.float_opt("illuminance")? {
                    irradiance *= e;
                }
                LightDesc::Directional { direction: direction(from, to)?, irradiance }
            }
            "infinite" => {
                if self.lights.iter().any(|l| matches!(l, LightDesc::Constant { .. } | LightDesc::EnvMap { .. })) {
                    return Err(err(file, d.pos, "a second infinite light (only one environment is supported)"));
                }
                for name in ["illuminance", "portal"] {
                    if let Some(x) = p.find(name) {
                        return Err(p.error(x.pos, format!("parameter '{name}' is not supported")));
                    }
                }
                match p.string("filename")? {
                    None => LightDesc::Constant {
                        radiance: self.light_emission(p, "L").map(|(c, s)| {
                            spectrum = s.map(|s| (c, s));
                            c
                        })? * scale,
                    },
                    Some((filename, fpos)) => {
                        if let Some(x) = p.find("L") {
                            return Err(p.error(x.pos, "'L' and 'filename' exclude each other"));
                        }
                        let path = resolve(file, &filename);
                        let image =
                            crate::read_image(&path).map_err(|e| p.error(fpos, format!("cannot read image: {e}")))?;
                        if image.width != image.height {
                            return Err(p.error(
                                fpos,
                                format!(
                                    "environment image is {}×{}: pbrt-v4 needs a square equal-area octahedral image",
                                    image.width, image.height
                                ),
                            ));
                        }
                        let to_world = rotation_columns(&ctm)
                            .ok_or_else(|| err(file, d.pos, "infinite light under a non-rotation transformation"))?;
                        LightDesc::EnvMap {
                            image: Arc::new(envmap::octahedral_to_latlong(image.width, &image.pixels)),
                            scale,
                            to_world,
                        }
                    }
                }
            }
            "projection" => self.projection_light(file, d, scale)?,
            "goniometric" => {
                let intensity = self.light_emission(p, "I").map(|(c, s)| {
                    spectrum = s.map(|s| (c, s));
                    c
                })? * scale;
                goniometric::goniometric_light(file, d, &ctm, intensity)?
            }
            other => return Err(err(file, d.arg_pos[0], format!("unknown light type \"{other}\""))),
        };
        if let Some((unscaled, s)) = spectrum {
            // The file's scale, power and illuminance factors multiply every channel alike.
            let value = match &light {
                LightDesc::Point { intensity, .. }
                | LightDesc::Spot { intensity, .. }
                | LightDesc::Goniometric { intensity, .. } => *intensity,
                LightDesc::Directional { irradiance, .. } => *irradiance,
                LightDesc::Constant { radiance } => *radiance,
                LightDesc::EnvMap { .. } | LightDesc::Projector { .. } => Rgb::BLACK,
            };
            let base = scene::LightSpectrum { spectrum: s, base: unscaled };
            let scaled = base.spectrum.scaled(base.factor(value)).map_err(|e| err(file, d.pos, e))?;
            self.emission_spectra.lights.insert(self.lights.len() as u32, scaled);
        }
        self.lights.push(light);
        self.warn_unused(p);
        Ok(())
    }
}

/// The radiance image of a `diffuse` area light (`filename`), times `scale`: 8-bit images
/// sRGB-decoded, float images linear, looked up bilinearly at `(u, 1 − v)` (pbrt-v4's
/// convention for images, as for `imagemap`) with clamped edges.
/// An emitter's image file as linear texels times `scale` (8-bit files decoded from sRGB, as
/// pbrt-v4 reads them); negative or non-finite values are errors.
pub(super) fn light_image(path: &Path, scale: f32) -> Result<Arc<TextureImage>, String> {
    let stored = crate::read_texture_file(path).map_err(|e| format!("cannot read image: {e}"))?;
    let image = stored.linear(crate::TextureEncoding::Srgb);
    if let Some(v) = image.pixels.iter().flatten().find(|v| !v.is_finite() || **v < 0.0) {
        return Err(format!("image '{}' has a negative or non-finite value {v}", path.display()));
    }
    let pixels = image.pixels.iter().map(|px| Rgb::from_array(px.map(|v| v * scale))).collect();
    Ok(Arc::new(TextureImage { width: image.width as u32, height: image.height as u32, pixels }))
}

pub(super) fn area_light_image(path: &Path, scale: f32) -> Result<Texture, String> {
    let image = light_image(path, scale)?;
    let to_uv = UvTransform { columns: [Vec2::new(1.0, 0.0), Vec2::new(0.0, -1.0)], translation: Vec2::new(0.0, 1.0) };
    Ok(Texture::bitmap(image, to_uv, Sampling { wrap: WrapMode::Clamp, filter: FilterMode::Bilinear }))
}
