//! All multiple-importance-sampling algebra of the VCM engine: the per-iteration constants,
//! the partial sub-path quantities dVCM, dVC, dVM (and the radius-free cVC, cVM of §6.1), their
//! initialisation and update along a random walk, and the weights of every technique.
//!
//! Equation numbers refer to Georgiev, "Implementing Vertex Connection and Merging" (2012).
//! All weights use the balance heuristic (β = 1). Pdfs passed in here already include light
//! selection and Russian roulette where the caller's documentation says so. Everything is a
//! pure function of its arguments, so the MIS oracle test can drive it with explicit pdfs.
//!
//! **Medium vertices** (volumetric photon points, the point–point estimator of Křivánek et
//! al. 2014). A merge at vertex x accepts the light vertices within r of x: on a surface that
//! is the disc η_A = N_VM π r² of eq. 20; in a medium, where the vertex densities are volume
//! densities (`super::medium`), it is the ball η_V = N_VM (4/3) π r³, and the merge divides
//! by the volume instead of the disc (kernel 1/((4/3) π r³ N_VM)). Every other weight is a
//! ratio of path pdfs in which a merge at vertex j carries *its own* η_j. The report's
//! recursion folds one η into global constants; here the quantities stay normalised by
//! η_A = `eta_vcm` (so a surface-only path computes exactly the same floats as before) and the
//! ratio η_V/η_A = (4/3) r_V³/r² ([`MisConstants::volume_over_area`]) enters where a medium vertex's
//! merge is counted:
//!
//! - dVCM (eqs. 31, 34): no η (it holds the connection to the vertex and the camera's 1/p).
//! - dVC (eq. 35) at vertex i−1: the merge at i−1 is `η_VCM` → `η_VCM · η_{i−1}/η_A`.
//! - dVM (eq. 36) at vertex i−1: the report's `1` is that merge over the merge at i, both
//!   η_A; with dVM kept relative to η_A it becomes `η_{i−1}/η_A`; cVM (eq. 61) likewise.
//!   cVC (eq. 60) has none. ([`SubPathMis::scatter_medium`].)
//! - Connections (eqs. 40, 41, 45, 46): the `η_VCM` term is the merge at the connected light
//!   or camera vertex, scaled by that vertex's η/η_A ([`connection_weight_at`],
//!   [`nee_weight_at`], [`camera_connection_weight_at`]); an emitter hit (eq. 43) has none.
//! - Merge at x (eqs. 38, 39): w_light and w_camera are relative to a merge of η_A; relative
//!   to the merge actually made they are multiplied by η_A/η_x ([`merge_weight_in_medium`]).
//!
//! Eqs. 62, 63 rebuild dVC and dVM from cVC and cVM for the *same* radii only: cVM now
//! holds (4/3) r_V³/r², so the per-pixel radius (§6.1) is refused in scenes with media.

use math::PI;

/// Constants of one iteration (eq. 20 and the normalisation of the merging kernel).
///
/// Two sample counts enter: N_L, the number of light sub-paths, is the number of samples of
/// light tracing (t = 1: every light sub-path may splat into every pixel); N_VM, the number of
/// light sub-paths a camera vertex merges with, is N_L, or N_L/K when the sub-paths of an
/// iteration are split into K wavelength groups that merge only within their group (spectral
/// mode, `super::wavelengths`). Connections have one sample (the pixel's own light sub-path).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MisConstants {
    /// η_VCM = n_VM/n_VC · π r² with n_VC = 1 and n_VM = N_VM (eq. 20), in units of area.
    pub eta_vcm: f32,
    /// η_VCM when merging is enabled, else 0: the weight of the merging techniques relative to
    /// connections.
    pub vm_weight: f32,
    /// 1/η_VCM when connecting is enabled, else 0.
    pub vc_weight: f32,
    /// 1/(π r² N_VM): the merging kernel normalisation (a disc of radius r, N_VM light paths).
    pub vm_normalization: f32,
    /// N_L, the number of light sub-paths (and of samples of the t = 1 technique).
    pub light_path_count: f32,
    /// N_VM, the number of light sub-paths a camera vertex merges with (N_L/K with K wavelength
    /// groups).
    pub merge_path_count: f32,
    /// η_V/η_A = (4/3) r_V³/r² (scene units): the ratio of a medium vertex's merge acceptance
    /// volume N_VM (4/3) π r_V³ to a surface vertex's area N_VM π r² (see "Medium vertices" in
    /// the module doc).
    pub volume_over_area: f32,
    /// r, the merging radius at surface vertices (scene units).
    pub radius: f32,
    /// r_V, the radius of the merge ball at medium vertices (scene units); r, unless
    /// [`MisConstants::with_volume_radius`] set another.
    pub volume_radius: f32,
}

