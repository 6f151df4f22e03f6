//! pbrt-v4's image infinite lights store radiance in Clarberg's equal-area octahedral mapping
//! of the sphere onto a square; our `LightDesc::EnvMap` is latitude–longitude. We resample:
//! every lat-long texel takes the bilinearly interpolated value of the square image at the
//! direction through the texel's centre (edges clamped, where pbrt wraps octahedrally — a
//! difference confined to the outermost half texel).

use std::f64::consts::PI;

use scene::desc::TextureImage;
use spectrum::Rgb;

use crate::pbrt::transform::V3;

/// Clarberg's equal-area map from the unit square to the unit sphere (pbrt-v4's
/// `EqualAreaSquareToSphere`): uniform density on the square becomes uniform density on the
/// sphere.
pub fn square_to_sphere(p: [f64; 2]) -> V3 {
    let u = 2.0 * p[0] - 1.0;
    let v = 2.0 * p[1] - 1.0;
    let (up, vp) = (u.abs(), v.abs());
    let signed_distance = 1.0 - (up + vp);
    let d = signed_distance.abs();
    let r = 1.0 - d;
    let phi = if r == 0.0 { 1.0 } else { (vp - up) / r + 1.0 } * PI / 4.0;
    let z = (1.0 - r * r).copysign(signed_distance);
    let cos_phi = phi.cos().copysign(u);
    let sin_phi = phi.sin().copysign(v);
    let s = r * (2.0 - r * r).max(0.0).sqrt();
    [cos_phi * s, sin_phi * s, z]
}

/// The inverse of [`square_to_sphere`] for a unit direction.
pub fn sphere_to_square(d: V3) -> [f64; 2] {
    let (x, y, z) = (d[0].abs(), d[1].abs(), d[2].abs());
    let r = (1.0 - z).max(0.0).sqrt();
    let a = x.max(y);
    let b = if a == 0.0 { 0.0 } else { x.min(y) / a };
    let mut phi = b.atan() * 2.0 / PI;
    if x < y {
        phi = 1.0 - phi;
    }
    let mut v = phi * r;
    let mut u = r - v;
    if d[2] < 0.0 {
        std::mem::swap(&mut u, &mut v);
        u = 1.0 - u;
        v = 1.0 - v;
    }
    let u = u.copysign(d[0]);
    let v = v.copysign(d[1]);
    [(u + 1.0) * 0.5, (v + 1.0) * 0.5]
}

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
            let st = sphere_to_square(latlong_direction(i, j, width, height));
            let c = bilinear_clamped(side, side, pixels, st);
            out.push(Rgb::new(c[0] as f32, c[1] as f32, c[2] as f32));
        }
    }
    TextureImage { width: width as u32, height: height as u32, pixels: out }
}
