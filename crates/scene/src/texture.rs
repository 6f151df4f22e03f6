//! Textures: RGB values that vary over a surface with its texture coordinates.

use std::sync::Arc;

use math::Vec2;
use spectrum::Rgb;

use crate::desc::{TextureImage, UvTransform};

/// A texture, evaluated at texture coordinates `uv`.
#[derive(Clone, Debug, PartialEq)]
pub enum Texture {
    /// The same value everywhere.
    Constant(Rgb),
    /// Mitsuba's `checkerboard`: with `uv' = to_uv(uv)`, `color0` where the fractional parts
    /// of `u'` and `v'` are both below or both above ½, `color1` elsewhere.
    Checkerboard {
        /// First colour.
        color0: Rgb,
        /// Second colour.
        color1: Rgb,
        /// Map applied to the surface's uv first.
        to_uv: UvTransform,
    },
    /// An image, bilinearly interpolated and repeated: `u'` runs left to right over the
    /// columns, `v'` top to bottom over the rows, texel centres at half-integers.
    Bitmap {
        /// Linear RGB texels.
        image: Arc<TextureImage>,
        /// Map applied to the surface's uv first.
        to_uv: UvTransform,
    },
}

impl Texture {
    /// The value at `uv`.
    #[inline]
    pub fn eval(&self, uv: Vec2) -> Rgb {
        match self {
            Texture::Constant(value) => *value,
            Texture::Checkerboard { color0, color1, to_uv } => {
                let p = to_uv.apply(uv);
                let a = p.x - p.x.floor() > 0.5;
                let b = p.y - p.y.floor() > 0.5;
                if a == b { *color0 } else { *color1 }
            }
            Texture::Bitmap { image, to_uv } => bilinear(image, to_uv.apply(uv)),
        }
    }

    /// The constant value, if the texture does not vary.
    pub fn as_constant(&self) -> Option<Rgb> {
        match self {
            Texture::Constant(value) => Some(*value),
            _ => None,
        }
    }

    /// An upper bound of every channel over the surface.
    pub fn max_value(&self) -> Rgb {
        match self {
            Texture::Constant(value) => *value,
            Texture::Checkerboard { color0, color1, .. } => color0.max(*color1),
            Texture::Bitmap { image, .. } => image.pixels.iter().fold(Rgb::BLACK, |a, b| a.max(*b)),
        }
    }
}

impl From<Rgb> for Texture {
    fn from(value: Rgb) -> Self {
        Texture::Constant(value)
    }
}

/// Bilinear lookup with repeat wrapping.
fn bilinear(image: &TextureImage, uv: Vec2) -> Rgb {
    let w = image.width as i64;
    let h = image.height as i64;
    let x = uv.x * image.width as f32 - 0.5;
    let y = uv.y * image.height as f32 - 0.5;
    if !x.is_finite() || !y.is_finite() {
        return Rgb::BLACK;
    }
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let wrap = |i: i64, n: i64| i.rem_euclid(n) as u32;
    let (x0, y0) = (x0 as i64, y0 as i64);
    let (xa, xb) = (wrap(x0, w), wrap(x0 + 1, w));
    let (ya, yb) = (wrap(y0, h), wrap(y0 + 1, h));
    let top = image.pixel(xa, ya) * (1.0 - fx) + image.pixel(xb, ya) * fx;
    let bottom = image.pixel(xa, yb) * (1.0 - fx) + image.pixel(xb, yb) * fx;
    top * (1.0 - fy) + bottom * fy
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checkerboard_alternates() {
        let t = Texture::Checkerboard {
            color0: Rgb::splat(0.4),
            color1: Rgb::splat(0.2),
            to_uv: UvTransform { columns: [Vec2::new(2.0, 0.0), Vec2::new(0.0, 2.0)], translation: Vec2::ZERO },
        };
        assert_eq!(t.eval(Vec2::new(0.1, 0.1)), Rgb::splat(0.4));
        assert_eq!(t.eval(Vec2::new(0.3, 0.1)), Rgb::splat(0.2));
        assert_eq!(t.eval(Vec2::new(0.3, 0.3)), Rgb::splat(0.4));
        assert_eq!(t.eval(Vec2::new(0.6, 0.1)), Rgb::splat(0.4));
    }

    #[test]
    fn bitmap_interpolates_and_wraps() {
        let image = Arc::new(TextureImage { width: 2, height: 1, pixels: vec![Rgb::splat(0.0), Rgb::splat(1.0)] });
        let t = Texture::Bitmap { image, to_uv: UvTransform::IDENTITY };
        assert_eq!(t.eval(Vec2::new(0.25, 0.5)), Rgb::splat(0.0));
        assert_eq!(t.eval(Vec2::new(0.75, 0.5)), Rgb::splat(1.0));
        assert!((t.eval(Vec2::new(0.5, 0.5)).r - 0.5).abs() < 1e-6);
        // Between the last and (wrapped) first texel.
        assert!((t.eval(Vec2::new(1.0, 0.5)).r - 0.5).abs() < 1e-6);
        assert!((t.eval(Vec2::new(2.25, 7.5)).r - 0.0).abs() < 1e-6);
    }
}
