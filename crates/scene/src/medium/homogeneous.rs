//! Distance sampling and transmittance in a homogeneous medium, for chromatic coefficients.
//!
//! Transmittance over a distance `d` is Beer–Lambert's `T(d) = exp(−σ_t d)` per channel. Free
//! flights are sampled with **path-level spectral MIS**: a path picks one channel `c` uniformly
//! among the [`SpectralMode::CHANNELS`] and samples all its distances with `σ_t,c`; the path's
//! contribution `f` is divided by the *average* over the channels `j` of the densities `p_j`
//! with which channel `j` would have sampled the same distances (the balance heuristic over the
//! channel choice; the scheme of Mitsuba 3's `volpathmis` and pbrt-v4's rescaled path
//! probabilities). Every channel then stays unbiased and its weight is at most `n` times its own
//! single-channel weight (a product of albedos), so chromatic media give no colour noise
//! blow-up.
//!
//! Numerically, the caller keeps the normalised ratios `q_j = p_j / mean(p)` (all 1 at the
//! start of a path). An event with per-channel factor `g` and densities `d_j` multiplies the
//! estimate by `g / mean(q ⊙ d)` and maps `q ← q ⊙ d / mean(q ⊙ d)`:
//!
//! - scattering at `t < t_max`: `g = σ_s e^{−σ_t t}`, `d = σ_t e^{−σ_t t}` (per unit length);
//! - passing to `t_max` (the next surface, possibly at infinity): `g = d = e^{−σ_t t_max}`.

use spectrum::SpectralMode;

/// Beer–Lambert transmittance `exp(−σ_t d)` per channel (`d` in scene units, may be
/// infinite; a channel with `σ_t = 0` transmits 1 at any distance).
#[inline]
pub fn transmittance<S: SpectralMode>(sigma_t: S, distance: f32) -> S {
    sigma_t.map(|s| if s <= 0.0 { 1.0 } else { (-s * distance).exp() })
}

/// The outcome of distance sampling along a ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DistanceSample<S> {
    /// Distance to the sampled point along the ray (scene units): `t < t_max` when the ray
    /// scattered in the medium, `t_max` otherwise.
    pub distance: f32,
    /// Whether a scattering event was sampled before `t_max`.
    pub scattered: bool,
    /// The factor on the path's estimate (unitless): `g / mean(q ⊙ d)` (module documentation).
    pub weight: S,
}

/// Samples a free-flight distance along a ray inside the medium with extinction `sigma_t` and
/// scattering `sigma_s` (per scene unit), up to `t_max` (the next surface; may be infinite),
/// with the path's channel `channel` (< [`SpectralMode::CHANNELS`]) and `u_distance ∈ [0,1)`.
/// `ratios` holds the path's normalised channel density ratios `q` and is updated.
#[inline]
pub fn sample_distance<S: SpectralMode>(
    sigma_t: S,
    sigma_s: S,
    t_max: f32,
    channel: usize,
    u_distance: f32,
    ratios: &mut S,
) -> DistanceSample<S> {
    let sigma = sigma_t.channel(channel.min(S::CHANNELS - 1));
    let t = if sigma > 0.0 { -(1.0 - u_distance).ln() / sigma } else { f32::INFINITY };
    let scattered = t < t_max;
    let distance = if scattered { t } else { t_max };
    let transmitted = transmittance(sigma_t, distance);
    let (factor, density) =
        if scattered { (sigma_s * transmitted, sigma_t * transmitted) } else { (transmitted, transmitted) };
    let weighted = *ratios * density;
    let mean = (0..S::CHANNELS).map(|c| weighted.channel(c)).sum::<f32>() / S::CHANNELS as f32;
    // (Zero only when every density underflowed: the path carries nothing.)
    if !(mean > 0.0 && mean.is_finite()) {
        return DistanceSample { distance, scattered, weight: S::default() };
    }
    *ratios = weighted * (1.0 / mean);
    DistanceSample { distance, scattered, weight: factor * (1.0 / mean) }
}
