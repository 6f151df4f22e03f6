//! The path tracer's volumetric walk: camera paths through participating media and
//! index-matched (null) boundaries, with next-event estimation at surface and medium vertices
//! combined with BSDF and phase-function sampling by MIS. [`crate::path_tracer`] uses it for
//! scenes whose [`scene::medium::Media`] is active; surface-only scenes never reach this file.
//!
//! **Free flights** ([`scene::medium::sample_distance`]): in a medium the distance to the next
//! vertex is sampled with path-level spectral MIS: the path picks one channel for all its
//! distances and divides by the average over the channels of the densities of its distances
//! (unbiased per channel, bounded weights; see the module `scene::medium::homogeneous`). The
//! `RAY_EPSILON` a ray leaving a surface skips is counted in its free flight (and in the shadow
//! rays' transmittance), so a medium is exactly as thick as its geometry. Heterogeneous media
//! sample free flights by delta tracking with the same spectral MIS and estimate shadow-ray
//! transmittance by ratio tracking (the module `scene::medium::heterogeneous`); homogeneous
//! media keep their closed forms (one random number per free flight, as before).
//!
//! **Medium vertices** scatter with the phase function: NEE samples a light and multiplies by
//! the phase value and the shadow ray's transmittance; phase sampling continues the path with
//! weight `f/p = 1`. Both are combined with the light sampling technique by the heuristic on
//! *directional* solid-angle densities (the light's `direct_pdf` against the phase or BSDF
//! pdf). The free-flight probabilities are left out of both weights: the weights still sum to
//! one for every path (each technique's weight uses the same two densities), so the estimator
//! stays unbiased; it only spends more samples than needed where the medium is dense.
//!
//! **Shadow rays** ([`shadow_transmittance`]) pass through null boundaries, multiplying the
//! Beer–Lambert transmittance of every medium segment and switching media at interfaces. They
//! also cross thin dielectrics, multiplying by their straight-through factor `T·(1 − R')`
//! ([`scene::Bsdf::null_transmission`]): Mitsuba 3's thin dielectric transmits through a
//! `Null` component, which its `volpath` treats this way. Any other surface blocks them.
//!
//! **Null boundaries** neither count as vertices nor change the direction; a BSDF or light
//! sampling pdf measured at the last scattering vertex stays valid across them (the emitter's
//! area pdf is converted with the whole distance from that vertex). A sampled straight-through
//! transmission of a thin dielectric is handled the same way (its expected weight is the shadow
//! rays' factor `T·(1 − R')`), so an emitter found behind a thin dielectric is weighted by MIS
//! against next-event estimation through it instead of counting as seen through a specular
//! vertex. Both sides decide with the same test (`null_factor`), which keeps the weights of
//! every path summing to one.
//!
//! Path length counts scattering vertices (surface or medium) as the surface-only tracer
//! counts surface vertices; a thin dielectric's straight-through transmission is no vertex and
//! does not count: Mitsuba 3 gives only its thin dielectric's transmission a null component,
//! which its volumetric path tracers do not count as a bounce (so a path at its length limit
//! may still pass straight through one). The VCM engine follows the same rule
//! (`vcm::medium::crosses_as_null`). Fluorescent materials in scenes with media are refused by the
//! driver (not implemented, issue #15).

use math::{RAY_EPSILON, Ray, Rng, Vec3};
use scene::medium::{Media, sample_distance, transmittance};
use scene::{Bsdf, Material, Scene, SurfaceHit, TransportMode};
use spectrum::SpectralMode;

use crate::path_tracer::{PathTracer, RussianRoulette};

