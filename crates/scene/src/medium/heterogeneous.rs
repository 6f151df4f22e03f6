//! Heterogeneous media: delta tracking for free flights and ratio tracking for transmittance,
//! against a grey (channel-independent) majorant, with the path-level spectral MIS of
//! [`super::homogeneous`].
//!
//! **Coefficients.** `σ_t(p) = scale · sigma_t(p)` and `σ_s(p) = σ_t(p) · albedo(p)` (albedo
//! clamped to [0, 1]), both [`Volume`]s (or `σ_s(p) = scale · sigma_s(p)` when given directly), inside `region` (a box; Mitsuba's medium lives in
//! the `sigma_t` volume's bounding box, pbrt-v4's grid in `p0`–`p1`); outside it the medium is
//! empty. The majorant `σ̄ = scale · grid bound · max_j value_j` bounds `σ_t` in every channel.
//!
//! **Null-scattering formulation** (Miller, Georgiev and Jarosz 2019, "A null-scattering path
//! integral formulation of light transport"): with `σ_n = σ̄ − σ_t`, tentative
//! collisions are sampled with density `σ̄ e^{−σ̄ t}`, the same for every channel. At a
//! collision at `x` the path's channel `c` takes a real scattering event with probability
//! `σ_t,c(x) / σ̄` and a null event otherwise; a channel `j` would have taken the same event
//! with probability `σ_t,j / σ̄` or `σ_n,j / σ̄`. The path contribution of the event is
//! `T̄ σ_s(x)` (real) or `T̄ σ_n(x)` (null), its density under channel `j` `T̄ σ_t,j(x)` or
//! `T̄ σ_n,j(x)`: the common `T̄ = e^{−σ̄ t}` cancels and each event is one factor `g` with
//! densities `d` in the scheme of [`super::homogeneous`] (balance heuristic over the channel,
//! `g / mean(q ⊙ d)`, `q ← q ⊙ d / mean(q ⊙ d)`): real `g = σ_s(x)`, `d = σ_t(x)`; null
//! `g = d = σ_n(x)`. Passing the end of the segment has `g = d = T̄`, the same in every
//! channel, and changes nothing. For a grey `σ_t` (one-channel density grid) every null
//! event has weight 1 and a real event the albedo: plain delta tracking (Woodcock et al.
//! 1965).
//!
//! **Majorant grid** ([`super::majorant`]): with a gridded σ_t, tentative collisions are sampled
//! cell by cell of a coarse grid with each cell's (grey) majorant instead of the global one;
//! everything above holds per cell.
//!
//! **Ratio tracking** (Novák, Selle and Jarosz 2014, "Residual ratio tracking for estimating attenuation in participating media"): the transmittance along a segment
//! is estimated by the product `Π (1 − σ_t(x_i) / σ̄)` over the tentative collisions `x_i`,
//! unbiased per channel (the collisions do not depend on the channel).

use glam::{Affine3A, Vec3};
use math::Rng;
use spectrum::{Rgb, SpectralMode};

use std::sync::Arc;

use super::DistanceSample;
use super::grid::Volume;
use super::majorant::MajorantGrid;

/// The spatially varying coefficients of a heterogeneous medium.
#[derive(Clone, Debug, PartialEq)]
pub struct Heterogeneous {
    /// Extinction σ_t per scene unit before the medium's `scale`.
    pub sigma_t: Volume,
    /// Single-scattering albedo in [0, 1] (unused when `sigma_s` is given).
    pub albedo: Volume,
    /// Scattering σ_s per scene unit before `scale`, when given directly (pbrt-v4's
    /// `rgbgrid`); the builder keeps it at most `sigma_t` everywhere (e.g. `sigma_t` holds
    /// `σ_a + σ_s` voxel by voxel: interpolation is linear).
    pub sigma_s: Option<Volume>,
    /// World → the unit cube of the box the medium fills (empty outside).
    pub region: Affine3A,
    /// Per-cell majorants of `sigma_t` over the region (built by [`Heterogeneous::new`]).
    majorants: Option<Arc<MajorantGrid>>,
}

