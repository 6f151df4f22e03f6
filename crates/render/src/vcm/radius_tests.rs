//! Unit tests of the merging scale and the initial radius.

use super::*;
use crate::vcm::VcmAlgorithm;
use math::Vec3;
use scene::shape::{Shape, Triangle};
use scene::{Camera, Material, Primitive, ReferenceMaterial};
use spectrum::Rgb;

fn vcm_settings(mode: RadiusMode) -> VcmSettings {
    VcmSettings { radius_mode: mode, ..VcmSettings::new(VcmAlgorithm::VertexConnectionMerging) }
}

/// A diffuse square floor `[-half, half]²` at z = 0, no lights, seen by `camera`.
fn floor(half: f32, camera: Camera) -> Scene {
    let c = |x: f32, y: f32| Vec3::new(x * half, y * half, 0.0);
    let primitives = [[c(-1., -1.), c(1., -1.), c(1., 1.)], [c(-1., -1.), c(1., 1.), c(-1., 1.)]]
        .map(|[a, b, d]| Primitive::new(Shape::Triangle(Triangle::new(a, b, d)), 0, None))
        .to_vec();
    let material: Material = ReferenceMaterial::diffuse(Rgb::splat(0.5)).into();
    Scene::new("floor", primitives, vec![material], Vec::new(), camera)
}

/// A camera at height 1 above the origin looking straight down with a 90° field of view: it
/// sees the square `[-1, 1]²` of the floor.
fn looking_down(width: u32, height: u32) -> Camera {
    Camera::new(Vec3::Z, -Vec3::Z, Vec3::Y, 90.0, width, height)
}

#[test]
fn global_radius_keeps_the_expected_vertices_per_query_above_512_squared() {
    let radius = |w: u32, h: u32, mode| base_radius(&scene::cornell::build(0, w, h).unwrap(), &vcm_settings(mode));
    let unscaled = radius(64, 64, RadiusMode::Fixed);
    assert!(unscaled > 0.0);
    // Up to 512² pixels (and for the fixed mode everywhere) the scene-relative radius.
    for (w, h) in [(64, 64), (512, 512), (1024, 256)] {
        assert_eq!(radius(w, h, RadiusMode::Global), unscaled, "{w}x{h}");
    }
    for (w, h) in [(1024, 1024), (4096, 2048)] {
        assert_eq!(radius(w, h, RadiusMode::Fixed), unscaled);
    }
    // N_L r² constant: 4x the pixels, half the radius; 32x the pixels, 1/√32.
    assert!((radius(1024, 1024, RadiusMode::Global) / unscaled - 0.5).abs() < 1e-6);
    assert!((radius(4096, 2048, RadiusMode::Global) / unscaled - 32f32.sqrt().recip()).abs() < 1e-6);
}

#[test]
fn every_builtin_cornell_scene_keeps_the_scene_relative_radius_bit_for_bit() {
    for builtin in scene::cornell::builtin_scenes() {
        for (w, h) in [(512, 512), (256, 256), (640, 360), (1024, 1024)] {
            let scene = scene::cornell::build(builtin.mask, w, h).unwrap();
            let scale = MergingScale::of(&scene);
            // The rule before the merging scale, written out: factor × R_scene, resolution-scaled.
            let shrink = if w * h > 512 * 512 { (512.0 * 512.0 / (w * h) as f64).sqrt() as f32 } else { 1.0 };
            let old = 0.003 * scene.bounding_sphere.radius * shrink;
            assert_eq!(base_radius(&scene, &vcm_settings(RadiusMode::Global)).to_bits(), old.to_bits());
            // Far from the boundary of the rule: the camera sees most of the box.
            let s = scale.visible_radius.unwrap() / scale.scene_radius;
            assert!(s > 0.7, "{} {w}x{h}: s = {s}", builtin.name);
        }
    }
}

#[test]
fn a_huge_floor_seen_over_a_small_square_gets_the_radius_of_the_visible_square() {
    // A 2000 × 2000 floor (R_scene = 1000√2) of which the camera sees [-1, 1]² (R_vis = √2).
    let scene = floor(1000.0, looking_down(48, 48));
    let scale = MergingScale::of(&scene);
    assert!((scale.scene_radius - 1000.0 * 2f32.sqrt()).abs() < 1e-2, "{scale:?}");
    let visible = scale.visible_radius.unwrap();
    assert!((visible - 2f32.sqrt()).abs() < 1e-5, "{scale:?}");
    assert_eq!(scale.scale, visible);
    let radius = base_radius(&scene, &vcm_settings(RadiusMode::Global));
    assert_eq!(radius, 0.003 * visible);
    // The same camera over a floor it sees whole (the floor fills the middle 30 % of the view):
    // the scene-relative radius.
    let small = floor(0.3, looking_down(48, 48));
    assert_eq!(MergingScale::of(&small).scale, small.bounding_sphere.radius);
}

#[test]
fn a_camera_that_sees_nothing_keeps_the_scene_radius() {
    let away = Camera::new(Vec3::Z, Vec3::Z, Vec3::Y, 90.0, 16, 16);
    let scene = floor(1000.0, away);
    let scale = MergingScale::of(&scene);
    assert_eq!(scale.visible_radius, None);
    assert_eq!(scale.scale, scale.scene_radius);
}

#[test]
fn the_merging_scale_is_continuous_and_monotonic_in_the_visible_radius() {
    let scene_radius = 8.0f32;
    let at = |s: f32| merging_scale(scene_radius, Some(s * scene_radius)) / scene_radius;
    assert_eq!(at(0.01), 0.01);
    assert_eq!(at(0.25), 0.25);
    assert_eq!(at(0.5), 1.0);
    assert_eq!(at(0.9), 1.0);
    assert!((at(0.375) - 4.0 * 0.375 * 0.375).abs() < 1e-6);
    // Continuous at both joins and never decreasing.
    for join in [0.25f32, 0.5] {
        assert!((at(join - 1e-6) - at(join + 1e-6)).abs() < 1e-5, "join {join}");
    }
    let mut previous = 0.0;
    for k in 1..=1000 {
        let value = at(k as f32 / 1000.0);
        assert!(value >= previous, "s = {}", k as f32 / 1000.0);
        previous = value;
    }
    // Degenerate visible parts fall back to the scene radius.
    for visible in [None, Some(0.0), Some(f32::NAN), Some(f32::INFINITY)] {
        assert_eq!(merging_scale(scene_radius, visible), scene_radius);
    }
}
