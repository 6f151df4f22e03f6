//! Vertex connection techniques: a light vertex to the camera (t = 1), a camera vertex to a
//! light (s = 1, next-event estimation), a camera vertex to a light vertex (s, t > 1), and the
//! weight of an emitter hit by a camera path (s = 0); and [`LightBsdfs`], the light sub-path's
//! BSDFs built once per camera sub-path.

use math::{Rng, Vec2, Vec3};
use scene::camera::CameraConnection;
use scene::filter::FilmMode;
use scene::light::EmissionSample;
use scene::{Bsdf, Scene};
use spectrum::{Rgb, SpectralMode};

use super::Iteration;
use super::light_vertex::LightVertex;
use super::medium::{MediumSide, Scatterer, segment};
use super::mis::{self, ConnectionPdfs, MisConstants, NeePdfs};
use super::subpath::SubPath;
use crate::fluorescent::{FluorescentVertex, scatter_slots, view};
use crate::hash_grid::GridQuery;

/// A light-tracing contribution.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Splat {
    /// Where it goes.
    pub target: SplatTarget,
    /// Contribution (already divided by the number of light sub-paths; for
    /// [`SplatTarget::Pixel`] already multiplied by the filter value).
    pub value: Rgb,
    /// Vertices of the light sub-path, the connected one included: the `s` of the t = 1
    /// technique, for per-(s, t) images.
    pub s: u32,
}

/// Where a light-tracing contribution is added.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SplatTarget {
    /// Added as is to this pixel (row-major index).
    Pixel(u32),
    /// Spread over the pixels [`scene::Camera::filter_pixels`] lists for this raster position
    /// (pixels), each receiving `value × f(raster − centre)/∫f` (`/N_j` under
    /// [`scene::filter::FilmMode::Splat`], [`scene::Camera::splat_weight`]).
    Filtered(Vec2),
}

/// Connects light sub-path vertex `position` (with `bsdf`) to the camera (t = 1) and appends
/// the resulting splats: none if the vertex projects where no pixel's filter reaches, faces
/// away or is occluded. The thin lens draws its lens point from `rng` (two numbers, drawn
/// before anything can fail); the other cameras draw nothing. `weighted = false` gives plain
/// light tracing (weight 1).
///
/// The weight uses the constants of the pixel the splat is added to: with a per-pixel radius
/// and a filter wider than the box, one splat per pixel in the filter's reach, each weighted
/// for its pixel; otherwise a single splat (the pixel the vertex lands in for the box filter,
/// the raster position for the others).
#[allow(clippy::too_many_arguments)]
pub fn connect_to_camera<S: SpectralMode>(
    scene: &Scene,
    light: &SubPath<S>,
    end: &LightEnd,
    weighted: bool,
    it: &Iteration,
    rng: &mut Rng,
    splats: &mut Vec<Splat>,
    wavelengths: &S::Wavelengths,
) {
    let (scatterer, position) = (&end.scatterer, end.position);
    let camera = &scene.camera;
    let u_lens = if camera.needs_lens_sample() { rng.uniform2() } else { [0.5, 0.5] };
    let Some(connection) = camera.connect(position, u_lens) else { return };
    let Some(eval) = scatterer.evaluate(connection.direction) else { return };
    // With media: the segment's transmittance, and the camera ray's free-flight density of
    // reaching this vertex (the segment's reverse product, `super::medium`).
    let media = if scene.media.is_active() {
        let towards = end.side.towards(connection.direction);
        let d = connection.distance;
        let Some(segment) = segment::<S>(
            scene,
            position,
            connection.direction,
            d,
            towards,
            scatterer.is_medium(),
            false,
            wavelengths,
            rng,
        ) else {
            return;
        };
        Some(segment)
    } else {
        None
    };
    // Density of the camera sampling this point: image-plane density 1 per pixel, to area at
    // the vertex (the thin lens' lens-point density cancels between techniques). It is also the
    // camera's importance times the geometry term in the estimate. With media the weight
    // takes the camera ray's free-flight density of reaching the vertex on top (`mis_pdf_a`).
    let camera_pdf_a = connection.area_pdf(eval.cos_generated).0;
    let mis_pdf_a = match &media {
        Some(segment) => connection.area_pdf(eval.cos_generated * segment.reverse).0,
        None => camera_pdf_a,
    };
    let reverse = eval.reverse * scatterer.continuation();
    // The pixel integral is over the image plane: the estimate is f·T·(camera pdf)/N_L.
    let unweighted = match &media {
        Some(segment) => scatterer.spectral::<S>(wavelengths, eval.value) * light.throughput * segment.transmittance,
        None => scatter_slots(end.fluorescent, wavelengths, eval.value, light.throughput, rng),
    }
    .to_rgb(wavelengths);
    let weight_for = |k: &MisConstants| {
        if weighted {
            let light_mis = if it.rebase() { light.mis.for_constants(k) } else { light.mis };
            mis::camera_connection_weight_at(&light_mis, mis_pdf_a, reverse, k, k.eta_scale(scatterer.is_medium()))
        } else {
            1.0
        }
    };
    // With media the segment's transmittance already accounts for what blocks it.
    let shadow_from = media.is_none().then_some(position);
    let s = light.path_length + 1;
    push_camera_splats(scene, it, &connection, unweighted, camera_pdf_a, weighted, weight_for, s, shadow_from, splats);
}

