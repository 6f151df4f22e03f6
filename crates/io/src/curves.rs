//! Mitsuba 3's curve shapes, `linearcurve` and `bsplinecurve`, as triangle meshes.
//!
//! Mitsuba intersects curves analytically (Embree/OptiX curve primitives); the renderer has no
//! curve primitive yet (issue #14), so the tubes are tessellated at load:
//!
//! - `linearcurve`: each segment between control points `(p_i, r_i)` and `(p_{i+1}, r_{i+1})`
//!   is a frustum (a cone's slice) and every control point a sphere of radius `r_i` — Mitsuba's
//!   "smooth spherical joints" and end caps. The union's outer surface is the tube; inner parts
//!   of the overlapping pieces are never the first hit of a ray from outside (they matter only
//!   to rays that start inside the tube, which Mitsuba culls as back faces).
//! - `bsplinecurve`: each uniform cubic B-spline segment of four consecutive control points
//!   (positions and radii alike) is sampled at [`SAMPLES_PER_SEGMENT`] steps and swept as one
//!   continuous tube whose rings are perpendicular to the curve's tangent and carried along it
//!   without twisting (parallel transport); it is open-ended, as in Mitsuba.
//!
//! Rings have [`SIDES`] vertices at the radius `r·(θ/2)/sin(θ/2)`, `θ = 2π/SIDES`, so a ring's
//! perimeter is the circle's (as [`crate::cylinder`] does). uv follows Mitsuba: `u` the angle
//! around the tube over 2π, `v` the segment index plus the position along it, over the number
//! of segments of the shape. Radii are not scaled by `to_world` (Mitsuba: "the control points'
//! radii are invariant to this transformation"), so the mesh is built in world space.
//!
//! The file holds one control point per line, `x y z radius`; an empty line starts a new curve.

use std::f64::consts::TAU;
use std::path::Path;

use glam::DVec3;
use math::Vec2;
use scene::desc::MeshData;

/// Vertices per ring.
pub(crate) const SIDES: usize = 16;
/// Samples per B-spline segment.
pub(crate) const SAMPLES_PER_SEGMENT: usize = 8;

/// One control point: position (world space) and radius.
pub(crate) type ControlPoint = (DVec3, f64);

/// The two curve bases.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Basis {
    /// Piecewise linear, with spherical joints and caps.
    Linear,
    /// Uniform cubic B-spline, open-ended.
    BSpline,
}

impl Basis {
    /// Fewest control points of one curve.
    fn minimum_points(self) -> usize {
        match self {
            Basis::Linear => 2,
            Basis::BSpline => 4,
        }
    }
}

/// Reads a curve file (see the module documentation): the curves' control points in object
/// space. Errors name the file and line.
pub(crate) fn read_curves(path: &Path, basis: Basis) -> Result<Vec<Vec<ControlPoint>>, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("cannot read '{}': {e}", path.display()))?;
    let mut curves: Vec<Vec<ControlPoint>> = vec![Vec::new()];
    for (number, line) in text.lines().enumerate() {
        let fields: Vec<&str> = line.split_whitespace().collect();
        if fields.is_empty() {
            if !curves.last().is_some_and(Vec::is_empty) {
                curves.push(Vec::new());
            }
            continue;
        }
        let values: Option<Vec<f64>> = fields.iter().map(|f| f.parse().ok().filter(|v: &f64| v.is_finite())).collect();
        let at = || format!("{}:{}", path.display(), number + 1);
        match values.as_deref() {
            Some(&[x, y, z, r]) if r >= 0.0 => curves.last_mut().unwrap().push((DVec3::new(x, y, z), r)),
            Some(&[_, _, _, r]) => return Err(format!("{}: negative radius {r}", at())),
            _ => return Err(format!("{}: expected four numbers 'x y z radius', found '{line}'", at())),
        }
    }
    curves.retain(|c| !c.is_empty());
    if curves.is_empty() {
        return Err(format!("'{}' holds no control points", path.display()));
    }
    let minimum = basis.minimum_points();
    if let Some(c) = curves.iter().position(|c| c.len() < minimum) {
        return Err(format!(
            "'{}': curve {} has {} control points; a {} curve needs at least {minimum}",
            path.display(),
            c + 1,
            curves[c].len(),
            if basis == Basis::Linear { "linear" } else { "B-spline" }
        ));
    }
    Ok(curves)
}

