//! Lights and the three queries every integrator asks of them (tech report §3 and §5.1).
//!
//! * [`Light::sample_direct`]: next-event estimation from a receiving point.
//! * [`Light::sample_emission`]: the start of a light sub-path.
//! * [`Light::radiance_on_hit`]: a camera ray that hits (or escapes to) the light.
//!
//! Conventions shared by all three:
//! * `direct_pdf` is the density of choosing the *point* on the light by direct sampling. For
//!   finite lights it is per unit area ([`PdfA`]); `sample_direct` reports it converted to solid
//!   angle at the receiver. Delta-position lights (point, spot) have area density 1, so their
//!   solid angle density is `distance²`; the directional light has density 1 for its one
//!   direction. Infinite lights (directional, constant and image environments) store solid-angle
//!   densities in the area slot (tech report §5.1).
//! * `emission_pdf` is the density of emitting along the connecting ray from the light: area
//!   density of the origin × solid-angle density of the direction. Infinite lights emit from a
//!   disc of the scene's bounding sphere perpendicular to the direction, with area density
//!   `1/(πR²)`.
//! * `cos_at_light` is the cosine between the light's normal and the emitted direction (1 for
//!   lights without a surface).
//! * Light selection is not included: the caller multiplies by its pick probability; for
//!   power-proportional selection [`Light::power`] gives each light's emitted flux.
//!
//! Area lights are one-sided (the front is the side their geometric normal points to) and emit
//! constant radiance; their points are sampled uniformly by area on every shape (sphere
//! included), so direct and emission sampling share one area density.

use std::sync::Arc;

use math::{Distribution2D, Frame, PI, PdfA, PdfW, Vec2, Vec3, warp};
use spectrum::Rgb;

use crate::desc::{LightDesc, TextureImage};
use crate::shape::Triangle;

/// The scene's bounding sphere, needed by infinite lights.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoundingSphere {
    /// Centre (scene units).
    pub center: Vec3,
    /// Radius (scene units).
    pub radius: f32,
}

/// The surface of an area light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AreaShape {
    /// A triangle; its front is the side of [`Triangle::normal`].
    Triangle(Triangle),
    /// A sphere; its front is outside (inside when `flip_normals`).
    Sphere {
        /// Centre (scene units).
        center: Vec3,
        /// Radius (scene units, > 0).
        radius: f32,
        /// The normals (and the emission) point inward.
        flip_normals: bool,
    },
    /// The (possibly elliptic) disc `center + x·axis_u + y·axis_v`, `x² + y² ≤ 1`.
    Disc {
        /// Centre (scene units).
        center: Vec3,
        /// Image of the unit disc's x axis (scene units).
        axis_u: Vec3,
        /// Image of the unit disc's y axis (scene units).
        axis_v: Vec3,
        /// Unit front normal: `normalize(axis_u × axis_v)`, negated for flipped discs.
        normal: Vec3,
    },
}

/// A one-sided surface emitting constant radiance into the hemisphere of its normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AreaLight {
    /// The emitting surface.
    pub shape: AreaShape,
    /// Emitted radiance (W·m⁻²·sr⁻¹ per channel).
    pub radiance: Rgb,
    inv_area: f32,
}

impl AreaLight {
    /// An area light on `triangle` with constant `radiance`, emitting on the side of the
    /// triangle's normal.
    pub fn new(triangle: Triangle, radiance: Rgb) -> Self {
        Self { shape: AreaShape::Triangle(triangle), radiance, inv_area: 1.0 / triangle.area() }
    }

    /// An emitting sphere: outward normals (emission leaves the sphere), or inward ones when
    /// `flip_normals`. Fails for a radius that is not positive and finite, a non-finite centre
    /// or a radiance that is negative or not finite.
    pub fn sphere(center: Vec3, radius: f32, flip_normals: bool, radiance: Rgb) -> Result<Self, String> {
        check_point("sphere centre", center)?;
        if !(radius.is_finite() && radius > 0.0) {
            return Err(format!("sphere emitter: expected a positive finite radius, got {radius}"));
        }
        check_rgb("sphere emitter radiance", radiance)?;
        let area = 4.0 * PI * radius * radius;
        Ok(Self { shape: AreaShape::Sphere { center, radius, flip_normals }, radiance, inv_area: 1.0 / area })
    }

