//! The VCM engine: one implementation of light tracing (`lt`), progressive photon mapping
//! (`ppm`), bidirectional photon mapping (`bpm`), bidirectional path tracing (`bpt`) and
//! vertex connection and merging (`vcm`), obtained by switching technique families on and off
//! (Georgiev 2012, §5.5 and §5.6).
//!
//! An iteration has two passes. The light pass traces one light sub-path per pixel, stores
//! its non-specular vertices and builds the range-search grid over them. The camera pass traces
//! one camera sub-path per pixel. A full path reaches the image in one of six ways:
//!
//! 1. **light tracing** (t = 1): a light vertex connected to the camera, splatted into the pixel
//!    it projects to ([`connect::connect_to_camera`]); with light tracing alone (`lt`), also the
//!    emitter's own point (s = 1, [`connect::connect_emitter_to_camera`]), so that `lt` shows
//!    emitters seen directly, which the other algorithms get from emitter hits;
//! 2. **emitter hit** (s = 0): a camera sub-path hits an emitter or escapes to the environment;
//! 3. **next-event estimation** (s = 1): a camera vertex connected to a point sampled on a
//!    light ([`connect::next_event`]);
//! 4. **vertex connection** (s, t > 1): a camera vertex connected to a vertex of the pixel's
//!    light sub-path ([`connect::connect_vertices`]);
//! 5. **vertex merging** (s, t ≥ 2): a camera vertex merged with every light vertex within the
//!    radius ([`merge::merge`]);
//! 6. **purely specular camera paths** hitting an emitter, the only way the merging-only
//!    algorithms see emitters through mirrors and glass (a special case of 2 with weight 1).
//!
//! All MIS algebra lives in [`mis`]. Results do not depend on the thread count: every sub-path
//! draws from its own random stream and light-tracing splats are added in path order.
//!
//! **Spectral mode.** The passes are generic over [`SpectralMode`]; [`VcmEngine`] picks
//! [`Rgb`] or [`Hero4`] once, from [`VcmSettings::spectral`]. Sub-paths that meet must carry
//! the same wavelengths ([`wavelengths`]): without merging, light sub-path `i` and camera
//! path `i` (the only pair that is connected) share the set of index `i`; with merging, the
//! sub-paths are split into wavelength groups with a set each, and a camera vertex merges only
//! with the light vertices of its group. Light tracing splats and camera paths convert
//! their estimates to linear sRGB as they are made ([`SpectralMode::to_rgb`]), so the film, the
//! technique images and the NaN counting are the same in both modes.
//!
//! On request the engine also files every contribution by family ([`Family`]) and by its
//! (s, t) technique ([`technique_images`], which states the conventions); the frame is the same
//! bit for bit with and without recording.

pub mod camera_pass;
pub mod connect;
pub mod light_pass;
pub mod light_vertex;
pub mod medium;
pub mod memory;
pub mod merge;
pub mod mis;
pub mod radius;
mod splats;
pub mod subpath;
pub mod technique_images;
pub mod wavelengths;

use math::Rng;
use rayon::prelude::*;
use scene::{FrameBuffer, Scene};
use spectrum::{Hero4, Rgb, SpectralMode};

use crate::hash_grid::HashGrid;
use camera_pass::trace_camera_path_recorded;
use connect::Splat;
use light_pass::{prefetch_light_path, trace_light_path};
use light_vertex::{LightPath, LightVertex, LightVertexStore, MergeRecord, NormalCodes};
use merge::{MergeGroup, MergeScope, MergeSource, MergeVertices};
use mis::MisConstants;
use splats::SplatSums;
use technique_images::{TechniqueFrame, TechniqueLayout, TechniqueValues};
use wavelengths::{DEFAULT_WAVELENGTH_GROUPS, WavelengthSource};

use radius::pixel_footprints;
pub use radius::{DEFAULT_VOLUME_RADIUS_FACTOR, RADIUS_REFERENCE_PIXELS, base_radius, base_volume_radius};

/// The algorithms of the VCM engine.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VcmAlgorithm {
    /// Light tracing: light sub-paths connected to the camera, no MIS.
    LightTracing,
    /// Progressive photon mapping: camera paths merge at their first non-specular vertex.
    ProgressivePhotonMapping,
    /// Bidirectional photon mapping: merging at every camera vertex, MIS over merges.
    BidirectionalPhotonMapping,
    /// Bidirectional path tracing: all connections, MIS over connections.
    BidirectionalPathTracing,
    /// Vertex connection and merging: everything, full MIS.
    VertexConnectionMerging,
}

/// Which technique families an algorithm enables.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Techniques {
    /// Light tracing only (no camera sub-paths).
    pub light_trace_only: bool,
    /// Vertex connection: NEE, connections, light tracing, emitter hits with MIS.
    pub connect: bool,
    /// Vertex merging.
    pub merge: bool,
    /// Photon mapping: merge at the first non-specular camera vertex, weight 1.
    pub ppm: bool,
}

impl Techniques {
    /// The families of `algorithm`.
    pub fn of(algorithm: VcmAlgorithm) -> Self {
        let none = Techniques { light_trace_only: false, connect: false, merge: false, ppm: false };
        match algorithm {
            VcmAlgorithm::LightTracing => Techniques { light_trace_only: true, ..none },
            VcmAlgorithm::ProgressivePhotonMapping => Techniques { merge: true, ppm: true, ..none },
            VcmAlgorithm::BidirectionalPhotonMapping => Techniques { merge: true, ..none },
            VcmAlgorithm::BidirectionalPathTracing => Techniques { connect: true, ..none },
            VcmAlgorithm::VertexConnectionMerging => Techniques { connect: true, merge: true, ..none },
        }
    }

    /// Whether the light pass stores vertices.
    pub fn store_light_vertices(&self) -> bool {
        self.connect || self.merge
    }

    /// Whether the light pass connects vertices to the camera.
    pub fn connect_to_camera(&self) -> bool {
        self.connect || self.light_trace_only
    }
}