/// The triangle mesh of `curves` (world space) in `basis`; see the module documentation.
pub(crate) fn curve_mesh(curves: &[Vec<ControlPoint>], basis: Basis) -> MeshData {
    let segments: usize = curves.iter().map(|c| c.len() + 1 - basis.minimum_points()).sum();
    let mut mesh = MeshData::default();
    let mut first_segment = 0;
    for curve in curves {
        let count = curve.len() + 1 - basis.minimum_points();
        let v_of = |segment: usize, t: f64| (first_segment + segment) as f64 + t;
        match basis {
            Basis::Linear => {
                for (i, pair) in curve.windows(2).enumerate() {
                    let samples = [(pair[0].0, pair[0].1, v_of(i, 0.0)), (pair[1].0, pair[1].1, v_of(i, 1.0))];
                    let tangent = pair[1].0 - pair[0].0;
                    tube(&mut mesh, &samples, &[tangent, tangent], segments);
                }
                for &(centre, radius) in curve {
                    sphere(&mut mesh, centre, radius);
                }
            }
            Basis::BSpline => {
                let mut samples = Vec::new();
                let mut tangents = Vec::new();
                for (i, window) in curve.windows(4).enumerate() {
                    let first = if i == 0 { 0 } else { 1 };
                    for k in first..=SAMPLES_PER_SEGMENT {
                        let t = k as f64 / SAMPLES_PER_SEGMENT as f64;
                        let (p, r, d) = b_spline(window, t);
                        samples.push((p, r, v_of(i, t)));
                        tangents.push(d);
                    }
                }
                tube(&mut mesh, &samples, &tangents, segments);
            }
        }
        first_segment += count;
    }
    mesh
}

/// Position, radius and position derivative of the uniform cubic B-spline segment of `points`
/// at `t ∈ [0, 1]`.
fn b_spline(points: &[ControlPoint], t: f64) -> (DVec3, f64, DVec3) {
    let s = 1.0 - t;
    let weights = [
        s * s * s / 6.0,
        (3.0 * t * t * t - 6.0 * t * t + 4.0) / 6.0,
        (-3.0 * t * t * t + 3.0 * t * t + 3.0 * t + 1.0) / 6.0,
        t * t * t / 6.0,
    ];
    let derivatives = [-0.5 * s * s, 1.5 * t * t - 2.0 * t, -1.5 * t * t + t + 0.5, 0.5 * t * t];
    let (mut p, mut r, mut d) = (DVec3::ZERO, 0.0, DVec3::ZERO);
    for (k, &(q, radius)) in points.iter().enumerate() {
        p += weights[k] * q;
        r += weights[k] * radius;
        d += derivatives[k] * q;
    }
    (p, r, d)
}

/// Any unit vector perpendicular to unit `axis`.
fn perpendicular(axis: DVec3) -> DVec3 {
    let helper = if axis.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
    axis.cross(helper).normalize()
}