/// A heterogeneous medium prepared for a path's wavelengths.
#[derive(Clone, Copy, Debug)]
pub struct Tracker<'a, S: SpectralMode> {
    medium: &'a Heterogeneous,
    /// `scale · sigma_t.value` at the wavelengths.
    sigma_t_tint: S,
    /// `albedo.value` at the wavelengths, or `scale · sigma_s.value`.
    albedo_tint: S,
    /// σ̄, per scene unit.
    majorant: f32,
    /// The largest channel of `sigma_t_tint`.
    tint_max: f32,
    /// The RGB basis at the wavelengths, negative parts removed (3-channel grids).
    basis: [S; 3],
}

/// The majorant along a ray interval ([`Tracker::majorant_profile`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MajorantProfile {
    /// `∫ μ` over the interval (unitless optical depth).
    pub depth: f32,
    /// `μ` at the interval's start (per scene unit; 0 outside the region).
    pub at_start: f32,
    /// `μ` at the interval's end (per scene unit; 0 outside the region).
    pub at_end: f32,
}

impl MajorantProfile {
    /// The profile of an interval outside the region: no depth, `μ = 0` at both ends.
    pub const ZERO: MajorantProfile = MajorantProfile { depth: 0.0, at_start: 0.0, at_end: 0.0 };
}

/// A [`MajorantProfile`] being summed stretch by stretch along a ray.
#[derive(Clone, Copy, Debug, Default)]
struct ProfileSum {
    /// `∫ μ` over the non-empty stretches so far (unitless).
    depth: f32,
    /// `μ` of the first non-empty stretch (per scene unit).
    first: Option<f32>,
    /// `μ` of the last non-empty stretch (per scene unit).
    last: f32,
}

impl ProfileSum {
    /// Adds the stretch `[s0, s1]` of majorant `majorant` (skipped when empty).
    #[inline]
    fn add(&mut self, s0: f32, s1: f32, majorant: f32) {
        if s1 > s0 {
            self.depth += (s1 - s0) * majorant;
            self.first.get_or_insert(majorant);
            self.last = majorant;
        }
    }

    /// The profile, with `μ` at the start (end) when the summed stretches reach the
    /// interval's start (end) rather than a face of the region.
    fn profile(self, reaches_start: bool, reaches_end: bool) -> MajorantProfile {
        MajorantProfile {
            depth: self.depth,
            at_start: if reaches_start { self.first.unwrap_or(0.0) } else { 0.0 },
            at_end: if reaches_end { self.last } else { 0.0 },
        }
    }
}

impl Heterogeneous {
    /// A medium with σ_t `sigma_t`, albedo `albedo` (or scattering `sigma_s`) filling the box
    /// whose unit cube is `region` of world space; builds the majorant grid of a gridded σ_t.
    pub fn new(sigma_t: Volume, albedo: Volume, sigma_s: Option<Volume>, region: Affine3A) -> Self {
        let majorants = MajorantGrid::new(&sigma_t, region).map(Arc::new);
        Self { sigma_t, albedo, sigma_s, region, majorants }
    }

    /// The same medium sampled with its global majorant only (no majorant grid), for tests.
    pub fn without_majorant_grid(mut self) -> Self {
        self.majorants = None;
        self
    }

    /// The medium at the wavelengths `w`, with the medium's `scale`.
    pub fn tracker<'a, S: SpectralMode>(&'a self, scale: f32, w: &S::Wavelengths) -> Tracker<'a, S> {
        let sigma_t_tint = self.sigma_t.value.eval::<S>(w, false) * scale;
        let albedo_tint = match &self.sigma_s {
            Some(sigma_s) => sigma_s.value.eval::<S>(w, false) * scale,
            None => self.albedo.value.eval::<S>(w, true),
        };
        let value_max = (0..S::CHANNELS).map(|c| sigma_t_tint.channel(c)).fold(0.0, f32::max);
        let majorant = value_max * self.sigma_t.grid_bound::<S>(w);
        let basis = [(1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)]
            .map(|(r, g, b)| S::from_reflectance(w, spectrum::Rgb::new(r, g, b)).map(|v| v.max(0.0)));
        Tracker { medium: self, sigma_t_tint, albedo_tint, majorant, tint_max: value_max, basis }
    }

    /// The largest albedo over space and the RGB channels (unitless).
    pub fn max_albedo(&self) -> f32 {
        if self.sigma_s.is_some() {
            return 1.0;
        }
        let tint = self.albedo.value.eval::<spectrum::Rgb>(&(), true).max_component();
        (tint * self.albedo.grid_bound::<spectrum::Rgb>(&())).min(1.0)
    }

    /// The world-space box of the region (for checks and documentation).
    pub fn region_bounds(&self) -> (Vec3, Vec3) {
        super::grid::Volume::constant(super::Coefficient::rgb(spectrum::Rgb::splat(1.0)), self.region).world_bounds()
    }
}

