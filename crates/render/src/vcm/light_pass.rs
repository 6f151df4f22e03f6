//! The light pass: traces light sub-paths, stores their non-specular vertices and connects
//! each to the camera (t = 1).

use math::{RAY_EPSILON, Ray, Rng, Vec3};
use scene::{Bsdf, Scene, TransportMode};
use spectrum::SpectralMode;

use crate::fluorescent::FluorescentVertex;

use super::Iteration;
use super::connect::{LightEnd, Splat, connect_emitter_to_camera, connect_to_camera};
use super::light_vertex::{LightVertex, NormalCodes, VertexData};
use super::medium::{Arrival, Flight, MediumSide, Scatterer, advance};
use super::mis::SubPathMis;
use super::subpath::{NullSurface, SubPath};

/// Stream selector of the camera connections' generator.
const CAMERA_CONNECTIONS: u64 = 0x6361_6d65_7261;

/// The numbers a light sub-path's start draws from its generator, in this order.
struct PathStart {
    /// Seeds the camera connections' generator (two draws, high word first).
    camera_seed: u64,
    /// Picks the light ([`Scene::pick_light`]).
    pick_u: f32,
    /// The point on the light.
    u_position: [f32; 2],
    /// The direction of emission.
    u_direction: [f32; 2],
}

impl PathStart {
    #[inline]
    fn draw(rng: &mut Rng) -> Self {
        let high = u64::from(rng.next_u32());
        let camera_seed = high << 32 | u64::from(rng.next_u32());
        PathStart { camera_seed, pick_u: rng.uniform(), u_position: rng.uniform2(), u_direction: rng.uniform2() }
    }
}

/// A prefetch hint for the emission sample of the light sub-path that `rng` (its generator,
/// not yet drawn from) will start: when it picks an environment map, the map's tables and texels
/// (megabytes, read at random) are fetched while the caller traces the sub-path before it
/// ([`scene::Light::prefetch_emission`]). Reads a copy of the generator: no value changes.
/// Worth calling only when [`Scene::has_prefetchable_background`].
#[inline]
pub fn prefetch_light_path(scene: &Scene, rng: &Rng) {
    let start = PathStart::draw(&mut rng.clone());
    if let Some((_, light, _)) = scene.pick_light(start.pick_u) {
        light.prefetch_emission(start.u_direction);
    }
}

