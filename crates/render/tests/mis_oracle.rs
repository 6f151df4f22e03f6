//! The MIS oracle: on random short paths (2–6 segments; diffuse, glossy, mirror and glass
//! vertices; area, point, directional and environment lights) the weights that the engine's
//! recursive quantities (tech report eqs. 31–47) give every technique equal an explicit,
//! non-recursive balance-heuristic evaluation of eq. (12) from per-vertex forward and reverse
//! area pdfs, and the weights of all techniques that can produce a path sum to 1 — for `vcm`,
//! `bpt` (merging disabled) and `bpm` (connections disabled), also with K wavelength groups
//! (N_L/K merges per camera vertex, N_L light-tracing samples).
//!
//! Path convention: vertices x0 (on the light, or a direction for infinite lights) … xk (the
//! pinhole). Technique VC_s connects light vertex x_{s−1} to camera vertex x_s (s = 0: the
//! camera path hits the light; s = k: light tracing, t = 1). VM_j merges at x_j.

// Loops run over vertex numbers x_i of the path notation, which index several arrays.
#![allow(clippy::needless_range_loop)]

use crate::common::mis_surface;
use math::{Frame, PI, Rng, Vec3};
use mis_surface::{facing_normal, materials, random_unit, reference_bsdf};
use render::vcm::mis::{self, ConnectionPdfs, MisConstants, NeePdfs, SubPathMis};
use scene::material::fresnel_dielectric;
use scene::{Camera, ReferenceMaterial, TransportMode};

#[derive(Clone, Copy, Debug, PartialEq)]
enum LightKind {
    Area,
    Point,
    Directional,
    Environment,
}

impl LightKind {
    fn is_delta(self) -> bool {
        matches!(self, LightKind::Point | LightKind::Directional)
    }
    fn is_finite(self) -> bool {
        matches!(self, LightKind::Area | LightKind::Point)
    }
}

/// A full path with everything both the oracle and the recursion need.
struct TestPath {
    light: LightKind,
    /// Positions x0…xk; for infinite lights x0 is unused (see `light_direction`).
    x: Vec<Vec3>,
    /// Normals at x0 (area light) and x1…x(k−1).
    normal: Vec<Vec3>,
    /// Materials at x1…x(k−1) (index 0 and k unused).
    material: Vec<ReferenceMaterial>,
    /// For infinite lights: unit direction from x1 towards the light.
    light_direction: Vec3,
    camera: Camera,
    light_area: f32,
}

const PICK: f32 = 0.5;
const SCENE_RADIUS: f32 = 3.0;

impl TestPath {
    fn k(&self) -> usize {
        self.x.len() - 1
    }

    /// Builds a random path of `k` segments by a walk from the camera: every scattering
    /// direction is sampled from the vertex's BSDF, so every BSDF on the path is non-zero.
    fn random(k: usize, light: LightKind, rng: &mut Rng) -> Option<TestPath> {
        let all = materials();
        let camera_position = Vec3::new(0.0, -3.0, 0.5);
        let first = (Vec3::new(0.1, 1.0, -0.05) + 0.2 * random_unit(rng)).normalize();
        let forward = (first + 0.15 * random_unit(rng)).normalize();
        let camera = Camera::new(camera_position, forward, Vec3::Z, 60.0, 64, 64);
        // Walk from the camera: x[k], x[k-1], …, x[1], then the light.
        let mut rev_x = vec![camera_position];
        let mut rev_n = vec![Vec3::Z];
        let mut rev_m = vec![ReferenceMaterial::BLACK];
        let mut direction = first;
        for _ in 1..k {
            let position = *rev_x.last().unwrap() + direction * (0.5 + rng.uniform() * 1.5);
            let normal = facing_normal(-direction, rng);
            let material = all[(rng.uniform() * 4.0) as usize % 4];
            let bsdf = reference_bsdf(&material, normal, -direction, TransportMode::Radiance)?;
            let sample = bsdf.sample(rng.uniform3())?;
            rev_x.push(position);
            rev_n.push(normal);
            rev_m.push(material);
            direction = sample.direction;
        }
        // The light end, in `direction` from x1.
        let x1 = *rev_x.last().unwrap();
        let (x0, light_normal) = match light {
            LightKind::Area => {
                let p = x1 + direction * (0.5 + rng.uniform());
                (p, facing_normal(-direction, rng))
            }
            LightKind::Point => (x1 + direction * (0.5 + rng.uniform()), Vec3::Z),
            LightKind::Directional | LightKind::Environment => (x1 + direction, Vec3::Z),
        };
        rev_x.push(x0);
        rev_n.push(light_normal);
        rev_m.push(ReferenceMaterial::BLACK);
        rev_x.reverse();
        rev_n.reverse();
        rev_m.reverse();
        camera.raster_position(rev_x[k - 1].max(Vec3::splat(-1e9)))?;
        Some(TestPath {
            light,
            x: rev_x,
            normal: rev_n,
            material: rev_m,
            light_direction: direction,
            camera,
            light_area: 0.05 + 0.2 * rng.uniform(),
        })
    }

