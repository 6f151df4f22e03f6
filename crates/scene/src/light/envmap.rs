//! The image-based environment (Mitsuba 3's `envmap`), importance-sampled.

use std::sync::Arc;

use math::{Distribution2D, Frame, PI, PdfA, PdfW, Vec2, Vec3};
use spectrum::Rgb;

use super::{BoundingSphere, DirectSample, EmissionSample, HitRadiance, disc_origin, disc_pdf};
use crate::desc::TextureImage;

/// An image-based environment (Mitsuba 3's `envmap`), importance-sampled.
///
/// Lookup: the world direction `d` is mapped to the local direction `v = R⁻¹·d` and to
/// `u = atan2(v.x, −v.z)/(2π)` (wrapped into [0,1)), `v = acos(v.y)/π`. As in Mitsuba 3, the
/// image is a grid of samples interpolated bilinearly: pixel `(x, y)` of a `W × H` image sits
/// at `u = (x + ½)/W` (periodic in `u`) and `v = y/(H − 1)` (row 0 at the north pole `v.y = 1`,
/// row `H − 1` at the south pole).
///
/// Sampling: a piecewise-constant density over the `W × (H − 1)` cells of that grid, each cell
/// weighted by the exact integral of the luminance of its bilinear radiance over its solid
/// angle, so the density is positive wherever the radiance can be. A point `(s, t)` of the unit
/// square has density `p(s, t)` per unit area and the direction it maps to has density
/// `p / (2π² sin θ)` per steradian.
#[derive(Clone, Debug, PartialEq)]
pub struct EnvMapLight {
    data: Arc<EnvMapData>,
}

#[derive(Debug, PartialEq)]
struct EnvMapData {
    width: usize,
    height: usize,
    /// Pixels with the scale applied, row-major, row 0 at the top; negatives clamped to 0.
    pixels: Vec<Rgb>,
    /// Rotation local → world (columns: images of the local axes).
    to_world: [Vec3; 3],
    distribution: Distribution2D,
    /// `∫ luminance(L(ω)) dω` over the sphere.
    luminance_integral: f32,
}

impl EnvMapLight {
    /// Builds the light from a `width × height` image (at least 1 × 2 pixels), a scale factor
    /// applied to every pixel and the local-to-world rotation (columns; orthonormal within
    /// 1e-3, a reflection is accepted too). Negative pixel values are clamped to zero;
    /// non-finite ones are an error.
    pub fn new(image: &TextureImage, scale: f32, to_world: [Vec3; 3]) -> Result<Self, String> {
        let (width, height) = (image.width as usize, image.height as usize);
        if width < 1 || height < 2 {
            return Err(format!("environment map: expected at least 1×2 pixels, got {width}×{height}"));
        }
        if image.pixels.len() != width * height {
            return Err(format!(
                "environment map: expected {width}×{height} = {} pixels, got {}",
                width * height,
                image.pixels.len()
            ));
        }
        if !(scale.is_finite() && scale >= 0.0) {
            return Err(format!("environment map: expected a finite non-negative scale, got {scale}"));
        }
        if let Some(i) = image.pixels.iter().position(|p| !p.is_finite()) {
            return Err(format!(
                "environment map: pixel ({}, {}) is not finite: {:?}",
                i % width,
                i / width,
                image.pixels[i]
            ));
        }
        for (i, a) in to_world.iter().enumerate() {
            for (j, b) in to_world.iter().enumerate() {
                let error = (a.dot(*b) - if i == j { 1.0 } else { 0.0 }).abs();
                if error.is_nan() || error > 1e-3 {
                    return Err(format!(
                        "environment map: to_world must be a rotation (orthonormal columns), got columns {to_world:?}"
                    ));
                }
            }
        }
        let pixels: Vec<Rgb> = image.pixels.iter().map(|p| (*p * scale).max(Rgb::BLACK)).collect();

        // Exact integral of the luminance of the bilinear radiance over each cell's solid
        // angle. Across a cell the radiance averaged over u is linear in θ, from `a` (upper
        // row) to `b` (lower row); ∫ (a + (b−a)t) sin(θ0 + tΔ) Δ dt = a·k_a + b·k_b.
        let cells_y = height - 1;
        let delta = std::f64::consts::PI / cells_y as f64;
        let cell_phi = 2.0 * std::f64::consts::PI / width as f64;
        let lum = |x: usize, y: usize| pixels[y * width + x].luminance().max(0.0) as f64;
        let mut weights = Vec::with_capacity(width * cells_y);
        let mut integral = 0.0f64;
        for j in 0..cells_y {
            let (theta0, theta1) = (j as f64 * delta, (j + 1) as f64 * delta);
            let k_b = ((theta1.sin() - theta0.sin()) / delta - theta1.cos()).max(0.0);
            let k_a = ((theta0.cos() - theta1.cos()) - k_b).max(0.0);
            for i in 0..width {
                let i1 = (i + 1) % width;
                let a = 0.5 * (lum(i, j) + lum(i1, j));
                let b = 0.5 * (lum(i, j + 1) + lum(i1, j + 1));
                let w = cell_phi * (a * k_a + b * k_b);
                integral += w;
                weights.push(w as f32);
            }
        }
        // A black map emits nothing; sample it uniformly in the square so that the pdfs stay
        // valid.
        let distribution = Distribution2D::new(&weights, width, cells_y)
            .or_else(|| Distribution2D::new(&vec![1.0; width * cells_y], width, cells_y))
            .ok_or_else(|| "environment map: cannot build the sampling distribution".to_string())?;
        Ok(Self {
            data: Arc::new(EnvMapData {
                width,
                height,
                pixels,
                to_world,
                distribution,
                luminance_integral: integral as f32,
            }),
        })
    }

