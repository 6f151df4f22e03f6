//! The pinhole camera: primary rays, the projection of points onto the raster (for light
//! tracing) and the density that converts between image-plane area and solid angle.
//!
//! Raster coordinates: `x` grows to the right, `y` grows downward, pixel `(0, 0)` covers
//! `[0,1)²` at the top-left. Pixels are square; the field of view is horizontal.

use math::{PdfW, Ray, Vec2, Vec3};

/// A pinhole camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Position of the pinhole.
    pub position: Vec3,
    /// Unit viewing direction.
    pub forward: Vec3,
    /// Unit vector pointing right in the image.
    pub right: Vec3,
    /// Unit vector pointing up in the image.
    pub up: Vec3,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    tan_half_fov: f32,
    /// Distance of the image plane from the pinhole, in pixels: `width / (2 tan(fov/2))`.
    image_plane_distance: f32,
}

impl Camera {
    /// A camera at `position` looking along `forward` with up hint `up_hint`, horizontal field
    /// of view `fov_degrees`, for a `width × height` raster. The basis is
    /// `right = normalize(up_hint × −forward)`, `up = −forward × right`.
    pub fn new(position: Vec3, forward: Vec3, up_hint: Vec3, fov_degrees: f32, width: u32, height: u32) -> Self {
        let forward = forward.normalize();
        let right = up_hint.cross(-forward).normalize();
        let up = (-forward).cross(right);
        let tan_half_fov = (fov_degrees.to_radians() * 0.5).tan();
        Self {
            position,
            forward,
            right,
            up,
            width,
            height,
            tan_half_fov,
            image_plane_distance: width as f32 / (2.0 * tan_half_fov),
        }
    }

    /// Number of pixels.
    pub fn pixel_count(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// The primary ray through raster point `raster` (in pixels). It starts exactly at the
    /// pinhole.
    pub fn generate_ray(&self, raster: Vec2) -> Ray {
        let w = self.width as f32;
        let h = self.height as f32;
        let x = self.tan_half_fov * (2.0 * raster.x / w - 1.0);
        let y = self.tan_half_fov * (2.0 * raster.y / h - 1.0) * (h / w);
        let direction = (self.forward + x * self.right - y * self.up).normalize();
        Ray::new(self.position, direction)
    }

    /// The raster position (pixels) onto which `point` projects, or `None` when it is behind
    /// the camera or outside the image.
    pub fn raster_position(&self, point: Vec3) -> Option<Vec2> {
        let d = point - self.position;
        let z = d.dot(self.forward);
        if z <= 0.0 {
            return None;
        }
        let w = self.width as f32;
        let h = self.height as f32;
        let x = d.dot(self.right) / z;
        let y = d.dot(self.up) / z;
        let raster =
            Vec2::new((x / self.tan_half_fov + 1.0) * 0.5 * w, (1.0 - y / (self.tan_half_fov * (h / w))) * 0.5 * h);
        (raster.x >= 0.0 && raster.x < w && raster.y >= 0.0 && raster.y < h).then_some(raster)
    }

    /// Distance of the image plane from the pinhole, in pixels (one pixel has unit area there).
    pub fn image_plane_distance(&self) -> f32 {
        self.image_plane_distance
    }

    /// Density per unit solid angle of a primary ray with cosine `cos_at_camera` to the
    /// viewing axis, when raster points are sampled with unit density per pixel:
    /// `d² / cos³` (the image plane at distance `d` pixels).
    pub fn solid_angle_pdf(&self, cos_at_camera: f32) -> PdfW {
        let d = self.image_plane_distance;
        PdfW(d * d / (cos_at_camera * cos_at_camera * cos_at_camera))
    }
}

#[cfg(test)]
// The expected values are quoted from the specification with all their digits.
#[allow(clippy::excessive_precision)]
mod tests {
    use super::*;

    fn reference() -> Camera {
        Camera::new(
            Vec3::new(-0.0439815, -4.12529, 0.222539),
            Vec3::new(0.00688625, 0.998505, -0.0542161),
            Vec3::new(3.73896e-4, 0.0542148, 0.998529),
            45.0,
            512,
            512,
        )
    }

    fn close(a: Vec3, b: Vec3, tolerance: f32) -> bool {
        (a - b).abs().max_element() < tolerance
    }

    #[test]
    fn reference_basis_and_rays() {
        let c = reference();
        assert!(close(c.forward, Vec3::new(0.00688625313, 0.998505473, -0.0542161278), 1e-7));
        assert!(close(c.right, Vec3::new(0.999976218, -0.00689639617, 0.0), 1e-6));
        assert!(close(c.up, Vec3::new(0.00037389627, 0.0542148389, 0.998529255), 1e-6));
        assert!((c.image_plane_distance() - 618.038635).abs() < 1e-3);
        let d = c.generate_ray(Vec2::new(0.0, 0.0)).direction;
        assert!(close(d, Vec3::new(-0.3513228, 0.8834083, 0.3101000), 1e-6), "{d}");
        assert!(close(c.generate_ray(Vec2::new(256.0, 256.0)).direction, c.forward, 1e-7));
        let d = c.generate_ray(Vec2::new(512.0, 512.0)).direction;
        assert!(close(d, Vec3::new(0.3632062, 0.8397255, -0.4036613), 1e-6), "{d}");
    }

    #[test]
    fn projection_inverts_ray_generation() {
        for (w, h) in [(512, 512), (320, 200), (100, 300)] {
            let c = Camera::new(Vec3::new(1.0, 2.0, 3.0), Vec3::new(0.2, 1.0, -0.1), Vec3::Z, 60.0, w, h);
            for raster in
                [Vec2::new(0.5, 0.5), Vec2::new(w as f32 * 0.3, h as f32 * 0.8), Vec2::new(w as f32 - 0.25, 1.0)]
            {
                let ray = c.generate_ray(raster);
                let back = c.raster_position(ray.at(7.5)).unwrap();
                assert!((back - raster).length() < 2e-3 * w as f32 / 100.0, "{raster} -> {back}");
            }
            assert!(c.raster_position(c.position - c.forward).is_none());
        }
    }

    #[test]
    fn solid_angle_pdf_is_inverse_pixel_solid_angle() {
        // A pixel subtends ≈ |(d10 − d00) × (d01 − d00)| steradians (unit corner directions);
        // the density of a ray through it must be its inverse.
        let c = reference();
        for (x, y) in [(100.0, 40.0), (256.0, 256.0), (500.0, 3.0)] {
            let d00 = c.generate_ray(Vec2::new(x, y)).direction;
            let d10 = c.generate_ray(Vec2::new(x + 1.0, y)).direction;
            let d01 = c.generate_ray(Vec2::new(x, y + 1.0)).direction;
            let solid_angle = (d10 - d00).cross(d01 - d00).length();
            let centre = c.generate_ray(Vec2::new(x + 0.5, y + 0.5)).direction;
            let pdf = c.solid_angle_pdf(c.forward.dot(centre)).0;
            assert!((pdf * solid_angle - 1.0).abs() < 1e-2, "{x},{y}: {}", pdf * solid_angle);
        }
    }
}
