//! The camera pass: one camera sub-path per pixel; at every vertex the emitter hit (s = 0),
//! next-event estimation (s = 1), connections to the pixel's light sub-path (s, t > 1) and
//! merges with all light vertices in range (s, t ≥ 2), then BSDF sampling with Russian
//! roulette. A surface vertex's merges are usually computed after the next ray has been traced,
//! so that the light vertices they read have arrived in the cache (same results: see "The merge
//! after the next ray" in the loop).

use math::{RAY_EPSILON, Ray, Rng, Vec3};
use scene::camera::PrimaryDensity;
use scene::light::Light;
use scene::{Bsdf, Scene, SurfaceHit, TransportMode};
use spectrum::SpectralMode;

use super::connect::{CameraEnd, LightBsdfs, connect_vertices, next_event};
use super::light_vertex::LightPath;
use super::medium::{Arrival, Flight, MediumSide, Scatterer, advance};
use super::merge::{GroupThroughputs, MergeScope, MergeSource, MergeWeighting, merge};
use super::mis::{self, SubPathMis};
use super::subpath::{NullSurface, SubPath};
use super::technique_images::{Record, TechniqueValues};
use super::{Family, FamilyValues, Iteration, Techniques};
use crate::fluorescent::{FluorescentVertex, view};
use crate::hash_grid::GridQuery;
use crate::path_tracer::LightSampler;

/// Traces the camera sub-path through raster pixel `(x, y)` and returns its contributions by
/// technique family.
#[allow(clippy::too_many_arguments)]
pub fn trace_camera_path<S: SpectralMode>(
    scene: &Scene,
    it: &Iteration,
    x: u32,
    y: u32,
    rng: &mut Rng,
    light_path: LightPath<S>,
    merge_source: Option<&MergeSource<S>>,
    wavelengths: &S::Wavelengths,
) -> FamilyValues {
    let mut out = FamilyValues::default();
    trace_camera_path_into(scene, it, x, y, rng, light_path, merge_source, wavelengths, &mut out);
    out
}

/// [`trace_camera_path`], also filing every contribution under its (s, t) image when
/// `techniques` is given; returns the family values (an overflowing estimate discarded in the
/// images too, see [`TechniqueValues::finish`]).
#[allow(clippy::too_many_arguments)]
pub fn trace_camera_path_recorded<S: SpectralMode>(
    scene: &Scene,
    it: &Iteration,
    x: u32,
    y: u32,
    rng: &mut Rng,
    light_path: LightPath<S>,
    merge_source: Option<&MergeSource<S>>,
    wavelengths: &S::Wavelengths,
    techniques: Option<TechniqueValues>,
) -> FamilyValues {
    match techniques {
        None => trace_camera_path(scene, it, x, y, rng, light_path, merge_source, wavelengths),
        Some(mut values) => {
            trace_camera_path_into(scene, it, x, y, rng, light_path, merge_source, wavelengths, &mut values);
            values.finish()
        }
    }
}

