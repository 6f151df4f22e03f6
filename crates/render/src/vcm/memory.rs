//! Memory estimate of a render's buffers, made before the first iteration so that a render
//! too large for the machine can stop with a clear message (or switch to the memory-efficient
//! mode where that is smaller) instead of being killed by the operating system.
//!
//! The estimate is a sum of the buffers the driver and the engine hold at the peak of an
//! iteration, each from the size of its element type (docs/performance.md, "Memory", compares it
//! with the measured peak resident memory of every algorithm). It does not include what the
//! process holds before rendering (the program, the scene and its BVH): the caller adds that.
//!
//! The numbers of stored light vertices and of light-tracing splats are random; a pilot traces
//! [`PILOT_PATHS`] light sub-paths of iteration 0 (the same random streams the render will
//! use) and scales their mean counts to one sub-path per pixel.

use scene::Scene;
use spectrum::{Hero4, Rgb};

use super::connect::Splat;
use super::light_pass::trace_light_path;
use super::light_vertex::{LightVertex, MergeRecord, NormalCodes};
use super::mis::MisConstants;
use super::{Iteration, Techniques, VcmSettings, light_stream};

/// Light sub-paths traced by the pilot.
pub const PILOT_PATHS: usize = 4096;

/// Bytes per pixel the driver holds whatever the algorithm: the film's sums (3 × f64) and the
/// iteration's frame (3 × f32). (Recording technique families adds five films and a frame.)
pub const FILM_BYTES_PER_PIXEL: usize = 36;

/// Bytes per pixel of the film's sums of squares (3 × f64), kept for variance images and
/// checkpoints ([`crate::RenderSettings::variance`]).
pub const SQUARES_BYTES_PER_PIXEL: usize = 24;

/// Bytes per pixel of the engine: the light sub-paths' end indices (u32).
const ENGINE_BYTES_PER_PIXEL: usize = 4;

/// Bytes per pixel of the per-pixel radius mode: footprints and radii (2 × f32).
const PER_PIXEL_RADIUS_BYTES: usize = 8;

/// Bytes of the range-search grid per indexed vertex ([`crate::hash_grid::HashGrid::build_lean`],
/// both modes): sorted indices (4) and one transient `u32` (the keys while it is built; in the
/// memory-efficient mode, then the slot map while the records are permuted). The bucket starts
/// (4 per bucket, one bucket per vertex rounded up to a power of two) come on top.
const LEAN_GRID_BYTES_PER_VERTEX: usize = 8;

/// Bytes of the slot map that leads connections to vertices stored in grid order (u32).
const SLOT_BYTES_PER_VERTEX: usize = 4;

/// The estimate for one scene, resolution and algorithm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MemoryEstimate {
    /// Mean stored light vertices per light sub-path in the pilot.
    pub vertices_per_path: f64,
    /// Mean light-tracing splats per light sub-path in the pilot.
    pub splats_per_path: f64,
    /// Light sub-paths per iteration (one per pixel).
    pub light_paths: usize,
    /// Peak bytes of the render in the two-stage mode (film and frames included, the process's
    /// program and scene not).
    pub two_stage_bytes: u64,
    /// Peak bytes of the render in the memory-efficient mode, likewise.
    pub memory_efficient_bytes: u64,
}

/// Estimates the peak buffers of a render of `scene` with `settings` and `seed` (the pilot's
/// random streams are those of the render's first iteration).
pub fn estimate(scene: &Scene, settings: &VcmSettings, seed: u64) -> MemoryEstimate {
    let light_paths = scene.camera.pixel_count();
    let techniques = Techniques::of(settings.algorithm);
    let radius = super::base_radius(scene, settings);
    let it = Iteration {
        constants: MisConstants::new(light_paths, radius.max(1e-7), techniques.connect, techniques.merge),
        max_length: settings.max_length,
        radius,
        grid_radius: radius,
        pixel_radii: None,
        techniques,
        across_groups: false,
        film_offset: crate::splat_frame::film_offset(seed, 0),
        mis_compensation: settings.compensates(scene),
    };
    let pilot = light_paths.clamp(1, PILOT_PATHS);
    let mut vertices = Vec::new();
    let mut splats = Vec::new();
    let (mut stored, mut splatted) = (0usize, 0usize);
    let mut codes = NormalCodes::default();
    for path in 0..pilot {
        let mut rng = light_stream(seed, 0, path);
        // The vertex count does not depend on the spectral mode (sampling decisions use RGB
        // values in both), so the pilot traces in RGB.
        trace_light_path::<Rgb>(scene, &it, &mut rng, &mut vertices, &mut splats, &(), &mut codes);
        stored += vertices.len();
        splatted += splats.len();
        vertices.clear();
        splats.clear();
    }
    let vertices_per_path = stored as f64 / pilot as f64;
    let splats_per_path = splatted as f64 / pilot as f64;
    let counts = Counts {
        pixels: light_paths as f64,
        vertices: vertices_per_path * light_paths as f64,
        splats: splats_per_path * light_paths as f64,
    };
    MemoryEstimate {
        vertices_per_path,
        splats_per_path,
        light_paths,
        two_stage_bytes: peak_bytes(&counts, settings, false),
        memory_efficient_bytes: peak_bytes(&counts, settings, true),
    }
}

