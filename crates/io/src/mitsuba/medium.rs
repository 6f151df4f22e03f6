//! `<medium type="homogeneous">` with its `<phase>`, media referenced from shapes
//! (`interior`, `exterior`) and the sensor, and the `null` BSDF of index-matched boundaries.
//!
//! A homogeneous medium reads `sigma_t` (default 1) and `albedo` (default 0.75), as `rgb`,
//! `float` or `spectrum` (a tabulated spectrum is also kept for spectral rendering), `scale`
//! (default 1) and a `<phase>`: `isotropic` (the default) or `hg` with `g` (default 0.8,
//! Mitsuba's). `heterogeneous` media read their volumes in [`super::volume`]. Other medium
//! types and phase functions are errors naming the file, line and feature (issue #15).

use std::sync::Arc;

use scene::medium::{Coefficient, Coefficients, Medium, PhaseFunction};
use scene::texture::Texture;
use spectrum::Rgb;

use super::Loader;
use super::colour::SpectrumUse;
use super::props::{Object, Plugin};
use super::xml::Node;
use crate::scene_error::SceneError;

impl<'a> Loader<'a> {
    /// The index of the medium defined by `node` (a `<medium>`, or a `<ref>` to one).
    pub(crate) fn medium_index(&mut self, node: &'a Node) -> Result<u32, SceneError> {
        let node = if node.tag == "ref" {
            let id = node.required_attr("id")?;
            let target =
                self.ids.get(id).copied().ok_or_else(|| node.pos.error(format!("<ref>: unknown id '{id}'")))?;
            if target.tag != "medium" {
                return Err(node.pos.error(format!("id '{id}' is a <{}>, expected a medium", target.tag)));
            }
            target
        } else {
            node
        };
        if let Some(&index) = node.attr("id").and_then(|id| self.medium_of_id.get(id)) {
            return Ok(index);
        }
        let medium = self.medium(node)?;
        self.media.media.push(medium);
        let index = self.media.media.len() as u32 - 1;
        if let Some(id) = node.attr("id") {
            self.medium_of_id.insert(id.to_string(), index);
        }
        Ok(index)
    }

    /// Whether `object` (a nested object of a shape or sensor) is a medium or a `<ref>` to one.
    pub(crate) fn is_medium(&self, object: &Object) -> bool {
        match object.node.tag.as_str() {
            "medium" => true,
            "ref" => object.node.attr("id").and_then(|id| self.ids.get(id)).is_some_and(|n| n.tag == "medium"),
            _ => false,
        }
    }

    /// Whether `node` (a `<bsdf>` or a `<ref>` to one) is a `null` BSDF.
    pub(crate) fn is_null_bsdf(&self, node: &Node) -> bool {
        let node = match node.tag.as_str() {
            "ref" => match node.attr("id").and_then(|id| self.ids.get(id)) {
                Some(target) => *target,
                None => return false,
            },
            _ => node,
        };
        node.tag == "bsdf" && node.attr("type") == Some("null")
    }

    /// The material index of the `null` BSDF (one black placeholder shared by all; the scene
    /// marks it as an index-matched boundary, so it is never evaluated).
    pub(crate) fn null_material(&mut self) -> u32 {
        if let Some(&index) = self.media.null_materials.first() {
            return index;
        }
        let index =
            self.push_material(scene::material::Material::Diffuse { reflectance: Texture::Constant(Rgb::BLACK) });
        self.media.null_materials.push(index);
        index
    }

    /// A `<medium>` element.
    fn medium(&mut self, node: &'a Node) -> Result<Medium, SceneError> {
        let p = Plugin::new(node)?;
        let coefficients = match p.ty.as_str() {
            "homogeneous" => {
                if let Some(object) = p.objects.iter().find(|o| matches!(o.node.tag.as_str(), "volume" | "texture")) {
                    return Err(object.node.pos.error(format!(
                        "{}: volume data (<{}>) needs a 'heterogeneous' medium",
                        p.what(),
                        object.node.tag
                    )));
                }
                let sigma_t = self.coefficient(&p, "sigma_t", 1.0, SpectrumUse::Emission)?;
                let albedo = self.coefficient(&p, "albedo", 0.75, SpectrumUse::Reflectance)?;
                Coefficients::ExtinctionAlbedo { sigma_t, albedo }
            }
            "heterogeneous" => self.heterogeneous(&p)?,
            other => {
                return Err(p.error(format!(
                    "medium type '{other}' is not supported (only 'homogeneous' and 'heterogeneous')"
                )));
            }
        };
        let scale = p.float_or("scale", 1.0)? as f32;
        p.ignore(&["sample_emitters", "has_spectral_extinction"]);
        let mut phase = PhaseFunction::Isotropic;
        for object in p.objects.iter().filter(|o| o.node.tag == "phase") {
            object.take();
            phase = self.phase(object.node)?;
        }
        p.finish(&mut self.warnings);
        let medium = Medium { coefficients, scale, phase };
        medium.validate().map_err(|e| p.error(e))?;
        Ok(medium)
    }

    /// A `<phase>` element.
    fn phase(&mut self, node: &'a Node) -> Result<PhaseFunction, SceneError> {
        let p = Plugin::new(node)?;
        let phase = match p.ty.as_str() {
            "isotropic" => PhaseFunction::Isotropic,
            "hg" => PhaseFunction::henyey_greenstein(p.float_or("g", 0.8)? as f32).map_err(|e| p.error(e))?,
            other => return Err(p.error(format!("phase function '{other}' is not supported (isotropic, hg)"))),
        };
        p.finish(&mut self.warnings);
        Ok(phase)
    }

    /// A medium coefficient: a colour (RGB) and, for a tabulated spectrum, the spectrum.
    pub(super) fn coefficient(
        &mut self,
        p: &Plugin,
        name: &str,
        default: f32,
        usage: SpectrumUse,
    ) -> Result<Coefficient, SceneError> {
        let Some(rgb) = p.color(name, usage, &mut self.warnings)? else {
            return Ok(Coefficient::rgb(Rgb::splat(default)));
        };
        let rgb = Rgb::new(rgb[0] as f32, rgb[1] as f32, rgb[2] as f32);
        let spectrum = match p.emission_spectrum(name)? {
            Some(scene::desc::EmissionSpectrum::Tabulated(t)) => Some(Arc::clone(&t)),
            Some(_) => return Err(p.error(format!("'{name}': a blackbody spectrum is not a medium coefficient"))),
            None => None,
        };
        Ok(Coefficient { rgb, spectrum })
    }
}
