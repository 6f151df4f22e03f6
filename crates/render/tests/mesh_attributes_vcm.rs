//! Mesh attributes at stored light vertices: a floor read from a PLY file with vertex colours
//! (Mitsuba's `mesh_attribute` reflectance) lit by a point light, and a white wall that the
//! camera sees. Light sub-paths store vertices on the floor, and connections from camera
//! vertices on the wall rebuild the floor's BSDF from the stored record (the attribute packed
//! into the uv slot), so BPT and VCM must agree with the path tracer (per 8 × 8 block
//! Z-test with a Šidák correction, and on the pooled means), and the pooled test must detect
//! a relative bias of a few percent ([`common::detectable_bias`]).
//!
//! These connections carry a small share of the image: scaling the unpacked attribute by 0.9
//! moved the pooled means by only 0.35 % and went undetected. The exact check of the packed
//! path is `light_vertex::tests::stored_vertices_rebuild_attribute_bsdfs`; this test shows the
//! whole engine stays consistent with it.

use crate::common;

use std::path::PathBuf;

use common::{block_estimate, detectable_bias, settings};
use math::Rng;
use scene::Scene;
use testkit::z_test_entries;

const ALPHA: f64 = 1e-3;
const RESOLUTION: u32 = 32;
const BLOCK: u32 = 8;

/// The floor `[-1, 1]²` at `z = 0` as a 3 × 3 grid with colours in [0.05, 0.95].
fn floor_ply() -> String {
    let mut rng = Rng::for_stream(3, 0, 0);
    let mut s = String::from(
        "ply\nformat ascii 1.0\nelement vertex 9\nproperty float x\nproperty float y\nproperty float z\n\
         property float red\nproperty float green\nproperty float blue\nelement face 4\n\
         property list uchar int vertex_indices\nend_header\n",
    );
    for i in 0..9 {
        let c = [0; 3].map(|_: i32| 0.05 + 0.9 * rng.uniform());
        s += &format!("{} {} 0 {} {} {}\n", (i % 3) as f32 - 1.0, (i / 3) as f32 - 1.0, c[0], c[1], c[2]);
    }
    s + "4 0 1 4 3\n4 1 2 5 4\n4 3 4 7 6\n4 4 5 8 7\n"
}

fn scene() -> Scene {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("mesh_attributes_vcm");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("floor.ply"), floor_ply()).unwrap();
    let xml = format!(
        r#"<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="3"/></integrator>
  <sensor type="perspective">
    <float name="fov" value="50"/>
    <transform name="to_world"><lookat origin="0, -2.5, 1" target="0, 1, 0.7" up="0, 0, 1"/></transform>
    <film type="hdrfilm"><integer name="width" value="{RESOLUTION}"/><integer name="height" value="{RESOLUTION}"/>
      <rfilter type="box"/></film>
  </sensor>
  <emitter type="point"><point name="position" x="0" y="-0.3" z="1.6"/><rgb name="intensity" value="4"/></emitter>
  <shape type="ply">
    <string name="filename" value="floor.ply"/>
    <bsdf type="diffuse"><texture type="mesh_attribute" name="reflectance"><string name="name" value="vertex_color"/>
      </texture></bsdf>
  </shape>
  <shape type="rectangle">
    <transform name="to_world"><rotate x="1" angle="90"/><translate y="1" z="1"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.8"/></bsdf>
  </shape>
</scene>"#
    );
    let path = dir.join("scene.xml");
    std::fs::write(&path, xml).unwrap();
    let desc = io::load_scene(&path, &[]).unwrap_or_else(|e| panic!("{e}"));
    Scene::from_description(&desc, None).unwrap_or_else(|e| panic!("{e}")).0
}

fn agrees_with_pt(scene: &Scene, algorithm: &str, iterations: u64) {
    let mut pt_settings = settings("pt", 1);
    pt_settings.max_length = 3;
    let pt = block_estimate(scene, &pt_settings, iterations, BLOCK);
    let mut other_settings = settings(algorithm, 2);
    other_settings.max_length = 3;
    let other = block_estimate(scene, &other_settings, iterations, BLOCK);
    let outcome = z_test_entries(&other.means, &other.std_errors, &pt.means, &pt.std_errors, ALPHA / 2.0);
    let keep = vec![true; other.means.len() / 3];
    let (om, oe) = other.pooled(&keep);
    let (pm, pe) = pt.pooled(&keep);
    let pooled = z_test_entries(&om, &oe, &pm, &pe, ALPHA / 2.0);
    let detectable = detectable_bias(&om, &oe, &pm, &pe, ALPHA / 2.0);
    eprintln!(
        "{algorithm} vs pt: blocks worst z {:.2}; pooled {om:.4?} vs {pm:.4?}, worst z {:.2}, detects {:.2} %",
        outcome.worst_z,
        pooled.worst_z,
        100.0 * detectable
    );
    assert!(pm.iter().all(|m| *m > 0.01), "the image is dark ({pm:?})");
    assert!(outcome.passed, "{algorithm} disagrees with pt on a block: {outcome:?}");
    assert!(pooled.passed, "{algorithm} disagrees with pt on the means: {om:?} vs {pm:?}");
    assert!(detectable < 0.03, "the test only detects a bias of {detectable}");
}

#[test]
fn bpt_and_vcm_agree_with_path_tracing_on_vertex_colours() {
    let scene = scene();
    agrees_with_pt(&scene, "bpt", 64);
    agrees_with_pt(&scene, "vcm", 64);
}
