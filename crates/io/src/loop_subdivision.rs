//! Loop subdivision surfaces (pbrt's `loopsubdiv` shape), refined into a triangle mesh at load.
//!
//! Each level splits every triangle into four (Loop 1987, as in pbrt-v4's `LoopSubdivide`):
//!
//! - a new ("odd") vertex on every edge `ab`: `3/8 (a + b) + 1/8 (c + d)` with `c`, `d` the
//!   vertices opposite the edge in its two triangles, or `(a + b) / 2` on a boundary edge;
//! - every old ("even") vertex `v` of valence `n` moves to `(1 − n β) v + β Σ neighbours`, with
//!   Warren's `β = 3/16` for `n = 3` and `3/(8n)` otherwise, and a boundary vertex to
//!   `3/4 v + 1/8 (b₀ + b₁)` (its two boundary neighbours), so boundaries are cubic B-splines.
//!
//! After the last level the vertices are moved to their limit positions: interior
//! `(1 − n γ) v + γ Σ neighbours` with `γ = 1 / (n + 3 / (8 β))`, boundary
//! `3/5 v + 1/5 (b₀ + b₁)`. Interior shading normals are the limit surface's: the cross product
//! of the two tangents `Σ cos(2πj/n) p_j` and `Σ sin(2πj/n) p_j` over the neighbours `p_j` in
//! counter-clockwise order; boundary vertices take the area-weighted normal of their triangles
//! (pbrt uses special tangent weights there; the difference is a shading-normal difference
//! along the boundary only).
//!
//! The input must be an edge-manifold mesh with consistently oriented triangles (every edge in
//! at most two triangles, once in each direction): anything else is an error.

use std::collections::HashMap;
use std::f64::consts::TAU;

use glam::DVec3;
use math::Vec3;
use scene::desc::MeshData;

/// Most subdivision levels accepted (each multiplies the triangle count by four).
pub(crate) const MAX_LEVELS: u32 = 10;
/// Most triangles the refined mesh may have.
const MAX_TRIANGLES: usize = 1 << 28;

/// An edge's data during one level: the index of its new vertex and the vertices opposite it.
struct Edge {
    new_vertex: u32,
    opposite: [u32; 2],
    faces: u8,
}

/// The mesh of `positions` and counter-clockwise `triangles` subdivided `levels` times and
/// moved to the limit surface, with shading normals (see the module documentation). Errors name
/// what is wrong with the input.
pub(crate) fn subdivide(positions: &[Vec3], triangles: &[[u32; 3]], levels: u32) -> Result<MeshData, String> {
    if levels > MAX_LEVELS {
        return Err(format!("{levels} subdivision levels: at most {MAX_LEVELS} are supported"));
    }
    if triangles.len().saturating_mul(1 << (2 * levels)) > MAX_TRIANGLES {
        return Err(format!(
            "{} triangles subdivided {levels} times would make more than {MAX_TRIANGLES} triangles",
            triangles.len()
        ));
    }
    let count = positions.len();
    if let Some(t) = triangles.iter().find(|t| t.iter().any(|&i| i as usize >= count)) {
        return Err(format!("triangle {t:?} has an index out of range (there are {count} vertices)"));
    }
    if let Some(t) = triangles.iter().find(|t| t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) {
        return Err(format!("triangle {t:?} repeats a vertex"));
    }
    let mut points: Vec<DVec3> = positions.iter().map(|p| p.as_dvec3()).collect();
    let mut faces = triangles.to_vec();
    for _ in 0..levels {
        (points, faces) = refine(&points, &faces)?;
    }
    let topology = Topology::new(points.len(), &faces)?;
    let limit: Vec<DVec3> = (0..points.len()).map(|v| topology.limit_position(v, &points)).collect();
    let normals = topology.normals(&limit, &faces);
    Ok(MeshData {
        positions: limit.iter().map(|p| p.as_vec3()).collect(),
        normals: normals.iter().map(|n| n.as_vec3()).collect(),
        triangles: faces,
        ..MeshData::default()
    })
}