/// The families of techniques, for per-technique images.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Family {
    /// s = 0: camera sub-path hits an emitter (or the environment).
    EmitterHit = 0,
    /// s = 1: next-event estimation.
    NextEvent = 1,
    /// t = 1: light vertex connected to the camera.
    LightTracing = 2,
    /// s, t > 1: vertex connection.
    Connection = 3,
    /// Vertex merging.
    Merging = 4,
}

impl Family {
    /// All families in index order.
    pub const ALL: [Family; 5] =
        [Family::EmitterHit, Family::NextEvent, Family::LightTracing, Family::Connection, Family::Merging];

    /// A short name for file names and reports.
    pub fn name(self) -> &'static str {
        match self {
            Family::EmitterHit => "emitter-hit",
            Family::NextEvent => "next-event",
            Family::LightTracing => "light-tracing",
            Family::Connection => "connection",
            Family::Merging => "merging",
        }
    }
}

/// Contributions of one camera sub-path, by family (`.0`), and the number of non-finite (NaN or
/// infinite) estimates each family produced and that were discarded (`.1`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FamilyValues(pub [Rgb; 5], pub [u32; 5]);

/// Discarded non-finite estimates per family ([`Family`] order).
pub type RejectedCounts = [u64; 5];

impl FamilyValues {
    /// Adds `value` to `family`; a NaN or infinite value is counted for the family instead and
    /// never reaches the image.
    #[inline]
    pub fn add(&mut self, family: Family, value: Rgb) {
        if value.is_finite() {
            self.0[family as usize] += value;
        } else {
            self.1[family as usize] += 1;
        }
    }

    /// Zeroes the values when their sum is not finite (finite values that overflow together),
    /// counting the estimate against the family with the largest value. Returns whether it did.
    fn discard_overflow(&mut self) -> bool {
        if self.total().is_finite() {
            return false;
        }
        let largest = (0..5).max_by(|a, b| self.0[*a].max_component().total_cmp(&self.0[*b].max_component()));
        self.0 = [Rgb::BLACK; 5];
        self.1[largest.unwrap_or(0)] += 1;
        true
    }

    /// Adds this estimate's discarded counts to `counts`.
    fn count_rejected(&self, counts: &mut RejectedCounts) {
        for (c, r) in counts.iter_mut().zip(self.1) {
            *c += u64::from(r);
        }
    }

    /// The sum over families.
    pub fn total(&self) -> Rgb {
        self.0.iter().fold(Rgb::BLACK, |a, b| a + *b)
    }
}

/// How the merging radius is chosen.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RadiusMode {
    /// One radius for the whole image: `radius_factor` × the scene's merging scale
    /// ([`radius::MergingScale`]) up to [`RADIUS_REFERENCE_PIXELS`] pixels, shrunk by √(reference / pixels) above, so the
    /// expected number of light vertices a merge query finds stays that of a 512² image and an
    /// iteration's cost grows linearly with the pixel count ([`base_radius`]).
    Global,
    /// One radius for the whole image at every resolution: `radius_factor` × the scene's
    /// merging scale. Merge queries find more light vertices as the pixel count grows
    /// (the cost of merging grows like pixels²), with the bias of a radius that spans more
    /// pixels.
    Fixed,
    /// Per pixel (§6.1): the radius of a disc with the area of the pixel's footprint at the
    /// first surface its centre sees (the global radius where it sees nothing). The light
    /// vertices carry the radius-free cVC, cVM, and every full path is weighted with the radius
    /// of its pixel, so the weights of all its techniques still sum to one.
    PerPixel,
}

/// Settings of the engine.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VcmSettings {
    /// Which algorithm.
    pub algorithm: VcmAlgorithm,
    /// Maximum path length in segments.
    pub max_length: u32,
    /// Initial merging radius as a fraction of the scene's merging scale
    /// ([`radius::MergingScale`]: its bounding-sphere radius, or the visible part's).
    pub radius_factor: f32,
    /// Radius reduction α: r_i = r_0 · (i+1)^((α−1)/2); the volume radius follows
    /// r_V,i = r_V,0 · (i+1)^((α−1)/3).
    pub radius_alpha: f32,
    /// Initial merging radius at medium vertices (the 3-D kernel of volumetric photon points) as
    /// a fraction of the scene's merging scale ([`radius::base_volume_radius`]); only scenes
    /// with media use it.
    pub volume_radius_factor: f32,
    /// Global (resolution-scaled), fixed or per-pixel radius.
    pub radius_mode: RadiusMode,
    /// Memory-efficient mode (after §6.2): only 44-byte merging records of the light vertices are
    /// kept; each pixel traces its light sub-path again right before its camera sub-path and
    /// connects to it. The image is the default mode's, bit for bit; the light walks cost twice.
    pub memory_efficient: bool,
    /// Spectral mode: four hero-rotated wavelengths per path ([`Hero4`]) instead of RGB.
    pub spectral: bool,
    /// Spectral mode with merging (two-stage mode): the number K of wavelength groups per
    /// iteration ([`wavelengths`]); 1 is one set for the whole iteration. Ignored otherwise.
    pub wavelength_groups: u32,
    /// The driver's film keeps the sums of squares ([`crate::RenderSettings::variance`]); only
    /// the memory estimate ([`memory`]) reads it.
    pub film_variance: bool,
    /// MIS compensation: next-event estimation samples an image environment's compensated
    /// density ([`Light::sample_direct_compensated`]), and every MIS weight of the engine uses
    /// that density as the next-event technique's pdf (camera sub-paths escaping to the map, and
    /// the start of light sub-paths from it: [`Light::sample_emission_compensated`]). Only in
    /// scenes without media (their vertices in media sample the full density); other lights are
    /// unaffected.
    ///
    /// [`Light::sample_direct_compensated`]: scene::light::Light::sample_direct_compensated
    /// [`Light::sample_emission_compensated`]: scene::light::Light::sample_emission_compensated
    pub mis_compensation: bool,
}