/// Radiance along `camera_ray` in a scene with media (see the module documentation).
pub(crate) fn radiance<S: SpectralMode>(
    tracer: &PathTracer,
    scene: &Scene,
    camera_ray: Ray,
    rng: &mut Rng,
    w: &S::Wavelengths,
) -> S {
    let (max_length, nee, heuristic) = (tracer.max_length, tracer.next_event_estimation, tracer.heuristic);
    let albedo_roulette = tracer.russian_roulette == RussianRoulette::Albedo;
    let media = &scene.media;
    let sphere = &scene.bounding_sphere;
    let hero = S::hero_wavelength(w);
    let mut ray = camera_ray;
    let mut medium = media.camera;
    let mut throughput = S::splat(1.0);
    let mut terminated = false;
    let mut result = S::default();
    let mut path_length = 1u32;
    // Solid-angle pdf of the last direction sample (Russian roulette included) and whether it
    // was specular; distance from the last scattering vertex to the current ray origin.
    let mut last_pdf = 1.0f32;
    let mut last_specular = true;
    // Position and normal (zero in a medium) of the last scattering vertex: the receiver of
    // the light pick whose probability the MIS weight of an emitter hit needs.
    let (mut last_position, mut last_normal) = (Vec3::ZERO, Vec3::ZERO);
    let pick_probability = |index, p, n| tracer.light_sampler.probability(scene, p, n, index) * tracer.mis_pick_scale;
    let mut travelled = 0.0f32;
    // The medium between the last vertex and the ray origin (the offset of a ray leaving a
    // surface), counted in the next free flight.
    let mut gap = 0.0f32;
    // Path-level spectral MIS: the path's channel and its density ratios (module
    // `scene::medium::homogeneous`).
    let channel = ((rng.uniform() * S::CHANNELS as f32) as usize).min(S::CHANNELS - 1);
    let mut ratios = S::splat(1.0);

    loop {
        let hit = scene.intersect(&ray);
        let t_max = hit.as_ref().map_or(f32::INFINITY, |h| h.distance);

        // Free flight through the current medium.
        if let Some(index) = medium {
            let m = media.medium(index);
            let flight = if let Some(h) = m.heterogeneous() {
                let origin = ray.origin - gap * ray.direction;
                let tracker = h.tracker::<S>(m.scale, w);
                tracker.sample_distance(origin, ray.direction, t_max + gap, channel, rng, &mut ratios, w)
            } else {
                let c = m.coefficients::<S>(w);
                sample_distance(c.sigma_t, c.sigma_s, t_max + gap, channel, rng.uniform(), &mut ratios)
            };
            throughput *= flight.weight;
            if flight.scattered {
                if path_length >= max_length || throughput.is_black() {
                    break;
                }
                let position = ray.at((flight.distance - gap).max(0.0));
                let fixed = -ray.direction;
                let continuation = if albedo_roulette { m.max_albedo() } else { 1.0 };

                // Next-event estimation from the medium vertex.
                if nee
                    && let Some((light_index, light, pick)) =
                        tracer.light_sampler.pick(scene, position, Vec3::ZERO, rng.uniform())
                {
                    let u = rng.uniform2();
                    if let Some(direct) = light.sample_direct(position, u, sphere) {
                        let phase = m.phase.evaluate(fixed, direct.direction);
                        if phase > 0.0
                            && let Some(carried) = tracked_transmittance::<S>(
                                scene,
                                position,
                                direct.direction,
                                direct.distance,
                                medium,
                                w,
                                rng,
                            )
                        {
                            let light_pdf = direct.direct_pdf.0 * pick;
                            let weight =
                                if light.is_delta() { 1.0 } else { heuristic.weight(light_pdf, phase * continuation) };
                            let emitted = scene.emission::<S>(light_index, w, direct.radiance);
                            result += throughput * emitted * carried * (phase * weight / light_pdf);
                        }
                    }
                }

                // Continue by phase sampling (weight f/p = 1), with Russian roulette.
                let sample = m.phase.sample(fixed, rng.uniform2());
                if continuation < 1.0 {
                    if rng.uniform() >= continuation {
                        break;
                    }
                    throughput *= 1.0 / continuation;
                }
                if !survives_throughput_roulette(tracer, path_length, &mut throughput, rng) {
                    break;
                }
                last_pdf = sample.pdf * continuation;
                last_specular = false;
                (last_position, last_normal) = (position, Vec3::ZERO);
                ray = Ray::new(position, sample.direction);
                travelled = 0.0;
                gap = 0.0;
                path_length += 1;
                continue;
            }
        }

        let Some(hit) = hit else {
            // The ray leaves the scene: environment light.
            if let Some(index) = scene.background
                && let Some(emitted) =
                    scene.lights[index as usize].radiance_on_hit(ray.direction, Vec3::ZERO, Vec3::ZERO, sphere)
            {
                let weight = if last_specular || !nee {
                    1.0
                } else {
                    let pick = pick_probability(index, last_position, last_normal);
                    heuristic.weight(last_pdf, emitted.direct_pdf.0 * pick)
                };
                result += throughput * scene.emission::<S>(index, w, emitted.radiance) * weight;
            }
            break;
        };
        let distance = travelled + hit.distance;

        // Emitter hit: collect (front side only).
        if let Some(light_index) = hit.light {
            let light = &scene.lights[light_index as usize];
            if let Some(emitted) = light.radiance_on_hit(ray.direction, hit.position, hit.normal, sphere) {
                let weight = if last_specular || !nee {
                    1.0
                } else {
                    let direct_pdf = emitted.direct_pdf.to_solid_angle(distance * distance, emitted.cos_at_light);
                    let pick = pick_probability(light_index, last_position, last_normal);
                    heuristic.weight(last_pdf, direct_pdf.0 * pick)
                };
                result += throughput * scene.emission::<S>(light_index, w, emitted.radiance) * weight;
            }
        }
        let interface = media.interface(hit.primitive);

        // An index-matched boundary: pass through, switching media.
        if media.is_null(hit.material) {
            if let Some(i) = interface {
                medium = i.medium_towards(ray.direction, hit.normal);
            }
            ray = Ray::new(hit.position + RAY_EPSILON * ray.direction, ray.direction);
            travelled = distance + RAY_EPSILON;
            gap = RAY_EPSILON;
            continue;
        }
        // At the length limit only a thin dielectric's straight-through transmission (no
        // vertex) may continue.
        let at_limit = path_length >= max_length;
        let fixed_direction = -ray.direction;
        // Borrowed, not moved out of the `Option`: a move copies the several-hundred-byte BSDF.
        let built =
            Bsdf::new_at(scene.material(&hit), &hit.shading_point(), fixed_direction, TransportMode::Radiance, hero);
        let Some(bsdf) = built.as_ref() else {
            break;
        };
        if at_limit && !bsdf.is_delta() {
            break;
        }
        let continuation = if albedo_roulette { bsdf.continuation_probability() } else { 1.0 };
        let medium_towards = |direction: Vec3| interface.map_or(medium, |i| i.medium_towards(direction, hit.normal));

        // Next-event estimation from the surface vertex.
        if nee
            && !at_limit
            && !bsdf.is_delta()
            && let Some((index, light, pick)) =
                tracer.light_sampler.pick(scene, hit.position, hit.shading_normal, rng.uniform())
        {
            let u = rng.uniform2();
            if let Some(direct) = light.sample_direct(hit.position, u, sphere)
                && let Some(eval) = bsdf.evaluate(direct.direction)
                && let Some(carried) = tracked_transmittance::<S>(
                    scene,
                    hit.position,
                    direct.direction,
                    direct.distance,
                    medium_towards(direct.direction),
                    w,
                    rng,
                )
            {
                let light_pdf = direct.direct_pdf.0 * pick;
                let weight =
                    if light.is_delta() { 1.0 } else { heuristic.weight(light_pdf, eval.pdf.forward.0 * continuation) };
                let emitted = scene.emission::<S>(index, w, direct.radiance);
                let scale = eval.cos_generated * weight / light_pdf;
                result += throughput * emitted * S::from_reflectance(w, eval.value) * carried * scale;
            }
        }

        // Continue by BSDF sampling, with Russian roulette.
        let Some(sample) = bsdf.sample(rng.uniform3()) else { break };
        // Through a thin dielectric's null component: no vertex (see the module docs).
        let null_crossing = sample.is_straight_through(fixed_direction) && is_null_interface(scene, &hit);
        if at_limit && !null_crossing {
            break;
        }
        if continuation < 1.0 && rng.uniform() >= continuation {
            break;
        }
        let pdf = sample.pdf.forward.0 * continuation;
        throughput *= S::from_reflectance(w, sample.value) * (sample.cos_generated / pdf);
        if !survives_throughput_roulette(tracer, path_length, &mut throughput, rng) {
            break;
        }
        if sample.dispersive && !terminated {
            throughput = throughput.terminate_secondary();
            terminated = true;
        }
        medium = medium_towards(sample.direction);
        ray = Ray::new(hit.position + RAY_EPSILON * sample.direction, sample.direction);
        gap = RAY_EPSILON;
        if null_crossing {
            travelled = distance + RAY_EPSILON;
            continue;
        }
        last_pdf = pdf;
        last_specular = sample.lobe.is_specular();
        (last_position, last_normal) = (hit.position, hit.shading_normal);
        travelled = RAY_EPSILON;
        path_length += 1;
    }
    result
}