/// One level of subdivision.
fn refine(points: &[DVec3], faces: &[[u32; 3]]) -> Result<(Vec<DVec3>, Vec<[u32; 3]>), String> {
    let topology = Topology::new(points.len(), faces)?;
    let mut edges: HashMap<(u32, u32), Edge> = HashMap::with_capacity(faces.len() * 3 / 2 + 1);
    let mut next = points.len() as u32;
    for f in faces {
        for k in 0..3 {
            let (a, b, c) = (f[k], f[(k + 1) % 3], f[(k + 2) % 3]);
            let edge = edges.entry((a.min(b), a.max(b))).or_insert_with(|| {
                next += 1;
                Edge { new_vertex: next - 1, opposite: [c, c], faces: 0 }
            });
            // Topology::new has checked that no edge is in more than two triangles.
            edge.opposite[usize::from(edge.faces.min(1))] = c;
            edge.faces += 1;
        }
    }
    let mut refined = Vec::with_capacity(next as usize);
    refined.extend((0..points.len()).map(|v| topology.even_position(v, points)));
    refined.resize(next as usize, DVec3::ZERO);
    for (&(a, b), edge) in &edges {
        let (a, b) = (points[a as usize], points[b as usize]);
        refined[edge.new_vertex as usize] = if edge.faces == 2 {
            let [c, d] = edge.opposite.map(|i| points[i as usize]);
            0.375 * (a + b) + 0.125 * (c + d)
        } else {
            0.5 * (a + b)
        };
    }
    let mut refined_faces = Vec::with_capacity(faces.len() * 4);
    let middle = |a: u32, b: u32| edges[&(a.min(b), a.max(b))].new_vertex;
    for &[a, b, c] in faces {
        let (ab, bc, ca) = (middle(a, b), middle(b, c), middle(c, a));
        refined_faces.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
    }
    Ok((refined, refined_faces))
}

/// Warren's β for valence `n`.
fn beta(n: usize) -> f64 {
    if n == 3 { 3.0 / 16.0 } else { 3.0 / (8.0 * n as f64) }
}

/// Each vertex's one-ring: its neighbours in counter-clockwise order (starting after a boundary
/// when there is one) and whether it lies on the boundary.
struct Topology {
    rings: Vec<Vec<u32>>,
    boundary: Vec<bool>,
}

impl Topology {
    fn new(vertices: usize, faces: &[[u32; 3]]) -> Result<Self, String> {
        // next[v] maps a neighbour x of v to the neighbour after it counter-clockwise: the
        // triangle (v, x, y) says y follows x around v.
        let mut next: Vec<HashMap<u32, u32>> = vec![HashMap::new(); vertices];
        for f in faces {
            for k in 0..3 {
                let (v, x, y) = (f[k], f[(k + 1) % 3], f[(k + 2) % 3]);
                if next[v as usize].insert(x, y).is_some() {
                    return Err(format!(
                        "the edge {v}-{x} is used twice in the same direction (a non-manifold edge or \
                         inconsistently oriented triangles)"
                    ));
                }
            }
        }
        let mut rings = Vec::with_capacity(vertices);
        let mut boundary = Vec::with_capacity(vertices);
        for (v, around) in next.iter().enumerate() {
            // A boundary vertex has exactly one neighbour that follows no other: start there.
            let followers: std::collections::HashSet<u32> = around.values().copied().collect();
            let starts: Vec<u32> = around.keys().copied().filter(|x| !followers.contains(x)).collect();
            let (start, open) = match starts.as_slice() {
                [] => (around.keys().copied().min(), false),
                [s] => (Some(*s), true),
                _ => return Err(format!("vertex {v} joins two separate fans of triangles (a non-manifold vertex)")),
            };
            let mut ring = Vec::with_capacity(around.len() + 1);
            if let Some(mut x) = start {
                ring.push(x);
                while let Some(&y) = around.get(&x) {
                    if y == start.unwrap_or(u32::MAX) {
                        break;
                    }
                    if ring.len() > around.len() {
                        return Err(format!("vertex {v} joins two separate fans of triangles (a non-manifold vertex)"));
                    }
                    ring.push(y);
                    x = y;
                }
            }
            let expected = around.len() + usize::from(open);
            if ring.len() != expected {
                return Err(format!("vertex {v} joins two separate fans of triangles (a non-manifold vertex)"));
            }
            rings.push(ring);
            boundary.push(open);
        }
        Ok(Self { rings, boundary })
    }

