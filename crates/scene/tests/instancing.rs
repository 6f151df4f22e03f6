//! The two-level BVH against brute force: a scene of instanced objects (a triangle soup under
//! general affine maps, mirrors and non-uniform scales included, and a sphere under
//! similarities) is intersected by random rays through `Scene::intersect` and
//! `Scene::occluded`, and every answer is checked against the flattened world geometry
//! intersected one primitive at a time in double precision.

use glam::{Affine3A, Quat};
use math::{Ray, Rng, Vec3};
use scene::Scene;
use scene::desc::{
    CameraDesc, FilmDesc, FilterDesc, Geometry, InstanceDesc, MeshData, ObjectDesc, Projection, SceneDescription,
    ShapeDesc,
};
use scene::material::Material;
use scene::texture::Texture;
use spectrum::Rgb;

fn random_vec(rng: &mut Rng, scale: f32) -> Vec3 {
    Vec3::new(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5) * 2.0 * scale
}

fn random_direction(rng: &mut Rng) -> Vec3 {
    loop {
        let v = random_vec(rng, 1.0);
        if v.length_squared() > 1e-3 && v.length_squared() <= 1.0 {
            return v.normalize();
        }
    }
}

/// Triangles with vertices in the unit cube.
fn soup(rng: &mut Rng, triangles: usize) -> MeshData {
    let mut mesh = MeshData::default();
    for t in 0..triangles {
        let center = random_vec(rng, 0.8);
        for _ in 0..3 {
            mesh.positions.push(center + random_vec(rng, 0.2));
        }
        let i = 3 * t as u32;
        mesh.triangles.push([i, i + 1, i + 2]);
    }
    mesh
}

fn shape(name: &str, geometry: Geometry) -> ShapeDesc {
    ShapeDesc { name: name.into(), geometry, material: 0, emission: None, alpha: None }
}

/// A world-space primitive of the flattened scene.
enum Flat {
    Triangle([Vec3; 3], f32),
    Sphere(Vec3, f32),
}

/// Nearest hit of the flattened scene in double precision: distance, unit normal (triangles:
/// the world winding's normal times the sign of the instance's determinant, i.e. the normal
/// the object-space normal maps to; spheres: outward).
fn brute_force(flat: &[Flat], ray: &Ray) -> Option<(f64, Vec3)> {
    let o = ray.origin.as_dvec3();
    let d = ray.direction.as_dvec3();
    let mut best: Option<(f64, Vec3)> = None;
    for primitive in flat {
        let hit = match primitive {
            Flat::Triangle([a, b, c], sign) => {
                let (a, b, c) = (a.as_dvec3(), b.as_dvec3(), c.as_dvec3());
                let (e1, e2) = (b - a, c - a);
                let p = d.cross(e2);
                let det = e1.dot(p);
                if det.abs() < 1e-14 {
                    continue;
                }
                let s = o - a;
                let u = s.dot(p) / det;
                let q = s.cross(e1);
                let v = d.dot(q) / det;
                let t = e2.dot(q) / det;
                if u < 0.0 || v < 0.0 || u + v > 1.0 || t <= 0.0 {
                    continue;
                }
                (t, (e1.cross(e2).normalize() * f64::from(*sign)).as_vec3())
            }
            Flat::Sphere(center, radius) => {
                let oc = o - center.as_dvec3();
                let b = oc.dot(d);
                let disc = b * b - (oc.dot(oc) - f64::from(*radius).powi(2));
                if disc < 0.0 {
                    continue;
                }
                let (t0, t1) = (-b - disc.sqrt(), -b + disc.sqrt());
                let t = if t0 > 0.0 { t0 } else { t1 };
                if t <= 0.0 {
                    continue;
                }
                (t, (o + t * d - center.as_dvec3()).normalize().as_vec3())
            }
        };
        if best.is_none_or(|(t, _)| hit.0 < t) {
            best = Some(hit);
        }
    }
    best
}

