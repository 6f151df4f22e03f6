//! Mesh attributes (Mitsuba's `mesh_attribute` texture) through the whole renderer: a diffuse
//! plane read from a PLY file written here, with known vertex or face colours as its
//! reflectance, under a constant environment of radiance 1. The plane is open to the whole
//! hemisphere, so its radiance is exactly its reflectance at the point (L = ρ·Le), for any
//! path length. Every pixel whose footprint lies inside one triangle (vertex colours) or one
//! face (face colours) must equal the colour the test interpolates itself from the file's
//! values (per-pixel Z-test, Šidák-corrected), and the pooled relative error must be zero
//! within its standard error; a reflectance 2 % too bright, and vertex colours taken flat per
//! triangle, fail these same tests.

use std::path::PathBuf;

use math::{Rng, Vec2, Vec3};
use render::driver::Budget;
use scene::Scene;
use testkit::z_test_entries;

/// Family-wise significance.
const ALPHA: f64 = 1e-3;
const RESOLUTION: u32 = 24;
const ITERATIONS: u64 = 96;

/// A 3 × 3 grid of vertices over `[-1, 1]²` at `z = 0` (normal `+z`), four quad faces.
fn grid() -> (Vec<Vec3>, Vec<[usize; 4]>) {
    let positions = (0..9).map(|i| Vec3::new((i % 3) as f32 - 1.0, (i / 3) as f32 - 1.0, 0.0)).collect();
    let faces = vec![[0, 1, 4, 3], [1, 2, 5, 4], [3, 4, 7, 6], [4, 5, 8, 7]];
    (positions, faces)
}

/// Colours in [0.1, 0.9] from a fixed stream.
fn colours(count: usize, stream: u64) -> Vec<[f32; 3]> {
    let mut rng = Rng::for_stream(11, stream, 0);
    (0..count).map(|_| [0; 3].map(|_: i32| 0.1 + 0.8 * rng.uniform())).collect()
}

/// An ASCII PLY of the grid with vertex colours `red green blue` and face colours
/// `color_0 color_1 color_2` (Mitsuba's `vertex_color` and `face_color`).
fn ply(vertex: &[[f32; 3]], face: &[[f32; 3]]) -> String {
    let (positions, faces) = grid();
    let mut s = format!(
        "ply\nformat ascii 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
         property float red\nproperty float green\nproperty float blue\nelement face {}\n\
         property list uchar int vertex_indices\nproperty float color_0\nproperty float color_1\n\
         property float color_2\nend_header\n",
        positions.len(),
        faces.len()
    );
    for (p, c) in positions.iter().zip(vertex) {
        s += &format!("{} {} {} {} {} {}\n", p.x, p.y, p.z, c[0], c[1], c[2]);
    }
    for (f, c) in faces.iter().zip(face) {
        s += &format!("4 {} {} {} {} {} {} {}\n", f[0], f[1], f[2], f[3], c[0], c[1], c[2]);
    }
    s
}

/// The scene: the plane seen from `z = 3`, reflectance from the attribute `attribute`.
fn scene(name: &str, attribute: &str, vertex: &[[f32; 3]], face: &[[f32; 3]]) -> Scene {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("mesh_attributes");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join(format!("{name}.ply")), ply(vertex, face)).unwrap();
    let xml = format!(
        r#"<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="4"/></integrator>
  <sensor type="perspective">
    <float name="fov" value="45"/>
    <transform name="to_world"><lookat origin="0, 0, 3" target="0, 0, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="{RESOLUTION}"/><integer name="height" value="{RESOLUTION}"/>
      <rfilter type="box"/></film>
  </sensor>
  <emitter type="constant"><rgb name="radiance" value="1"/></emitter>
  <shape type="ply">
    <string name="filename" value="{name}.ply"/>
    <bsdf type="diffuse"><texture type="mesh_attribute" name="reflectance"><string name="name" value="{attribute}"/>
      </texture></bsdf>
  </shape>
</scene>"#
    );
    let path = dir.join(format!("{name}.xml"));
    std::fs::write(&path, xml).unwrap();
    let desc = io::load_scene(&path, &[]).unwrap_or_else(|e| panic!("{e}"));
    Scene::from_description(&desc, None).unwrap_or_else(|e| panic!("{e}")).0
}

