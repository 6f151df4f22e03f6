//! The Embree backend (feature `embree`) against our BVH on Mitsuba's material-preview scene
//! (`shared/scenes/mitsuba/matpreview`, skipped with a message when absent): 100k random rays
//! from points in the scene's box give the same primitive and distance, and 100k segments
//! between such points the same `occluded` answer.
#![cfg(feature = "embree")]

use std::path::PathBuf;

use math::{Aabb, RAY_EPSILON, Ray, Rng, warp};
use scene::Scene;
use scene::accel::Bvh;

/// `shared/scenes/mitsuba` (`$VCM_SHARED/scenes/mitsuba` when set).
fn mitsuba_dir() -> PathBuf {
    match std::env::var_os("VCM_SHARED") {
        Some(shared) => PathBuf::from(shared).join("scenes/mitsuba"),
        None => PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/scenes/mitsuba"),
    }
}

#[test]
fn embree_matches_bvh_on_matpreview() {
    let path = mitsuba_dir().join("matpreview/matpreview.xml");
    if !path.exists() {
        eprintln!("SKIPPED: {} does not exist", path.display());
        return;
    }
    let desc = io::load_scene(&path, &[]).unwrap_or_else(|e| panic!("{e}"));
    let (scene, _) = Scene::from_description(&desc, Some((64, 48))).unwrap_or_else(|e| panic!("{e}"));
    if std::env::var("VCM_ACCEL").is_ok_and(|v| v == "bvh") {
        eprintln!("SKIPPED: VCM_ACCEL=bvh forces our BVH");
        return;
    }
    assert_eq!(scene.accel_backend(), "embree", "matpreview is triangles only and should use Embree");
    let bounds: Vec<Aabb> = scene.primitives.iter().map(|p| p.shape.bounds()).collect();
    let bvh = Bvh::build(&bounds);
    // Points in the box around the preview object (the floor plane is far larger).
    let object = scene
        .primitives
        .iter()
        .filter(|p| p.material != scene.primitives[0].material)
        .fold(Aabb::EMPTY, |b, p| b.union(p.shape.bounds()));
    let (center, radius) = object.bounding_sphere();
    let point = |rng: &mut Rng| center + 1.5 * radius * warp::uniform_sphere(rng.uniform2()) * rng.uniform().cbrt();
    let (mut closest_bad, mut shadow_bad, mut hits, mut blocked) = (0, 0, 0, 0);
    const RAYS: u64 = 100_000;
    for i in 0..RAYS {
        let mut rng = Rng::for_stream(21, 0, i);
        let ray = Ray::new(point(&mut rng), warp::uniform_sphere(rng.uniform2()));
        let ours = bvh.closest_hit(&ray, f32::INFINITY, |p, r, t| scene.primitives[p as usize].shape.intersect(r, t));
        let theirs = scene.intersect(&ray).map(|h| (h.primitive, h.distance));
        hits += ours.is_some() as usize;
        let same = match (ours, theirs) {
            (None, None) => true,
            (Some((pa, ta)), Some((pb, tb))) => {
                // Relative 1e-5 of the distance, or of the coordinates' magnitude for short hits
                // (a distance's rounding error is ε times the coordinates).
                let scale = ta.max(tb).max(ray.origin.abs().max_element()).max(ray.at(ta).abs().max_element());
                (ta - tb).abs() <= 1e-5 * scale
                    && (pa == pb || scene.primitives[pb as usize].shape.intersect(&ray, ta + 1e-5 * scale).is_some())
            }
            _ => false,
        };
        if !same && closest_bad < 5 {
            eprintln!("closest hits differ on {ray:?}: ours {ours:?}, Embree {theirs:?}");
        }
        closest_bad += !same as usize;
        let (a, b) = (point(&mut rng), point(&mut rng));
        let length = (b - a).length();
        let direction = (b - a) / length;
        // What Scene::occluded asks our BVH.
        let offset = Ray::new(a + RAY_EPSILON * direction, direction);
        let t_max = length - 2.0 * RAY_EPSILON;
        let ours = t_max > 0.0
            && bvh.any_hit(&offset, t_max, |p, r, t| scene.primitives[p as usize].shape.intersect(r, t).is_some());
        blocked += ours as usize;
        shadow_bad += (ours != scene.occluded(a, direction, length)) as usize;
    }
    eprintln!("matpreview: {hits} of {RAYS} rays hit, {blocked} of {RAYS} segments blocked");
    assert!(hits > RAYS as usize / 4 && blocked > RAYS as usize / 20, "too few hits to compare");
    assert_eq!(closest_bad, 0, "closest hits differ on {closest_bad} of {RAYS} rays");
    assert_eq!(shadow_bad, 0, "occluded differs on {shadow_bad} of {RAYS} segments");
}
