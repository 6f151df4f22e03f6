//! The path tracer with the light tree ([`LightSampler::Tree`]) against the path tracer with
//! the scene-global selection ([`LightSampler::Power`]) on a floor and a wall lit by a
//! rectangle and a sphere emitter, a spot and a point light (path length 3: direct light,
//! one bounce, and MIS between next-event estimation and BSDF hits on the area emitters).
//! Per 8 × 8 block and on the pooled means (Z-test, family-wise α = 1e-3); and a tree whose
//! probability is wrong in the MIS weight of BSDF hits only (×0.5) must fail the same test.
//! The same comparison with a scattering medium sphere on the floor exercises the volumetric
//! path tracer (medium vertices pick lights with no normal).

use crate::common;

use std::path::PathBuf;

use common::detectable_bias;
use math::{Rng, Vec2};
use render::path_tracer::{LightSampler, PathTracer};
use scene::Scene;
use testkit::{MeanVar, z_test_entries};

const ALPHA: f64 = 1e-3;
const RESOLUTION: u32 = 32;
const BLOCK: u32 = 8;
const SPP: u64 = 512;

/// The lit floor and wall, with `extra` shapes added; written to `name`.xml.
fn scene(name: &str, extra: &str) -> Scene {
    let xml = format!(
        r#"<scene version="3.0.0">
  <sensor type="perspective">
    <float name="fov" value="60"/>
    <transform name="to_world"><lookat origin="0, 3, 0.01" target="0, 0, 0" up="0, 0, 1"/></transform>
    <film type="hdrfilm"><integer name="width" value="{RESOLUTION}"/><integer name="height" value="{RESOLUTION}"/>
      <rfilter type="box"/></film>
  </sensor>
  <bsdf type="diffuse" id="white"><rgb name="reflectance" value="0.7"/></bsdf>
  <shape type="rectangle"><transform name="to_world"><scale value="2"/><rotate x="1" angle="-90"/></transform>
    <ref id="white"/></shape>
  <shape type="rectangle"><transform name="to_world"><scale value="2"/><rotate y="1" angle="180"/>
    <translate z="1.5"/></transform><ref id="white"/></shape>
  <shape type="rectangle">
    <transform name="to_world"><scale value="0.3"/><rotate x="1" angle="90"/><translate x="-1" y="0.6"/></transform>
    <emitter type="area"><rgb name="radiance" value="3, 2, 1"/></emitter></shape>
  <shape type="sphere"><point name="center" x="1" y="0.4" z="-0.8"/><float name="radius" value="0.15"/>
    <emitter type="area"><rgb name="radiance" value="1, 2, 4"/></emitter></shape>
  <emitter type="spot"><rgb name="intensity" value="6"/><float name="cutoff_angle" value="25"/>
    <float name="beam_width" value="15"/>
    <transform name="to_world"><lookat origin="0.8, 2, 0.6" target="0.8, 0, 0.6" up="0, 0, 1"/></transform></emitter>
  <emitter type="point"><point name="position" x="-1" y="1.5" z="1"/><rgb name="intensity" value="0.8"/></emitter>
  {extra}
</scene>"#
    );
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("light_tree");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!("{name}.xml"));
    std::fs::write(&path, xml).unwrap();
    let desc = io::load_scene(&path, &[]).unwrap_or_else(|e| panic!("{e}"));
    Scene::from_description(&desc, None).unwrap_or_else(|e| panic!("{e}")).0
}

/// Per-block and channel means and standard errors, `SPP` independent samples a pixel.
fn blocks(scene: &Scene, tracer: PathTracer, seed: u64) -> (Vec<f64>, Vec<f64>) {
    let camera = &scene.camera;
    let bw = camera.width / BLOCK;
    let mut stats = vec![MeanVar::new(); (bw * (camera.height / BLOCK) * 3) as usize];
    for y in 0..camera.height {
        for x in 0..camera.width {
            let b = ((y / BLOCK) * bw + x / BLOCK) as usize;
            for s in 0..SPP {
                let mut rng = Rng::for_stream(seed, s, (y * camera.width + x) as u64);
                let raster = Vec2::new(x as f32 + rng.uniform(), y as f32 + rng.uniform());
                let v = tracer.radiance(scene, camera.generate_ray(raster), &mut rng);
                for (c, value) in v.to_array().into_iter().enumerate() {
                    stats[b * 3 + c].push(f64::from(value));
                }
            }
        }
    }
    (stats.iter().map(MeanVar::mean).collect(), stats.iter().map(MeanVar::std_error).collect())
}

fn tracer(light_sampler: LightSampler, mis_pick_scale: f32) -> PathTracer {
    PathTracer { light_sampler, mis_pick_scale, ..PathTracer::new(3) }
}

