//! Homogeneous participating media in the VCM engine: free flights of the sub-paths, the
//! transmittance and free-flight densities of connection segments, and the scattering
//! "BSDF" of a medium vertex (the phase function).
//!
//! **A deterministic free-flight density per event.** Every technique must evaluate the same
//! density for a sampling decision, forward and reverse, so that the MIS weights of a path sum
//! to 1. A segment between two vertices is cut into *pieces* by the index-matched (null)
//! boundaries it crosses; each piece lies in one medium (or in vacuum). One free-flight event
//! samples one piece of length `ℓ` in a medium with extinction `σ_t`: a channel `c` of the
//! medium's **linear-sRGB** extinction is picked uniformly, then `t ∝ σ_t,c e^{−σ_t,c t}`, so
//! the event has the channel-mixture densities
//!
//! - scattering at `t < ℓ`: `D(t) = mean_c σ_t,c e^{−σ_t,c t}` (per unit length),
//! - passing the piece: `P(ℓ) = mean_c e^{−σ_t,c ℓ}` (a probability),
//!
//! and the sub-path's throughput is multiplied by `σ_s(t) e^{−σ_t t} / D(t)` or
//! `e^{−σ_t ℓ} / P(ℓ)` per channel of the path's spectrum. The densities use the RGB
//! coefficients in spectral mode too: they are then the same for every wavelength set, so a
//! light vertex and a camera vertex of different wavelength groups agree on them. (A medium
//! whose RGB extinction is zero but whose spectrum is not is never sampled; no loader makes one.)
//! In vacuum a piece is passed with probability 1.
//!
//! **Grid (heterogeneous) media: surrogate densities.** The true free-flight density of delta
//! tracking in a grid cannot be evaluated, but the MIS weights do not need it: they only need
//! *deterministic* functions that every technique evaluates identically for the same event,
//! forward and reverse. The weights of a path then still sum to 1 over the techniques that can
//! sample it, so the estimate stays unbiased; only its variance depends on how close the
//! surrogates are to the true densities. They must be positive wherever a vertex with σ_s > 0
//! can be sampled. A grid piece uses the piecewise-constant RGB **majorant** `μ(t)` along the
//! ray (the majorant grid's cells, or the global majorant without a grid; 0 outside the
//! medium's box): `P̂(ℓ) = exp(−∫_0^ℓ μ)` (unitless) and `D̂(t) = μ(t) exp(−∫_0^t μ)` (per
//! unit length; the reverse flight's density at the piece's near end is `μ(0) P̂(ℓ)`),
//! [`grid_surrogate`]. They are what [`Flight::end_piece_with`] and [`segment`] take for grid
//! pieces; `∫_0^ℓ D̂ + P̂(ℓ) = 1`. The majorant is computed from the RGB coefficients, so it is
//! the same for every wavelength set.
//!
//! **Grid media: weighted delta tracking** ([`advance`]; Kutz et al. 2017, "Spectral and
//! decomposition tracking"): tentative collisions of the majorant `μ`; at a collision at `x` a
//! real event with probability `q(x) = mean_c σ_t,c(x) / μ` over the RGB channels (the same
//! for every wavelength set), else a null event. The throughput at wavelength (channel) `λ` is
//! multiplied by `σ_s,λ(x) / (μ q)` at a real event and `(μ − σ_t,λ(x)) / (μ (1 − q))` at a
//! null one, which is unbiased per `λ` (the null-collision integral equation with the
//! sampling probabilities divided out); with `σ_t,λ ≤ μ` a convex combination of the channel
//! values, both weights are at most 3. A real event only happens where `q > 0`, a null event
//! where `q < 1`, so no weight divides by zero. Passing a grid piece multiplies by the product
//! of its null weights. Connections estimate a grid piece's transmittance by ratio tracking
//! ([`scene::medium::Tracker::transmittance`], the path tracer's), which draws random numbers
//! from the caller's `Rng`: only when a grid piece is crossed, so other scenes draw the same
//! numbers as before. A merge at a medium vertex divides by σ_s at the camera vertex's position
//! ([`sigma_s_at`]).
//!
//! **Measures.** A surface vertex is reached with a density per unit *area*; a medium vertex
//! with a density per unit *volume* (Veach 1997 §8.2 area–product measure extended to volumes,
//! as in Georgiev's and Křivánek et al.'s path formulation). Converting a solid-angle density
//! `p_ω` at `x` to the measure at `y` over a segment of pieces `1..n`:
//! `p(y) = p_ω · Π_{k<n} P_k · E_n / ‖x − y‖²` with `E_n = P_n |cos θ_y|` at a surface and
//! `E_n = D_n` in a medium (no cosine). The reverse conversion (sampling `x` from `y`) takes the
//! pieces the other way: `Π_{k>1} P_k · E_1`. [`Flight`] accumulates these two products
//! without the cosines (`forward`, `reverse`) while a sub-path traces a segment;
//! [`super::mis::SubPathMis::apply_flight`] folds them into dVCM, dVC, dVM (tech. rep. eqs.
//! 31–36 with `g = cos/d²` replaced by the conversions above; the cosines and distances are
//! applied as before). [`segment`] evaluates the same products for a connection.
//!
//! **Medium vertices** scatter with the phase function: value = solid-angle pdf, the reverse pdf
//! equals the forward one, no cosines; Russian roulette continues with the medium's largest
//! RGB albedo ([`scene::medium::Medium::max_albedo`]), as the path tracer's albedo rule does.
//!
//! **The medium a light sub-path starts in** is read from the first surface with an interface
//! that its ray meets (surfaces without one are passed): the medium on the side the ray arrives
//! from; if there is none, the camera's medium for a finite light and vacuum for an infinite
//! one, whose rays start outside the scene's bounding sphere. (Reading it from the first
//! surface only, an emitting torus inside a medium sphere whose rays hit the torus itself
//! started those rays in vacuum: bpt was 1.7 % dark in red against pt on Mitsuba's
//! `test_homo_emitter_inside_medium`.) (Taking the camera's
//! medium for an infinite light's ray that meets nothing scattered its photons in the vacuum
//! around a medium sphere holding the camera: +1.7 % on the camera-inside furnace.)