    /// An emitting disc `center + x·axis_u + y·axis_v` over the unit disc (an ellipse for
    /// unequal or non-orthogonal axes), with front normal `normalize(axis_u × axis_v)`, negated
    /// when `flip_normals`. Fails for degenerate axes (zero area) or non-finite input.
    pub fn disc(center: Vec3, axis_u: Vec3, axis_v: Vec3, flip_normals: bool, radiance: Rgb) -> Result<Self, String> {
        check_point("disc centre", center)?;
        check_point("disc axis_u", axis_u)?;
        check_point("disc axis_v", axis_v)?;
        check_rgb("disc emitter radiance", radiance)?;
        let cross = axis_u.cross(axis_v);
        let area = PI * cross.length();
        if !(area.is_finite() && area > 0.0) {
            return Err(format!("disc emitter: the axes {axis_u} and {axis_v} span no area"));
        }
        let normal = if flip_normals { -cross.normalize() } else { cross.normalize() };
        Ok(Self { shape: AreaShape::Disc { center, axis_u, axis_v, normal }, radiance, inv_area: 1.0 / area })
    }

    /// Surface area (square scene units).
    pub fn area(&self) -> f32 {
        1.0 / self.inv_area
    }

    /// The triangle, for triangle emitters.
    pub fn triangle(&self) -> Option<&Triangle> {
        match &self.shape {
            AreaShape::Triangle(t) => Some(t),
            _ => None,
        }
    }

    /// A point uniformly distributed by area (density `1/area`) and the unit front normal there.
    fn sample_point(&self, u: [f32; 2]) -> (Vec3, Vec3) {
        match self.shape {
            AreaShape::Triangle(t) => {
                let b = warp::uniform_triangle(u);
                (t.point(b.x, b.y), t.normal)
            }
            AreaShape::Sphere { center, radius, flip_normals } => {
                let d = warp::uniform_sphere(u);
                (center + radius * d, if flip_normals { -d } else { d })
            }
            AreaShape::Disc { center, axis_u, axis_v, normal } => {
                let q = warp::concentric_disc(u);
                (center + q.x * axis_u + q.y * axis_v, normal)
            }
        }
    }
}

/// An isotropic point light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointLight {
    /// Position.
    pub position: Vec3,
    /// Radiant intensity (W·sr⁻¹ per channel).
    pub intensity: Rgb,
}

/// A spot light (Mitsuba's `spot`): a point emitting `intensity` within `beam_width` of its
/// axis, falling off *linearly in angle* to zero at `cutoff` (Mitsuba 3's falloff curve):
/// `f(θ) = 1` for `θ ≤ beam_width`, `(cutoff − θ)/(cutoff − beam_width)` up to `cutoff`, 0 beyond.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpotLight {
    /// Position.
    pub position: Vec3,
    /// Radiant intensity on the axis (W·sr⁻¹ per channel).
    pub intensity: Rgb,
    /// Frame whose `z` is the unit axis.
    frame: Frame,
    /// Half-angle where the falloff ends (radians).
    cutoff: f32,
    /// Half-angle where the falloff begins (radians, ≤ `cutoff`).
    beam_width: f32,
    cos_cutoff: f32,
    cos_beam_width: f32,
}

impl SpotLight {
    /// A spot light at `position` shining along `axis` (normalised here). Both angles are
    /// half-angles from the axis in degrees, `0 < cutoff ≤ 180` and `0 ≤ beam_width ≤ cutoff`.
    pub fn new(
        position: Vec3,
        axis: Vec3,
        intensity: Rgb,
        cutoff_degrees: f32,
        beam_width_degrees: f32,
    ) -> Result<Self, String> {
        check_point("spot light position", position)?;
        let axis = check_direction("spot light direction", axis)?;
        check_rgb("spot light intensity", intensity)?;
        if !(cutoff_degrees > 0.0 && cutoff_degrees <= 180.0) {
            return Err(format!("spot light: expected a cutoff angle in (0°, 180°], got {cutoff_degrees}°"));
        }
        if !(0.0..=cutoff_degrees).contains(&beam_width_degrees) {
            return Err(format!(
                "spot light: expected a beam width in [0°, cutoff = {cutoff_degrees}°], got {beam_width_degrees}°"
            ));
        }
        let (cutoff, beam_width) = (cutoff_degrees.to_radians(), beam_width_degrees.to_radians());
        Ok(Self {
            position,
            intensity,
            frame: Frame::from_z(axis),
            cutoff,
            beam_width,
            cos_cutoff: cutoff.cos(),
            cos_beam_width: beam_width.cos(),
        })
    }

