//! The mean of a texture, for parameters that can only take a constant (a textured `radiance`
//! on a sphere or disc in a permissive load).

use math::Vec2;
use scene::Texture;
use spectrum::Rgb;

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
