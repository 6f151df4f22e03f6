//! Marching tetrahedra on a refined lattice: the zero set of an [`SdfGrid`]'s trilinear
//! interpolant as a triangle mesh (see the parent module for the error bound).
//!
//! Every voxel with a sign change is split into `k³` sub-cubes (lattice points at index-space
//! coordinates `a / k`), every sub-cube into six tetrahedra around its main diagonal (Kuhn's
//! triangulation, which splits each square face along the same diagonal from both sides, so
//! the surface has no cracks), and every tetrahedron contributes one triangle (one or three
//! corners inside) or two (two inside). Inside means a negative value. A surface vertex lies
//! on a tetrahedron edge with one corner inside and one outside, at a root of the interpolant
//! along it: exactly linear on edges parallel to an axis, found by regula falsi (Illinois)
//! on the face and body diagonals. Lattice values and vertices are functions of the lattice
//! points alone (never of the voxel being processed), so neighbouring voxels agree to the bit.

use std::collections::HashMap;

use glam::DVec3;

use super::grid::SdfGrid;

/// How the mesh's vertex normals are made (Mitsuba's `normals` parameter).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum NormalMode {
    /// `smooth`: the blended voxel gradients of [`SdfGrid::smooth_normal`]; vertices are
    /// shared between voxels.
    Smooth,
    /// `analytic`: the gradient of the voxel a triangle lies in; vertices on voxel faces are
    /// duplicated per voxel, so shading normals jump across voxel faces as in Mitsuba.
    Analytic,
}

/// Most triangles a tessellation may make.
pub(crate) const MAX_TRIANGLES: usize = 1 << 24;

/// A tessellation in the grid's object space (the unit cube).
#[derive(Clone, Debug, Default)]
pub(crate) struct Tessellation {
    /// Vertex positions (object space).
    pub positions: Vec<DVec3>,
    /// Unit vertex normals (object space).
    pub normals: Vec<DVec3>,
    /// Triangles, counter-clockwise seen from outside (positive values).
    pub triangles: Vec<[u32; 3]>,
    /// The voxel (index) each triangle lies in.
    pub voxels: Vec<[usize; 3]>,
}

/// Kuhn's six tetrahedra of a cube (corner `c` at offset `(c & 1, c >> 1 & 1, c >> 2 & 1)`),
/// each listed with positive orientation (`det(v1 − v0, v2 − v0, v3 − v0) > 0`).
pub(crate) const TETRAHEDRA: [[usize; 4]; 6] = [
    [0, 1, 3, 7], // x, y, z (even)
    [0, 2, 6, 7], // y, z, x (even)
    [0, 4, 5, 7], // z, x, y (even)
    [0, 1, 7, 5], // x, z, y (odd: last two swapped)
    [0, 4, 7, 6], // z, y, x (odd)
    [0, 2, 7, 3], // y, x, z (odd)
];

/// The twelve even permutations of four elements.
pub(crate) const EVEN_PERMUTATIONS: [[usize; 4]; 12] = [
    [0, 1, 2, 3],
    [0, 2, 3, 1],
    [0, 3, 1, 2],
    [1, 0, 3, 2],
    [1, 2, 0, 3],
    [1, 3, 2, 0],
    [2, 0, 1, 3],
    [2, 1, 3, 0],
    [2, 3, 0, 1],
    [3, 0, 2, 1],
    [3, 1, 0, 2],
    [3, 2, 1, 0],
];

/// A lattice point (index space times `k`).
type Lattice = [u32; 3];

struct Builder<'a> {
    grid: &'a SdfGrid,
    k: u32,
    mode: NormalMode,
    /// (first lattice point, second lattice point, voxel key) → vertex index.
    vertices: HashMap<(u64, u64, u64), u32>,
    /// Per vertex: the voxel whose gradient gives its analytic normal.
    vertex_voxel: Vec<[usize; 3]>,
    out: Tessellation,
}

