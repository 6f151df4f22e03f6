//! The image-based environment (Mitsuba 3's `envmap`), importance-sampled.

use std::sync::Arc;

use math::{AliasRows, Distribution1D, Frame, PI, PdfA, PdfW, Vec3, warp};
use spectrum::Rgb;

use super::{BoundingSphere, DirectSample, EmissionSample, HitRadiance, disc_origin, disc_pdf};
use crate::desc::TextureImage;

mod compensated;
use compensated::Compensated;

/// An image-based environment (Mitsuba 3's `envmap`), importance-sampled.
///
/// Lookup: the world direction `d` is mapped to the local direction `v = R⁻¹·d` and to
/// `u = atan2(v.x, −v.z)/(2π)` (wrapped into [0,1)), `v = acos(v.y)/π`. As in Mitsuba 3, the
/// image is a grid of samples interpolated bilinearly: pixel `(x, y)` of a `W × H` image sits
/// at `u = (x + ½)/W` (periodic in `u`) and `v = y/(H − 1)` (row 0 at the north pole `v.y = 1`,
/// row `H − 1` at the south pole).
///
/// Sampling (as Mitsuba 3 does, with its own construction here): the density over the
/// sampling square `(s, t)` is the bilinear interpolation of the lattice values
/// `w = luminance × sin θ` (θ of the pixel's row), normalised — so that per steradian it follows
/// the bilinear radiance's luminance within each cell instead of being constant over the cell.
/// A cell is picked in proportion to the mean of its four corners (the integral of the bilinear
/// density over it), then a point within it from the bilinear density ([`math::warp::bilinear`]).
/// The density is positive wherever the radiance is (on the pole rows `sin θ` is taken a
/// quarter row from the pole, so a lit pole row beside a black one keeps a density). A
/// point `(s, t)` with density `p(s, t)` per unit area maps to a direction with density
/// `p / (2π² sin θ)` per steradian.
///
/// Next-event estimation in the path tracer may sample a second, *compensated* density
/// instead ([`Light::sample_direct_compensated`](super::Light::sample_direct_compensated); MIS
/// compensation, Karlík et al. 2019, as pbrt-v4's path tracer samples its image lights): the
/// lattice values are `max(0, luminance − L̄) × sin θ`, with `L̄` the map's mean luminance over
/// the sphere, so directions dimmer than the mean are left to BSDF sampling, which the MIS
/// weights then give the whole weight there (`envmap/compensated.rs`).
#[derive(Clone, Debug, PartialEq)]
pub struct EnvMapLight {
    data: Arc<EnvMapData>,
}

/// One pixel of the map and the sampling density at its lattice point, side by side:
/// [`EnvMapLight::evaluate`] interpolates both from the same four pixels (16 bytes, aligned: a
/// texel never straddles two cache lines).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(align(16))]
struct Texel {
    /// The pixel with the scale applied; negatives clamped to 0.
    radiance: Rgb,
    /// Density per unit area of the sampling square at this lattice point: `w / Z` with
    /// `w = luminance × sin θ` and `Z` the integral of the bilinear `w` over the square (1
    /// everywhere for a black map, which is sampled uniformly).
    density: f32,
}

#[derive(Debug, PartialEq)]
struct EnvMapData {
    width: usize,
    height: usize,
    /// The `W × H` pixels row-major, row 0 at the top, each with the sampling density at its
    /// lattice point.
    texels: Vec<Texel>,
    /// Rotation local → world (columns: images of the local axes).
    to_world: [Vec3; 3],
    /// Picks a row of lattice cells in proportion to the integral of the bilinear density over
    /// it (255 entries for a 512 × 256 map: small enough to stay in cache, so inverted).
    rows: Distribution1D,
    /// For each row of cells, picks a cell in proportion to the integral of the density over
    /// it: one table read per sample (the cumulative sums and their guide were two reads from
    /// memory that is not in cache, measured 9 % of a matpreview render).
    columns: AliasRows,
    /// `½/W`: the offset between the map's `u` and the sampling square's `s`.
    half_texel: f32,
    /// `W` as `f32` (lattice columns per unit of `s`).
    width_f32: f32,
    /// `H − 1` as `f32` (lattice rows per unit of `t`).
    cells_y_f32: f32,
    /// `∫ luminance(L(ω)) dω` over the sphere.
    luminance_integral: f32,
    /// The compensated density, or `None` when no pixel is brighter than the mean (a
    /// constant or black map): then the full density serves both.
    compensated: Option<Compensated>,
}