    /// Sum of the neighbours' positions and (for boundary vertices) the sum of the two boundary
    /// neighbours: the first and last of the ring.
    fn even_position(&self, v: usize, points: &[DVec3]) -> DVec3 {
        let ring = &self.rings[v];
        let p = points[v];
        if ring.is_empty() {
            p
        } else if self.boundary[v] {
            let ends = points[ring[0] as usize] + points[ring[ring.len() - 1] as usize];
            0.75 * p + 0.125 * ends
        } else {
            let n = ring.len();
            let sum: DVec3 = ring.iter().map(|&j| points[j as usize]).sum();
            (1.0 - n as f64 * beta(n)) * p + beta(n) * sum
        }
    }

    /// The limit position of vertex `v`.
    fn limit_position(&self, v: usize, points: &[DVec3]) -> DVec3 {
        let ring = &self.rings[v];
        let p = points[v];
        if ring.is_empty() {
            p
        } else if self.boundary[v] {
            let ends = points[ring[0] as usize] + points[ring[ring.len() - 1] as usize];
            0.6 * p + 0.2 * ends
        } else {
            let n = ring.len();
            let gamma = 1.0 / (n as f64 + 3.0 / (8.0 * beta(n)));
            let sum: DVec3 = ring.iter().map(|&j| points[j as usize]).sum();
            (1.0 - n as f64 * gamma) * p + gamma * sum
        }
    }

