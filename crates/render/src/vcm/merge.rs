//! Vertex merging: the density estimate at a camera vertex from all light vertices within the
//! merging radius, each MIS-weighted (eqs. 38, 39).

use math::Vec3;
use scene::Bsdf;
use spectrum::{Rgb, SpectralMode};

use super::connect::CameraEnd;
use super::light_vertex::MergeVertex;
use super::mis::{self, MisConstants};
use super::subpath::SubPath;
use super::technique_images::Record;
use crate::fluorescent::view;
use crate::hash_grid::HashGrid;
use math::Rng;

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
pub struct MergeSource<'a, S: SpectralMode = Rgb> {
    /// Vertices in the grid's slot order.
    pub vertices: &'a [MergeVertex<S>],
    /// The range-search structure over them.
    pub grid: &'a HashGrid,
    /// The vertices' dVC/dVM were computed for other constants (another radius or iteration):
    /// rebuild them from cVC/cVM (eqs. 62, 63).
    pub rebase: bool,
    /// Merge only with the light vertices of this wavelength group (`None`: with all).
    pub group: Option<MergeGroup>,
}

/// The light vertices of one wavelength group (spectral mode, `super::wavelengths`): those
/// the grid was built with at indices `first..end`, and the factor that turns the kernel
/// normalisation 1/(π r² N_VM) of the MIS constants into 1/(π r² n_g) for the group's exact
/// number n_g of light sub-paths (N_VM is the average N_L/K).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MergeGroup {
    /// First grid index of the group's vertices.
    pub first: u32,
    /// One past the last.
    pub end: u32,
    /// N_VM / n_g (dimensionless).
    pub normalization_scale: f32,
}

/// The merged contribution at camera vertex `position` within `radius` (throughput and kernel
/// normalisation included). When `out` wants per-(s, t) values ([`Record::PER_TECHNIQUE`]),
/// each merged light vertex's part is also staged there (s = its light sub-path vertices, the
/// merged one included; t = the camera sub-path's vertices); the caller records the sum.
#[allow(clippy::too_many_arguments)]
pub fn merge<S: SpectralMode, R: Record>(
    camera: &SubPath<S>,
    end: &CameraEnd,
    source: &MergeSource<S>,
    radius: f32,
    max_length: u32,
    weighting: MergeWeighting,
    k: &MisConstants,
    wavelengths: &S::Wavelengths,
    rng: &mut Rng,
    out: &mut R,
) -> S {
    let (bsdf, position): (&Bsdf, Vec3) = (end.bsdf, end.position);
    // One label for the camera vertex, shared by all its merges.
    let label = end.fluorescent.map(|f| (f, f.sample_label::<S>(rng.uniform())));
    let continuation = bsdf.continuation_probability();
    let mut sum = S::default();
    let normalization = match source.group {
        None => k.vm_normalization,
        Some(group) => k.vm_normalization * group.normalization_scale,
    };
    let visit = |slot: usize| {
        let light = &source.vertices[slot];
        // A merged path is one segment shorter than a connected one.
        if u32::from(light.path_length) + camera.path_length > max_length {
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
        let weight = if camera.terminated && light.terminated { weight * S::DOUBLE_TERMINATION } else { weight };
        let scattered = match label {
            None => S::from_reflectance(wavelengths, eval.value) * light.throughput,
            Some((f, label)) => f.apply_slots(wavelengths, label, eval.value, light.throughput),
        };
        let part = scattered * weight;
        sum += part;
        if R::PER_TECHNIQUE {
            let t = camera.path_length + 1;
            let value = camera.throughput * view(&camera.slots, part) * normalization;
            out.stage_merge(u32::from(light.path_length) + 1, t, value.to_rgb(wavelengths));
        }
    };
    match source.group {
        None => source.grid.for_each_slot_within(position, radius, visit),
        Some(g) => source.grid.for_each_slot_within_indices(position, radius, g.first..g.end, visit),
    }
    camera.throughput * view(&camera.slots, sum) * normalization
}
