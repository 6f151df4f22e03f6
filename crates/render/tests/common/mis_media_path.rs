//! The random paths of the media MIS oracle (`mis_oracle_media.rs`): inner vertices on
//! surfaces (the reference materials of `mis_surface.rs`) or in one of three homogeneous
//! media, segments cut into vacuum and medium pieces by index-matched boundaries, the camera
//! and finite lights in or out of a medium; their geometry and the solid-angle pdfs of their
//! vertices.

#![allow(dead_code)]

use math::{PI, Rng, Vec3};
use scene::material::fresnel_dielectric;
use scene::medium::PhaseFunction;
use scene::{Camera, ReferenceMaterial, TransportMode};

use super::mis_surface::{facing_normal, materials, random_unit, reference_bsdf};

/// The light at x0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightKind {
    /// A one-sided area light (a surface: hit by camera paths).
    Area,
    /// A point light (delta position).
    Point,
    /// A directional light (delta direction, infinite).
    Directional,
    /// A uniform environment (infinite: solid-angle densities, §5.1).
    Environment,
}

impl LightKind {
    /// Point and directional lights: sampling cannot hit them.
    pub fn is_delta(self) -> bool {
        matches!(self, LightKind::Point | LightKind::Directional)
    }
    /// Area and point lights (a position at a finite distance).
    pub fn is_finite(self) -> bool {
        matches!(self, LightKind::Area | LightKind::Point)
    }
}

/// A homogeneous medium of the test: extinction per RGB channel (1/scene unit), phase
/// function, Russian-roulette continuation probability at its vertices.
pub struct TestMedium {
    /// σ_t per linear-sRGB channel (1/scene unit).
    pub sigma_t: [f32; 3],
    /// Phase function (value = solid-angle pdf).
    pub phase: PhaseFunction,
    /// Russian-roulette continuation probability at a vertex in this medium.
    pub continuation: f32,
}

/// Isotropic; forward-scattering HG with a zero blue σ_t; backward-scattering HG.
pub fn media() -> [TestMedium; 3] {
    [
        TestMedium { sigma_t: [0.5, 1.0, 2.0], phase: PhaseFunction::Isotropic, continuation: 0.9 },
        TestMedium { sigma_t: [1.5, 0.4, 0.0], phase: PhaseFunction::HenyeyGreenstein { g: 0.7 }, continuation: 0.75 },
        TestMedium { sigma_t: [0.8, 0.8, 0.8], phase: PhaseFunction::HenyeyGreenstein { g: -0.4 }, continuation: 1.0 },
    ]
}

/// An inner vertex.
#[derive(Clone, Copy, Debug)]
pub enum Vertex {
    /// On a surface with this normal and material.
    Surface(Vec3, ReferenceMaterial),
    /// A scattering event in medium `usize`.
    Medium(usize),
}

/// A piece of a segment: its length and medium (`None`: vacuum).
#[derive(Clone, Copy, Debug)]
pub struct Piece {
    /// Length (scene units).
    pub length: f32,
    /// Index into [`media`], `None` in vacuum.
    pub medium: Option<usize>,
}

/// A full path with everything the oracle and the engine driver need.
pub struct TestPath {
    /// The light at x0.
    pub light: LightKind,
    /// x0…xk (x0 unused for infinite lights).
    pub x: Vec<Vec3>,
    /// Inner vertices at 1…k−1 (0 and k: placeholders).
    pub vertex: Vec<Vertex>,
    /// Normal of the area light at x0.
    pub light_normal: Vec3,
    /// Pieces of segment i (x_{i−1} to x_i), ordered from x_{i−1}; index 0 unused.
    pub pieces: Vec<Vec<Piece>>,
    /// Unit direction from x1 towards an infinite light.
    pub light_direction: Vec3,
    /// The pinhole camera at xk.
    pub camera: Camera,
    /// Area of the area light (scene units²).
    pub light_area: f32,
}