/// Bytes the driver holds for a render of `pixel_count` pixels whatever the algorithm (the
/// whole estimate of the path tracer and the eye light), with the film's sums of squares when
/// `variance` is set.
pub fn driver_bytes(pixel_count: usize, variance: bool) -> u64 {
    (pixel_count * film_bytes_per_pixel(variance)) as u64
}

/// The peak bytes of a render whose one-lane peak is `one_lane` when `lanes` iterations run side
/// by side ([`crate::Parallelism::Iterations`]): the film's sums are shared, every other buffer
/// (the engine's, the frame) is one per lane.
pub fn lanes_bytes(one_lane: u64, pixel_count: usize, variance: bool, lanes: usize) -> u64 {
    let shared = (pixel_count * (film_bytes_per_pixel(variance) - FRAME_BYTES_PER_PIXEL)) as u64;
    let per_lane = one_lane.saturating_sub(shared);
    shared.min(one_lane) + per_lane * lanes.max(1) as u64
}

/// Bytes per pixel of an iteration's frame (3 × f32), one per lane.
const FRAME_BYTES_PER_PIXEL: usize = 12;

/// Bytes per pixel of the film and the frame.
fn film_bytes_per_pixel(variance: bool) -> usize {
    FILM_BYTES_PER_PIXEL + if variance { SQUARES_BYTES_PER_PIXEL } else { 0 }
}

/// An upper bound of [`MemoryEstimate::two_stage_bytes`] without a pilot: every light sub-path
/// stores at most `max_length − 1` vertices and makes at most one splat per vertex. When it
/// fits, the pilot is not needed.
pub fn upper_bound(scene: &Scene, settings: &VcmSettings) -> u64 {
    let pixels = scene.camera.pixel_count() as f64;
    let per_path = f64::from(settings.max_length.saturating_sub(1));
    let counts = Counts { pixels, vertices: pixels * per_path, splats: pixels * per_path };
    peak_bytes(&counts, settings, false).max(peak_bytes(&counts, settings, true))
}

/// Expected numbers of pixels, stored light vertices and splats of one iteration.
struct Counts {
    pixels: f64,
    vertices: f64,
    splats: f64,
}

/// The peak of the buffers of one iteration for `counts`.
fn peak_bytes(counts: &Counts, settings: &VcmSettings, memory_efficient: bool) -> u64 {
    let techniques = Techniques::of(settings.algorithm);
    let (vertex, record) = if settings.spectral {
        (std::mem::size_of::<LightVertex<Hero4>>(), std::mem::size_of::<MergeRecord<Hero4>>())
    } else {
        (std::mem::size_of::<LightVertex<Rgb>>(), std::mem::size_of::<MergeRecord<Rgb>>())
    };
    let mut per_pixel = (film_bytes_per_pixel(settings.film_variance) + ENGINE_BYTES_PER_PIXEL) as f64;
    if settings.radius_mode == super::RadiusMode::PerPixel {
        per_pixel += PER_PIXEL_RADIUS_BYTES as f64;
    }
    // Light-tracing splats: one sum per pixel, and the splats of one batch of light sub-paths
    // (or of camera rows, memory-efficient mode) before they are summed.
    let splats = if counts.splats > 0.0 {
        let batch = (super::LIGHT_BATCH as f64).min(counts.pixels);
        counts.pixels * std::mem::size_of::<Rgb>() as f64
            + counts.splats / counts.pixels.max(1.0) * batch * std::mem::size_of::<Splat>() as f64
    } else {
        0.0
    };
    let stored = techniques.store_light_vertices();
    let grid = if techniques.merge {
        let buckets = (counts.vertices.max(1.0) as u64).next_power_of_two() as f64;
        // The default mode keeps the slot map for its connections; the permutation's transient
        // copy of it (4 bytes) comes after the keys are freed.
        let per_vertex = if memory_efficient {
            LEAN_GRID_BYTES_PER_VERTEX
        } else {
            LEAN_GRID_BYTES_PER_VERTEX + SLOT_BYTES_PER_VERTEX
        };
        counts.vertices * per_vertex as f64 + 4.0 * buckets
    } else {
        0.0
    };
    // One batch of the light pass in per-chunk vectors (capacity up to twice their length)
    // before it moves into the store.
    // (The memory-efficient mode without merging keeps no vertex beyond one light sub-path.)
    let batch = if stored && (techniques.merge || !memory_efficient) {
        2.0 * counts.vertices / counts.pixels.max(1.0) * (super::LIGHT_BATCH as f64).min(counts.pixels) * vertex as f64
    } else {
        0.0
    };
    let vertices = if !stored {
        0.0
    } else if memory_efficient {
        // Merging-only records (none without merging): connections use a light sub-path
        // traced again right before each camera path.
        if techniques.merge { counts.vertices * record as f64 } else { 0.0 }
    } else {
        counts.vertices * vertex as f64
    };
    (counts.pixels * per_pixel + splats + vertices + grid + batch).ceil() as u64
}

