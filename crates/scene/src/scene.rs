//! The scene container: primitives with their materials and emitters, the lights, the camera,
//! the bounding sphere and the BVH, with the two ray queries every integrator uses.

use math::{Aabb, RAY_EPSILON, Ray, Vec2, Vec3};

use crate::accel::Bvh;
use crate::camera::Camera;
use crate::light::{BoundingSphere, Light};
use crate::material::{Material, ShadingPoint};
use crate::shape::Shape;

/// A shape with the index of its material and, if it emits, of its light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Primitive {
    /// Geometry.
    pub shape: Shape,
    /// Index into [`Scene::materials`].
    pub material: u32,
    /// Index into [`Scene::lights`] when the primitive is an area emitter.
    pub light: Option<u32>,
}

/// A ray–surface intersection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceHit {
    /// Hit point.
    pub position: Vec3,
    /// Unit geometric normal (as stored: triangles by winding, spheres outward).
    pub normal: Vec3,
    /// Unit shading normal (interpolated vertex normals; the geometric normal otherwise).
    pub shading_normal: Vec3,
    /// Texture coordinates.
    pub uv: Vec2,
    /// Distance along the ray from its origin.
    pub distance: f32,
    /// Index of the primitive hit.
    pub primitive: u32,
    /// Material index.
    pub material: u32,
    /// Light index when the primitive emits.
    pub light: Option<u32>,
}

impl SurfaceHit {
    /// The local geometry a BSDF is built from.
    #[inline]
    pub fn shading_point(&self) -> ShadingPoint {
        ShadingPoint { geometric_normal: self.normal, shading_normal: self.shading_normal, uv: self.uv }
    }
}

/// A complete scene ready to render.
#[derive(Debug)]
pub struct Scene {
    /// Human-readable name.
    pub name: String,
    /// Geometry, in scene order (the order only matters for exact ties).
    pub primitives: Vec<Primitive>,
    /// Materials referenced by the primitives.
    pub materials: Vec<Material>,
    /// Lights, in selection order.
    pub lights: Vec<Light>,
    /// The camera.
    pub camera: Camera,
    /// Bounding sphere of all primitives (spheres count as their bounding cubes).
    pub bounding_sphere: BoundingSphere,
    /// Index of the environment light, seen by rays that leave the scene.
    pub background: Option<u32>,
    bvh: Bvh,
}

impl Scene {
    /// Builds the BVH and the bounding sphere. Light indices of primitives must be valid.
    pub fn new(
        name: impl Into<String>,
        primitives: Vec<Primitive>,
        materials: Vec<Material>,
        lights: Vec<Light>,
        camera: Camera,
    ) -> Self {
        let bounds: Vec<Aabb> = primitives.iter().map(|p| p.shape.bounds()).collect();
        let scene_box = bounds.iter().fold(Aabb::EMPTY, |a, b| a.union(*b));
        let (center, radius) = if scene_box.is_empty() { (Vec3::ZERO, 1.0) } else { scene_box.bounding_sphere() };
        let background = lights.iter().position(Light::is_environment).map(|i| i as u32);
        let bvh = Bvh::build(&bounds);
        Self {
            name: name.into(),
            primitives,
            materials,
            lights,
            camera,
            bounding_sphere: BoundingSphere { center, radius },
            background,
            bvh,
        }
    }

    /// Nearest intersection of `ray` (any distance > 0).
    #[inline]
    pub fn intersect(&self, ray: &Ray) -> Option<SurfaceHit> {
        let (index, distance) = self
            .bvh
            .closest_hit(ray, f32::INFINITY, |i, r, t_max| self.primitives[i as usize].shape.intersect(r, t_max))?;
        let primitive = &self.primitives[index as usize];
        let position = ray.at(distance);
        let normal = primitive.shape.normal_at(position);
        Some(SurfaceHit {
            position,
            normal,
            shading_normal: normal,
            uv: Vec2::ZERO,
            distance,
            primitive: index,
            material: primitive.material,
            light: primitive.light,
        })
    }

    /// True when something blocks the segment from `point` along unit `direction` over the
    /// open interval `(ε, distance − ε)`, ε = [`RAY_EPSILON`]. `distance` may be infinite.
    #[inline]
    pub fn occluded(&self, point: Vec3, direction: Vec3, distance: f32) -> bool {
        let ray = Ray::new(point + RAY_EPSILON * direction, direction);
        let t_max = distance - 2.0 * RAY_EPSILON;
        if t_max <= 0.0 {
            return false;
        }
        self.bvh.any_hit(&ray, t_max, |i, r, t| self.primitives[i as usize].shape.intersect(r, t).is_some())
    }

    /// Picks a light uniformly with `u ∈ [0,1)`: its index, the light, and the probability.
    pub fn pick_light(&self, u: f32) -> Option<(u32, &Light, f32)> {
        if self.lights.is_empty() {
            return None;
        }
        let n = self.lights.len();
        let index = ((u * n as f32) as usize).min(n - 1);
        Some((index as u32, &self.lights[index], 1.0 / n as f32))
    }

    /// Probability with which [`Scene::pick_light`] picks any given light.
    pub fn light_pick_probability(&self) -> f32 {
        if self.lights.is_empty() { 0.0 } else { 1.0 / self.lights.len() as f32 }
    }

    /// The environment light, if any.
    pub fn background_light(&self) -> Option<&Light> {
        self.background.map(|i| &self.lights[i as usize])
    }

    /// The material of a hit.
    pub fn material(&self, hit: &SurfaceHit) -> &Material {
        &self.materials[hit.material as usize]
    }
}
