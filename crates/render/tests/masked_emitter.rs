//! A masked area emitter through the whole renderer. A 1 × 1 rectangle 1.5 above a diffuse
//! floor, facing down, with a Mitsuba `mask` whose opacity is a 2 × 2 checkerboard of 1 and 0,
//! must light the floor exactly like the two opaque quarters cut out as separate rectangles
//! (no mask: the unmasked code path is the independent truth). The masked scene is rendered
//! with pt (emitter hits by BSDF sampling and next-event estimation, MIS-combined), lt
//! (emission sampling only), bpt and vcm, and compared with pt on the cut-out scene block by
//! block (8 × 8 pixels, Šidák-corrected Z-test) and on the pooled channel means; the pooled
//! comparison detects a relative bias of a few percent (asserted). Which quarters are opaque
//! is read from the masked scene itself (rays cast up through each quarter).

use crate::common;

use std::path::PathBuf;

use common::{block_estimate, detectable_bias, settings};
use math::{Ray, Vec3};
use scene::Scene;
use testkit::z_test_entries;

/// Family-wise significance of every comparison.
const ALPHA: f64 = 1e-3;
const RESOLUTION: u32 = 32;
const BLOCK: u32 = 8;
const ITERATIONS: u64 = 256;

/// The floor (`[-2, 2]²` at `y = 0`, reflectance 0.7) seen from 1.2 above, and `emitters`.
fn floor_scene(name: &str, emitters: &str) -> Scene {
    let xml = format!(
        r#"<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="2"/></integrator>
  <sensor type="perspective">
    <float name="fov" value="60"/>
    <transform name="to_world"><lookat origin="0, 1.2, 0.01" target="0, 0, 0" up="0, 0, 1"/></transform>
    <film type="hdrfilm"><integer name="width" value="{RESOLUTION}"/><integer name="height" value="{RESOLUTION}"/>
      <rfilter type="box"/></film>
  </sensor>
  <shape type="rectangle">
    <transform name="to_world"><scale value="2"/><rotate x="1" angle="-90"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.7"/></bsdf>
  </shape>
  {emitters}
</scene>"#
    );
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("masked_emitter");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!("{name}.xml"));
    std::fs::write(&path, xml).unwrap();
    let desc = io::load_scene(&path, &[]).unwrap_or_else(|e| panic!("{e}"));
    Scene::from_description(&desc, None).unwrap_or_else(|e| panic!("{e}")).0
}

/// A downward-facing emitting rectangle of half side `half` centred at `(x, 1.5, z)`, with `bsdf`.
fn emitter(half: f32, x: f32, z: f32, bsdf: &str) -> String {
    format!(
        r#"<shape type="rectangle">
    <transform name="to_world"><scale value="{half}"/><rotate x="1" angle="90"/><translate x="{x}" y="1.5" z="{z}"/></transform>
    {bsdf}<emitter type="area"><rgb name="radiance" value="4.0, 2.0, 1.0"/></emitter></shape>"#
    )
}

fn compare(truth: &Scene, scene: &Scene, algorithm: &str) {
    let mut pt_settings = settings("pt", 1);
    pt_settings.max_length = 2;
    let reference = block_estimate(truth, &pt_settings, ITERATIONS, BLOCK);
    let mut other_settings = settings(algorithm, 2);
    other_settings.max_length = 2;
    let other = block_estimate(scene, &other_settings, ITERATIONS, BLOCK);
    let blocks = other.means.len();
    let outcome = z_test_entries(&other.means, &other.std_errors, &reference.means, &reference.std_errors, ALPHA / 2.0);
    let keep = vec![true; blocks / 3];
    let (om, oe) = other.pooled(&keep);
    let (pm, pe) = reference.pooled(&keep);
    let pooled = z_test_entries(&om, &oe, &pm, &pe, ALPHA / 2.0);
    let detectable = detectable_bias(&om, &oe, &pm, &pe, ALPHA / 2.0);
    eprintln!(
        "masked emitter, {algorithm} vs pt on the cut-out scene: blocks worst z {:.2}; pooled {om:.4?} vs {pm:.4?}, \
         worst z {:.2}, detects {:.2} %",
        outcome.worst_z,
        pooled.worst_z,
        100.0 * detectable
    );
    assert!(pm.iter().all(|m| *m > 0.01), "the floor is dark ({pm:?})");
    assert!(outcome.passed, "{algorithm} on the masked scene disagrees on a block: {outcome:?}");
    assert!(pooled.passed, "{algorithm} on the masked scene disagrees on the means: {om:?} vs {pm:?}");
    assert!(detectable < 0.03, "the test only detects a bias of {detectable}");
}

#[test]
fn a_masked_emitter_renders_like_its_opaque_parts_with_every_algorithm() {
    let mask = r#"<bsdf type="mask"><texture type="checkerboard" name="opacity">
      <rgb name="color0" value="1"/><rgb name="color1" value="0"/></texture><bsdf type="diffuse"/></bsdf>"#;
    let masked = floor_scene("masked", &emitter(0.5, 0.0, 0.0, mask));
    // The opaque quarters, seen from below.
    let mut quarters = String::new();
    let mut opaque = 0;
    for (x, z) in [(-0.25f32, -0.25f32), (0.25, -0.25), (-0.25, 0.25), (0.25, 0.25)] {
        let hit = masked.intersect(&Ray::new(Vec3::new(x, 0.5, z), Vec3::Y));
        if hit.is_some_and(|h| (h.distance - 1.0).abs() < 1e-4) {
            quarters += &emitter(0.25, x, z, r#"<bsdf type="diffuse"/>"#);
            opaque += 1;
        }
    }
    assert_eq!(opaque, 2, "a 2 × 2 checkerboard has two opaque quarters");
    let cut_out = floor_scene("cut-out", &quarters);
    for algorithm in ["pt", "lt", "bpt", "vcm"] {
        compare(&cut_out, &masked, algorithm);
    }
}