    /// Unit axis.
    pub fn axis(&self) -> Vec3 {
        self.frame.z
    }

    /// Falloff factor in `[0, 1]` for a direction whose cosine with the axis is `cos_theta`.
    pub fn falloff(&self, cos_theta: f32) -> f32 {
        if cos_theta <= self.cos_cutoff {
            0.0
        } else if cos_theta >= self.cos_beam_width {
            1.0
        } else {
            ((self.cutoff - cos_theta.clamp(-1.0, 1.0).acos()) / (self.cutoff - self.beam_width)).clamp(0.0, 1.0)
        }
    }

    /// Solid-angle density of emitted directions: uniform in the cutoff cone.
    fn cone_pdf(&self) -> f32 {
        1.0 / (2.0 * PI * (1.0 - self.cos_cutoff))
    }

    /// `∫ f(θ) dω` over the sphere (steradians): `2π(1 − (sin c − sin b)/(c − b))`, which is
    /// `2π(1 − cos c)` when `b = c`.
    pub fn falloff_solid_angle(&self) -> f32 {
        let (c, b) = (self.cutoff as f64, self.beam_width as f64);
        // (sin c − sin b)/(c − b) = cos((c+b)/2)·sinc((c−b)/2), stable for c ≈ b.
        let h = 0.5 * (c - b);
        let sinc = if h.abs() < 1e-4 { 1.0 - h * h / 6.0 } else { h.sin() / h };
        (2.0 * std::f64::consts::PI * (1.0 - (0.5 * (c + b)).cos() * sinc)) as f32
    }
}

/// A directional light ("sun").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DirectionalLight {
    /// Unit direction in which the light travels.
    pub direction: Vec3,
    /// Irradiance on a surface perpendicular to `direction` (W·m⁻² per channel).
    pub irradiance: Rgb,
    frame: Frame,
}

impl DirectionalLight {
    /// Light travelling along `direction` (normalised here) with the given irradiance.
    pub fn new(direction: Vec3, irradiance: Rgb) -> Self {
        let direction = direction.normalize();
        Self { direction, irradiance, frame: Frame::from_z(direction) }
    }
}

/// A constant environment: the same radiance from every direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BackgroundLight {
    /// Radiance arriving from every direction (W·m⁻²·sr⁻¹ per channel).
    pub radiance: Rgb,
}

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

/// The kinds of light. Closed set: matched exhaustively.
#[derive(Clone, Debug, PartialEq)]
pub enum Light {
    /// One-sided surface emitter (triangle, sphere, disc).
    Area(AreaLight),
    /// Point light.
    Point(PointLight),
    /// Spot light.
    Spot(SpotLight),
    /// Directional light.
    Directional(DirectionalLight),
    /// Constant environment.
    Background(BackgroundLight),
    /// Image-based environment.
    EnvMap(EnvMapLight),
}

/// Result of [`Light::sample_direct`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DirectSample {
    /// Radiance arriving at the receiver (irradiance for the directional light, intensity for
    /// the point and spot lights); the estimate is `radiance · f · cos / direct_pdf`.
    pub radiance: Rgb,
    /// Unit direction from the receiver towards the light.
    pub direction: Vec3,
    /// Distance to the light point; `f32::INFINITY` for infinite lights.
    pub distance: f32,
    /// Density of this sample per unit solid angle at the receiver.
    pub direct_pdf: PdfW,
    /// Density with which the light would emit this ray (area × solid angle), see the module.
    pub emission_pdf: PdfW,
    /// Cosine at the light (1 without a surface).
    pub cos_at_light: f32,
}

/// Result of [`Light::sample_emission`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmissionSample {
    /// Emitted radiance times `cos_at_light` (before division by `emission_pdf`).
    pub energy: Rgb,
    /// Start of the light sub-path.
    pub origin: Vec3,
    /// Unit direction of travel.
    pub direction: Vec3,
    /// Density of `(origin, direction)`: area density × solid-angle density.
    pub emission_pdf: PdfW,
    /// Density of choosing `origin` by direct sampling (area; solid angle for infinite lights).
    pub direct_pdf: PdfA,
    /// Cosine at the light (1 without a surface).
    pub cos_at_light: f32,
}

/// Result of [`Light::radiance_on_hit`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HitRadiance {
    /// Radiance arriving along the ray.
    pub radiance: Rgb,
    /// Density of choosing the hit point by direct sampling (area; solid angle for infinite
    /// lights).
    pub direct_pdf: PdfA,
    /// Density with which the light would emit the reversed ray.
    pub emission_pdf: PdfW,
    /// Cosine at the light (1 without a surface).
    pub cos_at_light: f32,
}

