//! Geometric primitives (triangles and analytic spheres) and their ray intersection.
//!
//! Intersections accept `0 < t < t_max` (strict on both ends), so a later primitive replaces an
//! earlier hit only when it is strictly closer. Normals are *geometric* normals: for triangles
//! `normalize((p1−p0) × (p2−p0))`, for spheres the outward normal.

use math::{Aabb, Ray, Vec3};

/// A triangle stored by its vertices (kept exactly as given) and its precomputed unit normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle {
    /// First vertex.
    pub p0: Vec3,
    /// Second vertex.
    pub p1: Vec3,
    /// Third vertex.
    pub p2: Vec3,
    /// Unit geometric normal `normalize((p1 − p0) × (p2 − p0))`.
    pub normal: Vec3,
}

impl Triangle {
    /// The triangle `(p0, p1, p2)`; its normal follows the right-hand rule.
    pub fn new(p0: Vec3, p1: Vec3, p2: Vec3) -> Self {
        Self { p0, p1, p2, normal: (p1 - p0).cross(p2 - p0).normalize() }
    }

    /// `p1 − p0`.
    #[inline]
    pub fn edge1(&self) -> Vec3 {
        self.p1 - self.p0
    }

    /// `p2 − p0`.
    #[inline]
    pub fn edge2(&self) -> Vec3 {
        self.p2 - self.p0
    }

    /// The point with barycentric coordinates `(b1, b2)`: `p0 + b1·(p1−p0) + b2·(p2−p0)`.
    #[inline]
    pub fn point(&self, b1: f32, b2: f32) -> Vec3 {
        self.p0 + self.edge1() * b1 + self.edge2() * b2
    }

    /// The three vertices.
    pub fn vertices(&self) -> [Vec3; 3] {
        [self.p0, self.p1, self.p2]
    }

    /// Area in square scene units.
    pub fn area(&self) -> f32 {
        0.5 * self.edge1().cross(self.edge2()).length()
    }

    /// Bounding box.
    pub fn bounds(&self) -> Aabb {
        Aabb::from_points(self.vertices())
    }

    /// Distance along `ray` to the intersection in `(0, t_max)`, by the Möller–Trumbore test.
    /// Both sides of the triangle are hit.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<f32> {
        let edge1 = self.edge1();
        let edge2 = self.edge2();
        let pvec = ray.direction.cross(edge2);
        let det = edge1.dot(pvec);
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        let inv_det = 1.0 / det;
        let tvec = ray.origin - self.p0;
        let u = tvec.dot(pvec) * inv_det;
        if !(0.0..=1.0).contains(&u) {
            return None;
        }
        let qvec = tvec.cross(edge1);
        let v = ray.direction.dot(qvec) * inv_det;
        if v < 0.0 || u + v > 1.0 {
            return None;
        }
        let t = edge2.dot(qvec) * inv_det;
        (t > 0.0 && t < t_max).then_some(t)
    }
}

/// An analytic sphere.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    /// Centre (scene units).
    pub center: Vec3,
    /// Radius (scene units).
    pub radius: f32,
}

impl Sphere {
    /// Bounding box: the axis-aligned cube around the sphere.
    pub fn bounds(&self) -> Aabb {
        Aabb::new(self.center - Vec3::splat(self.radius), self.center + Vec3::splat(self.radius))
    }

    /// Distance along `ray` to the nearest intersection in `(0, t_max)`; from inside the sphere
    /// this is the exit point.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<f32> {
        let o = ray.origin - self.center;
        let a = ray.direction.dot(ray.direction);
        let b = 2.0 * ray.direction.dot(o);
        let c = o.dot(o) - self.radius * self.radius;
        let discriminant = b * b - 4.0 * a * c;
        if discriminant < 0.0 {
            return None;
        }
        // Numerically stable roots: q = −(b + sign(b)·√disc)/2, t0 = q/a, t1 = c/q.
        let root = discriminant.sqrt();
        let q = if b < 0.0 { -0.5 * (b - root) } else { -0.5 * (b + root) };
        let (mut t0, mut t1) = (q / a, c / q);
        if t0 > t1 {
            std::mem::swap(&mut t0, &mut t1);
        }
        if t0 > 0.0 && t0 < t_max {
            Some(t0)
        } else if t1 > 0.0 && t1 < t_max {
            Some(t1)
        } else {
            None
        }
    }

    /// Outward unit normal at a point on the surface.
    #[inline]
    pub fn normal_at(&self, point: Vec3) -> Vec3 {
        (point - self.center).normalize()
    }
}

/// A primitive of the scene. Closed set: matched exhaustively.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shape {
    /// A triangle.
    Triangle(Triangle),
    /// An analytic sphere.
    Sphere(Sphere),
}

impl Shape {
    /// Bounding box.
    pub fn bounds(&self) -> Aabb {
        match self {
            Shape::Triangle(t) => t.bounds(),
            Shape::Sphere(s) => s.bounds(),
        }
    }

    /// Distance to the nearest intersection in `(0, t_max)`.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<f32> {
        match self {
            Shape::Triangle(t) => t.intersect(ray, t_max),
            Shape::Sphere(s) => s.intersect(ray, t_max),
        }
    }

    /// Unit geometric normal at `point` (which lies on the surface).
    #[inline]
    pub fn normal_at(&self, point: Vec3) -> Vec3 {
        match self {
            Shape::Triangle(t) => t.normal,
            Shape::Sphere(s) => s.normal_at(point),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn triangle_hits_inside_and_misses_outside() {
        let t = Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y);
        assert_eq!(t.normal, Vec3::Z);
        let down = Ray::new(Vec3::new(0.25, 0.25, 1.0), -Vec3::Z);
        assert_eq!(t.intersect(&down, f32::INFINITY), Some(1.0));
        assert_eq!(t.intersect(&down, 1.0), None, "t_max is exclusive");
        let up = Ray::new(Vec3::new(0.25, 0.25, -2.0), Vec3::Z);
        assert_eq!(t.intersect(&up, f32::INFINITY), Some(2.0), "back side is hit too");
        let miss = Ray::new(Vec3::new(0.75, 0.75, 1.0), -Vec3::Z);
        assert_eq!(t.intersect(&miss, f32::INFINITY), None);
        assert!((t.area() - 0.5).abs() < 1e-7);
    }

    #[test]
    fn sphere_front_and_exit_hits() {
        let s = Sphere { center: Vec3::new(0.0, 0.0, 5.0), radius: 1.0 };
        let r = Ray::new(Vec3::ZERO, Vec3::Z);
        assert!((s.intersect(&r, f32::INFINITY).unwrap() - 4.0).abs() < 1e-5);
        let inside = Ray::new(Vec3::new(0.0, 0.0, 5.0), Vec3::Z);
        assert!((s.intersect(&inside, f32::INFINITY).unwrap() - 1.0).abs() < 1e-5);
        assert!(s.intersect(&r, 3.9).is_none());
        assert!(s.intersect(&Ray::new(Vec3::ZERO, -Vec3::Z), f32::INFINITY).is_none());
        assert!((s.normal_at(Vec3::new(0.0, 0.0, 4.0)) + Vec3::Z).length() < 1e-6);
    }
}
