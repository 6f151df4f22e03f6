//! [`Scene::intersect`] and [`Scene::occluded`] with triangle blocks, on a scene that mixes plain
//! triangles (blocks) with everything that goes through the scene's closure: spheres, discs,
//! alpha-masked triangles (fractional and zero opacity), hair fibres (back sides skipped) and
//! instances of an object with masked triangles. The answers must be brute force's over the
//! primitives' own tests, as the closure alone gave them before blocks: the nearest hit (distance
//! bit for bit, primitive, material; the smallest id of equally near ones) and the any-hit answer.

use glam::Affine3A;
use math::{Isa, RAY_EPSILON, Ray, Rng, Vec3};
use spectrum::Rgb;

use super::tests::{random_direction, random_soup, random_vec};
use crate::Camera;
use crate::alpha::AlphaMask;
use crate::instance::{Instance, Object};
use crate::material::{HairParameters, Material, ReferenceMaterial};
use crate::scene::{Primitive, Scene};
use crate::shape::{Disk, Shape, Sphere, Triangle};
use crate::texture::Texture;

/// Materials: 0 diffuse, 1 hair (a fibre).
const HAIR: u32 = 1;

fn triangle(t: &[Vec3; 3], material: u32, alpha: Option<u32>) -> Primitive {
    Primitive { alpha, ..Primitive::new(Shape::Triangle(Triangle::new(t[0], t[1], t[2])), material, None) }
}

/// World primitives of every kind, interleaved so that leaves mix them, and two instances.
fn mixed_scene(rng: &mut Rng) -> Scene {
    let mut primitives = Vec::new();
    for (i, t) in random_soup(rng, 2500, 1.5).iter().enumerate() {
        primitives.push(match i % 16 {
            0 => triangle(t, 0, Some(0)),
            1 => triangle(t, 0, Some(1)),
            2 => triangle(t, HAIR, None),
            3 => Primitive::new(Shape::Sphere(Sphere { center: t[0], radius: 0.1 + 0.3 * rng.uniform() }), 0, None),
            4 => {
                let disk = Disk::new(t[0], t[1] - t[0], t[2] - t[0], i % 32 == 4).expect("a disc");
                Primitive::new(Shape::Disk(disk), 0, None)
            }
            _ => triangle(t, 0, None),
        });
    }
    // Regions of plain triangles only, so that whole leaves are blocks.
    for t in random_soup(rng, 1500, 0.3) {
        primitives.push(triangle(&[t[0] * 0.4, t[1] * 0.4, t[2] * 0.4], 0, None));
    }
    // Coincident copies: ties between blocks and the closure.
    for i in 0..50 {
        let copy = primitives[i * 16 + 5];
        primitives.push(copy);
        primitives.push(Primitive { alpha: Some(0), ..copy });
    }
    let object_primitives: Vec<Primitive> = random_soup(rng, 300, 0.8)
        .iter()
        .enumerate()
        .map(|(i, t)| triangle(&[t[0] * 0.2, t[1] * 0.2, t[2] * 0.2], 0, (i % 3 == 0).then_some(0)))
        .collect();
    let object = Object::new("masked", object_primitives).expect("an object");
    let instances = [Vec3::new(1.0, 2.0, 0.5), Vec3::new(-2.0, 0.0, 1.0), Vec3::new(0.0, -3.0, -2.0)]
        .map(|at| Instance::new(0, Affine3A::from_scale_rotation_translation(Vec3::splat(3.0), Default::default(), at)))
        .map(|i| i.expect("an instance"));
    let materials = vec![
        Material::Reference(ReferenceMaterial::diffuse(Rgb::splat(0.5))),
        Material::Hair(HairParameters::default()),
    ];
    let camera = Camera::new(Vec3::new(0.0, 0.0, 20.0), -Vec3::Z, Vec3::Y, 40.0, 8, 8);
    Scene::with_instances("mixed", primitives, vec![object], instances.to_vec(), materials, Vec::new(), camera)
        .with_alpha_masks(vec![
            AlphaMask::new(Texture::Constant(Rgb::splat(0.5))),
            AlphaMask::new(Texture::Constant(Rgb::BLACK)),
        ])
}

