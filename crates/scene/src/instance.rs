//! Instancing: geometry stored once in its own space ([`Object`], with its own bottom-level
//! BVH) and placed any number of times by affine transforms ([`Instance`]). The scene's
//! top-level BVH holds each instance as one leaf primitive with its world-space box; a ray
//! that reaches it is transformed into object space and traced through the object's BVH.
//!
//! The object-space ray keeps the world ray's parameter: its direction is the world direction
//! mapped by the inverse transform, not renormalised, so a hit at `t` in object space is at `t`
//! in world space and distances compare across instances. Every shape's intersection routine
//! accepts such non-unit directions. Normals go back to world space by the inverse transpose
//! of the linear part, renormalised, so they stay perpendicular to the transformed surface for
//! any invertible map (also non-uniform scales and mirrors).
//!
//! Memory grows with the unique geometry: an instance is a transform pair and an object index
//! ([`Instance::BYTES`]). This module does not own area lights: instanced shapes cannot emit.

use math::{Aabb, Ray, Vec3};

use crate::accel::Bvh;
use crate::scene::Primitive;

pub use glam::{Affine3A, Mat3};

/// Geometry in object space with its own BVH.
#[derive(Clone, Debug)]
pub struct Object {
    /// Name for messages.
    pub name: String,
    /// The primitives, in object space (no lights).
    pub primitives: Vec<Primitive>,
    bvh: Bvh,
}

impl Object {
    /// Builds the object's BVH. Errors when a primitive emits (instanced emitters are not
    /// supported, as in Mitsuba 3).
    pub fn new(name: impl Into<String>, primitives: Vec<Primitive>) -> Result<Self, String> {
        let name = name.into();
        if primitives.iter().any(|p| p.light.is_some()) {
            return Err(format!("object '{name}': an instanced shape cannot emit light"));
        }
        let bounds: Vec<Aabb> = primitives.iter().map(|p| p.shape.bounds()).collect();
        Ok(Self { name, bvh: Bvh::build(&bounds), primitives })
    }

    /// Bounding box in object space.
    pub fn bounds(&self) -> Aabb {
        self.bvh.bounds()
    }

    /// Nearest primitive hit along the object-space `ray` with parameter in `(0, t_max)` that
    /// `keep(primitive, ray, t)` accepts (the scene's alpha test): its index into
    /// [`Object::primitives`] and the parameter.
    #[inline]
    pub fn closest_hit(
        &self,
        ray: &Ray,
        t_max: f32,
        keep: impl Fn(&Primitive, &Ray, f32) -> bool,
    ) -> Option<(u32, f32)> {
        self.bvh.closest_hit(ray, t_max, |i, r, t_max| {
            let primitive = &self.primitives[i as usize];
            primitive.shape.intersect(r, t_max).filter(|&t| keep(primitive, r, t))
        })
    }

    /// Whether anything of the object that `keep(primitive, ray, t)` accepts lies along the
    /// object-space `ray` in `(0, t_max)`.
    #[inline]
    pub fn any_hit(&self, ray: &Ray, t_max: f32, keep: impl Fn(&Primitive, &Ray, f32) -> bool) -> bool {
        self.bvh.any_hit(ray, t_max, |i, r, t_max| {
            let primitive = &self.primitives[i as usize];
            primitive.shape.intersect(r, t_max).is_some_and(|t| keep(primitive, r, t))
        })
    }
}

/// One placement of an [`Object`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Instance {
    /// Index into [`crate::Scene::objects`].
    pub object: u32,
    /// Object space to world space.
    pub to_world: Affine3A,
    /// World space to object space (the inverse of `to_world`).
    pub to_object: Affine3A,
    /// Inverse transpose of `to_world`'s linear part: object-space normals to world space.
    pub normal_to_world: Mat3,
}

impl Instance {
    /// Bytes of one instance in memory.
    pub const BYTES: usize = std::mem::size_of::<Instance>();

    /// An instance of `object` placed by `to_world`; `None` when the transform is not finite or
    /// not invertible.
    pub fn new(object: u32, to_world: Affine3A) -> Option<Self> {
        let linear = Mat3::from(to_world.matrix3);
        let determinant = linear.determinant();
        if !(to_world.is_finite() && determinant.is_finite() && determinant != 0.0) {
            return None;
        }
        let to_object = to_world.inverse();
        if !to_object.is_finite() {
            return None;
        }
        Some(Self { object, to_world, to_object, normal_to_world: linear.inverse().transpose() })
    }

