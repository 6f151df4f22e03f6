//! Scene descriptions: the plain data a scene file loader produces (Mitsuba 3 XML, pbrt-v4) and
//! [`crate::Scene::from_description`] turns into a renderable scene.
//!
//! Everything here is in world space and already resolved: transforms applied, references
//! replaced by indices, files read, parameters substituted. The loaders live in the `io` crate;
//! this crate never touches the file system.
//!
//! Units: lengths in scene units, angles in degrees where the field name says so, radiance in
//! W·m⁻²·sr⁻¹ (linear RGB), intensity in W·sr⁻¹, irradiance in W·m⁻². An emitter may also
//! carry its spectrum ([`EmissionSpectra`]), which spectral rendering uses instead of upsampling
//! its RGB value.

use std::collections::BTreeMap;
use std::sync::Arc;

use math::{Vec2, Vec3};
use spectrum::Rgb;
use spectrum::tabulated::Tabulated;

use crate::material::Material;
use crate::texture::Texture;

/// A linear-RGB image used as a texture or an environment map. Row-major, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct TextureImage {
    /// Width in pixels (≥ 1).
    pub width: u32,
    /// Height in pixels (≥ 1).
    pub height: u32,
    /// `width × height` linear RGB values (sRGB-encoded files are decoded by the loader).
    pub pixels: Vec<Rgb>,
}

impl TextureImage {
    /// The pixel at column `x`, row `y` (row 0 at the top).
    #[inline]
    pub fn pixel(&self, x: u32, y: u32) -> Rgb {
        self.pixels[(y * self.width + x) as usize]
    }
}

/// A 2D affine map of texture coordinates, `uv' = m · uv + t` (Mitsuba's `to_uv`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvTransform {
    /// Columns of the 2×2 linear part.
    pub columns: [Vec2; 2],
    /// Translation.
    pub translation: Vec2,
}

impl UvTransform {
    /// The identity.
    pub const IDENTITY: UvTransform =
        UvTransform { columns: [Vec2::new(1.0, 0.0), Vec2::new(0.0, 1.0)], translation: Vec2::ZERO };

    /// Applies the map.
    #[inline]
    pub fn apply(&self, uv: Vec2) -> Vec2 {
        self.columns[0] * uv.x + self.columns[1] * uv.y + self.translation
    }
}

/// The geometry of a shape, in world space.
#[derive(Clone, Debug, PartialEq)]
pub enum Geometry {
    /// A triangle mesh.
    Mesh(MeshData),
    /// An analytic sphere; its geometric normal points outward (inward when `flip_normals`).
    Sphere {
        /// Centre.
        center: Vec3,
        /// Radius (> 0).
        radius: f32,
        /// Normals point inward (Mitsuba's `flip_normals`).
        flip_normals: bool,
    },
    /// An analytic disc: the unit disc `x² + y² ≤ 1, z = 0` mapped by `center + x·axis_u +
    /// y·axis_v`. Its geometric normal is `normalize(axis_u × axis_v)` (flipped when
    /// `flip_normals`). Non-orthogonal or unequal axes give an ellipse.
    Disk {
        /// Centre.
        center: Vec3,
        /// Image of the local x axis (its length is the radius along it).
        axis_u: Vec3,
        /// Image of the local y axis.
        axis_v: Vec3,
        /// Flip the normal.
        flip_normals: bool,
    },
}

/// A triangle mesh in world space.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshData {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Per-vertex shading normals (unit length), empty when the mesh has none. Triangles then
    /// shade with their geometric normal.
    pub normals: Vec<Vec3>,
    /// Per-vertex texture coordinates, empty when the mesh has none.
    pub uvs: Vec<Vec2>,
    /// Vertex indices of each triangle; the geometric normal follows the right-hand rule
    /// `(p1 − p0) × (p2 − p0)`.
    pub triangles: Vec<[u32; 3]>,
    /// Extra per-vertex or per-face values (Mitsuba's mesh attributes, e.g. vertex colours),
    /// read by [`Texture::MeshAttribute`].
    pub attributes: Vec<MeshAttribute>,
}