/// Appends the splats of a camera connection whose contribution before weighting and before the
/// camera's density is `unweighted` (RGB), `camera_pdf_a` the camera's density of sampling the
/// point (area) and `weight_for(k)` its MIS weight under the constants `k`; `s` light sub-path
/// vertices. Where they go depends on the filter and the film (see [`connect_to_camera`]). With
/// `shadow_from`, the segment from that point to the camera is then tested, and the splats are
/// taken back if it is blocked (no shadow ray when nothing was splatted).
#[allow(clippy::too_many_arguments)]
fn push_camera_splats(
    scene: &Scene,
    it: &Iteration,
    connection: &CameraConnection,
    unweighted: Rgb,
    camera_pdf_a: f32,
    weighted: bool,
    weight_for: impl Fn(&MisConstants) -> f32,
    s: u32,
    shadow_from: Option<Vec3>,
    splats: &mut Vec<Splat>,
) {
    let start = splats.len();
    let camera = &scene.camera;
    if camera.filter.is_box() {
        let Some((pixel, _)) = camera.filter_pixels(connection.raster).next() else { return };
        let k = &it.pixel_constants(pixel as usize);
        let value = unweighted * (weight_for(k) * camera_pdf_a / k.light_path_count);
        if !value.is_black() {
            splats.push(Splat { target: SplatTarget::Pixel(pixel), value, s });
        }
    } else if it.rebase() && weighted && camera.film == FilmMode::Fis {
        // Every pixel weighs the path with its own radius (its camera samples, spread by the
        // filter around its centre, use that radius).
        for (pixel, filter) in camera.filter_pixels(connection.raster) {
            let k = &it.pixel_constants(pixel as usize);
            let value = unweighted * (weight_for(k) * camera_pdf_a * filter / k.light_path_count);
            if !value.is_black() {
                splats.push(Splat { target: SplatTarget::Pixel(pixel), value, s });
            }
        }
    } else {
        // Splatting: every pixel counts the camera samples of the pixel containing the raster
        // point, so the path takes that pixel's constants.
        let containing = || {
            let (x, y) = (connection.raster.x as u32, connection.raster.y as u32);
            (y.min(camera.height - 1) * camera.width + x.min(camera.width - 1)) as usize
        };
        let k = if it.rebase() { &it.pixel_constants(containing()) } else { &it.constants };
        let value = unweighted * (weight_for(k) * camera_pdf_a / k.light_path_count);
        if !value.is_black() {
            splats.push(Splat { target: SplatTarget::Filtered(connection.raster), value, s });
        }
    }
    if let Some(point) = shadow_from
        && splats.len() > start
        && scene.occluded(point, connection.direction, connection.distance)
    {
        splats.truncate(start);
    }
}

