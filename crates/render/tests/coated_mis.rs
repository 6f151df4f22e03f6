//! The MIS oracle on paths through pbrt-v4's coated materials: on random paths of 2–5 segments
//! from an area light to a pinhole camera whose vertices are coated (rough diffuse, smooth
//! diffuse with its delta lobe, rough gold over a scattering medium), the weights the engine's
//! recursive quantities give every technique (`render::vcm::mis`) equal an explicit
//! non-recursive balance-heuristic evaluation from per-vertex forward and reverse area pdfs,
//! and sum to 1, for vcm and bpt. This holds only because the coated BSDF's pdfs are the same
//! deterministic functions however and from whichever side they are asked for (its *values*
//! are random-walk estimates). `mis_oracle.rs` tests the same algebra on the reference
//! material with every kind of light; this file keeps to area lights.

// Loops run over vertex numbers x_i of the path notation, which index several arrays.
#![allow(clippy::needless_range_loop)]

use math::{PI, Rng, Vec3};
use render::vcm::mis::{self, ConnectionPdfs, MisConstants, NeePdfs, SubPathMis};
use scene::material::{CoatedBase, CoatedParameters, CoatingInterface, CoatingLayer, ConductorIor};
use scene::{Bsdf, Camera, Material, ShadingPoint, Texture, TransportMode};
use spectrum::Rgb;

const PICK: f32 = 0.5;

fn coated(alpha: f32, layer: CoatingLayer, base: CoatedBase) -> Material {
    let interface = CoatingInterface { eta: 1.5, alpha_u: alpha, alpha_v: alpha };
    Material::Coated(Box::new(CoatedParameters::new(interface, layer, base).unwrap()))
}

/// The three materials, built once (each builds its quadrature tables).
fn materials() -> &'static [Material; 3] {
    static MATERIALS: std::sync::OnceLock<[Material; 3]> = std::sync::OnceLock::new();
    MATERIALS.get_or_init(build_materials)
}

fn build_materials() -> [Material; 3] {
    let diffuse = || CoatedBase::Diffuse { reflectance: Texture::Constant(Rgb::new(0.7, 0.5, 0.3)) };
    let gold = CoatedBase::Conductor {
        ior: ConductorIor::Complex { eta: Rgb::new(0.18, 0.42, 1.37), k: Rgb::new(3.42, 2.35, 1.77) },
        alpha_u: 0.2,
        alpha_v: 0.2,
    };
    let medium =
        CoatingLayer { thickness: 0.3, albedo: Texture::Constant(Rgb::splat(0.6)), g: 0.3, ..Default::default() };
    [
        coated(0.3, CoatingLayer::default(), diffuse()),
        coated(0.0, CoatingLayer::default(), diffuse()),
        coated(0.1, medium, gold),
    ]
}

/// A path x0 (on the area light) … xk (the pinhole).
struct TestPath {
    x: Vec<Vec3>,
    normal: Vec<Vec3>,
    material: Vec<usize>,
    /// The vertex scattered through a delta lobe.
    specular: Vec<bool>,
    camera: Camera,
    light_area: f32,
}

fn facing_normal(towards: Vec3, rng: &mut Rng) -> Vec3 {
    loop {
        let n = (towards + 0.8 * math::warp::uniform_sphere(rng.uniform2())).normalize();
        if n.dot(towards) > 0.3 {
            return n;
        }
    }
}

fn bsdf(material: &Material, normal: Vec3, fixed: Vec3, mode: TransportMode) -> Option<Bsdf> {
    Bsdf::new(material, &ShadingPoint::flat(normal), fixed, mode)
}

impl TestPath {
    fn k(&self) -> usize {
        self.x.len() - 1
    }