/// Which of the map's two sampling densities a query uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Density {
    /// `luminance × sin θ`: every technique's.
    Full,
    /// The compensated density where the map has one ([`Compensated`]).
    Compensated,
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

        // Exact integral of the luminance of the bilinear radiance over the sphere (the
        // light's power for light selection). Across a cell the radiance averaged over u is
        // linear in θ, from `a` (upper row) to `b` (lower row); ∫ (a + (b−a)t) sin(θ0 + tΔ) Δ dt
        // = a·k_a + b·k_b.
        let cells_y = height - 1;
        let delta = std::f64::consts::PI / cells_y as f64;
        let cell_phi = 2.0 * std::f64::consts::PI / width as f64;
        let lum = |x: usize, y: usize| pixels[y * width + x].luminance().max(0.0) as f64;
        let mut integral = 0.0f64;
        for j in 0..cells_y {
            let (theta0, theta1) = (j as f64 * delta, (j + 1) as f64 * delta);
            let k_b = ((theta1.sin() - theta0.sin()) / delta - theta1.cos()).max(0.0);
            let k_a = ((theta0.cos() - theta1.cos()) - k_b).max(0.0);
            for i in 0..width {
                let i1 = (i + 1) % width;
                let a = 0.5 * (lum(i, j) + lum(i1, j));
                let b = 0.5 * (lum(i, j + 1) + lum(i1, j + 1));
                integral += cell_phi * (a * k_a + b * k_b);
            }
        }
        // The sampling density's lattice values w = luminance × sin θ, and each cell's weight,
        // the mean of its corners (the integral of the bilinear w over the cell, per unit of
        // cell area). On the pole rows sin θ = 0 would leave no density where the radiance
        // there is positive and the next row black (a bias), so θ is taken at least a quarter
        // row away from the poles. A black map gets w = 1 everywhere (uniform in the square) so
        // that the densities stay valid.
        let row_sin = |j: usize| (j as f64 * delta).clamp(0.25 * delta, std::f64::consts::PI - 0.25 * delta).sin();
        let mut lattice: Vec<f64> =
            (0..width * height).map(|k| lum(k % width, k / width) * row_sin(k / width)).collect();
        let cell_weights = |lattice: &[f64]| -> Vec<f64> {
            let at = |i: usize, j: usize| lattice[j * width + i % width];
            (0..cells_y)
                .flat_map(|j| (0..width).map(move |i| (i, j)))
                .map(|(i, j)| 0.25 * (at(i, j) + at(i + 1, j) + at(i, j + 1) + at(i + 1, j + 1)))
                .collect()
        };
        let mut weights = cell_weights(&lattice);
        if !weights.iter().any(|w| *w > 0.0) {
            lattice.iter_mut().for_each(|w| *w = 1.0);
            weights = cell_weights(&lattice);
        }
        // Z = ∫ bilinear(w) ds dt over the square = the mean cell weight.
        let z = weights.iter().sum::<f64>() / weights.len() as f64;
        let weights: Vec<f32> = weights.iter().map(|w| *w as f32).collect();
        let row_sums: Vec<f32> =
            weights.chunks_exact(width).map(|row| row.iter().map(|w| *w as f64).sum::<f64>() as f32).collect();
        let rows = Distribution1D::new(&row_sums)
            .ok_or_else(|| "environment map: cannot build the sampling distribution".to_string())?;
        // A row without weight is never picked; it gets a uniform table (`AliasRows::new`).
        let columns = AliasRows::new(&weights, width)
            .ok_or_else(|| "environment map: cannot build the sampling distribution".to_string())?;
        let compensated = Compensated::new(&pixels, width, integral, row_sin);
        let texels = pixels
            .iter()
            .zip(&lattice)
            .map(|(radiance, w)| Texel { radiance: *radiance, density: (w / z) as f32 })
            .collect();
        Ok(Self {
            data: Arc::new(EnvMapData {
                width,
                height,
                texels,
                to_world,
                rows,
                columns,
                half_texel: 0.5 / width as f32,
                width_f32: width as f32,
                cells_y_f32: cells_y as f32,
                luminance_integral: integral as f32,
                compensated,
            }),
        })
    }

    /// Radiance arriving from the unit world direction `direction` (pointing away from the
    /// scene, towards the environment).
    pub fn radiance(&self, direction: Vec3) -> Rgb {
        self.evaluate(direction).0
    }

    /// Density per steradian with which [`Light::sample_direct`](super::Light::sample_direct) picks `direction`.
    pub fn pdf(&self, direction: Vec3) -> f32 {
        self.evaluate(direction).1
    }

    /// Radiance from `direction` and its density per steradian, both looked up at the same
    /// point of the map.
    ///
    /// The radiance and the density `p` per unit area of the sampling square are both the
    /// bilinear interpolations at the sampling-square point `(s, t)` (lattice coordinates
    /// `s·W`, periodic, and `t·(H − 1)`) of the four surrounding texels.
    #[inline]
    fn evaluate(&self, direction: Vec3) -> (Rgb, f32) {
        let (radiance, pdf, _) = self.evaluate_with(direction, Density::Full);
        (radiance, pdf)
    }

    /// [`EnvMapLight::evaluate`] with the density `density`: the radiance, the chosen density's
    /// pdf per steradian and the full density's (the same number for [`Density::Full`]).
    #[inline]
    fn evaluate_with(&self, direction: Vec3, density: Density) -> (Rgb, f32, f32) {
        let d = &*self.data;
        let local = self.to_local(direction);
        let sin_theta = (local.x * local.x + local.z * local.z).sqrt();
        let (s, t) = self.square_of(local);
        // Lattice cell (i0, j0) and the position within it. `as usize` maps negative and NaN
        // values to 0, as `Distribution2D` does when it finds the cell of a point.
        // (`as u32` saturates as `as usize` does, and costs less; both sizes fit in `u32`.)
        let x = s * d.width_f32;
        let i0 = (x.max(0.0) as u32).min(d.width as u32 - 1) as usize;
        let fx = (x - i0 as f32).clamp(0.0, 1.0);
        let y = t * d.cells_y_f32;
        let j0 = (y.max(0.0) as u32).min(d.height as u32 - 2) as usize;
        let fy = (y - j0 as f32).clamp(0.0, 1.0);
        let corners = d.corners(i0, j0);
        let (radiance, full_density) = interpolate(corners, corners.map(|texel| texel.density), fx, fy);
        let chosen_density = match d.compensated_for(density) {
            Some(c) => bilinear_value(c.corners(&corners, j0), fx, fy),
            None => full_density,
        };
        // 0 outside the closed unit square (NaN included) and at the poles.
        let inside = sin_theta > 0.0 && (0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&t);
        let per_steradian = |density: f32| if inside { density / (2.0 * PI * PI * sin_theta) } else { 0.0 };
        (radiance, per_steradian(chosen_density), per_steradian(full_density))
    }

    /// `∫ luminance(L(ω)) dω` over the whole sphere (W·m⁻²).
    pub fn luminance_integral(&self) -> f32 {
        self.data.luminance_integral
    }

    /// Samples a direction towards the environment: the unit world direction, its radiance and
    /// its density per steradian, both interpolated at the sampled point from the same four
    /// texels that [`EnvMapLight::evaluate`] (and so [`Light::radiance_on_hit`]) reads for that
    /// direction. Both are continuous, so the two queries agree to rounding (the direction's
    /// round trip through `atan2`/`acos`), and this skips that round trip. `None` when nothing is
    /// emitted from the sampled point (or at the poles, where the density is singular).
    ///
    /// `density` is the density sampled; the sample also reports the density per steradian of
    /// the full density and of `report` at the sampled point (the light pass samples the full
    /// density and needs the compensated one's for its MIS).
    fn sample(&self, u: [f32; 2], density: Density, report: Density) -> Option<EnvSample> {
        let d = &*self.data;
        let compensated = d.compensated_for(density);
        let (rows, columns) = d.tables(compensated);
        let (j0, v) = rows.sample_remapped(u[1]);
        let (i0, w) = columns.sample_remapped(j0, u[0]);
        let corners = d.corners(i0, j0);
        let densities = match compensated {
            None => corners.map(|texel| texel.density),
            Some(c) => c.corners(&corners, j0),
        };
        let f = warp::bilinear([w, v], densities);
        let (fx, fy) = (f.x, f.y);
        let (s, t) = ((i0 as f32 + fx) / d.width_f32, (j0 as f32 + fy) / d.cells_y_f32);
        // θ = πt is half a turn times t; φ = 2π·u_map is u_map turns.
        let mut u_map = s + d.half_texel;
        if u_map >= 1.0 {
            u_map -= 1.0;
        }
        let (sin_theta, cos_theta) = math::sin_cos_turns(0.5 * t.min(1.0));
        if sin_theta.is_nan() || sin_theta <= 0.0 {
            return None;
        }
        let (sin_phi, cos_phi) = math::sin_cos_turns(u_map);
        let local = Vec3::new(sin_phi * sin_theta, cos_theta, -cos_phi * sin_theta);
        let [c0, c1, c2] = d.to_world;
        let direction = (c0 * local.x + c1 * local.y + c2 * local.z).normalize();
        // The same interpolation as `evaluate`, at the sampled point of the cell.
        let (radiance, density) = interpolate(corners, densities, fx, fy);
        let full = match compensated {
            None => density,
            Some(_) => bilinear_value(corners.map(|texel| texel.density), fx, fy),
        };
        let reported = match d.compensated_for(report) {
            Some(c) if compensated.is_none() => bilinear_value(c.corners(&corners, j0), fx, fy),
            Some(_) => density,
            None => full,
        };
        let per_steradian = |density: f32| density / (2.0 * PI * PI * sin_theta);
        let pdf = per_steradian(density);
        (pdf > 0.0 && !radiance.is_black()).then(|| EnvSample {
            direction,
            radiance,
            pdf,
            full_pdf: per_steradian(full),
            reported_pdf: per_steradian(reported),
        })
    }

    /// Prefetch hints ([`math::prefetch()`]) for what [`EnvMapLight::sample`] will read for the
    /// same `u`: the alias slot of the sampled row and the texels of the slot's own cell (its
    /// alias's are only known from the slot). Of the cell's four texels only the two of its
    /// left column are hinted: each shares its cache line with its right neighbour except at a
    /// line's end (16-byte texels: one pair in four), and hinting all four was slower (paired
    /// median 0.976 over 16 rounds on matpreview `pt` for the two; docs/performance.md). A hint
    /// only: no value changes.
    #[inline]
    pub(super) fn prefetch_sample(&self, u: [f32; 2], density: Density) {
        let d = &*self.data;
        let (rows, columns) = d.tables(d.compensated_for(density));
        let (j0, _) = rows.sample_remapped(u[1]);
        let (slot, i0) = columns.slot_of(j0, u[0]);
        math::prefetch(slot);
        for k in [j0 * d.width + i0, (j0 + 1) * d.width + i0] {
            math::prefetch(&d.texels[k]);
        }
    }

    #[inline]
    fn to_local(&self, direction: Vec3) -> Vec3 {
        let [c0, c1, c2] = self.data.to_world;
        Vec3::new(c0.dot(direction), c1.dot(direction), c2.dot(direction))
    }

    /// The point `(s, t)` of the sampling square for a map-local direction: `s = u − ½/W`
    /// (wrapped), `t = v`.
    #[inline]
    fn square_of(&self, v: Vec3) -> (f32, f32) {
        let u = v.x.atan2(-v.z) * (0.5 / PI) - self.data.half_texel;
        let s = fraction(u);
        let s = if s >= 1.0 { 0.0 } else { s };
        let t = v.y.clamp(-1.0, 1.0).acos() / PI;
        (s, t.clamp(0.0, 1.0))
    }
}