/// Light tracing alone (`lt`): the light sub-path's first vertex, on the emitter, connected to
/// the camera (s = 1, t = 1), so that emitters seen directly appear as they do with Mitsuba's
/// particle tracer. No other technique of `lt` samples these paths (its camera sub-paths trace
/// nothing), so the weight is 1; the algorithms with camera sub-paths see emitters by hitting
/// them (s = 0) and do not call this. The estimate is `L_e(y₀ → camera) · p_cam,A(y₀) /
/// (p_A(y₀) · N_L)`, `p_A(y₀)` the area density of the emission sample's point (light choice
/// included, `position_pdf`) and `p_cam,A` the camera's density of sampling `y₀` (area, with the
/// cosine at the light), as for the other light-tracing splats. Only area and textured-triangle
/// lights have a point to connect (point-like and infinite lights cannot be seen), and the
/// connection is not made in scenes with media (their segment would need the transmittance;
/// `lt` there still leaves emitters seen directly black). The thin lens draws its lens point
/// from `rng`.
#[allow(clippy::too_many_arguments)]
pub fn connect_emitter_to_camera<S: SpectralMode>(
    scene: &Scene,
    it: &Iteration,
    light_index: u32,
    emission: &EmissionSample,
    position_pdf: f32,
    rng: &mut Rng,
    splats: &mut Vec<Splat>,
    wavelengths: &S::Wavelengths,
) {
    let light = &scene.lights[light_index as usize];
    if !light.is_finite() || light.is_delta() || scene.media.is_active() || position_pdf.is_nan() || position_pdf <= 0.0
    {
        return;
    }
    let camera = &scene.camera;
    let u_lens = if camera.needs_lens_sample() { rng.uniform2() } else { [0.5, 0.5] };
    let Some(connection) = camera.connect(emission.origin, u_lens) else { return };
    let Some(seen) =
        light.radiance_on_hit(-connection.direction, emission.origin, emission.normal, &scene.bounding_sphere)
    else {
        return;
    };
    let camera_pdf_a = connection.area_pdf(seen.cos_at_light).0;
    let radiance = scene.emission::<S>(light_index, wavelengths, seen.radiance).to_rgb(wavelengths);
    let value = radiance / position_pdf;
    push_camera_splats(scene, it, &connection, value, camera_pdf_a, false, |_| 1.0, 1, Some(emission.origin), splats);
}

/// The end of a light sub-path being connected to the camera.
pub struct LightEnd<'a> {
    /// Its BSDF (importance transport) or phase function.
    pub scatterer: Scatterer<'a>,
    /// Its position.
    pub position: Vec3,
    /// Its fluorescence, if any.
    pub fluorescent: Option<&'a FluorescentVertex<'a>>,
    /// The media around it.
    pub side: MediumSide,
}

/// The end of a camera sub-path being connected or merged.
pub struct CameraEnd<'a> {
    /// Its BSDF (radiance transport) or phase function.
    pub scatterer: Scatterer<'a>,
    /// Its position.
    pub position: Vec3,
    /// Its fluorescence, if any.
    pub fluorescent: Option<&'a FluorescentVertex<'a>>,
    /// The media around it.
    pub side: MediumSide,
    /// Its merge query planned on the merging grid when the hit was found, with the first
    /// prefetch hint ([`super::merge::MergeSource::plan_and_prefetch`]); `None`: the merge
    /// plans it.
    pub grid_query: Option<GridQuery>,
}

impl CameraEnd<'_> {
    /// What arrives at the camera path's channels from the light side: the slot-indexed
    /// quantity `arriving` scattered at this vertex with BSDF value `value` (a label is drawn at
    /// a fluorescent vertex), read through the camera path's slots.
    #[inline]
    pub fn receive<S: SpectralMode>(
        &self,
        camera: &SubPath<S>,
        value: Rgb,
        arriving: S,
        rng: &mut Rng,
        w: &S::Wavelengths,
    ) -> S {
        if self.scatterer.is_medium() {
            return arriving * self.scatterer.spectral::<S>(w, value);
        }
        view(&camera.slots, scatter_slots(self.fluorescent, w, value, arriving, rng))
    }
}

/// Light vertices (the first ones in path order) whose BSDFs [`LightBsdfs`] keeps. A later
/// vertex's BSDF is rebuilt at every connection; light sub-paths within the default maximum
/// path length (10 segments) never have one.
pub const CACHED_LIGHT_BSDFS: usize = 16;