/// Traces one light sub-path: appends its stored vertices to `vertices` and its camera
/// connections to `splats`. `codes` caches the codes of the stored normals (pass the same one
/// for the light sub-paths traced one after another).
///
/// The walk draws from `rng`; the camera connections draw from a generator seeded by the walk's
/// first two numbers, so the walk (and the stored vertices) are the same whether or not the
/// iteration's techniques connect to the camera: the memory-efficient mode traces each light
/// sub-path twice, once for merging without camera connections and once with them.
pub fn trace_light_path<S: SpectralMode>(
    scene: &Scene,
    it: &Iteration,
    rng: &mut Rng,
    vertices: &mut Vec<LightVertex<S>>,
    splats: &mut Vec<Splat>,
    wavelengths: &S::Wavelengths,
    codes: &mut NormalCodes,
) {
    let hero = S::hero_wavelength(wavelengths);
    let k = &it.constants;
    let techniques = &it.techniques;
    let PathStart { camera_seed, pick_u, u_position, u_direction } = PathStart::draw(rng);
    let mut camera_rng = Rng::new(camera_seed, CAMERA_CONNECTIONS);
    let Some((index, light, pick)) = scene.pick_light(pick_u) else { return };
    // With MIS compensation, `direct_pdf` is the compensated density's: the next-event
    // technique's pdf in the sub-path's MIS quantities.
    let emission = if it.mis_compensation {
        light.sample_emission_compensated(u_position, u_direction, &scene.bounding_sphere)
    } else {
        light.sample_emission(u_position, u_direction, &scene.bounding_sphere)
    };
    let emission_pdf = emission.emission_pdf.0 * pick;
    let direct_pdf = emission.direct_pdf.0 * pick;
    if emission_pdf.is_nan() || emission_pdf <= 0.0 || emission.energy.is_black() {
        return;
    }
    // Light tracing alone shows the emitters seen directly by connecting y₀ (s = 1, t = 1).
    if techniques.light_trace_only && it.max_length >= 1 {
        connect_emitter_to_camera::<S>(scene, it, index, &emission, direct_pdf, &mut camera_rng, splats, wavelengths);
    }
    let media_active = scene.media.is_active();
    let cos_used = if light.is_finite() { emission.cos_at_light } else { 1.0 };
    let mut path = SubPath {
        ray: Ray::new(emission.origin + RAY_EPSILON * emission.direction, emission.direction),
        throughput: scene.emission::<S>(index, wavelengths, emission.energy) / emission_pdf,
        path_length: 1,
        mis: SubPathMis::light_start(emission_pdf, direct_pdf, cos_used, light.is_delta(), k),
        is_finite_light: light.is_finite(),
        specular_path: true,
        origin_offset: RAY_EPSILON,
        terminated: false,
        slots: S::Slots::default(),
        flight: Flight {
            unresolved: media_active,
            fallback: if light.is_finite() { scene.media.camera } else { None },
            ..Flight::start(None, false, RAY_EPSILON)
        },
    };

    loop {
        let arrival = if media_active {
            let p = &mut path;
            advance(scene, &mut p.ray, &mut p.origin_offset, &mut p.flight, &mut p.throughput, rng, wavelengths)
        } else {
            scene.intersect(&path.ray).map_or(Arrival::Escaped, Arrival::Surface)
        };
        let hit = match arrival {
            Arrival::Surface(hit) => hit,
            Arrival::Escaped => break,
            Arrival::Medium { position, distance, medium } => {
                if !medium_vertex(
                    scene,
                    it,
                    &mut path,
                    position,
                    distance,
                    medium,
                    rng,
                    vertices,
                    splats,
                    &mut camera_rng,
                    wavelengths,
                ) {
                    break;
                }
                continue;
            }
        };
        // A thin dielectric's straight-through transmission is no vertex in media.
        let mut presampled = None;
        if media_active {
            match path.cross_null_surface(scene, &hit, TransportMode::Importance, hero, rng, wavelengths) {
                NullSurface::Crossed => continue,
                NullSurface::Stop => break,
                NullSurface::Vertex(sample) => presampled = sample,
            }
        }
        let fixed = -path.ray.direction;
        // Borrowed, not moved out of the `Option`: a move copies the several-hundred-byte BSDF.
        let built = Bsdf::new_at(scene.material(&hit), &hit.shading_point(), fixed, TransportMode::Importance, hero);
        let Some(bsdf) = built.as_ref() else {
            break;
        };
        let distance_squared = path.arrival_distance_squared(hit.distance);
        path.mis.arrive(distance_squared, bsdf.cos_fixed());
        if media_active {
            path.mis.apply_flight(path.flight.forward, path.flight.reverse);
        }
        let side = MediumSide::at_surface(scene, &hit, path.flight.medium);
        let fluorescent = FluorescentVertex::at(scene.material(&hit), hit.uv);

        if !bsdf.is_delta() {
            if techniques.store_light_vertices() {
                let flags = scene.material_flags(hit.material);
                let data = VertexData {
                    position: hit.position,
                    throughput: path.throughput,
                    mis: path.mis,
                    path_length: path.path_length,
                    material: hit.material,
                    normal: hit.normal,
                    shading_normal: hit.shading_normal,
                    uv: hit.uv,
                    tangent: flags.anisotropic.then_some(hit.tangent),
                    attribute: flags.reads_mesh_attribute.then_some(hit.attribute),
                    fixed,
                    continuation: bsdf.continuation_probability(),
                    terminated: path.terminated,
                };
                vertices.push(LightVertex::with_normal_codes(&data, codes));
            }
            if techniques.connect_to_camera() && path.path_length < it.max_length {
                let endpoint = LightEnd {
                    scatterer: Scatterer::Surface(bsdf),
                    position: hit.position,
                    fluorescent: fluorescent.as_ref(),
                    side,
                };
                connect_to_camera(
                    scene,
                    &path,
                    &endpoint,
                    techniques.connect,
                    it,
                    &mut camera_rng,
                    splats,
                    wavelengths,
                );
            }
        }
        // A longer light sub-path could not be connected to any camera vertex.
        if path.path_length + 2 > it.max_length {
            break;
        }
        if path
            .scatter(bsdf, hit.position, rng, false, k, wavelengths, fluorescent.as_ref(), false, presampled)
            .is_none()
        {
            break;
        }
        path.flight = Flight::start(side.towards(path.ray.direction), false, RAY_EPSILON);
    }
}

/// A light sub-path's vertex in medium `medium` at `distance` along its ray: completes the MIS
/// quantities (no cosine, `super::medium`), stores it, connects it to the camera and scatters
/// with the phase function. Returns false when the walk ends.
#[allow(clippy::too_many_arguments)]
fn medium_vertex<S: SpectralMode>(
    scene: &Scene,
    it: &Iteration,
    path: &mut SubPath<S>,
    position: Vec3,
    distance: f32,
    medium: u32,
    rng: &mut Rng,
    vertices: &mut Vec<LightVertex<S>>,
    splats: &mut Vec<Splat>,
    camera_rng: &mut Rng,
    wavelengths: &S::Wavelengths,
) -> bool {
    if path.throughput.is_black() {
        return false;
    }
    let techniques = &it.techniques;
    let m = scene.media.medium(medium);
    let fixed = -path.ray.direction;
    let distance_squared = path.arrival_distance_squared(distance);
    path.mis.arrive(distance_squared, 1.0);
    path.mis.apply_flight(path.flight.forward, path.flight.reverse);
    if techniques.store_light_vertices() {
        vertices.push(LightVertex::new_in_medium(
            position,
            path.throughput,
            path.mis,
            path.path_length,
            medium,
            fixed,
            m.max_albedo(),
            path.terminated,
        ));
    }
    if techniques.connect_to_camera() && path.path_length < it.max_length {
        let endpoint = LightEnd {
            scatterer: Scatterer::Medium(m, fixed),
            position,
            fluorescent: None,
            side: MediumSide::inside(Some(medium)),
        };
        connect_to_camera(scene, path, &endpoint, techniques.connect, it, camera_rng, splats, wavelengths);
    }
    if path.path_length + 2 > it.max_length {
        return false;
    }
    path.scatter_medium(m, medium, position, rng, &it.constants)
}