    fn is_specular(&self, i: usize) -> bool {
        i >= 1 && i < self.k() && self.material[i].diffuse.is_black() && self.material[i].phong.is_black()
    }

    /// Unit direction from x_i to x_j (towards the light for j = 0 on infinite lights).
    fn dir(&self, i: usize, j: usize) -> Vec3 {
        if j == 0 && !self.light.is_finite() {
            return self.light_direction;
        }
        if i == 0 && !self.light.is_finite() {
            return -self.light_direction;
        }
        (self.x[j] - self.x[i]).normalize()
    }

    fn dist2(&self, i: usize, j: usize) -> f32 {
        (self.x[j] - self.x[i]).length_squared()
    }

    /// |cos| at x_i towards x_j (1 at point lights, infinite lights and the camera).
    fn cos(&self, i: usize, j: usize) -> f32 {
        if (i == 0 && self.light != LightKind::Area) || i == self.k() {
            return 1.0;
        }
        self.normal[i].dot(self.dir(i, j)).abs()
    }

    /// At vertex i (1 ≤ i < k): solid-angle pdfs of scattering from `from` to `to` and back
    /// (forward, reverse), Russian roulette included, for the walk that arrived from `from`.
    fn scatter_pdfs(&self, i: usize, from: usize, to: usize) -> (f32, f32) {
        let mode = if from > i { TransportMode::Radiance } else { TransportMode::Importance };
        let bsdf = reference_bsdf(&self.material[i], self.normal[i], self.dir(i, from), mode).unwrap();
        let cont = bsdf.continuation_probability();
        if self.is_specular(i) {
            let m = &self.material[i];
            let p = if m.ior < 0.0 {
                1.0
            } else {
                let f = fresnel_dielectric(self.normal[i].dot(self.dir(i, from)), m.ior);
                let reflected = self.normal[i].dot(self.dir(i, from)) * self.normal[i].dot(self.dir(i, to)) > 0.0;
                if reflected { f } else { 1.0 - f }
            };
            return (p * cont, p * cont);
        }
        let eval = bsdf.evaluate(self.dir(i, to)).expect("the path was built with non-zero BSDFs");
        (eval.pdf.forward.0 * cont, eval.pdf.reverse.0 * cont)
    }

    /// Light densities: (p0_trace, p0_connect, emission solid-angle pdf of direction x0→x1
    /// times p0_trace, i.e. the light's `emission_pdf`, all including the pick probability).
    fn light_pdfs(&self) -> (f32, f32, f32) {
        let disc = 1.0 / (PI * SCENE_RADIUS * SCENE_RADIUS);
        match self.light {
            LightKind::Area => {
                let a = PICK / self.light_area;
                (a, a, a * self.cos(0, 1) / PI)
            }
            LightKind::Point => (PICK, PICK, PICK / (4.0 * PI)),
            LightKind::Directional => (PICK, PICK, PICK * disc),
            LightKind::Environment => (PICK / (4.0 * PI), PICK / (4.0 * PI), PICK / (4.0 * PI) * disc),
        }
    }

    /// Camera solid-angle pdf of the primary ray to x(k−1).
    fn camera_pdf_w(&self) -> f32 {
        let k = self.k();
        let d = self.dir(k, k - 1);
        self.camera.solid_angle_pdf(self.camera.forward.dot(d)).0
    }
}

