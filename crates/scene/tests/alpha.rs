//! Alpha masks at intersection level: a quad whose opacity texture is 0 on its left half
//! (x < 0) and 1 on its right half, as a world shape and as an instanced object, in front of an
//! opaque backstop. Rays through the left half pass to the backstop (closest hit) and are not
//! occluded by the quad (any hit); rays through the right half stop at the quad. A constant
//! fractional opacity keeps a fraction α of the hits; masked emitting spheres and non-finite
//! opacities are build errors (masked emitting meshes: `tests/masked_emitter.rs`).

use glam::Affine3A;
use math::{Ray, Vec2, Vec3};
use scene::Scene;
use scene::desc::{
    CameraDesc, FilmDesc, FilterDesc, Geometry, InstanceDesc, MeshData, ObjectDesc, Projection, SceneDescription,
    ShapeDesc, UvTransform,
};
use scene::material::Material;
use scene::texture::Texture;
use spectrum::Rgb;

/// The square `[-1, 1]² × {z}` facing +z, with uv = ((x + 1)/2, (y + 1)/2).
fn quad(z: f32) -> Geometry {
    Geometry::Mesh(MeshData {
        positions: vec![
            Vec3::new(-1.0, -1.0, z),
            Vec3::new(1.0, -1.0, z),
            Vec3::new(1.0, 1.0, z),
            Vec3::new(-1.0, 1.0, z),
        ],
        normals: Vec::new(),
        uvs: vec![Vec2::new(0.0, 0.0), Vec2::new(1.0, 0.0), Vec2::new(1.0, 1.0), Vec2::new(0.0, 1.0)],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
        attributes: Vec::new(),
    })
}

/// Opacity 0 where u < ½, 1 where u > ½ (a checkerboard squashed along v).
fn half_mask() -> Texture {
    Texture::Checkerboard {
        color0: Rgb::BLACK,
        color1: Rgb::WHITE,
        to_uv: UvTransform { columns: [Vec2::new(1.0, 0.0), Vec2::ZERO], translation: Vec2::ZERO },
    }
}

fn shape(name: &str, geometry: Geometry, material: u32, alpha: Option<Texture>) -> ShapeDesc {
    ShapeDesc { name: name.into(), geometry, material, emission: None, alpha }
}

/// A backstop (material 1) at z = −1 and the shapes of `world`; `objects` instanced once each
/// with the identity.
fn description(world: Vec<ShapeDesc>, objects: Vec<ShapeDesc>) -> SceneDescription {
    let diffuse = |v: f32| Material::Diffuse { reflectance: Texture::Constant(Rgb::splat(v)) };
    let mut shapes = vec![shape("backstop", quad(-1.0), 1, None)];
    shapes.extend(world);
    let instances = (0..objects.len() as u32)
        .map(|i| InstanceDesc { name: format!("instance {i}"), object: i, to_world: Affine3A::IDENTITY })
        .collect();
    SceneDescription {
        name: "alpha".into(),
        camera: CameraDesc {
            position: Vec3::new(0.0, 0.0, 5.0),
            forward: -Vec3::Z,
            up: Vec3::Y,
            right: Vec3::X,
            projection: Projection::Perspective { horizontal_fov_degrees: 40.0 },
        },
        film: FilmDesc { width: 4, height: 4, filter: FilterDesc::Box },
        materials: vec![diffuse(0.5), diffuse(0.2)],
        shapes,
        lights: Vec::new(),
        max_path_length: Some(5),
        warnings: Vec::new(),
        emission_spectra: Default::default(),
        objects: objects
            .into_iter()
            .enumerate()
            .map(|(i, s)| ObjectDesc { name: format!("object {i}"), shapes: vec![s] })
            .collect(),
        instances,
        media: Default::default(),
    }
}

fn build(desc: &SceneDescription) -> Scene {
    Scene::from_description(desc, None).unwrap_or_else(|e| panic!("{e}")).0
}

