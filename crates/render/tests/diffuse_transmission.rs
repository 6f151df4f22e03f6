//! pbrt-v4's `diffusetransmission` through the whole renderer: a sheet with reflectance R and
//! transmittance T fills the view under a constant environment of radiance 1. A single sheet
//! has no inter-reflection, so every pixel sees exactly `R + T` (R from the camera's side, T
//! from behind), for any path length. pt, bpt and vcm must agree with it per channel (image
//! means pooled over the pixels, whose standard errors come from their iterations); each test
//! also shows that an expectation 2 % off would be rejected.

use std::path::PathBuf;

use render::driver::{Algorithm, Budget, RenderSettings};
use scene::Scene;

const RESOLUTION: u32 = 16;
const ITERATIONS: u64 = 64;
const REFLECTANCE: [f64; 3] = [0.5, 0.3, 0.1];
const TRANSMITTANCE: [f64; 3] = [0.2, 0.4, 0.3];

fn scene() -> Scene {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("diffuse_transmission");
    std::fs::create_dir_all(&dir).unwrap();
    let [r0, r1, r2] = REFLECTANCE;
    let [t0, t1, t2] = TRANSMITTANCE;
    let text = format!(
        r#"LookAt 0 0 3  0 0 0  0 1 0
Camera "perspective" "float fov" 30
Film "rgb" "integer xresolution" {RESOLUTION} "integer yresolution" {RESOLUTION}
PixelFilter "box"
WorldBegin
LightSource "infinite" "rgb L" [1 1 1]
Material "diffusetransmission" "rgb reflectance" [{r0} {r1} {r2}] "rgb transmittance" [{t0} {t1} {t2}]
Shape "trianglemesh" "point3 P" [-5 -5 0  5 -5 0  5 5 0  -5 5 0] "integer indices" [0 1 2 0 2 3]
"#
    );
    let path = dir.join("sheet.pbrt");
    std::fs::write(&path, text).unwrap();
    let desc = io::load_scene(&path, &[]).unwrap_or_else(|e| panic!("{e}"));
    Scene::from_description(&desc, None).unwrap_or_else(|e| panic!("{e}")).0
}

/// Per channel, the image mean and its standard error (pixels are independent).
fn image_mean(scene: &Scene, algorithm: &str) -> [(f64, f64); 3] {
    let settings = RenderSettings {
        algorithm: Algorithm::from_name(algorithm).unwrap(),
        budget: Budget::Iterations(ITERATIONS),
        seed: 9,
        ..Default::default()
    };
    let film = render::render(scene, &settings).unwrap().film;
    assert_eq!(film.rejected_samples(), 0);
    let mean = film.mean();
    let variance = film.variance_of_mean().unwrap();
    let n = mean.len() as f64;
    [0, 1, 2].map(|c| {
        let m = mean.iter().map(|p| f64::from(p[c])).sum::<f64>() / n;
        let v = variance.iter().map(|p| f64::from(p[c])).sum::<f64>() / (n * n);
        (m, v.sqrt())
    })
}

#[test]
fn a_diffuse_transmitter_under_a_uniform_sky_shows_r_plus_t() {
    let scene = scene();
    for algorithm in ["pt", "bpt", "vcm"] {
        for (c, (mean, se)) in image_mean(&scene, algorithm).into_iter().enumerate() {
            let expected = REFLECTANCE[c] + TRANSMITTANCE[c];
            let z = (mean - expected) / se;
            let z_biased = (mean - 1.02 * expected) / se;
            eprintln!("{algorithm} channel {c}: {mean:.5} ± {se:.5} against {expected}: z = {z:.2}");
            // 9 comparisons at a family-wise 1e-3: |z| < 3.9.
            assert!(z.abs() < 3.9, "{algorithm} channel {c}: {mean} ± {se}, expected {expected}");
            assert!(z_biased.abs() > 3.9, "{algorithm} channel {c}: cannot see a 2 % bias (z = {z_biased})");
        }
    }
}
