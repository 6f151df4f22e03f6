//! Anisotropic roughness is oriented along ∂p/∂u: hits on anisotropic materials carry ∂p/∂u
//! (meshes from their uvs, spheres ∂p/∂φ, discs the radial direction), the BSDF's `alpha_u`
//! lies along it, and isotropic materials carry no tangent.

use math::{Ray, Vec2, Vec3};
use scene::microfacet::Distribution;
use scene::scene::SurfaceAttributes;
use scene::shape::Shape;
use scene::shape::{Disk, Sphere, Triangle};
use scene::{Bsdf, Camera, Material, Primitive, Scene, ShadingPoint, Texture, TransportMode};
use spectrum::Rgb;

fn conductor(distribution: Distribution, alpha_u: f32, alpha_v: f32) -> Material {
    Material::RoughConductor {
        distribution,
        alpha_u,
        alpha_v,
        eta: Rgb::new(0.2, 0.9, 1.1),
        k: Rgb::new(3.9, 2.4, 2.1),
        specular_reflectance: Texture::Constant(Rgb::WHITE),
    }
}

/// A point on the plane z = 0 with the given tangent.
fn point(tangent: Vec3) -> ShadingPoint {
    ShadingPoint { tangent, ..ShadingPoint::flat(Vec3::Z) }
}

/// `alpha_u` follows the tangent: (αu, αv) along x equals (αv, αu) along y, for both
/// distributions, values and both pdfs; a tangent with a normal component is projected.
#[test]
fn alpha_u_lies_along_the_tangent() {
    let fixed = Vec3::new(0.3, -0.5, 0.8).normalize();
    for kind in [Distribution::Ggx, Distribution::Beckmann] {
        let (a, b) = (conductor(kind, 0.4, 0.08), conductor(kind, 0.08, 0.4));
        let along_x = Bsdf::new(&a, &point(Vec3::X * 2.0 + Vec3::Z), fixed, TransportMode::Radiance).unwrap();
        let along_y = Bsdf::new(&b, &point(Vec3::Y), fixed, TransportMode::Radiance).unwrap();
        let swapped = Bsdf::new(&a, &point(Vec3::Y), fixed, TransportMode::Radiance).unwrap();
        let mut differs = false;
        for generated in [Vec3::new(-0.2, 0.6, 0.77), Vec3::new(-0.7, 0.1, 0.7), Vec3::new(0.1, 0.9, 0.42)] {
            let generated = generated.normalize();
            let (p, q) = (along_x.evaluate(generated).unwrap(), along_y.evaluate(generated).unwrap());
            let close = |x: f32, y: f32| (x - y).abs() <= 1e-4 * x.abs().max(y.abs());
            assert!(close(p.value.r, q.value.r), "{kind:?}: {} vs {}", p.value.r, q.value.r);
            assert!(close(p.pdf.forward.0, q.pdf.forward.0) && close(p.pdf.reverse.0, q.pdf.reverse.0));
            let s = swapped.evaluate(generated).unwrap();
            differs |= !close(p.value.r, s.value.r);
        }
        assert!(differs, "{kind:?}: the tangent's direction makes no difference");
    }
}

fn camera() -> Camera {
    Camera::new(Vec3::new(0.0, 0.0, 5.0), -Vec3::Z, Vec3::Y, 40.0, 8, 8)
}

fn hit(scene: &Scene, origin: Vec3, direction: Vec3) -> scene::SurfaceHit {
    scene.intersect(&Ray::new(origin, direction.normalize())).expect("the ray hits")
}

/// Hits report ∂p/∂u for anisotropic materials and zero for isotropic ones: a triangle whose
/// `u` runs along world `y`, a sphere (∂p/∂φ = (−y, x, 0)), a disc (radial).
#[test]
fn hits_on_anisotropic_materials_carry_dp_du() {
    let triangle = Triangle::new(Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, -1.0, 0.0), Vec3::new(-1.0, 1.0, 0.0));
    // u along +y, v along +x.
    let uvs = [Vec2::new(0.0, 0.0), Vec2::new(0.0, 1.0), Vec2::new(1.0, 0.0)];
    let mut primitives =
        vec![Primitive::new(Shape::Triangle(triangle), 0, None), Primitive::new(Shape::Triangle(triangle), 1, None)];
    for p in &mut primitives {
        p.attributes = 0;
    }
    let materials = vec![conductor(Distribution::Beckmann, 0.3, 0.1), conductor(Distribution::Beckmann, 0.2, 0.2)];
    let attributes = vec![SurfaceAttributes::Triangle { normals: None, uvs: Some(uvs), attribute: None }];
    let mesh = |i: usize| {
        Scene::new("t", vec![primitives[i]], materials.clone(), Vec::new(), camera())
            .with_attributes(attributes.clone())
    };
    let h = hit(&mesh(0), Vec3::new(-0.5, -0.5, 1.0), -Vec3::Z);
    assert!(h.tangent.normalize().dot(Vec3::Y) > 0.9999, "{:?}", h.tangent);
    assert_eq!(hit(&mesh(1), Vec3::new(-0.5, -0.5, 1.0), -Vec3::Z).tangent, Vec3::ZERO);

    let sphere = Sphere { center: Vec3::ZERO, radius: 1.0 };
    let scene =
        Scene::new("s", vec![Primitive::new(Shape::Sphere(sphere), 0, None)], materials.clone(), Vec::new(), camera());
    let h = hit(&scene, Vec3::new(3.0, 0.0, 0.2), -Vec3::X);
    assert!(h.tangent.normalize().dot(Vec3::Y) > 0.9999, "{:?}", h.tangent);

    let disk = Disk::new(Vec3::ZERO, Vec3::X, Vec3::Y, false).unwrap();
    let scene = Scene::new("d", vec![Primitive::new(Shape::Disk(disk), 0, None)], materials, Vec::new(), camera());
    let h = hit(&scene, Vec3::new(0.3, 0.4, 1.0), -Vec3::Z);
    assert!(h.tangent.normalize().dot(Vec3::new(0.6, 0.8, 0.0)) > 0.9999, "{:?}", h.tangent);
}

