//! Vertex merging: the density estimate at a camera vertex from all light vertices within the
//! merging radius, each MIS-weighted (eqs. 38, 39).

use math::Vec3;
use spectrum::{Rgb, SpectralMode};

use super::connect::CameraEnd;
use super::light_vertex::{LightVertex, MergeRecord};
use super::medium::Scatterer;
use super::mis::{self, MisConstants};
use super::subpath::{Scattered, SubPath};
use super::technique_images::Record;
use crate::fluorescent::view;
use crate::hash_grid::{GridQuery, HashGrid};
use math::Rng;

/// How merges are weighted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MergeWeighting {
    /// MIS over all enabled techniques (BPM, VCM).
    Mis,
    /// Weight 1: progressive photon mapping, where merging is the only technique.
    None,
}

/// Stored light vertices in the grid's slot order: full records (two-stage mode) or
/// merging-only ones (memory-efficient mode).
#[derive(Clone, Copy)]
pub enum MergeVertices<'a, S: SpectralMode = Rgb> {
    /// Full records, also read by connections.
    Full(&'a [LightVertex<S>]),
    /// Merging-only records.
    Compact(&'a [MergeRecord<S>]),
}

/// The light vertices a camera vertex merges with.
#[derive(Clone, Copy)]
pub struct MergeSource<'a, S: SpectralMode = Rgb> {
    /// Vertices in the grid's slot order.
    pub vertices: MergeVertices<'a, S>,
    /// The range-search structure over them.
    pub grid: &'a HashGrid,
    /// Which of them, and at which wavelengths.
    pub scope: MergeScope<'a, S>,
}

impl<S: SpectralMode> MergeSource<'_, S> {
    /// Plans the merge query at `position` ([`HashGrid::plan`]) and issues its first prefetch
    /// hint (the grid's bucket starts); pass the plan to [`MergeSource::prefetch_records`]
    /// later, and to [`merge`] in [`CameraEnd::grid_query`].
    #[inline]
    pub fn plan_and_prefetch(&self, position: Vec3) -> GridQuery {
        let plan = self.grid.plan(position);
        self.grid.prefetch_buckets(&plan);
        plan
    }

    /// The second prefetch hint of a planned merge query: the first records of its buckets.
    #[inline]
    pub fn prefetch_records(&self, plan: &GridQuery) {
        match self.vertices {
            MergeVertices::Full(v) => self.grid.prefetch_slots(plan, v),
            MergeVertices::Compact(v) => self.grid.prefetch_slots(plan, v),
        }
    }
}

/// Which stored light vertices a camera vertex merges with, and at which wavelengths.
#[derive(Clone, Copy)]
pub enum MergeScope<'a, S: SpectralMode = Rgb> {
    /// All, at the camera sub-path's wavelengths (RGB mode; spectral mode with one wavelength
    /// set per iteration).
    All,
    /// Those of the camera sub-path's wavelength group only (spectral mode in scenes whose
    /// camera sub-paths cannot be re-evaluated at other wavelengths: dispersion, fluorescence).
    Group(MergeGroup),
    /// All, each at the wavelengths of its own group (`groups[h]` its grid indices, `sets[h]`
    /// its wavelengths): the camera sub-path's throughput is known at every group's set
    /// ([`GroupThroughputs`], the `group_throughputs` of [`merge`]), so a camera vertex merges
    /// with all N_L light sub-paths, as in RGB mode, while every pixel still sees K wavelength
    /// sets.
    AcrossGroups(&'a [MergeGroup], &'a [S::Wavelengths]),
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

/// How many scattering steps [`GroupThroughputs`] keeps before it applies them to every group.
const PENDING_STEPS: usize = 16;

