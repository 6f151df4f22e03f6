//! The textured lights through the whole renderer: on small Mitsuba scenes of our own (a
//! diffuse floor lit by a textured spot, a projector, or a textured rectangle emitter; the
//! textures are checkerboards, so no image files are needed), light tracing and BPT agree with
//! the path tracer block by block (8 × 8 pixel blocks, per-block Z-test with a Šidák
//! correction) and on the pooled channel means, and the pooled test would detect a relative
//! bias of a few percent (asserted with [`common::detectable_bias`]). Light tracing starts
//! every path with the lights' emission samplers and the path tracer uses their direct
//! samplers, so the two agreeing checks one against the other. In spectral mode BPT renders
//! the textured rectangle like the RGB path tracer (textures upsampled per lookup).

use crate::common;

use std::path::PathBuf;

use common::{block_estimate, detectable_bias, settings};
use scene::Scene;
use testkit::z_test_entries;

/// Family-wise significance of every comparison.
const ALPHA: f64 = 1e-3;
/// Image side (pixels) and block side.
const RESOLUTION: u32 = 32;
const BLOCK: u32 = 8;

/// A diffuse floor (`[-2, 2]²` at `y = 0`, reflectance 0.7) seen from `height` above by a 60°
/// camera, with `lights` added; path length 2 (direct light).
fn floor_scene(name: &str, height: f32, lights: &str) -> Scene {
    let xml = format!(
        r#"<scene version="3.0.0">
  <integrator type="path"><integer name="max_depth" value="2"/></integrator>
  <sensor type="perspective">
    <float name="fov" value="60"/>
    <transform name="to_world"><lookat origin="0, {height}, 0.01" target="0, 0, 0" up="0, 0, 1"/></transform>
    <film type="hdrfilm"><integer name="width" value="{RESOLUTION}"/><integer name="height" value="{RESOLUTION}"/>
      <rfilter type="box"/></film>
  </sensor>
  <shape type="rectangle">
    <transform name="to_world"><scale value="2"/><rotate x="1" angle="-90"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0.7"/></bsdf>
  </shape>
  {lights}
</scene>"#
    );
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("textured_lights");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!("{name}.xml"));
    std::fs::write(&path, xml).unwrap();
    let desc = io::load_scene(&path, &[]).unwrap_or_else(|e| panic!("{e}"));
    Scene::from_description(&desc, None).unwrap_or_else(|e| panic!("{e}")).0
}

/// A checkerboard of `a` and `b` with `n × n` squares over uv ∈ [0, 1]².
fn checkerboard(name: &str, a: &str, b: &str, n: u32) -> String {
    format!(
        r#"<texture type="checkerboard" name="{name}"><rgb name="color0" value="{a}"/><rgb name="color1" value="{b}"/>
      <transform name="to_uv"><scale x="{h}" y="{h}"/></transform></texture>"#,
        h = n / 2
    )
}

/// `algorithm` against the path tracer on every block and on the pooled means; asserts that
/// the pooled comparison detects a relative bias of at most `max_detectable`.
fn agrees_with_pt(scene: &Scene, what: &str, algorithm: &str, iterations: u64, max_detectable: f64) {
    compare_with_pt(scene, what, algorithm, false, iterations, max_detectable);
}

