//! Textures: RGB values that vary over a surface with its texture coordinates, or with a
//! mesh attribute resolved at the hit ([`TexturePoint::attribute`]).

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
    /// columns, `v'` top to bottom over the rows, texel centres at half-integers. The same as
    /// [`Texture::SampledBitmap`] with [`Sampling::DEFAULT`].
    Bitmap {
        /// Linear RGB texels.
        image: Arc<TextureImage>,
        /// Map applied to the surface's uv first.
        to_uv: UvTransform,
    },
    /// An image with explicit wrap and filter modes (see [`Sampling`]); otherwise as
    /// [`Texture::Bitmap`]. [`Texture::bitmap`] builds whichever of the two fits.
    SampledBitmap {
        /// Linear RGB texels.
        image: Arc<TextureImage>,
        /// Map applied to the surface's uv first.
        to_uv: UvTransform,
        /// How texels are looked up.
        sampling: Sampling,
    },
    /// The product of two textures, channel by channel (pbrt's `scale`: `tex · scale`).
    Scale {
        /// The texture scaled.
        texture: Arc<Texture>,
        /// The factor.
        scale: Arc<Texture>,
    },
    /// `(1 − a)·tex1 + a·tex2` with `a` the red channel of `amount` clamped to [0, 1] (pbrt's
    /// `mix`, whose float `amount` texture has equal channels; pbrt does not clamp).
    Mix {
        /// The texture where `a` = 0.
        tex1: Arc<Texture>,
        /// The texture where `a` = 1.
        tex2: Arc<Texture>,
        /// The blend weight.
        amount: Arc<Texture>,
    },
    /// Mitsuba's `mesh_attribute`: the value of the mesh attribute `name` at the hit
    /// (interpolated for `vertex_` attributes, constant per triangle for `face_` ones) times
    /// `scale`. The scene resolves the attribute at each hit into [`TexturePoint::attribute`];
    /// a material reads at most one attribute name. Only materials' reflectance-like textures
    /// may use it (loaders and the scene build reject it elsewhere).
    MeshAttribute {
        /// `vertex_<name>` or `face_<name>`.
        name: String,
        /// Factor (unitless).
        scale: f32,
    },
}

/// Where a texture is looked up.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TexturePoint {
    /// Texture coordinates.
    pub uv: Vec2,
    /// The value of the mesh attribute the material reads, at the hit (black when there is
    /// none).
    pub attribute: Rgb,
}

impl TexturePoint {
    /// A point without a mesh attribute.
    #[inline]
    pub fn at_uv(uv: Vec2) -> Self {
        Self { uv, attribute: Rgb::BLACK }
    }
}

/// What an image lookup does with texel coordinates outside the image.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum WrapMode {
    /// Tile the image: texel `i` is `i mod n` (Mitsuba's and pbrt's default).
    Repeat,
    /// Tile mirrored copies: texels `0 … n−1` then `n−1 … 0`, and so on (Mitsuba's `mirror`).
    Mirror,
    /// Repeat the edge texels: texel `i` is `clamp(i, 0, n−1)` (Mitsuba's and pbrt's `clamp`).
    Clamp,
    /// Texels outside the image are black (pbrt's `black`).
    Black,
}

/// How an image lookup combines texels.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum FilterMode {
    /// The texel containing the point (Mitsuba's `nearest`, pbrt's `point`).
    Nearest,
    /// Bilinear interpolation between the four nearest texel centres.
    Bilinear,
}

/// The wrap and filter modes of an image lookup.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Sampling {
    /// Texel coordinates outside the image.
    pub wrap: WrapMode,
    /// Texel interpolation.
    pub filter: FilterMode,
}

impl Sampling {
    /// Repeat and bilinear: the lookup of [`Texture::Bitmap`].
    pub const DEFAULT: Sampling = Sampling { wrap: WrapMode::Repeat, filter: FilterMode::Bilinear };
}

impl Default for Sampling {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// `x.floor()`, bit for bit (signed zeros, infinities and NaN included), without the library
/// call that `f32::floor` is on the baseline x86-64 target: below 2^23 in magnitude the
/// truncation through `i32` is exact and one step from the floor; from 2^23 on every `f32` is
/// an integer (or not finite) and its own floor.
#[inline]
fn floor(x: f32) -> f32 {
    if x.abs() < 8_388_608.0 {
        let t = x as i32 as f32;
        // `t` is +0 for x in (−1, 1): keep the sign of a zero `x` (⌊−0⌋ = −0).
        if t > x { t - 1.0 } else { t.copysign(x) }
    } else {
        x
    }
}

impl Texture {
    /// The value at `uv`, for textures without mesh attributes (a
    /// [`Texture::MeshAttribute`] gives black; see [`Texture::eval_at`]).
    #[inline]
    pub fn eval(&self, uv: Vec2) -> Rgb {
        self.eval_at(TexturePoint::at_uv(uv))
    }

