//! The stochastic estimate of a layered BSDF's value by pbrt-v4's random walk (the book's
//! section 14.3, "Layered BxDFs"): a dielectric top interface, a medium of depth `thickness`
//! (unit extinction, single-scattering albedo `albedo`, Henyey–Greenstein phase function) and
//! an opaque base, for reflection with both directions above the surface.
//!
//! The walk enters through the top with a transmission sample for `wo`, presamples a
//! transmission for `wi` (the "virtual light"), bounces between the interfaces (and scatters
//! in the medium when `albedo > 0`), and adds next-event estimates through the top towards
//! `wi` at every vertex, weighted by the power heuristic where both the vertex's sampler and
//! the top's can produce the connection. At most `max_depth` interface or medium events per
//! walk, Russian roulette after four, `samples` walks averaged. The top's own reflection is
//! *not* included: the caller adds it exactly.
//!
//! The random numbers come from a generator seeded by hashing `wo` and `wi` (as pbrt does), so
//! the estimate is a deterministic function of the pair: every technique that evaluates the
//! same pair gets the same number. It is an unbiased estimate of pbrt's layered BSDF (whose
//! expectation stops at `max_depth` events).
//!
//! **One deliberate difference from pbrt-v4.** A direction `y` inside the layer that leaves
//! towards `wi` is produced by two strategies: the presampled exit (density `p_top(wi → y)`)
//! and a bounce at a vertex (density `p_vertex`). pbrt weighs the bounce with the power
//! heuristic against `p_top(y → wi)`, the density of sampling `wi` from `y`, which is not the
//! density of the competing strategy; the two weights of one `y` then do not sum to one, and
//! pbrt's estimate under a rough interface is biased and not reciprocal (measured on a rough
//! diffuse coating: 6–8 % too bright, and 2 % apart between the two orders of a pair;
//! `walk_weights_of_pbrt_are_biased_under_a_rough_top` in `coated_tests.rs`). We weigh the
//! bounce against `p_top(wi → y)`, which makes the two weights sum to one. Under a smooth
//! interface the two agree (no bounce leaves through a specular interface).
//!
//! **A second one.** Between a smooth top and a smooth conductor, pbrt's walk connects a
//! scattering vertex to the exit only straight up; the light that reaches the exit through
//! mirror bounces (down to the conductor, or round trips between the two interfaces) cannot be
//! sampled either, so pbrt loses it (measured: a lossless medium over a perfect mirror reflects
//! 77 % instead of 100 %; `pbrt_walk_loses_the_mirror_chains` in `coated_tests.rs`). We add
//! those chains in closed form (`Layers::mirror_chains`).

use math::{Rng, Vec3};
use spectrum::Rgb;

use super::layered_interfaces::{Base, Events, HenyeyGreenstein, Top, power_heuristic};

/// The layered configuration the walk runs in (the layer's local frame, `z` up).
#[derive(Clone, Copy, Debug)]
pub(super) struct Layers {
    pub top: Top,
    pub base: Base,
    /// Depth of the medium, in units of its mean free path.
    pub thickness: f32,
    /// Single-scattering albedo of the medium (black: no medium, only attenuation).
    pub albedo: Rgb,
    /// Henyey–Greenstein asymmetry.
    pub g: f32,
    /// Largest number of events per walk.
    pub max_depth: u32,
    /// Walks averaged per evaluation.
    pub samples: u32,
}

/// Transmittance along `w` over the depth difference `dz` (unit extinction).
#[inline]
pub(super) fn transmittance(dz: f32, w: Vec3) -> f32 {
    if dz.abs() <= f32::MIN_POSITIVE { 1.0 } else { (-(dz / w.z).abs()).exp() }
}

/// The generator for the pair `(wo, wi)`: a hash of their bits.
pub(super) fn pair_rng(wo: Vec3, wi: Vec3) -> Rng {
    let bits = |v: Vec3| {
        let mut h = 0x9e37_79b9_7f4a_7c15u64;
        for c in [v.x, v.y, v.z] {
            h = mix(h ^ c.to_bits() as u64);
        }
        h
    };
    Rng::new(bits(wo), bits(wi))
}

