//! Geometric primitives (triangles and analytic spheres) and their ray intersection.
//!
//! Intersections accept `0 < t < t_max` (strict on both ends), so a later primitive replaces an
//! earlier hit only when it is strictly closer. Normals are *geometric* normals: for triangles
//! `normalize((p1−p0) × (p2−p0))`, for spheres the outward normal.

use math::{Aabb, PI, Ray, Vec2, Vec3};

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

    /// Barycentric coordinates `(b1, b2)` of `point` (assumed to lie in the triangle's plane),
    /// so that `point ≈ self.point(b1, b2)`.
    #[inline]
    pub fn barycentrics(&self, point: Vec3) -> (f32, f32) {
        let (e1, e2, d) = (self.edge1(), self.edge2(), point - self.p0);
        let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
        let (d1, d2) = (d.dot(e1), d.dot(e2));
        let det = d11 * d22 - d12 * d12;
        if det == 0.0 {
            return (0.0, 0.0);
        }
        ((d22 * d1 - d12 * d2) / det, (d11 * d2 - d12 * d1) / det)
    }

    /// Bounding box.
    pub fn bounds(&self) -> Aabb {
        Aabb::from_points(self.vertices())
    }

    /// Distance along `ray` to the intersection in `(0, t_max)`, by the Möller–Trumbore test.
    /// Both sides of the triangle are hit.
    #[inline(always)]
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

impl Sphere {
    /// Mitsuba's sphere parameterisation at a surface point: `u = φ/2π` (φ = atan2(y, x)
    /// about the centre, in [0, 1)), `v = θ/π` (θ from +z), in world axes.
    pub fn uv_at(&self, point: Vec3) -> Vec2 {
        let d = (point - self.center) / self.radius;
        let phi = d.y.atan2(d.x);
        let u = if phi < 0.0 { phi + 2.0 * PI } else { phi } / (2.0 * PI);
        Vec2::new(u, d.z.clamp(-1.0, 1.0).acos() / PI)
    }
}

/// An analytic disc (or ellipse): the unit disc `x² + y² ≤ 1` mapped by
/// `center + x·axis_u + y·axis_v`. Stored as 48 bytes, like a triangle, so that it does not grow
/// [`Shape`]: the axes are recovered from their dual basis when needed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Disk {
    /// Centre.
    pub center: Vec3,
    /// Unit geometric normal (`±normalize(axis_u × axis_v)`).
    pub normal: Vec3,
    /// Dual basis: `x = dual_u · (p − center)`, `y = dual_v · (p − center)` for points in the
    /// plane.
    dual_u: Vec3,
    dual_v: Vec3,
}

/// The dual basis of `(a, b)` within their plane: `a'·a = 1, a'·b = 0, b'·a = 0, b'·b = 1`.
/// The dual of the dual is the original pair.
#[inline]
fn dual_basis(a: Vec3, b: Vec3) -> Option<(Vec3, Vec3)> {
    let cross = a.cross(b);
    let len2 = cross.length_squared();
    if len2.is_nan() || len2 <= 0.0 || !len2.is_finite() {
        return None;
    }
    Some((b.cross(cross) / len2, cross.cross(a) / len2))
}

impl Disk {
    /// The disc with the given axes; `flip` reverses the normal. `None` when the axes are
    /// parallel or not finite.
    pub fn new(center: Vec3, axis_u: Vec3, axis_v: Vec3, flip: bool) -> Option<Self> {
        if !center.is_finite() {
            return None;
        }
        let (dual_u, dual_v) = dual_basis(axis_u, axis_v)?;
        let normal = axis_u.cross(axis_v).normalize();
        Some(Self { center, normal: if flip { -normal } else { normal }, dual_u, dual_v })
    }

    /// The axes `(axis_u, axis_v)`.
    pub fn axes(&self) -> (Vec3, Vec3) {
        dual_basis(self.dual_u, self.dual_v).unwrap_or((Vec3::ZERO, Vec3::ZERO))
    }

    /// Area in square scene units: `π |axis_u × axis_v|`.
    pub fn area(&self) -> f32 {
        let (u, v) = self.axes();
        PI * u.cross(v).length()
    }

    /// Bounding box.
    pub fn bounds(&self) -> Aabb {
        let (u, v) = self.axes();
        let extent = Vec3::new(u.x.hypot(v.x), u.y.hypot(v.y), u.z.hypot(v.z));
        Aabb::new(self.center - extent, self.center + extent)
    }