impl EnvMapData {
    /// The compensated density when `density` asks for it and the map has one (`None`: the
    /// full density serves).
    #[inline]
    fn compensated_for(&self, density: Density) -> Option<&Compensated> {
        self.compensated.as_ref().filter(|_| density == Density::Compensated)
    }

    /// The tables that pick a cell of the full density, or of `compensated`: the row
    /// distribution and the per-row alias tables.
    #[inline]
    fn tables<'a>(&'a self, compensated: Option<&'a Compensated>) -> (&'a Distribution1D, &'a AliasRows) {
        match compensated {
            Some(c) => (&c.rows, &c.columns),
            None => (&self.rows, &self.columns),
        }
    }

    /// The texels at the corners of lattice cell `(i0, j0)` (`j0 < H − 1`): upper left, upper
    /// right (column `i0 + 1`, wrapping to 0), lower left, lower right.
    /// Always inlined: as a call (which `#[inline]` left it) the four texels came back through
    /// memory and their first reads waited for the stores (matpreview `pt`, paired median 0.989
    /// over 8 rounds against the call; docs/performance.md, "The cell's corners inlined").
    #[inline(always)]
    fn corners(&self, i0: usize, j0: usize) -> [Texel; 4] {
        let i1 = if i0 + 1 == self.width { 0 } else { i0 + 1 };
        let (top, bottom) = (&self.texels[j0 * self.width..], &self.texels[(j0 + 1) * self.width..]);
        [top[i0], top[i1], bottom[i0], bottom[i1]]
    }
}