/// Hits on spheres and discs carry their uv parameterisation when the material reads uvs (a
/// checkerboard, or a normal map over a constant), and (0, 0) when it does not
/// (`MaterialFlags::reads_uv`: the parameterisation is then not computed).
#[test]
fn sphere_and_disc_hits_carry_uv_only_for_materials_that_read_it() {
    let checker = Material::Diffuse {
        reflectance: Texture::Checkerboard {
            color0: Rgb::WHITE,
            color1: Rgb::BLACK,
            to_uv: scene::desc::UvTransform::IDENTITY,
        },
    };
    let plain = Material::Diffuse { reflectance: Texture::Constant(Rgb::WHITE) };
    let mapped = Material::NormalMap {
        normals: Texture::Constant(Rgb::new(0.5, 0.5, 1.0)),
        nested: Box::new(plain.clone()),
        options: scene::material::MapOptions::MITSUBA,
    };
    let materials = vec![checker, plain, mapped];
    let sphere = Sphere { center: Vec3::ZERO, radius: 1.0 };
    let disk = Disk::new(Vec3::ZERO, Vec3::X, Vec3::Y, false).unwrap();
    // A sphere hit at φ = 90°, z = 0.6 (u = 1/4, v = acos(0.6)/π); a disc hit at radius 0.5,
    // angle 0 (u = 0.5, v = 0).
    let sphere_origin = Vec3::new(0.0, 3.0, 0.6);
    let sphere_uv = Vec2::new(0.25, 0.6f32.acos() / std::f32::consts::PI);
    let disk_origin = Vec3::new(0.5, 0.0, 1.0);
    for (material, reads) in [(0, true), (1, false), (2, true)] {
        let scene = |shape| {
            Scene::new("u", vec![Primitive::new(shape, material, None)], materials.clone(), Vec::new(), camera())
        };
        assert_eq!(scene(Shape::Sphere(sphere)).material_flags(material).reads_uv, reads);
        let on_sphere = hit(&scene(Shape::Sphere(sphere)), sphere_origin, -Vec3::Y).uv;
        let on_disk = hit(&scene(Shape::Disk(disk)), disk_origin, -Vec3::Z).uv;
        if reads {
            assert!((on_sphere - sphere_uv).length() < 1e-5, "material {material}: sphere uv {on_sphere}");
            assert!((on_disk - Vec2::new(0.5, 0.0)).length() < 1e-5, "material {material}: disc uv {on_disk}");
        } else {
            assert_eq!((on_sphere, on_disk), (Vec2::ZERO, Vec2::ZERO), "material {material}");
        }
    }
}

/// The scene's per-material table of purely specular materials (the VCM camera pass reads it
/// at every hit) answers as `Material::is_specular_only` for each material, and false beyond.
#[test]
fn the_specular_only_table_follows_the_materials() {
    let glass = Material::Dielectric {
        int_ior: 1.5,
        ext_ior: 1.0,
        specular_reflectance: Texture::Constant(Rgb::WHITE),
        specular_transmittance: Texture::Constant(Rgb::WHITE),
        dispersion: None,
    };
    let materials = vec![
        Material::Diffuse { reflectance: Texture::Constant(Rgb::WHITE) },
        Material::perfect_mirror(),
        glass,
        conductor(Distribution::Ggx, 0.2, 0.2),
    ];
    let sphere = Sphere { center: Vec3::ZERO, radius: 1.0 };
    let scene = Scene::new("m", vec![Primitive::new(Shape::Sphere(sphere), 0, None)], materials, Vec::new(), camera());
    let expected = [false, true, true, false];
    for (index, material) in scene.materials.iter().enumerate() {
        assert_eq!(material.is_specular_only(), expected[index], "material {index}");
        assert_eq!(scene.material_flags(index as u32).specular_only, expected[index], "table entry {index}");
    }
    assert_eq!(scene.material_flags(4), scene::MaterialFlags::UNKNOWN);
}
