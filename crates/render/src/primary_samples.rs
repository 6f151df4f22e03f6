//! Where the path tracer's first vertices take their random numbers from: the camera path's
//! generator (independent samples), or a randomised (0,2)-sequence per pixel and dimension pair,
//! indexed by the iteration ([`math::sobol02`]), so that over the iterations a pixel's raster
//! position (its film offset when splatting, shared by all pixels of an iteration), light
//! samples, BSDF samples and roulette decisions at its first [`STRATIFIED_VERTICES`] vertices
//! are stratified. Deeper vertices, and the volumetric walk of scenes with media, draw from the
//! generator.
//!
//! Each pair's point in one iteration is uniform over the keys (the render's seed), so every
//! iteration's estimate keeps the independent estimator's distribution and stays unbiased; what
//! changes is that iterations of one pixel are no longer independent of each other: they are
//! negatively correlated, and a variance image computed from their spread over-estimates the
//! variance of the mean (as for the spectral wavelength sequence, [`crate::wavelength_sequence`]).
//! The tests that take their errors from that spread use independent numbers; the sequence is
//! tested against them with errors over independent renders (`tests/primary_samples.rs`).
//!
//! Each vertex's four pairs come from the same sequence under different keys. Its index shuffle
//! keeps every power-of-two prefix stratified, and so (like any such nested shuffle, measured
//! with a true nested scramble too) it does not decorrelate two pairs as fully as independent
//! random permutations of the samples would: for a product of one coordinate of each of two
//! pairs, the variance of a 64-sample mean is about 1.6× that of independent samples (0.64×
//! for the product of two indicators of a half, 0.18× for a disc in one pair; 1.0×, 0.32× and
//! 0.17× with random permutations). What the path tracer gains from the pairs' own
//! stratification outweighs this on every scene measured (docs/performance.md, "Stratified
//! first vertices").

use math::sobol02::{self, SequenceIndex};

/// Vertices of a camera path (0: the first surface hit) whose numbers come from the sequence;
/// deeper vertices draw from the path's generator.
pub const STRATIFIED_VERTICES: u32 = 2;

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
    /// The first vertices' numbers from a randomised (0,2)-sequence per pixel and dimension pair.
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
    sequence: Option<(u64, SequenceIndex)>,
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
            PrimarySamples::Sobol => {
                PathDims { sequence: Some((sobol02::key(seed, pixel, 0), SequenceIndex::new(iteration as u32))) }
            }
        }
    }

    /// The raster position's two numbers (film modes that place each pixel's sample on its
    /// own, [`scene::Camera::sample_primary_with`]), when they come from the sequence.
    #[inline]
    pub(crate) fn raster(&self) -> Option<[f32; 2]> {
        self.sequence.map(|(key, index)| index.point(key))
    }

    /// The numbers of vertex `vertex` (0: the first surface hit), when it takes them from the
    /// sequence: four dimension pairs, each keyed apart.
    #[inline]
    pub(crate) fn vertex(&self, vertex: u32) -> Option<VertexDims> {
        match self.sequence {
            Some((key, index)) if vertex < STRATIFIED_VERTICES => {
                let pair = |slot: u32| index.point(key ^ u64::from(4 * vertex + slot + 1));
                Some(VertexDims { light: pair(0), direction: pair(1), pick_and_lobe: pair(2), roulette: pair(3) })
            }
            _ => None,
        }
    }
}

/// The film offset of iteration `iteration` ([`crate::splat_frame::film_offset`]'s role) from
/// the sequence: one pair for the whole image, keyed by the seed alone.
pub(crate) fn film_offset(seed: u64, iteration: u64) -> [f32; 2] {
    sobol02::point(iteration as u32, sobol02::key(seed, u64::MAX, 0))
}