/// The radiance and a sampling density interpolated bilinearly at `(fx, fy)` in a cell with
/// the `corners` of [`EnvMapData::corners`] and the density's values `densities` there.
#[inline]
fn interpolate([a, b, c, e]: [Texel; 4], densities: [f32; 4], fx: f32, fy: f32) -> (Rgb, f32) {
    let top = a.radiance * (1.0 - fx) + b.radiance * fx;
    let bottom = c.radiance * (1.0 - fx) + e.radiance * fx;
    (top * (1.0 - fy) + bottom * fy, bilinear_value(densities, fx, fy))
}

/// The bilinear interpolation at `(fx, fy)` of four corner values in [`EnvMapData::corners`]'
/// order.
#[inline]
fn bilinear_value(corners: [f32; 4], fx: f32, fy: f32) -> f32 {
    let top = corners[0] * (1.0 - fx) + corners[1] * fx;
    let bottom = corners[2] * (1.0 - fx) + corners[3] * fx;
    top * (1.0 - fy) + bottom * fy
}

/// `u − ⌊u⌋`, bit for bit, without the library `floor` for `u ∈ [−1, 1)` (the range of the
/// map's `u`): there `⌊u⌋` is ±0 or −1, and `u − (±0)` is `u + 0` (both turn −0 into +0),
/// `u − (−1)` is `u + 1`.
#[inline]
fn fraction(u: f32) -> f32 {
    if (0.0..1.0).contains(&u) {
        u + 0.0
    } else if (-1.0..0.0).contains(&u) {
        u + 1.0
    } else {
        u - u.floor()
    }
}

