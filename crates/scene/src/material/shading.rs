//! The local geometry a BSDF is built on, the transport mode, and the side tests shared by
//! every model oriented by a shading normal.

use math::{COSINE_EPSILON, Frame, Vec2, Vec3};
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
    /// Unit surface tangent along which an anisotropic roughness's `alpha_u` lies: ∂p/∂u made
    /// orthogonal to the shading normal (Mitsuba's shading frame, see [`crate::tangent`]).
    /// [`Vec3::ZERO`] when the material is isotropic (or ∂p/∂u is degenerate): the BSDF then
    /// uses the frame of [`math::Frame::from_z`] about the shading normal.
    pub tangent: Vec3,
    /// The value of the mesh attribute the material reads ([`crate::Texture::MeshAttribute`])
    /// at the point; black when the material reads none.
    pub attribute: Rgb,
}

impl ShadingPoint {
    /// A point whose shading normal is its geometric normal, at uv (0, 0), without a tangent
    /// or a mesh attribute.
    pub fn flat(normal: Vec3) -> Self {
        Self {
            geometric_normal: normal,
            shading_normal: normal,
            uv: Vec2::ZERO,
            tangent: Vec3::ZERO,
            attribute: Rgb::BLACK,
        }
    }

    /// The shading frame: `z` the unit shading normal `n`, `x` the tangent made orthogonal to
    /// `n` (Gram–Schmidt), `y = n × x`; [`Frame::from_z`] when the tangent is zero or parallel
    /// to `n`.
    #[inline]
    pub fn frame(n: Vec3, tangent: Vec3) -> Frame {
        if tangent == Vec3::ZERO {
            return Frame::from_z(n);
        }
        let s = (tangent - n * n.dot(tangent)).normalize_or_zero();
        if s == Vec3::ZERO || !s.is_finite() {
            return Frame::from_z(n);
        }
        Frame { x: s, y: n.cross(s), z: n }
    }
}

/// The unit shading normal of `point` on the side of its geometric normal; a degenerate one
/// (nearly perpendicular to the geometric normal, NaN or infinite) is replaced by the geometric
/// normal. Every BSDF built on a shading point orients its lobes by this normal.
#[inline]
pub(super) fn oriented_shading_normal(point: &ShadingPoint) -> Vec3 {
    let geometric = point.geometric_normal;
    let shading = point.shading_normal;
    let cos_normals = shading.dot(geometric);
    if cos_normals.abs() < 1e-4 || cos_normals.is_nan() || !shading.is_finite() {
        geometric
    } else if cos_normals < 0.0 {
        -shading
    } else {
        shading
    }
}

/// The frame a BSDF built on a shading point works in, with its fixed direction: what the
/// leaf-model mixture and the plain Lambertian share.
#[derive(Clone, Copy, Debug)]
pub(super) struct FixedFrame {
    /// Shading frame (z = shading normal, on the side of the geometric normal).
    pub frame: Frame,
    /// Unit geometric normal (world).
    pub geometric: Vec3,
    /// Unit fixed direction (world).
    pub fixed: Vec3,
    /// Fixed direction in the shading frame.
    pub local_fixed: Vec3,
    /// Signed cosine of the fixed direction with the geometric normal.
    pub cos_fixed_geometric: f32,
    pub mode: TransportMode,
    /// Shading normal equal to the geometric normal: no shading-normal correction.
    pub flat: bool,
}

impl FixedFrame {
    /// The frame about the unit `shading` normal (already oriented, e.g. by
    /// [`oriented_shading_normal`]) with `point`'s tangent, for the unit `fixed` direction.
    #[inline]
    pub fn new(point: &ShadingPoint, shading: Vec3, fixed: Vec3, mode: TransportMode) -> Self {
        let geometric = point.geometric_normal;
        let frame = ShadingPoint::frame(shading, point.tangent);
        Self {
            frame,
            geometric,
            fixed,
            local_fixed: frame.to_local(fixed),
            cos_fixed_geometric: fixed.dot(geometric),
            mode,
            flat: shading == geometric,
        }
    }

    /// The factor that turns the shading-frame BSDF into the value in the geometric-normal
    /// formulation, for a generated direction with shading cosine `cos_shading` and geometric
    /// cosine `cos_geometric`.
    #[inline]
    pub fn shading_factor(&self, cos_shading: f32, cos_geometric: f32) -> f32 {
        if self.flat {
            return 1.0;
        }
        match self.mode {
            TransportMode::Radiance => (cos_shading / cos_geometric).abs(),
            TransportMode::Importance => (self.local_fixed.z / self.cos_fixed_geometric).abs(),
        }
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

/// The side test of a direction at a BSDF built with `relaxed` (a material that is one leaf
/// model following its shading normal alone, `LeafModel::follows_shading_normal`: a smooth
/// dielectric or a thin dielectric sheet, without a normal or bump map) or not: [`consistent`], or with `relaxed`
/// only that neither cosine is grazing (below [`COSINE_EPSILON`]). Such a material is then
/// oriented by its shading normal alone, as Mitsuba 3's `dielectric` and `thindielectric` are:
/// a direction that the shading frame refracts, reflects or lets through but that lies on the
/// other side of the geometric tangent plane is kept, and the medium it enters is still read
/// from the geometric normal. On a coarse mesh with interpolated normals, rejecting such
/// directions lost energy, most of it in chains of internal reflections: in Mitsuba's
/// `test_homo_dielectric_envmap` (a glass sphere on a glass base of 5632 triangles whose normals
/// deviate up to 15° from their faces) every algorithm came out 0.5 % dark (pt at 4096 samples
/// per pixel: ×0.9952 ± 0.09 %, the base up to 6 %), and the same base as a thin sheet in
/// `test_homo_area_light` without its media 0.6 % dark against Mitsuba; kept, both match
/// (`docs/conformance.md`). Delta lobes are never connected to, so every technique of the VCM
/// engine still sees the same vertices.
#[inline]
pub(super) fn sides_allowed(relaxed: bool, cos_geometric: f32, cos_shading: f32) -> bool {
    if relaxed {
        cos_geometric.abs() >= COSINE_EPSILON && cos_shading.abs() >= COSINE_EPSILON
    } else {
        consistent(cos_geometric, cos_shading)
    }
}