impl MisConstants {
    /// Constants for `light_path_count` light sub-paths that all merge with every camera
    /// vertex, merging radius `radius` and the enabled technique families.
    pub fn new(light_path_count: usize, radius: f32, connect: bool, merge: bool) -> Self {
        let n = light_path_count as f32;
        Self::with_merge_paths(n, n, radius, connect, merge)
    }

    /// Constants for `light_path_count` light sub-paths of which `merge_path_count` (on
    /// average) merge with a camera vertex (N_L/K with K wavelength groups).
    pub fn with_merge_paths(
        light_path_count: f32,
        merge_path_count: f32,
        radius: f32,
        connect: bool,
        merge: bool,
    ) -> Self {
        let eta_vcm = PI * radius * radius * merge_path_count; // [tech. rep. eq. 20]
        Self {
            eta_vcm,
            vm_weight: if merge { eta_vcm } else { 0.0 },
            vc_weight: if connect { 1.0 / eta_vcm } else { 0.0 },
            vm_normalization: 1.0 / eta_vcm,
            light_path_count,
            merge_path_count,
            volume_over_area: 4.0 / 3.0 * radius,
            radius,
            volume_radius: radius,
        }
    }

    /// These constants with the merge ball of medium vertices of radius `volume_radius` (r_V,
    /// scene units) instead of the surface radius r: η_V/η_A = (4/3) r_V³/r². The surface
    /// quantities are unchanged; `volume_radius == r` gives exactly the single-radius constants
    /// (the ratio is then exactly 1).
    pub fn with_volume_radius(self, volume_radius: f32) -> Self {
        let ratio = volume_radius / self.radius;
        Self { volume_over_area: 4.0 / 3.0 * volume_radius * ratio * ratio, volume_radius, ..self }
    }

    /// η of a vertex's type over the surface η_A: 1 on a surface, η_V/η_A = (4/3) r_V³/r² in a
    /// medium (module doc, "Medium vertices").
    #[inline]
    pub fn eta_scale(&self, medium: bool) -> f32 {
        if medium { self.volume_over_area } else { 1.0 }
    }
}

/// Partial MIS quantities carried by a sub-path and stored at its vertices (§4.1).
///
/// `d_vcm`, `d_vc`, `d_vm` are the report's quantities for the iteration's global radius.
/// `c_vc`, `c_vm` are the radius-independent quantities of §6.1 (eqs. 57–61), carried
/// alongside so that a vertex can be weighted for another radius (per-pixel radius) and so that
/// a stored light vertex needs only dVCM, cVC, cVM ([`SubPathMis::for_constants`] rebuilds
/// the rest).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SubPathMis {
    /// dVCM.
    pub d_vcm: f32,
    /// dVC.
    pub d_vc: f32,
    /// dVM.
    pub d_vm: f32,
    /// cVC (§6.1).
    pub c_vc: f32,
    /// cVM (§6.1).
    pub c_vm: f32,
}

impl SubPathMis {
    /// A light sub-path leaving its light (eqs. 31–33; 48–50 for delta lights; §5.1 for
    /// infinite lights). `emission_pdf_w` (p0_trace) is the density of the emitted ray and
    /// `direct_pdf_a` (p0_connect) the density of direct sampling of its origin, both including
    /// the light selection probability. `cos_at_light` is the emission cosine for finite
    /// lights and 1 for infinite ones.
    pub fn light_start(
        emission_pdf_w: f32,
        direct_pdf_a: f32,
        cos_at_light: f32,
        is_delta: bool,
        k: &MisConstants,
    ) -> Self {
        let d_vcm = direct_pdf_a / emission_pdf_w; // [tech. rep. eq. 31] (1/p→1 follows at the hit)
        let c_vc = if is_delta { 0.0 } else { cos_at_light / emission_pdf_w }; // [eqs. 32, 49, 57]
        Self {
            d_vcm,
            d_vc: c_vc,               // [tech. rep. eq. 32]
            d_vm: c_vc * k.vc_weight, // [tech. rep. eq. 33]
            c_vc,
            c_vm: 0.0, // [tech. rep. eq. 58]
        }
    }