/// A direction sampled from the map ([`EnvMapLight::sample`]).
struct EnvSample {
    /// Unit world direction towards the environment.
    direction: Vec3,
    /// Radiance arriving from it.
    radiance: Rgb,
    /// The sampled density's pdf of `direction`, per steradian.
    pdf: f32,
    /// The full density's pdf, per steradian.
    full_pdf: f32,
    /// The reported density's pdf, per steradian.
    reported_pdf: f32,
}

impl EnvMapLight {
    /// Next-event estimation: a direction importance-sampled from the map.
    pub(super) fn sample_direct(&self, u: [f32; 2], sphere: &BoundingSphere) -> Option<DirectSample> {
        self.sample_direct_with(u, sphere, Density::Full)
    }

    /// [`EnvMapLight::sample_direct`] from the compensated density (the full one when the map
    /// has none): `direct_pdf` is the compensated density's, `emission_pdf` stays the full
    /// density's.
    pub(super) fn sample_direct_compensated(&self, u: [f32; 2], sphere: &BoundingSphere) -> Option<DirectSample> {
        self.sample_direct_with(u, sphere, Density::Compensated)
    }

    fn sample_direct_with(&self, u: [f32; 2], sphere: &BoundingSphere, density: Density) -> Option<DirectSample> {
        let EnvSample { direction, radiance, pdf, full_pdf, .. } = self.sample(u, density, density)?;
        Some(DirectSample {
            radiance,
            direction,
            distance: f32::INFINITY,
            direct_pdf: PdfW(pdf),
            emission_pdf: PdfW(full_pdf * disc_pdf(sphere)),
            cos_at_light: 1.0,
        })
    }

