//! Alpha masks through the whole renderer (Mitsuba scenes of our own, 32 × 32 pixels, 8 × 8
//! pixel blocks, Z-tests with a Šidák correction at family-wise significance 10⁻³):
//!
//! 1. A plane whose opacity is 0 on its left half and 1 on its right half, in front of a
//!    textured emitter and lit from the front by a point light: with each of pt, lt, bpt and
//!    vcm, the blocks seen through the holes equal its image of the scene without the plane,
//!    and the opaque blocks its image of the scene with an unmasked plane.
//! 2. A point light above a Lambertian floor, behind a fully transparent (α = 0) occluder that
//!    also covers the camera: every block equals the closed form `ρ/π · I cos θ / d²`
//!    integrated over its pixels (camera rays, shadow rays and light paths pass the occluder).
//! 3. The same with a black occluder of opacity ½ between the light and a camera below it: the
//!    image is half the unoccluded one, and the pooled tests of pt and BPT would detect a 2 %
//!    bias (light tracing, with few useful light paths here, only a larger one).

use crate::common;

use std::path::PathBuf;

use common::{block_estimate, detectable_bias, settings};
use math::Vec2;
use scene::Scene;
use testkit::z_test_entries;

/// Family-wise significance of every comparison.
const ALPHA: f64 = 1e-3;
/// Image side (pixels) and block side.
const RESOLUTION: u32 = 32;
const BLOCK: u32 = 8;

/// Loads a Mitsuba scene of `body` with a 32 × 32 box-filtered camera at `origin` looking at
/// `target` (up +y) with a horizontal field of view of `fov` degrees.
fn load(name: &str, origin: &str, target: &str, fov: f32, body: &str) -> Scene {
    let xml = format!(
        r#"<scene version="3.0.0">
  <sensor type="perspective">
    <float name="fov" value="{fov}"/>
    <transform name="to_world"><lookat origin="{origin}" target="{target}" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="{RESOLUTION}"/><integer name="height" value="{RESOLUTION}"/>
      <rfilter type="box"/></film>
  </sensor>
  {body}
</scene>"#
    );
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("alpha_masks");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!("{name}.xml"));
    std::fs::write(&path, xml).unwrap();
    let desc = io::load_scene(&path, &[]).unwrap_or_else(|e| panic!("{e}"));
    Scene::from_description(&desc, None).unwrap_or_else(|e| panic!("{e}")).0
}