    /// Distance along `ray` to the intersection in `(0, t_max)`.
    #[inline(never)]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<f32> {
        let denominator = ray.direction.dot(self.normal);
        if denominator == 0.0 {
            return None;
        }
        let t = (self.center - ray.origin).dot(self.normal) / denominator;
        if !(t > 0.0 && t < t_max) {
            return None;
        }
        let d = ray.at(t) - self.center;
        let (x, y) = (self.dual_u.dot(d), self.dual_v.dot(d));
        (x * x + y * y <= 1.0).then_some(t)
    }

    /// Local polar texture coordinates: `u` = radius in [0, 1], `v` = angle / 2π in [0, 1).
    pub fn uv_at(&self, point: Vec3) -> Vec2 {
        let d = point - self.center;
        let (x, y) = (self.dual_u.dot(d), self.dual_v.dot(d));
        let phi = y.atan2(x);
        Vec2::new((x * x + y * y).sqrt(), if phi < 0.0 { phi + 2.0 * PI } else { phi } / (2.0 * PI))
    }

    /// The point with local coordinates `(x, y)` on the unit disc.
    pub fn point(&self, x: f32, y: f32) -> Vec3 {
        let (u, v) = self.axes();
        self.center + u * x + v * y
    }
}

/// A primitive of the scene. Closed set: matched exhaustively.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shape {
    /// A triangle.
    Triangle(Triangle),
    /// An analytic sphere.
    Sphere(Sphere),
    /// An analytic disc.
    Disk(Disk),
}

impl Shape {
    /// Bounding box.
    pub fn bounds(&self) -> Aabb {
        match self {
            Shape::Triangle(t) => t.bounds(),
            Shape::Sphere(s) => s.bounds(),
            Shape::Disk(d) => d.bounds(),
        }
    }

    /// Distance to the nearest intersection in `(0, t_max)`.
    #[inline(always)]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<f32> {
        match self {
            Shape::Triangle(t) => t.intersect(ray, t_max),
            Shape::Sphere(s) => s.intersect(ray, t_max),
            Shape::Disk(d) => d.intersect(ray, t_max),
        }
    }

    /// Unit geometric normal at `point` (which lies on the surface).
    #[inline]
    pub fn normal_at(&self, point: Vec3) -> Vec3 {
        match self {
            Shape::Triangle(t) => t.normal,
            Shape::Sphere(s) => s.normal_at(point),
            Shape::Disk(d) => d.normal,
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
    fn disk_hits_inside_its_ellipse() {
        let d = Disk::new(Vec3::new(0.0, 0.0, 1.0), Vec3::new(2.0, 0.0, 0.0), Vec3::new(0.0, 0.5, 0.0), false).unwrap();
        assert_eq!(d.normal, Vec3::Z);
        assert!((d.area() - PI).abs() < 1e-6);
        let hit = |x: f32, y: f32| d.intersect(&Ray::new(Vec3::new(x, y, 3.0), -Vec3::Z), f32::INFINITY);
        assert_eq!(hit(1.9, 0.0), Some(2.0));
        assert_eq!(hit(0.0, 0.45), Some(2.0));
        assert_eq!(hit(0.0, 0.55), None);
        assert_eq!(hit(1.5, 0.4), None, "outside the ellipse, inside its box");
        assert!((d.uv_at(Vec3::new(1.0, 0.0, 1.0)) - Vec2::new(0.5, 0.0)).length() < 1e-6);
        let b = d.bounds();
        assert!((b.max - Vec3::new(2.0, 0.5, 1.0)).length() < 1e-6);
        let (u, v) = d.axes();
        assert!((u - Vec3::new(2.0, 0.0, 0.0)).length() < 1e-6 && (v - Vec3::new(0.0, 0.5, 0.0)).length() < 1e-6);
        assert!((d.point(0.0, 1.0) - Vec3::new(0.0, 0.5, 1.0)).length() < 1e-6);
        assert_eq!(std::mem::size_of::<Shape>(), 52, "a disc does not grow the shape");
        let flipped = Disk::new(Vec3::ZERO, Vec3::X, Vec3::Y, true).unwrap();
        assert_eq!(flipped.normal, -Vec3::Z);
        assert!(Disk::new(Vec3::ZERO, Vec3::X, Vec3::X, false).is_none());
    }

    #[test]
    fn triangle_barycentrics_invert_point() {
        let t = Triangle::new(Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 2.0, 0.5), Vec3::new(-1.0, 0.3, 2.0));
        let (b1, b2) = t.barycentrics(t.point(0.2, 0.7));
        assert!((b1 - 0.2).abs() < 1e-5 && (b2 - 0.7).abs() < 1e-5, "{b1} {b2}");
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