    /// A camera sub-path leaving the camera (eqs. 31–33, eye side): `camera_pdf_w` is the
    /// solid-angle density of the primary ray (image-plane density 1 per pixel), or, for an
    /// orthographic camera, its area density on the film (§5.2: the first arrival then applies
    /// no distance factor).
    pub fn camera_start(camera_pdf_w: f32, k: &MisConstants) -> Self {
        Self {
            d_vcm: k.light_path_count / camera_pdf_w, // [tech. rep. eq. 31] n_light/p→1, p0 ratio 1
            d_vc: 0.0,                                // [tech. rep. eq. 32]
            d_vm: 0.0,                                // [tech. rep. eq. 33]
            c_vc: 0.0,
            c_vm: 0.0,
        }
    }

    /// Completes the quantities at a vertex just reached: divides by the area conversion of the
    /// forward pdf, `|cos θ_fixed| / distance²` (the `1/p→_i` factors of eqs. 31–36). For the
    /// first segment from an infinite light `distance_squared` is `None` (§5.1: no distance).
    pub fn arrive(&mut self, distance_squared: Option<f32>, cos_fixed: f32) {
        if let Some(d2) = distance_squared {
            self.d_vcm *= d2;
        }
        let inv_cos = 1.0 / cos_fixed;
        self.d_vcm *= inv_cos;
        self.d_vc *= inv_cos;
        self.d_vm *= inv_cos;
        self.c_vc *= inv_cos;
        self.c_vm *= inv_cos;
    }

    /// Folds the free-flight products of the segment just traced into the quantities (after
    /// [`SubPathMis::arrive`], or alone for a ray that escaped): `forward` multiplies the
    /// forward density of reaching the vertex, `reverse` the density of sampling the previous
    /// vertex from it (`super::medium`; both 1 in vacuum). dVCM = 1/p→ gets `1/forward`; dVC,
    /// dVM, cVC, cVM carry the ratio of the reverse to the forward conversion
    /// (eqs. 34–36) and get `reverse/forward`.
    pub fn apply_flight(&mut self, forward: f32, reverse: f32) {
        let ratio = reverse / forward;
        self.d_vcm /= forward;
        self.d_vc *= ratio;
        self.d_vm *= ratio;
        self.c_vc *= ratio;
        self.c_vm *= ratio;
    }

    /// Starts the quantities of the next vertex after the walk sampled a direction with
    /// solid-angle pdfs `forward` and `reverse` (Russian roulette included) and cosine
    /// `cos_generated` at this vertex (eqs. 34–36; 53–55 for a specular event, whose forward and
    /// reverse probabilities are equal and cancel).
    pub fn scatter(&mut self, cos_generated: f32, forward: f32, reverse: f32, specular: bool, k: &MisConstants) {
        if specular {
            self.d_vcm = 0.0; // [tech. rep. eq. 53]
            self.d_vc *= cos_generated; // [tech. rep. eq. 54]
            self.d_vm *= cos_generated; // [tech. rep. eq. 55]
            self.c_vc *= cos_generated;
            self.c_vm *= cos_generated;
        } else {
            let g_over_p = cos_generated / forward;
            self.d_vc = g_over_p * (self.d_vc * reverse + self.d_vcm + k.vm_weight); // [tech. rep. eq. 35]
            self.d_vm = g_over_p * (self.d_vm * reverse + self.d_vcm * k.vc_weight + 1.0); // [tech. rep. eq. 36]
            self.c_vc = g_over_p * (self.c_vc * reverse + self.d_vcm); // [tech. rep. eq. 60]
            self.c_vm = g_over_p * (self.c_vm * reverse + 1.0); // [tech. rep. eq. 61]
            self.d_vcm = 1.0 / forward; // [tech. rep. eq. 34]
        }
    }

