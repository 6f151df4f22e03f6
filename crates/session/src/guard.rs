//! The memory guard: the VCM engine's light-vertex and merging-grid memory is estimated before
//! rendering and compared with a limit.

use anyhow::{Result, bail};
use render::Algorithm;
use render::vcm::VcmSettings;
use render::vcm::memory::{self, format_size};
use scene::Scene;

/// What the guard decided.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Guard {
    /// The render fits as asked.
    Fits,
    /// It fits only in the memory-efficient mode; the message says so with the numbers.
    SwitchToMemoryEfficient(String),
}

/// Checks the estimated memory (bytes) of the engine's buffers against `limit` (default: half
/// of the physical memory; no check when that is unknown). Fails with the numbers when even
/// the memory-efficient mode does not fit (or, in spectral mode with merging, cannot be used).
pub fn check(scene: &Scene, settings: &VcmSettings, seed: u64, limit: Option<u64>) -> Result<Guard> {
    let Some(limit) = limit.or_else(|| memory::physical_memory().map(|m| m / 2)) else {
        return Ok(Guard::Fits);
    };
    if memory::upper_bound(scene, settings) <= limit {
        return Ok(Guard::Fits);
    }
    let estimate = memory::estimate(scene, settings, seed);
    if estimate.two_stage_bytes <= limit {
        return Ok(Guard::Fits);
    }
    let need = format!(
        "{} light sub-paths x {:.2} stored vertices each need about {}",
        estimate.light_paths,
        estimate.vertices_per_path,
        format_size(estimate.two_stage_bytes)
    );
    if settings.spectral && render::vcm::Techniques::of(settings.algorithm).merge {
        bail!(
            "{need}, more than --max-memory {}; spectral mode cannot switch to --memory-efficient with {} \
             (its merges would pair different wavelengths): lower the resolution or --max-length, or raise \
             --max-memory",
            format_size(limit),
            Algorithm::Vcm(settings.algorithm).name()
        );
    }
    if estimate.memory_efficient_bytes <= limit {
        return Ok(Guard::SwitchToMemoryEfficient(format!(
            "{need}, more than --max-memory {}; switching to --memory-efficient (about {})",
            format_size(limit),
            format_size(estimate.memory_efficient_bytes)
        )));
    }
    bail!(
        "{need} ({} in the memory-efficient mode), more than --max-memory {}: lower the resolution or \
         --max-length, or raise --max-memory",
        format_size(estimate.memory_efficient_bytes),
        format_size(limit)
    )
}

/// The guard's estimate (bytes) for `settings` as they will run: the memory-efficient figure
/// when that mode is on, the two-stage one otherwise. Used by `vcm bench` to set the estimate
/// beside the measured peak.
pub fn estimate_bytes(scene: &Scene, settings: &VcmSettings, seed: u64) -> u64 {
    let estimate = memory::estimate(scene, settings, seed);
    if settings.memory_efficient { estimate.memory_efficient_bytes } else { estimate.two_stage_bytes }
}