use math::{RAY_EPSILON, Ray, Rng, Vec3};
use scene::medium::{Heterogeneous, MajorantProfile, Medium, MediumInterface, transmittance};
use scene::{Bsdf, Scene, SurfaceHit};
use spectrum::{Rgb, SpectralMode};

/// `mean_c e^{−σ_t,c ℓ}` over the RGB channels: the probability that a free flight passes a
/// piece of length `ℓ` (scene units; may be infinite).
#[inline]
pub fn pass_probability(sigma_t: Rgb, length: f32) -> f32 {
    let p = |s: f32| if s <= 0.0 { 1.0 } else { (-s * length).exp() };
    (p(sigma_t.r) + p(sigma_t.g) + p(sigma_t.b)) / 3.0
}

/// `mean_c σ_t,c e^{−σ_t,c t}` over the RGB channels: the density (per unit length) of a free
/// flight scattering at distance `t` from the start of its piece.
#[inline]
pub fn flight_density(sigma_t: Rgb, t: f32) -> f32 {
    let d = |s: f32| if s <= 0.0 { 0.0 } else { s * (-s * t).exp() };
    (d(sigma_t.r) + d(sigma_t.g) + d(sigma_t.b)) / 3.0
}

/// The free-flight state of a sub-path on the segment it is tracing (see the module doc).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Flight {
    /// The medium the ray travels in (`None` = vacuum).
    pub medium: Option<u32>,
    /// The medium is not known yet (a light sub-path's first segment): read it from the first
    /// surface hit.
    pub unresolved: bool,
    /// The medium of an unresolved segment whose first surface has no interface, or that
    /// meets no surface: the camera's medium for finite lights, vacuum for infinite ones (whose
    /// rays start outside the scene's bounding sphere).
    pub fallback: Option<u32>,
    /// `Π P_k · E_n` of the pieces finished so far, forward (unitless or per unit length).
    pub forward: f32,
    /// `Π P_k · E_1` of the pieces finished so far, reverse.
    pub reverse: f32,
    /// No piece of this segment is finished yet.
    pub first: bool,
    /// The segment starts at a medium vertex (its first piece's reverse factor is `D_1`).
    pub from_medium: bool,
    /// Distance from the start of the current piece to the ray origin (the offset of a ray
    /// leaving a surface or crossing a boundary).
    pub gap: f32,
}