/// Traces the camera sub-path through raster pixel `(x, y)` and records its contributions in
/// `out`, each with its technique's (s, t) (see [`super::technique_images`]): at camera vertex
/// `z_{t−1}` (the sub-path has `t` vertices, `path_length = t − 1` segments) an emitter hit
/// there is (0, t), next-event estimation from it (1, t), a connection to light vertex
/// `y_{s−1}` (s, t) and a merge with it (s, t).
#[allow(clippy::too_many_arguments)]
pub fn trace_camera_path_into<S: SpectralMode, R: Record>(
    scene: &Scene,
    it: &Iteration,
    x: u32,
    y: u32,
    rng: &mut Rng,
    light_path: LightPath<S>,
    merge_source: Option<&MergeSource<S>>,
    wavelengths: &S::Wavelengths,
    out: &mut R,
) {
    // Its vertices lie scattered over the store: start their cache misses before the first ray.
    if it.techniques.connect {
        light_path.prefetch();
    }
    let w = wavelengths;
    let hero = S::hero_wavelength(w);
    let techniques = &it.techniques;
    let pixel = (y * scene.camera.width + x) as usize;
    // The constants (radius) of this camera path: global, or the pixel's own (§6.1).
    let k = &it.pixel_constants(pixel);
    let radius = it.pixel_radius(pixel);
    let camera = &scene.camera;
    // Raster position through the filter (its weight starts the throughput), then the lens.
    let primary = camera.sample_primary(x, y, it.film_offset, rng);
    // The start density for MIS: per solid angle for perspective cameras; per area on the
    // film for the orthographic camera, whose first segment then takes no distance factor
    // (like the first segment from an infinite light, §5.2).
    let (camera_pdf, distance_on_first_segment) = match camera.primary_density(primary.ray.direction) {
        PrimaryDensity::SolidAngle(pdf) => (pdf.0, true),
        PrimaryDensity::Area(pdf) => (pdf.0, false),
    };
    let media_active = scene.media.is_active();
    let mut path = SubPath {
        ray: primary.ray,
        throughput: S::splat(primary.weight),
        path_length: 1,
        mis: SubPathMis::camera_start(camera_pdf, k),
        is_finite_light: distance_on_first_segment,
        specular_path: true,
        origin_offset: 0.0,
        terminated: false,
        slots: S::Slots::default(),
        flight: Flight::start(scene.media.camera, false, 0.0),
    };
    // Merging across wavelength groups: the throughput at every group's wavelengths (computed
    // when a merge needs it).
    let group_sets = match merge_source.map(|s| s.scope) {
        Some(MergeScope::AcrossGroups(_, sets)) => sets,
        _ => &[],
    };
    let mut group_throughputs = (!group_sets.is_empty()).then(|| GroupThroughputs::new(group_sets, path.throughput));
    // The light sub-path's BSDFs, built on first use and shared by all camera vertices.
    let mut light_bsdfs = LightBsdfs::new(hero);
    // Next-event estimation draws first at a surface vertex (s = 1, below): an environment
    // map's sample can be prefetched while the ray to the vertex is traced (not in media, where
    // the flight draws before it).
    let hint = techniques.connect && !media_active && scene.has_prefetchable_background();
    // Plans a hit's merge query and starts its first cache misses, unless no merge can happen
    // there (a purely specular material: its BSDF is delta or absent).
    let plan_at = |hit: &SurfaceHit| {
        let source = merge_source?;
        (!scene.material_flags(hit.material).specular_only).then(|| source.plan_and_prefetch(hit.position))
    };
    // The next surface the path's ray meets, outside media, with the environment map's
    // next-event sample hinted first (see `hint`).
    let next_surface = |ray: &Ray, rng: &mut Rng| {
        if hint {
            LightSampler::Power.prefetch_next_event(scene, rng, it.mis_compensation);
        }
        scene.intersect(ray)
    };
    // The next ray's arrival and merge query when the last vertex traced it before its merge
    // (see "The merge after the next ray" below).
    let mut traced: Option<(Arrival, Option<GridQuery>)> = None;

    loop {
        let (arrival, planned) = match traced.take() {
            Some((arrival, planned)) => (arrival, Some(planned)),
            None => {
                let arrival = if media_active {
                    // (`hint` is off in media.)
                    let p = &mut path;
                    advance(scene, &mut p.ray, &mut p.origin_offset, &mut p.flight, &mut p.throughput, rng, w)
                } else {
                    next_surface(&path.ray, rng).map_or(Arrival::Escaped, Arrival::Surface)
                };
                (arrival, None)
            }
        };
        if let Arrival::Medium { position, distance, medium } = arrival {
            let args = (position, distance, medium);
            let lights = (light_path, &mut light_bsdfs);
            if !medium_vertex(scene, it, &mut path, args, rng, lights, merge_source, k, radius, w, out) {
                break;
            }
            continue;
        }
        let Arrival::Surface(hit) = arrival else {
            if media_active {
                path.mis.apply_flight(path.flight.forward, path.flight.reverse);
            }
            // Escaped: the environment light (infinite: no distance update, §5.1).
            let direction = path.ray.direction;
            let escaped = |light: &Light| {
                // With MIS compensation the next-event technique's pdf is the compensated one.
                if it.mis_compensation {
                    light.radiance_on_hit_compensated(direction, Vec3::ZERO, Vec3::ZERO, &scene.bounding_sphere)
                } else {
                    light.radiance_on_hit(direction, Vec3::ZERO, Vec3::ZERO, &scene.bounding_sphere)
                }
            };
            if let Some(index) = scene.background
                && let Some(emitted) = escaped(&scene.lights[index as usize])
                && let pick = scene.light_pick_probability(index)
                && let Some(weight) =
                    emitter_weight(&path, techniques, emitted.direct_pdf.0 * pick, emitted.emission_pdf.0 * pick)
            {
                let value =
                    path.throughput * view(&path.slots, scene.emission::<S>(index, w, emitted.radiance)) * weight;
                // The environment is the camera sub-path's last vertex.
                out.record(Family::EmitterHit, 0, path.path_length + 1, value.to_rgb(w));
            }
            break;
        };
        // The merge query's cache misses start now and are over by the time it comes.
        let grid_query = planned.unwrap_or_else(|| plan_at(&hit));
        // A thin dielectric's straight-through transmission is no vertex in media.
        let mut presampled = None;
        if media_active {
            match path.cross_null_surface(scene, &hit, TransportMode::Radiance, hero, rng, w) {
                NullSurface::Crossed => continue,
                NullSurface::Stop => break,
                NullSurface::Vertex(sample) => presampled = sample,
            }
        }
        let direction = path.ray.direction;
        let cos_fixed = hit.normal.dot(-direction).abs();
        let distance_squared = path.arrival_distance_squared(hit.distance);
        path.mis.arrive(distance_squared, cos_fixed);
        if media_active {
            path.mis.apply_flight(path.flight.forward, path.flight.reverse);
        }
        let side = MediumSide::at_surface(scene, &hit, path.flight.medium);
        // Camera sub-path vertices up to this hit.
        let t = path.path_length + 1;

        // Emitter hit (s = 0).
        if let Some(light_index) = hit.light
            && let Some(emitted) = scene.lights[light_index as usize].radiance_on_hit(
                direction,
                hit.position,
                hit.normal,
                &scene.bounding_sphere,
            )
            && let pick = scene.light_pick_probability(light_index)
            && let Some(weight) =
                emitter_weight(&path, techniques, emitted.direct_pdf.0 * pick, emitted.emission_pdf.0 * pick)
        {
            let value =
                path.throughput * view(&path.slots, scene.emission::<S>(light_index, w, emitted.radiance)) * weight;
            out.record(Family::EmitterHit, 0, t, value.to_rgb(w));
        }
        // Borrowed, not moved out of the `Option`: a move copies the several-hundred-byte BSDF.
        let built = Bsdf::new_at(scene.material(&hit), &hit.shading_point(), -direction, TransportMode::Radiance, hero);
        let Some(bsdf) = built.as_ref() else {
            break;
        };
        if path.path_length >= it.max_length {
            break;
        }

        let fluorescent = FluorescentVertex::at(scene.material(&hit), hit.uv);
        let end = CameraEnd {
            scatterer: Scatterer::Surface(bsdf),
            position: hit.position,
            fluorescent: fluorescent.as_ref(),
            side,
            grid_query,
        };
        let mut specular_only = false;
        // The sub-path as it arrived here, for a merge done after the next ray.
        let mut merge_later = None;
        if !bsdf.is_delta() {
            if techniques.connect {
                // Next-event estimation (s = 1).
                out.record(
                    Family::NextEvent,
                    1,
                    t,
                    next_event(scene, &path, &end, rng, k, it.mis_compensation, w).to_rgb(w),
                );
            }
            if let (Some(source), Some(plan)) = (merge_source, &grid_query) {
                source.prefetch_records(plan);
            }
            if techniques.connect {
                // Connections to the pixel's light sub-path (s, t > 1), stored in path order.
                for (index, light) in light_path.iter().enumerate() {
                    if light.record.path_length() + 1 + path.path_length > it.max_length {
                        break;
                    }
                    let value = connect_vertices(scene, &path, &end, (light, index), &mut light_bsdfs, k, w, rng);
                    out.record(Family::Connection, light.record.path_length() + 1, t, value.to_rgb(w));
                }
            }
            // The merge after the next ray: the merge query's records, hinted above, have until
            // then to arrive (its bucket starts were hinted at the hit). The result is that of
            // merging now: a merge draws no random number unless the vertex is fluorescent,
            // and it adds to its own family's sums (and images), whose order is unchanged. Not
            // for fluorescent vertices, merges across wavelength groups (whose throughputs the
            // scattering changes), photon mapping (which may end the path here) or media
            // (whose walk draws numbers before the next surface).
            let later = merge_source.is_some()
                && end.fluorescent.is_none()
                && group_throughputs.is_none()
                && !techniques.ppm
                && !media_active;
            if later {
                merge_later = Some(path);
            } else if let Some(source) = merge_source {
                let weighting = if techniques.ppm { MergeWeighting::None } else { MergeWeighting::Mis };
                let merged = merge(
                    &path,
                    group_throughputs.as_mut(),
                    &end,
                    source,
                    radius,
                    it.max_length,
                    weighting,
                    k,
                    w,
                    rng,
                    out,
                );
                out.record(Family::Merging, 0, t, merged);
                // Photon mapping stops at the first non-specular vertex; through a mixed
                // vertex it continues along the specular lobes only.
                if techniques.ppm {
                    if !bsdf.has_specular() {
                        break;
                    }
                    specular_only = true;
                }
            }
        }
        let scattered =
            path.scatter(bsdf, hit.position, rng, specular_only, k, w, fluorescent.as_ref(), true, presampled);
        if let Some(scattered) = scattered {
            path.flight = Flight::start(side.towards(path.ray.direction), false, RAY_EPSILON);
            // No fluorescence here: the step is what `SubPath::scatter` applied.
            if let Some(throughputs) = &mut group_throughputs {
                throughputs.push(scattered);
            }
        }
        if let (Some(arrived), Some(source)) = (merge_later, merge_source) {
            if scattered.is_some() {
                // Trace the next ray (as the loop's start would: `merge_later` excludes media)
                // and start its merge query's misses, then merge here.
                let next = next_surface(&path.ray, rng);
                let next_query = next.as_ref().and_then(plan_at);
                traced = Some((next.map_or(Arrival::Escaped, Arrival::Surface), next_query));
            }
            let merged =
                merge(&arrived, None, &end, source, radius, it.max_length, MergeWeighting::Mis, k, w, rng, out);
            out.record(Family::Merging, 0, t, merged);
        }
        if scattered.is_none() {
            break;
        }
    }
}

