//! Compact storage of light sub-path vertices: a flat `Vec` of vertices plus, per light
//! sub-path, the index one past its last vertex. A vertex keeps what connections and merges
//! need — position, throughput, MIS quantities — and the data to rebuild its BSDF (material,
//! normal, fixed direction), never a full BSDF.

use math::{Vec2, Vec3};
use scene::{Bsdf, Scene, ShadingPoint, TransportMode};
use spectrum::{Rgb, SpectralMode};

use super::mis::SubPathMis;

/// A stored light sub-path vertex (100 bytes in RGB mode, 104 in spectral mode).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightVertex<S: SpectralMode = Rgb> {
    /// Position on the surface.
    pub position: Vec3,
    /// Throughput of the light sub-path up to this vertex (emitted energy / pdfs, BSDFs and
    /// cosines of the earlier vertices).
    pub throughput: S,
    /// MIS quantities at this vertex.
    pub mis: SubPathMis,
    /// Segments from the light to this vertex (`u16` keeps the vertex at 100 bytes and the
    /// merging data at 64 with the termination flag; light sub-paths end long before).
    pub path_length: u16,
    /// Material index, to rebuild the BSDF.
    pub material: u32,
    /// Geometric normal.
    pub normal: Vec3,
    /// Shading normal.
    pub shading_normal: Vec3,
    /// Texture coordinates.
    pub uv: Vec2,
    /// Unit direction towards the previous vertex (the BSDF's fixed direction).
    pub fixed: Vec3,
    /// Russian-roulette continuation probability of the vertex's BSDF.
    pub continuation: f32,
    /// The light sub-path kept only its hero wavelength ([`super::subpath::SubPath::terminated`]).
    pub terminated: bool,
}

impl<S: SpectralMode> LightVertex<S> {
    /// Rebuilds the vertex's BSDF (importance transport) at the hero wavelength `hero`.
    #[inline]
    pub fn bsdf(&self, scene: &Scene, hero: Option<f32>) -> Option<Bsdf> {
        let point = ShadingPoint { geometric_normal: self.normal, shading_normal: self.shading_normal, uv: self.uv };
        Bsdf::new_at(&scene.materials[self.material as usize], &point, self.fixed, TransportMode::Importance, hero)
    }

    /// The vertex's fluorescence, if its material is fluorescent.
    #[inline]
    pub fn fluorescent<'s>(&self, scene: &'s Scene) -> Option<crate::fluorescent::FluorescentVertex<'s>> {
        crate::fluorescent::FluorescentVertex::at(&scene.materials[self.material as usize], self.uv)
    }
}

/// All light vertices of one iteration, grouped by light sub-path.
#[derive(Clone, Debug)]
pub struct LightVertexStore<S: SpectralMode = Rgb> {
    /// The vertices, light sub-path after light sub-path, each in path order.
    pub vertices: Vec<LightVertex<S>>,
    /// For light sub-path `p`, the index one past its last vertex.
    pub path_ends: Vec<u32>,
}

impl<S: SpectralMode> Default for LightVertexStore<S> {
    fn default() -> Self {
        Self { vertices: Vec::new(), path_ends: Vec::new() }
    }
}

impl<S: SpectralMode> LightVertexStore<S> {
    /// The vertices of light sub-path `path`.
    #[inline]
    pub fn path(&self, path: usize) -> &[LightVertex<S>] {
        let start = if path == 0 { 0 } else { self.path_ends[path - 1] as usize };
        &self.vertices[start..self.path_ends[path] as usize]
    }

    /// Empties the store, keeping its allocations.
    pub fn clear(&mut self) {
        self.vertices.clear();
        self.path_ends.clear();
    }

    /// Bytes per stored vertex.
    pub const BYTES_PER_VERTEX: usize = std::mem::size_of::<LightVertex<S>>();
}

/// What merging needs of a light vertex (64 bytes), stored in the range-search grid's slot
/// order so that a query reads neighbouring vertices from contiguous memory. In the
/// memory-efficient mode this is all that is kept of a light vertex.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MergeVertex<S: SpectralMode = Rgb> {
    /// Position on the surface.
    pub position: Vec3,
    /// Unit direction towards the previous vertex.
    pub fixed: Vec3,
    /// Throughput of the light sub-path up to this vertex.
    pub throughput: S,
    /// MIS quantities at this vertex.
    pub mis: SubPathMis,
    /// Segments from the light to this vertex (`u16` keeps the vertex at 100 bytes and the
    /// merging data at 64 with the termination flag; light sub-paths end long before).
    pub path_length: u16,
    /// Russian-roulette continuation probability of the vertex's BSDF.
    pub continuation: f32,
    /// The light sub-path kept only its hero wavelength.
    pub terminated: bool,
}

impl<S: SpectralMode> From<&LightVertex<S>> for MergeVertex<S> {
    fn from(v: &LightVertex<S>) -> Self {
        Self {
            position: v.position,
            fixed: v.fixed,
            throughput: v.throughput,
            mis: v.mis,
            path_length: v.path_length,
            continuation: v.continuation,
            terminated: v.terminated,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use spectrum::Hero4;

    #[test]
    fn stored_vertices_keep_their_sizes() {
        // The memory estimates and the documentation quote these sizes.
        assert_eq!(std::mem::size_of::<LightVertex<Rgb>>(), 100);
        assert_eq!(std::mem::size_of::<MergeVertex<Rgb>>(), 64);
        assert_eq!(std::mem::size_of::<LightVertex<Hero4>>(), 104);
        assert_eq!(std::mem::size_of::<MergeVertex<Hero4>>(), 68);
    }
}
