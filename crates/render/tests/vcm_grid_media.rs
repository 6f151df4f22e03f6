//! The VCM engine's algorithms in heterogeneous (grid) media (`render::vcm::medium`: surrogate
//! majorant densities in the MIS, weighted delta tracking, ratio tracking in connections)
//! against the path tracer, whose grid-medium tracking is tested against closed forms in
//! `tests/heterogeneous.rs`.
//!
//! The scene is a closed fog room: the inside of a diffuse sphere of radius 2 filled with a
//! grid medium (a smooth blob of σ_t over the room's bounding box, with the majorant grid the
//! medium builds), a small emitting sphere and a diffuse ball inside, the camera in the fog.
//! Each algorithm's per-8×8-block means (and channels) are Z-tested against a longer pt render
//! (Šidák over the entries, α = 1e-3, standard errors from the spread of the per-iteration
//! frames), then the image means likewise, and the same data must be able to see a 4 % bias of
//! the image mean (`common::detectable_bias`): the power check.
//!
//! Two unit tests check the surrogate densities of a grid piece: `∫_0^ℓ D̂ + P̂(ℓ) = 1`, and the
//! sub-path walk and the connection segments evaluate the same products (the MIS consistency;
//! the per-block tests above are not sensitive enough to see every MIS inconsistency: `P̂`
//! instead of `D̂` at a connection's medium end passes them, and fails this one).

use crate::common;

use common::BlockEstimate;
use common::sphere_room::sphere;

use std::sync::{Arc, OnceLock};

use math::Vec3;
use render::RenderSettings;
use render::vcm::medium::grid_surrogate;
use scene::Scene;
use scene::instance::Affine3A;
use scene::material::Material;
use scene::medium::{
    Coefficient, Coefficients, Filter, Grid, Heterogeneous, MediaDesc, Medium, MediumInterface, Outside, PhaseFunction,
    Volume,
};
use scene::texture::Texture;
use spectrum::Rgb;
use testkit::z_test_entries;

/// The bias the image-mean comparison must be able to see.
const POWER: f64 = 0.04;

/// Grid resolution per axis.
const N: usize = 8;

/// A smooth blob of σ_t over `[−2, 2]³` on an `N³` grid: `0.15 + 1.2 e^{−|x − c|²/0.8}` around
/// `c = (0.3, 0.2, 0.4)` (0 for z < −1.25), per channel scaled by `tint` (one channel when `chromatic` is false,
/// the tint then being the volume's value; three channels, scaled per channel differently,
/// when true), albedo 0.85.
fn blob(chromatic: bool) -> Medium {
    let centre = Vec3::new(0.3, 0.2, 0.4);
    let mut values = Vec::new();
    for k in 0..N {
        for j in 0..N {
            for i in 0..N {
                let p = (Vec3::new(i as f32, j as f32, k as f32) + 0.5) / N as f32 * 4.0 - 2.0;
                let v = 0.15 + 1.2 * (-(p - centre).length_squared() / 0.8).exp();
                // No medium within 0.25 of the camera's plane z = −1.5 (voxel centres at z ≤ −1.25
                // are 0): light tracing's 1/d² near the camera keeps a finite variance.
                let v = if p.z < -1.0 { 0.0 } else { v };
                if chromatic {
                    // The channels peak at different places: red follows x, blue the opposite.
                    let s = 0.5 + 0.25 * p.x;
                    values.extend([v * (0.5 + s), v, v * (1.5 - s)]);
                } else {
                    values.push(v);
                }
            }
        }
    }
    let to_world = Affine3A::from_translation(Vec3::splat(-2.0)) * Affine3A::from_scale(Vec3::splat(4.0));
    let channels = if chromatic { 3 } else { 1 };
    let tint = if chromatic { Rgb::splat(1.0) } else { Rgb::new(0.6, 1.0, 1.4) };
    let sigma_t = Volume {
        grid: Some(Arc::new(Grid::new([N, N, N], channels, values).unwrap())),
        value: Coefficient::rgb(tint),
        to_local: to_world.inverse(),
        filter: Filter::Trilinear,
        outside: Outside::Clamp,
    };
    let albedo = Volume::constant(Coefficient::rgb(Rgb::splat(0.85)), Affine3A::IDENTITY);
    Medium {
        coefficients: Coefficients::Heterogeneous(Arc::new(Heterogeneous::new(
            sigma_t,
            albedo,
            None,
            to_world.inverse(),
        ))),
        scale: 1.0,
        phase: PhaseFunction::henyey_greenstein(0.3).unwrap(),
    }
}