    /// [`SubPathMis::scatter`] at a medium vertex (no cosines, never specular) with solid-angle
    /// pdfs `forward` and `reverse` (Russian roulette included): eqs. 35, 36, 60, 61 with the
    /// merge at this vertex counted with its volume η_V = η_A · (4/3) r_V³/r² (module doc).
    pub fn scatter_medium(&mut self, forward: f32, reverse: f32, k: &MisConstants) {
        let g_over_p = 1.0 / forward;
        let v = k.volume_over_area;
        self.d_vc = g_over_p * (self.d_vc * reverse + self.d_vcm + k.vm_weight * v); // [eq. 35, η_V]
        self.d_vm = g_over_p * (self.d_vm * reverse + self.d_vcm * k.vc_weight + v); // [eq. 36, η_V/η_A]
        self.c_vc = g_over_p * (self.c_vc * reverse + self.d_vcm); // [tech. rep. eq. 60]
        self.c_vm = g_over_p * (self.c_vm * reverse + v); // [eq. 61, η_V/η_A]
        self.d_vcm = 1.0 / forward; // [tech. rep. eq. 34]
    }

    /// The same vertex weighted for other constants (another radius): dVC and dVM rebuilt from
    /// cVC and cVM (eqs. 62, 63), restricted to the enabled techniques.
    pub fn for_constants(&self, k: &MisConstants) -> Self {
        Self {
            d_vc: self.c_vc + k.vm_weight * self.c_vm, // [tech. rep. eq. 62]
            d_vm: self.c_vc * k.vc_weight + self.c_vm, // [tech. rep. eq. 63]
            ..*self
        }
    }
}

/// Weight of a camera sub-path that hits an emitter (s = 0; eqs. 42, 43, 37). `direct_pdf_a`
/// and `emission_pdf_w` are the light's densities for the hit point (area, or solid angle for
/// infinite lights) and for emitting the reversed ray, both including light selection.
pub fn emitter_hit_weight(camera: &SubPathMis, direct_pdf_a: f32, emission_pdf_w: f32) -> f32 {
    let w_camera = direct_pdf_a * camera.d_vcm + emission_pdf_w * camera.d_vc; // [tech. rep. eq. 43]
    1.0 / (1.0 + w_camera) // [tech. rep. eq. 37] with w_light = 0 [eq. 42]
}

/// The densities a next-event (s = 1) connection needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NeePdfs {
    /// Density of sampling this light point by direct sampling, per solid angle at the camera
    /// vertex, including light selection.
    pub direct_w: f32,
    /// Density of emitting the connecting ray from the light (including light selection).
    pub emission_w: f32,
    /// Camera BSDF density of the direction to the light (Russian roulette included); 0 for
    /// delta lights, which BSDF sampling cannot hit.
    pub bsdf_forward_w: f32,
    /// Camera BSDF density of the reverse direction (Russian roulette included).
    pub bsdf_reverse_w: f32,
    /// Cosine at the camera vertex towards the light.
    pub cos_at_vertex: f32,
    /// Cosine at the light (1 without a surface).
    pub cos_at_light: f32,
}

/// Weight of next-event estimation (s = 1; eqs. 44, 45, 37).
pub fn nee_weight(camera: &SubPathMis, p: &NeePdfs, k: &MisConstants) -> f32 {
    nee_weight_at(camera, p, k, 1.0)
}

/// [`nee_weight`] at a camera vertex whose merge η is `eta_scale` · η_A
/// ([`MisConstants::eta_scale`]).
pub fn nee_weight_at(camera: &SubPathMis, p: &NeePdfs, k: &MisConstants, eta_scale: f32) -> f32 {
    // Both densities are on the light, so their area conversions cancel: a ratio of solid-angle
    // densities at the camera vertex.
    let w_light = p.bsdf_forward_w / p.direct_w; // [tech. rep. eq. 44]
    // p0_trace/p0_connect as a ratio of area densities at the light.
    let trace_over_connect = p.emission_w * p.cos_at_vertex / (p.direct_w * p.cos_at_light);
    let w_camera = trace_over_connect * (k.vm_weight * eta_scale + camera.d_vcm + camera.d_vc * p.bsdf_reverse_w); // [tech. rep. eq. 45]
    1.0 / (w_light + 1.0 + w_camera) // [tech. rep. eq. 37]
}

/// The densities a connection of a light vertex and a camera vertex (s, t > 1) needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConnectionPdfs {
    /// Camera BSDF density of sampling the light vertex, converted to area at the light vertex.
    pub camera_forward_a: f32,
    /// Camera BSDF density of sampling the camera vertex's fixed direction from the connection
    /// direction (solid angle, Russian roulette included).
    pub camera_reverse_w: f32,
    /// Light BSDF density of sampling the camera vertex, converted to area at the camera vertex.
    pub light_forward_a: f32,
    /// Light BSDF density of sampling the light vertex's fixed direction (solid angle, Russian
    /// roulette included).
    pub light_reverse_w: f32,
}

