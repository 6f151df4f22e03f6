//! Cameras: the pinhole, the thin lens (depth of field) and the orthographic camera, each with a
//! pixel reconstruction [`Filter`]. They provide primary rays, the projection of points onto the
//! raster (for light tracing) and the densities the integrators' MIS needs.
//!
//! Raster coordinates: `x` grows to the right, `y` grows downward, pixel `(0, 0)` covers
//! `[0,1)²` at the top-left. Pixels are square; the field of view is horizontal.
//!
//! **Densities.** Raster points are sampled, for MIS purposes, with density 1 per pixel (unit
//! area): whatever the filter, every technique uses this same constant image-plane density, so
//! the weights of a path's techniques still sum to one. For the perspective cameras (pinhole and
//! thin lens) the image plane lies at `d = width / (2 tan(fov/2))` pixels, so a primary ray with
//! cosine `cos` to the viewing axis has the solid-angle density `d²/cos³` at its origin; for the
//! thin lens this holds at every lens point (rays through one raster point converge on the plane
//! in focus, whose points map to the raster with the same Jacobian as the pinhole's), and the
//! uniform density of the lens point is the same for primary rays and light-tracing
//! connections, so it cancels between techniques. For the orthographic camera a primary ray
//! starts on the film rectangle with density `1 / A_pixel` per unit film area (`A_pixel` the
//! world-space area of one pixel there): its first vertex has an area density without distance
//! factor, like the first segment from an infinite light (tech report §5.2).

use math::{PdfA, PdfW, Ray, Rng, Vec2, Vec3, warp};

use crate::desc::{CameraDesc, Projection};
use crate::filter::{FilmMode, Filter};

/// How a camera maps raster points to rays.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CameraModel {
    /// Pinhole perspective: every ray starts at the camera position.
    Pinhole,
    /// Thin lens: rays start on a disc of radius `aperture_radius` (scene units) around the
    /// camera position, perpendicular to the viewing direction, and pass through the point of
    /// the plane at `focus_distance` (scene units, along the viewing direction) that the pinhole
    /// ray through the same raster point reaches.
    ThinLens {
        /// Radius of the aperture (scene units, > 0).
        aperture_radius: f32,
        /// Distance of the plane in focus (scene units, > 0).
        focus_distance: f32,
    },
    /// Orthographic: parallel rays along the viewing direction from a film rectangle centred on
    /// the camera position; one pixel is a `pixel_size × pixel_size` square there.
    Orthographic {
        /// Side of one pixel on the film (scene units, > 0).
        pixel_size: f32,
    },
}

/// A camera: position, orthonormal basis, raster size, model and reconstruction filter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Position of the pinhole, the lens centre or the centre of the orthographic film.
    pub position: Vec3,
    /// Unit viewing direction.
    pub forward: Vec3,
    /// Unit vector pointing right in the image (may be mirrored: `right × up = ±forward`).
    pub right: Vec3,
    /// Unit vector pointing up in the image.
    pub up: Vec3,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// The projection.
    pub model: CameraModel,
    /// The pixel reconstruction filter.
    pub filter: Filter,
    /// How camera samples reach the pixels ([`FilmMode::Fis`] unless set; the box filter
    /// behaves the same in both modes).
    pub film: FilmMode,
    /// `tan(fov/2)` of the perspective models (unused by the orthographic one).
    tan_half_fov: f32,
    /// Distance of the image plane from the pinhole, in pixels: `width / (2 tan(fov/2))`
    /// (perspective models; infinite for the orthographic one).
    image_plane_distance: f32,
}

/// A primary ray sampled for a pixel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrimarySample {
    /// The ray (starting exactly on the pinhole, lens or film).
    pub ray: Ray,
    /// The raster position (pixels) it passes through: pixel centre + filter offset.
    pub raster: Vec2,
    /// The filter weight `(f/∫f)/pdf` the sample's radiance is multiplied by (1 for the box).
    pub weight: f32,
}

/// The density with which the camera starts a sub-path along a primary ray, for MIS
/// (image-plane density 1 per pixel).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PrimaryDensity {
    /// Perspective: a solid-angle density at the ray origin, converted to area at the first
    /// hit with `cos/distance²`.
    SolidAngle(PdfW),
    /// Orthographic: an area density on the film plane (per scene unit²); at the first hit it
    /// becomes `density × cos` without a distance factor.
    Area(PdfA),
}