/// The fog room (module doc) with `medium`, `resolution`² pixels; with `light_behind` the light
/// (radius 0.1 instead of 0.2, four times the radiance) sits behind the camera, out of view.
fn grid_room(medium: Medium, resolution: u32, light_behind: bool) -> Scene {
    let (light, light_radius, radiance) =
        if light_behind { (Vec3::new(0.3, 0.3, -1.75), 0.1, 80.0) } else { (Vec3::new(0.5, 0.8, 0.5), 0.2, 20.0) };
    let mut media = MediaDesc { media: vec![medium], camera: Some(0), ..Default::default() };
    media.shapes.insert(0, MediumInterface { interior: Some(0), exterior: None });
    let materials = vec![
        Material::Diffuse { reflectance: Texture::Constant(Rgb::splat(0.5)) },
        Material::Diffuse { reflectance: Texture::Constant(Rgb::new(0.7, 0.4, 0.3)) },
    ];
    let shapes = vec![
        sphere("room", Vec3::ZERO, 2.0, 0, None),
        sphere("light", light, light_radius, 0, Some(Rgb::splat(radiance))),
        sphere("ball", Vec3::new(-0.5, -0.7, 0.6), 0.4, 1, None),
    ];
    let desc = common::sphere_room::room("grid fog room", resolution, materials, shapes, media);
    Scene::from_description(&desc, None).unwrap().0
}

/// A block estimate of `algorithm` in `scene` (length limit 8).
fn estimate(
    scene: &Scene,
    algorithm: &str,
    spectral: bool,
    radius_factor: f32,
    iterations: u64,
    seed: u64,
) -> BlockEstimate {
    // One radius for the disc and the ball, as the factors were chosen.
    let settings = RenderSettings {
        max_length: 8,
        radius_factor,
        volume_radius_factor: radius_factor,
        spectral,
        ..common::settings(algorithm, seed)
    };
    common::block_estimate(scene, &settings, iterations, 8)
}

/// `got` (of `algorithm`) against the pt estimate `pt`, per 8×8 block and in the image mean,
/// with the power to see a [`POWER`] bias of the image mean (module doc).
fn matches_pt(algorithm: &str, got: &BlockEstimate, pt: &BlockEstimate) {
    let outcome = z_test_entries(&got.means, &got.std_errors, &pt.means, &pt.std_errors, 1e-3);
    eprintln!("grid room, {algorithm} vs pt per block: {outcome}");
    assert!(outcome.passed, "{algorithm}: {outcome}");
    let keep = vec![true; got.means.len() / 3];
    let ((gm, ge), (pm, pe)) = (got.pooled(&keep), pt.pooled(&keep));
    let detectable = common::detectable_bias(&gm, &ge, &pm, &pe, 1e-3);
    eprintln!("image means {algorithm} {gm:?} ± {ge:?}, pt {pm:?} ± {pe:?}; detects {:.2} %", 100.0 * detectable);
    assert!(z_test_entries(&gm, &ge, &pm, &pe, 1e-3).passed, "{algorithm}: image means differ");
    assert!(detectable < POWER, "{algorithm}: no power, detects only {:.2} %", 100.0 * detectable);
}

/// The pt reference of the chromatic grid room with the light in front (1000 iterations, seed 5),
/// rendered once for the three tests that compare against it (bpt and vcm, bpm, ppm): the same
/// estimate each of them rendered before, bit for bit (the image does not depend on the
/// thread count or on what else runs).
fn chromatic_pt() -> &'static BlockEstimate {
    static PT: OnceLock<BlockEstimate> = OnceLock::new();
    PT.get_or_init(|| estimate(&grid_room(blob(true), 32, false), "pt", false, 0.0, 1000, 5))
}

