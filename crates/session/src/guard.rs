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
    /// It fits only with one iteration at a time ([`render::Parallelism::Pixels`]), not with the
    /// lanes asked for (each lane holds its own buffers).
    OneIterationAtATime,
    /// It fits only in the memory-efficient mode; the message says so with the numbers.
    SwitchToMemoryEfficient(String),
}

/// Checks the estimated peak memory (bytes; the process's resident memory now plus the
/// render's buffers, `lanes` sets of them when iterations run side by side) against `limit`
/// (default: half of the physical memory; no check when that is unknown). With more than one
/// lane, falls back to one iteration at a time when only that fits; then switches to the
/// memory-efficient mode when only that fits; fails with the numbers when nothing does.
pub fn check(scene: &Scene, settings: &VcmSettings, seed: u64, limit: Option<u64>, lanes: usize) -> Result<Guard> {
    let Some(limit) = limit.or_else(|| memory::physical_memory().map(|m| m / 2)) else {
        return Ok(Guard::Fits);
    };
    let resident = memory::resident_bytes().unwrap_or(0);
    let pixels = scene.camera.pixel_count();
    // Whether buffers of `one` bytes per lane fit with `lanes` lanes (one lane: `one` itself).
    let fits = |one, lanes| resident + memory::lanes_bytes(one, pixels, settings.film_variance, lanes) <= limit;
    let bound = memory::upper_bound(scene, settings);
    if fits(bound, lanes) {
        return Ok(Guard::Fits);
    }
    let estimate = memory::estimate(scene, settings, seed);
    if fits(estimate.two_stage_bytes, lanes) {
        return Ok(Guard::Fits);
    }
    if lanes > 1 && (fits(bound, 1) || fits(estimate.two_stage_bytes, 1)) {
        return Ok(Guard::OneIterationAtATime);
    }
    let (two_stage, efficient) = (resident + estimate.two_stage_bytes, resident + estimate.memory_efficient_bytes);
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

/// The guard's estimate (bytes) for `settings` as they will run with `lanes` iterations at a
/// time, the process's resident memory now included: the memory-efficient figure when that
/// mode is on, the two-stage one otherwise. Used by `vcm bench` to set the estimate beside the
/// measured peak.
pub fn estimate_bytes(scene: &Scene, settings: &VcmSettings, seed: u64, lanes: usize) -> u64 {
    let estimate = memory::estimate(scene, settings, seed);
    let resident = memory::resident_bytes().unwrap_or(0);
    let one = if settings.memory_efficient { estimate.memory_efficient_bytes } else { estimate.two_stage_bytes };
    resident + memory::lanes_bytes(one, scene.camera.pixel_count(), settings.film_variance, lanes)
}

#[cfg(test)]
mod tests {
    use super::*;
    use render::RenderSettings;

    #[test]
    fn lanes_fall_back_to_one_iteration_at_a_time_when_only_that_fits() {
        // 1024²: the second lane's buffers (about a hundred MB) dwarf what other tests of
        // this process allocate meanwhile, which moves the resident memory the guard reads.
        let scene = scene::cornell::build(273, 1024, 1024).unwrap();
        let vcm = Algorithm::from_name("vcm").unwrap();
        let settings = RenderSettings { algorithm: vcm, ..RenderSettings::default() }.vcm_settings().unwrap();
        let one = memory::estimate(&scene, &settings, 0).two_stage_bytes;
        let two = memory::lanes_bytes(one, scene.camera.pixel_count(), settings.film_variance, 2);
        // Only the film's sums are shared.
        let shared = 24 * scene.camera.pixel_count() as u64 * if settings.film_variance { 2 } else { 1 };
        assert_eq!(two, 2 * one - shared);
        let resident = memory::resident_bytes().unwrap_or(0);
        let between = Some(resident + (one + two) / 2);
        assert_eq!(check(&scene, &settings, 0, between, 2).unwrap(), Guard::OneIterationAtATime);
        assert_eq!(check(&scene, &settings, 0, between, 1).unwrap(), Guard::Fits);
        assert_eq!(check(&scene, &settings, 0, Some(resident + two + one / 4), 2).unwrap(), Guard::Fits);
        // Too little for one lane: what the guard decides without lanes (here an error).
        let tight = Some(resident + one / 2);
        // (Not the errors' texts: they hold the resident memory of the moment, which other tests
        // of this process move between the two calls.)
        let decide = |lanes| check(&scene, &settings, 0, tight, lanes).map_err(|_| ());
        assert_eq!(decide(1), Err(()));
        assert_eq!(decide(2), decide(1));
    }
}