/// A connection of a surface point to the camera (light tracing, t = 1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraConnection {
    /// The raster position (pixels) the point projects to; may lie up to the filter radius
    /// outside the image.
    pub raster: Vec2,
    /// The camera vertex: the pinhole, the sampled lens point, or the film point.
    pub lens_point: Vec3,
    /// Unit direction from the surface point towards `lens_point`.
    pub direction: Vec3,
    /// Distance from the surface point to `lens_point` (scene units).
    pub distance: f32,
    density: ConnectionDensity,
}

/// How a connection's area density at the surface point follows from the cosine there.
#[derive(Clone, Copy, Debug, PartialEq)]
enum ConnectionDensity {
    /// Perspective: solid-angle density at the lens point and the squared distance.
    SolidAngle { pdf: PdfW, distance_squared: f32 },
    /// Orthographic: film-plane density (per scene unit²), projected along the axis.
    Film(PdfA),
}

impl CameraConnection {
    /// Density per unit area at the surface point (per scene unit²) with which the camera's
    /// primary rays (image-plane density 1 per pixel) sample it, given the cosine between the
    /// surface normal and [`CameraConnection::direction`]: `d²/cos_cam³ · |cos|/distance²` for
    /// the perspective models, `|cos| / A_pixel` for the orthographic one.
    pub fn area_pdf(&self, cos_at_point: f32) -> PdfA {
        match self.density {
            ConnectionDensity::SolidAngle { pdf, distance_squared } => pdf.to_area(distance_squared, cos_at_point),
            ConnectionDensity::Film(pdf) => PdfA(pdf.0 * cos_at_point.abs()),
        }
    }
}