/// The merging radius factor (r_0 = factor × 2 × 16 ≈ 1 scene unit at 32², as in
/// `tests/vcm_media.rs`, so merges carry a large share of the image).
const VCM_RADIUS_FACTOR: f32 = 0.03;

/// RGB, chromatic three-channel grid: bpt and vcm against pt.
#[test]
fn bpt_vcm_match_pt_in_a_chromatic_grid_room() {
    let scene = grid_room(blob(true), 32, false);
    let pt = chromatic_pt();
    matches_pt("bpt", &estimate(&scene, "bpt", false, 0.003, 500, 6), pt);
    matches_pt("vcm", &estimate(&scene, "vcm", false, VCM_RADIUS_FACTOR, 800, 7), pt);
}

/// Light tracing alone (only the t = 1 connections through grid pieces, with ratio tracking,
/// and the light sub-paths' weighted delta tracking), with the light behind the camera (light
/// tracing cannot render an emitter seen directly).
#[test]
fn lt_matches_pt_in_a_chromatic_grid_room() {
    let scene = grid_room(blob(true), 32, true);
    let pt = estimate(&scene, "pt", false, 0.0, 1000, 5);
    matches_pt("lt", &estimate(&scene, "lt", false, 0.0, 4000, 6), &pt);
}

/// Spectral mode, a one-channel grid with a chromatic tint: bpt and vcm against pt. bpt at 1000
/// iterations detects a 1.93 % bias of the image mean (at 2000 it detected 1.49 %; the bound is
/// [`POWER`], 4 %).
#[test]
fn bpt_vcm_match_pt_in_a_tinted_grid_room_spectral() {
    let scene = grid_room(blob(false), 32, false);
    let pt = estimate(&scene, "pt", true, 0.0, 4000, 5);
    matches_pt("bpt", &estimate(&scene, "bpt", true, 0.003, 1000, 6), &pt);
    matches_pt("vcm", &estimate(&scene, "vcm", true, VCM_RADIUS_FACTOR, 800, 7), &pt);
}

/// `∫_0^ℓ D̂(t) dt + P̂(ℓ) = 1` for the surrogate densities of a grid piece crossing several
/// majorant-grid cells (midpoint rule, 200 000 steps; the piecewise-constant μ makes the error
/// of the rule far below the 1e-3 tolerance, which is above f32 round-off of the sum), and the
/// piece does cross cells with different majorants (else the test would be the homogeneous
/// one). The reverse density `near` integrated from the far end gives the same.
#[test]
fn surrogate_densities_integrate_to_one() {
    for chromatic in [false, true] {
        let medium = blob(chromatic);
        let h = medium.heterogeneous().unwrap();
        let origin = Vec3::new(-1.9, -1.3, -1.7);
        let direction = Vec3::new(1.0, 0.8, 0.9).normalize();
        let length = 1.5f32;
        let steps = 200_000;
        let dt = f64::from(length) / steps as f64;
        let (mut integral, mut reverse) = (0.0f64, 0.0f64);
        let mut majorants: Vec<f32> = Vec::new();
        for i in 0..steps {
            let t = ((i as f64 + 0.5) * dt) as f32;
            let forward = grid_surrogate(h, medium.scale, origin, direction, 0.0, t);
            integral += f64::from(forward.far) * dt;
            if forward.pass > 0.0 {
                let mu = forward.far / forward.pass;
                if !majorants.iter().any(|m| (m - mu).abs() < 1e-4) {
                    majorants.push(mu);
                }
            }
            let back = grid_surrogate(h, medium.scale, origin, direction, length - t, length);
            reverse += f64::from(back.near) * dt;
        }
        let pass = f64::from(grid_surrogate(h, medium.scale, origin, direction, 0.0, length).pass);
        eprintln!(
            "chromatic {chromatic}: ∫D̂ = {integral:.5}, reverse {reverse:.5}, P̂ = {pass:.5}, {} majorants",
            majorants.len()
        );
        assert!(majorants.len() >= 3, "the piece should cross cells with different majorants: {majorants:?}");
        assert!(pass > 0.01 && pass < 0.9, "P̂ = {pass}: the piece should be neither empty nor opaque");
        assert!((integral + pass - 1.0).abs() < 1e-3, "∫D̂ + P̂ = {}", integral + pass);
        assert!((reverse + pass - 1.0).abs() < 1e-3, "reverse ∫D̂ + P̂ = {}", reverse + pass);
    }
}

