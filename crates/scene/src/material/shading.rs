//! The local geometry a BSDF is built on, the transport mode, and the side tests shared by
//! every model oriented by a shading normal.

use math::{COSINE_EPSILON, Vec2, Vec3};
use spectrum::Rgb;

/// The local geometry at a surface point that a BSDF needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadingPoint {
    /// Unit geometric normal (defines the sides of the surface and all cosines the
    /// integrators use).
    pub geometric_normal: Vec3,
    /// Unit shading normal (interpolated mesh normal; equal to the geometric normal
    /// otherwise). BSDF lobes are oriented by it.
    pub shading_normal: Vec3,
    /// Texture coordinates.
    pub uv: Vec2,
    /// The value of the mesh attribute the material reads ([`crate::Texture::MeshAttribute`])
    /// at the point; black when the material reads none.
    pub attribute: Rgb,
}

impl ShadingPoint {
    /// A point whose shading normal is its geometric normal, at uv (0, 0), without a mesh
    /// attribute.
    pub fn flat(normal: Vec3) -> Self {
        Self { geometric_normal: normal, shading_normal: normal, uv: Vec2::ZERO, attribute: Rgb::BLACK }
    }
}

/// Which quantity a sub-path carries. The adjoint BSDF differs for refraction.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TransportMode {
    /// Camera sub-paths: radiance flows towards the fixed direction.
    Radiance,
    /// Light sub-paths: importance flows towards the fixed direction.
    Importance,
}

/// Whether a direction with geometric cosine `cos_geometric` and shading cosine
/// `cos_shading` lies on the same side of both tangent planes, neither grazing (below
/// [`COSINE_EPSILON`]).
#[inline]
pub(super) fn consistent(cos_geometric: f32, cos_shading: f32) -> bool {
    cos_geometric * cos_shading > 0.0 && cos_geometric.abs() >= COSINE_EPSILON && cos_shading.abs() >= COSINE_EPSILON
}