impl Camera {
    /// A pinhole camera at `position` looking along `forward` with up hint `up_hint`, horizontal
    /// field of view `fov_degrees`, for a `width × height` raster, with the box filter. The
    /// basis is `right = normalize(up_hint × −forward)`, `up = −forward × right`.
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
            model: CameraModel::Pinhole,
            filter: Filter::Box,
            film: FilmMode::Fis,
            tan_half_fov,
            image_plane_distance: width as f32 / (2.0 * tan_half_fov),
        }
    }

    /// The camera a scene description asks for, for a `width × height` raster, with the box
    /// filter (see [`Camera::with_filter`]). The basis is re-orthonormalised (`up` against
    /// `forward`, `right` from both) keeping the handedness of the given `right`, so mirrored
    /// cameras stay mirrored. Returns a message naming the problem for an empty raster,
    /// non-finite or degenerate vectors, a field of view outside (0°, 180°), or a non-positive
    /// aperture, focus distance or orthographic width.
    pub fn from_desc(desc: &CameraDesc, width: u32, height: u32) -> Result<Camera, String> {
        if width == 0 || height == 0 {
            return Err(format!("the image must have at least one pixel, got {width}x{height}"));
        }
        let finite = |name: &str, v: Vec3| {
            if v.is_finite() { Ok(v) } else { Err(format!("camera {name} is not finite: {v}")) }
        };
        let position = finite("position", desc.position)?;
        let forward =
            finite("forward direction", desc.forward)?.try_normalize().ok_or("camera forward direction is zero")?;
        let up = finite("up direction", desc.up)?;
        let up = (up - forward * forward.dot(up))
            .try_normalize()
            .ok_or_else(|| format!("camera up direction {up} is zero or parallel to the viewing direction"))?;
        let right = finite("right direction", desc.right)?;
        let standard = up.cross(-forward);
        let handedness = right.dot(standard);
        if handedness.abs() < 0.5 * right.length() || right.length() == 0.0 {
            return Err(format!(
                "camera right direction {right} is not perpendicular to the viewing direction {forward} and up {up}"
            ));
        }
        let right = if handedness > 0.0 { standard } else { -standard };
        let positive = |name: &str, v: f32| {
            if v.is_finite() && v > 0.0 {
                Ok(v)
            } else {
                Err(format!("camera {name} must be a finite positive number, got {v}"))
            }
        };
        let fov = |degrees: f32| {
            if degrees.is_finite() && degrees > 0.0 && degrees < 180.0 {
                Ok((degrees.to_radians() * 0.5).tan())
            } else {
                Err(format!(
                    "camera horizontal field of view must lie strictly between 0 and 180 degrees, got {degrees}"
                ))
            }
        };
        let (model, tan_half_fov) = match desc.projection {
            Projection::Perspective { horizontal_fov_degrees } => (CameraModel::Pinhole, fov(horizontal_fov_degrees)?),
            Projection::ThinLens { horizontal_fov_degrees, aperture_radius, focus_distance } => (
                CameraModel::ThinLens {
                    aperture_radius: positive("aperture radius", aperture_radius)?,
                    focus_distance: positive("focus distance", focus_distance)?,
                },
                fov(horizontal_fov_degrees)?,
            ),
            Projection::Orthographic { width: film_width } => {
                let film_width = positive("orthographic width", film_width)?;
                (CameraModel::Orthographic { pixel_size: film_width / width as f32 }, 0.0)
            }
        };
        let image_plane_distance = match model {
            CameraModel::Orthographic { .. } => f32::INFINITY,
            _ => width as f32 / (2.0 * tan_half_fov),
        };
        Ok(Self {
            position,
            forward,
            right,
            up,
            width,
            height,
            model,
            filter: Filter::Box,
            film: FilmMode::Fis,
            tan_half_fov,
            image_plane_distance,
        })
    }

    /// The same camera with reconstruction filter `filter`.
    pub fn with_filter(self, filter: Filter) -> Self {
        Self { filter, ..self }
    }

    /// The same camera with film mode `film`.
    pub fn with_film(self, film: FilmMode) -> Self {
        Self { film, ..self }
    }

    /// Whether camera samples are splatted to the pixels around them ([`FilmMode::Splat`] with a
    /// filter other than the box); otherwise every camera sample counts for its own pixel.
    pub fn splats_camera_samples(&self) -> bool {
        self.film == FilmMode::Splat && !self.filter.is_box()
    }

    /// Under [`FilmMode::Splat`], the weight `f(raster − c_j) / N_j` (per pixel², `N_j` the
    /// expected weight sum over the image, [`Filter::clipped_integral_1d`] on both axes) with
    /// which a sample at `raster` (pixels) counts for pixel `(x, y)` (centre `c_j`).
    pub fn splat_weight(&self, raster: Vec2, x: u32, y: u32) -> f32 {
        let (cx, cy) = (x as f32 + 0.5, y as f32 + 0.5);
        let f = self.filter.profile_1d(raster.x - cx) * self.filter.profile_1d(raster.y - cy);
        if f == 0.0 {
            return 0.0;
        }
        f / self.splat_normalization(x, y)
    }

    /// `N_j` of pixel `(x, y)` under [`FilmMode::Splat`] (pixels²): `∫_image f(x − c_j) dx`.
    pub fn splat_normalization(&self, x: u32, y: u32) -> f32 {
        let nx = self.filter.clipped_integral_1d(x as f32 + 0.5, self.width as f32);
        let ny = self.filter.clipped_integral_1d(y as f32 + 0.5, self.height as f32);
        (nx * ny) as f32
    }

    /// Number of pixels.
    pub fn pixel_count(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// Whether primary rays and light-tracing connections need two uniform numbers for a lens
    /// point (the thin lens only; the pinhole and the orthographic camera draw none).
    pub fn needs_lens_sample(&self) -> bool {
        matches!(self.model, CameraModel::ThinLens { .. })
    }

    /// A raster position in pixel `(x, y)` from `u ∈ [0,1)²` through the filter: the pixel
    /// centre plus a sampled offset, and the filter weight `(f/∫f)/pdf`. With the box filter
    /// or when splatting ([`Camera::splats_camera_samples`]) this is exactly `(x + u₀, y + u₁)`
    /// with weight 1 (the filter is applied when the sample is spread over the pixels).
    pub fn sample_pixel(&self, x: u32, y: u32, u: [f32; 2]) -> (Vec2, f32) {
        if self.filter.is_box() || self.film == FilmMode::Splat {
            return (Vec2::new(x as f32 + u[0], y as f32 + u[1]), 1.0);
        }
        let (offset, weight) = self.filter.sample(u);
        (Vec2::new(x as f32 + 0.5, y as f32 + 0.5) + offset, weight)
    }

    /// Samples a primary ray for pixel `(x, y)`: the raster position, then two numbers from
    /// `rng` for the lens point if [`Camera::needs_lens_sample`].
    ///
    /// The raster position is `(x, y) + film_offset` when camera samples are splatted
    /// ([`Camera::splats_camera_samples`]): every pixel of an iteration shares one offset,
    /// uniform in `[0,1)²`, so each sample is still uniform in its pixel (the estimate stays
    /// unbiased) while the weight sum a pixel receives from its neighbours is almost constant
    /// (see `render::splat_frame`). Otherwise it takes two numbers from `rng`.
    pub fn sample_primary(&self, x: u32, y: u32, film_offset: [f32; 2], rng: &mut Rng) -> PrimarySample {
        let u = if self.splats_camera_samples() { film_offset } else { rng.uniform2() };
        let (raster, weight) = self.sample_pixel(x, y, u);
        let ray = if self.needs_lens_sample() {
            self.generate_ray_through_lens(raster, rng.uniform2())
        } else {
            self.generate_ray(raster)
        };
        PrimarySample { ray, raster, weight }
    }

    /// Position on the plane at unit distance along the axis (perspective) of raster point
    /// `raster`, as coordinates along `right` and `up`.
    #[inline]
    fn perspective_plane(&self, raster: Vec2) -> (f32, f32) {
        let w = self.width as f32;
        let h = self.height as f32;
        let x = self.tan_half_fov * (2.0 * raster.x / w - 1.0);
        let y = self.tan_half_fov * (2.0 * raster.y / h - 1.0) * (h / w);
        (x, y)
    }

    /// Position on the orthographic film of raster point `raster`, as coordinates along
    /// `right` and `up` (scene units).
    #[inline]
    fn film_plane(&self, raster: Vec2, pixel_size: f32) -> (f32, f32) {
        let x = (raster.x - 0.5 * self.width as f32) * pixel_size;
        let y = (raster.y - 0.5 * self.height as f32) * pixel_size;
        (x, y)
    }

    /// The primary ray through raster point `raster` (pixels, any value) and the centre of the
    /// lens: from the pinhole (also the thin lens' centre ray) or from the film point
    /// (orthographic).
    pub fn generate_ray(&self, raster: Vec2) -> Ray {
        match self.model {
            CameraModel::Orthographic { pixel_size } => {
                let (x, y) = self.film_plane(raster, pixel_size);
                Ray::new(self.position + x * self.right - y * self.up, self.forward)
            }
            _ => {
                let (x, y) = self.perspective_plane(raster);
                let direction = (self.forward + x * self.right - y * self.up).normalize();
                Ray::new(self.position, direction)
            }
        }
    }

    /// The point on the lens (scene units) for `u ∈ [0,1)²`: uniform on the aperture disc
    /// (concentric mapping), the camera position for the other models.
    pub fn lens_point(&self, u: [f32; 2]) -> Vec3 {
        match self.model {
            CameraModel::ThinLens { aperture_radius, .. } => {
                let p = warp::concentric_disc(u) * aperture_radius;
                self.position + p.x * self.right + p.y * self.up
            }
            _ => self.position,
        }
    }

    /// The primary ray through raster point `raster` (pixels) and the lens point of `u_lens`
    /// (thin lens; ignored by the other models, whose ray is [`Camera::generate_ray`]'s).
    pub fn generate_ray_through_lens(&self, raster: Vec2, u_lens: [f32; 2]) -> Ray {
        match self.model {
            CameraModel::ThinLens { focus_distance, .. } => {
                let (x, y) = self.perspective_plane(raster);
                let focus = self.position + focus_distance * (self.forward + x * self.right - y * self.up);
                let origin = self.lens_point(u_lens);
                Ray::new(origin, (focus - origin).normalize())
            }
            _ => self.generate_ray(raster),
        }
    }

    /// The density of a primary ray along unit `direction` for MIS (image-plane density 1 per
    /// pixel): solid angle `d²/cos³` for the perspective models, area `1/A_pixel` on the film
    /// for the orthographic one.
    pub fn primary_density(&self, direction: Vec3) -> PrimaryDensity {
        match self.model {
            CameraModel::Orthographic { pixel_size } => PrimaryDensity::Area(PdfA(1.0 / (pixel_size * pixel_size))),
            _ => PrimaryDensity::SolidAngle(self.solid_angle_pdf(self.forward.dot(direction))),
        }
    }

    /// Raster position of `point` projected through the lens centre (along the axis for the
    /// orthographic camera), without bounds check; `None` behind the camera.
    #[inline]
    fn project_centre(&self, point: Vec3) -> Option<Vec2> {
        let d = point - self.position;
        let z = d.dot(self.forward);
        if z <= 0.0 {
            return None;
        }
        let w = self.width as f32;
        let h = self.height as f32;
        Some(match self.model {
            CameraModel::Orthographic { pixel_size } => {
                Vec2::new(d.dot(self.right) / pixel_size + 0.5 * w, 0.5 * h - d.dot(self.up) / pixel_size)
            }
            _ => {
                let x = d.dot(self.right) / z;
                let y = d.dot(self.up) / z;
                Vec2::new((x / self.tan_half_fov + 1.0) * 0.5 * w, (1.0 - y / (self.tan_half_fov * (h / w))) * 0.5 * h)
            }
        })
    }

    /// The raster position (pixels) onto which `point` projects through the lens centre (along
    /// the axis for the orthographic camera), or `None` when it is behind the camera or outside
    /// the image `[0, width) × [0, height)`.
    pub fn raster_position(&self, point: Vec3) -> Option<Vec2> {
        let raster = self.project_centre(point)?;
        let (w, h) = (self.width as f32, self.height as f32);
        (raster.x >= 0.0 && raster.x < w && raster.y >= 0.0 && raster.y < h).then_some(raster)
    }

    /// Whether a raster position contributes to some pixel: inside the image for the box
    /// filter and under [`FilmMode::Splat`] (whose pixels integrate over the image only),
    /// otherwise within the filter radius of some pixel centre (up to `radius − 0.5` pixels
    /// outside the image).
    pub fn accepts_raster(&self, raster: Vec2) -> bool {
        let (w, h) = (self.width as f32, self.height as f32);
        if self.filter.is_box() || self.film == FilmMode::Splat {
            return raster.x >= 0.0 && raster.x < w && raster.y >= 0.0 && raster.y < h;
        }
        let margin = self.filter.radius() - 0.5;
        raster.x > -margin && raster.x < w + margin && raster.y > -margin && raster.y < h + margin
    }

    /// Connects surface point `point` to the camera (light tracing, t = 1): the lens point
    /// (from `u_lens` for the thin lens, ignored otherwise), the raster position the point
    /// projects to through it, the direction and distance to it and the density with which
    /// primary rays sample the point. `None` when the point is behind the camera or projects
    /// where no pixel's filter reaches ([`Camera::accepts_raster`]).
    pub fn connect(&self, point: Vec3, u_lens: [f32; 2]) -> Option<CameraConnection> {
        match self.model {
            CameraModel::Pinhole => {
                let raster = self.project_centre(point).filter(|r| self.accepts_raster(*r))?;
                let to_camera = self.position - point;
                let distance = to_camera.length();
                let direction = to_camera / distance;
                let pdf = self.solid_angle_pdf(self.forward.dot(-direction));
                let density = ConnectionDensity::SolidAngle { pdf, distance_squared: distance * distance };
                Some(CameraConnection { raster, lens_point: self.position, direction, distance, density })
            }
            CameraModel::ThinLens { focus_distance, .. } => {
                let lens_point = self.lens_point(u_lens);
                let to_point = point - lens_point;
                let distance = to_point.length();
                let outgoing = to_point / distance;
                let cos = self.forward.dot(outgoing);
                if cos.is_nan() || cos <= 0.0 {
                    return None;
                }
                // Where the ray from the lens point through `point` crosses the plane in focus.
                let focus = lens_point + outgoing * (focus_distance / cos) - self.position;
                let x = focus.dot(self.right) / focus_distance;
                let y = focus.dot(self.up) / focus_distance;
                let (w, h) = (self.width as f32, self.height as f32);
                let raster = Vec2::new(
                    (x / self.tan_half_fov + 1.0) * 0.5 * w,
                    (1.0 - y / (self.tan_half_fov * (h / w))) * 0.5 * h,
                );
                if !self.accepts_raster(raster) {
                    return None;
                }
                let density = ConnectionDensity::SolidAngle {
                    pdf: self.solid_angle_pdf(cos),
                    distance_squared: distance * distance,
                };
                Some(CameraConnection { raster, lens_point, direction: -outgoing, distance, density })
            }
            CameraModel::Orthographic { pixel_size } => {
                let raster = self.project_centre(point).filter(|r| self.accepts_raster(*r))?;
                let d = point - self.position;
                let distance = d.dot(self.forward);
                let lens_point = point - distance * self.forward;
                let density = ConnectionDensity::Film(PdfA(1.0 / (pixel_size * pixel_size)));
                Some(CameraConnection { raster, lens_point, direction: -self.forward, distance, density })
            }
        }
    }

    /// The pixels a raster position contributes to, with the filter's normalised value
    /// `f(raster − centre)/∫f` (per pixel²) for each ([`Camera::splat_weight`]
    /// `f(raster − centre)/N_j` under [`FilmMode::Splat`]): for the box filter the one pixel the
    /// position lies in (weight 1), otherwise every pixel whose centre lies within the filter
    /// radius on both axes (pixels with a zero filter value included).
    pub fn filter_pixels(&self, raster: Vec2) -> impl Iterator<Item = (u32, f32)> + '_ {
        let (w, h) = (self.width, self.height);
        let (x_range, y_range) = if self.filter.is_box() {
            let x = (raster.x.max(0.0) as u32).min(w.saturating_sub(1));
            let y = (raster.y.max(0.0) as u32).min(h.saturating_sub(1));
            ((x, x), (y, y))
        } else {
            let r = self.filter.radius();
            let range = |v: f32, n: u32| {
                let lo = (v - 0.5 - r).ceil().max(0.0) as u32;
                let hi = (v - 0.5 + r).floor().min(n as f32 - 1.0);
                if hi < 0.0 { (1, 0) } else { (lo, hi as u32) }
            };
            (range(raster.x, w), range(raster.y, h))
        };
        let is_box = self.filter.is_box();
        let splat = self.film == FilmMode::Splat;
        (y_range.0..=y_range.1).flat_map(move |y| {
            (x_range.0..=x_range.1).map(move |x| {
                let value = if is_box {
                    1.0
                } else if splat {
                    self.splat_weight(raster, x, y)
                } else {
                    self.filter.eval_normalized(raster - Vec2::new(x as f32 + 0.5, y as f32 + 0.5))
                };
                (y * w + x, value)
            })
        })
    }

    /// Radius (scene units) of a disc with the area of one pixel's footprint, seen along the
    /// centre ray `ray` of the pixel at hit distance `distance`, perpendicular to the ray:
    /// `distance · sqrt(cos³/π) / d` for the perspective models (cos to the axis, d the image
    /// plane distance in pixels), `sqrt(A_pixel/π)` for the orthographic one.
    pub fn footprint_radius(&self, ray: &Ray, distance: f32) -> f32 {
        match self.model {
            CameraModel::Orthographic { pixel_size } => pixel_size / math::PI.sqrt(),
            _ => {
                let cos = self.forward.dot(ray.direction);
                distance * (cos * cos * cos / math::PI).sqrt() / self.image_plane_distance
            }
        }
    }

    /// Distance of the image plane from the pinhole, in pixels (one pixel has unit area there);
    /// infinite for the orthographic camera.
    pub fn image_plane_distance(&self) -> f32 {
        self.image_plane_distance
    }

    /// Density per unit solid angle of a perspective primary ray with cosine `cos_at_camera`
    /// to the viewing axis, when raster points are sampled with unit density per pixel:
    /// `d² / cos³` (the image plane at distance `d` pixels). Meaningless for the orthographic
    /// camera (see [`Camera::primary_density`]).
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
