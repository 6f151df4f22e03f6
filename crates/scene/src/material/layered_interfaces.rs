//! The pieces pbrt-v4's layered BSDF (`layered_walk`) is built from, in the local frame of the
//! layer (`z` up, the top interface at depth `thickness`, the base at depth 0): the dielectric
//! top interface seen from either side, the opaque base (Lambertian or conductor, seen from
//! above only), and the Henyey–Greenstein phase function of the medium between them.
//!
//! Unlike the leaf models, these answer pbrt's `BxDF` queries: `f` without the cosine,
//! sampling restricted to reflection or transmission, and pdfs per steradian of the sampled
//! direction (a specular sample's pdf is the probability of its discrete choice and its `f`
//! is `weight / |cos θ|`). The transport mode matters only for refraction: in radiance mode a
//! transmission is divided by `η_t²/η_i²` of the crossing (η_t: the side of the sampled
//! direction), in importance mode it is not.

use math::{Frame, INV_PI, Vec3, sqr, warp};
use spectrum::Rgb;

use super::fresnel::fresnel_dielectric;
use crate::microfacet::{Microfacet, fresnel_conductor_rgb, reflect, refract};

/// Which events a sampler may produce.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum Events {
    Reflection,
    Transmission,
}

/// One sampled direction of an interface.
#[derive(Clone, Copy)]
pub(super) struct InterfaceSample {
    /// The sampled direction (unit, pointing away from the interface).
    pub wi: Vec3,
    /// The BSDF value (per steradian, without the cosine).
    pub f: Rgb,
    /// Solid-angle density of `wi` (a specular sample: the probability of its choice).
    pub pdf: f32,
}

/// pbrt's power heuristic with exponent 2 for one sample of each of two strategies.
#[inline]
pub(super) fn power_heuristic(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2.is_infinite() {
        return 1.0;
    }
    if a2 + b2 > 0.0 { a2 / (a2 + b2) } else { 0.0 }
}

/// The dielectric top interface: relative IOR `eta` (layer over outside) and a GGX
/// distribution, or `None` for a smooth interface.
#[derive(Clone, Copy, Debug)]
pub(super) struct Top {
    pub eta: f32,
    pub dist: Option<Microfacet>,
}

impl Top {
    /// True for a smooth (specular) interface.
    #[inline]
    pub(super) fn is_specular(&self) -> bool {
        self.dist.is_none()
    }

    /// The BSDF for `wo`, `wi` on either side (0 for a smooth interface).
    pub(super) fn f(&self, wo: Vec3, wi: Vec3, radiance: bool) -> f32 {
        let Some(dist) = &self.dist else { return 0.0 };
        let Some(h) = self.half_vector(wo, wi) else { return 0.0 };
        let d = dist.d(h.m);
        let g = dist.g(wo, wi, h.m);
        let fresnel = fresnel_dielectric(wo.dot(h.m), self.eta);
        if h.reflection {
            return d * g * fresnel / (4.0 * wo.z * wi.z).abs();
        }
        let denominator = sqr(wi.dot(h.m) + wo.dot(h.m) / h.etap) * wi.z * wo.z;
        let ft = (1.0 - fresnel) * d * g * (wi.dot(h.m) * wo.dot(h.m) / denominator).abs();
        if radiance { ft / sqr(h.etap) } else { ft }
    }

    /// The density of sampling `wi` from `wo` with [`Top::sample`] restricted to `events`.
    pub(super) fn pdf(&self, wo: Vec3, wi: Vec3, events: Events) -> f32 {
        let Some(dist) = &self.dist else { return 0.0 };
        let Some(h) = self.half_vector(wo, wi) else { return 0.0 };
        let fresnel = fresnel_dielectric(wo.dot(h.m), self.eta);
        let (pr, pt) = restrict(fresnel, events);
        if pr + pt <= 0.0 {
            return 0.0;
        }
        let visible = visible_pdf(dist, wo, h.m);
        if h.reflection {
            if events == Events::Transmission {
                return 0.0;
            }
            visible / (4.0 * wo.dot(h.m).abs()) * pr / (pr + pt)
        } else {
            if events == Events::Reflection {
                return 0.0;
            }
            let denominator = sqr(wi.dot(h.m) + wo.dot(h.m) / h.etap);
            visible * wi.dot(h.m).abs() / denominator * pt / (pr + pt)
        }
    }