    /// A walk from the camera that samples every direction from the vertex's BSDF.
    fn random(k: usize, rng: &mut Rng) -> Option<TestPath> {
        let all = materials();
        let camera_position = Vec3::new(0.0, -3.0, 0.5);
        let first = (Vec3::new(0.1, 1.0, -0.05) + 0.2 * math::warp::uniform_sphere(rng.uniform2())).normalize();
        let camera = Camera::new(camera_position, first, Vec3::Z, 60.0, 64, 64);
        let (mut x, mut normal, mut material, mut specular) =
            (vec![camera_position], vec![Vec3::Z], vec![0], vec![false]);
        let mut direction = first;
        for _ in 1..k {
            let position = *x.last().unwrap() + direction * (0.5 + rng.uniform() * 1.5);
            let n = facing_normal(-direction, rng);
            let m = (rng.uniform() * 3.0) as usize % 3;
            let s = bsdf(&all[m], n, -direction, TransportMode::Radiance)?.sample(rng.uniform3())?;
            x.push(position);
            normal.push(n);
            material.push(m);
            specular.push(s.lobe.is_specular());
            direction = s.direction;
        }
        let x0 = *x.last().unwrap() + direction * (0.5 + rng.uniform());
        x.push(x0);
        normal.push(facing_normal(-direction, rng));
        material.push(0);
        specular.push(false);
        material.reverse();
        x.reverse();
        normal.reverse();
        specular.reverse();
        camera.raster_position(x[k - 1])?;
        Some(TestPath { x, normal, material, specular, camera, light_area: 0.05 + 0.2 * rng.uniform() })
    }

    fn dir(&self, i: usize, j: usize) -> Vec3 {
        (self.x[j] - self.x[i]).normalize()
    }

    fn dist2(&self, i: usize, j: usize) -> f32 {
        (self.x[j] - self.x[i]).length_squared()
    }

    fn cos(&self, i: usize, j: usize) -> f32 {
        if i == self.k() { 1.0 } else { self.normal[i].dot(self.dir(i, j)).abs() }
    }

    /// Solid-angle pdfs (forward, reverse) at vertex i from `from` to `to`, Russian roulette
    /// included; a delta vertex reports its lobe probability.
    fn scatter_pdfs(&self, i: usize, from: usize, to: usize) -> (f32, f32) {
        let mode = if from > i { TransportMode::Radiance } else { TransportMode::Importance };
        let all = materials();
        let b = bsdf(&all[self.material[i]], self.normal[i], self.dir(i, from), mode).unwrap();
        let cont = b.continuation_probability();
        if self.specular[i] {
            let s = b.sample([0.5, 0.5, 0.0]).unwrap();
            assert!(s.lobe.is_specular());
            return (s.pdf.forward.0 * cont, s.pdf.reverse.0 * cont);
        }
        // The pdfs do not depend on the walk's estimate: take them even when it is zero.
        let e = b.evaluate(self.dir(i, to));
        let e = e.unwrap_or_else(|| panic!("vertex {i}: zero estimate"));
        (e.pdf.forward.0 * cont, e.pdf.reverse.0 * cont)
    }

    fn light_pdfs(&self) -> (f32, f32) {
        let a = PICK / self.light_area;
        (a, a * self.cos(0, 1) / PI)
    }