impl VcmSettings {
    /// Defaults: radius factor 0.003, volume radius factor [`DEFAULT_VOLUME_RADIUS_FACTOR`],
    /// α = 0.75, 10 segments, global radius, two-stage mode, [`DEFAULT_WAVELENGTH_GROUPS`]
    /// wavelength groups, MIS compensation on.
    pub fn new(algorithm: VcmAlgorithm) -> Self {
        Self {
            algorithm,
            max_length: 10,
            radius_factor: 0.003,
            radius_alpha: 0.75,
            volume_radius_factor: DEFAULT_VOLUME_RADIUS_FACTOR,
            radius_mode: RadiusMode::Global,
            memory_efficient: false,
            spectral: false,
            wavelength_groups: DEFAULT_WAVELENGTH_GROUPS,
            film_variance: true,
            mis_compensation: true,
        }
    }

    /// Whether an iteration on `scene` compensates ([`VcmSettings::mis_compensation`]): asked
    /// for, and no media (whose vertices sample the full density).
    pub fn compensates(&self, scene: &Scene) -> bool {
        self.mis_compensation && !scene.media.is_active()
    }
}

/// Per-iteration values shared by the passes.
#[derive(Clone, Copy, Debug)]
pub struct Iteration<'a> {
    /// MIS constants of the global radius.
    pub constants: MisConstants,
    /// Maximum path length in segments.
    pub max_length: u32,
    /// Global merging radius at surface vertices.
    pub radius: f32,
    /// The radius the grid is built for: the largest radius any query asks for (the surface
    /// radius, the volume radius in scenes with media, the largest per-pixel radius).
    pub grid_radius: f32,
    /// Per-pixel radii of this iteration ([`RadiusMode::PerPixel`]).
    pub pixel_radii: Option<&'a [f32]>,
    /// Which families are on.
    pub techniques: Techniques,
    /// Camera vertices merge with the light vertices of every wavelength group, each at its
    /// group's wavelengths ([`merge::MergeScope::AcrossGroups`]; spectral mode with groups).
    pub across_groups: bool,
    /// The raster offset every splatted camera sample of this iteration shares
    /// ([`crate::splat_frame::film_offset`]).
    pub film_offset: [f32; 2],
    /// MIS compensation for image environments ([`VcmSettings::mis_compensation`], off in
    /// scenes with media).
    pub mis_compensation: bool,
}

impl Iteration<'_> {
    /// The merging radius of camera paths through `pixel`.
    #[inline]
    pub fn pixel_radius(&self, pixel: usize) -> f32 {
        self.pixel_radii.map_or(self.radius, |r| r[pixel])
    }

    /// The MIS constants of full paths through `pixel`.
    #[inline]
    pub fn pixel_constants(&self, pixel: usize) -> MisConstants {
        match self.pixel_radii {
            None => self.constants,
            Some(r) => MisConstants::with_merge_paths(
                self.constants.light_path_count,
                self.constants.merge_path_count,
                r[pixel],
                self.techniques.connect,
                self.techniques.merge,
            ),
        }
    }

    /// Whether stored light vertices must be re-weighted for a camera path's constants.
    #[inline]
    pub fn rebase(&self) -> bool {
        self.pixel_radii.is_some()
    }
}

/// Statistics of the last iteration.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct IterationStats {
    /// Light vertices stored for merging or connection.
    pub light_vertices: usize,
    /// Bytes per stored light vertex: the record's size ([`light_vertex::LightVertex`], 64 in
    /// RGB mode, 68 in spectral mode; [`light_vertex::MergeRecord`], 44 or 48, in the
    /// memory-efficient mode). With merging, the two-stage mode adds a 4-byte slot map.
    pub bytes_per_vertex: usize,
    /// Light-tracing splats.
    pub splats: usize,
    /// Non-finite contributions discarded.
    pub rejected: u64,
    /// The same, per technique family ([`Family`] order).
    pub rejected_by_family: RejectedCounts,
    /// Global merging radius used (surface vertices).
    pub radius: f32,
    /// Merging radius at medium vertices (0 in scenes without media).
    pub volume_radius: f32,
    /// Wall-clock time of the phases (two-stage mode only).
    pub phases: PhaseTimes,
}

/// Wall-clock time of the phases of a two-stage iteration.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PhaseTimes {
    /// Tracing light sub-paths, their camera connections, gathering their vertices.
    pub light_pass: std::time::Duration,
    /// Building the grid and laying out the merging data.
    pub grid_build: std::time::Duration,
    /// Tracing camera sub-paths with all their connections and merges.
    pub camera_pass: std::time::Duration,
}

/// Light sub-paths are traced in chunks of this many; each chunk's vertices and splats are
/// collected separately and concatenated in order (deterministic for any thread count).
const LIGHT_CHUNK: usize = 1024;

/// Offset that separates the random streams of light sub-paths from those of camera paths.
const LIGHT_STREAM: u64 = 1 << 62;

/// The random stream of light sub-path `path` in iteration `iteration` (the counterpart of
/// [`crate::splat_frame::camera_stream`]): every light pass starts that sub-path with it.
#[inline]
pub(super) fn light_stream(seed: u64, iteration: u64, path: usize) -> Rng {
    Rng::for_stream(seed, iteration, LIGHT_STREAM | path as u64)
}

/// The engine and its buffers (kept across iterations), in RGB or spectral mode.
pub struct VcmEngine {
    kind: EngineKind,
}

enum EngineKind {
    Rgb(Box<Engine<Rgb>>),
    Spectral(Box<Engine<Hero4>>),
}

impl VcmEngine {
    /// An engine for `scene`; spectral when [`VcmSettings::spectral`] is set.
    pub fn new(scene: &Scene, settings: VcmSettings) -> Self {
        let kind = if settings.spectral {
            EngineKind::Spectral(Box::new(Engine::new(scene, settings)))
        } else {
            EngineKind::Rgb(Box::new(Engine::new(scene, settings)))
        };
        Self { kind }
    }

    /// Keeps the per-pixel contributions of each technique family of every iteration (see
    /// [`VcmEngine::family_frames`]).
    pub fn record_families(&mut self, enabled: bool) {
        match &mut self.kind {
            EngineKind::Rgb(e) => e.family_frames = enabled.then(Vec::new),
            EngineKind::Spectral(e) => e.family_frames = enabled.then(Vec::new),
        }
    }

    /// Per-pixel contributions of the last iteration by family (light tracing included), if
    /// recording is on. They sum to the iteration's frame.
    pub fn family_frames(&self) -> Option<&[FamilyValues]> {
        match &self.kind {
            EngineKind::Rgb(e) => e.family_frames.as_deref(),
            EngineKind::Spectral(e) => e.family_frames.as_deref(),
        }
    }

