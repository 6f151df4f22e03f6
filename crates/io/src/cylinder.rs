//! Open cylinders (Mitsuba's and pbrt's `cylinder` shapes) as triangle meshes.
//!
//! The renderer has no analytic cylinder, so the lateral surface is tessellated into
//! [`SEGMENTS_PER_TURN`] flat strips per full turn with smooth vertex normals. The vertices lie
//! at the radius `R = r · (θ/2) / sin(θ/2)` (θ the angle of one strip), which makes each
//! strip's width `2R·sin(θ/2)` equal to the arc `r·θ` it replaces: the mesh has exactly the
//! cylinder's area, so an emitting cylinder emits the same power. The surface stays within
//! about `r·θ²/12` of the true cylinder (2·10⁻⁴ r for 128 strips: vertices `r·θ²/24` outside,
//! strip centres `r·θ²/24` inside).

use std::f64::consts::TAU;

use math::{Vec2, Vec3};
use scene::desc::MeshData;

/// Strips per full turn.
pub(crate) const SEGMENTS_PER_TURN: u32 = 128;

/// The lateral surface of the cylinder of radius `radius` around the z axis from `z_min` to
/// `z_max`, swept from φ = 0 to `phi_max` (radians, in (0, 2π]), in object space. Normals
/// point away from the axis and the winding agrees with them; uv is `(φ / phi_max,
/// (z − z_min) / (z_max − z_min))`, as in Mitsuba and pbrt.
pub(crate) fn cylinder_mesh(radius: f64, z_min: f64, z_max: f64, phi_max: f64) -> MeshData {
    let strips = ((f64::from(SEGMENTS_PER_TURN) * phi_max / TAU).ceil() as u32).max(1);
    let theta = phi_max / f64::from(strips);
    let vertex_radius = radius * (theta / 2.0) / (theta / 2.0).sin();
    let mut mesh = MeshData::default();
    for i in 0..=strips {
        let phi = theta * f64::from(i);
        let (s, c) = phi.sin_cos();
        for (z, v) in [(z_min, 0.0), (z_max, 1.0)] {
            mesh.positions.push(Vec3::new((vertex_radius * c) as f32, (vertex_radius * s) as f32, z as f32));
            mesh.normals.push(Vec3::new(c as f32, s as f32, 0.0));
            mesh.uvs.push(Vec2::new((f64::from(i) / f64::from(strips)) as f32, v));
        }
    }
    for i in 0..strips {
        // Vertices 2i (bottom) and 2i + 1 (top) at φ_i; (∂p/∂φ) × (∂p/∂z) points outward.
        let (a, d, b, c) = (2 * i, 2 * i + 1, 2 * i + 2, 2 * i + 3);
        mesh.triangles.push([a, b, c]);
        mesh.triangles.push([c, d, a]);
    }
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The summed triangle area equals the cylinder's `φ_max · r · h`, and every geometric
    /// normal points away from the axis.
    #[test]
    fn area_and_orientation() {
        for (r, z0, z1, phi) in [(1.0, 0.0, 1.0, TAU), (0.3, -2.0, 5.0, TAU), (2.0, -1.0, 1.0, 1.0)] {
            let m = cylinder_mesh(r, z0, z1, phi);
            let mut area = 0.0f64;
            for t in &m.triangles {
                let [p0, p1, p2] = t.map(|i| m.positions[i as usize]);
                let n = (p1 - p0).cross(p2 - p0);
                area += 0.5 * f64::from(n.length());
                let centre = (p0 + p1 + p2) / 3.0;
                assert!(n.x * centre.x + n.y * centre.y > 0.0);
            }
            let exact = phi * r * (z1 - z0);
            assert!((area - exact).abs() < 1e-5 * exact, "{area} vs {exact}");
            // A deliberately wrong tessellation (vertices on the true radius) is off by far
            // more than that tolerance: 1 − sin(θ/2)/(θ/2) ≈ θ²/24 ≈ 1e-4 for 128 strips.
            let theta = phi / (f64::from(SEGMENTS_PER_TURN) * phi / TAU).ceil();
            assert!(1.0 - (theta / 2.0).sin() / (theta / 2.0) > 1e-5);
        }
    }
}