/// A named value per vertex or per triangle of a mesh (Mitsuba's `vertex_<name>` and
/// `face_<name>` attributes). Values are unitless; one-component attributes are stored with
/// the value in all three channels.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshAttribute {
    /// The name as a `mesh_attribute` texture refers to it: `vertex_<name>` or `face_<name>`.
    pub name: String,
    /// 1 or 3.
    pub components: u8,
    /// One value per vertex (`vertex_` attributes, interpolated barycentrically) or per
    /// triangle (`face_` attributes, constant over the triangle).
    pub values: Vec<Rgb>,
}

impl MeshAttribute {
    /// Whether the attribute has one value per triangle rather than per vertex.
    pub fn per_face(&self) -> bool {
        self.name.starts_with("face_")
    }
}

impl MeshData {
    /// Checks indices and attribute counts; returns a message naming the first problem.
    pub fn validate(&self) -> Result<(), String> {
        let n = self.positions.len();
        if !self.normals.is_empty() && self.normals.len() != n {
            return Err(format!("{} normals for {} vertices", self.normals.len(), n));
        }
        if !self.uvs.is_empty() && self.uvs.len() != n {
            return Err(format!("{} texture coordinates for {} vertices", self.uvs.len(), n));
        }
        if let Some((i, t)) = self.triangles.iter().enumerate().find(|(_, t)| t.iter().any(|&v| v as usize >= n)) {
            return Err(format!("triangle {i} refers to vertex {:?}, but there are {n} vertices", t));
        }
        if let Some(i) = self.positions.iter().position(|p| !p.is_finite()) {
            return Err(format!("vertex {i} has a non-finite position"));
        }
        for a in &self.attributes {
            let (expected, per) = if a.per_face() {
                (self.triangles.len(), "triangles")
            } else if a.name.starts_with("vertex_") {
                (n, "vertices")
            } else {
                return Err(format!("mesh attribute `{}` must start with `vertex_` or `face_`", a.name));
            };
            if a.values.len() != expected {
                return Err(format!("mesh attribute `{}` has {} values for {expected} {per}", a.name, a.values.len()));
            }
        }
        Ok(())
    }
}

/// A shape with its material and, when it emits, its emitted radiance.
#[derive(Clone, Debug, PartialEq)]
pub struct ShapeDesc {
    /// Name for messages (the file's id, or the shape type and index).
    pub name: String,
    /// Geometry in world space.
    pub geometry: Geometry,
    /// Index into [`SceneDescription::materials`].
    pub material: u32,
    /// Radiance emitted from the front side (the side the geometric normal points to), if the
    /// shape is an area emitter. Emitters are one-sided, as in Mitsuba.
    pub emission: Option<Rgb>,
    /// Opacity texture (unitless, in [0, 1]; see [`crate::alpha::AlphaMask`]) of an alpha-masked
    /// shape (Mitsuba's `mask` BSDF, pbrt's shape `alpha`). Emitters cannot be masked.
    pub alpha: Option<Texture>,
}

/// How a [`LightDesc::Projector`]'s image becomes intensity.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ProjectorModel {
    /// Mitsuba 3's `projector`: the image is the irradiance the image plane (at distance 1)
    /// receives, divided by π: intensity `π·scale·E(u, v)/cos³θ` (W/sr).
    Irradiance,
    /// pbrt-v4's `projection` light: the image is the intensity itself, `scale·E(u, v)` (W/sr),
    /// with no falloff across the image.
    Intensity,
}