impl Light {
    /// Builds a light that is not attached to a shape from its description (`Constant` becomes
    /// [`Light::Background`]). Returns a message naming the first invalid parameter.
    pub fn from_desc(desc: &LightDesc) -> Result<Light, String> {
        match desc {
            LightDesc::Point { position, intensity } => {
                check_point("point light position", *position)?;
                check_rgb("point light intensity", *intensity)?;
                Ok(Light::Point(PointLight { position: *position, intensity: *intensity }))
            }
            LightDesc::Spot { position, direction, intensity, cutoff_degrees, beam_width_degrees } => Ok(Light::Spot(
                SpotLight::new(*position, *direction, *intensity, *cutoff_degrees, *beam_width_degrees)?,
            )),
            LightDesc::Directional { direction, irradiance } => {
                let direction = check_direction("directional light direction", *direction)?;
                check_rgb("directional light irradiance", *irradiance)?;
                Ok(Light::Directional(DirectionalLight::new(direction, *irradiance)))
            }
            LightDesc::Constant { radiance } => {
                check_rgb("constant environment radiance", *radiance)?;
                Ok(Light::Background(BackgroundLight { radiance: *radiance }))
            }
            LightDesc::EnvMap { image, scale, to_world } => {
                Ok(Light::EnvMap(EnvMapLight::new(image, *scale, *to_world)?))
            }
        }
    }

    /// True for lights whose position (point, spot) or direction (directional) is a delta
    /// distribution: they cannot be hit by rays.
    pub fn is_delta(&self) -> bool {
        matches!(self, Light::Point(_) | Light::Spot(_) | Light::Directional(_))
    }

    /// True for lights at finite distance (area, point, spot).
    pub fn is_finite(&self) -> bool {
        matches!(self, Light::Area(_) | Light::Point(_) | Light::Spot(_))
    }

    /// True for the environment lights (constant and image), which rays leaving the scene see.
    pub fn is_environment(&self) -> bool {
        matches!(self, Light::Background(_) | Light::EnvMap(_))
    }

    /// Luminance ([`Rgb::luminance`]) of the flux the light emits (watts), for
    /// power-proportional light selection:
    /// * area: `π·A·L`; point: `4π·I`; spot: `I·∫f dω` with the exact integral of the falloff,
    ///   `2π·I·(1 − (sin c − sin b)/(c − b))`;
    /// * directional: `π·R²·E`, the flux through the bounding-sphere disc;
    /// * constant and image environments: `π·R²·∫L(ω) dω` — the radiance from each direction ω
    ///   crosses the bounding-sphere disc perpendicular to ω (area πR²); for a constant
    ///   environment this is `4π²R²·L`, what [`Light::sample_emission`] emits on average.
    pub fn power(&self, sphere: &BoundingSphere) -> f32 {
        let disc_area = PI * sphere.radius * sphere.radius;
        match self {
            Light::Area(light) => PI * light.area() * light.radiance.luminance(),
            Light::Point(light) => 4.0 * PI * light.intensity.luminance(),
            Light::Spot(light) => light.falloff_solid_angle() * light.intensity.luminance(),
            Light::Directional(light) => disc_area * light.irradiance.luminance(),
            Light::Background(light) => disc_area * 4.0 * PI * light.radiance.luminance(),
            Light::EnvMap(light) => disc_area * light.luminance_integral(),
        }
    }