    fn camera_pdf_w(&self) -> f32 {
        let k = self.k();
        self.camera.solid_angle_pdf(self.camera.forward.dot(self.dir(k, k - 1))).0
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Technique {
    Vc(usize),
    Vm(usize),
}

/// Eq. (12) of the tech report evaluated explicitly: every technique's path pdf (times its
/// sample count) as a product of per-vertex area pdfs, in f64.
fn oracle(path: &TestPath, light_paths: f64, radius: f64, merge: bool) -> Vec<(Technique, f64)> {
    let k = path.k();
    let (p0, emission_pdf) = path.light_pdfs();
    let mut fwd = vec![0.0f64; k];
    fwd[0] = p0 as f64;
    fwd[1] = (emission_pdf / p0 * path.cos(1, 0) / path.dist2(0, 1)) as f64;
    for i in 2..k {
        fwd[i] = (path.scatter_pdfs(i - 1, i - 2, i).0 * path.cos(i, i - 1) / path.dist2(i - 1, i)) as f64;
    }
    let mut rev = vec![0.0f64; k];
    rev[k - 1] = (path.camera_pdf_w() * path.cos(k - 1, k) / path.dist2(k - 1, k)) as f64;
    for i in (0..k - 1).rev() {
        rev[i] = (path.scatter_pdfs(i + 1, i + 2, i).0 * path.cos(i, i + 1) / path.dist2(i, i + 1)) as f64;
    }
    let connectable = |i: usize| !path.specular[i];
    let mut techniques = Vec::new();
    for s in 0..=k {
        let t = k + 1 - s;
        let possible = (s <= 1 || connectable(s - 1)) && (t == 1 || connectable(s));
        if (s == 1 && t == 1) || !possible {
            continue;
        }
        let p: f64 = fwd.iter().take(s).product::<f64>() * rev.iter().skip(s).product::<f64>();
        if p > 0.0 {
            techniques.push((Technique::Vc(s), if t == 1 { light_paths } else { 1.0 } * p));
        }
    }
    if merge {
        for j in (1..k).filter(|&j| connectable(j)) {
            let p = std::f64::consts::PI
                * radius
                * radius
                * rev[j]
                * fwd.iter().take(j + 1).product::<f64>()
                * rev.iter().skip(j + 1).product::<f64>();
            if p > 0.0 {
                techniques.push((Technique::Vm(j), light_paths * p));
            }
        }
    }
    techniques
}

/// The engine's recursive weight of `technique` (tech report eqs. 31–47).
fn recursive_weight(path: &TestPath, technique: Technique, kc: &MisConstants) -> f32 {
    let k = path.k();
    let (p0, emission_pdf) = path.light_pdfs();
    let mut light_states = vec![SubPathMis::default(); k];
    let mut state = SubPathMis::light_start(emission_pdf, p0, path.cos(0, 1), false, kc);
    for i in 1..k {
        state.arrive(Some(path.dist2(i - 1, i)), path.cos(i, i - 1));
        light_states[i] = state;
        if i + 1 < k {
            let (f, r) = path.scatter_pdfs(i, i - 1, i + 1);
            state.scatter(path.cos(i, i + 1), f, r, path.specular[i], kc);
        }
    }
    let mut camera_states = vec![SubPathMis::default(); k];
    let mut state = SubPathMis::camera_start(path.camera_pdf_w(), kc);
    for i in (1..k).rev() {
        state.arrive(Some(path.dist2(i, i + 1)), path.cos(i, i + 1));
        camera_states[i] = state;
        let (f, r) = path.scatter_pdfs(i, i + 1, i - 1);
        state.scatter(path.cos(i, i - 1), f, r, path.specular[i], kc);
    }
    state.arrive(Some(path.dist2(0, 1)), path.cos(0, 1));
    camera_states[0] = state;
    match technique {
        Technique::Vc(0) => mis::emitter_hit_weight(&camera_states[0], p0, emission_pdf),
        Technique::Vc(1) => {
            let (forward, reverse) = path.scatter_pdfs(1, 2, 0);
            let pdfs = NeePdfs {
                direct_w: p0 * path.dist2(0, 1) / path.cos(0, 1),
                emission_w: emission_pdf,
                bsdf_forward_w: forward,
                bsdf_reverse_w: reverse,
                cos_at_vertex: path.cos(1, 0),
                cos_at_light: path.cos(0, 1),
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

fn check(name: &str, merge: bool) {
    let mut rng = Rng::for_stream(1414, merge as u64, 0);
    let (light_paths, radius) = (4096usize, 0.02f32);
    let kc = MisConstants::new(light_paths, radius, true, merge);
    let (mut paths, mut weights, mut specular) = (0, 0, 0);
    for trial in 0..1500 {
        let k = 2 + trial % 4;
        let Some(path) = TestPath::random(k, &mut rng) else { continue };
        // A vertex whose walk estimate towards the next one is zero carries no path.
        let zero = (1..k).any(|i| {
            !path.specular[i] && {
                let b =
                    bsdf(&materials()[path.material[i]], path.normal[i], path.dir(i, i + 1), TransportMode::Radiance);
                b.and_then(|b| b.evaluate(path.dir(i, i - 1))).is_none()
            }
        });
        if zero {
            continue;
        }
        let techniques = oracle(&path, light_paths as f64, radius as f64, merge);
        let total: f64 = techniques.iter().map(|(_, p)| p).sum();
        let mut sum = 0.0f64;
        for &(technique, p) in &techniques {
            let (expected, got) = (p / total, recursive_weight(&path, technique, &kc) as f64);
            sum += got;
            assert!(
                (got - expected).abs() <= 1e-4 * expected.max(1e-3) + 1e-6,
                "{name}: {k} segments, specular {:?}: {technique:?} weight {got} vs oracle {expected}",
                path.specular
            );
            weights += 1;
        }
        assert!((sum - 1.0).abs() < 1e-4, "{name}: weights sum to {sum} on a path of {k} segments");
        paths += 1;
        specular += path.specular.iter().any(|s| *s) as usize;
    }
    eprintln!("{name}: {paths} paths ({specular} with a delta vertex), {weights} weights");
    assert!(paths > 800 && weights > 3000 && specular > 50, "{name}: too few paths checked");
}

#[test]
fn vcm_weights_through_coated_vertices_match_the_oracle() {
    check("vcm", true);
}

#[test]
fn bpt_weights_through_coated_vertices_match_the_oracle() {
    check("bpt", false);
}