/// [`agrees_with_pt`], the tested algorithm in spectral mode when `spectral` (the path tracer
/// stays in RGB mode: upsampled textures must give the RGB image in expectation).
fn compare_with_pt(scene: &Scene, what: &str, algorithm: &str, spectral: bool, iterations: u64, max_detectable: f64) {
    let mut pt_settings = settings("pt", 1);
    pt_settings.max_length = 2;
    let pt = block_estimate(scene, &pt_settings, iterations, BLOCK);
    let mut other_settings = settings(algorithm, 2);
    other_settings.max_length = 2;
    other_settings.spectral = spectral;
    let other = block_estimate(scene, &other_settings, iterations, BLOCK);
    let blocks = other.means.len();
    let outcome = z_test_entries(&other.means, &other.std_errors, &pt.means, &pt.std_errors, ALPHA / 2.0);
    let keep = vec![true; blocks / 3];
    let (om, oe) = other.pooled(&keep);
    let (pm, pe) = pt.pooled(&keep);
    let pooled = z_test_entries(&om, &oe, &pm, &pe, ALPHA / 2.0);
    let detectable = detectable_bias(&om, &oe, &pm, &pe, ALPHA / 2.0);
    eprintln!(
        "{what}, {algorithm} vs pt: blocks worst z {:.2}; pooled {om:.4?} vs {pm:.4?}, worst z {:.2}, detects {:.2} %",
        outcome.worst_z,
        pooled.worst_z,
        100.0 * detectable
    );
    assert!(pm.iter().all(|m| *m > 0.01), "{what}: the floor is dark ({pm:?})");
    assert!(outcome.passed, "{what}: {algorithm} disagrees with pt on a block: {outcome:?}");
    assert!(pooled.passed, "{what}: {algorithm} disagrees with pt on the means: {om:?} vs {pm:?}");
    assert!(detectable < max_detectable, "{what}: the test only detects a bias of {detectable}");
}

#[test]
fn textured_spot_light_tracing_and_bpt_agree_with_path_tracing() {
    let texture = checkerboard("texture", "1.0, 0.2, 0.1", "0.1, 0.5, 1.0", 4);
    let spot = format!(
        r#"<emitter type="spot"><rgb name="intensity" value="8"/><float name="cutoff_angle" value="30"/>
      <float name="beam_width" value="20"/>{texture}
      <transform name="to_world"><lookat origin="0.3, 2, 0" target="0, 0, 0.2" up="0, 0, 1"/></transform></emitter>"#
    );
    let scene = floor_scene("spot", 3.0, &spot);
    agrees_with_pt(&scene, "textured spot", "lt", 64, 0.03);
    agrees_with_pt(&scene, "textured spot", "bpt", 64, 0.03);
}

#[test]
fn projector_light_tracing_and_bpt_agree_with_path_tracing() {
    let irradiance = checkerboard("irradiance", "1.0, 0.2, 0.1", "0.05, 0.3, 1.0", 6);
    let projector = format!(
        r#"<emitter type="projector"><float name="scale" value="2"/><float name="fov" value="50"/>{irradiance}
      <transform name="to_world"><lookat origin="-0.4, 2, 0" target="0, 0, 0" up="0, 0, 1"/></transform></emitter>"#
    );
    let scene = floor_scene("projector", 3.0, &projector);
    agrees_with_pt(&scene, "projector", "lt", 64, 0.03);
    agrees_with_pt(&scene, "projector", "bpt", 64, 0.03);
}

#[test]
fn textured_area_emitter_light_tracing_bpt_and_vcm_agree_with_path_tracing() {
    // A 1 × 1 rectangle 1.5 above the floor, facing down, above the camera (at 1.2).
    let radiance = checkerboard("radiance", "1.0, 0.5, 0.2", "0.2, 0.6, 1.0", 4);
    let emitter = format!(
        r#"<shape type="rectangle">
      <transform name="to_world"><scale value="0.5"/><rotate x="1" angle="90"/><translate y="1.5"/></transform>
      <emitter type="area">{radiance}</emitter></shape>"#
    );
    let scene = floor_scene("area", 1.2, &emitter);
    agrees_with_pt(&scene, "textured rectangle", "lt", 256, 0.03);
    agrees_with_pt(&scene, "textured rectangle", "bpt", 256, 0.03);
    agrees_with_pt(&scene, "textured rectangle", "vcm", 256, 0.03);
    compare_with_pt(&scene, "textured rectangle, spectral", "bpt", true, 256, 0.03);
}