    /// Samples a point on the light as seen from `receiver` with two uniform numbers.
    /// Returns `None` when nothing is emitted towards the receiver.
    pub fn sample_direct(&self, receiver: Vec3, u: [f32; 2], sphere: &BoundingSphere) -> Option<DirectSample> {
        match self {
            Light::Area(light) => {
                let (point, normal) = light.sample_point(u);
                let to_light = point - receiver;
                let distance_squared = to_light.length_squared();
                let distance = distance_squared.sqrt();
                let direction = to_light / distance;
                let cos_at_light = normal.dot(-direction);
                if cos_at_light < math::COSINE_EPSILON || !distance_squared.is_normal() {
                    return None;
                }
                Some(DirectSample {
                    radiance: light.radiance,
                    direction,
                    distance,
                    direct_pdf: PdfA(light.inv_area).to_solid_angle(distance_squared, cos_at_light),
                    emission_pdf: PdfW(light.inv_area * warp::cosine_hemisphere_pdf(cos_at_light)),
                    cos_at_light,
                })
            }
            Light::Point(light) => {
                let to_light = light.position - receiver;
                let distance_squared = to_light.length_squared();
                let distance = distance_squared.sqrt();
                Some(DirectSample {
                    radiance: light.intensity,
                    direction: to_light / distance,
                    distance,
                    direct_pdf: PdfA(1.0).to_solid_angle(distance_squared, 1.0),
                    emission_pdf: PdfW(warp::UNIFORM_SPHERE_PDF),
                    cos_at_light: 1.0,
                })
            }
            Light::Spot(light) => {
                let to_light = light.position - receiver;
                let distance_squared = to_light.length_squared();
                let distance = distance_squared.sqrt();
                let direction = to_light / distance;
                let falloff = light.falloff(light.axis().dot(-direction));
                if falloff <= 0.0 {
                    return None;
                }
                Some(DirectSample {
                    radiance: light.intensity * falloff,
                    direction,
                    distance,
                    direct_pdf: PdfA(1.0).to_solid_angle(distance_squared, 1.0),
                    emission_pdf: PdfW(light.cone_pdf()),
                    cos_at_light: 1.0,
                })
            }
            Light::Directional(light) => Some(DirectSample {
                radiance: light.irradiance,
                direction: -light.direction,
                distance: f32::INFINITY,
                direct_pdf: PdfW(1.0),
                emission_pdf: PdfW(disc_pdf(sphere)),
                cos_at_light: 1.0,
            }),
            Light::Background(light) => {
                let direction = warp::uniform_sphere(u);
                Some(DirectSample {
                    radiance: light.radiance,
                    direction,
                    distance: f32::INFINITY,
                    direct_pdf: PdfW(warp::UNIFORM_SPHERE_PDF),
                    emission_pdf: PdfW(warp::UNIFORM_SPHERE_PDF * disc_pdf(sphere)),
                    cos_at_light: 1.0,
                })
            }
            Light::EnvMap(light) => {
                let (direction, radiance, pdf) = light.sample(u)?;
                Some(DirectSample {
                    radiance,
                    direction,
                    distance: f32::INFINITY,
                    direct_pdf: PdfW(pdf),
                    emission_pdf: PdfW(pdf * disc_pdf(sphere)),
                    cos_at_light: 1.0,
                })
            }
        }
    }