    /// Keeps the per-pixel contributions of every (s, t) technique of each iteration, laid out
    /// as `layout` says (`None`: off, the default). See [`VcmEngine::technique_frame`].
    pub fn record_techniques(&mut self, layout: Option<TechniqueLayout>) {
        let frame = layout.map(|layout| TechniqueFrame::new(layout, 0));
        match &mut self.kind {
            EngineKind::Rgb(e) => e.technique_frame = frame,
            EngineKind::Spectral(e) => e.technique_frame = frame,
        }
    }

    /// Per-pixel contributions of the last iteration by (s, t) technique (light tracing
    /// included), if recording is on. They sum to the iteration's frame up to float rounding.
    pub fn technique_frame(&self) -> Option<&TechniqueFrame> {
        match &self.kind {
            EngineKind::Rgb(e) => e.technique_frame.as_ref(),
            EngineKind::Spectral(e) => e.technique_frame.as_ref(),
        }
    }

    /// Statistics of the last iteration.
    pub fn stats(&self) -> IterationStats {
        match &self.kind {
            EngineKind::Rgb(e) => e.stats,
            EngineKind::Spectral(e) => e.stats,
        }
    }

    /// The global merging radius of iteration `iteration` (0-based): r_0 · (i+1)^((α−1)/2).
    pub fn radius(&self, iteration: u64) -> f32 {
        match &self.kind {
            EngineKind::Rgb(e) => e.radius(iteration),
            EngineKind::Spectral(e) => e.radius(iteration),
        }
    }

    /// Renders iteration `iteration` into `frame` (overwritten). Returns the number of rejected
    /// (non-finite) contributions.
    pub fn run_iteration(&mut self, scene: &Scene, seed: u64, iteration: u64, frame: &mut FrameBuffer) -> u64 {
        match &mut self.kind {
            EngineKind::Rgb(e) => e.run_iteration(scene, seed, iteration, frame),
            EngineKind::Spectral(e) => e.run_iteration(scene, seed, iteration, frame),
        }
    }
}

/// The engine for one spectral mode.
struct Engine<S: SpectralMode> {
    settings: VcmSettings,
    techniques: Techniques,
    base_radius: f32,
    /// The volume radius before the schedule, in scenes with media.
    base_volume_radius: Option<f32>,
    /// Per-pixel footprint radii before the iteration schedule (per-pixel mode).
    pixel_footprints: Option<Vec<f32>>,
    pixel_radii: Vec<f32>,
    store: LightVertexStore<S>,
    /// The memory-efficient mode's merging-only records, in grid order.
    records: Vec<MergeRecord<S>>,
    grid: HashGrid,
    /// Per-pixel contributions by family of the last iteration, when requested.
    family_frames: Option<Vec<FamilyValues>>,
    /// Per-pixel contributions by (s, t) technique of the last iteration, when requested.
    technique_frame: Option<TechniqueFrame>,
    stats: IterationStats,
    /// The wavelength groups' ranges in the grid (spectral mode with merging; else empty).
    merge_groups: Vec<MergeGroup>,
    /// The iteration's light-tracing splats, summed per pixel.
    splat_sums: SplatSums,
}

/// One chunk of light sub-paths: vertices, per-path ends (relative), splats.
type LightChunk<S> = (Vec<LightVertex<S>>, Vec<u32>, Vec<Splat>);

/// One image row of the memory-efficient mode: splats, per-pixel family values and rejected
/// estimates.
type RowResult = (Vec<Splat>, Vec<FamilyValues>, RejectedCounts);

impl<S: SpectralMode> Engine<S> {
    /// An engine for `scene`.
    fn new(scene: &Scene, settings: VcmSettings) -> Self {
        let base_radius = base_radius(scene, &settings);
        let pixel_footprints =
            (settings.radius_mode == RadiusMode::PerPixel).then(|| pixel_footprints(scene, base_radius));
        Self {
            settings,
            techniques: Techniques::of(settings.algorithm),
            base_radius,
            base_volume_radius: scene.media.is_active().then(|| base_volume_radius(scene, &settings)),
            pixel_footprints,
            pixel_radii: Vec::new(),
            store: LightVertexStore::default(),
            records: Vec::new(),
            grid: HashGrid::new(),
            family_frames: None,
            technique_frame: None,
            stats: IterationStats::default(),
            merge_groups: Vec::new(),
            splat_sums: SplatSums::default(),
        }
    }

    /// The radius-reduction factor of iteration `iteration` (0-based): (i+1)^((α−1)/2).
    fn schedule(&self, iteration: u64) -> f32 {
        ((iteration.saturating_add(1)) as f32).powf(0.5 * (self.settings.radius_alpha - 1.0))
    }

    fn radius(&self, iteration: u64) -> f32 {
        (self.base_radius * self.schedule(iteration)).max(1e-7)
    }

    /// The volume radius of iteration `iteration`, r_V,0 · (i+1)^((α−1)/3) (the 3-D analogue of
    /// the surface schedule: the ball's volume shrinks as (i+1)^(α−1), as the disc's area does),
    /// or `None` in scenes without media.
    fn volume_radius(&self, iteration: u64) -> Option<f32> {
        let base = self.base_volume_radius?;
        let schedule = ((iteration.saturating_add(1)) as f32).powf((self.settings.radius_alpha - 1.0) / 3.0);
        Some((base * schedule).max(1e-7))
    }

