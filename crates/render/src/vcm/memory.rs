//! Memory estimate of the engine's per-iteration buffers, made before the first iteration so
//! that a render too large for the machine can switch to the memory-efficient mode (§6.2) or
//! stop with a clear message instead of being killed by the operating system.
//!
//! The number of stored light vertices is random; a pilot traces [`PILOT_PATHS`] light sub-paths
//! of iteration 0 (the same random streams the render will use) and scales their mean vertex
//! count to one sub-path per pixel.

use math::Rng;
use scene::Scene;
use spectrum::{Hero4, Rgb};

use super::light_pass::trace_light_path;
use super::light_vertex::{LightVertex, MergeVertex};
use super::mis::MisConstants;
use super::{Iteration, LIGHT_STREAM, Techniques, VcmSettings};

/// Light sub-paths traced by the pilot.
pub const PILOT_PATHS: usize = 4096;

/// Bytes of the range-search grid per light vertex: the position copy it is built from (12)
/// and its index permutation (4).
const GRID_BYTES_PER_VERTEX: usize = 16;

/// The estimate for one scene, resolution and algorithm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MemoryEstimate {
    /// Mean stored light vertices per light sub-path in the pilot.
    pub vertices_per_path: f64,
    /// Light sub-paths per iteration (one per pixel).
    pub light_paths: usize,
    /// Peak bytes of the two-stage mode: light vertices in the tracing chunks and in the store
    /// (both alive while the store is filled), the merging copy and the grid.
    pub two_stage_bytes: u64,
    /// Peak bytes of the memory-efficient mode: the previous and the current iteration's
    /// merging data, the grid, and one image row of full light vertices per thread (small).
    pub memory_efficient_bytes: u64,
}

/// Estimates the buffers of the VCM engine for `scene` with `settings` and `seed` (the pilot's
/// random streams are those of the render's first iteration).
pub fn estimate(scene: &Scene, settings: &VcmSettings, seed: u64) -> MemoryEstimate {
    let light_paths = scene.camera.pixel_count();
    let techniques = Techniques::of(settings.algorithm);
    let radius = settings.radius_factor * scene.bounding_sphere.radius;
    let it = Iteration {
        constants: MisConstants::new(light_paths, radius.max(1e-7), techniques.connect, techniques.merge),
        max_length: settings.max_length,
        radius,
        pixel_radii: None,
        techniques,
    };
    let pilot = light_paths.clamp(1, PILOT_PATHS);
    let mut vertices = Vec::new();
    let mut splats = Vec::new();
    let mut stored = 0usize;
    for path in 0..pilot {
        let mut rng = Rng::for_stream(seed, 0, LIGHT_STREAM | path as u64);
        // The vertex count does not depend on the spectral mode (sampling decisions use RGB
        // values in both), so the pilot traces in RGB.
        trace_light_path::<Rgb>(scene, &it, &mut rng, &mut vertices, &mut splats, &());
        stored += vertices.len();
        vertices.clear();
        splats.clear();
    }
    let vertices_per_path = stored as f64 / pilot as f64;
    let total_vertices = vertices_per_path * light_paths as f64;
    let (full, merge) = vertex_sizes(settings);
    let merge = if techniques.merge { merge + GRID_BYTES_PER_VERTEX } else { 0 };
    let two_stage = total_vertices * (2 * full + merge) as f64;
    let memory_efficient = total_vertices * (2 * merge) as f64;
    MemoryEstimate {
        vertices_per_path,
        light_paths,
        two_stage_bytes: two_stage.ceil() as u64,
        memory_efficient_bytes: memory_efficient.ceil() as u64,
    }
}

/// An upper bound of [`MemoryEstimate::two_stage_bytes`] without a pilot: every light sub-path
/// stores at most `max_length − 1` vertices. When it fits, the pilot is not needed.
pub fn upper_bound(scene: &Scene, settings: &VcmSettings) -> u64 {
    let techniques = Techniques::of(settings.algorithm);
    let (full, merge) = vertex_sizes(settings);
    let merge = if techniques.merge { merge + GRID_BYTES_PER_VERTEX } else { 0 };
    let per_vertex = (2 * full + merge) as u64;
    scene.camera.pixel_count() as u64 * u64::from(settings.max_length.saturating_sub(1)) * per_vertex
}

/// Bytes of a stored light vertex and of its merging copy in the settings' spectral mode.
fn vertex_sizes(settings: &VcmSettings) -> (usize, usize) {
    if settings.spectral {
        (std::mem::size_of::<LightVertex<Hero4>>(), std::mem::size_of::<MergeVertex<Hero4>>())
    } else {
        (std::mem::size_of::<LightVertex<Rgb>>(), std::mem::size_of::<MergeVertex<Rgb>>())
    }
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
        assert!(e.two_stage_bytes > e.memory_efficient_bytes);
        assert!(upper_bound(&scene, &settings) >= e.two_stage_bytes);
        assert!(physical_memory().is_none_or(|m| m > 1 << 20));
    }
}
