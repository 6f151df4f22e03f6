//! Vertex merging: the density estimate at a camera vertex from all light vertices within the
//! merging radius, each MIS-weighted (eqs. 38, 39).

use math::Vec3;
use scene::Bsdf;
use spectrum::Rgb;

use super::light_vertex::LightVertex;
use super::mis::{self, MisConstants};
use super::subpath::SubPath;
use crate::hash_grid::HashGrid;

/// How merges are weighted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MergeWeighting {
    /// MIS over all enabled techniques (BPM, VCM).
    Mis,
    /// Weight 1: progressive photon mapping, where merging is the only technique.
    None,
}

/// The merged contribution at camera vertex `position` (throughput and kernel normalisation
/// included). `vertices` are the ones `grid` was built over; `light_mis` maps a stored vertex's
/// MIS quantities to this camera path's constants.
#[allow(clippy::too_many_arguments)]
pub fn merge(
    camera: &SubPath,
    bsdf: &Bsdf,
    position: Vec3,
    vertices: &[LightVertex],
    grid: &HashGrid,
    max_length: u32,
    weighting: MergeWeighting,
    k: &MisConstants,
) -> Rgb {
    let continuation = bsdf.continuation_probability();
    let mut sum = Rgb::BLACK;
    grid.for_each_in_radius(position, |index| {
        let light = &vertices[index];
        // A merged path is one segment shorter than a connected one.
        if light.path_length + camera.path_length > max_length {
            return;
        }
        let Some(eval) = bsdf.evaluate(light.fixed) else { return };
        let weight = match weighting {
            MergeWeighting::None => 1.0,
            MergeWeighting::Mis => {
                // The reverse density belongs to the camera BSDF, but the light sub-path's
                // Russian roulette would have governed it.
                let forward = eval.pdf.forward.0 * continuation;
                let reverse = eval.pdf.reverse.0 * light.continuation;
                mis::merge_weight(&light.mis, &camera.mis, forward, reverse, k)
            }
        };
        sum += eval.value * light.throughput * weight;
    });
    camera.throughput * sum * k.vm_normalization
}