/// Mitsuba's throughput rule ([`RussianRoulette::Throughput`]) after a scattering vertex of a
/// path `path_length` segments long: false when the path stops, else the survivor is scaled.
#[inline]
fn survives_throughput_roulette<S: SpectralMode>(
    tracer: &PathTracer,
    path_length: u32,
    throughput: &mut S,
    rng: &mut Rng,
) -> bool {
    if let RussianRoulette::Throughput { start } = tracer.russian_roulette
        && path_length >= start
    {
        let survival = throughput.max_component().min(0.95);
        if survival.is_nan() || survival <= 0.0 || rng.uniform() >= survival {
            return false;
        }
        *throughput *= 1.0 / survival;
    }
    true
}

/// The transmittance (per channel, unitless) of the segment from `point` along unit
/// `direction` over `distance` (may be infinite), starting in `medium`: the product of the
/// transmittances of its medium pieces and of the straight-through factors of the thin
/// dielectrics it crosses, switching media at interfaces (the walk of `crate::null_walk`).
/// `None` when any other surface blocks it (over the open interval `(ε, distance − ε)` of
/// [`Scene::occluded`]) or nothing gets through. Homogeneous pieces give Beer–Lambert's
/// exact value; heterogeneous pieces a ratio-tracking estimate drawn from a generator seeded
/// by the segment itself (deterministic per segment — the path tracer uses
/// [`tracked_transmittance`] with its own generator instead).
pub fn shadow_transmittance<S: SpectralMode>(
    scene: &Scene,
    point: Vec3,
    direction: Vec3,
    distance: f32,
    medium: Option<u32>,
    w: &S::Wavelengths,
) -> Option<S> {
    let bits = [point.x, point.y, point.z, direction.x, direction.y, direction.z, distance];
    let seed = bits.iter().fold(0u64, |h, v| (h ^ v.to_bits() as u64).wrapping_mul(0x100_0000_01b3));
    tracked_transmittance(scene, point, direction, distance, medium, w, &mut Rng::new(seed, 0x5eed))
}

