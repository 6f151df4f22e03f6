//! `<emitter>` plugins: area emitters (attached to shapes) and the other lights.

use std::sync::Arc;

use scene::Texture;
use scene::desc::{EmissionSpectrum, FilmDesc, FilterDesc, Geometry, LightDesc, SpotTexture, TextureImage};
use spectrum::Rgb;

use super::Loader;
use super::colour::SpectrumUse;
use super::props::Plugin;
use super::transform::{Mat4, cross, dot, length, normalize, to_vec3};
use super::xml::Node;
use crate::scene_error::SceneError;

fn rgb(v: [f64; 3]) -> Rgb {
    Rgb::new(v[0] as f32, v[1] as f32, v[2] as f32)
}

/// What an area emitter emits: its radiance (linear sRGB, W·m⁻²·sr⁻¹) and, when the file
/// gives it spectrally, its spectral radiance (W·m⁻²·sr⁻¹·nm⁻¹), or, when the file gives a
/// texture, that texture (then `radiance` is its upper bound, for messages only).
#[derive(Clone, Debug)]
pub(crate) struct AreaEmission {
    pub radiance: Rgb,
    pub spectrum: Option<EmissionSpectrum>,
    pub texture: Option<Arc<Texture>>,
}

impl<'a> Loader<'a> {
    /// An `<emitter type="area">`: its radiance.
    pub(crate) fn area_emitter(&mut self, node: &'a Node) -> Result<AreaEmission, SceneError> {
        let p = Plugin::new(node)?;
        if p.ty != "area" {
            return Err(p.error("only area emitters can be attached to shapes"));
        }
        if p.named_object("radiance").is_some() {
            let texture = self.texture_prop(&p, "radiance", 0.0, SpectrumUse::Emission)?;
            p.finish(&mut self.warnings);
            if let Some(name) = texture.mesh_attribute() {
                return Err(p.error(format!("an emitter cannot read the mesh attribute '{name}' (only bsdfs can)")));
            }
            let bound = texture.max_value();
            if !bound.is_finite() {
                return Err(p.error("the radiance texture has non-finite values"));
            }
            return Ok(AreaEmission { radiance: bound, spectrum: None, texture: Some(Arc::new(texture)) });
        }
        let radiance = p
            .color("radiance", SpectrumUse::Emission, &mut self.warnings)?
            .ok_or_else(|| p.error("missing required property 'radiance'"))?;
        let spectrum = p.emission_spectrum("radiance")?;
        p.finish(&mut self.warnings);
        Ok(AreaEmission { radiance: rgb(radiance), spectrum, texture: None })
    }

    /// Records what the shape about to be pushed emits: its spectrum, its texture (on meshes;
    /// on analytic shapes an error, or in a permissive load the texture's mean with a warning),
    /// and returns its RGB radiance.
    pub(crate) fn attach_area_emission(
        &mut self,
        e: AreaEmission,
        geometry: &Geometry,
        node: &Node,
    ) -> Result<Rgb, SceneError> {
        let index = self.shapes.len() as u32;
        if let Some(spectrum) = e.spectrum {
            self.emission_spectra.shapes.insert(index, spectrum);
        }
        match e.texture {
            None => Ok(e.radiance),
            Some(texture) if matches!(geometry, Geometry::Mesh(_)) => {
                self.emission_spectra.textures.insert(index, texture);
                Ok(e.radiance)
            }
            Some(texture) => {
                let error = node.pos.error(
                    "a textured 'radiance' is supported on triangle meshes only (obj, ply, serialized, \
                     rectangle, cube), not on spheres and discs",
                );
                self.unsupported(error, "the texture's mean value is used")?;
                Ok(super::textured::mean(&texture))
            }
        }
    }

    /// An emitter color with a default, and its spectrum when the file gives one (recorded for
    /// the light about to be pushed).
    fn emitted(&mut self, p: &Plugin, name: &str, default: f64) -> Result<Rgb, SceneError> {
        let value = rgb(p.color(name, SpectrumUse::Emission, &mut self.warnings)?.unwrap_or([default; 3]));
        if let Some(spectrum) = p.emission_spectrum(name)? {
            self.emission_spectra.lights.insert(self.lights.len() as u32, spectrum);
        }
        Ok(value)
    }