    /// Samples reflection or transmission for `wo` (either side) with `uc` (the choice) and
    /// `u` (the microfacet normal).
    pub(super) fn sample(
        &self,
        wo: Vec3,
        uc: f32,
        u: [f32; 2],
        radiance: bool,
        events: Events,
    ) -> Option<InterfaceSample> {
        if wo.z == 0.0 {
            return None;
        }
        let Some(dist) = &self.dist else {
            let fresnel = fresnel_dielectric(wo.z, self.eta);
            let (pr, pt) = restrict(fresnel, events);
            if pr + pt <= 0.0 {
                return None;
            }
            if uc < pr / (pr + pt) {
                let wi = Vec3::new(-wo.x, -wo.y, wo.z);
                return Some(InterfaceSample { wi, f: Rgb::splat(fresnel / wi.z.abs()), pdf: pr / (pr + pt) });
            }
            let normal = Vec3::new(0.0, 0.0, wo.z.signum());
            let etap = if wo.z > 0.0 { self.eta } else { 1.0 / self.eta };
            let wi = refract(wo, normal, etap)?;
            let ft = (1.0 - fresnel) / wi.z.abs();
            let ft = if radiance { ft / sqr(etap) } else { ft };
            return Some(InterfaceSample { wi, f: Rgb::splat(ft), pdf: pt / (pr + pt) });
        };
        // A visible normal for the direction mirrored to +z (the normal stays on +z).
        let side = wo.z.signum();
        let m = dist.sample_visible(wo * side, u);
        let cos_o = wo.dot(m);
        if cos_o == 0.0 {
            return None;
        }
        let fresnel = fresnel_dielectric(cos_o, self.eta);
        let (pr, pt) = restrict(fresnel, events);
        if pr + pt <= 0.0 {
            return None;
        }
        let visible = visible_pdf(dist, wo, m);
        if uc < pr / (pr + pt) {
            let wi = reflect(wo, m);
            if wi.z * wo.z <= 0.0 {
                return None;
            }
            let f = dist.d(m) * dist.g(wo, wi, m) * fresnel / (4.0 * wi.z * wo.z).abs();
            let pdf = visible / (4.0 * cos_o.abs()) * pr / (pr + pt);
            return Some(InterfaceSample { wi, f: Rgb::splat(f), pdf });
        }
        // Refraction through m, seen from wo's side of the microfacet.
        let (facing, etap) = if cos_o > 0.0 { (m, self.eta) } else { (-m, 1.0 / self.eta) };
        let wi = refract(wo, facing, etap)?;
        if wi.z * wo.z >= 0.0 {
            return None;
        }
        let denominator = sqr(wi.dot(m) + cos_o / etap);
        let pdf = visible * wi.dot(m).abs() / denominator * pt / (pr + pt);
        let ft =
            (1.0 - fresnel) * dist.d(m) * dist.g(wo, wi, m) * (wi.dot(m) * cos_o / (denominator * wi.z * wo.z)).abs();
        let ft = if radiance { ft / sqr(etap) } else { ft };
        Some(InterfaceSample { wi, f: Rgb::splat(ft), pdf })
    }

    /// The generalised half vector of a pair (on +z), or `None` for a degenerate or
    /// back-facing configuration.
    fn half_vector(&self, wo: Vec3, wi: Vec3) -> Option<HalfVector> {
        if wo.z == 0.0 || wi.z == 0.0 {
            return None;
        }
        let reflection = wo.z * wi.z > 0.0;
        let etap = if reflection {
            1.0
        } else if wo.z > 0.0 {
            self.eta
        } else {
            1.0 / self.eta
        };
        let m = (wi * etap + wo).normalize_or_zero();
        if m == Vec3::ZERO || !m.is_finite() {
            return None;
        }
        let m = if m.z < 0.0 { -m } else { m };
        // Both directions on the side of the microfacet they are on of the macro surface.
        if wi.dot(m) * wi.z < 0.0 || wo.dot(m) * wo.z < 0.0 {
            return None;
        }
        Some(HalfVector { m, etap, reflection })
    }
}

struct HalfVector {
    m: Vec3,
    /// η on the far side over η on `wo`'s side (1 for reflection).
    etap: f32,
    reflection: bool,
}

/// The visible-normal density of `m` (on +z) for `w` on either side.
#[inline]
fn visible_pdf(dist: &Microfacet, w: Vec3, m: Vec3) -> f32 {
    dist.visible_pdf(w * w.z.signum(), m)
}

/// The unnormalised probabilities of reflection and transmission with Fresnel reflectance
/// `fresnel`, restricted to `events`.
#[inline]
fn restrict(fresnel: f32, events: Events) -> (f32, f32) {
    match events {
        Events::Reflection => (fresnel, 0.0),
        Events::Transmission => (0.0, 1.0 - fresnel),
    }
}