    /// Radiance arriving from the unit world direction `direction` (pointing away from the
    /// scene, towards the environment).
    pub fn radiance(&self, direction: Vec3) -> Rgb {
        self.evaluate(direction).0
    }

    /// Density per steradian with which [`Light::sample_direct`] picks `direction`.
    pub fn pdf(&self, direction: Vec3) -> f32 {
        self.evaluate(direction).1
    }

    /// Radiance from `direction` and its density per steradian, both looked up at the same
    /// point of the map.
    fn evaluate(&self, direction: Vec3) -> (Rgb, f32) {
        let local = self.to_local(direction);
        let sin_theta = (local.x * local.x + local.z * local.z).sqrt();
        let (s, t) = self.square_of(local);
        let radiance = self.lookup(s, t);
        let pdf = if sin_theta > 0.0 {
            self.data.distribution.pdf(Vec2::new(s, t)) / (2.0 * PI * PI * sin_theta)
        } else {
            0.0
        };
        (radiance, pdf)
    }

    /// `∫ luminance(L(ω)) dω` over the whole sphere (W·m⁻²).
    pub fn luminance_integral(&self) -> f32 {
        self.data.luminance_integral
    }

    /// Samples a direction towards the environment: the unit world direction, its radiance and
    /// its density per steradian. Both are evaluated from the direction (as
    /// [`Light::radiance_on_hit`] does), so the two queries agree exactly. `None` when nothing
    /// is emitted from the sampled direction (or at the poles, where the density is singular).
    fn sample(&self, u: [f32; 2]) -> Option<(Vec3, Rgb, f32)> {
        let (p, _) = self.data.distribution.sample(u);
        let theta = p.y * PI;
        let mut u_map = p.x + 0.5 / self.data.width as f32;
        if u_map >= 1.0 {
            u_map -= 1.0;
        }
        let phi = 2.0 * PI * u_map;
        let (sin_theta, cos_theta) = theta.sin_cos();
        let (sin_phi, cos_phi) = phi.sin_cos();
        let local = Vec3::new(sin_phi * sin_theta, cos_theta, -cos_phi * sin_theta);
        let [c0, c1, c2] = self.data.to_world;
        let direction = (c0 * local.x + c1 * local.y + c2 * local.z).normalize();
        let (radiance, pdf) = self.evaluate(direction);
        (pdf > 0.0 && !radiance.is_black()).then_some((direction, radiance, pdf))
    }

