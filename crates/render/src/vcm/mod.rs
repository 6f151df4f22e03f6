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
//!    it projects to ([`connect::connect_to_camera`]);
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

pub mod camera_pass;
pub mod connect;
pub mod light_pass;
pub mod light_vertex;
pub mod merge;
pub mod mis;
pub mod subpath;

use math::Rng;
use rayon::prelude::*;
use scene::{FrameBuffer, Scene};
use spectrum::Rgb;

use crate::hash_grid::HashGrid;
use camera_pass::{MergeSource, trace_camera_path};
use connect::Splat;
use light_pass::trace_light_path;
use light_vertex::{LightVertex, LightVertexStore};
use mis::MisConstants;

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

/// Contributions of one camera sub-path, by family.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FamilyValues(pub [Rgb; 5]);

impl FamilyValues {
    /// Adds `value` to `family`.
    #[inline]
    pub fn add(&mut self, family: Family, value: Rgb) {
        self.0[family as usize] += value;
    }

    /// The sum over families.
    pub fn total(&self) -> Rgb {
        self.0.iter().fold(Rgb::BLACK, |a, b| a + *b)
    }
}

/// Settings of the engine.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VcmSettings {
    /// Which algorithm.
    pub algorithm: VcmAlgorithm,
    /// Maximum path length in segments.
    pub max_length: u32,
    /// Initial merging radius as a fraction of the scene's bounding-sphere radius.
    pub radius_factor: f32,
    /// Radius reduction α: r_i = r_0 · (i+1)^((α−1)/2).
    pub radius_alpha: f32,
}

impl VcmSettings {
    /// Defaults: radius factor 0.003, α = 0.75, 10 segments.
    pub fn new(algorithm: VcmAlgorithm) -> Self {
        Self { algorithm, max_length: 10, radius_factor: 0.003, radius_alpha: 0.75 }
    }
}

/// Per-iteration values shared by the passes.
#[derive(Clone, Copy, Debug)]
pub struct Iteration {
    /// MIS constants.
    pub constants: MisConstants,
    /// Maximum path length in segments.
    pub max_length: u32,
    /// Merging radius.
    pub radius: f32,
}

/// Statistics of the last iteration.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct IterationStats {
    /// Light vertices stored.
    pub light_vertices: usize,
    /// Bytes per stored light vertex.
    pub bytes_per_vertex: usize,
    /// Light-tracing splats.
    pub splats: usize,
    /// Non-finite contributions discarded.
    pub rejected: u64,
    /// Merging radius used.
    pub radius: f32,
}

/// Light sub-paths are traced in chunks of this many; each chunk's vertices and splats are
/// collected separately and concatenated in order (deterministic for any thread count).
const LIGHT_CHUNK: usize = 1024;

/// Offset that separates the random streams of light sub-paths from those of camera paths.
const LIGHT_STREAM: u64 = 1 << 62;

/// The engine and its per-iteration buffers.
pub struct VcmEngine {
    settings: VcmSettings,
    techniques: Techniques,
    base_radius: f32,
    store: LightVertexStore,
    grid: HashGrid,
    /// Per-pixel contributions by family of the last iteration, when requested.
    family_frames: Option<Vec<FamilyValues>>,
    stats: IterationStats,
}

impl VcmEngine {
    /// An engine for `scene`.
    pub fn new(scene: &Scene, settings: VcmSettings) -> Self {
        Self {
            settings,
            techniques: Techniques::of(settings.algorithm),
            base_radius: settings.radius_factor * scene.bounding_sphere.radius,
            store: LightVertexStore::default(),
            grid: HashGrid::new(),
            family_frames: None,
            stats: IterationStats::default(),
        }
    }

    /// Keeps the per-pixel contributions of each technique family of every iteration (see
    /// [`VcmEngine::family_frames`]).
    pub fn record_families(&mut self, enabled: bool) {
        self.family_frames = enabled.then(Vec::new);
    }

    /// Per-pixel contributions of the last iteration by family (light tracing included), if
    /// recording is on. They sum to the iteration's frame.
    pub fn family_frames(&self) -> Option<&[FamilyValues]> {
        self.family_frames.as_deref()
    }

    /// Statistics of the last iteration.
    pub fn stats(&self) -> IterationStats {
        self.stats
    }

    /// The merging radius of iteration `iteration` (0-based): r_0 · (i+1)^((α−1)/2).
    pub fn radius(&self, iteration: u64) -> f32 {
        let exponent = 0.5 * (self.settings.radius_alpha - 1.0);
        (self.base_radius * ((iteration + 1) as f32).powf(exponent)).max(1e-7)
    }