/// A camera sub-path's throughput at the wavelength set of every group
/// ([`MergeScope::AcrossGroups`]), brought up to date lazily: the scattering steps
/// ([`Scattered`]: an RGB BSDF value and a wavelength-free factor) are recorded as the sub-path
/// is traced and applied to group h only when a merge finds a light vertex of that group
/// (in scene 1 most merge queries find none). Each group's value is the product of its steps
/// taken in path order, so it is bit for bit the value of updating every group at every step.
/// Units: those of the sub-path's throughput (the camera's importance over the sampling
/// densities, dimensionless for the pinhole camera).
#[derive(Clone, Debug)]
pub struct GroupThroughputs<'a, S: SpectralMode> {
    /// The groups' wavelength sets (empty: no merging across groups).
    sets: &'a [S::Wavelengths],
    /// Group h's throughput after its first `applied[h]` pending steps.
    values: [S; super::wavelengths::MAX_CROSS_GROUPS],
    /// How many of the pending steps each group's value includes.
    applied: [u8; super::wavelengths::MAX_CROSS_GROUPS],
    /// Steps not yet applied to every group, in path order.
    pending: [Scattered; PENDING_STEPS],
    /// Number of pending steps.
    len: usize,
}

impl<'a, S: SpectralMode> GroupThroughputs<'a, S> {
    /// The throughputs at `sets` (at most [`super::wavelengths::MAX_CROSS_GROUPS`]; more are
    /// ignored) of a sub-path whose throughput is `start` at every set (its filter weight).
    pub fn new(sets: &'a [S::Wavelengths], start: S) -> Self {
        let sets = &sets[..sets.len().min(super::wavelengths::MAX_CROSS_GROUPS)];
        let idle = Scattered { value: Rgb::BLACK, scale: 0.0 };
        Self {
            sets,
            values: [start; super::wavelengths::MAX_CROSS_GROUPS],
            applied: [0; super::wavelengths::MAX_CROSS_GROUPS],
            pending: [idle; PENDING_STEPS],
            len: 0,
        }
    }

    /// Records a scattering step of the sub-path (as [`SubPath::scatter`] applied it at the
    /// sub-path's own set; no fluorescence).
    #[inline]
    pub fn push(&mut self, step: Scattered) {
        if self.len == PENDING_STEPS {
            for h in 0..self.sets.len() {
                self.catch_up(h);
            }
            self.applied = [0; super::wavelengths::MAX_CROSS_GROUPS];
            self.len = 0;
        }
        self.pending[self.len] = step;
        self.len += 1;
    }

    /// The throughput at group `h`'s wavelengths (`h` < the number of sets).
    #[inline]
    pub fn get(&mut self, h: usize) -> S {
        self.catch_up(h);
        self.values[h]
    }

    /// Applies the pending steps group `h` lacks.
    #[inline]
    fn catch_up(&mut self, h: usize) {
        let set = &self.sets[h];
        for step in &self.pending[self.applied[h] as usize..self.len] {
            // As `SubPath::scatter` updates the sub-path's own throughput.
            self.values[h] *= S::from_reflectance(set, step.value) * step.scale;
        }
        self.applied[h] = self.len as u8;
    }
}

/// The merged contribution at camera vertex `position` within `radius` (throughput and kernel
/// normalisation included), in linear sRGB. `group_throughputs` holds the camera sub-path's
/// throughput at the wavelengths of every group (required by [`MergeScope::AcrossGroups`],
/// unused by the other scopes).
/// When `out` wants per-(s, t) values ([`Record::PER_TECHNIQUE`]), each merged light vertex's
/// part is also staged there (s = its light sub-path vertices, the merged one included; t = the
/// camera sub-path's vertices); the caller records the sum.
#[allow(clippy::too_many_arguments)]
pub fn merge<S: SpectralMode, R: Record>(
    camera: &SubPath<S>,
    group_throughputs: Option<&mut GroupThroughputs<S>>,
    end: &CameraEnd,
    source: &MergeSource<S>,
    radius: f32,
    max_length: u32,
    weighting: MergeWeighting,
    k: &MisConstants,
    wavelengths: &S::Wavelengths,
    rng: &mut Rng,
    out: &mut R,
) -> Rgb {
    let args = (camera, group_throughputs, end, source, radius, max_length, weighting, k, wavelengths);
    match source.vertices {
        MergeVertices::Full(vertices) => merge_with(vertices, args, rng, out),
        MergeVertices::Compact(vertices) => merge_with(vertices, args, rng, out),
    }
}

