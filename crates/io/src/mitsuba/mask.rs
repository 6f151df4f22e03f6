//! The `mask` BSDF: an opacity (a float or a texture) over a nested BSDF. The renderer applies
//! masks at intersection level (see `scene::alpha`), not as a BSDF: the loader takes the opacity
//! out of the BSDF tree and gives it to every shape that uses the BSDF
//! ([`scene::desc::ShapeDesc::alpha`]). A mask must therefore be the outermost BSDF of a shape,
//! or the only BSDF nested in a `twosided` (`twosided(mask(b))` is `mask(twosided(b))`); a mask
//! inside a blend, a normal or bump map, or another mask is an error.

use scene::Texture;
use scene::material::Material;

use super::Loader;
use super::colour::SpectrumUse;
use super::props::Plugin;
use crate::scene_error::SceneError;

/// A BSDF as the loader reads it: the material and, for a `mask`, its opacity texture.
#[derive(Clone, Debug)]
pub(crate) struct Masked {
    /// The material (the mask's nested BSDF for a mask).
    pub(crate) material: Material,
    /// The opacity (unitless, in [0, 1]) of a `mask`.
    pub(crate) opacity: Option<Texture>,
}

impl<'a> Loader<'a> {
    /// A `mask`: its nested material and its opacity (`opacity`, default 0.5 as in Mitsuba; a
    /// constant must lie in [0, 1]).
    pub(crate) fn mask(&mut self, p: &Plugin<'a>) -> Result<(Material, Texture), SceneError> {
        let opacity = self.texture_prop(p, "opacity", 0.5, SpectrumUse::Unbounded)?;
        if let Some(c) = opacity.as_constant()
            && [c.r, c.g, c.b].iter().any(|v| !(0.0..=1.0).contains(v))
        {
            let pos = p.prop("opacity").map_or_else(|| p.node.pos.clone(), |q| q.pos.clone());
            return Err(pos.error(format!("{}: 'opacity' = {:?} must lie in [0, 1]", p.what(), c.to_array())));
        }
        let nested = self.nested_bsdfs(p)?;
        if nested.iter().any(|m| m.opacity.is_some()) {
            return Err(p.error("a mask cannot contain another mask"));
        }
        let mut nested = nested.into_iter();
        match (nested.next(), nested.next()) {
            (Some(m), None) => Ok((m.material, opacity)),
            _ => Err(p.error("needs exactly one nested BSDF")),
        }
    }
}

/// The materials of `nested`; an error when one of them is a mask (masks may only be outermost,
/// or alone inside a `twosided`).
pub(crate) fn unmasked(p: &Plugin, nested: Vec<Masked>) -> Result<Vec<Material>, SceneError> {
    if nested.iter().any(|m| m.opacity.is_some()) {
        return Err(p.error(format!(
            "a mask inside a {} is not supported: the mask must be the outermost bsdf (or alone in a twosided)",
            p.ty
        )));
    }
    Ok(nested.into_iter().map(|m| m.material).collect())
}

/// The materials nested in a `twosided` and the opacity it passes on: that of its only nested
/// BSDF when that is a mask. Masks on the two sides of a two-sided BSDF are an error.
pub(crate) fn twosided_parts(p: &Plugin, nested: Vec<Masked>) -> Result<(Vec<Material>, Option<Texture>), SceneError> {
    if let [only] = nested.as_slice() {
        return Ok((vec![only.material.clone()], only.opacity.clone()));
    }
    Ok((unmasked(p, nested)?, None))
}