/// Where a point of the plane lies: its face, the triangle of the face's fan (0 or 1), and
/// the barycentric weights of that triangle's corners (fan corners 0, k, k + 1).
fn locate(point: Vec3) -> Option<(usize, usize, [f32; 3])> {
    let (positions, faces) = grid();
    for (f, face) in faces.iter().enumerate() {
        for k in 1..3 {
            let [a, b, c] = [face[0], face[k], face[k + 1]].map(|i| positions[i].truncate());
            let p = point.truncate();
            let cross = |u: Vec2, v: Vec2| u.x * v.y - u.y * v.x;
            let area = cross(b - a, c - a);
            let wb = cross(p - a, c - a) / area;
            let wc = cross(b - a, p - a) / area;
            let wa = 1.0 - wb - wc;
            if [wa, wb, wc].iter().all(|w| *w >= -1e-4) {
                return Some((f, k - 1, [wa, wb, wc]));
            }
        }
    }
    None
}

/// For each pixel whose footprint (centre and corners) lies on one triangle (`per_face`:
/// one face), the expected radiance from `expected(face, fan triangle, weights)`.
fn expectations(
    scene: &Scene,
    per_face: bool,
    expected: impl Fn(usize, usize, [f32; 3]) -> [f32; 3],
) -> Vec<Option<[f64; 3]>> {
    let camera = &scene.camera;
    let mut out = Vec::new();
    for y in 0..RESOLUTION {
        for x in 0..RESOLUTION {
            let at = |dx: f32, dy: f32| {
                let hit = scene.intersect(&camera.generate_ray(Vec2::new(x as f32 + dx, y as f32 + dy)))?;
                locate(hit.position)
            };
            let corners = [at(0.0, 0.0), at(1.0, 0.0), at(0.0, 1.0), at(1.0, 1.0)];
            let centre = at(0.5, 0.5);
            let same = |c: &Option<(usize, usize, [f32; 3])>| match (c, centre) {
                (Some(c), Some(m)) => c.0 == m.0 && (per_face || c.1 == m.1),
                _ => false,
            };
            out.push(match centre {
                Some((f, t, w)) if corners.iter().all(same) => Some(expected(f, t, w).map(f64::from)),
                _ => None,
            });
        }
    }
    out
}

/// Renders with the path tracer; per-pixel means and standard errors.
fn render(scene: &Scene) -> (Vec<[f64; 3]>, Vec<[f64; 3]>) {
    let mut settings = render::driver::RenderSettings {
        algorithm: render::driver::Algorithm::from_name("pt").unwrap(),
        seed: 5,
        ..Default::default()
    };
    settings.budget = Budget::Iterations(ITERATIONS);
    let film = render::render(scene, &settings).unwrap().film;
    assert_eq!(film.rejected_samples(), 0);
    let n = ITERATIONS as f64;
    let mean: Vec<[f64; 3]> = film.sums().iter().map(|s| s.map(|v| v / n)).collect();
    let se = film
        .sum_squares()
        .iter()
        .zip(&mean)
        .map(|(q, m)| [0, 1, 2].map(|c| ((q[c] / n - m[c] * m[c]).max(0.0) * n / (n - 1.0) / n).sqrt()))
        .collect();
    (mean, se)
}

