//! The test scene of the media tests: a unit sphere of one medium with an index-matched
//! boundary under a uniform environment of radiance 1, seen along +z.

use math::Vec3;
use scene::Scene;
use scene::desc::{LightDesc, SceneDescription};
use scene::material::Material;
use scene::medium::{MediaDesc, Medium, MediumInterface};
use scene::texture::Texture;
use spectrum::Rgb;

use super::sphere_room::{camera, room, sphere};

/// Where the camera of [`medium_sphere`] looks from and what it sees.
pub struct View {
    /// Camera position; the camera looks along +z.
    pub position: Vec3,
    /// Whether the camera sits inside the medium (then `position` must be inside the sphere).
    pub inside: bool,
    /// Horizontal field of view in degrees.
    pub fov_degrees: f32,
    /// Film width and height in pixels.
    pub resolution: u32,
}

/// The sphere of `medium` (radius 1 at the origin, a null boundary, vacuum outside) under a
/// constant environment of radiance 1; with `shell`, a lossless thin dielectric sphere of
/// radius 1.2 around it (vacuum between them).
pub fn medium_sphere(medium: Medium, view: View, shell: bool) -> Scene {
    let camera_medium = view.inside.then_some(0);
    let mut media =
        MediaDesc { media: vec![medium], null_materials: vec![0], camera: camera_medium, ..Default::default() };
    media.shapes.insert(0, MediumInterface { interior: Some(0), exterior: None });
    let materials = vec![
        Material::Diffuse { reflectance: Texture::Constant(Rgb::BLACK) },
        Material::ThinDielectric {
            int_ior: 1.5,
            ext_ior: 1.0,
            specular_reflectance: Texture::Constant(Rgb::WHITE),
            specular_transmittance: Texture::Constant(Rgb::WHITE),
        },
    ];
    let shapes = [(1.0, 0), (1.2, 1)]
        .into_iter()
        .take(if shell { 2 } else { 1 })
        .map(|(radius, material)| sphere("sphere", Vec3::ZERO, radius, material, None))
        .collect();
    let desc = SceneDescription {
        camera: camera(view.position, view.fov_degrees),
        lights: vec![LightDesc::Constant { radiance: Rgb::splat(1.0) }],
        ..room("medium sphere", view.resolution, materials, shapes, media)
    };
    Scene::from_description(&desc, None).unwrap().0
}