    /// A light sub-path start: an importance-sampled direction (the full density), an origin on
    /// the bounding-sphere disc. `direct_pdf` is `direct`'s density per steradian of the
    /// direction towards the light, the density with which next-event estimation would have
    /// sampled it.
    pub(super) fn sample_emission(
        &self,
        u_position: [f32; 2],
        u_direction: [f32; 2],
        sphere: &BoundingSphere,
        direct: Density,
    ) -> EmissionSample {
        // The light travels away from the sampled environment direction.
        let Some(EnvSample { direction: towards_light, radiance, pdf, reported_pdf, .. }) =
            self.sample(u_direction, Density::Full, direct)
        else {
            return EmissionSample {
                normal: Vec3::ZERO,
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
            normal: Vec3::ZERO,
            energy: radiance,
            origin: disc_origin(&Frame::from_z(direction), u_position, sphere),
            direction,
            emission_pdf: PdfW(pdf * disc_pdf(sphere)),
            direct_pdf: PdfA(reported_pdf),
            cos_at_light: 1.0,
        }
    }

    /// The radiance of a ray escaping the scene along `ray_direction`.
    pub(super) fn radiance_on_hit(&self, ray_direction: Vec3, sphere: &BoundingSphere) -> Option<HitRadiance> {
        self.radiance_on_hit_with(ray_direction, sphere, Density::Full)
    }

    /// [`EnvMapLight::radiance_on_hit`] whose `direct_pdf` is the compensated density's (the
    /// emission pdf stays the full density's).
    pub(super) fn radiance_on_hit_compensated(
        &self,
        ray_direction: Vec3,
        sphere: &BoundingSphere,
    ) -> Option<HitRadiance> {
        self.radiance_on_hit_with(ray_direction, sphere, Density::Compensated)
    }

    fn radiance_on_hit_with(
        &self,
        ray_direction: Vec3,
        sphere: &BoundingSphere,
        density: Density,
    ) -> Option<HitRadiance> {
        let (radiance, pdf, full) = self.evaluate_with(ray_direction, density);
        Some(HitRadiance {
            radiance,
            direct_pdf: PdfA(pdf),
            emission_pdf: PdfW(full * disc_pdf(sphere)),
            cos_at_light: 1.0,
        })
    }

    /// Whether the map has a compensated density (a pixel brighter than the mean).
    pub fn has_compensated_density(&self) -> bool {
        self.data.compensated.is_some()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use math::Rng;

    /// A small map with a black region, a bright spot and a seam that differs across `u = 0`.
    fn test_light(width: u32, height: u32, to_world: [Vec3; 3]) -> EnvMapLight {
        let pixels = (0..width * height)
            .map(|i| {
                let (x, y) = (i % width, i / width);
                if y == 1 && x < width / 2 {
                    Rgb::BLACK
                } else {
                    Rgb::new(1.0 + x as f32, 0.5 + (x * y % 3) as f32, if x == 2 { 40.0 } else { 0.25 })
                }
            })
            .collect();
        EnvMapLight::new(&TextureImage { width, height, pixels }, 1.5, to_world).unwrap()
    }

    /// `evaluate` written plainly (library `floor`, `usize` conversions, modular wrap): the
    /// radiance and the density each from its own bilinear lookup.
    fn evaluate_reference(light: &EnvMapLight, direction: Vec3) -> (Rgb, f32) {
        let d = &*light.data;
        let local = light.to_local(direction);
        let sin_theta = (local.x * local.x + local.z * local.z).sqrt();
        let u = local.x.atan2(-local.z) * (0.5 / PI) - 0.5 / d.width as f32;
        let s = u - u.floor();
        let s = if s >= 1.0 { 0.0 } else { s };
        let t = (local.y.clamp(-1.0, 1.0).acos() / PI).clamp(0.0, 1.0);
        let x = s * d.width as f32;
        let i0 = (x.max(0.0) as usize).min(d.width - 1);
        let fx = (x - i0 as f32).clamp(0.0, 1.0);
        let i1 = (i0 + 1) % d.width;
        let y = t * (d.height - 1) as f32;
        let j0 = (y.max(0.0) as usize).min(d.height - 2);
        let fy = (y - j0 as f32).clamp(0.0, 1.0);
        let px = |i: usize, j: usize| d.texels[j * d.width + i].radiance;
        let top = px(i0, j0) * (1.0 - fx) + px(i1, j0) * fx;
        let bottom = px(i0, j0 + 1) * (1.0 - fx) + px(i1, j0 + 1) * fx;
        let radiance = top * (1.0 - fy) + bottom * fy;
        let w = |i: usize, j: usize| d.texels[j * d.width + i].density;
        let top = w(i0, j0) * (1.0 - fx) + w(i1, j0) * fx;
        let bottom = w(i0, j0 + 1) * (1.0 - fx) + w(i1, j0 + 1) * fx;
        let density = top * (1.0 - fy) + bottom * fy;
        let pdf = if sin_theta > 0.0 { density / (2.0 * PI * PI * sin_theta) } else { 0.0 };
        (radiance, pdf)
    }

    fn same_bits(a: (Rgb, f32), b: (Rgb, f32)) -> bool {
        let bits = |v: (Rgb, f32)| [v.0.r.to_bits(), v.0.g.to_bits(), v.0.b.to_bits(), v.1.to_bits()];
        bits(a) == bits(b)
    }

    #[test]
    fn evaluate_is_bit_identical_to_the_reference() {
        let (c, s) = (0.6f32.cos(), 0.6f32.sin());
        let rotation = [Vec3::new(c, 0.0, -s), Vec3::Y, Vec3::new(s, 0.0, c)];
        let mut rng = Rng::new(3, 5);
        for (w, h, to_world) in [(8, 5, rotation), (1, 2, [Vec3::X, Vec3::Y, Vec3::Z]), (7, 16, rotation)] {
            let light = test_light(w, h, to_world);
            // Random directions, the poles, the seam and axis directions, and sampled directions.
            let mut directions: Vec<Vec3> = (0..20_000)
                .map(|_| {
                    let [a, b] = rng.uniform2();
                    let z = 1.0 - 2.0 * a;
                    let r = (1.0 - z * z).max(0.0).sqrt();
                    Vec3::new(r * (2.0 * PI * b).cos(), z, r * (2.0 * PI * b).sin())
                })
                .collect();
            directions.extend([Vec3::Y, -Vec3::Y, Vec3::X, -Vec3::X, Vec3::Z, -Vec3::Z]);
            directions.extend(
                (0..2000)
                    .filter_map(|_| light.sample(rng.uniform2(), Density::Full, Density::Full).map(|s| s.direction)),
            );
            for direction in directions {
                let world = to_world[0] * direction.x + to_world[1] * direction.y + to_world[2] * direction.z;
                for v in [direction, world] {
                    assert!(same_bits(light.evaluate(v), evaluate_reference(&light, v)), "{v}");
                }
            }
        }
    }

    #[test]
    fn a_sample_reports_what_evaluate_finds_for_its_direction() {
        // `sample` interpolates at the sampled point instead of re-deriving it from the
        // direction, with either density sampled and either reported: the two agree to
        // rounding, relative 1e-4 plus the conditioning of
        // `evaluate`'s lookup near a pole: acos(y) moves by ε / sin θ for a rounding ε of y, and
        // the density and radiance there vary like θ (and with the ill-defined azimuth), so
        // relatively by about ε / sin² θ.
        let (c, s) = (0.6f32.cos(), 0.6f32.sin());
        let rotation = [Vec3::new(c, 0.0, -s), Vec3::Y, Vec3::new(s, 0.0, c)];
        let mut rng = Rng::new(9, 4);
        for (w, h) in [(8, 5), (1, 2), (7, 16), (64, 32)] {
            let light = test_light(w, h, rotation);
            let pairs =
                [Density::Full, Density::Compensated].map(|a| [Density::Full, Density::Compensated].map(|b| (a, b)));
            for (density, report) in pairs.into_iter().flatten() {
                for _ in 0..10_000 {
                    let Some(EnvSample { direction, radiance, pdf, full_pdf: full, reported_pdf }) =
                        light.sample(rng.uniform2(), density, report)
                    else {
                        continue;
                    };
                    let (r, p, full_p) = light.evaluate_with(direction, density);
                    let (_, reported_p, _) = light.evaluate_with(direction, report);
                    let close =
                        |a: f32, b: f32, tolerance: f32| (a - b).abs() <= tolerance * a.abs().max(b.abs()) + 1e-6;
                    let local = light.to_local(direction);
                    let tolerance = 1e-4 + 2e-7 / (local.x * local.x + local.z * local.z);
                    assert!(close(pdf, p, tolerance), "{w}×{h} {density:?}: pdf {pdf} vs {p} at {direction}");
                    assert!(close(full, full_p, tolerance), "{w}×{h} {density:?}: full pdf {full} vs {full_p}");
                    // The radiance is interpolated between corners that may differ a lot (the
                    // test map's seam cell goes from 64 to 1), so its rounding is relative to
                    // the cell's largest corner, not to the value. So is the reported density's
                    // when it is not the sampled one: the sample lands anywhere in its cell,
                    // also where the compensated density is near its zero.
                    let (s, t) = light.square_of(local);
                    let cell = (
                        ((s * w as f32) as usize).min(w as usize - 1),
                        ((t * (h - 1) as f32) as usize).min(h as usize - 2),
                    );
                    let corners = light.data.corners(cell.0, cell.1);
                    let scale = corners.iter().map(|t| t.radiance.max_component()).fold(0.0, f32::max);
                    let lattice = match light.data.compensated_for(report) {
                        Some(c) => c.corners(&corners, cell.1),
                        None => corners.map(|t| t.density),
                    };
                    let sin_theta = (local.x * local.x + local.z * local.z).sqrt();
                    let pdf_scale = lattice.into_iter().fold(0.0, f32::max) / (2.0 * PI * PI * sin_theta);
                    assert!(
                        (reported_pdf - reported_p).abs()
                            <= tolerance * reported_pdf.max(reported_p).max(pdf_scale) + 1e-6,
                        "{w}×{h} {density:?} reporting {report:?}: pdf {reported_pdf} vs {reported_p}"
                    );
                    for (a, b) in [(radiance.r, r.r), (radiance.g, r.g), (radiance.b, r.b)] {
                        assert!(
                            (a - b).abs() <= tolerance * scale + 1e-6,
                            "{w}×{h}: radiance {radiance:?} vs {r:?} at {direction}"
                        );
                    }
                }
            }
        }
    }

    /// The compensated density is the full one's shape minus the mean: zero in the cells whose
    /// four pixels are all at or below the map's mean luminance (while the full density is not),
    /// never sampled there, and absent for a constant map.
    #[test]
    fn the_compensated_density_leaves_the_dim_cells_to_bsdf_sampling() {
        let light = test_light(16, 9, [Vec3::X, Vec3::Y, Vec3::Z]);
        let d = &*light.data;
        let c = d.compensated.as_ref().expect("a map with a bright column has a compensated density");
        let dim_cell = |i: usize, j: usize| {
            d.corners(i, j).iter().zip([j, j, j + 1, j + 1]).all(|(t, row)| c.of(t.radiance, row) == 0.0)
        };
        let mut dim = 0;
        let mut rng = Rng::new(3, 7);
        for _ in 0..50_000 {
            let direction = math::warp::uniform_sphere(rng.uniform2());
            let (s, t) = light.square_of(light.to_local(direction));
            let (i, j) = ((s * 16.0) as usize % 16, ((t * 8.0) as usize).min(7));
            let (_, compensated, full) = light.evaluate_with(direction, Density::Compensated);
            if dim_cell(i, j) {
                dim += 1;
                assert_eq!(compensated, 0.0, "dim cell ({i}, {j}) at {direction}");
                assert!(full > 0.0, "the full density covers ({i}, {j})");
            }
        }
        assert!(dim > 1000, "{dim} directions in dim cells");
        for _ in 0..20_000 {
            if let Some(EnvSample { direction, pdf, .. }) =
                light.sample(rng.uniform2(), Density::Compensated, Density::Compensated)
            {
                let (s, t) = light.square_of(light.to_local(direction));
                let (i, j) = ((s * 16.0) as usize % 16, ((t * 8.0) as usize).min(7));
                assert!(pdf > 0.0 && !dim_cell(i, j), "sampled the dim cell ({i}, {j})");
            }
        }
        let constant = TextureImage { width: 8, height: 4, pixels: vec![Rgb::splat(0.7); 32] };
        let constant = EnvMapLight::new(&constant, 1.0, [Vec3::X, Vec3::Y, Vec3::Z]).unwrap();
        assert!(!constant.has_compensated_density());
        let direction = Vec3::new(0.3, 0.5, -0.2).normalize();
        assert_eq!(constant.evaluate_with(direction, Density::Compensated).1, constant.evaluate(direction).1);
    }

    #[test]
    fn fraction_is_u_minus_its_floor() {
        let mut rng = Rng::new(8, 1);
        let mut us: Vec<f32> = (0..100_000).map(|_| rng.uniform() * 3.0 - 1.5).collect();
        us.extend([0.0, -0.0, 1.0, -1.0, -0.5, 0.5, ONE_BELOW_ONE, -ONE_BELOW_ONE, -1.0000001, f32::MIN_POSITIVE]);
        us.extend([-f32::MIN_POSITIVE, f32::from_bits(1), -f32::from_bits(1), 1e9, -1e9]);
        for u in us {
            assert_eq!(fraction(u).to_bits(), (u - u.floor()).to_bits(), "u = {u}");
        }
        assert!(fraction(f32::NAN).is_nan());
    }

    const ONE_BELOW_ONE: f32 = 1.0 - f32::EPSILON / 2.0;

    #[test]
    fn a_changed_density_is_detected() {
        // Power check of the bit comparison: a density one ulp off is reported.
        let light = test_light(8, 5, [Vec3::X, Vec3::Y, Vec3::Z]);
        let (radiance, pdf) = light.evaluate(Vec3::new(0.3, 0.2, -0.9).normalize());
        assert!(!same_bits((radiance, pdf), (radiance, f32::from_bits(pdf.to_bits() + 1))));
    }
}