/// A tube through `samples` (centre, radius, v before the division by `segments`) with rings
/// perpendicular to `tangents`, the ring frame carried from one ring to the next by the
/// smallest rotation (parallel transport).
pub(crate) fn tube(mesh: &mut MeshData, samples: &[(DVec3, f64, f64)], tangents: &[DVec3], segments: usize) {
    let scale = (0.5 * TAU / SIDES as f64) / (0.5 * TAU / SIDES as f64).sin();
    let base = mesh.positions.len() as u32;
    let mut previous_axis: Option<DVec3> = None;
    let mut x = DVec3::ZERO;
    for (k, (&(centre, radius, v), &tangent)) in samples.iter().zip(tangents).enumerate() {
        let axis = tangent.try_normalize().or(previous_axis).unwrap_or(DVec3::Z);
        x = match previous_axis {
            None => perpendicular(axis),
            // Remove the component along the new axis: the minimal rotation to first order.
            Some(_) => (x - axis * x.dot(axis)).try_normalize().unwrap_or_else(|| perpendicular(axis)),
        };
        previous_axis = Some(axis);
        let y = axis.cross(x);
        // The surface's slope along the axis tilts the normal: n ∝ radial − (dr/ds) axis.
        let slope = match (samples.get(k + 1), k.checked_sub(1).and_then(|j| samples.get(j))) {
            (Some(next), _) => (next.1 - radius) / (next.0 - centre).length().max(1e-12),
            (None, Some(before)) => (radius - before.1) / (centre - before.0).length().max(1e-12),
            _ => 0.0,
        };
        for side in 0..=SIDES {
            let angle = TAU * side as f64 / SIDES as f64;
            let radial = x * angle.cos() + y * angle.sin();
            mesh.positions.push((centre + radial * radius * scale).as_vec3());
            mesh.normals.push((radial - axis * slope).normalize().as_vec3());
            mesh.uvs.push(Vec2::new((side as f64 / SIDES as f64) as f32, (v / segments as f64) as f32));
        }
    }
    let ring = (SIDES + 1) as u32;
    for k in 0..samples.len().saturating_sub(1) as u32 {
        for side in 0..SIDES as u32 {
            let (a, b) = (base + k * ring + side, base + k * ring + side + 1);
            let (c, d) = (a + ring, b + ring);
            // Counter-clockwise seen from outside: (x, y, axis) is right-handed.
            mesh.triangles.push([a, b, d]);
            mesh.triangles.push([a, d, c]);
        }
    }
}