impl Flight {
    /// A segment starting in `medium`, at a medium vertex when `from_medium`, with the ray
    /// origin `gap` past the vertex.
    pub fn start(medium: Option<u32>, from_medium: bool, gap: f32) -> Self {
        Flight { medium, unresolved: false, fallback: None, forward: 1.0, reverse: 1.0, first: true, from_medium, gap }
    }

    /// Ends a piece with pass probability `pass` (unitless, [`pass_probability`] of the
    /// piece's length; 1 in vacuum) and free-flight density `density` (per unit length,
    /// [`flight_density`] at the piece's far end); `scattered` when the segment ends there at a
    /// medium vertex. [`advance`] calls it for every piece it traces; it is public so that the
    /// MIS oracle (`tests/mis_oracle_media.rs`) accumulates a segment's products exactly as
    /// the walk does.
    #[inline]
    pub fn end_piece(&mut self, pass: f32, density: f32, scattered: bool) {
        self.end_piece_with(pass, density, density, scattered);
    }

    /// [`Flight::end_piece`] with different densities (per unit length) at the two ends of the
    /// piece: `far` for a flight along the ray stopping at the far end, `near` for the reverse
    /// flight stopping at the near end (equal in a homogeneous medium; a grid piece's
    /// surrogate densities differ, see [`grid_surrogate`]).
    #[inline]
    pub fn end_piece_with(&mut self, pass: f32, far: f32, near: f32, scattered: bool) {
        self.forward *= if scattered { far } else { pass };
        self.reverse *= if self.first && self.from_medium { near } else { pass };
        self.first = false;
    }
}

/// Where a sub-path's ray ended.
#[derive(Clone, Copy, Debug)]
pub enum Arrival {
    /// A surface that is not an index-matched boundary.
    Surface(SurfaceHit),
    /// A scattering event in medium `medium` at `distance` along the current ray.
    Medium {
        /// Position of the vertex.
        position: Vec3,
        /// Distance from the ray origin (scene units).
        distance: f32,
        /// The medium's index.
        medium: u32,
    },
    /// Nothing: the ray left the scene.
    Escaped,
}

