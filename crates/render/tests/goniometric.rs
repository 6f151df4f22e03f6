//! pbrt-v4's goniometric light through the whole renderer: a floor lit from 1.5 above by a
//! goniometric light whose image (16 × 16, coloured stripes and a gradient) is centred on the
//! floor. Light tracing starts every path with the light's emission sampler (directions drawn in
//! proportion to the image), the path tracer uses its direct query (the image looked up along
//! the connection): lt and bpt agree with pt block by block (8 × 8 pixels, Šidák-corrected
//! Z-test) and on the pooled channel means, and the pooled comparison detects a relative bias of
//! a few percent (asserted).

use crate::common;

use std::path::PathBuf;

use common::{block_estimate, detectable_bias, settings};
use scene::Scene;
use testkit::z_test_entries;

const ALPHA: f64 = 1e-3;
const BLOCK: u32 = 8;
const ITERATIONS: u64 = 256;

fn scene() -> Scene {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("goniometric");
    std::fs::create_dir_all(&dir).unwrap();
    let image = io::Image::from_fn(16, 16, |x, y| {
        let stripe = if (x / 2 + y / 3) % 2 == 0 { 1.0 } else { 0.2 };
        [stripe * (0.5 + 0.1 * x as f32), stripe, 0.3 + 0.05 * y as f32]
    });
    io::write_image(&dir.join("gonio.pfm"), &image, &io::WriteOptions::default()).unwrap();
    // Rotate −90 about x turns the light's +y (the image's centre) to −z, towards the floor.
    let text = r#"LookAt 0 -0.01 2.5  0 0 0  0 1 0
Camera "perspective" "float fov" 60
Film "rgb" "integer xresolution" 32 "integer yresolution" 32
PixelFilter "box"
WorldBegin
AttributeBegin
  Translate 0.2 0 1.5
  Rotate -90 1 0 0
  LightSource "goniometric" "string filename" "gonio.pfm" "rgb I" [2 1.5 1]
AttributeEnd
Material "diffuse" "rgb reflectance" [0.7 0.7 0.7]
Shape "trianglemesh" "point3 P" [-3 -3 0  3 -3 0  3 3 0  -3 3 0] "integer indices" [0 1 2 0 2 3]
"#;
    let path = dir.join("scene.pbrt");
    std::fs::write(&path, text).unwrap();
    let desc = io::load_scene(&path, &[]).unwrap_or_else(|e| panic!("{e}"));
    Scene::from_description(&desc, None).unwrap_or_else(|e| panic!("{e}")).0
}

#[test]
fn light_tracing_and_bpt_agree_with_path_tracing() {
    let scene = scene();
    let mut pt_settings = settings("pt", 1);
    pt_settings.max_length = 2;
    let pt = block_estimate(&scene, &pt_settings, ITERATIONS, BLOCK);
    for algorithm in ["lt", "bpt"] {
        let mut other_settings = settings(algorithm, 2);
        other_settings.max_length = 2;
        let other = block_estimate(&scene, &other_settings, ITERATIONS, BLOCK);
        let outcome = z_test_entries(&other.means, &other.std_errors, &pt.means, &pt.std_errors, ALPHA / 2.0);
        let keep = vec![true; other.means.len() / 3];
        let (om, oe) = other.pooled(&keep);
        let (pm, pe) = pt.pooled(&keep);
        let pooled = z_test_entries(&om, &oe, &pm, &pe, ALPHA / 2.0);
        let detectable = detectable_bias(&om, &oe, &pm, &pe, ALPHA / 2.0);
        eprintln!(
            "goniometric, {algorithm} vs pt: blocks worst z {:.2}; pooled {om:.4?} vs {pm:.4?}, worst z {:.2}, \
             detects {:.2} %",
            outcome.worst_z,
            pooled.worst_z,
            100.0 * detectable
        );
        assert!(pm.iter().all(|m| *m > 0.01), "the floor is dark ({pm:?})");
        assert!(outcome.passed, "{algorithm} disagrees with pt on a block: {outcome:?}");
        assert!(pooled.passed, "{algorithm} disagrees with pt on the means: {om:?} vs {pm:?}");
        assert!(detectable < 0.03, "{algorithm}: the test only detects a bias of {detectable}");
    }
}