/// Explicit evaluation of eq. (12): every technique's path pdf as a product of per-vertex area
/// pdfs, in f64.
struct Oracle {
    /// (technique, n · p) for every technique that can produce the path.
    techniques: Vec<(Technique, f64)>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Technique {
    Vc(usize),
    Vm(usize),
}

impl Oracle {
    /// The techniques of `path`: `n_light` samples of light tracing (t = 1), one of every other
    /// connection, `n_merge` merges per camera vertex with a disc of radius `radius`.
    fn new(path: &TestPath, counts: &Counts, connect: bool, merge: bool) -> Oracle {
        let k = path.k();
        let (p0_trace, p0_connect, emission_pdf) = path.light_pdfs();
        // Light-direction (forward) area pdfs p→_i, i = 0…k−1.
        let mut fwd = vec![0.0f64; k];
        fwd[0] = p0_trace as f64;
        fwd[1] = if path.light.is_finite() {
            (emission_pdf / p0_trace * path.cos(1, 0) / path.dist2(0, 1)) as f64
        } else {
            (emission_pdf / p0_trace * path.cos(1, 0)) as f64 // §5.1: no distance
        };
        for i in 2..k {
            let (f, _) = path.scatter_pdfs(i - 1, i - 2, i);
            fwd[i] = (f * path.cos(i, i - 1) / path.dist2(i - 1, i)) as f64;
        }
        // Camera-direction (reverse) area pdfs p←_i, i = 0…k−1 (the pinhole has pdf 1).
        let mut rev = vec![0.0f64; k];
        rev[k - 1] = (path.camera_pdf_w() * path.cos(k - 1, k) / path.dist2(k - 1, k)) as f64;
        for i in (0..k - 1).rev() {
            let (f, _) = path.scatter_pdfs(i + 1, i + 2, i);
            rev[i] = match (i, path.light) {
                (0, LightKind::Point | LightKind::Directional) => 0.0, // delta lights cannot be hit
                (0, LightKind::Environment) => f as f64,               // solid angle (§5.1)
                _ => (f * path.cos(i, i + 1) / path.dist2(i, i + 1)) as f64,
            };
        }
        let connectable = |i: usize| !path.is_specular(i);
        let n_light = counts.light as f64;
        let area = std::f64::consts::PI * (counts.radius as f64).powi(2);
        let mut techniques = Vec::new();
        if connect {
            for s in 0..=k {
                let t = k + 1 - s;
                if s == 1 && t == 1 {
                    continue; // a light point connected to the camera is not a technique here
                }
                let possible = (s == 0 || connectable(s - 1) || s == 1) && (t == 1 || connectable(s));
                if !possible {
                    continue;
                }
                let mut p = 1.0f64;
                for (i, f) in fwd.iter().enumerate().take(s) {
                    p *= if i == 0 && s == 1 { p0_connect as f64 } else { *f };
                }
                for r in rev.iter().take(k).skip(s) {
                    p *= r;
                }
                let n = if t == 1 { n_light } else { 1.0 };
                if p > 0.0 {
                    techniques.push((Technique::Vc(s), n * p));
                }
            }
        }
        if merge {
            for j in 1..k {
                if !connectable(j) {
                    continue;
                }
                let mut p = area * rev[j];
                for f in fwd.iter().take(j + 1) {
                    p *= f;
                }
                for r in rev.iter().take(k).skip(j + 1) {
                    p *= r;
                }
                if p > 0.0 {
                    techniques.push((Technique::Vm(j), counts.merge as f64 * p));
                }
            }
        }
        Oracle { techniques }
    }