    fn to_local(&self, direction: Vec3) -> Vec3 {
        let [c0, c1, c2] = self.data.to_world;
        Vec3::new(c0.dot(direction), c1.dot(direction), c2.dot(direction))
    }

    /// The point `(s, t)` of the sampling square for a map-local direction: `s = u − ½/W`
    /// (wrapped), `t = v`.
    fn square_of(&self, v: Vec3) -> (f32, f32) {
        let u = v.x.atan2(-v.z) * (0.5 / PI) - 0.5 / self.data.width as f32;
        let s = u - u.floor();
        let s = if s >= 1.0 { 0.0 } else { s };
        let t = v.y.clamp(-1.0, 1.0).acos() / PI;
        (s, t.clamp(0.0, 1.0))
    }

    /// Bilinear interpolation at the sampling-square point `(s, t)`: lattice coordinates
    /// `s·W` (periodic) and `t·(H − 1)`.
    fn lookup(&self, s: f32, t: f32) -> Rgb {
        let d = &*self.data;
        let x = s * d.width as f32;
        let i0 = (x.max(0.0) as usize).min(d.width - 1);
        let fx = (x - i0 as f32).clamp(0.0, 1.0);
        let i1 = (i0 + 1) % d.width;
        let y = t * (d.height - 1) as f32;
        let j0 = (y.max(0.0) as usize).min(d.height - 2);
        let fy = (y - j0 as f32).clamp(0.0, 1.0);
        let px = |i: usize, j: usize| d.pixels[j * d.width + i];
        let top = px(i0, j0) * (1.0 - fx) + px(i1, j0) * fx;
        let bottom = px(i0, j0 + 1) * (1.0 - fx) + px(i1, j0 + 1) * fx;
        top * (1.0 - fy) + bottom * fy
    }
}

impl EnvMapLight {
    /// Next-event estimation: a direction importance-sampled from the map.
    pub(super) fn sample_direct(&self, u: [f32; 2], sphere: &BoundingSphere) -> Option<DirectSample> {
        let (direction, radiance, pdf) = self.sample(u)?;
        Some(DirectSample {
            radiance,
            direction,
            distance: f32::INFINITY,
            direct_pdf: PdfW(pdf),
            emission_pdf: PdfW(pdf * disc_pdf(sphere)),
            cos_at_light: 1.0,
        })
    }

    /// A light sub-path start: an importance-sampled direction, an origin on the
    /// bounding-sphere disc.
    pub(super) fn sample_emission(
        &self,
        u_position: [f32; 2],
        u_direction: [f32; 2],
        sphere: &BoundingSphere,
    ) -> EmissionSample {
        // The light travels away from the sampled environment direction.
        let Some((towards_light, radiance, pdf)) = self.sample(u_direction) else {
            return EmissionSample {
                energy: Rgb::BLACK,
                origin: sphere.center,
                direction: Vec3::Z,
                emission_pdf: PdfW(0.0),
                direct_pdf: PdfA(0.0),
                cos_at_light: 1.0,
            };
        };
        let direction = -towards_light;
        EmissionSample {
            energy: radiance,
            origin: disc_origin(&Frame::from_z(direction), u_position, sphere),
            direction,
            emission_pdf: PdfW(pdf * disc_pdf(sphere)),
            direct_pdf: PdfA(pdf),
            cos_at_light: 1.0,
        }
    }

    /// The radiance of a ray escaping the scene along `ray_direction`.
    pub(super) fn radiance_on_hit(&self, ray_direction: Vec3, sphere: &BoundingSphere) -> Option<HitRadiance> {
        let (radiance, pdf) = self.evaluate(ray_direction);
        Some(HitRadiance {
            radiance,
            direct_pdf: PdfA(pdf),
            emission_pdf: PdfW(pdf * disc_pdf(sphere)),
            cos_at_light: 1.0,
        })
    }
}