/// A 3 × 3 plane at z = 0 facing +z: two-sided diffuse, wrapped in a mask of opacity 0 for
/// x < 0 and 1 for x > 0 when `masked`.
fn half_plane(masked: bool) -> String {
    let diffuse =
        r#"<bsdf type="twosided"><bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.5, 0.4"/></bsdf></bsdf>"#;
    let bsdf = if masked {
        format!(
            r#"<bsdf type="mask"><texture type="checkerboard" name="opacity"><rgb name="color0" value="0, 0, 0"/>
        <rgb name="color1" value="1, 1, 1"/><transform name="to_uv"><scale x="1" y="0.001"/></transform></texture>
        {diffuse}</bsdf>"#
        )
    } else {
        diffuse.to_string()
    };
    format!(r#"<shape type="rectangle"><transform name="to_world"><scale value="1.5"/></transform>{bsdf}</shape>"#)
}

/// Scene 1: a black textured emitter (6 × 6 at z = −1, facing the camera at z = 3), a point
/// light in front, and `plane`.
fn plane_scene(name: &str, plane: &str) -> Scene {
    let body = format!(
        r#"<shape type="rectangle"><transform name="to_world"><scale value="3"/><translate z="-1"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>
    <emitter type="area"><texture type="checkerboard" name="radiance"><rgb name="color0" value="1.0, 0.6, 0.3"/>
      <rgb name="color1" value="0.2, 0.5, 1.0"/><transform name="to_uv"><scale x="3" y="3"/></transform></texture></emitter>
  </shape>
  <emitter type="point"><point name="position" x="0.4" y="0.3" z="2"/><rgb name="intensity" value="3"/></emitter>
  {plane}"#
    );
    load(name, "0, 0, 3", "0, 0, 0", 40.0, &body)
}

/// Which side of x = 0 the camera sees every block of `scene` on, in the plane z = 0: `Some(true)`
/// left (the holes), `Some(false)` right, `None` for blocks that straddle the boundary.
fn block_sides(scene: &Scene) -> Vec<Option<bool>> {
    let blocks = RESOLUTION / BLOCK;
    let mut sides = Vec::new();
    for by in 0..blocks {
        for bx in 0..blocks {
            // The centres of the block's corner pixels.
            let corners = [(0, 0), (1, 0), (0, 1), (1, 1)].map(|(i, j)| {
                let at = |b: u32, k: u32| (b * BLOCK + k * (BLOCK - 1)) as f32 + 0.5;
                let raster = Vec2::new(at(bx, i), at(by, j));
                let ray = scene.camera.generate_ray(raster);
                let t = -ray.origin.z / ray.direction.z;
                ray.at(t).x < 0.0
            });
            sides.push(if corners.iter().all(|&c| c) {
                Some(true)
            } else if corners.iter().all(|&c| !c) {
                Some(false)
            } else {
                None
            });
        }
    }
    sides
}

/// The entries (block × channel) of `values` for the blocks that `keep` selects.
fn select(values: &[f64], keep: &[bool]) -> Vec<f64> {
    values.chunks(3).zip(keep).filter(|(_, k)| **k).flat_map(|(v, _)| v.to_vec()).collect()
}

#[test]
fn a_half_masked_plane_shows_the_emitter_through_its_holes_with_every_algorithm() {
    let masked = plane_scene("masked", &half_plane(true));
    let without = plane_scene("without", "");
    let opaque = plane_scene("opaque", &half_plane(false));
    let sides = block_sides(&masked);
    let holes: Vec<bool> = sides.iter().map(|s| *s == Some(true)).collect();
    let solid: Vec<bool> = sides.iter().map(|s| *s == Some(false)).collect();
    assert_eq!((holes.iter().filter(|h| **h).count(), solid.iter().filter(|s| **s).count()), (8, 8));
    let iterations = 48;
    for algorithm in ["pt", "lt", "bpt", "vcm"] {
        let render = |scene: &Scene, seed: u64| {
            let mut s = settings(algorithm, seed);
            s.max_length = 3;
            block_estimate(scene, &s, iterations, BLOCK)
        };
        let estimate = render(&masked, 3);
        let (without, opaque) = (render(&without, 11), render(&opaque, 12));
        for (what, keep, truth) in [("holes", &holes, &without), ("opaque half", &solid, &opaque)] {
            let (m, e) = (select(&estimate.means, keep), select(&estimate.std_errors, keep));
            let (tm, te) = (select(&truth.means, keep), select(&truth.std_errors, keep));
            let outcome = z_test_entries(&m, &e, &tm, &te, ALPHA / 8.0);
            let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
            eprintln!(
                "{algorithm}, {what}: mean {:.4} vs {:.4} (unmasked scene), worst z {:.2} over {} entries",
                mean(&m),
                mean(&tm),
                outcome.worst_z,
                m.len()
            );
            // Light tracing does not render directly visible emitters: its holes are black
            // in both scenes.
            if algorithm != "lt" || what != "holes" {
                assert!(mean(&tm) > 0.02, "{algorithm}, {what}: the reference is dark");
            }
            assert!(outcome.passed, "{algorithm}, {what}: {outcome:?}");
        }
    }
}

/// Scene 2 and 3: a Lambertian floor (ρ = [`RHO`], 8 × 8 at z = 0), a point light of intensity
/// [`INTENSITY`] at [`LIGHT_HEIGHT`], and a 6 × 6 occluder at `occluder_z` of opacity
/// `opacity` and reflectance 0, seen by a camera at `camera_z` (60° field of view).
fn occluder_scene(name: &str, opacity: f32, occluder_z: f32, camera_z: f32) -> Scene {
    let body = format!(
        r#"<shape type="rectangle"><transform name="to_world"><scale value="4"/></transform>
    <bsdf type="diffuse"><rgb name="reflectance" value="{RHO}"/></bsdf></shape>
  <shape type="rectangle"><transform name="to_world"><scale value="3"/><translate z="{occluder_z}"/></transform>
    <bsdf type="mask"><float name="opacity" value="{opacity}"/>
      <bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf></bsdf></shape>
  <emitter type="point"><point name="position" x="0" y="0" z="{LIGHT_HEIGHT}"/><rgb name="intensity" value="{INTENSITY}"/></emitter>"#
    );
    load(name, &format!("0.1, 0.05, {camera_z}"), "0.1, 0.05, 0", 60.0, &body)
}

const RHO: f32 = 0.5;
const INTENSITY: f32 = 4.0;
const LIGHT_HEIGHT: f32 = 2.0;

/// The unoccluded image's block means: `ρ/π · I · cos θ / d²` on the floor (θ at the floor,
/// d the distance to the light), averaged over a 16 × 16 grid in every pixel (the box filter).
fn analytic_blocks(scene: &Scene) -> Vec<f64> {
    let blocks = (RESOLUTION / BLOCK) as usize;
    let mut sums = vec![0.0f64; blocks * blocks];
    let n = 16;
    for y in 0..RESOLUTION {
        for x in 0..RESOLUTION {
            for i in 0..n {
                for j in 0..n {
                    let raster =
                        Vec2::new(x as f32 + (i as f32 + 0.5) / n as f32, y as f32 + (j as f32 + 0.5) / n as f32);
                    let ray = scene.camera.generate_ray(raster);
                    let p = ray.at(-ray.origin.z / ray.direction.z);
                    let (dx, dy, dz) = (-p.x as f64, -p.y as f64, LIGHT_HEIGHT as f64 - p.z as f64);
                    let d2 = dx * dx + dy * dy + dz * dz;
                    let cos = dz / d2.sqrt();
                    let radiance = RHO as f64 / std::f64::consts::PI * INTENSITY as f64 * cos / d2;
                    sums[(y / BLOCK) as usize * blocks + (x / BLOCK) as usize] += radiance;
                }
            }
        }
    }
    let per_block = (BLOCK * BLOCK) as f64 * (n * n) as f64;
    sums.iter().flat_map(|s| [s / per_block; 3]).collect()
}

/// `algorithm`'s block means of `scene` against `truth` (exact), per block and pooled; returns
/// the smallest relative bias the pooled test detects.
fn against_truth(scene: &Scene, what: &str, algorithm: &str, iterations: u64, truth: &[f64]) -> f64 {
    let mut s = settings(algorithm, 5);
    s.max_length = 2;
    let estimate = block_estimate(scene, &s, iterations, BLOCK);
    let zeros = vec![0.0; truth.len()];
    let blocks = estimate.means.len();
    let outcome = z_test_entries(&estimate.means, &estimate.std_errors, truth, &zeros, ALPHA / 2.0);
    let keep = vec![true; blocks / 3];
    let (m, e) = estimate.pooled(&keep);
    let pooled_truth = [0, 1, 2].map(|c| truth.iter().skip(c).step_by(3).sum::<f64>() / (blocks / 3) as f64);
    let pooled = z_test_entries(&m, &e, &pooled_truth, &[0.0; 3], ALPHA / 2.0);
    let detectable = detectable_bias(&m, &e, &pooled_truth, &[0.0; 3], ALPHA / 2.0);
    eprintln!(
        "{what}, {algorithm}: blocks worst z {:.2}; pooled {:.4} vs {:.4}, z {:.2}, detects {:.2} %",
        outcome.worst_z,
        m[0],
        pooled_truth[0],
        pooled.worst_z,
        100.0 * detectable
    );
    assert!(outcome.passed, "{what}, {algorithm}: a block disagrees with the closed form: {outcome:?}");
    assert!(pooled.passed, "{what}, {algorithm}: the mean disagrees with the closed form: {m:?} vs {pooled_truth:?}");
    detectable
}

#[test]
fn a_fully_transparent_occluder_leaves_the_analytic_irradiance() {
    // The occluder at z = 1 lies between the light (z = 2) and the floor, and between the
    // camera (z = 3) and the floor.
    let scene = occluder_scene("transparent", 0.0, 1.0, 3.0);
    let truth = analytic_blocks(&scene);
    // Light tracing wastes most light paths (the camera sees 1/10 of the light's solid
    // angle), so its test is the weakest.
    for (algorithm, max_detectable) in [("pt", 0.05), ("lt", 0.25), ("bpt", 0.05), ("vcm", 0.05)] {
        let detectable = against_truth(&scene, "α = 0", algorithm, 16, &truth);
        assert!(detectable < max_detectable, "{algorithm}: the test only detects a bias of {detectable}");
    }
}

#[test]
fn an_occluder_of_opacity_one_half_transmits_half() {
    // The occluder at z = 1.5 lies between the light and the floor; the camera at z = 1 is
    // below it. Expected: half the unoccluded image.
    let scene = occluder_scene("half", 0.5, 1.5, 1.0);
    let truth: Vec<f64> = analytic_blocks(&scene).iter().map(|v| 0.5 * v).collect();
    // A 2 % bias fails the path tracer's and BPT's pooled tests; light tracing (few useful
    // light paths, see above) is checked within its noise.
    for (algorithm, max_detectable) in [("pt", 0.02), ("bpt", 0.02), ("lt", 0.3)] {
        let detectable = against_truth(&scene, "α = ½", algorithm, 64, &truth);
        assert!(detectable < max_detectable, "{algorithm}: the test only detects a bias of {detectable}");
    }
}
