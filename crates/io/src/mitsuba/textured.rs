//! Textures on parameters that we can only take as constants (a rough material's `alpha`, an
//! area emitter's `radiance`): an error naming the parameter, or with a permissive load the
//! texture's mean value.

use math::Vec2;
use scene::Texture;
use spectrum::Rgb;

use super::Loader;
use super::colour::SpectrumUse;
use super::props::Plugin;
use crate::scene_error::SceneError;

/// Samples per axis of the grid over uv ∈ [0, 1]² that averages a texture.
const MEAN_GRID: u32 = 64;

/// The mean of `texture` over uv ∈ [0, 1]², estimated at the centres of a
/// `MEAN_GRID × MEAN_GRID` grid.
pub(crate) fn mean(texture: &Texture) -> Rgb {
    if let Some(c) = texture.as_constant() {
        return c;
    }
    let mut sum = [0.0f64; 3];
    for j in 0..MEAN_GRID {
        for i in 0..MEAN_GRID {
            let uv = Vec2::new((i as f32 + 0.5) / MEAN_GRID as f32, (j as f32 + 0.5) / MEAN_GRID as f32);
            let v = texture.eval(uv);
            for (s, c) in sum.iter_mut().zip([v.r, v.g, v.b]) {
                *s += f64::from(c);
            }
        }
    }
    let n = f64::from(MEAN_GRID * MEAN_GRID);
    Rgb::new((sum[0] / n) as f32, (sum[1] / n) as f32, (sum[2] / n) as f32)
}

impl<'a> Loader<'a> {
    /// `None` when `name` is not given as a texture (nested or `<ref>`); otherwise an error, or
    /// in a permissive load the texture's mean (with a warning).
    pub(crate) fn untextured(&mut self, p: &Plugin<'a>, name: &str) -> Result<Option<Rgb>, SceneError> {
        let Some(object) = p.objects.iter().find(|o| o.name.as_deref() == Some(name)) else { return Ok(None) };
        let error =
            object.node.pos.error(format!("{}: a texture on '{name}' is not supported (only a constant)", p.what()));
        self.unsupported(error, "the texture's mean value is used")?;
        let texture = self.texture_prop(p, name, 0.0, SpectrumUse::Reflectance)?;
        Ok(Some(mean(&texture)))
    }
}