/// Per-pixel Z-test of the render against `expected` (pixels with an expectation), and the
/// pooled relative error with its standard error.
fn compare(render: &(Vec<[f64; 3]>, Vec<[f64; 3]>), expected: &[Option<[f64; 3]>]) -> (bool, f64, f64) {
    let (mut a, mut a_se, mut b) = (Vec::new(), Vec::new(), Vec::new());
    let (mut sum, mut sum_se2) = (0.0, 0.0);
    for ((m, s), e) in render.0.iter().zip(&render.1).zip(expected) {
        let Some(e) = e else { continue };
        for c in 0..3 {
            a.push(m[c]);
            a_se.push(s[c]);
            b.push(e[c]);
            sum += (m[c] - e[c]) / e[c];
            sum_se2 += (s[c] / e[c]).powi(2);
        }
    }
    let n = a.len() as f64;
    assert!(n >= 3.0 * 100.0, "only {} pixels lie inside one triangle", n / 3.0);
    let zeros = vec![0.0; a.len()];
    let outcome = z_test_entries(&a, &a_se, &b, &zeros, ALPHA);
    eprintln!("{} pixels: {outcome}; pooled relative error {:.5} ± {:.5}", n / 3.0, sum / n, sum_se2.sqrt() / n);
    (outcome.passed, sum / n, sum_se2.sqrt() / n)
}

/// The pooled relative error passes at the Šidák-free level `ALPHA` (|z| < 3.29).
fn pooled_ok(mean: f64, se: f64) -> bool {
    (mean / se).abs() < 3.29
}

#[test]
fn vertex_colours_are_interpolated_barycentrically() {
    let (vertex, face) = (colours(9, 1), colours(4, 2));
    let scene = scene("vertex", "vertex_color", &vertex, &face);
    let (_, faces) = grid();
    let interpolated = |f: usize, t: usize, w: [f32; 3]| {
        let corners = [faces[f][0], faces[f][t + 1], faces[f][t + 2]];
        [0, 1, 2].map(|c| (0..3).map(|k| w[k] * vertex[corners[k]][c]).sum())
    };
    let expected = expectations(&scene, false, interpolated);
    let image = render(&scene);
    let (passed, mean, se) = compare(&image, &expected);
    assert!(passed && pooled_ok(mean, se), "per-pixel test passed: {passed}; pooled relative error {mean} ± {se}");
    // A 2 % brighter reflectance fails the pooled test.
    let brighter: Vec<_> = expected.iter().map(|e| e.map(|e| e.map(|v| v * 1.02))).collect();
    let (_, mean, se) = compare(&image, &brighter);
    assert!(!pooled_ok(mean, se), "a 2 % bias went undetected: {mean} ± {se}");
    // The triangle's mean colour (flat shading) fails the per-pixel test.
    let flat = expectations(&scene, false, |f, t, _| interpolated(f, t, [1.0 / 3.0; 3]));
    assert!(!compare(&image, &flat).0, "flat colours passed");
}

#[test]
fn face_colours_are_constant_per_face() {
    let (vertex, face) = (colours(9, 3), colours(4, 4));
    let scene = scene("face", "face_color", &vertex, &face);
    let expected = expectations(&scene, true, |f, _, _| face[f]);
    let image = render(&scene);
    let (passed, mean, se) = compare(&image, &expected);
    assert!(passed && pooled_ok(mean, se), "per-pixel test passed: {passed}; pooled relative error {mean} ± {se}");
    // The faces' colours in the wrong order fail.
    let shifted = expectations(&scene, true, |f, _, _| face[(f + 1) % 4]);
    assert!(!compare(&image, &shifted).0, "shifted face colours passed");
}

#[test]
fn a_missing_attribute_names_what_the_mesh_has() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("mesh_attributes");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("missing.ply"), ply(&colours(9, 1), &colours(4, 2))).unwrap();
    let xml = r#"<scene version="3.0.0">
  <shape type="ply" id="plane"><string name="filename" value="missing.ply"/>
    <bsdf type="diffuse"><texture type="mesh_attribute" name="reflectance"><string name="name" value="vertex_albedo"/>
    </texture></bsdf></shape>
</scene>"#;
    let path = dir.join("missing.xml");
    std::fs::write(&path, xml).unwrap();
    let desc = io::load_scene(&path, &[]).unwrap_or_else(|e| panic!("{e}"));
    let error = Scene::from_description(&desc, None).map(|_| ()).expect_err("a missing attribute must be an error");
    assert!(
        error.contains("`vertex_albedo`") && error.contains("`vertex_color`") && error.contains("`face_color`"),
        "{error}"
    );
}