    /// A light that is not attached to a shape.
    pub(crate) fn light(&mut self, node: &'a Node) -> Result<(), SceneError> {
        let p = Plugin::new(node)?;
        let to_world = p.transform("to_world")?;
        let light = match p.ty.as_str() {
            "point" => {
                let position = match (p.vector("position")?, to_world) {
                    (Some(_), Some(_)) => return Err(p.error("give either 'position' or 'to_world', not both")),
                    (Some(v), None) => v,
                    (None, Some(m)) => m.point([0.0; 3]),
                    (None, None) => [0.0; 3],
                };
                LightDesc::Point { position: to_vec3(position), intensity: self.emitted(&p, "intensity", 1.0)? }
            }
            "spot" => {
                let m = to_world.unwrap_or(Mat4::IDENTITY);
                let direction = normalize(m.vector([0.0, 0.0, 1.0]))
                    .ok_or_else(|| p.error("'to_world' maps the spot axis (+z) to zero"))?;
                let cutoff = p.float_or("cutoff_angle", 20.0)?;
                let beam = p.float_or("beam_width", cutoff * 0.75)?;
                if !(cutoff > 0.0 && cutoff <= 180.0) {
                    return Err(p.error(format!("'cutoff_angle' must be in (0, 180] degrees, got {cutoff}")));
                }
                if beam.is_nan() || beam < 0.0 {
                    return Err(p.error(format!("'beam_width' must be non-negative, got {beam}")));
                }
                let beam = if beam > cutoff {
                    self.warnings.push(format!(
                        "{}: {}: beam_width {beam} exceeds cutoff_angle {cutoff}; clamped",
                        node.pos.location(),
                        p.what()
                    ));
                    cutoff
                } else {
                    beam
                };
                let texture = match p.named_object("texture") {
                    None => None,
                    Some(_) => {
                        let texture = self.texture_prop(&p, "texture", 1.0, SpectrumUse::Emission)?;
                        if cutoff >= 90.0 {
                            return Err(
                                p.error(format!("a spot 'texture' needs a cutoff_angle below 90°, got {cutoff}"))
                            );
                        }
                        let axis = |v: [f64; 3], name: &str| {
                            normalize(m.vector(v))
                                .ok_or_else(|| p.error(format!("'to_world' maps the {name} axis to zero")))
                        };
                        Some(SpotTexture {
                            texture: Arc::new(texture),
                            x_axis: to_vec3(axis([1.0, 0.0, 0.0], "x")?),
                            y_axis: to_vec3(axis([0.0, 1.0, 0.0], "y")?),
                        })
                    }
                };
                let intensity = self.emitted(&p, "intensity", 1.0)?;
                if texture.is_some() && self.emission_spectra.lights.contains_key(&(self.lights.len() as u32)) {
                    return Err(p.error("a spot light with a 'texture' needs an RGB 'intensity', not a spectrum"));
                }
                LightDesc::Spot {
                    position: to_vec3(m.point([0.0; 3])),
                    direction: to_vec3(direction),
                    intensity,
                    cutoff_degrees: cutoff as f32,
                    beam_width_degrees: beam as f32,
                    texture,
                }
            }
            "projector" => self.projector(&p, to_world.unwrap_or(Mat4::IDENTITY))?,
            "directional" => {
                let direction = match (p.vector("direction")?, to_world) {
                    (Some(_), Some(_)) => return Err(p.error("give either 'direction' or 'to_world', not both")),
                    (Some(v), None) => v,
                    (None, Some(m)) => m.vector([0.0, 0.0, 1.0]),
                    (None, None) => [0.0, 0.0, 1.0],
                };
                let direction = normalize(direction).ok_or_else(|| p.error("the direction is zero"))?;
                LightDesc::Directional {
                    direction: to_vec3(direction),
                    irradiance: self.emitted(&p, "irradiance", 1.0)?,
                }
            }
            "constant" => {
                self.check_single_environment(&p)?;
                LightDesc::Constant { radiance: self.emitted(&p, "radiance", 1.0)? }
            }
            "envmap" => {
                self.check_single_environment(&p)?;
                let filename = p.string_required("filename")?.to_string();
                let scale = p.float_or("scale", 1.0)?;
                if !scale.is_finite() || scale < 0.0 {
                    return Err(p.error(format!("'scale' must be non-negative, got {scale}")));
                }
                let to_world = self.rotation_part(&p, to_world.unwrap_or(Mat4::IDENTITY))?;
                let image = self.environment_image(&filename, node)?;
                LightDesc::EnvMap { image, scale: scale as f32, to_world }
            }
            "area" => return Err(p.error("an area emitter must be inside a <shape> or referenced by one")),
            other => return Err(p.error(format!("unsupported emitter type '{other}'"))),
        };
        p.finish(&mut self.warnings);
        self.lights.push(light);
        Ok(())
    }