    fn run_iteration(&mut self, scene: &Scene, seed: u64, iteration: u64, frame: &mut FrameBuffer) -> u64 {
        let pixel_count = frame.pixels.len();
        let techniques = self.techniques;
        let schedule = self.schedule(iteration);
        let mut radius = self.radius(iteration);
        // Taken out of `self` for the iteration, so the passes can borrow the engine mutably.
        let mut pixel_radii = std::mem::take(&mut self.pixel_radii);
        if let Some(footprints) = &self.pixel_footprints {
            pixel_radii.clear();
            pixel_radii.extend(footprints.iter().map(|r| (r * schedule).max(1e-7)));
            // The grid must cover the largest per-pixel radius.
            radius = pixel_radii.iter().fold(0.0f32, |a, b| a.max(*b));
        }
        // Wavelength groups: spectral mode with merging (both modes merge within the iteration).
        let grouped = self.settings.spectral && techniques.merge;
        let groups = if grouped { self.settings.wavelength_groups.max(1) } else { 1 };
        let light_paths = pixel_count as f32;
        let across = groups > 1 && merges_across_groups(scene, groups);
        let merge_paths = if groups > 1 && !across { light_paths / groups as f32 } else { light_paths };
        let constants =
            MisConstants::with_merge_paths(light_paths, merge_paths, radius, techniques.connect, techniques.merge);
        let volume_radius = self.volume_radius(iteration);
        let it = Iteration {
            constants: volume_radius.map_or(constants, |r| constants.with_volume_radius(r)),
            max_length: self.settings.max_length,
            radius,
            grid_radius: volume_radius.map_or(radius, |r| r.max(radius)),
            pixel_radii: self.pixel_footprints.as_ref().map(|_| pixel_radii.as_slice()),
            techniques,
            across_groups: across,
            film_offset: crate::splat_frame::film_offset(seed, iteration),
            mis_compensation: self.settings.compensates(scene),
        };
        let width = frame.width as usize;
        let sets = WavelengthSource::<S>::new(scene, seed, iteration, techniques.merge, groups, width, pixel_count);
        let (rejected, splats) = if self.settings.memory_efficient && !techniques.light_trace_only {
            self.run_single_stage(scene, seed, iteration, &it, frame, &sets)
        } else {
            self.run_two_stages(scene, seed, iteration, &it, frame, &sets)
        };
        self.pixel_radii = pixel_radii;
        self.stats.splats = splats;
        self.stats.rejected = rejected.iter().sum();
        self.stats.rejected_by_family = rejected;
        self.stats.radius = radius;
        self.stats.volume_radius = volume_radius.unwrap_or(0.0);
        self.stats.rejected
    }

    /// The two-stage iteration (§2.3): all light sub-paths, the grid, then all camera paths.
    fn run_two_stages(
        &mut self,
        scene: &Scene,
        seed: u64,
        iteration: u64,
        it: &Iteration,
        frame: &mut FrameBuffer,
        sets: &WavelengthSource<S>,
    ) -> (RejectedCounts, usize) {
        let pixel_count = frame.pixels.len();
        let start = std::time::Instant::now();
        self.store.clear();
        self.splat_sums.start(pixel_count, self.family_frames.is_some() || self.technique_frame.is_some());
        trace_light_pass(scene, (seed, iteration), it, pixel_count, sets, &mut self.store, &mut self.splat_sums);
        let light_pass = start.elapsed();
        if it.techniques.merge {
            let groups = sets.groups().map(|g| (g, it.constants.merge_path_count));
            let order = build_grid(
                &self.store.vertices,
                &self.store.path_ends,
                groups,
                &mut self.grid,
                it.grid_radius,
                &mut self.merge_groups,
            );
            self.store.permute_to_slots(order.as_deref().unwrap_or(self.grid.sorted_indices()));
        }
        let grid_build = start.elapsed() - light_pass;
        let store = &self.store;
        let scopes = MergeScopes::new(it, sets, &self.merge_groups);
        let source = MergeSource {
            vertices: MergeVertices::Full(&self.store.vertices),
            grid: &self.grid,
            scope: MergeScope::All,
        };
        let merge_source = it.techniques.merge.then_some(source);
        let width = frame.width as usize;
        let mut rejected =
            render_pixels(frame, self.family_frames.as_mut(), self.technique_frame.as_mut(), |index, techniques| {
                if it.techniques.light_trace_only {
                    return FamilyValues::default();
                }
                let mut rng = crate::splat_frame::camera_stream(seed, iteration, index);
                let (x, y) = ((index % width) as u32, (index / width) as u32);
                let light_path = store.path(index);
                let wavelengths = sets.get(seed, iteration, index as u64);
                let scoped = merge_source.map(|s| MergeSource { scope: scopes.of(index), ..s });
                let merge = scoped.as_ref();
                trace_camera_path_recorded(scene, it, x, y, &mut rng, light_path, merge, &wavelengths, techniques)
            });
        if !it.techniques.light_trace_only {
            crate::splat_frame::spread_camera_pass(
                &scene.camera,
                seed,
                iteration,
                &mut frame.pixels,
                self.family_frames.as_mut(),
                self.technique_frame.as_mut(),
                // Fresh buffers, freed before the next light pass: kept across iterations they
                // would add 24 bytes per pixel to the peak the memory guard estimates, for no
                // gain this machine resolves (docs/performance.md, "Buffers kept across
                // iterations").
                &mut Default::default(),
            );
        }
        let camera_pass = start.elapsed() - light_pass - grid_build;
        let splats = self.splat_sums.finish(
            &mut frame.pixels,
            &scene.camera,
            self.family_frames.as_mut(),
            self.technique_frame.as_mut(),
            &mut rejected,
        );
        self.stats.phases = PhaseTimes { light_pass, grid_build, camera_pass };
        self.stats.light_vertices = self.store.vertices.len();
        self.stats.bytes_per_vertex = LightVertexStore::<S>::BYTES_PER_VERTEX;
        (rejected, splats)
    }