    /// Samples the start of a light sub-path: `u_position` for the point, `u_direction` for
    /// the direction. A sample with zero `emission_pdf` or black `energy` carries nothing.
    pub fn sample_emission(
        &self,
        u_position: [f32; 2],
        u_direction: [f32; 2],
        sphere: &BoundingSphere,
    ) -> EmissionSample {
        match self {
            Light::Area(light) => {
                let (origin, normal) = light.sample_point(u_position);
                let local = warp::cosine_hemisphere(u_direction);
                let cos_at_light = local.z;
                EmissionSample {
                    energy: light.radiance * cos_at_light,
                    origin,
                    direction: Frame::from_z(normal).to_world(local),
                    emission_pdf: PdfW(light.inv_area * warp::cosine_hemisphere_pdf(cos_at_light)),
                    direct_pdf: PdfA(light.inv_area),
                    cos_at_light,
                }
            }
            Light::Point(light) => EmissionSample {
                energy: light.intensity,
                origin: light.position,
                direction: warp::uniform_sphere(u_direction),
                emission_pdf: PdfW(warp::UNIFORM_SPHERE_PDF),
                direct_pdf: PdfA(1.0),
                cos_at_light: 1.0,
            },
            Light::Spot(light) => {
                // Uniform in the cutoff cone: cos θ uniform in [cos c, 1].
                let cos_theta = 1.0 - u_direction[1] * (1.0 - light.cos_cutoff);
                let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
                let (sin_phi, cos_phi) = (2.0 * PI * u_direction[0]).sin_cos();
                let local = Vec3::new(cos_phi * sin_theta, sin_phi * sin_theta, cos_theta);
                EmissionSample {
                    energy: light.intensity * light.falloff(cos_theta),
                    origin: light.position,
                    direction: light.frame.to_world(local),
                    emission_pdf: PdfW(light.cone_pdf()),
                    direct_pdf: PdfA(1.0),
                    cos_at_light: 1.0,
                }
            }
            Light::Directional(light) => EmissionSample {
                energy: light.irradiance,
                origin: disc_origin(&light.frame, u_position, sphere),
                direction: light.direction,
                emission_pdf: PdfW(disc_pdf(sphere)),
                direct_pdf: PdfA(1.0),
                cos_at_light: 1.0,
            },
            Light::Background(light) => {
                let direction = warp::uniform_sphere(u_direction);
                EmissionSample {
                    energy: light.radiance,
                    origin: disc_origin(&Frame::from_z(direction), u_position, sphere),
                    direction,
                    emission_pdf: PdfW(warp::UNIFORM_SPHERE_PDF * disc_pdf(sphere)),
                    direct_pdf: PdfA(warp::UNIFORM_SPHERE_PDF),
                    cos_at_light: 1.0,
                }
            }
            Light::EnvMap(light) => {
                // The light travels away from the sampled environment direction.
                let Some((towards_light, radiance, pdf)) = light.sample(u_direction) else {
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
        }
    }

    /// Radiance along a ray with unit direction `ray_direction` that hits the light (area
    /// lights) or escapes the scene (environment lights). `normal` is the unit geometric normal
    /// at the hit point, oriented like the emitter's front (for spheres with flipped normals,
    /// inward); triangles and discs use their own (constant) normal, spheres this one, and
    /// infinite lights ignore it. `None` for delta lights, which cannot be hit, and for the
    /// back of area lights.
    pub fn radiance_on_hit(&self, ray_direction: Vec3, normal: Vec3, sphere: &BoundingSphere) -> Option<HitRadiance> {
        match self {
            Light::Area(light) => {
                let front = match light.shape {
                    AreaShape::Triangle(t) => t.normal,
                    AreaShape::Disc { normal, .. } => normal,
                    AreaShape::Sphere { .. } => normal,
                };
                let cos_at_light = front.dot(-ray_direction);
                if cos_at_light <= 0.0 {
                    return None;
                }
                Some(HitRadiance {
                    radiance: light.radiance,
                    direct_pdf: PdfA(light.inv_area),
                    emission_pdf: PdfW(light.inv_area * warp::cosine_hemisphere_pdf(cos_at_light)),
                    cos_at_light,
                })
            }
            Light::Point(_) | Light::Spot(_) | Light::Directional(_) => None,
            Light::Background(light) => Some(HitRadiance {
                radiance: light.radiance,
                direct_pdf: PdfA(warp::UNIFORM_SPHERE_PDF),
                emission_pdf: PdfW(warp::UNIFORM_SPHERE_PDF * disc_pdf(sphere)),
                cos_at_light: 1.0,
            }),
            Light::EnvMap(light) => {
                let (radiance, pdf) = light.evaluate(ray_direction);
                Some(HitRadiance {
                    radiance,
                    direct_pdf: PdfA(pdf),
                    emission_pdf: PdfW(pdf * disc_pdf(sphere)),
                    cos_at_light: 1.0,
                })
            }
        }
    }
}

/// Area density `1/(πR²)` of an origin on the bounding-sphere disc.
fn disc_pdf(sphere: &BoundingSphere) -> f32 {
    warp::CONCENTRIC_DISC_PDF / (sphere.radius * sphere.radius)
}

/// A point on the disc of radius R centred at `center − R·z`, perpendicular to `frame.z`.
fn disc_origin(frame: &Frame, u: [f32; 2], sphere: &BoundingSphere) -> Vec3 {
    let d = warp::concentric_disc(u);
    sphere.center + sphere.radius * (-frame.z + frame.x * d.x + frame.y * d.y)
}

/// Error unless every coordinate of `p` is finite.
fn check_point(what: &str, p: Vec3) -> Result<(), String> {
    if p.is_finite() { Ok(()) } else { Err(format!("{what}: expected finite coordinates, got {p}")) }
}

/// The normalised direction, or an error for a zero or non-finite vector.
fn check_direction(what: &str, d: Vec3) -> Result<Vec3, String> {
    let n = d.normalize_or_zero();
    if d.is_finite() && n != Vec3::ZERO {
        Ok(n)
    } else {
        Err(format!("{what}: expected a non-zero finite vector, got {d}"))
    }
}

/// Error unless every channel is finite and non-negative.
fn check_rgb(what: &str, c: Rgb) -> Result<(), String> {
    if c.is_finite() && c.r >= 0.0 && c.g >= 0.0 && c.b >= 0.0 {
        Ok(())
    } else {
        Err(format!("{what}: expected finite non-negative values, got ({}, {}, {})", c.r, c.g, c.b))
    }
}