/// Traces `ray` to its next vertex: samples free flights in the media it crosses, passes
/// index-matched boundaries (moving `ray` and adding the distance to `origin_offset`, the
/// distance of the ray origin from the last vertex) and multiplies `throughput` by the
/// free-flight weights (module doc; grid media by weighted delta tracking). Draws no random
/// numbers in vacuum, so surface-only scenes consume exactly the numbers they did before.
pub fn advance<S: SpectralMode>(
    scene: &Scene,
    ray: &mut Ray,
    origin_offset: &mut f32,
    flight: &mut Flight,
    throughput: &mut S,
    rng: &mut Rng,
    w: &S::Wavelengths,
) -> Arrival {
    let media = &scene.media;
    loop {
        let hit = scene.intersect(ray);
        if flight.unresolved {
            flight.unresolved = false;
            flight.medium = locate_medium(scene, ray, hit.as_ref()).unwrap_or(flight.fallback);
        }
        let t_max = hit.as_ref().map_or(f32::INFINITY, |h| h.distance);
        let length = t_max + flight.gap;
        if let Some(index) = flight.medium
            && let Some(h) = media.medium(index).heterogeneous()
        {
            let m = media.medium(index);
            match advance_grid(m, h, ray, length, flight, throughput, rng, w) {
                GridOutcome::Scattered(t) => {
                    let distance = (t - flight.gap).max(0.0);
                    return Arrival::Medium { position: ray.at(distance), distance, medium: index };
                }
                GridOutcome::Passed => {}
                GridOutcome::Absorbed => return Arrival::Escaped,
            }
        } else if let Some(index) = flight.medium {
            let m = media.medium(index);
            let rgb = m.coefficients::<Rgb>(&()).sigma_t;
            let channel = ((rng.uniform() * 3.0) as usize).min(2);
            let sigma = rgb.channel(channel);
            let u = rng.uniform();
            let t = if sigma > 0.0 { -(1.0 - u).ln() / sigma } else { f32::INFINITY };
            let c = m.coefficients::<S>(w);
            if t < length {
                let density = flight_density(rgb, t);
                flight.end_piece(pass_probability(rgb, t), density, true);
                *throughput *= c.sigma_s * transmittance(c.sigma_t, t) * (1.0 / density);
                let distance = (t - flight.gap).max(0.0);
                return Arrival::Medium { position: ray.at(distance), distance, medium: index };
            }
            let pass = pass_probability(rgb, length);
            // (The density at the piece's far end is the reverse flight's, from a medium vertex.)
            flight.end_piece(pass, flight_density(rgb, length), false);
            *throughput *= if pass > 0.0 { transmittance(c.sigma_t, length) * (1.0 / pass) } else { S::default() };
        } else {
            flight.end_piece(1.0, 0.0, false);
        }
        let Some(hit) = hit else { return Arrival::Escaped };
        if !media.is_null(hit.material) {
            return Arrival::Surface(hit);
        }
        pass_boundary(scene, &hit, ray, origin_offset, flight);
    }
}

/// The surrogate free-flight quantities of a grid piece (module doc): `P̂` and `D̂` at both ends.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridSurrogate {
    /// `P̂(ℓ) = exp(−∫_0^ℓ μ)`: the surrogate probability of passing the piece (unitless).
    pub pass: f32,
    /// `μ(ℓ) P̂(ℓ)`: the surrogate density (per unit length) of a flight along the ray
    /// stopping at the piece's far end.
    pub far: f32,
    /// `μ(0) P̂(ℓ)`: the surrogate density (per unit length) of the reverse flight stopping
    /// at the piece's near end.
    pub near: f32,
}

/// The surrogate densities ([`GridSurrogate`]) of the piece `[start, end]` (distances along the
/// unit `direction` from `origin`, scene units; `end` may be infinite) in grid medium `h`
/// (with the medium's `scale`), from the piecewise-constant RGB majorant `μ` of the majorant
/// grid. Deterministic: the same for every technique and every wavelength set.
pub fn grid_surrogate(
    h: &Heterogeneous,
    scale: f32,
    origin: Vec3,
    direction: Vec3,
    start: f32,
    end: f32,
) -> GridSurrogate {
    GridSurrogate::from_profile(h.tracker::<Rgb>(scale, &()).majorant_profile(origin, direction, start, end))
}

impl GridSurrogate {
    /// The surrogate quantities of a piece whose majorant profile is `profile`.
    #[inline]
    fn from_profile(profile: MajorantProfile) -> Self {
        let pass = (-profile.depth).exp();
        GridSurrogate { pass, far: profile.at_end * pass, near: profile.at_start * pass }
    }
}

/// How a sub-path's flight through a grid piece ended.
enum GridOutcome {
    /// A real scattering event at this distance from the piece's start.
    Scattered(f32),
    /// The piece was passed.
    Passed,
    /// The throughput became zero (spectral null weights).
    Absorbed,
}