/// The arguments of [`merge`] that [`merge_with`] passes through.
type MergeArgs<'a, 'b, 'c, S> = (
    &'a SubPath<S>,
    Option<&'a mut GroupThroughputs<'c, S>>,
    &'a CameraEnd<'b>,
    &'a MergeSource<'a, S>,
    f32,
    u32,
    MergeWeighting,
    &'a MisConstants,
    &'a <S as SpectralMode>::Wavelengths,
);

/// [`merge`] over one kind of stored record.
fn merge_with<S: SpectralMode, R: Record, V: AsRef<MergeRecord<S>>>(
    vertices: &[V],
    (camera, group_throughputs, end, source, radius, max_length, weighting, k, wavelengths): MergeArgs<S>,
    rng: &mut Rng,
    out: &mut R,
) -> Rgb {
    let (scatterer, position): (&Scatterer, Vec3) = (&end.scatterer, end.position);
    // One label for the camera vertex, shared by all its merges.
    let label = end.fluorescent.map(|f| (f, f.sample_label::<S>(rng.uniform())));
    let continuation = scatterer.continuation();
    let grid = source.grid;
    let normalization = match source.scope {
        MergeScope::Group(group) => k.vm_normalization * group.normalization_scale,
        MergeScope::All | MergeScope::AcrossGroups(..) => k.vm_normalization,
    };
    // A medium vertex merges with the 3-D kernel 1/((4/3) π r_V³ N_VM) (Křivánek et al. 2014,
    // point–point) within its own radius r_V: the area normalisation times η_A/η_V.
    let (normalization, radius) = if scatterer.is_medium() {
        (normalization / k.volume_over_area, k.volume_radius)
    } else {
        (normalization, radius)
    };
    // The MIS-weighted value of merging with `light` at wavelengths `w` (before the camera
    // sub-path's throughput and the kernel normalisation), or `None` when it does not count.
    let part = |light: &MergeRecord<S>, w: &S::Wavelengths| -> Option<S> {
        // A merged path is one segment shorter than a connected one.
        if light.path_length() + camera.path_length > max_length {
            return None;
        }
        // Surface vertices merge with surface vertices, medium vertices with medium vertices.
        if light.in_medium() != scatterer.is_medium() {
            return None;
        }
        let eval = scatterer.evaluate(light.fixed())?;
        let weight = match weighting {
            MergeWeighting::None => 1.0,
            MergeWeighting::Mis => {
                let light_mis = light.mis(k);
                // The reverse density belongs to the camera BSDF, but the light sub-path's
                // Russian roulette would have governed it.
                let forward = eval.forward * continuation;
                let reverse = eval.reverse * light.continuation();
                if scatterer.is_medium() {
                    mis::merge_weight_in_medium(&light_mis, &camera.mis, forward, reverse, k)
                } else {
                    mis::merge_weight(&light_mis, &camera.mis, forward, reverse, k)
                }
            }
        };
        let weight = if camera.terminated && light.terminated() { weight * S::DOUBLE_TERMINATION } else { weight };
        let scattered = match label {
            None => scatterer.spectral::<S>(w, eval.value) * light.throughput,
            Some((f, label)) => f.apply_slots(w, label, eval.value, light.throughput),
        };
        // The merged path has one vertex where the two sub-paths' vertices meet, but both
        // throughputs took σ_s of their free flight: divide one out (the volume photon map's
        // 1/σ_s(x), Jensen and Christensen 1998).
        let scattered = match scatterer {
            Scatterer::Medium(m, _) => {
                scattered * super::medium::sigma_s_at::<S>(m, position, w).map(|s| if s > 0.0 { 1.0 / s } else { 0.0 })
            }
            Scatterer::Surface(_) => scattered,
        };
        Some(scattered * weight)
    };
    let t = camera.path_length + 1;
    let plan = end.grid_query.unwrap_or_else(|| grid.plan(position));
    // Positions of the slots, for a grid that keeps none (the memory-efficient mode).
    let at = |slot: usize| vertices[slot].as_ref().position;
    match source.scope {
        MergeScope::All | MergeScope::Group(_) => {
            let mut sum = S::default();
            let visit = |slot: usize| {
                let light = vertices[slot].as_ref();
                let Some(part) = part(light, wavelengths) else { return };
                sum += part;
                if R::PER_TECHNIQUE {
                    let value = camera.throughput * view(&camera.slots, part) * normalization;
                    out.stage_merge(light.path_length() + 1, t, value.to_rgb(wavelengths));
                }
            };
            let range = match source.scope {
                MergeScope::Group(g) => Some(g.first..g.end),
                _ => None,
            };
            grid.for_each_slot_near((position, &plan), radius, range, at, visit);
            (camera.throughput * view(&camera.slots, sum) * normalization).to_rgb(wavelengths)
        }
        MergeScope::AcrossGroups(groups, sets) => {
            // The camera pass always passes them with this scope.
            let Some(group_throughputs) = group_throughputs else {
                debug_assert!(false, "merging across groups without the group throughputs");
                return Rgb::BLACK;
            };
            // No fluorescence here (the engine groups such scenes): the slots are the identity.
            let mut sums = [S::default(); super::wavelengths::MAX_CROSS_GROUPS];
            // Bit h: group h has a merged light vertex. A group without one adds +0 to the
            // total, which changes no sum: it is skipped, and its throughput never computed.
            let mut found = 0u32;
            let indices = grid.sorted_indices();
            grid.for_each_slot_near((position, &plan), radius, None, at, |slot| {
                let index = indices[slot];
                let h = groups.iter().position(|g| index < g.end).unwrap_or(groups.len() - 1);
                let light = vertices[slot].as_ref();
                let Some(part) = part(light, &sets[h]) else { return };
                sums[h] += part;
                found |= 1 << h;
                if R::PER_TECHNIQUE {
                    let value = group_throughputs.get(h) * part * normalization;
                    out.stage_merge(light.path_length() + 1, t, value.to_rgb(&sets[h]));
                }
            });
            let mut total = Rgb::BLACK;
            while found != 0 {
                let h = found.trailing_zeros() as usize;
                found &= found - 1;
                total += (group_throughputs.get(h) * sums[h] * normalization).to_rgb(&sets[h]);
            }
            total
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use spectrum::{Hero4, Wavelengths4};

    /// The lazily computed throughputs are bit for bit those of updating every group at every
    /// step, also for paths longer than the pending buffer (the flush).
    #[test]
    fn lazy_group_throughputs_equal_eager_ones() {
        let mut rng = Rng::for_stream(11, 0, 0);
        let sets: Vec<Wavelengths4> =
            (0..7).map(|g| Wavelengths4::sample((g as f32 + 0.3) / 7.0, 0.0, false)).collect();
        let start = Hero4::splat(0.83);
        let mut eager = vec![start; sets.len()];
        let mut lazy = GroupThroughputs::<Hero4>::new(&sets, start);
        for step in 0..3 * PENDING_STEPS + 5 {
            let value = Rgb::new(rng.uniform(), rng.uniform(), rng.uniform()) * 0.4;
            let scattered = Scattered { value, scale: 0.5 + 2.0 * rng.uniform() };
            for (v, set) in eager.iter_mut().zip(&sets) {
                *v *= Hero4::from_reflectance(set, scattered.value) * scattered.scale;
            }
            lazy.push(scattered);
            // Ask for some groups now and then, for all at the end.
            let h = (rng.next_u32() as usize) % sets.len();
            if step % 3 == 0 {
                assert_eq!(lazy.get(h).0.map(f32::to_bits), eager[h].0.map(f32::to_bits), "step {step}, group {h}");
            }
        }
        for (h, v) in eager.iter().enumerate() {
            assert_eq!(lazy.get(h).0.map(f32::to_bits), v.0.map(f32::to_bits), "group {h}");
        }
    }
}