/// The sub-path walk (`advance`) and the connection segment (`segment`) evaluate the same
/// surrogate products for the same segment — what the MIS weights need to sum to 1: from a
/// medium vertex in the grid room, on 2000 random directions, the flight's forward and reverse
/// products up to where `advance` stopped (a medium vertex or the wall) equal `segment`'s
/// (relative 1e-5). Using `D̂` at the far end for the reverse flight, or `P̂` for a medium end
/// in `segment`, fails it.
#[test]
fn sub_path_flights_and_segments_agree_on_the_surrogates() {
    use math::{Ray, Rng};
    use render::vcm::medium::{Arrival, Flight, advance, segment};
    for chromatic in [false, true] {
        let scene = grid_room(blob(chromatic), 8, false);
        let (mut media_ends, mut surface_ends) = (0, 0);
        for i in 0..2000u64 {
            let mut rng = Rng::for_stream(3, 0, i);
            let origin = Vec3::new(0.4 * rng.uniform() - 0.2, 0.4 * rng.uniform() - 0.2, 0.4 * rng.uniform() - 0.2);
            let z = 2.0 * rng.uniform() - 1.0;
            let phi = std::f32::consts::TAU * rng.uniform();
            let r = (1.0 - z * z).max(0.0).sqrt();
            let direction = Vec3::new(r * phi.cos(), r * phi.sin(), z);
            let mut ray = Ray::new(origin, direction);
            let (mut offset, mut throughput) = (0.0f32, Rgb::splat(1.0));
            let mut flight = Flight::start(Some(0), true, 0.0);
            let arrival = advance::<Rgb>(&scene, &mut ray, &mut offset, &mut flight, &mut throughput, &mut rng, &());
            let (distance, to_medium) = match arrival {
                Arrival::Medium { distance, .. } => (distance, true),
                Arrival::Surface(hit) => (hit.distance, false),
                Arrival::Escaped => panic!("the room is closed"),
            };
            if to_medium {
                media_ends += 1
            } else {
                surface_ends += 1
            }
            let mut other = Rng::for_stream(4, 0, i);
            let Some(s) =
                segment::<Rgb>(&scene, origin, direction, distance, Some(0), true, to_medium, &(), &mut other)
            else {
                continue;
            };
            for (what, walk, connection) in
                [("forward", flight.forward, s.forward), ("reverse", flight.reverse, s.reverse)]
            {
                assert!(
                    (walk - connection).abs() <= 1e-5 * walk.abs().max(connection.abs()),
                    "{what}, chromatic {chromatic}, path {i} (medium end {to_medium}): walk {walk} vs segment {connection}"
                );
            }
        }
        eprintln!("chromatic {chromatic}: {media_ends} medium ends, {surface_ends} surface ends");
        assert!(media_ends > 200 && surface_ends > 200, "both kinds of ends: {media_ends}, {surface_ends}");
    }
}

/// bpm against pt (RGB, chromatic grid): merging (at medium vertices with the 3-D kernel and
/// σ_s at the camera vertex, `vcm::medium::sigma_s_at`) is its only technique besides purely
/// specular emitter hits; radius factor 0.02 as in `tests/vcm_media.rs`.
#[test]
fn bpm_matches_pt_in_a_chromatic_grid_room() {
    let scene = grid_room(blob(true), 32, false);
    let pt = chromatic_pt();
    matches_pt("bpm", &estimate(&scene, "bpm", false, 0.02, 3000, 8), pt);
}

/// ppm against pt (RGB, chromatic grid): camera paths merge at their first non-specular
/// vertex, here mostly medium vertices (3-D kernel, σ_s at the camera vertex); radius factor
/// 0.02 (r_0 ≈ 0.6), whose kernel bias stays below what the test sees in this smooth fog
/// (measured, not bounded).
#[test]
fn ppm_matches_pt_in_a_chromatic_grid_room() {
    let scene = grid_room(blob(true), 32, false);
    let pt = chromatic_pt();
    matches_pt("ppm", &estimate(&scene, "ppm", false, 0.02, 3000, 9), pt);
}
