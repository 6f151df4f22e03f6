//! pbrt-v4's shape parameter `alpha`: `"float alpha" [a]` with `a ∈ [0, 1]`, or
//! `"texture alpha" "name"` naming a float texture. The renderer applies it at intersection
//! level (see `scene::alpha`): where the opacity is 0 rays pass through the shape, where it is
//! fractional they pass with probability `1 − a` (pbrt-v4's stochastic alpha test).

use super::Builder;
use super::parser::{ParamSet, Value};
use crate::scene_error::SceneError;
use scene::texture::Texture;
use spectrum::Rgb;

impl Builder {
    /// The opacity texture of a shape's `alpha` parameter; `None` when it is absent or 1.
    pub(super) fn shape_alpha(&self, p: &ParamSet) -> Result<Option<Texture>, SceneError> {
        let Some(param) = p.find("alpha") else { return Ok(None) };
        match param.ty.as_str() {
            "float" => match param.numbers()[..] {
                [a] if (0.0..=1.0).contains(&a) => Ok((a < 1.0).then(|| Texture::Constant(Rgb::splat(a as f32)))),
                [a] => Err(p.error(param.pos, format!("alpha {a} must lie in [0, 1]"))),
                _ => Err(p.error(param.pos, "\"float alpha\" needs one value")),
            },
            "texture" => {
                let [Value::Str(name)] = &param.values[..] else {
                    return Err(p.error(param.pos, "\"texture alpha\" needs one texture name"));
                };
                match self.textures.get(name) {
                    Some(t) => Ok(Some(t.texture.clone())),
                    None => Err(p.error(param.pos, format!("unknown texture \"{name}\" for alpha"))),
                }
            }
            other => {
                Err(p.error(param.pos, format!("parameter 'alpha' has type '{other}', expected float or texture")))
            }
        }
    }
}