/// Weighted delta tracking through a grid piece of `length` (module doc): tentative collisions
/// of the RGB majorant `μ` from the piece's start (`flight.gap` before `ray`'s origin); at a
/// collision at `x` a real event with probability `q(x) = mean_c σ_t,c(x) / μ` over the RGB
/// channels, weight `σ_s,λ(x) / (μ q)`, else a null event, weight `(μ − σ_t,λ(x)) / (μ (1 − q))`.
/// Ends the flight's piece with the surrogate densities.
#[allow(clippy::too_many_arguments)]
fn advance_grid<S: SpectralMode>(
    m: &Medium,
    h: &Heterogeneous,
    ray: &Ray,
    length: f32,
    flight: &mut Flight,
    throughput: &mut S,
    rng: &mut Rng,
    w: &S::Wavelengths,
) -> GridOutcome {
    let start = ray.origin - flight.gap * ray.direction;
    let direction = ray.direction;
    let rgb = h.tracker::<Rgb>(m.scale, &());
    let spectral = h.tracker::<S>(m.scale, w);
    let mut weight = S::splat(1.0);
    let mut real = None;
    // One walk of the majorant grid gives the collisions and the surrogate densities, one
    // lookup of the σ_t grid per collision both the RGB and the path's σ_t (the albedo only
    // at a real event).
    let profile = rgb.tentative_collisions(start, direction, 0.0, length, rng, |t, mu, rng| {
        let x = start + t * direction;
        let (sigma_t, rgb_t) = spectral.extinction_with_rgb(&rgb, x, w);
        let q = ((rgb_t.r.min(mu) + rgb_t.g.min(mu) + rgb_t.b.min(mu)) / (3.0 * mu)).clamp(0.0, 1.0);
        if rng.uniform() < q {
            weight *= spectral.scattering(x, w, sigma_t) * (1.0 / (mu * q));
            real = Some(t);
            return false;
        }
        weight *= sigma_t.map(|s| mu - s) * (1.0 / (mu * (1.0 - q)));
        !weight.is_black()
    });
    *throughput *= weight;
    let surrogate = match real {
        Some(_) => GridSurrogate::from_profile(profile),
        // The walk stopped at a null event that zeroed the throughput: the piece's profile
        // still covers all of it.
        None if weight.is_black() => grid_surrogate(h, m.scale, start, direction, 0.0, length),
        None => GridSurrogate::from_profile(profile),
    };
    flight.end_piece_with(surrogate.pass, surrogate.far, surrogate.near, real.is_some());
    match real {
        Some(t) => GridOutcome::Scattered(t),
        None if weight.is_black() => GridOutcome::Absorbed,
        None => GridOutcome::Passed,
    }
}

/// σ_s (per scene unit) of medium `m` at `position` at the wavelengths `w`: the medium's
/// constant σ_s, or a grid medium's at the point.
pub fn sigma_s_at<S: SpectralMode>(m: &Medium, position: Vec3, w: &S::Wavelengths) -> S {
    match m.heterogeneous() {
        Some(h) => h.tracker::<S>(m.scale, w).coefficients(position, w).1,
        None => m.coefficients::<S>(w).sigma_s,
    }
}

/// The medium at `ray`'s origin, read from the first surface with a medium interface along
/// the ray (`hit`: its first hit): the medium on the side the ray arrives from. Surfaces
/// without an interface are passed (a light's own mesh, objects inside a medium), so a light
/// inside a closed medium boundary finds that medium even when its ray first meets another
/// object. `None` when no such surface lies ahead (within [`LOCATE_HITS`] hits).
fn locate_medium(scene: &Scene, ray: &Ray, hit: Option<&SurfaceHit>) -> Option<Option<u32>> {
    let arriving = -ray.direction;
    let mut hit = hit.copied();
    for _ in 0..LOCATE_HITS {
        let h = hit?;
        if let Some(i) = scene.media.interface(h.primitive) {
            return Some(i.medium_towards(arriving, h.normal));
        }
        hit = scene.intersect(&Ray::new(h.position + RAY_EPSILON * ray.direction, ray.direction));
    }
    None
}

/// How many surfaces [`locate_medium`] passes before it gives up.
const LOCATE_HITS: usize = 64;