/// The BSDFs of one light sub-path's surface vertices, for one camera sub-path (one hero
/// wavelength), each built the first time a connection needs it.
///
/// The camera pass connects every vertex of a camera sub-path to the vertices of the same light
/// sub-path (SmallVCM's scheme), so without it a light vertex's BSDF would be rebuilt from its
/// record once per camera vertex. Building a BSDF draws no random numbers and depends only on
/// the vertex and the hero wavelength, so the kept value is bit for bit the one a rebuild gives.
pub struct LightBsdfs {
    /// The camera sub-path's hero wavelength (nm; `None` in RGB mode).
    hero: Option<f32>,
    /// Per vertex index (path order): `None` until built, then what [`LightVertex::bsdf`]
    /// returned.
    cached: [Option<Option<Bsdf>>; CACHED_LIGHT_BSDFS],
    /// The last BSDF built for a vertex beyond [`CACHED_LIGHT_BSDFS`].
    spare: Option<Bsdf>,
}

impl LightBsdfs {
    /// An empty cache for a camera sub-path at hero wavelength `hero` (nm; `None` in RGB mode).
    #[inline]
    pub fn new(hero: Option<f32>) -> Self {
        Self { hero, cached: [None; CACHED_LIGHT_BSDFS], spare: None }
    }

    /// The BSDF (importance transport) of `vertex`, the light sub-path's vertex of index
    /// `index` in path order (0 nearest the light), as [`LightVertex::bsdf`] builds it: `None`
    /// where its material cannot scatter for the vertex's fixed direction, and in a medium. The
    /// caller passes the same vertex for an index throughout the cache's life.
    #[inline]
    pub fn get<S: SpectralMode>(&mut self, scene: &Scene, index: usize, vertex: &LightVertex<S>) -> Option<&Bsdf> {
        let hero = self.hero;
        match self.cached.get_mut(index) {
            Some(slot) => slot.get_or_insert_with(|| vertex.bsdf(scene, hero)).as_ref(),
            None => {
                self.spare = vertex.bsdf(scene, hero);
                self.spare.as_ref()
            }
        }
    }
}

/// Next-event estimation from camera vertex `end` (s = 1), MIS-weighted (eqs. 44, 45);
/// `compensated`: from [`scene::light::Light::sample_direct_compensated`] (MIS compensation,
/// [`super::Iteration::mis_compensation`]).
pub fn next_event<S: SpectralMode>(
    scene: &Scene,
    camera: &SubPath<S>,
    end: &CameraEnd,
    rng: &mut Rng,
    k: &MisConstants,
    compensated: bool,
    wavelengths: &S::Wavelengths,
) -> S {
    let (scatterer, position) = (&end.scatterer, end.position);
    let pick_u = rng.uniform();
    let u = rng.uniform2();
    let Some((index, light, pick)) = scene.pick_light(pick_u) else { return S::default() };
    let direct = if compensated {
        light.sample_direct_compensated(position, u, &scene.bounding_sphere)
    } else {
        light.sample_direct(position, u, &scene.bounding_sphere)
    };
    let Some(direct) = direct else { return S::default() };
    let Some(eval) = scatterer.evaluate(direct.direction) else { return S::default() };
    let continuation = scatterer.continuation();
    let mut pdfs = NeePdfs {
        direct_w: direct.direct_pdf.0 * pick,
        emission_w: direct.emission_pdf.0 * pick,
        bsdf_forward_w: if light.is_delta() { 0.0 } else { eval.forward * continuation },
        bsdf_reverse_w: eval.reverse * continuation,
        cos_at_vertex: eval.cos_generated,
        cos_at_light: direct.cos_at_light,
    };
    if scene.media.is_active() {
        // The shadow segment: transmittance; BSDF/phase sampling reaches the light only past
        // every piece (forward product), emission reaches the vertex with the reverse one.
        let towards = end.side.towards(direct.direction);
        let Some(segment) = segment::<S>(
            scene,
            position,
            direct.direction,
            direct.distance,
            towards,
            scatterer.is_medium(),
            false,
            wavelengths,
            rng,
        ) else {
            return S::default();
        };
        pdfs.bsdf_forward_w *= segment.forward;
        pdfs.cos_at_vertex *= segment.reverse;
        let weight = mis::nee_weight_at(&camera.mis, &pdfs, k, k.eta_scale(scatterer.is_medium()));
        let emitted = scene.emission::<S>(index, wavelengths, direct.radiance) * segment.transmittance;
        let value =
            end.receive(camera, eval.value, emitted, rng, wavelengths) * (weight * eval.cos_generated / pdfs.direct_w);
        return camera.throughput * value;
    }
    let weight = mis::nee_weight(&camera.mis, &pdfs, k);
    let emitted = scene.emission::<S>(index, wavelengths, direct.radiance);
    let value =
        end.receive(camera, eval.value, emitted, rng, wavelengths) * (weight * eval.cos_generated / pdfs.direct_w);
    if value.is_black() || scene.occluded(position, direct.direction, direct.distance) {
        return S::default();
    }
    camera.throughput * value
}

