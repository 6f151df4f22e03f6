//! pbrt-v4 participating media: `MakeNamedMedium "name" "string type" "homogeneous"` (`sigma_a`,
//! `sigma_s` as rgb, float or sampled spectrum, default 1 each; `scale`, default 1; `g`,
//! Henyey–Greenstein, default 0), `MediumInterface "inside" "outside"` (one name: both sides;
//! `""` is vacuum), the camera's medium (the current outside medium at `Camera`) and the
//! `interface` material of index-matched boundaries. A shape gets the current interface when
//! its two sides differ (pbrt-v4's `IsMediumTransition`). Grid media: `uniformgrid`, `rgbgrid`
//! (`grid_medium.rs`) and `nanovdb` (`nanovdb_medium.rs`). Named presets, emissive media
//! (`Le`, temperature grids) and the medium `cloud` are errors naming the file, line and
//! feature (issue #15).

use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

use scene::medium::{Coefficient, Coefficients, MediaDesc, Medium, MediumInterface, PhaseFunction};
use spectrum::Rgb;
use spectrum::tabulated::Tabulated;

use super::parser::{Directive, ParamSet, Value};
use super::{Builder, err};
use crate::scene_error::SceneError;

/// The loader's media state.
#[derive(Debug, Default)]
pub(super) struct PbrtMedia {
    desc: MediaDesc,
    named: HashMap<String, u32>,
    /// Named materials of type `interface`.
    interface_names: Vec<String>,
}

impl PbrtMedia {
    /// The media of the description.
    pub(super) fn finish(self) -> MediaDesc {
        self.desc
    }

    /// Whether the named material `name` is an `interface`.
    pub(super) fn is_interface_name(&self, name: &str) -> bool {
        self.interface_names.iter().any(|n| n == name)
    }

    /// Marks material index `material` as an index-matched boundary.
    pub(super) fn mark_interface(&mut self, material: u32) {
        if !self.desc.null_materials.contains(&material) {
            self.desc.null_materials.push(material);
        }
    }

    /// Remembers that named material `name` is an `interface`.
    pub(super) fn name_interface(&mut self, name: &str) {
        self.interface_names.push(name.to_string());
    }

    /// Sets the camera's medium.
    pub(super) fn set_camera(&mut self, interface: MediumInterface) {
        self.desc.camera = interface.exterior;
    }

    /// Gives shape `shape` the interface `interface` when its sides differ.
    pub(super) fn shape(&mut self, shape: u32, interface: MediumInterface) {
        if interface.interior != interface.exterior {
            self.desc.shapes.insert(shape, interface);
        }
    }
}

impl Builder {
    /// `MakeNamedMedium`.
    pub(super) fn make_named_medium(&mut self, file: &Path, d: &Directive) -> Result<(), SceneError> {
        let name = d.str_arg(0).to_string();
        if self.media.named.contains_key(&name) {
            return Err(err(file, d.arg_pos[0], format!("medium \"{name}\" is defined twice")));
        }
        let p = &d.params;
        let Some((ty, pos)) = p.string("type")? else {
            return Err(err(file, d.pos, format!("MakeNamedMedium \"{name}\" needs a \"string type\"")));
        };
        if !matches!(ty.as_str(), "homogeneous" | "uniformgrid" | "rgbgrid" | "nanovdb") {
            return Err(err(
                file,
                pos,
                format!(
                    "medium type \"{ty}\" is not supported (only \"homogeneous\", \"uniformgrid\", \"rgbgrid\" and \"nanovdb\"; issue #15)"
                ),
            ));
        }
        if let Some((preset, pos)) = p.string("preset")? {
            return Err(err(
                file,
                pos,
                format!("named medium presets (\"{preset}\") are not supported; give sigma_a and sigma_s"),
            ));
        }
        // pbrt-v4's nanovdb medium has no "Le" (its emission comes from a temperature grid,
        // checked in nanovdb_medium.rs); an "Le" there is an unused parameter.
        if let Some(le) = (ty != "nanovdb").then(|| p.find("Le")).flatten() {
            let emits = le.values.iter().any(|v| matches!(v, Value::Num(x) if *x != 0.0));
            let scale = p.float("Lescale", 1.0)?;
            if emits && scale != 0.0 {
                return Err(err(file, le.pos, "emissive media (\"Le\") are not supported"));
            }
        }
        let scale = p.float("scale", 1.0)?;
        let g = p.float("g", 0.0)?;
        let phase = PhaseFunction::henyey_greenstein(g).map_err(|e| err(file, d.pos, e))?;
        let ctm = self.state.ctm;
        let coefficients = if ty == "rgbgrid" {
            super::grid_medium::rgb_grid(file, d, &ctm)?
        } else {
            let sigma_a = coefficient(p, "sigma_a")?;
            let sigma_s = coefficient(p, "sigma_s")?;
            if ty == "uniformgrid" {
                super::grid_medium::uniform_grid(file, d, &ctm, &sigma_a, &sigma_s)?
            } else if ty == "nanovdb" {
                super::nanovdb_medium::nanovdb_grid(file, d, &ctm, &sigma_a, &sigma_s)?
            } else {
                Coefficients::AbsorptionScattering { sigma_a, sigma_s }
            }
        };
        let medium = Medium { coefficients, scale, phase };
        medium.validate().map_err(|e| err(file, d.pos, format!("medium \"{name}\": {e}")))?;
        self.warn_unused(p);
        self.media.desc.media.push(medium);
        let index = self.media.desc.media.len() as u32 - 1;
        self.media.named.insert(name, index);
        Ok(())
    }