    /// A `projector`: its frame from `to_world` (orthonormalised, scale dropped), the
    /// `irradiance` texture (required), `scale` and the field of view of a perspective camera
    /// whose film has the texture's resolution (1 × 1 for a constant).
    fn projector(&mut self, p: &Plugin<'a>, m: Mat4) -> Result<LightDesc, SceneError> {
        if p.named_object("irradiance").is_none() && p.prop("irradiance").is_none() {
            return Err(p.error("missing required property 'irradiance'"));
        }
        let irradiance = self.texture_prop(p, "irradiance", 1.0, SpectrumUse::Emission)?;
        if p.emission_spectrum("irradiance")?.is_some() {
            return Err(p.error("a projector's 'irradiance' must be RGB or a texture, not a spectrum"));
        }
        let scale = p.float_or("scale", 1.0)?;
        if !scale.is_finite() || scale < 0.0 {
            return Err(p.error(format!("'scale' must be non-negative, got {scale}")));
        }
        let (width, height) = irradiance.resolution().unwrap_or((1, 1));
        let film = FilmDesc { width, height, filter: FilterDesc::Box };
        let fov_x = self.field_of_view(p, &film)?;
        let bad = || p.error("'to_world' is singular");
        let ez = normalize(m.vector([0.0, 0.0, 1.0])).ok_or_else(bad)?;
        let y = m.vector([0.0, 1.0, 0.0]);
        let d = dot(y, ez);
        let ey = normalize([y[0] - d * ez[0], y[1] - d * ez[1], y[2] - d * ez[2]]).ok_or_else(bad)?;
        // Keep the handedness of the file's x axis (a mirrored frame mirrors the image).
        let mut ex = cross(ey, ez);
        if dot(ex, m.vector([1.0, 0.0, 0.0])) < 0.0 {
            ex = ex.map(|v| -v);
        }
        Ok(LightDesc::Projector {
            model: scene::desc::ProjectorModel::Irradiance,
            position: to_vec3(m.point([0.0; 3])),
            frame: [to_vec3(ex), to_vec3(ey), to_vec3(ez)],
            irradiance: Arc::new(irradiance),
            scale: scale as f32,
            fov_x_degrees: fov_x as f32,
            aspect: width as f32 / height as f32,
        })
    }

    fn check_single_environment(&self, p: &Plugin) -> Result<(), SceneError> {
        if self.lights.iter().any(|l| matches!(l, LightDesc::Constant { .. } | LightDesc::EnvMap { .. })) {
            return Err(p.error("a scene can have only one environment emitter (constant or envmap)"));
        }
        Ok(())
    }

    /// The orthonormalised rotation part of an environment map's `to_world` (translation is
    /// irrelevant for directions; scale is dropped with a warning).
    fn rotation_part(&mut self, p: &Plugin, m: Mat4) -> Result<[math::Vec3; 3], SceneError> {
        let x = m.vector([1.0, 0.0, 0.0]);
        let y = m.vector([0.0, 1.0, 0.0]);
        let bad = || p.error("'to_world' is singular");
        let ex = normalize(x).ok_or_else(bad)?;
        let d = dot(y, ex);
        let ey = normalize([y[0] - d * ex[0], y[1] - d * ex[1], y[2] - d * ex[2]]).ok_or_else(bad)?;
        let mut ez = cross(ex, ey);
        let z = m.vector([0.0, 0.0, 1.0]);
        if dot(z, ez) < 0.0 {
            ez = ez.map(|v| -v);
            self.warnings.push(format!(
                "{}: {}: 'to_world' mirrors the environment map",
                p.node.pos.location(),
                p.what()
            ));
        }
        let lengths = [length(x), length(y), length(z)];
        let orthogonal = dot(x, y).abs() + dot(y, z).abs() + dot(x, z).abs() < 1e-4 * lengths[0] * lengths[0];
        if !orthogonal || lengths.iter().any(|l| (l - 1.0).abs() > 1e-4) {
            self.warnings.push(format!(
                "{}: {}: 'to_world' is not a rotation; only its orientation is used",
                p.node.pos.location(),
                p.what()
            ));
        }
        Ok([to_vec3(ex), to_vec3(ey), to_vec3(ez)])
    }

    fn environment_image(&mut self, filename: &str, node: &Node) -> Result<Arc<TextureImage>, SceneError> {
        let path = self.resolve_file(filename, node)?;
        let image = crate::read_image(&path).map_err(|e| node.pos.error(format!("cannot read envmap: {e}")))?;
        let (Ok(width), Ok(height)) = (u32::try_from(image.width), u32::try_from(image.height)) else {
            return Err(node.pos.error(format!("envmap '{}' is too large", path.display())));
        };
        if width == 0 || height == 0 {
            return Err(node.pos.error(format!("envmap '{}' is empty", path.display())));
        }
        if image.pixels.iter().flatten().any(|v| !v.is_finite() || *v < 0.0) {
            self.warnings.push(format!(
                "{}: envmap '{}' has negative or non-finite pixels; set to 0",
                node.pos.location(),
                path.display()
            ));
        }
        let pixels = image
            .pixels
            .iter()
            .map(|p| Rgb::from_array(p.map(|v| if v.is_finite() && v > 0.0 { v } else { 0.0 })))
            .collect();
        Ok(Arc::new(TextureImage { width, height, pixels }))
    }
}
