//! `<medium type="heterogeneous">`: `sigma_t` (default 1) and `albedo` (default 0.75), each a
//! colour or a nested `<volume>`: `gridvolume` (a `.vol` file of 1 or 3 channels, `to_world`,
//! `filter_type` `trilinear` (default) or `nearest`, `wrap_mode` `clamp`, `use_grid_bbox`) or
//! `constvolume` (`value`, `to_world`). As in Mitsuba 3, a volume's grid space is the unit cube
//! mapped through `to_world` (with `use_grid_bbox`, the file's bounds mapped through it), a
//! plain colour is a constant volume on the unit cube, and the medium fills only the world
//! bounding box of its `sigma_t` volume. `scale` multiplies `sigma_t`.

use std::sync::Arc;

use glam::{Affine3A, Vec3};
use scene::medium::{Coefficient, Coefficients, Filter, Grid, Heterogeneous, Outside, Volume};
use spectrum::Rgb;

use super::Loader;
use super::colour::SpectrumUse;
use super::props::Plugin;
use super::transform::Mat4;
use super::xml::Node;
use crate::scene_error::SceneError;
use crate::volfile::{VolHeader, read_bytes};

impl<'a> Loader<'a> {
    /// The coefficients of a `heterogeneous` medium.
    pub(super) fn heterogeneous(&mut self, p: &Plugin<'a>) -> Result<Coefficients, SceneError> {
        let sigma_t = self.volume_property(p, "sigma_t", 1.0, SpectrumUse::Emission)?;
        let albedo = self.volume_property(p, "albedo", 0.75, SpectrumUse::Reflectance)?;
        let (lo, hi) = sigma_t.world_bounds();
        let extent = hi - lo;
        if !(extent.is_finite() && extent.min_element() > 0.0) {
            return Err(p.error(format!("the sigma_t volume's bounding box {lo} – {hi} is empty")));
        }
        let region = Affine3A::from_scale(extent.recip()) * Affine3A::from_translation(-lo);
        Ok(Coefficients::Heterogeneous(Arc::new(Heterogeneous::new(sigma_t, albedo, None, region))))
    }

    /// Property `name` of a heterogeneous medium: a nested `<volume>` or a colour (a constant
    /// volume on the unit cube).
    fn volume_property(
        &mut self,
        p: &Plugin<'a>,
        name: &str,
        default: f32,
        usage: SpectrumUse,
    ) -> Result<Volume, SceneError> {
        if let Some(object) = p.named_object(name) {
            if object.node.tag != "volume" {
                return Err(object.node.pos.error(format!(
                    "{}: '{name}' is a <{}>, expected a <volume> or a colour",
                    p.what(),
                    object.node.tag
                )));
            }
            return self.volume(object.node, usage);
        }
        let value = self.coefficient(p, name, default, usage)?;
        Ok(Volume::constant(value, Affine3A::IDENTITY))
    }

    /// A `<volume>` element.
    fn volume(&mut self, node: &'a Node, usage: SpectrumUse) -> Result<Volume, SceneError> {
        let p = Plugin::new(node)?;
        let to_world = match p.transform("to_world")? {
            Some(m) => affine(&m).ok_or_else(|| p.error("'to_world' is singular or not affine"))?,
            None => Affine3A::IDENTITY,
        };
        let volume = match p.ty.as_str() {
            "constvolume" => {
                let value = self.coefficient(&p, "value", 1.0, usage)?;
                Volume::constant(value, to_world.inverse())
            }
            "gridvolume" => {
                let filter = match p.string("filter_type")?.unwrap_or("trilinear") {
                    "trilinear" => Filter::Trilinear,
                    "nearest" => Filter::Nearest,
                    other => return Err(p.error(format!("filter_type '{other}': expected 'trilinear' or 'nearest'"))),
                };
                match p.string("wrap_mode")?.unwrap_or("clamp") {
                    "clamp" => {}
                    other => return Err(p.error(format!("wrap_mode '{other}' is not supported (only 'clamp')"))),
                }
                if p.boolean_or("raw", false)? {
                    return Err(p.error("'raw' grids (no spectral upsampling) are not supported"));
                }
                p.ignore(&["accel"]);
                let filename = p.string_required("filename")?.to_string();
                let path = self.resolve_file(&filename, node)?;
                let (grid, bounds) = read_grid(&path).map_err(|e| p.error(format!("{}: {e}", path.display())))?;
                let mut to_local = to_world.inverse();
                if p.boolean_or("use_grid_bbox", false)? {
                    let (lo, hi) = (Vec3::from_slice(&bounds[..3]), Vec3::from_slice(&bounds[3..]));
                    let extent = hi - lo;
                    if !(extent.is_finite() && extent.min_element() > 0.0) {
                        return Err(p.error(format!("use_grid_bbox: the file's bounds {lo} – {hi} are empty")));
                    }
                    to_local = Affine3A::from_scale(extent.recip()) * Affine3A::from_translation(-lo) * to_local;
                }
                Volume {
                    grid: Some(Arc::new(grid)),
                    value: Coefficient::rgb(Rgb::splat(1.0)),
                    to_local,
                    filter,
                    outside: Outside::Clamp,
                }
            }
            other => {
                return Err(p.error(format!("volume type '{other}' is not supported (gridvolume, constvolume)")));
            }
        };
        p.finish(&mut self.warnings);
        Ok(volume)
    }
}

/// A medium grid and the bounds stored in a `.vol` file.
pub(crate) fn read_grid(path: &std::path::Path) -> Result<(Grid, [f32; 6]), String> {
    let bytes = read_bytes(path)?;
    let header = VolHeader::parse(&bytes)?;
    if header.channels != 1 && header.channels != 3 {
        return Err(format!("{} channels: a medium grid has 1 or 3", header.channels));
    }
    let values = header.values(&bytes)?;
    let dims = header.dims.map(|d| d as usize);
    Ok((Grid::new(dims, header.channels as usize, values)?, header.bounds))
}

/// The affine part of `m` in single precision; `None` when it is singular or not finite.
fn affine(m: &Mat4) -> Option<Affine3A> {
    let column = |c: usize| Vec3::new(m.m[0][c] as f32, m.m[1][c] as f32, m.m[2][c] as f32);
    let affine = Affine3A::from_cols(column(0).into(), column(1).into(), column(2).into(), column(3).into());
    let determinant = affine.matrix3.determinant();
    (affine.is_finite() && determinant.is_finite() && determinant != 0.0 && m.is_affine()).then_some(affine)
}