/// Light selection probability.
pub const PICK: f32 = 0.5;
/// Radius of the scene's bounding sphere (the emission disc of infinite lights).
pub const SCENE_RADIUS: f32 = 3.0;

impl TestPath {
    /// Segments of the path.
    pub fn k(&self) -> usize {
        self.x.len() - 1
    }

    /// A random path of `k` segments, built by a walk from the camera that samples every
    /// direction from the vertex's BSDF or phase function (so none is zero); the camera sits
    /// in `camera_medium`.
    pub fn random(k: usize, light: LightKind, camera_medium: Option<usize>, rng: &mut Rng) -> Option<TestPath> {
        let all = materials();
        let media = media();
        let camera_position = Vec3::new(0.0, -3.0, 0.5);
        let first = (Vec3::new(0.1, 1.0, -0.05) + 0.2 * random_unit(rng)).normalize();
        let forward = (first + 0.15 * random_unit(rng)).normalize();
        let camera = Camera::new(camera_position, forward, Vec3::Z, 60.0, 64, 64);
        let mut rev_x = vec![camera_position];
        let mut rev_v = vec![Vertex::Medium(usize::MAX)];
        let mut direction = first;
        for _ in 1..k {
            let position = *rev_x.last().unwrap() + direction * (0.5 + rng.uniform() * 1.5);
            let vertex = if rng.uniform() < 0.5 {
                let m = (rng.uniform() * 3.0) as usize % 3;
                direction = media[m].phase.sample(-direction, rng.uniform2()).direction;
                Vertex::Medium(m)
            } else {
                let normal = facing_normal(-direction, rng);
                let material = all[(rng.uniform() * 4.0) as usize % 4];
                let bsdf = reference_bsdf(&material, normal, -direction, TransportMode::Radiance)?;
                direction = bsdf.sample(rng.uniform3())?.direction;
                Vertex::Surface(normal, material)
            };
            rev_x.push(position);
            rev_v.push(vertex);
        }
        let x1 = *rev_x.last().unwrap();
        let (x0, light_normal) = match light {
            LightKind::Area => (x1 + direction * (0.5 + rng.uniform()), facing_normal(-direction, rng)),
            LightKind::Point => (x1 + direction * (0.5 + rng.uniform()), Vec3::Z),
            LightKind::Directional | LightKind::Environment => (x1 + direction, Vec3::Z),
        };
        rev_x.push(x0);
        rev_v.push(Vertex::Medium(usize::MAX));
        rev_x.reverse();
        rev_v.reverse();
        camera.raster_position(rev_x[k - 1].max(Vec3::splat(-1e9)))?;
        // The light's medium: vacuum for infinite lights (their rays come from outside the scene).
        let light_medium = if light.is_finite() { random_medium(rng) } else { None };
        let mut ends = vec![None; k + 1];
        for (i, end) in ends.iter_mut().enumerate() {
            *end = match i {
                0 => light_medium,
                i if i == k => camera_medium,
                i => match rev_v[i] {
                    Vertex::Medium(m) => Some(m),
                    Vertex::Surface(..) => random_medium(rng),
                },
            };
        }
        let mut pieces = vec![Vec::new()];
        for i in 1..=k {
            let length = (rev_x[i] - rev_x[i - 1]).length();
            let (start, end) = (ends[i - 1], ends[i]);
            let n = 1 + (rng.uniform() * 3.0) as usize % 3;
            let n = if n == 1 && start != end { 2 } else { n };
            let mut cuts: Vec<f32> = (1..n).map(|_| 0.05 + 0.9 * rng.uniform()).collect();
            cuts.sort_by(f32::total_cmp);
            cuts.insert(0, 0.0);
            cuts.push(1.0);
            let segment: Vec<Piece> = (0..n)
                .map(|p| Piece {
                    length: (cuts[p + 1] - cuts[p]) * length,
                    medium: if p == 0 {
                        start
                    } else if p == n - 1 {
                        end
                    } else {
                        random_medium(rng)
                    },
                })
                .collect();
            pieces.push(segment);
        }
        Some(TestPath {
            light,
            x: rev_x,
            vertex: rev_v,
            light_normal,
            pieces,
            light_direction: direction,
            camera,
            light_area: 0.05 + 0.2 * rng.uniform(),
        })
    }

