//! The state of a random walk (light or camera sub-path) and its scattering step.

use math::{RAY_EPSILON, Ray, Rng, Vec3};
use scene::medium::Medium;
use scene::{Bsdf, BsdfSample, Scene, SurfaceHit, TransportMode};
use spectrum::{Rgb, SpectralMode};

use crate::fluorescent::{FluorescentVertex, view};

use super::medium::{Flight, crosses_as_null, pass_boundary};
use super::mis::{MisConstants, SubPathMis};

/// A sub-path being traced, carrying `S` ([`spectrum::Rgb`] or [`spectrum::Hero4`]).
#[derive(Clone, Copy, Debug)]
pub struct SubPath<S: SpectralMode> {
    /// The next ray to trace (already offset from the last vertex).
    pub ray: Ray,
    /// Product of the BSDF values, cosines and inverse pdfs so far (for light sub-paths it
    /// starts with emitted energy / emission pdf).
    pub throughput: S,
    /// Segments traced so far; the vertex about to be found is reached by `path_length`
    /// segments.
    pub path_length: u32,
    /// MIS quantities for the vertex about to be found (partial until [`SubPathMis::arrive`]).
    pub mis: SubPathMis,
    /// False for light sub-paths from infinite lights, and for camera sub-paths of the
    /// orthographic camera, until their first vertex: the start density is already per unit
    /// area, so the first segment gets no distance factor (§5.1).
    pub is_finite_light: bool,
    /// True while every scattering event so far was specular.
    pub specular_path: bool,
    /// How far `ray.origin` lies past the previous vertex along the ray (0 for camera rays,
    /// [`RAY_EPSILON`] otherwise), so that MIS uses true vertex distances.
    pub origin_offset: f32,
    /// A dispersive refraction kept only the hero wavelength (spectral mode): the throughput's
    /// hero already carries the factor 4 ([`SpectralMode::terminate_secondary`]).
    pub terminated: bool,
    /// Camera sub-paths: the wavelength slot of each channel (moved by fluorescent shifts; the
    /// identity for light sub-paths, whose throughput is indexed by slot).
    pub slots: S::Slots,
    /// The free-flight state of the segment being traced (`super::medium`; vacuum in
    /// surface-only scenes).
    pub flight: Flight,
}

impl<S: SpectralMode> SubPath<S> {
    /// Distance² between the previous vertex and a hit at ray distance `distance`, to pass
    /// to [`SubPathMis::arrive`]; `None` for the first segment from an infinite light (§5.1).
    pub fn arrival_distance_squared(&self, distance: f32) -> Option<f32> {
        if self.path_length > 1 || self.is_finite_light {
            let d = distance + self.origin_offset;
            Some(d * d)
        } else {
            None
        }
    }

    /// Samples the next direction at `position` from `bsdf` (only its specular lobes when
    /// `specular_only`; `presampled`, when given, is that sample already drawn, see
    /// [`SubPath::cross_null_surface`]), applies Russian roulette, updates throughput and MIS quantities
    /// (eqs. 34–36, 53–55) and prepares the next ray. At a fluorescent vertex a label is drawn
    /// and applied as a light sub-path (`camera` false: by slot) or as a camera sub-path does.
    /// Returns what scattering multiplied the throughput by, or `None` when the walk ends.
    #[allow(clippy::too_many_arguments)]
    pub fn scatter(
        &mut self,
        bsdf: &Bsdf,
        position: Vec3,
        rng: &mut Rng,
        specular_only: bool,
        k: &MisConstants,
        wavelengths: &S::Wavelengths,
        fluorescent: Option<&FluorescentVertex>,
        camera: bool,
        presampled: Option<BsdfSample>,
    ) -> Option<Scattered> {
        // Russian roulette before the BSDF is sampled (a stopped walk does not pay for the
        // sample), with the numbers drawn in the order of sampling first: a sub-path's stream
        // ends with the walk, so the images are the same as when the sample came first.
        let u = if presampled.is_none() { rng.uniform3() } else { [0.0; 3] };
        let continuation = bsdf.continuation_probability();
        if continuation < 1.0 && rng.uniform() >= continuation {
            return None;
        }
        let sample = match presampled {
            Some(sample) => sample,
            None => if specular_only { bsdf.sample_specular(u) } else { bsdf.sample(u) }?,
        };
        let specular = sample.lobe.is_specular();
        let forward = sample.pdf.forward.0 * continuation;
        let reverse = sample.pdf.reverse.0 * continuation;
        self.mis.scatter(sample.cos_generated, forward, reverse, specular, k);
        let scale = sample.cos_generated / forward;
        match fluorescent {
            None => self.throughput *= view(&self.slots, S::from_reflectance(wavelengths, sample.value)) * scale,
            Some(f) => {
                let label = f.sample_label::<S>(rng.uniform());
                self.throughput = if camera {
                    f.apply_camera(wavelengths, label, sample.value, &mut self.slots, self.throughput) * scale
                } else {
                    f.apply_slots(wavelengths, label, sample.value, self.throughput) * scale
                };
            }
        }
        if sample.dispersive && !self.terminated {
            self.throughput = self.throughput.terminate_secondary();
            self.terminated = true;
        }
        self.specular_path &= specular;
        self.ray = Ray::new(position + RAY_EPSILON * sample.direction, sample.direction);
        self.origin_offset = RAY_EPSILON;
        self.path_length += 1;
        Some(Scattered { value: sample.value, scale })
    }
}