    /// `MediumInterface "inside" ["outside"]`: the interface of the shapes that follow.
    pub(super) fn medium_interface(&mut self, file: &Path, d: &Directive) -> Result<MediumInterface, SceneError> {
        let names: Vec<&str> = (0..d.args.len()).map(|i| d.str_arg(i)).collect();
        let (inside, outside) = match names[..] {
            [one] => (one, one),
            [inside, outside] => (inside, outside),
            _ => return Err(err(file, d.pos, "MediumInterface needs one or two medium names")),
        };
        let lookup = |n: &str, i: usize| -> Result<Option<u32>, SceneError> {
            if n.is_empty() {
                return Ok(None);
            }
            match self.media.named.get(n) {
                Some(&m) => Ok(Some(m)),
                None => Err(err(file, d.arg_pos[i.min(d.arg_pos.len() - 1)], format!("unknown medium \"{n}\""))),
            }
        };
        Ok(MediumInterface { interior: lookup(inside, 0)?, exterior: lookup(outside, 1)? })
    }
}

/// A medium coefficient `name` (default 1 per unit length): rgb, one float, or sampled
/// wavelength/value pairs (kept as a spectrum; its RGB value is read at the primaries).
fn coefficient(p: &ParamSet, name: &str) -> Result<Coefficient, SceneError> {
    let Some(param) = p.find(name) else { return Ok(Coefficient::rgb(Rgb::splat(1.0))) };
    let pos = param.pos;
    let v = param.numbers();
    let coefficient = match (param.ty.as_str(), &v[..]) {
        ("rgb", [r, g, b]) => Coefficient::rgb(Rgb::new(*r as f32, *g as f32, *b as f32)),
        ("float" | "spectrum", [x]) => Coefficient::rgb(Rgb::splat(*x as f32)),
        ("spectrum", pairs) if pairs.len() >= 4 && pairs.len() % 2 == 0 => {
            let points: Vec<(f32, f32)> = pairs.chunks(2).map(|c| (c[0] as f32, c[1] as f32)).collect();
            let table = Tabulated::new(&points).map_err(|e| p.error(pos, format!("parameter '{name}': {e}")))?;
            let [r, g, b] = super::color::PRIMARY_WAVELENGTHS.map(|l| table.eval(l as f32));
            Coefficient { rgb: Rgb::new(r, g, b), spectrum: Some(Arc::new(table)) }
        }
        ("spectrum", _) if matches!(param.values[..], [Value::Str(_)]) => {
            return Err(p.error(pos, format!("parameter '{name}': named spectra are not supported for media")));
        }
        (ty, _) => {
            return Err(p.error(
                pos,
                format!(
                    "parameter '{name}' ({ty}, {} values): expected rgb (3), float (1) or wavelength/value pairs",
                    v.len()
                ),
            ));
        }
    };
    Ok(coefficient)
}