/// A light that is not attached to a shape.
#[derive(Clone, Debug, PartialEq)]
pub enum LightDesc {
    /// Isotropic point light.
    Point {
        /// Position.
        position: Vec3,
        /// Radiant intensity (W/sr).
        intensity: Rgb,
    },
    /// Spot light at `position` shining along `direction`: full intensity within
    /// `beam_width_degrees` of the axis, falling smoothly to zero at `cutoff_degrees`
    /// (Mitsuba's `spot`: both angles are half-angles from the axis).
    Spot {
        /// Position.
        position: Vec3,
        /// Unit axis.
        direction: Vec3,
        /// Intensity on the axis (W/sr).
        intensity: Rgb,
        /// Half-angle where the falloff ends (degrees).
        cutoff_degrees: f32,
        /// Half-angle where the falloff begins (degrees, ≤ cutoff).
        beam_width_degrees: f32,
        /// An image projected over the cone (Mitsuba's spot `texture`), if any.
        texture: Option<SpotTexture>,
    },
    /// A projector (Mitsuba's `projector`, pbrt-v4's `projection` light): a point at
    /// `position` projecting `irradiance` through a pinhole, as a perspective camera with the
    /// same frame and field of view would see it. The image plane lies at distance 1 along
    /// `frame[2]`; a direction with local coordinates `(x, y, z)` (`z > 0`) looks up
    /// `u = ½ − ½·x/(z·t)`, `v = ½ − ½·a·y/(z·t)`, `t = tan(fov_x/2)`, `a` = `aspect`, and
    /// carries the intensity of `model`: `π·scale·E(u, v)/cos³θ` (W/sr), so that the image
    /// plane receives the irradiance `π·scale·E` (Mitsuba 3), or `scale·E(u, v)` (pbrt-v4).
    Projector {
        /// How the image becomes intensity.
        model: ProjectorModel,
        /// Position of the pinhole.
        position: Vec3,
        /// World images of the local axes: `x` (the image's left), `y` (its up), `z` (the
        /// optical axis); orthonormal.
        frame: [Vec3; 3],
        /// The projected image (unitless texture over uv ∈ [0, 1]², row 0 at the top).
        irradiance: Arc<Texture>,
        /// Factor applied to the image.
        scale: f32,
        /// Full horizontal field of view (degrees, in (0, 180)).
        fov_x_degrees: f32,
        /// Image width / height.
        aspect: f32,
    },
    /// pbrt-v4's goniometric light: a point at `position` whose intensity along the unit world
    /// direction `d` is `intensity · m(s)`, with `m` the mean of the R, G and B channels of the
    /// square `image` at its nearest texel to `s`, the equal-area octahedral square point of the
    /// local direction `(d·frame[0], d·frame[1], d·frame[2])` (the image's centre is `frame[2]`).
    Goniometric {
        /// Position.
        position: Vec3,
        /// World images of the map's local axes; orthonormal.
        frame: [Vec3; 3],
        /// The intensity image (unitless; square, row 0 at the top, i.e. `s.y = 0`).
        image: Arc<TextureImage>,
        /// Factor applied to the image's values (W/sr per channel).
        intensity: Rgb,
    },
    /// Directional light travelling along `direction`.
    Directional {
        /// Unit direction of travel.
        direction: Vec3,
        /// Irradiance on a perpendicular surface (W/m²).
        irradiance: Rgb,
    },
    /// Constant environment radiance from every direction.
    Constant {
        /// Radiance.
        radiance: Rgb,
    },
    /// An image-based environment (equirectangular / latitude–longitude, Mitsuba's `envmap`
    /// convention): the world direction `d` is looked up at local direction `v = R⁻¹·d` with
    /// `u = atan2(v.x, −v.z)/(2π)` (wrapped into [0,1)) and `v = acos(v.y)/π`, row 0 at the top
    /// (`v.y = 1`).
    EnvMap {
        /// The radiance image.
        image: Arc<TextureImage>,
        /// Factor applied to every pixel.
        scale: f32,
        /// Rotation from the map's local frame to world space (columns are the images of the
        /// local x, y, z axes; orthonormal).
        to_world: [Vec3; 3],
    },
}

