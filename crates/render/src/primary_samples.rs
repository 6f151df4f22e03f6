//! Where the path tracer's first vertex takes its random numbers from: the camera path's
//! generator (independent samples), or the first [`math::sobol::DIMENSIONS`] dimensions of one
//! Sobol sequence, Owen-scrambled per pixel and indexed by the iteration ([`math::sobol`]), so
//! that over the iterations a pixel's light sample, BSDF sample, light pick, lobe choice and
//! roulette decisions at its first surface hit are stratified, jointly. Deeper vertices, the
//! raster position (or the splatting film's offset), the volumetric walk of scenes with media
//! and the other algorithms draw from the generator.
//!
//! Each number in one iteration is uniform over the keys (the render's seed), so every
//! iteration's estimate keeps the independent estimator's distribution and stays unbiased; and
//! all of a pixel's dimensions come from one sequence with one index, so they fill their joint
//! space together (an earlier version drew every pair from its own shuffle of a two-dimensional
//! sequence, and its renders stopped converging at 512²; docs/performance.md, "Stratified first
//! vertices"). `tests/primary_samples.rs` checks that each pixel converges. Iterations of one
//! pixel are not independent of each other: a variance image computed from their spread
//! over-estimates the variance of the mean. The tests that take their errors from that spread use
//! independent numbers; the sequence is tested against them with errors over independent renders
//! (`tests/primary_samples.rs`).

use math::sobol;

/// Vertices of a camera path (0: the first surface hit) whose numbers come from the sequence;
/// deeper vertices draw from the path's generator.
pub const STRATIFIED_VERTICES: u32 = 1;

/// How the path tracer draws the numbers of its first vertices (`--sampler`).
///
/// The engine's default ([`crate::RenderSettings`]) is [`PrimarySamples::Independent`]: every
/// iteration independent of the others, which the statistical tests that take their errors
/// from the spread of the iterations need. The front ends (`session::Request`: the command
/// line, Python, MPI ranks) default to [`PrimarySamples::Sobol`], which has less noise per
/// sample (docs/performance.md, "Stratified first vertices").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PrimarySamples {
    /// Every number from the camera path's own generator (independent iterations).
    #[default]
    Independent,
    /// The first surface hit's numbers from one Owen-scrambled Sobol sequence per pixel,
    /// indexed by the iteration ([`math::sobol`]).
    Sobol,
}

impl PrimarySamples {
    /// The option's name (`independent`, `sobol`).
    pub fn name(self) -> &'static str {
        match self {
            PrimarySamples::Independent => "independent",
            PrimarySamples::Sobol => "sobol",
        }
    }

    /// The value of a name given by [`PrimarySamples::name`].
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "independent" => Some(PrimarySamples::Independent),
            "sobol" => Some(PrimarySamples::Sobol),
            _ => None,
        }
    }
}

/// The numbers one vertex takes from the sequence.
#[derive(Clone, Copy, Debug)]
pub(crate) struct VertexDims {
    /// The light sample of next-event estimation.
    pub light: [f32; 2],
    /// The BSDF sample's direction (`u[0]`, `u[1]`).
    pub direction: [f32; 2],
    /// The light pick (first) and the BSDF's lobe choice `u[2]` (second).
    pub pick_and_lobe: [f32; 2],
    /// The albedo rule's continuation (first) and the throughput rule's survival (second).
    pub roulette: [f32; 2],
}

/// The numbers of one camera path: its pixel's key and the iteration, or nothing (independent).
#[derive(Clone, Copy, Debug)]
pub(crate) struct PathDims {
    sequence: Option<(u64, u32)>,
}

impl PathDims {
    /// Every number from the path's generator.
    pub(crate) const INDEPENDENT: PathDims = PathDims { sequence: None };

    /// The dimensions of pixel (or stream) `pixel`'s camera path in iteration `iteration` of the
    /// render with seed `seed`.
    pub(crate) fn new(samples: PrimarySamples, seed: u64, pixel: u64, iteration: u64) -> Self {
        match samples {
            PrimarySamples::Independent => Self::INDEPENDENT,
            // Iterations beyond 2³² wrap: the sequence restarts, each point still uniform.
            PrimarySamples::Sobol => PathDims { sequence: Some((sobol::key(seed, pixel), iteration as u32)) },
        }
    }

    /// The numbers of vertex `vertex` (0: the first surface hit), when it takes them from the
    /// sequence: eight dimensions of the pixel's sequence.
    #[inline]
    pub(crate) fn vertex(&self, vertex: u32) -> Option<VertexDims> {
        match self.sequence {
            Some((key, index)) if vertex < STRATIFIED_VERTICES => {
                // One Sobol sequence: each number its own dimension (module doc of math::sobol).
                let [l0, l1, d0, d1, pick, lobe, r0, r1] = sobol::point(index, key);
                Some(VertexDims {
                    light: [l0, l1],
                    direction: [d0, d1],
                    pick_and_lobe: [pick, lobe],
                    roulette: [r0, r1],
                })
            }
            _ => None,
        }
    }
}