    /// The medium of x_i when it is an inner medium vertex.
    pub fn medium_at(&self, i: usize) -> Option<usize> {
        match self.vertex[i] {
            Vertex::Medium(m) if i >= 1 && i < self.k() => Some(m),
            _ => None,
        }
    }

    /// x_i is an inner medium vertex.
    pub fn is_medium(&self, i: usize) -> bool {
        self.medium_at(i).is_some()
    }

    /// x_i is an inner surface vertex with a purely specular material.
    pub fn is_specular(&self, i: usize) -> bool {
        match self.vertex[i] {
            Vertex::Surface(_, m) if i >= 1 && i < self.k() => m.diffuse.is_black() && m.phong.is_black(),
            _ => false,
        }
    }

    /// Unit direction from x_i to x_j (towards the light for j = 0 on infinite lights).
    pub fn dir(&self, i: usize, j: usize) -> Vec3 {
        if j == 0 && !self.light.is_finite() {
            return self.light_direction;
        }
        if i == 0 && !self.light.is_finite() {
            return -self.light_direction;
        }
        (self.x[j] - self.x[i]).normalize()
    }

    /// ‖x_j − x_i‖² (scene units²).
    pub fn dist2(&self, i: usize, j: usize) -> f32 {
        (self.x[j] - self.x[i]).length_squared()
    }

    /// |cos| at x_i towards x_j: 1 at medium vertices, point and infinite lights and the camera.
    pub fn cos(&self, i: usize, j: usize) -> f32 {
        if i == 0 {
            return if self.light == LightKind::Area { self.light_normal.dot(self.dir(0, j)).abs() } else { 1.0 };
        }
        match self.vertex[i] {
            Vertex::Surface(n, _) if i < self.k() => n.dot(self.dir(i, j)).abs(),
            _ => 1.0,
        }
    }

    /// At inner vertex i: solid-angle pdfs (forward, reverse) of scattering from `from` to
    /// `to`, Russian roulette included.
    pub fn scatter_pdfs(&self, i: usize, from: usize, to: usize) -> (f32, f32) {
        let (normal, material) = match self.vertex[i] {
            Vertex::Medium(m) => {
                let m = &media()[m];
                let p = m.phase.evaluate(self.dir(i, from), self.dir(i, to)) * m.continuation;
                return (p, p);
            }
            Vertex::Surface(n, material) => (n, material),
        };
        let mode = if from > i { TransportMode::Radiance } else { TransportMode::Importance };
        let bsdf = reference_bsdf(&material, normal, self.dir(i, from), mode).unwrap();
        let cont = bsdf.continuation_probability();
        if self.is_specular(i) {
            let p = if material.ior < 0.0 {
                1.0
            } else {
                let f = fresnel_dielectric(normal.dot(self.dir(i, from)), material.ior);
                let reflected = normal.dot(self.dir(i, from)) * normal.dot(self.dir(i, to)) > 0.0;
                if reflected { f } else { 1.0 - f }
            };
            return (p * cont, p * cont);
        }
        let eval = bsdf.evaluate(self.dir(i, to)).expect("the path was built with non-zero BSDFs");
        (eval.pdf.forward.0 * cont, eval.pdf.reverse.0 * cont)
    }

    /// (p0_trace, p0_connect, emission pdf), pick probability included.
    pub fn light_pdfs(&self) -> (f32, f32, f32) {
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
    pub fn camera_pdf_w(&self) -> f32 {
        let k = self.k();
        self.camera.solid_angle_pdf(self.camera.forward.dot(self.dir(k, k - 1))).0
    }
}

/// Vacuum or one of the [`media`], each with probability 1/4.
pub fn random_medium(rng: &mut Rng) -> Option<usize> {
    let u = (rng.uniform() * 4.0) as usize % 4;
    (u < 3).then_some(u)
}