impl<S: SpectralMode> SubPath<S> {
    /// Scatters at a medium vertex at `position` in `medium` (index `index`): samples the phase
    /// function (weight f/p = 1), applies Russian roulette with the medium's largest albedo,
    /// updates the MIS quantities (eqs. 34–36 with no cosines: a medium vertex has none) and
    /// starts the next segment in the same medium. Returns false when the walk ends.
    pub fn scatter_medium(
        &mut self,
        medium: &Medium,
        index: u32,
        position: Vec3,
        rng: &mut Rng,
        k: &MisConstants,
    ) -> bool {
        let fixed = -self.ray.direction;
        let sample = medium.phase.sample(fixed, rng.uniform2());
        let continuation = medium.max_albedo();
        if continuation < 1.0 && rng.uniform() >= continuation {
            return false;
        }
        if sample.pdf.is_nan() || sample.pdf <= 0.0 {
            return false;
        }
        let pdf = sample.pdf * continuation;
        self.mis.scatter_medium(pdf, pdf, k);
        self.throughput *= 1.0 / continuation;
        self.specular_path = false;
        self.ray = Ray::new(position, sample.direction);
        self.origin_offset = 0.0;
        self.flight = Flight::start(Some(index), true, 0.0);
        self.path_length += 1;
        true
    }
}

/// What [`SubPath::cross_null_surface`] did at a surface.
#[derive(Clone, Copy, Debug)]
pub enum NullSurface {
    /// The sub-path went straight through: no vertex, the segment goes on.
    Crossed,
    /// The surface is a vertex; for a thin dielectric, with the (reflection) sample already
    /// drawn, to pass to [`SubPath::scatter`].
    Vertex(Option<BsdfSample>),
    /// The walk ends (no BSDF, no sample, or Russian roulette).
    Stop,
}

impl<S: SpectralMode> SubPath<S> {
    /// At a surface `hit` in a scene with media: a thin dielectric that
    /// [`crosses_as_null`] samples its BSDF (built for `mode` at the `hero` wavelength in
    /// spectral mode); a
    /// straight-through transmission is no vertex, as in the volumetric path tracer: the
    /// throughput takes `f·cos/p` (and the BSDF's Russian roulette) and the ray continues the
    /// segment through the surface ([`pass_boundary`]), so the pdfs of the last vertex and the
    /// distance to the next one span the crossing. Any other surface is a vertex.
    #[allow(clippy::too_many_arguments)]
    pub fn cross_null_surface(
        &mut self,
        scene: &Scene,
        hit: &SurfaceHit,
        mode: TransportMode,
        hero: Option<f32>,
        rng: &mut Rng,
        wavelengths: &S::Wavelengths,
    ) -> NullSurface {
        if !crosses_as_null(scene, hit) {
            return NullSurface::Vertex(None);
        }
        let fixed = -self.ray.direction;
        let Some(bsdf) = Bsdf::new_at(scene.material(hit), &hit.shading_point(), fixed, mode, hero) else {
            return NullSurface::Stop;
        };
        let Some(sample) = bsdf.sample(rng.uniform3()) else { return NullSurface::Stop };
        if !sample.is_straight_through(fixed) {
            return NullSurface::Vertex(Some(sample));
        }
        let continuation = bsdf.continuation_probability();
        if continuation < 1.0 && rng.uniform() >= continuation {
            return NullSurface::Stop;
        }
        let scale = sample.cos_generated / (sample.pdf.forward.0 * continuation);
        self.throughput *= view(&self.slots, S::from_reflectance(wavelengths, sample.value)) * scale;
        pass_boundary(scene, hit, &mut self.ray, &mut self.origin_offset, &mut self.flight);
        NullSurface::Crossed
    }
}

/// What one scattering step multiplied a sub-path's throughput by (without a fluorescent
/// label): the BSDF value, upsampled at the sub-path's wavelengths, times `scale`. Merging across
/// wavelength groups re-applies it at other wavelengths (`super::merge::MergeScope`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scattered {
    /// BSDF value f of the sampled direction, linear sRGB (1/sr; for specular lobes `ρ/|cos θ|`).
    pub value: Rgb,
    /// `|cos θ| / p`, p the solid-angle density of the direction times the continuation
    /// probability (sr).
    pub scale: f32,
}
