//! The sphere rooms of the media tests: the inside of a sphere of radius 2 seen from
//! (0, 0, −1.5) along +z with a 60° field of view and a box filter, built from spheres.

use math::Vec3;
use scene::desc::{CameraDesc, FilmDesc, FilterDesc, Geometry, Projection, SceneDescription, ShapeDesc};
use scene::material::Material;
use scene::medium::MediaDesc;
use spectrum::Rgb;

/// An analytic sphere shape (outward normals), emitting `emission` (radiance) if given.
pub fn sphere(name: &str, center: Vec3, radius: f32, material: u32, emission: Option<Rgb>) -> ShapeDesc {
    ShapeDesc {
        name: name.into(),
        geometry: Geometry::Sphere { center, radius, flip_normals: false },
        material,
        emission,
        alpha: None,
    }
}

/// A perspective camera at `position` looking along +z (up +y), with a horizontal field of
/// view of `fov_degrees` degrees.
pub fn camera(position: Vec3, fov_degrees: f32) -> CameraDesc {
    CameraDesc {
        position,
        forward: Vec3::Z,
        up: Vec3::Y,
        right: Vec3::X,
        projection: Projection::Perspective { horizontal_fov_degrees: fov_degrees },
    }
}

/// A room description at `resolution`² pixels with the given materials, shapes and media, no
/// lights besides emitting shapes, seen by the room's [`camera`] (the struct-update syntax
/// changes the rest).
pub fn room(
    name: &str,
    resolution: u32,
    materials: Vec<Material>,
    shapes: Vec<ShapeDesc>,
    media: MediaDesc,
) -> SceneDescription {
    SceneDescription {
        name: name.into(),
        camera: camera(Vec3::new(0.0, 0.0, -1.5), 60.0),
        film: FilmDesc { width: resolution, height: resolution, filter: FilterDesc::Box },
        materials,
        shapes,
        lights: Vec::new(),
        max_path_length: None,
        warnings: Vec::new(),
        emission_spectra: Default::default(),
        objects: Vec::new(),
        instances: Vec::new(),
        media,
    }
}
