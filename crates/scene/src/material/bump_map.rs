//! Mitsuba's `bumpmap`: a nested material whose shading normal is tilted by the gradient of a
//! scalar height texture `h(u, v)` times `scale` (Blinn 1978 in Mitsuba's form):
//! `∂p/∂u' = ∂p/∂u + n (scale·∂h/∂u − n·∂p/∂u)` (likewise for v), `n' = normalize(∂p/∂u' ×
//! ∂p/∂v')`, flipped to the side of the geometric normal. `h` is the texture's luminance.
//! The BSDF is the nested material's with the perturbed normal (see [`super::perturb`]).

use math::{Vec2, Vec3};

use super::perturb::SurfaceTangents;
use crate::desc::UvTransform;
use crate::texture::Texture;

/// The perturbed unit normal.
pub(super) fn perturb(height: &Texture, scale: f32, tangents: &SurfaceTangents) -> Vec3 {
    let gradient = luminance_gradient(height, tangents.uv) * scale;
    let n = tangents.shading_normal;
    let dp_du = tangents.dp_du + n * (gradient.x - n.dot(tangents.dp_du));
    let dp_dv = tangents.dp_dv + n * (gradient.y - n.dot(tangents.dp_dv));
    let normal = dp_du.cross(dp_dv).normalize();
    if normal.dot(tangents.geometric_normal) < 0.0 { -normal } else { normal }
}

/// `(∂h/∂u, ∂h/∂v)` of the texture's luminance `h` at `uv`. For an image with bilinear
/// filtering this is the exact derivative of the interpolation: a difference quotient over a
/// quarter texel taken towards the inside of the interpolation cell, where `h` is linear along
/// each axis (zero for nearest filtering, as in Mitsuba); constants have none; other textures
/// use a central difference of 10⁻⁴ in uv.
pub fn luminance_gradient(texture: &Texture, uv: Vec2) -> Vec2 {
    let h = |p: Vec2| texture.eval(p).luminance();
    match texture {
        Texture::Constant(_) => Vec2::ZERO,
        Texture::Bitmap { image, to_uv } | Texture::SampledBitmap { image, to_uv, .. } => {
            let Some(inverse) = inverse(to_uv) else { return Vec2::ZERO };
            let size = Vec2::new(image.width as f32, image.height as f32);
            let p = to_uv.apply(uv);
            let texel = p * size - Vec2::splat(0.5);
            let cell = texel - texel.floor();
            let towards = |f: f32| if f < 0.5 { 0.25 } else { -0.25 };
            let step = Vec2::new(towards(cell.x), towards(cell.y)) / size;
            let at = |q: Vec2| if *to_uv == UvTransform::IDENTITY { h(q) } else { h(inverse.apply(q)) };
            let h0 = at(p);
            let dx = (at(p + Vec2::new(step.x, 0.0)) - h0) / step.x;
            let dy = (at(p + Vec2::new(0.0, step.y)) - h0) / step.y;
            // Chain rule through p = to_uv(uv): columns[i] = ∂p/∂uv_i.
            let [du, dv] = to_uv.columns;
            let gradient = Vec2::new(dx * du.x + dy * du.y, dx * dv.x + dy * dv.y);
            if gradient.is_finite() { gradient } else { Vec2::ZERO }
        }
        _ => {
            const H: f32 = 1e-4;
            let du = (h(uv + Vec2::new(H, 0.0)) - h(uv - Vec2::new(H, 0.0))) / (2.0 * H);
            let dv = (h(uv + Vec2::new(0.0, H)) - h(uv - Vec2::new(0.0, H))) / (2.0 * H);
            Vec2::new(du, dv)
        }
    }
}

/// The inverse of an affine uv map, `None` when it is singular.
fn inverse(m: &UvTransform) -> Option<UvTransform> {
    let [a, b] = m.columns;
    let det = a.x * b.y - b.x * a.y;
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let columns = [Vec2::new(b.y, -a.y) / det, Vec2::new(-b.x, a.x) / det];
    let translation = -(columns[0] * m.translation.x + columns[1] * m.translation.y);
    Some(UvTransform { columns, translation })
}