/// Continues `ray` straight through the surface at `hit` without a vertex (an index-matched
/// boundary, or a thin dielectric's straight-through transmission, see
/// [`crosses_as_null`]): switches the flight's medium at an interface, starts the next piece
/// past the surface and adds the distance to `origin_offset`.
pub fn pass_boundary(scene: &Scene, hit: &SurfaceHit, ray: &mut Ray, origin_offset: &mut f32, flight: &mut Flight) {
    if let Some(i) = scene.media.interface(hit.primitive) {
        flight.medium = i.medium_towards(ray.direction, hit.normal);
    }
    *origin_offset += hit.distance + RAY_EPSILON;
    *ray = Ray::new(hit.position + RAY_EPSILON * ray.direction, ray.direction);
    flight.gap = RAY_EPSILON;
}

/// Whether the surface at `hit` is, in a scene with media, crossed without a vertex when light
/// goes straight through it: a plain thin dielectric that does not emit, the same test as the
/// volumetric path tracer's (`crate::volumetric`, after Mitsuba 3's null component). A sub-path
/// that samples its straight-through transmission continues the segment
/// ([`super::subpath::SubPath::cross_null_surface`]); a connection segment crosses it with the
/// factor `T·(1 − R')` ([`segment`]). Both sides decide with this test, so every technique
/// sees the same vertices.
#[inline]
pub fn crosses_as_null(scene: &Scene, hit: &SurfaceHit) -> bool {
    crate::volumetric::is_null_interface(scene, hit)
}

/// What a connection segment carries: the transmittance per channel and the free-flight
/// products of its pieces (module doc), `forward` for sampling its end from its start and
/// `reverse` for sampling its start from its end (without cosines).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment<S> {
    /// Beer–Lambert transmittance of the media along the segment, per channel (an unbiased
    /// ratio-tracking estimate through grid media).
    pub transmittance: S,
    /// `Π_{k<n} P_k · (D_n or P_n)`.
    pub forward: f32,
    /// `Π_{k>1} P_k · (D_1 or P_1)`.
    pub reverse: f32,
}

/// The segment from `point` along unit `direction` over `distance` (may be infinite),
/// starting in `medium`; `from_medium` / `to_medium` say whether its ends are medium vertices.
/// Grid pieces take ratio tracking's transmittance estimate (random numbers from `rng`; none
/// are drawn without a grid piece) and the surrogate densities ([`grid_surrogate`]).
/// `None` when a surface that is neither an index-matched boundary nor crossed as null
/// ([`crosses_as_null`], whose straight-through factor multiplies the transmittance) blocks
/// it (over the open interval `(ε, distance − ε)`, as [`Scene::occluded`]) or nothing gets
/// through.
#[allow(clippy::too_many_arguments)]
pub fn segment<S: SpectralMode>(
    scene: &Scene,
    point: Vec3,
    direction: Vec3,
    distance: f32,
    medium: Option<u32>,
    from_medium: bool,
    to_medium: bool,
    w: &S::Wavelengths,
    rng: &mut Rng,
) -> Option<Segment<S>> {
    let media = &scene.media;
    let mut carried = S::splat(1.0);
    let (mut forward, mut reverse) = (1.0f32, 1.0f32);
    // The walk crosses null boundaries and thin dielectrics (`crosses_as_null`).
    let surfaces = crate::null_walk::walk::<S>(scene, point, direction, distance, medium, w, |piece| {
        if let Some(index) = piece.medium {
            let m: &Medium = media.medium(index);
            if let Some(h) = m.heterogeneous() {
                let tracker = h.tracker::<S>(m.scale, w);
                carried *= tracker.transmittance(point, direction, piece.start, piece.end, rng, w);
                let g = grid_surrogate(h, m.scale, point, direction, piece.start, piece.end);
                forward *= if piece.last && to_medium { g.far } else { g.pass };
                reverse *= if piece.first && from_medium { g.near } else { g.pass };
                return;
            }
            let rgb = m.coefficients::<Rgb>(&()).sigma_t;
            let length = piece.end - piece.start;
            carried *= transmittance(m.coefficients::<S>(w).sigma_t, length);
            let (pass, density) = (pass_probability(rgb, length), flight_density(rgb, length));
            forward *= if piece.last && to_medium { density } else { pass };
            reverse *= if piece.first && from_medium { density } else { pass };
        }
    })?;
    carried *= surfaces;
    (!carried.is_black()).then_some(Segment { transmittance: carried, forward, reverse })
}