    /// The value at `point`.
    #[inline]
    pub fn eval_at(&self, point: TexturePoint) -> Rgb {
        // The common constant is read in place; the rest is one call.
        match self {
            Texture::Constant(value) => *value,
            _ => self.eval_varying(point),
        }
    }

    /// [`Texture::eval_at`] of every texture (constants included).
    fn eval_varying(&self, point: TexturePoint) -> Rgb {
        let uv = point.uv;
        match self {
            Texture::Constant(value) => *value,
            Texture::Checkerboard { color0, color1, to_uv } => {
                let p = to_uv.apply(uv);
                let a = p.x - floor(p.x) > 0.5;
                let b = p.y - floor(p.y) > 0.5;
                if a == b { *color0 } else { *color1 }
            }
            Texture::Bitmap { image, to_uv } => lookup(image, to_uv.apply(uv), Sampling::DEFAULT),
            Texture::SampledBitmap { image, to_uv, sampling } => lookup(image, to_uv.apply(uv), *sampling),
            Texture::Scale { texture, scale } => texture.eval_at(point) * scale.eval_at(point),
            Texture::Mix { tex1, tex2, amount } => {
                let a = amount.eval_at(point).r.clamp(0.0, 1.0);
                tex1.eval_at(point) * (1.0 - a) + tex2.eval_at(point) * a
            }
            Texture::MeshAttribute { scale, .. } => point.attribute * *scale,
        }
    }

    /// The mesh attribute the texture reads, if any (the first one found in a product or
    /// blend).
    pub fn mesh_attribute(&self) -> Option<&str> {
        match self {
            Texture::MeshAttribute { name, .. } => Some(name),
            Texture::Scale { texture: a, scale: b } => a.mesh_attribute().or_else(|| b.mesh_attribute()),
            Texture::Mix { tex1, tex2, amount } => {
                tex1.mesh_attribute().or_else(|| tex2.mesh_attribute()).or_else(|| amount.mesh_attribute())
            }
            _ => None,
        }
    }

    /// Calls `f` with the name of every mesh attribute the texture reads.
    pub fn for_each_mesh_attribute<'a>(&'a self, f: &mut dyn FnMut(&'a str)) {
        match self {
            Texture::MeshAttribute { name, .. } => f(name),
            Texture::Scale { texture: a, scale: b } => {
                a.for_each_mesh_attribute(f);
                b.for_each_mesh_attribute(f);
            }
            Texture::Mix { tex1, tex2, amount } => {
                tex1.for_each_mesh_attribute(f);
                tex2.for_each_mesh_attribute(f);
                amount.for_each_mesh_attribute(f);
            }
            _ => {}
        }
    }

    /// Whether the texture varies with the texture coordinates.
    pub fn reads_uv(&self) -> bool {
        match self {
            Texture::Constant(_) | Texture::MeshAttribute { .. } => false,
            Texture::Checkerboard { .. } | Texture::Bitmap { .. } | Texture::SampledBitmap { .. } => true,
            Texture::Scale { texture: a, scale: b } => a.reads_uv() || b.reads_uv(),
            Texture::Mix { tex1, tex2, amount } => tex1.reads_uv() || tex2.reads_uv() || amount.reads_uv(),
        }
    }

    /// An image texture: [`Texture::Bitmap`] for [`Sampling::DEFAULT`], else
    /// [`Texture::SampledBitmap`].
    pub fn bitmap(image: Arc<TextureImage>, to_uv: UvTransform, sampling: Sampling) -> Texture {
        if sampling == Sampling::DEFAULT {
            Texture::Bitmap { image, to_uv }
        } else {
            Texture::SampledBitmap { image, to_uv, sampling }
        }
    }

    /// The constant value, if the texture does not vary.
    pub fn as_constant(&self) -> Option<Rgb> {
        match self {
            Texture::Constant(value) => Some(*value),
            _ => None,
        }
    }

    /// The image resolution `(width, height)` in texels, for image textures (the largest of
    /// the parts of a product or blend); `None` for textures without a natural resolution.
    pub fn resolution(&self) -> Option<(u32, u32)> {
        match self {
            Texture::Constant(_) | Texture::Checkerboard { .. } | Texture::MeshAttribute { .. } => None,
            Texture::Bitmap { image, .. } | Texture::SampledBitmap { image, .. } => Some((image.width, image.height)),
            Texture::Scale { texture: a, scale: b } | Texture::Mix { tex1: a, tex2: b, .. } => {
                match (a.resolution(), b.resolution()) {
                    (Some(x), Some(y)) => Some((x.0.max(y.0), x.1.max(y.1))),
                    (x, y) => x.or(y),
                }
            }
        }
    }

