//! Piecewise-constant densities over the unit square that follow a non-negative function (a
//! texture's luminance), for the lights that importance-sample their textures.
//!
//! The density only has to be positive wherever the function can be and close to it in shape;
//! the estimators divide by exactly the density [`Distribution2D::pdf`] reports. Each cell's
//! weight is the largest value at its four corners and its centre, plus a floor of
//! [`FLOOR_FRACTION`] of the mean weight so that no cell has zero density (a texture can be
//! positive between the points where it is evaluated).

use math::{Distribution2D, Vec2};

/// Share of the mean cell weight added to every cell.
pub const FLOOR_FRACTION: f32 = 0.05;

/// A tabulated density over `[0, 1]²` with `width × height` cells (rows along the second
/// coordinate) following `f`, and the midpoint-rule estimate of `∫ f` over the square
/// (from the cell centres). `None` when `f` is zero (or not finite) at every point evaluated.
pub fn tabulate(width: usize, height: usize, f: impl Fn(Vec2) -> f32) -> Option<(Distribution2D, f32)> {
    let (w, h) = (width.max(1), height.max(1));
    let value = |x: usize, y: usize, dx: f32, dy: f32| {
        let v = f(Vec2::new((x as f32 + dx) / w as f32, (y as f32 + dy) / h as f32));
        if v.is_finite() { v.max(0.0) } else { 0.0 }
    };
    // Corner values, shared between neighbouring cells.
    let corners: Vec<f32> =
        (0..=h).flat_map(|y| (0..=w).map(move |x| (x, y))).map(|(x, y)| value(x, y, 0.0, 0.0)).collect();
    let corner = |x: usize, y: usize| corners[y * (w + 1) + x];
    let mut weights = Vec::with_capacity(w * h);
    let mut integral = 0.0f64;
    for y in 0..h {
        for x in 0..w {
            let centre = value(x, y, 0.5, 0.5);
            integral += f64::from(centre);
            let m = centre.max(corner(x, y)).max(corner(x + 1, y)).max(corner(x, y + 1)).max(corner(x + 1, y + 1));
            weights.push(m);
        }
    }
    let mean = weights.iter().map(|&v| f64::from(v)).sum::<f64>() / (w * h) as f64;
    if !(mean > 0.0 && mean.is_finite()) {
        return None;
    }
    let floor = FLOOR_FRACTION * mean as f32;
    weights.iter_mut().for_each(|v| *v += floor);
    let distribution = Distribution2D::new(&weights, w, h)?;
    Some((distribution, (integral / (w * h) as f64) as f32))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn positive_everywhere_and_proportional_where_smooth() {
        // f = x on [0,1]²: integral ½; every cell positive; density grows with x.
        let (d, integral) = tabulate(8, 2, |p| p.x).unwrap();
        assert!((integral - 0.5).abs() < 1e-6);
        let left = d.pdf(Vec2::new(0.01, 0.5));
        let right = d.pdf(Vec2::new(0.99, 0.5));
        assert!(left > 0.0 && right > 5.0 * left, "{left} {right}");
        assert!(tabulate(4, 4, |_| 0.0).is_none());
    }
}