#[test]
fn instanced_scene_matches_brute_force_over_the_flattened_geometry() {
    let mut rng = Rng::for_stream(42, 0, 0);
    let mesh = soup(&mut rng, 60);
    let mut instances = Vec::new();
    let mut flat = Vec::new();
    let mut offsets = Vec::new();
    for i in 0..24 {
        let rotation = Quat::from_axis_angle(random_direction(&mut rng), 6.0 * rng.uniform());
        let offset = random_vec(&mut rng, 6.0);
        offsets.push(offset);
        let (object, to_world) = if i % 3 == 2 {
            // The sphere, under a similarity.
            let to_world =
                Affine3A::from_scale_rotation_translation(Vec3::splat(0.5 + rng.uniform()), rotation, offset);
            let scale = to_world.transform_vector3(Vec3::X).length();
            flat.push(Flat::Sphere(to_world.transform_point3(Vec3::new(0.2, 0.0, 0.0)), 0.7 * scale));
            (1, to_world)
        } else {
            // The soup, stretched, every fourth one mirrored.
            let mut scale = Vec3::new(0.5, 0.5, 0.5) + Vec3::new(rng.uniform(), 2.0 * rng.uniform(), rng.uniform());
            if i % 4 == 0 {
                scale.x = -scale.x;
            }
            let to_world = Affine3A::from_scale_rotation_translation(scale, rotation, offset);
            let sign = to_world.matrix3.determinant().signum();
            for t in &mesh.triangles {
                let corners = t.map(|v| to_world.transform_point3(mesh.positions[v as usize]));
                flat.push(Flat::Triangle(corners, sign));
            }
            (0, to_world)
        };
        instances.push(InstanceDesc { name: format!("instance {i}"), object, to_world });
    }
    let objects = vec![
        ObjectDesc { name: "soup".into(), shapes: vec![shape("soup", Geometry::Mesh(mesh))] },
        ObjectDesc {
            name: "ball".into(),
            shapes: vec![shape(
                "ball",
                Geometry::Sphere { center: Vec3::new(0.2, 0.0, 0.0), radius: 0.7, flip_normals: false },
            )],
        },
    ];
    let desc = SceneDescription {
        name: "instances".into(),
        camera: CameraDesc {
            position: Vec3::new(0.0, 0.0, 20.0),
            forward: -Vec3::Z,
            up: Vec3::Y,
            right: Vec3::X,
            projection: Projection::Perspective { horizontal_fov_degrees: 40.0 },
        },
        film: FilmDesc { width: 4, height: 4, filter: FilterDesc::Box },
        materials: vec![Material::Diffuse { reflectance: Texture::Constant(Rgb::splat(0.5)) }],
        shapes: Vec::new(),
        lights: Vec::new(),
        max_path_length: None,
        warnings: Vec::new(),
        emission_spectra: Default::default(),
        objects,
        instances,
        media: Default::default(),
    };
    let (scene, report) = Scene::from_description(&desc, None).unwrap();
    // The soup's 60 triangles are stored once, not once per instance.
    assert_eq!((report.triangles, report.analytic_shapes), (60, 1));
    assert_eq!((scene.objects.len(), scene.instances.len()), (2, 24));

    // Rays from around the scene towards random points near the instances. A ray may legitimately
    // disagree where it grazes an edge (the BVH intersects in f32 in object space); with 60·16
    // triangles of edge length ~0.3 and 4000 rays, a handful of grazing rays is the most to
    // expect, so at most 0.2 % (8) disagreements are allowed, and none in distance or normal
    // where both hit the same surface.
    let rays = 4000;
    let mut disagreements = 0;
    let mut hits = 0;
    for _ in 0..rays {
        let origin = random_vec(&mut rng, 12.0);
        let target =
            offsets[(rng.uniform() * offsets.len() as f32) as usize % offsets.len()] + random_vec(&mut rng, 1.0);
        let ray = Ray::new(origin, (target - origin).normalize());
        let expected = brute_force(&flat, &ray);
        let found = scene.intersect(&ray);
        match (expected, found) {
            (None, None) => {}
            (Some((t, normal)), Some(hit)) => {
                hits += 1;
                let relative = (f64::from(hit.distance) - t).abs() / t;
                if relative > 1e-4 {
                    disagreements += 1;
                    continue;
                }
                assert!(hit.normal.dot(normal) > 0.9999, "normal {} vs {normal}", hit.normal);
                assert!((hit.position - ray.at(t as f32)).length() < 1e-3 * t as f32);
                // Nothing blocks the segment up to just before the hit; the hit blocks beyond.
                assert!(!scene.occluded(ray.origin, ray.direction, 0.999 * t as f32));
                assert!(scene.occluded(ray.origin, ray.direction, 1.001 * t as f32 + 1e-3));
            }
            _ => disagreements += 1,
        }
    }
    eprintln!("{hits} hits, {disagreements} disagreements of {rays} rays");
    assert!(hits > rays / 4, "most rays must hit something: {hits}");
    assert!(disagreements <= rays / 500, "{disagreements} of {rays} rays disagree");
}

#[test]
fn instanced_emitters_are_refused() {
    let mut desc = SceneDescription {
        name: "lamp".into(),
        camera: CameraDesc {
            position: Vec3::new(0.0, 0.0, 5.0),
            forward: -Vec3::Z,
            up: Vec3::Y,
            right: Vec3::X,
            projection: Projection::Perspective { horizontal_fov_degrees: 40.0 },
        },
        film: FilmDesc { width: 4, height: 4, filter: FilterDesc::Box },
        materials: vec![Material::Diffuse { reflectance: Texture::Constant(Rgb::splat(0.5)) }],
        shapes: Vec::new(),
        lights: Vec::new(),
        max_path_length: None,
        warnings: Vec::new(),
        emission_spectra: Default::default(),
        objects: vec![ObjectDesc {
            name: "lamps".into(),
            shapes: vec![ShapeDesc {
                name: "bulb".into(),
                geometry: Geometry::Sphere { center: Vec3::ZERO, radius: 1.0, flip_normals: false },
                material: 0,
                emission: Some(Rgb::splat(1.0)),
                alpha: None,
            }],
        }],
        instances: vec![InstanceDesc { name: "i".into(), object: 0, to_world: Affine3A::IDENTITY }],
        media: Default::default(),
    };
    let error = Scene::from_description(&desc, None).err().unwrap();
    assert!(error.contains("bulb") && error.contains("lamps") && error.contains("emit"), "{error}");
    desc.objects[0].shapes[0].emission = None;
    desc.instances[0].object = 3;
    assert!(Scene::from_description(&desc, None).err().unwrap().contains("object 3"));
    desc.instances[0].object = 0;
    desc.instances[0].to_world = Affine3A::from_scale(Vec3::ZERO);
    assert!(Scene::from_description(&desc, None).err().unwrap().contains("singular"));
}
