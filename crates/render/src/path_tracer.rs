//! The reference path tracer: unidirectional camera paths with BSDF sampling and next-event
//! estimation (one light sample per non-specular vertex), combined with the balance heuristic.
//! Russian roulette uses the BSDF's continuation probability and enters the BSDF pdf.
//!
//! Path length counts segments including the camera segment: an emitter seen directly is a
//! path of length 1, direct lighting of the first hit length 2.
//!
//! An emitter that also reflects (a material with non-zero albedo) keeps scattering after its
//! emission is collected; the reference scenes' emitters are black and end the path.

use math::{RAY_EPSILON, Ray, Rng, Vec3};
use scene::{Bsdf, Scene, TransportMode};
use spectrum::{Hero4, Rgb, SpectralMode};

use crate::balance_heuristic;
use crate::fluorescent::{FluorescentVertex, scatter_slots, view};

/// Settings of the path tracer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathTracer {
    /// Maximum path length in segments.
    pub max_length: u32,
    /// Use next-event estimation (combined with BSDF sampling by MIS). Without it, light is
    /// found only by BSDF sampling, an independent estimator used to test the MIS weights;
    /// delta lights then contribute nothing.
    pub next_event_estimation: bool,
    /// Spectral mode ([`Hero4`]): each camera path draws its own four wavelengths (the first
    /// number of its stream); otherwise RGB.
    pub spectral: bool,
}

impl PathTracer {
    /// The path tracer with next-event estimation.
    pub fn new(max_length: u32) -> Self {
        Self { max_length, next_event_estimation: true, spectral: false }
    }

    /// Radiance arriving at the camera along `camera_ray`, as linear sRGB.
    pub fn radiance(&self, scene: &Scene, camera_ray: Ray, rng: &mut Rng) -> Rgb {
        if self.spectral {
            let (u, v) = (rng.uniform(), rng.uniform());
            let wavelengths = Hero4::sample_wavelengths(u, v, scene.has_fluorescence());
            radiance::<Hero4>(scene, camera_ray, rng, self.max_length, self.next_event_estimation, &wavelengths)
                .to_rgb(&wavelengths)
        } else {
            radiance::<Rgb>(scene, camera_ray, rng, self.max_length, self.next_event_estimation, &())
        }
    }
}

fn radiance<S: SpectralMode>(
    scene: &Scene,
    camera_ray: Ray,
    rng: &mut Rng,
    max_length: u32,
    nee: bool,
    w: &S::Wavelengths,
) -> S {
    let sphere = &scene.bounding_sphere;
    let hero = S::hero_wavelength(w);
    let mut ray = camera_ray;
    let mut throughput = S::splat(1.0);
    let mut terminated = false;
    // The wavelength slot of each channel (moved by fluorescent shifts).
    let mut slots = S::Slots::default();
    let mut result = S::default();
    let mut path_length = 1u32;
    // Solid-angle pdf of the last BSDF sample (Russian roulette included), and whether it
    // was specular (then no other technique could have produced the next vertex).
    let mut last_pdf = 1.0f32;
    let mut last_specular = true;
    // Extra distance from the last vertex to the current ray origin.
    let mut origin_offset = 0.0f32;

    loop {
        let Some(hit) = scene.intersect(&ray) else {
            // The ray leaves the scene: environment light.
            if let Some(index) = scene.background
                && let Some(emitted) = scene.lights[index as usize].radiance_on_hit(ray.direction, Vec3::ZERO, sphere)
            {
                let weight = if last_specular || !nee {
                    1.0
                } else {
                    balance_heuristic(last_pdf, emitted.direct_pdf.0 * scene.light_pick_probability(index))
                };
                result += throughput * view(&slots, scene.emission::<S>(index, w, emitted.radiance)) * weight;
            }
            break;
        };

        // Emitter hit: collect (front side only).
        if let Some(light_index) = hit.light {
            let light = &scene.lights[light_index as usize];
            if let Some(emitted) = light.radiance_on_hit(ray.direction, hit.normal, sphere) {
                let weight = if last_specular || !nee {
                    1.0
                } else {
                    let distance = hit.distance + origin_offset;
                    let direct_pdf = emitted.direct_pdf.to_solid_angle(distance * distance, emitted.cos_at_light);
                    balance_heuristic(last_pdf, direct_pdf.0 * scene.light_pick_probability(light_index))
                };
                result += throughput * view(&slots, scene.emission::<S>(light_index, w, emitted.radiance)) * weight;
            }
        }
        if path_length >= max_length {
            break;
        }

        let Some(bsdf) =
            Bsdf::new_at(scene.material(&hit), &hit.shading_point(), -ray.direction, TransportMode::Radiance, hero)
        else {
            break;
        };
        let continuation = bsdf.continuation_probability();
        let fluorescent = FluorescentVertex::at(scene.material(&hit), hit.uv);

        // Next-event estimation (a path one segment longer).
        if nee
            && !bsdf.is_delta()
            && let Some((index, light, pick)) = scene.pick_light(rng.uniform())
        {
            let u = rng.uniform2();
            if let Some(direct) = light.sample_direct(hit.position, u, sphere)
                && let Some(eval) = bsdf.evaluate(direct.direction)
                && !scene.occluded(hit.position, direct.direction, direct.distance)
            {
                let light_pdf = direct.direct_pdf.0 * pick;
                let weight = if light.is_delta() {
                    1.0
                } else {
                    balance_heuristic(light_pdf, eval.pdf.forward.0 * continuation)
                };
                let emitted = scene.emission::<S>(index, w, direct.radiance);
                let scale = eval.cos_generated * weight / light_pdf;
                if fluorescent.is_none() && slots == S::Slots::default() {
                    // The RGB-era product order, so that RGB renders stay bit-identical.
                    result += throughput * emitted * S::from_reflectance(w, eval.value) * scale;
                } else {
                    let arriving = scatter_slots(fluorescent.as_ref(), w, eval.value, emitted, rng);
                    result += throughput * view(&slots, arriving) * scale;
                }
            }
        }

        // Continue by BSDF sampling, with Russian roulette.
        let Some(sample) = bsdf.sample(rng.uniform3()) else { break };
        if continuation < 1.0 && rng.uniform() >= continuation {
            break;
        }
        let pdf = sample.pdf.forward.0 * continuation;
        match &fluorescent {
            None => throughput *= view(&slots, S::from_reflectance(w, sample.value)) * (sample.cos_generated / pdf),
            Some(f) => {
                let label = f.sample_label::<S>(rng.uniform());
                throughput =
                    f.apply_camera(w, label, sample.value, &mut slots, throughput) * (sample.cos_generated / pdf);
            }
        }
        if sample.dispersive && !terminated {
            throughput = throughput.terminate_secondary();
            terminated = true;
        }
        last_pdf = pdf;
        last_specular = sample.lobe.is_specular();
        ray = Ray::new(hit.position + RAY_EPSILON * sample.direction, sample.direction);
        origin_offset = RAY_EPSILON;
        path_length += 1;
    }
    result
}
