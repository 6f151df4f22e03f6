//! Vertex merging: the density estimate at a camera vertex from all light vertices within the
//! merging radius, each MIS-weighted (eqs. 38, 39).

use math::Vec3;
use scene::Bsdf;
use spectrum::Rgb;

use super::light_vertex::MergeVertex;
use super::mis::{self, MisConstants};
use super::subpath::SubPath;
use super::technique_images::Record;
use crate::hash_grid::HashGrid;

/// How merges are weighted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MergeWeighting {
    /// MIS over all enabled techniques (BPM, VCM).
    Mis,
    /// Weight 1: progressive photon mapping, where merging is the only technique.
    None,
}

/// The light vertices a camera vertex merges with.
#[derive(Clone, Copy)]
pub struct MergeSource<'a> {
    /// Vertices in the grid's slot order.
    pub vertices: &'a [MergeVertex],
    /// The range-search structure over them.
    pub grid: &'a HashGrid,
    /// The vertices' dVC/dVM were computed for other constants (another radius or iteration):
    /// rebuild them from cVC/cVM (eqs. 62, 63).
    pub rebase: bool,
}

/// The merged contribution at camera vertex `position` within `radius` (throughput and kernel
/// normalisation included). When `out` wants per-(s, t) values ([`Record::PER_TECHNIQUE`]),
/// each merged light vertex's part is also staged there (s = its light sub-path vertices, the
/// merged one included; t = the camera sub-path's vertices); the caller records the sum.
#[allow(clippy::too_many_arguments)]
pub fn merge<R: Record>(
    camera: &SubPath,
    bsdf: &Bsdf,
    position: Vec3,
    source: &MergeSource,
    radius: f32,
    max_length: u32,
    weighting: MergeWeighting,
    k: &MisConstants,
    out: &mut R,
) -> Rgb {
    let continuation = bsdf.continuation_probability();
    let mut sum = Rgb::BLACK;
    source.grid.for_each_slot_within(position, radius, |slot| {
        let light = &source.vertices[slot];
        // A merged path is one segment shorter than a connected one.
        if light.path_length + camera.path_length > max_length {
            return;
        }
        let Some(eval) = bsdf.evaluate(light.fixed) else { return };
        let weight = match weighting {
            MergeWeighting::None => 1.0,
            MergeWeighting::Mis => {
                let light_mis = if source.rebase { light.mis.for_constants(k) } else { light.mis };
                // The reverse density belongs to the camera BSDF, but the light sub-path's
                // Russian roulette would have governed it.
                let forward = eval.pdf.forward.0 * continuation;
                let reverse = eval.pdf.reverse.0 * light.continuation;
                mis::merge_weight(&light_mis, &camera.mis, forward, reverse, k)
            }
        };
        let part = eval.value * light.throughput * weight;
        sum += part;
        if R::PER_TECHNIQUE {
            let t = camera.path_length + 1;
            out.stage_merge(light.path_length + 1, t, camera.throughput * part * k.vm_normalization);
        }
    });
    camera.throughput * sum * k.vm_normalization
}
