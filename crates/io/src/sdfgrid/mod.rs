//! Mitsuba 3's `sdfgrid` shape, tessellated at load into a triangle mesh.
//!
//! **What Mitsuba renders.** A grid of `nx × ny × nz` values (a single-channel `.vol` file,
//! [`vol`]) spans the unit cube of object space: grid point `(i, j, k)` sits at
//! `(i/(nx−1), j/(ny−1), k/(nz−1))`. The surface is the zero set of the values' trilinear
//! interpolant (Mitsuba intersects it per voxel by solving the cubic along the ray, Hansson-
//! Söderlund et al. 2022); negative is inside, the gradient points out. The surface stops at the
//! cube's faces: where the interpolant is negative on a face, the shape is open there. Shading
//! normals are `smooth` (the default: blended voxel gradients, [`grid::SdfGrid::smooth_normal`])
//! or `analytic` (the gradient of the voxel hit, discontinuous across voxel faces); the
//! geometric normal is the gradient. The shape has no uv (every hit has uv `(0, 0)`), cannot be
//! an area emitter, and has no `flip_normals`. Its `to_world` applies to the unit cube.
//!
//! **Why tessellate.** The renderer's shapes are triangles, spheres and discs (`crates/scene`);
//! a mesh needs no new primitive in the BVH, works with instancing, both ray queries and every
//! light-transport algorithm at once, as the curve and subdivision shapes do. The price is a
//! geometric error that a refinement factor controls:
//!
//! **The mesh** ([`tessellate`]) is marching tetrahedra on the grid refined `k` times per voxel
//! and axis. Its vertices lie *on* Mitsuba's surface (roots of the interpolant along lattice
//! edges, up to `f32` rounding of the positions); between them, each triangle lies inside one
//! sub-cube of one voxel, where the interpolant `F` is a polynomial, and a second-order Taylor
//! expansion about any point `x = Σ bᵢ vᵢ` of a triangle with `F(vᵢ) = 0` gives
//!
//! `|F(x)| ≤ ½ M₂ Σ bᵢ |vᵢ − x|² ≤ ½ M₂ R²,`
//!
//! with `R` the radius of the sub-cube's circumscribed sphere (`√3 / (2k)` voxels on a cubic
//! grid) and `M₂` a bound on the norm of the interpolant's Hessian in that voxel (its diagonal
//! is zero; the mixed derivatives are blends of the voxel faces' twists
//! `f₁₁ − f₁₀ − f₀₁ + f₀₀`). The distance to the surface is `|F(x)| / |∇F|` to first order:
//! `O(1/k²)` of the voxel size, `≈ 3κ/(8k²)` voxels for a true distance field of curvature `κ`
//! (per voxel). Vertex normals are the chosen normal at the vertices, interpolated across each
//! triangle: also `O(1/k²)` away from Mitsuba's per-point normal. `k` is [`refinement`]: at
//! least [`LATTICE_CELLS`] lattice cells along the grid's longest axis. Tested in `tests.rs`:
//! vertices on the interpolant's zero set, the bound at points inside triangles, closed and
//! consistently oriented meshes, a sphere's enclosed volume and area, and a plane grid against
//! Mitsuba's own unit test.

mod grid;
mod tessellate;
#[cfg(test)]
mod tests;
mod vol;

use math::Vec3;
use scene::desc::MeshData;

pub(crate) use grid::SdfGrid;
pub(crate) use tessellate::{NormalMode, tessellate};
pub(crate) use vol::read_vol;
#[cfg(test)]
pub(crate) use vol::{encode_vol, parse_vol};

/// Lattice cells along the grid's longest axis the refinement aims for.
pub(crate) const LATTICE_CELLS: usize = 128;
/// Largest refinement per voxel.
pub(crate) const MAX_REFINEMENT: u32 = 128;

/// The refinement `k` of a grid: the smallest with `k · (n − 1) ≥` [`LATTICE_CELLS`] along the
/// longest axis, at least 1 and at most [`MAX_REFINEMENT`].
pub(crate) fn refinement(grid: &SdfGrid) -> u32 {
    let voxels = grid.dims().iter().max().copied().unwrap_or(2).saturating_sub(1).max(1);
    (LATTICE_CELLS.div_ceil(voxels) as u32).clamp(1, MAX_REFINEMENT)
}

/// The surface of `grid` as an object-space mesh (the unit cube; `to_world` is the caller's)
/// with vertex normals per `mode` and no uvs. Errors when the grid has no surface or too many
/// triangles.
pub(crate) fn sdfgrid_mesh(grid: &SdfGrid, mode: NormalMode) -> Result<MeshData, String> {
    let t = tessellate(grid, refinement(grid), mode)?;
    Ok(MeshData {
        positions: t.positions.iter().map(|p| Vec3::new(p.x as f32, p.y as f32, p.z as f32)).collect(),
        normals: t.normals.iter().map(|n| Vec3::new(n.x as f32, n.y as f32, n.z as f32)).collect(),
        triangles: t.triangles,
        ..MeshData::default()
    })
}