    /// `ray` in object space, with the same parameter (the direction is not renormalised).
    #[inline]
    pub fn to_object_ray(&self, ray: &Ray) -> Ray {
        Ray {
            origin: self.to_object.transform_point3(ray.origin),
            direction: self.to_object.transform_vector3(ray.direction),
        }
    }

    /// A unit object-space normal as a unit world-space normal.
    #[inline]
    pub fn normal_to_world(&self, normal: Vec3) -> Vec3 {
        (self.normal_to_world * normal).normalize()
    }

    /// World-space box around the object-space box `bounds` (its eight corners transformed).
    pub fn world_bounds(&self, bounds: Aabb) -> Aabb {
        if bounds.is_empty() {
            return Aabb::EMPTY;
        }
        let corners = (0..8).map(|i| {
            let pick = |bit: usize, lo: f32, hi: f32| if i & bit == 0 { lo } else { hi };
            let corner = Vec3::new(
                pick(1, bounds.min.x, bounds.max.x),
                pick(2, bounds.min.y, bounds.max.y),
                pick(4, bounds.min.z, bounds.max.z),
            );
            self.to_world.transform_point3(corner)
        });
        Aabb::from_points(corners)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shape::{Shape, Sphere, Triangle};

    fn unit_sphere() -> Object {
        let sphere = Shape::Sphere(Sphere { center: Vec3::ZERO, radius: 1.0 });
        Object::new("ball", vec![Primitive::new(sphere, 0, None)]).unwrap()
    }

    #[test]
    fn object_space_rays_keep_the_world_parameter() {
        // A unit sphere scaled by 2 and moved to (10, 0, 0): a ray from the origin along +x
        // hits it at t = 8 in world space, and the object-space ray at the same parameter.
        let to_world = Affine3A::from_scale_rotation_translation(
            Vec3::splat(2.0),
            glam::Quat::from_rotation_z(0.3),
            Vec3::new(10.0, 0.0, 0.0),
        );
        let instance = Instance::new(0, to_world).unwrap();
        let ray = Ray::new(Vec3::ZERO, Vec3::X);
        let all = |_: &Primitive, _: &Ray, _: f32| true;
        let (_, t) = unit_sphere().closest_hit(&instance.to_object_ray(&ray), f32::INFINITY, all).unwrap();
        assert!((t - 8.0).abs() < 1e-5, "{t}");
        assert!(!unit_sphere().any_hit(&instance.to_object_ray(&ray), 7.9, all));
        assert!(unit_sphere().any_hit(&instance.to_object_ray(&ray), 8.1, all));
        assert!(!unit_sphere().any_hit(&instance.to_object_ray(&ray), 8.1, |_, _, _| false));
    }

    #[test]
    fn normals_use_the_inverse_transpose() {
        // A plane x = y in object space (normal (1, −1, 0)/√2) stretched by 3 along x: the
        // world plane is x = 3y, whose normal is (1, −3, 0)/√10, not the stretched normal.
        let instance = Instance::new(0, Affine3A::from_scale(Vec3::new(3.0, 1.0, 1.0))).unwrap();
        let n = instance.normal_to_world(Vec3::new(1.0, -1.0, 0.0).normalize());
        let expected = Vec3::new(1.0, -3.0, 0.0).normalize();
        assert!((n - expected).length() < 1e-6, "{n}");
        // A point on the world plane stays on it: (3, 1, 0) · n = 0.
        assert!(Vec3::new(3.0, 1.0, 0.0).dot(n).abs() < 1e-6);
    }

    #[test]
    fn world_bounds_enclose_the_transformed_box() {
        let instance = Instance::new(
            0,
            Affine3A::from_rotation_translation(glam::Quat::from_rotation_z(0.25 * std::f32::consts::PI), Vec3::Z),
        )
        .unwrap();
        let b = instance.world_bounds(Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0)));
        let half_diagonal = 2f32.sqrt();
        assert!((b.max.x - half_diagonal).abs() < 1e-5 && (b.min.y + half_diagonal).abs() < 1e-5, "{b:?}");
        assert!((b.min.z - 0.0).abs() < 1e-6 && (b.max.z - 2.0).abs() < 1e-6, "{b:?}");
    }

    #[test]
    fn singular_transforms_and_emitters_are_refused() {
        assert!(Instance::new(0, Affine3A::from_scale(Vec3::new(1.0, 0.0, 1.0))).is_none());
        assert!(Instance::new(0, Affine3A::from_translation(Vec3::splat(f32::NAN))).is_none());
        let triangle = Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y);
        let error = Object::new("lamp", vec![Primitive::new(Shape::Triangle(triangle), 0, Some(0))]).unwrap_err();
        assert!(error.contains("lamp") && error.contains("emit"), "{error}");
    }
}
