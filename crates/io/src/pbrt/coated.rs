//! pbrt-v4's layered materials `coateddiffuse` and `coatedconductor` →
//! [`Material::Coated`], wrapped two-sided (pbrt's layered BSDFs are two-sided).
//!
//! Parameters and defaults as pbrt-v4: `coateddiffuse` takes `reflectance` (0.5, textured),
//! `roughness` / `uroughness` / `vroughness` (0) and `eta` (1.5); `coatedconductor` takes
//! `interface.roughness` / `.uroughness` / `.vroughness` (0), `interface.eta` (1.5),
//! `conductor.eta` and `conductor.k` (copper) or `reflectance` (textured; not with η and k),
//! `conductor.roughness` / `.uroughness` / `.vroughness` (0). Both take `thickness` (0.01),
//! `albedo` (0, textured), `g` (0), `maxdepth` (10), `nsamples` (1) and `remaproughness`
//! (true). Float parameters must be constants (a constant texture is accepted).

use scene::material::{CoatedBase, CoatedParameters, CoatingInterface, CoatingLayer, ConductorIor, Material};
use spectrum::Rgb;

use super::parser::{Directive, ParamSet, Value};
use super::tokenizer::Pos;
use super::{Builder, color};
use crate::scene_error::SceneError;

impl Builder {
    /// The coated material of type `ty` (`"coateddiffuse"` or `"coatedconductor"`).
    pub(super) fn coated_material(&self, d: &Directive, ty: &str) -> Result<Material, SceneError> {
        let p = &d.params;
        let pos = p.params.first().map_or(d.pos, |x| x.pos);
        let remap = p.bool("remaproughness", true)?;
        let (prefix, eta_name) = if ty == "coateddiffuse" { ("", "eta") } else { ("interface.", "interface.eta") };
        let (alpha_u, alpha_v) = self.prefixed_roughness(p, prefix, remap, pos)?;
        let interface = CoatingInterface { eta: self.coating_eta(p, eta_name)?, alpha_u, alpha_v };
        let base = if ty == "coateddiffuse" {
            CoatedBase::Diffuse { reflectance: self.spectrum_texture(p, "reflectance", Rgb::splat(0.5), true)? }
        } else {
            let ior = if p.find("reflectance").is_some() {
                if let Some(x) = p.find("conductor.eta").or_else(|| p.find("conductor.k")) {
                    return Err(p.error(x.pos, "'conductor.eta'/'conductor.k' and 'reflectance' exclude each other"));
                }
                ConductorIor::Reflectance(self.spectrum_texture(p, "reflectance", Rgb::WHITE, true)?)
            } else {
                ConductorIor::Complex {
                    eta: self.unbounded(p, "conductor.eta", "metal-Cu-eta")?,
                    k: self.unbounded(p, "conductor.k", "metal-Cu-k")?,
                }
            };
            let (alpha_u, alpha_v) = self.prefixed_roughness(p, "conductor.", remap, pos)?;
            CoatedBase::Conductor { ior, alpha_u, alpha_v }
        };
        let count = |name: &str, default: i64| -> Result<u32, SceneError> {
            let n = p.int(name, default)?;
            u32::try_from(n).ok().filter(|&n| (1..=10_000).contains(&n)).ok_or_else(|| {
                p.error(p.find(name).map_or(pos, |x| x.pos), format!("{name} = {n} must lie in [1, 10000]"))
            })
        };
        let layer = CoatingLayer {
            thickness: self.constant_float(p, "thickness", 0.01)?,
            albedo: self.spectrum_texture(p, "albedo", Rgb::BLACK, true)?,
            g: self.constant_float(p, "g", 0.0)?,
            max_depth: count("maxdepth", 10)?,
            samples: count("nsamples", 1)?,
        };
        let parameters = CoatedParameters::new(interface, layer, base).map_err(|e| p.error(pos, e))?;
        Ok(Material::TwoSided { front: Box::new(Material::Coated(Box::new(parameters))), back: None })
    }

    /// GGX α along u and v from `{prefix}roughness`, `{prefix}uroughness` and
    /// `{prefix}vroughness` (each of the last two overrides the first), square-rooted when
    /// `remap` (pbrt's `RoughnessToAlpha`); errors at the parameter (or at `pos`).
    fn prefixed_roughness(&self, p: &ParamSet, prefix: &str, remap: bool, pos: Pos) -> Result<(f32, f32), SceneError> {
        let name = |s: &str| format!("{prefix}{s}");
        let r = self.constant_float(p, &name("roughness"), 0.0)?;
        let u = self.constant_float(p, &name("uroughness"), r)?;
        let v = self.constant_float(p, &name("vroughness"), r)?;
        for (value, n) in [(u, "uroughness"), (v, "vroughness")] {
            if !(value >= 0.0 && value.is_finite()) {
                let at = p.find(&name(n)).or_else(|| p.find(&name("roughness"))).map_or(pos, |x| x.pos);
                return Err(p.error(at, format!("{prefix}roughness must be a finite number ≥ 0, got {value}")));
            }
        }
        Ok(if remap { (u.sqrt(), v.sqrt()) } else { (u, v) })
    }

    /// The coating's index of refraction `name`: a float, a constant spectrum, a named glass
    /// or a sampled spectrum (taken at 587.6 nm); 1.5 when absent.
    fn coating_eta(&self, p: &ParamSet, name: &str) -> Result<f32, SceneError> {
        let Some(param) = p.find(name) else { return Ok(1.5) };
        let pos = param.pos;
        let eta = match (param.ty.as_str(), &param.values[..]) {
            ("float" | "spectrum", [Value::Num(x)]) => *x as f32,
            ("spectrum", [Value::Str(s)]) => {
                color::named_glass(s).ok_or_else(|| p.error(pos, format!("unknown named glass spectrum \"{s}\"")))?
            }
            ("texture", _) => self.constant_float(p, name, 1.5)?,
            ("spectrum", _) => {
                let nums = param.numbers();
                let s = color::piecewise_linear(&nums)
                    .filter(|_| nums.len() % 2 == 0)
                    .ok_or_else(|| p.error(pos, format!("{name}: expected wavelength/value pairs")))?;
                s(587.6) as f32
            }
            _ => return Err(p.error(pos, format!("{name} needs one float or a spectrum"))),
        };
        if !(eta > 0.0 && eta.is_finite()) {
            return Err(p.error(pos, format!("{name} = {eta} must be positive")));
        }
        Ok(eta)
    }
}