/// The image a spot light projects over its cone: a local direction `(x, y, z)` (`z` along
/// the axis, `x` and `y` along the axes below) looks up
/// `uv = (½ + ½·x/(z·tan c), ½ + ½·y/(z·tan c))`, `c` the cutoff angle (Mitsuba 3's spot).
#[derive(Clone, Debug, PartialEq)]
pub struct SpotTexture {
    /// The texture (unitless factor on the intensity).
    pub texture: Arc<Texture>,
    /// Unit world direction of the local `x` axis (orthogonal to the spot's axis).
    pub x_axis: Vec3,
    /// Unit world direction of the local `y` axis (orthogonal to the axis and `x_axis`).
    pub y_axis: Vec3,
}

/// The camera's projection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    /// Pinhole perspective.
    Perspective {
        /// Full horizontal field of view (degrees).
        horizontal_fov_degrees: f32,
    },
    /// Thin lens: perspective with depth of field.
    ThinLens {
        /// Full horizontal field of view (degrees).
        horizontal_fov_degrees: f32,
        /// Radius of the lens aperture (scene units, > 0).
        aperture_radius: f32,
        /// Distance of the plane in focus along the viewing direction (scene units, > 0).
        focus_distance: f32,
    },
    /// Orthographic: parallel rays along the viewing direction from a rectangle of
    /// `width × height` scene units centred on the camera position.
    Orthographic {
        /// Width of the visible rectangle (scene units); the height follows from the aspect.
        width: f32,
    },
}

/// A camera in world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraDesc {
    /// Position of the eye (pinhole, lens centre, or centre of the orthographic rectangle).
    pub position: Vec3,
    /// Unit viewing direction.
    pub forward: Vec3,
    /// Unit vector pointing up in the image (orthogonal to `forward`).
    pub up: Vec3,
    /// Unit vector pointing right in the image (orthogonal to both; its handedness is kept
    /// as the file gives it, so mirrored cameras stay mirrored).
    pub right: Vec3,
    /// The projection.
    pub projection: Projection,
}

/// The pixel reconstruction filter (Mitsuba's `rfilter`, pbrt's `Film` filter).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FilterDesc {
    /// Box of half-width 0.5 pixel (each sample counts for its own pixel).
    Box,
    /// Tent (triangle) of half-width `radius` pixels, separable.
    Tent {
        /// Half-width in pixels (Mitsuba's default 1).
        radius: f32,
    },
    /// Gaussian with standard deviation `stddev` pixels, truncated at `radius` pixels and
    /// shifted to reach zero there (`max(0, g(x) − g(radius))`), separable. Mitsuba's default
    /// is `stddev` 0.5, `radius` 4·stddev = 2.
    Gaussian {
        /// Standard deviation in pixels.
        stddev: f32,
        /// Truncation radius in pixels.
        radius: f32,
    },
}

/// The film.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FilmDesc {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Reconstruction filter.
    pub filter: FilterDesc,
}

/// A complete scene description.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneDescription {
    /// Name for messages and reports (usually the file name).
    pub name: String,
    /// The camera.
    pub camera: CameraDesc,
    /// The film.
    pub film: FilmDesc,
    /// Materials, referenced by index from the shapes.
    pub materials: Vec<Material>,
    /// Shapes (area emitters included).
    pub shapes: Vec<ShapeDesc>,
    /// Lights not attached to shapes. At most one environment (`Constant` or `EnvMap`).
    pub lights: Vec<LightDesc>,
    /// Maximum path length in segments from the file's integrator (`None` = no limit given or
    /// unlimited).
    pub max_path_length: Option<u32>,
    /// Warnings the loader wants the user to see (skipped optional attributes).
    pub warnings: Vec<String>,
    /// Spectra of emitters given spectrally in the file (empty for RGB-only scenes).
    pub emission_spectra: EmissionSpectra,
    /// Geometry defined once and placed by [`SceneDescription::instances`] (Mitsuba
    /// `shapegroup`, pbrt-v4 `ObjectBegin`/`ObjectEnd`); see [`crate::instance`].
    pub objects: Vec<ObjectDesc>,
    /// Placements of [`SceneDescription::objects`] (Mitsuba `instance`, pbrt-v4
    /// `ObjectInstance`).
    pub instances: Vec<InstanceDesc>,
    /// Participating media and index-matched boundaries (empty for surface-only scenes).
    pub media: crate::medium::MediaDesc,
}