    /// Unit shading normals: limit tangents inside, area-weighted on the boundary.
    fn normals(&self, points: &[DVec3], faces: &[[u32; 3]]) -> Vec<DVec3> {
        let mut area_weighted = vec![DVec3::ZERO; points.len()];
        for &[a, b, c] in faces {
            let n = (points[b as usize] - points[a as usize]).cross(points[c as usize] - points[a as usize]);
            for v in [a, b, c] {
                area_weighted[v as usize] += n;
            }
        }
        (0..points.len())
            .map(|v| {
                let ring = &self.rings[v];
                let normal = if self.boundary[v] || ring.len() < 3 {
                    area_weighted[v]
                } else {
                    let n = ring.len() as f64;
                    let (mut s, mut t) = (DVec3::ZERO, DVec3::ZERO);
                    for (j, &x) in ring.iter().enumerate() {
                        let (sin, cos) = (TAU * j as f64 / n).sin_cos();
                        s += cos * points[x as usize];
                        t += sin * points[x as usize];
                    }
                    s.cross(t)
                };
                normal.try_normalize().or_else(|| area_weighted[v].try_normalize()).unwrap_or(DVec3::Z)
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A regular tetrahedron centred at the origin, outward-facing counter-clockwise triangles.
    fn tetrahedron() -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let p = vec![
            Vec3::new(1.0, 1.0, 1.0),
            Vec3::new(1.0, -1.0, -1.0),
            Vec3::new(-1.0, 1.0, -1.0),
            Vec3::new(-1.0, -1.0, 1.0),
        ];
        (p, vec![[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]])
    }

    #[test]
    fn one_level_of_a_tetrahedron_matches_the_rules_by_hand() {
        // Valence 3: β = 3/16, the neighbours sum to −v, so v' = (1 − 9/16) v − 3/16 v = v/4;
        // an edge point is 3/8 (a + b) + 1/8 (c + d) = 3/8 (a + b) − 1/8 (a + b) = (a + b)/4.
        let (p, t) = tetrahedron();
        let (points, faces) = refine(&p.iter().map(|v| v.as_dvec3()).collect::<Vec<_>>(), &t).unwrap();
        assert_eq!((points.len(), faces.len()), (4 + 6, 16));
        for (v, q) in p.iter().zip(&points) {
            assert!((*q - 0.25 * v.as_dvec3()).length() < 1e-12, "{q}");
        }
        for f in &faces[..] {
            for &i in f {
                assert!((i as usize) < points.len());
            }
        }
        let edge_points: Vec<DVec3> = points[4..].to_vec();
        for (a, b) in [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)] {
            let expected = 0.25 * (p[a] + p[b]).as_dvec3();
            assert!(edge_points.iter().any(|q| (*q - expected).length() < 1e-12), "edge {a}-{b}");
        }
    }

    #[test]
    fn a_closed_mesh_stays_closed_convex_and_outward_facing() {
        let (p, t) = tetrahedron();
        let mesh = subdivide(&p, &t, 3).unwrap();
        assert_eq!(mesh.triangles.len(), 4 * 64);
        // Vertices: V − E + F = 2 for a sphere.
        assert_eq!(mesh.positions.len() as i64 - mesh.triangles.len() as i64 * 3 / 2 + mesh.triangles.len() as i64, 2);
        for (q, n) in mesh.positions.iter().zip(&mesh.normals) {
            assert!((n.length() - 1.0).abs() < 1e-5);
            // Symmetric about the origin, so every normal of the convex limit points outward.
            assert!(n.dot(*q) > 0.5 * q.length(), "{q} {n}");
        }
        for &[a, b, c] in &mesh.triangles {
            let (a, b, c) = (mesh.positions[a as usize], mesh.positions[b as usize], mesh.positions[c as usize]);
            assert!((b - a).cross(c - a).dot(a + b + c) > 0.0, "a triangle faces inward");
        }
    }

    #[test]
    fn a_planar_patch_with_a_boundary_stays_planar() {
        // A 3×3 grid of squares, two triangles each, in z = 0: interior and boundary rules keep
        // every point in the plane and every normal +z.
        let mut p = Vec::new();
        for y in 0..4 {
            for x in 0..4 {
                p.push(Vec3::new(x as f32, y as f32, 0.0));
            }
        }
        let mut t = Vec::new();
        for y in 0..3u32 {
            for x in 0..3u32 {
                let i = y * 4 + x;
                t.push([i, i + 1, i + 5]);
                t.push([i, i + 5, i + 4]);
            }
        }
        let mesh = subdivide(&p, &t, 2).unwrap();
        assert_eq!(mesh.triangles.len(), 18 * 16);
        for (q, n) in mesh.positions.iter().zip(&mesh.normals) {
            assert!(q.z.abs() < 1e-6 && (n.z - 1.0).abs() < 1e-6, "{q} {n}");
            assert!(q.x >= -1e-6 && q.x <= 3.0 + 1e-6 && q.y >= -1e-6 && q.y <= 3.0 + 1e-6);
        }
        // The boundary is a cubic B-spline of the boundary polygon (no corner rule, as pbrt):
        // it is straight exactly where four consecutive control points are collinear, i.e. on
        // the middle third of each side (x ∈ [1, 2] on y = 0: 2 levels make 4 segments, 5
        // vertices), and rounds the corners.
        let on_edge: Vec<&Vec3> = mesh.positions.iter().filter(|q| q.y.abs() < 1e-6).collect();
        assert_eq!(on_edge.len(), 5, "{on_edge:?}");
        assert!(on_edge.iter().all(|q| (1.0 - 1e-6..=2.0 + 1e-6).contains(&q.x)));
    }

    #[test]
    fn bad_meshes_are_errors() {
        let (p, t) = tetrahedron();
        let mut fan = t.clone();
        fan.push([0, 1, 2]);
        assert!(subdivide(&p, &fan, 1).unwrap_err().contains("non-manifold edge"));
        assert!(subdivide(&p, &[[0, 0, 1]], 1).unwrap_err().contains("repeats a vertex"));
        assert!(subdivide(&p, &[[0, 1, 9]], 1).unwrap_err().contains("out of range"));
        assert!(subdivide(&p, &t, MAX_LEVELS + 1).unwrap_err().contains("at most"));
        // Two tetrahedra sharing only vertex 0: a non-manifold vertex.
        let mut q = p.clone();
        q.extend([Vec3::new(3.0, 1.0, 1.0), Vec3::new(1.0, 3.0, 1.0), Vec3::new(1.0, 1.0, 3.0)]);
        let mut two = t.clone();
        two.extend([[0, 4, 5], [0, 6, 4], [0, 5, 6], [4, 6, 5]]);
        assert!(subdivide(&q, &two, 1).unwrap_err().contains("non-manifold vertex"));
    }
}
