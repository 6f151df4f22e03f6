//! pbrt's `curve` shape, tessellated into a tube mesh in object space (the caller transforms it
//! like any mesh, so widths scale with the transformation as in pbrt).
//!
//! - `basis` `"bezier"` (default): `degree` 3 (default) takes `3n + 1` control points `P` for
//!   `n` segments sharing end points, `degree` 2 takes `2n + 1`; `"bspline"`: uniform
//!   B-splines of degree 3 (`n + 3` points) or 2 (`n + 2` points).
//! - The width runs linearly from `width0` to `width1` over the whole curve (both default to
//!   `width`, default 1); the tube radius is half the width.
//! - `type` `"flat"` (default), `"ribbon"` and `"cylinder"` all become the same closed tube of
//!   [`curves::SIDES`] sides. pbrt's flat curves always face the ray, so a camera-independent
//!   tube has their silhouette from every direction; ribbons (oriented by `N`) are not
//!   modelled and their `N` is read and ignored (a warning-free approximation, documented in
//!   `docs/materials.md`).
//! - Each segment is sampled at `2^splitdepth` steps (pbrt's `splitdepth`, default 3, clamped to
//!   [1, 6]).
//!
//! uv follow [`crate::curves`]: `u` around the tube, `v` along the curve over the number of
//! segments, so that the hair BSDF's fibre direction `n × ∂p/∂u` runs along the curve.

use glam::DVec3;
use scene::desc::MeshData;

use super::parser::ParamSet;
use crate::curves;
use crate::pbrt::tokenizer::Pos;
use crate::scene_error::SceneError;

/// The two bases of pbrt's curves.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Basis {
    Bezier,
    BSpline,
}

/// Reads the `curve` parameters of `p` (directive at `pos`) and returns the object-space tube.
pub(super) fn curve_mesh(p: &ParamSet, pos: Pos) -> Result<MeshData, SceneError> {
    let Some((values, ppos)) = p.numbers("P", &["point3"], 3)? else {
        return Err(p.error(pos, "curve needs \"point3 P\""));
    };
    let points: Vec<DVec3> = values.chunks(3).map(|v| DVec3::new(v[0], v[1], v[2])).collect();
    let basis = match p.string("basis")? {
        None => Basis::Bezier,
        Some((b, _)) if b == "bezier" => Basis::Bezier,
        Some((b, _)) if b == "bspline" => Basis::BSpline,
        Some((b, bpos)) => return Err(p.error(bpos, format!("curve basis \"{b}\" is not \"bezier\" or \"bspline\""))),
    };
    let degree = p.int("degree", 3)?;
    if degree != 2 && degree != 3 {
        let dpos = p.find("degree").map_or(pos, |x| x.pos);
        return Err(p.error(dpos, format!("curve degree {degree} is not 2 or 3")));
    }
    let degree = degree as usize;
    if let Some((t, tpos)) = p.string("type")?
        && !matches!(t.as_str(), "flat" | "ribbon" | "cylinder")
    {
        return Err(p.error(tpos, format!("curve type \"{t}\" is not \"flat\", \"ribbon\" or \"cylinder\"")));
    }
    // Ribbon normals: read (and so not reported as unused) but not modelled.
    let _ = p.numbers("N", &["normal3", "normal"], 3)?;
    let width = p.float("width", 1.0)?;
    let (width0, width1) = (p.float("width0", width)?, p.float("width1", width)?);
    if !(width0 >= 0.0 && width1 >= 0.0 && width0.is_finite() && width1.is_finite()) {
        return Err(p.error(pos, format!("curve widths {width0}, {width1} must be non-negative")));
    }
    let steps = 1usize << p.int("splitdepth", 3)?.clamp(1, 6);
    let segments = match basis {
        Basis::Bezier if points.len() > degree && (points.len() - 1) % degree == 0 => (points.len() - 1) / degree,
        Basis::BSpline if points.len() > degree => points.len() - degree,
        _ => {
            let expected = match basis {
                Basis::Bezier => format!("{degree}n + 1 control points"),
                Basis::BSpline => format!("at least {} control points", degree + 1),
            };
            return Err(p.error(
                ppos,
                format!("a degree-{degree} {basis:?} curve needs {expected}, got {}", points.len()).to_lowercase(),
            ));
        }
    };
    let mut samples = Vec::new();
    let mut tangents = Vec::new();
    for segment in 0..segments {
        let window = match basis {
            Basis::Bezier => &points[segment * degree..=segment * degree + degree],
            Basis::BSpline => &points[segment..=segment + degree],
        };
        for k in usize::from(segment > 0)..=steps {
            let t = k as f64 / steps as f64;
            let (position, derivative) = match basis {
                Basis::Bezier => bezier(window, t),
                Basis::BSpline => b_spline(window, t),
            };
            let along = (segment as f64 + t) / segments as f64;
            let radius = 0.5 * (f64::from(width0) * (1.0 - along) + f64::from(width1) * along);
            samples.push((position, radius, segment as f64 + t));
            tangents.push(derivative);
        }
    }
    let mut mesh = MeshData::default();
    curves::tube(&mut mesh, &samples, &tangents, segments);
    Ok(mesh)
}