impl<S: SpectralMode> Tracker<'_, S> {
    /// The majorant σ̄ (per scene unit).
    pub fn majorant(&self) -> f32 {
        self.majorant
    }

    /// σ_t and σ_s at world point `p` (per scene unit; zero outside the region).
    #[inline]
    pub fn coefficients(&self, p: Vec3, w: &S::Wavelengths) -> (S, S) {
        if !self.inside(p) {
            return (S::default(), S::default());
        }
        let sigma_t = self.clamp_extinction(self.medium.sigma_t.eval::<S>(p, w, self.sigma_t_tint));
        (sigma_t, self.scattering_inside(p, w, sigma_t))
    }

    /// σ_t at world point `p` (per scene unit; zero outside the region): the first of
    /// [`Tracker::coefficients`] without looking up the albedo.
    #[inline]
    pub fn extinction(&self, p: Vec3, w: &S::Wavelengths) -> S {
        if !self.inside(p) {
            return S::default();
        }
        self.clamp_extinction(self.medium.sigma_t.eval::<S>(p, w, self.sigma_t_tint))
    }

    /// σ_t at world point `p` (per scene unit; zero outside the region) at the wavelengths `w`
    /// and in linear sRGB from one lookup of the σ_t grid: the [`Tracker::extinction`] of this
    /// tracker and of `rgb`, which must be this medium's RGB tracker with the same scale.
    #[inline]
    pub fn extinction_with_rgb(&self, rgb: &Tracker<'_, Rgb>, p: Vec3, w: &S::Wavelengths) -> (S, Rgb) {
        debug_assert!(std::ptr::eq(self.medium, rgb.medium), "the RGB tracker of another medium");
        if !self.inside(p) {
            return (S::default(), Rgb::default());
        }
        let (sigma_t, sigma_t_rgb) = self.medium.sigma_t.eval_with_rgb::<S>(p, w, self.sigma_t_tint, rgb.sigma_t_tint);
        (self.clamp_extinction(sigma_t), rgb.clamp_extinction(sigma_t_rgb))
    }

    /// σ_s at world point `p` (per scene unit; zero outside the region) given `sigma_t`, this
    /// tracker's σ_t there ([`Tracker::extinction`]): the second of [`Tracker::coefficients`].
    #[inline]
    pub fn scattering(&self, p: Vec3, w: &S::Wavelengths, sigma_t: S) -> S {
        if !self.inside(p) {
            return S::default();
        }
        self.scattering_inside(p, w, sigma_t)
    }

    /// Whether world point `p` lies in the region (the medium is empty outside it).
    #[inline]
    fn inside(&self, p: Vec3) -> bool {
        let local = self.medium.region.transform_point3(p);
        local.cmpge(Vec3::ZERO).all() && local.cmple(Vec3::ONE).all()
    }

    /// A looked-up σ_t clamped to `[0, σ̄]`.
    #[inline]
    fn clamp_extinction(&self, sigma_t: S) -> S {
        sigma_t.map(|v| v.clamp(0.0, self.majorant))
    }

    /// σ_s at `p` inside the region, where σ_t is `sigma_t`.
    #[inline]
    fn scattering_inside(&self, p: Vec3, w: &S::Wavelengths, sigma_t: S) -> S {
        if let Some(sigma_s) = &self.medium.sigma_s {
            return sigma_s.eval::<S>(p, w, self.albedo_tint).map(|v| v.max(0.0));
        }
        let albedo = self.medium.albedo.eval::<S>(p, w, self.albedo_tint).map(|a| a.clamp(0.0, 1.0));
        sigma_t * albedo
    }

    /// The parameter interval `[t0, t1]` of the ray `origin + t·direction`, `0 ≤ t ≤ t_max`,
    /// inside the region, `None` when it misses (slab test in the region's unit cube; the
    /// affine map keeps the ray parameter).
    fn clip(&self, origin: Vec3, direction: Vec3, t_max: f32) -> Option<(f32, f32)> {
        let o = self.medium.region.transform_point3(origin);
        let d = self.medium.region.transform_vector3(direction);
        let (mut t0, mut t1) = (0.0f32, t_max);
        for a in 0..3 {
            if d[a] == 0.0 {
                if !(0.0..=1.0).contains(&o[a]) {
                    return None;
                }
                continue;
            }
            let (a0, a1) = ((0.0 - o[a]) / d[a], (1.0 - o[a]) / d[a]);
            t0 = t0.max(a0.min(a1));
            t1 = t1.min(a0.max(a1));
        }
        (t0 < t1 && self.majorant > 0.0).then_some((t0, t1))
    }

    /// The majorant (per scene unit) of a majorant-grid cell with per-channel grid maxima `max`
    /// (the bound of [`Volume::grid_bound`] applied to the cell), at most the global one.
    #[inline]
    fn cell_majorant(&self, max: spectrum::Rgb) -> f32 {
        let grid_bound = if self.medium.sigma_t.grid.as_ref().is_some_and(|g| g.channels() == 1) {
            max.r
        } else {
            let b = self.basis[0] * max.r + self.basis[1] * max.g + self.basis[2] * max.b;
            (0..S::CHANNELS).map(|c| b.channel(c)).fold(0.0, f32::max)
        };
        (self.tint_max * grid_bound).min(self.majorant)
    }

    /// Calls `visit(t0, t1, σ̄)` for the stretches of `[t0, t1]` along the ray with a constant
    /// majorant: the cells of the majorant grid, or the whole interval with the global one.
    fn stretches(&self, origin: Vec3, direction: Vec3, t0: f32, t1: f32, mut visit: impl FnMut(f32, f32, f32) -> bool) {
        match &self.medium.majorants {
            Some(grid) => grid
                .walk(&self.medium.region, origin, direction, t0, t1, |s| visit(s.t0, s.t1, self.cell_majorant(s.max))),
            None => {
                visit(t0, t1, self.majorant);
            }
        }
    }

    /// The part `[t0, t1]` of the ray interval `[t_start, t_end]` inside the region (see
    /// [`Tracker::clip`]), `None` when it is empty.
    fn span(&self, origin: Vec3, direction: Vec3, t_start: f32, t_end: f32) -> Option<(f32, f32)> {
        let (t0, t1) = self.clip(origin, direction, t_end)?;
        let t0 = t0.max(t_start);
        (t0 < t1).then_some((t0, t1))
    }

    /// The tentative collisions along `[t0, t1]`: a Poisson process at each stretch's majorant
    /// (free flights `−ln(1 − u) / majorant` drawn from `rng`), visited in order as
    /// `visit(t, majorant, rng)` until it returns false. Delta and ratio tracking differ only
    /// in what they do at a collision. Returns the majorant of the stretches walked, up to the
    /// collision where `visit` stopped (its distance the second value) or to `t1`.
    fn collisions(
        &self,
        origin: Vec3,
        direction: Vec3,
        t0: f32,
        t1: f32,
        rng: &mut Rng,
        mut visit: impl FnMut(f32, f32, &mut Rng) -> bool,
    ) -> (ProfileSum, Option<f32>) {
        let mut sum = ProfileSum::default();
        let mut stop = None;
        self.stretches(origin, direction, t0, t1, |start, end, majorant| {
            if majorant > 0.0 {
                let mut t = start;
                loop {
                    t -= (1.0 - rng.uniform()).ln() / majorant;
                    if t >= end {
                        break;
                    }
                    if !visit(t, majorant, rng) {
                        sum.add(start, t, majorant);
                        stop = Some(t);
                        return false;
                    }
                }
            }
            sum.add(start, end, majorant);
            true
        });
        (sum, stop)
    }

    /// The piecewise-constant majorant `μ` (per scene unit) along the ray from `origin` along
    /// unit `direction` over `[t_start, t_end]` (`t_end` may be infinite): the stretches of the
    /// majorant grid, or the global majorant without one, and 0 outside the region. Returns
    /// its integral `∫ μ` over the interval (unitless optical depth) and `μ` at the two ends.
    /// Deterministic: it draws no random numbers (the VCM engine's surrogate free-flight
    /// densities are built from it).
    pub fn majorant_profile(&self, origin: Vec3, direction: Vec3, t_start: f32, t_end: f32) -> MajorantProfile {
        let Some((t0, t1)) = self.span(origin, direction, t_start, t_end) else { return MajorantProfile::ZERO };
        let mut sum = ProfileSum::default();
        self.stretches(origin, direction, t0, t1, |s0, s1, majorant| {
            sum.add(s0, s1, majorant);
            true
        });
        sum.profile(t0 <= t_start, t1 >= t_end)
    }

    /// The tentative collisions of the piecewise-constant majorant (see
    /// [`Tracker::majorant_profile`]) along the ray from `origin` along unit `direction` over
    /// `[t_start, t_end]`, in order: `visit(t, μ, rng)` with the distance `t` from `origin` and
    /// the local majorant `μ` (per scene unit), until it returns false. Free flights
    /// `−ln(1 − u) / μ` are drawn from `rng`. Returns the walk's [`Tracker::majorant_profile`]
    /// over `[t_start, t]`, `t` the collision where `visit` stopped, or over `[t_start, t_end]`
    /// when it never did (bit for bit: the same stretches summed in the same order).
    pub fn tentative_collisions(
        &self,
        origin: Vec3,
        direction: Vec3,
        t_start: f32,
        t_end: f32,
        rng: &mut Rng,
        visit: impl FnMut(f32, f32, &mut Rng) -> bool,
    ) -> MajorantProfile {
        let Some((t0, t1)) = self.span(origin, direction, t_start, t_end) else { return MajorantProfile::ZERO };
        let (sum, stop) = self.collisions(origin, direction, t0, t1, rng, visit);
        match stop {
            // `majorant_profile` over `[t_start, t]` clips the region to end at `t` (< t1);
            // a collision at `t0` itself leaves that interval empty.
            Some(t) if t <= t0 => MajorantProfile::ZERO,
            Some(_) => sum.profile(t0 <= t_start, true),
            None => sum.profile(t0 <= t_start, t1 >= t_end),
        }
    }

    /// Delta tracking along the ray from `origin` along unit `direction` up to `t_max` (may be
    /// infinite) with the path's channel `channel` and density ratios `ratios` (updated);
    /// module documentation. The distance is from `origin`.
    #[allow(clippy::too_many_arguments)]
    pub fn sample_distance(
        &self,
        origin: Vec3,
        direction: Vec3,
        t_max: f32,
        channel: usize,
        rng: &mut Rng,
        ratios: &mut S,
        w: &S::Wavelengths,
    ) -> DistanceSample<S> {
        let channel = channel.min(S::CHANNELS - 1);
        let mut weight = S::splat(1.0);
        let Some((t0, t1)) = self.clip(origin, direction, t_max) else {
            return DistanceSample { distance: t_max, scattered: false, weight };
        };
        let mut outcome = None;
        self.collisions(origin, direction, t0, t1, rng, |t, majorant, rng| {
            let (sigma_t, sigma_s) = self.coefficients(origin + t * direction, w);
            let sigma_t = sigma_t.map(|s| s.min(majorant));
            let real = rng.uniform() * majorant < sigma_t.channel(channel);
            let (g, d) = if real {
                (sigma_s, sigma_t)
            } else {
                let sigma_n = sigma_t.map(|s| majorant - s);
                (sigma_n, sigma_n)
            };
            let weighted = *ratios * d;
            let mean = (0..S::CHANNELS).map(|c| weighted.channel(c)).sum::<f32>() / S::CHANNELS as f32;
            if !(mean > 0.0 && mean.is_finite()) {
                outcome = Some(DistanceSample { distance: t, scattered: real, weight: S::default() });
                return false;
            }
            *ratios = weighted * (1.0 / mean);
            weight *= g * (1.0 / mean);
            if real {
                outcome = Some(DistanceSample { distance: t, scattered: true, weight });
                return false;
            }
            true
        });
        outcome.unwrap_or(DistanceSample { distance: t_max, scattered: false, weight })
    }

    /// Ratio-tracking estimate of the transmittance (per channel, unitless) of the segment from
    /// `origin` along unit `direction` over `[t_min, t_max]` (module documentation).
    pub fn transmittance(
        &self,
        origin: Vec3,
        direction: Vec3,
        t_min: f32,
        t_max: f32,
        rng: &mut Rng,
        w: &S::Wavelengths,
    ) -> S {
        let mut carried = S::splat(1.0);
        let Some((t0, t1)) = self.span(origin, direction, t_min, t_max) else { return carried };
        self.collisions(origin, direction, t0, t1, rng, |t, majorant, _| {
            let sigma_t = self.extinction(origin + t * direction, w);
            carried *= sigma_t.map(|s| 1.0 - s.min(majorant) / majorant);
            !carried.is_black()
        });
        carried
    }
}