/// Shapes defined in their own (object) space, to be placed by instances. The shapes must not
/// emit: Mitsuba 3 refuses emitters in a `shapegroup`, and pbrt-v4 area lights in an object.
#[derive(Clone, Debug, PartialEq)]
pub struct ObjectDesc {
    /// Name for messages (the file's id or object name).
    pub name: String,
    /// The shapes, in object space; their materials index [`SceneDescription::materials`].
    pub shapes: Vec<ShapeDesc>,
}

/// One placement of an object.
#[derive(Clone, Debug, PartialEq)]
pub struct InstanceDesc {
    /// Name for messages.
    pub name: String,
    /// Index into [`SceneDescription::objects`].
    pub object: u32,
    /// Object space to world space (affine, invertible; scene units).
    pub to_world: glam::Affine3A,
}

/// Wavelength range (nm) over which [`EmissionSpectrum::Blackbody`] emits: the range of the CIE
/// tables, as Mitsuba 3's `blackbody` spectrum (zero outside it).
pub const BLACKBODY_RANGE_NM: (f32, f32) = (360.0, 830.0);

/// The spectral distribution of an emitted quantity, per nm of wavelength: spectral radiance
/// (W·m⁻²·sr⁻¹·nm⁻¹) for area emitters and environments, spectral intensity (W·sr⁻¹·nm⁻¹) for
/// point and spot lights, spectral irradiance (W·m⁻²·nm⁻¹) for directional lights.
///
/// Its colour is the emission normalisation of Mitsuba 3 (and of the film in spectral mode):
/// `XYZ = ∫ s(λ) (x̄, ȳ, z̄)(λ) dλ / ∫ ȳ dλ` ([`EmissionSpectrum::xyz`]), so the constant
/// spectrum 1 has luminance `Y = 1`.
#[derive(Clone, Debug, PartialEq)]
pub enum EmissionSpectrum {
    /// Piecewise-linear samples, zero outside them.
    Tabulated(Arc<Tabulated>),
    /// Planck's law ([`spectrum::cie::blackbody`], W·m⁻²·sr⁻¹·nm⁻¹ for `scale` 1) times
    /// `scale`, zero outside [`BLACKBODY_RANGE_NM`].
    Blackbody {
        /// Temperature (K, > 0).
        kelvin: f32,
        /// Factor (≥ 0, unitless).
        scale: f32,
    },
}

impl EmissionSpectrum {
    /// The spectrum at `lambda_nm` (nm), per nm (units of the emitted quantity).
    #[inline]
    pub fn eval(&self, lambda_nm: f32) -> f32 {
        match self {
            EmissionSpectrum::Tabulated(t) => t.eval(lambda_nm),
            EmissionSpectrum::Blackbody { kelvin, scale } => {
                let (lo, hi) = BLACKBODY_RANGE_NM;
                if (lo..=hi).contains(&lambda_nm) { scale * spectrum::cie::blackbody(lambda_nm, *kelvin) } else { 0.0 }
            }
        }
    }

    /// The spectrum times `k`; fails when a value becomes non-finite.
    pub fn scaled(&self, k: f32) -> Result<EmissionSpectrum, String> {
        match self {
            EmissionSpectrum::Tabulated(t) => {
                let points: Vec<(f32, f32)> = t.points().map(|(l, v)| (l, v * k)).collect();
                Ok(EmissionSpectrum::Tabulated(Arc::new(Tabulated::new(&points)?)))
            }
            EmissionSpectrum::Blackbody { kelvin, scale } if (scale * k).is_finite() => {
                Ok(EmissionSpectrum::Blackbody { kelvin: *kelvin, scale: scale * k })
            }
            EmissionSpectrum::Blackbody { scale, .. } => {
                Err(format!("a blackbody's scale {scale} times {k} is not finite"))
            }
        }
    }