/// The media around a vertex: the medium a segment leaving it along a direction starts in.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MediumSide {
    /// The medium the arriving ray travelled in.
    pub current: Option<u32>,
    /// The interface of the surface, if any (`None` at medium vertices).
    pub interface: Option<MediumInterface>,
    /// Geometric normal of the surface (unused without an interface).
    pub normal: Vec3,
}

impl MediumSide {
    /// Inside medium `medium` (a medium vertex, or a camera/light in a medium).
    pub fn inside(medium: Option<u32>) -> Self {
        MediumSide { current: medium, interface: None, normal: Vec3::ZERO }
    }

    /// At surface `hit` reached through `current`.
    pub fn at_surface(scene: &Scene, hit: &SurfaceHit, current: Option<u32>) -> Self {
        MediumSide { current, interface: scene.media.interface(hit.primitive), normal: hit.normal }
    }

    /// The medium a ray leaving along `direction` travels in.
    #[inline]
    pub fn towards(&self, direction: Vec3) -> Option<u32> {
        self.interface.map_or(self.current, |i| i.medium_towards(direction, self.normal))
    }
}

/// A scattering vertex's local model: a surface BSDF or a medium's phase function.
#[derive(Clone, Copy)]
pub enum Scatterer<'a> {
    /// A surface vertex.
    Surface(&'a Bsdf),
    /// A medium vertex: the medium and its fixed direction (towards the previous vertex).
    Medium(&'a Medium, Vec3),
}

/// [`Scatterer::evaluate`]'s result.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScatterEval {
    /// BSDF value (1/sr, linear sRGB), or the phase value in every channel.
    pub value: Rgb,
    /// `|cos|` of the generated direction at a surface, 1 in a medium.
    pub cos_generated: f32,
    /// Solid-angle pdf of generating the direction (Russian roulette not included).
    pub forward: f32,
    /// Solid-angle pdf of the reverse (Russian roulette not included).
    pub reverse: f32,
}

impl Scatterer<'_> {
    /// Value and pdfs for the unit generated direction, `None` when zero.
    pub fn evaluate(&self, generated: Vec3) -> Option<ScatterEval> {
        match self {
            Scatterer::Surface(bsdf) => bsdf.evaluate(generated).map(|e| ScatterEval {
                value: e.value,
                cos_generated: e.cos_generated,
                forward: e.pdf.forward.0,
                reverse: e.pdf.reverse.0,
            }),
            Scatterer::Medium(m, fixed) => {
                let p = m.phase.evaluate(*fixed, generated);
                (p > 0.0).then_some(ScatterEval { value: Rgb::splat(p), cos_generated: 1.0, forward: p, reverse: p })
            }
        }
    }

    /// The Russian-roulette continuation probability.
    pub fn continuation(&self) -> f32 {
        match self {
            Scatterer::Surface(bsdf) => bsdf.continuation_probability(),
            Scatterer::Medium(m, _) => m.max_albedo(),
        }
    }

    /// Whether this is a medium vertex.
    pub fn is_medium(&self) -> bool {
        matches!(self, Scatterer::Medium(..))
    }

    /// The evaluated value at wavelengths `w`: the BSDF upsampled as a reflectance, the phase
    /// value as is (it may exceed 1).
    #[inline]
    pub fn spectral<S: SpectralMode>(&self, w: &S::Wavelengths, value: Rgb) -> S {
        match self {
            Scatterer::Surface(_) => S::from_reflectance(w, value),
            Scatterer::Medium(..) => S::splat(value.r),
        }
    }
}