/// Brute force: every world primitive, then every instance, in id order, a later one only when
/// strictly nearer. Returns the distance, the primitive (of the object for an instance), its
/// material and whether it is an instance's.
fn brute_intersect(scene: &Scene, ray: &Ray) -> Option<(f32, u32, u32, bool)> {
    let mut best = None;
    let mut t_best = f32::INFINITY;
    for (i, p) in scene.primitives.iter().enumerate() {
        if let Some(t) = p.shape.intersect(ray, t_best).filter(|&t| scene.alpha_keeps(p, ray, t)) {
            (t_best, best) = (t, Some((t, i as u32, p.material, false)));
        }
    }
    for instance in &scene.instances {
        let object = &scene.objects[instance.object as usize];
        let keep = |p: &Primitive, r: &Ray, t: f32| scene.alpha_keeps(p, r, t);
        if let Some((p, t)) = object.closest_hit(&instance.to_object_ray(ray), t_best, keep) {
            (t_best, best) = (t, Some((t, p, object.primitives[p as usize].material, true)));
        }
    }
    best
}

/// Brute force of [`Scene::occluded`].
fn brute_occluded(scene: &Scene, point: Vec3, direction: Vec3, distance: f32) -> bool {
    let ray = Ray::new(point + RAY_EPSILON * direction, direction);
    let t_max = distance - 2.0 * RAY_EPSILON;
    let keep = |p: &Primitive, r: &Ray, t: f32| scene.alpha_keeps(p, r, t);
    t_max > 0.0
        && (scene.primitives.iter().any(|p| p.shape.intersect(&ray, t_max).is_some_and(|t| keep(p, &ray, t)))
            || scene
                .instances
                .iter()
                .any(|i| scene.objects[i.object as usize].any_hit(&i.to_object_ray(&ray), t_max, keep)))
}

#[test]
fn scene_queries_with_blocks_match_brute_force() {
    let mut rng = Rng::for_stream(31, 0, 0);
    let scene = mixed_scene(&mut rng);
    let (mut hits, mut kinds, mut blocked) = (0, [0; 4], 0);
    for i in 0..4000 {
        // Axis-aligned directions (zero components) for some rays.
        let direction = if i % 7 == 0 { [Vec3::X, -Vec3::Y, Vec3::Z][i % 3] } else { random_direction(&mut rng) };
        let ray = Ray::new(random_vec(&mut rng, 14.0), direction);
        let expected = brute_intersect(&scene, &ray);
        let got = scene.intersect(&ray).map(|h| (h.distance, h.primitive, h.material));
        assert_eq!(
            expected.map(|(t, p, m, _)| (t.to_bits(), p, m)),
            got.map(|(t, p, m)| (t.to_bits(), p, m)),
            "{ray:?}: expected {expected:?}, got {got:?}"
        );
        if let Some((_, p, _, instance)) = expected {
            hits += 1;
            let p = &scene.primitives[p as usize];
            let kind = match (instance, &p.shape, p.alpha, p.material) {
                (true, ..) => 3,
                (false, Shape::Triangle(_), None, 0) => 0,
                (false, Shape::Triangle(_), ..) => 1,
                (false, ..) => 2,
            };
            kinds[kind] += 1;
        }
        let (point, target) = (random_vec(&mut rng, 14.0), random_vec(&mut rng, 14.0));
        let (direction, distance) = ((target - point).normalize(), (target - point).length());
        let expected = brute_occluded(&scene, point, direction, distance);
        assert_eq!(expected, scene.occluded(point, direction, distance), "{point:?} → {target:?}");
        blocked += expected as usize;
    }
    assert!(hits > 1000 && blocked > 500, "{hits} hits, {blocked} blocked");
    assert!(kinds.iter().all(|&k| k > 20), "hits by plain, masked or fibre triangle, analytic, instance: {kinds:?}");
}

/// Every instruction set's copy of [`Scene::intersect`] (`math::isa`) returns the baseline
/// copy's hit bit for bit (all fields, through their `Debug` text, which tells every distinct
/// float apart) on the mixed scene; where the processor lacks a set, its copy falls back to a
/// narrower one, so the comparison still runs.
#[test]
fn scene_intersect_is_the_same_with_every_instruction_set() {
    let mut rng = Rng::for_stream(32, 0, 0);
    let scene = mixed_scene(&mut rng);
    let mut hits = 0;
    for i in 0..4000 {
        let direction = if i % 7 == 0 { [Vec3::X, -Vec3::Y, Vec3::Z][i % 3] } else { random_direction(&mut rng) };
        let ray = Ray::new(random_vec(&mut rng, 14.0), direction);
        let baseline = format!("{:?}", scene.intersect_at(&ray, Isa::Baseline));
        for isa in [Isa::Avx2, Isa::Avx512] {
            assert_eq!(format!("{:?}", scene.intersect_at(&ray, isa)), baseline, "{ray:?} with {isa:?}");
        }
        assert_eq!(format!("{:?}", scene.intersect(&ray)), baseline, "{ray:?}");
        hits += baseline.starts_with("Some") as usize;
    }
    assert!(hits > 1000, "{hits} hits");
    eprintln!("instruction sets compared: baseline against {}", Isa::detected().name());
}