/// The opaque base, seen from inside the layer (`wo.z > 0`).
#[derive(Clone, Copy, Debug)]
pub(super) enum Base {
    /// Lambertian with reflectance ρ.
    Diffuse(Rgb),
    /// A conductor with the complex IOR `eta + i·k` relative to the layer; `dist` `None` is
    /// smooth.
    Conductor { eta: Rgb, k: Rgb, dist: Option<Microfacet> },
}

impl Base {
    /// True for a smooth conductor.
    #[inline]
    pub(super) fn is_specular(&self) -> bool {
        matches!(self, Base::Conductor { dist: None, .. })
    }

    /// The BSDF (0 for a smooth conductor, and unless both directions are on +z).
    pub(super) fn f(&self, wo: Vec3, wi: Vec3) -> Rgb {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Rgb::BLACK;
        }
        match self {
            Base::Diffuse(rho) => *rho * INV_PI,
            Base::Conductor { dist: None, .. } => Rgb::BLACK,
            Base::Conductor { eta, k, dist: Some(dist) } => {
                let m = (wo + wi).normalize_or_zero();
                if m == Vec3::ZERO {
                    return Rgb::BLACK;
                }
                fresnel_conductor_rgb(wo.dot(m), *eta, *k) * (dist.d(m) * dist.g(wo, wi, m) / (4.0 * wo.z * wi.z))
            }
        }
    }

    /// The density of [`Base::sample`] producing `wi` from `wo` (0 for a smooth conductor).
    pub(super) fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        match self {
            Base::Diffuse(_) => wi.z * INV_PI,
            Base::Conductor { dist: None, .. } => 0.0,
            Base::Conductor { dist: Some(dist), .. } => {
                let m = (wo + wi).normalize_or_zero();
                if m == Vec3::ZERO { 0.0 } else { dist.reflection_pdf(wo, m) }
            }
        }
    }

    /// Samples a reflected direction for `wo` (`wo.z > 0`).
    pub(super) fn sample(&self, wo: Vec3, u: [f32; 2]) -> Option<InterfaceSample> {
        if wo.z <= 0.0 {
            return None;
        }
        let wi = match self {
            Base::Diffuse(_) => warp::cosine_hemisphere(u),
            Base::Conductor { eta, k, dist: None } => {
                let wi = Vec3::new(-wo.x, -wo.y, wo.z);
                return Some(InterfaceSample { wi, f: fresnel_conductor_rgb(wo.z, *eta, *k) / wi.z, pdf: 1.0 });
            }
            Base::Conductor { dist: Some(dist), .. } => reflect(wo, dist.sample_visible(wo, u)),
        };
        let pdf = self.pdf(wo, wi);
        if wi.z <= 0.0 || pdf <= 0.0 {
            return None;
        }
        Some(InterfaceSample { wi, f: self.f(wo, wi), pdf })
    }
}

/// The Henyey–Greenstein phase function with asymmetry `g`, in pbrt's convention: both
/// directions point away from the scattering point, so forward scattering is `wo·wi = −1`.
/// Densities per steradian; sampling is exact (pdf = value).
#[derive(Clone, Copy, Debug)]
pub(super) struct HenyeyGreenstein {
    pub g: f32,
}

impl HenyeyGreenstein {
    /// The phase function value (= the sampling density).
    pub(super) fn p(&self, wo: Vec3, wi: Vec3) -> f32 {
        let g = self.g;
        let denominator = 1.0 + g * g + 2.0 * g * wo.dot(wi);
        (1.0 - g * g) / (4.0 * math::PI * denominator * denominator.max(0.0).sqrt())
    }

    /// Samples `wi` for `wo`: the cosine `μ` with the direction of travel `−wo` by inverting
    /// the cumulative distribution of `(1 − g²)/(2 (1 + g² − 2gμ)^{3/2})`, the azimuth uniform.
    pub(super) fn sample(&self, wo: Vec3, u: [f32; 2]) -> (Vec3, f32) {
        let g = self.g;
        let mu = if g.abs() < 1e-3 {
            1.0 - 2.0 * u[0]
        } else {
            let s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u[0]);
            ((1.0 + g * g - s * s) / (2.0 * g)).clamp(-1.0, 1.0)
        };
        let sin = (1.0 - mu * mu).max(0.0).sqrt();
        let (sin_phi, cos_phi) = math::sin_cos_turns(u[1]);
        let local = Vec3::new(sin * cos_phi, sin * sin_phi, mu);
        let wi = Frame::from_z(-wo).to_world(local).normalize();
        (wi, self.p(wo, wi))
    }
}