/// Checks both halves of a half-masked quad at z = 0 in `scene`.
fn check_halves(scene: &Scene, what: &str) {
    for x in [-0.7f32, -0.2, 0.3, 0.8] {
        for y in [-0.6f32, 0.1, 0.7] {
            let origin = Vec3::new(x, y, 2.0);
            let hit = scene.intersect(&Ray::new(origin, -Vec3::Z)).unwrap();
            let blocked = scene.occluded(origin, -Vec3::Z, 2.5);
            if x < 0.0 {
                assert!((hit.distance - 3.0).abs() < 1e-4, "{what}: ({x}, {y}) should reach the backstop: {hit:?}");
                assert_eq!(hit.material, 1, "{what}");
                assert!(!blocked, "{what}: ({x}, {y}) the transparent half occludes");
            } else {
                assert!((hit.distance - 2.0).abs() < 1e-4, "{what}: ({x}, {y}) should stop at the quad: {hit:?}");
                assert_eq!(hit.material, 0, "{what}");
                assert!(blocked, "{what}: ({x}, {y}) the opaque half does not occlude");
            }
        }
    }
}

#[test]
fn transparent_texels_are_skipped_by_both_queries_in_world_and_instanced_shapes() {
    let world = build(&description(vec![shape("quad", quad(0.0), 0, Some(half_mask()))], Vec::new()));
    assert_eq!(world.alpha_masks.len(), 1);
    check_halves(&world, "world quad");
    let instanced = build(&description(Vec::new(), vec![shape("quad", quad(0.0), 0, Some(half_mask()))]));
    assert!(instanced.primitives.iter().all(|p| p.alpha.is_none()), "the backstop has no mask");
    check_halves(&instanced, "instanced quad");
    // An opacity of 1 everywhere is no mask at all.
    let opaque = build(&description(vec![shape("quad", quad(0.0), 0, Some(Texture::Constant(Rgb::WHITE)))], vec![]));
    assert!(opaque.alpha_masks.is_empty() && opaque.primitives.iter().all(|p| p.alpha.is_none()));
}

#[test]
fn a_fractional_opacity_keeps_that_fraction_of_the_hits() {
    // α = 0.3 on the quad: of 40 000 parallel rays on a grid, 30 % stop at it (5σ ≈ 1.2 %).
    let alpha = Some(Texture::Constant(Rgb::splat(0.3)));
    for (what, desc) in [
        ("world", description(vec![shape("quad", quad(0.0), 0, alpha.clone())], vec![])),
        ("instanced", description(vec![], vec![shape("quad", quad(0.0), 0, alpha.clone())])),
    ] {
        let scene = build(&desc);
        let n = 200;
        let (mut stopped, mut blocked) = (0usize, 0usize);
        for i in 0..n {
            for j in 0..n {
                let origin = Vec3::new(-0.99 + 1.98 * i as f32 / n as f32, -0.99 + 1.98 * j as f32 / n as f32, 2.0);
                let hit = scene.intersect(&Ray::new(origin, -Vec3::Z)).unwrap();
                stopped += (hit.material == 0) as usize;
                blocked += scene.occluded(origin, -Vec3::Z, 2.5) as usize;
            }
        }
        let total = (n * n) as f64;
        let sigma = (0.3f64 * 0.7 / total).sqrt();
        for (query, count) in [("closest hit", stopped), ("any hit", blocked)] {
            let fraction = count as f64 / total;
            assert!((fraction - 0.3).abs() < 5.0 * sigma, "{what} {query}: {fraction}");
        }
    }
}

#[test]
fn masked_emitters_and_bad_opacities_are_errors() {
    let ball = Geometry::Sphere { center: Vec3::ZERO, radius: 1.0, flip_normals: false };
    let mut emitter = shape("lamp", ball, 0, Some(half_mask()));
    emitter.emission = Some(Rgb::WHITE);
    let error = Scene::from_description(&description(vec![emitter], vec![]), None).unwrap_err();
    assert!(error.contains("lamp") && error.contains("alpha"), "{error}");
    let nan = shape("quad", quad(0.0), 0, Some(Texture::Constant(Rgb::splat(f32::NAN))));
    let error = Scene::from_description(&description(vec![nan], vec![]), None).unwrap_err();
    assert!(error.contains("quad") && error.contains("non-finite"), "{error}");
}