/// Pooled (all blocks) mean per channel with its standard error.
fn pooled(means: &[f64], errors: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let n = (means.len() / 3) as f64;
    let m = (0..3).map(|c| means.iter().skip(c).step_by(3).sum::<f64>() / n).collect();
    let e = (0..3).map(|c| errors.iter().skip(c).step_by(3).map(|e| e * e).sum::<f64>().sqrt() / n).collect();
    (m, e)
}

#[test]
fn tree_and_power_selection_agree_and_a_wrong_mis_probability_is_detected() {
    let scene = scene("lights", "");
    let (pm, pe) = blocks(&scene, tracer(LightSampler::Power, 1.0), 1);
    let (tm, te) = blocks(&scene, tracer(LightSampler::Tree, 1.0), 2);
    let per_block = z_test_entries(&tm, &te, &pm, &pe, ALPHA / 2.0);
    let (tpm, tpe) = pooled(&tm, &te);
    let (ppm, ppe) = pooled(&pm, &pe);
    let means = z_test_entries(&tpm, &tpe, &ppm, &ppe, ALPHA / 2.0);
    let detectable = detectable_bias(&tpm, &tpe, &ppm, &ppe, ALPHA / 2.0);
    // The tree's standard errors against the power selection's, at equal samples.
    let ratio = te.iter().zip(&pe).map(|(t, p)| (t / p).powi(2)).sum::<f64>() / te.len() as f64;
    eprintln!(
        "tree {tpm:.4?} vs power {ppm:.4?}: blocks worst z {:.2}, means worst z {:.2}, detects {:.2} %, variance ratio {ratio:.3}",
        per_block.worst_z,
        means.worst_z,
        100.0 * detectable
    );
    assert!(ppm.iter().all(|m| *m > 0.05), "the scene is dark: {ppm:?}");
    assert!(per_block.passed, "tree and power disagree on a block: {per_block}");
    assert!(means.passed, "tree and power disagree on the means: {tpm:?} vs {ppm:?}");
    assert!(detectable < 0.02, "the pooled test only detects a bias of {detectable}");

    let (wm, we) = blocks(&scene, tracer(LightSampler::Tree, 0.5), 3);
    let wrong_blocks = z_test_entries(&wm, &we, &pm, &pe, ALPHA / 2.0);
    let (wpm, wpe) = pooled(&wm, &we);
    let wrong_means = z_test_entries(&wpm, &wpe, &ppm, &ppe, ALPHA / 2.0);
    eprintln!(
        "wrong MIS probability: blocks worst z {:.2}, means worst z {:.2}",
        wrong_blocks.worst_z, wrong_means.worst_z
    );
    assert!(!wrong_blocks.passed || !wrong_means.passed, "a pick probability ×0.5 in the MIS weight passes");
}

#[test]
fn tree_and_power_selection_agree_through_a_medium() {
    let medium = r#"<medium id="fog" type="homogeneous"><rgb name="sigma_t" value="3, 3, 3"/>
    <rgb name="albedo" value="0.9, 0.8, 0.7"/><phase type="isotropic"/></medium>
  <shape type="sphere"><point name="center" x="0.3" y="0.5" z="0.2"/><float name="radius" value="0.5"/>
    <bsdf type="null"/><ref id="fog" name="interior"/></shape>"#;
    let scene = scene("medium", medium);
    assert!(scene.media.is_active(), "the volumetric walk renders this scene");
    let (pm, pe) = blocks(&scene, tracer(LightSampler::Power, 1.0), 4);
    let (tm, te) = blocks(&scene, tracer(LightSampler::Tree, 1.0), 5);
    let per_block = z_test_entries(&tm, &te, &pm, &pe, ALPHA / 2.0);
    let (tpm, tpe) = pooled(&tm, &te);
    let (ppm, ppe) = pooled(&pm, &pe);
    let means = z_test_entries(&tpm, &tpe, &ppm, &ppe, ALPHA / 2.0);
    let detectable = detectable_bias(&tpm, &tpe, &ppm, &ppe, ALPHA / 2.0);
    eprintln!(
        "medium: tree {tpm:.4?} vs power {ppm:.4?}: blocks worst z {:.2}, means worst z {:.2}, detects {:.2} %",
        per_block.worst_z,
        means.worst_z,
        100.0 * detectable
    );
    assert!(per_block.passed, "tree and power disagree on a block: {per_block}");
    assert!(means.passed, "tree and power disagree on the means: {tpm:?} vs {ppm:?}");
    assert!(detectable < 0.02, "the pooled test only detects a bias of {detectable}");
    let (wm, we) = blocks(&scene, tracer(LightSampler::Tree, 0.5), 6);
    let wrong_blocks = z_test_entries(&wm, &we, &pm, &pe, ALPHA / 2.0);
    let (wpm, wpe) = pooled(&wm, &we);
    let wrong_means = z_test_entries(&wpm, &wpe, &ppm, &ppe, ALPHA / 2.0);
    assert!(!wrong_blocks.passed || !wrong_means.passed, "a pick probability ×0.5 in the MIS weight passes");
}