/// Resident memory of this process in bytes (Linux: `VmRSS` of `/proc/self/status`), if known.
pub fn resident_bytes() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = text.lines().find(|l| l.starts_with("VmRSS:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// Physical memory of the machine in bytes (Linux: `MemTotal` of `/proc/meminfo`), if known.
pub fn physical_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// Parses a memory size: a number with an optional suffix K, M, G or T (powers of 1024; a
/// trailing `B` or `iB` is accepted), e.g. `512M`, `8G`, `1.5GiB`, `1000000`.
pub fn parse_size(text: &str) -> Result<u64, String> {
    let t = text.trim();
    let upper = t.to_ascii_uppercase();
    let stripped = upper.strip_suffix("IB").or_else(|| upper.strip_suffix('B')).unwrap_or(&upper);
    let (number, factor) = match stripped.chars().last() {
        Some('K') => (&stripped[..stripped.len() - 1], 1u64 << 10),
        Some('M') => (&stripped[..stripped.len() - 1], 1 << 20),
        Some('G') => (&stripped[..stripped.len() - 1], 1 << 30),
        Some('T') => (&stripped[..stripped.len() - 1], 1 << 40),
        _ => (stripped, 1),
    };
    let value: f64 =
        number.trim().parse().map_err(|_| format!("invalid memory size '{text}': expected e.g. 512M or 8G"))?;
    if !(value.is_finite() && value > 0.0) {
        return Err(format!("invalid memory size '{text}': must be positive"));
    }
    Ok((value * factor as f64) as u64)
}

/// A byte count for messages: `1.23 GiB`.
pub fn format_size(bytes: u64) -> String {
    let b = bytes as f64;
    if b >= (1u64 << 30) as f64 {
        format!("{:.2} GiB", b / (1u64 << 30) as f64)
    } else if b >= (1u64 << 20) as f64 {
        format!("{:.1} MiB", b / (1u64 << 20) as f64)
    } else {
        format!("{:.0} KiB", b / 1024.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vcm::VcmAlgorithm;

    #[test]
    fn sizes_parse() {
        assert_eq!(parse_size("512M"), Ok(512 << 20));
        assert_eq!(parse_size("8G"), Ok(8 << 30));
        assert_eq!(parse_size("1.5GiB"), Ok(3 << 29));
        assert_eq!(parse_size("1000"), Ok(1000));
        assert!(parse_size("-1G").is_err());
        assert!(parse_size("lots").is_err());
        assert_eq!(format_size(3 << 29), "1.50 GiB");
    }

    #[test]
    fn estimate_matches_the_first_iteration() {
        // The pilot's vertex count scaled to the image must agree with what iteration 0 stores.
        let scene = scene::cornell::build(273, 64, 64).unwrap();
        let settings = VcmSettings::new(VcmAlgorithm::VertexConnectionMerging);
        let e = estimate(&scene, &settings, 5);
        let mut engine = super::super::VcmEngine::new(&scene, settings);
        let mut frame = scene::FrameBuffer::new(64, 64);
        engine.run_iteration(&scene, 5, 0, &mut frame);
        let actual = engine.stats().light_vertices as f64;
        let predicted = e.vertices_per_path * e.light_paths as f64;
        // 4096 pilot paths = the whole 64×64 image: the same streams, the same count.
        assert_eq!(predicted, actual);
        assert!(upper_bound(&scene, &settings) >= e.two_stage_bytes);
        assert!(physical_memory().is_none_or(|m| m > 1 << 20));
    }
}