    /// An upper bound of every channel over the surface (for textures without negative
    /// values, which the loaders ensure for reflectances); infinite for mesh attributes.
    pub fn max_value(&self) -> Rgb {
        match self {
            Texture::Constant(value) => *value,
            Texture::Checkerboard { color0, color1, .. } => color0.max(*color1),
            Texture::Bitmap { image, .. } | Texture::SampledBitmap { image, .. } => {
                image.pixels.iter().fold(Rgb::BLACK, |a, b| a.max(*b))
            }
            Texture::Scale { texture, scale } => texture.max_value() * scale.max_value(),
            Texture::Mix { tex1, tex2, .. } => tex1.max_value().max(tex2.max_value()),
            // Not known without the mesh: no finite bound.
            Texture::MeshAttribute { .. } => Rgb::splat(f32::INFINITY),
        }
    }
}

impl From<Rgb> for Texture {
    fn from(value: Rgb) -> Self {
        Texture::Constant(value)
    }
}

/// The texel index `i` of an image `n` texels wide after wrapping, `None` for black.
fn wrap(i: i64, n: i64, mode: WrapMode) -> Option<u32> {
    let j = match mode {
        WrapMode::Repeat => i.rem_euclid(n),
        WrapMode::Mirror => {
            let m = i.rem_euclid(2 * n);
            if m >= n { 2 * n - 1 - m } else { m }
        }
        WrapMode::Clamp => i.clamp(0, n - 1),
        WrapMode::Black => {
            if !(0..n).contains(&i) {
                return None;
            }
            i
        }
    };
    Some(j as u32)
}

/// The image at `uv` (`u` across the columns, `v` down the rows, both in [0, 1] over the
/// image; texel centres at half-integers of `uv · size`).
fn lookup(image: &TextureImage, uv: Vec2, sampling: Sampling) -> Rgb {
    let (w, h) = (i64::from(image.width), i64::from(image.height));
    let texel = |x: i64, y: i64| match (wrap(x, w, sampling.wrap), wrap(y, h, sampling.wrap)) {
        (Some(x), Some(y)) => image.pixel(x, y),
        _ => Rgb::BLACK,
    };
    // Positions beyond ±2^62 texels cannot be wrapped exactly; they are as meaningless as NaN.
    const LIMIT: f32 = 4.0e18;
    let fine = |v: f32| v.is_finite() && v.abs() < LIMIT;
    match sampling.filter {
        FilterMode::Nearest => {
            let (x, y) = ((uv.x * image.width as f32).floor(), (uv.y * image.height as f32).floor());
            if !fine(x) || !fine(y) {
                return Rgb::BLACK;
            }
            texel(x as i64, y as i64)
        }
        FilterMode::Bilinear => {
            let x = uv.x * image.width as f32 - 0.5;
            let y = uv.y * image.height as f32 - 0.5;
            if !fine(x) || !fine(y) {
                return Rgb::BLACK;
            }
            let (x0, y0) = (x.floor(), y.floor());
            let (fx, fy) = (x - x0, y - y0);
            let (x0, y0) = (x0 as i64, y0 as i64);
            let top = texel(x0, y0) * (1.0 - fx) + texel(x0 + 1, y0) * fx;
            let bottom = texel(x0, y0 + 1) * (1.0 - fx) + texel(x0 + 1, y0 + 1) * fx;
            top * (1.0 - fy) + bottom * fy
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floor_is_the_library_floor() {
        let mut xs = vec![0.0f32, -0.0, 0.5, -0.5, 1.0, -1.0, 8_388_607.5, -8_388_607.5, 8_388_608.0, -8_388_608.0];
        xs.extend([16_777_216.0, -3e9, 3e9, f32::MAX, f32::MIN, f32::INFINITY, f32::NEG_INFINITY]);
        xs.extend([f32::from_bits(1), -f32::from_bits(1), f32::MIN_POSITIVE, -f32::MIN_POSITIVE]);
        xs.extend([1.0 - f32::EPSILON / 2.0, -1.0 + f32::EPSILON / 2.0, 2.0 - f32::EPSILON, -2.0 + f32::EPSILON]);
        let mut rng = math::Rng::new(2, 3);
        for scale in [1.0f32, 10.0, 1e4, 1e7, 1e8] {
            xs.extend((0..20_000).map(|_| (rng.uniform() - 0.5) * 2.0 * scale));
        }
        for x in xs {
            assert_eq!(floor(x).to_bits(), x.floor().to_bits(), "x = {x}");
        }
        assert!(floor(f32::NAN).is_nan());
    }

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

    /// A 3×1 ramp 0, 1, 2 looked up at texel centres and between them, for every mode.
    #[test]
    fn wrap_and_filter_modes() {
        let ramp =
            Arc::new(TextureImage { width: 3, height: 1, pixels: (0..3).map(|i| Rgb::splat(i as f32)).collect() });
        let at = |u: f32, wrap: WrapMode, filter: FilterMode| {
            Texture::bitmap(ramp.clone(), UvTransform::IDENTITY, Sampling { wrap, filter }).eval(Vec2::new(u, 0.5)).r
        };
        // Texel centres (u = (i + ½)/3) for i = −3 … 5, expected texel per mode.
        let expected: [(WrapMode, [f32; 9]); 4] = [
            (WrapMode::Repeat, [0.0, 1.0, 2.0, 0.0, 1.0, 2.0, 0.0, 1.0, 2.0]),
            (WrapMode::Mirror, [2.0, 1.0, 0.0, 0.0, 1.0, 2.0, 2.0, 1.0, 0.0]),
            (WrapMode::Clamp, [0.0, 0.0, 0.0, 0.0, 1.0, 2.0, 2.0, 2.0, 2.0]),
            (WrapMode::Black, [0.0, 0.0, 0.0, 0.0, 1.0, 2.0, 0.0, 0.0, 0.0]),
        ];
        for (wrap, values) in expected {
            for (k, &v) in values.iter().enumerate() {
                let u = (k as f32 - 3.0 + 0.5) / 3.0;
                for filter in [FilterMode::Nearest, FilterMode::Bilinear] {
                    assert!((at(u, wrap, filter) - v).abs() < 1e-5, "{wrap:?} {filter:?} texel {}", k as i32 - 3);
                }
            }
        }
        // A quarter texel right of texel 1's centre: nearest keeps texel 1, bilinear blends.
        let u = (1.5 + 0.25) / 3.0;
        assert_eq!(at(u, WrapMode::Clamp, FilterMode::Nearest), 1.0);
        assert!((at(u, WrapMode::Clamp, FilterMode::Bilinear) - 1.25).abs() < 1e-5);
        // Right of the last centre: clamp holds 2, repeat blends towards texel 0, mirror stays
        // on texel 2 (its mirror image), black fades to 0.
        let u = (2.5 + 0.5) / 3.0;
        assert!((at(u, WrapMode::Clamp, FilterMode::Bilinear) - 2.0).abs() < 1e-5);
        assert!((at(u, WrapMode::Repeat, FilterMode::Bilinear) - 1.0).abs() < 1e-5);
        assert!((at(u, WrapMode::Mirror, FilterMode::Bilinear) - 2.0).abs() < 1e-5);
        assert!((at(u, WrapMode::Black, FilterMode::Bilinear) - 1.0).abs() < 1e-5);
        // The default sampling builds the plain bitmap variant.
        assert!(matches!(Texture::bitmap(ramp, UvTransform::IDENTITY, Sampling::DEFAULT), Texture::Bitmap { .. }));
    }

    #[test]
    fn scale_and_mix() {
        let ramp =
            Arc::new(TextureImage { width: 2, height: 1, pixels: vec![Rgb::splat(0.0), Rgb::new(1.0, 2.0, 4.0)] });
        let bitmap = Arc::new(Texture::Bitmap { image: ramp, to_uv: UvTransform::IDENTITY });
        let constant = |c: Rgb| Arc::new(Texture::Constant(c));
        let right = Vec2::new(0.75, 0.5);
        let scaled = Texture::Scale { texture: bitmap.clone(), scale: constant(Rgb::new(0.5, 0.25, 0.125)) };
        assert_eq!(scaled.eval(right), Rgb::splat(0.5));
        assert_eq!(scaled.max_value(), Rgb::splat(0.5));
        let mix = |a: f32| Texture::Mix {
            tex1: constant(Rgb::splat(0.2)),
            tex2: bitmap.clone(),
            amount: constant(Rgb::splat(a)),
        };
        assert_eq!(mix(0.0).eval(right), Rgb::splat(0.2));
        assert_eq!(mix(1.0).eval(right), Rgb::new(1.0, 2.0, 4.0));
        let half = mix(0.25).eval(right);
        assert!((half.r - (0.75 * 0.2 + 0.25)).abs() < 1e-6 && (half.b - (0.75 * 0.2 + 1.0)).abs() < 1e-6);
        // The amount is clamped.
        assert_eq!(mix(3.0).eval(right), Rgb::new(1.0, 2.0, 4.0));
        assert_eq!(mix(0.5).max_value(), Rgb::new(1.0, 2.0, 4.0));
    }
}
