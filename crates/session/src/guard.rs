//! The memory guard: the render's peak memory — what the process holds already (program, scene,
//! BVH) plus the buffers of the film and the VCM engine ([`render::vcm::memory`]) — is estimated
//! before rendering and compared with a limit.

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

/// Checks the estimated peak memory (bytes; the process's resident memory now plus the
/// render's buffers) against `limit` (default: half of the physical memory; no check when that
/// is unknown). Switches to the memory-efficient mode when only that fits; fails with the
/// numbers when neither does.
pub fn check(scene: &Scene, settings: &VcmSettings, seed: u64, limit: Option<u64>) -> Result<Guard> {
    let Some(limit) = limit.or_else(|| memory::physical_memory().map(|m| m / 2)) else {
        return Ok(Guard::Fits);
    };
    let resident = memory::resident_bytes().unwrap_or(0);
    if resident + memory::upper_bound(scene, settings) <= limit {
        return Ok(Guard::Fits);
    }
    let estimate = memory::estimate(scene, settings, seed);
    let (two_stage, efficient) = (resident + estimate.two_stage_bytes, resident + estimate.memory_efficient_bytes);
    if two_stage <= limit {
        return Ok(Guard::Fits);
    }
    let need = format!(
        "{} light sub-paths x {:.2} stored vertices each need about {} at the peak",
        estimate.light_paths,
        estimate.vertices_per_path,
        format_size(two_stage)
    );
    if efficient <= limit && efficient < two_stage {
        return Ok(Guard::SwitchToMemoryEfficient(format!(
            "{need}, more than --max-memory {}; switching to --memory-efficient (about {}, the same image)",
            format_size(limit),
            format_size(efficient)
        )));
    }
    bail!(
        "{need} ({} in the memory-efficient mode), more than --max-memory {} for {}: lower the resolution or \
         --max-length, or raise --max-memory",
        format_size(efficient),
        format_size(limit),
        Algorithm::Vcm(settings.algorithm).name()
    )
}

/// The guard's estimate (bytes) for `settings` as they will run, the process's resident memory
/// now included: the memory-efficient figure when that mode is on, the two-stage one
/// otherwise. Used by `vcm bench` to set the estimate beside the measured peak.
pub fn estimate_bytes(scene: &Scene, settings: &VcmSettings, seed: u64) -> u64 {
    let estimate = memory::estimate(scene, settings, seed);
    let resident = memory::resident_bytes().unwrap_or(0);
    resident + if settings.memory_efficient { estimate.memory_efficient_bytes } else { estimate.two_stage_bytes }
}
