//! pbrt-v4's image infinite lights store radiance in Clarberg's equal-area octahedral mapping
//! of the sphere onto a square; our `LightDesc::EnvMap` is latitude–longitude. We resample:
//! every lat-long texel takes the bilinearly interpolated value of the square image at the
//! direction through the texel's centre (edges clamped, where pbrt wraps octahedrally — a
//! difference confined to the outermost half texel).

use std::f64::consts::PI;

use math::Vec3;
use scene::desc::TextureImage;
use scene::light::equal_area;
use spectrum::Rgb;

use crate::pbrt::transform::V3;

/// Bilinear lookup in a row-major image at continuous coordinates `st` ∈ [0,1]², texel centres
/// at half-integers, clamped at the edges.
fn bilinear_clamped(width: usize, height: usize, pixels: &[[f32; 3]], st: [f64; 2]) -> [f64; 3] {
    let x = (st[0] * width as f64 - 0.5).clamp(0.0, (width - 1) as f64);
    let y = (st[1] * height as f64 - 0.5).clamp(0.0, (height - 1) as f64);
    let (x0, y0) = (x.floor() as usize, y.floor() as usize);
    let (x1, y1) = ((x0 + 1).min(width - 1), (y0 + 1).min(height - 1));
    let (fx, fy) = (x - x0 as f64, y - y0 as f64);
    let at = |xx: usize, yy: usize| pixels[yy * width + xx].map(f64::from);
    let mut out = [0.0; 3];
    for (k, o) in out.iter_mut().enumerate() {
        let top = at(x0, y0)[k] * (1.0 - fx) + at(x1, y0)[k] * fx;
        let bottom = at(x0, y1)[k] * (1.0 - fx) + at(x1, y1)[k] * fx;
        *o = top * (1.0 - fy) + bottom * fy;
    }
    out
}

/// The local direction our lat-long convention assigns to the centre of texel `(i, j)` of a
/// `width × height` map: `u = atan2(v.x, −v.z)/(2π)`, `v = acos(v.y)/π`.
pub fn latlong_direction(i: usize, j: usize, width: usize, height: usize) -> V3 {
    let phi = 2.0 * PI * (i as f64 + 0.5) / width as f64;
    let theta = PI * (j as f64 + 0.5) / height as f64;
    [theta.sin() * phi.sin(), theta.cos(), -theta.sin() * phi.cos()]
}

/// Resamples a square equal-area octahedral image (`side × side`, row 0 at the top, pbrt's
/// `st = (x, y) / side`) into a `2·side × side` lat-long image in the same local frame.
pub fn octahedral_to_latlong(side: usize, pixels: &[[f32; 3]]) -> TextureImage {
    let (width, height) = (2 * side, side);
    let mut out = Vec::with_capacity(width * height);
    for j in 0..height {
        for i in 0..width {
            let d = latlong_direction(i, j, width, height);
            let st = equal_area::sphere_to_square(Vec3::new(d[0] as f32, d[1] as f32, d[2] as f32).normalize());
            let st = [f64::from(st.x), f64::from(st.y)];
            let c = bilinear_clamped(side, side, pixels, st);
            out.push(Rgb::new(c[0] as f32, c[1] as f32, c[2] as f32));
        }
    }
    TextureImage { width: width as u32, height: height as u32, pixels: out }
}