/// The zero set of `grid` with each voxel refined `k` times per axis (`k` of 0 counts as 1). Errors when
/// there is no surface or it would need more than [`MAX_TRIANGLES`] triangles.
pub(crate) fn tessellate(grid: &SdfGrid, k: u32, mode: NormalMode) -> Result<Tessellation, String> {
    let k = k.max(1);
    let dims = grid.dims();
    let mut b =
        Builder { grid, k, mode, vertices: HashMap::new(), vertex_voxel: Vec::new(), out: Tessellation::default() };
    let side = k as usize + 1;
    let mut values = vec![0.0f64; side * side * side];
    for vz in 0..dims[2] - 1 {
        for vy in 0..dims[1] - 1 {
            for vx in 0..dims[0] - 1 {
                let voxel = [vx, vy, vz];
                let corners = grid.corners(voxel);
                if corners.iter().all(|&v| v < 0.0) || corners.iter().all(|&v| v >= 0.0) {
                    continue; // The interpolant is a convex blend of the corners: no sign change inside.
                }
                let origin = [vx as u32 * k, vy as u32 * k, vz as u32 * k];
                for (i, value) in values.iter_mut().enumerate() {
                    let offset = [(i % side) as u32, (i / side % side) as u32, (i / (side * side)) as u32];
                    *value = b.lattice_value([origin[0] + offset[0], origin[1] + offset[1], origin[2] + offset[2]]);
                }
                for sz in 0..k as usize {
                    for sy in 0..k as usize {
                        for sx in 0..k as usize {
                            b.sub_cube(voxel, origin, [sx, sy, sz], &values, side)?;
                        }
                    }
                }
            }
        }
    }
    if b.out.triangles.is_empty() {
        return Err("the grid has no surface (no sign change between neighbouring values)".into());
    }
    b.normals();
    Ok(b.out)
}