/// Weight of a vertex connection (s, t > 1; eqs. 40, 41, 37).
pub fn connection_weight(light: &SubPathMis, camera: &SubPathMis, p: &ConnectionPdfs, k: &MisConstants) -> f32 {
    connection_weight_at(light, camera, p, k, [1.0, 1.0])
}

/// [`connection_weight`] with the merge η of the light and the camera vertex `eta_scale`
/// (`[light, camera]`) times η_A ([`MisConstants::eta_scale`]).
pub fn connection_weight_at(
    light: &SubPathMis,
    camera: &SubPathMis,
    p: &ConnectionPdfs,
    k: &MisConstants,
    eta_scale: [f32; 2],
) -> f32 {
    let w_light = p.camera_forward_a * (k.vm_weight * eta_scale[0] + light.d_vcm + light.d_vc * p.light_reverse_w); // [tech. rep. eq. 40]
    let w_camera = p.light_forward_a * (k.vm_weight * eta_scale[1] + camera.d_vcm + camera.d_vc * p.camera_reverse_w); // [tech. rep. eq. 41]
    1.0 / (w_light + 1.0 + w_camera) // [tech. rep. eq. 37]
}

/// Weight of connecting a light vertex to the camera (t = 1; eqs. 46, 47, 37).
/// `camera_pdf_a` is the density with which the camera samples the light vertex (image-plane
/// density 1 per pixel, converted to area at the vertex); `light_reverse_w` the light BSDF's
/// reverse density (Russian roulette included).
pub fn camera_connection_weight(light: &SubPathMis, camera_pdf_a: f32, light_reverse_w: f32, k: &MisConstants) -> f32 {
    camera_connection_weight_at(light, camera_pdf_a, light_reverse_w, k, 1.0)
}

/// [`camera_connection_weight`] at a light vertex whose merge η is `eta_scale` · η_A
/// ([`MisConstants::eta_scale`]).
pub fn camera_connection_weight_at(
    light: &SubPathMis,
    camera_pdf_a: f32,
    light_reverse_w: f32,
    k: &MisConstants,
    eta_scale: f32,
) -> f32 {
    let w_light =
        camera_pdf_a / k.light_path_count * (k.vm_weight * eta_scale + light.d_vcm + light.d_vc * light_reverse_w); // [tech. rep. eq. 46]
    1.0 / (w_light + 1.0) // [tech. rep. eq. 37] with w_camera = 0 [eq. 47]
}

/// Weight of merging a light vertex at a camera vertex (s, t ≥ 2; eqs. 38, 39, 37).
/// `camera_forward_w` is the camera BSDF's density of the light vertex's incoming direction
/// and `camera_reverse_w` that of the camera's fixed direction from it (both solid angle,
/// Russian roulette included: the camera's for forward, the light vertex's for reverse).
pub fn merge_weight(
    light: &SubPathMis,
    camera: &SubPathMis,
    camera_forward_w: f32,
    camera_reverse_w: f32,
    k: &MisConstants,
) -> f32 {
    let w_light = light.d_vcm * k.vc_weight + light.d_vm * camera_forward_w; // [tech. rep. eq. 38]
    let w_camera = camera.d_vcm * k.vc_weight + camera.d_vm * camera_reverse_w; // [tech. rep. eq. 39]
    1.0 / (w_light + 1.0 + w_camera) // [tech. rep. eq. 37]
}

/// [`merge_weight`] at a medium vertex: every other technique relative to a merge whose
/// acceptance is the volume η_V, not the area η_A the quantities are normalised by (dVM and
/// the 1/η_VCM of eqs. 38, 39 are relative to η_A), so `w_light + w_camera` is scaled by η_A/η_V.
pub fn merge_weight_in_medium(
    light: &SubPathMis,
    camera: &SubPathMis,
    camera_forward_w: f32,
    camera_reverse_w: f32,
    k: &MisConstants,
) -> f32 {
    let w_light = light.d_vcm * k.vc_weight + light.d_vm * camera_forward_w; // [tech. rep. eq. 38]
    let w_camera = camera.d_vcm * k.vc_weight + camera.d_vm * camera_reverse_w; // [tech. rep. eq. 39]
    1.0 / (1.0 + (w_light + w_camera) / k.volume_over_area) // [eq. 37, η_A/η_V]
}