    /// The memory-efficient iteration (§6.2, restructured): merging-only records of every light
    /// sub-path and the grid over them, then per pixel its light sub-path traced again (the same
    /// random stream, so the same vertices; camera connections on) right before its camera
    /// sub-path, which connects to it and merges with the records. Nothing but the 44-byte
    /// records is kept for a whole iteration, and merging uses the iteration's own light
    /// vertices, so the MIS weights and the wavelengths are those of the two-stage mode.
    fn run_single_stage(
        &mut self,
        scene: &Scene,
        seed: u64,
        iteration: u64,
        it: &Iteration,
        frame: &mut FrameBuffer,
        sets: &WavelengthSource<S>,
    ) -> (RejectedCounts, usize) {
        let pixel_count = frame.pixels.len();
        let start = std::time::Instant::now();
        if it.techniques.merge {
            // The first trace stores vertices and connects nothing to the camera.
            let merging_only = Iteration { techniques: Techniques { connect: false, ..it.techniques }, ..*it };
            let ends = trace_merge_records(scene, seed, iteration, &merging_only, pixel_count, sets, &mut self.records);
            let groups = sets.groups().map(|g| (g, it.constants.merge_path_count));
            let order =
                build_grid(&self.records, &ends, groups, &mut self.grid, it.grid_radius, &mut self.merge_groups);
            drop(ends);
            let mut slots = Vec::new();
            light_vertex::slot_map(
                self.records.len(),
                order.as_deref().unwrap_or(self.grid.sorted_indices()),
                &mut slots,
            );
            light_vertex::permute(&mut self.records, &mut slots);
        } else {
            self.records.clear();
        }
        let light_pass = start.elapsed();
        // Every row traces its pixels' light sub-paths and camera paths; rows return their
        // splats, per-pixel family values and rejected counts. Rows run in parallel batches, and
        // each batch's splats are summed in row (= light sub-path) order before the next batch.
        let width = frame.width as usize;
        let source =
            MergeSource { vertices: MergeVertices::Compact(&self.records), grid: &self.grid, scope: MergeScope::All };
        let scopes = MergeScopes::new(it, sets, &self.merge_groups);
        let merge_source = it.techniques.merge.then_some(source);
        let mut family_frames = self.family_frames.as_mut();
        let layout = self.technique_frame.as_ref().map(|t| t.layout);
        let images = layout.map_or(0, |l| l.len());
        if let Some(techniques) = &mut self.technique_frame {
            techniques.clear(pixel_count);
        }
        if let Some(frames) = family_frames.as_deref_mut() {
            frames.clear();
        }
        self.splat_sums.start(pixel_count, family_frames.is_some() || layout.is_some());
        // Row chunks of the technique values (none when not recorded).
        let mut technique_rows: Vec<&mut [Rgb]> = match &mut self.technique_frame {
            Some(techniques) => techniques.values.chunks_mut(width * images).collect(),
            None => frame.pixels.chunks(width).map(|_| <&mut [Rgb]>::default()).collect(),
        };
        let record_families = family_frames.is_some();
        // Each pixel's light sub-path hints the emission sample of the next pixel's.
        let hint = scene.has_prefetchable_background();
        let trace_row = |row: usize, pixels: &mut [Rgb], technique_row: &mut [Rgb]| -> RowResult {
            let mut vertices = Vec::new();
            let mut splats = Vec::new();
            // Per-pixel family values, kept only when recorded.
            let mut families = Vec::new();
            let mut rejected = RejectedCounts::default();
            let mut stage = vec![Rgb::BLACK; images];
            let mut codes = NormalCodes::default();
            // The next pixel's light generator, built once: for the hint, then for its path.
            let mut next_light_rng = light_stream(seed, iteration, row * width);
            for (column, pixel) in pixels.iter_mut().enumerate() {
                let index = row * width + column;
                vertices.clear();
                let mut light_rng = std::mem::replace(&mut next_light_rng, light_stream(seed, iteration, index + 1));
                if hint {
                    prefetch_light_path(scene, &next_light_rng);
                }
                let wavelengths = sets.get(seed, iteration, index as u64);
                trace_light_path(scene, it, &mut light_rng, &mut vertices, &mut splats, &*wavelengths, &mut codes);
                let mut rng = crate::splat_frame::camera_stream(seed, iteration, index);
                let light_path = LightPath::Contiguous(&vertices);
                let techniques = layout.map(|layout| {
                    let pixel_images = &mut technique_row[column * images..(column + 1) * images];
                    TechniqueValues::new(layout, pixel_images, &mut stage)
                });
                let merge = merge_source.map(|s| MergeSource { scope: scopes.of(index), ..s });
                let mut values = trace_camera_path_recorded(
                    scene,
                    it,
                    column as u32,
                    row as u32,
                    &mut rng,
                    light_path,
                    merge.as_ref(),
                    &wavelengths,
                    techniques,
                );
                values.discard_overflow();
                values.count_rejected(&mut rejected);
                *pixel = values.total();
                if record_families {
                    families.push(values);
                }
            }
            (splats, families, rejected)
        };
        let rows_per_batch = (LIGHT_BATCH / width.max(1)).max(1);
        let mut rejected = RejectedCounts::default();
        for (batch, (pixels, technique_rows)) in
            frame.pixels.chunks_mut(width * rows_per_batch).zip(technique_rows.chunks_mut(rows_per_batch)).enumerate()
        {
            let rows: Vec<RowResult> = pixels
                .par_chunks_mut(width)
                .zip(technique_rows.par_iter_mut())
                .enumerate()
                .map(|(row, (pixels, technique_row))| trace_row(batch * rows_per_batch + row, pixels, technique_row))
                .collect();
            for (mut splats, families, row_rejected) in rows {
                self.splat_sums.add(&scene.camera, &mut splats);
                if let Some(frames) = family_frames.as_deref_mut() {
                    frames.extend_from_slice(&families);
                }
                for (total, r) in rejected.iter_mut().zip(row_rejected) {
                    *total += r;
                }
            }
        }
        crate::splat_frame::spread_camera_pass(
            &scene.camera,
            seed,
            iteration,
            &mut frame.pixels,
            family_frames.as_deref_mut(),
            self.technique_frame.as_mut(),
            &mut Default::default(),
        );
        let camera_pass = start.elapsed() - light_pass;
        let splats = self.splat_sums.finish(
            &mut frame.pixels,
            &scene.camera,
            family_frames,
            self.technique_frame.as_mut(),
            &mut rejected,
        );
        self.stats.phases = PhaseTimes { light_pass, grid_build: std::time::Duration::ZERO, camera_pass };
        self.stats.light_vertices = self.records.len();
        self.stats.bytes_per_vertex = std::mem::size_of::<MergeRecord<S>>();
        (rejected, splats)
    }
}