    /// Renders iteration `iteration` into `frame` (overwritten). Returns the number of rejected
    /// (non-finite) contributions.
    pub fn run_iteration(&mut self, scene: &Scene, seed: u64, iteration: u64, frame: &mut FrameBuffer) -> u64 {
        let pixel_count = frame.pixels.len();
        let radius = self.radius(iteration);
        let techniques = self.techniques;
        let it = Iteration {
            constants: MisConstants::new(pixel_count, radius, techniques.connect, techniques.merge),
            max_length: self.settings.max_length,
            radius,
        };

        // Light pass.
        let chunks: Vec<(Vec<LightVertex>, Vec<u32>, Vec<Splat>)> = (0..pixel_count.div_ceil(LIGHT_CHUNK))
            .into_par_iter()
            .map(|chunk| {
                let mut vertices = Vec::new();
                let mut ends = Vec::new();
                let mut splats = Vec::new();
                let end = ((chunk + 1) * LIGHT_CHUNK).min(pixel_count);
                for path in chunk * LIGHT_CHUNK..end {
                    let mut rng = Rng::for_stream(seed, iteration, LIGHT_STREAM | path as u64);
                    trace_light_path(scene, &it, &techniques, &mut rng, &mut vertices, &mut splats);
                    ends.push(vertices.len() as u32);
                }
                (vertices, ends, splats)
            })
            .collect();
        self.store.clear();
        let mut splat_count = 0;
        for (vertices, ends, splats) in &chunks {
            let base = self.store.vertices.len() as u32;
            self.store.vertices.extend_from_slice(vertices);
            self.store.path_ends.extend(ends.iter().map(|e| e + base));
            splat_count += splats.len();
        }
        if techniques.merge {
            let positions: Vec<math::Vec3> = self.store.vertices.iter().map(|v| v.position).collect();
            self.grid.build(&positions, radius);
        }

        // Camera pass.
        let width = frame.width as usize;
        let store = &self.store;
        let grid = &self.grid;
        let merge_source = techniques.merge.then_some(MergeSource { vertices: &store.vertices, grid });
        let trace = |index: usize| -> FamilyValues {
            if techniques.light_trace_only {
                return FamilyValues::default();
            }
            let mut rng = Rng::for_stream(seed, iteration, index as u64);
            let (x, y) = ((index % width) as u32, (index / width) as u32);
            trace_camera_path(scene, &it, &techniques, x, y, &mut rng, store.path(index), merge_source.as_ref())
        };
        let mut rejected: u64 = match &mut self.family_frames {
            None => frame
                .pixels
                .par_chunks_mut(width)
                .enumerate()
                .map(|(row, pixels)| {
                    let mut rejected = 0;
                    for (column, pixel) in pixels.iter_mut().enumerate() {
                        *pixel = accept(trace(row * width + column).total(), &mut rejected);
                    }
                    rejected
                })
                .sum(),
            Some(families) => {
                families.clear();
                families.resize(pixel_count, FamilyValues::default());
                frame
                    .pixels
                    .par_chunks_mut(width)
                    .zip(families.par_chunks_mut(width))
                    .enumerate()
                    .map(|(row, (pixels, family_row))| {
                        let mut rejected = 0;
                        for (column, (pixel, family)) in pixels.iter_mut().zip(family_row).enumerate() {
                            let mut values = trace(row * width + column);
                            if !values.total().is_finite() {
                                values = FamilyValues::default();
                                rejected += 1;
                            }
                            *family = values;
                            *pixel = values.total();
                        }
                        rejected
                    })
                    .sum()
            }
        };

        // Light-tracing splats, in light sub-path order.
        for (_, _, splats) in &chunks {
            for splat in splats {
                let value = accept(splat.value, &mut rejected);
                frame.pixels[splat.pixel as usize] += value;
                if let Some(families) = &mut self.family_frames {
                    families[splat.pixel as usize].add(Family::LightTracing, value);
                }
            }
        }

        self.stats = IterationStats {
            light_vertices: self.store.vertices.len(),
            bytes_per_vertex: LightVertexStore::BYTES_PER_VERTEX,
            splats: splat_count,
            rejected,
            radius,
        };
        rejected
    }
}

/// `value` if finite, else black and one more rejection.
#[inline]
fn accept(value: Rgb, rejected: &mut u64) -> Rgb {
    if value.is_finite() {
        value
    } else {
        *rejected += 1;
        Rgb::BLACK
    }
}
