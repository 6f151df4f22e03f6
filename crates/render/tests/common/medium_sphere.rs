//! The test scene of the media tests: a unit sphere of one medium with an index-matched
//! boundary under a uniform environment of radiance 1, seen along +z.

use math::Vec3;
use scene::Scene;
use scene::desc::{CameraDesc, FilmDesc, FilterDesc, Geometry, LightDesc, Projection, SceneDescription, ShapeDesc};
use scene::material::Material;
use scene::medium::{MediaDesc, Medium, MediumInterface};
use scene::texture::Texture;
use spectrum::Rgb;

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
    let camera = view.inside.then_some(0);
    let mut media = MediaDesc { media: vec![medium], null_materials: vec![0], camera, ..Default::default() };
    media.shapes.insert(0, MediumInterface { interior: Some(0), exterior: None });
    let desc = SceneDescription {
        name: "medium sphere".into(),
        camera: CameraDesc {
            position: view.position,
            forward: Vec3::Z,
            up: Vec3::Y,
            right: Vec3::X,
            projection: Projection::Perspective { horizontal_fov_degrees: view.fov_degrees },
        },
        film: FilmDesc { width: view.resolution, height: view.resolution, filter: FilterDesc::Box },
        materials: vec![
            Material::Diffuse { reflectance: Texture::Constant(Rgb::BLACK) },
            Material::ThinDielectric {
                int_ior: 1.5,
                ext_ior: 1.0,
                specular_reflectance: Texture::Constant(Rgb::WHITE),
                specular_transmittance: Texture::Constant(Rgb::WHITE),
            },
        ],
        shapes: [(1.0, 0), (1.2, 1)]
            .into_iter()
            .take(if shell { 2 } else { 1 })
            .map(|(radius, material)| ShapeDesc {
                name: "sphere".into(),
                geometry: Geometry::Sphere { center: Vec3::ZERO, radius, flip_normals: false },
                material,
                emission: None,
                alpha: None,
            })
            .collect(),
        lights: vec![LightDesc::Constant { radiance: Rgb::splat(1.0) }],
        max_path_length: None,
        warnings: Vec::new(),
        emission_spectra: Default::default(),
        objects: Vec::new(),
        instances: Vec::new(),
        media,
    };
    Scene::from_description(&desc, None).unwrap().0
}