/// Position and derivative of the Bézier curve of `points` (degree `points.len() − 1`) at `t`
/// (de Casteljau).
fn bezier(points: &[DVec3], t: f64) -> (DVec3, DVec3) {
    let mut level: Vec<DVec3> = points.to_vec();
    while level.len() > 2 {
        level = level.windows(2).map(|w| w[0].lerp(w[1], t)).collect();
    }
    let degree = (points.len() - 1) as f64;
    (level[0].lerp(level[1], t), degree * (level[1] - level[0]))
}

/// Position and derivative of the uniform B-spline segment of `points` (3 points: quadratic,
/// 4: cubic) at `t`.
fn b_spline(points: &[DVec3], t: f64) -> (DVec3, DVec3) {
    let s = 1.0 - t;
    let (weights, derivatives): (Vec<f64>, Vec<f64>) = if points.len() == 3 {
        (vec![0.5 * s * s, 0.5 * (-2.0 * t * t + 2.0 * t + 1.0), 0.5 * t * t], vec![-s, 1.0 - 2.0 * t, t])
    } else {
        (
            vec![
                s * s * s / 6.0,
                (3.0 * t * t * t - 6.0 * t * t + 4.0) / 6.0,
                (-3.0 * t * t * t + 3.0 * t * t + 3.0 * t + 1.0) / 6.0,
                t * t * t / 6.0,
            ],
            vec![-0.5 * s * s, 1.5 * t * t - 2.0 * t, -1.5 * t * t + t + 0.5, 0.5 * t * t],
        )
    };
    points
        .iter()
        .zip(weights.iter().zip(&derivatives))
        .fold((DVec3::ZERO, DVec3::ZERO), |(p, d), (q, (w, dw))| (p + *q * *w, d + *q * *dw))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Bézier and B-spline evaluation: end points, derivatives by finite differences, and the
    /// B-spline's partition of unity.
    #[test]
    fn bases_evaluate_and_differentiate() {
        let pts = [DVec3::ZERO, DVec3::new(1.0, 2.0, 0.0), DVec3::new(3.0, 2.0, 1.0), DVec3::new(4.0, 0.0, 0.0)];
        for window in [&pts[..3], &pts[..]] {
            let (p0, _) = bezier(window, 0.0);
            let (p1, _) = bezier(window, 1.0);
            assert!(p0.distance(window[0]) < 1e-12 && p1.distance(*window.last().unwrap()) < 1e-12);
            for f in [bezier, b_spline] {
                let t = 0.37;
                let h = 1e-6;
                let numeric = (f(window, t + h).0 - f(window, t - h).0) / (2.0 * h);
                assert!(numeric.distance(f(window, t).1) < 1e-5, "{numeric} {:?}", f(window, t).1);
            }
        }
        // Equal control points: the B-spline is that point (weights sum to 1).
        let same = [DVec3::ONE; 4];
        assert!(b_spline(&same, 0.3).0.distance(DVec3::ONE) < 1e-12);
        assert!(b_spline(&same[..3], 0.8).0.distance(DVec3::ONE) < 1e-12);
    }
}