/// Whether the camera sub-paths of `scene` merge with the light vertices of all `groups`
/// wavelength groups (`super::wavelengths`, "Merging across groups"): only where no material is
/// dispersive or fluorescent, in scenes without media (free flights are not re-weighted at other
/// wavelengths), and for at most [`wavelengths::MAX_CROSS_GROUPS`] groups.
fn merges_across_groups(scene: &Scene, groups: u32) -> bool {
    groups as usize <= wavelengths::MAX_CROSS_GROUPS
        && !scene.has_fluorescence()
        && !scene.has_dispersion()
        && !scene.media.is_active()
}

/// The merge scope of each pixel of one iteration.
enum MergeScopes<'a, S: SpectralMode> {
    /// One for all pixels.
    Same(MergeScope<'a, S>),
    /// Pixel i merges within its group (`ranges[layout.group_of(i)]`).
    OwnGroup(&'a wavelengths::GroupLayout, &'a [MergeGroup]),
}

impl<'a, S: SpectralMode> MergeScopes<'a, S> {
    /// The scopes of iteration `it` with wavelength source `sets` and groups `ranges`.
    fn new(it: &Iteration, sets: &'a WavelengthSource<S>, ranges: &'a [MergeGroup]) -> Self {
        match (sets.groups(), sets.group_sets()) {
            (Some(_), Some(group_sets)) if it.across_groups => Self::Same(MergeScope::AcrossGroups(ranges, group_sets)),
            (Some(layout), _) => Self::OwnGroup(layout, ranges),
            _ => Self::Same(MergeScope::All),
        }
    }

    /// The scope of pixel `index`.
    #[inline]
    fn of(&self, index: usize) -> MergeScope<'a, S> {
        match self {
            Self::Same(scope) => *scope,
            Self::OwnGroup(layout, ranges) => MergeScope::Group(ranges[layout.group_of(index)]),
        }
    }
}

/// Builds `grid` over `items` (light vertices of sub-paths ending at `path_ends`, in path order)
/// for queries of radius `radius`. The grid order — `order[s]` is the item that belongs in slot
/// `s`, the caller permutes the items so — is the grid's own [`HashGrid::sorted_indices`]
/// (`None` is returned), except with wavelength groups (their layout and the merge path count
/// N_VM): the items then enter the grid group after group, the order is returned, and
/// `merge_groups` gets each group's range of grid indices (otherwise it is emptied). The grid
/// is lean ([`HashGrid::build_lean`]): it keeps no positions, queries read them from the items
/// once they are permuted into slot order. (In both modes: against a grid with its own sorted
/// copy of the positions, the estimate holds 44 bytes less per vertex, and scene 1's peak at
/// 512² fell from 120 to 72 MB at an equal iteration time, docs/memory.md.)
fn build_grid<V: AsRef<MergeRecord<S>> + Sync, S: SpectralMode>(
    items: &[V],
    path_ends: &[u32],
    groups: Option<(&wavelengths::GroupLayout, f32)>,
    grid: &mut HashGrid,
    radius: f32,
    merge_groups: &mut Vec<MergeGroup>,
) -> Option<Vec<u32>> {
    merge_groups.clear();
    let Some((layout, merge_paths)) = groups else {
        grid.build_lean(items.len(), |i| items[i].as_ref().position, radius);
        return None;
    };
    let (order, starts) = layout.order_by_group(path_ends);
    merge_groups.extend(layout.sizes().iter().enumerate().map(|(g, &size)| MergeGroup {
        first: starts[g],
        end: starts[g + 1],
        normalization_scale: if size > 0 { merge_paths / size as f32 } else { 0.0 },
    }));
    grid.build_lean(order.len(), |j| items[order[j] as usize].as_ref().position, radius);
    // Grid indices count in group order; the items are in path order.
    Some(grid.sorted_indices().iter().map(|&j| order[j as usize]).collect())
}

/// Light sub-paths traced per batch of the light pass: the vertices of one batch are moved into
/// the store before the next batch is traced, so the pass never holds a second copy of the
/// iteration's vertices (16 chunks: enough parallel work for 16 threads).
pub(crate) const LIGHT_BATCH: usize = 16 * LIGHT_CHUNK;

/// Traces the `pixel_count` light sub-paths of `iteration` in batches of parallel chunks and
/// hands each batch's chunks to `take`, in path order (deterministic for any thread count); a
/// batch is handed over before the next one is traced. The chunks' buffers are reused from
/// batch to batch (`take` may empty them; they are cleared before the next batch), so after the
/// first batch tracing neither allocates nor grows them.
fn trace_in_batches<S: SpectralMode>(
    scene: &Scene,
    (seed, iteration): (u64, u64),
    it: &Iteration,
    pixel_count: usize,
    sets: &WavelengthSource<S>,
    mut take: impl FnMut(&mut [LightChunk<S>]),
) {
    let mut chunks = Vec::new();
    for batch in (0..pixel_count).step_by(LIGHT_BATCH) {
        let paths = batch..(batch + LIGHT_BATCH).min(pixel_count);
        trace_light_chunks(scene, seed, iteration, it, paths, sets, &mut chunks);
        take(&mut chunks);
    }
}

/// Traces the light sub-paths of `iteration` and appends their vertices and path ends to
/// `store` and their light-tracing splats to `splats`, in path order.
fn trace_light_pass<S: SpectralMode>(
    scene: &Scene,
    (seed, iteration): (u64, u64),
    it: &Iteration,
    pixel_count: usize,
    sets: &WavelengthSource<S>,
    store: &mut LightVertexStore<S>,
    splats: &mut SplatSums,
) {
    trace_in_batches(scene, (seed, iteration), it, pixel_count, sets, |chunks| {
        // Between two batches the other threads would wait: the copy into the store and the
        // splat sums touch different memory, so they run side by side (each in path order).
        let (stored, chunk_splats): (Vec<_>, Vec<_>) =
            chunks.iter_mut().map(|(vertices, ends, splats)| ((&*vertices, &*ends), splats)).unzip();
        rayon::join(
            || {
                for (vertices, ends) in stored {
                    let base = store.vertices.len() as u32;
                    store.vertices.extend_from_slice(vertices);
                    store.path_ends.extend(ends.iter().map(|e| e + base));
                }
            },
            || chunk_splats.into_iter().for_each(|s| splats.add(&scene.camera, s)),
        );
    });
}