    fn weight(&self, technique: Technique) -> f64 {
        let total: f64 = self.techniques.iter().map(|(_, p)| p).sum();
        self.techniques.iter().find(|(t, _)| *t == technique).map_or(0.0, |(_, p)| p / total)
    }
}

/// The engine's recursive weights for every technique the oracle lists. The light sub-path is
/// walked with `light_k`; when that differs from `kc` (another radius: per-pixel radius or the
/// previous iteration's vertices), its vertices are rebased with cVC/cVM (eqs. 62, 63).
fn recursive_weight(path: &TestPath, technique: Technique, kc: &MisConstants, light_k: &MisConstants) -> f32 {
    let k = path.k();
    let (p0_trace, p0_connect, emission_pdf) = path.light_pdfs();
    // Light sub-path: MIS state at each vertex x1…x(k−1) after arriving there.
    let mut light_states = vec![SubPathMis::default(); k];
    let cos_light = if path.light.is_finite() { path.cos(0, 1) } else { 1.0 };
    let mut state = SubPathMis::light_start(emission_pdf, p0_trace, cos_light, path.light.is_delta(), light_k);
    for i in 1..k {
        let d2 = if i == 1 && !path.light.is_finite() { None } else { Some(path.dist2(i - 1, i)) };
        state.arrive(d2, path.cos(i, i - 1));
        light_states[i] = if light_k == kc { state } else { state.for_constants(kc) };
        if i + 1 < k {
            let (f, r) = path.scatter_pdfs(i, i - 1, i + 1);
            state.scatter(path.cos(i, i + 1), f, r, path.is_specular(i), light_k);
        }
    }
    // Camera sub-path: MIS state at x(k−1)…x0 after arriving there.
    let mut camera_states = vec![SubPathMis::default(); k];
    let mut state = SubPathMis::camera_start(path.camera_pdf_w(), kc);
    for i in (1..k).rev() {
        state.arrive(Some(path.dist2(i, i + 1)), path.cos(i, i + 1));
        camera_states[i] = state;
        let (f, r) = path.scatter_pdfs(i, i + 1, i - 1);
        state.scatter(path.cos(i, i - 1), f, r, path.is_specular(i), kc);
    }
    if path.light == LightKind::Area {
        state.arrive(Some(path.dist2(0, 1)), path.cos(0, 1));
    }
    camera_states[0] = state;

    match technique {
        Technique::Vc(0) => mis::emitter_hit_weight(&camera_states[0], p0_connect, emission_pdf),
        Technique::Vc(1) => {
            let (bsdf_forward, bsdf_reverse) = path.scatter_pdfs(1, 2, 0);
            let direct_w = match path.light {
                LightKind::Area => p0_connect * path.dist2(0, 1) / path.cos(0, 1),
                LightKind::Point => p0_connect * path.dist2(0, 1),
                LightKind::Directional | LightKind::Environment => p0_connect,
            };
            let pdfs = NeePdfs {
                direct_w,
                emission_w: emission_pdf,
                bsdf_forward_w: if path.light.is_delta() { 0.0 } else { bsdf_forward },
                bsdf_reverse_w: bsdf_reverse,
                cos_at_vertex: path.cos(1, 0),
                cos_at_light: if path.light == LightKind::Area { path.cos(0, 1) } else { 1.0 },
            };
            mis::nee_weight(&camera_states[1], &pdfs, kc)
        }
        Technique::Vc(s) if s == k => {
            let camera_pdf_a = path.camera_pdf_w() * path.cos(k - 1, k) / path.dist2(k - 1, k);
            let (_, light_reverse) = path.scatter_pdfs(k - 1, k - 2, k);
            mis::camera_connection_weight(&light_states[k - 1], camera_pdf_a, light_reverse, kc)
        }
        Technique::Vc(s) => {
            let (l, c) = (s - 1, s);
            let d2 = path.dist2(l, c);
            let (camera_forward, camera_reverse) = path.scatter_pdfs(c, c + 1, l);
            let (light_forward, light_reverse) = path.scatter_pdfs(l, l - 1, c);
            let pdfs = ConnectionPdfs {
                camera_forward_a: camera_forward * path.cos(l, c) / d2,
                camera_reverse_w: camera_reverse,
                light_forward_a: light_forward * path.cos(c, l) / d2,
                light_reverse_w: light_reverse,
            };
            mis::connection_weight(&light_states[l], &camera_states[c], &pdfs, kc)
        }
        Technique::Vm(j) => {
            let (camera_forward, camera_reverse) = path.scatter_pdfs(j, j + 1, j - 1);
            mis::merge_weight(&light_states[j], &camera_states[j], camera_forward, camera_reverse, kc)
        }
    }
}

/// Sample counts of the techniques, independent of the engine's constants.
struct Counts {
    /// Light sub-paths (samples of light tracing).
    light: usize,
    /// Light sub-paths a camera vertex merges with.
    merge: usize,
    /// Merging radius.
    radius: f32,
}

fn check_mode(name: &str, connect: bool, merge: bool) {
    check(name, connect, merge, 0.02, 1);
}

/// Checks the weights for camera paths of radius 0.02 with light sub-paths traced for
/// `light_radius`, 4096 light sub-paths in `groups` wavelength groups that merge only within
/// their group (so 4096/groups merges per camera vertex, 4096 light-tracing samples).
fn check(name: &str, connect: bool, merge: bool, light_radius: f32, groups: usize) {
    let mut rng = Rng::for_stream(2012, 0, 0);
    let counts = Counts { light: 4096, merge: 4096 / groups, radius: 0.02 };
    let constants = |radius: f32| {
        if groups == 1 {
            MisConstants::new(4096, radius, connect, merge)
        } else {
            MisConstants::with_merge_paths(4096.0, (4096 / groups) as f32, radius, connect, merge)
        }
    };
    let kc = constants(0.02);
    let light_k = constants(light_radius);
    let lights = [LightKind::Area, LightKind::Point, LightKind::Directional, LightKind::Environment];
    let mut checked_paths = 0;
    let mut checked_weights = 0;
    let mut worst = 0.0f64;
    for trial in 0..4000 {
        let k = 2 + trial % 5;
        let light = lights[(trial / 5) % 4];
        let Some(path) = TestPath::random(k, light, &mut rng) else { continue };
        let oracle = Oracle::new(&path, &counts, connect, merge);
        if oracle.techniques.is_empty() {
            continue;
        }
        let mut sum = 0.0f64;
        for &(technique, _) in &oracle.techniques {
            let expected = oracle.weight(technique);
            let got = recursive_weight(&path, technique, &kc, &light_k) as f64;
            sum += got;
            let error = (got - expected).abs() / expected.max(1e-3);
            worst = worst.max(error);
            assert!(
                error < 1e-4,
                "{name}: path of {k} segments, {light:?} light, specular {:?}: {technique:?} weight {got} vs oracle {expected}",
                (1..k).map(|i| path.is_specular(i)).collect::<Vec<_>>()
            );
            checked_weights += 1;
        }
        assert!((sum - 1.0).abs() < 1e-4, "{name}: weights sum to {sum} on a path of {k} segments, {light:?}");
        checked_paths += 1;
    }
    eprintln!("{name}: {checked_paths} paths, {checked_weights} weights, worst relative error {worst:.2e}");
    assert!(checked_paths > 1000 && checked_weights > 3000, "{name}: too few paths checked");
}

#[test]
fn vcm_weights_match_the_oracle() {
    check_mode("vcm", true, true);
}

#[test]
fn bpt_weights_match_the_oracle() {
    check_mode("bpt", true, false);
}

#[test]
fn bpm_weights_match_the_oracle() {
    check_mode("bpm", false, true);
}

#[test]
fn rebased_light_vertices_give_the_weights_of_the_camera_paths_radius() {
    // Per-pixel radius (§6.1) and merging with the previous iteration's vertices (§6.2): the
    // light vertices' quantities, computed for another radius, are rebuilt from cVC and cVM.
    check("vcm, light vertices traced for radius 0.05", true, true, 0.05, 1);
    check("bpm, light vertices traced for radius 0.007", false, true, 0.007, 1);
}

#[test]
fn wavelength_groups_merge_with_a_kth_of_the_light_paths() {
    // Spectral mode splits an iteration into K wavelength groups that merge only within their
    // group: merging has N_L/K samples per camera vertex, light tracing still N_L.
    check("vcm, 16 groups", true, true, 0.02, 16);
    check("bpm, 16 groups", false, true, 0.02, 16);
    check("vcm, 4 groups, light vertices traced for radius 0.05", true, true, 0.05, 4);
}

#[test]
fn the_oracle_tells_the_merge_count_from_the_light_tracing_count() {
    // A deliberately wrong engine: 16 groups but N_L merges per camera vertex in the
    // constants. Its weights must disagree with the oracle.
    let mut rng = Rng::for_stream(2012, 0, 0);
    let counts = Counts { light: 4096, merge: 256, radius: 0.02 };
    let kc = MisConstants::new(4096, 0.02, true, true);
    let mut worst = 0.0f64;
    for trial in 0..400 {
        let Some(path) = TestPath::random(2 + trial % 5, LightKind::Area, &mut rng) else { continue };
        let oracle = Oracle::new(&path, &counts, true, true);
        for &(technique, _) in &oracle.techniques {
            let expected = oracle.weight(technique);
            let got = recursive_weight(&path, technique, &kc, &kc) as f64;
            worst = worst.max((got - expected).abs() / expected.max(1e-3));
        }
    }
    assert!(worst > 0.1, "the oracle does not see a wrong merge count (worst relative error {worst})");
}

#[test]
fn frames_are_orthonormal_for_the_generated_normals() {
    // Guard for the path builder: its normals are unit vectors.
    let mut rng = Rng::for_stream(1, 2, 3);
    for _ in 0..100 {
        let n = facing_normal(Vec3::Z, &mut rng);
        assert!((n.length() - 1.0).abs() < 1e-5);
        let f = Frame::from_z(n);
        assert!(f.x.dot(n).abs() < 1e-5);
    }
}