    /// Checks that the spectrum can be emitted: finite and non-negative everywhere (a positive
    /// finite temperature and a finite non-negative scale for a blackbody).
    pub fn validate(&self) -> Result<(), String> {
        match self {
            EmissionSpectrum::Tabulated(t) => match t.points().find(|(_, v)| *v < 0.0) {
                Some((l, v)) => Err(format!("the emission spectrum is negative ({v}) at {l} nm")),
                None => Ok(()),
            },
            EmissionSpectrum::Blackbody { kelvin, scale } => {
                if !(kelvin.is_finite() && *kelvin > 0.0) {
                    return Err(format!("a blackbody needs a positive finite temperature, got {kelvin} K"));
                }
                if !(scale.is_finite() && *scale >= 0.0) {
                    return Err(format!("a blackbody's scale must be finite and non-negative, got {scale}"));
                }
                Ok(())
            }
        }
    }

    /// Normalised CIE XYZ `∫ s (x̄, ȳ, z̄) dλ / ∫ ȳ dλ` (units of the emitted quantity, per
    /// channel like an RGB emitter value). Exact for tabulated spectra
    /// ([`Tabulated::to_xyz`]); for a blackbody Simpson's rule on every 0.5 nm step of the
    /// 5 nm colour-matching tables (relative error below 10⁻⁶).
    pub fn xyz(&self) -> [f64; 3] {
        let raw = match self {
            EmissionSpectrum::Tabulated(t) => t.to_xyz(),
            EmissionSpectrum::Blackbody { .. } => {
                let (lo, hi) = BLACKBODY_RANGE_NM;
                let steps = ((hi - lo) / 0.5).round() as usize;
                let mut sum = [0.0f64; 3];
                let f = |l: f64| {
                    let v = f64::from(self.eval(l as f32));
                    spectrum::cie::cmf(l as f32).map(|c| f64::from(c) * v)
                };
                for i in 0..steps {
                    let a = f64::from(lo) + 0.5 * i as f64;
                    let (fa, fm, fb) = (f(a), f(a + 0.25), f(a + 0.5));
                    for c in 0..3 {
                        sum[c] += 0.5 / 6.0 * (fa[c] + 4.0 * fm[c] + fb[c]);
                    }
                }
                sum
            }
        };
        raw.map(|v| v / spectrum::cie::CIE_Y_INTEGRAL)
    }
}

/// Spectra of emitters, added to a description beside their RGB values (which RGB rendering
/// keeps using). A spectrum is the emitted quantity itself, every scale of the file applied;
/// the emitter's RGB value in the description is its colour as the loader converted it
/// (possibly clamped into the gamut). Spectral rendering emits the spectrum wherever RGB
/// rendering emits the RGB value, times the same geometric factors (see
/// [`crate::Scene::emission`]). It also carries the radiance textures of textured area
/// emitters, the other way in which an emitter's emission differs from one RGB value.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct EmissionSpectra {
    /// Spectra of area emitters, by index into [`SceneDescription::shapes`].
    pub shapes: BTreeMap<u32, EmissionSpectrum>,
    /// Spectra of other lights, by index into [`SceneDescription::lights`] (not for image
    /// environments).
    pub lights: BTreeMap<u32, EmissionSpectrum>,
    /// Radiance textures of area emitters (W·m⁻²·sr⁻¹ per channel, looked up at the surface's
    /// uv), by index into [`SceneDescription::shapes`]; such a shape's
    /// [`ShapeDesc::emission`] must be `Some` (its value is then unused) and it has no spectrum.
    /// Spectral rendering upsamples the texture's RGB values.
    pub textures: BTreeMap<u32, Arc<Texture>>,
}