/// Traces the light sub-paths of `iteration` and replaces `records` with the merging-only
/// records of their vertices, in path order; returns each sub-path's end index.
fn trace_merge_records<S: SpectralMode>(
    scene: &Scene,
    seed: u64,
    iteration: u64,
    it: &Iteration,
    pixel_count: usize,
    sets: &WavelengthSource<S>,
    records: &mut Vec<MergeRecord<S>>,
) -> Vec<u32> {
    records.clear();
    let mut path_ends = Vec::with_capacity(pixel_count);
    trace_in_batches(scene, (seed, iteration), it, pixel_count, sets, |chunks| {
        for (vertices, ends, _) in chunks {
            let base = records.len() as u32;
            records.extend(vertices.iter().map(|v| v.record));
            path_ends.extend(ends.iter().map(|e| e + base));
        }
    });
    path_ends
}

/// Traces the light sub-paths `paths` of `iteration` in parallel chunks of [`LIGHT_CHUNK`], in
/// order, into `chunks` (resized to the chunk count; each chunk's buffers are cleared, not
/// reallocated).
fn trace_light_chunks<S: SpectralMode>(
    scene: &Scene,
    seed: u64,
    iteration: u64,
    it: &Iteration,
    paths: std::ops::Range<usize>,
    sets: &WavelengthSource<S>,
    chunks: &mut Vec<LightChunk<S>>,
) {
    chunks.resize_with(paths.len().div_ceil(LIGHT_CHUNK), Default::default);
    let hint = scene.has_prefetchable_background();
    chunks.par_iter_mut().enumerate().for_each(|(c, (vertices, ends, splats))| {
        vertices.clear();
        ends.clear();
        splats.clear();
        let mut codes = NormalCodes::default();
        let first = paths.start + c * LIGHT_CHUNK;
        let end = (first + LIGHT_CHUNK).min(paths.end);
        // The next sub-path's generator, built once: for the hint, then for its path.
        let mut next_rng = light_stream(seed, iteration, first);
        for path in first..end {
            let mut rng = std::mem::replace(&mut next_rng, light_stream(seed, iteration, path + 1));
            // The emission sample of the next sub-path is fetched while this one is traced.
            if hint {
                prefetch_light_path(scene, &next_rng);
            }
            let wavelengths = sets.get(seed, iteration, path as u64);
            trace_light_path(scene, it, &mut rng, vertices, splats, &*wavelengths, &mut codes);
            ends.push(vertices.len() as u32);
        }
    });
}

/// Fills `frame` (and the family and technique frames, if recorded) with `trace(pixel,
/// techniques)` for every pixel, in parallel over rows; `techniques` is where the pixel's
/// (s, t) values go when recorded. Returns the number of rejected (non-finite) pixel estimates.
fn render_pixels(
    frame: &mut FrameBuffer,
    family_frames: Option<&mut Vec<FamilyValues>>,
    technique_frame: Option<&mut TechniqueFrame>,
    trace: impl Fn(usize, Option<TechniqueValues>) -> FamilyValues + Sync,
) -> RejectedCounts {
    let width = frame.width as usize;
    let pixel_count = frame.pixels.len();
    let rows = pixel_count.div_ceil(width.max(1));
    // Per-row slices of the optional buffers (empty when not recorded).
    let mut family_rows: Vec<&mut [FamilyValues]> = match family_frames {
        Some(families) => {
            families.clear();
            families.resize(pixel_count, FamilyValues::default());
            families.chunks_mut(width).collect()
        }
        None => (0..rows).map(|_| <&mut [FamilyValues]>::default()).collect(),
    };
    let (layout, images) = match &technique_frame {
        Some(t) => (Some(t.layout), t.layout.len()),
        None => (None, 0),
    };
    let mut technique_rows: Vec<&mut [Rgb]> = match technique_frame {
        Some(techniques) => {
            techniques.clear(pixel_count);
            techniques.values.chunks_mut(width * images).collect()
        }
        None => (0..rows).map(|_| <&mut [Rgb]>::default()).collect(),
    };
    let sum = |a: RejectedCounts, b: RejectedCounts| std::array::from_fn(|i| a[i] + b[i]);
    frame
        .pixels
        .par_chunks_mut(width)
        .zip(family_rows.par_iter_mut())
        .zip(technique_rows.par_iter_mut())
        .enumerate()
        .map(|(row, ((pixels, family_row), technique_row))| {
            let mut rejected = RejectedCounts::default();
            let mut stage = vec![Rgb::BLACK; images];
            for (column, pixel) in pixels.iter_mut().enumerate() {
                let techniques = layout.map(|layout| {
                    let pixel_images = &mut technique_row[column * images..(column + 1) * images];
                    TechniqueValues::new(layout, pixel_images, &mut stage)
                });
                let mut values = trace(row * width + column, techniques);
                values.discard_overflow();
                values.count_rejected(&mut rejected);
                *pixel = values.total();
                if let Some(family) = family_row.get_mut(column) {
                    *family = values;
                }
            }
            rejected
        })
        .reduce(RejectedCounts::default, sum)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn non_finite_estimates_are_counted_per_family_and_never_added() {
        let mut values = FamilyValues::default();
        values.add(Family::NextEvent, Rgb::splat(1.0));
        values.add(Family::NextEvent, Rgb::new(f32::NAN, 0.0, 0.0));
        values.add(Family::Merging, Rgb::splat(f32::INFINITY));
        values.add(Family::Merging, Rgb::splat(2.0));
        assert_eq!(values.total(), Rgb::splat(3.0));
        assert_eq!(values.1, [0, 1, 0, 0, 1]);
        // Finite values whose sum overflows: dropped, counted against the largest.
        let mut overflow = FamilyValues::default();
        overflow.add(Family::Connection, Rgb::splat(f32::MAX));
        overflow.add(Family::EmitterHit, Rgb::splat(f32::MAX * 0.5));
        overflow.discard_overflow();
        assert_eq!(overflow.total(), Rgb::BLACK);
        let mut counts = RejectedCounts::default();
        values.count_rejected(&mut counts);
        overflow.count_rejected(&mut counts);
        assert_eq!(counts, [0, 1, 0, 1, 1]);
    }
}