/// [`shadow_transmittance`] with ratio tracking in heterogeneous media drawing from `rng`
/// (an unbiased estimate per channel; exact for homogeneous media, which draw nothing).
#[allow(clippy::too_many_arguments)]
pub fn tracked_transmittance<S: SpectralMode>(
    scene: &Scene,
    point: Vec3,
    direction: Vec3,
    distance: f32,
    medium: Option<u32>,
    w: &S::Wavelengths,
    rng: &mut Rng,
) -> Option<S> {
    let media: &Media = &scene.media;
    let mut carried = S::splat(1.0);
    let surfaces = crate::null_walk::walk::<S>(scene, point, direction, distance, medium, w, |piece| {
        if let Some(index) = piece.medium {
            let m = media.medium(index);
            let (start, end) = (piece.start, piece.end);
            if let Some(h) = m.heterogeneous() {
                carried *= h.tracker::<S>(m.scale, w).transmittance(point, direction, start, end, rng, w);
            } else {
                carried *= transmittance(m.coefficients::<S>(w).sigma_t, end - start);
            }
        }
    })?;
    carried *= surfaces;
    (!carried.is_black()).then_some(carried)
}

/// Whether the surface at `hit` is a thin dielectric that does not emit, whose
/// straight-through transmission the volumetric walk (and the VCM engine in media) treats as a
/// null component (module docs). An emitting one stays a vertex, so its emission is counted.
#[inline]
pub(crate) fn is_null_interface(scene: &Scene, hit: &SurfaceHit) -> bool {
    hit.light.is_none() && matches!(scene.material(hit), Material::ThinDielectric { .. })
}

/// The factor (per channel) by which a shadow ray along `direction` crosses the surface at
/// `hit`: `T·(1 − R')` for a thin dielectric ([`scene::Bsdf::null_transmission`]); `None` for
/// any other surface, which blocks it.
pub(crate) fn null_factor<S: SpectralMode>(
    scene: &Scene,
    hit: &SurfaceHit,
    direction: Vec3,
    w: &S::Wavelengths,
) -> Option<S> {
    if !is_null_interface(scene, hit) {
        return None;
    }
    let bsdf = Bsdf::new(scene.material(hit), &hit.shading_point(), -direction, TransportMode::Radiance)?;
    let factor = S::from_reflectance(w, bsdf.null_transmission()?);
    (!factor.is_black()).then_some(factor)
}