impl Builder<'_> {
    /// The interpolant at a lattice point, from a voxel chosen by the point alone.
    fn lattice_value(&self, point: Lattice) -> f64 {
        let dims = self.grid.dims();
        let mut voxel = [0usize; 3];
        let mut local = DVec3::ZERO;
        for axis in 0..3 {
            let cell = (point[axis] / self.k).min(dims[axis] as u32 - 2);
            voxel[axis] = cell as usize;
            local[axis] = (point[axis] - cell * self.k) as f64 / self.k as f64;
        }
        self.grid.eval_in_voxel(voxel, local)
    }

    fn lattice_index(&self, point: Lattice) -> u64 {
        let dims = self.grid.dims();
        let side = |axis: usize| (dims[axis] as u64 - 1) * self.k as u64 + 1;
        point[0] as u64 + side(0) * (point[1] as u64 + side(1) * point[2] as u64)
    }

    /// Object-space position of a lattice-space point.
    fn object(&self, lattice: DVec3) -> DVec3 {
        lattice / (self.grid.resolution() * self.k as f64)
    }

    fn sub_cube(
        &mut self,
        voxel: [usize; 3],
        origin: Lattice,
        sub: [usize; 3],
        values: &[f64],
        side: usize,
    ) -> Result<(), String> {
        let corner_value: [f64; 8] = std::array::from_fn(|c| {
            let (x, y, z) = (sub[0] + (c & 1), sub[1] + (c >> 1 & 1), sub[2] + (c >> 2 & 1));
            values[x + side * (y + side * z)]
        });
        if corner_value.iter().all(|&v| v < 0.0) || corner_value.iter().all(|&v| v >= 0.0) {
            return Ok(());
        }
        let corner_point = |c: usize| -> Lattice {
            [
                origin[0] + (sub[0] + (c & 1)) as u32,
                origin[1] + (sub[1] + (c >> 1 & 1)) as u32,
                origin[2] + (sub[2] + (c >> 2 & 1)) as u32,
            ]
        };
        for tet in TETRAHEDRA {
            let inside: [bool; 4] = tet.map(|c| corner_value[c] < 0.0);
            let count = inside.iter().filter(|&&i| i).count();
            if count == 0 || count == 4 {
                continue;
            }
            // An even reordering (a, b, c, d) keeps the orientation positive; with `a` alone on
            // its side, the triangle (ab, ac, ad) faces away from `a`.
            let wanted = |p: &[usize; 4]| match count {
                1 => inside[p[0]],
                3 => !inside[p[0]],
                _ => inside[p[0]] && inside[p[1]],
            };
            let Some(order) = EVEN_PERMUTATIONS.iter().find(|p| wanted(p)) else {
                unreachable!("some even permutation puts any one or two chosen corners first")
            };
            let [a, b, c, d] = order.map(|i| tet[i]);
            let mut edge = |u: usize, v: usize| {
                self.vertex(corner_point(u), corner_value[u], corner_point(v), corner_value[v], voxel)
            };
            let mut triangles = [[0u32; 3]; 2];
            let made = match count {
                1 => {
                    triangles[0] = [edge(a, b), edge(a, c), edge(a, d)];
                    1
                }
                3 => {
                    triangles[0] = [edge(a, b), edge(a, d), edge(a, c)];
                    1
                }
                _ => {
                    let (ac, ad, bd, bc) = (edge(a, c), edge(a, d), edge(b, d), edge(b, c));
                    triangles = [[ac, ad, bd], [ac, bd, bc]];
                    2
                }
            };
            for &t in &triangles[..made] {
                if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
                    continue; // Collapsed where the surface passes through a lattice point.
                }
                if self.out.triangles.len() >= MAX_TRIANGLES {
                    return Err(format!("the surface needs more than {MAX_TRIANGLES} triangles"));
                }
                self.out.triangles.push(t);
                self.out.voxels.push(voxel);
            }
        }
        Ok(())
    }

    /// The surface vertex on the edge between lattice points `u` and `v`, whose values have
    /// different signs.
    fn vertex(&mut self, u: Lattice, fu: f64, v: Lattice, fv: f64, voxel: [usize; 3]) -> u32 {
        // Inside (negative) end first, so the root search does not depend on the caller.
        let ((inner, f_in), (outer, f_out)) = if fu < 0.0 { ((u, fu), (v, fv)) } else { ((v, fv), (u, fu)) };
        let voxel_key = match self.mode {
            NormalMode::Smooth => u64::MAX,
            NormalMode::Analytic => voxel[0] as u64 + ((voxel[1] as u64) << 21) + ((voxel[2] as u64) << 42),
        };
        let (i, o) = (self.lattice_index(inner), self.lattice_index(outer));
        // A zero at the outside end is a vertex of its own, shared by all edges that meet there.
        let key = if f_out == 0.0 { (o, o, voxel_key) } else { (i.min(o), i.max(o), voxel_key) };
        if let Some(&index) = self.vertices.get(&key) {
            return index;
        }
        let lattice = |p: Lattice| DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64);
        let (a, b) = (lattice(inner), lattice(outer));
        let s = if f_out == 0.0 { 1.0 } else { self.root(inner, outer, f_in, f_out) };
        let index = self.out.positions.len() as u32;
        self.out.positions.push(self.object(a + (b - a) * s));
        self.vertex_voxel.push(voxel);
        self.vertices.insert(key, index);
        index
    }

    /// The parameter `s ∈ [0, 1]` of a zero of the interpolant on the segment from `inner`
    /// (value `f_in < 0`) to `outer` (value `f_out > 0`).
    fn root(&self, inner: Lattice, outer: Lattice, f_in: f64, f_out: f64) -> f64 {
        let differing = (0..3).filter(|&axis| inner[axis] != outer[axis]).count();
        if differing == 1 {
            return f_in / (f_in - f_out); // The interpolant is linear along an axis.
        }
        // The segment lies in the sub-cube at the lower corner of its ends, inside one voxel.
        let dims = self.grid.dims();
        let mut voxel = [0usize; 3];
        let (mut start, mut step) = (DVec3::ZERO, DVec3::ZERO);
        for axis in 0..3 {
            let low = inner[axis].min(outer[axis]);
            let cell = (low / self.k).min(dims[axis] as u32 - 2);
            voxel[axis] = cell as usize;
            let k = self.k as f64;
            start[axis] = (inner[axis] as f64 - (cell * self.k) as f64) / k;
            step[axis] = (outer[axis] as f64 - inner[axis] as f64) / k;
        }
        let f = |s: f64| self.grid.eval_in_voxel(voxel, start + step * s);
        // Regula falsi with the Illinois modification, keeping a bracket [s0, s1].
        let (mut s0, mut f0, mut s1, mut f1) = (0.0f64, f_in, 1.0f64, f_out);
        let mut side = 0i8;
        let mut s = 0.5;
        for _ in 0..100 {
            if s1 - s0 <= 1e-13 {
                break;
            }
            s = (s0 * f1 - s1 * f0) / (f1 - f0);
            let fs = f(s);
            if fs == 0.0 {
                break;
            }
            if fs < 0.0 {
                (s0, f0) = (s, fs);
                if side == -1 {
                    f1 *= 0.5;
                }
                side = -1;
            } else {
                (s1, f1) = (s, fs);
                if side == 1 {
                    f0 *= 0.5;
                }
                side = 1;
            }
        }
        s.clamp(0.0, 1.0)
    }

    /// Vertex normals per the mode, with the area-weighted face normal where the gradient
    /// vanishes.
    fn normals(&mut self) {
        let grid = self.grid;
        let out = &mut self.out;
        out.normals = out
            .positions
            .iter()
            .zip(&self.vertex_voxel)
            .map(|(&p, voxel)| match self.mode {
                NormalMode::Smooth => grid.smooth_normal(p),
                NormalMode::Analytic => grid.voxel_gradient(p, voxel.map(|i| i as i64)),
            })
            .map(|n| n.normalize_or_zero())
            .collect();
        let unset: Vec<usize> = (0..out.normals.len()).filter(|&i| out.normals[i] == DVec3::ZERO).collect();
        if unset.is_empty() {
            return;
        }
        let mut face_sum = vec![DVec3::ZERO; out.positions.len()];
        for t in &out.triangles {
            let [a, b, c] = t.map(|i| out.positions[i as usize]);
            let n = (b - a).cross(c - a);
            for &i in t {
                face_sum[i as usize] += n;
            }
        }
        for i in unset {
            out.normals[i] = face_sum[i].normalize_or(DVec3::Z);
        }
    }
}