/// A sphere of `radius` around `centre` (latitude-longitude rings, outward normals).
fn sphere(mesh: &mut MeshData, centre: DVec3, radius: f64) {
    let rings = SIDES / 2;
    let base = mesh.positions.len() as u32;
    for i in 0..=rings {
        let theta = 0.5 * TAU * i as f64 / rings as f64;
        for j in 0..=SIDES {
            let phi = TAU * j as f64 / SIDES as f64;
            let n = DVec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos());
            mesh.positions.push((centre + n * radius).as_vec3());
            mesh.normals.push(n.as_vec3());
            mesh.uvs.push(Vec2::new(j as f32 / SIDES as f32, i as f32 / rings as f32));
        }
    }
    let row = (SIDES + 1) as u32;
    for i in 0..rings as u32 {
        for j in 0..SIDES as u32 {
            let (a, b) = (base + i * row + j, base + i * row + j + 1);
            let (c, d) = (a + row, b + row);
            // θ grows towards −z: (∂p/∂θ) × (∂p/∂φ) points outward.
            if i > 0 {
                mesh.triangles.push([a, c, b]);
            }
            if i + 1 < rings as u32 {
                mesh.triangles.push([b, c, d]);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use math::Vec3;

    /// Triangles wind with their vertex normals, and normals point away from `inside(p)`.
    fn outward(mesh: &MeshData, inside: impl Fn(Vec3) -> Vec3) {
        for (k, t) in mesh.triangles.iter().enumerate() {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
            let normals: Vec3 = t.iter().map(|&i| mesh.normals[i as usize]).sum();
            assert!((b - a).cross(c - a).dot(normals) > 0.0, "triangle {k} winds against its normals");
        }
        for (p, n) in mesh.positions.iter().zip(&mesh.normals) {
            assert!((n.length() - 1.0).abs() < 1e-5 && n.dot(*p - inside(*p)) >= -1e-6, "{p} {n}");
        }
    }

    #[test]
    fn a_linear_segment_is_a_frustum_with_spherical_caps() {
        let curve = vec![(DVec3::ZERO, 0.5), (DVec3::new(0.0, 0.0, 4.0), 0.25)];
        let mesh = curve_mesh(&[curve], Basis::Linear);
        mesh.validate().unwrap();
        // Every vertex lies on the frustum (the radius interpolated along z, up to the ring
        // scale) or on a cap sphere.
        let scale = (0.5 * TAU / SIDES as f64) / (0.5 * TAU / SIDES as f64).sin();
        for p in &mesh.positions {
            let (z, rho) = (f64::from(p.z), f64::from(p.x).hypot(f64::from(p.y)));
            let frustum = (-1e-6..=4.0 + 1e-6).contains(&z) && (rho - (0.5 - 0.0625 * z) * scale).abs() < 1e-5;
            let caps = (p.as_dvec3().length() - 0.5).abs() < 1e-5
                || ((p.as_dvec3() - DVec3::new(0.0, 0.0, 4.0)).length() - 0.25).abs() < 1e-5;
            assert!(frustum || caps, "{p}");
        }
        outward(&mesh, |p| Vec3::new(0.0, 0.0, p.z.clamp(0.0, 4.0)));
        // uv: v runs from 0 to 1 along the only segment.
        assert!(mesh.uvs.iter().all(|uv| (0.0..=1.0).contains(&uv.x) && (0.0..=1.0).contains(&uv.y)));
    }

    #[test]
    fn a_b_spline_tube_follows_the_curve() {
        // Control points at z = 0, 1, 2, 3 on the z axis: the segment runs from
        // (0 + 4·1 + 2)/6 = 1 to (1 + 4·2 + 3)/6 = 2 with unit speed; constant radius 0.1.
        let curve: Vec<ControlPoint> = (0..4).map(|k| (DVec3::new(0.0, 0.0, f64::from(k)), 0.1)).collect();
        let (start, r, d) = b_spline(&curve, 0.0);
        assert!((start - DVec3::new(0.0, 0.0, 1.0)).length() < 1e-12 && (r - 0.1).abs() < 1e-12);
        assert!((d - DVec3::Z).length() < 1e-12);
        let mesh = curve_mesh(&[curve], Basis::BSpline);
        mesh.validate().unwrap();
        assert_eq!(mesh.positions.len(), (SAMPLES_PER_SEGMENT + 1) * (SIDES + 1));
        for p in &mesh.positions {
            assert!(p.z >= 1.0 - 1e-6 && p.z <= 2.0 + 1e-6 && (p.x.hypot(p.y) - 0.1).abs() < 0.002, "{p}");
        }
        outward(&mesh, |p| Vec3::new(0.0, 0.0, p.z));
        // A bent curve keeps its rings untwisted and its triangles outward.
        let bent = vec![
            (DVec3::ZERO, 0.1),
            (DVec3::new(1.0, 0.0, 0.0), 0.1),
            (DVec3::new(1.0, 1.0, 0.0), 0.1),
            (DVec3::new(0.0, 1.0, 0.5), 0.1),
            (DVec3::new(0.0, 0.0, 1.0), 0.1),
        ];
        let mesh = curve_mesh(&[bent], Basis::BSpline);
        mesh.validate().unwrap();
        assert_eq!(mesh.triangles.len(), 2 * SIDES * 2 * SAMPLES_PER_SEGMENT);
    }

    #[test]
    fn curve_files_are_read_and_checked() {
        let dir = testkit::TempDir::new("curves");
        let path = dir.join("c.txt");
        std::fs::write(&path, "0 0 0 1\n1 0 0 1\n\n\n0 1 0 0.5\n0 2 0 0.5\n0 3 0 0.5\n").unwrap();
        let curves = read_curves(&path, Basis::Linear).unwrap();
        assert_eq!(curves.iter().map(Vec::len).collect::<Vec<_>>(), vec![2, 3]);
        let e = read_curves(&path, Basis::BSpline).unwrap_err();
        assert!(e.contains("curve 1 has 2 control points") && e.contains("at least 4"), "{e}");
        std::fs::write(&path, "0 0 0 1\n1 0 x 1\n").unwrap();
        let e = read_curves(&path, Basis::Linear).unwrap_err();
        assert!(e.contains("c.txt:2: expected four numbers"), "{e}");
        std::fs::write(&path, "0 0 0 -1\n1 0 0 1\n").unwrap();
        assert!(read_curves(&path, Basis::Linear).unwrap_err().contains("c.txt:1: negative radius"));
    }
}