/// A camera sub-path's vertex in a medium (`args`: position, distance along the ray, medium
/// index): next-event estimation, connections to the pixel's light sub-path (with its BSDFs
/// kept for the camera sub-path) and merges (medium
/// vertices merge with medium vertices), then phase sampling. Returns false when the walk ends.
/// (Camera paths in media never merge across wavelength groups: the engine groups such
/// scenes.)
#[allow(clippy::too_many_arguments)]
fn medium_vertex<S: SpectralMode, R: Record>(
    scene: &Scene,
    it: &Iteration,
    path: &mut SubPath<S>,
    (position, distance, medium): (Vec3, f32, u32),
    rng: &mut Rng,
    (light_path, light_bsdfs): (LightPath<S>, &mut LightBsdfs),
    merge_source: Option<&MergeSource<S>>,
    k: &mis::MisConstants,
    radius: f32,
    w: &S::Wavelengths,
    out: &mut R,
) -> bool {
    if path.throughput.is_black() {
        return false;
    }
    let techniques = &it.techniques;
    let distance_squared = path.arrival_distance_squared(distance);
    path.mis.arrive(distance_squared, 1.0);
    path.mis.apply_flight(path.flight.forward, path.flight.reverse);
    if path.path_length >= it.max_length {
        return false;
    }
    let t = path.path_length + 1;
    let m = scene.media.medium(medium);
    let end = CameraEnd {
        scatterer: Scatterer::Medium(m, -path.ray.direction),
        position,
        fluorescent: None,
        side: MediumSide::inside(Some(medium)),
        grid_query: None,
    };
    if techniques.connect {
        out.record(Family::NextEvent, 1, t, next_event(scene, path, &end, rng, k, it.mis_compensation, w).to_rgb(w));
        for (index, light) in light_path.iter().enumerate() {
            if light.record.path_length() + 1 + path.path_length > it.max_length {
                break;
            }
            let value = connect_vertices(scene, path, &end, (light, index), light_bsdfs, k, w, rng);
            out.record(Family::Connection, light.record.path_length() + 1, t, value.to_rgb(w));
        }
    }
    if let Some(source) = merge_source {
        let weighting = if techniques.ppm { MergeWeighting::None } else { MergeWeighting::Mis };
        let merged = merge(path, None, &end, source, radius, it.max_length, weighting, k, w, rng, out);
        out.record(Family::Merging, 0, t, merged);
        if techniques.ppm {
            return false;
        }
    }
    path.scatter_medium(m, medium, position, rng, k)
}

/// MIS weight of an emitter hit, or `None` when the enabled techniques do not count it.
fn emitter_weight<S: SpectralMode>(
    path: &SubPath<S>,
    techniques: &Techniques,
    direct_pdf_a: f32,
    emission_pdf_w: f32,
) -> Option<f32> {
    if path.path_length == 1 {
        // Seen directly: no other technique samples it.
        return Some(1.0);
    }
    if !techniques.connect {
        // Merging only (PPM, BPM): purely specular camera paths are the only way to these
        // paths; the rest is found by merging.
        return path.specular_path.then_some(1.0);
    }
    Some(mis::emitter_hit_weight(&path.mis, direct_pdf_a, emission_pdf_w))
}