/// SplitMix64's finaliser.
#[inline]
fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

impl Layers {
    /// The walk's estimate of the layered BSDF below the top's own reflection, in radiance
    /// mode, for `wo` (towards the viewer) and `wi` (towards the light), both with `z > 0`.
    pub(super) fn estimate(&self, wo: Vec3, wi: Vec3, rng: &mut Rng) -> Rgb {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Rgb::BLACK;
        }
        let mut f = Rgb::BLACK;
        for _ in 0..self.samples.max(1) {
            f += self.walk(wo, wi, rng, false);
        }
        f / self.samples.max(1) as f32
    }

    /// Between a smooth top and a smooth conductor, the paths from a scattering vertex at depth
    /// `zp` (arrived along `w`) to the presampled exit direction `exit_in` (pointing down, into
    /// the layer) through specular bounces only, beside the straight one the walk connects:
    /// up and `k ≥ 1` round trips (top reflection, base reflection) before leaving, or first
    /// down to the base and `k ≥ 0` round trips. The walk cannot sample these (every bounce is
    /// a delta), so they are summed here, per channel, without the exit's weight:
    /// `[p(u) Tr(thickness − zp) R + p(d) Tr(zp) F_c Tr(thickness)] / (1 − R)`,
    /// `R = F_top F_c Tr(thickness)²`, `u = −exit_in` and `d` its mirror image.
    fn mirror_chains(&self, phase: &HenyeyGreenstein, w: Vec3, zp: f32, exit_in: Vec3) -> Rgb {
        let Base::Conductor { eta, k, dist: None } = self.base else { return Rgb::BLACK };
        let up = -exit_in;
        let down = Vec3::new(up.x, up.y, -up.z);
        let conductor = crate::microfacet::fresnel_conductor_rgb(up.z, eta, k);
        let top_reflection = super::fresnel::fresnel_dielectric(-up.z, self.top.eta);
        let crossing = transmittance(self.thickness, up);
        let round_trip = conductor * (top_reflection * crossing * crossing);
        let first = round_trip * (phase.p(-w, up) * transmittance(self.thickness - zp, up))
            + conductor * (phase.p(-w, down) * transmittance(zp, down) * crossing);
        Rgb::new(first.r / (1.0 - round_trip.r), first.g / (1.0 - round_trip.g), first.b / (1.0 - round_trip.b))
    }

    /// pbrt-v4's walk: its weighting of the bounces that leave through a rough top, and
    /// without the mirror chains (see the module documentation), for the tests that measure
    /// the differences.
    #[cfg(test)]
    pub(super) fn estimate_with_pbrt_weights(&self, wo: Vec3, wi: Vec3, rng: &mut Rng) -> Rgb {
        self.walk(wo, wi, rng, true)
    }

    /// One walk; `pbrt_weights` weighs a bounce leaving through a rough top against the density
    /// of sampling `wi` from the bounce direction instead of the presampled exit's and leaves
    /// out the mirror chains, as pbrt-v4 does.
    fn walk(&self, wo: Vec3, wi: Vec3, rng: &mut Rng, pbrt_weights: bool) -> Rgb {
        let exit_density = |w: Vec3| {
            if pbrt_weights {
                self.top.pdf(-w, wi, Events::Transmission)
            } else {
                self.top.pdf(wi, -w, Events::Transmission)
            }
        };
        let (top, base, thickness) = (&self.top, &self.base, self.thickness);
        let phase = HenyeyGreenstein { g: self.g };
        let scattering = !self.albedo.is_black();
        let mut f = Rgb::BLACK;
        // Enter through the top; presample the exit towards wi (adjoint: importance mode).
        let Some(entry) = top.sample(wo, rng.uniform(), rng.uniform2(), true, Events::Transmission) else {
            return f;
        };
        let Some(exit) = top.sample(wi, rng.uniform(), rng.uniform2(), false, Events::Transmission) else {
            return f;
        };
        if entry.pdf <= 0.0 || entry.wi.z == 0.0 || exit.pdf <= 0.0 || exit.wi.z == 0.0 || exit.f.is_black() {
            return f;
        }
        let exit_weight = exit.f / exit.pdf;
        let mut beta = entry.f * (entry.wi.z.abs() / entry.pdf);
        let mut z = thickness;
        let mut w = entry.wi;
        for depth in 0..self.max_depth {
            // Russian roulette.
            if depth > 3 && beta.max_component() < 0.25 {
                let q = (1.0 - beta.max_component()).max(0.0);
                if rng.uniform() < q {
                    break;
                }
                beta = beta / (1.0 - q);
            }
            if !scattering {
                z = if z == thickness { 0.0 } else { thickness };
                beta *= transmittance(thickness, w);
            } else {
                let dz = -(1.0 - rng.uniform()).ln() * w.z.abs();
                let zp = if w.z > 0.0 { z + dz } else { z - dz };
                if 0.0 < zp && zp < thickness {
                    // Scattering in the medium: connect through the presampled exit.
                    let p = phase.p(-w, -exit.wi);
                    let weight = if top.is_specular() { 1.0 } else { power_heuristic(exit.pdf, p) };
                    f += beta * self.albedo * exit_weight * (p * weight * transmittance(zp - thickness, exit.wi));
                    if top.is_specular() && base.is_specular() && !pbrt_weights {
                        f += beta * self.albedo * exit_weight * self.mirror_chains(&phase, w, zp, exit.wi);
                    }
                    let (next, pdf) = phase.sample(-w, rng.uniform2());
                    if pdf <= 0.0 || next.z == 0.0 {
                        continue;
                    }
                    beta *= self.albedo;
                    w = next;
                    z = zp;
                    // The phase sample itself may leave through a rough top.
                    if w.z > 0.0 && !top.is_specular() {
                        let f_exit = top.f(-w, wi, true);
                        if f_exit > 0.0 {
                            let weight = power_heuristic(pdf, exit_density(w));
                            f += beta * (transmittance(zp - thickness, w) * f_exit * weight);
                        }
                    }
                    continue;
                }
                z = zp.clamp(0.0, thickness);
            }
            if z == thickness {
                // Internal reflection at the top.
                let Some(s) = top.sample(-w, rng.uniform(), rng.uniform2(), true, Events::Reflection) else { break };
                if s.f.is_black() || s.pdf <= 0.0 || s.wi.z == 0.0 {
                    break;
                }
                beta *= s.f * (s.wi.z.abs() / s.pdf);
                w = s.wi;
            } else {
                // At the base: connect through the presampled exit, then bounce.
                if !base.is_specular() {
                    let weight =
                        if top.is_specular() { 1.0 } else { power_heuristic(exit.pdf, base.pdf(-w, -exit.wi)) };
                    let connection = base.f(-w, -exit.wi) * exit_weight;
                    f += beta * connection * (exit.wi.z.abs() * weight * transmittance(thickness, exit.wi));
                }
                let Some(s) = base.sample(-w, rng.uniform2()) else { break };
                if s.f.is_black() || s.pdf <= 0.0 || s.wi.z == 0.0 {
                    break;
                }
                beta *= s.f * (s.wi.z.abs() / s.pdf);
                w = s.wi;
                // The bounce itself may leave through a rough top.
                if !top.is_specular() {
                    let f_exit = top.f(-w, wi, true);
                    if f_exit > 0.0 {
                        let weight = if base.is_specular() { 1.0 } else { power_heuristic(s.pdf, exit_density(w)) };
                        f += beta * (transmittance(thickness, w) * f_exit * weight);
                    }
                }
            }
        }
        f
    }
}
