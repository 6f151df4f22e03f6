//! `<bsdf type="principled">` and `<bsdf type="principledthin">`: Mitsuba 3's Disney BSDFs.
//! Every parameter is a number or a texture (scalar parameters use the texture's luminance);
//! constants are checked to lie in Mitsuba's documented ranges (scalar checkerboards swapped as
//! Mitsuba reads them, see `weight`). The sampling-rate properties
//! only change Mitsuba's sampler, not the image; they are reported as ignored.

use scene::Texture;
use scene::material::{Material, PrincipledParameters, PrincipledThinParameters};
use spectrum::Rgb;

use super::Loader;
use super::bsdf::float_evaluation;
use super::colour::SpectrumUse;
use super::props::Plugin;
use crate::scene_error::SceneError;

impl<'a> Loader<'a> {
    /// `principled`: base_color, roughness, anisotropic, metallic, spec_trans, spec_tint,
    /// sheen, sheen_tint, flatness, clearcoat, clearcoat_gloss, and `eta` or `specular`.
    pub(crate) fn principled(&mut self, p: &Plugin<'a>) -> Result<Material, SceneError> {
        let base_color = self.texture_prop(p, "base_color", 0.5, SpectrumUse::Reflectance)?;
        let mut weight = |name: &str, default: f64| self.weight(p, name, default, 1.0);
        let roughness = weight("roughness", 0.5)?;
        let anisotropic = weight("anisotropic", 0.0)?;
        let metallic = weight("metallic", 0.0)?;
        let spec_trans = weight("spec_trans", 0.0)?;
        let spec_tint = weight("spec_tint", 0.0)?;
        let sheen = weight("sheen", 0.0)?;
        let sheen_tint = weight("sheen_tint", 0.0)?;
        let flatness = weight("flatness", 0.0)?;
        let clearcoat = weight("clearcoat", 0.0)?;
        let clearcoat_gloss = weight("clearcoat_gloss", 0.0)?;
        // Mitsuba nudges an interface that would vanish when there is transmission.
        let transmits = p.has("spec_trans") && spec_trans.as_constant() != Some(Rgb::BLACK);
        let eta = match (p.has("eta"), p.has("specular")) {
            (true, true) => return Err(p.error("give either 'eta' or 'specular', not both")),
            (true, false) => {
                let eta = p.float_required("eta")?;
                if !(eta.is_finite() && eta > 0.0) {
                    return Err(p.error(format!("'eta' must be a positive number, got {eta}")));
                }
                if transmits && eta == 1.0 { 1.001 } else { eta }
            }
            (false, _) => {
                let specular = p.float_or("specular", 0.5)?;
                if !(0.0..=1.0).contains(&specular) {
                    return Err(p.error(format!("'specular' must lie in [0, 1], got {specular}")));
                }
                let specular = if transmits && specular == 0.0 { 1e-3 } else { specular };
                // Inverse of specular = 12.5·R0 with R0 = ((η − 1)/(η + 1))².
                2.0 / (1.0 - (0.08 * specular).sqrt()) - 1.0
            }
        };
        let parameters = PrincipledParameters {
            base_color,
            roughness,
            anisotropic,
            metallic,
            spec_trans,
            spec_tint,
            sheen,
            sheen_tint,
            flatness,
            clearcoat,
            clearcoat_gloss,
            eta: eta as f32,
        };
        Ok(Material::Principled(Box::new(parameters)))
    }

    /// `principledthin`: base_color, roughness, anisotropic, spec_trans, spec_tint, sheen,
    /// sheen_tint, flatness, diff_trans (in [0, 2]) and eta (a number or a texture).
    pub(crate) fn principled_thin(&mut self, p: &Plugin<'a>) -> Result<Material, SceneError> {
        let base_color = self.texture_prop(p, "base_color", 0.5, SpectrumUse::Reflectance)?;
        let mut weight = |name: &str, default: f64| self.weight(p, name, default, 1.0);
        let parameters = PrincipledThinParameters {
            base_color,
            roughness: weight("roughness", 0.5)?,
            anisotropic: weight("anisotropic", 0.0)?,
            spec_trans: weight("spec_trans", 0.0)?,
            spec_tint: weight("spec_tint", 0.0)?,
            sheen: weight("sheen", 0.0)?,
            sheen_tint: weight("sheen_tint", 0.0)?,
            flatness: weight("flatness", 0.0)?,
            diff_trans: self.weight(p, "diff_trans", 0.0, 2.0)?,
            eta: self.weight(p, "eta", 1.5, f64::INFINITY)?,
        };
        if let Some(eta) = parameters.eta.as_constant()
            && eta.r <= 0.0
        {
            return Err(p.error("'eta' must be positive"));
        }
        Ok(Material::PrincipledThin(Box::new(parameters)))
    }

    /// A scalar parameter: a texture, or a number checked to lie in `[0, max]`. A checkerboard
    /// read as a scalar takes Mitsuba's float-evaluation parity ([`float_evaluation`]: its
    /// colours are exchanged), as the suite's references are rendered.
    fn weight(&mut self, p: &Plugin<'a>, name: &str, default: f64, max: f64) -> Result<Texture, SceneError> {
        let texture = float_evaluation(self.texture_prop(p, name, default, SpectrumUse::Unbounded)?);
        if let Some(c) = texture.as_constant()
            && !(c.r >= 0.0 && c.max_component() <= max as f32)
        {
            return Err(p.error(format!("'{name}' must lie in [0, {max}], got {}", c.r)));
        }
        Ok(texture)
    }
}