/// Connects camera vertex `end` to `light`, the light sub-path's vertex of index
/// `light_index` in path order (s, t > 1), MIS-weighted (eqs. 40, 41) with the camera path's
/// constants `k` (the light vertex's dVC/dVM are rebuilt for them, eqs. 62, 63). A surface
/// vertex's BSDF comes from `light_bsdfs`. Labels of fluorescent ends are drawn from `rng`.
#[allow(clippy::too_many_arguments)]
pub fn connect_vertices<S: SpectralMode>(
    scene: &Scene,
    camera: &SubPath<S>,
    end: &CameraEnd,
    (light, light_index): (&LightVertex<S>, usize),
    light_bsdfs: &mut LightBsdfs,
    k: &MisConstants,
    wavelengths: &S::Wavelengths,
    rng: &mut Rng,
) -> S {
    let (scatterer, position) = (&end.scatterer, end.position);
    let to_light = light.record.position - position;
    let distance_squared = to_light.length_squared();
    let distance = distance_squared.sqrt();
    let direction = to_light / distance;
    let Some(camera_eval) = scatterer.evaluate(direction) else { return S::default() };
    let light_medium = light.medium().map(|m| scene.media.medium(m));
    let light_scatterer = match light_medium {
        Some(m) => Scatterer::Medium(m, light.record.fixed()),
        None => {
            let Some(bsdf) = light_bsdfs.get(scene, light_index, light) else { return S::default() };
            Scatterer::Surface(bsdf)
        }
    };
    let Some(light_eval) = light_scatterer.evaluate(-direction) else { return S::default() };
    let media = if scene.media.is_active() {
        let towards = end.side.towards(direction);
        let (from, to) = (scatterer.is_medium(), light_medium.is_some());
        let Some(segment) = segment::<S>(scene, position, direction, distance, towards, from, to, wavelengths, rng)
        else {
            return S::default();
        };
        Some(segment)
    } else {
        None
    };
    let (forward, reverse) = media.map_or((1.0, 1.0), |m| (m.forward, m.reverse));
    let camera_continuation = scatterer.continuation();
    let inv_d2 = 1.0 / distance_squared;
    let pdfs = ConnectionPdfs {
        camera_forward_a: camera_eval.forward * camera_continuation * (light_eval.cos_generated * forward) * inv_d2,
        camera_reverse_w: camera_eval.reverse * camera_continuation,
        light_forward_a: light_eval.forward
            * light.record.continuation()
            * (camera_eval.cos_generated * reverse)
            * inv_d2,
        light_reverse_w: light_eval.reverse * light.record.continuation(),
    };
    let light_mis = light.record.mis(k);
    let eta_scale = [k.eta_scale(light_medium.is_some()), k.eta_scale(scatterer.is_medium())];
    let weight = mis::connection_weight_at(&light_mis, &camera.mis, &pdfs, k, eta_scale);
    let geometry = camera_eval.cos_generated * light_eval.cos_generated * inv_d2;
    let both_terminated = camera.terminated && light.record.terminated();
    let scale = if both_terminated { S::DOUBLE_TERMINATION } else { 1.0 };
    if let Some(segment) = media {
        // Media (no fluorescence: the driver refuses it with media).
        let value = scatterer.spectral::<S>(wavelengths, camera_eval.value)
            * light_scatterer.spectral::<S>(wavelengths, light_eval.value)
            * segment.transmittance
            * (weight * geometry * scale);
        return view(&camera.slots, light.record.throughput * value) * camera.throughput;
    }
    let light_fluorescent = light.fluorescent(scene);
    if end.fluorescent.is_none() && light_fluorescent.is_none() && camera.slots == S::Slots::default() {
        let value = S::from_reflectance(wavelengths, camera_eval.value)
            * S::from_reflectance(wavelengths, light_eval.value)
            * (weight * geometry * scale);
        if value.is_black() || scene.occluded(position, direction, distance) {
            return S::default();
        }
        return camera.throughput * light.record.throughput * value;
    }
    // Fluorescence on the way: scatter the light throughput at the light end, then at the
    // camera end, by slot; read it through the camera path's slots.
    let leaving =
        scatter_slots(light_fluorescent.as_ref(), wavelengths, light_eval.value, light.record.throughput, rng);
    let value = end.receive(camera, camera_eval.value, leaving, rng, wavelengths) * (weight * geometry * scale);
    if value.is_black() || scene.occluded(position, direction, distance) {
        return S::default();
    }
    camera.throughput * value
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vcm::light_vertex::VertexData;
    use crate::vcm::mis::SubPathMis;
    use scene::{Camera, Material, Texture};

    /// Light vertex `i`: a checker-textured or a plain diffuse surface, its own uv and fixed
    /// direction; every seventh one has its fixed direction in the surface (no BSDF).
    fn vertex(i: u32) -> LightVertex {
        let f = i as f32;
        let normal = Vec3::Z;
        let fixed = if i % 7 == 3 { Vec3::X } else { Vec3::new(0.05 * f - 0.5, 0.1, 1.0).normalize() };
        LightVertex::new(&VertexData {
            position: Vec3::new(f, 0.0, 0.0),
            throughput: Rgb::splat(1.0),
            mis: SubPathMis { d_vcm: 1.0, d_vc: 0.0, d_vm: 0.0, c_vc: 0.0, c_vm: 0.0 },
            path_length: 1 + i,
            material: i % 2,
            normal,
            shading_normal: normal,
            uv: Vec2::new(0.013 + 0.097 * f, 0.5),
            tangent: None,
            attribute: None,
            fixed,
            continuation: 1.0,
            terminated: false,
        })
    }

    #[test]
    fn cached_light_bsdfs_are_the_rebuilt_ones_bit_for_bit() {
        let checker = Material::Diffuse {
            reflectance: Texture::Checkerboard {
                color0: Rgb::new(0.2, 0.3, 0.4),
                color1: Rgb::new(0.8, 0.7, 0.6),
                to_uv: scene::desc::UvTransform::IDENTITY,
            },
        };
        let plain = Material::Diffuse { reflectance: Texture::Constant(Rgb::new(0.5, 0.25, 0.125)) };
        let camera = Camera::new(Vec3::new(0.0, 0.0, 5.0), -Vec3::Z, Vec3::Y, 40.0, 4, 4);
        let scene = Scene::new("t", Vec::new(), vec![checker, plain], Vec::new(), camera);
        // More vertices than are kept: the last ones take the rebuilt-every-time path.
        let count = CACHED_LIGHT_BSDFS as u32 + 4;
        let vertices: Vec<LightVertex> = (0..count).map(vertex).collect();
        let generated = Vec3::new(0.3, -0.2, 0.9).normalize();
        let rebuilt = |v: &LightVertex| v.bsdf(&scene, None).map(|b| b.evaluate(generated));
        let fresh: Vec<_> = vertices.iter().map(rebuilt).collect();
        // The check can tell vertices apart: no two neighbours evaluate alike, some have no BSDF.
        assert!(fresh.windows(2).all(|w| w[0] != w[1]));
        assert!(fresh.iter().any(Option::is_none) && fresh.iter().filter(|e| e.is_some()).count() > 10);
        let mut cache = LightBsdfs::new(None);
        // Asked in path order per camera vertex (possibly stopping early), as the camera pass does.
        for stop in [count as usize, 5, count as usize, 2, count as usize] {
            for (index, v) in vertices.iter().enumerate().take(stop) {
                let cached = cache.get(&scene, index, v).map(|b| b.evaluate(generated));
                assert_eq!(cached, fresh[index], "vertex {index}");
                let bits = |e: &Option<Option<scene::BsdfEval>>| format!("{e:?}");
                assert_eq!(bits(&cached), bits(&fresh[index]));
            }
        }
    }
}
